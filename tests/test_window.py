"""``regression_window``: a gyro correction learnt from a window of past readings, judged on a unit
written here with numpy alone whose gyro bias follows its recent motion (what a static map cannot see).

The generator: smooth random rotation (sums of sinusoids, up to 1.5 rad/s), gravity in the body frame,
and a gyro error ``b + c·m(t)`` with ``m(t)`` the mean rate size over the past second (a bias that rises
while the unit moves, as BROAD's hand-held unit's does), plus white noise. The reference is exact per
sample. Fitted on one session, judged on another of other motions.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sins import compensation
from sins.compensation import window
from sins.core.series import CalibrationData, ImuRates

RATE_HZ = 100.0
NOISE = 2e-3  # rad/s per sample
BIAS = np.array([3e-3, -2e-3, 1e-3])  # rad/s
MOTION_GAIN = np.array([1.6e-2, -1.2e-2, 0.8e-2])  # rad/s of bias per rad/s of recent mean rate size


def _session(seed: int, duration_s: float = 600.0) -> CalibrationData:
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, 1.0 / RATE_HZ)
    omega = np.zeros((len(t), 3))
    for axis in range(3):
        for _ in range(4):
            f, phase, a = rng.uniform(0.01, 0.3), rng.uniform(0, 2 * np.pi), rng.uniform(0.1, 0.4)
            omega[:, axis] += a * np.sin(2 * np.pi * f * t + phase)
    # Rests: the motion switched off on a third of the time, in stretches of 10-30 s.
    still = np.zeros(len(t), dtype=bool)
    at = 0.0
    while at < duration_s:
        at += rng.uniform(20, 60)
        still[(t >= at) & (t < at + rng.uniform(10, 30))] = True
        at += 30
    omega[still] = 0.0
    f_b = np.tile([0.0, 0.0, -9.81], (len(t), 1)) + 0.3 * np.roll(omega, 50, axis=0)
    size = np.linalg.norm(omega, axis=1)
    past = np.convolve(size, np.ones(100) / 100)[: len(t)]  # causal mean over the past second
    gyro = omega + BIAS + past[:, None] * MOTION_GAIN + rng.normal(0, NOISE, omega.shape)
    accel = f_b + rng.normal(0, 1e-3, f_b.shape)
    return CalibrationData(t=t, gyro=gyro, accel=accel, ref_gyro=omega, ref_accel=f_b, source=f"numpy {seed}")


def _beyond_noise(strategy: compensation.Strategy, data: CalibrationData) -> np.ndarray:
    """Per gyro axis, the RMS of the corrected error beyond the white noise, rad/s."""
    out = strategy.correct_rates(ImuRates(t=data.t, omega_ib_b=data.gyro, f_ib_b=data.accel))
    rms = np.sqrt(np.mean((out.omega_ib_b - data.ref_gyro) ** 2, axis=0))
    return np.sqrt(np.maximum(rms**2 - NOISE**2, 0.0))


def test_the_window_learns_a_bias_that_follows_the_motion() -> None:
    """On a session of other motions, the seed model leaves the motion-dependent bias (several times the
    noise's share); the window takes most of it away on every axis (bar: a third of what the seed model
    leaves beyond the noise; the window's features are block means of the rate, not the mean of its size,
    so it approximates the truth, and the ridge shrinks) and passes the guard on every axis."""
    fit_on, judged = _session(0), _session(1)
    seed_only = compensation.make("regression").fit(fit_on)
    windowed = compensation.make("regression_window").fit(fit_on)
    assert isinstance(windowed, window.WindowRegression)
    assert windowed.window_axes == ["x", "y", "z"]
    left_seed, left_window = _beyond_noise(seed_only, judged), _beyond_noise(windowed, judged)
    assert np.all(left_seed > 1.0 * NOISE), left_seed
    assert np.all(left_window < left_seed / 3), (left_window, left_seed)


def test_the_guard_keeps_the_seed_model_where_the_window_sees_nothing() -> None:
    """A unit whose bias does not follow the motion: no axis passes the guard, and the correction is the
    seed model's to the last bit."""
    data = _session(2)
    plain = CalibrationData(
        t=data.t, gyro=data.gyro - _motion_part(data), accel=data.accel, ref_gyro=data.ref_gyro,
        ref_accel=data.ref_accel,
    )  # fmt: skip
    windowed = compensation.make("regression_window").fit(plain)
    assert windowed.window_axes == []
    rates = ImuRates(t=plain.t, omega_ib_b=plain.gyro, f_ib_b=plain.accel)
    seed = compensation.make("regression").fit(plain).correct_rates(rates)
    np.testing.assert_array_equal(windowed.correct_rates(rates).omega_ib_b, seed.omega_ib_b)


def _motion_part(data: CalibrationData) -> np.ndarray:
    size = np.linalg.norm(data.ref_gyro, axis=1)
    return np.convolve(size, np.ones(100) / 100)[: len(size)][:, None] * MOTION_GAIN


def test_the_correction_is_causal_and_saved_exactly(tmp_path: Path) -> None:
    """A reading's correction depends on the readings before it only (changing the readings from one on
    changes nothing before it), and a model file gives the same corrections to the last bit."""
    data = _session(0, duration_s=300.0)
    windowed = compensation.make("regression_window").fit(data)
    rates = ImuRates(t=data.t, omega_ib_b=data.gyro, f_ib_b=data.accel)
    k = len(data.t) // 2
    later = data.gyro.copy()
    later[k:] += 0.5
    changed = windowed.correct_rates(ImuRates(t=data.t, omega_ib_b=later, f_ib_b=data.accel))
    np.testing.assert_array_equal(changed.omega_ib_b[:k], windowed.correct_rates(rates).omega_ib_b[:k])
    path = tmp_path / "window.json"
    compensation.save(windowed, path)
    back = compensation.load(path)
    np.testing.assert_array_equal(
        back.correct_rates(rates).omega_ib_b, windowed.correct_rates(rates).omega_ib_b
    )


def test_too_short_a_recording_is_refused() -> None:
    data = _session(0, duration_s=15.0)
    with pytest.raises(ValueError, match="regression_window needs at least 20 s"):
        compensation.make("regression_window").fit(data)
