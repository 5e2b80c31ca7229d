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

from dataclasses import dataclass

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
    """Gaussian log-likelihood of innovations with their own variance, up to a constant."""
    return -0.5 * len(nu) * float(np.log(np.mean(nu * nu)))


@dataclass(frozen=True)
class RandomBiasFit:
    """A random bias fitted to a residual: ``b' = φ b + w (q)`` under white noise of variance ``r``.

    ``trials`` are the one-step innovations of every row for the chosen ``φ`` and each drive of the
    fine grid (:data:`FINE_DRIVE`); ``chosen`` indexes the one the fit rows prefer (what
    :func:`falsified` holds against the others); ``fit_loglik`` is its likelihood on the fit rows.
    """

    phi: float
    q: float
    r: float
    trials: tuple[Array, ...] = ()
    chosen: int = 0
    fit_loglik: float = -np.inf

    @property
    def innovations(self) -> Array:
        """The chosen drive's one-step innovations of every row."""
        return self.trials[self.chosen]

    @property
    def gain(self) -> float:
        """The steady-state Kalman gain."""
        return steady_gain(self.phi, self.q, self.r)[0]


def fit(y: Array, rows: NDArray[np.bool_], step_s: float, r: float, walk: bool) -> RandomBiasFit:
    """The (φ, q) maximising the innovations' likelihood on ``rows``, over a grid of τ and q/r.

    ``r`` is the white noise's variance. The grid chooses the bias's correlation (``φ =
    exp(−step/τ)`` over :data:`TAUS_S`; 1 for a random walk) and drive ``q`` (:data:`DRIVE_RATIOS`
    of ``r``), and the drive is then refined by :data:`FINE_DRIVE` about the best.

    The filter runs over every row in time order (so rows left out are predicted from what came
    before them, as a filter in the field would), but only ``rows``' innovations choose.
    """

    def trial(phi: float, ratio: float) -> Array:
        return innovations(y, phi, steady_gain(phi, ratio * r, r)[0])

    phis = [1.0] if walk else list(np.exp(-step_s / TAUS_S))
    _, phi, ratio = max(
        (log_likelihood(trial(phi, ratio)[rows]), phi, ratio) for phi in phis for ratio in DRIVE_RATIOS
    )
    # The drive's likelihood is sharp on long records: between two coarse steps it can drop by more
    # than a per-quarter drive gains by chance, which would falsify real processes (falsified).
    ratios = ratio * FINE_DRIVE
    trials = tuple(trial(phi, q) for q in ratios)
    lls = [log_likelihood(nu[rows]) for nu in trials]
    j = int(np.argmax(lls))
    return RandomBiasFit(phi, float(ratios[j]) * r, r, trials, j, lls[j])


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
    phi, trials, common = process.phi, process.trials, process.innovations
    nu = common[rows]
    w = int(np.clip(round(1.0 / (1.0 - phi * (1.0 - process.gain))), 1, len(nu) // 4))
    c = np.concatenate([[0.0], np.cumsum(nu)])
    z = np.abs(c[w:] - c[:-w]) / (np.std(nu) * np.sqrt(w))
    if float(z.max()) > float(norm.isf(0.0005 / len(z))):
        return True
    edges = np.quantile(t[rows], [0.25, 0.5, 0.75])
    quarter = np.searchsorted(edges, t, side="right")
    gain = 0.0
    for k in range(4):
        part = rows & (quarter == k)
        gain += max(log_likelihood(nu[part]) for nu in trials) - log_likelihood(common[part])
    return 2.0 * gain > 16.3  # χ² with 3 degrees of freedom at p = 0.001


__all__ = [
    "DRIVE_RATIOS",
    "FINE_DRIVE",
    "TAUS_S",
    "RandomBiasFit",
    "falsified",
    "fit",
    "innovations",
    "log_likelihood",
    "steady_gain",
]
