"""The training points of the learned strategies (:mod:`sins.compensation.residual`): a session's
residuals against the rig's reference made into averaged points, cut into blocks of like input, and the
held-back loss and gains those points give.

The inputs are the reference's, scaled by their physical range (``residual`` does the scaling); these
functions take them scaled.

* **Sufficient statistics.** Rows whose inputs fall in one cell of a fine
  grid (1/64 of the scaled range: 4.7 °/s on a 300 °/s rig, 0.15 m/s²)
  within one time block are averaged into one point weighted by its count.
  For least squares on the reference inputs this changes the loss by a
  constant where inputs repeat exactly (a static hold is one point) and by
  half the residual's curvature times the cell's variance otherwise (for
  ``k2 ω²``, ``k2 δ²/12``: 1e-4 of the error at 300 °/s); it makes a
  100,000-row session a few thousand points.
* **Rows that repeat one draw are one observation.** Where consecutive rows'
  residuals share their error (a reference held over an interval, as the
  per-sample references of :func:`sins.compensation.intervals.interval_reference`
  are; a slow drift), a fine cell holds one row of moving inputs, and the
  points would be as many as the rows though the draws are far fewer. The
  number of rows a draw spans is read off the residual itself
  (:func:`repeats`: the within-block variogram), and where it is 4 or more,
  runs of that many rows are averaged first (their mean input and residual)
  and the cells then group the runs: the loss of a run's mean is that of an
  interval's integral, to second order. White noise (sins's rigs, a real unit
  against an exact reference) repeats nothing, and the points are the cells'.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: Grid of the sufficient statistics and of the block segmentation, in scaled input units.
_CELL = 1.0 / 64.0
_SEGMENT_CELL = 1.0 / 8.0
_MIN_BLOCK_S, _MAX_BLOCK_S = 1.0, 20.0
#: Rows a draw must span before runs of them are averaged into one observation (see ``repeats``):
#: below it the cells already hold most of the saving, and sins's rigs, whose gyros drift (bias
#: instability) beside their white noise, repeat 1.6-2.6 rows.
MIN_REPEATS = 4


@dataclass(frozen=True)
class Points:
    """Averaged training points of one sensor: inputs ``x`` (m, d), mean residual ``y`` (m, 3),
    row counts ``n`` (m,) and the time block each came from ``block`` (m,)."""

    x: Array
    y: Array
    n: Array
    block: NDArray[np.intp]
    #: Σ y² of the rows behind each point (m, 3): the regression's own sum of squares.
    sq: Array


def input_columns(sensor: str, w: Array, f: Array, temp: Array | None) -> Array:
    """The raw inputs a sensor's residual depends on: gyro ``[ω, f, T]``, accel ``[f, T]``."""
    parts = [w, f] if sensor == "gyro" else [f]
    if temp is not None:
        parts.append(np.asarray(temp, dtype=float)[:, None])
    return np.hstack(parts)


def segment(scaled: Array, t: Array) -> NDArray[np.intp]:
    """Block index of every row: a new block where the coarse cell of ``scaled`` (n, d) changes, merged
    to at least 1 s and split to at most 20 s."""
    n = len(t)
    dt = float(np.median(np.diff(t))) if n > 1 else 1.0
    min_rows, max_rows = max(1, round(_MIN_BLOCK_S / dt)), max(1, round(_MAX_BLOCK_S / dt))
    coarse = np.floor(scaled / _SEGMENT_CELL)
    changes = np.flatnonzero((coarse[1:] != coarse[:-1]).any(axis=1)) + 1
    starts = [0]
    for c in changes.tolist():
        while c - starts[-1] > max_rows:
            starts.append(starts[-1] + max_rows)
        if c - starts[-1] >= min_rows:
            starts.append(c)
    while n - starts[-1] > max_rows:
        starts.append(starts[-1] + max_rows)
    block = np.zeros(n, dtype=np.intp)
    block[np.array(starts[1:], dtype=np.intp)] = 1
    return np.cumsum(block)


def repeats(y: Array, block: NDArray[np.intp]) -> int:
    """How many consecutive rows of residuals ``y`` (n, k) repeat one draw of their error: the run the
    points average over (:func:`aggregate`), 1 where it is below :data:`MIN_REPEATS`.

    Per channel, within the blocks (``block`` sorted, each a stretch of like input): the semivariogram
    ``D(L) = ½ mean (y[i+L] − y[i])²`` at lags 1 and 2 against the within-block variance ``V``. White
    noise has ``D(1) = V``; rows that share a draw over ``m`` rows (a held reference, a drift) change
    from row to row by ``V / m``, and ``D`` grows linearly with the lag (``D(2) ≈ 2 D(1)``). A channel
    repeats ``V / D(1)`` rows where ``D`` grows linearly (``D(2) < 3 D(1)``); a smooth residual without
    noise grows quadratically (``D(2) ≈ 4 D(1)``: a ramp's curve, not a repeated draw), and counts as
    rows of their own. The sensor repeats what its most independent channel does.
    """
    n = len(y)
    starts = np.r_[0, np.flatnonzero(np.diff(block)) + 1]
    counts = np.diff(np.r_[starts, n])
    if n - len(starts) < 3:
        return 1
    means = np.add.reduceat(y, starts, axis=0) / counts[:, None]
    within = ((y - np.repeat(means, counts, axis=0)) ** 2).sum(axis=0) / (n - len(starts))
    lag: list[Array] = []
    for step in (1, 2):
        same = block[step:] == block[:-step]
        lag.append(0.5 * np.mean((y[step:] - y[:-step])[same] ** 2, axis=0))
    spans = [
        float(v / d1) if d2 < 3.0 * d1 else 1.0
        for v, d1, d2 in zip(within, *lag, strict=True)
        if v > 0 and d1 > 0
    ]
    run = int(min(spans)) if spans else 1
    return run if run >= MIN_REPEATS else 1


def aggregate(x: Array, y: Array, block: NDArray[np.intp], run: int = 1) -> Points:
    """Average rows sharing a fine input cell and a block (see the module docstring); with ``run`` > 1
    each row takes the cell of its run's mean input (runs of ``run`` rows from each block's start,
    ``block`` sorted), so that a run's rows join one point."""
    cells = x if run <= 1 else _run_means(x, block, run)
    keys = np.column_stack([np.floor(cells / _CELL).astype(np.int64), block])
    inverse, counts = _group(keys)
    m = len(counts)
    sums_x = np.zeros((m, x.shape[1]))
    sums_y = np.zeros((m, y.shape[1]))
    sq = np.zeros((m, y.shape[1]))
    np.add.at(sums_x, inverse, x)
    np.add.at(sums_y, inverse, y)
    np.add.at(sq, inverse, y * y)
    first = np.full(m, len(block), dtype=np.intp)
    np.minimum.at(first, inverse, np.arange(len(block)))
    n = counts.astype(float)
    return Points(sums_x / n[:, None], sums_y / n[:, None], n, block[first], sq)


def _run_means(x: Array, block: NDArray[np.intp], run: int) -> Array:
    """Each row's run's mean of ``x``: runs of ``run`` rows from the start of each block."""
    n = len(x)
    new_block = np.r_[True, block[1:] != block[:-1]]
    starts = np.flatnonzero(new_block)
    position = np.arange(n) - np.repeat(starts, np.diff(np.r_[starts, n]))
    run_id = np.cumsum(new_block | (position % run == 0)) - 1
    counts = np.bincount(run_id)
    means = np.stack([np.bincount(run_id, x[:, c]) for c in range(x.shape[1])], axis=1) / counts[:, None]
    out: Array = means[run_id]
    return out


def _group(keys: NDArray[np.int64]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """``np.unique(keys, axis=0)``'s inverse and counts: the groups of equal rows, numbered in the
    rows' lexicographic order. The columns are packed into one integer (each less its minimum, in a
    radix of its range) where they fit in 63 bits, whose order is the lexicographic one, so the groups
    and their numbering are the same; sorting one integer column is several times faster than
    sorting rows (``axis=0`` sorts a structured view)."""
    if len(keys) == 0:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    lo = keys.min(axis=0)
    spans = keys.max(axis=0) - lo + 1
    if float(np.prod(spans.astype(float))) >= 2.0**62:
        _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
        return inverse.ravel(), counts
    packed = np.zeros(len(keys), dtype=np.int64)
    for c in range(keys.shape[1]):
        packed = packed * spans[c] + (keys[:, c] - lo[c])
    _, inverse, counts = np.unique(packed, return_inverse=True, return_counts=True)
    return inverse.ravel(), counts


def block_gains(points: Points, pred: Array) -> tuple[Array, Array]:
    """Per block and channel, the drop in the sum of squared residuals that ``pred`` brings,
    Σ n (ȳ² − (ȳ − p)²) (exact for the rows behind each averaged point), and regression's own sum."""
    gain = points.n[:, None] * (points.y**2 - (points.y - pred) ** 2)
    blocks, index = np.unique(points.block, return_inverse=True)
    out = np.zeros((len(blocks), pred.shape[1]))
    base = np.zeros((len(blocks), pred.shape[1]))
    np.add.at(out, index.ravel(), gain)
    np.add.at(base, index.ravel(), points.sq)
    return out, base


def held_loss(held: Points, pred: Array, sigma: Array) -> float:
    """The weighted held-back loss of predictions ``pred`` at ``held``'s points, in units of ``sigma``."""
    return float((held.n[:, None] * ((held.y - pred) / sigma) ** 2).sum())


__all__ = [
    "MIN_REPEATS",
    "Points",
    "aggregate",
    "block_gains",
    "held_loss",
    "input_columns",
    "repeats",
    "segment",
]
