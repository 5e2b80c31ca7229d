"""Reference trajectories given in a local Cartesian frame (a ROS ``odom`` or ``map`` frame, a motion-capture
room) placed on the WGS84 ellipsoid as a :class:`~sins.core.series.NavSeries`.

The local frame is ENU (x east, y north, z up, as ROS's REP 103 and 105 have it) with its origin at a
geodetic point. Positions go through ECEF exactly (a drive of many kilometres keeps its shape); each
velocity and attitude is turned from the origin's NED axes into the NED axes at its own position (they
differ by the angle the Earth's curvature turns between them: 1.6e-4 rad over a kilometre).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sins.core import rotation
from sins.core.earth import E2, lla_to_ecef, radii
from sins.core.series import NavSeries
from sins.errors import SinsInputError
from sins.io.axes import ENU_TO_NED

#: Where a recording's local frame is placed when its place is not known (a room frame, a bag without a
#: fix; rad, rad, m): 45° N at sea level, whose normal gravity (9.8062 m/s²) is within 0.026 m/s² of any
#: site's at sea level (9.780 at the equator, 9.832 at the poles). 0° N, taken before, was up to 0.052
#: m/s² off (0.027 in Zurich, where EuRoC was recorded): a hand-held unit's fit or diagnosis then read
#: the difference, which scales gravity and not the unit's own acceleration, as an effect.
NOMINAL_ORIGIN = (float(np.radians(45.0)), 0.0, 0.0)
#: How :data:`NOMINAL_ORIGIN` is said in notes.
NOMINAL_PLACE = "45° N, 0° E, 0 m (gravity 9.806 m/s², within 0.026 of any site's at sea level)"

Array = NDArray[np.float64]


def room_frame_rate(origin_given: bool) -> str:
    """What a local frame with no geographic heading (a room's: EuRoC's R, an ``.npz``'s world) lets be
    placed of Earth's rate, for its readers' notes: none at :data:`NOMINAL_ORIGIN` (its latitude is not
    the recording's either: ``latitude_known`` False), the vertical part at a given origin
    (``heading_known`` False). Each such reader says it in these words, as the flags it sets do."""
    if not origin_given:
        return ("its heading and latitude are not known, so Earth's rate is left out of what is judged "
                "against it (give --origin for the place)")  # fmt: skip
    return "its heading is not known, so only the vertical part of Earth's rate is placed in it"


def ned_to_ecef_matrix(lat: Array, lon: Array) -> Array:
    """``C_en`` (..., 3, 3): NED axes at ``(lat, lon)`` (rad) into ECEF."""
    s_lat, c_lat, s_lon, c_lon = np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon)
    out = np.empty((*np.shape(lat), 3, 3))
    out[..., 0, 0], out[..., 0, 1], out[..., 0, 2] = -s_lat * c_lon, -s_lon, -c_lat * c_lon
    out[..., 1, 0], out[..., 1, 1], out[..., 1, 2] = -s_lat * s_lon, c_lon, -c_lat * s_lon
    out[..., 2, 0], out[..., 2, 1], out[..., 2, 2] = c_lat, np.zeros_like(lat), -s_lat
    return out


def ecef_to_lla(x: Array, y: Array, z: Array) -> tuple[Array, Array, Array]:
    """Geodetic ``(lat, lon, h)`` (rad, rad, m) of ECEF points: fixed-point iteration on the latitude,
    to below 1e-12 rad (6 µm) in five steps anywhere outside the Earth's centre."""
    p = np.hypot(x, y)
    lat = np.arctan2(z, p * (1.0 - E2))
    for _ in range(5):
        _, r_n = radii(lat)
        h = np.where(np.abs(np.cos(lat)) > 1e-9, p / np.cos(lat) - r_n, np.abs(z) - r_n * (1.0 - E2))
        lat = np.arctan2(z, p * (1.0 - E2 * r_n / (r_n + h)))
    _, r_n = radii(lat)
    c, s = np.cos(lat), np.sin(lat)
    # The height from the better-conditioned of the two projections.
    h = np.where(np.abs(c) > np.abs(s), p / np.where(c == 0, 1.0, c) - r_n,
                 z / np.where(s == 0, 1.0, s) - r_n * (1.0 - E2))  # fmt: skip
    return lat, np.arctan2(y, x), h


def describe_origin(origin: tuple[float, float, float]) -> str:
    """``(lat, lon, h)`` (rad, rad, m) as degrees and metres, for notes."""
    lat, lon, h = origin
    return f"{np.degrees(lat):.7f}°, {np.degrees(lon):.7f}°, {h:.2f} m"


#: A room frame whose up, as its reference sees gravity, lies within this of one of its axes other than
#: z is read turned to put that axis at z (:func:`levelled`), °: the reference's own tilt check's
#: (:data:`sins.io.frame_check.REFERENCE_TILT_DEG`; a 1 m/s² accelerometer bias tilts it 6°).
LEVEL_WITHIN_DEG = 10.0


def mean_in_world(t: Array, f_s: Array, q_xyzw: Array) -> Array:
    """The specific force ``f_s`` (n, 3), read on the axes whose attitude is ``q_xyzw`` (scalar last),
    rotated into the world and averaged over ``t``'s span, each reading weighted by its share of it
    (uneven stamps): gravity's reaction and the mean acceleration, as the reference sees them."""
    weights = np.gradient(t) if len(t) > 1 else np.ones(1)
    return np.asarray(weights @ rotation.rotate(q_xyzw, f_s) / float(np.sum(weights)))


def levelled(t: Array, f_s: Array, q_xyzw: Array, v_w: Array, p_w: Array) -> tuple[Array, Array, Array, str]:
    """A room's reference (the attitude ``q_xyzw`` of the sensor's axes, scalar last, its velocity
    ``v_w`` and position ``p_w``, at ``t``; ``f_s`` the specific force read on those axes at ``t``) in a
    world frame with z up, where the file's world has its up along another of its axes (a motion
    capture's frame with y up; NED's z down written for ENU): the attitude, velocity and position turned
    by the one rotation of 90° or 180° that takes that axis to z, and a note saying so (else everything
    as it is and an empty note). Up is gravity's reaction as the reference sees it: the specific force
    rotated into the world, averaged over the recording, less the mean acceleration its velocity gives.
    Taken only within :data:`LEVEL_WITHIN_DEG` of an axis: a world tilted elsewhere, or an attitude that
    is not of the readings' axes, is left for :func:`sins.io.frame_check.reference_findings` to name (its
    turns against the gyro's judge the attitude whichever way the world is turned)."""
    rows = slice(None, None, max(1, len(t) // 200_000))  # the mean of a long recording from 200,000 rows
    up = mean_in_world(t[rows], f_s[rows], q_xyzw[rows])
    if t[-1] > t[0]:
        up = up - (v_w[-1] - v_w[0]) / float(t[-1] - t[0])
    size = float(np.linalg.norm(up))
    k = int(np.argmax(np.abs(up)))
    if not size > 0 or (k == 2 and up[2] > 0):
        return q_xyzw, v_w, p_w, ""
    tilt = float(np.degrees(np.arccos(min(1.0, abs(float(up[k])) / size))))
    if tilt > LEVEL_WITHIN_DEG:
        return q_xyzw, v_w, p_w, ""
    axis = np.zeros(3)
    axis[k] = np.sign(up[k])
    # 90° about the horizontal axis that takes this one to z; 180° about x for z down.
    rotvec = np.array([np.pi, 0.0, 0.0]) if k == 2 else np.pi / 2 * np.cross(axis, [0.0, 0.0, 1.0])
    turn = rotation.quat_from_rotvec(rotvec)
    note = (
        f"its world frame's up lies along {_axis_name(axis)} (gravity's reaction as the reference sees it, "
        f"within {tilt:.1f}° of that axis), where the form's is z: the reference is read turned by "
        f"{np.degrees(np.linalg.norm(rotvec)):.0f}° about {_axis_name(rotvec)} to put its up at z"
    )
    return (
        rotation.quat_multiply(turn, q_xyzw),
        rotation.rotate(turn, v_w),
        rotation.rotate(turn, p_w),
        note,
    )


#: A room reference's velocity read on its positions' clock where it lags (or leads) them by this much or
#: more, s ... (EuRoC's eleven sequences, velocities from their estimator: 0.04-0.43 ms; velocities made
#: as a backward difference of the positions, as a preprocessing for learned gyro correction writes
#: them: half a step, 2.5 ms at 200 Hz.)
VELOCITY_LAG_S = 1e-3
#: ... up to this much (beyond, the first-order estimate of :func:`velocity_lag_s` is not the lag) ...
MAX_VELOCITY_LAG_S = 0.02
#: ... and where the lag explains this share of their difference at least (EuRoC's: none of it; a
#: backward difference: all of it on V1_02, which opens at rest, 94 % on a numpy unit that opens moving,
#: whose first velocity the backward difference leaves zero).
LAG_EXPLAINS = 0.5
#: The half-width of the moving mean both are compared through, s: a lag commutes with it, and it takes
#: the noise differentiated positions carry (a motion capture's 0.1 mm over 5 ms is 0.03 m/s).
_LAG_SMOOTHING_S = 0.05


def velocity_lag_s(t: Array, v_w: Array, p_w: Array) -> tuple[float, float]:
    """How late the velocities ``v_w`` (n, 3) run against the derivative of the positions ``p_w`` at
    ``t``, s (v(t) = ṗ(t − τ): a backward difference of the positions is late by half a step), and the
    share of their difference that lag explains (0 to 1). To first order in τ, on both smoothed alike:
    v − ṗ = −τ p̈, solved by least squares. (0, 0) where the recording is too short or never accelerates."""
    dt = float(np.median(np.diff(t)))
    k = max(1, round(_LAG_SMOOTHING_S / dt))
    if len(t) < 4 * k + 3:
        return 0.0, 0.0
    kernel = np.ones(2 * k + 1) / (2 * k + 1)

    def smooth(x: Array) -> Array:
        return np.column_stack([np.convolve(x[:, i], kernel, mode="valid") for i in range(3)])

    v_s, d_s = smooth(v_w), smooth(np.gradient(p_w, t, axis=0))
    a_s = np.gradient(d_s, t[k : len(t) - k], axis=0)
    if not np.sum(a_s * a_s) > 0:
        return 0.0, 0.0
    tau = -float(np.sum((v_s - d_s) * a_s) / np.sum(a_s * a_s))
    before, after = np.sum((v_s - d_s) ** 2), np.sum((v_s - d_s + tau * a_s) ** 2)
    return tau, float(1.0 - after / before) if before > 0 else 0.0


def on_positions_clock(t: Array, v_w: Array, p_w: Array) -> tuple[Array, str]:
    """A room reference's velocities on its positions' clock: read :func:`velocity_lag_s` earlier where
    they lag by :data:`VELOCITY_LAG_S` to :data:`MAX_VELOCITY_LAG_S` and the lag explains
    :data:`LAG_EXPLAINS` of their difference, with a note saying so; else as they are and "". A lag of
    the velocities alone reads, in a fit or a gap diagnosis, as the accelerometer's time offset
    (2.5 ms of backward difference moved a EuRoC sequence's fitted offset from 1.9 ms to 0.0 ms, and
    its diagnosis named ``accel.time_offset`` where the velocities as estimated named nothing)."""
    tau, share = velocity_lag_s(t, v_w, p_w)
    if not (VELOCITY_LAG_S <= abs(tau) <= MAX_VELOCITY_LAG_S and share >= LAG_EXPLAINS):
        return v_w, ""
    moved = np.column_stack([np.interp(t + tau, t, v_w[:, i]) for i in range(3)])
    said = f"{'lag' if tau > 0 else 'lead'} its positions by {1e3 * abs(tau):.2f} ms"
    return moved, (
        f"its velocities {said} (the lag explains {100 * share:.0f} % of their difference; a backward "
        "difference of positions lags by half a step): read on the positions' clock"
    )


def _axis_name(vector: Array) -> str:
    """The axis ``vector`` lies along most, with its sign ("+y", "-z")."""
    k = int(np.argmax(np.abs(vector)))
    return f"{'+' if vector[k] > 0 else '-'}{'xyz'[k]}"


def enu_track(
    t: Array,
    p_enu: Array,
    origin: tuple[float, float, float],
    *,
    q_enu_body: Array | None = None,
    v_enu: Array | None = None,
    body_to_frd: Array | None = None,
    source: str = "",
) -> NavSeries:
    """A local ENU trajectory as a geodetic :class:`NavSeries`.

    Parameters
    ----------
    t : (n,) s, increasing
    p_enu : (n, 3) m, positions in the local ENU frame
    origin : ``(lat, lon, h)`` of the local frame's origin, rad, rad, m
    q_enu_body : (n, 4) scalar-last, the body's attitude in the ENU frame (``v_enu = R(q) v_body``);
        None: identity (the attitude is then meaningless and the caller says so)
    v_enu : (n, 3) m/s in ENU, or None to differentiate the positions (second-order central differences)
    body_to_frd : (3, 3), the body axes into FRD (:func:`sins.io.axes.frame_matrix`); None: the body is FRD
    source : for messages

    Raises
    ------
    SinsInputError
        fewer than two samples where the velocity must be differentiated.
    """
    t = np.asarray(t, dtype=float)
    p_ned0 = np.asarray(p_enu, dtype=float) @ ENU_TO_NED.T
    lat0, lon0, h0 = origin
    c_en0 = ned_to_ecef_matrix(np.asarray(lat0), np.asarray(lon0))
    x0, y0, z0 = lla_to_ecef(lat0, lon0, h0)
    ecef = np.array([x0, y0, z0]) + p_ned0 @ c_en0.T
    lat, lon, h = ecef_to_lla(ecef[:, 0], ecef[:, 1], ecef[:, 2])
    # NED at each point from the origin's NED: C_ne(lat, lon) C_en0.
    turn = np.swapaxes(ned_to_ecef_matrix(lat, lon), -1, -2) @ c_en0
    if v_enu is None:
        if len(t) < 2:
            raise SinsInputError(
                f"{source}: a reference trajectory without velocities needs two or more poses"
            )
        v_ned0 = np.gradient(p_ned0, t, axis=0)
    else:
        v_ned0 = np.asarray(v_enu, dtype=float) @ ENU_TO_NED.T
    v_n = np.einsum("nij,nj->ni", turn, v_ned0)
    c_enu_body = np.broadcast_to(np.eye(3), (len(t), 3, 3)) if q_enu_body is None else (
        rotation.dcm_from_quat(q_enu_body))  # fmt: skip
    m = np.eye(3) if body_to_frd is None else np.asarray(body_to_frd, dtype=float)
    c_nb = turn @ (ENU_TO_NED @ c_enu_body) @ m.T
    return NavSeries(t=t, lat=lat, lon=lon, h=h, v_n=v_n, q_nb=rotation.quat_from_dcm(c_nb))


__all__ = [
    "LAG_EXPLAINS",
    "LEVEL_WITHIN_DEG",
    "MAX_VELOCITY_LAG_S",
    "NOMINAL_ORIGIN",
    "NOMINAL_PLACE",
    "VELOCITY_LAG_S",
    "describe_origin",
    "ecef_to_lla",
    "enu_track",
    "levelled",
    "mean_in_world",
    "ned_to_ecef_matrix",
    "on_positions_clock",
    "room_frame_rate",
    "velocity_lag_s",
]
