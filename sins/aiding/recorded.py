"""Real recordings aided by their reference: the IMU navigated by the GNSS/INS filter with the reference's
positions as fixes, through outages opened in them.

:func:`aided_through_outages` takes any recording's increments, its reference at the IMU's place and
the fixes; :func:`psins_vehicle_outages` prepares the PSINS vehicle recording (its MEMS, the FOG-INS
solution as the reference) for it. Beside :mod:`sins.compensation.referenced` (compensation judged against a
recording's reference), which it does not import.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sins.aiding import ekf, gnss
from sins.aiding.outages import EDGE_S, OutageError, outage_errors, window_rows
from sins.core import rotation
from sins.core.series import ImuIncrements, NavSeries
from sins.nav import strapdown
from sins.nav.metrics import nav_errors


@dataclass(frozen=True)
class RecordingOutages:
    """A real recording's IMU aided by its reference position as fixes, with outages opened in them.

    ``outages`` are each window's horizontal error at its end and its maximum (:class:`OutageError`),
    ``predicted_m`` the filter's horizontal 1σ at each window's end, ``free_m`` the error of the raw
    readings (no bias correction) integrated over each window from the aided state at its start: what
    the filter's estimate of the biases is worth. ``gyro_bias`` and ``accel_bias`` are the final
    estimates (rad/s, m/s²); ``rms_m`` the horizontal RMS over the run; ``fixes`` and ``rejected`` the
    fixes given and those the gate refused.
    """

    outages: tuple[OutageError, ...]
    predicted_m: tuple[float, ...]
    free_m: tuple[float, ...]
    gyro_bias: NDArray[np.float64]
    accel_bias: NDArray[np.float64]
    rms_m: float
    fixes: int
    rejected: int


def aided_through_outages(
    imu: ImuIncrements,
    reference: NavSeries,
    fixes: gnss.GnssFixes,
    config: ekf.FilterConfig,
    outages: Sequence[tuple[float, float]],
) -> RecordingOutages:
    """``imu`` aided by ``fixes`` (outage windows already taken out of them) from ``reference``'s state
    at ``imu.t[0]``; errors against ``reference``, which is at the IMU's place and spans the IMU.

    Windows (:func:`sins.aiding.outages.window_rows`) that hold no IMU sample are left out of every
    tuple of the result.
    """
    result = ekf.run(imu, fixes, config, strapdown.InitialState.from_series(reference.interpolate(imu.t[:1])))
    at_imu = reference.interpolate(imu.t)
    horizontal = nav_errors(result.nav, at_imu).horizontal_m
    windows = outage_errors(outages, imu.t, horizontal)
    predicted, free = [], []
    for window in windows:
        # The filter's last prediction at or before the fix that closes the window.
        row = int(np.flatnonzero((result.t_cov <= window.end_s + EDGE_S) & ~result.after_update)[-1])
        predicted.append(float(np.hypot(*result.sigma()[row, :2])))
        # The raw readings from the aided state at the window's start (after its last fix).
        inside = window_rows(imu.t, window.start_s, window.end_s)
        k, last = int(inside[0]) - 1, int(inside[-1])
        seg = imu.steps(k, last)
        alone = strapdown.integrate(seg, strapdown.InitialState.from_series(result.nav, k))
        free.append(float(nav_errors(alone.at(-1), at_imu.at(last)).horizontal_m[0]))
    return RecordingOutages(
        outages=tuple(windows), predicted_m=tuple(predicted), free_m=tuple(free),
        gyro_bias=result.gyro_bias[-1], accel_bias=result.accel_bias[-1],
        rms_m=float(np.sqrt(np.mean(horizontal**2))), fixes=len(fixes), rejected=result.rejected,
    )  # fmt: skip


def psins_vehicle_outages(
    outages: tuple[tuple[float, float], ...] = ((30.0, 45.0), (60.0, 80.0), (85.0, 95.0)),
    *,
    rate_hz: float = 1.0,
    sigma_m: float = 0.5,
    grade: str = "consumer",
    root: str | os.PathLike[str] | None = None,
) -> RecordingOutages:
    """The PSINS vehicle recording's MEMS aided by the FOG-INS position as fixes, through outages.

    The MEMS increments are integrated from the FOG-INS state (moved to the MEMS's place) at their
    first time inside the reference; fixes are the FOG-INS position at ``rate_hz`` (its place, so the
    lever arm is the reader's estimate of it, in MEMS axes) with ``sigma_m`` told to the filter; the
    filter is tuned to ``grade`` (the file's MEMS has ≈ 0.06 °/s gyro and 5 mg accelerometer biases:
    consumer grade). Errors are against the FOG-INS solution moved to the MEMS's place.

    Raises
    ------
    SinsInputError
        the recording is not under ``root`` (default ``SINS_DATA`` or ``../shared/data``), or an outage
        window ends before it starts.
    """
    from sins.io.datasets.psins_vehicle import psins_alignment, read_psins_vehicle

    data, fog = read_psins_vehicle(root)
    assert fog is not None  # the recording holds its FOG-INS solution
    arm = psins_alignment(root).lever_arm_m  # the MEMS from the FOG-INS, MEMS axes
    dt = 0.01  # the MEMS's increments: row k covers the 10 ms before t + 5 ms
    t_end = data.t + 0.5 * dt
    lat, lon, h = gnss.offset_position(fog.lat, fog.lon, fog.h, rotation.dcm_from_quat(fog.q_nb) @ arm)
    reference = NavSeries(t=fog.t, lat=lat, lon=lon, h=h, v_n=fog.v_n, q_nb=fog.q_nb)
    t = np.r_[t_end[0] - dt, t_end]
    rows = np.flatnonzero((t >= reference.t[0]) & (t <= reference.t[-1]))
    k0, k1 = int(rows[0]), int(rows[-1])
    imu = ImuIncrements(t=t[k0 : k1 + 1], dtheta_b=data.gyro[k0:k1] * dt, dv_b=data.accel[k0:k1] * dt)
    fix_t = np.arange(np.ceil(imu.t[0] * rate_hz), imu.t[-1] * rate_hz) / rate_hz
    at = fog.interpolate(fix_t)
    fixes = gnss.GnssFixes(
        t=fix_t, lat=at.lat, lon=at.lon, h=at.h, v_n=np.full((len(fix_t), 3), np.nan),
        sigma_pos_m=np.full(3, sigma_m), lever_arm_b=-arm,
    ).without([gnss.Outage(a, b) for a, b in outages])  # fmt: skip
    config = ekf.FilterConfig.for_grade(
        grade, position_sigma_m=sigma_m, velocity_sigma_mps=0.1, tilt_sigma_rad=np.radians(0.5),
        heading_sigma_rad=np.radians(1.0),
    )  # fmt: skip
    return aided_through_outages(imu, reference, fixes, config, outages)


__all__ = [
    "RecordingOutages",
    "aided_through_outages",
    "psins_vehicle_outages",
]
