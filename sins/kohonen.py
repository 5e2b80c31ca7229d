"""The ``kohonen`` compensation strategy: a self-organising map over the readings (minisom).

The seed paper's idea for g-dependent errors: normalise the inputs, let a
Kohonen map place its codebook vectors over the input space, store for each
node the mean error of the calibration samples it wins, and predict by
interpolation among the nodes nearest to a new input (inverse-distance
weights over the ``neighbours`` nearest codebook vectors).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.compensation import Strategy
from sins.series import CalibrationData

Array = NDArray[np.float64]


class Kohonen(Strategy):
    """Self-organising-map strategy.

    Parameters
    ----------
    rows, cols : map size
    sigma : initial neighbourhood radius (nodes)
    learning_rate : initial learning rate
    iterations : training iterations (random samples)
    neighbours : codebook vectors interpolated for a prediction
    seed : minisom's random seed
    """

    name = "kohonen"

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
        self.rows, self.cols = rows, cols
        self.sigma = sigma
        self.learning_rate = learning_rate
        self.iterations = iterations
        self.neighbours = neighbours
        self.seed = seed

    def params(self) -> dict[str, Any]:
        return {
            "rows": self.rows, "cols": self.cols, "sigma": self.sigma, "learning_rate": self.learning_rate,
            "iterations": self.iterations, "neighbours": self.neighbours, "seed": self.seed,
        }  # fmt: skip

    def fit(self, data: CalibrationData) -> Kohonen:
        from minisom import MiniSom

        ok = np.isfinite(data.ref_gyro).all(axis=1) & np.isfinite(data.ref_accel).all(axis=1)
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
        winners = self._nearest(xs, codebook, 1)[:, 0]
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

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        xs = (np.hstack([gyro, accel]) - self.x_mean_) / self.x_scale_
        k = min(self.neighbours, len(self.codebook_))
        err = np.empty((len(xs), 6))
        for start in range(0, len(xs), 65536):  # bounded memory for the distance matrix
            part = xs[start : start + 65536]
            idx = self._nearest(part, self.codebook_, k)
            d = np.sqrt(((part[:, None, :] - self.codebook_[idx]) ** 2).sum(axis=2))
            w = 1.0 / np.maximum(d, 1e-9)
            weighted = (w[:, :, None] * self.node_error_[idx]).sum(axis=1)
            err[start : start + len(part)] = weighted / w.sum(axis=1)[:, None]
        return gyro - err[:, :3], accel - err[:, 3:]
