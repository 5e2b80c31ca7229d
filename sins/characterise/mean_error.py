"""The standard error of a mean pooled over several rests, from the readings themselves.

Each rest (a ``(start, stop)`` row range) is taken about its own mean: a bias pooled over rests in
different attitudes (a Ferraris session's six holds) must not count the readings' change from one
attitude to the next as noise (it had: 1.17e4 µg "if white" for Ferraris's accel.x, where the holds'
own spread, 0.011–0.018 m/s² over 3272 rows, gives about 27 µg).

* :func:`white_sigma`: what white noise would give, the spread about each rest's own mean over ``√n``;
* :func:`batch_means_sigma`: the batch-means standard error (non-overlapping batches of ``m`` rows, each
  rest cut on its own). The variance of a mean of ``n`` rows of a stationary noise is
  ``Var(batch mean) · m / n`` once the batches are long against the noise's correlation, whatever its
  spectrum: white noise gives ``σ²/n``, a Gauss–Markov process ``(1 + φ)/(1 − φ)`` times that. It needs
  no noise model, so it holds where a fitted one does not (a vibration hump a quantization-only model
  misses). :data:`BATCHES` batches in all: 29 degrees of freedom, a relative spread of ``1/√58``, 13 %, in
  the 1σ, while each batch spans a thirtieth of the rows, longer than any correlation the Allan curve of
  those rows resolves (its longest τ is a ninth of the span). A correlation longer than a batch is
  underestimated; there the Allan model's figure, the larger, stands (:mod:`sins.characterise.bias`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: How many non-overlapping batches the rows are cut into (see the module's text).
BATCHES = 30
#: Fewer degrees of freedom than this (rests too short for a batch of a thirtieth of all rows), and the
#: batches are halved until there are (a relative spread of 1/√20, 22 %, at most).
MIN_DOF = 10


def _deviations(values: Array, segments: Sequence[tuple[int, int]]) -> list[Array]:
    """Each rest's rows (k_i, c) less the rest's own mean."""
    return [values[a:b] - values[a:b].mean(axis=0) for a, b in segments]


def white_sigma(values: Array, segments: Sequence[tuple[int, int]]) -> Array:
    """The standard error (c,) of the mean of ``values`` (n, c) over ``segments`` were it white: the
    standard deviation about each rest's own mean (one degree of freedom per rest) over ``√rows``."""
    parts = _deviations(np.asarray(values, dtype=float), segments)
    rows = sum(len(p) for p in parts)
    dof = max(rows - len(parts), 1)
    square = sum(np.sum(p * p, axis=0) for p in parts)
    return np.asarray(np.sqrt(square / dof / rows), dtype=float)


def batch_means_sigma(values: Array, segments: Sequence[tuple[int, int]]) -> Array:
    """The batch-means standard error (c,) of the mean of ``values`` (n, c) over ``segments`` (see the
    module's text): batches of ``rows // BATCHES`` rows (fewer where the rests leave under
    :data:`MIN_DOF` degrees of freedom), their means' variance about their rest's mean times the batch's
    rows over all rows. NaN where even batches of one row leave too few (under 2 rows a rest)."""
    parts = _deviations(np.asarray(values, dtype=float), segments)
    rows = sum(len(p) for p in parts)
    size = max(rows // BATCHES, 1)
    while True:
        means = [p[: len(p) // size * size].reshape(-1, size, p.shape[1]).mean(axis=1) for p in parts]
        # Each rest's batch means about their own mean: a rest of k batches gives k − 1 degrees.
        dof = sum(max(len(m) - 1, 0) for m in means)
        if dof >= MIN_DOF or size == 1:
            break
        size = max(size // 2, 1)
    if dof == 0:
        return np.full(parts[0].shape[1] if parts else 0, math.nan)
    square = sum(np.sum((m - m.mean(axis=0)) ** 2, axis=0) for m in means if len(m) > 1)
    return np.asarray(np.sqrt(square / dof * size / rows), dtype=float)


def pooled_rests_sigma(values: Array, groups: Sequence[Sequence[tuple[int, int]]]) -> Array:
    """The standard error (c,) of the mean of ``values`` (n, c) pooled over rests (``groups``: each rest's
    row ranges) where the rests may disagree beyond their noise: a random-effects model (DerSimonian and
    Laird's): each rest's mean is the bias plus its own noise (its batch-means error) plus a spread
    ``τ²`` common to the rests, estimated from how far their means scatter beyond their noise (0 where
    they do not). The pooled mean weighs each rest by its rows, so its variance is the sum of the rests'
    ``(rows/n)² (σ_r² + τ²)``. Ferraris's six holds, whose accelerometer biases lie 4e4 µg apart (its
    scale factors and misalignments, seen in six attitudes), had been given ±25 µg, each hold's noise;
    rests that agree keep their noise's figure. NaN with fewer than two rests."""
    parts = [np.concatenate([np.asarray(values[a:b], dtype=float) for a, b in g]) for g in groups]
    if len(parts) < 2:
        return np.full(np.shape(values)[1], math.nan)
    means = np.array([p.mean(axis=0) for p in parts])
    se2 = np.array([batch_means_sigma(p, [(0, len(p))]) ** 2 for p in parts])
    se2 = np.maximum(np.nan_to_num(se2, nan=np.inf), 1e-300)  # a rest too short to tell weighs nothing
    w = 1.0 / se2
    centre = (w * means).sum(axis=0) / w.sum(axis=0)
    q = (w * (means - centre) ** 2).sum(axis=0)
    c = w.sum(axis=0) - (w**2).sum(axis=0) / w.sum(axis=0)
    tau2 = np.maximum(0.0, (q - (len(parts) - 1)) / np.maximum(c, 1e-300))
    share = np.array([len(p) for p in parts], dtype=float)[:, None] / sum(len(p) for p in parts)
    finite = np.where(np.isfinite(se2), se2, 0.0)
    return np.asarray(np.sqrt((share**2 * (finite + tau2)).sum(axis=0)), dtype=float)


__all__ = ["BATCHES", "MIN_DOF", "batch_means_sigma", "pooled_rests_sigma", "white_sigma"]
