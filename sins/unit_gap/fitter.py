"""Least squares on a sensor's interval residuals, with the noise that shared epochs give them.

Two neighbouring intervals share a reference epoch: its noise enters the first's residual with one sign
and the second's with the other, so where the reference is noisier than the sensor the residuals are
anti-correlated from one interval to the next (a first-order moving average, lag-one correlation down
to −0.5); an error that wanders slowly (a bias that drifts in flight, a reference whose error follows
the pose) correlates them positively. A least-squares fit and a Gaussian likelihood that took them for
independent would misjudge every effect (one slow beside the intervals is seen far better than
independence says: the reference's noise cancels along a chain). :class:`SensorFit` estimates each
component's noise as an ARMA(1, 1) process from a model's residual on the fit intervals (the wander
``φ`` only where the model holds a random bias, :data:`NO_WANDER` otherwise), whitens the residuals and
any columns by its inverse filter along each chain of joined intervals (generalised least squares),
weighs each component by its innovations' spread, and scores a model by the Gaussian likelihood of its
withheld innovations, each component with its own variance, as the per-sample diagnosis does
(:func:`sins.gap.scoring.trial_gain`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from sins.gap.floor import TINY

Array = NDArray[np.float64]
Rows = NDArray[np.bool_]

#: The grid of the noise's autoregressive coefficient φ (a slow wander: a bias that drifts, a reference
#: whose error follows the pose) and moving-average coefficient θ (the epochs' noise shared by
#: neighbouring intervals), each component's pair chosen by the fit intervals' one-step prediction error.
#: The noise alone has no wander (φ = 0); a random bias adds it: a Gauss-Markov bias of correlation
#: time ``−L / ln φ`` (intervals of ``L``), or, near φ = 1, a random walk.
NO_WANDER = np.array([0.0])
INSTABILITY = np.array([0.2, 0.4, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95])
RANDOM_WALK = np.array([0.995])
#: The moving average is the epochs' noise, which neighbouring intervals share with opposite signs:
#: θ ≤ 0. A residual correlated positively from one interval to the next holds something slow (an
#: unmodelled effect, a step, a wander), which a noise model that took it would whiten away (a bias step
#: on EuRoC's V1_02 kept 9.5 of the 91 nats it is worth).
_THETA = np.linspace(-0.9, 0.0, 10)
#: Columns whose scaled singular value falls below this fraction of the largest are cut (a real
#: recording that turns in too few directions to determine every coefficient).
_RCOND = 1e-9


def chains(joined: Rows) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of intervals joined end to start."""
    starts = np.flatnonzero(~joined)
    if len(starts) == 0 or starts[0] != 0:
        starts = np.concatenate([[0], starts])
    stops = np.concatenate([starts[1:], [len(joined)]])
    return list(zip(starts.tolist(), stops.tolist(), strict=True))


def innovations(z: Array, phi: float, theta: float, joined: Rows) -> Array:
    """The one-step prediction errors of ``z`` (k, ...) under ``(1 − φB) z = (1 + θB) a`` along each
    chain of joined intervals, each chain's first divided by its stationary spread in units of ``a``."""
    out = np.empty_like(z, dtype=float)
    first = np.sqrt((1.0 + 2.0 * phi * theta + theta * theta) / (1.0 - phi * phi))
    for a, b in chains(joined):
        part = lfilter([1.0, -phi], [1.0, theta], z[a:b], axis=0)
        part[0] = z[a] / first
        out[a:b] = part
    return out


def arma11(residual: Array, rows: Rows, joined: Rows, phis: Array = NO_WANDER) -> tuple[float, float]:
    """The ``(φ, θ)``, φ among ``phis``, whose innovations of ``residual`` (k,) have the least mean square
    over ``rows`` (conditional least squares: the Gaussian likelihood's maximum, the first rows aside)."""
    if rows.sum() < 10:
        return 0.0, 0.0
    best, pair = np.inf, (0.0, 0.0)
    for phi in phis:
        for theta in _THETA:
            e = innovations(residual, float(phi), float(theta), joined)[rows]
            first = np.sqrt((1.0 + 2.0 * phi * theta + theta * theta) / (1.0 - phi * phi))
            # Each chain's first row is scaled to the innovations' units: its log-determinant counted.
            ms = float(np.mean(e * e)) * np.exp(2.0 * np.log(first) * np.sum(~joined & rows) / rows.sum())
            if ms < best:
                best, pair = ms, (float(phi), float(theta))
    return pair


@dataclass(frozen=True, eq=False)
class SensorFit:
    """A sensor's interval residuals ``y`` (k, 3) with their fit and withheld intervals, and per
    component the noise's coefficients ``phi`` and ``theta`` (3,) and its innovations' spread
    ``sigma`` (3,)."""

    y: Array
    fit: Rows
    withheld: Rows
    joined: Rows
    phi: Array
    theta: Array
    sigma: Array

    @classmethod
    def of(
        cls, y: Array, fit: Rows, withheld: Rows, joined: Rows, columns: Array, phis: Array = NO_WANDER
    ) -> SensorFit:
        """The noise (φ among ``phis``) estimated from the residual the ``columns`` (k, 3, p) leave on
        the fit intervals (least squares, then again with the noise so found: generalised least
        squares)."""
        plain = cls(y, fit, withheld, joined, np.zeros(3), np.zeros(3), np.ones(3))
        left = plain.solve(columns)[1]
        for _ in range(2):
            pairs = [arma11(left[:, c], fit, joined, phis) for c in range(3)]
            phi, theta = np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs])
            white = cls(y, fit, withheld, joined, phi, theta, np.ones(3))
            left = white.solve(columns)[1]
        sigma = np.sqrt(np.mean(white.whiten(left)[fit] ** 2, axis=0)) + TINY
        return cls(y, fit, withheld, joined, phi, theta, sigma)

    def whiten(self, z: Array) -> Array:
        """``z`` (k, 3, ...): each component's innovations (:func:`innovations`), divided by ``sigma``."""
        out = np.empty_like(z, dtype=float)
        for c in range(3):
            out[:, c] = innovations(z[:, c], float(self.phi[c]), float(self.theta[c]), self.joined)
        shape = (1, 3) + (1,) * (z.ndim - 2)
        return out / self.sigma.reshape(shape)

    def solve(self, columns: Array) -> tuple[Array, Array]:
        """Least squares of the whitened residual on the whitened ``columns`` (k, 3, p) over the fit
        intervals: the coefficients (p,) and the residual ``y − X c`` (k, 3), unwhitened."""
        if columns.shape[2] == 0:
            return np.zeros(0), self.y.copy()
        xw, yw = self.whiten(columns), self.whiten(self.y)
        a = xw[self.fit].reshape(-1, columns.shape[2])
        scale = np.abs(a).max(axis=0)
        scale = np.where(scale > 0.0, scale, 1.0)
        coef = np.linalg.lstsq(a / scale, yw[self.fit].reshape(-1), rcond=_RCOND)[0] / scale
        return coef, self.y - np.einsum("kap,p->ka", columns, coef)

    def raw_innovations(self, left: Array) -> Array:
        """The innovations (k, 3) of a residual ``left`` (k, 3) under this noise, in its own units."""
        return self.whiten(left) * self.sigma

    def fit_loglik(self, left: Array) -> Array:
        """Per component (3,), the Gaussian log-likelihood of the fit intervals' innovations of a
        residual ``left`` (k, 3) under this noise, each with its own variance."""
        e = self.raw_innovations(left)[self.fit]
        m = len(e)
        return np.asarray(-0.5 * m * (np.log(2.0 * np.pi * (np.mean(e**2, axis=0) + TINY**2)) + 1.0))

    def bic_penalty(self, parameters: int) -> float:
        """BIC's penalty for ``parameters`` more on the fit intervals: half their number times the log of
        the intervals' count (two at least)."""
        return 0.5 * parameters * float(np.log(max(int(self.fit.sum()), 2)))

    def gains(self, before: Array, after: Array) -> Array:
        """Per component (3,), the withheld Gaussian log-likelihood gain of the model leaving
        ``after`` over the one leaving ``before`` (both unwhitened, (k, 3)), each with its own variance."""
        w0, w1 = self.whiten(before)[self.withheld], self.whiten(after)[self.withheld]
        s0 = np.mean(w0**2, axis=0) + TINY**2
        s1 = np.mean(w1**2, axis=0) + TINY**2
        return np.asarray(0.5 * len(w0) * np.log(s0 / s1))


def refit_allowance(sf: SensorFit, columns: Array, threshold: float) -> float:
    """What a random bias may gain on the withheld intervals where the current model holds, beyond
    ``threshold``: as on samples (:func:`sins.gap.scoring.refit_allowance`), its noise's wander follows
    the withheld residuals and so makes up for the errors of coefficients fitted on the others, whose
    withheld cost is ``½ Σ λ_j χ²₁``, ``λ`` the eigenvalues of ``(A_fᵀA_f)⁻¹ A_wᵀA_w`` of the whitened
    columns ``A``. Its quantile at probability ``e^-threshold`` by Satterthwaite's scaled χ² (the same
    mean and variance): a real recording's columns are excited unevenly (a force met mostly in the
    withheld blocks), and ``λ_max`` times every degree, the bound on samples, charged the gyro of a
    EuRoC flight 68-188 nats where the scaled χ² charges 10-30."""
    from scipy.stats import chi2

    if columns.shape[2] == 0:
        return 0.0
    w = sf.whiten(columns)
    a_f, a_w = w[sf.fit].reshape(-1, columns.shape[2]), w[sf.withheld].reshape(-1, columns.shape[2])
    _, sv, vt = np.linalg.svd(a_f, full_matrices=False)
    keep = sv > 1e-9 * sv[0]
    basis = vt[keep].T / sv[keep]
    lam = np.clip(np.linalg.eigvalsh(basis.T @ (a_w.T @ a_w) @ basis), 0.0, None)
    if lam.sum() <= 0.0:
        return 0.0
    scale, degrees = float(np.sum(lam**2) / np.sum(lam)), float(np.sum(lam) ** 2 / np.sum(lam**2))
    return float(0.5 * scale * chi2.isf(np.exp(-threshold), degrees))


def cross_gains(a: SensorFit, left_a: Array, b: SensorFit, left_b: Array) -> Array:
    """Per component (3,), the withheld Gaussian log-likelihood gain of model ``b`` (its noise, its
    residual ``left_b``) over model ``a``: each one's innovations with their own variance."""
    ea, eb = a.raw_innovations(left_a)[a.withheld], b.raw_innovations(left_b)[b.withheld]
    s0 = np.mean(ea**2, axis=0) + TINY**2
    s1 = np.mean(eb**2, axis=0) + TINY**2
    return np.asarray(0.5 * len(ea) * np.log(s0 / s1))


__all__ = [
    "INSTABILITY",
    "NO_WANDER",
    "RANDOM_WALK",
    "SensorFit",
    "arma11",
    "chains",
    "cross_gains",
    "innovations",
    "refit_allowance",
]
