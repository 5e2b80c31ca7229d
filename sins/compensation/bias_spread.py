"""How far a new recording's gyro and accelerometer biases may fall from what a unit's training
recordings show: the statistics :mod:`sins.compensation.unit_bias`'s rule takes from a few recordings'
biases. A few recordings say little of their own spread, and a new power-up is one more draw: each
function says which bound it takes and why.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: The confidence at which the training recordings' mean bias is taken as the unit's (two-sided).
DETERMINED = 0.95


#: The least spread a rule takes, rad/s (0.2 °/h): two recordings that happen to agree say little more.
MIN_SPREAD = 1e-6
#: The widths :func:`mixture_width` tries, as shares of the training recordings' spread.
_WIDTH_SHARES = 2.0 ** np.linspace(-6.0, 0.0, 61)


#: The least accelerometer-bias prior the online estimate takes, m/s² (0.1 mg): recordings whose biases
#: happen to agree say little more.
_MIN_ACCEL_SPREAD = 1e-3


def accel_spread(accel_biases: Array) -> float:
    """The online estimate's prior on a new recording's accelerometer bias, m/s²: the training
    recordings' own biases (r, 3) about their mean (which the model takes away), their standard deviation
    as the root mean square over the axes, raised to its upper 95 % bound (chi-squared of ``r − 1``
    degrees of freedom: × 2.1 for six recordings, × 4.4 for three, × 16 for two) and at least
    :data:`_MIN_ACCEL_SPREAD`. A few recordings say little of a spread, and a prior held too tight makes
    the gyro's bias take up what the accelerometer's does. A fixed 0.2 m/s² had let the estimate trade
    the gyro's bias for an accelerometer bias ten times any EuRoC recording's (0.011-0.018 m/s² about
    their mean)."""
    from scipy.stats import chi2

    biases = np.asarray(accel_biases, dtype=float)
    dof = len(biases) - 1
    spread = float(np.sqrt(np.mean(biases.std(axis=0, ddof=1) ** 2)))
    return float(max(spread * np.sqrt(dof / chi2.ppf(1.0 - DETERMINED, dof)), _MIN_ACCEL_SPREAD))


def predictive_bound(count: int) -> float:
    """How many times a new recording's bias can stray further than ``count`` recordings' spread
    says, at :data:`DETERMINED`: the predictive Student-t's half-width over the normal's,
    ``t(dof) · √(1 + 1/count) / z`` with ``dof = count − 1`` (× 2.5 for three, × 1.4 for six). The
    recordings' mean and spread are themselves estimates; this is the interval for the next one."""
    from scipy.stats import norm, t

    q = 1.0 - (1.0 - DETERMINED) / 2.0
    return float(t.ppf(q, count - 1) * np.sqrt(1.0 + 1.0 / count) / norm.ppf(q))


def mixture_width(biases: Array, spread: Array) -> Array:
    """The width (3,) rad/s of each training recording's component in the online estimate's mixture
    prior: ``h × spread``, ``h`` in (0, 1] the share that best predicts each recording's bias (``biases``
    (r, 3)) from the mixture of the others' (leave one out, the log-likelihood summed over the
    recordings): where the recordings' biases fall in clusters (days, power-ups) a new one's is likely
    near one of them and the width is the clusters'; where each is a draw of its own, of the order of
    their distances apart (at most the spread)."""
    from scipy.special import logsumexp

    z = np.asarray(biases, dtype=float) / spread  # each axis in its spread
    d2 = ((z[:, None, :] - z[None, :, :]) ** 2).sum(axis=2)
    others = ~np.eye(len(z), dtype=bool)

    def score(h: float) -> float:
        logs = np.where(others, -0.5 * d2 / h**2 - 3.0 * np.log(h), -np.inf)
        return float(np.sum(logsumexp(logs, axis=1)))

    best = max(_WIDTH_SHARES, key=score)
    return np.asarray(np.maximum(best * spread, MIN_SPREAD), dtype=float)


def shrunk(mean_bias: Array, spread: Array, count: int) -> Array:
    """What of a model's gyro bias ``mean_bias`` (rad/s, the mean of ``count`` training recordings'
    biases, which differ by ``spread``) a new recording's prior leaves out, per axis. A new power-up's
    bias is the unit's mean give or take ``spread``, and the mean of ``count`` is itself uncertain by
    ``spread / √count``. Where the mean is not determined (Student's t of ``count − 1`` degrees of freedom,
    the spread being estimated from the same recordings, not beyond its two-sided :data:`DETERMINED`
    quantile: 4.30 standard errors for three recordings, 2.57 for six) all of it is left out: each
    power-up draws its own bias about a mean the recordings cannot tell from zero, and the readings' own
    bias stands (which the online estimate may still correct). Elsewhere the prior keeps
    ``λ = m² / (m² + spread² / count)`` of it, what minimises a new recording's expected squared error with
    ``m`` the mean itself (plug-in shrinkage, as empirical Bayes does): EuRoC's six recordings agree on
    biases of 2-80 mrad/s two mrad/s apart, and keep all but 1e-4 to 1e-2 of them. A walkthrough's unit
    (BROAD's unit B with 0.05-0.5 °/s added to each of three parts) had the mean of three such draws take
    a recording whose bias happened to be small from 3.7° to 17.0° of open-loop attitude; now 2.2°."""
    from scipy.stats import t as student

    m2, uncertain = mean_bias**2, spread**2 / max(count, 1)
    keep = m2 / np.maximum(m2 + uncertain, 1e-300)
    critical = float(student.ppf(0.5 + DETERMINED / 2.0, max(count - 1, 1)))
    keep = np.where(m2 > critical**2 * uncertain, keep, 0.0)
    return np.asarray(mean_bias * (1.0 - keep), dtype=float)


__all__ = [
    "DETERMINED",
    "MIN_SPREAD",
    "accel_spread",
    "mixture_width",
    "predictive_bound",
    "shrunk",
]
