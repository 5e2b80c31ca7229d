"""Scenario files: presets, refusals with one-line messages, truth-file motions, segment semantics."""

from __future__ import annotations

import copy
import json
import math
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import recorded_runs
from conftest import refusal
from scipy.spatial.transform import Rotation

from sins import io, scenario
from sins.cli import main
from sins.imu import calibration
from sins.nav import motion, trajectory
from sins.runs import pipeline

SEED = 7_2024
PRESET_DIR = Path(__file__).resolve().parents[1] / "scenarios"
PRESETS = sorted(PRESET_DIR.glob("*.toml"))


# --------------------------------------------------------------------------- helpers


def _value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    return repr(v)


def _toml(doc: dict[str, Any]) -> str:
    """A small TOML writer: scalars, tables and arrays of tables (enough for scenarios)."""
    is_tables = lambda v: isinstance(v, dict) or (isinstance(v, list) and v and isinstance(v[0], dict))  # noqa: E731
    out = [f"{k} = {_value(v)}" for k, v in doc.items() if not is_tables(v)]
    for k, v in doc.items():
        if not is_tables(v):
            continue
        if isinstance(v, dict):
            out += [f"[{k}]"] + [f"{kk} = {_value(vv)}" for kk, vv in v.items()]
        elif isinstance(v, list):
            for item in v:
                out += [f"[[{k}]]"] + [f"{kk} = {_value(vv)}" for kk, vv in item.items()]
    return "\n".join(out) + "\n"


BASE: dict[str, Any] = {
    "name": "test",
    "imu": {"rate_hz": 100},
    "initial": {"lat_deg": 45.0, "lon_deg": 7.0, "alt_m": 100.0, "speed_mps": 10.0, "yaw_deg": 30.0},
    "segment": [
        {"type": "hold", "duration_s": 2.0},
        {"type": "accelerate", "duration_s": 4.0, "to_speed_mps": 20.0, "ramp_s": 1.0},
        {"type": "turn", "duration_s": 6.0, "rate_dps": 5.0, "ramp_s": 1.0},
    ],
}

WAYPOINTS: dict[str, Any] = {
    "name": "wp",
    "initial": {"lat_deg": 52.0, "lon_deg": 4.0, "alt_m": 2.0},
    "waypoint": [
        {"north_m": 0.0, "east_m": 0.0, "speed_mps": 5.0},
        {"north_m": 60.0, "east_m": 10.0, "speed_mps": 8.0},
        {"north_m": 100.0, "east_m": 60.0, "up_m": 2.0, "speed_mps": 6.0},
    ],
}


def _edit(doc: dict[str, Any], change) -> dict[str, Any]:
    new = copy.deepcopy(doc)
    change(new)
    return new


def _wrap_deg(angle: float) -> float:
    return (angle + 180.0) % 360.0 - 180.0


def _yaw_pitch_roll(q: np.ndarray) -> np.ndarray:
    return Rotation.from_quat(q).as_euler("ZYX")


# --------------------------------------------------------------------------- presets


def test_presets_are_found() -> None:
    assert {p.stem for p in PRESETS} >= {"static", "car_drive", "aircraft", "ship_seaway", "survey_waypoints"}


@pytest.mark.parametrize("path", PRESETS, ids=[p.stem for p in PRESETS])
def test_preset_loads_and_builds(path: Path) -> None:
    raw = tomllib.loads(path.read_text(encoding="utf-8"))
    sc = scenario.load(path)
    assert sc.name == raw["name"] == path.stem
    assert sc.rate_hz == raw.get("imu", {}).get("rate_hz", 100)
    m = scenario.build_motion(sc)
    duration = m.t_end - m.t_start
    if "segment" in raw:
        # Edges are a cumulative sum of the durations: exact up to a few roundings of ~3600.
        assert duration == pytest.approx(sum(s["duration_s"] for s in raw["segment"]), abs=1e-9)
        # The motion starts with the [initial] speed along the [initial] heading.
        kin = m.kinematics(np.array([m.t_start]))
        speed = raw["initial"].get("speed_mps", 0.0)
        assert np.hypot(*kin.v_n[0, :2]) == pytest.approx(speed, abs=1e-12)  # cos(0) * speed, rounding only
        if speed > 0:
            course = math.degrees(math.atan2(kin.v_n[0, 1], kin.v_n[0, 0]))
            assert _wrap_deg(course - raw["initial"].get("yaw_deg", 0.0)) == pytest.approx(0.0, abs=1e-9)
    else:
        # Each leg lasts chord / mean of its end speeds, so the whole lies between these two bounds.
        wps = raw["waypoint"]
        p = np.array([[w.get("north_m", 0.0), w.get("east_m", 0.0), w.get("up_m", 0.0)] for w in wps])
        s = np.array([w["speed_mps"] for w in wps])
        chords = np.linalg.norm(np.diff(p, axis=0), axis=1)
        low, high = (chords / np.maximum(s[:-1], s[1:])).sum(), (chords / np.minimum(s[:-1], s[1:])).sum()
        assert 0 < low <= duration <= high
    # Segments start at [initial]; the survey's first waypoint is at the origin, so it does too.
    assert m.lat0 == pytest.approx(math.radians(raw["initial"]["lat_deg"]), abs=1e-15)
    assert m.lon0 == pytest.approx(math.radians(raw["initial"]["lon_deg"]), abs=1e-15)


# --------------------------------------------------------------------------- refusals


def _seg(i: int, **changes: Any):
    return lambda d: d["segment"][i].update(changes)


def _pop(table: str, key: str, i: int | None = None):
    return lambda d: (d[table] if i is None else d[table][i]).pop(key)


def _drop(*keys: str):
    def apply(d: dict[str, Any]) -> None:
        for key in keys:
            d.pop(key)

    return apply


def _both(*changes):
    def apply(d: dict[str, Any]) -> None:
        for c in changes:
            c(d)

    return apply


REFUSALS = [
    ("unknown-top-level", BASE, lambda d: d.update(colour="red"), ["colour:", "unknown key"]),
    (
        "unknown-in-initial",
        BASE,
        lambda d: d["initial"].update(heading_deg=3.0),
        ["initial.heading_deg:", "unknown"],
    ),
    ("unknown-in-segment", BASE, _seg(1, rate=3.0), ["segment[2].rate:", "unknown key"]),
    ("key-of-other-type", BASE, _seg(1, rate_dps=3.0), ["segment[2].rate_dps:", "unknown key"]),
    ("ramp-in-hold", BASE, _seg(0, ramp_s=0.5), ["segment[1].ramp_s:", "unknown key"]),
    ("string-for-number", BASE, _seg(2, rate_dps="5"), ["segment[3].rate_dps:", "expected a number"]),
    ("bool-for-number", BASE, _seg(2, rate_dps=True), ["segment[3].rate_dps:", "expected a number"]),
    ("number-for-bool", BASE, _seg(2, coordinated=1), ["segment[3].coordinated:", "true or false"]),
    ("number-for-string", BASE, lambda d: d.update(name=3), ["name:", "expected a string"]),
    (
        "array-for-number",
        BASE,
        lambda d: d["imu"].update(rate_hz=[100]),
        ["imu.rate_hz:", "expected a number"],
    ),
    ("negative-duration", BASE, _seg(0, duration_s=-1.0), ["segment[1].duration_s:", "> 0"]),
    ("zero-duration", BASE, _seg(1, duration_s=0.0), ["segment[2].duration_s:", "> 0"]),
    ("missing-duration", BASE, _pop("segment", "duration_s", 1), ["segment[2].duration_s:", "missing"]),
    ("ramp-over-half", BASE, _seg(1, ramp_s=2.5), ["segment[2].ramp_s:", "half the duration"]),
    ("latitude-95", BASE, lambda d: d["initial"].update(lat_deg=95.0), ["initial.lat_deg:", "89.9"]),
    ("latitude-missing", BASE, _pop("initial", "lat_deg"), ["initial.lat_deg:", "missing"]),
    # A misspelt table is named (it had been the key the scenario then lacked: "initial.lat_deg: missing").
    ("misspelt-initial", BASE, lambda d: d.update(intial=d.pop("initial")), ["intial: unknown key"]),
    ("misspelt-segment", BASE, lambda d: d.update(segments=d.pop("segment")), ["segments: unknown key"]),
    ("latitude-nan", BASE, lambda d: d["initial"].update(lat_deg=math.nan), ["initial.lat_deg:", "finite"]),
    ("negative-speed", BASE, lambda d: d["initial"].update(speed_mps=-1.0), ["initial.speed_mps:", ">= 0"]),
    ("negative-to-speed", BASE, _seg(1, to_speed_mps=-2.0), ["segment[2].to_speed_mps:", ">= 0"]),
    ("unknown-segment-type", BASE, _seg(0, type="jump"), ["segment[1].type:", "hold, accelerate"]),
    (
        "accelerate-both",
        BASE,
        _seg(1, delta_speed_mps=3.0),
        ["segment[2]:", "exactly one", "delta_speed_mps"],
    ),
    ("accelerate-neither", BASE, _pop("segment", "to_speed_mps", 1), ["segment[2]:", "exactly one"]),
    (
        "accelerate-below-zero",
        BASE,
        _both(_pop("segment", "to_speed_mps", 1), _seg(1, delta_speed_mps=-25.0)),
        ["segment[2].delta_speed_mps:", "negative (-15 m/s)"],
    ),
    ("turn-both", BASE, _seg(2, angle_deg=10.0), ["segment[3]:", "rate_dps or angle_deg"]),
    (
        "climb-90",
        BASE,
        lambda d: d["segment"].append({"type": "climb", "duration_s": 4.0, "angle_deg": 90.0}),
        ["segment[4].angle_deg:", "<= 89"],
    ),
    (
        "segment-not-array",
        BASE,
        lambda d: d.update(segment={"type": "hold"}),
        ["segment:", "array of tables"],
    ),
    ("segment-empty", BASE, lambda d: d.update(segment=[]), ["segment:", "at least one"]),
    ("initial-not-table", BASE, lambda d: d.update(initial=3), ["initial:", "expected a table"]),
    ("unknown-in-imu", BASE, lambda d: d["imu"].update(bias=1.0), ["imu.bias:", "unknown"]),
    ("rate-zero", BASE, lambda d: d["imu"].update(rate_hz=0), ["imu.rate_hz:", ">= 1"]),
    (
        "vertical-mode",
        BASE,
        lambda d: d.update(navigation={"vertical": "up"}),
        ["navigation.vertical:", "free"],
    ),
    (
        "oscillation-period",
        BASE,
        lambda d: d.update(oscillation=[{"channel": "roll", "amplitude_deg": 1.0, "period_s": 0.0}]),
        ["oscillation[1].period_s:", "> 0"],
    ),
    ("no-trajectory", BASE, _drop("segment"), ["exactly one trajectory", "found none"]),
    (
        "two-trajectories",
        BASE,
        lambda d: d.update(waypoint=copy.deepcopy(WAYPOINTS["waypoint"])),
        ["exactly one trajectory", "found segment, waypoint"],
    ),
    (
        "waypoint-speed-0",
        WAYPOINTS,
        lambda d: d["waypoint"][1].update(speed_mps=0.0),
        ["waypoint[2].speed_mps:", "> 0"],
    ),
    (
        "waypoint-unknown",
        WAYPOINTS,
        lambda d: d["waypoint"][2].update(down_m=1.0),
        ["waypoint[3].down_m:", "unknown"],
    ),
    (
        "one-waypoint",
        WAYPOINTS,
        lambda d: d.update(waypoint=d["waypoint"][:1]),
        ["waypoint:", "at least two"],
    ),
    (
        "repeated-waypoint",
        WAYPOINTS,
        lambda d: d["waypoint"].insert(2, dict(d["waypoint"][1])),
        ["waypoint:", "waypoint 3 is at the same place as waypoint 2"],
    ),
    (
        "oscillation-with-waypoints",
        WAYPOINTS,
        lambda d: d.update(oscillation=[{"channel": "roll", "amplitude_deg": 1.0, "period_s": 3.0}]),
        ["oscillation:", "only for [[segment]]"],
    ),
    (
        "initial-with-truth",
        BASE,
        _both(_drop("segment"), lambda d: d.update(truth={"file": "truth.csv"})),
        ["initial:", "not used with a [truth]"],
    ),
    (
        "truth-without-file",
        BASE,
        _both(_drop("segment", "initial"), lambda d: d.update(truth={"path": "x.csv"})),
        ["truth.file:", "missing"],
    ),
]


@pytest.mark.parametrize(
    ("doc", "change", "fragments"), [r[1:] for r in REFUSALS], ids=[r[0] for r in REFUSALS]
)
def test_refused(tmp_path: Path, doc: dict[str, Any], change, fragments: list[str]) -> None:
    path = tmp_path / "scenario.toml"
    path.write_text(_toml(_edit(doc, change)), encoding="utf-8")
    message = refusal(lambda: scenario.load(path), f"{path}: ", *fragments)
    # The key path comes right after the file name.
    key = fragments[0]
    if key.endswith(":"):
        assert message.startswith(f"{path}: {key}")


@pytest.mark.parametrize(
    "points",
    [
        [{"speed_mps": 1.0}, {"up_m": 10.0, "speed_mps": 1.0}],  # straight up
        [{"speed_mps": 1.0}, {"north_m": 100.0, "speed_mps": 1.0}, {"north_m": 0.0, "speed_mps": 1.0}],
    ],
    ids=["vertical", "out-and-back"],
)
def test_a_waypoint_path_that_stops_moving_level_is_refused(
    tmp_path: Path, points: list[dict[str, Any]]
) -> None:
    """The attitude follows the level velocity: where it vanishes, the motion had NaN attitudes, numpy's
    warnings and a refusal that blamed the inputs' size ("beyond finite numbers"). Now one line says why."""
    path = tmp_path / "scenario.toml"
    path.write_text(_toml({**WAYPOINTS, "waypoint": points}), encoding="utf-8")
    refusal(lambda: scenario.build_motion(scenario.load(path)), f"{path}: waypoint[", "no level direction")


def test_base_documents_are_valid(tmp_path: Path) -> None:
    """The refusal tests edit valid documents: prove they are."""
    for i, doc in enumerate((BASE, WAYPOINTS)):
        path = tmp_path / f"ok{i}.toml"
        path.write_text(_toml(doc), encoding="utf-8")
        scenario.build_motion(scenario.load(path))


def test_malformed_toml(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text('name = "x"\n[initial\nlat_deg = 45\n', encoding="utf-8")
    refusal(lambda: scenario.load(path), str(path), "invalid TOML")


def test_missing_scenario_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.toml"
    refusal(lambda: scenario.load(path), str(path), "no such")


def test_scenario_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "latin1.toml"
    path.write_bytes('name = "Zürich"\n'.encode("latin-1"))
    refusal(lambda: scenario.load(path), str(path))


def test_huge_integer(tmp_path: Path) -> None:
    doc = _edit(BASE, lambda d: d["initial"].update(alt_m=10**400))
    path = tmp_path / "big.toml"
    path.write_text(_toml(doc), encoding="utf-8")
    refusal(lambda: scenario.load(path), str(path), "initial.alt_m")


@pytest.mark.parametrize(
    ("model", "said"),
    [("", "no such file or imu preset: ''"), (".", "'.' is a folder, expected an IMU file or preset"),
     ("unit.toml", "'unit.toml' no such file (in ")],
)  # fmt: skip
def test_an_imu_model_that_names_no_file_is_said_at_its_key(tmp_path: Path, model: str, said: str) -> None:
    """Before, ``model = ""`` and ``"."`` were ".: is a directory, expected a IMU file" and a missing
    file "unit.toml: no such IMU file": the scenario and its key lost."""
    doc = _edit(BASE, lambda d: d.update(imu={"model": model}))
    path = tmp_path / "s.toml"
    path.write_text(_toml(doc), encoding="utf-8")
    message = refusal(lambda: scenario.load(path), f"{path}: imu.model: ", said)
    assert "a IMU" not in message


def test_an_unknown_key_is_told_the_keys_taken_and_a_misspelt_one_is_named(tmp_path: Path) -> None:
    """Before, an unknown key listed the keys the file happened to give ("keys used here: none" for
    ``[gnss] sigma``), and ``lat_dg`` was "initial.lat_deg: missing required key", the typo unnamed."""
    path = tmp_path / "s.toml"
    path.write_text(_toml(_edit(BASE, lambda d: d.update(gnss={"sigma": 2.0}))), encoding="utf-8")
    message = refusal(lambda: scenario.load(path), f"{path}: gnss.sigma: unknown key (keys taken here: ")
    assert "sigma_m" in message and "rate_hz" in message
    path.write_text(_toml(_edit(BASE, lambda d: d["initial"].update(lat_dg=d["initial"].pop("lat_deg")))))
    said = "initial.lat_deg: missing required key ('lat_dg' is given: misspelt?)"
    refusal(lambda: scenario.load(path), said)


def test_a_damping_time_for_a_channel_not_damped_is_refused(tmp_path: Path) -> None:
    """It had run without a word (the time matters to ``damp`` alone), where ``sins integrate`` refused
    ``--vertical-tau-s`` beside a free channel."""
    path = tmp_path / "s.toml"
    for mode in ("free", "hold"):
        doc = _edit(BASE, lambda d, m=mode: d.update(navigation={"vertical": m, "vertical_tau_s": 5.0}))
        path.write_text(_toml(doc), encoding="utf-8")
        refusal(
            lambda: scenario.load(path),
            f'navigation.vertical_tau_s: goes with vertical = "damp" (the channel is {mode})',
        )
    path.write_text(
        _toml(_edit(BASE, lambda d: d.update(navigation={"vertical": "damp", "vertical_tau_s": 5.0})))
    )
    assert scenario.load(path).vertical_tau_s == 5.0


def test_truth_file_missing(tmp_path: Path) -> None:
    doc = {"name": "rec", "truth": {"file": "recordings/truth.csv"}}
    path = tmp_path / "rec.toml"
    path.write_text(_toml(doc), encoding="utf-8")
    sc = scenario.load(path)  # the file is only read when the motion is built
    # Relative to the scenario file's folder.
    refusal(lambda: scenario.build_motion(sc), str(tmp_path / "recordings" / "truth.csv"), "no such file")


# --------------------------------------------------------------------------- recorded truth


def _short_truth(tmp_path: Path) -> tuple[Path, Any]:
    start = motion.Start(
        lat=math.radians(45.0), lon=math.radians(7.0), h=300.0, speed=8.0, yaw=math.radians(40.0)
    )
    segs = [
        motion.Accelerate(2.0, 4.0, 0.5),
        motion.Turn(3.0, math.radians(10.0), 0.5),
        motion.Climb(2.0, 0.05, 0.5),
    ]
    truth, _ = trajectory.generate(motion.SegmentMotion.from_segments(start, segs), 20.0)
    path = tmp_path / "truth.csv"
    io.write_truth(path, truth)
    return path, truth


def test_truth_table_builds_recorded_motion(tmp_path: Path) -> None:
    _, truth = _short_truth(tmp_path)
    sc = scenario.from_dict({"name": "rec", "imu": {"rate_hz": 20}, "truth": {"file": "truth.csv"}},
                            source=tmp_path / "rec.toml")  # fmt: skip
    m = scenario.build_motion(sc)
    assert isinstance(m, motion.RecordedMotion)
    assert (m.t_start, m.t_end) == (truth.t[0], truth.t[-1])
    assert (m.lat0, m.h0) == pytest.approx((truth.lat[0], truth.h[0]), abs=1e-15)  # via degrees: 1 ulp
    kin = m.kinematics(truth.t)
    # A cubic spline interpolates its knots; 1e-9 m/s leaves room for the solve's rounding.
    np.testing.assert_allclose(kin.v_n, truth.v_n, rtol=0, atol=1e-9)
    sign = np.sign(np.sum(kin.q_nb * truth.q_nb, axis=1))[:, None]
    np.testing.assert_allclose(kin.q_nb * sign, truth.q_nb, rtol=0, atol=1e-12)  # Euler-degree round trip
    # Between knots the spline stays close to the smooth motion it samples (steps of 0.05 s).
    mid = 0.5 * (truth.t[:-1] + truth.t[1:])
    speed = np.linalg.norm(m.kinematics(mid).v_n, axis=1)
    assert np.all((speed > 7.9) & (speed < 12.1))


def test_a_truth_whose_velocities_do_not_integrate_to_its_positions_is_refused(tmp_path: Path) -> None:
    """The motion is made from a truth file's velocities (its first position the start); where they lead
    elsewhere than its positions, the file's positions would be set aside without a word. A solution's
    own noise (0.05 m/s on the velocities, 1 m on the positions, at 10 Hz over 2.4 km) passes; a velocity
    given east, north, down, or in km/h, is refused naming the time and the miss."""
    start = motion.Start(
        lat=math.radians(45.0), lon=math.radians(7.0), h=300.0, speed=20.0, yaw=math.radians(40.0)
    )
    segs = [motion.Turn(40.0, math.radians(3.0), 2.0), motion.Accelerate(40.0, 5.0, 2.0), motion.Hold(40.0)]
    truth, _ = trajectory.generate(motion.SegmentMotion.from_segments(start, segs), 10.0)
    rng = np.random.default_rng(3)
    noisy = replace(
        truth,
        v_n=truth.v_n + rng.normal(0, 0.05, truth.v_n.shape),
        h=truth.h + rng.normal(0, 1.0, len(truth.h)),
    )
    sc = scenario.from_dict({"truth": {"file": "truth.csv"}}, source=tmp_path / "rec.toml")
    io.write_truth(tmp_path / "truth.csv", noisy)
    assert isinstance(scenario.build_motion(sc), motion.RecordedMotion)
    for v_n in (truth.v_n[:, [1, 0, 2]], truth.v_n * 3.6):
        (tmp_path / "truth.csv").unlink()
        io.write_truth(tmp_path / "truth.csv", replace(truth, v_n=v_n))
        refusal(
            lambda: scenario.build_motion(sc),
            "truth.csv: its velocities do not integrate to its positions: at t = ",
        )


def test_a_motion_end_between_two_samples_is_said(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A run has ``floor(duration · rate)`` intervals: a 2.5 s turn at 1 Hz ran 2 s and never ended its
    turn, without a word (a walkthrough). ``sins run`` says so; whole intervals say nothing."""
    doc = {"name": "short", "imu": {"rate_hz": 1}, "initial": {"lat_deg": 45.0},
           "segment": [{"type": "turn", "duration_s": 2.5, "angle_deg": 90.0}]}  # fmt: skip
    assert scenario.unsampled_end(scenario.from_dict(doc)).startswith("the motion lasts 2.5 s; at 1 Hz its")
    doc["imu"]["rate_hz"] = 2  # type: ignore[index]
    assert scenario.unsampled_end(scenario.from_dict(doc)) == ""
    doc["imu"]["rate_hz"] = 1  # type: ignore[index]
    (tmp_path / "short.toml").write_text(_toml(doc), encoding="utf-8")
    assert main(["run", str(tmp_path / "short.toml")]) == 0
    assert "its last 0.5 s, shorter than an interval, are not run" in capsys.readouterr().err


def test_truth_table_too_short(tmp_path: Path) -> None:
    path = tmp_path / "truth.csv"
    path.write_text(
        "t,lat,lon,alt,vn,ve,vd,roll,pitch,yaw\n0,45,7,0,1,0,0,0,0,0\n1,45,7,0,1,0,0,0,0,0\n",
        encoding="utf-8",
    )
    sc = scenario.from_dict({"truth": {"file": "truth.csv"}}, source=tmp_path / "rec.toml")
    refusal(lambda: scenario.build_motion(sc), str(path), "at least 4 rows")


# --------------------------------------------------------------------------- segment semantics

SEMANTICS: dict[str, Any] = {
    "name": "semantics",
    "initial": {"lat_deg": 45.0, "lon_deg": 7.0, "alt_m": 100.0, "speed_mps": 10.0, "yaw_deg": 30.0},
    "segment": [
        {"type": "accelerate", "duration_s": 6.0, "to_speed_mps": 20.0, "ramp_s": 1.5},  # 0 .. 6
        {"type": "turn", "duration_s": 20.0, "angle_deg": 90.0, "ramp_s": 2.0},  # 6 .. 26
        {"type": "turn", "duration_s": 10.0, "rate_dps": 5.0, "ramp_s": 2.0},  # 26 .. 36, +40°
        {"type": "climb", "duration_s": 12.0, "angle_deg": 5.0, "ramp_s": 2.0},  # 36 .. 48
        {"type": "attitude", "duration_s": 6.0, "roll_deg": 10.0, "ramp_s": 1.0},  # 48 .. 54
        {"type": "hold", "duration_s": 2.0},  # 54 .. 56
    ],
}


@pytest.fixture(scope="module")
def semantics_motion():
    return scenario.build_motion(scenario.from_dict(SEMANTICS))


def _at(m, t: float):
    kin = m.kinematics(np.array([t]))
    yaw, pitch, roll = np.degrees(_yaw_pitch_roll(kin.q_nb[0]))
    return kin, yaw, pitch, roll


def test_accelerate_reaches_target_speed(semantics_motion) -> None:
    for t, speed in ((0.0, 10.0), (6.0, 20.0), (20.0, 20.0), (55.0, 20.0)):
        kin, *_ = _at(semantics_motion, t)
        assert np.linalg.norm(kin.v_n[0]) == pytest.approx(speed, abs=1e-9)  # closed form, rounding only


def test_turn_by_angle_and_by_rate(semantics_motion) -> None:
    _, yaw6, *_ = _at(semantics_motion, 6.0)
    _, yaw26, *_ = _at(semantics_motion, 26.0)
    _, yaw36, *_ = _at(semantics_motion, 36.0)
    assert yaw6 == pytest.approx(30.0, abs=1e-9)
    assert _wrap_deg(yaw26 - yaw6) == pytest.approx(90.0, abs=1e-9)  # angle_deg = 90
    assert _wrap_deg(yaw36 - yaw26) == pytest.approx(5.0 * (10.0 - 2.0), abs=1e-9)  # rate × (duration - ramp)
    # Yaw rate at mid-plateau (t = 31 s) by a central difference of scipy's yaw: O(h²) truncation is
    # zero on the plateau (yaw is linear there), so only rounding ~1e-16 / 1e-3 remains.
    h = 1e-3
    rate = (_at(semantics_motion, 31.0 + h)[1] - _at(semantics_motion, 31.0 - h)[1]) / (2 * h)
    assert rate == pytest.approx(5.0, abs=1e-9)
    kin, *_ = _at(semantics_motion, 31.0)
    assert math.degrees(kin.omega_nb_b[0, 2]) == pytest.approx(
        5.0, abs=1e-12
    )  # level: body z rate = yaw rate
    # The velocity follows the heading.
    course = math.degrees(math.atan2(kin.v_n[0, 1], kin.v_n[0, 0]))
    assert _wrap_deg(course - _at(semantics_motion, 31.0)[1]) == pytest.approx(0.0, abs=1e-9)


def test_climb_flight_path_angle(semantics_motion) -> None:
    kin, _, pitch, _ = _at(semantics_motion, 42.0)
    gamma = math.degrees(math.atan2(-kin.v_n[0, 2], np.hypot(*kin.v_n[0, :2])))
    assert gamma == pytest.approx(5.0, abs=1e-9)
    assert pitch == pytest.approx(5.0, abs=1e-9)  # nose along the velocity
    assert np.linalg.norm(kin.v_n[0]) == pytest.approx(20.0, abs=1e-9)  # the climb keeps the speed
    for t in (48.0, 50.0, 56.0):
        kin, _, pitch, _ = _at(semantics_motion, t)
        assert kin.v_n[0, 2] == pytest.approx(0.0, abs=1e-12)  # level again
        assert pitch == pytest.approx(0.0, abs=1e-9)


def test_attitude_segment_rolls_without_turning_the_velocity(semantics_motion) -> None:
    before, yaw0, pitch0, roll0 = _at(semantics_motion, 48.0)
    after, yaw1, pitch1, roll1 = _at(semantics_motion, 54.0)
    assert roll0 == pytest.approx(0.0, abs=1e-9)
    assert roll1 == pytest.approx(10.0, abs=1e-9)
    assert (yaw1, pitch1) == pytest.approx((yaw0, pitch0), abs=1e-9)
    np.testing.assert_allclose(after.v_n[0], before.v_n[0], rtol=0, atol=1e-12)  # same speed and direction
    kin, *_ = _at(semantics_motion, 51.0)
    np.testing.assert_allclose(kin.v_n[0], before.v_n[0], rtol=0, atol=1e-12)  # also while rolling
    assert _at(semantics_motion, 56.0)[3] == pytest.approx(10.0, abs=1e-9)  # and it stays rolled


RICH: dict[str, Any] = {
    "name": "rich",
    "initial": {"lat_deg": -33.0, "lon_deg": 151.0, "alt_m": 500.0, "speed_mps": 60.0, "yaw_deg": -120.0,
                "roll_deg": 2.0, "pitch_deg": 1.0},
    "segment": [
        {"type": "turn", "duration_s": 8.0, "rate_dps": -6.0, "ramp_s": 2.0, "coordinated": True},
        {"type": "climb", "duration_s": 6.0, "angle_deg": -7.0, "ramp_s": 1.5},
        {"type": "attitude", "duration_s": 4.0, "roll_deg": -15.0, "pitch_deg": 3.0, "yaw_deg": 8.0,
         "ramp_s": 1.0},
        {"type": "accelerate", "duration_s": 5.0, "delta_speed_mps": -20.0, "ramp_s": 2.0},
    ],
    "oscillation": [
        {"channel": "roll", "amplitude_deg": 4.0, "period_s": 5.0},
        {"channel": "pitch", "amplitude_deg": 1.5, "period_s": 3.7, "phase_deg": 30.0},
        {"channel": "yaw", "amplitude_deg": 1.0, "period_s": 6.1, "phase_deg": 100.0},
        {"channel": "heave", "amplitude_m": 0.8, "period_s": 4.3, "phase_deg": 200.0},
    ],
}  # fmt: skip


@pytest.mark.parametrize(
    ("doc", "in_ramps"),
    [
        (SEMANTICS, [0.7, 6.5, 7.9, 25.1, 36.4, 47.0, 48.3, 53.8]),
        (RICH, [0.3, 7.0, 8.6, 13.0, 14.5, 17.2, 19.0, 22.5]),
        (WAYPOINTS, []),  # no ramps: a quintic per leg, random times only
    ],
    ids=["semantics", "rich", "waypoints"],
)
def test_derivatives_match_finite_differences(doc: dict[str, Any], in_ramps: list[float]) -> None:
    m = scenario.build_motion(scenario.from_dict(doc))
    rng = np.random.default_rng(SEED)
    t = np.concatenate([rng.uniform(m.t_start + 0.01, m.t_end - 0.01, 25), in_ramps])
    h = 1e-4
    kin = m.kinematics(t)
    plus, minus = m.kinematics(t + h), m.kinematics(t - h)
    # Central difference: truncation h²/6·|v‴|, with |v‴| up to ~1e2 m/s⁴ for these ramps and sinusoids,
    # measured ≤ 2.2e-7 m/s²; rounding ε·|v|/h ≈ 1e-10. 1e-6 m/s² is above both, far below any missing term.
    a_fd = (plus.v_n - minus.v_n) / (2 * h)
    np.testing.assert_allclose(kin.a_n, a_fd, rtol=0, atol=1e-6)
    # Body rate from the rotation over [t-h, t+h] seen in the body frame: log(R(t-h)ᵀ R(t+h)) / 2h,
    # error O(h²·|ω′′|, h²·|ω × ω′|), measured ≤ 1e-8 rad/s here; rounding ε/h ≈ 1e-12.
    r_plus, r_minus = Rotation.from_quat(plus.q_nb), Rotation.from_quat(minus.q_nb)
    w_fd = (r_minus.inv() * r_plus).as_rotvec() / (2 * h)
    np.testing.assert_allclose(kin.omega_nb_b, w_fd, rtol=0, atol=1e-7)
    # The checks bite: accelerations and rates here are far from zero.
    assert np.abs(kin.a_n).max() > 0.5 and np.abs(kin.omega_nb_b).max() > 0.02


@pytest.mark.parametrize("name", pipeline.presets("rig"))
def test_rig_preset_loads_as_written(name: str) -> None:
    path = Path(__file__).resolve().parents[1] / "scenarios" / "rig" / f"{name}.toml"
    raw = tomllib.loads(path.read_text(encoding="utf-8"))
    rig = scenario.load_rig(path)
    assert rig.positions == raw["positions"]["count"] and rig.position_dwell_s == raw["positions"]["dwell_s"]
    assert rig.rate_hz == raw["rig"]["rate_hz"]
    assert len(calibration.static_orientations(rig.positions)) == rig.positions


@pytest.fixture(scope="module")
def short_runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, object]]:
    """``sins run --json`` of the short presets, run once for the tests below."""
    from test_fuzz import run_cli

    out = {}
    folder = tmp_path_factory.mktemp("runs")
    for name in recorded_runs.SHORT_PRESETS:
        rc, _, err = run_cli(["run", name, "--json", str(folder / f"{name}.json")])
        assert rc == 0, err
        out[name] = recorded_runs.normalised(json.loads((folder / f"{name}.json").read_text()))
    return out


@pytest.mark.parametrize("name", recorded_runs.SHORT_PRESETS)
def test_short_presets_run_as_recorded(name: str, short_runs: dict[str, dict[str, object]]) -> None:
    """``sins run --json`` of the short presets (the ideal IMU's engine, a waypoint drive, an aided drive
    with its alignment and outages) equals what was recorded, on any machine: every number within
    :data:`recorded_runs.RELATIVE` of its recorded value (or :data:`recorded_runs.ABSOLUTE` of a value
    near zero), every other field exactly. Another machine's kernels round the last bits of sums
    differently; a refactoring that changes a result moves it by far more."""
    recorded = json.loads((recorded_runs.FOLDER / f"{name}.json").read_text())
    assert recorded_runs.differences(short_runs[name], recorded) == []


@pytest.mark.parametrize("name", recorded_runs.SHORT_PRESETS)
def test_short_presets_run_as_recorded_to_the_last_bit(
    name: str, short_runs: dict[str, dict[str, object]]
) -> None:
    """The extra where the arithmetic is the one they were recorded on (``tests/recorded_runs.py``):
    every float to the last bit, so that a refactoring that moves a sum or a draw shows here. Elsewhere
    the tolerance test above judges, and this one says why it does not."""
    recorded_on = json.loads((recorded_runs.FOLDER / "platform.json").read_text())
    here = recorded_runs.platform()
    if here != recorded_on:
        differ = sorted(k for k in here.keys() | recorded_on.keys() if here.get(k) != recorded_on.get(k))
        pytest.skip(f"recorded on other arithmetic ({', '.join(differ)}): judged by tolerance above")
    assert short_runs[name] == json.loads((recorded_runs.FOLDER / f"{name}.json").read_text())


def test_the_recorded_runs_tolerance_bites() -> None:
    """A change of a recorded number beyond rounding, a missing field or a changed word is found."""
    recorded = json.loads((recorded_runs.FOLDER / "car_drive_aided_10min.json").read_text())
    moved = json.loads(json.dumps(recorded))
    moved["aided"]["none"]["final_north_m"] *= 1 + 1e-8
    assert recorded_runs.differences(moved, recorded) == [
        f".aided.none.final_north_m: {moved['aided']['none']['final_north_m']!r}, recorded "
        f"{recorded['aided']['none']['final_north_m']!r}"
    ]
    rounded = json.loads(json.dumps(recorded))
    rounded["aided"]["none"]["final_north_m"] *= 1 + 1e-12
    assert recorded_runs.differences(rounded, recorded) == []
    del moved["aided"]["none"]["final_east_m"]
    moved["scenario"]["vertical"] = "hold"
    assert len(recorded_runs.differences(moved, recorded)) == 3


@pytest.mark.parametrize(("duration_s", "said"), [(100.0, "reaches latitude"), (560.0, "reaches a pole at")])
def test_a_trajectory_over_a_pole_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], duration_s: float, said: str
) -> None:
    # 20 m/s north from 89.9° meets the pole after 0.1° × 111.7 km/° / 20 m/s ≈ 558.5 s: a run that ends
    # before it is refused by the latitude it reaches; one that gets there had crashed dividing by its
    # cos(lat) = 0 (ZeroDivisionError, a traceback): now one line, the time it gets there.
    path = tmp_path / "pole.toml"
    path.write_text(
        f'[initial]\nlat_deg = 89.9\nspeed_mps = 20\n[[segment]]\ntype = "hold"\nduration_s = {duration_s}\n'
    )
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"sins: error: {path}: the trajectory {said}") and err.count("\n") == 1, err
    if duration_s > 500:
        at = float(err.split("t = ")[1].split(" s")[0])
        assert abs(at - 558.5) < 1.0, at  # the meridian arc of 0.1° at the pole: 11.17 km
