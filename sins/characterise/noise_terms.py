"""The IEEE Std 952 / 1293 noise terms: their Allan variances, their spectra, and what a fit reports.

The Allan variance of a sum of independent processes is the sum of theirs (SI units, ``τ = m·dt`` in s):

    σ²(τ) = 3Q²/τ² + N²/τ + (2 ln 2/π) B² f(m) + σ_b² h(τ/T) + K²τ/3 + R²τ²/2

* ``Q`` quantization (angle or velocity: rad, m/s), read at the shortest cluster times;
* ``N`` white rate noise: angle or velocity random walk (rad/√s, m/s/√s);
* ``B`` the IEEE bias instability: flicker (1/f) noise of the rate, whose Allan deviation is the flat
  floor ``0.664 B`` (``√(2 ln 2/π)``); sampled, its spectrum is ``B²/(2 sin πf)`` per sample (``f`` in
  cycles per sample: the fractional difference ``(1 − z⁻¹)^(−1/2)`` of white noise of variance ``B²``),
  and ``f(m)`` is that spectrum's Allan variance over the floor's: ``1/ln 2`` at ``m = 1``, 1.05 at 4,
  within 0.05 % of 1 from ``m = 64`` (:func:`flicker_shape`);
* a first-order Gauss–Markov bias (``σ_b``, correlation time ``T``: the ``bias_instability`` effect sins
  simulates), whose exact Allan variance is ``σ_b² h(x)``, ``h(x) = (4e⁻ˣ − 3 − e⁻²ˣ + 2x) / x²``,
  ``x = τ/T``: it rises as ``2x/3`` (a rate random walk of ``2σ_b²/T``), peaks at ``x ≈ 1.89`` with
  ``σ ≈ 0.617 σ_b`` and falls as ``2/x`` (white noise of ``2σ_b²T``);
* ``K`` rate random walk (rad/s/√s, m/s²/√s);
* ``R`` rate ramp (rad/s², m/s³): deterministic, fitted to the rate itself before the Allan analysis
  (:mod:`sins.characterise.trend`); its column here is what a ramp left in the data would add.

Flicker and the Gauss–Markov bias are told apart by their shapes: a floor against a bump that falls
on both sides. :mod:`sins.characterise.selection` fits these columns to a curve and decides which terms
the data resolve; this module holds the columns, the noise spectra (for the points' degrees of freedom
and correlation, and for the ramp's uncertainty) and the dataclasses of what is reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sins.characterise.allan import MIN_CLUSTERS, AllanCurve

Array = NDArray[np.float64]

#: The six terms, in column order.
TERMS = ("quantization", "white", "flicker", "gauss_markov", "rate_random_walk", "rate_ramp")
#: The noise terms the Allan fit chooses among (the ramp is fitted to the rate itself).
NOISE_TERMS = TERMS[:5]
Q, N, B, GM, K, R = range(6)
SYMBOLS = {
    "quantization": "Q",
    "white": "N",
    "flicker": "B",
    "gauss_markov": "GM",
    "rate_random_walk": "K",
    "rate_ramp": "R",
}
#: ``σ = 0.664 B`` on a flicker floor: √(2 ln 2 / π).
FLICKER_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: Above this cluster size the sampled flicker's Allan variance is its floor (within 0.04 %).
_FLICKER_EXACT_UP_TO = 64
_flicker_cache: dict[int, float] = {}


def flicker_shape(clusters: NDArray[np.integer] | None) -> Array:
    """``f(m)``: the Allan variance of sampled flicker noise over its floor ``(2 ln 2/π) B²``.

    ``2 ∫₀^½ |H_m|² B²/(2 sin πf) df`` with ``|H_m|² = 2 sin⁴(πmf)/(m² sin²πf)`` (the Allan filter), by
    the midpoint rule on 200,000 points (exact to 1e-6 for ``m ≤ 64``; above, 1). None: the floor (1).
    """
    if clusters is None:
        return np.ones(1)
    out = np.ones(len(clusters))
    for j, m in enumerate(int(c) for c in clusters):
        if m > _FLICKER_EXACT_UP_TO:
            continue
        if m not in _flicker_cache:
            f = (np.arange(200_000) + 0.5) / 400_000
            s = np.sin(np.pi * f)
            # 2 ∫₀^½ g df is the mean of g over the midpoints (the interval is ½ long)
            avar = float(np.mean(np.sin(np.pi * m * f) ** 4 / (m * m * s**3)))
            _flicker_cache[m] = avar / FLICKER_FACTOR**2
        out[j] = _flicker_cache[m]
    return out


def gauss_markov_shape(x: Array) -> Array:
    """``h(x) = (4e⁻ˣ − 3 − e⁻²ˣ + 2x) / x²``: the Allan variance of a unit Gauss–Markov bias, ``x = τ/T``.

    A series for small ``x`` (``2x/3 − x²/2 + 7x³/30``) avoids the cancellation.
    """
    x = np.asarray(x, dtype=float)
    small = x < 1e-3
    xs = np.where(small, 1.0, x)
    exact = (4.0 * np.exp(-xs) - 3.0 - np.exp(-2.0 * xs) + 2.0 * xs) / (xs * xs)
    series = 2.0 * x / 3.0 - x * x / 2.0 + 7.0 * x**3 / 30.0
    return np.where(small, series, exact)


#: The peak of ``√h``, and where it lies (``x``).
_X = np.geomspace(0.1, 10.0, 20001)
GM_PEAK = float(np.sqrt(gauss_markov_shape(_X).max()))
GM_PEAK_X = float(_X[np.argmax(gauss_markov_shape(_X))])


def basis(tau_s: Array, tau_c_s: float | None, clusters: NDArray[np.integer] | None = None) -> Array:
    """The Allan variance per unit squared coefficient of each term at ``tau_s``: (k, 6), :data:`TERMS`'
    order. The Gauss–Markov column is zero when ``tau_c_s`` is None; the flicker column is the sampled
    one at ``clusters`` (None: its floor)."""
    tau = np.asarray(tau_s, dtype=float)
    gm = gauss_markov_shape(tau / tau_c_s) if tau_c_s is not None else np.zeros_like(tau)
    flicker = FLICKER_FACTOR**2 * np.broadcast_to(flicker_shape(clusters), tau.shape)
    return np.column_stack([3.0 / tau**2, 1.0 / tau, flicker, gm, tau / 3.0, tau**2 / 2.0])


def model_avar(tau_s: Array, coefficients: Array, tau_c_s: float | None,
               clusters: NDArray[np.integer] | None = None) -> Array:  # fmt: skip
    """The model's Allan variance at ``tau_s`` from the squared coefficients (6,), :data:`TERMS`' order."""
    return np.asarray(basis(tau_s, tau_c_s, clusters) @ np.asarray(coefficients, dtype=float))


def spectrum(f: Array, dt: float, coefficients: Array, tau_c_s: float | None) -> Array:
    """The noise terms' two-sided spectrum of the rate per sample, the rate's unit squared, at ``f`` (cycles
    per sample, ``0 < f ≤ ½``): ``N²/dt`` (white), ``4 sin²(πf) Q²/dt²`` (quantization of the angle),
    ``B²/(2 sin πf)`` (flicker), ``K² dt/(4 sin²(πf))`` (rate random walk) and the sampled Gauss–Markov
    bias's ``σ_b² (1 − φ²)/(1 − 2φ cos 2πf + φ²)``, ``φ = e^(−dt/T)``. A ramp is not random: none."""
    q2, n2, b2, gm2, k2 = (float(v) for v in np.asarray(coefficients, dtype=float)[:5])
    s = np.sin(np.pi * np.asarray(f, dtype=float))
    out = n2 / dt + 4.0 * s * s * q2 / dt**2 + k2 * dt / (4.0 * s * s) + b2 / (2.0 * s)
    if tau_c_s is not None and gm2 > 0.0:
        phi = math.exp(-dt / tau_c_s)
        out = out + gm2 * (1.0 - phi * phi) / (1.0 - 2.0 * phi * np.cos(2.0 * np.pi * f) + phi * phi)
    return np.asarray(out)


def spectral(curve: AllanCurve, coefficients: Array, tau_c_s: float | None) -> tuple[Array, Array]:
    """The EDF of each point of ``curve`` and the correlation between its points, for the given noise.

    The overlapping estimate at cluster size ``m`` is the mean of ``d²`` over its cluster differences,
    ``d`` the rate filtered by ``|H_m(f)|² = 2 sin⁴(π m f) / (m² sin²(π f))``. For Gaussian noise of
    two-sided spectrum ``S`` (:func:`spectrum`), the mean of ``d²`` is ``2 ∫ |H_m|² S df`` (the Allan
    variance; integrals over ``0 < f ≤ ½``) and two such means over ``n`` differences have covariance
    ``(4/n) ∫ |H_i|² |H_j|² S² df``, so the EDF is ``2n (∫ |H_m|² S df)² / ∫ |H_m|⁴ S² df`` (white rate
    noise at ``m = 1``: ``2n/3``, as NIST SP 1065's table). The integrals run on a logarithmic grid of
    ``f``; where it is coarser than the oscillation of ``sin⁴``, its points fall at scattered phases and
    average it. Without any noise: the curve's own EDF and no correlation.

    Returns
    -------
    edf : (k,) equivalent degrees of freedom (at least 1)
    corr : (k, k) correlation matrix of the Allan variance estimates
    """
    dt = float(curve.tau_s[0] / curve.clusters[0])
    m = np.asarray(curve.clusters, dtype=float)[:, None]
    f = np.geomspace(0.25 / max(max(curve.lengths), 2), 0.5, 6000)
    df = np.gradient(f)
    s2 = np.sin(np.pi * f) ** 2
    noise = spectrum(f, dt, coefficients, tau_c_s)
    if not np.any(noise > 0.0):
        return curve.edf, np.eye(len(m))
    h2 = 2.0 * np.sin(np.pi * m * f) ** 4 / (m * m * s2)
    g = h2 * (noise * np.sqrt(df))
    cov = g @ g.T
    d = np.sqrt(np.diag(cov))
    i1 = h2 @ (noise * df)
    edf = np.maximum(2.0 * curve.terms * i1 * i1 / np.maximum(d * d, 1e-300), 1.0)
    d[d == 0.0] = 1.0
    return edf, np.asarray(cov / np.outer(d, d))


@dataclass(frozen=True)
class Term:
    """One fitted term, SI units.

    Attributes
    ----------
    name : one of :data:`TERMS`
    resolved : whether the data resolve it (see :mod:`sins.characterise.selection`)
    value : the term (``Q``, ``N``, ``B``, ``σ_b``, ``K``; ``R`` signed) when resolved, else None
    sigma : its standard error (1σ) when resolved, else None
    upper : when not resolved, the largest value the data allow (about 3σ, 99.9 % one-sided)
    support_tau_s : the cluster times where the term is at least half the model's Allan variance
    needs_length_s : when not resolved, the recording length that would resolve a term of size ``upper``
    needs_rate_hz : when not resolved, the sampling rate that would
    """

    name: str
    resolved: bool
    value: float | None
    sigma: float | None
    upper: float | None
    support_tau_s: tuple[float, ...]
    needs_length_s: float | None = None
    needs_rate_hz: float | None = None

    @property
    def symbol(self) -> str:
        """The IEEE symbol: Q, N, B, GM, K or R."""
        return SYMBOLS[self.name]


@dataclass(frozen=True)
class NoiseFit:
    """The terms fitted to one channel, SI units.

    Attributes
    ----------
    terms : name → :class:`Term`, in :data:`TERMS` order
    coefficients : (6,) the resolved model's squared coefficients ``Q², N², B², σ_b², K², R²`` (zero for a
        term not resolved; ``R²`` zero too when the ramp was taken out of the curve before the fit)
    covariance : (6, 6) their covariance (rows and columns of terms not resolved are zero)
    tau_c_s : the Gauss–Markov correlation time, s (None without the term)
    tau_c_range_s : its range, ``(low, high)`` s, where χ² stays within 4 of its least (None without it)
    chi2 : the resolved model's χ² (log Allan variances, whitened)
    dof : its degrees of freedom (points less fitted parameters, at least 1)
    excluded_tau_s : the cluster times left out of the fit: where the noise model does not hold
    tolerance : the model error allowed each point (a fraction of its Allan variance; 0 when the
        statistics alone accept the fit)
    full_coefficients : (6,) the model with every candidate term, whose spectrum weights the fit
    full_tau_c_s : its correlation time
    ramp_removed : whether the resolved ramp was taken out of the rate before the Allan analysis
    """

    terms: dict[str, Term]
    coefficients: Array
    covariance: Array
    tau_c_s: float | None
    tau_c_range_s: tuple[float, float] | None
    chi2: float
    dof: int
    excluded_tau_s: tuple[float, ...] = ()
    tolerance: float = 0.0
    full_coefficients: Array | None = None
    full_tau_c_s: float | None = None
    ramp_removed: bool = False

    def avar(self, tau_s: Array, clusters: NDArray[np.integer] | None = None) -> Array:
        """The resolved model's Allan variance at ``tau_s`` (a removed ramp left out)."""
        c = self.coefficients.copy()
        if self.ramp_removed:
            c[R] = 0.0
        return model_avar(tau_s, c, self.tau_c_s, clusters)

    def resolved_avar(self, tau_s: Array, clusters: NDArray[np.integer] | None = None) -> Array:
        """The Allan variance of the resolved noise terms alone (what the model file holds)."""
        c = self.coefficients.copy()
        c[R] = 0.0
        return model_avar(tau_s, c, self.tau_c_s, clusters)

    @property
    def resolved(self) -> tuple[str, ...]:
        """The names of the resolved terms."""
        return tuple(n for n in TERMS if self.terms[n].resolved)


def needs(
    term: Array, rest: Array, tau_c_s: float | None, dt: float, length_s: float
) -> tuple[float | None, float | None]:
    """What would resolve a term of squared coefficients ``term`` (6,) beside the others' ``rest``.

    The term shows where it is at least half the model's Allan variance (its window of cluster times).
    A window beyond the longest cluster time (``length / MIN_CLUSTERS``) asks for a recording of
    :data:`MIN_CLUSTERS` times twice the window's start (two octaves in it); a window below the
    sampling step asks for a sampling rate twice the inverse of its end. A window that meets the measured
    cluster times asks for nothing here. Returns ``(needs_length_s, needs_rate_hz)``, at most one set.
    """
    tau = np.geomspace(dt * 1e-4, max(length_s, dt) * 1e4, 2000)
    a = basis(tau, tau_c_s)
    mine, others = a @ term, a @ rest
    window = tau[mine >= others]
    if len(window) == 0:
        return None, None
    top = length_s / MIN_CLUSTERS
    if window[0] > top:
        return float(2.0 * MIN_CLUSTERS * window[0]), None
    if window[-1] < dt:
        return None, float(2.0 / window[-1])
    return None, None


__all__ = [
    "FLICKER_FACTOR",
    "GM",
    "GM_PEAK",
    "GM_PEAK_X",
    "NOISE_TERMS",
    "SYMBOLS",
    "TERMS",
    "B",
    "K",
    "N",
    "NoiseFit",
    "Q",
    "R",
    "Term",
    "basis",
    "flicker_shape",
    "gauss_markov_shape",
    "model_avar",
    "needs",
    "spectral",
    "spectrum",
]
