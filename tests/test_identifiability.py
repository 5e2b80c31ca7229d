"""What a recording determines, and the bounds a fitted model is held to before it is written
(sins.compensation.identifiability, ``sins fit``): judged against units whose coefficients are known
(sins's own simulated units, drawn from their grade), against an exact linear design, and on real data.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import refusal
from test_fuzz import run_cli, to_toml

from sins.compensation import identifiability
from sins.core import earth
from sins.imu import DEG_PER_H, BiasInstability
from sins.imu.spec import GRADES, draw_unit
from sins.io.datasets.root import data_root

STILL: dict[str, object] = {
    "name": "still",
    "imu": {"rate_hz": 100, "model": "tactical", "seed": 1},
    "initial": {"lat_deg": 45.0},
    "segment": [{"type": "hold", "duration_s": 60.0}],
}


def _fit(tmp_path: Path, imu: Path, truth: Path | None, *more: str) -> tuple[int, str, str, dict]:
    out = tmp_path / "m.json"
    argv = ["fit", str(imu), *(["--truth", str(truth)] if truth else []), "--strategy", "regression", "--out",
            str(out), "--json", str(tmp_path / "f.json"), *more]  # fmt: skip
    rc, stdout, err = run_cli(argv)
    document = json.loads((tmp_path / "f.json").read_text()) if rc == 0 else {}
    return rc, stdout, err, document


def _numbers(path: Path) -> np.ndarray:
    """A sins CSV's numbers, read with numpy (its comment lines and header skipped)."""
    lines = path.read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    return np.loadtxt(path, delimiter=",", skiprows=header + 1)


def _coefficients(document: dict) -> dict[tuple[str, str, str], dict]:
    return {(c["sensor"], c["term"], c["axis"]): c for c in document["coefficients"]}


def test_a_still_recording_is_reduced_to_its_biases_which_are_the_units(tmp_path: Path) -> None:
    """60 s at rest against a constant truth: before, ``sins fit`` wrote a gyro scale of 6.55e10 ppm
    (± 19 ppm). Every scale factor, misalignment, g-sensitivity, time offset and the lever arm is held
    at zero with its reason, printed and in the model file; the biases kept are what the unit reads at
    rest beyond its true input (Earth's rate and gravity), the file's means taken with numpy, within
    three standard errors."""
    (tmp_path / "still.toml").write_text(to_toml(STILL))
    imu, truth = tmp_path / "imu.csv", tmp_path / "truth.csv"
    rc, _, err = run_cli(
        ["simulate", str(tmp_path / "still.toml"), "--imu", str(imu), "--truth", str(truth), "--form", "rate"]
    )
    assert rc == 0, err
    rc, out, err, doc = _fit(tmp_path, imu, truth)
    assert rc == 0, err
    held = doc["held"]
    assert set(held) == {
        n for n in (*identifiability.gyro_names(True, True), *identifiability.accel_names(True))
        if ".bias." not in n
    }  # fmt: skip
    assert "held at zero" in out and "not excited" in out and "confounded with accel bias z" in out
    model = json.loads((tmp_path / "m.json").read_text())
    assert set(model["state"]["fitted_on_"]["checks"]["held"]) == set(held)
    # What the unit reads at rest beyond its true input (Earth's rate, gravity), from the file with numpy.
    lat = np.radians(45.0)
    w_ie = np.array([np.cos(lat), 0.0, -np.sin(lat)]) * earth.OMEGA_IE
    f = np.array([0.0, 0.0, -float(earth.normal_gravity(lat, 0.0))])
    readings = _numbers(imu)
    excess = readings[:, 1:7].mean(axis=0) - np.concatenate([w_ie, f])
    expected = np.concatenate([excess[:3] / DEG_PER_H, excess[3:] / (1e-6 * earth.G0)])
    table = _coefficients(doc)
    for i, (sensor, axis) in enumerate((s, a) for s in ("gyro", "accel") for a in "xyz"):
        c = table[sensor, "bias", axis]
        # Three standard errors, not one: the interval fit turns each interval's force by the body's turn
        # in inertial space, leaving out the NED frame's own turn within it, which at rest tilts gravity
        # east by ω_N T/2 (26 µg at 45° N over 1 s intervals; noted for sins.compensation.interval_fit).
        assert abs(c["value"] - expected[i]) < 3.0 * c["se"], (sensor, axis, c, expected[i])
        assert table[sensor, "scale", axis]["value"] == 0.0 and table[sensor, "scale", axis]["se"] is None


def test_the_five_minute_drive_keeps_what_it_determines_and_that_is_the_units(tmp_path: Path) -> None:
    """``sins simulate car_drive_5min`` (a tactical unit, yaw turns on level roads): before, the fit gave
    gyro scale factors of 6e5-1.6e6 ppm. The roll and pitch gyros' scale factors and misalignments, the
    vertical accelerometer's scale factor and the g-sensitivity are held; every coefficient kept is
    within 4.5 standard errors of the simulated unit's own (drawn from the grade: independent of the
    fit; a bias with the mean effect of the terms held beside it, and its bias instability), and within
    the class's bounds."""
    imu, truth = tmp_path / "imu.csv", tmp_path / "truth.csv"
    argv = ["simulate", "car_drive_5min", "--model", "tactical", "--seed", "0"]
    rc, _, err = run_cli([*argv, "--imu", str(imu), "--truth", str(truth)])
    assert rc == 0, err
    rc, _, err, doc = _fit(tmp_path, imu, truth, "--grade", "tactical")
    assert rc == 0, err
    held = set(doc["held"])
    assert {"gyro.scale.x", "gyro.scale.y", "accel.scale.z"} <= held
    assert {f"gyro.g_sensitivity.{r}←z" for r in "xyz"} <= held
    unit = draw_unit("tactical", 1, 0)
    truths = identifiability.seed_values_of_model(unit)
    kept = [c for c in doc["coefficients"] if c["se"] is not None]
    names = {f"{c['sensor']}.{c['term']}.{c['axis']}" for c in kept}
    assert {"gyro.scale.z", "accel.scale.x", "accel.scale.y", *identifiability.bias_names("gyro")} <= names
    # A term held at zero leaves its mean effect to the bias of its channel (the bias's column is the
    # constant one): the unit's own term times the drive's mean input (from the file, with numpy).
    readings = _numbers(imu)
    span = readings[-1, 0] - readings[0, 0] + readings[1, 0] - readings[0, 0]
    mean_in = {"gyro": readings[:, 1:4].sum(axis=0) / span, "accel": readings[:, 4:7].sum(axis=0) / span}
    for name in held:
        sensor, term, axis = name.split(".")
        if term in ("scale", "misalignment", "g_sensitivity"):
            r, c = (axis, axis) if term == "scale" else axis.split("←")
            source = "accel" if term == "g_sensitivity" else sensor
            truths[f"{sensor}.bias.{r}"] += truths[name] * mean_in[source]["xyz".index(c)]
    instability = {e.sensor: float(e.sigma[0]) for e in unit.effects if isinstance(e, BiasInstability)}
    bounds = identifiability.class_bounds("tactical")
    for c in kept:
        name = f"{c['sensor']}.{c['term']}.{c['axis']}"
        value_si = c["value"] * _unit_si(c["unit"])
        se_si = c["se"] * _unit_si(c["unit"])
        # A bias also carries the unit's bias instability over the drive (a Gauss–Markov process of
        # stationary σ, 300 s correlation time: not part of its drawn coefficients).
        wander = instability[c["sensor"]] if c["term"] == "bias" else 0.0
        assert abs(value_si - truths[name]) < 4.5 * np.hypot(se_si, wander), (name, c, truths[name])
        assert abs(value_si) <= bounds.largest(name)


def _unit_si(unit: str) -> float:
    return {
        "°/h": DEG_PER_H,
        "µg": 1e-6 * earth.G0,
        "ppm": 1e-6,
        "mrad": 1e-3,
        "°/h/g": DEG_PER_H / earth.G0,
    }[unit]


@pytest.mark.parametrize("grade", sorted(GRADES))
def test_every_drawn_unit_of_a_grade_is_within_its_class_bounds(grade: str) -> None:
    """The bounds a fit is held to admit the units the grade draws (1,000 of them, every coefficient),
    and the spread that decides what is determined is the grade's own 1σ (its draws' RMS within 10 %)."""
    bounds = identifiability.class_bounds(grade)
    values: dict[str, list[float]] = {}
    for seed in range(1000):
        for name, value in identifiability.seed_values_of_model(draw_unit(grade, seed, seed + 7)).items():
            values.setdefault(name, []).append(value)
    for name, v in values.items():
        assert np.max(np.abs(v)) <= bounds.largest(name), name
        rms = float(np.sqrt(np.mean(np.square(v))))
        assert rms == pytest.approx(bounds.limit(name), rel=0.1), name


def test_determined_holds_the_collinear_and_the_unexcited_and_keeps_the_rest() -> None:
    """An exact linear design: a gyro's three biases, a scale factor the data excite well, one they
    barely excite (its standard error alone beyond the consumer spread) and one equal to a bias column
    (collinear): the weak and the collinear are held, with those reasons, the others kept."""
    rng = np.random.default_rng(3)
    k = 200
    x = np.zeros((k, 3, 6))
    x[:, :, :3] = np.eye(3)  # biases
    x[:, 0, 3] = rng.normal(0.0, 1.0, k)  # x scale: turns of ±1 rad
    x[:, 1, 4] = rng.normal(0.0, 1e-5, k)  # y scale: turns of 10 µrad
    x[:, 2, 5] = 0.3  # z scale: a constant turn, as the bias's column
    y = x @ np.array([1e-4, -2e-4, 3e-4, 1e-3, 0.0, 0.0]) + rng.normal(0.0, 1e-4, (k, 3))
    names = ("gyro.bias.x", "gyro.bias.y", "gyro.bias.z", "gyro.scale.x", "gyro.scale.y", "gyro.scale.z")
    free, reasons = identifiability.determined(x, y, names, identifiability.class_bounds("consumer"))
    assert free.tolist() == [True, True, True, True, False, False]
    assert reasons["gyro.scale.y"].startswith("too little excitation")
    assert reasons["gyro.scale.z"].startswith("confounded with gyro bias z")
    # Turns at the rounding of a constant rate (a unit at rest: 1e-20 rad): no measurement at all, where
    # it read "too little excitation: its standard error 1.65e+33 ms exceeds ..." (a new-user walk's).
    x[:, 1, 4] = rng.normal(0.0, 1e-20, k)
    _, reasons = identifiability.determined(x, y, names, identifiability.class_bounds("consumer"))
    assert reasons["gyro.scale.y"] == "not excited at all by the recording"


def test_a_rig_fit_beyond_its_class_is_refused(tmp_path: Path) -> None:
    """A rig session of a unit whose gyro x scale factor is 30 %: a fit that determines it well is
    refused for a consumer unit (whose bound is 10 %), naming the coefficient and the bound."""
    imu = {"grade": "tactical", "unit_seed": 2,
           "effect": [{"name": "gyro.scale_misalignment",
                       "matrix_ppm": [[3e5, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]}]}  # fmt: skip
    (tmp_path / "imu.toml").write_text(to_toml(imu))
    rig = tmp_path / "rig.csv"
    rc, _, err = run_cli(
        ["calibrate", "24pos_ratetable", "--imu", str(tmp_path / "imu.toml"), "--out", str(rig)]
    )
    assert rc == 0, err
    rc, _, err = run_cli(["fit", str(rig), "--strategy", "regression", "--out", str(tmp_path / "m.json")])
    assert (
        rc == 2 and "gyro scale x came out 3e+05 ppm" in err and "beyond what a consumer unit has" in err
    ), err
    assert not (tmp_path / "m.json").exists()


def test_review_refuses_what_is_not_determined_and_passes_what_is_held() -> None:
    bounds = identifiability.class_bounds("tactical")
    refusal(
        lambda: identifiability.review({"gyro.scale.x": (1e-4, 1e-2)}, bounds, "r.csv"),
        "r.csv: gyro scale x came out 100 ppm ± 1e+04 ppm: not determined",
        "300 ppm",
    )
    refusal(
        lambda: identifiability.review({"gyro.bias.x": (1e-3, np.nan)}, bounds, "r.csv"), "does not determine"
    )
    review = identifiability.review({"gyro.scale.x": (0.0, np.inf)}, bounds, "r.csv", {"gyro.scale.x": "why"})
    assert review.held == {"gyro.scale.x": "why"} and review.lines() == ["gyro scale x: why"]


BROAD_18 = data_root() / "broad_mocap" / "18_undisturbed_fast_translation_with_breaks_B.mat"


@pytest.mark.skipif(not BROAD_18.exists(), reason=f"BROAD not in {data_root()}")
def test_a_real_trial_holds_only_the_g_sensitivity_it_cannot_tell(tmp_path: Path) -> None:
    """BROAD's trial 18 (a consumer unit in a motion-capture room, turned about every axis): every
    coefficient but some g-sensitivity terms is determined for a consumer unit (and within its bounds:
    the fit is written)."""
    rc, _, err = run_cli(["fit", "--dataset", "broad_18", "--strategy", "regression", "--out",
                            str(tmp_path / "m.json"), "--json", str(tmp_path / "f.json")])  # fmt: skip
    assert rc == 0, err
    held = json.loads((tmp_path / "f.json").read_text())["held"]
    assert held and all(".g_sensitivity." in n for n in held), held
    assert (
        json.loads((tmp_path / "m.json").read_text())["state"]["fitted_on_"]["checks"]["grade"] == "consumer"
    )


def _still_npz(path: Path, k: int) -> Path:
    """A still ``.npz`` recording (the shared EuRoC form), its reference constant, its gyro bias
    1e-3 (k + 1) rad/s."""
    rng = np.random.default_rng(k)
    n = 6000
    t = 1.4e9 + np.arange(n) / 200.0 + 100.0 * k
    np.savez(path, t_s=t, gyro_rad_s=rng.normal(1e-3 * (k + 1), 1e-3, (n, 3)).astype(np.float32),
             accel_m_s2=(np.array([0.0, 0.0, 9.81]) + rng.normal(0, 1e-2, (n, 3))).astype(np.float32),
             q_wxyz=np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)).astype(np.float32),
             v_m_s=np.zeros((n, 3), np.float32), p_m=np.zeros((n, 3), np.float32))  # fmt: skip
    return path


def test_a_fit_on_several_still_recordings_keeps_their_biases_alone(tmp_path: Path) -> None:
    """Two still recordings of one unit fitted together (every coefficient shared but the biases): the
    shared scale factors and misalignments are not determined and are held at zero with their reasons,
    as a single recording's are; before, the model was written with 6.5e10 ppm. Each recording keeps its
    own biases. Each alone is fitted for its biases (what it determines)."""
    a, b = _still_npz(tmp_path / "a.npz", 0), _still_npz(tmp_path / "b.npz", 1)
    rc, out, err = run_cli(
        ["fit", str(a), str(b), "--strategy", "regression", "--out", str(tmp_path / "m.json"),
         "--json", str(tmp_path / "fit.json")]
    )  # fmt: skip
    assert rc == 0, err
    doc = json.loads((tmp_path / "fit.json").read_text())
    assert {"gyro.scale.x", "gyro.scale.y", "gyro.scale.z"} <= set(doc["held"]), doc["held"]
    # Printed and written as one recording's fit gives a held coefficient (before: a bare "0", se NaN).
    scale = _coefficients(doc)["gyro", "scale", "x"]
    assert scale["value"] == 0.0 and scale["se"] is None, scale
    assert re.search(r"gyro +scale +x +0 \(held\)", out), out
    state = json.loads((tmp_path / "m.json").read_text())["state"]
    np.testing.assert_array_equal(state["B_"], np.zeros((3, 3)))
    own = [r["gyro_bias_deg_h"] for r in doc["recording_biases"]]
    per_hour = np.degrees(1.0) * 3600
    np.testing.assert_allclose(own, [[1e-3 * per_hour] * 3, [2e-3 * per_hour] * 3], atol=0.2e-3 * per_hour)
    rc, _, err, doc = _fit(tmp_path, a, None)
    assert rc == 0, err
    assert {(c["sensor"], c["term"]) for c in doc["coefficients"] if c["se"] is not None} == {
        ("gyro", "bias"),
        ("accel", "bias"),
    }
