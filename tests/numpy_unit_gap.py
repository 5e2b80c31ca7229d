"""Recordings in the ``.npz`` form of ``shared/data/euroc`` (its SOURCE.md) written with numpy and scipy's
``Rotation`` alone (no ``sins``): a unit of known errors turned and moved in a room, its reference noisier
than the sensor, with one effect added to the readings. The data of ``tests/test_unit_gap.py``.

The motion is ``tests/numpy_referenced.py``'s: the attitude ``C0 Exp(φ(t))``, ``φ`` sines on every axis (up
to 80° each), its body rate exactly ``J_r(φ) φ̇``; slow sines of velocity. With ``rests``, the turning
pauses: ``φ(s(t))`` with ``ṡ`` falling to 0 for 10 s of every 40 (raised-cosine ramps of 1 s), the
body rate ``J_r(φ) φ'(s) ṡ``. Unlike there the room's frame
has no known latitude (the ``.npz`` form's world frame: z up, north unknown), so the gyro reads the body's
turn in the room alone, as EuRoC's published figures take it. The reference is at every reading, its
attitude with white rotation noise of ``ref_angle_deg`` per epoch and its velocity with ``ref_mps``: at
0.05° and 5 mm/s beside a gyro of 0.05 °/s and an accelerometer of 10 mg per sample at 100 Hz, the
reference's noise over a one-second interval is 14 times the gyro's (BROAD's motion capture: 8.8 times),
and differentiated per sample some 140 times.

Effects (added to the readings from the true inputs, each sensor reading its own axes):
``gyro.scale_asymmetry`` ``ka |ω_i|``; ``gyro.motion_bias`` ``b |ω|² / (|ω|² + ω₀²)``, ω₀ = 5 °/s;
``gyro.time_offset`` the gyro's input ``τ`` late; ``accel.time_offset`` the accelerometer's 5 ms late on
every axis, ``accel.time_offset (both signs)`` +5, -5 and +5 ms on x, y and z (no one clock); ``gyro.y step``
a bias step on gyro y half way; ``gyro y←x`` 20 mrad more of the x rate read on gyro y (a recording whose
misalignment is not the unit's);
``gyro.bias_instability`` a first-order Gauss-Markov bias on every gyro axis (τ = 10 s, 0.3 °/s);
``gyro.rate_random_walk`` a walk on every gyro axis (:data:`WALK_DENSITY`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy_referenced import _right_jacobian
from scipy.signal import lfilter
from scipy.spatial.transform import Rotation

#: Normal gravity at the ``.npz`` form's nominal origin (45° N, 0° E, 0 m: sins places a room whose place
#: is not given there): Somigliana's formula with WGS84's γ_e, k and e², sin²φ = ½.
G = 9.7803253359 * (1.0 + 0.00193185265241 * 0.5) / np.sqrt(1.0 - 0.00669437999013 * 0.5)
DEG = np.pi / 180.0
DPH = DEG / 3600.0
#: The room's frame (ENU, z up) from the NED the motion is written in.
ENU_FROM_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


#: ``gyro.rate_random_walk``'s density, rad/s/√s (2,475 °/h/√h: a consumer unit's tens, raised so that
#: 150 s show it: its spread after 150 s is 0.14 °/s).
WALK_DENSITY = 2e-4


def motion_bias(omega: np.ndarray, b: np.ndarray, half_rate: float = 5.0 * DEG) -> np.ndarray:
    """``b |ω|² / (|ω|² + ω₀²)`` (n, 3): the bias in motion beyond the bias at rest."""
    w2 = np.sum(omega * omega, axis=1, keepdims=True)
    return w2 / (w2 + half_rate**2) * b


def recording(
    seed: int, effect: str = "clean", *, duration_s: float = 150.0, rate_hz: float = 100.0,
    ref_angle_deg: float = 0.05, ref_mps: float = 0.005, size: float = 1.0, unit_seed: int = 0,
    rests: bool = True, clock_s: float = 0.0, world_tilt_deg: tuple[float, float] = (0.0, 0.0),
) -> dict[str, np.ndarray]:  # fmt: skip
    """The ``.npz`` arrays of one recording (see the module docstring): the motion drawn from ``seed``,
    the unit (its bias, scale and misalignment) from ``unit_seed`` (one unit over several recordings),
    ``effect`` at ``size`` times its stated size added; ``clock_s`` both sensors' inputs read that much
    later still (a reference whose clock runs ahead of the readings' by ``clock_s``); ``world_tilt_deg``
    (north, east) the reference's world frame turned by that rotation vector from the level room, its
    z no longer up (a motion capture's frame set on a floor that is not level)."""
    rng = np.random.default_rng([seed, 1])
    b0, b, a0, a = unit_errors(unit_seed)
    fine = 10
    n = round(duration_s * rate_hz)
    t_fine = np.arange(n * fine + 1) / (rate_hz * fine)
    freqs, amps = rng.uniform(0.03, 0.3, 3), DEG * rng.uniform(30.0, 80.0, 3)
    phases = rng.uniform(0.0, 2 * np.pi, 3)
    s_dot = _pace(t_fine) if rests else np.ones_like(t_fine)
    s = np.concatenate([[0.0], np.cumsum(0.5 * (s_dot[1:] + s_dot[:-1]) * np.diff(t_fine))])
    arg = 2 * np.pi * freqs * s[:, None] + phases
    phi, phi_dot = amps * np.sin(arg), amps * 2 * np.pi * freqs * np.cos(arg) * s_dot[:, None]
    omega = _right_jacobian(phi, phi_dot)
    att = Rotation.from_euler("ZYX", rng.uniform(-1.0, 1.0, 3)) * Rotation.from_rotvec(phi)
    vf, va, vp = rng.uniform(0.05, 0.3, 3), rng.uniform(0.05, 0.1, 3), rng.uniform(0, 2 * np.pi, 3)
    v_n = va * np.sin(2 * np.pi * vf * t_fine[:, None] + vp)
    a_n = va * 2 * np.pi * vf * np.cos(2 * np.pi * vf * t_fine[:, None] + vp)
    f_b = att.inv().apply(a_n - np.array([0.0, 0.0, G]))
    t = np.arange(n + 1) / rate_hz
    delay = clock_s + (5e-3 * size if effect == "gyro.time_offset" else 0.0)
    w = np.stack([np.interp(t - delay, t_fine, omega[:, i]) for i in range(3)], axis=1)
    f = f_b[::fine]
    taus = np.full(3, clock_s)
    if effect.startswith("accel.time_offset"):  # each axis's input τ late: 5 ms, or of both signs
        taus += 5e-3 * size * (np.array([1.0, -1.0, 1.0]) if "both signs" in effect else np.ones(3))
    if np.any(taus != 0.0):
        f = np.stack([np.interp(t - taus[i], t_fine, f_b[:, i]) for i in range(3)], axis=1)
    gyro = w + b0 + w @ b.T + rng.normal(0.0, 0.05 * DEG, w.shape)
    accel = f + a0 + f @ a.T + rng.normal(0.0, 0.01, f.shape)
    if effect == "gyro.scale_asymmetry":
        gyro += 3000e-6 * size * np.abs(w)
    elif effect == "gyro.motion_bias":
        gyro += motion_bias(w, size * np.array([300.0, -200.0, 250.0]) * DPH)
    elif effect == "gyro.time_offset" or effect.startswith("accel.time_offset"):
        pass  # read late above
    elif effect == "gyro.y step":
        gyro[:, 1] += size * 0.3 * DEG * (t >= 0.5 * t[-1])
    elif effect == "gyro y←x":  # this recording's misalignment, not the unit's
        gyro[:, 1] += size * 20e-3 * w[:, 0]
    elif effect == "gyro.bias_instability":
        phi = np.exp(-1.0 / (rate_hz * 10.0))
        drive = size * 0.3 * DEG * np.sqrt(1.0 - phi * phi) * rng.normal(0.0, 1.0, gyro.shape)
        gyro += lfilter([1.0], [1.0, -phi], drive, axis=0)
    elif effect == "gyro.rate_random_walk":  # a walk of WALK_DENSITY: its steps' spread density·√dt
        gyro += np.cumsum(size * WALK_DENSITY / np.sqrt(rate_hz) * rng.normal(0.0, 1.0, gyro.shape), axis=0)
    elif effect != "clean":
        raise ValueError(f"unknown effect {effect!r}")
    noise = Rotation.from_rotvec(rng.normal(0.0, ref_angle_deg * DEG, (n + 1, 3)))
    north, east = world_tilt_deg
    tilted = Rotation.from_rotvec(DEG * np.array([east, north, 0.0])) * Rotation.from_matrix(ENU_FROM_NED)
    q_enu = (tilted * att[::fine] * noise).as_quat()  # scalar last
    v_enu = tilted.apply(v_n[::fine])
    p_enu = np.concatenate([[np.zeros(3)], np.cumsum(0.5 * (v_enu[1:] + v_enu[:-1]) / rate_hz, axis=0)])
    return {
        "t_s": t, "gyro_rad_s": gyro, "accel_m_s2": accel, "q_wxyz": q_enu[:, [3, 0, 1, 2]],
        "v_m_s": v_enu + rng.normal(0.0, ref_mps, v_enu.shape), "p_m": p_enu,
    }  # fmt: skip


def unit_errors(unit_seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The unit's gyro bias (rad/s) and scale-misalignment matrix, its accelerometer's bias (m/s²) and
    matrix, drawn from ``unit_seed``: each reading is ``x + bias + M x`` of its true input ``x``."""
    unit = np.random.default_rng([unit_seed, 2])
    b0, b = DEG * unit.normal(0.0, 0.1, 3), unit.normal(0.0, 3e-3, (3, 3))
    a0, a = unit.normal(0.0, 0.05, 3), unit.normal(0.0, 3e-3, (3, 3))
    return b0, b, a0, a


def _pace(t: np.ndarray, period: float = 40.0, rest: float = 10.0, ramp: float = 1.0) -> np.ndarray:
    """``ṡ``: 1 while turning, 0 for ``rest`` s at the end of every ``period``, raised-cosine ramps
    down into the rest and up out of it (the first period starts turning)."""
    phase = np.mod(t, period)
    down = 0.5 * (1.0 + np.cos(np.pi * np.clip((phase - (period - rest - ramp)) / ramp, 0.0, 1.0)))
    up = 0.5 * (1.0 - np.cos(np.pi * np.clip(phase / ramp, 0.0, 1.0)))
    return np.asarray(np.where(t < ramp, down, np.minimum(up, down)))


def write(path: Path, arrays: dict[str, np.ndarray]) -> Path:
    """The arrays as an ``.npz`` file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez(path, **arrays)
    return path


def write_euroc(folder: Path, arrays: dict[str, np.ndarray], t0_ns: int = 1_403_636_579_758_555_392) -> Path:
    """The arrays as a EuRoC folder: ``mav0/imu0/data.csv`` (ns stamps, rates, forces) and
    ``mav0/state_groundtruth_estimate0/data.csv`` (ns, position, attitude w x y z, velocity, and the
    estimator's biases, zero), every float printed with ``repr`` (exact)."""
    ns = t0_ns + np.round(arrays["t_s"] * 1e9).astype(np.int64)
    imu = np.hstack([arrays["gyro_rad_s"], arrays["accel_m_s2"]])
    ref = np.hstack([arrays["p_m"], arrays["q_wxyz"], arrays["v_m_s"], np.zeros((len(ns), 6))])
    for sub, header, values in (
        ("imu0", "#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z", imu),
        ("state_groundtruth_estimate0", "#timestamp," + ",".join(["c"] * 16), ref),
    ):
        path = folder / "mav0" / sub / "data.csv"
        path.parent.mkdir(parents=True, exist_ok=True)
        rows = [f"{s}," + ",".join(repr(float(x)) for x in row) for s, row in zip(ns, values, strict=True)]
        path.write_text("\n".join([header, *rows]) + "\n", encoding="utf-8")
    return folder
