"""Static IMU noise written with numpy alone, independent of ``sins.characterise``: the recordings the
characterisation is judged on (``tests/test_characterise.py``, ``tools/characterise_recovery.py``).

Processes (SI: rad, rad/√s, rad/s, rad/s/√s, rad/s² for a gyro; m/s-based for an accelerometer):

* white rate noise ``N``: independent samples of standard deviation ``N/√dt``;
* quantization ``Q``: independent uniform angle errors of standard deviation ``Q``, differenced;
* a first-order Gauss–Markov bias (``σ_b``, ``T``): the AR(1) ``bₖ = φ bₖ₋₁ + σ_b √(1 − φ²) wₖ``,
  ``φ = e^(−dt/T)``, started in its stationary law;
* flicker (IEEE bias instability ``B``): Kasdin and Walter's fractional difference, white noise of
  standard deviation ``B`` filtered by ``(1 − z⁻¹)^(−1/2)`` (impulse response ``h₀ = 1``,
  ``hₖ = hₖ₋₁ (k − ½)/k``, applied by FFT convolution), whose two-sided spectrum per sample is
  ``B²/(2 sin πf)`` and whose Allan deviation is the floor ``0.664 B`` from a few samples on; the filter
  runs over twice the length and the first half is dropped (its start from rest);
* a rate random walk ``K``: the running sum of independent steps of standard deviation ``K √dt``;
* a rate ramp ``R``: ``R·t``.

:func:`exact_avar` writes out the exact discrete Allan variance of the classical processes (flicker has
no closed form: its test compares it with the library's sampled form over seeds).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import fftconvolve, lfilter

_DEG = math.pi / 180.0
_DPH = _DEG / 3600.0
_UG = 9.80665e-6

#: The statistical cases of issue 32, 4 h at 100 Hz: per case, the process (SI) and the sensor.
CASES: dict[str, dict[str, float]] = {
    # A gyro with quantization, white noise, a Gauss–Markov bias and a rate random walk: each dominates
    # over at least an octave and a half of the curve.
    "gyro_q_n_gm_k": dict(q=2e-5, arw=0.3 * _DEG / 60, sigma_b=5 * _DPH, tau_c=30.0, k=10 * _DPH / 60),
    # Flicker (the IEEE B) beside white noise: a floor over the last five octaves.
    "flicker_white": dict(arw=0.1 * _DEG / 60, flicker=2 * _DPH),
    # White noise and a rate ramp that rises above it over the last two octaves.
    "white_ramp": dict(arw=0.1 * _DEG / 60, r=3 * _DPH / 3600),
    # An accelerometer with white noise, a Gauss–Markov bias and a rate random walk.
    "accel_n_gm_k": dict(arw=100 * _UG, sigma_b=50 * _UG, tau_c=30.0, k=2 * _UG),
}
#: The generator's keys → the characterisation's term names.
KEYS = {
    "q": "quantization",
    "arw": "white",
    "flicker": "flicker",
    "sigma_b": "gauss_markov",
    "k": "rate_random_walk",
    "r": "rate_ramp",
}
DT = 0.01
HOURS = 4.0


def flicker(rng: np.random.Generator, n: int, b: float) -> np.ndarray:
    """``n`` samples of flicker noise of IEEE bias instability ``b`` (Kasdin and Walter's filter)."""
    total = 2 * n
    h = np.empty(total)
    h[0] = 1.0
    k = np.arange(1, total)
    h[1:] = np.cumprod((k - 0.5) / k)
    return np.asarray(fftconvolve(b * rng.standard_normal(total), h)[total - n : total])


def generate(rng: np.random.Generator, n: int, dt: float, *, q: float = 0.0, arw: float = 0.0,
             sigma_b: float = 0.0, tau_c: float = 1.0, flicker_b: float = 0.0, k: float = 0.0,
             r: float = 0.0, **aliases: float) -> np.ndarray:  # fmt: skip
    """A rate series of ``n`` samples at ``dt`` (see the module's text); ``flicker=`` is ``flicker_b``."""
    flicker_b = aliases.pop("flicker", flicker_b)
    if aliases:
        raise TypeError(f"unknown processes {sorted(aliases)}")
    x = np.zeros(n)
    if arw:
        x += arw / math.sqrt(dt) * rng.standard_normal(n)
    if k:
        x += np.cumsum(k * math.sqrt(dt) * rng.standard_normal(n))
    if sigma_b:
        phi = math.exp(-dt / tau_c)
        drive = sigma_b * math.sqrt(1.0 - phi * phi) * rng.standard_normal(n)
        x += lfilter([1.0], [1.0, -phi], drive, zi=[phi * sigma_b * rng.standard_normal()])[0]
    if flicker_b:
        x += flicker(rng, n, flicker_b)
    if q:
        x += np.diff(q * math.sqrt(12.0) * rng.uniform(-0.5, 0.5, n + 1)) / dt
    if r:
        x += r * dt * np.arange(n)
    return x


def case_series(case: str, seed: int, hours: float = HOURS, dt: float = DT) -> np.ndarray:
    """One seed of a case (the seed stream ``[seed, case's index]``)."""
    index = list(CASES).index(case)
    return generate(np.random.default_rng([seed, index, 32]), int(hours * 3600.0 / dt), dt, **CASES[case])


def truths(case: str) -> dict[str, float]:
    """Each term's true value in a case (0 for a term the case lacks)."""
    process = CASES[case]
    return {name: float(process.get(key, 0.0)) for key, name in KEYS.items()}


def exact_avar(m: np.ndarray, dt: float, *, q: float = 0.0, arw: float = 0.0, sigma_b: float = 0.0,
               tau_c: float = 1.0, k: float = 0.0, r: float = 0.0) -> np.ndarray:  # fmt: skip
    """The exact Allan variance of the generator's series at cluster sizes ``m`` (discrete forms)."""
    m = np.asarray(m, dtype=float)
    tau = m * dt
    out = (
        3.0 * q * q / tau**2
        + arw * arw / tau
        + k * k * dt * (2.0 * m * m + 1.0) / (6.0 * m)
        + r * r * tau**2 / 2
    )
    if sigma_b:
        phi = math.exp(-dt / tau_c)

        def v(mm: np.ndarray) -> np.ndarray:  # the variance of a sum of mm samples of the AR(1)
            return sigma_b**2 * (mm * (1 + phi) / (1 - phi) - 2 * phi * (1 - phi**mm) / (1 - phi) ** 2)

        out = out + (2.0 * v(m) - v(2.0 * m) / 2.0) / (m * m)
    return out
