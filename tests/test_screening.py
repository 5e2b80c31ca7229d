"""A reference's gross errors set aside before a fit against it (sins.compensation.screening), judged on
units of known errors written with numpy (tests/numpy_referenced.py) whose references are spoiled the
ways real ones are: a velocity that spikes at one epoch (a position glitch differentiated) and an attitude
slerped across a gap."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numpy_referenced import HEIGHT_M, LAT_DEG, session, typical_unit
from scipy.spatial.transform import Rotation, Slerp

from sins import compensation, imu, io
from sins.cli import main
from sins.compensation import evaluation, judging, referenced, screening
from sins.core.series import ImuRates, NavSeries
from sins.imu import calibration
from sins.imu import spec as imu_spec

#: Velocity spikes (m/s) at these reference epochs (s; ends of the fit's 1 s intervals), and the
#: attitude slerped between the ends of this span (s).
SPIKES_S, SPIKE_MPS = (30.0, 55.0, 91.0), np.array([2.0, -1.0, 0.5])
GAP_S = (70.0, 72.0)


def _recording(seed: int, spoiled: bool) -> tuple[referenced.ReferencedRecording, object]:
    """A numpy unit's 120 s recording beside its 10 Hz reference, ``spoiled`` or as it is."""
    rng = np.random.default_rng(seed)
    unit = typical_unit(rng)
    s = session(rng, unit, duration_s=120.0)
    q_nb, v_n = s.q_nb.copy(), s.v_n.copy()
    if spoiled:
        for t in SPIKES_S:
            v_n[int(np.argmin(np.abs(s.t_ref - t)))] += SPIKE_MPS
        a, b = (int(np.argmin(np.abs(s.t_ref - t))) for t in GAP_S)
        slerp = Slerp(s.t_ref[[a, b]], Rotation.from_quat(q_nb[[a, b]]))
        q_nb[a : b + 1] = slerp(s.t_ref[a : b + 1]).as_quat()
    return _beside(s.t, s.gyro, s.accel, s.t_ref, q_nb, v_n, "numpy unit"), unit


def _beside(
    t: np.ndarray, gyro: np.ndarray, accel: np.ndarray, t_ref: np.ndarray, q_nb: np.ndarray, v_n: np.ndarray,
    source: str,
) -> referenced.ReferencedRecording:  # fmt: skip
    """Rate samples at ``t`` beside a reference at ``t_ref`` (attitude ``q_nb``, velocity ``v_n``) at the
    numpy units' site."""
    n = len(t_ref)
    truth = NavSeries(
        t=t_ref, lat=np.full(n, math.radians(LAT_DEG)), lon=np.zeros(n), h=np.full(n, HEIGHT_M), v_n=v_n,
        q_nb=q_nb,
    )  # fmt: skip
    return judging.from_recording(ImuRates(t=t, omega_ib_b=gyro, f_ib_b=accel), truth, source)


def _z_scores(fitted: referenced.Fitted, unit: object) -> np.ndarray:
    """The fitted seed model against the unit's truth, in standard errors (the coefficients fitted)."""
    s = fitted.intervals.seed
    truth = np.concatenate([unit.B0, unit.B.ravel(), unit.A0, unit.A.ravel()])  # type: ignore[attr-defined]
    est = np.concatenate([s.B0, s.B.ravel(), s.A0, s.A.ravel()])
    se = np.concatenate([s.B0_se, s.B_se.ravel(), s.A0_se, s.A_se.ravel()])
    z = (est - truth) / se
    return z[np.isfinite(z)]


@pytest.mark.parametrize("seed", [1, 2])
def test_a_references_glitches_are_set_aside_and_the_fit_is_the_clean_ones(seed: int) -> None:
    """With three velocity spikes and a 2 s slerped gap in its reference, a unit's fit screened first
    (``screen="always"``, ``sins fit --screen always``) sets aside the
    spikes' epochs and the gap, and little else (2 s an epoch: the two intervals that share it), and
    recovers the unit as from the clean reference: as many coefficients fitted (within two: 6 s less
    reference), each within 4 standard errors of the truth, the z-scores' RMS between 0.4 and 2. Without
    the screen the spikes' residuals made every standard error large and 23 of 33 coefficients were held
    at zero as not determined; the clean reference sets nothing aside."""
    clean = referenced.fit("regression", _recording(seed, spoiled=False)[0])
    assert not any(a.spans_s for a in clean.set_aside)
    rec, unit = _recording(seed, spoiled=True)
    fitted = referenced.fit("regression", rec, screen="always")
    [aside] = fitted.set_aside
    assert aside.largest_z > screening.SCREEN_Z

    def covered(t: float, spans: tuple[tuple[float, float], ...]) -> bool:
        return any(a <= t <= b for a, b in spans)

    assert all(covered(t, aside.spans_s) for t in SPIKES_S)
    # the gap is told by the reference alone, before the screen (screening.filled)
    assert all(covered(t, aside.filled_s) for t in np.arange(GAP_S[0] + 0.1, GAP_S[1] - 0.05, 0.1))
    assert aside.seconds() <= 2.0 * len(SPIKES_S) + (GAP_S[1] - GAP_S[0]) + 2.0
    assert len(fitted.review.held) <= len(clean.review.held) + 2  # type: ignore[union-attr]
    z = _z_scores(fitted, unit)
    assert np.abs(z).max() < 4.0 and 0.4 < np.sqrt(np.mean(z**2)) < 2.0


def test_gross_takes_normal_residuals_as_they_are_and_a_planted_error_out() -> None:
    """10,000 intervals of normal residuals (each sensor its own scale): none beyond the screen; one
    planted 40 standard deviations off on one axis (twice the screen): that one alone. An exact
    reference's residuals (rounding, 1e-16) are not screened against their own spread."""
    rng = np.random.default_rng(5)
    gyro, accel = rng.normal(0.0, 1e-4, (10_000, 3)), rng.normal(0.0, 0.02, (10_000, 3))
    bad, z = screening.gross(gyro, accel)
    assert not bad.any() and z.max() < 6.0
    accel[1234, 2] += 40 * 0.02
    bad, _ = screening.gross(gyro, accel)
    assert np.flatnonzero(bad).tolist() == [1234]
    exact = rng.normal(0.0, 1e-16, (500, 3))
    exact[7] += 1e-13
    assert not screening.gross(exact, exact)[0].any()


def test_without_leaves_out_the_epochs_within_the_spans_ends_included() -> None:
    rec, _ = _recording(1, spoiled=False)
    t = rec.reference.t
    out = screening.without(rec, [(30.0, 31.0), (50.05, 50.15)])
    kept = out.reference.t
    assert len(kept) == len(t) - 11 - 1
    assert not np.any((kept >= 30.0 - 1e-9) & (kept <= 31.0 + 1e-9))
    np.testing.assert_array_equal(out.imu.t, rec.imu.t)


def test_without_the_screen_the_glitches_stay_and_the_fit_holds_what_they_hide(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """By default (``refused``) a fit that is not refused is not screened, and neither is one with
    ``never``: nothing set aside by the screen (the slerped gap, by default, as filled), and the spikes
    make the standard errors so large that most coefficients are held at zero as not determined (what
    ``--screen always`` is for; the fit says so, below).
    ``--screen`` other than the default beside a rig recording, whose rows are not screened, is refused
    in one line and nothing is written."""
    rec, _ = _recording(1, spoiled=True)
    for screen in ("refused", "never"):
        fitted = referenced.fit("regression", rec, screen=screen)
        [aside] = fitted.set_aside
        assert not aside.spans_s and bool(aside.filled_s) == (screen == "refused")  # the gap: filled
        # the clean reference holds 3; the spikes alone 11 (measured), with the gap 24
        assert len(fitted.review.held) >= (8 if screen == "refused" else 15)  # type: ignore[union-attr]
    rig = tmp_path / "rig.csv"
    procedure = calibration.RigProcedure(
        positions=6, position_dwell_s=2.0, rate_table=calibration.RateTable(rates_dps=(50.0,), dwell_s=2.0)
    )
    unit = imu_spec.draw_unit("tactical", 1, 101).only(*imu.BASELINE)
    io.write_recording(rig, calibration.simulate_rig(procedure, unit, seed=1))
    model = tmp_path / "m.json"
    assert main(["fit", str(rig), "--strategy", "regression", "--screen", "always", "--out", str(model)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--screen always" in err and "rig recording" in err and not model.exists()


def test_a_refused_fit_is_made_again_on_what_the_screen_leaves_else_the_refusal_stands() -> None:
    """``refused``: a fit that refuses the recording as it is (here: while the spikes are in it) is made
    again without the epochs the screen sets aside, and those are returned; on the clean recording the
    screen sets nothing aside and the refusal stands as it was; ``never`` passes it on untouched."""
    spoiled, _ = _recording(2, spoiled=True)
    clean, _ = _recording(2, spoiled=False)

    def make(rs: list[referenced.ReferencedRecording]) -> int:
        v = rs[0].reference.v_n
        if np.abs(np.diff(v, axis=0)).max() > 1.0 or len(rs[0].reference.t) == len(clean.reference.t):
            raise ValueError("refused")
        return len(rs[0].reference.t)

    kept, [rec], [aside] = screening.fitted_screened(make, [spoiled])
    assert kept == len(rec.reference.t) < len(spoiled.reference.t) and aside.spans_s
    assert np.abs(np.diff(rec.reference.v_n, axis=0)).max() < 1.0
    for screen in ("refused", "never"):
        with pytest.raises(ValueError, match="refused"):
            screening.fitted_screened(make, [clean], screen=screen)
    with pytest.raises(ValueError, match="refused"):
        screening.fitted_screened(make, [spoiled], screen="never")


def _turning(gap_s: tuple[float, float] | None) -> referenced.ReferencedRecording:
    """60 s turning about z, its rate a sinusoid but for 20-40 s at one rate (0.5 rad/s), read at 100 Hz
    with 1e-3 rad/s of noise beside its exact 20 Hz reference; with ``gap_s``, the reference slerped
    between those times as a converter fills a lost marker."""
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 60.0 + 1e-9, 0.01)
    steady = (t >= 20.0) & (t <= 40.0)
    # the angle, exactly: 0.5 rad/s in the steady part, a sinusoid of rate about it elsewhere
    angle = 0.5 * t + np.where(steady, 0.0, 0.8 * np.sin(2 * np.pi * (t - 20.0) / 5.0))
    rate = 0.5 + np.where(steady, 0.0, 0.8 * 2 * np.pi / 5.0 * np.cos(2 * np.pi * (t - 20.0) / 5.0))
    gyro = np.column_stack([np.zeros_like(t), np.zeros_like(t), rate]) + rng.normal(0.0, 1e-3, (len(t), 3))
    accel = np.tile([0.0, 0.0, -9.81], (len(t), 1)) + rng.normal(0.0, 1e-3, (len(t), 3))
    t_ref = t[::5]
    q = Rotation.from_rotvec(np.column_stack([np.zeros_like(t_ref), np.zeros_like(t_ref), angle[::5]]))
    q_nb = q.as_quat()
    if gap_s is not None:
        a, b = (int(np.argmin(np.abs(t_ref - g))) for g in gap_s)
        q_nb[a : b + 1] = Slerp(t_ref[[a, b]], q[[a, b]])(t_ref[a : b + 1]).as_quat()
    return _beside(t, gyro, accel, t_ref, q_nb, np.zeros((len(t_ref), 3)), "turning unit")


def test_a_span_filled_by_interpolation_is_told_by_the_reference_and_a_steady_turn_is_not() -> None:
    """``screening.filled``: an exact reference that turns at one rate for 20 s, where the unit does, is
    not filled (the gyro reads that one rate, to its noise); the same reference slerped across 1.5 s of
    the sinusoid, where the gyro's rate swings by 1 rad/s, is: its inner epochs, and nothing else.
    ``sins evaluate`` says so (and judges against the reference as it is)."""
    assert screening.filled(_turning(None)) == ()
    gapped = _turning((10.0, 11.5))
    [(a, b)] = screening.filled(gapped)
    assert (a, b) == pytest.approx((10.05, 11.45), abs=1e-9)
    # sins evaluate judges against the reference as it is, and says where it was filled
    judged = evaluation.evaluate_referenced(compensation.make("none"), gapped, "turning unit")
    assert judged.document["reference_filled_s"] == [[a, b]]
    said = "the reference holds 1 span(s) (1.4 s in all: 10.05-11.45 s) filled by interpolation"
    assert any(line.startswith(said) for line in judged.lines)
    clean = evaluation.evaluate_referenced(compensation.make("none"), _turning(None), "turning unit")
    assert clean.document["reference_filled_s"] == []


def test_a_gap_is_told_in_a_reference_upsampled_from_a_slower_capture() -> None:
    """A converter that writes its reference at a higher rate than its capture's slerps between the
    capture's samples, so that half its epochs hold their rate exactly (here 20 Hz from 10 Hz, the
    capture's noise 1e-4 rad on every sample); only the gap it slerps across, 1.3 s of the sinusoid, is
    filled, and its inner epochs alone."""
    rec = _turning(None)
    t = rec.reference.t
    captured = np.flatnonzero(((np.arange(len(t)) % 2) == 0) & ((t < 10.0) | (t > 11.19)))
    noise = Rotation.from_rotvec(np.random.default_rng(8).normal(0.0, 1e-4, (len(captured), 3)))
    upsampled = Slerp(t[captured], Rotation.from_quat(rec.reference.q_nb[captured]) * noise)(t)
    written = replace(rec, reference=replace(rec.reference, q_nb=upsampled.as_quat()))
    [(a, b)] = screening.filled(written)  # the capture's last sample before the gap at 9.9 s, first at 11.2 s
    assert (a, b) == pytest.approx((9.95, 11.15), abs=1e-9)


def test_an_exact_reference_at_rest_is_not_filled_beside_a_wandering_bias() -> None:
    """A simulation's exact reference holds one attitude for 2 minutes, then turns for one, while its
    unit's gyro bias wanders (a rate random walk of 1e-4 rad/s/√s: over the rest, its angle departs from
    one rate far more than white noise's would): a rest, not a gap. A slerp between two measured
    attitudes turns, by their noise at least."""
    rng = np.random.default_rng(6)
    t = np.arange(0.0, 180.0 + 1e-9, 0.01)
    angle = np.where(t > 120.0, 0.8 * (1.0 - np.cos(2 * np.pi * (t - 120.0) / 5.0)), 0.0)
    rate = np.where(t > 120.0, 0.8 * 2 * np.pi / 5.0 * np.sin(2 * np.pi * (t - 120.0) / 5.0), 0.0)
    wander = np.cumsum(rng.normal(0.0, 1e-4 * np.sqrt(0.01), (len(t), 3)), axis=0)
    gyro = np.column_stack([np.zeros_like(t), np.zeros_like(t), rate]) + wander
    gyro += rng.normal(0.0, 1e-3, (len(t), 3))
    accel = np.tile([0.0, 0.0, -9.81], (len(t), 1)) + rng.normal(0.0, 1e-3, (len(t), 3))
    t_ref = t[::5]
    n = len(t_ref)
    q_nb = Rotation.from_rotvec(np.column_stack([np.zeros(n), np.zeros(n), angle[::5]])).as_quat()
    rec = _beside(t, gyro, accel, t_ref, q_nb, np.zeros((n, 3)), "resting unit")
    assert screening.filled(rec) == ()
