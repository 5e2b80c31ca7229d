"""``regression_window``: the seed model, then a learned gyro correction from a window of past readings.

A static map corrects each reading from that reading alone. A hand-held MEMS gyro's bias in motion is not
its bias at rest, by an amount that depends on the motion (BROAD's unit B: 80 °/h between rests and
motion, different for slow rotation and fast translation), which no function of one reading can see. The
published gyro denoisers learn the correction from a window of past readings; this strategy does the same
with the least machinery that can: after the seed model (:class:`~sins.compensation.regression.Regression`),
each gyro axis's remaining error is a ridge regression on features of the corrected readings over the past
:data:`WINDOW_S` (the mean rate, the mean rate's size and the mean specific force in each of
:data:`BLOCKS` consecutive blocks), so the correction is causal: a reading's correction depends on the
readings before it only. The reading itself is left out on purpose: its own noise is in the target too
(the corrected reading less the reference), and a ridge on it learns to shrink the noise, a scale error
on the true rate.

The ridge's strength is chosen on :data:`FOLDS` contiguous held-back folds of the calibration data (the
learners' rule: data it did not see), and the guard is theirs too: an axis whose held-back gain over the
seed model alone is not above two standard errors (of the sum of the folds' gains) keeps the seed model. The
per-sample references of a real recording (:func:`sins.compensation.interval_fit.interval_reference`) hold
one draw of the reference's error over each interval; the folds are contiguous, so a held-back fold never
shares an interval with the rows fitted.

``correct`` (sample by sample) applies the seed model only; ``correct_rates`` and ``correct_increments``,
which see the readings in order, apply the window. The window starts at the first reading given: a
recording cut in chunks is corrected as if each chunk began the recording (the first
:data:`WINDOW_S` of each chunk see a shorter past).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sins.compensation.base import Array, state_array
from sins.compensation.regression import Regression
from sins.core.series import CalibrationData, ImuIncrements, ImuRates

#: Length of the past the correction reads, s.
WINDOW_S = 2.0
#: Consecutive blocks the window is cut into (each gives its mean rate, rate size and specific force).
BLOCKS = 4
#: Features of each block: mean rate (3), the mean rate's size (1), mean specific force (3).
PER_BLOCK = 7
#: Features: the blocks'.
FEATURES = BLOCKS * PER_BLOCK
#: Contiguous folds the ridge's strength and the guard are judged on.
FOLDS = 5
#: Ridge strengths tried, relative to the features' (standardised) variance per row.
RIDGE = (1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0)
#: An axis keeps the window only where its held-back gain is above this many standard errors.
GUARD_SE = 2.0


class GyroWindow(Regression):
    """The seed model, then a gyro correction from a window of past readings: what
    :class:`WindowRegression` (a ridge) and :class:`~sins.compensation.window_net.WindowNet` (networks) share.
    A subclass gives :meth:`window_error`; the readings are corrected in order, the window read from the
    seed-corrected readings."""

    def window_error(self, omega_ib_b: Array, f_ib_b: Array, dt: float) -> Array:
        """The gyro error (n, 3), rad/s, the window predicts in seed-corrected readings (every ``dt`` s)."""
        raise NotImplementedError

    def correct_rates(self, rates: ImuRates, temp: Array | None = None) -> ImuRates:
        """The seed model, then the window's gyro correction."""
        out = super().correct_rates(rates, temp)
        if len(rates.t) < 2:  # no step to read a window's or a rest's length by: the seed model alone
            return out
        error = self.window_error(out.omega_ib_b, out.f_ib_b, float(np.median(np.diff(rates.t))))
        return ImuRates(t=out.t, omega_ib_b=out.omega_ib_b - error, f_ib_b=out.f_ib_b)

    def correct_increments(self, imu: ImuIncrements, temp: Array | None = None) -> ImuIncrements:
        """The seed model, then the window's gyro correction on the mean rates."""
        out = super().correct_increments(imu, temp)
        if len(imu.t) < 2:  # no interval: nothing to correct beyond the seed model
            return out
        dt = np.diff(imu.t)
        error = self.window_error(out.dtheta_b / dt[:, None], out.dv_b / dt[:, None], float(np.median(dt)))
        return ImuIncrements(t=out.t, dtheta_b=out.dtheta_b - error * dt[:, None], dv_b=out.dv_b)


class WindowRegression(GyroWindow):
    """The seed model, then a ridge correction of each gyro axis from a window of past readings (see
    the module docstring)."""

    name = "regression_window"
    state_keys = (*GyroWindow.state_keys, "feature_mean_", "feature_scale_", "ridge_", "coef_",
                  "held_back_gain_", "held_back_gain_se_")  # fmt: skip

    def fit_beyond(self, data: CalibrationData) -> WindowRegression:
        """The window's ridge per gyro axis, after the seed model; returns self.

        Raises
        ------
        ValueError
            when the calibration data hold less than ``2 FOLDS`` windows with a reference.
        """
        omega, accel = self.correct(data.gyro, data.accel)
        dt = float(np.median(np.diff(data.t)))
        x = window_features(omega, accel, dt)
        ok = data.has_reference
        if ok.sum() < FOLDS * 2 * round(WINDOW_S / dt):
            raise ValueError(
                f"{data.source or 'recording'}: regression_window needs at least {FOLDS * 2 * WINDOW_S:g} s "
                "of readings with a reference"
            )
        x, y = x[ok], (omega - data.ref_gyro)[ok]
        self.feature_mean_ = x.mean(axis=0)
        self.feature_scale_ = np.where(x.std(axis=0) > 0, x.std(axis=0), 1.0)
        z = (x - self.feature_mean_) / self.feature_scale_
        fold = np.minimum(np.arange(len(z)) * FOLDS // len(z), FOLDS - 1)
        self.ridge_ = np.zeros(3)
        self.coef_ = np.zeros((FEATURES + 1, 3))
        self.held_back_gain_ = np.zeros(3)
        self.held_back_gain_se_ = np.zeros(3)
        for axis in range(3):
            ridge, gain, se = _choose(z, y[:, axis], fold)
            self.ridge_[axis], self.held_back_gain_[axis], self.held_back_gain_se_[axis] = ridge, gain, se
            if gain > GUARD_SE * se:
                self.coef_[:, axis] = _ridge(z, y[:, axis], ridge)
        return self

    @property
    def window_axes(self) -> list[str]:
        """The gyro axes whose window passed the guard."""
        return [a for a, c in zip("xyz", self.coef_.T, strict=True) if np.any(c)]

    def window_error(self, omega_ib_b: Array, f_ib_b: Array, dt: float) -> Array:
        """The gyro error (n, 3), rad/s, the window predicts in seed-corrected readings (every ``dt`` s)."""
        z = (window_features(omega_ib_b, f_ib_b, dt) - self.feature_mean_) / self.feature_scale_
        return np.asarray(z @ self.coef_[1:] + self.coef_[0])

    def check_state(self, state: dict[str, Any]) -> None:
        """The seed model's arrays, then the window's: ``coef_`` ({FEATURES}+1, 3), ``feature_mean_`` and
        ``feature_scale_`` ({FEATURES},), ``ridge_`` (3,)."""
        super().check_state(state)
        state_array(state, "coef_", (FEATURES + 1, 3))
        for key in ("feature_mean_", "feature_scale_"):
            state_array(state, key, (FEATURES,))
        state_array(state, "ridge_", (3,))


def window_features(omega_ib_b: Array, f_ib_b: Array, dt: float) -> Array:
    """The causal features (n, :data:`FEATURES`) of readings sampled every ``dt`` s: for each of
    :data:`BLOCKS` blocks of the :data:`WINDOW_S` before each reading (nearest first, the reading itself
    not in them), the mean rate, its size and the mean specific force. Before the first reading the
    window holds the first reading (a recording starts with what it reads)."""
    n = len(omega_ib_b)
    block = max(1, round(WINDOW_S / BLOCKS / dt))
    both = np.hstack([omega_ib_b, f_ib_b])
    sums = np.vstack([np.zeros((1, 6)), np.nancumsum(both, axis=0)])
    row = np.arange(n)
    out = np.empty((n, FEATURES))
    for k in range(BLOCKS):
        # Block k covers rows [row - (k+1)·block, row - k·block); rows before 0 read as row 0.
        hi, lo = row - k * block, row - (k + 1) * block
        before = np.maximum(-lo, 0) - np.maximum(-hi, 0)  # rows of the block before the recording
        hi_c, lo_c = np.maximum(hi, 0), np.maximum(lo, 0)
        mean = (sums[hi_c] - sums[lo_c] + before[:, None] * both[0]) / block
        out[:, k * PER_BLOCK : k * PER_BLOCK + 3] = mean[:, :3]
        out[:, k * PER_BLOCK + 3] = np.linalg.norm(mean[:, :3], axis=1)
        out[:, k * PER_BLOCK + 4 : (k + 1) * PER_BLOCK] = mean[:, 3:]
    return out


def _ridge(z: Array, y: Array, ridge: float) -> Array:
    """Intercept and coefficients (1 + features,) of the ridge on standardised features ``z``."""
    mean = y.mean()
    gram = z.T @ z + ridge * len(z) * np.eye(z.shape[1])
    return np.r_[mean, np.linalg.solve(gram, z.T @ (y - mean))]


def _choose(z: Array, y: Array, fold: Array) -> tuple[float, float, float]:
    """The ridge strength with the least held-back squared error over contiguous folds, and its gain over
    the seed model alone (the folds' own means: a constant is the seed model's bias) with the gain's
    standard error over the folds."""
    best: tuple[float, Array] | None = None
    for ridge in RIDGE:
        gains = np.empty(FOLDS)
        for f in range(FOLDS):
            held = fold == f
            coef = _ridge(z[~held], y[~held], ridge)
            predicted = z[held] @ coef[1:] + coef[0]
            base = y[held] - y[~held].mean()
            gains[f] = np.sum(base**2) - np.sum((y[held] - predicted) ** 2)
        if best is None or gains.sum() > best[1].sum():
            best = (ridge, gains)
    assert best is not None
    ridge, gains = best
    return ridge, float(gains.sum()), float(np.sqrt(FOLDS) * gains.std(ddof=1))


__all__ = [
    "BLOCKS",
    "FEATURES",
    "FOLDS",
    "GUARD_SE",
    "PER_BLOCK",
    "RIDGE",
    "WINDOW_S",
    "GyroWindow",
    "WindowRegression",
    "window_features",
]
