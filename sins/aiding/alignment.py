"""Initial alignment of a still unit: coarse levelling and gyrocompassing, then the filter's fine alignment.

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

from sins.aiding import ekf
from sins.aiding.gnss import GnssFixes
from sins.errors import SinsInputError
from sins.nav import earth, rotation, strapdown
from sins.series import ImuIncrements

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
    roll = np.arctan2(-f_b[1], -f_b[2])
    pitch = np.arctan2(f_b[0], np.hypot(f_b[1], f_b[2]))
    w = rotation.dcm_from_euler(roll, pitch, 0.0) @ omega_b
    yaw = np.arctan2(-w[1], w[0])
    return rotation.quat_from_euler(roll, pitch, yaw)


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
