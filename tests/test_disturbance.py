"""Disturbances outside the effect library: a bias step and an oscillation found beside regressors,
from the chosen rows only."""

from __future__ import annotations

import numpy as np
import pytest

from sins.gap import disturbance

N, STEP_S = 20_000, 0.1
T = np.arange(N) * STEP_S
ROWS = np.arange(N) % 1000 < 700  # the last 30 % of every 100 s left out, as the diagnosis does


def _columns() -> np.ndarray:
    """A bias and a slow drift that the model's regressors already explain."""
    return np.column_stack([np.ones(N), np.sin(2 * np.pi * T / T[-1])])


def _residual(y: np.ndarray) -> np.ndarray:
    """What the model leaves, its regressors fitted on the chosen rows (the functions' input)."""
    a = _columns()
    coef, *_ = np.linalg.lstsq(a[ROWS], y[ROWS], rcond=None)
    out = y - a @ coef
    out[~ROWS] = 1e3  # what the rows left out hold cannot move the fit
    return out


def test_a_bias_step_is_found_at_its_time_and_size_beside_the_regressors():
    """A step of 0.5 σ at 1,234.56 s under a drift the regressors explain. Its size's standard
    error is σ / √(sᵀ M s), with ``M`` the projection off the regressors on the chosen rows
    (0.030 σ here); its time is uncertain by about (σ / size)² = 4 rows. Rows left out may say
    anything."""
    rng = np.random.default_rng(0)
    y = 3.0 + 2.0 * _columns()[:, 1] + 0.5 * (T > 1234.56) + rng.standard_normal(N)
    t_step, size = disturbance.best_step(_residual(y), _columns(), ROWS, T)
    a, s = _columns()[ROWS], (T[ROWS] > 1234.56).astype(float)
    s_left = s - a @ np.linalg.lstsq(a, s, rcond=None)[0]
    assert t_step == pytest.approx(1234.56, abs=20 * STEP_S)
    assert size == pytest.approx(0.5, abs=4.0 / np.sqrt(s_left @ s_left))


def test_a_step_is_not_placed_at_the_ends_of_the_fit_rows():
    """An outlier in the first 20 rows would be a step after them; the first and last 5 % of the
    chosen rows are not tried, so the step lands after the first block of them (at 84.95 s, midway
    to the next)."""
    y = np.random.default_rng(1).standard_normal(N)
    y[:20] += 50.0
    t_step, _ = disturbance.best_step(_residual(y), _columns(), ROWS, T)
    fit_times = T[ROWS]
    margin = int(disturbance.STEP_MARGIN * len(fit_times))
    assert fit_times[margin - 1] < t_step < fit_times[-margin]


def test_an_oscillation_is_found_at_its_period_and_amplitude_beside_the_regressors():
    """0.3 σ every 37 s over 2,000 s: the frequency's Cramér–Rao bound is about 4e-4 of it here
    (√(12 / (SNR n N²)) of 2π/370 rad per row, SNR = 0.045, n = 14,000 rows chosen over N = 20,000),
    the amplitude's standard error σ √(2 / n) ≈ 0.012 σ. Rows left out may say anything."""
    rng = np.random.default_rng(2)
    y = 3.0 + 2.0 * _columns()[:, 1] + 0.3 * np.sin(2 * np.pi * T / 37.0 + 0.4) + rng.standard_normal(N)
    period_s, amplitude = disturbance.best_oscillation(_residual(y), _columns(), ROWS, T)
    assert period_s == pytest.approx(37.0, rel=5 * 4e-4)
    assert amplitude == pytest.approx(0.3, abs=5 * 0.012)
