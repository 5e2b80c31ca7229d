"""How a candidate is scored: its withheld log-likelihood gain, less what it needs to be significant.

Each candidate is fitted on the fit rows and scored on the withheld rows: the Gaussian log-likelihood
gain of its withheld residual over the current model's (:func:`trial_gain`). On readings that lie on
a lattice, each is scored instead by the probability of the reading at its recorded resolution: a
quantizer's probability of its lattice index, a continuous model's of the same lattice bin. Its
parameters need no penalty beyond what their errors cost the withheld rows; its score is the gain
less a significance threshold, :data:`SIGNIFICANT_NATS` (``ln(20 / 0.05)``: a likelihood ratio fitted
on other rows passes it by chance with probability ``0.05 / 20`` at most, Markov's bound). A random
bias, whose filter also follows the withheld rows, may correct the current coefficients' errors
there; what that can gain by chance is added to its threshold (:func:`refit_allowance`). A
candidate's channels together make one :class:`Trial`; gains within :data:`TIE_NATS` of each other
cannot be told apart.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from sins.gap import lattice
from sins.gap.channel import ChannelModel
from sins.gap.floor import TINY
from sins.imu import CHANNELS

Array = NDArray[np.float64]

#: The withheld log-likelihood gain a candidate needs, in nats: ln(20 / 0.05), a chance of 0.05 / 20
#: that one of some twenty candidates passes where the current model holds (see :func:`trial_gain`).
SIGNIFICANT_NATS = float(np.log(20 / 0.05))
#: Candidates whose withheld log-likelihood gains differ by less than this are
#: indistinguishable on the data: a likelihood ratio below e³ ≈ 20, short of "strong" evidence.
TIE_NATS = 3.0


def _gain(before: Array, after: Array, withheld: NDArray[np.bool_]) -> float:
    """Withheld log-likelihood gain (Gaussian, own variance)."""
    if np.isnan(after).any():
        return -np.inf
    s0 = float(np.mean(before[withheld] ** 2)) + TINY**2
    s1 = float(np.mean(after[withheld] ** 2)) + TINY**2
    return 0.5 * int(withheld.sum()) * float(np.log(s0 / s1))


def trial_gain(
    current: ChannelModel, trial: ChannelModel, withheld: NDArray[np.bool_], n_fit: int, extra: int = 0
) -> tuple[float, float]:
    """A fitted trial model's withheld log-likelihood gain over the fitted current one, and BIC's
    penalty for its extra parameters, for comparisons on the fit rows.

    Readings off a lattice: the Gaussian gain of the residuals, each with its own variance. On a
    lattice, each withheld reading's probability at the readings' resolution: a quantizer's own, a
    continuous model's of the reading's lattice bin (its residual Gaussian with its own variance).
    ``extra`` counts parameters the trial has beyond its columns (a step's time, a hum's frequency).

    The gain needs no penalty for the trial's parameters: they were fitted on other rows, and each
    one's error costs the withheld likelihood what it is worth. Where the current model holds, the
    withheld likelihood ratio of a model fitted on the fit rows has expectation 1 at most, so it
    exceeds ``e^T`` with probability ``e^-T`` at most (Markov): :data:`SIGNIFICANT_NATS` is ``T``.
    (Approximately: each model's variance here is its own withheld mean square.)
    """
    before, after = current.residual, trial.residual
    k = trial.n_params - current.n_params + extra
    penalty = 0.5 * k * float(np.log(n_fit))
    grid = trial.lattice
    if grid is None or np.isnan(after).any():
        return _gain(before, after, withheld), penalty

    def loglik(model: ChannelModel, residual: Array) -> float:
        if model.loglik_rows is not None:
            return float(model.loglik_rows[withheld].sum())
        sigma = float(np.sqrt(np.mean(residual[withheld] ** 2))) + TINY
        return float(lattice.binned(residual[withheld], grid.step, sigma).sum())

    return loglik(trial, after) - loglik(current, before), penalty


def refit_allowance(models: list[ChannelModel], withheld: NDArray[np.bool_]) -> float:
    """What a random bias may gain on the withheld rows where the current models hold, beyond
    :data:`SIGNIFICANT_NATS`: the part of their error that comes from coefficients fitted on the
    fit rows alone, at probability ``1 − e^-T``.

    A random bias's filter follows the withheld readings as they come, so it also corrects the
    current regressors' coefficient errors there: on a drive whose withheld rows are its last
    straight, a misfit that the fit rows' turns could not pin down. With white noise of variance
    ``σ²`` and columns ``A``, the coefficients' error is ``N(0, σ² (A_fᵀA_f)⁻¹)`` and the withheld
    log-likelihood it costs is ``½ Σ λ_j χ²₁``, ``λ`` the eigenvalues of ``(A_fᵀA_f)⁻¹ A_wᵀA_w``:
    at most ``½ λ_max χ²`` with as many degrees as there are nonzero ``λ``. On a rig whose holds
    are all split alike, ``λ ≈ n_withheld / n_fit`` for every column.

    The random bias's gain over the fitted current model is its gain over the true one (beyond
    ``T`` with probability ``e^-T`` at most, :func:`trial_gain`) plus this loss (beyond the
    allowance with probability ``e^-T``): beyond both with probability ``2 e^-T`` at most.
    """
    lam_max, degrees = 0.0, 0
    for m in models:
        # The eigenvalues of (A_fᵀA_f)⁻¹A_wᵀA_w, from A_f's singular values and A_w's Gram matrix,
        # both accumulated a chunk of rows at a time.
        factor = m.design().factor(m.fit, gram_rows=withheld)
        s, vt, keep = factor.singular()
        basis = vt[keep].T / s[keep]
        lam = np.clip(np.linalg.eigvalsh(basis.T @ factor.scaled_gram() @ basis), 0.0, None)
        lam_max = max(lam_max, float(lam.max(initial=0.0)))
        degrees += int(np.sum(lam > 1e-9 * lam.max(initial=0.0)))
    if degrees == 0:
        return 0.0
    return 0.5 * lam_max * float(chi2.isf(np.exp(-SIGNIFICANT_NATS), degrees))


class ChannelTrial(NamedTuple):
    """A candidate tried on one channel."""

    channel: int
    gain: float  # the withheld log-likelihood gain
    penalty: float  # BIC's, for comparisons on the fit rows
    fit_loglik: float  # the fit rows' log-likelihood: the process's innovations' for a random bias


@dataclass(frozen=True)
class Trial:
    """A candidate tried on a sensor's channels.

    The trial models and residuals are not kept: one per candidate and channel would hold
    hundreds of MB on a long recording. The accepted one's are fitted again.
    """

    rows: tuple[ChannelTrial, ...] = ()
    #: Beyond :data:`SIGNIFICANT_NATS`, what the candidate may gain where the current model holds
    #: (a random bias: :func:`refit_allowance`).
    allowance: float = 0.0

    @property
    def channels(self) -> list[int]:
        """The channels tried, as indices into :data:`sins.imu.CHANNELS`."""
        return [row.channel for row in self.rows]

    @property
    def names(self) -> tuple[str, ...]:
        """The channels tried, by name."""
        return tuple(CHANNELS[i] for i in self.channels)

    @property
    def gain(self) -> float:
        """The withheld log-likelihood gain."""
        return float(sum(row.gain for row in self.rows))

    @property
    def score(self) -> float:
        """The gain beyond what it needs to be significant: accepted above 0."""
        return self.gain - SIGNIFICANT_NATS - self.allowance
