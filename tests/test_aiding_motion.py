"""In-motion alignment from the GNSS velocity, the latency the filter compensates, refused velocities,
and the alignment a scenario picks by itself.

References, independent of the code under test: the truth's attitude, position and velocity at the
alignment's sample; the heading error a course over ground carries, ``σ_v / v`` (the velocity noise
across the track over the speed, the simulator's vehicle having no sideslip); the along-track offset an
uncompensated latency leaves, ``v · latency``; χ² bounds on normalised errors over seeded draws.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import refusal
from scipy.stats import chi2
from test_fuzz import run_cli, to_toml

from sins.aiding import alignment, ekf, gnss
from sins.core.series import ImuIncrements, NavSeries
from sins.imu import spec
from sins.nav import strapdown, trajectory
from sins.nav.motion import Accelerate, Hold, SegmentMotion, Start, Turn
from sins.runs import pipeline
from sins.scenario import from_dict

D = np.radians
ARM = np.array([1.0, 0.0, -1.2])


def no_stop() -> SegmentMotion:
    """A drive that starts moving at once: accelerate, turns both ways, slow down and speed up."""
    return SegmentMotion.from_segments(
        Start(lat=D(45.0), lon=D(7.6), h=250.0, yaw=D(30.0)),
        [Accelerate(12, 15.0, 2.0), Hold(20), Turn(15, D(6.0), 2.0), Hold(30), Turn(20, D(-4.5), 2.0),
         Accelerate(8, 5.0, 2.0), Hold(30), Turn(15, D(6.0), 2.0), Accelerate(10, -8.0, 2.0), Hold(40)],
    )  # fmt: skip


@pytest.fixture(scope="module")
def drive() -> tuple[NavSeries, ImuIncrements]:
    return trajectory.generate(no_stop(), 100.0)


def _start_errors(start: alignment.MotionStart, truth: NavSeries) -> np.ndarray:
    """Position, velocity and attitude errors (9,) of the alignment's state against the truth there."""
    s = start.initial
    one = NavSeries(t=truth.t[start.index : start.index + 1], lat=np.array([s.lat]), lon=np.array([s.lon]),
                    h=np.array([s.h]), v_n=s.v_n[None], q_nb=s.q_nb[None])  # fmt: skip
    return ekf.nav_error_state(one, truth.at(start.index))[0]


def test_in_motion_alignment_errors_match_what_the_gnss_velocity_predicts(drive):
    """40 receivers (velocity noise 0.1 m/s) align the ideal IMU as it passes 5 m/s: the heading σ told
    to the filter is ``σ_v / v`` (no sideslip told), and every state's error, normalised by its told σ,
    has a mean square within χ²₄₀'s 99 % band (0.54..1.58): neither optimistic nor padded."""
    truth, ideal = drive
    config = ekf.FilterConfig.for_grade("tactical")
    motion = alignment.MotionConfig(sideslip_sigma_rad=0.0)
    z2 = []
    for seed in range(40):
        fixes = gnss.simulate(truth, gnss.GnssConfig(sigma_vel_mps=0.1, lever_arm_b=ARM), seed=seed)
        start = alignment.in_motion_start(ideal, fixes, config, motion)
        speed = float(np.hypot(*truth.v_n[start.index, :2]))
        assert start.speed_mps == pytest.approx(speed, abs=0.5)  # 5σ of the fix's velocity
        assert start.heading_sigma_rad == pytest.approx(0.1 / start.speed_mps, rel=1e-3)
        z2.append(_start_errors(start, truth) ** 2 / np.diag(start.P0)[:9])
    band = chi2.ppf([0.005, 0.995], 40) / 40
    mean = np.mean(z2, axis=0)
    assert np.all((mean > band[0]) & (mean < band[1])), np.round(mean, 2)


def test_without_receiver_velocities_the_chord_of_the_fixes_gives_the_heading(drive):
    """Position fixes only: the velocity is the chord over 2 s (noise √2·1.5 m / 2 s, 1.06 m/s a
    component), so the heading at 5 m/s is known to ~12°; each of 40 draws lies within 3 of its
    told σ's 4 in every state (360 draws: a 3σ one is expected) and every state's mean square is
    under χ²₄₀'s 99 % bound (the chord's lag and the unmodelled acceleration may make σ conservative)."""
    truth, ideal = drive
    config = ekf.FilterConfig.for_grade("tactical")
    z = []
    for seed in range(40):
        fixes = gnss.simulate(truth, gnss.GnssConfig(lever_arm_b=ARM), seed=seed)
        start = alignment.in_motion_start(ideal, fixes, config, alignment.MotionConfig())
        z.append(_start_errors(start, truth) / np.sqrt(np.diag(start.P0)[:9]))
        assert start.heading_sigma_rad > 1.06 / 20.0  # at least the chord's noise over a car's speed
    assert np.all(np.abs(z) < 4.0), np.round(np.abs(z).max(axis=0), 2)
    assert np.all(np.mean(np.square(z), axis=0) < chi2.ppf(0.995, 40) / 40)


@pytest.mark.parametrize("sigma_vel", [0.1, None])
def test_the_aided_solution_converges_after_an_in_motion_start(drive, sigma_vel):
    """A tactical unit (biases, noise) aligned in motion: from a minute on, every attitude error at an
    update lies within 3σ of the filter's, and the heading σ has shrunk to under a fifth of the
    alignment's (the turns make it observable)."""
    truth, ideal = drive
    readings = spec.draw_unit("tactical", 1, run_seed=1).corrupt_increments(ideal, seed=1, dt_nominal=0.01)
    fixes = gnss.simulate(truth, gnss.GnssConfig(sigma_vel_mps=sigma_vel, lever_arm_b=ARM), seed=3)
    config = ekf.FilterConfig.for_grade("tactical")
    start, result = alignment.in_motion_run(readings, fixes, config, alignment.MotionConfig())
    assert result.nav.t[0] == truth.t[start.index] and result.rejected == 0
    errors = ekf.nav_error_state(result.nav, truth.at(np.arange(start.index, len(truth.t))))
    rec = result.after_update & (result.t_cov > result.nav.t[0] + 60.0)
    at = np.searchsorted(result.nav.t, result.t_cov[rec])
    ratio = np.abs(errors[at, 6:9]) / result.sigma()[rec, 6:9]
    assert np.all(ratio < 3.0), ratio.max(axis=0)
    assert result.sigma()[-1, 8] < start.heading_sigma_rad / 5.0


def test_a_vehicle_that_never_reaches_the_speed_is_refused_in_one_line(drive):
    truth, ideal = drive
    fixes = gnss.simulate(truth, gnss.GnssConfig(sigma_vel_mps=0.1), seed=1)
    config = ekf.FilterConfig.for_grade("tactical")
    refusal(
        lambda: alignment.in_motion_start(ideal, fixes, config, alignment.MotionConfig(min_speed_mps=30.0)),
        "alignment.min_speed_mps", "30 m/s", "at most 20", 'method = "static"',
    )  # fmt: skip
    refusal(lambda: alignment.MotionConfig(level_s=0.0), "level_s")
    refusal(lambda: alignment.MotionConfig(sideslip_sigma_rad=-1.0), "sideslip")


def _straight(seconds: float, speed: float) -> tuple[NavSeries, ImuIncrements]:
    motion = SegmentMotion.from_segments(
        Start(lat=D(45.0), lon=D(7.6), h=250.0, yaw=D(30.0), speed=speed), [Hold(seconds)]
    )
    return trajectory.generate(motion, 50.0)


def test_a_known_latency_is_compensated():
    """0.2 s latency at 20 m/s, 10 receivers: taken as of its stamp, a fix lies v·latency = 4 m behind
    and the aided solution follows it (mean along-track error 4 m lower than without latency); told to
    the filter, the solution is the one without latency, within the spread of the 10 draws' mean."""
    truth, ideal = _straight(120.0, 20.0)
    readings = spec.draw_unit("tactical", 1, run_seed=1).corrupt_increments(ideal, seed=1, dt_nominal=0.02)
    config = ekf.FilterConfig.for_grade("tactical")
    track = np.array([np.cos(D(30.0)), np.sin(D(30.0))])
    along = {}
    for label, latency, told in (("none", 0.0, True), ("stamp", 0.2, False), ("told", 0.2, True)):
        means = []
        for seed in range(10):
            receiver = gnss.GnssConfig(latency_s=latency, compensate_latency=told, lever_arm_b=ARM)
            fixes = gnss.simulate(truth, receiver, seed=seed)
            assert fixes.latency_s == (latency if told else 0.0)
            result = ekf.run(readings, fixes, config, strapdown.InitialState.from_series(truth))
            late = truth.t > 30.0  # the filter settled
            means.append(float(np.mean(ekf.nav_error_state(result.nav, truth)[late, :2] @ track)))
        along[label] = np.array(means)
    spread = 3.0 * along["none"].std(ddof=1) / np.sqrt(10) * np.sqrt(2)  # two means' difference, 3σ
    assert along["stamp"].mean() - along["none"].mean() == pytest.approx(-20.0 * 0.2, abs=0.3)
    assert abs(along["told"].mean() - along["none"].mean()) < spread


def test_latency_with_velocity_fixes_in_turns_and_refused_velocities_are_counted():
    """5 Hz fixes with velocity, 0.2 s late, through turns at 20 m/s: told the latency, the horizontal
    RMS error is the one without latency (within 3σ of the 5 draws' mean) and no velocity is refused;
    not told, the velocities are 0.2 s of a 2 m/s² centripetal turn off (0.4 m/s, against 0.1 m/s
    noise): the gate refuses some, and counts them apart from the positions."""
    motion = SegmentMotion.from_segments(
        Start(lat=D(45.0), lon=D(7.6), h=250.0, yaw=D(30.0), speed=20.0),
        [Hold(20), Turn(30, D(6.0), 2.0), Hold(20), Turn(30, D(-6.0), 2.0), Hold(20)],
    )
    truth, ideal = trajectory.generate(motion, 50.0)
    readings = spec.draw_unit("tactical", 1, run_seed=1).corrupt_increments(ideal, seed=1, dt_nominal=0.02)
    config = ekf.FilterConfig.for_grade("tactical")
    rms, refused = {}, {}
    for label, latency, told in (("none", 0.0, True), ("stamp", 0.2, False), ("told", 0.2, True)):
        rows = []
        for seed in range(5):
            receiver = gnss.GnssConfig(rate_hz=5.0, sigma_vel_mps=0.1, latency_s=latency,
                                       compensate_latency=told, lever_arm_b=ARM)  # fmt: skip
            result = ekf.run(readings, gnss.simulate(truth, receiver, seed=seed), config,
                             strapdown.InitialState.from_series(truth))  # fmt: skip
            e = ekf.nav_error_state(result.nav, truth)[truth.t > 20.0, :2]
            rows.append((np.sqrt(np.mean(np.sum(e**2, axis=1))), result.rejected, result.velocity_rejected))
        values = np.array(rows)
        rms[label], refused[label] = values[:, 0], values[:, 1:].sum(axis=0)
    spread = 3.0 * rms["none"].std(ddof=1) / np.sqrt(5) * np.sqrt(2)
    assert abs(rms["told"].mean() - rms["none"].mean()) < spread
    assert refused["told"].tolist() == [0, 0] and refused["none"].tolist() == [0, 0]
    assert refused["stamp"][0] == 0 and refused["stamp"][1] > 10


def test_a_wild_velocity_is_refused_and_counted():
    truth, ideal = _straight(30.0, 10.0)
    fixes = gnss.simulate(truth, gnss.GnssConfig(sigma_vel_mps=0.1), seed=2)
    v_n = fixes.v_n.copy()
    v_n[12] += np.array([5.0, 0.0, 0.0])  # 50σ
    fixes = gnss.GnssFixes(t=fixes.t, lat=fixes.lat, lon=fixes.lon, h=fixes.h, v_n=v_n,
                           sigma_pos_m=fixes.sigma_pos_m, sigma_vel_mps=0.1)  # fmt: skip
    config = ekf.FilterConfig.for_grade("navigation")
    result = ekf.run(ideal, fixes, config, strapdown.InitialState.from_series(truth))
    assert result.rejected == 0 and result.velocity_rejected == 1
    assert not result.velocity_accepted[12] and result.velocity_tried[12]


# A scenario: a tactical unit, 1 Hz fixes with velocity, a drive that starts with a 40 s stop.
DRIVE: dict[str, Any] = {
    "name": "aided",
    "imu": {"rate_hz": 50, "model": "tactical", "seed": 1},
    "gnss": {"rate_hz": 1, "sigma_vel_mps": 0.1, "lever_arm_m": [1.0, 0.0, -1.2], "seed": 3},
    "initial": {"lat_deg": 45.0, "lon_deg": 7.6, "alt_m": 250.0, "yaw_deg": 30.0},
    "segment": [
        {"type": "hold", "duration_s": 40.0},
        {"type": "accelerate", "duration_s": 12.0, "to_speed_mps": 15.0, "ramp_s": 2.0},
        {"type": "turn", "duration_s": 20.0, "angle_deg": 90.0, "ramp_s": 2.0},
        {"type": "hold", "duration_s": 60.0},
    ],
}


def _scenario(**changes: Any) -> dict[str, Any]:
    doc = copy.deepcopy(DRIVE)
    for key, value in changes.items():
        doc[key] = value
    return doc


def test_a_scenario_without_alignment_aligns_by_itself():
    """No [alignment]: a tactical gyro cannot find north (5 °/h against Ω cos 45° = 10.6 °/h), so even
    with a stop the run aligns in motion, when the speed passes 5 m/s (at 40 s + 2 s ramp + ~4 s);
    a navigation-grade unit on the same stop aligns still over it; a drive without a stop aligns in
    motion; ``method = "truth"`` starts from the truth."""
    runs = {
        "tactical": pipeline.run_scenario(from_dict(_scenario())),
        "navigation": pipeline.run_scenario(from_dict(_scenario(imu={"rate_hz": 50, "model": "navigation"}))),
        "moving": pipeline.run_scenario(from_dict(_scenario(segment=DRIVE["segment"][1:]))),
        "truth": pipeline.run_scenario(from_dict(_scenario(alignment={"method": "truth"}))),
    }
    got = {name: (r.aided["none"].alignment, r.aided["none"].start_s) for name, r in runs.items()}
    assert got["tactical"][0] == "gnss_velocity" and 44.0 < got["tactical"][1] < 48.0
    assert got["navigation"] == ("static", 0.0)
    assert runs["navigation"].aided["none"].static_s == pytest.approx(40.0, abs=0.05)  # the stop
    assert got["moving"][0] == "gnss_velocity" and 4.0 < got["moving"][1] < 8.0
    assert got["truth"] == ("truth", 0.0)
    for name, r in runs.items():  # aligned, the filter holds the drive to metres
        assert r.aided["none"].summary.final_horizontal_m < 5.0, name
    moving = runs["moving"].aided["none"]
    assert moving.errors is not None and moving.errors.t[0] == moving.start_s


def test_sins_run_reports_the_alignment_and_the_refused_velocities(tmp_path: Path):
    path = tmp_path / "aided.toml"
    path.write_text(to_toml(_scenario(segment=DRIVE["segment"][1:])), encoding="utf-8")
    rc, out, err = run_cli(["run", str(path), "--json", str(tmp_path / "out.json")])
    assert rc == 0, err
    assert "started aligned in motion at" in out and "heading from the GNSS velocity" in out
    assert "rejected v" in out
    aided = json.loads((tmp_path / "out.json").read_text())["aided"]["none"]
    assert aided["alignment"] == "gnss_velocity" and aided["rejected_velocity_fixes"] == 0
    assert 4.0 < aided["alignment_start_s"] < 8.0 and 0.0 < aided["alignment_heading_sigma_deg"] < 5.0


def test_bad_alignment_tables_are_refused_in_one_line():
    refusal(lambda: from_dict(_scenario(alignment={"method": "compass"})), "alignment.method", "one of")
    refusal(
        lambda: from_dict(_scenario(alignment={"method": "gnss_velocity", "static_s": 30.0})),
        "alignment.static_s", "not read by method 'gnss_velocity'",
    )  # fmt: skip
    refusal(
        lambda: from_dict(_scenario(alignment={"static_s": 30.0, "min_speed_mps": 3.0})),
        "alignment.min_speed_mps", "not read by method 'static'",
    )  # fmt: skip
    refusal(
        lambda: from_dict(_scenario(alignment={"method": "truth", "coarse_s": 3.0})), "alignment.coarse_s"
    )
    slow = _scenario(alignment={"method": "gnss_velocity", "min_speed_mps": 20.0})
    refusal(lambda: pipeline.run_scenario(from_dict(slow)), "aided: alignment.min_speed_mps", "20 m/s")
    refusal(lambda: from_dict(_scenario(gnss={"compensate_latency": 1})), "gnss.compensate_latency")
