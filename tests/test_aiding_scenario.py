"""Aiding from a scenario file: the ``[gnss]``, ``[[outage]]`` and ``[alignment]`` tables, ``sins run``'s
aided report and JSON, and the one-line refusals.

The run's figures are judged against physics, not against themselves: aided errors are metres where
the free run's are kilometres; an outage's error at its end exceeds what the fixes hold before it; the
per-outage error equals the aided solution's error at that sample (recomputed here with numpy from
the library's run).
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import refusal
from test_fuzz import run_cli, to_toml

from sins.runs import pipeline
from sins.scenario import from_dict

DRIVE: dict[str, Any] = {
    "name": "aided",
    "imu": {"rate_hz": 50, "model": "tactical", "seed": 1},
    "gnss": {"rate_hz": 1, "sigma_m": [1.5, 1.5, 3.0], "lever_arm_m": [1.0, 0.0, -1.2], "seed": 3},
    "outage": [{"start_s": 100.0, "end_s": 130.0}],
    "alignment": {"static_s": 60.0, "coarse_s": 30.0, "heading_sigma_deg": 1.0},
    "initial": {"lat_deg": 45.0, "lon_deg": 7.6, "alt_m": 250.0, "yaw_deg": 30.0},
    "segment": [
        {"type": "hold", "duration_s": 60.0},
        {"type": "accelerate", "duration_s": 12.0, "to_speed_mps": 15.0, "ramp_s": 2.0},
        {"type": "turn", "duration_s": 20.0, "angle_deg": 90.0, "ramp_s": 2.0},
        {"type": "hold", "duration_s": 80.0},
    ],
}


def _with(**tables: Any) -> dict[str, Any]:
    doc = copy.deepcopy(DRIVE)
    for key, value in tables.items():
        if value is None:
            doc.pop(key, None)
        else:
            doc[key] = value
    return doc


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, dict[str, Any]]:
    tmp = tmp_path_factory.mktemp("aided")
    path = tmp / "aided.toml"
    path.write_text(to_toml(DRIVE), encoding="utf-8")
    rc, out, err = run_cli(["run", str(path), "--json", str(tmp / "out.json")])
    assert rc == 0, err
    return out, json.loads((tmp / "out.json").read_text())


def test_run_reports_the_aided_errors_and_each_outage(cli_run):
    out, doc = cli_run
    assert "aided by GNSS at 1 Hz (1 outage), filter tuned to the tactical grade" in out
    assert "started aligned over the first 60 s (heading from elsewhere)" in out
    assert "100-130 s" in out
    free, aided = doc["strategies"]["none"], doc["aided"]["none"]
    assert free["final_horizontal_m"] > 100.0 and aided["final_horizontal_m"] < 3.0
    assert aided["fixes"] == 173 - 29 and aided["rejected_fixes"] == 0  # 0..172 s, less 101..129 s
    (window,) = doc["outages"]["none"]
    assert (window["start_s"], window["end_s"]) == (100.0, 130.0)
    # 30 s without fixes: metres, more than the fixes hold the run to, and the worst at the end.
    assert 1.0 < window["final_horizontal_m"] < 30.0
    assert window["final_horizontal_m"] == window["max_horizontal_m"] > aided["rms_horizontal_m"]


def test_the_outage_error_is_the_solutions_error_at_that_sample():
    # The filter alone, from the truth's first state (without [alignment] the run would align itself).
    sc = from_dict(_with(alignment={"method": "truth"}))
    result = pipeline.run_scenario(sc)
    (window,) = result.aided["none"].outages
    # The same aided run from the library's pieces: the error at the last sample before 130 s.
    from sins.aiding import ekf, gnss
    from sins.core import earth
    from sins.nav import strapdown
    from sins.scenario import load_imu

    truth, ideal = pipeline.simulate(sc)
    assert sc.imu_model is not None
    readings = (
        load_imu(sc.imu_model)
        .model(run_seed=1)
        .corrupt_increments(ideal, np.full(len(ideal.t), 20.0), seed=1, dt_nominal=1.0 / 50)
    )
    receiver = gnss.GnssConfig(lever_arm_b=np.array([1.0, 0.0, -1.2]), outages=(gnss.Outage(100.0, 130.0),))
    fixes = gnss.simulate(truth, receiver, seed=3)
    run = ekf.run(
        readings, fixes, ekf.FilterConfig.for_grade("tactical"), strapdown.InitialState.from_series(truth)
    )
    k = int(np.searchsorted(truth.t, 130.0)) - 1
    r_m, r_n = earth.radii(truth.lat[k])
    north = (run.nav.lat[k] - truth.lat[k]) * (r_m + truth.h[k])
    east = (run.nav.lon[k] - truth.lon[k]) * (r_n + truth.h[k]) * np.cos(truth.lat[k])
    assert window.final_m == pytest.approx(np.hypot(north, east), rel=1e-6)
    assert result.aided["none"].fixes == len(fixes)


@pytest.mark.parametrize("unit", ["tactical", "ideal"])
def test_the_aided_runs_reuse_the_streamed_scenario_to_the_last_bit(unit: str):
    """The aided runs take the truth and ideal IMU the stream generated (8,600 samples: two chunks
    joined) instead of simulating the scenario again: every figure and series equals the aided run of
    the whole arrays :func:`pipeline.simulate` makes, bit for bit, with a unit and with the ideal IMU."""
    import dataclasses

    from sins import compensation
    from sins.scenario import load_imu

    sc = from_dict(DRIVE)
    if unit == "ideal":
        sc = dataclasses.replace(sc, imu_model=None)
    result = pipeline.run_scenario(sc, keep_hz=5.0)
    nav_model, grade, strategies = None, None, {"none": None}
    if sc.imu_model is not None:
        spec = load_imu(sc.imu_model)
        nav_model, grade = spec.model(run_seed=sc.imu_seed), spec.grade
        strategies = {"none": compensation.make("none")}
    again = pipeline.aided_runs(sc, strategies, *pipeline.simulate(sc), nav_model, grade, keep_every=10)
    got, want = result.aided["none"], again["none"]
    assert result.samples == 8600 and got.summary == want.summary and got.outages == want.outages
    for field in ("t_cov", "sigma", "bias", "fix_t"):
        np.testing.assert_array_equal(getattr(got, field), getattr(want, field))
    assert got.errors is not None and want.errors is not None
    np.testing.assert_array_equal(got.errors.pos_ned_m, want.errors.pos_ned_m)
    assert (got.true_bias is None) == (unit == "ideal")


def test_bad_aiding_tables_are_refused_in_one_line(tmp_path: Path):
    refusal(
        lambda: from_dict(_with(outage=[{"start_s": 50.0, "end_s": 40.0}])),
        "outage[1].end_s",
        "after start_s",
    )
    # Overlapping or nested: each outage's figure is the error at its own end, where fixes came back
    # (a walkthrough: 100-200 s beside 150-250 s was reported at 200 s, 34 m, with no fix until 250 s).
    for second in ({"start_s": 150.0, "end_s": 250.0}, {"start_s": 110.0, "end_s": 120.0}):
        both = _with(outage=[{"start_s": 100.0, "end_s": 200.0}, second])
        refusal(lambda doc=both: from_dict(doc), "outage[2].start_s", "overlaps outage[1] (100-200 s)")
    refusal(lambda: from_dict(_with(gnss=None)), "outage", "needs a [gnss] receiver")
    refusal(lambda: from_dict(_with(gnss={"sigma_m": [1.0, 2.0]})), "gnss.sigma_m", "expected 3 numbers")
    refusal(lambda: from_dict(_with(gnss={"rate_hz": 50})), "gnss.rate_hz", "<= 10 Hz")
    refusal(lambda: from_dict(_with(gnss={"filter_grade": "fog"})), "gnss.filter_grade")
    refusal(lambda: from_dict(_with(gnss={"antenna": 1})), "gnss.antenna", "unknown key")
    refusal(lambda: from_dict(_with(alignment={"static_s": 30.0, "coarse_s": 40.0})), "alignment.coarse_s")
    # A mean of less than ten readings levels nothing (0.001 s at 100 Hz was taken, a yaw error 5x 40 s's).
    short = _with(alignment={"static_s": 0.001})
    refusal(lambda: from_dict(short), "alignment.static_s", "at least 10 IMU samples")
    # A vehicle that moves within the alignment's window, and a window longer than the run.
    moving = _with(alignment={"static_s": 70.0})
    refusal(lambda: pipeline.run_scenario(from_dict(moving)), "alignment.static_s", "the vehicle moves")
    long = _with(alignment={"static_s": 3000.0})
    refusal(lambda: pipeline.run_scenario(from_dict(long)), "alignment.static_s", "longer than the run")
    # Aligning in motion through an outage of the whole run: said so (it read "the GNSS speed never
    # reaches 5 m/s (at most 0 m/s)", where no fix gave a speed at all).
    blind = _with(alignment={"method": "gnss_velocity"}, outage=[{"start_s": 0.0, "end_s": 1e4}])
    refusal(
        lambda: pipeline.run_scenario(from_dict(blind)), "alignment.min_speed_mps", "give a speed (outages?)"
    )
    # Through the command line: exit 2 and the file's name.
    path = tmp_path / "bad.toml"
    path.write_text(to_toml(_with(outage=[{"start_s": 5.0, "end_s": 5.0}])), encoding="utf-8")
    rc, _, err = run_cli(["run", str(path)])
    assert rc == 2 and str(path) in err and "outage[1].end_s" in err and err.count("\n") <= 1


def test_an_outage_past_the_runs_end_is_shown_to_that_end(tmp_path: Path):
    """An outage that the run's end cuts short was labelled with its whole window (a walkthrough's
    550-700 s of a 600 s run), its figure the run's last sample's: now shown to the run's end."""
    short = _with(imu={"rate_hz": 20, "model": "tactical", "seed": 1}, alignment={"static_s": 20.0},
                  outage=[{"start_s": 30.0, "end_s": 500.0}])  # fmt: skip
    short["segment"] = [
        {"type": "hold", "duration_s": 25.0},
        {"type": "accelerate", "duration_s": 15.0, "to_speed_mps": 10.0, "ramp_s": 2.0},
    ]
    path = tmp_path / "short.toml"
    path.write_text(to_toml(short), encoding="utf-8")
    rc, out, err = run_cli(["run", str(path)])
    assert rc == 0, err
    assert "30-40 s (the run's end)" in out and "30-500 s" not in out


def test_a_scenario_without_gnss_reports_no_aided_runs(tmp_path: Path):
    plain = _with(gnss=None, outage=None, alignment=None, imu={"rate_hz": 20})
    plain["segment"] = plain["segment"][:1]
    path = tmp_path / "plain.toml"
    path.write_text(to_toml(plain), encoding="utf-8")
    rc, out, err = run_cli(["run", str(path), "--json", str(tmp_path / "plain.json")])
    assert rc == 0, err
    doc = json.loads((tmp_path / "plain.json").read_text())
    assert "aided by GNSS" not in out and "aided" not in doc and "outages" not in doc


def test_rerun_shows_the_aided_errors_with_3_sigma_fixes_outages_and_biases(tmp_path: Path):
    from test_viz import _read

    from sins.imu import CHANNELS, display_unit
    from sins.viz import viewer as viz

    result = pipeline.run_scenario(from_dict(DRIVE))
    logged = _read(viz.save(result, tmp_path / "aided.rrd"))
    aided = result.aided["none"]
    assert aided.errors is not None and aided.sigma is not None and aided.bias is not None
    assert aided.true_bias is not None and aided.t_cov is not None and aided.fix_t is not None
    north = logged["/aided/north_m/none"]
    # The last logged error is the run's final error; the bands are ±3 of the filter's σ.
    assert north["scalars"][-1] == pytest.approx(aided.summary.final_north_m, abs=1e-9)
    assert np.allclose(logged["/aided/north_m/none_plus_3sigma"]["scalars"], 3.0 * aided.sigma[:, 0])
    assert np.allclose(
        logged["/aided/yaw_deg/none_minus_3sigma"]["scalars"], -3.0 * np.degrees(aided.sigma[:, 8])
    )
    assert np.allclose(logged["/aided/horizontal_m/fixes"]["t"], aided.fix_t)
    assert np.allclose(logged["/aided/horizontal_m/outages"]["t"], [100.0, 100.0, 130.0, 130.0])
    for i, channel in enumerate(CHANNELS):
        unit = display_unit(channel)[0]
        entity = f"/aided/bias/{viz.imu_entity(channel)}"
        assert np.allclose(logged[f"{entity}/true"]["scalars"], aided.true_bias[i] / unit)
        assert np.allclose(logged[f"{entity}/none"]["scalars"], aided.bias[:, i] / unit)
    # The drive's turns teach the filter the horizontal accelerometer biases: the last estimate is
    # within 3σ of the unit's constant bias, give or take its bias instability (20 µg = 2e-4 m/s²).
    last = aided.bias[-1, 3:5] - aided.true_bias[3:5]
    assert np.all(np.abs(last) < 3.0 * aided.sigma[-1, 12:14] + 2e-4), (last, aided.sigma[-1, 12:14])


def test_the_progress_ends_when_the_aided_filters_do(monkeypatch: pytest.MonkeyPatch):
    """A run's progress counts the aided filters, which run after the stream: its bar reached its end
    while a 2 h aided run still filtered for 20 s. Every call moves forward, and the end is reported only
    after the last filter has run (the filters are marked in the same log as the calls)."""
    from sins.aiding import policy

    log: list[tuple[str, int, int]] = []
    aligned = policy.run_aligned

    def marked(*args: Any, **kwargs: Any) -> Any:
        out = aligned(*args, **kwargs)
        log.append(("filter", 0, 0))
        return out

    monkeypatch.setattr(policy, "run_aligned", marked)
    pipeline.run_scenario(from_dict(DRIVE), progress=lambda done, work: log.append(("progress", done, work)))
    calls = [(done, work) for kind, done, work in log if kind == "progress"]
    last_filter = max(i for i, (kind, _, _) in enumerate(log) if kind == "filter")
    assert all(done < work for kind, done, work in log[:last_filter] if kind == "progress")
    assert log[-1][0] == "progress" and calls[-1][0] == calls[-1][1]
    assert [d for d, _ in calls] == sorted(d for d, _ in calls) and len({w for _, w in calls}) == 1


def test_an_outage_that_drops_no_fix_is_said_so(tmp_path: Path):
    """An outage drops the fixes strictly inside it: 100-101 s at 1 Hz drops none, and was reported as
    an outage without a word. Now a note says so; the run's fixes are those of no outage at all (173),
    and an outage that drops fixes (100-130 s) has no note. The same in the library."""
    from sins import scenario

    doc = _with(outage=[{"start_s": 100.0, "end_s": 101.0}, {"start_s": 110.0, "end_s": 130.0}])
    path = tmp_path / "idle.toml"
    path.write_text(to_toml(doc), encoding="utf-8")
    rc, _, err = run_cli(["run", str(path), "--json", str(tmp_path / "idle.json")])
    assert rc == 0, err
    assert "outage 100-101 s drops no fix of the 1 Hz receiver" in err and "110-130" not in err
    assert json.loads((tmp_path / "idle.json").read_text())["aided"]["none"]["fixes"] == 173 - 19
    assert scenario.idle_outages(from_dict(DRIVE)) == []
    shifted = _with(outage=[{"start_s": 100.5, "end_s": 101.5}])
    assert scenario.idle_outages(from_dict(shifted)) == []  # the fix at 101 s is dropped
    # An outage after the motion ends (DRIVE lasts under 200 s) was counted among the outages and said
    # nothing else: now a note.
    beyond = scenario.idle_outages(from_dict(_with(outage=[{"start_s": 700.0, "end_s": 800.0}])))
    assert len(beyond) == 1 and beyond[0].startswith("the outage 700-800 s starts after the motion ends (")
