"""The IEEE Std 952 / 1293 noise terms: their analytic Allan variances and a joint fit to a curve.

The Allan variance of a sum of independent processes is the sum of theirs (SI units, ``τ`` in s):

    σ²(τ) = 3Q²/τ² + N²/τ + σ_b² h(τ/T) + K²τ/3 + R²τ²/2

* ``Q`` quantization (angle or velocity: rad, m/s), read at the shortest cluster times;
* ``N`` white rate noise: angle or velocity random walk (rad/√s, m/s/√s);
* a bias instability, modelled as the first-order Gauss–Markov bias sins simulates
  (``bias_instability``: stationary ``σ_b``, correlation time ``T``), whose exact Allan variance is
  ``σ_b² h(x)``, ``h(x) = (4e⁻ˣ − 3 − e⁻²ˣ + 2x) / x²``, ``x = τ/T``: it rises as ``2x/3`` (a rate random
  walk of ``2σ_b²/T``), peaks at ``x ≈ 1.89`` with ``σ ≈ 0.617 σ_b`` and falls as ``2/x`` (white noise of
  ``2σ_b²T``). The IEEE bias-instability figure ``B`` (a flicker floor, ``σ = 0.664 B``) is reported as
  the flicker floor with the same peak: ``B = 0.617 σ_b / 0.664 = 0.929 σ_b``;
* ``K`` rate random walk (rad/s/√s, m/s²/√s);
* ``R`` rate ramp (rad/s², m/s³), which sins does not simulate.

The fit (:func:`fit_terms`) is a non-negative weighted least squares of the measured Allan variances on
the five columns, for each correlation time ``T`` of a grid inside the measured cluster times (and
without the Gauss–Markov column); the weights are ``edf / (2 σ²_model)``, the variance of a ``χ²(edf)``
estimate, iterated so they come from the model and not from the noisy points. The correlation time kept
is the one of least ``χ²`` once every fitted parameter is charged 2 (Akaike; the Gauss–Markov term has two),
and so is the choice of which of ``Q``, ``K``, ``R`` enter (each in or out: a rate random walk and a ramp
both rise at the longest cluster times, where few points tell them apart). The correlation time's range
is where ``χ²`` stays within 4 (times the reduced ``χ²`` where that exceeds 1) of its least (about 95 %). The
uncertainties come from the weighted fit's covariance, inflated by the reduced ``χ²`` where that exceeds
1. The points are treated as independent: adjacent octaves share data, so the covariance is a slight
underestimate, which the tests measure (over 20 seeds per case).

A term is *resolved* when leaving it out of the fitted model raises χ² by 9 or more (a likelihood-ratio
test at about 3σ; a 2σ test on the coefficient passed spurious terms, chosen as they are among subsets and
correlation times); the weakest term below that is dropped and the rest fitted again until every term
left passes, so the resolved terms are the model the file simulates. An unresolved term is given as an
upper bound (its coefficient fitted beside the resolved ones + 2σ), and :func:`needs` says what would
resolve a term of that size: a
recording long enough for it to rise above the other terms, or a faster sampling where it hides under
them at the shortest cluster time, or nothing (the data bound it already).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import stats
from scipy.linalg import solve_triangular
from scipy.optimize import nnls

from sins.characterise.allan import MIN_CLUSTERS, AllanCurve

Array = NDArray[np.float64]

#: The five terms, in column order, and their IEEE symbols.
TERMS = ("quantization", "white", "bias_instability", "rate_random_walk", "rate_ramp")
SYMBOLS = {
    "quantization": "Q",
    "white": "N",
    "bias_instability": "B",
    "rate_random_walk": "K",
    "rate_ramp": "R",
}
#: ``σ = 0.664 B`` on a flicker floor: √(2 ln 2 / π).
FLICKER_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: Correlation times tried per octave.
_GRID_PER_OCTAVE = 6
#: What each fitted parameter costs in χ² (Akaike's 2); the Gauss–Markov term has two.
_PARAM_PENALTY = 2.0
#: The column subsets tried: white noise and the Gauss–Markov column always, each of Q, K, R in or out.
_SUBSETS = [
    [k for k, on in zip((0, 3, 4), flags, strict=True) if on] + [1, 2]
    for flags in ((a, b, c) for a in (0, 1) for b in (0, 1) for c in (0, 1))
]
#: A term is resolved when leaving it out raises χ² by this much (a likelihood-ratio test at about 3σ:
#: the choice among subsets and correlation times makes a 2σ test pass spurious terms).
RESOLVED_CHI2 = 9.0
#: The fit is taken to hold when its χ² is at least this probable; otherwise its worst point is left out.
MODEL_HOLDS_P = 1e-3
#: The model error allowed each point where the statistics alone reject the fit: a fraction of its Allan
#: variance (10 %: 5 % of the deviation).
MODEL_TOLERANCE = 0.1
#: Points are left out while more than this many remain.
MIN_POINTS = 5
#: The correlation time's range: where χ² stays within this much of its least (about 95 %).
TAU_C_CHI2 = 4.0


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


def basis(tau_s: Array, tau_c_s: float | None) -> Array:
    """The Allan variance per unit squared coefficient of each term at ``tau_s``: (k, 5).

    The Gauss–Markov column is zero when ``tau_c_s`` is None.
    """
    tau = np.asarray(tau_s, dtype=float)
    gm = gauss_markov_shape(tau / tau_c_s) if tau_c_s is not None else np.zeros_like(tau)
    return np.column_stack([3.0 / tau**2, 1.0 / tau, gm, tau / 3.0, tau**2 / 2.0])


def model_avar(tau_s: Array, coefficients: Array, tau_c_s: float | None) -> Array:
    """The model's Allan variance at ``tau_s`` from the squared coefficients ``(Q², N², σ_b², K², R²)``."""
    return np.asarray(basis(tau_s, tau_c_s) @ np.asarray(coefficients, dtype=float))


@dataclass(frozen=True)
class Term:
    """One fitted noise term, SI units.

    Attributes
    ----------
    name : one of :data:`TERMS`
    resolved : whether the data resolve it (leaving it out raises χ² by :data:`RESOLVED_CHI2`)
    value : the term (``Q``, ``N``, ``σ_b``, ``K`` or ``R``) when resolved, else None
    sigma : its standard error (1σ) when resolved, else None
    upper : when not resolved, the largest value the data allow (coefficient + 2σ, square-rooted)
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
        """The IEEE symbol: Q, N, B, K or R."""
        return SYMBOLS[self.name]


@dataclass(frozen=True)
class NoiseFit:
    """The noise terms fitted jointly to one channel's Allan curve, SI units.

    Attributes
    ----------
    terms : name → :class:`Term`, in :data:`TERMS` order
    coefficients : (5,) the squared coefficients ``Q², N², σ_b², K², R²`` as fitted (zero at the bound)
    covariance : (5, 5) their covariance (rows and columns of terms left out of the fit are zero)
    tau_c_s : the Gauss–Markov correlation time, s (None without the term)
    tau_c_range_s : its range, ``(low, high)`` s, where χ² stays within 4 of its least (None without it)
    chi2 : the weighted fit's χ²
    dof : its degrees of freedom (points less fitted parameters, at least 1)
    excluded_tau_s : the cluster times left out of the fit: where the noise model does not hold
    tolerance : the model error allowed each point (a fraction of its Allan variance; 0 when the
        statistics alone accept the fit)
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

    def avar(self, tau_s: Array) -> Array:
        """The fitted model's Allan variance at ``tau_s``."""
        return model_avar(tau_s, self.coefficients, self.tau_c_s)

    def resolved_avar(self, tau_s: Array) -> Array:
        """The Allan variance of the resolved terms alone (what the model file holds, and a ramp)."""
        on = np.array([self.terms[n].resolved for n in TERMS], dtype=float)
        return model_avar(tau_s, self.coefficients * on, self.tau_c_s)

    @property
    def b_ieee(self) -> float | None:
        """The IEEE bias-instability figure ``B`` (the flicker floor of the same peak), when resolved."""
        t = self.terms["bias_instability"]
        return None if t.value is None else t.value * GM_PEAK / FLICKER_FACTOR

    @property
    def b_ieee_sigma(self) -> float | None:
        """The standard error of :attr:`b_ieee`."""
        t = self.terms["bias_instability"]
        return None if t.sigma is None else t.sigma * GM_PEAK / FLICKER_FACTOR


def spectral(curve: AllanCurve, coefficients: Array, tau_c_s: float | None) -> tuple[Array, Array]:
    """The EDF of each point of ``curve`` and the correlation between its points, for the given noise.

    The overlapping estimate at cluster size ``m`` is the mean of ``d²`` over its cluster differences,
    ``d`` the rate filtered by ``|H_m(f)|² = 2 sin⁴(π m f) / (m² sin²(π f))`` (``f`` in cycles per
    sample). For Gaussian noise of two-sided spectrum ``S``, the mean of ``d²`` is ``2 ∫ |H_m|² S df``
    (the Allan variance; integrals over ``0 < f ≤ ½``) and two such means over ``n`` differences have
    covariance ``(4/n) ∫ |H_i|² |H_j|² S² df``, so the EDF is ``2n (∫ |H_m|² S df)² / ∫ |H_m|⁴ S² df``
        (white rate noise at ``m = 1``: ``2n/3``, as NIST SP 1065's table). The integrals run on a logarithmic
    grid of ``f``; where it is coarser than the oscillation of
    ``sin⁴``, its points fall at scattered phases and average it. The spectra per sample: ``N²/dt``
    (white), ``4 sin²(π f) Q²/dt²`` (quantization of the angle), ``K² dt / (4 sin²(π f))`` (rate random
    walk) and the Gauss–Markov bias's ``σ_b² (1 − φ²) / (1 − 2φ cos 2πf + φ²)``, ``φ = e^(−dt/T)``; a ramp
    is not random and adds nothing. Without any noise: the curve's own EDF and no correlation.

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
    q2, n2, b2, k2, _ = (float(v) for v in coefficients)
    spectrum = n2 / dt + 4.0 * s2 * q2 / dt**2 + k2 * dt / (4.0 * s2)
    if tau_c_s is not None and b2 > 0.0:
        phi = math.exp(-dt / tau_c_s)
        spectrum = spectrum + b2 * (1.0 - phi * phi) / (1.0 - 2.0 * phi * np.cos(2.0 * np.pi * f) + phi * phi)
    if not np.any(spectrum > 0.0):
        return curve.edf, np.eye(len(m))
    h2 = 2.0 * np.sin(np.pi * m * f) ** 4 / (m * m * s2)
    g = h2 * (spectrum * np.sqrt(df))
    cov = g @ g.T
    d = np.sqrt(np.diag(cov))
    i1 = h2 @ (spectrum * df)
    edf = np.maximum(2.0 * curve.terms * i1 * i1 / np.maximum(d * d, 1e-300), 1.0)
    d[d == 0.0] = 1.0
    return edf, np.asarray(cov / np.outer(d, d))


def _whitener(mu: Array, edf: Array, corr: Array | None, tolerance: float = 0.0) -> Array:
    """The lower Cholesky factor ``L`` of the estimates' covariance ``V = S C S + (ε μ)²``,
    ``S = √(2/edf) μ``, ``ε`` the model tolerance (independent from point to point)."""
    sd = np.sqrt(2.0 / edf) * mu
    c = np.eye(len(mu)) if corr is None else corr
    v = c * np.outer(sd, sd) + np.diag(1e-9 * sd * sd + (tolerance * mu) ** 2)
    return np.asarray(np.linalg.cholesky(v))


def _nnls(wa: Array, wy: Array) -> tuple[Array, float]:
    """Non-negative least squares of the whitened ``wy ≈ wa c``: ``c`` and χ²."""
    scale = np.linalg.norm(wa, axis=0)
    scale[scale == 0.0] = 1.0
    cn, _ = nnls(wa / scale, wy, maxiter=50 * wa.shape[1])
    c = cn / scale
    r = wy - wa @ c
    return c, float(r @ r)


def _covariance(a: Array, white: Array, columns: list[int]) -> Array:
    """The covariance of the coefficients of ``columns`` from the whitened normal equations."""
    sub = white @ a[:, columns]
    scale = np.linalg.norm(sub, axis=0)
    scale[scale == 0.0] = 1.0
    normal = (sub / scale).T @ (sub / scale)
    inv = np.linalg.pinv(normal)
    return np.asarray(inv / np.outer(scale, scale))


def fit_terms(curve: AllanCurve, length_s: float | None = None, corr: Array | None = None,
              reference: Array | None = None) -> NoiseFit:  # fmt: skip
    """Fit the five IEEE terms jointly to an Allan curve, leaving out the points the model cannot hold.

    When the fit's χ² is improbable (:data:`MODEL_HOLDS_P`), the statistics alone reject the ideal sum of
    processes, which a real unit never is to the 0.1 % a long recording's short cluster times measure: each
    point is then allowed a model error of :data:`MODEL_TOLERANCE` of its Allan variance, and while the
    χ² is still improbable and more than :data:`MIN_POINTS` points are left, the shortest or the longest
    cluster time is left out (whichever leaves the likelier fit) and the terms fitted again: the model is
    taken to hold over one range of cluster times. The points left out are where it does not (a real
    unit's bursts and vibration lines at the short end, its base's motion at the long end), reported in
    :attr:`NoiseFit.excluded_tau_s`. Arguments as :func:`fit_points`.
    """
    use = np.ones(len(curve.tau_s), dtype=bool)
    fit = fit_points(curve, use, length_s, corr, reference)
    tolerance = 0.0
    while stats.chi2.sf(fit.chi2, fit.dof) < MODEL_HOLDS_P:
        points = int(np.count_nonzero(use & (curve.avar > 0.0) & (curve.edf >= 1.0)))
        if tolerance == 0.0:
            tolerance = MODEL_TOLERANCE
        elif points <= MIN_POINTS:
            break
        else:  # trim the end whose removal leaves the likelier fit
            inside = np.flatnonzero(use)
            trials = []
            for end in (inside[0], inside[-1]):
                trial = use.copy()
                trial[end] = False
                f = fit_points(curve, trial, length_s, corr, reference, tolerance)
                trials.append((stats.chi2.logsf(f.chi2, f.dof), trial, f))
            _, use, fit = max(trials, key=lambda x: x[0])
            continue
        fit = fit_points(curve, use, length_s, corr, reference, tolerance)
    excluded = tuple(float(t) for t in curve.tau_s[~use])
    return NoiseFit(fit.terms, fit.coefficients, fit.covariance, fit.tau_c_s, fit.tau_c_range_s, fit.chi2,
                    fit.dof, excluded, tolerance)  # fmt: skip


def fit_points(
    curve: AllanCurve,
    use: NDArray[np.bool_] | None = None,
    length_s: float | None = None,
    corr: Array | None = None,
    reference: Array | None = None,
    tolerance: float = 0.0,
) -> NoiseFit:
    """Fit the five IEEE terms jointly to the points ``use`` of an Allan curve (see the module's text).

    Parameters
    ----------
    curve : the measured curve (its EDF sets the estimates' variances; :func:`characterise_channel`
        refits with the EDF of the fitted noise types)
    use : the points to fit (default: all)
    length_s : the recording's longest segment, s, for what an unresolved term would need (default: the
        longest cluster time times :data:`MIN_CLUSTERS`)
    corr : the correlation between the curve's points (:func:`spectral`), None: independent
    reference : the Allan variance the estimates' variances ``2 σ⁴ / edf`` are taken from (a previous
        fit's), None: the measured one
    tolerance : ``ε``, the model error allowed each point, a fraction of its Allan variance

    Returns
    -------
    NoiseFit
    """
    keep = (curve.avar > 0.0) & (curve.edf >= 1.0)
    if use is not None:
        keep &= use
    tau, y, edf = curve.tau_s[keep], curve.avar[keep], curve.edf[keep]
    if corr is not None:
        corr = corr[np.ix_(keep, keep)]
    mu = y if reference is None else np.where(reference[keep] > 0.0, reference[keep], y)
    white = solve_triangular(_whitener(mu, edf, corr, tolerance), np.eye(len(y)), lower=True)
    wy = white @ y
    if len(tau) < 2:
        empty = {n: Term(n, False, None, None, None, ()) for n in TERMS}
        return NoiseFit(empty, np.zeros(5), np.zeros((5, 5)), None, None, 0.0, 1)
    results = _grid_fits(tau, white, wy)
    _, chi2, tc, c = min(results, key=lambda r: r[0])
    # The Gauss–Markov column for a term not in the model: the best correlation time it had.
    gm_any = [r for r in results if r[2] is not None]
    tc_probe = tc if tc is not None else (min(gm_any, key=lambda r: r[1])[2] if gm_any else None)
    if tc_probe is None:
        tc_probe = float(tau[len(tau) // 2])
    if c[2] <= 0.0:
        tc = None
    columns, c, chi2, tc, inflate, dof = _eliminate(tau, white, wy, c, chi2, tc)
    a = basis(tau, tc)
    cov = np.zeros((5, 5))
    if columns:
        cov[np.ix_(columns, columns)] = _covariance(a, white, columns) * inflate
    tc_range = None
    if tc is not None:
        gm = [r for r in results if r[2] is not None and r[3][2] > 0.0]
        inside = [float(r[2]) for r in gm if r[2] is not None and r[1] <= chi2 + TAU_C_CHI2 * inflate] or [tc]
        half_step = 2.0 ** (0.5 / _GRID_PER_OCTAVE)  # the grid's resolution
        tc_range = (float(min(inside)) / half_step, float(max(inside)) * half_step)
    length = length_s if length_s is not None else float(curve.tau_s[-1]) * MIN_CLUSTERS
    dt = float(curve.tau_s[0] / curve.clusters[0])
    fit = _Fitted(tau, white, wy, c, cov, columns, tc, inflate)
    terms = {name: _term(fit, k, name, tc_probe, dt, length) for k, name in enumerate(TERMS)}
    return NoiseFit(terms, c, cov, tc, tc_range, chi2, dof)


#: One grid point's fit: (score, χ², correlation time or None, coefficients).
_GridFit = tuple[float, float, float | None, Array]


def _grid_fits(tau: Array, white: Array, wy: Array) -> list[_GridFit]:
    """The best subset of terms for each correlation time of the grid (and for none)."""
    # The Gauss–Markov bump is told from a rate random walk or white noise only when its peak lies inside.
    lo, hi = 4.0 * tau[0], tau[-1] / 2.0
    grid: list[float | None] = [None]
    if hi > lo:
        count = max(int(_GRID_PER_OCTAVE * math.log2(hi / lo)) + 1, 2)
        grid += list(np.geomspace(lo, hi, count) / GM_PEAK_X)
    results: list[_GridFit] = []
    for tc in grid:
        wa = white @ basis(tau, tc)
        best_here: _GridFit | None = None
        for subset in _SUBSETS:
            cols = [k for k in subset if k != 2 or tc is not None]
            c = np.zeros(5)
            c[cols], chi2 = _nnls(wa[:, cols], wy)
            score = chi2 + _PARAM_PENALTY * (np.count_nonzero(c) + (1 if c[2] > 0.0 else 0))
            if best_here is None or score < best_here[0]:
                best_here = (score, chi2, tc, c)
        assert best_here is not None
        results.append(best_here)
    return results


def _eliminate(
    tau: Array, white: Array, wy: Array, c: Array, chi2: float, tc: float | None
) -> tuple[list[int], Array, float, float | None, float, int]:
    """Backward elimination: a term that leaving out costs less than RESOLVED_CHI2 goes, and the rest
    are fitted again without it (so the terms kept are the model the file simulates). The columns
    kept, coefficients, χ², correlation time, χ² inflation and degrees of freedom."""
    columns = [k for k in range(5) if c[k] > 0.0]
    while True:
        wa = white @ basis(tau, tc)
        dof = max(len(tau) - len(columns) - (1 if tc is not None else 0), 1)
        inflate = max(1.0, chi2 / dof)
        gains = {}
        for k in columns:
            rest = [j for j in columns if j != k]
            without = _nnls(wa[:, rest], wy)[1] if rest else float(wy @ wy)
            gains[k] = (without - chi2) / inflate
        weak = [k for k in columns if gains[k] < RESOLVED_CHI2]
        if not weak:
            return columns, c, chi2, tc, inflate, dof
        columns.remove(min(weak, key=lambda k: gains[k]))
        if 2 not in columns:
            tc = None
        c = np.zeros(5)
        if columns:
            c[columns], chi2 = _nnls((white @ basis(tau, tc))[:, columns], wy)
        else:
            chi2 = float(wy @ wy)
        columns = [k for k in columns if c[k] > 0.0]


@dataclass(frozen=True)
class _Fitted:
    """What :func:`fit_points` settled on, for reading off each term."""

    tau: Array
    white: Array
    wy: Array
    c: Array
    cov: Array
    columns: list[int]
    tc: float | None
    inflate: float


def _term(fit: _Fitted, k: int, name: str, tc_probe: float, dt: float, length: float) -> Term:
    """Term ``k``: its value and σ where resolved, else its upper bound and what would resolve it."""
    a_probe = basis(fit.tau, fit.tc if fit.tc is not None else tc_probe)
    c = fit.c
    model = a_probe @ c
    share = a_probe[:, k] * c[k] / np.maximum(model, 1e-300)
    support = tuple(float(t) for t in fit.tau[share >= 0.5])
    if k in fit.columns:
        value = math.sqrt(c[k])
        return Term(name, True, value, math.sqrt(max(fit.cov[k, k], 0.0)) / (2.0 * value), None, support)
    extended = sorted({*fit.columns, k})
    ce = np.zeros(5)
    ce[extended], _ = _nnls((fit.white @ a_probe)[:, extended], fit.wy)
    var = _covariance(a_probe, fit.white, extended)[extended.index(k), extended.index(k)] * fit.inflate
    upper = math.sqrt(max(ce[k], 0.0) + 2.0 * math.sqrt(max(var, 0.0)))
    size = np.zeros(5)
    size[k] = upper**2
    need_len, need_rate = needs(size, c, tc_probe, dt, length)
    if need_len is None and need_rate is None and k >= 2:
        # Bounded, not seen: a slow term smaller than its bound shows only at longer cluster times,
        # two octaves beyond these at the least.
        need_len = 4.0 * length
    return Term(name, False, None, None, upper, (), need_len, need_rate)


def needs(
    term: Array, rest: Array, tau_c_s: float | None, dt: float, length_s: float
) -> tuple[float | None, float | None]:
    """What would resolve a term of squared coefficients ``term`` beside the others' ``rest``.

    The term shows where it is at least half the model's Allan variance (its window of cluster times).
    A window beyond the longest cluster time (``length / MIN_CLUSTERS``) asks for a recording of
    :data:`MIN_CLUSTERS` times twice the window's start (two octaves in it); a window below the
    sampling step asks for a sampling rate twice the inverse of its end. A window that meets the measured
    cluster times asks for nothing here (:func:`fit_points` then asks a slow term, bias instability, rate
    random walk or ramp, for two octaves more: four times the length, a least). Returns
    ``(needs_length_s, needs_rate_hz)``, at most one of them set.
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
