"""A random bias under white noise, fitted and followed by the steady-state Kalman filter.

The model of a residual series ``y`` sampled every ``step_s``::

    b' = φ b + w,   w ~ N(0, q)      (φ = exp(−step/τ): a first-order Gauss–Markov bias;
    y  = b + v,     v ~ N(0, r)       φ = 1: a random walk)

Its steady-state filter is linear and time-invariant, so it runs as one ``lfilter`` pass over every
row: the innovations ``ν = y − ŷ`` are the one-step-ahead prediction errors, and their Gaussian
likelihood is the model's. :func:`fit` chooses ``(φ, q)`` by that likelihood on the fit rows over a
grid, ``r`` given; :func:`falsified` asks whether what was fitted is the process it claims to be.
The sim-to-real diagnosis (:mod:`sins.gap`) uses both for its bias instability and rate random walk
candidates.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter
from scipy.stats import norm

Array = NDArray[np.float64]

#: Gauss–Markov correlation times tried, s.
TAUS_S = np.geomspace(2.0, 5000.0, 12)
#: Drives ``q / r`` tried.
DRIVE_RATIOS = np.geomspace(1e-9, 1e-1, 17)
#: Factors about the coarse grid's best drive, spanning its step either side.
FINE_DRIVE = np.geomspace(10**-0.5, 10**0.5, 9)


def steady_gain(phi: float, q: float, r: float) -> tuple[float, float]:
    """Steady-state Kalman gain and innovation variance of ``b' = φ b + w (q)``, ``y = b + v (r)``."""
    # Riccati: P = φ² P r / (P + r) + q  (P the predicted variance).
    a, b, c = 1.0, r * (1.0 - phi * phi) - q, -q * r
    p = (-b + np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
    return p / (p + r), p + r


def innovations(y: Array, phi: float, gain: float) -> Array:
    """One-step-ahead innovations of the steady-state filter: ``x̂' = φ(1−K) x̂ + φ K y``.

    The filter starts from the mean of the first 100 samples, not from 0: a start from 0 would
    be a jump the process did not make.
    """
    # Transposed direct form: the state is the next prediction, so zi is the first one.
    pred, _ = lfilter([0.0, phi * gain], [1.0, -phi * (1.0 - gain)], y, zi=[float(np.mean(y[:100]))])
    return np.asarray(y - pred)


def log_likelihood(nu: Array) -> float:
    """Gaussian log-likelihood of innovations with their own variance, up to a constant (+inf for
    innovations of zero)."""
    return float(_loglik(np.asarray(np.sum(nu * nu)), len(nu)))


#: Rows a running sum of squares takes before it is added to its total (keeps the sums' rounding at
#: that of a blockwise sum, not of one long running sum).
_BLOCK = 4096


@numba.njit(cache=True, nogil=True)
def _sums_of_squares(
    y: Array,
    rows: NDArray[np.bool_],
    start: float,
    b1: Array,
    a1: Array,
    group: NDArray[np.int64],
    groups: int,
) -> Array:  # pragma: no cover - compiled
    """For each filter ``g``, ``ŷ' = b1[g] y − a1[g] ŷ`` from ``ŷ = start`` (scipy's ``lfilter`` with
    ``b = [0, b1]``, ``a = [1, a1]``, the same arithmetic), the sum of squared innovations ``y − ŷ``
    over ``rows``, per ``group`` of those rows: (filters, groups). Every filter in one pass."""
    n_filters = len(b1)
    predicted = np.full(n_filters, start)
    total = np.zeros((n_filters, groups))
    block = np.zeros((n_filters, groups))
    for k in range(len(y)):
        yk = y[k]
        if rows[k]:
            j = group[k]
            for g in range(n_filters):
                nu = yk - predicted[g]
                block[g, j] += nu * nu
                predicted[g] = b1[g] * yk - a1[g] * predicted[g]
        else:
            for g in range(n_filters):
                predicted[g] = b1[g] * yk - a1[g] * predicted[g]
        if (k + 1) % _BLOCK == 0:
            total += block
            block[:] = 0.0
    return total + block


def _grid_sums(
    y: Array,
    rows: NDArray[np.bool_],
    filters: list[tuple[float, float]],
    group: NDArray[np.int64] | None = None,
) -> Array:
    """:func:`_sums_of_squares` of the steady-state filters ``(φ, K)`` from the mean of the first 100
    rows (:func:`innovations`' start): (filters, groups), one group without ``group``."""
    phi, gain = (np.array(v, dtype=np.float64) for v in zip(*filters, strict=True))
    groups = 1 if group is None else int(group.max(initial=0)) + 1
    group = np.zeros(len(y), dtype=np.int64) if group is None else group
    y = np.ascontiguousarray(y, dtype=np.float64)
    return _sums_of_squares(
        y, np.ascontiguousarray(rows), float(np.mean(y[:100])), phi * gain, -phi * (1.0 - gain), group, groups
    )


def _loglik(sum_of_squares: Array, count: int | Array) -> Array:
    """:func:`log_likelihood` of innovations from their sum of squares and number (+inf for a sum of
    zero: a filter that leaves nothing fits perfectly)."""
    with np.errstate(divide="ignore"):
        return -0.5 * count * np.log(sum_of_squares / count)


@dataclass(frozen=True, eq=False)
class RandomBiasFit:
    """A random bias fitted to a residual ``y``: ``b' = φ b + w (q)`` under white noise of variance ``r``.

    ``ratios`` are the drives ``q / r`` of the fine grid (:data:`FINE_DRIVE`) for the chosen ``φ``;
    ``chosen`` indexes the one the fit rows prefer (what :func:`falsified` holds against the others);
    ``innovations`` are its one-step innovations of every row, ``fit_loglik`` their likelihood on
    the fit rows.
    """

    phi: float
    q: float
    r: float
    y: Array = field(default_factory=lambda: np.zeros(0))
    ratios: Array = field(default_factory=lambda: np.zeros(0))
    chosen: int = 0
    innovations: Array = field(default_factory=lambda: np.zeros(0))
    fit_loglik: float = -np.inf

    @property
    def gain(self) -> float:
        """The steady-state Kalman gain."""
        return steady_gain(self.phi, self.q, self.r)[0]

    def filters(self) -> list[tuple[float, float]]:
        """``(φ, K)`` of each drive of the fine grid."""
        return [(self.phi, steady_gain(self.phi, ratio * self.r, self.r)[0]) for ratio in self.ratios]


def sizes(phi: float, q: float, step_s: float) -> tuple[float, ...]:
    """A random bias's size in the library's terms from its discrete model ``b' = φ b + w`` (``w`` of
    variance ``q``) at steps of ``step_s``: a Gauss–Markov bias's stationary σ = √(q / (1 − φ²)) and
    correlation time τ = −step / ln φ (:class:`sins.imu.BiasInstability`'s ``sigma``, ``tau``); a walk's
    (φ = 1) density √(q / step) (:class:`sins.imu.RateRandomWalk`'s ``density``)."""
    if phi >= 1.0:
        return (float(np.sqrt(q / step_s)),)
    return float(np.sqrt(q / (1.0 - phi * phi))), float(-step_s / np.log(phi))


def fit(y: Array, rows: NDArray[np.bool_], step_s: float, r: float, walk: bool) -> RandomBiasFit:
    """The (φ, q) maximising the innovations' likelihood on ``rows``, over a grid of τ and q/r.

    ``r`` is the white noise's variance. The grid chooses the bias's correlation (``φ =
    exp(−step/τ)`` over :data:`TAUS_S`; 1 for a random walk) and drive ``q`` (:data:`DRIVE_RATIOS`
    of ``r``), and the drive is then refined by :data:`FINE_DRIVE` about the best.

    The filter runs over every row in time order (so rows left out are predicted from what came
    before them, as a filter in the field would), but only ``rows``' innovations choose. Every
    filter of a grid runs in one compiled pass over the rows (:func:`_sums_of_squares`), keeping
    sums of squares, not innovations.
    """
    count = int(np.sum(rows))
    phis = [1.0] if walk else list(np.exp(-step_s / TAUS_S))
    grid = [(phi, ratio) for phi in phis for ratio in DRIVE_RATIOS]
    lls = _loglik(_grid_sums(y, rows, [(phi, steady_gain(phi, q * r, r)[0]) for phi, q in grid])[:, 0], count)
    _, phi, ratio = max((float(ll), phi, ratio) for ll, (phi, ratio) in zip(lls, grid, strict=True))
    # The drive's likelihood is sharp on long records: between two coarse steps it can drop by more
    # than a per-quarter drive gains by chance, which would falsify real processes (falsified).
    ratios = ratio * FINE_DRIVE
    found = RandomBiasFit(phi, float(ratio) * r, r, y, ratios)
    j = int(np.argmax(_loglik(_grid_sums(y, rows, found.filters())[:, 0], count)))
    nu = innovations(y, phi, found.filters()[j][1])
    return dataclasses.replace(
        found, q=float(ratios[j]) * r, chosen=j, innovations=nu, fit_loglik=log_likelihood(nu[rows])
    )


def falsified(process: RandomBiasFit, rows: NDArray[np.bool_], t: Array) -> bool:
    """Whether a random bias fitted to a residual is not the process it claims to be.

    A random bias tracks a single jump or any other one-off misfit nearly as well as a real
    instability; only a real one drives the bias alike all along and leaves white innovations
    behind. Two tests on the fit ``rows``, each at p = 0.001:

    - *homogeneity*: with each quarter's own drive ``q`` (``φ`` and ``r`` kept), twice the
      log-likelihood gain over the common ``q`` is χ² with 3 degrees of freedom for a real process;
    - *no burst*: summed over the filter's own settling time ``w``, the innovations of a real process
      are ``N(0, w σ²)`` in every window. After a jump, the filter trails the new level for about
      ``w`` rows, and their sum shows it. The largest standardised window sum is held against the
      Bonferroni bound over every window.
    """
    if process.q <= 0.0:
        return True
    phi, common = process.phi, process.innovations
    nu = common[rows]
    if not np.std(nu) > 0.0:  # nothing left for a process to drive: none is there
        return True
    w = int(np.clip(round(1.0 / (1.0 - phi * (1.0 - process.gain))), 1, len(nu) // 4))
    c = np.concatenate([[0.0], np.cumsum(nu)])
    spread = np.std(nu) * np.sqrt(w)
    del nu
    z = np.subtract(c[w:], c[:-w])  # the window sums, standardised in place (a long record's rows)
    del c
    np.abs(z, out=z)
    z /= spread
    if float(z.max()) > float(norm.isf(0.0005 / len(z))):
        return True
    del z
    edges = np.quantile(t[rows], [0.25, 0.5, 0.75])
    quarter = np.searchsorted(edges, t, side="right").astype(np.int64, copy=False)
    sums = _grid_sums(process.y, rows, process.filters(), quarter)  # (drives, quarters)
    counts = np.bincount(quarter[rows], minlength=4)[:4].astype(np.float64)
    lls = _loglik(sums[:, :4], counts)
    return 2.0 * float(np.sum(lls.max(axis=0) - lls[process.chosen])) > 16.3  # χ² with 3 degrees, p = 0.001


__all__ = [
    "DRIVE_RATIOS",
    "FINE_DRIVE",
    "TAUS_S",
    "RandomBiasFit",
    "falsified",
    "fit",
    "innovations",
    "log_likelihood",
    "sizes",
    "steady_gain",
]
