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
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.compensation.base import state_array, sum_standard_error
from sins.imu import CHANNELS, vocabulary

Array = NDArray[np.float64]


def groups() -> tuple[str, ...]:
    """The term groups tried, in the order their columns come: the group of every effect of the
    vocabulary that declares one (:attr:`sins.imu.Effect.term`), by rank (strategy files keep the
    coefficients in this order). Read from the vocabulary when called."""
    terms = {t.term for t in vocabulary.effect_types() if t.term is not None}
    return tuple(t.group for t in sorted(terms, key=lambda t: t.rank))


def groups_of(channel: int) -> tuple[str, ...]:
    """The groups channel ``channel`` (0–5: gyro x, y, z, accel x, y, z) may take: those with an
    effect on its sensor (an accelerometer takes no ``g2``: the anisoelasticity is the gyros')."""
    sensor = "gyro" if channel < 3 else "accel"
    return tuple(g for g in groups() if any(sensor in cls.sensors for cls in _members(g)))


def _members(group: str) -> list[type[vocabulary.Effect]]:
    """The effect classes of ``group``, in the vocabulary's order (their columns' order)."""
    return [t for t in vocabulary.effect_types() if t.term is not None and t.term.group == group]


def _needs_temp(group: str) -> bool:
    return any(cls.needs_temp for cls in _members(group))


def __getattr__(name: str) -> Any:
    # ``GROUPS`` is read from the vocabulary when asked, so an effect registered later is among them.
    if name == "GROUPS":
        return groups()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class TermInputs:
    """The terms' inputs in the learners' scales: the rate ``omega_ib_b`` and force ``f_ib_b`` (n, 3),
    and the temperature ``temp_offset`` (n,) from the learners' origin, or None."""

    omega_ib_b: Array
    f_ib_b: Array
    temp_offset: Array | None

    def of(self, sensor: str) -> Array:
        """``omega_ib_b`` for "gyro", ``f_ib_b`` for "accel"."""
        return self.omega_ib_b if sensor == "gyro" else self.f_ib_b

    @property
    def omega_dot_b(self) -> Array:
        """Not held: no term group needs the angular acceleration (the size effect is left to the learner)."""
        raise ValueError("the physics terms hold no angular acceleration")

    # The names :mod:`sins.compensation.residual` reads until it takes the ones above.
    w = property(lambda self: self.omega_ib_b)
    f = property(lambda self: self.f_ib_b)
    t = property(lambda self: self.temp_offset)

    def rows(self, index: NDArray[np.intp] | NDArray[np.bool_]) -> TermInputs:
        """The inputs at ``index``."""
        temp = None if self.temp_offset is None else self.temp_offset[index]
        return TermInputs(self.omega_ib_b[index], self.f_ib_b[index], temp)


def design(groups: tuple[str, ...] | list[str], channel: int, x: TermInputs) -> Array:
    """The columns of channel ``channel`` (0–5: gyro x, y, z, accel x, y, z) with ``groups`` (n, k): the
    seed model's ``[1, ω, f]``, then each group's (its effects' :meth:`sins.imu.Effect.columns`, in
    the order of :func:`groups`).

    The seed model's columns come with the groups because regression's residual is what is left after
    fitting them alone: a group correlated with them on the rig (a temperature that rose while the
    table turned) leaves a residual that the group by itself fits with a biased coefficient. Fitted
    together, the groups' coefficients are those of the joint least squares (Frisch–Waugh), and the seed
    columns' say how regression's coefficients move with them."""
    cols = [np.ones((len(x.omega_ib_b), 1)), x.omega_ib_b, x.f_ib_b]
    sensor, axis = ("gyro", channel) if channel < 3 else ("accel", channel - 3)
    for group in groups_of(channel):
        if group not in groups:
            continue
        if _needs_temp(group) and x.temp_offset is None:
            raise ValueError("these terms were fitted with temperature: give the temperature series")
        cols += [cls.columns(x, sensor, axis) for cls in _members(group) if sensor in cls.sensors]
    return np.hstack(cols)


def subsets(with_temperature: bool, channel: int = 0) -> list[tuple[str, ...]]:
    """Every non-empty subset of the groups channel ``channel`` may take that the data support."""
    allowed = tuple(g for g in groups_of(channel) if with_temperature or not _needs_temp(g))
    return [s for r in range(1, len(allowed) + 1) for s in combinations(allowed, r)]


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
    x: TermInputs,
    fold_targets: list[tuple[NDArray[np.bool_], Array]],
    block: NDArray[np.intp],
    z: float,
    by_fold: bool = False,
) -> list[tuple[str, ...]]:
    """Each channel's groups: ``fold_targets`` holds, per fold, its training rows and regression's
    residual (n, 6) as refitted on them; a subset's gain is the drop in the held-back rows' sum of
    squares, per block over the folds (``by_fold``: per fold, each a recording), and the groups are taken
    forward (:func:`_forward`).

    Every subset of a channel is fitted from the Gram matrix of its design with every group (the
    columns scaled to unit RMS on the training rows), so a fold costs one pass over the rows a channel.
    """
    chosen: list[tuple[str, ...]] = []
    held_blocks = []  # per fold: how many held-back blocks, and each held-back row's
    for train, _ in fold_targets:
        blocks, index = np.unique(block[~train], return_inverse=True)
        held_blocks.append((len(blocks), index.ravel()))
    for c in range(6):
        options = subsets(x.temp_offset is not None, c)
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
                gains[s].append(
                    np.asarray(np.bincount(index, weights=y * y - e * e, minlength=n_blocks), float)
                )
        chosen.append(_forward(options, {s: _draws(g, by_fold) for s, g in gains.items()}, z))
    return chosen


def _draws(per_fold: list[Array], by_fold: bool) -> Array:
    """A subset's held-back gains as the guard's draws: every fold's blocks one after another, or
    (``by_fold``, each fold a recording) one sum per fold; none where no fold was held back."""
    if not per_fold:
        return np.zeros(0)
    return np.array([g.sum() for g in per_fold]) if by_fold else np.concatenate(per_fold)


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
            se = float(sum_standard_error(step))
            if total > z * se and total > best_gain:
                best, best_gain, best_g = s, total, g
        if best is None:
            return taken
        taken, base = best, best_g


def _columns_of(
    groups: tuple[str, ...], every: tuple[str, ...], channel: int, row: TermInputs
) -> NDArray[np.intp]:
    """The columns of :func:`design` with ``groups`` within its design with the groups ``every``, each
    group's width read off :func:`design` of one ``row``."""
    seed = design((), channel, row).shape[1]
    cols, at = list(range(seed)), seed
    for group in groups_of(channel):
        if group not in every:
            continue
        width = design((group,), channel, row).shape[1] - seed
        if group in groups:
            cols += range(at, at + width)
        at += width
    return np.array(cols, dtype=np.intp)


def predict(groups: list[tuple[str, ...]], coef: list[Array], x: TermInputs, channels: range) -> Array:
    """The terms' residual on ``channels`` (n, len(channels)); a channel without terms predicts 0."""
    out = np.zeros((len(x.omega_ib_b), len(channels)))
    for i, c in enumerate(channels):
        if groups[c]:
            out[:, i] = design(groups[c], c, x) @ coef[c]
    return out


def check_state(chosen: Any, uses_temp: bool) -> None:
    """Each channel's terms in a saved state (a model file's ``terms_``): known groups, and as many
    coefficients as their columns; ``ValueError`` naming the channel."""
    if not isinstance(chosen, dict):
        raise ValueError("state.terms_ must be an object by channel")
    one = TermInputs(np.zeros((1, 3)), np.zeros((1, 3)), np.zeros(1) if uses_temp else None)
    known = groups()
    for ch, entry in chosen.items():
        where = f"state.terms_.{ch}"
        if ch not in CHANNELS or not isinstance(entry, dict) or not isinstance(entry.get("groups"), list):
            raise ValueError(f"{where} must be a channel's terms (groups and coef)")
        chosen_groups = entry["groups"]
        if not all(g in known for g in chosen_groups) or ("temperature" in chosen_groups and not uses_temp):
            among = ", ".join(known)
            raise ValueError(f"{where}.groups must be among {among} (temperature if fitted with it)")
        columns = design(chosen_groups, CHANNELS.index(ch), one).shape[1]
        state_array(entry, "coef", (columns,), where)


__all__ = [
    "SHOWN",
    "TermInputs",
    "check_state",
    "choose",
    "design",
    "fit",
    "groups",
    "groups_of",
    "predict",
    "subsets",
]
