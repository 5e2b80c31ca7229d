"""Fits on several recordings of one unit (sins.compensation.several,
sins.compensation.referenced.fit_several), the
rule for a new recording's gyro bias (sins.compensation.unit_bias) and ``sins fit`` on several recordings,
judged on data sins did not make: units of known errors written with numpy (tests/numpy_referenced.py, and
a bounded-velocity recording below) and EuRoC's real recordings (skipped without the data)."""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import shutil
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from conftest import dataset_folder, refusal
from numpy_units import recordings, write_npz
from scipy.spatial.transform import Rotation

from sins import compensation, io
from sins.cli import main
from sins.compensation import (
    bias_spread,
    evaluation,
    interval_fit,
    judging,
    online_bias,
    referenced,
    rule_choice,
    several,
    unit_bias,
)
from sins.compensation.evaluation import Evaluation
from sins.compensation.kohonen import LocalLinearMap
from sins.compensation.regression import Regression
from sins.core.series import ImuIncrements, ImuRates

EUROC = dataset_folder("euroc")
needs_euroc = pytest.mark.skipif(not (EUROC / "V1_01_easy.npz").is_file(), reason=f"no EuRoC data in {EUROC}")


@pytest.mark.parametrize("seed", [4, 5])
def test_shared_coefficients_and_each_recordings_bias_are_recovered(seed: int) -> None:
    """Three recordings, three gyro biases 0.1 °/s apart: each recording's bias within 4 of its standard
    errors, the shared scale and misalignment too, and their z-scores' RMS between 0.4 and 2 (honest
    standard errors; 3 × 9 + 9 values scatter by ~0.15)."""
    recs, unit, biases = recordings(seed)
    fit = several.fit_several(recs)
    z_bias = (fit.gyro_bias - biases) / fit.gyro_bias_se
    z_b = (fit.seed.B - unit.B) / fit.seed.B_se
    z = np.concatenate([z_bias.ravel(), z_b.ravel()])
    assert np.all(np.abs(z) < 4.0), z.round(2)
    assert 0.4 < float(np.sqrt(np.mean(z * z))) < 2.0, z.round(2)
    # One pooled bias would miss each recording's by their spread (0.1 °/s); the own ones are far closer.
    rms = lambda x: float(np.sqrt(np.mean(x * x)))  # noqa: E731
    assert rms(fit.gyro_bias - biases) < 0.3 * rms(biases - biases.mean(axis=0))
    assert fit.time_offset_s == pytest.approx(unit.gyro_delay_s, abs=4 * fit.time_offset_se_s)


def test_one_recording_for_each_recording_reproduces_its_own_fit_bias() -> None:
    recs, _, _ = recordings(6)
    fit = several.fit_several(recs)
    for r in range(len(recs)):
        own = fit.for_recording(r)
        np.testing.assert_array_equal(own.seed.B0, fit.gyro_bias[r])
        np.testing.assert_array_equal(own.seed.B, fit.seed.B)


def _bounded_flight(seed: int, *, bias: np.ndarray, rest_s: float = 0.0, duration_s: float = 120.0,
                    rate_hz: float = 200.0,
                    rest_offset: np.ndarray | None = None) -> ImuIncrements:  # fmt: skip
    """A vehicle that yaws freely, tilts by up to 15° and moves at up to ~1 m/s in a room (its velocity
    bounded), after ``rest_s`` standing still; a gyro of bias ``bias`` (``bias + rest_offset`` at rest:
    motors idling) and white noise; gravity 9.81 up.
    Written with numpy and scipy's Rotation only (increments: the exact turn of each step, its rotation
    vector; the specific force's mean over the step, trapezoid)."""
    rng = np.random.default_rng(seed)
    n = round(duration_s * rate_hz)
    t = np.arange(n + 1) / rate_hz
    moving = np.clip((t - rest_s) / 2.0, 0.0, 1.0)[:, None]  # motion eases in over 2 s after the rest
    f_tilt, f_yaw = rng.uniform(0.05, 0.2, 2), rng.uniform(0.02, 0.06)
    tilt = np.radians(15.0) * moving * np.sin(2 * np.pi * np.outer(t, f_tilt) + rng.uniform(0, 6, 2))
    yaw = moving[:, 0] * 3.0 * np.sin(2 * np.pi * f_yaw * t)
    att = Rotation.from_euler("ZYX", np.column_stack([yaw, tilt[:, 0], tilt[:, 1]]))  # body to frame, z up
    fv = rng.uniform(0.05, 0.2, 3)
    v = moving * 0.8 * np.sin(2 * np.pi * np.outer(t, fv))
    a = np.gradient(v, t, axis=0)
    f_frame = a + np.array([0.0, 0.0, 9.81])
    f_b = att.inv().apply(f_frame)
    # White noise of 2e-3 rad/s a sample on the rate (its mean over a step).
    still = 1.0 - moving[1:] if rest_offset is not None else np.zeros((n, 1))
    bias_t = bias + still * (np.zeros(3) if rest_offset is None else rest_offset)
    dtheta = (att[:-1].inv() * att[1:]).as_rotvec() + (bias_t + rng.normal(0.0, 2e-3, (n, 3))) / rate_hz
    dv = 0.5 * (f_b[:-1] + f_b[1:]) / rate_hz + rng.normal(0.0, 0.02, (n, 3)) / rate_hz
    return ImuIncrements(t=t, dtheta_b=dtheta, dv_b=dv)


def test_the_opening_rest_is_found_from_the_readings() -> None:
    still = _bounded_flight(1, bias=np.array([0.01, -0.02, 0.03]), rest_s=3.0)
    dt = np.diff(still.t)
    rest = unit_bias.opening_rest(still.dtheta_b / dt[:, None], still.dv_b / dt[:, None], float(dt[0]))
    # The rest ends at 3 s; motion eases in, so the detection may run a window past it, never before.
    assert 3.0 <= rest * dt[0] <= 3.0 + 2 * unit_bias.REST_WINDOW_S
    moving = _bounded_flight(1, bias=np.array([0.01, -0.02, 0.03]))
    assert unit_bias.opening_rest(moving.dtheta_b / dt[:, None], moving.dv_b / dt[:, None], float(dt[0])) == 0


def test_the_rest_rule_takes_the_opening_rest_and_nothing_before_it() -> None:
    bias = np.array([0.01, -0.02, 0.03])
    imu = _bounded_flight(2, bias=bias, rest_s=4.0)
    rule = unit_bias.BiasRule(mode="rest", prior=np.zeros(3), rest_offset=np.zeros(3))
    track = unit_bias.bias_track(rule, imu)
    np.testing.assert_array_equal(track[0], 0.0)  # before the rest has ended: the prior
    # After: the rest's mean rate, the bias to its noise (2e-3 rad/s a sample over 800 samples).
    np.testing.assert_allclose(track[-1], bias, atol=4 * 2e-3 / math.sqrt(800))


def test_a_unit_at_rest_takes_its_bias_from_its_rest_so_far() -> None:
    """While a unit rests, the readings so far tell its bias: each step's is the rest's mean rate before
    it and the pooled prior weighted by their precisions, after the first window (the rest is told from
    whole windows). A new-user walk's unit stood still for its whole recording and kept the pooled prior
    throughout (the rest's end, after which its mean was taken, never came): its open loop drifted by the
    prior's error, and a correction was worse than the raw readings (9.05° against 7.38°). Here 60 s at
    rest, the prior 0.03 rad/s off on every axis: the attitude integrated over the rest is off by the
    first window's share of it and the noise, not by the whole minute's."""
    bias = np.array([0.01, -0.02, 0.03])
    imu = _bounded_flight(3, bias=bias, rest_s=60.0, duration_s=60.0)
    rule = unit_bias.BiasRule(mode="rest", prior=np.zeros(3), spread=np.full(3, 0.01),
                              rest_offset=np.full(3, 2e-3))  # fmt: skip
    track = unit_bias.bias_track(rule, imu)
    first = round(unit_bias.REST_WINDOW_S * 200.0)
    np.testing.assert_array_equal(track[:first], 0.0)
    k = np.arange(first, len(track))[:, None]
    assert np.all(np.abs(track[first:] - bias) < 5 * 2e-3 / np.sqrt(k) + 1e-4 * np.abs(bias))
    drift = np.abs(((bias - track) * np.diff(imu.t)[:, None]).sum(axis=0))
    assert np.all(drift < 1.1 * unit_bias.REST_WINDOW_S * np.abs(bias)), drift  # the whole minute: 60 s · |b|
    both = unit_bias.with_mode(rule, "rest+online")  # the online estimate takes over after the rest only
    np.testing.assert_array_equal(unit_bias.bias_track(both, imu), track)


def test_the_online_rule_holds_the_accelerometer_bias_to_the_recordings_own_spread() -> None:
    """The online estimate's prior on a new recording's accelerometer bias is the spread of the training
    recordings' own (standard deviation per axis, ddof 1, root mean square over the axes) raised to its
    upper 95 % bound (chi-squared of r − 1 degrees of freedom; the quantiles from their tables: 0.1026
    for 2, 0.3518 for 3), at least 1e-3 m/s²; without them, or with one recording, the rule keeps its
    default (0.2 m/s²)."""
    streams = [_bounded_flight(seed, bias=np.zeros(3), duration_s=10.0) for seed in range(31, 35)]
    accel = np.array(
        [[0.010, -0.020, 0.000], [0.030, 0.000, 0.010], [-0.010, 0.020, -0.010], [0.0, 0.0, 0.02]]
    )
    for r, quantile in ((3, 0.1026), (4, 0.3518)):
        rows = accel[:r]
        per_axis = [math.sqrt(sum((a - sum(c) / r) ** 2 for a in c) / (r - 1)) for c in rows.T]  # by hand
        spread = math.sqrt(sum(v * v for v in per_axis) / 3) * math.sqrt((r - 1) / quantile)
        rule = unit_bias.rule_from(np.zeros((r, 3)), streams[:r], accel_biases=rows)
        assert rule.sigma_accel_mps2 == pytest.approx(spread, rel=2e-4), r  # the tables' 4 digits
    same = unit_bias.rule_from(np.zeros((3, 3)), streams[:3], accel_biases=np.tile(accel[:1], (3, 1)))
    assert same.sigma_accel_mps2 == 1e-3
    default = unit_bias.BiasRule().sigma_accel_mps2
    assert unit_bias.rule_from(np.zeros((3, 3)), streams[:3]).sigma_accel_mps2 == default
    one = unit_bias.rule_from(np.zeros((1, 3)), streams[:1], accel_biases=accel[:1])
    assert one.sigma_accel_mps2 == default


def test_the_nearest_rule_takes_the_prior_of_the_day_whose_rests_read_alike() -> None:
    """A unit whose bias moves by 4e-3 rad/s between two days and 2e-4 within one, each rest reading its
    bias in flight plus a motor's 3e-4: trained on two recordings of each day, a new recording of day B
    takes day B's bias after its rest (within 1e-3 rad/s, where the pooled prior is 1.5e-3 off or more on
    every axis), and the pooled prior until its rest has ended; a recording of a day never seen (its rest
    0.03 rad/s from every one) and one that opens moving take the online estimate from the pooled prior,
    which their velocity takes nearer their bias than that prior (the one that opens moving keeps the prior
    until the estimate's first update). Its spread is what each training recording's prior from the others
    missed by: its day's sibling, not the pooled spread."""
    rng = np.random.default_rng(11)
    day_a = np.array([0.01, -0.02, 0.03])
    day_b = day_a + 4e-3

    def recording(seed: int, day: np.ndarray, rest_s: float = 3.0) -> tuple[np.ndarray, ImuIncrements]:
        bias = day + rng.normal(0.0, 2e-4, 3)
        motors = rng.normal(0.0, 3e-4, 3)
        return bias, _bounded_flight(seed, bias=bias, rest_s=rest_s, duration_s=20.0, rest_offset=motors)

    train = [recording(seed, day) for seed, day in ((21, day_a), (22, day_a), (23, day_b), (24, day_b))]
    rule = unit_bias.rule_from(np.array([b for b, _ in train]), [s for _, s in train], mode="nearest")
    assert np.all(rule.nearest_spread < 1e-3) and np.all(rule.spread > 1.5e-3), (
        rule.nearest_spread,
        rule.spread,
    )
    bias, new = recording(25, day_b)
    track = unit_bias.bias_track(rule, new)
    np.testing.assert_array_equal(track[0], rule.prior)  # before the rest has ended
    assert np.abs(track[-1] - bias).max() < 1e-3 and np.abs(rule.prior - bias).min() > 1.5e-3
    (far_bias, far), (moving_bias, moving) = recording(26, day_a + 0.03), recording(27, day_b, rest_s=0.0)
    for b, other in ((far_bias, far), (moving_bias, moving)):
        # Measured: 0.048 -> 0.041 rad/s (far), 3.5e-3 -> 2.7e-3 (opens moving).
        end = unit_bias.bias_track(rule, other)[-1]
        assert np.linalg.norm(end - b) < 0.9 * np.linalg.norm(rule.prior - b)
    first_update = round(online_bias.UPDATE_S / float(np.median(np.diff(moving.t))))
    np.testing.assert_array_equal(
        unit_bias.bias_track(rule, moving)[:first_update], rule.prior[None, :].repeat(first_update, 0)
    )
    # What sins evaluate says of each, beside the judged figures.
    assert "reads like some training recordings' rests" in unit_bias.prior_said(rule, new)
    assert "weighed against the rest's own reading" in unit_bias.prior_said(rule, new)  # four rests
    said = unit_bias.prior_said(rule, far)
    assert "reads like no training recording's (" in said and "another unit, a new day?)" in said
    # 0.03 rad/s from its day on every axis, against rests that differ by their noise and motors (3e-4):
    # tens of standard deviations, said (before, no figure).
    assert float(said.split("recording's (")[1].split(" standard")[0]) > 20.0, said
    said = unit_bias.prior_said(rule, moving)
    # A calibrated numpy unit's moving opener (tools/euroc_units.py --seeds 3312): 85.71° of its 86.21°
    # lay along gravity, where the prior alone had set the bias; evaluate says where that part comes from.
    assert "opens moving" in said and "along gravity turns the heading" in said, said


def test_nearest_weighs_the_matched_days_bias_against_the_rests_own_reading() -> None:
    """``nearest``'s prior is the least-variance combination, per axis, of the matched training
    recordings' bias (which missed by ``nearest_spread`` held back) and this rest's reading plus their
    own bias in motion less at rest (missing by the two rests' noise and twice the offsets' spread),
    written here by hand for one match; the matches alone where the matches predicted to nothing (a
    unit of a few days), the rest's reading where they missed by far more (each recording a new
    power-up: a helper's unit had a judged rest read like a training recording's and took its bias,
    4.64° raw to 17.01°). The matches alone, too, where fewer than three training recordings have a
    rest (their miss was not measured) and in a rule written before (no ``nearest_blend``)."""
    rates = np.array([[1e-3, 2e-3, -1e-3], [9e-3, -6e-3, 5e-3], [-8e-3, 7e-3, 6e-3]])
    off = np.array([[2e-4, -1e-4, 3e-4], [-3e-4, 2e-4, 1e-4], [1e-4, 1e-4, -2e-4]])
    biases = rates + off  # bias in motion, each rest's own
    rule = unit_bias.BiasRule(
        mode="nearest", rest_rates=rates, rest_rates_se=np.full((3, 3), 1e-4), rest_biases=biases,
        rest_spread=np.full(3, 2e-4), nearest_spread=np.array([1e-3, 5e-4, 2e-3]), nearest_blend=True,
    )  # fmt: skip
    rest, rest_se = rates[0] + np.array([3e-4, -2e-4, 1e-4]), np.full(3, 1.5e-4)  # near the first only
    match = unit_bias.nearest_prior(rule, rest, rest_se)
    assert match is not None
    np.testing.assert_allclose(match, biases[0], atol=1e-9)  # the others are 24 standard deviations away
    own = rest + (biases[0] - rates[0])
    var_match, var_own = rule.nearest_spread**2, 1.5e-4**2 + 1e-4**2 + 2 * 2e-4**2
    expected = (var_own * biases[0] + var_match * own) / (var_match + var_own)
    np.testing.assert_allclose(unit_bias.blended_nearest_prior(rule, rest, rest_se), expected, atol=1e-12)
    days = replace(rule, nearest_spread=np.full(3, 1e-9))
    np.testing.assert_allclose(unit_bias.blended_nearest_prior(days, rest, rest_se), biases[0], atol=1e-9)
    draws = replace(rule, nearest_spread=np.full(3, 1.0))
    np.testing.assert_allclose(unit_bias.blended_nearest_prior(draws, rest, rest_se), own, atol=1e-9)
    assert unit_bias.blended_nearest_prior(rule, rest + 0.03, rest_se) is None  # near none: pooled
    two = replace(rule, rest_rates=rates[:2], rest_rates_se=rule.rest_rates_se[:2], rest_biases=biases[:2])
    np.testing.assert_allclose(unit_bias.blended_nearest_prior(two, rest, rest_se), biases[0], atol=1e-9)
    # The model file's rule: written with the flag, read back with it; a rule written before reads as
    # it was fitted, the matches alone.
    assert unit_bias.BiasRule.from_dict(rule.to_dict()).nearest_blend is True
    old = {k: v for k, v in rule.to_dict().items() if k != "nearest_blend"}
    assert unit_bias.BiasRule.from_dict(old).nearest_blend is False
    with pytest.raises(ValueError, match="nearest_blend"):
        unit_bias.BiasRule.from_dict({**rule.to_dict(), "nearest_blend": "yes"})


def test_a_mean_bias_the_training_recordings_do_not_determine_is_left_to_the_readings() -> None:
    """A new recording's prior keeps of the model's mean gyro bias what the training recordings determine
    (``bias_spread.shrunk``): all of it but a sliver where they agree on a bias far from zero (EuRoC's six:
    2-80 mrad/s, 2 mrad/s apart), none where each power-up draws its own about a mean that Student's t
    of ``n − 1`` degrees of freedom cannot tell from zero (a walkthrough's BROAD unit with 0.05-0.5 °/s
    added to each of three parts took a recording whose own bias was small from 3.7° to 17.0°); and
    between, the share that least squares' expected error over a new draw keeps, m² / (m² + s²/n)."""
    euroc = bias_spread.shrunk(np.array([-2.35e-3, 21.9e-3, 78.6e-3]), np.array([0.59e-3, 1.9e-3, 2.3e-3]), 6)
    assert np.all(np.abs(euroc) < 0.011 * np.abs([2.35e-3, 21.9e-3, 78.6e-3])), euroc
    # Three draws about zero: 1148, -448, -1503 °/h means with spreads of 1076-1292 °/h (the walkthrough's).
    mean, spread = (
        np.radians(np.array([1148.0, -448.0, -1503.0]) / 3600),
        np.radians(np.array([1076.0, 1292.0, 1142.0]) / 3600),
    )
    np.testing.assert_array_equal(bias_spread.shrunk(mean, spread, 3), mean)  # t(2) at 97.5 %: 4.30 SE
    # Determined, but not by much: what least squares' expected error keeps (3.4 SE with six, t(5) 2.57).
    m, s = 2.0e-3, np.sqrt(6) * 2.0e-3 / 3.4
    kept = 1.0 - bias_spread.shrunk(np.array([m]), np.array([s]), 6)[0] / m
    assert kept == pytest.approx(m**2 / (m**2 + s**2 / 6))


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_the_online_rule_finds_a_bias_the_prior_missed_on_the_horizontal_axes(seed: int) -> None:
    """The prior misses the bias by 1e-3 rad/s on every axis; after two minutes of bounded flight the online
    estimate has at most a third of that error left in the horizontal plane (the vertical is seen only
    through the tilts) and the open-loop attitude error is at most half the prior's."""
    bias = np.array([0.02, -0.01, 0.005])
    imu = _bounded_flight(seed, bias=bias)
    prior = bias + 1e-3
    online = unit_bias.BiasRule(mode="online", prior=prior, spread=np.full(3, 2e-3))
    track = unit_bias.bias_track(online, imu)
    left = track[-1] - bias
    assert np.linalg.norm(left[:2]) < np.linalg.norm([1e-3, 1e-3]) / 3, left
    # Causal: the readings after a step do not move its bias.
    cut = len(imu.dtheta_b) // 2
    early = ImuIncrements(t=imu.t[: cut + 1], dtheta_b=imu.dtheta_b[:cut], dv_b=imu.dv_b[:cut])
    np.testing.assert_array_equal(unit_bias.bias_track(online, early), track[:cut])


def test_a_rule_round_trips_through_a_model_file(tmp_path: Path) -> None:
    recs, _, _ = recordings(7)
    fitted = referenced.fit_several("regression", recs)
    assert fitted.rule is not None and fitted.rule.mode in unit_bias.MODES
    # Chosen on held-back recordings, and beside them the raw readings': biases of 0.1 °/s drawn anew
    # for each recording leave the raw readings far worse than the chosen rule.
    held = fitted.rule.held_back_deg
    assert set(held) == {*unit_bias.MODES, "raw"} and held[fitted.rule.mode] < 0.5 * held["raw"], held
    path = tmp_path / "m.json"
    compensation.save(fitted.strategy, path)
    back = compensation.load(path)
    out_a = fitted.strategy.correct_recording(recs[0].imu)
    out_b = back.correct_recording(recs[0].imu)
    np.testing.assert_array_equal(out_a.dtheta_b, out_b.dtheta_b)


def test_bias_only_on_several_recordings_keeps_the_biases_alone() -> None:
    recs, _, _ = recordings(10)
    fitted = referenced.fit_several("bias_only", recs, rule_mode="pooled")
    s = fitted.strategy
    assert s.label == "bias_only"
    np.testing.assert_array_equal(s.B_, np.zeros((3, 3)))
    np.testing.assert_allclose(s.B0_, fitted.several.gyro_bias.mean(axis=0))
    # What sins fit prints and writes of it: the biases alone, as the model keeps (a walk found the scale
    # and misalignment of the shared fit printed, and none of them applied); on two recordings, the rule
    # said not to be chosen on held-back ones.
    from sins.compensation import fitting

    outcome = fitting.fit_several("bias_only", recs[:2], ["a", "b"])
    assert {c["term"] for c in outcome.document["coefficients"]} == {"bias"}
    assert any(
        "not chosen on held-back recordings: that takes three or more, here 2" in x for x in outcome.lines
    )


def test_bias_only_chooses_its_rule_by_its_own_correction_on_held_back_recordings() -> None:
    """Each recording held back in turn is corrected as the strategy corrects: ``bias_only`` by the
    biases alone (before, by the full seed model, as ``regression``, so its held-back figures were
    regression's to the last digit). Here they differ by 6-12 %: the biases alone, fitted on two
    recordings, do better held back than a scale and misalignment fitted on two as well."""
    recs, _, _ = recordings(10)
    fits = {name: referenced.fit_several(name, recs) for name in ("regression", "bias_only")}
    held = {name: fit.rule.held_back_deg for name, fit in fits.items() if fit.rule is not None}
    assert held["bias_only"]["raw"] == held["regression"]["raw"]
    for mode in ("pooled", "online"):
        assert abs(held["bias_only"][mode] / held["regression"][mode] - 1.0) > 0.02, held


def test_a_damaged_rule_is_refused(tmp_path: Path) -> None:
    recs, _, _ = recordings(7, count=2)
    fitted = referenced.fit_several("regression", recs)
    path = tmp_path / "m.json"
    compensation.save(fitted.strategy, path)
    doc = json.loads(path.read_text())
    doc["state"]["unit_bias_"]["mode"] = "crystal ball"
    path.write_text(json.dumps(doc))
    refusal(lambda: compensation.load(path), str(path), "crystal ball")
    doc["state"]["unit_bias_"] = {**fitted.rule.to_dict(), "held_back_each_deg": {"raw": 1.0}}
    path.write_text(json.dumps(doc))
    refusal(lambda: compensation.load(path), str(path), "held_back_each_deg")


def test_recordings_of_two_units_or_rates_are_refused() -> None:
    recs, _, _ = recordings(8, count=2)
    refusal(lambda: referenced.fit_several("regression", recs[:1]), "two or more")
    other = replace(recs[1], sensor="another unit")
    first = replace(recs[0], sensor="a unit")
    refusal(lambda: referenced.fit_several("regression", [first, other]), "one unit", "another unit")


def test_a_learner_leaves_each_recordings_own_bias_to_the_rule(monkeypatch: pytest.MonkeyPatch) -> None:
    """Three numpy recordings of one unit, its biases drawn anew for each (0.1 °/s), its other errors
    linear. ``kohonen`` fitted on them learns beside the seed model on readings taken to the recordings'
    mean bias: the bias each recording's corrected readings still hold then spreads as the unit's own
    biases do (the rule's spread within 20 % of the seed fit's, per axis). Before, the learner was shown
    each recording's bias, told the recordings apart by their motion, took 61-74 % of that spread into
    the model (0.39, 0.39, 0.26 of it left), and the rule, so told the unit's biases agree, kept a new
    recording's estimate near the prior: on a numpy MEMS unit's judged recording, worse than the raw
    readings. Its guard judges it on recordings held back whole (the cross-validation's folds are the
    recordings). It learns on top of the seed model the intervals fitted, as ``regression`` corrects with
    it (before, on least squares refitted on the per-sample references, which took the g-sensitivity the
    intervals held at zero: an aliased EuRoC unit's MH_02 6.67° where ``regression`` gave 3.46°, with no
    learner used)."""
    from sins.compensation import residual, terms

    recs, _, _ = recordings(10, count=3)
    counted: list[bool] = []  # how the guard and the terms took their standard errors: over recordings?
    verdicts, choose = residual._Trial.verdicts, terms.choose
    monkeypatch.setattr(
        residual._Trial,
        "verdicts",
        lambda self, z, by_fold=False: counted.append(by_fold) or verdicts(self, z, by_fold),
    )
    monkeypatch.setattr(
        terms, "choose", lambda *a, by_fold=False: counted.append(by_fold) or choose(*a, by_fold=by_fold)
    )
    out = referenced.fit_several("kohonen", recs)
    assert counted and all(counted), counted
    seed = Regression().set_fit(out.several.seed).get_state()
    base = out.strategy.base_  # type: ignore[attr-defined]
    assert all(np.array_equal(np.asarray(base[k]), np.asarray(v)) for k, v in seed.items()), (base, seed)
    assert out.rule is not None
    ratio = out.rule.spread / out.several.bias_spread()
    assert np.all((ratio > 0.8) & (ratio < 1.25)), ratio
    # Its guard judged it on recordings held back whole: three folds, one a recording.
    assert out.strategy.cv_folds_ == 3  # type: ignore[attr-defined]
    fresh = LocalLinearMap()
    rows = interval_fit.interval_reference(recs[0], out.several.for_recording(0))
    with pytest.raises(ValueError, match="recordings as folds need two or more"):
        fresh.fit(rows, recordings=np.zeros(len(rows), dtype=np.intp))
    with pytest.raises(ValueError, match="recordings: 3 rows; the data have"):
        fresh.fit(rows, recordings=np.zeros(3, dtype=np.intp))


def test_a_rest_strategy_on_recordings_without_rests_is_one_line_naming_them_once() -> None:
    """The numpy unit turns all the time: ``regression_rest`` has no rest to learn from, and says so in
    one line that names the recordings once (it named them twice, after two numpy warnings of an empty
    slice's mean)."""
    recs, _, _ = recordings(8, count=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy warning fails the test
        message = refusal(lambda: referenced.fit_several("regression_rest", recs), "needs rests")
    assert message.count(recs[0].source) == 1, message


def test_strategies_lists_the_registry_one_name_a_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["strategies"]) == 0
    names = capsys.readouterr().out.split()
    assert names == compensation.strategy_names()
    assert set(names) == (set(compensation.VARIANTS) - {"oracle"}) | {"bias_only"}


def _late(folder: Path, name: str, lag_s: float) -> None:
    """``folder/name.npz``'s reference stamped ``lag_s`` late by scipy (its attitude slerped, its
    velocity interpolated, at ``t - lag_s``)."""
    from scipy.spatial.transform import Slerp

    late = dict(np.load(folder / f"{name}.npz"))
    t = late["t_s"]
    shifted = np.clip(t - lag_s, t[0], t[-1])
    attitude = Rotation.from_quat(late["q_wxyz"], scalar_first=True)
    late["q_wxyz"] = Slerp(t, attitude)(shifted).as_quat(scalar_first=True)
    late["v_m_s"] = np.column_stack([np.interp(shifted, t, late["v_m_s"][:, i]) for i in range(3)])
    np.savez(folder / f"{name}.npz", **late)


def test_fit_says_each_references_clock_and_names_one_that_lags(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Numpy recordings, the second's reference stamped late by scipy. 20 ms late, fitted with the first:
    the fit names the late reference's clock, 20 ms behind (within 0.5 ms), and the shift that aligns
    it, not the first's; its residuals, pooled, leave the first recording's own bias determined only
    beyond a consumer unit's spread, which the fit says (a recording's bias is not the model's: it is
    not refused for it). 50 ms late, the shared fit is unstable: the refusal names the late clock and
    its shift first, and nothing is written. Fitted without it, the table gives each reference's clock,
    within 0.5 ms of its readings'; judged on it, the evaluation says its figures are judged against a
    clock 20 ms behind."""
    recs, _, _ = recordings(9)
    (tmp_path / "unit").mkdir()
    (tmp_path / "later").mkdir()
    for k, rec in enumerate(recs):
        write_npz(tmp_path / "unit", f"r{k}", rec)
        write_npz(tmp_path / "later", f"r{k}", rec)
    _late(tmp_path / "unit", "r1", 0.020)
    _late(tmp_path / "later", "r1", 0.050)
    monkeypatch.setenv("SINS_DATA", str(tmp_path))
    model, fit_json = tmp_path / "m.json", tmp_path / "fit.json"
    args = ["fit", "--strategy", "regression", "--out", str(model), "--json", str(fit_json)]
    capsys.readouterr()
    assert main([*args, "--dataset", "unit/r0", "--dataset", "unit/r1"]) == 0
    said = capsys.readouterr().out
    assert "unit/r1: the reference's clock sits 20." in said and "add -0.020" in said, said
    assert "unit/r0: the reference's clock" not in said, said
    assert "unit/r0: its own bias is determined only beyond a consumer unit's spread" in said, said
    model.unlink()
    fit_json.unlink()
    assert main([*args, "--dataset", "later/r0", "--dataset", "later/r1"]) == 2
    assert not model.exists() and not fit_json.exists()
    # The error is one line; a loaded machine may put progress lines (a job past 5 s) before it.
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("sins: error")]
    assert len(err) == 1, err
    assert "later/r1's reference clock sits 50." in err[0] and "later/r0's" not in err[0], err
    assert "ms behind its readings' (add -0.050" in err[0], err
    assert main([*args, "--dataset", "unit/r0", "--dataset", "unit/r2", "--bias-rule", "pooled"]) == 0
    clocks = [r["reference_clock_ms"] for r in json.loads(fit_json.read_text())["recording_biases"]]
    assert all(abs(c) < 0.5 for c in clocks), clocks
    # Judged on the late one, the evaluation says its figures are judged against that clock.
    capsys.readouterr()
    judged = tmp_path / "e.json"
    assert main(["evaluate", str(model), "--dataset", "unit/r1", "--json", str(judged)]) == 0
    assert json.loads(judged.read_text())["reference_clock_ms"] == pytest.approx(20.0, abs=0.5)
    assert "judged against it as stamped" in capsys.readouterr().out


def test_fit_on_several_datasets_then_evaluate_writes_the_aoe(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    recs, unit, _ = recordings(9)
    (tmp_path / "unit").mkdir()
    for k, rec in enumerate(recs):
        write_npz(tmp_path / "unit", f"r{k}", rec, positions=True)
    monkeypatch.setenv("SINS_DATA", str(tmp_path))
    model, fit_json, out = tmp_path / "m.json", tmp_path / "fit.json", tmp_path / "e.json"
    args = [
        "fit",
        "--dataset",
        "unit/r0",
        "--dataset",
        "unit/r1",
        "--strategy",
        "regression",
        "--out",
        str(model),
    ]
    assert main([*args, "--json", str(fit_json), "--bias-rule", "pooled"]) == 0
    doc = json.loads(fit_json.read_text())
    assert doc["recordings"] == ["unit/r0", "unit/r1"] and doc["bias_rule"]["mode"] == "pooled"
    # The shared time offsets and lever arm, said and written as one recording's fit says them: each
    # sensor's delay less half a 100 Hz step (the .npz holds each step's mean rate at its start) within
    # 4 standard errors (0.5 and 0.2 seen), and no arm (the numpy unit's accelerometer is at the
    # reference's point: 1.4 mm seen).
    for sensor, delay_s in (("gyro", unit.gyro_delay_s), ("accel", unit.accel_delay_s)):  # type: ignore[attr-defined]
        got, se = doc["time_offset_ms"][sensor], doc["time_offset_se_ms"][sensor]
        assert abs(got - (1e3 * delay_s - 5.0)) < 4 * se, (sensor, got, se, delay_s)
    assert np.linalg.norm(doc["lever_arm_mm"]) < 5.0, doc["lever_arm_mm"]
    # A recording given twice would weigh twice and be held back against a copy of itself: refused
    # before anything is read or written.
    capsys.readouterr()
    twice = [*args[:-1], str(tmp_path / "twice.json"), "--dataset", "unit/r0"]
    assert main(twice) == 2 and not (tmp_path / "twice.json").exists()
    err = capsys.readouterr().err.strip()
    assert err == "sins: error: fit: unit/r0 is given twice", err
    # So is the same file by another name: its path beside its FOLDER/NAME, a link, ./ before it.
    r0 = tmp_path / "unit" / "r0.npz"
    (tmp_path / "link.npz").symlink_to(r0)
    os.link(r0, tmp_path / "hard.npz")
    dotted = f"{r0.parent}/./r0.npz"  # pathlib would fold the "."
    for given in (["--dataset", "unit/r0", str(r0)], [str(tmp_path / "link.npz"), str(r0)],
                  [str(tmp_path / "hard.npz"), str(r0)], [str(r0), dotted]):  # fmt: skip
        assert main(["fit", *given, "--strategy", "regression", "--out", str(tmp_path / "twice.json")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("sins: error: fit: ") and err.endswith(" are one recording"), err
    assert not (tmp_path / "twice.json").exists()
    assert main(["evaluate", str(model), "--dataset", "unit/r2", "--json", str(out)]) == 0
    judged = json.loads(out.read_text())
    # The same recording in another folder is another unit's, and the refusal says why the folder counts.
    (tmp_path / "elsewhere").mkdir()
    shutil.copy(tmp_path / "unit" / "r2.npz", tmp_path / "elsewhere" / "r2.npz")
    capsys.readouterr()
    assert main(["evaluate", str(model), "--dataset", "elsewhere/r2"]) == 2
    assert "this recording is elsewhere (a data root's FOLDER/NAME takes its folder for its unit)" in (
        capsys.readouterr().err
    )
    # By its path the file names no unit: judged as the model's, and said so.
    assert main(["evaluate", str(model), str(tmp_path / "elsewhere" / "r2.npz")]) == 0
    assert "the recording names no unit: it is judged as unit's, the model's" in capsys.readouterr().out
    # --drive: a window backwards is refused as such; one past the reference is navigated to its end
    # and said so (before: "not within the reference" for the first, the asked end for the second).
    capsys.readouterr()
    assert main(["evaluate", str(model), "--dataset", "unit/r2", "--drive", "5:2"]) == 2
    assert "--drive '5:2': START must come before END" in capsys.readouterr().err
    assert main(["evaluate", str(model), "--dataset", "unit/r2", "--drive", "0:1e9"]) == 0
    said = capsys.readouterr().out
    window = re.search(r"free inertial from the reference's state at (\S+) s to (\S+) s", said)
    assert window is not None and 0.0 < float(window[2]) < 1e3, said  # 120 s recordings
    # --outage: each recording's outages from every second, then the mean of their RMS over the
    # recordings; an outage longer than a recording's reference is one line naming it, and no file.
    both = ["evaluate", str(model), "--dataset", "unit/r2", "--dataset", "unit/r1", "--json", str(out)]
    assert main([*both, "--outage", "2", "--outage", "5"]) == 0
    document = json.loads(out.read_text())
    each = [r["free_inertial_outages"] for r in document["recordings"]]
    for k, length in enumerate((2.0, 5.0)):
        assert [e[k]["length_s"] for e in each] == [length, length] and each[0][k]["outages"] > 100
        for side in ("raw", "corrected"):
            mean = document["mean"]["free_inertial_outages"][k][side]["rms_m"]
            assert mean == pytest.approx(np.mean([e[k][side]["rms_m"] for e in each]), rel=1e-12)
        # The unit's raw scale factors, misalignments and biases carry it further than corrected.
        assert all(e[k]["corrected"]["rms_m"] < e[k]["raw"]["rms_m"] for e in each), each
    assert "free-inertial outages: the RMS horizontal error at their ends, m" in capsys.readouterr().out
    out.unlink()
    assert main([*both, "--outage", "1e4"]) == 2
    err = capsys.readouterr().err
    assert "an outage of 10000 s does not fit within the reference's 119 s" in err and "r2.npz" in err, err
    assert err.count("\n") == 1 and not out.exists()
    raw, pooled = judged["open_loop_attitude_raw"]["aoe_deg"], judged["open_loop_attitude"]["aoe_deg"]
    # The third recording's bias was drawn anew (0.1 °/s apart): the training recordings' mean corrects
    # the unit's scale and misalignment but not that; the online rule, from the recording's own bounded
    # velocity, takes most of it out.
    assert main([*args, "--bias-rule", "online"]) == 0
    assert main(["evaluate", str(model), "--dataset", "unit/r2", "--json", str(out)]) == 0
    online = json.loads(out.read_text())["open_loop_attitude"]["aoe_deg"]
    assert online < pooled < raw, (online, pooled, raw)
    # A copy of r2 whose gyro x is clipped at half its largest rate: judged all the same, and said so.
    arrays = dict(np.load(tmp_path / "unit" / "r2.npz"))
    top = 0.5 * float(np.abs(arrays["gyro_rad_s"][:, 0]).max())
    arrays["gyro_rad_s"][:, 0] = np.clip(arrays["gyro_rad_s"][:, 0], -top, top)
    np.savez(tmp_path / "unit" / "r2_clipped.npz", **arrays)
    capsys.readouterr()
    assert main(["evaluate", str(model), "--dataset", "unit/r2_clipped"]) == 0
    assert f"the readings stick at their extremes (gyro_x at {top:+.6g} on " in capsys.readouterr().out
    # Several judged in one command: each recording's document as its own command writes it, and the
    # means numpy takes of theirs.
    singles = {}
    for name in ("unit/r2", "unit/r0"):
        assert main(["evaluate", str(model), "--dataset", name, "--json", str(out)]) == 0
        singles[name] = {
            k: v for k, v in json.loads(out.read_text()).items() if k not in ("sins", "model", "strategy")
        }
    several = ["evaluate", str(model), "--dataset", "unit/r2", "--dataset", "unit/r0"]
    assert main([*several, "--json", str(tmp_path / "several.json")]) == 0
    both = json.loads((tmp_path / "several.json").read_text())
    assert both["recordings"] == [singles["unit/r2"], singles["unit/r0"]]
    # r0 is one the model was fitted on, by its readings: said of it, and of the mean.
    assert [singles[n]["fitted_on_this_recording"] for n in ("unit/r2", "unit/r0")] == [False, True]
    assert both["fitted_on"] == ["unit/r0"]
    assert "the model was fitted on 1 of the 2 recordings judged (unit/r0)" in capsys.readouterr().out
    for key in ("open_loop_attitude", "open_loop_attitude_raw"):
        assert both["mean"][key]["aoe_deg"] == np.mean([d[key]["aoe_deg"] for d in singles.values()])
    # Each recording the correction left worse than its raw readings is named (a mean had hidden them).
    figures = {"a": (10.0, 2.0), "b": (1.0, 1.5), "c": (4.0, 4.0)}  # raw, corrected
    judged = {
        n: Evaluation([], {"open_loop_attitude_raw": {"aoe_deg": r}, "open_loop_attitude": {"aoe_deg": c}})
        for n, (r, c) in figures.items()
    }
    said = evaluation.across(judged, "m")
    assert said.document["worse_than_raw"] == ["b"] and both["worse_than_raw"] == []
    assert said.lines[-1] == "worse than the raw readings on 1 of the 3: b (+0.5°)"
    # A file and a dataset mixed: the same readings, the same figures.
    mixed = ["evaluate", str(model), str(tmp_path / "unit" / "r2.npz"), "--dataset", "unit/r0"]
    assert main([*mixed, "--json", str(tmp_path / "mixed.json")]) == 0
    assert json.loads((tmp_path / "mixed.json").read_text())["mean"] == both["mean"]
    # A copy of a training recording under another name and folder is still one it was fitted on.
    (tmp_path / "copy").mkdir()
    copy = Path(shutil.copy(tmp_path / "unit" / "r1.npz", tmp_path / "copy" / "renamed.npz"))
    assert main(["evaluate", str(model), str(copy), "--json", str(out)]) == 0
    assert json.loads(out.read_text())["fitted_on_this_recording"] is True
    # A part cut from a training recording (its middle, times made relative to its first again): said to
    # be one, by its share of the fit's marks; the recording the fit held out shares none of them.
    part = {k: v[2000:-3000] for k, v in np.load(tmp_path / "unit" / "r1.npz").items()}
    part["t_s"] = part["t_s"] - part["t_s"][0]
    np.savez(tmp_path / "copy" / "part.npz", **part)
    capsys.readouterr()
    assert main(["evaluate", str(model), str(tmp_path / "copy" / "part.npz"), "--json", str(out)]) == 0
    judged = json.loads(out.read_text())
    assert judged["fitted_on_this_recording"] is True and judged["share_in_fit"] == 1.0
    assert "about 100% of these readings were in the model's fit (a part of" in capsys.readouterr().out
    assert singles["unit/r2"]["share_in_fit"] == 0.0
    # A part too short for its marks to tell (under 4): neither said fitted nor said unseen (a docs walk
    # found a 500-row cut of a training recording written "fitted_on_this_recording": false).
    np.savez(tmp_path / "copy" / "short.npz", **{k: v[2000:2500] for k, v in part.items()})
    assert main(["evaluate", str(model), str(tmp_path / "copy" / "short.npz"), "--json", str(out)]) == 0
    judged = json.loads(out.read_text())
    assert judged["share_in_fit"] is None and judged["fitted_on_this_recording"] is None
    for extra, what in ((["--plot", str(tmp_path / "x.png")], "--plot"), (["--dataset", "unit/r2"], "twice")):
        assert main([*several, *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and what in err, err
    # The model's matrices are in the axes its readings were read on: readings read on others are refused.
    assert main(["evaluate", str(model), str(tmp_path / "unit" / "r2.npz"), "--frame", "flu"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "as frd; this recording is read as flu (read it with --frame frd" in err, err
    # A model fitted on this folder's unit is refused on a recording of another folder (another unit).
    (tmp_path / "other").mkdir()
    write_npz(tmp_path / "other", "x", recs[2])
    refusal(lambda: _exit(main(["evaluate", str(model), "--dataset", "other/x"])), "fitted on unit")


def test_a_model_fitted_at_another_rate_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    recs, _, _ = recordings(11)
    fitted = referenced.fit_several("regression", recs[:2], rule_mode="pooled")
    model = tmp_path / "m.json"
    compensation.save(fitted.strategy, model)
    rec = recs[2]
    pairs = len(rec.imu.dtheta_b) // 2 * 2  # the same readings at half the rate: pairs of steps summed
    slow = ImuIncrements(
        t=rec.imu.t[: pairs + 1 : 2], dtheta_b=rec.imu.dtheta_b[:pairs].reshape(-1, 2, 3).sum(1),
        dv_b=rec.imu.dv_b[:pairs].reshape(-1, 2, 3).sum(1),
    )  # fmt: skip
    halved = replace(rec, imu=slow)
    (tmp_path / "u").mkdir()
    write_npz(tmp_path / "u", "slow", halved)
    code = main(["evaluate", str(model), str(tmp_path / "u" / "slow.npz")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err, err
    assert "slow.npz" in err and "100 Hz" in err and "50 Hz" in err, err
    # The rate written as a whole number (as a hand or another tool may write it) is judged the same.
    doc = json.loads(model.read_text())
    doc["state"]["fitted_on_"]["rate_hz"] = round(doc["state"]["fitted_on_"]["rate_hz"])
    model.write_text(json.dumps(doc))
    assert main(["evaluate", str(model), str(tmp_path / "u" / "slow.npz")]) == 2
    assert "50 Hz" in capsys.readouterr().err


def _exit(code: int) -> None:
    if code:
        from sins.errors import SinsInputError

        raise SinsInputError("fitted on unit (the command said so on stderr)")


@needs_euroc
def test_euroc_training_recordings_each_keep_their_own_bias() -> None:
    """The six sequences Brossard et al. fit on: a day apart, the gyro bias moves by ~4e-3 rad/s
    (SOURCE.md: up to 0.08 rad/s between first seconds, most of it motion); each recording's own bias is
    determined to better than 1e-3 rad/s, and they differ between days by more than that."""

    names = ["MH_01_easy", "MH_05_difficult", "V2_01_easy"]
    fit = several.fit_several([io.read(dataset=f"euroc/{n}").beside_reference() for n in names])
    assert np.all(fit.gyro_bias_se < 1e-3)
    assert np.abs(fit.gyro_bias[2] - fit.gyro_bias[0]).max() > 2e-3


@pytest.mark.parametrize("seed", [3, 5])
def test_a_numpy_unit_read_calibrated_is_left_as_read_in_either_form(seed: int) -> None:
    """A numpy unit whose gyro reads its noise alone (no bias, scale, misalignment or delay, as read
    calibrated at every power-up): whatever a fit on two recordings estimates only adds to that, so
    held back every rule leaves a recording worse than its readings, and the model leaves the gyro as
    read, in increments and in rates alike, to the bit; the accelerometer it still corrects. (Seed 4,
    measured with the others before: since the mean bias the recordings do not determine is left to the
    readings, ``online`` there leaves no held-back recording worse, and is taken.)"""
    recs, _, _ = recordings(seed, calibrated=True)
    fitted = referenced.fit_several("regression", recs)
    rule = fitted.rule
    assert rule is not None and rule.mode == unit_bias.READINGS
    raw = np.array(rule.held_back_each_deg["raw"])
    for mode in unit_bias.MODES:
        assert len(rule.held_back_each_deg[mode]) == len(recs)
        assert np.any(np.array(rule.held_back_each_deg[mode]) > raw), mode
    imu = recs[0].imu
    out = fitted.strategy.correct_recording(imu)
    assert isinstance(out, ImuIncrements)
    assert np.array_equal(out.dtheta_b, imu.dtheta_b) and not np.array_equal(out.dv_b, imu.dv_b)
    dt = np.diff(imu.t)[:, None]
    rates = ImuRates(t=imu.t[:-1], omega_ib_b=imu.dtheta_b / dt, f_ib_b=imu.dv_b / dt)
    as_rates = fitted.strategy.correct_recording(rates)
    assert isinstance(as_rates, ImuRates) and np.array_equal(as_rates.omega_ib_b, rates.omega_ib_b)
    with pytest.raises(ValueError, match="takes no bias"):
        unit_bias.bias_track(rule, out)


def test_a_fit_on_several_takes_recordings_of_one_unit_each_once() -> None:
    """Refused in one line naming both: two units, and one recording's readings given twice
    under two names (a new-user walk fitted a EuRoC recording beside its float64 copy: the spread of the
    biases between recordings read 0.0 °/h, and the held-back rule judged the copy by itself)."""
    recs, _, _ = recordings(3)
    a, b = replace(recs[0], source="a.npz"), replace(recs[1], source="b.npz")
    refusal(lambda: several.check_one_unit([a]), "a fit on several recordings needs two or more")
    other = replace(b, sensor="another")
    refusal(
        lambda: several.check_one_unit([replace(a, sensor="one"), other]), "b.npz: recordings of one unit"
    )
    copy = replace(a, source="copy.npz")
    refusal(lambda: referenced.fit_several("regression", [a, b, copy]),
            "copy.npz: the same readings as a.npz: a fit on several recordings takes each once")  # fmt: skip
    several.check_one_unit([a, b])
    # A part of one (its middle minute): what a copy does, it does, and it is refused alike.
    part = replace(judging.between(a, 30.0, 90.0), source="part.npz")
    refusal(lambda: several.check_one_unit([a, b, part]),
            "part.npz: about 100% of its readings are a.npz's (a part of it): a fit on several recordings "
            "takes each reading once")  # fmt: skip
    # An interval that is not positive: refused (the walk over the reference's epochs never moved on).
    for bad in (0.0, -1.0, float("nan")):
        refusal(lambda v=bad: referenced.fit("regression", a, interval_s=v), "interval_s must be positive")


def test_a_mode_that_only_ties_with_the_readings_is_not_taken() -> None:
    """``bias_only`` on a numpy unit read calibrated (seed 5): its pooled prior gives back the mean bias
    the model takes (the recordings do not determine it), so held back it equals the readings on every
    recording, to rounding. It was taken (the first mode of least mean), and the model fitted on all
    three then moved the judged gyro by a hair: a helper's EuRoC unit read calibrated went from 0.64° and
    1.54° raw to 0.65° and 1.55°. A tie adds nothing: the gyro is left as read, to the bit."""
    recs, _, _ = recordings(5, calibrated=True)
    fitted = referenced.fit_several("bias_only", recs)
    each = fitted.rule.held_back_each_deg
    np.testing.assert_allclose(each["pooled"], each["raw"], rtol=1e-12)
    assert fitted.rule.mode == unit_bias.READINGS
    imu = recs[0].imu
    assert np.array_equal(fitted.strategy.correct_recording(imu).dtheta_b, imu.dtheta_b)
    # The choice alone: a strict gain on the mean, no loss on any recording.
    raw = [1.0, 2.0, 3.0]
    scores = {m: [2.0, 2.0, 3.0] for m in unit_bias.MODES}  # worse on the first
    assert rule_choice.chosen_mode(scores, raw) == unit_bias.READINGS
    scores["online"], scores["nearest"] = [1.0, 1.9, 3.0], [1.0, 1.5, 2.0]
    assert rule_choice.chosen_mode(scores, raw) == "nearest"
    assert rule_choice.chosen_mode({**scores, "online": raw, "nearest": raw}, raw) == unit_bias.READINGS
    # Two modes within one standard error of each other, recording by recording: the simpler (MODES'
    # order) is taken. A helper's unit of new power-ups held `rest+online` at 45.56, 1.73, 4.08 and
    # `nearest+online` at 45.56, 2.21, 3.23 (means 17.12 and 17.00): `nearest+online` was taken, and its
    # judged recordings, whose rests read like none of the training ones, went from 5.08 to 16.75.
    wide = [116.92, 115.62, 106.39]
    close = {m: wide for m in unit_bias.MODES}
    close.update({"rest+online": [45.56, 1.73, 4.08], "nearest+online": [45.56, 2.21, 3.23]})
    assert rule_choice.chosen_mode(close, wide) == "rest+online"
    close["rest+online"] = [45.56, 3.73, 6.08]  # 1.8 standard errors behind: the better one is taken
    assert rule_choice.chosen_mode(close, wide) == "nearest+online"
    # Two modes that differ on one recording alone lie behind by exactly their standard error (a/n both):
    # within, whatever rounding's last digit says. A helper's fit on three EuRoC recordings took `online`
    # or `rest+online` by 0.9028570299975037 against 0.9028570299975038; of 200 draws here, 16 flipped.
    rng = np.random.default_rng(0)
    for _ in range(200):
        base, ahead = rng.uniform(1.0, 10.0, 3), rng.uniform(0.1, 3.0)
        one = {m: list(wide) for m in unit_bias.MODES} | {"online": list(base)}
        one["rest+online"] = [base[0], base[1] - ahead, base[2]]
        assert rule_choice.chosen_mode(one, wide) == "online"
    # And sins fit says why the lower mean lost (it printed "online" beside rest+online's lower mean).
    from sins.compensation import fitting

    each = {"online": [4.0, 4.96, 6.0], "rest+online": [4.0, 2.25, 6.0], "raw": wide}
    rule = unit_bias.BiasRule(
        mode="online", held_back_each_deg=each, held_back_deg={m: float(np.mean(v)) for m, v in each.items()}
    )
    said = fitting._rule_lines(rule, ["a", "b", "c"], "")[0]
    assert said == (
        "a new recording's bias: online; rest+online is ahead by 0.90°, no more than its standard error "
        "over these recordings (0.90°), so the simpler online is taken"
    ), said


@needs_euroc
def test_a_unit_whose_readings_come_calibrated_keeps_its_gyro_as_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """EuRoC with each sequence's own constant gyro bias taken out (``tools/calibrated_unit.py``):
    readings that need nothing a fit on three recordings can add. Held back, every bias rule left one
    of them worse than its readings as they are (V1_03: 2.00° against 1.96°), so the model leaves the
    gyro as read, and a judged recording's open loop is the raw one to the bit. The rule of least
    held-back mean (``online``, 0.97°; the readings 0.94°), which sins took before it weighed the
    readings, leaves the judged MH_05 worse than its raw readings (0.44° against 0.39°): what the bar of
    another unit forbids."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
    from calibrated_unit import calibrated  # numpy and scipy alone

    (tmp_path / "cal").mkdir()
    train = ["V1_02_medium", "MH_04_difficult", "V1_03_difficult"]
    for name in [*train, "MH_05_difficult"]:
        calibrated(EUROC / f"{name}.npz", tmp_path / "cal")
    monkeypatch.setenv("SINS_DATA", str(tmp_path))
    model, fit_json, out = tmp_path / "m.json", tmp_path / "fit.json", tmp_path / "e.json"
    sets = [a for n in train for a in ("--dataset", f"cal/{n}")]
    assert main(["fit", *sets, "--strategy", "regression", "--out", str(model), "--json", str(fit_json)]) == 0
    said = capsys.readouterr().out
    rule = json.loads(fit_json.read_text())["bias_rule"]
    assert rule["mode"] == unit_bias.READINGS and set(rule["held_back_deg"]) == {*unit_bias.MODES, "raw"}
    each = rule["held_back_each_deg"]  # per training recording, in the order given
    assert all(any(v > r for v, r in zip(each[m], each["raw"], strict=True)) for m in unit_bias.MODES)
    assert "a new recording's gyro: left as read" in said
    assert "(the best, online: " in said and "cal/V1_03_difficult 2.00° against 1.96°" in said, said
    assert main(["evaluate", str(model), "--dataset", "cal/MH_05_difficult", "--json", str(out)]) == 0
    judged = json.loads(out.read_text())
    assert judged["gyro_as_read"] is True
    assert judged["open_loop_attitude"] == judged["open_loop_attitude_raw"]
    raw = judged["open_loop_attitude_raw"]["aoe_deg"]
    capsys.readouterr()
    fixed = tmp_path / "c.csv"
    assert main(["correct", str(model), "--dataset", "cal/MH_05_difficult", "--out", str(fixed)]) == 0
    assert "its gyro as read" in capsys.readouterr().out
    # The same model with the mode of least held-back mean, as sins chose before: worse than raw.
    doc = json.loads(model.read_text())
    held = {m: v for m, v in rule["held_back_deg"].items() if m in unit_bias.MODES}
    doc["state"]["unit_bias_"]["mode"] = min(held, key=held.__getitem__)
    model.write_text(json.dumps(doc))
    assert main(["evaluate", str(model), "--dataset", "cal/MH_05_difficult", "--json", str(out)]) == 0
    judged = json.loads(out.read_text())
    assert judged["gyro_as_read"] is False and judged["open_loop_attitude"]["aoe_deg"] > 1.05 * raw


def test_a_gap_in_the_readings_is_said_not_blamed_on_the_reference(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A recording whose stamps jump 2 s half way (readings and reference alike: nothing recorded
    there): before, ``sins fit`` refused it as a reference whose attitude is not of the readings' axes
    (one interval across the gap took the turns' correlation to 0.84). The intervals across the gap are
    left out of that check, the fit goes on, and ``sins evaluate`` says where the open loop crossed the
    gap, with its length (numpy's own)."""
    recs, _, _ = recordings(5)
    (tmp_path / "u").mkdir()
    write_npz(tmp_path / "u", "r", recs[0])
    path = tmp_path / "u" / "r.npz"
    with np.load(path) as held:
        doc = dict(held)
    half = len(doc["t_s"]) // 2
    doc["t_s"] = doc["t_s"] + np.where(np.arange(len(doc["t_s"])) >= half, 2.0, 0.0)
    np.savez(path, **doc)
    model = tmp_path / "m.json"
    assert main(["fit", str(path), "--strategy", "regression", "--out", str(model)]) == 0, capsys.readouterr()
    capsys.readouterr()
    assert main(["evaluate", str(model), str(path)]) == 0
    said = capsys.readouterr().out
    step = doc["t_s"][half] - doc["t_s"][half - 1]
    assert f"1 gap(s) in the readings (the longest {step:.3g} s at " in said, said


def test_the_learners_guard_counts_recordings_not_blocks_where_recordings_are_the_folds() -> None:
    """Where each fold is a recording, the guard's standard error is over the recordings: blocks of one
    recording share its day, motion and reference, so their spread says nothing of the next recording.
    A helper's numpy unit (EuRoC with trimmed openings and new biases) had `mlp` keep a gyro learner
    that gained 33 % on one held-back recording and lost 2 % and 4 % on the other two: 4.0 standard
    errors over its 399 blocks, 0.7 over the three recordings, and judged it took a recording from
    10.8° (least squares) to 22.3°. Here three folds of 100 blocks, the gain 0.3 a block on one and
    -0.1, -0.05 on the others (0.1 spread within each): over the blocks about 4 standard errors (the
    spread between the folds' means included), over the folds well under 1 (their sums about 30, -10,
    -5: total 15, standard error √(3 · 475) ≈ 38)."""
    from sins.compensation import terms
    from sins.compensation.residual import _Trial

    rng = np.random.default_rng(0)
    trial = _Trial({})
    for mean in (0.3, -0.1, -0.05):
        trial.gains.append(mean + 0.1 * rng.standard_normal((100, 6)))
        trial.base.append(np.ones((100, 6)))
    blocks, folds = trial.verdicts(2.0), trial.verdicts(2.0, by_fold=True)
    assert all(v["earns_its_place"] for v in blocks)
    assert not any(v["earns_its_place"] for v in folds)
    for b, f in zip(blocks, folds, strict=True):
        assert b["gain_fraction"] == pytest.approx(f["gain_fraction"], rel=1e-12)  # the same total
        z_blocks, z_folds = (v["gain_fraction"] / v["gain_se_fraction"] for v in (b, f))
        assert z_blocks > 3.0 and z_folds < 1.0, (z_blocks, z_folds)
    # The physics terms pass the same test: forward selection over the folds' sums, not the blocks'.
    options = [(), ("g2",)]
    per_fold = [mean + 0.1 * rng.standard_normal(100) for mean in (0.3, -0.1, -0.05)]
    assert terms._forward(options, {(): np.zeros(300), ("g2",): np.concatenate(per_fold)}, 2.0) == ("g2",)
    sums = np.array([g.sum() for g in per_fold])
    assert terms._forward(options, {(): np.zeros(3), ("g2",): sums}, 2.0) == ()


def test_every_guard_judges_against_the_standard_error_of_a_sum() -> None:
    """The one statistic of every guard (the residual learners', the physics terms', mlp_window's): the
    standard error of a sum of n independent draws, n times scipy's standard error of their mean, per
    column; with one draw there is no spread to judge by, and nothing passes (infinite)."""
    from scipy.stats import sem

    from sins.compensation.base import sum_standard_error

    draws = np.random.default_rng(3).standard_normal((7, 3)) * [1.0, 0.1, 5.0]
    np.testing.assert_allclose(sum_standard_error(draws), 7 * sem(draws, axis=0), rtol=1e-12)
    assert sum_standard_error(draws[:, 0]) == pytest.approx(7 * sem(draws[:, 0]), rel=1e-12)
    assert sum_standard_error([0.4]) == np.inf
    assert np.isinf(sum_standard_error(draws[:1])).all() and sum_standard_error(draws[:1]).shape == (3,)


def test_the_strategies_that_replace_the_seed_model_are_told_apart(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``sins fit`` on several recordings prints the shared seed model; for a strategy that corrects with
    a fit of its own from readings to errors (the seed paper's networks, ``regression_extended``), it
    says the seed model gives the recordings' biases and the bias rule, not the correction."""
    from sins.compensation import registry

    recs, _, _ = recordings(9)
    for k, rec in enumerate(recs[:2]):
        write_npz(tmp_path, f"r{k}", rec)
    monkeypatch.setenv("SINS_DATA", str(tmp_path.parent))
    said = "corrects with its own fit from readings to errors"
    for name, says in (("regression", False), ("regression_extended", True)):
        capsys.readouterr()
        datasets = ["--dataset", f"{tmp_path.name}/r0", "--dataset", f"{tmp_path.name}/r1"]
        out = str(tmp_path / f"{name}.json")
        assert main(["fit", *datasets, "--strategy", name, "--bias-rule", "pooled", "--out", out]) == 0
        assert (f"{name} {said}" in capsys.readouterr().out) is says, name

    made = {}
    for name in registry.strategy_names():
        with contextlib.suppress(ValueError):  # bias_only is made by the fit itself
            made[name] = compensation.make(name)
    replacing = {name for name, s in made.items() if referenced.replaces_seed_model(s)}
    assert replacing == {"regression_extended", "mlp_pure", "mlp_seed", "kohonen_pure", "ferraris"}


def test_none_fitted_against_references_is_written_and_corrects_nothing(tmp_path: Path) -> None:
    """``sins fit --dataset A [--dataset B] --strategy none`` ended in a traceback (its model said nothing
    of what it was fitted on, which the fit then wrote into): now it is written, on one recording or
    several, names what it was fitted on and, loaded, leaves every reading as read (the baseline a judged
    table's raw row is)."""
    from sins.compensation import fitting

    recs, _, _ = recordings(9, count=2)
    several = fitting.fit_several("none", recs, ["a", "b"]).strategy
    one = fitting.fit_referenced("none", recs[0], where="a").strategy
    assert several.fitted_on_["recordings"] == [r.source for r in recs]
    assert "reference_tilt" in several.fitted_on_ and "reference_tilt" in one.fitted_on_
    for k, strategy in enumerate((several, one)):
        path = tmp_path / f"none{k}.json"
        compensation.save(strategy, path)
        again = compensation.load(path).correct_recording(recs[1].imu)
        np.testing.assert_array_equal(again.dtheta_b, recs[1].imu.dtheta_b)
        np.testing.assert_array_equal(again.dv_b, recs[1].imu.dv_b)
