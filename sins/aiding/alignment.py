"""Initial alignment: a still unit's coarse levelling and gyrocompassing, then the filter's fine
alignment; or a moving unit's heading from the GNSS velocity (:func:`in_motion_run`).

Coarse: the mean specific force over the first ``coarse_s`` seconds gives roll and pitch (it points
up, ``f_b = C_bn (0, 0, -g)``); the mean angular rate, levelled, gives the heading from the Earth
rate's horizontal part, ``Ω cos φ`` pointing north. Fine: the error-state filter runs from the coarse
attitude with zero-velocity updates over the whole still window (and GNSS fixes if any), and goes on
navigating after it.

The physical limits (the filter cannot beat them: a still unit cannot tell a tilt from an
accelerometer bias, nor a heading error from an east gyro bias)::

    φ_N = r_aE / g,  φ_E = -r_aN / g,  φ_D = r_gE / (Ω cos φ) - tan φ · r_aE / g

with ``r`` the biases left uncompensated (true minus estimated) resolved in n, and ``φ`` the attitude
error of :mod:`sins.aiding.ekf` (``C_est = (I - [φ×]) C_nb``; for a level unit the heading error is
``-φ_D``). They follow from setting ``δv̇ = 0`` and ``φ̇_E = 0`` in the filter's error dynamics.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sins.aiding import ekf, gnss
from sins.aiding.gnss import GnssFixes
from sins.core import earth, rotation
from sins.core.series import ImuIncrements
from sins.errors import SinsInputError
from sins.nav import strapdown

Array = NDArray[np.float64]


@dataclass(frozen=True)
class AlignmentConfig:
    """How a run starts.

    Attributes
    ----------
    static_s : the unit stands still this long from the first sample, s (zero-velocity updates)
    coarse_s : the readings averaged by the coarse alignment, s (at most ``static_s``)
    """

    static_s: float = 300.0
    coarse_s: float = 60.0

    def __post_init__(self) -> None:
        """Refuse windows that are not positive or a coarse window longer than the still one."""
        if not (np.isfinite(self.static_s) and self.static_s > 0):
            raise SinsInputError(f"alignment static_s must be a positive number, got {self.static_s}")
        if not (np.isfinite(self.coarse_s) and 0 < self.coarse_s <= self.static_s):
            raise SinsInputError(
                f"alignment coarse_s must be positive and at most static_s {self.static_s}, "
                f"got {self.coarse_s}"
            )


def _window(imu: ImuIncrements, seconds: float) -> int:
    """The number of intervals in the first ``seconds`` of the IMU (refused if it is shorter)."""
    end = imu.t[0] + seconds
    if imu.t[-1] < end - 1e-9:
        raise SinsInputError(
            f"alignment needs {seconds} s of still readings, the IMU spans {imu.t[-1] - imu.t[0]:.6g} s"
        )
    return int(np.searchsorted(imu.t, end - 1e-9)) or 1


def coarse_attitude(imu: ImuIncrements, seconds: float) -> Array:
    """``q_nb`` from the mean readings of the first ``seconds``: levelling, then gyrocompassing.

    Roll ``atan2(-f_y, -f_z)``, pitch ``atan2(f_x, sqrt(f_y² + f_z²))``; the levelled rate
    ``w = C_lev ω_b = (Ω cos φ cos ψ, -Ω cos φ sin ψ, ·)`` gives the heading ``ψ = atan2(-w_y, w_x)``.
    """
    k = _window(imu, seconds)
    span = imu.t[k] - imu.t[0]
    f_b = imu.dv_b[:k].sum(axis=0) / span
    omega_b = imu.dtheta_b[:k].sum(axis=0) / span
    return rotation.quat_from_euler(*still_attitude(f_b, omega_b))


def still_attitude(f_b: Array, omega_b: Array) -> tuple[float, float, float]:
    """Roll, pitch and yaw (rad) of a still unit from its mean specific force ``f_b`` and angular rate
    ``omega_b`` (3,): levelling, then gyrocompassing (:func:`coarse_attitude`'s formulas)."""
    roll = float(np.arctan2(-f_b[1], -f_b[2]))
    pitch = float(np.arctan2(f_b[0], np.hypot(f_b[1], f_b[2])))
    w = rotation.dcm_from_euler(roll, pitch, 0.0) @ np.asarray(omega_b, dtype=float)
    return roll, pitch, float(np.arctan2(-w[1], w[0]))


def coarse_covariance(config: ekf.FilterConfig, lat: float, seconds: float, position_sigma_m: float) -> Array:
    """``P0`` after a coarse alignment of ``seconds``: the limits of the module docstring plus the noise.

    Tilt 1σ ``hypot(σ_ba, vrw/√T) / g``; heading ``hypot(σ_bg, arw/√T) / (Ω cos φ)`` plus
    ``tan φ`` times the tilt; both capped at 30° (beyond, the filter's small angles mean little).
    """
    g = earth.G0
    cap = np.radians(30.0)
    tilt = min(np.hypot(config.accel_bias_sigma, config.vrw_mps_rt_s / np.sqrt(seconds)) / g, cap)
    heading = (
        np.hypot(config.gyro_bias_sigma, config.arw_rad_rt_s / np.sqrt(seconds))
        / (earth.OMEGA_IE * np.cos(lat))
        + abs(np.tan(lat)) * tilt
    )
    sigma = np.concatenate([
        np.full(3, position_sigma_m), np.full(3, config.zupt_sigma_mps),
        [tilt, tilt, min(heading, cap)],
        np.full(3, config.gyro_bias_sigma), np.full(3, config.accel_bias_sigma),
    ])  # fmt: skip
    return np.diag(sigma**2)


def aligned_run(
    imu: ImuIncrements,
    fixes: GnssFixes,
    config: ekf.FilterConfig,
    alignment: AlignmentConfig,
    position: tuple[float, float, float] | None = None,
    heading: tuple[float, float] | None = None,
) -> ekf.AidedResult:
    """Align a unit that stands still at the start, then navigate with the fixes: the filter's whole run.

    Parameters
    ----------
    imu : the readings, still for ``alignment.static_s`` from ``imu.t[0]``
    fixes : GNSS fixes (may be empty)
    config : the filter
    alignment : the still window and the coarse alignment's span
    position : ``(lat, lon, h)`` of the unit (rad, rad, m); default the first fix (antenna and IMU are
        taken as one point for this start; the filter's position σ is the fix's)
    heading : ``(yaw, 1σ)`` in rad from elsewhere (a magnetometer, a dual antenna) instead of
        gyrocompassing: for a unit whose gyro bias is not well below ``Ω cos φ`` (a tactical unit's
        5 °/h against 10.6 °/h at 45°), whose gyrocompass heading is tens of degrees off

    Returns
    -------
    AidedResult from the coarse attitude, zero velocity, and ``position``
    """
    _window(imu, alignment.static_s)
    if position is None:
        if len(fixes) == 0:
            raise SinsInputError("alignment needs a start position: give one, or GNSS fixes")
        position = (float(fixes.lat[0]), float(fixes.lon[0]), float(fixes.h[0]))
        sigma_pos = float(np.max(fixes.sigma_pos_m) + np.linalg.norm(fixes.lever_arm_b))
    else:
        sigma_pos = 0.1
    lat, lon, h = position
    q_nb = coarse_attitude(imu, alignment.coarse_s)
    averaged = float(imu.t[_window(imu, alignment.coarse_s)] - imu.t[0])  # at least one interval
    P0 = coarse_covariance(config, lat, averaged, sigma_pos)
    if heading is not None:
        roll, pitch, _ = rotation.euler_from_quat(q_nb)
        q_nb = rotation.quat_from_euler(roll, pitch, heading[0])
        P0[ekf.ATT.stop - 1, ekf.ATT.stop - 1] = heading[1] ** 2
    initial = strapdown.InitialState(lat=lat, lon=lon, h=h, v_n=np.zeros(3), q_nb=q_nb)
    still = [(float(imu.t[0]), float(imu.t[0] + alignment.static_s))]
    return ekf.run(imu, fixes, config, initial, zupt=still, P0=P0)


def static_limits(C_nb: Array, lat: float, gyro_residual_b: Array, accel_residual_b: Array) -> Array:
    """The attitude error ``φ`` (3,) a still unit settles at (module docstring).

    Parameters
    ----------
    C_nb : (3, 3) the unit's attitude
    lat : its latitude, rad
    gyro_residual_b, accel_residual_b : (3,) the biases left uncompensated (true minus estimated), body frame
    """
    r_g = C_nb @ gyro_residual_b
    r_a = C_nb @ accel_residual_b
    g = earth.normal_gravity(lat, 0.0)
    phi_n = r_a[1] / g
    phi_e = -r_a[0] / g
    phi_d = r_g[1] / (earth.OMEGA_IE * np.cos(lat)) - np.tan(lat) * r_a[1] / g
    return np.array([phi_n, phi_e, phi_d])


#: The heading σ above which an automatic alignment does not gyrocompass (the filter's small attitude
#: angles hold a few degrees; a gyro bias near ``Ω cos φ`` leaves tens), rad.
GYROCOMPASS_MAX_SIGMA_RAD = float(np.radians(2.0))


@dataclass(frozen=True)
class MotionConfig:
    """An in-motion alignment from the GNSS velocity (the course over ground as the heading).

    Attributes
    ----------
    min_speed_mps : the horizontal speed the vehicle must reach; the first fix at or above it aligns
    sideslip_sigma_rad : 1σ of the angle between the body's x axis and its horizontal velocity (a car's
        sideslip, a ship's drift), rad
    level_s : the readings averaged for roll and pitch, s (their error is the vehicle's acceleration
        over ``g``, told to the filter)
    baseline_s : without velocity fixes, the velocity is the chord between fixes at least this far
        apart, s (the noise falls as ``√2 σ / baseline``, the chord's lag grows with it)
    """

    min_speed_mps: float = 5.0
    sideslip_sigma_rad: float = float(np.radians(1.0))
    level_s: float = 1.0
    baseline_s: float = 2.0

    def __post_init__(self) -> None:
        """Refuse a speed or a window that is not positive, a negative sideslip."""
        for name in ("min_speed_mps", "level_s", "baseline_s"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise SinsInputError(f"alignment {name} must be a positive number, got {value}")
        if not (np.isfinite(self.sideslip_sigma_rad) and self.sideslip_sigma_rad >= 0):
            raise SinsInputError(
                f"alignment sideslip_sigma must be a non-negative number, got {self.sideslip_sigma_rad}"
            )


@dataclass(frozen=True)
class MotionStart:
    """Where an in-motion alignment starts the filter.

    Attributes
    ----------
    index : the IMU sample it starts at (the aligning fix's time of validity)
    fix_row : the aligning fix (the filter takes the fixes after it)
    initial : the state there
    P0 : (15, 15) its covariance
    speed_mps : the horizontal GNSS speed there
    heading_sigma_rad, tilt_sigma_rad : the 1σ told to the filter
    """

    index: int
    fix_row: int
    initial: strapdown.InitialState
    P0: Array
    speed_mps: float
    heading_sigma_rad: float
    tilt_sigma_rad: float


def _gnss_velocity(fixes: GnssFixes, baseline_s: float) -> tuple[Array, Array, Array]:
    """Each fix's antenna velocity (k, 3), its 1σ per NED axis (k, 3) and how long before the fix it
    holds (k,): the receiver's, or the chord from the fix at least ``baseline_s`` earlier (NaN where
    there is none, or an outage lies between)."""
    k = len(fixes)
    if fixes.sigma_vel_mps is not None:
        return np.asarray(fixes.v_n, dtype=float), np.full((k, 3), fixes.sigma_vel_mps), np.zeros(k)
    v, sigma, lag = np.full((k, 3), np.nan), np.full((k, 3), np.nan), np.zeros(k)
    step = float(np.median(np.diff(fixes.t))) if k > 1 else np.inf
    back = np.searchsorted(fixes.t, fixes.t - baseline_s + 1e-9, side="right") - 1
    for j in np.flatnonzero(back >= 0):
        i = int(back[j])
        span = fixes.t[j] - fixes.t[i]
        if span > baseline_s + 1.5 * step:  # an outage between: not a chord of the motion
            continue
        lat, lon, h = fixes.lat, fixes.lon, fixes.h
        v[j] = earth.ned_offset(lat[j], lon[j], h[j], lat[i], lon[i], h[i]) / span
        sigma[j] = np.sqrt(2.0) * np.asarray(fixes.sigma_pos_m, dtype=float) / span
        lag[j] = 0.5 * span  # the chord is the velocity at its middle
    return v, sigma, lag


def _aligning_fix(
    imu: ImuIncrements, fixes: GnssFixes, motion: MotionConfig
) -> tuple[int, Array, Array, float, Array, Array]:
    """The first fix fast enough (with readings to level on before it): row, velocity, σ, lag, and
    every fix's velocity and σ."""
    v, sigma, lag = _gnss_velocity(fixes, motion.baseline_s)
    speed = np.hypot(v[:, 0], v[:, 1])
    valid = np.asarray(fixes.t, dtype=float) - fixes.latency_s
    fast = np.nan_to_num(speed, nan=0.0) >= motion.min_speed_mps
    rows = np.flatnonzero(fast & (valid - motion.level_s >= imu.t[0] - 1e-9) & (valid <= imu.t[-1]))
    if rows.size == 0:
        if not np.any(np.isfinite(speed)):  # no fix, or none with one before it within the baseline
            why = f"no two GNSS fixes within {motion.baseline_s:g} s of each other give a speed (outages?)"
        else:
            top = float(np.nanmax(speed))
            why = f"the GNSS speed never reaches {motion.min_speed_mps:g} m/s (at most {top:.3g} m/s)"
        raise SinsInputError(
            f'alignment.min_speed_mps: {why}: align still (method = "static") or start from the truth '
            '(method = "truth")'
        )
    j = int(rows[0])
    return j, v[j], sigma[j], float(lag[j]), v, sigma


def _gnss_acceleration(fixes: GnssFixes, v: Array, sigma: Array, j: int) -> tuple[Array, Array, float] | None:
    """The mean acceleration between the fix before ``j`` and ``j`` from their velocities (NED), its 1σ
    per axis, and the time between; None without the fix before (the first, after an outage) or
    without receiver velocities (a chord's second difference is noisier than the acceleration)."""
    if fixes.sigma_vel_mps is None or j == 0:
        return None
    step = float(np.median(np.diff(fixes.t)))
    span = float(fixes.t[j] - fixes.t[j - 1])
    if span > 1.5 * step or not np.all(np.isfinite(v[j - 1])):
        return None
    return (v[j] - v[j - 1]) / span, np.hypot(sigma[j], sigma[j - 1]) / span, span


def _level(f_b: Array, a_n: Array | None, yaw: float) -> tuple[float, float]:
    """Roll and pitch from the mean specific force ``f_b = C_bn (a_n - g_n)``: levelling on ``f_b``,
    then (``a_n`` known) on ``f_b - C_bn a_n`` twice (the second pass corrects the first's tilt, whose
    error on ``C_bn a_n`` is second order)."""
    roll = float(np.arctan2(-f_b[1], -f_b[2]))
    pitch = float(np.arctan2(f_b[0], np.hypot(f_b[1], f_b[2])))
    for _ in range(2 if a_n is not None else 0):
        assert a_n is not None
        gravity_b = f_b - rotation.dcm_from_euler(roll, pitch, yaw).T @ a_n
        roll = float(np.arctan2(-gravity_b[1], -gravity_b[2]))
        pitch = float(np.arctan2(gravity_b[0], np.hypot(gravity_b[1], gravity_b[2])))
    return roll, pitch


def in_motion_start(
    imu: ImuIncrements, fixes: GnssFixes, config: ekf.FilterConfig, motion: MotionConfig
) -> MotionStart:
    """Align a moving unit on the first GNSS fix at ``motion.min_speed_mps``: heading from the course over
    ground, roll and pitch from the mean specific force less the acceleration the GNSS velocities show,
    position and velocity from the fixes.

    The errors told to the filter: heading ``hypot(σ_v / v, sideslip)`` (``σ_v`` the velocity's
    horizontal noise, with the chord's lag times the acceleration); tilt ``hypot(σ_a, σ_ba) / g`` with
    ``σ_a`` the GNSS acceleration's noise, or, without receiver velocities, the acceleration itself
    ``a = sqrt(|f|² - g²)`` (levelling then takes it for gravity), capped at 30°; position the fix's σ
    and velocity the velocity's.
    """
    j, v_ant, sigma_v, lag, v_all, sigma_all = _aligning_fix(imu, fixes, motion)
    n = len(imu.dtheta_b)
    valid = np.asarray(fixes.t, dtype=float) - fixes.latency_s
    k = int(np.clip(np.argmin(np.abs(imu.t - valid[j])), 1, n))
    if k >= n:  # the first fix fast enough is the run's last: the filter would have nothing to navigate
        raise SinsInputError(
            f"alignment.min_speed_mps: the GNSS speed first reaches {motion.min_speed_mps:g} m/s at the "
            f"run's end ({valid[j]:g} s), leaving nothing to navigate; lower it, or align still or from "
            "the truth"
        )
    known = _gnss_acceleration(fixes, v_all, sigma_all, j)
    window = known[2] if known is not None else motion.level_s
    k0 = min(int(np.searchsorted(imu.t, imu.t[k] - window + 1e-9)), k - 1)
    span = float(imu.t[k] - imu.t[k0])
    f_b = imu.dv_b[k0:k].sum(axis=0) / span
    omega_b = imu.dtheta_b[k0:k].sum(axis=0) / span
    g = earth.normal_gravity(float(fixes.lat[j]), float(fixes.h[j]))
    accel = float(np.sqrt(max(float(f_b @ f_b) - g * g, 0.0)))
    if known is not None:
        accel = float(np.max(known[1][:2]))  # what is left of it: the GNSS acceleration's noise
    cap = np.radians(30.0)
    noise = config.vrw_mps_rt_s / np.sqrt(span)
    tilt = min(float(np.linalg.norm([accel, config.accel_bias_sigma, noise])) / g, cap)
    roll, pitch = _level(f_b, None if known is None else known[0], float(np.arctan2(v_ant[1], v_ant[0])))
    arm_b = np.asarray(fixes.lever_arm_b, dtype=float)
    C_nb = rotation.dcm_from_euler(roll, pitch, float(np.arctan2(v_ant[1], v_ant[0])))
    v_n = v_ant - C_nb @ np.cross(omega_b, arm_b)  # the IMU's velocity: less the lever arm turning
    turn = float((C_nb @ omega_b)[2] * lag)  # the heading's change since the chord's middle
    c, s = np.cos(turn), np.sin(turn)
    v_n = np.array([c * v_n[0] - s * v_n[1], s * v_n[0] + c * v_n[1], v_n[2]])
    yaw = float(np.arctan2(v_n[1], v_n[0]))
    C_nb = rotation.dcm_from_euler(roll, pitch, yaw)
    speed = float(np.hypot(v_n[0], v_n[1]))
    sigma_v = np.hypot(sigma_v, accel * lag)
    heading = min(float(np.hypot(np.max(sigma_v[:2]) / speed, motion.sideslip_sigma_rad)), cap)
    one = np.ones(1)
    lat, lon, h = gnss.offset_position(
        fixes.lat[j] * one, fixes.lon[j] * one, fixes.h[j] * one, -(C_nb @ arm_b)[None, :]
    )
    sigma_pos = np.hypot(
        np.asarray(fixes.sigma_pos_m, dtype=float), np.linalg.norm(arm_b) * max(tilt, heading)
    )
    sigma = np.concatenate([
        sigma_pos, sigma_v, [tilt, tilt, heading],
        np.full(3, config.gyro_bias_sigma), np.full(3, config.accel_bias_sigma),
    ])  # fmt: skip
    q_nb = rotation.quat_from_euler(roll, pitch, yaw)
    initial = strapdown.InitialState(lat=float(lat[0]), lon=float(lon[0]), h=float(h[0]), v_n=v_n, q_nb=q_nb)
    return MotionStart(k, j, initial, np.diag(sigma**2), speed, heading, tilt)


def in_motion_run(
    imu: ImuIncrements, fixes: GnssFixes, config: ekf.FilterConfig, motion: MotionConfig
) -> tuple[MotionStart, ekf.AidedResult]:
    """Align a moving unit (:func:`in_motion_start`) and navigate from there with the later fixes.

    Returns
    -------
    the alignment, and the filter's run from its sample (``nav`` starts at ``imu.t[start.index]``)
    """
    start = in_motion_start(imu, fixes, config, motion)
    k = start.index
    rest = imu.steps(k)
    rows = np.arange(len(fixes))
    later = fixes.select((rows > start.fix_row) & (fixes.t >= rest.t[0]))
    return start, ekf.run(rest, later, config, start.initial, P0=start.P0)


__all__ = [
    "GYROCOMPASS_MAX_SIGMA_RAD",
    "AlignmentConfig",
    "MotionConfig",
    "MotionStart",
    "aligned_run",
    "coarse_attitude",
    "coarse_covariance",
    "in_motion_run",
    "in_motion_start",
    "static_limits",
    "still_attitude",
]
