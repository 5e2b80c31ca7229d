"""The Ferraris calibration (``sins.compensation.ferraris``) and the annotated session's reader.

References: a Ferraris session written here with numpy and scipy's ``Rotation`` alone (a known unit,
holds placed by hand, turns of a known angle about a tilted axis, the motions between holds), imucal's
own ``FerrarisCalibration`` run on the same real recording (``imucal`` is a test dependency) and its
stored snapshot ``example_cal_snapshot.json``, and the real sessions' motions between holds, which no
fit sees.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from conftest import dataset_folder, refusal
from scipy.spatial.transform import Rotation

from sins import compensation, io
from sins.compensation.ferraris import HOLDS, TURNS, Ferraris, check_session, compare_with_imucal, to_imucal
from sins.core.series import CalibrationData, RigPhase
from sins.io import datasets

G = 9.81
FOLDER = dataset_folder(datasets.FERRARIS_FOLDER)


# --------------------------------------------------------------------------- a session written with numpy


@dataclass
class Unit:
    """The seed model's coefficients of a unit, SI."""

    B0: np.ndarray
    B: np.ndarray
    K: np.ndarray
    A0: np.ndarray
    A: np.ndarray

    @classmethod
    def draw(cls, rng: np.random.Generator) -> Unit:
        # A consumer MEMS unit (DESIGN.md §4): biases 0.3 m/s² and 0.5 °/s, scale and misalignment 1 %,
        # g-sensitivity 0.05 °/s per g.
        return cls(
            B0=np.radians(rng.normal(0, 0.5, 3)), B=rng.normal(0, 0.01, (3, 3)),
            K=np.radians(rng.normal(0, 0.05, (3, 3))) / G,
            A0=rng.normal(0, 0.3, 3), A=rng.normal(0, 0.01, (3, 3)),
        )  # fmt: skip


@dataclass
class Hand:
    """How the session is performed: placement and turn-axis tilts (rad, 1σ per axis), the turns' angle
    error (rad, 1σ), white noise per sample (rad/s, m/s²), and the Earth's rate on or off."""

    tilt: float = math.radians(0.2)
    turn: float = math.radians(2.0)
    gyro_noise: float = math.radians(0.05)
    accel_noise: float = 0.015
    earth_lat: float | None = None
    truth: dict[str, np.ndarray] = field(default_factory=dict)


RATE_HZ = 100.0
_UP = np.array([0.0, 0.0, 1.0])  # the local vertical in this generator's navigation frame (z up)


def _attitude_with_up(body_up: np.ndarray, heading: float) -> Rotation:
    """``C_nb`` putting the body vector ``body_up`` on the vertical, then turned ``heading`` about it."""
    align, _ = Rotation.align_vectors([_UP], [body_up])
    return Rotation.from_rotvec(heading * _UP) * align


def _numpy_session(unit: Unit, hand: Hand, rng: np.random.Generator) -> CalibrationData:
    """Holds (5 s each), then a turn about x, y and z (3 s, from rest to rest), with the motions between.

    Every motion is a rotation about an axis fixed in the body, its rate shaped ``1 − cos(2π t/T)`` so
    that it starts and ends at rest; the readings are the seed model of the true rate (with the Earth's
    if ``hand.earth_lat``) and specific force, plus white noise. Each hold is placed ``hand.tilt`` off its
    axis, each turn is about the vertical (so its axis is as far off the body axis as its start) by
    −360° plus ``hand.turn``; ``hand.truth`` keeps each turn's true angle vector in the body.
    """
    omega_ie = (
        np.zeros(3)
        if hand.earth_lat is None
        else 7.292115e-5 * np.array([0.0, math.cos(hand.earth_lat), math.sin(hand.earth_lat)])
    )
    tilt = lambda: Rotation.from_rotvec(rng.normal(0, hand.tilt, 3))  # noqa: E731
    rates: list[np.ndarray] = []
    forces: list[np.ndarray] = []
    phases: list[RigPhase] = []
    n_total = 0

    def add(name: str | None, kind: str, c_nb: Rotation, omega_b: np.ndarray, angle=None) -> None:
        nonlocal n_total
        n = len(omega_b)
        rates.append(omega_b + np.broadcast_to(c_nb.inv().apply(omega_ie), (n, 3)))
        forces.append(np.broadcast_to(c_nb.inv().apply(G * _UP), (n, 3)))
        if name is not None:
            phases.append(RigPhase(name, n_total, n_total + n, kind, angle))
        n_total += n

    def move(c0: Rotation, rotvec_b: np.ndarray, seconds: float, name=None, angle=None) -> Rotation:
        n = int(seconds * RATE_HZ)
        s = np.arange(n) / n  # one whole period: the rectangle rule integrates the rate exactly
        shape = 1.0 - np.cos(2.0 * np.pi * s)  # the rate's profile, mean 1
        phi = s - np.sin(2.0 * np.pi * s) / (2.0 * np.pi)  # its integral: the fraction of the turn done
        c_nb = c0 * Rotation.from_rotvec(phi[:, None] * rotvec_b[None, :])
        omega_b = shape[:, None] * (RATE_HZ / n) * rotvec_b[None, :]
        add(name, "rotation" if name else "transition", c_nb, omega_b, angle)
        return c0 * Rotation.from_rotvec(rotvec_b)

    def hold(name: str | None, c_nb: Rotation, seconds: float) -> None:
        n = int(seconds * RATE_HZ)
        add(name, "static", c_nb, np.zeros((n, 3)))

    headings = rng.uniform(0, 2 * np.pi, 9)
    c = None
    for k, name in enumerate(HOLDS):
        axis = np.eye(3)[k // 2] * (1.0 if k % 2 == 0 else -1.0)
        target = tilt() * _attitude_with_up(axis, headings[k])
        if c is not None:
            move(c, (c.inv() * target).as_rotvec(), 3.0)
        c = target
        hold(name, c, 5.0)
    for k, name in enumerate(TURNS):
        target = tilt() * _attitude_with_up(np.eye(3)[k], headings[6 + k])
        move(c, (c.inv() * target).as_rotvec(), 3.0)
        hold(None, target, 1.0)
        angle = -2.0 * np.pi + rng.normal(0, hand.turn)
        u_b = target.inv().apply(_UP)  # the vertical in the body: the turn's true axis
        hand.truth[name] = angle * u_b
        nominal = [0.0, 0.0, 0.0]
        nominal[k] = -2.0 * np.pi
        c = move(target, angle * u_b, 3.0, name, tuple(nominal))
        hold(None, c, 1.0)
    omega, f = np.vstack(rates), np.vstack(forces)
    gyro = omega + omega @ unit.B.T + f @ unit.K.T + unit.B0 + rng.normal(0, hand.gyro_noise, omega.shape)
    accel = f + f @ unit.A.T + unit.A0 + rng.normal(0, hand.accel_noise, f.shape)
    ref_gyro, ref_accel = np.full_like(omega, np.nan), np.full_like(f, np.nan)
    for k, p in enumerate(phases[:6]):
        ref_gyro[p.start : p.stop] = 0.0
        ref_accel[p.start : p.stop] = G * np.eye(3)[k // 2] * (1.0 if k % 2 == 0 else -1.0)
    return CalibrationData(
        t=np.arange(len(f)) / RATE_HZ, gyro=gyro, accel=accel, ref_gyro=ref_gyro, ref_accel=ref_accel,
        phases=tuple(phases), source="numpy session",
    )  # fmt: skip


def _z_scores(fitted: Ferraris, unit: Unit) -> dict[str, np.ndarray]:
    return {
        name: (getattr(fitted, f"{name}_") - getattr(unit, name)) / getattr(fitted, f"{name}_se_")
        for name in ("A0", "A", "B0", "B", "K")
    }


# --------------------------------------------------------------------------- the estimators on numpy sessions


def test_a_noise_free_session_gives_the_unit_back_exactly() -> None:
    """No noise, holds on their axes, turns of exactly −360° about them: every coefficient to rounding
    (the rectangle rule integrates the generator's whole-period rate profile exactly)."""
    rng = np.random.default_rng(1)
    unit = Unit.draw(rng)
    data = _numpy_session(unit, Hand(tilt=0.0, turn=0.0, gyro_noise=0.0, accel_noise=0.0), rng)
    fitted = Ferraris().fit(data)
    for name in ("A0", "A", "B0", "B", "K"):
        np.testing.assert_allclose(getattr(fitted, f"{name}_"), getattr(unit, name), rtol=0, atol=1e-12)
    assert fitted.placement_rad_ < 1e-12
    # Without g-sensitivity K is 0 and the same turns leave B as it was (K f is 1e-5 of it here).
    plain = Ferraris(g_sensitivity=False).fit(data)
    assert np.array_equal(plain.K_, np.zeros((3, 3)))
    np.testing.assert_allclose(plain.A_, unit.A, atol=1e-12)


def test_coefficients_lie_within_their_standard_errors() -> None:
    """30 numpy sessions of 30 drawn units, performed by a hand that places each hold 0.2° off (per
    axis), turns 2° off −360° (the default ``turn_sd_deg``) about an axis as far off, with white noise
    of 0.05 °/s and 15 mm/s² per sample.

    z = (fit − truth)/se, grouped by what sets the error. Each se is estimated (batch means: 9 degrees
    of freedom per hold; the placement: 6 half-sums), so z is t-like and its mean square can reach 1.5
    (Student's t with 6 degrees of freedom); with 90–270 values a group's mean z² has a sampling sd of
    0.15–0.25. Accepted: mean z² in [0.6, 1.6] per group and no |z| above 6. Before the placement was
    carried into A0's and A's diagonal se (through the misalignment), their mean z² was 1.7 and 1.8.
    """
    groups: dict[str, list[np.ndarray]] = {}
    for seed in range(30):
        rng = np.random.default_rng(seed)
        unit = Unit.draw(rng)
        fitted = Ferraris().fit(_numpy_session(unit, Hand(), rng))
        for name, z in _z_scores(fitted, unit).items():
            if z.ndim == 2:
                diag = np.eye(3, dtype=bool)
                groups.setdefault(f"{name} diagonal", []).append(z[diag])
                groups.setdefault(f"{name} off-diagonal", []).append(z[~diag])
            else:
                groups.setdefault(name, []).append(z)
    for name, zs in groups.items():
        z = np.concatenate(zs)
        assert 0.6 <= np.mean(z**2) <= 1.6, (name, np.mean(z**2))
        assert np.abs(z).max() < 6.0, (name, np.abs(z).max())


def test_the_earth_rate_reads_as_g_sensitivity() -> None:
    """The docstring's claim: at rest the Earth's rate is in the holds' gyro means, and their
    differences take it for g-sensitivity. Noise-free session at 49.6° N: K's diagonal gains
    ``Ω sin φ / g`` through the gyro's own scale (1 + B_kk, B of 1 % here: within 5 %), each off-diagonal
    at most ``Ω cos φ / g`` (same 5 %), whatever the holds' headings."""
    lat = math.radians(49.6)
    rng = np.random.default_rng(3)
    unit = Unit.draw(rng)
    hand = Hand(tilt=0.0, turn=0.0, gyro_noise=0.0, accel_noise=0.0, earth_lat=lat)
    shift = Ferraris().fit(_numpy_session(unit, hand, rng)).K_ - unit.K
    omega = 7.292115e-5
    np.testing.assert_allclose(np.diag(shift), omega * math.sin(lat) / G, rtol=0.05)
    assert np.abs(shift[~np.eye(3, dtype=bool)]).max() <= 1.05 * omega * math.cos(lat) / G


def test_check_session_on_a_numpy_session() -> None:
    """The motions between holds, which no fit sees, carried by a noise-free unit's fitted correction:
    the gravity direction arrives to 1e-9 rad (the turns and transitions are rotations about a fixed
    axis, which the trapezoidal attitude integrates exactly); the raw readings miss by degrees."""
    rng = np.random.default_rng(4)
    unit = Unit.draw(rng)
    data = _numpy_session(unit, Hand(tilt=0.0, turn=0.0, gyro_noise=0.0, accel_noise=0.0), rng)
    after = check_session(Ferraris().fit(data), data)
    before = check_session(compensation.make("none"), data)
    assert [t.start for t in after.transitions] == list(HOLDS[:-1])
    assert all(t.error_rad < 1e-9 for t in after.transitions)
    assert all(t.error_rad > math.radians(1.0) for t in before.transitions)
    for h in after.holds:
        assert abs(h.force_error_mps2) < 1e-9 and h.tilt_rad < 1e-9 and np.abs(h.rate_radps).max() < 1e-12
    for t in after.turns:
        np.testing.assert_allclose(t.angle_rad, t.expected_rad, atol=1e-9)


# --------------------------------------------------------------------------- the strategy's contract


def test_registered_saved_and_loaded_bit_for_bit(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    data = _numpy_session(Unit.draw(rng), Hand(), rng)
    fitted = compensation.make("ferraris", turn_sd_deg=1.0).fit(data)
    assert isinstance(fitted, Ferraris) and fitted.name in compensation.SAVED_STRATEGIES
    path = tmp_path / "ferraris.json"
    compensation.save(fitted, path)
    back = compensation.load(path)
    assert isinstance(back, Ferraris) and back.params() == fitted.params()
    for key, value in fitted.get_state().items():
        assert np.array_equal(getattr(back, key), np.asarray(value)), key
    gyro, accel = fitted.correct(data.gyro, data.accel)
    gyro_back, accel_back = back.correct(data.gyro, data.accel)
    assert np.array_equal(gyro, gyro_back) and np.array_equal(accel, accel_back)


def test_correction_inverts_the_seed_model_on_rates_and_increments() -> None:
    """Readings made by the fitted model from known inputs come back to those inputs; increments are
    corrected as their mean rate times the step (the model is affine)."""
    from sins.core.series import ImuIncrements

    rng = np.random.default_rng(6)
    fitted = Ferraris().fit(_numpy_session(Unit.draw(rng), Hand(), rng))
    omega, f = rng.normal(0, 1.0, (50, 3)), rng.normal(0, 10.0, (50, 3))
    accel = f + f @ fitted.A_.T + fitted.A0_
    gyro = omega + omega @ fitted.B_.T + f @ fitted.K_.T + fitted.B0_
    omega_c, f_c = fitted.correct(gyro, accel)
    np.testing.assert_allclose(omega_c, omega, atol=1e-12)
    np.testing.assert_allclose(f_c, f, atol=1e-12)
    t = np.arange(51) * 0.01
    inc = fitted.correct_increments(ImuIncrements(t=t, dtheta_b=gyro * 0.01, dv_b=accel * 0.01))
    np.testing.assert_allclose(inc.dtheta_b, omega * 0.01, atol=1e-14)
    np.testing.assert_allclose(inc.dv_b, f * 0.01, atol=1e-13)


def test_a_recording_without_the_session_is_refused_in_one_line() -> None:
    rng = np.random.default_rng(7)
    data = _numpy_session(Unit.draw(rng), Hand(), rng)
    fit = Ferraris().fit

    def without(name: str) -> CalibrationData:
        return CalibrationData(**{**vars(data), "phases": tuple(p for p in data.phases if p.name != name)})

    refusal(lambda: fit(without("y_a")), "numpy session", "six holds", "three turns", "missing y_a")
    refusal(lambda: fit(without("z_rot")), "missing z_rot")
    plain = CalibrationData(**{**vars(data), "phases": ()})
    refusal(lambda: fit(plain), "missing x_p, x_a, y_p, y_a, z_p, z_a, x_rot, y_rot, z_rot")
    renamed = tuple(
        RigPhase(p.name, p.start, p.stop, p.kind, None) if p.name == "y_rot" else p for p in data.phases
    )
    refusal(
        lambda: fit(CalibrationData(**{**vars(data), "phases": renamed})), "turn 'y_rot'", "no known angle"
    )
    flipped = data.ref_accel.copy()
    (x_a,) = [p for p in data.phases if p.name == "x_a"]
    flipped[x_a.start : x_a.stop] *= -1.0
    upside_down = CalibrationData(**{**vars(data), "ref_accel": flipped})
    refusal(lambda: fit(upside_down), "hold 'x_a'", "not along -x")
    # A turn cut short: its last 30 % held back, as `sins fit --validation 0.3` would (whose split also
    # drops the turns' angles, refused above).
    cut = tuple(
        RigPhase(p.name, p.start, p.stop - (p.stop - p.start) * 3 // 10, p.kind, p.angle_rad)
        if p.name == "x_rot" else p
        for p in data.phases
    )  # fmt: skip
    refusal(
        lambda: fit(CalibrationData(**{**vars(data), "phases": cut})),
        "turn 'x_rot' does not begin and end at rest", "whole",
    )  # fmt: skip
    refusal(lambda: fit(data.split(0.3)[0]), "turn 'x_rot' has no known angle", "nothing held back")
    sideways = tuple(
        RigPhase(p.name, p.start, p.stop, p.kind, (0.0, 0.0, -6.0)) if p.name == "x_rot" else p
        for p in data.phases
    )
    refusal(lambda: fit(CalibrationData(**{**vars(data), "phases": sideways})), "turn 'x_rot'", "about x")


# --------------------------------------------------------------------------- the annotated session's reader

ANNOTATED = FOLDER / "annotated_session.csv"
needs_annotated = pytest.mark.skipif(
    not ANNOTATED.is_file(),
    reason=f"imucal's annotated session not found at {ANNOTATED}: set SINS_DATA to the folder that holds "
    f"{datasets.FERRARIS_FOLDER}/ (the project's ../shared/data)",
)
needs_example = pytest.mark.skipif(
    not (FOLDER / "example_ferraris_session.csv").is_file(),
    reason=f"imucal's example session not found in {FOLDER}: set SINS_DATA (the project's ../shared/data)",
)


def _annotated_counts() -> tuple[np.ndarray, np.ndarray]:
    """The annotated CSV with the standard library alone: ``part`` (n,) and the six counts (n, 7) with
    ``samples`` first, in file order."""
    import csv

    with open(ANNOTATED, encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["part", "samples", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"]
    return np.array([r[0] for r in rows[1:]]), np.array([[float(x) for x in r[1:]] for r in rows[1:]])


@needs_annotated
def test_annotated_session_rows_units_and_references() -> None:
    parts, counts = _annotated_counts()
    data = io.read(dataset="ferraris_annotated").reference_inputs()[0]
    order = np.argsort(counts[:, 0])
    assert len(data) == 9414 and np.array_equal(counts[order, 0], np.arange(9414))
    np.testing.assert_array_equal(data.t, np.arange(9414) / 204.8)
    # Counts times 9.81/2048 m/s² and 2000/2¹⁵ °/s, in `samples` order.
    np.testing.assert_array_equal(data.accel, counts[order, 1:4] * (9.81 / 2048))
    np.testing.assert_array_equal(data.gyro, np.radians(counts[order, 4:7] * (2000 / 32768)))
    assert [p.name for p in data.phases] == list(datasets.FERRARIS_SECTIONS)
    for p in data.phases:
        assert set(parts[order][p.start : p.stop]) == {p.name}
        if p.kind == "rotation":
            angle = np.zeros(3)
            angle["xyz".index(p.name[0])] = 2.0 * math.pi  # this session's turns read positive
            assert p.angle_rad == tuple(angle)
        else:
            axis = "xyz".index(p.name[0])
            mean = data.accel[p.start : p.stop].mean(axis=0)
            assert mean[axis] * data.ref_accel[p.start, axis] > 0.99 * np.linalg.norm(mean) * G
    # The turns' sign: with imucal's −360° the gyro's matrix would be a reflection (det < 0).
    turns = [p for p in data.phases if p.kind == "rotation"]
    w = np.array([data.gyro[p.start : p.stop].sum(axis=0) for p in turns]).T
    assert np.linalg.det(w) > 0 and np.all(np.diag(w) > 0)


def test_annotated_files_are_refused_in_one_line(tmp_path: Path) -> None:
    folder = tmp_path / datasets.FERRARIS_FOLDER
    folder.mkdir()
    path = folder / "annotated_session.csv"
    refusal(lambda: datasets._read_ferraris_annotated(tmp_path), str(path), "no such file", "SINS_DATA")
    head = "part,samples,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n"
    good = [(name, k) for k, name in enumerate(datasets.FERRARIS_SECTIONS) for _ in range(3)]

    def write(rows: list[tuple[str, int]]) -> None:
        path.write_text(head + "".join(f"{n},{i},0,0,2000,1,2,3\n" for i, (n, _) in enumerate(rows)))

    write(good)
    assert len(datasets._read_ferraris_annotated(tmp_path).phases) == 9
    write([("w_p", 0), *good[1:]])
    refusal(lambda: datasets._read_ferraris_annotated(tmp_path), f"{path}:2:", "unknown section 'w_p'")
    write([r for r in good if r[0] != "y_rot"])
    refusal(lambda: datasets._read_ferraris_annotated(tmp_path), str(path), "missing section 'y_rot'")
    write([*good[3:6], *good[:3], *good[6:]])  # x_a's rows first: fine, `samples` orders them
    swapped = good[:1] + good[3:4] + good[2:3] + good[1:2] + good[4:]  # x_p, x_a, x_p, x_a, ...
    write(swapped)
    refusal(lambda: datasets._read_ferraris_annotated(tmp_path), "section 'x_p' is not one run")
    path.write_text(head + "".join(f"{n},{2 * i},0,0,2000,1,2,3\n" for i, (n, _) in enumerate(good)))
    refusal(lambda: datasets._read_ferraris_annotated(tmp_path), "column 'samples'", "each once")
    path.write_text(head.replace("part,", "section,") + "x_p,0,0,0,0,0,0,0\n")
    refusal(lambda: datasets._read_ferraris_annotated(tmp_path), "missing required column 'part'")
    path.write_text(head + "x_p,0,1e9,0,0,0,0,0\n")
    refusal(lambda: datasets._read_ferraris_annotated(tmp_path), f"{path}:2:", "column 'acc_x'", "outside")


# --------------------------------------------------------------------------- against imucal


def _imucal(grav: float, angle_deg: float):
    """imucal's Ferraris calibration of the annotated session, read as imucal's own test reads it."""
    pd = pytest.importorskip("pandas", reason="imucal needs pandas (the test extra)")
    imucal = pytest.importorskip("imucal", reason="imucal is a test dependency: pip install -e .[test]")
    frame = pd.read_csv(ANNOTATED, header=0, index_col=0)
    regions = imucal.ferraris_regions_from_df(frame)
    return imucal.FerrarisCalibration(grav=grav, expected_angle=angle_deg).compute(
        regions, sampling_rate_hz=204.8, from_acc_unit="a.u.", from_gyr_unit="a.u."
    )


UNITS = {"accel_unit_mps2": 9.81 / 2048, "gyro_unit_dps": 2000 / 32768}


@pytest.fixture(scope="module")
def annotated_fit() -> tuple[CalibrationData, Ferraris]:
    if not ANNOTATED.is_file():
        pytest.skip(f"imucal's annotated session not found at {ANNOTATED}: set SINS_DATA")
    data = datasets._read_ferraris_annotated()
    return data, Ferraris().fit(data)


@needs_annotated
def test_side_by_side_with_imucal_on_its_annotated_session(annotated_fit) -> None:
    """Every gain, misalignment and bias, imucal's (run here at sins's g and the session's +360°) beside
    sins's, through :func:`to_imucal`'s mapping (the table ``tools/ferraris_vs_imucal.py`` prints).

    * Accelerometer (K_a, R_a, b_a) and K_ga: the same estimators (each pair's difference; each axis's
      own pair for the bias): equal to 1e-9 relative (floating point in another order).
    * b_g: imucal pools the holds' samples, sins weighs the six holds alike. The difference must be
      exactly Σ (w_i − 1/6) Ḡ_i, the hold means Ḡ_i and sample shares w_i computed here from the raw
      counts (to 1e-9 count), and within half its standard error: the shares are 1/6 ± 0.036, so the
      difference's own spread is 0.15 se, and 0.5 se is 3.4 of it.
    * K_g R_g (the turns' integrated readings over their angle): sins's and imucal's differ only
      through that bias, column k by −Δb_g T_k / 360°, T_k the turn's duration (to 1e-9 relative).
    """
    data, fitted = annotated_fit
    g = float(data.ref_accel[data.phases[0].start, 0])
    ref = _imucal(g, 360.0)
    ours = to_imucal(fitted.B0_, fitted.B_, fitted.K_, fitted.A0_, fitted.A_, **UNITS)
    for name in ("K_a", "R_a", "b_a", "K_ga"):
        np.testing.assert_allclose(
            getattr(ours, name), getattr(ref, name), rtol=1e-9, atol=1e-15, err_msg=name
        )
    parts, counts = _annotated_counts()
    holds = [counts[parts == name, 4:7] for name in HOLDS]
    shares = np.array([len(h) for h in holds]) / sum(len(h) for h in holds)
    expected = sum((w - 1 / 6) * h.mean(axis=0) for w, h in zip(shares, holds, strict=True))
    delta_bg = ours.b_g - ref.b_g
    np.testing.assert_allclose(-delta_bg, expected, rtol=0, atol=1e-9)
    durations = np.array([np.sum(parts == name) for name in TURNS]) / 204.8
    reconciled = ours.K_g @ ours.R_g + np.outer(delta_bg, durations / 360.0)
    np.testing.assert_allclose(reconciled, ref.K_g @ ref.R_g, rtol=1e-9, atol=1e-12)
    rows = compare_with_imucal(fitted, ref, **UNITS)
    assert len(rows) == 3 + 9 + 3 + 3 + 9 + 9 + 3
    for row in rows:
        assert abs(row.sins - row.reference) <= 0.5 * row.se or not np.isfinite(row.se), row
        if not np.isfinite(row.se):  # R's diagonal: unit rows, the same to the misalignments' square
            assert abs(row.sins - row.reference) < 1e-6


@needs_annotated
def test_imucal_mapping_end_to_end(annotated_fit) -> None:
    """The mapping checked through imucal's own ``calibrate``: sins's coefficients, written in imucal's
    parameters, calibrate the raw counts (m/s², °/s) exactly as sins corrects the converted readings."""
    imucal = pytest.importorskip("imucal", reason="imucal is a test dependency: pip install -e .[test]")
    data, fitted = annotated_fit
    ours = to_imucal(fitted.B0_, fitted.B_, fitted.K_, fitted.A0_, fitted.A_, **UNITS)
    info = imucal.FerrarisCalibrationInfo(
        from_acc_unit="a.u.", from_gyr_unit="a.u.", **{k: getattr(ours, k) for k in vars(ours)}
    )
    raw_acc, raw_gyr = data.accel / UNITS["accel_unit_mps2"], np.degrees(data.gyro) / UNITS["gyro_unit_dps"]
    acc, gyr_dps = info.calibrate(raw_acc, raw_gyr, acc_unit="a.u.", gyr_unit="a.u.")
    omega, f = fitted.correct(data.gyro, data.accel)
    np.testing.assert_allclose(acc, f, rtol=0, atol=1e-10)
    np.testing.assert_allclose(np.radians(gyr_dps), omega, rtol=0, atol=1e-12)


@needs_annotated
def test_against_imucals_stored_snapshot(annotated_fit) -> None:
    """``example_cal_snapshot.json`` is imucal's calibration at its defaults, g = 9.81 m/s² and −360°.
    imucal here reproduces it (to 1e-9: another version may round differently); sins's fit, mapped to
    that g (gains per m/s² × g/9.81) and sign (R_g negated), agrees within half a standard error."""
    data, fitted = annotated_fit
    snapshot = json.loads((FOLDER / "example_cal_snapshot.json").read_text())
    default = _imucal(9.81, -360.0)
    for name in ("K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g"):
        stored = np.asarray(snapshot[name], dtype=float)
        np.testing.assert_allclose(getattr(default, name), stored, rtol=1e-9, atol=1e-12, err_msg=name)
    assert np.linalg.det(np.array(snapshot["R_g"])) < 0  # the reflection the −360° makes of this session
    g = float(data.ref_accel[data.phases[0].start, 0])
    ours = to_imucal(fitted.B0_, fitted.B_, fitted.K_, fitted.A0_, fitted.A_, **UNITS)
    se: dict[str, list[float]] = {}
    for r in compare_with_imucal(fitted, ours, **UNITS):  # for the standard errors, in imucal's units
        se.setdefault(r.parameter, []).append(r.se)
    mapped = {
        "K_a": np.diag(ours.K_a) * g / 9.81, "R_a": ours.R_a, "b_a": ours.b_a, "K_g": np.diag(ours.K_g),
        "R_g": -ours.R_g, "K_ga": ours.K_ga * g / 9.81, "b_g": ours.b_g,
    }  # fmt: skip
    for name, value in mapped.items():
        stored = np.array(snapshot[name], dtype=float)
        stored = np.diag(stored) if name in ("K_a", "K_g") else stored
        # R's diagonal (no se: 1 less half the row's misalignments squared) moves with the off-diagonal
        # entries times their size: ≤ 1e-5 × 0.04 here, so 1e-6.
        limit = 0.5 * np.nan_to_num(np.array(se[name]).reshape(stored.shape), nan=2e-6)
        assert (np.abs(value - stored) <= limit).all(), (name, value - stored, limit)


# --------------------------------------------------------------------------- the example session


@pytest.fixture(scope="module")
def example() -> CalibrationData:
    if not (FOLDER / "example_ferraris_session.csv").is_file():
        pytest.skip(f"imucal's example session not found in {FOLDER}: set SINS_DATA")
    return io.read(dataset="ferraris").reference_inputs()[0]


@needs_example
def test_the_example_session_before_and_after(example: CalibrationData) -> None:
    """What the calibration does to the example session (102.4 Hz, physical units; the figures of
    docs/validation.md, printed by tools/ferraris_vs_imucal.py).

    By construction: the turns come out at −360° about their axis and 0 off it (three turns, nine
    coefficients), and each hold's |f| at g up to its placement's off-axis part times the
    misalignment (0.05 m/s² × 0.02: 1 mm/s²; raw: 0.13–0.67 m/s² off). Not by construction: the five
    motions between holds (3.4–4.4 s, 91–180°), which no fit sees. The raw gyro's 0.6 °/s bias alone
    turns the gravity direction 2–3° over each; corrected, each must arrive within 3 standard errors
    of the fitted gyro (its scale's 0.56 % of the angle turned, the misalignments' and the bias's over
    the time), and better than the raw readings and than the holds' biases alone on RMS.
    """
    fitted = Ferraris().fit(example)
    before = check_session(compensation.make("none"), example)
    after = check_session(fitted, example)
    assert min(abs(h.force_error_mps2) for h in before.holds) > 0.1
    assert max(abs(h.force_error_mps2) for h in after.holds) < 2e-3
    for t in after.turns:
        np.testing.assert_allclose(t.angle_rad, t.expected_rad, rtol=0, atol=1e-9)
    assert len(after.transitions) == 5
    scale, misalignment = np.diag(fitted.B_se_).max(), fitted.B_se_[~np.eye(3, dtype=bool)].max()
    for b, a in zip(before.transitions, after.transitions, strict=True):
        allowed = 3.0 * (
            (scale + 2 * misalignment) * a.turned_rad + np.linalg.norm(fitted.B0_se_) * a.seconds
        )
        assert a.error_rad < allowed and a.error_rad < b.error_rad, (a, allowed, b)
    bias = Ferraris().fit(example)
    bias.B_, bias.K_, bias.A_ = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
    rms = lambda c: math.sqrt(np.mean([t.error_rad**2 for t in c.transitions]))  # noqa: E731
    assert rms(after) < rms(check_session(bias, example)) < rms(before)


@needs_example
def test_fit_and_evaluate_through_the_library(example: CalibrationData, tmp_path: Path) -> None:
    """What `sins fit --dataset ferraris --strategy ferraris --out M.json` and `sins evaluate M.json
    --dataset ferraris` do, through the library calls they make: fit, save, load, then the RMS of reading
    − reference over the rows with a reference (the six holds).

    What must be left: on the accelerometers the holds' placement, whose off-axis part the reference
    (±g on one axis) does not hold: below 1.5 g σ for the fitted placement σ per axis (four holds of six
    show it on any one channel, so its RMS is about 0.8 g σ), and a tenth of the raw error at most. On
    the gyros the noise: an RMS within 5 % of the holds' own spread about their means, a mean within 5
    standard errors of 0.
    """
    fitted = compensation.make("ferraris").fit(io.read(dataset="ferraris").reference_inputs()[0])
    compensation.save(fitted, tmp_path / "m.json")
    channels = compensation.residual_rms(compensation.load(tmp_path / "m.json"), example)
    holds = [p for p in example.phases if p.name in HOLDS]
    spread = np.sqrt(np.mean([example.gyro[p.start : p.stop].var(axis=0) for p in holds], axis=0))
    for name, v in channels.items():
        axis = "xyz".index(name[-1])
        if name.startswith("accel"):
            assert v["rms_after"] < min(1.5 * G * fitted.placement_rad_, 0.1 * v["rms_before"]), (name, v)
        else:
            assert v["rms_after"] < 1.05 * spread[axis] and abs(v["mean_after"]) < 5 * fitted.B0_se_[axis], v


@needs_example
def test_sins_fit_prints_the_procedures_own_coefficients(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``sins fit --dataset ferraris --strategy ferraris`` prints the strategy's own coefficients, its
    g-sensitivity from each pair's difference among them, each the model file's value (°/h/g): it had
    printed least squares of the seed model, which a session of angles cannot give a g-sensitivity (a
    docs walk found the guide's "and its g-sensitivity" nowhere in the output)."""
    from sins.cli import main

    model = tmp_path / "m.json"
    assert main(["fit", "--dataset", "ferraris", "--strategy", "ferraris", "--out", str(model)]) == 0
    out = capsys.readouterr().out
    assert "the Ferraris procedure's coefficients (± 1σ)" in out
    fitted = compensation.load(model)
    k_xx = fitted.K_[0, 0] * 3600.0 * 180.0 / math.pi * 9.80665  # rad/s per m/s² in °/h/g
    row = next(line for line in out.splitlines() if "g_sensitivity" in line and "x←x" in line)
    assert float(row.split()[3]) == pytest.approx(k_xx, rel=1e-3), row
