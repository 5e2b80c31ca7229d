"""``kohonen_pure``: the seed paper's self-organising map from readings to errors (minisom), kept so that
its question can still be asked.

The seed paper's idea for g-dependent errors: normalise the inputs, let a Kohonen map place its codebook
vectors over the input space, store for each node the mean error of the calibration samples it wins,
and predict by interpolation among the nodes nearest to a new input (inverse-distance weights over the
``neighbours`` nearest codebook vectors). ``kohonen`` (:mod:`sins.compensation.kohonen`) learns what the
seed model leaves instead, and is the one to pick on a rig.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import Any, ClassVar

import numba
import numpy as np
from numpy.typing import NDArray

from sins.compensation.base import SEED_RANGE, ParamRange, Strategy, state_array
from sins.compensation.kohonen import MAX_SIDE, check_map, row_squared_distances
from sins.core.series import CalibrationData
from sins.imu import calibration

Array = NDArray[np.float64]

#: Rows per block of the fit's (rows, nodes) distance matrices: 8192 × 400 nodes is 26 MB a matrix, where
#: a 51,000-row rig whole took 160 MB each, three at a time (each row's nearest nodes are its own).
_ROWS = 8192
#: The most nodes a prediction blends.
MAX_NEIGHBOURS = 64


class Kohonen(Strategy):
    """The seed paper's self-organising map from readings to errors, ``kohonen_pure`` (module docstring).

    Parameters
    ----------
    rows, cols : map size
    sigma : initial neighbourhood radius (nodes)
    learning_rate : initial learning rate
    iterations : training iterations (random samples)
    neighbours : codebook vectors interpolated for a prediction
    seed : minisom's random seed
    """

    name = "kohonen_pure"
    state_keys = (*Strategy.state_keys, "accel_seed_", "gyro_seed_", "x_mean_", "x_scale_", "codebook_",
                  "node_error_", "node_count_")  # fmt: skip
    param_ranges: ClassVar[dict[str, ParamRange]] = {
        "rows": ParamRange(1, MAX_SIDE, whole=True),
        "cols": ParamRange(1, MAX_SIDE, whole=True),
        "sigma": ParamRange(0, 100, above=True),
        "learning_rate": ParamRange(0, 10, above=True),
        "iterations": ParamRange(1, 10**8, whole=True),
        "neighbours": ParamRange(1, MAX_NEIGHBOURS, whole=True),
        "seed": SEED_RANGE,
    }

    def __init__(
        self,
        rows: int = 20,
        cols: int = 20,
        sigma: float = 2.0,
        learning_rate: float = 0.5,
        iterations: int = 60000,
        neighbours: int = 4,
        seed: int = 0,
    ) -> None:
        self.rows, self.cols = rows, cols  # kept as given; check_params holds them (param_ranges)
        self.sigma = sigma
        self.learning_rate = learning_rate
        self.iterations = iterations
        self.neighbours = neighbours
        self.seed = seed

    def fit(self, data: CalibrationData) -> Kohonen:
        """Train the map on standardised readings and store each node's mean error; returns self."""
        from minisom import MiniSom

        data.check_readings()
        calibration.fit_seed_model(data)  # rows that do not determine a linear model teach no map
        ok = data.has_reference
        x = np.hstack([data.gyro, data.accel])[ok]
        y = np.hstack([data.gyro - data.ref_gyro, data.accel - data.ref_accel])[ok]
        if len(x) < self.rows * self.cols:
            raise ValueError(f"{data.source or 'recording'}: fewer samples than map nodes")
        self.x_mean_ = x.mean(axis=0)
        self.x_scale_ = np.where(x.std(axis=0) > 0, x.std(axis=0), 1.0)
        xs = (x - self.x_mean_) / self.x_scale_
        som = MiniSom(self.rows, self.cols, xs.shape[1], sigma=self.sigma, learning_rate=self.learning_rate,
                      random_seed=self.seed)  # fmt: skip
        som.pca_weights_init(xs)
        som.train_random(xs, self.iterations)
        codebook = som.get_weights().reshape(-1, xs.shape[1])
        winners = np.concatenate(
            [self._nearest(xs[a : a + _ROWS], codebook, 1)[:, 0] for a in range(0, len(xs), _ROWS)]
        )
        sums = np.zeros((len(codebook), 6))
        np.add.at(sums, winners, y)
        counts = np.bincount(winners, minlength=len(codebook))
        values = np.where(counts[:, None] > 0, sums / np.maximum(counts, 1)[:, None], np.nan)
        # Nodes that won nothing take the mean of the nodes nearest to them that did.
        empty = np.flatnonzero(counts == 0)
        if empty.size:
            filled = np.flatnonzero(counts > 0)
            near = self._nearest(codebook[empty], codebook[filled], min(3, filled.size))
            values[empty] = values[filled][near].mean(axis=1)
        self.codebook_, self.node_error_, self.node_count_ = codebook, values, counts.astype(float)
        return self

    @staticmethod
    def _nearest(x: Array, codebook: Array, k: int) -> NDArray[np.intp]:
        d2 = (x * x).sum(axis=1)[:, None] - 2.0 * x @ codebook.T + (codebook * codebook).sum(axis=1)[None, :]
        return np.argsort(d2, axis=1)[:, :k] if k > 1 else np.argmin(d2, axis=1)[:, None]

    def check_state(self, state: dict[str, Any]) -> None:
        """A map of ``rows`` × ``cols`` nodes (:func:`check_map`): ``codebook_`` and ``node_error_``
        (nodes, 6), ``node_count_`` (nodes,), the inputs' scales (6, none zero)."""
        super().check_state(state)
        nodes = check_map(self.rows, "params.rows") * check_map(self.cols, "params.cols")
        for key, shape in (("codebook_", (nodes, 6)), ("node_error_", (nodes, 6)), ("node_count_", (nodes,)),
                           ("x_mean_", (6,)), ("x_scale_", (6,))):  # fmt: skip
            state_array(state, key, shape)
        if not (state_array(state, "x_scale_", (6,)) != 0).all():
            raise ValueError("state.x_scale_ holds a zero (the inputs are divided by it)")

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """Subtract the ``neighbours`` nearest nodes' errors, inverse-distance weighted (``temp`` unused):
        a compiled pass over the rows (:func:`_inverse_distance`), two threads on halves from
        :data:`_THREADED_ROWS` rows. numpy's distance matrix, sorted row by row for the four nearest of
        400 nodes, had corrected 0.22 M samples/s (EuRoC's model, ``tools/bench_correction.py``)."""
        xs = np.ascontiguousarray((np.hstack([gyro, accel]) - self.x_mean_) / self.x_scale_)
        k = min(self.neighbours, len(self.codebook_))
        err = np.empty((len(xs), 6))
        codebook_t = np.ascontiguousarray(np.asarray(self.codebook_, dtype=float).T)
        node_error = np.ascontiguousarray(self.node_error_, dtype=float)
        halves = [slice(0, len(xs) // 2), slice(len(xs) // 2, len(xs))] if len(xs) >= _THREADED_ROWS else []
        if halves:
            with ThreadPoolExecutor(2) as pool:
                list(pool.map(lambda h: _inverse_distance(xs[h], codebook_t, node_error, k, err[h]), halves))
        else:
            _inverse_distance(xs, codebook_t, node_error, k, err)
        return gyro - err[:, :3], accel - err[:, 3:]


#: The rows from which ``kohonen_pure``'s correction runs on two threads (each half compiled, GIL let go).
_THREADED_ROWS = 65_536


@numba.njit(cache=True, nogil=True)
def _inverse_distance(
    xs: Array, codebook_t: Array, node_error: Array, k: int, out: Array
) -> None:  # pragma: no cover  (compiled)
    """Into ``out`` (n, e): each row of ``xs`` (n, d)'s ``k`` nearest nodes of the map (``codebook_t``
    (d, m): its codebook transposed, :func:`~sins.compensation.kohonen.row_squared_distances`) by
    Euclidean distance (ties to the lower node), their ``node_error`` rows (m, e) weighted by the inverse
    distance (at least 1e-9), summed nearest first and divided by the weights' sum."""
    n, m = xs.shape[0], codebook_t.shape[1]
    d2 = np.empty(m)
    best_d2, best_i = np.empty(k), np.empty(k, dtype=np.int64)
    for r in range(n):
        row_squared_distances(xs, r, codebook_t, d2)
        count = 0
        for j in range(m):
            if count < k:
                pos = count
                count += 1
            elif d2[j] < best_d2[k - 1]:
                pos = k - 1
            else:
                continue
            while pos > 0 and best_d2[pos - 1] > d2[j]:
                best_d2[pos], best_i[pos] = best_d2[pos - 1], best_i[pos - 1]
                pos -= 1
            best_d2[pos], best_i[pos] = d2[j], j
        w_sum = 0.0
        out[r, :] = 0.0
        for q in range(count):
            w = 1.0 / max(np.sqrt(best_d2[q]), 1e-9)
            w_sum += w
            for e in range(out.shape[1]):
                out[r, e] += w * node_error[best_i[q], e]
        for e in range(out.shape[1]):
            out[r, e] /= w_sum


__all__ = [
    "MAX_NEIGHBOURS",
    "Kohonen",
]
