"""A unit of known errors moved along a known trajectory, with a noisy reference, written without ``sins``.

The generator of ``tests/test_referenced.py``: numpy and scipy's ``Rotation`` only. The body's attitude
is a rotation vector of sines on every axis (up to 80° each, turns that do not commute) and its rate
follows exactly from it; it moves slowly in a small room (velocities below 0.2 m/s, so that the Coriolis
and transport terms, which it leaves out, are below 3e-5 m/s²). The gyro sees Earth's rate. The unit
reads its own axes' rate and specific force through the seed model (``gyro = ω + B0 + B ω``,
``accel = f + A0 + A f``; the gyro's g-sensitivity left at zero), a time offset (each sensor reports its
input ``τ`` late) and white noise. The reference is the attitude and velocity at 10 Hz with white noise
ten times the sensor's own over a reference interval. Gravity is constant, the normal gravity of WGS84
at the stated latitude and height.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

#: Latitude and height of the room: 45° N, 0 m. Normal gravity there, Somigliana's closed formula with
#: WGS84's γ_e = 9.7803253359 m/s², k = 0.00193185265241, e² = 0.00669437999013: 9.8061977694 m/s².
LAT_DEG, HEIGHT_M, GRAVITY = 45.0, 0.0, 9.8061977694
#: Earth's rate, rad/s (the gyro measures it; the reference, fixed to the Earth, does not).
OMEGA_IE = 7.292115e-5


@dataclass(frozen=True)
class Unit:
    """The unit's true errors (errors as reading − truth, SI) and its noise per sample."""

    B0: np.ndarray
    B: np.ndarray
    A0: np.ndarray
    A: np.ndarray
    gyro_delay_s: float
    accel_delay_s: float
    gyro_sigma: float
    accel_sigma: float


@dataclass(frozen=True)
class Session:
    """Readings (rate form at ``t``), and the reference at ``t_ref``: ``q_nb`` scalar-last (NED), ``v_n``."""

    t: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    t_ref: np.ndarray
    q_nb: np.ndarray
    v_n: np.ndarray
    unit: Unit


def _right_jacobian(phi: np.ndarray, phi_dot: np.ndarray) -> np.ndarray:
    """``J_r(φ) φ̇`` row by row: the body rate of the attitude ``Exp(φ(t))``,
    ``J_r = I − (1 − cos θ)/θ² [φ]× + (θ − sin θ)/θ³ [φ]×²``."""
    theta = np.linalg.norm(phi, axis=1, keepdims=True)
    a = (1.0 - np.cos(theta)) / theta**2
    b = (theta - np.sin(theta)) / theta**3
    cross = np.cross(phi, phi_dot)
    return phi_dot - a * cross + b * np.cross(phi, cross)


def typical_unit(rng: np.random.Generator) -> Unit:
    """A MEMS-like unit: biases of 0.1 °/s and 5 mg, scale and misalignment of 0.3 %, delays of a few ms."""
    return Unit(
        B0=np.radians(rng.normal(0.0, 0.1, 3)),
        B=rng.normal(0.0, 3e-3, (3, 3)),
        A0=rng.normal(0.0, 0.05, 3),
        A=rng.normal(0.0, 3e-3, (3, 3)),
        gyro_delay_s=float(rng.uniform(1e-3, 5e-3)),
        accel_delay_s=float(rng.uniform(1e-3, 5e-3)),
        gyro_sigma=np.radians(0.05),
        accel_sigma=0.01,
    )


def session(
    rng: np.random.Generator, unit: Unit, *, duration_s: float = 240.0, rate_hz: float = 100.0,
    ref_hz: float = 10.0, ref_noise_ratio: float = 10.0, interval_s: float = 1.0,
) -> Session:  # fmt: skip
    """The unit turned and moved for ``duration_s``; the reference's noise per epoch is ``ref_noise_ratio``
    times the sensor's own white noise integrated over ``interval_s``."""
    fine = 10
    n = round(duration_s * rate_hz)
    t_fine = np.arange(n * fine + 1) / (rate_hz * fine) - 1.0  # a second before the readings start
    # Attitude C_nb = C0 Exp(φ(t)), φ sines on every axis (up to 80° each: turns that do not commute);
    # the body's rate is then exactly J_r(φ) φ̇ (SO(3)'s right Jacobian), with no integration.
    freqs = rng.uniform(0.03, 0.3, 3)
    amps = np.radians(rng.uniform(30.0, 80.0, 3))
    phases = rng.uniform(0.0, 2 * np.pi, 3)
    phi = amps * np.sin(2 * np.pi * freqs * t_fine[:, None] + phases)
    phi_dot = amps * 2 * np.pi * freqs * np.cos(2 * np.pi * freqs * t_fine[:, None] + phases)
    omega = _right_jacobian(phi, phi_dot)
    att = Rotation.from_euler("ZYX", rng.uniform(-1.0, 1.0, 3)) * Rotation.from_rotvec(phi)
    # Velocity: slow sines in NED (|v| < 0.3 m/s), acceleration their derivative.
    vf, va, vp = rng.uniform(0.05, 0.3, 3), rng.uniform(0.05, 0.1, 3), rng.uniform(0, 2 * np.pi, 3)
    v_n = va * np.sin(2 * np.pi * vf * t_fine[:, None] + vp)
    a_n = va * 2 * np.pi * vf * np.cos(2 * np.pi * vf * t_fine[:, None] + vp)
    g_n = np.array([0.0, 0.0, GRAVITY])
    f_b = att.inv().apply(a_n - g_n)
    lat = np.radians(LAT_DEG)
    w_ie_n = OMEGA_IE * np.array([np.cos(lat), 0.0, -np.sin(lat)])
    w_ib = omega + att.inv().apply(w_ie_n)
    # The readings at the IMU's times, each sensor seeing its input τ late.
    t = np.arange(n + 1) / rate_hz

    def at(x: np.ndarray, delay: float) -> np.ndarray:
        return np.stack([np.interp(t - delay, t_fine, x[:, i]) for i in range(3)], axis=1)

    w_true, f_true = at(w_ib, unit.gyro_delay_s), at(f_b, unit.accel_delay_s)
    gyro = w_true + unit.B0 + w_true @ unit.B.T + rng.normal(0.0, unit.gyro_sigma, w_true.shape)
    accel = f_true + unit.A0 + f_true @ unit.A.T + rng.normal(0.0, unit.accel_sigma, f_true.shape)
    # The reference at its epochs, with noise ten times the sensor's over an interval.
    every = fine * round(rate_hz / ref_hz)
    pick = np.arange(0, len(t_fine), every)
    pick = pick[(t_fine[pick] >= 0.0) & (t_fine[pick] <= t[-1])]
    angle_noise = ref_noise_ratio * unit.gyro_sigma * np.sqrt(interval_s / rate_hz)
    velocity_noise = ref_noise_ratio * unit.accel_sigma * np.sqrt(interval_s / rate_hz)
    q_ref = (att[pick] * Rotation.from_rotvec(rng.normal(0.0, angle_noise, (len(pick), 3)))).as_quat()
    v_ref = v_n[pick] + rng.normal(0.0, velocity_noise, (len(pick), 3))
    return Session(t=t, gyro=gyro, accel=accel, t_ref=t_fine[pick], q_nb=q_ref, v_n=v_ref, unit=unit)
