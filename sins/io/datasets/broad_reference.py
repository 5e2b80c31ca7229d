"""A BROAD trial as a :class:`~sins.core.series.ReferencedRecording`: the IMU's readings beside the optical
motion capture's orientation and position at every sample where the markers were seen.

Unlike :func:`~sins.io.datasets.broad._read_broad`, nothing is differentiated: the optical data are the
reference as they are (their orientation and the velocity of their position), so compensation is fitted
on the angle and velocity changes between optical epochs (:mod:`sins.compensation.interval_fit`), where the
optical noise does not grow with the sample rate. The judged rows are BROAD's own ``movement`` phases, on
which the benchmark scores orientation filters.
"""

from __future__ import annotations

import math
import os

# scipy's io, signal and interpolate modules are imported in the functions that use them: ~0.6 s at
# import, which every command paid for any recording (tools/bench_startup.py).
import numpy as np
from numpy.typing import NDArray

from sins.core import earth, rotation
from sins.core.series import ImuIncrements, NavSeries, ReferencedRecording
from sins.errors import SinsInputError
from sins.io.datasets.broad import (
    BROAD_FOLDER,
    BROAD_HEIGHT_M,
    BROAD_LAT_DEG,
    BROAD_RATE_HZ,
    _load,
    _longest_run,
    _stem,
    sensor_of,
)
from sins.io.datasets.root import dataset_file

Array = NDArray[np.float64]

#: Assumed longitude of the recording, deg (TU Berlin; the files do not say). Only the reference's
#: position uses it, and nothing here depends on it.
BROAD_LON_DEG = 13.33
#: ENU (the optical frame, z up) to NED: a proper rotation swapping east and north and turning up down.
_ENU_TO_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: Half-window of the optical position's velocity fit (quadratic Savitzky–Golay), samples: 0.1 s in all,
#: the velocity's noise from the position's (sub-millimetre) kept far below the accelerometer's.
_VELOCITY_HALF_WINDOW = 3
_VELOCITY_POLYORDER = 2


def _read_broad_reference(trial: str, root: str | os.PathLike[str] | None = None) -> ReferencedRecording:
    """One BROAD trial's readings beside its optical reference, nothing differentiated but the position.

    Readings: the longest stretch of rows with finite gyro and accelerometer readings, as increments by
    the trapezoid rule between samples (``imu.t`` = the sample times ``row / 285.714`` s, so the step
    boundaries are the samples). Reference, at every row of that stretch where the optical orientation
    and position are finite: the attitude of the IMU's own axes in NED (``opt_quat`` rotates IMU vectors
    into the optical ENU frame; turned into NED), the velocity of a quadratic Savitzky–Golay fit of the
    position over 0.1 s within each run of valid rows (runs shorter than the window left out), and a
    position at the assumed :data:`~sins.io.datasets.broad.BROAD_LAT_DEG`, :data:`BROAD_LON_DEG`,
    :data:`~sins.io.datasets.broad.BROAD_HEIGHT_M` moved by the optical position. ``judged``: BROAD's
    ``movement`` flag at each sample. No clock offset is applied: the interval fit estimates it.

    Raises
    ------
    SinsInputError
        one line: as :func:`~sins.io.datasets.broad._read_broad`, or a file without ``movement``, or too
        few rows with a reference.
    """
    stem = _stem(trial, root)
    path = dataset_file(BROAD_FOLDER, f"{stem}.mat", root)
    gyr, acc, quat, pos = _load(str(path))
    movement = _movement(str(path), len(gyr))
    start, stop = _longest_run(np.asarray(np.isfinite(np.hstack([gyr, acc])).all(axis=1), dtype=bool))
    rows = np.arange(start, stop)
    t = rows / BROAD_RATE_HZ
    valid = np.asarray(np.isfinite(np.hstack([quat, pos])[rows]).all(axis=1), dtype=bool)
    if np.count_nonzero(valid) < 4 * _VELOCITY_HALF_WINDOW:
        raise SinsInputError(f"{path}: {np.count_nonzero(valid)} rows with an optical reference; too few")
    dt = np.diff(t)[:, None]
    imu = ImuIncrements(
        t=t,
        dtheta_b=0.5 * (gyr[rows][:-1] + gyr[rows][1:]) * dt,
        dv_b=0.5 * (acc[rows][:-1] + acc[rows][1:]) * dt,
    )
    epochs, v_enu = _velocity(pos[rows], valid)
    q_enu_b = quat[rows][epochs][:, [1, 2, 3, 0]]
    q_ned_enu = rotation.quat_from_dcm(_ENU_TO_NED)
    p_ned = pos[rows][epochs] @ _ENU_TO_NED.T
    lat0, lon0 = math.radians(BROAD_LAT_DEG), math.radians(BROAD_LON_DEG)
    r_m, r_n = earth.radii(lat0)
    reference = NavSeries(
        t=t[epochs],
        lat=lat0 + p_ned[:, 0] / (r_m + BROAD_HEIGHT_M),
        lon=lon0 + p_ned[:, 1] / ((r_n + BROAD_HEIGHT_M) * math.cos(lat0)),
        h=BROAD_HEIGHT_M - p_ned[:, 2],
        v_n=v_enu @ _ENU_TO_NED.T,
        q_nb=rotation.quat_normalize(rotation.quat_multiply(q_ned_enu, q_enu_b)),
    )
    return ReferencedRecording(
        imu=imu,
        reference=reference,
        judged=movement[rows].astype(bool),
        sensor=sensor_of(stem),
        reference_name="optical motion capture (OptiTrack, 8 cameras)",
        source=str(path),
        heading_known=False,
    )


def _movement(path: str, n: int) -> NDArray[np.bool_]:
    """BROAD's ``movement`` flag (n,): 1 in the movement phases its benchmark scores, 0 at rest."""
    import scipy.io

    mat = scipy.io.loadmat(path, squeeze_me=True, variable_names=["movement"])
    flag = np.asarray(mat.get("movement", np.empty(0)), dtype=float).reshape(-1)
    if flag.shape != (n,) or not np.isin(flag, (0.0, 1.0)).all():
        raise SinsInputError(f"{path}: variable 'movement': expected {n} flags of 0 or 1")
    return flag == 1.0


def _velocity(pos: Array, valid: NDArray[np.bool_]) -> tuple[NDArray[np.intp], Array]:
    """The rows with a velocity (valid runs at least a window long) and that velocity, ENU, m/s."""
    from scipy.signal import savgol_filter

    n_window = 2 * _VELOCITY_HALF_WINDOW + 1
    edges = np.diff(np.r_[0, valid.astype(np.int8), 0])
    keep, velocity = [], []
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        if b - a < n_window:
            continue
        keep.append(np.arange(a, b))
        velocity.append(
            savgol_filter(pos[a:b], n_window, _VELOCITY_POLYORDER, deriv=1, delta=1.0 / BROAD_RATE_HZ, axis=0)
        )
    return np.concatenate(keep), np.vstack(velocity)


__all__ = [
    "BROAD_LON_DEG",
]
