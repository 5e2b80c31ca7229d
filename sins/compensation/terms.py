"""Physics terms beyond the seed model, each channel's chosen on held-back blocks: the step between
regression and a learner in the learned strategies (:mod:`sins.compensation.residual`).

A learner finds an error from what the rig showed it. Where the rig confounds two inputs, it cannot tell
which one the error follows, and on another rig or a drive it guesses: a rig that warms its chamber
while it turns the unit shows a temperature scale factor (``s (T − T0) ω``) only as rate at a
temperature, and a learner of the residual then puts part of it on the wrong input (on the cross-rig
benchmark's 20 units, mlp left 1.35× and kohonen 1.46× the noise on continuous tumbling and drifted
1.84× and 3.4× regression's on a warming drive; with the terms, 1.00× and 0.27×). Where the rig shows an
input only at a few levels (an accelerometer at ±1 g and 0 in its positions), a learner interpolates
between them, and a curved error is wrong in between. Least squares with the error's stated form
separates and bridges both, as far as the rig holds the forms apart at all. The groups tried are the
deterministic errors of sins's effect vocabulary beyond the seed model (``docs/guide/imu.md``), on
channel ``c`` with its own input ``u_c`` (rate or force, in the learners' scales, see ``residual``):

* ``temperature``: ``T``, ``T²`` and ``T u_c`` (temperature bias and scale), where the session spans a
  temperature range;
* ``squares``: ``u_c²`` (scale nonlinearity);
* ``asymmetry``: ``|u_c|`` (scale asymmetry);
* ``g2``, gyros only: ``f_j f_k``, the six products of the specific force (anisoelastic drift).

The groups are fitted to regression's residual together with the seed model's own columns
(:func:`design`) and taken forward (:func:`choose`): a group joins a channel's if its held-back gain over
the groups already taken, summed over the folds' blocks, is above ``z`` standard errors of it (the
learners' guard); then the learner learns what is left. ``squares`` and ``asymmetry`` are both even in
``u``: a rig that shows an input at one magnitude only cannot tell them apart, and forward selection then
takes the one that fits (alone, ``squares`` was taken for an asymmetry and fitted it only in part: mlp's
residual on tumbling rose from 1.24× to 1.91× the noise, units 0–4 of the benchmark), the other adding
nothing beyond chance. ``regression_extended`` fits every term on every channel, and on a unit whose
errors the seed model holds pays for it in drift (1.76× regression's on the benchmark's seed-model
units). Errors outside the vocabulary (or the size effect, which needs the angular acceleration) are
left to the learner.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: The term groups tried, in the order their columns come: the effect vocabulary's deterministic
#: errors beyond the seed model (``docs/guide/imu.md``), each channel's in its stated form.
GROUPS = ("temperature", "squares", "asymmetry", "g2")
#: The groups a gyro channel may take; an accelerometer's take no ``g2`` (the vocabulary's
#: anisoelasticity is the gyros').
GYRO_GROUPS, ACCEL_GROUPS = GROUPS, ("temperature", "squares", "asymmetry")


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
    u = (x.w if channel < 3 else x.f)[:, channel % 3 : channel % 3 + 1]
    for group in GROUPS:
        if group not in groups:
            continue
        if group == "temperature":
            if x.t is None:
                raise ValueError("these terms were fitted with temperature: give the temperature series")
            t = x.t[:, None]
            cols += [t, t * t, t * u]
        elif group == "squares":  # scale nonlinearity, k2 u²
            cols.append(u * u)
        elif group == "asymmetry":  # scale asymmetry, ka |u|
            cols.append(np.abs(u))
        elif group == "g2" and channel < 3:  # anisoelasticity, Σ G2_jk f_j f_k
            f = x.f
            cols += [f * f, f[:, [0, 0, 1]] * f[:, [1, 2, 2]]]
    return np.hstack(cols)


def subsets(with_temperature: bool, channel: int = 0) -> list[tuple[str, ...]]:
    """Every non-empty subset of the groups channel ``channel`` may take that the data support."""
    groups = tuple(
        g for g in (GYRO_GROUPS if channel < 3 else ACCEL_GROUPS) if with_temperature or g != "temperature"
    )
    return [s for r in range(1, len(groups) + 1) for s in combinations(groups, r)]


def fit(x: Array, r: Array) -> Array:
    """Least-squares coefficients of ``r`` (n,) on columns ``x`` (n, k), the columns scaled to unit RMS
    for the solve; a column the data do not show (:func:`_shown`) gets 0."""
    scale = _shown(np.sqrt(np.mean(x * x, axis=0)))
    coef = np.zeros(x.shape[1])
    keep = scale > 0
    coef[keep], *_ = np.linalg.lstsq(x[:, keep] / scale[keep], r, rcond=None)
    return np.asarray(coef / np.where(keep, scale, 1.0), dtype=float)


#: A column whose RMS is below this fraction of the largest column's is rounding, not data: a product
#: ``f_y f_z`` on a rig that only ever points one axis down is ~1e-17, and scaled to unit RMS its noise
#: took a coefficient of 1e12 that blew up on any other input.
SHOWN = 1e-9


def _shown(scale: Array) -> Array:
    """``scale`` with the columns the data do not show (RMS below :data:`SHOWN` of the largest) at 0."""
    return np.where(scale > SHOWN * scale.max(), scale, 0.0)


def choose(
    x: Inputs,
    fold_targets: list[tuple[NDArray[np.bool_], Array]],
    block: NDArray[np.intp],
    z: float,
) -> list[tuple[str, ...]]:
    """Each channel's groups: ``fold_targets`` holds, per fold, its training rows and regression's
    residual (n, 6) as refitted on them; a subset's gain is the drop in the held-back rows' sum of
    squares, per block, over the folds, and the groups are taken forward (:func:`_forward`).

    Every subset of a channel is fitted from the Gram matrix of its design with every group (the
    columns scaled to unit RMS on the training rows), so a fold costs one pass over the rows a channel.
    """
    chosen: list[tuple[str, ...]] = []
    held_blocks = []  # per fold: how many held-back blocks, and each held-back row's
    for train, _ in fold_targets:
        blocks, index = np.unique(block[~train], return_inverse=True)
        held_blocks.append((len(blocks), index.ravel()))
    for c in range(6):
        options = subsets(x.t is not None, c)
        full = design(options[-1], c, x)
        columns = {s: _columns_of(s, options[-1], c, x.rows(np.arange(1))) for s in options}
        gains: dict[tuple[str, ...], list[Array]] = {s: [] for s in options}
        for (train, targets), (n_blocks, index) in zip(fold_targets, held_blocks, strict=True):
            held = ~train
            x_train, y_train = full[train], targets[train, c]
            scale = _shown(np.sqrt(np.mean(x_train * x_train, axis=0)))
            shown = scale > 0
            x_train = x_train / np.where(shown, scale, 1.0)
            gram, moment = x_train.T @ x_train, x_train.T @ y_train
            x_held, y = full[held] / np.where(shown, scale, 1.0), targets[held, c]
            for s, every in columns.items():
                cols = every[shown[every]]  # a column the fold's rows do not show takes no part
                coef, *_ = np.linalg.lstsq(gram[np.ix_(cols, cols)], moment[cols], rcond=None)
                e = y - x_held[:, cols] @ coef
                # Summed row by row in order, as np.add.at does, and many times faster.
                gains[s].append(np.bincount(index, weights=y * y - e * e, minlength=n_blocks))
        chosen.append(
            _forward(options, {s: np.concatenate(g) if g else np.zeros(0) for s, g in gains.items()}, z)
        )
    return chosen


def _forward(
    options: list[tuple[str, ...]], gains: dict[tuple[str, ...], Array], z: float
) -> tuple[str, ...]:
    """Forward selection on the held-back gains per block: from no group, add the group whose gain over
    the groups already taken is largest and above ``z`` standard errors of it, until none is (a group
    whose columns the rig cannot tell from those taken adds nothing beyond chance, and is left out)."""
    taken: tuple[str, ...] = ()
    base = np.zeros_like(next(iter(gains.values())))
    while True:
        best, best_gain, best_g = None, 0.0, base
        for s in options:
            if len(s) != len(taken) + 1 or not set(taken) <= set(s):
                continue
            g = gains[s]
            step = g - base
            total = float(step.sum())
            se = float(np.sqrt(len(step) * step.var(ddof=1))) if len(step) > 1 else np.inf
            if total > z * se and total > best_gain:
                best, best_gain, best_g = s, total, g
        if best is None:
            return taken
        taken, base = best, best_g


def _columns_of(
    groups: tuple[str, ...], every: tuple[str, ...], channel: int, row: Inputs
) -> NDArray[np.intp]:
    """The columns of :func:`design` with ``groups`` within its design with the groups ``every``, each
    group's width read off :func:`design` of one ``row``."""
    seed = design((), channel, row).shape[1]
    cols, at = list(range(seed)), seed
    for group in GROUPS:
        if group not in every:
            continue
        width = design((group,), channel, row).shape[1] - seed
        if group in groups:
            cols += range(at, at + width)
        at += width
    return np.array(cols, dtype=np.intp)


def predict(groups: list[tuple[str, ...]], coef: list[Array], x: Inputs, channels: range) -> Array:
    """The terms' residual on ``channels`` (n, len(channels)); a channel without terms predicts 0."""
    out = np.zeros((len(x.w), len(channels)))
    for i, c in enumerate(channels):
        if groups[c]:
            out[:, i] = design(groups[c], c, x) @ coef[c]
    return out
