"""A random bias under white noise: the steady-state filter against filterpy's Kalman filter, the
fit's recovery of a simulated process, and the falsification tests' stated level."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from sins.gap import randombias


def _reference_filter(y: np.ndarray, phi: float, q: float, r: float, x0: float, p0: float):
    """filterpy's time-varying filter over ``y``: innovations, and the last gain and innovation variance."""
    kf = KalmanFilter(dim_x=1, dim_z=1)
    kf.F, kf.H, kf.Q, kf.R = np.array([[phi]]), np.array([[1.0]]), np.array([[q]]), np.array([[r]])
    kf.x, kf.P = np.array([[x0]]), np.array([[p0]])  # the prior of the first row
    nu = np.empty(len(y))
    for k, z in enumerate(y):
        kf.update(z)
        nu[k] = kf.y[0, 0]
        kf.predict()
    return nu, float(kf.K[0, 0]), float(kf.S[0, 0])


@pytest.mark.parametrize(("phi", "q", "r"), [(0.98, 0.05, 1.0), (1.0, 1e-4, 0.3), (0.5, 2.0, 0.01)])
def test_the_steady_state_filter_is_the_kalman_filters_limit(phi: float, q: float, r: float):
    """Started from the steady-state prior variance, filterpy's filter keeps the steady gain from
    the first row: its innovations are ours to rounding. Started from a vague prior, its gain and
    innovation variance converge to ours."""
    rng = np.random.default_rng(0)
    y = np.cumsum(rng.standard_normal(2000)) * np.sqrt(q) + np.sqrt(r) * rng.standard_normal(2000)
    gain, s = randombias.steady_gain(phi, q, r)
    x0 = float(np.mean(y[:100]))  # ours starts from the mean of the first 100 rows
    nu, k_ref, s_ref = _reference_filter(y, phi, q, r, x0, s - r)
    np.testing.assert_allclose(randombias.innovations(y, phi, gain), nu, rtol=0, atol=1e-12 * np.abs(y).max())
    assert (k_ref, s_ref) == pytest.approx((gain, s), rel=1e-12)
    _, k_ref, s_ref = _reference_filter(y, phi, q, r, 0.0, 1e6)
    assert (k_ref, s_ref) == pytest.approx((gain, s), rel=1e-9)


def test_the_fit_recovers_a_gauss_markov_bias_and_a_walk_on_their_grids():
    """τ = 50 s and a bias of twice the white noise's spread, 10⁴ s at 10 Hz: the grid's τ (steps of
    ×2.03) is one of the two values either side, and the drive is within the fine grid's step
    (×1.33) and its sampling error (a few %) of the truth: 0.84–1.19 of it over five seeds. A walk's
    drive (off both grids) likewise: 0.89–1.19."""
    rng = np.random.default_rng(1)
    n, step_s, tau_s, r = 100_000, 0.1, 50.0, 1.0
    phi = np.exp(-step_s / tau_s)
    q = 4.0 * r * (1.0 - phi**2)  # stationary variance 4 r
    w = rng.standard_normal(n) * np.sqrt(q)
    b = np.empty(n)
    b[0] = 2.0 * rng.standard_normal()
    for k in range(1, n):
        b[k] = phi * b[k - 1] + w[k]
    rows = np.ones(n, dtype=bool)
    fitted = randombias.fit(b + rng.standard_normal(n), rows, step_s, r, walk=False)
    assert tau_s / 2.03 < -step_s / np.log(fitted.phi) < tau_s * 2.03
    assert 1 / 1.4 < fitted.q / q < 1.4

    walk = np.cumsum(rng.standard_normal(n)) * np.sqrt(2e-3) + rng.standard_normal(n)
    fitted = randombias.fit(walk, rows, step_s, r, walk=True)
    assert fitted.phi == 1.0 and 1 / 1.4 < fitted.q / 2e-3 < 1.4
    assert fitted.fit_loglik == pytest.approx(randombias.log_likelihood(fitted.innovations))
    assert not randombias.falsified(fitted, rows, np.arange(n) * step_s)


def test_a_real_random_walk_passes_the_checks_on_a_random_bias_at_their_stated_level():
    """``falsified`` holds each quarter's own drive against the common one, and the largest window
    sum of innovations against its bound, each at p = 0.001. On 200 walks under white noise both
    keep that level: at most 3 falsified (0.4 expected). With the drive left on the coarse grid
    (steps of 10^0.5), each quarter won back by chance what the grid's step lost; 8 of these 200
    walks were falsified, and with them real walks on the rigs."""
    rng = np.random.default_rng(0)
    n, step_s = 60_000, 0.005
    t = np.arange(n) * step_s
    rows = np.ones(n, dtype=bool)
    falsified = 0
    for _ in range(200):
        y = np.cumsum(rng.standard_normal(n)) * np.sqrt(4.5e-4) + rng.standard_normal(n)
        y = y - y.mean()
        r = (float(np.std(np.diff(y))) / np.sqrt(2.0)) ** 2  # the diagnosis's floor: first differences
        falsified += randombias.falsified(randombias.fit(y, rows, step_s, r, walk=True), rows, t)
    assert falsified <= 3


def test_a_jump_is_not_taken_for_a_walk():
    """White noise with one jump of 10 σ halfway: the filter trails the new level, and the burst
    in its innovations falsifies the walk."""
    rng = np.random.default_rng(2)
    n, step_s = 20_000, 0.01
    y = rng.standard_normal(n) + 10.0 * (np.arange(n) >= n // 2)
    rows = np.ones(n, dtype=bool)
    fitted = randombias.fit(y - y.mean(), rows, step_s, 1.0, walk=True)
    assert randombias.falsified(fitted, rows, np.arange(n) * step_s)
