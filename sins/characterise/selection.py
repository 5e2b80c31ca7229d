"""Which noise terms an Allan curve resolves, decided so that one more refit cannot change it.

**Weights from a model with every candidate.** The points' degrees of freedom and correlation depend on
the noise type at each cluster time (:func:`~sins.characterise.noise_terms.spectral`). They are taken from the
*full* model, all five noise terms fitted together (:func:`weigh`), and iterated with it to a fixed point
(the EDF changes by less than 0.1 %): a continuous iteration, which converges in two to four passes. On
the log scale the weights do not depend on the fitted level (:mod:`sins.characterise.fitting`), so no
candidate model is weighted by a curve that lacks its own term (which would under-weight the longest
cluster times and resolve a slow term one refit and drop it the next: ``docs/guide/characterise.md``).

**A decision that is a function of those weights.** Every subset of the five terms is fitted under the
same weights. A subset is *admissible* when each of its terms is resolved in it: leaving the term out
raises χ² by :data:`RESOLVED_CHI2` or more (a likelihood-ratio test at about 3σ), every coefficient
positive. The admissible subset of least χ² is reported. All subsets, not a backward elimination: with
a Gauss–Markov bias and a rate random walk, eliminating one term at a time let a flicker floor stand in
for both. The σ of each resolved term comes from the reported subset's fit under the same weights (the
Gauss–Markov correlation time fitted beside it), scaled by the full model's reduced χ² where that
exceeds 1, and widened to its σ in the fit with any one unresolved term the data lean towards
(:data:`LEANING_CHI2`): the choice between near-alike models is part of its uncertainty. An
unresolved term is bounded by the profile likelihood: the value where χ², the resolved
terms refitted beside it, rises by :data:`UPPER_CHI2` (about 3σ, 99.9 % one-sided: a term not resolved at
3σ is bounded at 3σ; at 2σ, an unresolved rate random walk beside a Gauss–Markov bias fell below its
bound in one of five seeds).

**Where the model does not hold.** When the full model's χ² is improbable (:data:`MODEL_HOLDS_P`), the
statistics alone reject the ideal sum of processes, which a real unit never is to the 0.1 % a long
recording's short cluster times measure: each point is then allowed a model error of
:data:`MODEL_TOLERANCE` of its Allan variance, and while χ² is still improbable the fit is narrowed to
the widest run of cluster times where it holds (at least :data:`MIN_POINTS`; the likeliest run of that
width). The points left out are where it does not hold (a real unit's bursts and vibration lines at the
short end, its base's motion at the long end).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from sins.characterise.allan import MIN_CLUSTERS, AllanCurve
from sins.characterise.fitting import LogPoints, SubsetFit, covariance, fit_subset, solve, upper_bound
from sins.characterise.noise_terms import GM, NOISE_TERMS, TERMS, B, K, NoiseFit, Term, basis, needs, spectral

Array = NDArray[np.float64]

#: The five noise terms, as column indices.
ALL = frozenset(range(len(NOISE_TERMS)))
#: A term is resolved when leaving it out raises χ² by this much (a likelihood-ratio test at about 3σ).
RESOLVED_CHI2 = 9.0
#: An unresolved term's bound: where χ² has risen by this much (about 3σ: 99.9 % one-sided).
UPPER_CHI2 = 9.0
#: The slow terms' bounds a trend test holds against: where χ² has risen by this much (97.7 %).
SLOW_CHI2 = 4.0
#: The correlation time's range: where χ² stays within this much of its least (about 95 %), on a grid of
#: this many correlation times an octave.
TAU_C_CHI2 = 4.0
TAU_C_PER_OCTAVE = 8
#: An unresolved term the data lean towards (adding it lowers χ² by this much) widens the others' σ.
LEANING_CHI2 = 1.0
#: The fit is taken to hold when its χ² is at least this probable; otherwise its worst end is left out.
MODEL_HOLDS_P = 1e-3
#: The model error allowed each point where the statistics alone reject the fit: a fraction of its Allan
#: variance.
MODEL_TOLERANCE = 0.1
#: Points are left out while more than this many remain.
MIN_POINTS = 5
#: The weights' iteration stops when no point's EDF changes by more than this fraction ...
EDF_RTOL = 1e-3
#: ... or after this many passes.
MAX_PASSES = 12


@dataclass(frozen=True)
class Weights:
    """The full model (every candidate term) and the weights it gives the curve's points.

    Attributes
    ----------
    coefficients : (6,) the full model's squared coefficients (the ramp's zero)
    tau_c_s : its Gauss–Markov correlation time
    edf : (k,) the points' EDF from its spectrum
    corr : (k, k) their correlation
    use : (k,) the points fitted (False: left out where the model does not hold)
    tolerance : the model error allowed each point
    chi2, dof : the full model's fit
    passes : how many passes the EDF took to settle
    slow_upper : (6,) squared coefficients: the flicker's and the rate random walk's upper bounds beside
        the full model (:data:`SLOW_CHI2`), zero elsewhere: the slowest noise the curve allows
    """

    coefficients: Array
    tau_c_s: float | None
    edf: Array
    corr: Array
    use: NDArray[np.bool_]
    tolerance: float
    chi2: float
    dof: int
    passes: int
    slow_upper: Array

    def slow_models(self) -> list[Array]:
        """The full model, and it with each slow term (flicker, rate random walk) at its upper bound:
        the noise a trend test must hold against (squared coefficients, (6,) each)."""
        out = [self.coefficients]
        for k in (B, K):
            c = self.coefficients.copy()
            c[k] = max(c[k], self.slow_upper[k])
            out.append(c)
        return out

    @property
    def inflate(self) -> float:
        """The full model's reduced χ² where that exceeds 1 and has three degrees of freedom or more."""
        return max(1.0, self.chi2 / self.dof) if self.dof >= 3 else 1.0


def _six(c: Array) -> Array:
    return np.r_[c, 0.0]


@dataclass(frozen=True)
class _Full:
    points: LogPoints
    subset: frozenset[int]
    fit: SubsetFit
    dof: int


def _full(curve: AllanCurve, use: NDArray[np.bool_], edf: Array, corr: Array | None, tolerance: float
          ) -> _Full:  # fmt: skip
    points = LogPoints.of(curve.with_edf(edf), use, corr, tolerance)
    subset = ALL
    fit = fit_subset(points, subset)
    if not math.isfinite(fit.chi2):  # too few points for a Gauss–Markov term
        subset = ALL - {GM}
        fit = fit_subset(points, subset)
    params = int(np.count_nonzero(fit.coefficients)) + (1 if fit.tau_c_s is not None else 0)
    return _Full(points, subset, fit, max(len(points) - params, 1))


def weigh(curve: AllanCurve, start: Weights | None = None, passes: int = MAX_PASSES) -> Weights:
    """The full model's weights for ``curve``: its EDF and correlation iterated with it to a fixed point,
    and the points where the model holds (see the module's text). ``start``: a previous result to go on
    from (its points and tolerance kept), for ``passes`` passes."""
    usable = (curve.avar > 0.0) & (curve.edf >= 1.0)
    use, tolerance = (usable.copy(), 0.0) if start is None else (start.use.copy(), start.tolerance)
    edf, corr = (curve.edf, None) if start is None else (start.edf, start.corr)
    total = 0
    while True:
        for _ in range(passes):
            full = _full(curve, use, edf, corr, tolerance)
            new_edf, corr = spectral(curve, _six(full.fit.coefficients), full.fit.tau_c_s)
            total += 1
            settled = bool(np.max(np.abs(new_edf / edf - 1.0)) < EDF_RTOL)
            edf = new_edf
            if settled:
                break
        full = _full(curve, use, edf, corr, tolerance)
        if start is not None or stats.chi2.sf(full.fit.chi2, full.dof) >= MODEL_HOLDS_P:
            break
        if tolerance == 0.0:
            tolerance = MODEL_TOLERANCE
            continue
        if np.count_nonzero(use) <= MIN_POINTS:
            break
        use = _narrow(curve, use, edf, corr, tolerance)
    inflate = max(1.0, full.fit.chi2 / full.dof) if full.dof >= 3 else 1.0
    slow = np.zeros(6)
    for k in (B, K):
        slow[k] = upper_bound(full.points, full.fit, full.subset, k, SLOW_CHI2 * inflate)
    return Weights(_six(full.fit.coefficients), full.fit.tau_c_s, edf, np.asarray(corr), use, tolerance,
                   full.fit.chi2, full.dof, total, slow)  # fmt: skip


def _narrow(curve: AllanCurve, use: NDArray[np.bool_], edf: Array, corr: Array | None, tolerance: float
            ) -> NDArray[np.bool_]:  # fmt: skip
    """The widest run of ``use``'s points (shorter by one at least) where the full model holds, the
    likeliest of the widest when none holds; at least :data:`MIN_POINTS` points. Whole windows, not one
    end at a time: a ring-laser gyro's bump over four short cluster times made the model miss its long
    end, and a greedy trim took that end away first."""
    inside = np.flatnonzero(use)
    best: tuple[float, NDArray[np.bool_]] | None = None
    for width in range(len(inside) - 1, MIN_POINTS - 1, -1):
        for first in range(len(inside) - width + 1):
            trial = np.zeros_like(use)
            trial[inside[first : first + width]] = True
            full = _full(curve, trial, edf, corr, tolerance)
            score = float(stats.chi2.logsf(full.fit.chi2, full.dof))
            if best is None or score > best[0]:
                best = (score, trial)
        assert best is not None
        if best[0] >= math.log(MODEL_HOLDS_P):
            break
    return use if best is None else best[1]


def fit_all(points: LogPoints) -> dict[frozenset[int], SubsetFit]:
    """Every non-empty subset of the noise terms fitted to ``points``."""
    out: dict[frozenset[int], SubsetFit] = {}
    order = sorted(ALL)
    for size in range(1, len(order) + 1):
        for subset in combinations(order, size):
            key = frozenset(subset)
            out[key] = fit_subset(points, key, out.get(key - {GM}) if GM in key else None)
    return out


def admissible(fits: dict[frozenset[int], SubsetFit], inflate: float) -> list[frozenset[int]]:
    """The subsets whose every term is resolved in them (positive, and leaving it out costs
    :data:`RESOLVED_CHI2` or more, in units of ``inflate``)."""
    out = []
    for subset, fit in fits.items():
        if not math.isfinite(fit.chi2) or any(fit.coefficients[k] <= 0.0 for k in subset):
            continue
        gains = [
            (fits[subset - {k}].chi2 if len(subset) > 1 else math.inf) - fit.chi2 for k in subset
        ]  # fmt: skip
        if min(gains) >= RESOLVED_CHI2 * inflate:
            out.append(subset)
    return out


def fit_terms(curve: AllanCurve, length_s: float | None = None, weights: Weights | None = None) -> NoiseFit:
    """The noise terms of one curve: every subset fitted under the full model's weights (:func:`weigh`'s,
    computed here when not given), the admissible one of least χ² reported (see the module's text).

    Parameters
    ----------
    curve : the measured curve
    length_s : the recording's longest segment, s, for what an unresolved term would need (default: the
        longest cluster time times :data:`~sins.characterise.allan.MIN_CLUSTERS`)
    weights : the full model's weights for this curve

    Returns
    -------
    NoiseFit
        the noise terms (the ramp's, unresolved and unbounded here, is
        :mod:`sins.characterise.trend`'s to judge).
    """
    if weights is None:
        weights = weigh(curve)
    weighted = curve.with_edf(weights.edf)
    points = LogPoints.of(weighted, weights.use, weights.corr, weights.tolerance)
    inflate = weights.inflate
    fits = fit_all(points)
    chosen = min(admissible(fits, inflate), key=lambda s: fits[s].chi2, default=frozenset())
    fit = fits.get(chosen, SubsetFit(math.inf, np.zeros(5), None))
    cov = _resolved_covariance(points, fits, chosen, inflate)
    length = length_s if length_s is not None else float(curve.tau_s[-1]) * MIN_CLUSTERS
    terms = {
        NOISE_TERMS[k]: _term(points, fits, chosen, k, cov, inflate, weights, length)
        for k in range(len(NOISE_TERMS))
    }
    terms["rate_ramp"] = Term("rate_ramp", False, None, None, None, ())
    cov6 = np.zeros((6, 6))
    cov6[:5, :5] = cov
    params = len(chosen) + (1 if fit.tau_c_s is not None else 0)
    dof = max(len(points) - params, 1)
    noise = NoiseFit(
        terms, _six(fit.coefficients), cov6, fit.tau_c_s, _tau_c_range(points, fit, chosen, inflate),
        fit.chi2 if chosen else math.inf, dof, tuple(float(t) for t in curve.tau_s[~weights.use]),
        weights.tolerance, weights.coefficients, weights.tau_c_s,
    )  # fmt: skip
    return noise


def _resolved_covariance(points: LogPoints, fits: dict[frozenset[int], SubsetFit], chosen: frozenset[int],
                         inflate: float) -> Array:  # fmt: skip
    """The chosen terms' covariance (5, 5), each variance the largest of the chosen fit's and of the fits
    with one unresolved term the data lean towards (adding it lowers χ² by :data:`LEANING_CHI2` or
    more): a term that may be there, unresolved, widens the others' σ as it would if it were fitted
    (a rate random walk left bounded beside a Gauss–Markov bias lets the bias's correlation time take its
    rise; the bias's σ then holds its truth)."""
    if not chosen:
        return np.zeros((5, 5))
    cov = covariance(points, fits[chosen], chosen) * inflate
    var = np.diag(cov).copy()
    for j in sorted(ALL - chosen):
        wider = fits.get(chosen | {j})
        if wider is None or fits[chosen].chi2 - wider.chi2 < LEANING_CHI2 * inflate:
            continue
        var = np.maximum(var, np.diag(covariance(points, wider, chosen | {j})) * inflate)
    scale = np.sqrt(var / np.where(np.diag(cov) > 0.0, np.diag(cov), 1.0))
    return np.asarray(cov * np.outer(scale, scale))


def _tau_c_range(points: LogPoints, fit: SubsetFit, chosen: frozenset[int], inflate: float
                 ) -> tuple[float, float] | None:  # fmt: skip
    """Where χ² of the chosen terms, the correlation time held, stays within :data:`TAU_C_CHI2`: on a
    grid of :data:`TAU_C_PER_OCTAVE` a octave over the fit's range, padded by half its step."""
    if fit.tau_c_s is None:
        return None
    cols = sorted(chosen)
    grid = points.grid()
    if len(grid) < 2:
        return fit.tau_c_s, fit.tau_c_s
    fine = np.geomspace(grid[0], grid[-1], max(int(TAU_C_PER_OCTAVE * math.log2(grid[-1] / grid[0])) + 1, 2))
    inside = [
        float(tc) for tc in fine
        if solve(points, points.columns(float(tc))[:, cols], start=fit.coefficients[cols])[1]
        <= fit.chi2 + TAU_C_CHI2 * inflate
    ] or [fit.tau_c_s]  # fmt: skip
    half = float(fine[1] / fine[0]) ** 0.5
    return float(min(min(inside), fit.tau_c_s) / half), float(max(max(inside), fit.tau_c_s) * half)


def _term(points: LogPoints, fits: dict[frozenset[int], SubsetFit], chosen: frozenset[int], k: int,
          cov: Array, inflate: float, weights: Weights, length: float) -> Term:  # fmt: skip
    """Term ``k``: its value and σ where resolved, else its bound and what would resolve it."""
    name = NOISE_TERMS[k]
    fit = fits.get(chosen, SubsetFit(math.inf, np.zeros(5), None))
    tc = fit.tau_c_s if fit.tau_c_s is not None else weights.tau_c_s
    a = basis(points.tau, tc, points.clusters)[:, :5]
    model = a @ fit.coefficients
    if k in chosen:
        value = math.sqrt(fit.coefficients[k])
        share = a[:, k] * fit.coefficients[k] / np.maximum(model, 1e-300)
        support = tuple(float(t) for t in points.tau[share >= 0.5])
        return Term(name, True, value, math.sqrt(max(cov[k, k], 0.0)) / (2.0 * value), None, support)
    extended = chosen | {k}
    wider = fits.get(extended)
    if wider is None or not math.isfinite(wider.chi2):
        return Term(name, False, None, None, None, ())
    upper = math.sqrt(upper_bound(points, wider, extended, k, UPPER_CHI2 * inflate))
    size = np.zeros(6)
    size[k] = upper**2
    dt = float(points.tau[0] / points.clusters[0])
    need_len, need_rate = needs(size, _six(fit.coefficients), wider.tau_c_s or tc, dt, length)
    if need_len is None and need_rate is None and k >= 2:
        # Bounded, not seen: a slow term smaller than its bound shows only at longer cluster times,
        # two octaves beyond these at the least.
        need_len = 4.0 * length
    return Term(name, False, None, None, upper, (), need_len, need_rate)


__all__ = [
    "ALL",
    "EDF_RTOL",
    "LEANING_CHI2",
    "MAX_PASSES",
    "MIN_POINTS",
    "MODEL_HOLDS_P",
    "MODEL_TOLERANCE",
    "RESOLVED_CHI2",
    "SLOW_CHI2",
    "TAU_C_CHI2",
    "TAU_C_PER_OCTAVE",
    "TERMS",
    "UPPER_CHI2",
    "Weights",
    "admissible",
    "fit_all",
    "fit_terms",
    "weigh",
]
