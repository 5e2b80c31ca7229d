"""``regression_rest``: the seed model, with the gyro bias taken again at every rest in operation.

A MEMS gyro's bias moves between runs (turn-on) and within one (warming): a calibration made on another
day leaves it wrong by more than any scale factor costs (BROAD's unit B: 0.01 °/s between two trials,
2° of open-loop attitude in three minutes). Where the unit stands still now and then, the readings
themselves say what the bias is: this strategy corrects with the fitted seed model and, in operation,
sets the gyro bias to the mean of the corrected readings over each rest the readings show (a zero-rate
update), causally: a rest's estimate is used from its start on, and held through the motion that
follows. A unit held in the hand does not keep its rest bias while it moves (it warms, it is shaken):
the fit measures how far the bias in motion sits from the bias at rest on the calibration data
(``motion_offset_``) and adds it during motion.

Rest is told from the corrected gyro alone (no accelerometer, no reference): the RMS of its rate over a
trailing window of :data:`WINDOW_S` below ``rest_rms_`` (from the fit's own rests) for at least
:data:`MIN_REST_S`. ``correct`` (sample by sample) applies the seed model only; ``correct_rates`` and
``correct_increments``, which see the stream, apply the rest updates. They see what they are given: a run
that corrects its stream a chunk at a time (``sins run``) starts each chunk without the rests before it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.compensation.base import Array, state_array
from sins.compensation.regression import Regression
from sins.core.series import CalibrationData, ImuIncrements, ImuRates

#: Trailing window of the rest detector, s.
WINDOW_S = 0.5
#: Shortest rest that updates the bias, s: shorter pauses in motion are not rests.
MIN_REST_S = 1.0
#: A window is at rest below this many times the 95th percentile of the fit's rest windows' RMS.
REST_MARGIN = 1.5
#: The reference is still where its rate is below this, rad/s (0.5 °/s: far below hand motion, above a
#: motion capture's differentiated noise at rest) ...
STILL_RATE = np.radians(0.5)
#: ... and its specific force within this of gravity's, shaking by less than this, m/s² (a vehicle's
#: vibration is several times more).
STILL_FORCE = 0.1


class RestAware(Regression):
    """The seed model with the gyro bias re-taken at every rest in operation (see the module docstring)."""

    name = "regression_rest"
    state_keys = (*Regression.state_keys, "rest_rms_", "motion_offset_")

    def fit_beyond(self, data: CalibrationData) -> RestAware:
        """The rest detector's threshold and the motion offset, after the seed model; returns self.

        Raises
        ------
        ValueError
            when the calibration data have no rest of :data:`MIN_REST_S` (by the reference) or no motion.
        """
        ok = data.has_reference
        omega, _ = self.correct(data.gyro, data.accel)
        dt = float(np.median(np.diff(data.t)))
        rms = _window_rms(omega, dt)
        # Still by the reference: hardly turning, and the specific force gravity's alone (a vehicle cruising
        # straight turns as little as a unit at rest, but it shakes).
        force = np.linalg.norm(_smooth(data.ref_accel, dt), axis=1)
        shake = np.linalg.norm(_smooth(data.ref_accel, dt) - data.ref_accel, axis=1)
        calm = ok & (np.linalg.norm(_smooth(data.ref_gyro, dt), axis=1) < STILL_RATE)
        if calm.any():  # (no rows hardly turning: no rest, refused below)
            calm &= (np.abs(force - np.median(force[calm])) < STILL_FORCE) & (
                _smooth(shake[:, None], dt)[:, 0] < STILL_FORCE
            )
        still = _long_runs(calm, round(MIN_REST_S / dt))
        moving = ok & ~calm
        if still.sum() < round(MIN_REST_S / dt) or moving.sum() < round(MIN_REST_S / dt):
            raise ValueError(
                f"{data.source or 'recording'}: regression_rest needs rests (≥ {MIN_REST_S:g} s, the "
                "reference still) and motion in the calibration data"
            )
        self.rest_rms_ = float(REST_MARGIN * np.percentile(rms[still], 95))
        error = omega - data.ref_gyro
        self.motion_offset_ = np.asarray(error[moving].mean(axis=0) - error[still].mean(axis=0), dtype=float)
        return self

    def check_state(self, state: dict[str, Any]) -> None:
        """The seed model's arrays, then the rest rule's: ``rest_rms_`` a rate spread (rad/s, ≥ 0) and
        ``motion_offset_`` (3,). A file without them had loaded and then failed at its first recording
        ("not fitted: call fit() first"), which a user holding a model file cannot do."""
        super().check_state(state)
        rest_rms = state_array(state, "rest_rms_", ())
        if rest_rms < 0.0:
            raise ValueError(f"state.rest_rms_ is {float(rest_rms):g}, expected a rate spread of 0 or more")
        state_array(state, "motion_offset_", (3,))

    def correct_rates(self, rates: ImuRates, temp: Array | None = None) -> ImuRates:
        """The seed model, then the gyro bias re-taken at each rest (module docstring)."""
        out = super().correct_rates(rates, temp)
        if len(rates.t) < 2:  # no step to read a window's or a rest's length by: the seed model alone
            return out
        dt = float(np.median(np.diff(rates.t)))
        return ImuRates(
            t=out.t, omega_ib_b=out.omega_ib_b - self.bias_track(out.omega_ib_b, dt), f_ib_b=out.f_ib_b
        )

    def correct_increments(self, imu: ImuIncrements, temp: Array | None = None) -> ImuIncrements:
        """The seed model, then the gyro bias re-taken at each rest (module docstring)."""
        out = super().correct_increments(imu, temp)
        if len(imu.t) < 2:  # no interval: nothing to correct beyond the seed model
            return out
        dt = np.diff(imu.t)
        track = self.bias_track(out.dtheta_b / dt[:, None], float(np.median(dt)))
        return ImuIncrements(t=out.t, dtheta_b=out.dtheta_b - track * dt[:, None], dv_b=out.dv_b)

    def bias_track(self, omega: Array, dt: float) -> Array:
        """The gyro bias left in seed-corrected rates ``omega`` (n, 3) at each sample, rad/s: the running
        mean over the current rest, else the last rest's mean plus ``motion_offset_``, else zero."""
        still = _long_runs(_window_rms(omega, dt) < self.rest_rms_, round(MIN_REST_S / dt))
        out = np.zeros_like(omega)
        edges = np.diff(np.r_[0, still.astype(np.int8), 0])
        starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
        last: NDArray[np.float64] | None = None
        previous = 0
        for a, b in zip(starts, stops, strict=True):
            if last is not None:
                out[previous:a] = last + self.motion_offset_
            running = np.nancumsum(omega[a:b], axis=0) / np.arange(1, b - a + 1)[:, None]
            out[a:b] = running
            last, previous = running[-1], int(b)
        if last is not None:
            out[previous:] = last + self.motion_offset_
        return out


def _window_rms(x: Array, dt: float) -> Array:
    """RMS of the rate's norm over a trailing window of :data:`WINDOW_S` (n,)."""
    n = max(1, round(WINDOW_S / dt))
    power = np.nancumsum(np.r_[0.0, np.sum(x * x, axis=1)])
    count = np.minimum(np.arange(1, len(x) + 1), n)
    return np.asarray(np.sqrt((power[1:] - power[np.maximum(np.arange(1, len(x) + 1) - n, 0)]) / count))


def _smooth(x: Array, dt: float) -> Array:
    """A centred moving mean over :data:`WINDOW_S` (the reference's rate is noisy sample by sample)."""
    n = max(1, round(WINDOW_S / dt))
    kernel = np.ones(n) / n
    return np.stack(
        [np.convolve(np.nan_to_num(x[:, i]), kernel, mode="same") for i in range(x.shape[1])], axis=1
    )


def _long_runs(mask: NDArray[np.bool_], shortest: int) -> NDArray[np.bool_]:
    """``mask`` with its runs of True shorter than ``shortest`` cleared."""
    out = np.asarray(mask, dtype=bool).copy()
    edges = np.diff(np.r_[0, out.astype(np.int8), 0])
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        if b - a < shortest:
            out[a:b] = False
    return out


__all__ = [
    "MIN_REST_S",
    "REST_MARGIN",
    "STILL_FORCE",
    "STILL_RATE",
    "WINDOW_S",
    "RestAware",
]
