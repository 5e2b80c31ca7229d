"""Navigation errors against a truth, and their summary.

Errors are estimate − truth. Position errors are in metres along the truth's
local north, east and down: ``δN = δlat (R_M + h)``, ``δE = δlon (R_N + h) cos lat``,
``δD = -δh``; linearised, which is within 0.01 % for errors below 100 km.
Attitude errors are the differences of ZYX Euler angles, wrapped to ±180°.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from sins import earth, rotation
from sins.series import NavSeries

Array = NDArray[np.float64]

#: One international nautical mile, m.
NAUTICAL_MILE_M = 1852.0


@dataclass(frozen=True)
class NavErrors:
    """Error series at ``n`` common times.

    Attributes
    ----------
    t : (n,) s
    pos_ned_m : (n, 3) north, east, down position error, m
    vel_ned_mps : (n, 3) velocity error, m/s
    att_rpy_rad : (n, 3) roll, pitch, yaw error, rad
    """

    t: Array
    pos_ned_m: Array
    vel_ned_mps: Array
    att_rpy_rad: Array

    @property
    def horizontal_m(self) -> Array:
        return np.hypot(self.pos_ned_m[:, 0], self.pos_ned_m[:, 1])


def nav_errors(estimate: NavSeries, truth: NavSeries) -> NavErrors:
    """Errors of ``estimate`` against ``truth``.

    When the time bases differ, the truth is interpolated to the estimate's
    times that fall within the truth's span (see :meth:`NavSeries.interpolate`).
    """
    if len(estimate.t) != len(truth.t) or not np.array_equal(estimate.t, truth.t):
        inside = (estimate.t >= truth.t[0] - 1e-9) & (estimate.t <= truth.t[-1] + 1e-9)
        if not inside.any():
            raise ValueError("the estimate and the truth share no time span")
        estimate = estimate.at(np.flatnonzero(inside))
        truth = truth.interpolate(estimate.t)
    r_m, r_n = earth.radii(truth.lat)
    pos = np.column_stack(
        [
            (estimate.lat - truth.lat) * (r_m + truth.h),
            rotation.wrap_angle(estimate.lon - truth.lon) * (r_n + truth.h) * np.cos(truth.lat),
            -(estimate.h - truth.h),
        ]
    )
    att = rotation.wrap_angle(np.column_stack(estimate.euler()) - np.column_stack(truth.euler()))
    return NavErrors(t=estimate.t, pos_ned_m=pos, vel_ned_mps=estimate.v_n - truth.v_n, att_rpy_rad=att)


@dataclass(frozen=True)
class DriftSummary:
    """The headline figures of a run (errors are estimate − truth).

    ``drift_rate_m_per_h`` is the final horizontal error divided by the elapsed
    time; ``*_rms_*`` are over all compared samples.
    """

    duration_s: float
    final_north_m: float
    final_east_m: float
    final_down_m: float
    final_horizontal_m: float
    max_horizontal_m: float
    rms_horizontal_m: float
    final_vn_mps: float
    final_ve_mps: float
    final_vd_mps: float
    final_roll_deg: float
    final_pitch_deg: float
    final_yaw_deg: float
    max_roll_deg: float
    max_pitch_deg: float
    max_yaw_deg: float
    drift_rate_m_per_h: float
    drift_rate_nmi_per_h: float

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


def summarize(errors: NavErrors) -> DriftSummary:
    """Final, maximum and RMS errors and the drift rate of an error series."""
    hor = errors.horizontal_m
    duration = float(errors.t[-1] - errors.t[0])
    att_deg = np.degrees(errors.att_rpy_rad)
    rate = float(hor[-1]) / (duration / 3600.0) if duration > 0 else 0.0
    return DriftSummary(
        duration_s=duration,
        final_north_m=float(errors.pos_ned_m[-1, 0]),
        final_east_m=float(errors.pos_ned_m[-1, 1]),
        final_down_m=float(errors.pos_ned_m[-1, 2]),
        final_horizontal_m=float(hor[-1]),
        max_horizontal_m=float(hor.max()),
        rms_horizontal_m=float(np.sqrt(np.mean(hor * hor))),
        final_vn_mps=float(errors.vel_ned_mps[-1, 0]),
        final_ve_mps=float(errors.vel_ned_mps[-1, 1]),
        final_vd_mps=float(errors.vel_ned_mps[-1, 2]),
        final_roll_deg=float(att_deg[-1, 0]),
        final_pitch_deg=float(att_deg[-1, 1]),
        final_yaw_deg=float(att_deg[-1, 2]),
        max_roll_deg=float(np.abs(att_deg[:, 0]).max()),
        max_pitch_deg=float(np.abs(att_deg[:, 1]).max()),
        max_yaw_deg=float(np.abs(att_deg[:, 2]).max()),
        drift_rate_m_per_h=rate,
        drift_rate_nmi_per_h=rate / NAUTICAL_MILE_M,
    )
