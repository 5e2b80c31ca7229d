"""Another tool's rig procedures and IMU, written with numpy alone (no ``sins``): data sins did not arrange.

Used by the cross-rig tests and ``tools/bench_crossrig.py`` to judge compensation fitted on one
procedure against others. Conventions, stated here once: SI units; body axes forward-right-down, the
navigation frame north-east-down; ``C_nb`` turns body vectors into navigation ones; at rest the
specific force is ``C_bn (0, 0, -G)`` (a level unit reads ``f_z = -G``) and the angular rate
``C_bn ω_ie`` with ``ω_ie = Ω (cos φ, 0, -sin φ)`` at latitude φ = 45°. ``G`` is a constant (a rig's
own gravity, not a model). A table turns about the local vertical, positive clockwise seen from above
(about +down). The reference is the truth: the rig's own errors are not modelled.

A :class:`Unit` holds the errors the seed paper models (bias, scale and misalignment, g-sensitivity)
and the nonlinear ones sins's library names, each written out below from its textbook form.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

G = 9.80665
EARTH_RATE = 7.292115e-5
LAT = np.radians(45.0)
DEG = np.pi / 180.0


def _zeros(*shape: int) -> np.ndarray:
    """A zero-array default (a ``dataclasses.field`` with a factory, not a shared array)."""
    return field(default_factory=lambda: np.zeros(shape))


@dataclass(frozen=True)
class Unit:
    """An IMU's errors; every field SI. Noise as densities (per √Hz): a sample's σ = density·√rate."""

    gyro_bias: np.ndarray = _zeros(3)
    gyro_M: np.ndarray = _zeros(3, 3)  # error M ω
    gyro_K: np.ndarray = _zeros(3, 3)  # error K f
    accel_bias: np.ndarray = _zeros(3)
    accel_M: np.ndarray = _zeros(3, 3)
    gyro_noise: float = 0.0
    accel_noise: float = 0.0
    gyro_k2: np.ndarray = _zeros(3)  # k2_i ω_i²
    accel_k2: np.ndarray = _zeros(3)
    gyro_ka: np.ndarray = _zeros(3)  # ka_i |u_i|
    accel_ka: np.ndarray = _zeros(3)
    gyro_g2: np.ndarray = _zeros(3, 3, 3)  # Σ_jk G2[i, j, k] f_j f_k
    gyro_tc1: np.ndarray = _zeros(3)  # c1 (T - 20) + c2 (T - 20)²
    gyro_tc2: np.ndarray = _zeros(3)
    accel_tc1: np.ndarray = _zeros(3)
    accel_tc2: np.ndarray = _zeros(3)
    gyro_ts: np.ndarray = _zeros(3)  # s_i (T - 20) u_i
    accel_ts: np.ndarray = _zeros(3)

    def errors(self, w: np.ndarray, f: np.ndarray, temp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Deterministic errors (n, 3) of the gyros and accelerometers at true inputs ``w``, ``f``."""
        dt = (np.asarray(temp, dtype=float) - 20.0)[:, None]
        e_g = self.gyro_bias + w @ self.gyro_M.T + f @ self.gyro_K.T + self.gyro_k2 * w**2
        e_g = e_g + self.gyro_ka * np.abs(w) + np.einsum("ijk,nj,nk->ni", self.gyro_g2, f, f)
        e_g = e_g + self.gyro_tc1 * dt + self.gyro_tc2 * dt**2 + self.gyro_ts * dt * w
        e_a = self.accel_bias + f @ self.accel_M.T + self.accel_k2 * f**2 + self.accel_ka * np.abs(f)
        e_a = e_a + self.accel_tc1 * dt + self.accel_tc2 * dt**2 + self.accel_ts * dt * f
        return e_g, e_a

    def read(
        self, w: np.ndarray, f: np.ndarray, temp: np.ndarray, rate_hz: float, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """Readings: truth + errors + white noise."""
        e_g, e_a = self.errors(w, f, temp)
        root = np.sqrt(rate_hz)
        gyro = w + e_g + self.gyro_noise * root * rng.standard_normal(w.shape)
        accel = f + e_a + self.accel_noise * root * rng.standard_normal(f.shape)
        return gyro, accel


def baseline_unit(rng: np.random.Generator) -> Unit:
    """The issue's baseline unit: 0.05 °/s gyro bias, 2e-3 scale and misalignment, 0.02 °/s/g
    g-sensitivity, 5 mg accelerometer bias; 0.01 °/s and 1 mg white noise per sample at 100 Hz."""
    return Unit(
        gyro_bias=0.05 * DEG * rng.standard_normal(3),
        gyro_M=2e-3 * rng.standard_normal((3, 3)),
        gyro_K=0.02 * DEG / G * rng.standard_normal((3, 3)),
        accel_bias=5e-3 * G * rng.standard_normal(3),
        accel_M=2e-3 * rng.standard_normal((3, 3)),
        gyro_noise=0.01 * DEG / 10.0,
        accel_noise=1e-3 * G / 10.0,
    )


@dataclass(frozen=True)
class Session:
    """A procedure's truth (= reference) and chamber temperature at ``rate_hz``."""

    t: np.ndarray
    ref_gyro: np.ndarray
    ref_accel: np.ndarray
    temp: np.ndarray
    rate_hz: float
    name: str


# ----------------------------------------------------------------------------- rotations (scalar first)


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    w = aw * bw - ax * bx - ay * by - az * bz
    x = aw * bx + ax * bw + ay * bz - az * by
    y = aw * by - ax * bz + ay * bw + az * bx
    z = aw * bz + ax * by - ay * bx + az * bw
    return np.stack([w, x, y, z], axis=-1)


def _qrotvec(v: np.ndarray) -> np.ndarray:
    angle = np.linalg.norm(v, axis=-1, keepdims=True)
    half = 0.5 * angle
    sinc = np.where(angle > 1e-12, np.sin(half) / np.where(angle > 1e-12, angle, 1.0), 0.5)
    return np.concatenate([np.cos(half), sinc * v], axis=-1)


def _dcm(q: np.ndarray) -> np.ndarray:
    """C_nb (..., 3, 3) of quaternions q_nb (body to navigation)."""
    w, x, y, z = np.moveaxis(q, -1, 0)
    rows = (
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    )
    return np.stack([np.stack(r, -1) for r in rows], -2)


def _up(axis: np.ndarray) -> np.ndarray:
    """q_nb with body vector ``axis`` pointing up (along -down) by the shortest rotation."""
    a = axis / np.linalg.norm(axis)
    up = np.array([0.0, 0.0, -1.0])
    c = float(a @ up)
    if c < -1 + 1e-12:
        return np.array([0.0, 1.0, 0.0, 0.0])
    v = np.cross(a, up)
    q = np.concatenate([[1.0 + c], v])
    return q / np.linalg.norm(q)


def _inputs(q_nb: np.ndarray, w_turn_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Body angular rate (Earth's plus the turn's) and specific force along an attitude history."""
    c_bn = np.swapaxes(_dcm(q_nb), -1, -2)
    w_ie = EARTH_RATE * np.array([np.cos(LAT), 0.0, -np.sin(LAT)])
    return c_bn @ w_ie + w_turn_b, c_bn @ np.array([0.0, 0.0, -G])


def _table(q_mount: np.ndarray, rates: list[float], dwell_s: float, accel: float, rate_hz: float):
    """Attitude and body turn rate of a table about +down through ``rates`` (rad/s), from rest to rest:
    a ramp at ``accel`` to each rate, a dwell, and a ramp back to rest at the end."""
    knots_t, knots_w = [0.0], [0.0]
    for w in [*rates, 0.0]:
        knots_t.append(knots_t[-1] + abs(w - knots_w[-1]) / accel)
        knots_w.append(w)
        if w != 0.0:
            knots_t.append(knots_t[-1] + dwell_s)
            knots_w.append(w)
    t = np.arange(round(knots_t[-1] * rate_hz)) / rate_hz
    rate = np.interp(t, knots_t, knots_w)
    kt, kw = np.array(knots_t), np.array(knots_w)
    kangle = np.concatenate([[0.0], np.cumsum(0.5 * (kw[1:] + kw[:-1]) * np.diff(kt))])
    i = np.clip(np.searchsorted(kt, t, side="right") - 1, 0, len(kt) - 2)
    angle = kangle[i] + 0.5 * (kw[i] + rate) * (t - kt[i])  # exact: the rate is piecewise linear
    q_turn = _qrotvec(angle[:, None] * np.array([0.0, 0.0, 1.0]))
    q = _qmul(q_turn, q_mount)
    c_bn = np.swapaxes(_dcm(q), -1, -2)
    return q, c_bn @ np.array([0.0, 0.0, 1.0]) * rate[:, None]


def _session(parts: list[tuple[np.ndarray, np.ndarray]], temp_of, rate_hz: float, name: str) -> Session:
    q = np.concatenate([p[0] for p in parts])
    w_turn = np.concatenate([p[1] for p in parts])
    w, f = _inputs(q, w_turn)
    t = np.arange(len(q)) / rate_hz
    return Session(t=t, ref_gyro=w, ref_accel=f, temp=temp_of(t), rate_hz=rate_hz, name=name)


def _hold(q: np.ndarray, seconds: float, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    n = round(seconds * rate_hz)
    return np.repeat(q[None], n, axis=0), np.zeros((n, 3))


def _move(q0: np.ndarray, q1: np.ndarray, seconds: float, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """From q0 to q1 at a constant body rate over ``seconds``."""
    rel = _qmul(q0 * np.array([1, -1, -1, -1]), q1)  # q0⁻¹ q1: the turn in body axes
    rel = rel if rel[0] >= 0 else -rel
    angle = 2.0 * np.arctan2(np.linalg.norm(rel[1:]), rel[0])
    axis = rel[1:] / max(np.linalg.norm(rel[1:]), 1e-15)
    n = round(seconds * rate_hz)
    s = np.arange(n) / rate_hz
    return _qmul(q0, _qrotvec(s[:, None] * axis * angle / seconds)), np.tile(axis * angle / seconds, (n, 1))


def tumble_and_table(rate_hz: float = 100.0, seed: int = 0, holds: int = 30, hold_s: float = 8.0,
                     move_s: float = 2.0, max_rate_dps: float = 250.0,
                     temp_range: tuple[float, float] = (10.0, 40.0)) -> Session:  # fmt: skip
    """Tumbling through ``holds`` random orientations (uniform on the rotations; held ``hold_s``,
    turned between at a constant rate over ``move_s``), then a table to ``max_rate_dps`` with the unit
    in seven mounts (each axis up and down, then a body diagonal up); temperature linear over the range."""
    rng = np.random.default_rng([seed, 11])
    quats = rng.standard_normal((holds, 4))
    quats /= np.linalg.norm(quats, axis=1, keepdims=True)
    parts = []
    for k in range(holds):
        parts.append(_hold(quats[k], hold_s, rate_hz))
        if k + 1 < holds:
            parts.append(_move(quats[k], quats[k + 1], move_s, rate_hz))
    mounts = [np.eye(3)[i] * s for i in range(3) for s in (1.0, -1.0)] + [np.ones(3)]
    rates = [s * r * max_rate_dps * DEG for r in (0.1, 0.3, 0.6, 1.0) for s in (1.0, -1.0)]
    for axis in mounts:
        parts.append(_table(_up(axis), rates, 4.0, 200.0 * DEG, rate_hz))
    total = sum(len(p[0]) for p in parts) / rate_hz
    return _session(parts, lambda t: np.interp(t, [0.0, total], temp_range), rate_hz, "tumble_and_table")


def faces_and_axis_table(rate_hz: float = 200.0, seed: int = 0, hold_s: float = 15.0,
                         max_rate_dps: float = 300.0, temp_profile: str = "soak") -> Session:  # fmt: skip
    """Six faces down, then a table with the x, y and z axis up in turn, to ``max_rate_dps``.
    Temperature ``soak`` (20 °C, then a first-order approach to 35 °C with τ = 120 s from half-way),
    ``ramp`` (15 -> 35 °C) or ``constant`` (20 °C)."""
    parts = [_hold(_up(-np.eye(3)[i] * s), hold_s, rate_hz) for i in range(3) for s in (1.0, -1.0)]
    rates = [s * r * max_rate_dps * DEG for r in (0.05, 0.2, 0.5, 1.0) for s in (1.0, -1.0)]
    for i in range(3):
        parts.append(_table(_up(np.eye(3)[i]), rates, 6.0, 150.0 * DEG, rate_hz))
    total = sum(len(p[0]) for p in parts) / rate_hz

    def temp_of(t: np.ndarray) -> np.ndarray:
        if temp_profile == "soak":
            return np.where(t < total / 2, 20.0, 35.0 - 15.0 * np.exp(-(t - total / 2) / 120.0))
        if temp_profile == "ramp":
            return np.interp(t, [0.0, total], [15.0, 35.0])
        return np.full_like(t, 20.0)

    return _session(parts, temp_of, rate_hz, "faces_and_axis_table")


def continuous_tumble(rate_hz: float = 50.0, seed: int = 0, duration_s: float = 600.0,
                      max_rate_dps: float = 200.0,
                      temp_range: tuple[float, float] = (15.0, 30.0)) -> Session:  # fmt: skip
    """Continuous tumbling: each body rate a sum of three sines of incommensurate periods and random
    phases peaking near ``max_rate_dps``; temperature one slow sine between the range's ends."""
    rng = np.random.default_rng([seed, 13])
    n = round(duration_s * rate_hz)
    t = np.arange(n) / rate_hz
    periods = rng.uniform(3.0, 40.0, (3, 3))
    phases = rng.uniform(0.0, 2 * np.pi, (3, 3))
    amps = np.array([0.5, 0.3, 0.2]) * max_rate_dps * DEG
    w_turn = sum(amps[k] * np.sin(2 * np.pi * t[:, None] / periods[:, k] + phases[:, k]) for k in range(3))
    # Attitude by the rotation vector of the midpoint rate over each step (second order).
    mid = 0.5 * (w_turn[1:] + w_turn[:-1]) / rate_hz
    q = np.empty((n, 4))
    q[0] = _up(np.array([0.3, -0.2, 1.0]))
    steps = _qrotvec(mid)
    for k in range(n - 1):
        q[k + 1] = _qmul(q[k], steps[k])
    lo, hi = temp_range

    def temp_of(tt: np.ndarray) -> np.ndarray:
        return lo + (hi - lo) * 0.5 * (1.0 - np.cos(2 * np.pi * tt / duration_s))

    return _session([(q, w_turn)], temp_of, rate_hz, "continuous_tumble")


def write_csv(path: Path, session: Session, gyro: np.ndarray, accel: np.ndarray, digits: int = 10) -> None:
    """A recording as another tool would print it: ``numpy.savetxt`` at ``digits`` significant digits,
    columns in an order of its own, no phases."""
    names = ["temp", "ref_accel_x", "ref_accel_y", "ref_accel_z", "t", "accel_x", "accel_y", "accel_z",
             "gyro_x", "gyro_y", "gyro_z", "ref_gyro_x", "ref_gyro_y", "ref_gyro_z"]  # fmt: skip
    table = np.column_stack([session.temp, session.ref_accel, session.t, accel, gyro, session.ref_gyro])
    np.savetxt(path, table, delimiter=",", fmt=f"%.{digits}g", header=",".join(names), comments="")
    path.write_text(
        f"# written with numpy.savetxt by tests/numpy_rigs.py: {session.name}\n" + path.read_text()
    )
