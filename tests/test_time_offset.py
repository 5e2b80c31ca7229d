"""Reading a sensor later by a time offset (``intervals.shifted``): the running integral at the shifted
times, against numpy's ``interp`` of it (to the last bit) and against the exact integral of a rate
constant over each step (an analytic oracle)."""

from __future__ import annotations

import numpy as np
import pytest

from sins.compensation.intervals import shifted


def _by_interp(t: np.ndarray, d: np.ndarray, tau_s: float) -> np.ndarray:
    """The running integral at ``t + tau_s`` by numpy's ``interp`` a column at a time, extended past
    both ends at the end steps' rates."""
    total = np.vstack([np.zeros((1, 3)), np.cumsum(d, axis=0)])
    at = t + tau_s
    rate_first, rate_last = d[0] / (t[1] - t[0]), d[-1] / (t[-1] - t[-2])
    out = np.empty_like(total)
    for i in range(3):
        out[:, i] = np.interp(at, t, total[:, i])
        before, after = at < t[0], at > t[-1]
        out[before, i] = (at[before] - t[0]) * rate_first[i]
        out[after, i] = total[-1, i] + (at[after] - t[-1]) * rate_last[i]
    return np.diff(out, axis=0)


@pytest.mark.parametrize("uneven", [False, True])
def test_a_shifted_sensor_is_numpys_interpolation_to_the_last_bit(uneven: bool):
    """Offsets within a step, of many steps, on a step's boundary, negative, and beyond both ends (the
    whole recording's length); a column of zeros (a flat running integral)."""
    rng = np.random.default_rng(7)
    n = 2_000
    steps = rng.uniform(0.7, 1.3, n) * 0.005 if uneven else np.full(n, 0.005)
    t = 100.0 + np.concatenate([[0.0], np.cumsum(steps)])
    d = rng.normal(0.0, 1e-3, (n, 3))
    d[:, 2] = 0.0
    for tau in (0.002, -0.002, 0.037, -0.037, steps[0], float(t[5] - t[0]), 12.0, -12.0, 1e-12):
        np.testing.assert_array_equal(shifted(t, d, tau), _by_interp(t, d, tau))


def test_a_shifted_sensor_is_the_integral_of_its_rate_constant_over_each_step():
    """A rate constant over each step: the increment over ``(t[k-1] + τ, t[k] + τ]`` is the rate
    integrated over that span, by hand (the steps it overlaps, each at its own rate)."""
    rng = np.random.default_rng(8)
    n = 300
    t = np.concatenate([[0.0], np.cumsum(rng.uniform(0.004, 0.006, n))])
    rate = rng.normal(0.0, 0.5, (n, 3))
    d = rate * np.diff(t)[:, None]
    tau = 0.0123  # two to three steps
    exact = np.zeros((n, 3))
    for k in range(n):
        lo, hi = t[k] + tau, t[k + 1] + tau
        for j in range(n):
            a, b = max(lo, t[j]), min(hi, t[j + 1])
            if b > a:
                exact[k] += rate[j] * (b - a)
        if hi > t[-1]:  # beyond the last step: its rate goes on
            exact[k] += rate[-1] * (hi - max(lo, t[-1]))
    np.testing.assert_allclose(shifted(t, d, tau), exact, rtol=0, atol=1e-15)
