"""Every numeric field of the scenario, IMU-model and rig files at its bounds.

Just inside a bound the command runs and its result is sound (finite numbers), or, where the value
makes the run enormous (a 1e9 s segment), it is refused up front for its size; just outside, it is
refused in one line naming the file and the key. The bounds come from the code's own tables
(``SCENARIO_BOUNDS``, ``RIG_BOUNDS``, the parameters of ``sins.imu.spec.parameters()``), so a field added
there is walked here; the fields whose bound depends on another field are walked beside them. The
guide's tables (``docs/guide/scenarios.md``) list the same bounds: :func:`test_the_guide_lists_every_bound`.
"""

from __future__ import annotations

import copy
import math
import re
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import refusal
from test_fuzz import IMU_MODEL, NON_FINITE, RIG, SCENARIO, WAYPOINTS, assert_one_line, run_cli, to_toml

from sins.campaign import quality
from sins.imu import spec as imu_spec
from sins.imu.vocabulary import Param
from sins.scenario import validate
from sins.scenario.files import MIN_DWELL_SAMPLES, RIG_BOUNDS
from sins.scenario.toml import MAX_SEED, Bound

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "scenarios.md"


def _inside(bound: Bound) -> tuple[float, float]:
    low = math.nextafter(bound.low, math.inf) if bound.low_open else bound.low
    high = math.nextafter(bound.high, -math.inf) if bound.high_open else bound.high
    return low, high


def _outside(bound: Bound) -> tuple[float, float]:
    low = bound.low if bound.low_open else math.nextafter(bound.low, -math.inf)
    high = bound.high if bound.high_open else math.nextafter(bound.high, math.inf)
    return low, high


def _place(path: tuple[Any, ...]) -> str:
    """``("segment", 1, "ramp_s")`` -> ``segment[2].ramp_s`` (as the messages name it)."""
    out = ""
    for k in path:
        if k is None:
            continue
        out += f"[{k + 1}]" if isinstance(k, int) else (f".{k}" if out else k)
    return out


def _set(doc: dict[str, Any], path: tuple[Any, ...], value: float) -> dict[str, Any]:
    doc = copy.deepcopy(doc)
    target: Any = doc
    for k in path[:-2] if path[-1] is None else path[:-1]:
        target = target[k]
    if path[-1] is None:  # an array: every element at the value, a time array spread out around it
        key = path[-2]
        n = len(target[key])
        target[key] = [value] * n if key != "times_s" else sorted({value, 0.0 if value else 1.0})[:n]
        if key == "times_s":
            target["temps_degc"] = target["temps_degc"][: len(target[key])]
    else:
        target[path[-1]] = value
    return doc


# A scenario without oscillations (their period depends on the rate) and a short one at a high rate.
PLAIN = {k: v for k, v in SCENARIO.items() if k != "oscillation"}
HOLD = {"name": "hold", "imu": {"rate_hz": 20}, "initial": {"lat_deg": 45.0},
        "segment": [{"type": "hold", "duration_s": 1.0}]}  # fmt: skip
FAST_WAYPOINTS = copy.deepcopy(WAYPOINTS)
for _wp in FAST_WAYPOINTS["waypoint"]:
    _wp["speed_mps"] = 1e4  # legs of up to 1e6 m pass in 100 s

# 30 s still at 20 Hz, aided by a receiver with every option, one outage, aligned over 20 s.
AIDED = {**HOLD, "segment": [{"type": "hold", "duration_s": 30.0}],
         "gnss": {"rate_hz": 1.0, "sigma_m": [1.5, 1.5, 3.0], "markov_sigma_m": [0.5, 0.5, 1.0],
                  "markov_tau_s": 100.0, "sigma_vel_mps": 0.1, "lever_arm_m": [1.0, 0.0, -1.0],
                  "latency_s": 0.1},
         "outage": [{"start_s": 10.0, "end_s": 20.0}],
         "alignment": {"static_s": 20.0, "coarse_s": 10.0, "heading_sigma_deg": 1.0}}  # fmt: skip

# A drive from rest to 20 m/s and on, aligned in motion from the GNSS velocity.
MOVING_AIDED = {**HOLD, "segment": [{"type": "accelerate", "duration_s": 10.0, "to_speed_mps": 20.0},
                                    {"type": "hold", "duration_s": 20.0}],
                "gnss": {"rate_hz": 1.0, "sigma_vel_mps": 0.1},
                "alignment": {"method": "gnss_velocity", "min_speed_mps": 5.0,
                              "sideslip_sigma_deg": 1.0}}  # fmt: skip

#: Scenario field -> (document, path to set). Each key of SCENARIO_BOUNDS appears once.
SCENARIO_FIELDS: dict[str, tuple[dict[str, Any], tuple[Any, ...]]] = {
    "imu.rate_hz": (HOLD, ("imu", "rate_hz")),
    "imu.times_s": (SCENARIO, ("imu", "times_s", None)),
    "imu.temps_degc": (SCENARIO, ("imu", "temps_degc", None)),
    "compensation.validation": (
        {
            **HOLD,
            "imu": {"rate_hz": 20, "model": "tactical"},
            "compensation": {"rig": "rig.toml", "strategies": ["regression"]},
        },
        ("compensation", "validation"),
    ),
    "navigation.vertical_tau_s": (SCENARIO, ("navigation", "vertical_tau_s")),
    "initial.lat_deg": (HOLD, ("initial", "lat_deg")),
    "initial.lon_deg": (SCENARIO, ("initial", "lon_deg")),
    "initial.alt_m": (SCENARIO, ("initial", "alt_m")),
    "initial.speed_mps": (_set(SCENARIO, ("segment", 1, "delta_speed_mps"), 0.0), ("initial", "speed_mps")),
    "initial.roll_deg": (SCENARIO, ("initial", "roll_deg")),
    "initial.pitch_deg": (SCENARIO, ("initial", "pitch_deg")),
    "initial.yaw_deg": (SCENARIO, ("initial", "yaw_deg")),
    "segment.duration_s": (SCENARIO, ("segment", 0, "duration_s")),
    "segment.ramp_s": (SCENARIO, ("segment", 1, "ramp_s")),
    "segment.to_speed_mps": (SCENARIO, ("segment", 2, "to_speed_mps")),
    "segment.delta_speed_mps": (SCENARIO, ("segment", 1, "delta_speed_mps")),
    "segment.rate_dps": (SCENARIO, ("segment", 3, "rate_dps")),
    "segment.angle_deg": (SCENARIO, ("segment", 5, "angle_deg")),
    "segment.roll_deg": (SCENARIO, ("segment", 6, "roll_deg")),
    "segment.pitch_deg": (SCENARIO, ("segment", 6, "pitch_deg")),
    "segment.yaw_deg": (SCENARIO, ("segment", 6, "yaw_deg")),
    "oscillation.amplitude_deg": (SCENARIO, ("oscillation", 0, "amplitude_deg")),
    "oscillation.amplitude_m": (SCENARIO, ("oscillation", 1, "amplitude_m")),
    "oscillation.period_s": (SCENARIO, ("oscillation", 0, "period_s")),
    "oscillation.phase_deg": (SCENARIO, ("oscillation", 0, "phase_deg")),
    "waypoint.north_m": (FAST_WAYPOINTS, ("waypoint", 2, "north_m")),
    "waypoint.east_m": (FAST_WAYPOINTS, ("waypoint", 2, "east_m")),
    "waypoint.up_m": (FAST_WAYPOINTS, ("waypoint", 2, "up_m")),
    "waypoint.speed_mps": (WAYPOINTS, ("waypoint", 1, "speed_mps")),
    "gnss.rate_hz": (AIDED, ("gnss", "rate_hz")),
    "gnss.sigma_m": (AIDED, ("gnss", "sigma_m", None)),
    "gnss.markov_sigma_m": (AIDED, ("gnss", "markov_sigma_m", None)),
    "gnss.markov_tau_s": (AIDED, ("gnss", "markov_tau_s")),
    "gnss.sigma_vel_mps": (AIDED, ("gnss", "sigma_vel_mps")),
    "gnss.lever_arm_m": (AIDED, ("gnss", "lever_arm_m", None)),
    "gnss.latency_s": (AIDED, ("gnss", "latency_s")),
    "outage.start_s": (AIDED, ("outage", 0, "start_s")),
    "outage.end_s": (AIDED, ("outage", 0, "end_s")),
    "alignment.static_s": (AIDED, ("alignment", "static_s")),
    "alignment.coarse_s": (AIDED, ("alignment", "coarse_s")),
    "alignment.heading_sigma_deg": (AIDED, ("alignment", "heading_sigma_deg")),
    "alignment.min_speed_mps": (MOVING_AIDED, ("alignment", "min_speed_mps")),
    "alignment.sideslip_sigma_deg": (MOVING_AIDED, ("alignment", "sideslip_sigma_deg")),
}

#: Fields whose upper bound makes a run too long to try here: their value just inside is run at the
#: highest rate, where it is refused for its size on any machine (1e14 samples).
HUGE = {"segment.duration_s", "segment.ramp_s"}


def _fits(doc: dict[str, Any], key: str, value: float, inside: bool = True) -> dict[str, Any]:
    """The document made to hold ``value`` where another field bounds it (a ramp needs its duration)."""
    if key == "segment.ramp_s" and value > 1e6 and not inside:  # a duration within the total's bound
        doc["segment"] = doc["segment"][:2]
        doc["segment"][1]["duration_s"] = 1e9 - 10.0
    elif key == "segment.ramp_s":
        doc["segment"][1]["duration_s"] = max(doc["segment"][1]["duration_s"], 2 * value)
    if key in HUGE and value > 1e6 and inside:  # that segment alone, at the highest rate
        doc["segment"] = [
            s for s in doc["segment"] if s.get("ramp_s", 0) == value or s["duration_s"] == value
        ]
        doc["imu"]["rate_hz"] = 100000.0
        doc.pop("oscillation", None)
    if key == "segment.delta_speed_mps":  # from rest up to the fastest, or from the fastest to rest
        doc["initial"]["speed_mps"] = 0.0 if value > 0 else min(-value, 1e4)
        doc["segment"][2]["to_speed_mps"] = 4.0
    if key == "waypoint.speed_mps" and value > 1e3:  # the path then lasts 5 ms: sample it at 100 kHz
        doc["imu"]["rate_hz"] = 100000.0
    if key == "outage.start_s":  # the window still ends after it starts
        doc["outage"][0]["end_s"] = max(doc["outage"][0]["end_s"], min(1e9, value + 10.0))
    if key == "outage.end_s":
        doc["outage"][0]["start_s"] = min(doc["outage"][0]["start_s"], value / 2)
    if key in ("alignment.static_s", "alignment.coarse_s") and inside:  # still long enough, the coarse within
        align = doc["alignment"]
        align["static_s"] = max(align["static_s"], value) if key == "alignment.coarse_s" else value
        align["coarse_s"] = min(align["coarse_s"], value) if key == "alignment.static_s" else value
        doc["segment"][0]["duration_s"] = max(doc["segment"][0]["duration_s"], align["static_s"])
        doc["imu"]["rate_hz"] = 1.0 if align["static_s"] > 100 else doc["imu"]["rate_hz"]
    if key == "alignment.min_speed_mps" and inside and value > 20.0:  # the drive reaches that speed
        doc["segment"][0]["to_speed_mps"] = value
    return doc


#: The lower bounds that depend on another field (or on the rate, 20 Hz here), above the static ones;
#: :func:`test_bounds_that_depend_on_another_field` walks them.
DYNAMIC_LOW = {"segment.duration_s": 2e-3, "waypoint.speed_mps": 0.01, "navigation.vertical_tau_s": 0.1,
               "oscillation.period_s": 0.5, "alignment.static_s": 0.5}  # fmt: skip


def _run(tmp: Path, doc: dict[str, Any]) -> tuple[int, str, str, Path]:
    (tmp / "rig.toml").write_text(to_toml(_SMALL_RIG), encoding="utf-8")
    path = tmp / "s.toml"
    path.write_text(to_toml(doc), encoding="utf-8")
    rc, out, err = run_cli(["run", str(path)])
    return rc, out, err, path


def _assert_sound(rc: int, out: str, err: str, files: list[Path], key: str) -> None:
    """Exit 0 with finite numbers, or an up-front refusal for the run's size (never for the field)."""
    if rc == 0:
        assert not NON_FINITE.search(out), out
        return
    assert_one_line(err, files)
    assert "of memory" in err or "free;" in err, f"{key}: refused just inside its bound: {err}"


_SMALL_RIG = {**RIG, "rate_table": {**RIG["rate_table"], "dwell_s": 2.0}}


@pytest.mark.parametrize("key", sorted(validate.SCENARIO_BOUNDS))
def test_scenario_field_at_its_bounds(key: str, tmp_path: Path) -> None:
    bound = validate.SCENARIO_BOUNDS[key]
    doc, path = SCENARIO_FIELDS[key]
    low, high = _inside(bound)
    for value in (max(low, DYNAMIC_LOW.get(key, low)), high):
        rc, out, err, file = _run(tmp_path, _fits(_set(doc, path, value), key, value))
        _assert_sound(rc, out, err, [file], key)
    for value in _outside(bound):
        rc, out, err, file = _run(tmp_path, _fits(_set(doc, path, value), key, value, inside=False))
        assert rc == 2, f"{key} = {value!r} was taken: {out}"
        assert_one_line(err, [file])
        assert _place(path) in err, err


def test_every_scenario_field_is_walked() -> None:
    assert set(SCENARIO_FIELDS) == set(validate.SCENARIO_BOUNDS)


@pytest.mark.parametrize(
    ("doc", "path", "inside", "outside", "fragment"),
    [
        # A segment lasts long enough for a ramp in and out of the shortest length (at 100 kHz, so
        # that 2 ms are 200 samples).
        (_set(HOLD, ("imu", "rate_hz"), 1e5), ("segment", 0, "duration_s"), 2e-3, math.nextafter(2e-3, 0.0),
         "at least 0.002 s"),
        # The damp loop spans two samples (20 Hz: 0.1 s).
        (SCENARIO, ("navigation", "vertical_tau_s"), 0.1, math.nextafter(0.1, 0.0), "2 IMU samples"),
        # An oscillation spans ten samples (0.5 s).
        (SCENARIO, ("oscillation", 0, "period_s"), 0.5, math.nextafter(0.5, 0.0), "10 IMU samples"),
        # A static alignment averages ten samples (0.5 s).
        (_set(AIDED, ("alignment", "coarse_s"), 0.25), ("alignment", "static_s"), 0.5,
         math.nextafter(0.5, 0.0), "10 IMU samples"),
        # The slowest waypoint.
        (WAYPOINTS, ("waypoint", 1, "speed_mps"), 0.01, math.nextafter(0.01, 0.0), "at least 0.01 m/s"),
        # A turn by angle is at most 360 °/s over its plateau (1 s - 0.25 s).
        (SCENARIO, ("segment", 4, "angle_deg"), 270.0, math.nextafter(270.0, 1e3), "faster than 360"),
        # The speed a segment reaches.
        (SCENARIO, ("segment", 1, "delta_speed_mps"), 1e4 - 5.0, math.nextafter(1e4 - 5.0, 2e4),
         "above 10000"),
    ],
)  # fmt: skip
def test_bounds_that_depend_on_another_field(
    tmp_path: Path, doc: dict[str, Any], path: tuple[Any, ...], inside: float, outside: float, fragment: str
) -> None:
    rc, out, err, file = _run(tmp_path, _set(doc, path, inside))
    _assert_sound(rc, out, err, [file], _place(path))
    rc, out, err, file = _run(tmp_path, _set(doc, path, outside))
    assert rc == 2, out
    assert_one_line(err, [file])
    assert _place(path) in err and fragment in err, err


def test_total_duration_and_seeds(tmp_path: Path) -> None:
    # Two segments of 6e8 s: each within its bound, together beyond the scenario's 1e9 s.
    doc = {**HOLD, "segment": [{"type": "hold", "duration_s": 6e8}, {"type": "hold", "duration_s": 6e8}]}
    rc, _, err, file = _run(tmp_path, doc)
    assert rc == 2 and "segment[2].duration_s" in err and "1e+09" in err, err
    for value, ok in ((0, True), (MAX_SEED, True), (-1, False), (1.5, False), (1e300, False)):
        rc, _, err, file = _run(tmp_path, _set(HOLD, ("imu", "seed"), value))
        assert (rc == 0) == ok, (value, err)
        if not ok:
            assert_one_line(err, [file])
            assert "imu.seed" in err


# --------------------------------------------------------------------------- rig files

RIG_FIELDS: dict[str, tuple[Any, ...]] = {
    "rig.lat_deg": ("rig", "lat_deg"),
    "rig.lon_deg": ("rig", "lon_deg"),
    "rig.alt_m": ("rig", "alt_m"),
    "rig.rate_hz": ("rig", "rate_hz"),
    "rig.orientation_error_deg": ("rig", "orientation_error_deg"),
    "rig.rate_error_ppm": ("rig", "rate_error_ppm"),
    "positions.dwell_s": ("positions", "dwell_s"),
    "rate_table.rates_dps": ("rate_table", "rates_dps", None),
    "rate_table.dwell_s": ("rate_table", "dwell_s"),
    "rate_table.accel_dps2": ("rate_table", "accel_dps2"),
    "temperature.times_s": ("temperature", "times_s", None),
    "temperature.temps_degc": ("temperature", "temps_degc", None),
}


def _calibrate(tmp: Path, rig: dict[str, Any], imu: dict[str, Any]) -> tuple[int, str, str, list[Path]]:
    (tmp / "rig.toml").write_text(to_toml(rig), encoding="utf-8")
    (tmp / "imu.toml").write_text(to_toml(imu), encoding="utf-8")
    out = tmp / "rec.csv"
    out.unlink(missing_ok=True)
    rc, stdout, err = run_cli(["calibrate", str(tmp / "rig.toml"), "--imu", str(tmp / "imu.toml"), "--out",
                               str(out)])  # fmt: skip
    if rc != 0:
        assert not out.exists()
    return rc, stdout, err, [tmp / "rig.toml", tmp / "imu.toml", out]


def _rig_fits(rig: dict[str, Any], key: str, value: float) -> dict[str, Any]:
    if key == "rig.rate_hz" and value > 1000:  # a short session at the highest rate
        rig = {**rig, "positions": {"count": 6, "dwell_s": 1e-3}, "rate_table": {**rig["rate_table"],
               "dwell_s": 1e-3, "accel_dps2": 1e6}}  # fmt: skip
    if key.endswith("dwell_s") and value > 1e3:  # so long a session that it is refused for its size
        rig = {**rig, "rig": {**rig["rig"], "rate_hz": 1e5}}
    if key == "rate_table.rates_dps" and value > 1e3:
        rig = {**rig, "rate_table": {**rig["rate_table"], "accel_dps2": 1e5}}
    if key == "rate_table.accel_dps2" and value < 10:
        rig = {**rig, "rate_table": {**rig["rate_table"], "rates_dps": [1.0]}}
    return rig


@pytest.mark.parametrize("key", sorted(RIG_BOUNDS))
def test_rig_field_at_its_bounds(key: str, tmp_path: Path) -> None:
    bound, path = RIG_BOUNDS[key], RIG_FIELDS[key]
    for value in _inside(bound):
        if key.endswith("dwell_s") and value * 10 < MIN_DWELL_SAMPLES:
            value = MIN_DWELL_SAMPLES / 10  # the rate-dependent bound is above the static one
        rc, out, err, files = _calibrate(
            tmp_path, _rig_fits(_set(_SMALL_RIG, path, value), key, value), IMU_MODEL
        )
        _assert_sound(rc, out, err, files, key)
    for value in _outside(bound):
        rc, out, err, files = _calibrate(
            tmp_path, _rig_fits(_set(_SMALL_RIG, path, value), key, value), IMU_MODEL
        )
        assert rc == 2, f"{key} = {value!r} was taken"
        assert_one_line(err, files)
        assert _place(path) in err, err


def test_rig_dwell_is_two_samples_and_counts_are_known(tmp_path: Path) -> None:
    for table in ("positions", "rate_table"):
        rc, _, err, _ = _calibrate(tmp_path, _set(_SMALL_RIG, (table, "dwell_s"), 0.2), IMU_MODEL)
        assert rc == 0, err
        rc, _, err, _ = _calibrate(tmp_path, _set(_SMALL_RIG, (table, "dwell_s"), 0.19), IMU_MODEL)
        assert rc == 2 and f"{table}.dwell_s" in err and "2 samples" in err, err
    for count, ok in ((0, True), (6, True), (26, True), (7, False), (6.5, False), (-6, False)):
        rc, _, err, _ = _calibrate(tmp_path, _set(_SMALL_RIG, ("positions", "count"), count), IMU_MODEL)
        assert (rc == 0) == ok, (count, err)


# --------------------------------------------------------------------------- IMU files

EFFECT_PARAMS = [(name, p) for name, e in imu_spec.parameters().items() for p in e.params]
#: A scenario with an IMU model (the file ``imu.toml`` beside it): the model's errors are navigated.
MODEL_RUN = {**HOLD, "imu": {"rate_hz": 20, "model": "imu.toml"},
             "segment": [{"type": "turn", "duration_s": 2.0, "rate_dps": 30.0}]}  # fmt: skip


@pytest.mark.parametrize(("name", "param"), EFFECT_PARAMS, ids=[f"{n}.{p.key}" for n, p in EFFECT_PARAMS])
def test_effect_parameter_at_its_bounds(name: str, param: Param, tmp_path: Path) -> None:
    bound = Bound(param.low, param.high, param.unit, low_open=param.low_open)

    def imu(value: float) -> dict[str, Any]:
        shaped = np.full(param.shape, value).tolist()
        return {"effect": [{"name": name, param.key: shaped}]}

    for value in _inside(bound):
        rc, out, err, files = _calibrate(tmp_path, _SMALL_RIG, imu(value))
        assert rc == 0, f"{name}.{param.key} = {value!r}: {err}"
        rc, out, err, path = _run(tmp_path, MODEL_RUN)
        _assert_sound(rc, out, err, [path], f"{name}.{param.key}")
        assert rc == 0, err
    for value in _outside(bound):
        rc, out, err, files = _calibrate(tmp_path, _SMALL_RIG, imu(value))
        assert rc == 2, f"{name}.{param.key} = {value!r} was taken"
        assert_one_line(err, files)
        assert f"effect[1]: {name}.{param.key}" in err, err


def test_unit_seed(tmp_path: Path) -> None:
    for value, ok in ((0, True), (MAX_SEED, True), (-1, False), (2.5, False)):
        rc, _, err, _ = _calibrate(tmp_path, _SMALL_RIG, {"grade": "tactical", "unit_seed": value})
        assert (rc == 0) == ok, (value, err)
        if not ok:
            assert "unit_seed" in err


def test_quality_tolerances(tmp_path: Path) -> None:
    (tmp_path / "case.toml").write_text(  # a case the suite can run: its cases are checked when read
        'name = "a"\n[imu]\nrate_hz = 10\nmodel = "tactical"\n[compensation]\nrig = "24pos_ratetable"\n'
        '[initial]\nlat_deg = 45\n[[segment]]\ntype = "hold"\nduration_s = 5\n',
        encoding="utf-8",
    )
    for value, ok in ((0.0, True), (quality.MAX_TOLERANCE, True), (-1e-9, False), (100.5, False)):
        path = tmp_path / "suite.toml"
        path.write_text(
            f'[[case]]\nname = "a"\nscenario = "case.toml"\n[tolerance]\nhorizontal = {value!r}\n'
        )
        if ok:
            assert quality.load_suite(path).tolerances["horizontal"] == value
        else:
            refusal(partial(quality.load_suite, path), str(path), "tolerance.horizontal")


# --------------------------------------------------------------------------- the guide


def _guide_rows() -> dict[str, str]:
    """``{field: its row}`` from the guide's bound tables (first cell, in backticks)."""
    rows = {}
    for line in GUIDE.read_text(encoding="utf-8").splitlines():
        match = re.match(r"\|\s*`([^`]+)`\s*\|(.*)\|\s*$", line)
        if match:
            rows[match.group(1)] = match.group(2)
    return rows


def _numbers(text: str) -> set[float]:
    return {float(x) for x in re.findall(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?", text.replace("−", "-"))}


def test_the_guide_lists_every_bound() -> None:
    rows = _guide_rows()
    tables = {**validate.SCENARIO_BOUNDS, **RIG_BOUNDS}
    tables |= {f"{n}.{p.key}": Bound(p.low, p.high, p.unit, low_open=p.low_open) for n, p in EFFECT_PARAMS}
    missing = [k for k in tables if k not in rows]
    assert not missing, f"not in {GUIDE.name}: {missing}"
    for key, bound in tables.items():
        numbers = _numbers(rows[key])
        for value in (bound.low, bound.high):
            assert value in numbers, f"{key}: {value:g} is not in the guide's row {rows[key]!r}"
