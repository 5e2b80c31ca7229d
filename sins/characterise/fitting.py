"""Least squares of the noise terms on the logarithm of an Allan curve.

An overlapping Allan variance estimate ``σ̂²`` at a point of ``ν`` equivalent degrees of freedom is
read as ``σ² χ²(ν)/ν``. Its logarithm has mean ``log σ² + ψ(ν/2) − log(ν/2)`` and variance ``ψ'(ν/2)``
(``ψ`` the digamma function): a variance that does not depend on the level ``σ²`` at all (the log is
the variance-stabilising transform of a scaled χ²), and a distribution far closer to Gaussian than
``σ̂²`` itself at the few degrees of freedom of the longest cluster times. So the terms are fitted by
least squares of

    z = log σ̂² − ψ(ν/2) + log(ν/2)  against  log(A c),    c ≥ 0,

whitened by the points' covariance ``D C D`` (``D = diag √ψ'(ν/2)``, ``C`` their correlation, which the
logarithm keeps to first order), plus an allowed model error ``ε`` per point (independent). The weights
depend on the noise *type* at each point (through ``ν`` and ``C``), never on the fitted level, so no
model that lacks a term can give the points where that term lives a too small variance.

``A`` holds the terms' columns (:func:`sins.characterise.noise_terms.basis`), ``c`` their squared
coefficients. The minimum over ``c ≥ 0`` is found by Gauss–Newton steps, each a non-negative least
squares of the linearised problem (``log(Ac) ≈ log μ₀ + A(c − c₀)/μ₀``), halved until χ² falls; the
Gauss–Markov correlation time ``T`` is profiled over a grid and refined by a bounded scalar search.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray
from scipy import optimize, special
from scipy.linalg import solve_triangular
from scipy.optimize import nnls

from sins.characterise.allan import AllanCurve
from sins.characterise.noise_terms import GM, GM_PEAK_X, basis

Array = NDArray[np.float64]

#: Correlation times tried per octave before the refinement.
GRID_PER_OCTAVE = 3
#: The Gauss–Markov peak (``τ = 1.89 T``) must lie at least this many shortest cluster times in, and
#: at most the longest cluster time over this: a bump whose fall is not seen is a rate random walk.
PEAK_FROM_SHORTEST = 4.0
PEAK_TO_LONGEST = 4.0
#: Gauss–Newton stops when χ² falls by less than this fraction.
_CONVERGED = 1e-10
_MAX_STEPS = 60


@dataclass(frozen=True)
class LogPoints:
    """The points of a curve a fit uses, on the log scale, whitened.

    Attributes
    ----------
    tau : (k,) cluster times, s
    clusters : (k,) cluster sizes
    z : (k,) ``log σ̂² − ψ(ν/2) + log(ν/2)``
    white : (k, k) the inverse Cholesky factor of the covariance of ``z``
    """

    tau: Array
    clusters: NDArray[np.int64]
    z: Array
    white: Array

    #: The noise columns the fit chooses among (the ramp's is not one).
    COLUMNS: ClassVar[int] = 5

    @classmethod
    def of(cls, curve: AllanCurve, use: NDArray[np.bool_], corr: Array | None, tolerance: float) -> LogPoints:
        """The points ``use`` of ``curve`` (its EDF ``ν``), correlated by ``corr`` (None: independent),
        each allowed a model error of ``tolerance`` (a fraction of its Allan variance)."""
        keep = use & (curve.avar > 0.0)
        nu = curve.edf[keep]
        z = np.log(curve.avar[keep]) - special.digamma(nu / 2.0) + np.log(nu / 2.0)
        sd = np.sqrt(special.polygamma(1, nu / 2.0))
        c = np.eye(len(nu)) if corr is None else corr[np.ix_(keep, keep)]
        v = c * np.outer(sd, sd) + np.diag(1e-9 * sd * sd + math.log1p(tolerance) ** 2)
        white = solve_triangular(np.linalg.cholesky(v), np.eye(len(nu)), lower=True)
        return cls(curve.tau_s[keep], curve.clusters[keep], z, white)

    def __len__(self) -> int:
        return len(self.z)

    def columns(self, tau_c_s: float | None) -> Array:
        """The noise columns (k, 5) at these points."""
        return basis(self.tau, tau_c_s, self.clusters)[:, : self.COLUMNS]

    def chi2(self, a: Array, c: Array) -> float:
        """χ² of the model ``a @ c`` (inf where it is not positive)."""
        mu = a @ c
        if not np.all(mu > 0.0):
            return math.inf
        r = self.white @ (self.z - np.log(mu))
        return float(r @ r)

    def grid(self) -> list[float]:
        """The correlation times tried (see :data:`PEAK_FROM_SHORTEST`); empty when none fits inside."""
        lo, hi = PEAK_FROM_SHORTEST * self.tau[0], self.tau[-1] / PEAK_TO_LONGEST
        if len(self) < 3 or hi <= lo:
            return []
        count = max(int(GRID_PER_OCTAVE * math.log2(hi / lo)) + 1, 2)
        return [float(t) for t in np.geomspace(lo, hi, count) / GM_PEAK_X]


def _nnls(a: Array, b: Array) -> Array:
    """Non-negative least squares ``a x ≈ b`` on unit-norm columns (the columns span decades)."""
    scale = np.linalg.norm(a, axis=0)
    scale[scale == 0.0] = 1.0
    x, _ = nnls(a / scale, b, maxiter=50 * a.shape[1] + 50)
    return np.asarray(x / scale)


def solve(points: LogPoints, a: Array, offset: Array | None = None, start: Array | None = None
          ) -> tuple[Array, float]:  # fmt: skip
    """The least-squares ``c ≥ 0`` of ``z ≈ log(offset + a c)`` and its χ².

    ``offset`` (k,) is a fixed part of the model (a term held at a value), None for none; ``start`` a
    first guess (default: the linear fit of the relative residuals ``1 − (offset + a c)/σ̂²``).
    """
    w, z = points.white, points.z
    base = np.zeros(len(points)) if offset is None else offset

    def chi2_of(mu: Array) -> float:
        if not np.all(mu > 0.0):
            return math.inf
        r = w @ (z - np.log(mu))
        return float(r @ r)

    starts = [] if start is None else [np.maximum(np.asarray(start, dtype=float), 0.0)]
    if start is None:
        # Relative residuals, whitened and plain: the whitened start alone fell, on the ring-laser gyro's
        # curve (a bump at its short cluster times), into a basin without its quantization.
        y = np.exp(z)
        starts += [_nnls(m @ (a / y[:, None]), m @ (1.0 - base / y)) for m in (w, np.eye(len(z)))]
    best: tuple[float, Array] | None = None
    for c in starts:
        if not np.all(base + a @ c > 0.0):
            c = c + np.max(np.exp(z) / np.maximum(a.sum(axis=1), 1e-300)) * 1e-6
        found = _descend(chi2_of, w, z, a, base, c)
        if best is None or found[0] < best[0]:
            best = found
    assert best is not None
    return best[1], best[0]


def _descend(chi2_of: Callable[[Array], float], w: Array, z: Array, a: Array, base: Array, c: Array
             ) -> tuple[float, Array]:  # fmt: skip
    """Gauss–Newton steps from ``c``, each a non-negative least squares of the linearised problem, halved
    until χ² falls: ``(χ², c)`` where it stops."""
    mu = base + a @ c
    chi2 = chi2_of(mu)
    for _ in range(_MAX_STEPS):
        j = a / mu[:, None]
        proposal = _nnls(w @ j, w @ (z - np.log(mu) + j @ c))
        step = 1.0
        while True:
            new = c + step * (proposal - c)
            new_mu = base + a @ new
            new_chi2 = chi2_of(new_mu)
            if new_chi2 <= chi2 or step < 1e-4:
                break
            step *= 0.5
        if new_chi2 > chi2:
            break
        done = chi2 - new_chi2 <= _CONVERGED * max(chi2, 1.0)
        c, chi2, mu = new, new_chi2, new_mu
        if done:
            break
    return chi2, c


@dataclass(frozen=True)
class SubsetFit:
    """The fit of one set of noise terms: χ², the squared coefficients (5,) and the correlation time."""

    chi2: float
    coefficients: Array
    tau_c_s: float | None


def fit_subset(points: LogPoints, subset: frozenset[int], start: SubsetFit | None = None) -> SubsetFit:
    """Fit the noise columns ``subset`` (indices of :data:`~sins.characterise.noise_terms.NOISE_TERMS`); with
    the Gauss–Markov column, its correlation time profiled over :meth:`LogPoints.grid` and refined."""
    cols = sorted(subset)
    if GM not in subset:
        c, chi2 = solve(points, points.columns(None)[:, cols])
        return SubsetFit(chi2, _spread(c, cols), None)
    grid = points.grid()
    if not grid:
        return SubsetFit(math.inf, np.zeros(LogPoints.COLUMNS), None)
    best: tuple[float, Array, float] | None = None
    guess = None if start is None else start.coefficients[cols]
    for tc in grid:
        c, chi2 = solve(points, points.columns(tc)[:, cols], start=guess)
        guess = c
        if best is None or chi2 < best[0]:
            best = (chi2, c, tc)
    assert best is not None
    step = grid[1] / grid[0] if len(grid) > 1 else 2.0
    lo, hi = math.log(max(best[2] / step, grid[0])), math.log(min(best[2] * step, grid[-1]))
    if hi > lo:
        seed = best[1]
        found = optimize.minimize_scalar(
            lambda lt: solve(points, points.columns(math.exp(lt))[:, cols], start=seed)[1],
            bounds=(lo, hi), method="bounded", options={"xatol": 1e-2},
        )  # fmt: skip
        tc = math.exp(float(found.x))
        c, chi2 = solve(points, points.columns(tc)[:, cols], start=seed)
        if chi2 < best[0]:
            best = (chi2, c, tc)
    return SubsetFit(best[0], _spread(best[1], cols), best[2])


def _spread(c: Array, cols: list[int]) -> Array:
    out = np.zeros(LogPoints.COLUMNS)
    out[cols] = c
    return out


def covariance(points: LogPoints, fit: SubsetFit, subset: frozenset[int]) -> Array:
    """The covariance (5, 5) of the squared coefficients of ``subset`` at the fit (the correlation time,
    where there is one, fitted beside them and its uncertainty carried into theirs)."""
    cols = sorted(subset)
    a = points.columns(fit.tau_c_s)
    mu = a @ fit.coefficients
    j = a[:, cols] / mu[:, None]
    if fit.tau_c_s is not None:
        h = 1e-4  # d/d(log T) by central differences
        up = points.columns(fit.tau_c_s * math.exp(h))[:, GM]
        down = points.columns(fit.tau_c_s * math.exp(-h))[:, GM]
        j = np.column_stack([j, fit.coefficients[GM] * (up - down) / (2.0 * h) / mu])
    wj = points.white @ j
    inv = np.linalg.pinv(wj.T @ wj)[: len(cols), : len(cols)]
    out = np.zeros((LogPoints.COLUMNS, LogPoints.COLUMNS))
    out[np.ix_(cols, cols)] = inv
    return out


def upper_bound(points: LogPoints, fit: SubsetFit, subset: frozenset[int], k: int, rise: float) -> float:
    """The largest squared coefficient of term ``k`` the data allow beside the rest of ``subset``: where
    χ², the others refitted with term ``k`` held, exceeds its least (``fit``) by ``rise`` (a profile
    likelihood bound, to 3 % of it). A Gauss–Markov correlation time is refitted too, within half an
    octave of the fit's (a bias that may shorten leaves room for a rate random walk at its longest
    cluster times)."""
    others = sorted(subset - {k})
    times: list[float | None] = [fit.tau_c_s]
    if fit.tau_c_s is not None and GM in others:
        grid = points.grid()
        times = [t for t in fit.tau_c_s * 2.0 ** np.array([-0.5, 0.0, 0.5]) if grid[0] <= t <= grid[-1]]
        times = times or [fit.tau_c_s]
    columns = [points.columns(t) for t in times]
    least = fit.chi2 + rise

    def chi2_at(value: float) -> float:
        if not others:
            return points.chi2(columns[0][:, [k]], np.array([value]))
        return min(solve(points, a[:, others], offset=a[:, k] * value)[1] for a in columns)

    a = columns[0]
    level = float(np.min(np.exp(points.z) / np.maximum(a[:, k], 1e-300)))  # the term alone at a point
    lo = max(float(fit.coefficients[k]), 0.0)
    hi = max(2.0 * lo, 1e-3 * level)
    while chi2_at(hi) < least and hi < 1e6 * level:
        lo, hi = hi, 4.0 * hi
    for _ in range(60):
        if hi <= 1.03 * lo:
            break
        mid = math.sqrt(lo * hi) if lo > 0.0 else 0.5 * hi
        if chi2_at(mid) < least:
            lo = mid
        else:
            hi = mid
    return hi


__all__ = [
    "GRID_PER_OCTAVE",
    "PEAK_FROM_SHORTEST",
    "PEAK_TO_LONGEST",
    "LogPoints",
    "SubsetFit",
    "covariance",
    "fit_subset",
    "solve",
    "upper_bound",
]
