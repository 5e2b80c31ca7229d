"""The IMU error library: every effect's deterministic or statistical signature, in both IMU forms.

Inputs are synthetic signals whose values and exact integrals are known in
closed form (ramps, sinusoid sums, constant rotations), so the rate form is
checked against the formula of each effect and the increment form against the
exact integral of the corrupted rate. Stochastic effects are checked through
the overlapping Allan deviation (written here from its definition and
cross-checked against allantools when it is installed) with tolerances taken
from the estimator's variance; every seed is fixed.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sins.core.series import ImuIncrements, ImuRates
from sins.imu import (
    BASELINE,
    Bias,
    BiasInstability,
    G2Sensitivity,
    GSensitivity,
    ImuModel,
    Noise,
    Quantization,
    QuantizationNoise,
    RateRandomWalk,
    Saturation,
    ScaleAsymmetry,
    ScaleMisalignment,
    ScaleNonlinearity,
    SizeEffect,
    TemperatureBias,
    TemperatureScale,
    TimeOffset,
    effect_names,
)

EPS = np.finfo(float).eps
Z = 4.0  # statistical checks are 4σ bounds: a false failure has odds < 1e-4 per check (and seeds are fixed)


# --------------------------------------------------------------------------- helpers


def oadev_phase(x: np.ndarray, tau0: float, ms: np.ndarray) -> np.ndarray:
    """Overlapping Allan deviation of phase ``x`` (n+1, c) spaced ``tau0``, for clusters of ``ms`` samples.

    σ²(mτ0) = Σ_k (x[k+2m] − 2 x[k+m] + x[k])² / (2 (mτ0)² (n+1−2m)): the definition
    (IEEE Std 1139, overlapping estimator). Returns (len(ms), c).
    """
    out = []
    for m in ms:
        d = x[2 * m :] - 2.0 * x[m:-m] + x[: -2 * m]
        out.append(np.sqrt(np.mean(d * d, axis=0) / (2.0 * (m * tau0) ** 2)))
    return np.array(out)


def phase_from_rates(y: np.ndarray, dt: float) -> np.ndarray:
    """The integral of rate samples (rectangle rule), starting at 0: the 'phase' of the Allan computation."""
    return np.vstack([np.zeros((1, y.shape[1])), np.cumsum(y, axis=0) * dt])


def phase_from_increments(inc: np.ndarray) -> np.ndarray:
    """Running sum of increments (rad or m/s), starting at 0; its Allan deviation is that of ``inc / dt``."""
    return np.vstack([np.zeros((1, inc.shape[1])), np.cumsum(inc, axis=0)])


def pooled_adev(x: np.ndarray, tau0: float, ms: np.ndarray) -> np.ndarray:
    """Allan deviation pooled over the channels (columns) of ``x``: the root of the mean Allan variance."""
    return np.sqrt(np.mean(oadev_phase(x, tau0, ms) ** 2, axis=1))


def white_rel_err(n: int, m: np.ndarray, channels: int) -> np.ndarray:
    """Relative 1σ error of the Allan deviation with ``n // m`` clusters, pooled over ``channels``.

    1/sqrt(2 (n/m − 1)) per channel: the (non-overlapping, hence conservative) estimator's
    χ² law with n/m − 1 degrees of freedom.
    """
    return 1.0 / np.sqrt(2.0 * channels * (n / m - 1.0))


def log_ms(lo: int, hi: int, count: int) -> np.ndarray:
    return np.unique(np.round(np.geomspace(lo, hi, count)).astype(int))


def zeros_rates(n: int, dt: float) -> ImuRates:
    t = np.arange(n) * dt
    return ImuRates(t, np.zeros((n, 3)), np.zeros((n, 3)))


def zeros_increments(n: int, dt: float) -> ImuIncrements:
    t = np.arange(n + 1) * dt
    return ImuIncrements(t, np.zeros((n, 3)), np.zeros((n, 3)))


class SineSum:
    """A band-limited random signal per channel: Σ_k a_k sin(2π f_k t + φ_k), with its exact integral."""

    def __init__(self, seed: int, fmax: float, count: int = 40, fmin: float = 0.5, offset: float = 0.0):
        rng = np.random.default_rng(seed)
        self.freq = rng.uniform(fmin, fmax, (count, 3))
        self.phase = rng.uniform(0.0, 2.0 * np.pi, (count, 3))
        self.amp = rng.standard_normal((count, 3)) / np.sqrt(count)
        self.offset = offset

    def __call__(self, t: np.ndarray) -> np.ndarray:
        arg = 2.0 * np.pi * self.freq[None] * t[:, None, None] + self.phase[None]
        return self.offset + np.einsum("kc,nkc->nc", self.amp, np.sin(arg))

    def integral(self, t: np.ndarray) -> np.ndarray:
        w = 2.0 * np.pi * self.freq[None]
        arg = w * t[:, None, None] + self.phase[None]
        return self.offset * t[:, None] + np.einsum("kc,nkc->nc", self.amp, -np.cos(arg) / w)

    def increments(self, t: np.ndarray, delay: np.ndarray | float = 0.0) -> np.ndarray:
        """Exact ∫ over (t[k] − d, t[k+1] − d] per channel (d per channel)."""
        d = np.broadcast_to(np.asarray(delay, dtype=float), (3,))
        return np.column_stack([np.diff(self.integral(t - d[i])[:, i]) for i in range(3)])

    def delayed(self, t: np.ndarray, delay: np.ndarray) -> np.ndarray:
        return np.column_stack([self(t - delay[i])[:, i] for i in range(3)])

    def sum_abs_amp_times(self, power: int, h: float) -> np.ndarray:
        """Σ_k |a_k| (ω_k h)^power per channel: bounds the k-th derivative terms of interpolation errors."""
        return np.sum(np.abs(self.amp) * (2.0 * np.pi * self.freq * h) ** power, axis=0)


def ramp(t: np.ndarray, start: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Per-channel linear ramps from ``start`` at t[0] to ``stop`` at t[-1]."""
    s = ((t - t[0]) / (t[-1] - t[0]))[:, None]
    return np.asarray(start) + (np.asarray(stop) - np.asarray(start)) * s


def ramp_increments(t: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Exact integrals of a signal linear in time over the (rounded) intervals of ``t``."""
    return np.diff(t)[:, None] * 0.5 * (u[:-1] + u[1:])


def simpson(g0: np.ndarray, gm: np.ndarray, g1: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """∫ over each interval of a function quadratic in time from its values at the ends and middle (exact)."""
    return dt[:, None] * (g0 + 4.0 * gm + g1) / 6.0


def assert_rounding_close(actual: np.ndarray, expected: np.ndarray, scale: float, ulps: float = 64.0) -> None:
    """Equal to within ``ulps`` roundings of ``scale`` (the magnitude of the terms that were summed)."""
    np.testing.assert_allclose(actual, expected, rtol=0.0, atol=ulps * EPS * scale)


# --------------------------------------------------------------------------- the Allan reference


def test_oadev_helper_matches_allantools():
    allantools = pytest.importorskip("allantools")
    rng = np.random.default_rng(0)
    dt = 0.01
    y = rng.standard_normal((20000, 1)) + np.cumsum(rng.standard_normal((20000, 1)), axis=0) * 1e-2
    ms = np.array([1, 3, 10, 100, 1000])
    ours = oadev_phase(phase_from_rates(y, dt), dt, ms)[:, 0]
    taus, theirs, _, _ = allantools.oadev(y[:, 0], rate=1.0 / dt, data_type="freq", taus=ms * dt)
    np.testing.assert_allclose(taus, ms * dt)
    np.testing.assert_allclose(ours, theirs, rtol=1e-9)  # same estimator: equal to rounding


def gm_avar_continuous(x: np.ndarray) -> np.ndarray:
    """Allan variance / σ² of a continuous first-order Gauss–Markov process of correlation time T at τ = x·T.

    (2T/τ)[1 − (T/2τ)(3 − 4e^{−τ/T} + e^{−2τ/T})]: IEEE Std 952-1997 Annex C ("correlated noise");
    El-Sheimy, Hou & Niu, IEEE Trans. Instrum. Meas. 57(1), 2008, with q²T/2 = σ².
    """
    return 2.0 / x * (1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * x))


def gm_avar_discrete(sigma: float, phi: float, m: int) -> float:
    """Exact Allan variance of an AR(1) sequence (variance σ², lag-1 correlation φ) in clusters of m samples.

    AVAR = (Var S − Cov(S₁, S₂)) / m² with S the sum of one cluster: Var S = σ² Σ_{|l|<m} (m−|l|) φ^|l|,
    Cov(S₁, S₂) = σ² Σ_{l=1}^{2m−1} min(l, 2m−l) φ^l.
    """
    lag = np.arange(-(m - 1), m)
    var_s = np.sum((m - np.abs(lag)) * phi ** np.abs(lag))
    lag = np.arange(1, 2 * m)
    cov = np.sum(np.minimum(lag, 2 * m - lag) * phi**lag)
    return float(sigma**2 * (var_s - cov) / m**2)


# --------------------------------------------------------------------------- white noise


@pytest.mark.parametrize("hz", [100.0, 400.0])
def test_white_noise_rate_form_allan_slope_and_density(hz):
    dt, minutes = 1.0 / hz, 10
    n = int(minutes * 60 * hz)
    dens_g, dens_a = 2e-3, 5e-3  # rad/√s, m/s/√s
    model = ImuModel((Noise("gyro", dens_g), Noise("accel", dens_a)))
    out = model.corrupt_rates(zeros_rates(n, dt), seed=11)
    ms = log_ms(4, n // 10, 14)
    taus = ms * dt
    err = white_rel_err(n, ms, 3)
    for y, dens in ((out.omega_ib_b, dens_g), (out.f_ib_b, dens_a)):
        # per-sample standard deviation density/√dt: sample std has relative error 1/sqrt(2·3n)
        assert np.std(y) * np.sqrt(dt) / dens == pytest.approx(1.0, abs=Z / np.sqrt(6 * n))
        adev = pooled_adev(phase_from_rates(y, dt), dt, ms)
        # every point: σ(τ) = N/√τ exactly for white samples, within 4σ of the estimator's error
        assert np.all(np.abs(adev * np.sqrt(taus) / dens - 1.0) < Z * err), adev * np.sqrt(taus) / dens
        slope = np.polyfit(np.log(taus), np.log(adev), 1)[0]
        # slope error ≲ the two end points' errors over the span in log τ
        assert slope == pytest.approx(-0.5, abs=Z * np.hypot(err[0], err[-1]) / np.log(ms[-1] / ms[0]))
        sigma_1s = pooled_adev(phase_from_rates(y, dt), dt, np.array([round(hz)]))[0]
        assert sigma_1s / dens == pytest.approx(1.0, abs=Z * white_rel_err(n, round(hz), 3))


@pytest.mark.parametrize("hz", [100.0, 400.0])
def test_white_noise_increment_form_allan_slope_and_density(hz):
    dt, minutes = 1.0 / hz, 10
    n = int(minutes * 60 * hz)
    dens_g, dens_a = 2e-3, 5e-3
    model = ImuModel((Noise("gyro", dens_g), Noise("accel", dens_a)))
    out = model.corrupt_increments(zeros_increments(n, dt), seed=12)
    ms = log_ms(4, n // 10, 14)
    taus = ms * dt
    err = white_rel_err(n, ms, 3)
    for inc, dens in ((out.dtheta_b, dens_g), (out.dv_b, dens_a)):
        # each increment is a random walk step of std density·√dt
        assert np.std(inc) / (dens * np.sqrt(dt)) == pytest.approx(1.0, abs=Z / np.sqrt(6 * n))
        adev = pooled_adev(phase_from_increments(inc), dt, ms)
        assert np.all(np.abs(adev * np.sqrt(taus) / dens - 1.0) < Z * err), adev * np.sqrt(taus) / dens
        slope = np.polyfit(np.log(taus), np.log(adev), 1)[0]
        assert slope == pytest.approx(-0.5, abs=Z * np.hypot(err[0], err[-1]) / np.log(ms[-1] / ms[0]))
        sigma_1s = pooled_adev(phase_from_increments(inc), dt, np.array([round(hz)]))[0]
        assert sigma_1s / dens == pytest.approx(1.0, abs=Z * white_rel_err(n, round(hz), 3))


def test_white_noise_is_white_and_independent_across_channels_and_sensors():
    n, dt = 60000, 0.01
    model = ImuModel((Noise("gyro", 1e-3), Noise("accel", 1e-3)))
    for out in (
        model.corrupt_rates(zeros_rates(n, dt), seed=5),
        model.corrupt_increments(zeros_increments(n, dt), seed=5),
    ):
        y = np.hstack([out.omega_ib_b, out.f_ib_b] if isinstance(out, ImuRates) else [out.dtheta_b, out.dv_b])
        corr = np.corrcoef(y.T)
        # sample correlations of independent series have sd 1/√n
        assert np.all(np.abs(corr - np.eye(6)) < Z / np.sqrt(n)), corr
        lag1 = [np.corrcoef(y[:-1, i], y[1:, i])[0, 1] for i in range(6)]
        assert np.all(np.abs(lag1) < Z / np.sqrt(n)), lag1


def test_stochastic_effects_draw_independent_numbers():
    # Each effect's stream is keyed by its name: the white sequences driving the gyro's noise, rate random
    # walk and bias instability, and the accel's noise, are mutually uncorrelated (sd of a correlation 1/√n).
    n, dt, tc = 30000, 0.01, 5.0
    z = zeros_rates(n, dt)
    base = ImuModel((Noise("gyro", 1.0), RateRandomWalk("gyro", 1.0), BiasInstability("gyro", 1.0, tc)))
    base = base.with_effects(Noise("accel", 1.0))
    drives = [
        base.only("gyro.noise").corrupt_rates(z, seed=4).omega_ib_b[1:],
        np.diff(base.only("gyro.rate_random_walk").corrupt_rates(z, seed=4).omega_ib_b, axis=0),
        innovations(base.only("gyro.bias_instability").corrupt_rates(z, seed=4).omega_ib_b, np.exp(-dt / tc)),
        base.only("accel.noise").corrupt_rates(z, seed=4).f_ib_b[1:],
    ]
    for a in range(len(drives)):
        for b in range(a + 1, len(drives)):
            for lag in (-1, 0, 1):
                x, y = np.roll(drives[a], lag, axis=0).ravel(), drives[b].ravel()
                assert abs(np.corrcoef(x, y)[0, 1]) < Z / np.sqrt(x.size), (a, b, lag)


def innovations(b: np.ndarray, phi: float) -> np.ndarray:
    """The white drive of an AR(1) sequence: b[k+1] − φ b[k]."""
    return b[1:] - phi * b[:-1]


# --------------------------------------------------------------------------- rate random walk


def rwfm_edf(n_phase: int, m: np.ndarray) -> np.ndarray:
    """Equivalent degrees of freedom of the overlapping Allan variance for random-walk FM.

    Howe, Allan & Barnes (1981), as tabulated in Stable32 and NIST SP 1065 §5.3:
    edf = (N−2)/m · ((N−1)² − 3m(N−1) + 4m²) / (N−3)², N phase points.
    """
    big = float(n_phase)
    return (big - 2.0) / m * ((big - 1.0) ** 2 - 3.0 * m * (big - 1.0) + 4.0 * m * m) / (big - 3.0) ** 2


@pytest.mark.parametrize("form", ["rates", "increments"])
def test_rate_random_walk_allan_slope_plus_half_and_level(form):
    dt, n = 0.01, 120000  # 20 min: long τ is the point of this effect
    dens_g, dens_a = 1e-4, 3e-4  # rad/s/√s, m/s²/√s
    model = ImuModel((RateRandomWalk("gyro", dens_g), RateRandomWalk("accel", dens_a)))
    if form == "rates":
        out = model.corrupt_rates(zeros_rates(n, dt), seed=21)
        pairs = ((phase_from_rates(out.omega_ib_b, dt), dens_g), (phase_from_rates(out.f_ib_b, dt), dens_a))
    else:
        out = model.corrupt_increments(zeros_increments(n, dt), seed=21)
        pairs = ((phase_from_increments(out.dtheta_b), dens_g), (phase_from_increments(out.dv_b), dens_a))
    # from 30 samples on, the discrete-sampling correction (1 + 1/(2m²)) is below 0.06 %
    ms = log_ms(30, n // 10, 12)
    taus = ms * dt
    err = 1.0 / np.sqrt(2.0 * 3 * rwfm_edf(n + 1, ms))  # relative 1σ of the pooled deviation
    for x, k in pairs:
        adev = pooled_adev(x, dt, ms)
        ratio = adev / (k * np.sqrt(taus / 3.0))
        assert np.all(np.abs(ratio - 1.0) < Z * err), ratio
        slope = np.polyfit(np.log(taus), np.log(adev), 1)[0]
        assert slope == pytest.approx(0.5, abs=Z * np.hypot(err[0], err[-1]) / np.log(ms[-1] / ms[0]))


def test_rate_random_walk_steps_have_variance_density_squared_dt():
    dt, n = 0.01, 60000
    dens = 2e-4
    y = ImuModel((RateRandomWalk("gyro", dens),)).corrupt_rates(zeros_rates(n, dt), seed=3).omega_ib_b
    steps = np.diff(y, axis=0)
    assert np.std(steps) / (dens * np.sqrt(dt)) == pytest.approx(1.0, abs=Z / np.sqrt(6 * n))


# --------------------------------------------------------------------------- bias instability


def test_bias_instability_allan_peak_near_1_89_tc_with_0_62_sigma():
    # the closed form peaks at τ = 1.89 T with 0.618 σ (the figures usually quoted)
    x = np.linspace(0.5, 5.0, 45001)
    closed = np.sqrt(gm_avar_continuous(x))
    x_peak, adev_peak = x[np.argmax(closed)], closed.max()
    assert x_peak == pytest.approx(1.89, abs=0.01) and adev_peak == pytest.approx(0.618, abs=0.001)
    dt, n = 0.01, 120000  # 20 min = 4800 correlation times
    sigma, tc = 0.01, 0.25
    out = ImuModel((BiasInstability("gyro", sigma, tc),)).corrupt_rates(zeros_rates(n, dt), seed=31)
    ms = log_ms(5, 400, 60)
    taus = ms * dt
    adev = pooled_adev(phase_from_rates(out.omega_ib_b, dt), dt, ms)
    phi = np.exp(-dt / tc)
    exact = np.sqrt([gm_avar_discrete(sigma, phi, int(m)) for m in ms])
    err = white_rel_err(n, ms, 3)
    assert np.all(np.abs(adev / exact - 1.0) < Z * err), adev / exact
    # The curve is flat at the top (±30 % in τ lowers it by only 1–2 %), so the argmax of a noisy estimate is
    # located through a parabola in log τ fitted over 0.6..6 T; across 20 seeds its spread was ≈4 %, and the
    # sampled process's own peak (dt/T = 0.04) sits at 1.84 T, so ±20 % of 1.89 T.
    sel = (taus > 0.6 * tc) & (taus < 6.0 * tc)
    p = np.polyfit(np.log(taus[sel] / tc), np.log(adev[sel]), 2)
    assert p[0] < 0.0
    peak = np.exp(-p[1] / (2.0 * p[0]))
    assert peak == pytest.approx(x_peak, rel=0.2)
    m_peak = round(x_peak * tc / dt)
    assert adev.max() / sigma == pytest.approx(adev_peak, abs=adev_peak * Z * white_rel_err(n, m_peak, 3))


def test_bias_instability_stationary_std_and_correlation_time():
    dt, n = 0.01, 120000
    sigma, tc = np.array([0.01, 0.02, 0.005]), 0.25
    out = ImuModel((BiasInstability("accel", sigma, tc),)).corrupt_rates(zeros_rates(n, dt), seed=32)
    b = out.f_ib_b / sigma  # unit-variance processes
    phi = np.exp(-dt / tc)
    # var of the sample variance of AR(1): 2σ⁴(1+φ²)/((1−φ²) n); pooled over 3 channels
    rel_var_sd = np.sqrt(2.0 * (1 + phi**2) / ((1 - phi**2) * 3 * n))
    assert np.mean(b * b) == pytest.approx(1.0, abs=Z * rel_var_sd)
    lag = round(tc / dt)
    rho = np.mean([np.corrcoef(b[:-lag, i], b[lag:, i])[0, 1] for i in range(3)])
    # Bartlett: var r_L ≈ [(1+φ²)(1−φ^{2L})/(1−φ²) − 2Lφ^{2L}] / n, pooled over 3 channels
    bartlett = ((1 + phi**2) * (1 - phi ** (2 * lag)) / (1 - phi**2) - 2 * lag * phi ** (2 * lag)) / (3 * n)
    assert rho == pytest.approx(np.exp(-1.0), abs=Z * np.sqrt(bartlett))
    # the process starts from its stationary law, not from zero
    starts = [
        ImuModel((BiasInstability("accel", 1.0, 100.0),)).corrupt_rates(zeros_rates(2, dt), seed=s).f_ib_b[0]
        for s in range(200)
    ]
    assert np.std(starts) == pytest.approx(1.0, abs=Z / np.sqrt(2 * 600))


def test_bias_instability_increment_form_keeps_the_allan_peak():
    dt, n = 0.01, 120000
    sigma, tc = 0.02, 0.25
    out = ImuModel((BiasInstability("accel", sigma, tc),)).corrupt_increments(
        zeros_increments(n, dt), seed=33
    )
    m = np.array([round(1.89 * tc / dt)])
    adev = pooled_adev(phase_from_increments(out.dv_b), dt, m)[0]
    # averaging the process over each interval changes the peak by O((dt/T)²) ≈ 0.2 %, below the error
    assert adev / sigma == pytest.approx(0.618, abs=0.618 * Z * white_rel_err(n, int(m[0]), 3))


# --------------------------------------------------------------------------- scale nonlinearity, asymmetry


def test_scale_nonlinearity_rate_form_is_k2_u_squared():
    t = np.arange(2001) * 0.01
    u = ramp(t, [-3.0, -1.0, 2.0], [3.0, 4.0, -5.0])
    k2 = np.array([1e-3, -2e-3, 5e-4])
    out = ImuModel((ScaleNonlinearity("gyro", k2),)).corrupt_rates(ImuRates(t, u, u))
    err = out.omega_ib_b - u
    np.testing.assert_array_equal(out.f_ib_b, u)
    for i in range(3):
        c2, c1, c0 = np.polyfit(u[:, i], err[:, i], 2)
        # noiseless: the least-squares fit recovers the coefficients to rounding
        assert c2 == pytest.approx(k2[i], rel=1e-9)
        assert abs(c1) < 1e-12 and abs(c0) < 1e-12
    assert_rounding_close(err, k2 * u * u, scale=np.abs(u).max())


def test_scale_nonlinearity_increments_are_the_integral_of_the_corrupted_rate():
    dt = 0.01
    t = np.arange(3001) * dt
    start, stop = np.array([-3.0, -1.0, 2.0]), np.array([3.0, 4.0, -5.0])
    u = ramp(t, start, stop)
    inc = ramp_increments(t, u)
    k2 = np.array([1e-3, -2e-3, 5e-4])
    out = ImuModel((ScaleNonlinearity("accel", k2),)).corrupt_increments(ImuIncrements(t, inc, inc))
    # ∫ u² over an interval of a ramp = dt (u0² + u0 u1 + u1²)/3, exactly
    exact = k2 * np.diff(t)[:, None] * (u[:-1] ** 2 + u[:-1] * u[1:] + u[1:] ** 2) / 3.0
    assert_rounding_close(out.dv_b - inc, exact, scale=np.abs(inc).max())
    np.testing.assert_array_equal(out.dtheta_b, inc)


def test_scale_nonlinearity_increments_on_a_sinusoid_are_fourth_order():
    dt, a, w = 0.01, 2.0, 2.0 * np.pi * 0.5
    t = np.arange(3001) * dt
    inc = np.repeat(((np.cos(w * t[:-1]) - np.cos(w * t[1:])) * a / w)[:, None], 3, axis=1)
    k2 = 1e-3
    out = ImuModel((ScaleNonlinearity("gyro", k2),)).corrupt_increments(ImuIncrements(t, inc, inc))
    prim = a * a * (t / 2.0 - np.sin(2.0 * w * t) / (4.0 * w))  # ∫ a² sin²(wt)
    exact = np.repeat(k2 * np.diff(prim)[:, None], 3, axis=1)
    # documented O(dt⁴): the error per interval is below k2 a² dt (w dt)⁴ (a unit constant; ends included)
    np.testing.assert_allclose(out.dtheta_b - inc, exact, rtol=0, atol=k2 * a * a * dt * (w * dt) ** 4)


def test_scale_asymmetry_is_ka_abs_u_and_symmetric_in_sign():
    t = np.arange(2001) * 0.01
    u = ramp(t, [-3.0, -1.0, 2.0], [3.0, 4.0, -5.0])
    ka = np.array([1e-3, -2e-3, 5e-4])
    model = ImuModel((ScaleAsymmetry("gyro", ka),))
    err = model.corrupt_rates(ImuRates(t, u, u)).omega_ib_b - u
    err_neg = model.corrupt_rates(ImuRates(t, -u, u)).omega_ib_b + u
    np.testing.assert_allclose(err_neg, err, rtol=0, atol=16 * EPS * 5.0)
    for i in range(3):
        design = np.column_stack([np.abs(u[:, i]), u[:, i], np.ones(len(t))])
        coef = np.linalg.lstsq(design, err[:, i], rcond=None)[0]
        assert coef[0] == pytest.approx(ka[i], rel=1e-9)
        assert np.all(np.abs(coef[1:]) < 1e-12)


def test_scale_asymmetry_increments_integrate_abs_u():
    dt = 0.01
    t = np.arange(2001) * dt
    u = ramp(t, [-3.0025, -1.0011, 2.0], [3.0, 4.0, -5.0])  # each channel changes sign inside an interval
    inc = ramp_increments(t, u)
    ka = np.array([1e-3, -2e-3, 5e-4])
    out = ImuModel((ScaleAsymmetry("accel", ka),)).corrupt_increments(ImuIncrements(t, inc, inc))
    err = out.dv_b - inc
    u0, u1 = u[:-1], u[1:]
    crossing = u0 * u1 < 0
    # away from a sign change |u| is a ramp: ∫|u| = dt |u0 + u1| / 2 exactly
    smooth = ka * np.diff(t)[:, None] * np.abs(u0 + u1) / 2.0
    np.testing.assert_allclose(err[~crossing], smooth[~crossing], rtol=0, atol=64 * EPS * 5.0 * dt)
    # across it, both the exact ∫|u| (in [|u̇|dt²/4, |u̇|dt²/2]) and the two-node rule (≤ 0.79 |u̇|dt²) are small
    exact = ka * (u0**2 + u1**2) / (2.0 * np.abs(u1 - u0) / dt)
    slope = np.abs(u[-1] - u[0]) / (t[-1] - t[0])
    assert crossing.sum() == 3
    assert np.all(
        np.abs(err - exact)[crossing] <= (np.abs(ka) * slope * dt * dt * 0.6)[np.nonzero(crossing)[1]]
    )


# --------------------------------------------------------------------------- g and g² sensitivity, scale


def test_g2_sensitivity_is_the_quadratic_form_and_scales_with_f_squared():
    rng = np.random.default_rng(7)
    n = 500
    t = np.arange(n) * 0.01
    omega = rng.standard_normal((n, 3))
    f = rng.normal(0.0, 10.0, (n, 3))
    g2 = rng.normal(0.0, 1e-6, (3, 3, 3))
    model = ImuModel((G2Sensitivity("gyro", g2),))
    err = model.corrupt_rates(ImuRates(t, omega, f)).omega_ib_b - omega
    expected = np.zeros((n, 3))
    for i in range(3):
        for j in range(3):
            for k in range(3):
                expected[:, i] += g2[i, j, k] * f[:, j] * f[:, k]
    scale = np.abs(g2).sum() * 100.0 * 16.0
    assert_rounding_close(err, expected, scale=max(scale, 1.0))
    err2 = model.corrupt_rates(ImuRates(t, omega, 2.0 * f)).omega_ib_b - omega
    np.testing.assert_allclose(err2, 4.0 * err, rtol=1e-9)
    # only the gyro is affected, and the error does not depend on the rate
    err_other = model.corrupt_rates(ImuRates(t, 3.0 * omega, f)).omega_ib_b - 3.0 * omega
    np.testing.assert_allclose(err_other, err, rtol=0, atol=1e-14)
    with pytest.raises(ValueError):
        G2Sensitivity("accel", g2)


def test_g2_sensitivity_increments_integrate_the_quadratic_form():
    dt = 0.01
    t = np.arange(1001) * dt
    f = ramp(t, [-5.0, 2.0, -9.8], [7.0, -3.0, -9.0])
    dv = ramp_increments(t, f)
    omega = ramp(t, [0.1, 0.2, 0.3], [0.1, 0.2, 0.3])
    dth = ramp_increments(t, omega)
    g2 = np.random.default_rng(8).normal(0.0, 1e-5, (3, 3, 3))
    out = ImuModel((G2Sensitivity("gyro", g2),)).corrupt_increments(ImuIncrements(t, dth, dv))

    def form(x: np.ndarray) -> np.ndarray:
        return np.einsum("ijk,nj,nk->ni", g2, x, x)

    exact = simpson(form(f[:-1]), form(0.5 * (f[:-1] + f[1:])), form(f[1:]), np.diff(t))
    assert_rounding_close(out.dtheta_b - dth, exact, scale=np.abs(dth).max() + np.abs(exact).max())
    np.testing.assert_array_equal(out.dv_b, dv)


def linear_model(rng: np.random.Generator) -> tuple[ImuModel, dict[str, np.ndarray]]:
    p = {
        "bg": rng.normal(0, 1e-3, 3),
        "ba": rng.normal(0, 1e-2, 3),
        "mg": rng.normal(0, 1e-3, (3, 3)),
        "ma": rng.normal(0, 1e-3, (3, 3)),
        "k": rng.normal(0, 1e-4, (3, 3)),
    }
    model = ImuModel(
        (
            Bias("gyro", p["bg"]),
            Bias("accel", p["ba"]),
            ScaleMisalignment("gyro", p["mg"]),
            ScaleMisalignment("accel", p["ma"]),
            GSensitivity("gyro", p["k"]),
        )
    )
    return model, p


def test_bias_scale_misalignment_and_g_sensitivity_are_exact_linear_maps_in_rate_form():
    rng = np.random.default_rng(9)
    n = 1000
    t = np.arange(n) * 0.01
    omega, f = rng.normal(0, 2.0, (n, 3)), rng.normal(0, 10.0, (n, 3))
    model, p = linear_model(rng)
    out = model.corrupt_rates(ImuRates(t, omega, f))
    np.testing.assert_allclose(
        out.omega_ib_b, omega + omega @ p["mg"].T + f @ p["k"].T + p["bg"], rtol=0, atol=32 * EPS * 10.0
    )
    np.testing.assert_allclose(out.f_ib_b, f + f @ p["ma"].T + p["ba"], rtol=0, atol=32 * EPS * 50.0)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), uniform=st.booleans())
def test_linear_effects_are_exact_for_any_increments(seed, uniform):
    # Linear effects commute with integration: whatever the signal (here white, i.e. nothing like a
    # quadratic) and whatever the steps, the increment of M u is M times the increment of u.
    rng = np.random.default_rng(seed)
    n = 200
    dt = np.full(n, 0.01) if uniform else rng.uniform(0.005, 0.02, n)
    t = np.concatenate([[rng.uniform(-1e3, 1e3)], dt]).cumsum()
    dth, dv = rng.normal(0, 1e-2, (n, 3)), rng.normal(0, 1e-1, (n, 3))
    model, p = linear_model(rng)
    out = model.corrupt_increments(ImuIncrements(t, dth, dv))
    dtk = np.diff(t)[:, None]
    # rounding: the reconstruction adds neighbours' means, so the scale is the largest rate times dt
    sg = np.abs(dth / dtk).max() * dt.max()
    sa = np.abs(dv / dtk).max() * dt.max()
    assert_rounding_close(out.dtheta_b, dth + dth @ p["mg"].T + dv @ p["k"].T + p["bg"] * dtk, scale=sg + sa)
    assert_rounding_close(out.dv_b, dv + dv @ p["ma"].T + p["ba"] * dtk, scale=sa)


# --------------------------------------------------------------------------- temperature


def test_temperature_bias_follows_the_temperature_ramp():
    n = 3001
    t = np.arange(n) * 0.01
    temp = 10.0 + 40.0 * t / t[-1]
    omega = np.tile([0.1, -0.2, 0.3], (n, 1))
    c1 = np.array([1e-5, -2e-5, 3e-5])
    linear = ImuModel((TemperatureBias("gyro", c1, t0=25.0),))
    err = linear.corrupt_rates(ImuRates(t, omega, omega), temp=temp).omega_ib_b - omega
    for i in range(3):
        assert abs(np.corrcoef(temp, err[:, i])[0, 1]) > 0.99  # noiseless and linear in T: |r| = 1
    c2 = np.array([3e-7, 1e-7, -2e-7])
    quad = ImuModel((TemperatureBias("gyro", c1, c2, t0=25.0),))
    err = quad.corrupt_rates(ImuRates(t, omega, omega), temp=temp).omega_ib_b - omega
    for i in range(3):
        fit = np.polyfit(temp - 25.0, err[:, i], 2)
        np.testing.assert_allclose(fit, [c2[i], c1[i], 0.0], rtol=1e-7, atol=1e-15)
    with pytest.raises(ValueError, match="temperature"):
        quad.corrupt_rates(ImuRates(t, omega, omega))


def test_temperature_scale_is_s1_dT_u():
    n = 3001
    t = np.arange(n) * 0.01
    temp = 10.0 + 40.0 * t / t[-1]
    s1 = np.array([1e-4, -2e-4, 5e-5])
    model = ImuModel((TemperatureScale("accel", s1, t0=20.0),))
    f_const = np.tile([0.5, -1.0, -9.8], (n, 1))
    err = model.corrupt_rates(ImuRates(t, f_const, f_const), temp=temp).f_ib_b - f_const
    for i in range(3):
        assert abs(np.corrcoef(temp, err[:, i])[0, 1]) > 0.99
    f = SineSum(4, 2.0, offset=3.0)(t)
    err = model.corrupt_rates(ImuRates(t, f, f), temp=temp).f_ib_b - f
    for i in range(3):
        # error = s1 (T − T0) u: a least-squares fit of error against (T − T0) u returns s1
        x = (temp - 20.0) * f[:, i]
        assert np.dot(x, err[:, i]) / np.dot(x, x) == pytest.approx(s1[i], rel=1e-10)
    assert_rounding_close(err, s1 * (temp - 20.0)[:, None] * f, scale=np.abs(f).max())


def test_temperature_effects_increments_are_exact_integrals_for_ramps():
    dt = 0.01
    t = np.arange(2001) * dt
    temp = 10.0 + 40.0 * t / t[-1]
    w = ramp(t, [0.1, -0.3, 1.0], [0.5, 0.2, -1.0])
    f = ramp(t, [1.0, -2.0, -9.8], [-1.0, 2.0, -9.7])
    dth, dv = ramp_increments(t, w), ramp_increments(t, f)
    c1, c2, s1 = np.array([1e-5, -2e-5, 3e-5]), np.array([3e-7, 1e-7, -2e-7]), np.array([1e-4, -2e-4, 5e-5])
    model = ImuModel((TemperatureBias("gyro", c1, c2, t0=25.0), TemperatureScale("accel", s1, t0=20.0)))
    out = model.corrupt_increments(ImuIncrements(t, dth, dv), temp=temp)
    mid = lambda x: 0.5 * (x[:-1] + x[1:])  # noqa: E731 (T and u are ramps: the midpoint value is the mean)
    d = temp - 25.0
    g = c1 * d[:, None] + c2 * d[:, None] ** 2
    exact_g = simpson(g[:-1], c1 * mid(d)[:, None] + c2 * mid(d)[:, None] ** 2, g[1:], np.diff(t))
    assert_rounding_close(out.dtheta_b - dth, exact_g, scale=np.abs(dth).max() + np.abs(exact_g).max())
    a = s1 * (temp - 20.0)[:, None] * f
    exact_a = simpson(a[:-1], s1 * mid(temp - 20.0)[:, None] * mid(f), a[1:], np.diff(t))
    assert_rounding_close(out.dv_b - dv, exact_a, scale=np.abs(dv).max() + np.abs(exact_a).max())
    # with c2 = 0 the gyro error tracks T (noiseless: |r| = 1 to rounding)
    lin = ImuModel((TemperatureBias("gyro", c1, t0=25.0),)).corrupt_increments(
        ImuIncrements(t, dth, dv), temp=temp
    )
    for i in range(3):
        assert abs(np.corrcoef(mid(temp), (lin.dtheta_b - dth)[:, i])[0, 1]) > 0.99
    with pytest.raises(ValueError, match="temperature"):
        model.corrupt_increments(ImuIncrements(t, dth, dv))
    with pytest.raises(ValueError, match="temp"):
        model.corrupt_increments(ImuIncrements(t, dth, dv), temp=temp[1:])


# --------------------------------------------------------------------------- time offset


def xcorr_peak(y: np.ndarray, x: np.ndarray, max_lag: int) -> np.ndarray:
    """Lag (samples) maximising Σ y[k] x[k − L] per channel."""
    lags = np.arange(-max_lag, max_lag + 1)
    w = max_lag
    c = np.array([[np.dot(y[w:-w, i], x[w - lag : len(x) - w - lag, i]) for lag in lags] for i in range(3)])
    return lags[np.argmax(c, axis=1)]


def test_time_offset_rate_form_delays_each_channel():
    dt = 1e-3  # 1 kHz
    t = np.arange(20001) * dt
    sig = SineSum(13, fmax=20.0)
    delay_g, delay_a = np.array([7.3e-3, 2.1e-3, 0.0]), np.array([0.0, 12.6e-3, 4.5e-3])
    model = ImuModel((TimeOffset("gyro", delay_g), TimeOffset("accel", delay_a)))
    u = sig(t)
    out = model.corrupt_rates(ImuRates(t, u, u))
    for y, d in ((out.omega_ib_b, delay_g), (out.f_ib_b, delay_a)):
        assert np.all(np.abs(xcorr_peak(y, u, 20) - d / dt) <= 1.0)
        # sub-sample: cubic Hermite with central-difference slopes; |error| ≤ h·(slope error h²u‴/6)/4
        # + h⁴u⁗/384 per sinusoid, i.e. Σ|a|((ωh)³/24 + (ωh)⁴/384); linear interpolation's (ωh)²/8 is
        # 3/(ωh) ≥ 24 times that, a nearest-sample shift's ωh/2 more still
        bound = sig.sum_abs_amp_times(3, dt) / 24.0 + sig.sum_abs_amp_times(4, dt) / 384.0
        inner = slice(int(np.ceil(d.max() / dt)) + 2, -2)
        ref = sig.delayed(t, d)
        assert np.all(np.abs(y - ref)[inner] <= bound), (np.abs(y - ref)[inner].max(0), bound)
        np.testing.assert_array_equal(y[:, d == 0], u[:, d == 0])


def test_time_offset_increment_form_delays_each_channel():
    dt = 1e-3
    t = np.arange(20001) * dt
    sig = SineSum(14, fmax=20.0)
    delay_g, delay_a = np.array([7.3e-3, 2.1e-3, 0.0]), np.array([0.0, 12.6e-3, 4.5e-3])
    model = ImuModel((TimeOffset("gyro", delay_g), TimeOffset("accel", delay_a)))
    inc = sig.increments(t)
    out = model.corrupt_increments(ImuIncrements(t, inc, inc))
    for y, d in ((out.dtheta_b, delay_g), (out.dv_b, delay_a)):
        assert np.all(np.abs(xcorr_peak(y, inc, 20) - d / dt) <= 1.0)
        # Hermite interpolation of the running integral with slopes from the three-mean quadratic (slope error
        # h³u‴/12): per increment ≤ 2(h·δ/4 + h⁴·(∫u)⁗/384), in rate units Σ|a|(ωh)³(1/24 + 1/192)
        bound = sig.sum_abs_amp_times(3, dt) * (1.0 / 24.0 + 1.0 / 192.0) * dt
        inner = slice(int(np.ceil(d.max() / dt)) + 2, -2)
        ref = sig.increments(t, d)
        assert np.all(np.abs(y - ref)[inner] <= bound), (np.abs(y - ref)[inner].max(0), bound)
        np.testing.assert_array_equal(y[:, d == 0], inc[:, d == 0])


def test_time_offset_comes_before_the_deterministic_errors():
    dt = 1e-3
    t = np.arange(5001) * dt
    sig = SineSum(15, fmax=5.0, offset=1.0)
    d, k2 = np.array([5e-3, 5e-3, 5e-3]), 1e-2
    model = ImuModel((ScaleNonlinearity("gyro", k2), TimeOffset("gyro", d)))
    u = sig(t)
    y = model.corrupt_rates(ImuRates(t, u, u)).omega_ib_b
    ud = sig.delayed(t, d)
    inner = slice(10, -2)
    # the error is k2 u(t−τ)², not k2 u(t)²: the two differ by ≈ 2 k2 u u̇ τ ≫ the interpolation error
    np.testing.assert_allclose(y[inner], (ud + k2 * ud * ud)[inner], rtol=0, atol=1e-6)
    assert np.abs(y - (ud + k2 * u * u))[inner].max() > 1e-4


def test_time_offset_treats_temperature_alike_in_both_forms():
    # A zero rate, a temperature ramp of 10 °C/s and c1 = 1e-3 rad/s/°C: the gyro error is linear in time,
    # so the trapezoid of the rate-form readings is the exact integral the increment form must return.
    dt, n = 0.01, 1000
    t = np.arange(n + 1) * dt
    temp = 20.0 + 10.0 * t
    model = ImuModel((TemperatureBias("gyro", 1e-3, t0=20.0), TimeOffset("gyro", 0.05)))
    z = np.zeros((n + 1, 3))
    rates = model.corrupt_rates(ImuRates(t, z, z), temp=temp).omega_ib_b
    inc = model.corrupt_increments(ImuIncrements(t, z[1:], z[1:]), temp=temp).dtheta_b
    assert_rounding_close(inc, ramp_increments(t, rates), scale=0.2 * dt)


# --------------------------------------------------------------------------- quantization, saturation


def test_quantization_rate_form_rounds_to_the_step():
    dt = 0.01
    t = np.arange(6001) * dt
    u = SineSum(16, fmax=3.0)(t)
    step_g, step_a = np.array([1e-3, 3.7e-3, 0.0]), 0.0123
    model = ImuModel((Quantization("gyro", step_g), Quantization("accel", step_a)))
    out = model.corrupt_rates(ImuRates(t, u, u))
    for y, step in ((out.omega_ib_b, np.broadcast_to(step_g, 3)), (out.f_ib_b, np.full(3, step_a))):
        on = step > 0
        k = y[:, on] / step[on]
        np.testing.assert_allclose(k, np.round(k), rtol=0, atol=1e-9)
        assert np.all(np.abs(y - u)[:, on] <= step[on] / 2 * (1 + 1e-12))
        np.testing.assert_array_equal(y[:, ~on], u[:, ~on])


def test_quantization_increments_carry_the_remainder_over_a_long_record():
    dt = 0.01
    t = np.arange(60001) * dt  # 10 min
    sig = SineSum(17, fmax=3.0, offset=0.1)
    inc = sig.increments(t)
    step_g, step_a = np.array([1e-3, 3.7e-3, 2e-2]), 0.0123
    model = ImuModel((Quantization("gyro", step_g), Quantization("accel", step_a)))
    out = model.corrupt_increments(ImuIncrements(t, inc, inc))
    for y, step in ((out.dtheta_b, step_g), (out.dv_b, np.full(3, step_a))):
        q = step * dt
        k = y / q
        np.testing.assert_allclose(k, np.round(k), rtol=0, atol=1e-6)
        drift = np.cumsum(y, axis=0) - np.cumsum(inc, axis=0)
        # the running sums stay within half a step (plus float summation error of 6e4 terms of ≤ 1e-2)
        assert np.all(np.abs(drift) <= q / 2 + 1e-10), np.abs(drift).max(0) / q
    # without carrying, per-sample rounding of these increments would drift by many steps
    naive = np.cumsum(np.round(inc / (step_g * dt)) * step_g * dt - inc, axis=0)
    assert np.any(np.abs(naive).max(0) > 10 * step_g * dt)


#: The quantization noise's errors of the integrated output: gyro (rad), accelerometer (m/s), per axis.
Q_GYRO, Q_ACCEL = np.array([2e-6, 5e-6, 2.5e-5]), np.array([1e-4, 3e-4, 1.3e-3])


def _quantization_noise_rates(form: str, n: int, dt: float, seed: int) -> np.ndarray:
    """(n, 6) readings of a unit at rest with quantization noise only, as rates (rad/s, m/s²)."""
    model = ImuModel((QuantizationNoise("gyro", Q_GYRO), QuantizationNoise("accel", Q_ACCEL)))
    t = np.arange(n + 1) * dt
    if form == "increments":
        zero = np.zeros((n, 3))
        out = model.corrupt_increments(ImuIncrements(t, zero, zero), seed=seed)
        return np.hstack([out.dtheta_b, out.dv_b]) / dt
    rates = model.corrupt_rates(ImuRates(t[:n], np.zeros((n, 3)), np.zeros((n, 3))), seed=seed)
    return np.hstack([rates.omega_ib_b, rates.f_ib_b])


@pytest.mark.parametrize("form", ["increments", "rates"])
def test_quantization_noise_has_the_ieee_allan_variance(form):
    """The overlapping Allan variance (numpy, from the integrated output) is ``3q²/τ²`` at every octave.

    Tolerance: the estimate at cluster size ``m`` is the mean over ``N = n − 2m`` positions of ``d²``,
    ``d = e_{k+2m} − 2e_{k+m} + e_k`` (the readings' integral telescopes to the output errors), whose
    autocovariance is ``6q², −4q², q²`` at lags ``0, m, 2m`` and zero elsewhere; the variance of the mean is
    then at most ``2 (36 + 2·16 + 2·1) q⁴ / N`` (Gaussian ``e``), an EDF of ``72 N / 140``, and each point
    must lie in its two-sided χ² interval at ``1 − 1e-5`` (78 points: a false alarm in 1,300 runs)."""
    from scipy import stats

    dt, n = 0.01, 1 << 16
    x = _quantization_noise_rates(form, n, dt, seed=11)
    theta = np.vstack([np.zeros((1, 6)), np.cumsum(x * dt, axis=0)])
    q = np.concatenate([Q_GYRO, Q_ACCEL])
    for m in 2 ** np.arange(13):
        tau = m * dt
        d = theta[2 * m :] - 2.0 * theta[m:-m] + theta[: -2 * m]
        avar = np.mean(d * d, axis=0) / (2.0 * tau * tau)
        exact = 3.0 * q * q / tau**2
        edf = 72.0 * len(d) / 140.0
        lo, hi = stats.chi2.ppf([0.5e-5, 1.0 - 0.5e-5], edf) / edf
        ratio = avar / exact
        assert np.all((ratio > lo) & (ratio < hi)), (m, ratio, lo, hi)


def test_quantization_noise_has_the_spectrum_of_a_differenced_white_angle():
    """The Hann-windowed periodogram of the rate (numpy, 64 segments of 1024) follows the exact
    expectation ``(q²/dt²)(2 − 2ρ cos 2πf dt)``, ``ρ`` the window's lag-one autocorrelation (the spectrum
    ``4 sin²(π f dt) q²/dt²`` seen through the window), at every frequency from the first bin to the last
    but Nyquist: it rises as ``f²`` from nothing, unlike white noise. Each bin's mean of 64 periodograms
    is ``χ²(128)/128`` times its expectation; the interval is two-sided at ``1 − 1e-6`` (3,066 bins). The
    lowest bins are 1e-5 of the highest: a white floor a thousandth of the peak would break them."""
    from scipy import stats

    dt, size, segments = 0.01, 1024, 64
    x = _quantization_noise_rates("increments", size * segments, dt, seed=12)
    w = np.sin(np.pi * (np.arange(size) + 0.5) / size) ** 2
    rho = np.sum(w[1:] * w[:-1]) / np.sum(w * w)
    spectra = np.abs(np.fft.rfft(x.reshape(segments, size, 6) * w[None, :, None], axis=1)) ** 2
    p = spectra.mean(axis=0) / np.sum(w * w)  # (bins, 6): E = Σ_l r(l) ρ_w(l) e^{-2πifl dt}
    f = np.fft.rfftfreq(size, dt)
    q = np.concatenate([Q_GYRO, Q_ACCEL])
    expected = (q * q / dt**2)[None, :] * (2.0 - 2.0 * rho * np.cos(2.0 * np.pi * f * dt))[:, None]
    lo, hi = stats.chi2.ppf([0.5e-6, 1.0 - 0.5e-6], 2 * segments) / (2 * segments)
    ratio = (p / expected)[1:-1]
    assert np.all((ratio > lo) & (ratio < hi)), (ratio.min(), ratio.max(), lo, hi)
    assert np.all(expected[1] < 1e-4 * expected[-1])


def test_quantization_noise_adds_nothing_to_the_integrated_output_but_its_last_error():
    """The increments' running sum differs from the true angle by the last output error less the first
    (no random walk): over 10 min its largest excursion stays below 10 q (``|e_first| < 4q`` and every
    ``|e_k| < 6q``: a miss in 8,000 runs for 6e4 Gaussian samples), where a white rate noise as large per
    sample would have walked some 350 q."""
    dt, n = 0.01, 60_000
    x = _quantization_noise_rates("increments", n, dt, seed=13)
    drift = np.cumsum(x * dt, axis=0)
    q = np.concatenate([Q_GYRO, Q_ACCEL])
    assert np.all(np.abs(drift).max(axis=0) < 10.0 * q)
    assert np.all(np.abs(drift).max(axis=0) > 2.0 * q)


def test_saturation_rate_form_clips_and_leaves_the_rest():
    dt = 0.01
    t = np.arange(3001) * dt
    u = 3.0 * SineSum(18, fmax=2.0)(t)
    lim_g, lim_a = np.array([1.0, 2.0, 0.5]), 1.5
    model = ImuModel((Saturation("gyro", lim_g), Saturation("accel", lim_a)))
    out = model.corrupt_rates(ImuRates(t, u, u))
    for y, lim in ((out.omega_ib_b, lim_g), (out.f_ib_b, np.full(3, lim_a))):
        assert np.all(np.abs(y) <= lim)
        over = np.abs(u) > lim
        assert over.any() and (~over).any()
        np.testing.assert_array_equal(y[over], (np.sign(u) * lim)[over])
        np.testing.assert_array_equal(y[~over], u[~over])


def test_saturation_increment_form_clips_and_leaves_the_rest():
    dt = 0.01
    t = np.arange(3001) * dt
    sig = SineSum(18, fmax=2.0)
    sig.amp *= 3.0
    u, inc = sig(t), sig.increments(t)
    lim = np.array([1.0, 2.0, 0.5])
    out = ImuModel((Saturation("gyro", lim),)).corrupt_increments(ImuIncrements(t, inc, inc))
    y = out.dtheta_b
    assert np.all(np.abs(y) <= lim * dt * (1 + 1e-12))
    # classify intervals by the true rate over the interval and its two neighbours (the reconstruction's
    # support), with a 1 % margin that dwarfs the reconstruction's O((ωdt)³) error
    umin = np.minimum(u[:-1], u[1:])
    umax = np.maximum(u[:-1], u[1:])
    lo = np.minimum.reduce([umin, np.roll(umin, 1, 0), np.roll(umin, -1, 0)])
    hi = np.maximum.reduce([umax, np.roll(umax, 1, 0), np.roll(umax, -1, 0)])
    above, below = lo > 1.01 * lim, hi < -1.01 * lim
    inside = (hi < 0.99 * lim) & (lo > -0.99 * lim)
    assert above.any() and below.any() and inside.any()
    np.testing.assert_allclose(y[above], (lim * dt * np.ones_like(y))[above], rtol=1e-12)
    np.testing.assert_allclose(y[below], (-lim * dt * np.ones_like(y))[below], rtol=1e-12)
    np.testing.assert_allclose(y[inside], inc[inside], rtol=0, atol=16 * EPS * 3 * lim.max() * dt)
    np.testing.assert_array_equal(out.dv_b, inc)


def test_saturation_comes_after_bias_and_noise_and_before_quantization_in_rate_form():
    n, dt = 5000, 0.01
    t = np.arange(n) * dt
    u = np.tile([5.0, -5.0, 0.2], (n, 1))
    model = ImuModel(
        (Quantization("gyro", 0.3), Noise("gyro", 0.05), Saturation("gyro", 1.0), Bias("gyro", 0.1))
    )
    y = model.corrupt_rates(ImuRates(t, u, u), seed=1).omega_ib_b
    # the saturated channels read round(±1.0 / 0.3) · 0.3 = ±0.9 whatever the noise; the third is noisy
    np.testing.assert_allclose(y[:, :2], np.tile([0.9, -0.9], (n, 1)), rtol=1e-12)
    assert np.std(y[:, 2]) > 0.3
    k = y[:, 2] / 0.3
    np.testing.assert_allclose(k, np.round(k), atol=1e-9)


def saturated_noisy_gyro(form: str) -> tuple[np.ndarray, float]:
    """Gyro readings (rate units) with true rates (5, −5, 0.2) rad/s, limit 1 rad/s, noise 0.01 rad/√s."""
    n, dt = 5000, 0.01
    t = np.arange(n + 1) * dt
    model = ImuModel((Saturation("gyro", 1.0), Noise("gyro", 0.01)))
    if form == "rates":
        w = np.tile([5.0, -5.0, 0.2], (n + 1, 1))
        return model.corrupt_rates(ImuRates(t, w, w), seed=2).omega_ib_b, dt
    inc = np.tile([5.0 * dt, -5.0 * dt, 0.2 * dt], (n, 1))
    return model.corrupt_increments(ImuIncrements(t, inc, inc), seed=2).dtheta_b / dt, dt


@pytest.mark.parametrize("form", ["rates", "increments"])
def test_saturation_bounds_noisy_readings(form):
    y, dt = saturated_noisy_gyro(form)
    assert np.all(np.abs(y) <= 1.0 * (1 + 1e-12)), np.abs(y).max()  # 1e-12: the rounding of dt = diff(t)
    # the unsaturated channel keeps its noise: sd density/√dt, sample sd relative error 1/√(2n)
    assert np.std(y[:, 2]) / (0.01 / np.sqrt(dt)) == pytest.approx(1.0, abs=Z / np.sqrt(2 * len(y)))


@pytest.mark.parametrize("form", ["rates", "increments"])
def test_noise_comes_before_saturation(form):
    # Documented order: noise, then saturation. Driven 4 rad/s past its limit, a channel whose noise has sd
    # 0.1 rad/s (density/√dt) reads exactly ±limit in every sample, in both forms.
    y, _ = saturated_noisy_gyro(form)
    np.testing.assert_allclose(y[:, :2], np.tile([1.0, -1.0], (len(y), 1)), rtol=1e-12)


# --------------------------------------------------------------------------- size effect


LEVER_ARMS = np.array([[0.05, -0.02, 0.01], [0.03, 0.04, -0.02], [-0.01, 0.02, 0.06]])  # row i: accel i, m


def size_effect_reference(w: np.ndarray, wd: np.ndarray) -> np.ndarray:
    """e_iᵀ(ω̇ × r_i + ω × (ω × r_i)), with ω × (ω × r) = ω (ω·r) − r |ω|² and × via the Levi-Civita symbol."""
    eps3 = np.zeros((3, 3, 3))
    eps3[0, 1, 2] = eps3[1, 2, 0] = eps3[2, 0, 1] = 1.0
    eps3[0, 2, 1] = eps3[2, 1, 0] = eps3[1, 0, 2] = -1.0
    out = np.empty_like(w)
    for i in range(3):
        r = LEVER_ARMS[i]
        tangential = np.einsum("jk,nj,k->n", eps3[i], wd, r)
        centripetal = w[:, i] * (w @ r) - r[i] * np.sum(w * w, axis=1)
        out[:, i] = tangential + centripetal
    return out


def test_size_effect_constant_rotation_is_centripetal_and_quadratic_in_rate():
    n, dt = 200, 0.01
    t = np.arange(n) * dt
    f = np.tile([0.0, 0.0, -9.8], (n, 1))
    model = ImuModel((SizeEffect("accel", LEVER_ARMS),))
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    errs = []
    for rate in (1.0, 2.0):
        w = np.tile(rate * axis, (n, 1))
        out = model.corrupt_rates(ImuRates(t, w, f))
        np.testing.assert_array_equal(out.omega_ib_b, w)
        errs.append(out.f_ib_b - f)
        assert_rounding_close(errs[-1], size_effect_reference(w, np.zeros_like(w)), scale=10.0)
    np.testing.assert_allclose(errs[1], 4.0 * errs[0], rtol=1e-12)  # doubling ω quadruples the error
    assert np.abs(errs[0]).min() > 1e-3
    with pytest.raises(ValueError):
        SizeEffect("gyro", LEVER_ARMS)


def test_size_effect_angular_acceleration_term_both_forms():
    dt = 0.01
    t = np.arange(1001) * dt
    alpha = np.array([0.5, -0.3, 0.8])  # rad/s², constant
    w = np.array([0.1, 0.2, -0.1]) + alpha * t[:, None]
    f = np.tile([0.0, 0.0, -9.8], (len(t), 1))
    model = ImuModel((SizeEffect("accel", LEVER_ARMS),))
    wd = np.tile(alpha, (len(t), 1))
    err = model.corrupt_rates(ImuRates(t, w, f)).f_ib_b - f
    ref = size_effect_reference(w, wd)
    assert_rounding_close(err, ref, scale=100.0)
    # the tangential term matters: without ω̇ the reference differs by far more than rounding
    assert np.abs(ref - size_effect_reference(w, 0 * wd)).min() > 1e-4
    # increments: ω is a ramp, so the error is quadratic in time and Simpson's rule is its exact integral
    dth, dv = ramp_increments(t, w), ramp_increments(t, f)
    out = model.corrupt_increments(ImuIncrements(t, dth, dv))
    wm = 0.5 * (w[:-1] + w[1:])
    exact = simpson(ref[:-1], size_effect_reference(wm, wd[:-1]), ref[1:], np.diff(t))
    assert_rounding_close(out.dv_b - dv, exact, scale=10.0 * dt + np.abs(dv).max())
    np.testing.assert_array_equal(out.dtheta_b, dth)


# --------------------------------------------------------------------------- composition and withholding


def rich_model() -> ImuModel:
    return ImuModel(
        (
            Bias("gyro", [1e-4, -2e-4, 3e-4]),
            Bias("accel", [0.01, -0.02, 0.005]),
            ScaleMisalignment("gyro", np.diag([1e-3, -2e-3, 5e-4]) + 1e-4),
            ScaleMisalignment("accel", np.diag([5e-4, 1e-3, -1e-3]) - 2e-4),
            GSensitivity("gyro", np.full((3, 3), 1e-5)),
            ScaleNonlinearity("accel", 1e-4),
            TemperatureBias("gyro", 1e-6, 1e-8, t0=20.0),
            Noise("gyro", 1e-3),
            Noise("accel", 2e-3),
            BiasInstability("gyro", 5e-4, 30.0),
            BiasInstability("accel", 1e-3, 10.0),
            RateRandomWalk("gyro", 1e-5),
            RateRandomWalk("accel", 3e-5),
        )
    )


def rich_inputs(n: int = 6000, dt: float = 0.01):
    t = np.arange(n + 1) * dt
    w_sig, f_sig = SineSum(40, 2.0), SineSum(41, 2.0, offset=-3.0)
    temp = 15.0 + 10.0 * t / t[-1]
    rates = ImuRates(t, w_sig(t), f_sig(t))
    inc = ImuIncrements(t, w_sig.increments(t), f_sig.increments(t))
    return rates, inc, temp


def outputs(model: ImuModel, form: str, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rates, inc, temp = rich_inputs()
    if form == "rates":
        out = model.corrupt_rates(rates, temp=temp, seed=seed)
        return out.omega_ib_b, out.f_ib_b
    out = model.corrupt_increments(inc, temp=temp, seed=seed)
    return out.dtheta_b, out.dv_b


def ideal(form: str) -> tuple[np.ndarray, np.ndarray]:
    rates, inc, _ = rich_inputs()
    return (rates.omega_ib_b, rates.f_ib_b) if form == "rates" else (inc.dtheta_b, inc.dv_b)


@pytest.mark.parametrize("form", ["rates", "increments"])
@pytest.mark.parametrize("withheld", ["gyro.noise", "gyro.bias_instability", "accel.rate_random_walk"])
def test_withholding_an_effect_removes_only_its_contribution(form, withheld):
    model = rich_model()
    full_g, full_a = outputs(model, form, seed=99)
    less_g, less_a = outputs(model.without(withheld), form, seed=99)
    alone_g, alone_a = outputs(model.only(withheld), form, seed=99)
    ideal_g, ideal_a = ideal(form)
    sensor = withheld.split(".")[0]
    # the other sensor is bit-identical: its draws do not depend on the withheld effect
    if sensor == "gyro":
        np.testing.assert_array_equal(less_a, full_a)
        full, less, alone, base = full_g, less_g, alone_g, ideal_g
    else:
        np.testing.assert_array_equal(less_g, full_g)
        full, less, alone, base = full_a, less_a, alone_a, ideal_a
    # on its own sensor the difference is exactly what the effect adds on its own (same seed, same draws)
    contribution = alone - base
    assert np.abs(contribution).max() > 0
    assert_rounding_close(full - less, contribution, scale=4 * np.abs(full).max())


@pytest.mark.parametrize("form", ["rates", "increments"])
def test_seeds_reproduce_and_differ(form):
    model = rich_model()
    a = outputs(model, form, seed=5)
    b = outputs(model, form, seed=5)
    c = outputs(model, form, seed=6)
    for x, y, z in zip(a, b, c, strict=True):
        np.testing.assert_array_equal(x, y)
        assert np.all(x != z)


@pytest.mark.parametrize("form", ["rates", "increments"])
def test_the_order_of_effects_in_a_model_does_not_matter(form):
    model = rich_model().with_effects(
        Saturation("accel", 4.0), Quantization("gyro", 1e-4), TimeOffset("accel", [1e-3, 0.0, 2.5e-3])
    )
    shuffled = ImuModel(tuple(np.random.default_rng(3).permutation(np.array(model.effects, dtype=object))))
    assert shuffled.names != model.names and sorted(shuffled.names) == sorted(model.names)
    for x, y in zip(outputs(model, form, seed=8), outputs(shuffled, form, seed=8), strict=True):
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-13)


def test_model_names_and_their_errors():
    model = rich_model()
    assert model.names[0] == "gyro.bias" and len(model.names) == 13
    assert set(model.without("gyro.noise", "accel.bias").names) == set(model.names) - {
        "gyro.noise",
        "accel.bias",
    }
    assert model.only("gyro.noise", "accel.noise").names == ("gyro.noise", "accel.noise")
    # withholding a known effect that the model lacks is fine; unknown names are not
    assert model.without("accel.size_effect").names == model.names
    for bad in ("gyro.nope", "noise", "gyro.size_effect", "accel.g_sensitivity", "Gyro.noise"):
        with pytest.raises(ValueError):
            model.without(bad)
        with pytest.raises(ValueError):
            model.only(bad)
    with pytest.raises(ValueError, match="twice"):
        ImuModel((Noise("gyro", 1e-3), Noise("gyro", 2e-3)))
    replaced = model.with_effects(Noise("gyro", 5e-3))
    assert replaced.names.count("gyro.noise") == 1 and len(replaced.names) == 13
    assert np.all(replaced.get("gyro.noise").density == 5e-3)


def test_effect_parameters_are_validated():
    with pytest.raises(ValueError):
        Bias("mag", 0.0)
    with pytest.raises(ValueError):
        GSensitivity("accel", np.zeros((3, 3)))
    with pytest.raises(ValueError):
        Bias("gyro", [1.0, 2.0])
    with pytest.raises(ValueError):
        Noise("gyro", np.nan)
    with pytest.raises(ValueError):
        ScaleMisalignment("gyro", np.zeros((2, 3)))
    with pytest.raises(ValueError):
        BiasInstability("gyro", 1.0, 0.0)
    with pytest.raises(ValueError):
        Saturation("gyro", -1.0)
    with pytest.raises(ValueError):
        Quantization("gyro", -1e-3)


def test_effect_vocabulary_matches_the_design():
    # DESIGN.md §4 plus the IEEE quantization term's white noise of the output: both sensors, except
    # the gyro-only g and g² sensitivities and the accel-only size effect
    both = (
        "bias scale_misalignment noise bias_instability rate_random_walk scale_nonlinearity scale_asymmetry "
        "temperature_bias temperature_scale time_offset quantization saturation quantization_noise "
        "motion_bias"
    ).split()
    expected = {f"{s}.{k}" for s in ("gyro", "accel") for k in both}
    expected |= {"gyro.g_sensitivity", "gyro.g2_sensitivity", "accel.size_effect"}
    names = effect_names()
    assert set(names) == expected and len(names) == len(expected)
    assert set(BASELINE) == {
        "gyro.bias",
        "accel.bias",
        "gyro.scale_misalignment",
        "accel.scale_misalignment",
        "gyro.g_sensitivity",
        "gyro.noise",
        "accel.noise",
    }


# --------------------------------------------------------------------------- one hour, baseline


def test_an_hour_at_100_hz_with_the_baseline_effects():
    dt, n = 0.01, 360000
    t = np.arange(n + 1) * dt
    bg, ba = np.array([1e-5, -2e-5, 3e-5]), np.array([0.01, -0.01, 0.02])
    dens_g, dens_a = 1e-4, 1e-3
    model = ImuModel(
        (
            Bias("gyro", bg),
            Bias("accel", ba),
            ScaleMisalignment("gyro", np.full((3, 3), 2e-4)),
            ScaleMisalignment("accel", np.full((3, 3), -3e-4)),
            GSensitivity("gyro", np.full((3, 3), 1e-6)),
            Noise("gyro", dens_g),
            Noise("accel", dens_a),
        )
    )
    assert set(model.names) == set(BASELINE)
    w = np.tile([0.0, 0.0, 7.3e-5], (n + 1, 1))
    f = np.tile([0.0, 0.0, -9.8], (n + 1, 1))
    rates = model.corrupt_rates(ImuRates(t, w, f), seed=1)
    inc = model.corrupt_increments(ImuIncrements(t, w[1:] * dt, f[1:] * dt), seed=1)
    assert rates.omega_ib_b.shape == rates.f_ib_b.shape == (n + 1, 3)
    assert inc.dtheta_b.shape == inc.dv_b.shape == (n, 3)
    # the mean error is the bias plus the linear terms; the noise mean has sd density/√T
    lin_g = w[0] @ np.full((3, 3), 2e-4).T + f[0] @ np.full((3, 3), 1e-6).T
    lin_a = f[0] @ np.full((3, 3), -3e-4).T
    span = n * dt
    for err_g, err_a in (
        ((rates.omega_ib_b - w).mean(0), (rates.f_ib_b - f).mean(0)),
        ((inc.dtheta_b / dt - w[1:]).mean(0), (inc.dv_b / dt - f[1:]).mean(0)),
    ):
        np.testing.assert_allclose(err_g, bg + lin_g, rtol=0, atol=Z * dens_g / np.sqrt(span))
        np.testing.assert_allclose(err_a, ba + lin_a, rtol=0, atol=Z * dens_a / np.sqrt(span))


@pytest.mark.parametrize("t", [[0.0, 0.01, 0.01, 0.02, 0.03, 0.04], [0.0, 0.01, 0.02, 0.015, 0.03, 0.04]])
def test_times_that_do_not_increase_are_refused_not_integrated(t: list[float]) -> None:
    # A repeated or backward stamp had made corrupt_rates and corrupt_increments NaN rows (numpy's
    # divide-by-zero warnings) and ImuRates.to_increments increments of the wrong sign, without a word.
    t_s = np.array(t)
    rates = ImuRates(t=t_s, omega_ib_b=np.zeros((6, 3)), f_ib_b=np.tile([0.0, 0.0, -9.8], (6, 1)))
    model = ImuModel((Noise("gyro", 1e-3), Noise("accel", 1e-3)))
    increments = ImuIncrements(t=t_s, dtheta_b=np.zeros((5, 3)), dv_b=np.zeros((5, 3)))
    calls = {
        "ImuRates.to_increments": rates.to_increments,
        "corrupt_rates": lambda: model.corrupt_rates(rates, seed=1),
        "corrupt_increments": lambda: model.corrupt_increments(increments, seed=1),
    }
    for what, call in calls.items():
        with pytest.raises(ValueError, match=rf"^{what}: t must increase from each sample to the next"):
            call()


def test_rates_check_their_temperature_and_an_effect_keeps_its_own_parameters() -> None:
    """``corrupt_rates`` takes the temperature as ``corrupt_increments`` does (one value of length 1 had
    been broadcast to every sample, NaN had made NaN readings); an effect's parameters are its own copy,
    read-only (a caller's array changed after the check had changed the frozen model)."""
    n = 201
    rates = ImuRates(t=np.arange(n) / 100.0, omega_ib_b=np.zeros((n, 3)), f_ib_b=np.zeros((n, 3)))
    unit = ImuModel((TemperatureBias("gyro", c1=np.full(3, 1e-5)),))
    for temp, said in ((np.array([30.0]), "one value per sample time"), (np.full(n, np.nan), "finite")):
        with pytest.raises(ValueError, match=said):
            unit.corrupt_rates(rates, temp=temp)
    warm = unit.corrupt_rates(rates, temp=np.full(n, 30.0))
    np.testing.assert_allclose(warm.omega_ib_b, 1e-4, rtol=1e-12)  # c1 (T - T0), T0 20 °C
    b = np.array([1e-5, 0.0, 0.0])
    model = ImuModel((Bias("gyro", b),))
    b[0] = np.nan
    assert np.isfinite(model.corrupt_rates(rates).omega_ib_b).all()
    with pytest.raises(ValueError, match="read-only"):
        model.effects[0].value[0] = 1.0  # type: ignore[attr-defined]
