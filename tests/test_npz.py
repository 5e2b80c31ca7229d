"""Recordings in the .npz form of shared/data/euroc: the reader, its refusals, ``--dataset FOLDER/NAME``,
and the open-loop attitude of the raw gyro against SOURCE.md's figures (an independent scipy integration)."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import numpy_unit_gap as nu
import pytest
from conftest import dataset_folder, refusal
from scipy.spatial.transform import Rotation

from sins import io
from sins.cli import main
from sins.compensation import judging, referenced
from sins.core import earth
from sins.core.series import NavSeries
from sins.errors import SinsInputError
from sins.io import datasets, inspection, local
from sins.io.frame_check import REFERENCE_LAG_S

EUROC = dataset_folder("euroc")
needs_euroc = pytest.mark.skipif(not (EUROC / "V1_01_easy.npz").is_file(), reason=f"no EuRoC data in {EUROC}")


def _write(path: Path, n: int = 400, seed: int = 3, **changes: object) -> dict[str, np.ndarray]:
    """A short recording turning at a constant rate about the world's vertical, its reference exact."""
    rng = np.random.default_rng(seed)
    t = 1.4e9 + np.arange(n) / 200.0
    w_z = 0.3
    q = Rotation.from_rotvec(np.outer(t - t[0], [0.0, 0.0, w_z]))
    arrays: dict[str, np.ndarray] = {
        "t_s": t,
        "gyro_rad_s": (np.tile([0.0, 0.0, w_z], (n, 1)) + rng.normal(0, 1e-3, (n, 3))).astype(np.float32),
        "accel_m_s2": np.tile([0.0, 0.0, 9.81], (n, 1)).astype(np.float32),
        "q_wxyz": q.as_quat(scalar_first=True).astype(np.float32),
        "v_m_s": np.zeros((n, 3), np.float32),
        "p_m": np.zeros((n, 3), np.float32),
    }
    for key, value in changes.items():
        if value is None:
            arrays.pop(key)
        else:
            arrays[key] = np.asarray(value)
    np.savez(path, **arrays)
    return arrays


def test_readings_and_reference_read_back(tmp_path: Path) -> None:
    path = tmp_path / "rec.npz"
    arrays = _write(path)
    rec = io.read(path)
    assert rec.kind == "npz" and not rec.heading_known and not rec.latitude_known
    np.testing.assert_allclose(rec.imu.t, arrays["t_s"] - arrays["t_s"][0], atol=1e-6)
    np.testing.assert_array_equal(rec.imu.omega_ib_b, arrays["gyro_rad_s"].astype(float))
    assert rec.t0_ns == round(arrays["t_s"][0] * 1e9)
    # The attitude of the sensor's axes in the world frame (z up, taken as ENU) turned into NED: the
    # body's z axis (up in the world) is down in NED, and the turn about the vertical keeps its size.
    up_in_ned = Rotation.from_quat(rec.truth.q_nb).apply([0.0, 0.0, 1.0])
    np.testing.assert_allclose(up_in_ned, np.tile([0.0, 0.0, -1.0], (len(up_in_ned), 1)), atol=1e-6)
    turned = Rotation.from_quat(rec.truth.q_nb[-1]) * Rotation.from_quat(rec.truth.q_nb[0]).inv()
    assert turned.magnitude() == pytest.approx(0.3 * (arrays["t_s"][-1] - arrays["t_s"][0]), rel=1e-5)
    # Beside its own reference the report names it so, and keeps the room frame's unknown latitude.
    beside = rec.beside_reference()
    assert beside.reference_name == "its own reference (npz)" and not beside.latitude_known


def _swinging(path: Path, order: str = "wxyz", inverse: bool = False, lag_s: float = 0.0) -> None:
    """Ten seconds of a unit swinging about a tilted axis (angle 0.8 sin(2π t / 3) rad), its readings
    exact: the rate along the axis, gravity's reaction (9.81 m/s² up in the world) in the sensor's axes;
    the reference's quaternion written in ``order``, or the other way round (the world in the sensor),
    and stamped ``lag_s`` late (the attitude at ``t - lag_s`` stamped ``t``)."""
    t = np.arange(2000) / 200.0
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    angle, rate = 0.8 * np.sin(2 * np.pi * t / 3.0), 0.8 * 2 * np.pi / 3.0 * np.cos(2 * np.pi * t / 3.0)
    q = Rotation.from_rotvec(np.outer(angle, axis)) * Rotation.from_euler("x", 0.3)
    late = Rotation.from_rotvec(np.outer(0.8 * np.sin(2 * np.pi * (t - lag_s) / 3.0), axis))
    written = (q.inv() if inverse else q) if lag_s == 0.0 else late * Rotation.from_euler("x", 0.3)
    _write(
        path, n=2000, t_s=t, gyro_rad_s=np.outer(rate, Rotation.from_euler("x", 0.3).inv().apply(axis)),
        accel_m_s2=q.inv().apply([0.0, 0.0, 9.81]),
        q_wxyz=written.as_quat(scalar_first=order == "wxyz"), v_m_s=np.zeros((2000, 3)),
        p_m=np.zeros((2000, 3)),
    )  # fmt: skip


@pytest.mark.parametrize(
    ("order", "inverse", "seen"),
    [("wxyz", False, None), ("xyzw", False, "correlate -0.48"), ("wxyz", True, "correlate -0.96"),
     ("steady xyzw", False, "17° from up")],
)  # fmt: skip
def test_inspect_judges_the_axes_by_the_reference_attitude(
    tmp_path: Path, order: str, inverse: bool, seen: str | None
) -> None:
    """Beside a reference, the readings' axes are its body's whatever they are called: a reference of
    these axes gives no finding (gravity along a tilted axis, which FRD's convention would call a
    mistake; and the swing's still moments, where the readings barely change, are not taken for rest);
    a quaternion of the other order or the other way round shows in the turns, and where the unit turns
    steadily (which a gyro bias could explain), the other order shows in gravity; what judges against
    the reference refuses it."""
    path = tmp_path / "swing.npz"
    if order == "steady xyzw":  # the steady turn about the vertical, its quaternion scalar last
        steady = _write(path)
        _write(path, q_wxyz=np.roll(steady["q_wxyz"], -1, axis=1))
    else:
        _swinging(path, order, inverse)
    findings = inspection.inspect(io.read(path)).findings
    if seen is None:
        assert not findings, findings
        assert io.read(path).beside_reference().reference.t[-1] == pytest.approx(9.995)
    else:
        assert [f.code for f in findings] == ["reference_attitude"] and seen in findings[0].what, findings
        # What judges against the reference (fit, evaluate, gap) refuses it: every figure would be wrong.
        refusal(lambda: io.read(path).beside_reference(), str(path), seen, "quaternion order")


def _world_turned(path: Path, turn: Rotation) -> None:
    """The recording at ``path`` written again with its world frame turned by ``turn`` (its attitude,
    velocity and position: the readings and the turns they make are the same)."""
    doc = {k: np.asarray(v, dtype=float) if k != "t_s" else v for k, v in np.load(path).items()}
    q = turn * Rotation.from_quat(doc["q_wxyz"], scalar_first=True)
    np.savez(
        path, **{**doc, "q_wxyz": q.as_quat(scalar_first=True), "v_m_s": turn.apply(doc["v_m_s"]),
                 "p_m": turn.apply(doc["p_m"])},
    )  # fmt: skip


def test_a_reference_in_a_world_with_z_down_is_read_turned_and_said_so(tmp_path: Path) -> None:
    """The swing's reference written in a world with z down (NED: east and north swapped, up turned
    down, by scipy's Rotation) where the form says z up: gravity's reaction points along -z, so it is
    read turned by 180° and said so, and its turns, in the body, are those of the file as written with
    z up (the attitude is of the readings' axes; only the world was turned)."""
    upright, down = tmp_path / "swing.npz", tmp_path / "down.npz"
    _swinging(upright)
    _swinging(down)
    _world_turned(down, Rotation.from_matrix([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]))
    rec = io.read(down)
    assert any("up lies along -z" in note and "turned by 180°" in note for note in rec.notes), rec.notes
    assert not inspection.inspect(rec).findings
    a, b = (Rotation.from_quat(io.read(p).beside_reference().reference.q_nb) for p in (upright, down))
    np.testing.assert_allclose((a[0].inv() * a).as_rotvec(), (b[0].inv() * b).as_rotvec(), atol=1e-9)
    np.testing.assert_allclose(b.apply([0.0, 0.0, 1.0])[:, 2], a.apply([0.0, 0.0, 1.0])[:, 2], atol=1e-9)


def test_a_world_tilted_off_its_axes_is_refused_and_the_turns_that_agree_are_said(tmp_path: Path) -> None:
    """A world frame turned 30° about x: no axis of it is up, so it is not turned; the refusal says the
    attitude is of the readings' axes (its turns agree with the gyro's) and where its up lies."""
    path = tmp_path / "swing.npz"
    _swinging(path)
    _world_turned(path, Rotation.from_euler("x", 30, degrees=True))
    findings = inspection.inspect(io.read(path)).findings
    assert [f.code for f in findings] == ["reference_attitude"], findings
    refusal(
        lambda: io.read(path).beside_reference(), str(path), "30° from up", "turns agree", "readings' axes",
        "(x, y, z) = (0.00, -0.50, 0.87)",
    )  # fmt: skip


@needs_euroc
def test_a_real_recordings_world_with_y_up_is_read_as_with_z_up(tmp_path: Path) -> None:
    """EuRoC's V1_02 written with its world's up along +y (a motion capture's frame, turned by scipy's
    Rotation): read turned back by 90° and said so; its reference is the z-up file's to 1e-9."""
    path = tmp_path / "V1_02_medium.npz"
    np.savez(path, **dict(np.load(EUROC / "V1_02_medium.npz")))
    _world_turned(path, Rotation.from_euler("x", -90, degrees=True))
    rec = io.read(path)
    assert any("up lies along +y" in note and "turned by 90° about +x" in note for note in rec.notes)
    want, got = io.read(EUROC / "V1_02_medium.npz").truth, rec.truth
    angle = (Rotation.from_quat(want.q_nb).inv() * Rotation.from_quat(got.q_nb)).magnitude()
    assert angle.max() < 1e-9
    np.testing.assert_allclose(got.v_n, want.v_n, atol=1e-9)
    np.testing.assert_allclose(got.lat, want.lat, atol=1e-14)


@pytest.mark.parametrize("lag_s", [0.0, 0.0031, 0.020, -0.0125])
def test_inspect_says_how_the_references_clock_sits_and_names_it_from_5_ms(
    tmp_path: Path, lag_s: float
) -> None:
    """The reference stamped late or early by a known shift (the swing's attitude, analytic, at ``t -
    lag``): the shift at which its turns agree best with the gyro's is that lag within 0.3 ms (a
    twentieth of the readings' 5 ms interval, refined between them), and a likely mistake from 5 ms
    (3.1 ms is said, not named); its sign tells a lagging clock from a leading one."""
    path = tmp_path / "swing.npz"
    _swinging(path, lag_s=lag_s)
    found = inspection.inspect(io.read(path))
    assert found.reference_lag is not None
    assert found.reference_lag.lag_s == pytest.approx(lag_s, abs=3e-4)
    codes = [f.code for f in found.findings]
    if abs(lag_s) < 0.005:
        assert codes == [], found.findings
    else:
        assert codes == ["reference_lag"], found.findings
        assert ("lags" if lag_s > 0 else "leads") in found.findings[0].what
        assert f"add {-lag_s:+.4f} s" in found.findings[0].advice
        assert found.reference_lag.agreement > found.reference_lag.as_stamped


def test_the_clock_search_stays_within_the_reference() -> None:
    """Readings at the middles of a 50 Hz reference's steps (as fits and diagnoses compare them): their
    interval's median is a hair under 20 ms, 0.25 s of it 12.5000000000003 steps, and rounding to 13
    steps shifted the first interval to -0.01 s, before the reference, where ``sins fit`` ended in a
    ValueError (found by tests/test_fuzz_safety.py). The swing's attitude is exact: no lag."""
    from sins.core.series import NavSeries
    from sins.io import frame_check

    t_ref = np.arange(1101) * 0.02
    t = 0.5 * (t_ref[:-1] + t_ref[1:])
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    q = Rotation.from_rotvec(np.outer(0.8 * np.sin(2 * np.pi * t_ref / 3.0), axis)).as_quat()
    zeros = np.zeros(len(t_ref))
    truth = NavSeries(t=t_ref, lat=zeros, lon=zeros, h=zeros, v_n=np.zeros((len(t_ref), 3)), q_nb=q)
    rate = np.outer(0.8 * 2 * np.pi / 3.0 * np.cos(2 * np.pi * t / 3.0), axis)
    lag = frame_check.reference_lag(truth, t, rate)
    assert lag is not None and abs(lag.lag_s) < 1e-4, lag


@pytest.mark.parametrize(
    ("key", "factor", "alone", "said"),
    [("gyro_rad_s", np.degrees(1.0), "gyro_range", "57.3 × the reference's: readings in degrees"),
     ("accel_m_s2", 1 / 9.81, None, "× gravity: readings in g read as m/s²"),
     ("gyro_rad_s", 2.0, None, "2 × the reference's; check the gyro's unit"),
     ("accel_m_s2", 1.6, None, "× gravity; check the accelerometer's unit"),
     ("gyro_rad_s", 1.2, None, None), ("accel_m_s2", 0.8, None, None)],
)  # fmt: skip
def test_readings_of_another_size_than_the_reference_are_refused_by_what_judges_against_it(
    tmp_path: Path, key: str, factor: float, alone: str | None, said: str | None
) -> None:
    """The swing's gyro or accelerometer readings multiplied by ``factor``: in degrees (57.3), in g
    (1/9.81), or 2 and 1.6 times, which no unit's scale error reaches (50 % either way is the bound).
    What judges against the reference refuses them in one line: the gyro's turns against the
    reference's, the specific force's mean in the world against gravity's (before, a gyro in degrees
    was fitted until "gyro bias x ... moved to 8.79e+04 °/h: the fit is unstable"). ``sins inspect``
    names the mistake once: where the readings alone show it (a gyro beyond any range), theirs, which
    says what to pass; the swing has no rest at which |f| would show the g. Scale errors of 20 % pass."""
    path = tmp_path / "swing.npz"
    _swinging(path)
    doc = dict(np.load(path))
    np.savez(path, **{**doc, key: doc[key] * factor})
    codes = [f.code for f in inspection.inspect(io.read(path)).findings]
    if said is None:
        assert codes == []
        io.read(path).beside_reference()
        return
    assert codes == [alone or ("reference_gyro_scale" if key.startswith("gyro") else "reference_accel_scale")]
    refusal(lambda: io.read(path).beside_reference(), str(path), *said.split("; "))


def _flying(path: Path) -> dict[str, np.ndarray]:
    """Twenty seconds of a unit turning at a constant rate about a tilted axis while it moves about a
    room (positions of sines, up to 0.5 m: accelerations up to 1.2 m/s²), its readings exact: the rate
    in its axes, the acceleration less gravity's pull (9.81 m/s², z up) turned into them."""
    t = np.arange(4000) / 200.0
    w_b = np.array([0.05, -0.03, 0.2])
    q = Rotation.from_euler("x", 0.2) * Rotation.from_rotvec(np.outer(t, w_b))
    k = 2 * np.pi / np.array([4.0, 5.0, 3.0])
    amp, phase = np.array([0.5, 0.4, 0.1]), np.array([0.0, 1.0, 2.0])
    p = amp * np.sin(np.outer(t, k) + phase)
    v = amp * k * np.cos(np.outer(t, k) + phase)
    a = -amp * k**2 * np.sin(np.outer(t, k) + phase)
    return _write(
        path, n=4000, t_s=t, gyro_rad_s=np.tile(w_b, (4000, 1)),
        accel_m_s2=q.inv().apply(a + np.array([0.0, 0.0, 9.81])), q_wxyz=q.as_quat(scalar_first=True),
        v_m_s=v, p_m=p,
    )  # fmt: skip


def test_velocities_that_lag_their_positions_are_read_on_the_positions_clock(tmp_path: Path) -> None:
    """Numpy's moving unit with its velocities a backward difference of its positions, the first row
    zero, as the published preprocessing for learned gyro correction writes a motion capture's (half a
    step late: 2.5 ms at 200 Hz): read on the positions' clock, within the central difference's own
    error (amp k³ dt²/6: 1e-5 m/s here) of the exact velocities, and said; the lag measured against
    numpy's gradient of the positions within 1 %. The exact velocities are read as written, nothing
    said. A lag of the velocities alone reads as the accelerometer's time offset in a fit and a
    diagnosis (2.5 ms moved EuRoC's V1_02's fitted offset from 1.9 to 0.0 ms)."""
    exact = _flying(tmp_path / "exact.npz")
    t, p = exact["t_s"], exact["p_m"]
    late = np.zeros_like(p)
    late[1:] = np.diff(p, axis=0) / np.diff(t)[:, None]
    _write(tmp_path / "late.npz", **{**exact, "v_m_s": late})
    tau, share = local.velocity_lag_s(t, late, p)
    assert tau == pytest.approx(0.0025, rel=0.01) and share > 0.9  # its zero first row explains the rest
    read_exact, read_late = io.read(tmp_path / "exact.npz"), io.read(tmp_path / "late.npz")
    assert not any("positions' clock" in n for n in read_exact.notes), read_exact.notes
    assert any("velocities lag its positions by 2.50 ms" in n for n in read_late.notes), read_late.notes
    assert read_exact.truth is not None and read_late.truth is not None
    v_exact, v_late = read_exact.truth.v_n[1:-1], read_late.truth.v_n[1:-1]
    np.testing.assert_allclose(v_late, v_exact, rtol=0, atol=1e-4)
    assert np.abs(late[1:-1] - exact["v_m_s"][1:-1]).max() > 1e-3  # as written, they were not
    # A lag below the threshold, or one that explains little of the difference (noise), is left as read.
    assert local.on_positions_clock(t, exact["v_m_s"], p)[1] == ""
    noisy = exact["v_m_s"] + np.random.default_rng(1).normal(0.0, 0.05, exact["v_m_s"].shape)
    assert local.on_positions_clock(t, noisy, p)[1] == ""


@pytest.mark.parametrize(
    ("change", "code", "said"),
    [
        (lambda d: {}, None, None),
        # Before each of these was fitted: lever arms of metres, a model written without a word.
        (lambda d: {"accel_m_s2": -d["accel_m_s2"]}, "reference_force", "reads against the motion"),
        (lambda d: {"v_m_s": 0 * d["v_m_s"]}, "reference_velocity", "integrate to 0 m"),
        (lambda d: {"p_m": 1000 * d["p_m"]}, "reference_velocity", "positions move"),
        (
            lambda d: {"gyro_rad_s": d["gyro_rad_s"] * [1, 0, 1]},
            "dead_channel",
            "gyro's y reads 0 on every one",
        ),
    ],
    ids=["as written", "accelerometer negated", "velocity zero", "positions in mm", "dead gyro axis"],
)
def test_a_reference_that_contradicts_the_readings_or_itself_is_refused(
    tmp_path: Path, change: Any, code: str | None, said: str | None
) -> None:
    """Numpy's moving unit with one thing wrong: what judges against the reference refuses it in one
    line and ``sins inspect`` names it. A negated accelerometer shows gravity's reaction pointing down,
    as a world written with z down does (the reader turns it up); only its horizontal force, which runs
    against the reference's acceleration (correlation -1), tells them apart."""
    path = tmp_path / "fly.npz"
    doc = _flying(path)
    np.savez(path, **{**doc, **change(doc)})
    if code is None:
        assert not inspection.inspect(io.read(path)).findings
        io.read(path).beside_reference()
        return
    assert [f.code for f in inspection.inspect(io.read(path)).findings] == [code]
    refusal(lambda: io.read(path).beside_reference(), str(path), said)


@needs_euroc
def test_a_clipped_or_negated_gyro_is_not_blamed_on_the_reference(tmp_path: Path) -> None:
    """EuRoC's V1_02 with its gyro clipped at ±0.3 rad/s, and negated (numpy): both turn away from the
    reference's turns. Clipped, it was refused as a quaternion of the wrong order (correlation 0.90); now
    the refusal names the clipped axis, its level and how many readings sit there. Negated (correlation
    −1.00), it says the gyro may read every turn negated, beside the reference's advice."""
    with np.load(EUROC / "V1_02_medium.npz") as held:
        doc = dict(held)
    for name, gyro, said in [
        ("clipped", np.clip(doc["gyro_rad_s"], -0.3, 0.3), "clipped at the sensor's range"),
        ("negated", -doc["gyro_rad_s"], "or the gyro reads every turn negated"),
    ]:
        path = tmp_path / f"{name}.npz"
        np.savez(path, **{**doc, "gyro_rad_s": gyro})
        refusal(lambda p=path: io.read(p).beside_reference(), str(path), said)


@needs_euroc
def test_a_constant_reference_and_swapped_columns_are_named_as_such(tmp_path: Path) -> None:
    """EuRoC's V1_02 (its first 30 s) with a reference that never turns, and with the gyro's and the
    accelerometer's columns swapped (numpy): both were refused as a quaternion of the wrong order (a new
    user's walk); now each refusal says what it is."""
    with np.load(EUROC / "V1_02_medium.npz") as held:
        doc = {k: v[:6000] for k, v in held.items()}
    for name, change, said in [
        ("constant", {"q_wxyz": doc["q_wxyz"][:1].repeat(6000, 0)}, "the reference barely turns"),
        ("swapped", {"gyro_rad_s": doc["accel_m_s2"], "accel_m_s2": doc["gyro_rad_s"]}, "look swapped"),
    ]:
        path = tmp_path / f"{name}.npz"
        np.savez(path, **{**doc, **change})
        refusal(lambda p=path: io.read(p).beside_reference(), str(path), said)


def test_a_time_column_in_another_unit_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The swing's time written in ns, read as s: its readings 5e6 s apart, no IMU's rate; and in
    units of 1e-300 s. Every command refuses it when it is read, naming the time's unit (the clock
    search had said the reference's clock lagged 5,000,000,000 ms; steps of 1e-300 s were integrated
    without a word, and ``sins characterise`` failed inside scipy's splines). In ms read as s (0.2 Hz
    here, a slow logger's rate) it is read, and ``sins inspect`` names the unit."""
    path = tmp_path / "swing.npz"
    _swinging(path)
    doc = dict(np.load(path))
    for scale, said in ((1e9, r"every 5e\+06 s \(2e-07 Hz\), no IMU's rate"), (1e-298, r"\(2e\+300 Hz\)")):
        np.savez(path, **{**doc, "t_s": doc["t_s"] * scale})
        with pytest.raises(SinsInputError, match=rf"^{path}: one reading .*{said}.*time column's unit$"):
            io.read(path)
        for command in ("integrate", "characterise"):
            assert main([command, str(path)]) == 2
            err = capsys.readouterr().err
            assert err.count("\n") == 1 and "time column's unit" in err, err
    np.savez(path, **{**doc, "t_s": doc["t_s"] * 1e3})
    found = inspection.inspect(io.read(path))
    assert found.reference_lag is None
    assert [f.code for f in found.findings] == ["time_unit"], found.findings


@needs_euroc
def test_euroc_references_sit_on_the_readings_clock() -> None:
    """EuRoC's references are the dataset's ground-truth estimate (laser tracker or Vicon fused with
    these readings), interpolated onto the IMU's stamps (SOURCE.md): every one sits on the readings'
    clock within the 5 ms from which a lag is named (measured: 0.4 ms or less, V2_03 2.5 ms), none named."""
    for name in sorted(p.stem for p in EUROC.glob("*.npz")):
        found = inspection.inspect(io.read(EUROC / f"{name}.npz"))
        assert found.reference_lag is not None and abs(found.reference_lag.lag_s) < REFERENCE_LAG_S, name
        assert "reference_lag" not in [f.code for f in found.findings], name


def test_readings_alone(tmp_path: Path) -> None:
    """Readings without a reference, as a path and as a data root's ``FOLDER/NAME`` alike: read and
    inspected (before, the name was refused as "no reference", the path read); what needs a reference
    says so when it asks for one."""
    (tmp_path / "unit").mkdir()
    path = tmp_path / "unit" / "imu.npz"
    _write(path, q_wxyz=None, v_m_s=None, p_m=None)
    for rec in (io.read(path), io.read(dataset="unit/imu", root=tmp_path)):
        assert rec.truth is None and len(rec.imu) == 400
        inspection.inspect(rec)
        refusal(rec.beside_reference, "no reference")


@pytest.mark.parametrize(
    ("changes", "fragments"),
    [
        ({"gyro_rad_s": None}, ("no key 'gyro_rad_s'",)),
        ({"v_m_s": None}, ("has 'q_wxyz' but no 'v_m_s'",)),
        ({"accel_m_s2": np.zeros((399, 3))}, ("accel_m_s2 has 399 rows; t_s has 400",)),
        ({"gyro_rad_s": np.zeros((400, 2))}, ("gyro_rad_s has shape (400, 2)",)),
        (
            {"t_s": np.r_[np.arange(200) / 200.0, np.arange(200) / 200.0]},
            ("t_s: row 201", "does not increase"),
        ),
        (
            {"accel_m_s2": np.where(np.arange(1200).reshape(400, 3) == 31, np.nan, 9.0)},
            ("accel_m_s2: row 11",),
        ),
        ({"gyro_rad_s": np.full((400, 3), 1e9)}, ("gyro_rad_s: row 1", "beyond")),
        ({"q_wxyz": np.tile([2.0, 0, 0, 0], (400, 1))}, ("q_wxyz: row 1 has norm 2",)),
        ({"t_s": np.array(["a"] * 400)}, ("t_s holds",)),
        # Absolute stamps in float32 (as EuRoC's readings are): 128 s apart at 1.4e9 s.
        (
            {"t_s": (1.4e9 + np.arange(400) / 200.0).astype(np.float32)},
            ("t_s is float32, whose steps at 1.4e+09 s are 128 s", "write t_s as float64"),
        ),
    ],
)
def test_bad_files_are_refused_naming_the_file_and_key(
    tmp_path: Path, changes: dict[str, object], fragments: tuple[str, ...]
) -> None:
    path = tmp_path / "bad.npz"
    _write(path, **changes)
    message = refusal(lambda: io.read(path), str(path), *fragments)
    # What is wrong with a key is said once, as it is: not as an unreadable archive, not in numpy's repr.
    assert "not a readable" not in message and "np.float64" not in message and message.count(str(path)) == 1


def test_keys_not_of_the_form_are_said_not_read(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A magnetometer beside the form's keys: read as the form says, the rest named in the notes (nothing
    is dropped silently), by its path and as a data root's FOLDER/NAME alike (whose notes were dropped:
    ``sins inspect --dataset`` said nothing of them)."""
    path = tmp_path / "unit" / "rec.npz"
    path.parent.mkdir()
    _write(path, mag_uT=np.zeros((400, 3)), temp_c=np.zeros(400))
    assert f"{path}: not read (not of the form): mag_uT, temp_c" in io.read(path).notes
    monkeypatch.setenv("SINS_DATA", str(tmp_path))
    assert f"{path}: not read (not of the form): mag_uT, temp_c" in io.read(dataset="unit/rec").notes
    _write(path)
    assert not any("not read" in note for note in io.read(path).notes)


def test_a_reference_beyond_a_room_is_named_by_row_and_column(tmp_path: Path) -> None:
    """Positions within 1e6 m and speeds within 1e3 m/s (a room frame's), each refused beyond by its row
    and column, as a EuRoC folder's reference is by its line (``sins.io.formats.first_beyond``)."""
    path = tmp_path / "far.npz"
    cases = (
        ("p_m", (7, 1), 2e6, "p_m: row 8, column 2: 2e+06 m is beyond ±1e+06"),
        ("v_m_s", (3, 2), -5e3, "v_m_s: row 4, column 3: -5000 m/s is beyond ±1000"),
    )
    for key, at, value, said in cases:
        values = np.zeros((400, 3))
        values[at] = value
        _write(path, **{key: values})
        refusal(lambda: io.read(path), str(path), said)


def test_an_archive_that_lies_about_its_members_is_refused_before_it_is_read(tmp_path: Path) -> None:
    """A member's header claims the array's shape; numpy allocates it before reading. A 20 kB file whose
    t_s claimed 1e12 rows had asked for 7 TiB (a MemoryError's traceback), and one claiming (400, 300)
    more than its member holds; a member flagged encrypted raised RuntimeError. Each is one line now."""
    import io as bytes_io
    import zipfile

    good = _write(tmp_path / "good.npz")
    for key, shape, said in (
        ("t_s", (10**12,), "t_s has 1000000000000 rows; sins reads at most"),
        ("gyro_rad_s", (400, 300), "gyro_rad_s's header claims shape (400, 300) (480000 bytes); the member"),
    ):  # fmt: skip
        path = tmp_path / f"{key}.npz"
        with zipfile.ZipFile(path, "w") as archive:
            for name, value in good.items():
                member = bytes_io.BytesIO()
                if name == key:
                    header = {"descr": value.dtype.str, "fortran_order": False, "shape": shape}
                    np.lib.format.write_array_header_1_0(member, header)
                    member.write(value.tobytes())
                else:
                    np.save(member, value)
                archive.writestr(f"{name}.npy", member.getvalue())
        refusal(lambda p=path: io.read(p), str(path), said)
    locked = bytearray((tmp_path / "good.npz").read_bytes())
    for signature, flags_at in ((b"PK\x03\x04", 6), (b"PK\x01\x02", 8)):  # the local and central headers
        at = locked.find(signature) + flags_at
        locked[at] |= 1  # bit 0 of the general-purpose flags: encrypted
    path = tmp_path / "locked.npz"
    path.write_bytes(bytes(locked))
    refusal(lambda: io.read(path), str(path), "not a readable .npz archive", "password required")


def test_not_an_archive(tmp_path: Path) -> None:
    path = tmp_path / "x.npz"
    path.write_bytes(b"PK\x03\x04 not really a zip")
    # A zip's first bytes, then nothing a zip holds: refused as the damaged archive it is, in one line.
    refusal(lambda: io.read(path), str(path), "not a readable .npz archive")
    # Cut short (an interrupted copy): the same, not read as a CSV that is "not UTF-8" (before).
    good = tmp_path / "good.npz"
    _write(good)
    path.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    message = refusal(lambda: io.read(path), str(path), "not a readable .npz archive")
    assert "UTF-8" not in message
    # Not a zip at all: named as an archive, and not read as a CSV (an empty file, or CSV text that an
    # older sins correct wrote under an .npz name, which it read as a recording before).
    not_zip = "its first bytes are not a zip archive's"
    for content, why in ((b"\x00\x01 binary", not_zip), (b"", "it is empty"), (b"t,gyro_x\n0,1\n", not_zip)):
        path.write_bytes(content)
        refusal(lambda: io.read(path), str(path), f"named as a NumPy archive, but {why}; not read as a CSV")


def test_dataset_names_and_a_missing_one(tmp_path: Path) -> None:
    (tmp_path / "unit").mkdir()
    _write(tmp_path / "unit" / "a.npz")
    assert "unit/a" in datasets.names(tmp_path)
    rec = io.read(dataset="unit/a", root=tmp_path).beside_reference()
    assert rec.sensor == "unit" and not rec.latitude_known
    refusal(lambda: io.read(dataset="unit/b", root=tmp_path).beside_reference(), "unit/b.npz", "no such file")
    refusal(lambda: io.read(dataset="unit/../x", root=tmp_path).beside_reference(), "expected FOLDER/NAME")
    # The file's name given for the dataset's: said so (before: no such file unit/a.npz.npz).
    refusal(lambda: io.read(dataset="unit/a.npz", root=tmp_path), "the name without .npz (unit/a)")
    # The library's refusals name its arguments, not the command line's flags (they had said --dataset).
    with pytest.raises(ValueError, match=r"^dataset 'unit/a\.npz'"):
        io.read(dataset="unit/a.npz", root=tmp_path)


def test_an_origin_not_in_radians_or_not_three_numbers_is_refused(tmp_path: Path) -> None:
    # The library takes the origin in radians (the command line in degrees): (45, 7, 100) given in degrees
    # had placed the room at 58.3° N (45 rad), NaN made every latitude NaN, and two numbers failed in
    # numpy's words.
    (tmp_path / "unit").mkdir()
    _write(tmp_path / "unit" / "a.npz")
    for origin, said in [((45.0, 7.0, 100.0), "in radians"), ((np.nan, 0.0, 0.0), "in radians"),
                         ((0.7, 0.1), "expected (lat, lon, h)")]:  # fmt: skip
        refusal(lambda o=origin: io.read(dataset="unit/a", root=tmp_path, origin=o), "origin", said)
    rec = io.read(dataset="unit/a", root=tmp_path, origin=(np.radians(47.4), np.radians(8.5), 400.0))
    assert rec.beside_reference().latitude_known


def test_the_room_is_placed_at_45_degrees_or_where_given(tmp_path: Path) -> None:
    """Without a place, the room lies at 45° N, 0 m: normal gravity 9.8062 m/s² there (Somigliana's
    formula, WGS84), within 0.026 m/s² of any site's at sea level. ``origin`` places it, by path and as
    ``FOLDER/NAME`` alike; a named dataset, whose reader knows its place, refuses it."""
    (tmp_path / "unit").mkdir()
    path = tmp_path / "unit" / "a.npz"
    _write(path)
    nominal = io.read(path).truth
    assert np.degrees(nominal.lat[0]) == pytest.approx(45.0) and nominal.h[0] == pytest.approx(0.0, abs=1e-6)
    gamma = 9.7803253359 * (1 + 0.00193185265241 * 0.5) / np.sqrt(1 - 0.00669437999013 * 0.5)
    assert earth.normal_gravity(nominal.lat[0], nominal.h[0]) == pytest.approx(gamma, abs=1e-9)
    zurich = (np.radians(47.37), np.radians(8.55), 400.0)
    for rec in (io.read(path, origin=zurich), io.read(dataset="unit/a", root=tmp_path, origin=zurich)):
        assert rec.latitude_known and not rec.heading_known
        assert np.degrees(rec.truth.lat[0]) == pytest.approx(47.37) and rec.truth.h[0] == pytest.approx(400.0)
    refusal(lambda: io.read(dataset="unit/a", root=tmp_path, frame="flu"), "frame does not apply", "origin")


def test_earth_rate_is_left_out_where_the_latitude_is_unknown(tmp_path: Path) -> None:
    """A noise-free unit turning at a constant rate, its frame of unknown latitude: the open loop of the
    exact readings holds the reference to the integration's own error, with no Earth rate put in."""
    (tmp_path / "unit").mkdir()
    n = 2000
    t = np.arange(n) / 200.0
    q = Rotation.from_rotvec(np.outer(t, [0.0, 0.0, 0.3]))
    np.savez(
        tmp_path / "unit" / "exact.npz", t_s=t, gyro_rad_s=np.tile([0.0, 0.0, 0.3], (n, 1)),
        accel_m_s2=np.tile([0.0, 0.0, 9.81], (n, 1)), q_wxyz=q.as_quat(scalar_first=True),
        v_m_s=np.zeros((n, 3)), p_m=np.zeros((n, 3)),
    )  # fmt: skip
    rec = io.read(dataset="unit/exact", root=tmp_path).beside_reference()
    # Earth's rate (7.3e-5 rad/s) over 10 s would leave 0.04°; the exact readings leave rounding.
    assert judging.open_loop_attitude(None, rec).total_deg < 1e-6


@needs_euroc
@pytest.mark.parametrize(("name", "published"), [("MH_04_difficult", 130.3), ("V1_01_easy", 114.1)])
def test_raw_open_loop_matches_source_md(name: str, published: float) -> None:
    """SOURCE.md's raw figures come from an independent scipy integration (rectangle rule, nothing
    fitted); sins integrates the trapezoid increments: the same within 1 %."""
    rec = io.read(dataset=f"euroc/{name}").beside_reference()
    assert judging.open_loop_attitude(None, rec).total_deg == pytest.approx(published, rel=0.01)


@pytest.fixture(scope="module")
def unit_root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A data root with one numpy unit's three recordings in the .npz form, and a model fitted on two."""
    from numpy_units import recordings, write_npz

    root = tmp_path_factory.mktemp("data")
    (root / "unit").mkdir()
    recs, _, _ = recordings(12)
    for k, rec in enumerate(recs):
        write_npz(root / "unit", f"r{k}", rec)
    fitted = referenced.fit_several("regression", recs[:2], rule_mode="pooled")
    from sins import compensation

    compensation.save(fitted.strategy, root / "model.json")
    return root


@pytest.mark.parametrize(
    "argv",
    [
        ["fit", "{npz}", "--strategy", "regression", "--out", "{out}/m.json"],
        ["evaluate", "{root}/model.json", "{npz}", "--json", "{out}/e.json"],
        ["correct", "{root}/model.json", "{npz}", "--out", "{out}/c.csv"],
        ["inspect", "{npz}", "--json", "{out}/i.json"],
        ["inspect", "--dataset", "unit/r2"],
        ["integrate", "{npz}", "--out", "{out}/sol.csv"],
        ["integrate", "--dataset", "unit/r2", "--out", "{out}/sol.csv"],
        ["characterise", "{npz}", "--out", "{out}/imu.toml"],
        ["characterise", "--dataset", "unit/r2", "--out", "{out}/imu.toml"],
    ],
    ids=lambda a: " ".join(a[:2]),
)
def test_every_command_reads_an_npz_recording(
    argv: list[str], unit_root: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    """By its path and, where a command takes one, as --dataset FOLDER/NAME; each writes what it says
    (``correct``: the readings only, and that its reference is not in them)."""
    from sins.cli import main

    monkeypatch.setenv("SINS_DATA", str(unit_root))
    fill = {"npz": str(unit_root / "unit" / "r2.npz"), "root": str(unit_root), "out": str(tmp_path)}
    assert main([a.format(**fill) for a in argv]) == 0
    if argv[0] == "correct":
        assert "; the readings only, not its reference" in capsys.readouterr().out
    for a in argv:
        if "{out}" in a:
            assert Path(a.format(**fill)).is_file()


def test_a_euroc_folders_world_with_y_up_is_read_as_with_z_up(tmp_path: Path) -> None:
    """The EuRoC/TUM-VI folder reader turns a y-up room as the .npz reader does: a numpy unit's recording
    (tests/numpy_unit_gap.py) written as two EuRoC folders, one with its world's up along +y, reads back
    the same reference to 1e-9 (its poses at their own stamps, gravity judged from the readings there)."""
    arrays = nu.recording(3, duration_s=30.0)
    turn = Rotation.from_euler("x", -90, degrees=True)
    q = turn * Rotation.from_quat(arrays["q_wxyz"], scalar_first=True)
    turned = {**arrays, "q_wxyz": q.as_quat(scalar_first=True), "v_m_s": turn.apply(arrays["v_m_s"]),
              "p_m": turn.apply(arrays["p_m"])}  # fmt: skip
    upright = io.read(nu.write_euroc(tmp_path / "z_up", arrays))
    read = io.read(nu.write_euroc(tmp_path / "y_up", turned))
    assert any("up lies along +y" in note and "turned by 90° about +x" in note for note in read.notes)
    assert not any("up lies along" in note for note in upright.notes)
    want, got = upright.truth, read.truth
    angle = (Rotation.from_quat(want.q_nb).inv() * Rotation.from_quat(got.q_nb)).magnitude()
    assert angle.max() < 1e-9
    np.testing.assert_allclose(got.v_n, want.v_n, atol=1e-9)
    assert not inspection.inspect(read).findings


def test_corrected_readings_keep_the_stamp_their_times_count_from(
    unit_root: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An .npz stamped in Unix seconds is read from its first stamp; ``sins correct`` writes that stamp
    (``# time origin: N ns``), by path and by ``--dataset``, and the CSV reads back with it: every row's
    stamp is the original's (within 1 µs, what float64 seconds hold at 1.4e9 s). Without stamps (the
    numpy recording as written, from 0 s) the origin is 0."""
    from sins.cli import main
    from sins.io import provenance

    arrays = dict(np.load(unit_root / "unit" / "r2.npz"))
    stamps = 1.4e9 + arrays["t_s"]
    np.savez(unit_root / "unit" / "r2_stamped.npz", **{**arrays, "t_s": stamps})
    monkeypatch.setenv("SINS_DATA", str(unit_root))
    origin = round(float(stamps[0]) * 1e9)
    for name, given in (
        ("path.csv", [str(unit_root / "unit" / "r2_stamped.npz")]),
        ("dataset.csv", ["--dataset", "unit/r2_stamped"]),
    ):
        out = tmp_path / name
        assert main(["correct", str(unit_root / "model.json"), *given, "--out", str(out)]) == 0
        assert f"# time origin: {origin} ns" in out.read_text().splitlines()[:6]
        back = io.read(out)
        assert back.t0_ns == origin
        stamped = back.t0_ns * 1e-9 + back.imu.t
        np.testing.assert_allclose(stamped, stamps[: len(stamped)], rtol=0, atol=1e-6)
    plain = tmp_path / "plain.csv"
    assert main(["correct", str(unit_root / "model.json"), "--dataset", "unit/r2", "--out", str(plain)]) == 0
    assert io.read(plain).t0_ns == 0
    # A line that is no whole number of ns is no origin.
    bad = tmp_path / "bad.csv"
    for line in ("# time origin: 1.5e9 s", "# time origin: --5 ns", "# time origin: 12 34 ns"):
        bad.write_text(plain.read_text().replace("# time origin: 0 ns", line))
        said = provenance.read_provenance(bad)
        assert said.t0_ns is None and said.corrected_by, (line, said)


def test_marks_know_a_part_of_readings_wherever_it_is_cut() -> None:
    # Content-defined marks (sins.io.provenance.readings_marks): a part cut anywhere from readings holds
    # their marks of that part, all of them, so its share in the whole is 1; readings drawn apart share
    # none; about one window in MARK_EVERY is a mark (random readings: binomial, within 4 sigma).
    from sins.io import provenance

    rng = np.random.default_rng(7)
    gyro, accel = rng.normal(size=(60_000, 3)), rng.normal(size=(60_000, 3))
    whole = provenance.readings_marks(gyro, accel)
    expected = (60_000 - provenance.MARK_ROWS + 1) / provenance.MARK_EVERY
    assert abs(len(whole) - expected) < 4 * np.sqrt(expected)
    for start, stop in ((0, 20_000), (12_345, 51_001), (7, 59_990)):
        part = provenance.readings_marks(gyro[start:stop], accel[start:stop])
        assert set(part) <= set(whole) and provenance.shared_share(part, [whole]) == 1.0
    other = provenance.readings_marks(rng.normal(size=(20_000, 3)), rng.normal(size=(20_000, 3)))
    assert provenance.shared_share(other, [whole]) == 0.0
    # One reading changed by one bit: the windows over it are new, the others are kept.
    nudged = gyro.copy()
    nudged[30_000, 0] = np.nextafter(nudged[30_000, 0], np.inf)
    changed = set(whole) ^ set(provenance.readings_marks(nudged, accel))
    assert len(changed) <= 2 * provenance.MARK_ROWS
    # Too short to tell: no share, not a share of 0.
    assert provenance.shared_share(provenance.readings_marks(gyro[:200], accel[:200]), [whole]) is None


def test_a_reference_that_never_turns_beside_a_turning_gyro_is_found_without_a_numpy_warning() -> None:
    # A reference held at one attitude beside a gyro swinging at 0.5 rad/s: the turns' correlation was
    # 0/0, NaN with numpy's "invalid value encountered"; it is no agreement (0), and the finding says the
    # reference barely turns.
    from sins.io.frame_check import reference_findings

    t = np.arange(0.0, 20.0, 0.005)
    zero, rng = np.zeros(len(t)), np.random.default_rng(2)
    still = NavSeries(t=t, lat=zero + 0.8, lon=zero, h=zero, v_n=np.zeros((len(t), 3)),
                      q_nb=np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1)))  # fmt: skip
    w = np.outer(0.5 * np.sin(2.0 * np.pi * t / 4.0), [0.0, 0.0, 1.0]) + rng.normal(0, 1e-3, (len(t), 3))
    f = np.tile([0.0, 0.0, -9.81], (len(t), 1)) + rng.normal(0, 1e-2, (len(t), 3))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        found = reference_findings(still, t, w, f)
    assert [x.code for x in found] == ["reference_attitude"] and "barely turns" in found[0].what, found


def test_an_npz_integrates_alike_by_its_path_and_as_a_dataset(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """By its path the readings' rates are integrated to increments (four-point quadrature); as
    ``--dataset FOLDER/NAME`` they had been the referenced form's trapezoid increments: EuRoC's V1_02 ended
    24,113.9 m off its reference one way and 24,115.1 m the other. Now one integration, to the bit; the
    fits still take the referenced form (``on_reference``)."""
    import json

    path = tmp_path / "unit" / "rec.npz"
    path.parent.mkdir()
    # Stamps from 0, uniform to the bit (1.4e9 s stamps jitter beyond the quadrature's 1 ppm: trapezoid)
    _write(path, n=2000, t_s=np.arange(2000) / 200.0)
    monkeypatch.setenv("SINS_DATA", str(tmp_path))
    summaries = []
    for how, out in ((["--dataset", "unit/rec"], "a.json"), ([str(path)], "b.json")):
        assert main(["integrate", *how, "--json", str(tmp_path / out)]) == 0
        doc = json.loads((tmp_path / out).read_text())
        summaries.append({k: v for k, v in doc.items() if k not in ("imu", "sins")})
    capsys.readouterr()
    assert summaries[0] == summaries[1]
    rec = io.read(dataset="unit/rec")
    assert rec.on_reference is not None and rec.on_reference.imu.t[0] == rec.imu.t[0]


@needs_euroc
def test_a_drive_where_the_reference_pitches_steeply_reads_its_angle() -> None:
    """EuRoC's body x points up, so its reference's pitch lies near -90° (MH_01 reaches 74° in 10-60 s):
    roll and yaw errors grow and cancel there (a helper read roll 9.2° and yaw 10.7° RMS beside an angle
    of 4.1°). The drive's table carries the angle (the JSON's ``attitude_angle_rms_deg``), and the pitch
    is said, checked here against scipy's Euler angles of the reference."""
    from sins import compensation
    from sins.compensation import evaluation

    rec = io.read(dataset="euroc/MH_01_easy", root=EUROC.parent).beside_reference()
    rec = judging.between(rec, 10.0, 30.0)
    result = evaluation.evaluate_referenced(compensation.make("none"), rec, "MH_01", drive=(12.0, 28.0))
    text = "\n".join(result.lines)
    inside = (rec.reference.t >= 12.0) & (rec.reference.t <= 28.0)
    pitch = Rotation.from_quat(rec.reference.q_nb[inside]).as_euler("ZYX", degrees=True)[:, 1]
    assert f"the reference pitches to {np.max(np.abs(pitch)):.0f}° here" in text, text
    assert np.max(np.abs(pitch)) > evaluation.STEEP_PITCH_DEG
    drive = result.to_dict()["drive"]["none (raw readings)"]
    assert "angle °" in text and f"{drive['attitude_angle_rms_deg']:.4f}" in text
