"""Physics terms beyond the seed model, each channel's chosen on held-back blocks: the step between
regression and a learner in the learned strategies (:mod:`sins.compensation.residual`).

A learner finds an error from what the rig showed it. Where the rig confounds two inputs, it cannot tell
which one the error follows, and on another rig or a drive it guesses: a rig that warms its chamber
while it turns the unit shows a temperature scale factor (``s (T − T0) ω``) only as rate at a
temperature, and a learner of the residual then puts part of it on the wrong input (on the cross-rig
benchmark's 20 units, mlp left 1.35× and kohonen 1.46× the noise on continuous tumbling and drifted
1.84× and 3.4× regression's on a warming drive; with the terms, 1.00× and 0.27×). Least squares with the
term's form separates them, as far as the rig holds both apart at all. The group tried:

* ``temperature``: ``T``, ``T²`` and ``T u_c`` on channel ``c`` (temperature bias and scale), where the
  session spans a temperature range (``T`` in the learners' scale, see ``residual``).

Each channel's group is fitted to regression's residual together with the seed model's own columns
(:func:`design`), and kept if its held-back gain over regression, summed over the folds' blocks, is
above ``z`` standard errors of it (the learners' guard); then the learner learns what is left.
``regression_extended`` fits every term on every channel, and on a unit whose errors the seed model
holds pays for it in drift (1.76× regression's on the benchmark's seed-model units).

Squares of the inputs (``ω²``, ``f²``: scale nonlinearity) are not tried: the rig shows them along the
rates and orientations it turns through, which the learners follow without a stated form, and as a
group chosen on held-back gain they were taken for a scale asymmetry (``|ω|``) as well, which they fit
only in part: mlp's residual on tumbling rose from 1.24× to 1.91× the noise there (units 0–4).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: The term groups tried, in the order their columns come (``squares`` is not: see the module docstring).
GROUPS = ("temperature",)


@dataclass(frozen=True)
class Inputs:
    """The terms' inputs in physical scales: rate ``w`` and force ``f`` (n, 3), temperature ``t`` (n,) or
    None."""

    w: Array
    f: Array
    t: Array | None

    def rows(self, index: NDArray[np.intp] | NDArray[np.bool_]) -> Inputs:
        """The inputs at ``index``."""
        return Inputs(self.w[index], self.f[index], None if self.t is None else self.t[index])


def design(groups: tuple[str, ...] | list[str], channel: int, x: Inputs) -> Array:
    """The columns of channel ``channel`` (0–5: gyro x, y, z, accel x, y, z) with ``groups`` (n, k): the
    seed model's ``[1, ω, f]``, then each group's.

    The seed model's columns come with the groups because regression's residual is what is left after
    fitting them alone: a group correlated with them on the rig (a temperature that rose while the
    table turned) leaves a residual that the group by itself fits with a biased coefficient. Fitted
    together, the groups' coefficients are those of the joint least squares (Frisch–Waugh), and the seed
    columns' say how regression's coefficients move with them."""
    cols = [np.ones((len(x.w), 1)), x.w, x.f]
    if "temperature" in groups:
        if x.t is None:
            raise ValueError("these terms were fitted with temperature: give the temperature series")
        t = x.t[:, None]
        u = (x.w if channel < 3 else x.f)[:, channel % 3 : channel % 3 + 1]
        cols += [t, t * t, t * u]
    return np.hstack(cols)


def subsets(with_temperature: bool) -> list[tuple[str, ...]]:
    """Every non-empty subset of the groups tried that the data support."""
    groups = tuple(g for g in GROUPS if with_temperature or g != "temperature")
    return [s for r in range(1, len(groups) + 1) for s in combinations(groups, r)]


def fit(x: Array, r: Array) -> Array:
    """Least-squares coefficients of ``r`` (n,) on columns ``x`` (n, k), the columns scaled to unit RMS
    for the solve."""
    scale = np.sqrt(np.mean(x * x, axis=0))
    scale = np.where(scale > 0, scale, 1.0)
    coef, *_ = np.linalg.lstsq(x / scale, r, rcond=None)
    return np.asarray(coef / scale, dtype=float)


def choose(
    x: Inputs,
    fold_targets: list[tuple[NDArray[np.bool_], Array]],
    block: NDArray[np.intp],
    z: float,
) -> list[tuple[str, ...]]:
    """Each channel's groups: ``fold_targets`` holds, per fold, its training rows and regression's
    residual (n, 6) as refitted on them; a subset's gain is the drop in the held-back rows' sum of
    squares, per block, over the folds."""
    options = subsets(x.t is not None)
    gains = {s: np.zeros((0, 6)) for s in options}
    for train, targets in fold_targets:
        held = ~train
        blocks, index = np.unique(block[held], return_inverse=True)
        x_train, x_held = x.rows(train), x.rows(held)
        for s in options:
            out = np.zeros((len(blocks), 6))
            for c in range(6):
                coef = fit(design(s, c, x_train), targets[train, c])
                y = targets[held, c]
                e = y - design(s, c, x_held) @ coef
                np.add.at(out[:, c], index.ravel(), y * y - e * e)
            gains[s] = np.vstack([gains[s], out])
    chosen: list[tuple[str, ...]] = []
    for c in range(6):
        best: tuple[str, ...] = ()
        best_gain = 0.0
        for s in options:
            g = gains[s][:, c]
            total = float(g.sum())
            se = float(np.sqrt(len(g) * g.var(ddof=1))) if len(g) > 1 else np.inf
            if total > z * se and total > best_gain:
                best, best_gain = s, total
        chosen.append(best)
    return chosen


def predict(groups: list[tuple[str, ...]], coef: list[Array], x: Inputs, channels: range) -> Array:
    """The terms' residual on ``channels`` (n, len(channels)); a channel without terms predicts 0."""
    out = np.zeros((len(x.w), len(channels)))
    for i, c in enumerate(channels):
        if groups[c]:
            out[:, i] = design(groups[c], c, x) @ coef[c]
    return out
