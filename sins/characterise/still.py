"""Where a unit stood still, read from its own readings; and whether a "static" recording moved.

**Still stretches** (:func:`still_rows`). The readings are cut into windows of :data:`WINDOW_S` (at least
:data:`MIN_WINDOW_ROWS` rows). A unit at rest reads a constant input plus its noise, so a window is still
when, on every channel, its spread is at most :data:`QUIET_FACTOR` times the channel's quiet level (the
:data:`QUIET_PERCENTILE`-th percentile of the windows' spreads: the recording must rest a tenth of the
time or more), and its mean gyro reading lies within :data:`MEAN_SIGMAS` standard errors (of a window's
mean at the quiet spread) of the median of the quiet windows' means, or within :data:`GYRO_MEAN_TOL`: a
slow, smooth turn has a quiet spread but not the resting rate. Accelerometer means are not compared: a
hand-held unit rests at other tilts between its motions. Each run of still windows loses one window at
either end (the motion starting and stopping).

**Motion in a recording said to be static** (:func:`motion`). Each channel's mean over windows of
:data:`MOTION_WINDOW_S` must stay within :data:`GYRO_MOTION` (gyros) or :data:`ACCEL_MOTION`
(accelerometers) of its median over the recording, or within :data:`MEAN_SIGMAS` standard errors of a
window's mean, whichever is wider. No unit at rest drifts so far (1 °/s is 3,600 °/h; 0.5 m/s² is 51 mg,
beyond a consumer accelerometer's bias over temperature), and a vehicle's turns and starts, or a hand's
tilt, exceed it at once.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from sins.imu import CHANNELS, DEG

Array = NDArray[np.float64]

#: Window of the still test, s (a quarter of a second: short against a rest, long against a sample).
WINDOW_S = 0.25
MIN_WINDOW_ROWS = 16
#: A still window's spread is at most this many times its channel's quiet level ...
QUIET_FACTOR = 2.0
#: ... the spread below which this percentage of the windows lie.
QUIET_PERCENTILE = 10.0
#: A still window's mean gyro reading lies this many standard errors from the resting one, ...
MEAN_SIGMAS = 8.0
#: ... or this close to it, rad/s (0.05 °/s: above any unit's bias drift over a recording's rests).
GYRO_MEAN_TOL = 0.05 * DEG
#: The motion test's window, s, and how far a window's mean may depart from the recording's median.
MOTION_WINDOW_S = 1.0
GYRO_MOTION = 1.0 * DEG
ACCEL_MOTION = 0.5


def _windows(values: Array, rows: int) -> tuple[Array, Array]:
    """Mean and standard deviation (w, 6) of consecutive windows of ``rows`` rows (the tail dropped), one
    channel at a time (a temporary of one channel, not six: 80 MB, not 480, at 10 million rows)."""
    count = len(values) // rows
    mean, spread = np.empty((count, values.shape[1])), np.empty((count, values.shape[1]))
    for i in range(values.shape[1]):
        blocks = values[: count * rows, i].reshape(count, rows)
        mean[:, i], spread[:, i] = blocks.mean(axis=1), blocks.std(axis=1)
    return mean, spread


def still_rows(readings: Array, dt: float) -> NDArray[np.bool_]:
    """Rows (n,) where the unit stood still by its own readings (n, 6), rad/s and m/s² (see the module's
    text). All False when the recording is too short for two windows."""
    n = len(readings)
    rows = max(MIN_WINDOW_ROWS, round(WINDOW_S / dt))
    out = np.zeros(n, dtype=bool)
    if n < 2 * rows or not np.isfinite(readings).all():
        return out
    mean, spread = _windows(readings, rows)
    quiet_level = np.percentile(spread, QUIET_PERCENTILE, axis=0)
    quiet = np.all(spread <= QUIET_FACTOR * np.maximum(quiet_level, 1e-300), axis=1)
    if not quiet.any():
        return out
    rest = np.median(mean[quiet, :3], axis=0)
    tol = np.maximum(MEAN_SIGMAS * quiet_level[:3] / math.sqrt(rows), GYRO_MEAN_TOL)
    still = quiet & np.all(np.abs(mean[:, :3] - rest) <= tol, axis=1)
    # One window off either end of each still run: the motion starting and stopping.
    inner = still.copy()
    inner[1:] &= still[:-1]
    inner[:-1] &= still[1:]
    out[: len(inner) * rows] = np.repeat(inner, rows)
    return out


def motion(t: Array, readings: Array) -> str | None:
    """Where a recording said to be static moves (see the module's text), in words; None where it does not.

    ``t`` (n,) s, ``readings`` (n, 6) rad/s and m/s². The words name the channel, how far its window mean
    departs from its median, and when.
    """
    n = len(readings)
    dt = float(np.median(np.diff(t))) if n > 1 else 1.0
    rows = max(MIN_WINDOW_ROWS, round(MOTION_WINDOW_S / dt))
    if n < 2 * rows or not np.isfinite(readings).all():
        return None
    mean, spread = _windows(readings, rows)
    median = np.median(mean, axis=0)
    noise = np.median(spread, axis=0) / math.sqrt(rows)
    limit = np.maximum(np.r_[[GYRO_MOTION] * 3, [ACCEL_MOTION] * 3], MEAN_SIGMAS * noise)
    departure = np.abs(mean - median) / limit
    window, channel = np.unravel_index(int(np.argmax(departure)), departure.shape)
    if departure[window, channel] <= 1.0:
        return None
    size = float(np.abs(mean[window, channel] - median[channel]))
    gyro = channel < 3
    text = f"{size / DEG:.3g} °/s" if gyro else f"{size:.3g} m/s²"
    bound = f"{limit[channel] / DEG:.3g} °/s" if gyro else f"{limit[channel]:.3g} m/s²"
    start = float(t[window * rows])
    return (
        f"{CHANNELS[channel]}'s {MOTION_WINDOW_S:g}-s mean departs from its median by {text} at t = "
        f"{start:.6g} s (a unit at rest stays within {bound})"
    )


__all__ = [
    "ACCEL_MOTION",
    "GYRO_MEAN_TOL",
    "GYRO_MOTION",
    "MEAN_SIGMAS",
    "MIN_WINDOW_ROWS",
    "MOTION_WINDOW_S",
    "QUIET_FACTOR",
    "QUIET_PERCENTILE",
    "WINDOW_S",
    "motion",
    "still_rows",
]
