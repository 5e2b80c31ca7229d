"""An independent calibration rig: another tool's procedures and IMU, with numpy alone (no ``sins``, no scipy).

It plays a rig procedure sins did not arrange, so that sins's learned IMU-error compensation can be
judged on data it had no hand in. Everything here is written from the textbook physics below.

Conventions
-----------
* SI units throughout (s, rad, rad/s, m/s², °C); angles in the public arguments are named ``*_dps``
  where they are degrees per second.
* Body frame FRD (x forward, y right, z down); navigation frame NED, fixed to the Earth at a point
  at latitude ``LAT`` = 45° (no linear motion, no lever arm: the rig sits still on the ground).
* Attitude: quaternion ``q_nb`` **scalar first** ``(w, x, y, z)``, Hamilton product, body → nav:
  ``v_n = q_nb ⊗ v_b ⊗ q_nb*``; its DCM ``C_nb`` (body → nav), ``C_bn = C_nbᵀ``.
* Specific force ``f_ib_b = C_bn (0, 0, -G)`` (a level unit at rest reads ``f_z = -G``). ``G`` is a
  constant 9.80665 m/s² (the rig's own value; no gravity model, no plumb-line deflection).
* Angular rate ``omega_ib_b = C_bn omega_ie_n + omega_nb_b`` with ``omega_ie_n = Ω (cos φ, 0, -sin φ)``,
  ``Ω = 7.292115e-5`` rad/s; ``omega_nb_b`` is the rig's turning (tumble or table) in body axes. The
  nav frame turns with the Earth only (the transport rate is zero: the rig does not move).
* A rate table turns about the local vertical; a positive table rate turns the unit about +down,
  clockwise seen from above (heading increasing): ``omega_nb_n = (0, 0, rate)``, so
  ``omega_nb_b = C_bn (0, 0, rate)``.
* The rig's reference is the truth: the rig's own errors (table rate error, tilt, timing) are not
  modelled. Temperatures are the unit's, °C.
* At rest ``f·ω = (-G)(-Ω sin φ) = G Ω sin φ``: the angle between the force (up) and the Earth's rate
  is ``90° - φ``.

Public: :class:`Unit` (an IMU's errors, :meth:`Unit.errors`, :meth:`Unit.read`), :func:`baseline_unit`,
:class:`Session` and the procedures :func:`tumble_and_table`, :func:`faces_and_axis_table`,
:func:`continuous_tumble`, and :func:`write_csv` (a rig recording sins's ``read_recording`` accepts).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np

G = 9.80665  # m/s², a constant
EARTH_RATE = 7.292115e-5  # rad/s
LAT = np.radians(45.0)
DEG = np.pi / 180.0
OMEGA_IE_N = EARTH_RATE * np.array([np.cos(LAT), 0.0, -np.sin(LAT)])
GRAVITY_F_N = np.array([0.0, 0.0, -G])  # specific force at rest, nav frame (up)
REST_S = 2.0  # a table's rest before and after each mount's run, s
T_REF = 20.0  # the temperature at which the unit's temperature terms vanish, °C

_Z3 = partial(np.zeros, 3)


# ----------------------------------------------------------------------------------------------- the unit


@dataclass(frozen=True)
class Unit:
    """An IMU's errors, SI. ``u`` below is the true input (``ω`` rad/s for gyros, ``f`` m/s² for accels).

    reading = u + bias + M u [+ K f for gyros] + k2·u² + ka·|u| [+ G2 f f for gyros]
              + tc1 (T - 20) + tc2 (T - 20)² + ts (T - 20)·u + white noise

    The noises are densities (rad/s/√Hz, m/s²/√Hz): a sample at ``rate_hz`` has σ = density·√rate_hz
    (white noise band-limited to the Nyquist frequency, rate_hz/2, with a two-sided density).
    """

    gyro_bias: np.ndarray = field(default_factory=_Z3)  # (3,) rad/s
    gyro_M: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))  # scale + misalignment: M ω
    gyro_K: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))  # g-sensitivity: K f, rad/s per m/s²
    accel_bias: np.ndarray = field(default_factory=_Z3)  # (3,) m/s²
    accel_M: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))  # M f
    gyro_noise: float = 0.0  # rad/s/√Hz
    accel_noise: float = 0.0  # m/s²/√Hz
    gyro_k2: np.ndarray = field(default_factory=_Z3)  # k2_i ω_i², per rad/s
    accel_k2: np.ndarray = field(default_factory=_Z3)  # k2_i f_i², per m/s²
    gyro_ka: np.ndarray = field(default_factory=_Z3)  # asymmetry ka_i |ω_i|
    accel_ka: np.ndarray = field(default_factory=_Z3)  # ka_i |f_i|
    gyro_g2: np.ndarray = field(default_factory=lambda: np.zeros((3, 3, 3)))  # Σ_jk G2[i,j,k] f_j f_k
    gyro_tc1: np.ndarray = field(default_factory=_Z3)  # rad/s/K
    gyro_tc2: np.ndarray = field(default_factory=_Z3)  # rad/s/K²
    accel_tc1: np.ndarray = field(default_factory=_Z3)  # m/s²/K
    accel_tc2: np.ndarray = field(default_factory=_Z3)  # m/s²/K²
    gyro_ts: np.ndarray = field(default_factory=_Z3)  # scale per K: s_i (T - 20) ω_i
    accel_ts: np.ndarray = field(default_factory=_Z3)

    def errors(self, omega: np.ndarray, f: np.ndarray, temp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Deterministic errors ``(e_gyro, e_accel)``, (n, 3) each, at true ``omega``, ``f`` (n, 3), ``temp`` (n,)."""
        w, f = np.atleast_2d(omega), np.atleast_2d(f)
        dT = (np.asarray(temp, dtype=float).reshape(-1) - T_REF)[:, None]
        e_g = (self.gyro_bias + w @ self.gyro_M.T + f @ self.gyro_K.T + self.gyro_k2 * w**2
               + self.gyro_ka * np.abs(w) + np.einsum("ijk,nj,nk->ni", self.gyro_g2, f, f)
               + self.gyro_tc1 * dT + self.gyro_tc2 * dT**2 + self.gyro_ts * dT * w)  # fmt: skip
        e_a = (self.accel_bias + f @ self.accel_M.T + self.accel_k2 * f**2 + self.accel_ka * np.abs(f)
               + self.accel_tc1 * dT + self.accel_tc2 * dT**2 + self.accel_ts * dT * f)  # fmt: skip
        return e_g, e_a

    def read(
        self, omega: np.ndarray, f: np.ndarray, temp: np.ndarray, rate_hz: float, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """The unit's readings ``(gyro, accel)``: truth + :meth:`errors` + white noise at ``rate_hz``."""
        e_g, e_a = self.errors(omega, f, temp)
        root = np.sqrt(rate_hz)
        gyro = omega + e_g + self.gyro_noise * root * rng.standard_normal(e_g.shape)
        accel = f + e_a + self.accel_noise * root * rng.standard_normal(e_a.shape)
        return gyro, accel


def baseline_unit(rng: np.random.Generator) -> Unit:
    """The issue's baseline unit, drawn from ``rng``.

    Gyro bias N(0, 0.05 °/s) per axis; gyro and accel scale/misalignment entries N(0, 2e-3); gyro
    g-sensitivity N(0, 0.02 °/s/g) per entry; accel bias N(0, 5 mg); white noise 0.001 °/s/√Hz and
    0.1 mg/√Hz, i.e. σ = 0.01 °/s and 1 mg per sample at 100 Hz.
    """
    return Unit(
        gyro_bias=rng.normal(0.0, 0.05 * DEG, 3),
        gyro_M=rng.normal(0.0, 2e-3, (3, 3)),
        gyro_K=rng.normal(0.0, 0.02 * DEG / G, (3, 3)),
        accel_bias=rng.normal(0.0, 5e-3 * G, 3),
        accel_M=rng.normal(0.0, 2e-3, (3, 3)),
        gyro_noise=0.01 * DEG / np.sqrt(100.0),
        accel_noise=1e-3 * G / np.sqrt(100.0),
    )


# ----------------------------------------------------------------------------------------------- rotations


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a ⊗ b``, scalar first, broadcasting over leading axes."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], axis=-1)  # fmt: skip


def _qconj(q: np.ndarray) -> np.ndarray:
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def _qexp(rv: np.ndarray) -> np.ndarray:
    """The unit quaternion of rotation vector ``rv`` (rad): ``(cos θ/2, sin(θ/2) rv/θ)``."""
    rv = np.asarray(rv, dtype=float)
    theta = np.linalg.norm(rv, axis=-1, keepdims=True)
    small = theta < 1e-4
    safe = np.where(small, 1.0, theta)
    # sin(θ/2)/θ: the series below is exact to 1e-18 for θ < 1e-4
    k = np.where(small, 0.5 - theta**2 / 48.0, np.sin(safe / 2) / safe)
    return np.concatenate([np.cos(theta / 2), k * rv], axis=-1)


def _qlog(q: np.ndarray) -> np.ndarray:
    """The rotation vector (rad, angle in [0, π]) of unit quaternion ``q``: the shortest way round."""
    q = np.where(q[..., :1] < 0, -q, q)
    s = np.linalg.norm(q[..., 1:], axis=-1, keepdims=True)
    theta = 2 * np.arctan2(s, q[..., :1])
    tiny = s < 1e-12  # then w ≈ 1 and θ/s → 2/w
    return q[..., 1:] * np.where(tiny, 2.0 / np.where(tiny, q[..., :1], 1.0), theta / np.where(tiny, 1.0, s))


def _dcm(q: np.ndarray) -> np.ndarray:
    """``C_nb`` (..., 3, 3) of ``q_nb`` (..., 4)."""
    w, x, y, z = np.moveaxis(q / np.linalg.norm(q, axis=-1, keepdims=True), -1, 0)
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
                     np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
                     np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)],
                    axis=-2)  # fmt: skip


def _qz(psi: np.ndarray) -> np.ndarray:
    """Rotation by ``psi`` about nav +down (heading)."""
    psi = np.asarray(psi, dtype=float)[..., None]
    zero = np.zeros_like(psi)
    return np.concatenate([np.cos(psi / 2), zero, zero, np.sin(psi / 2)], axis=-1)


def _qcumprod(dq: np.ndarray) -> np.ndarray:
    """Running products ``dq[0] ⊗ dq[1] ⊗ … ⊗ dq[k]`` for every k: a parallel prefix scan.

    Hillis–Steele: log2(n) vectorized passes, each element through at most log2(n) products, so the
    rounding stays at ~1e-15 where a sequential loop would pile up n products (and be slow in Python).
    The product is associative, not commutative: the earlier factor always stays on the left.
    """
    out = dq.copy()
    d = 1
    while d < len(out):
        out[d:] = _qmul(out[:-d], out[d:])
        d *= 2
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def _random_quat(rng: np.random.Generator, n: int) -> np.ndarray:
    """Uniform on SO(3): a normalized 4-D normal vector is uniform on S³ (the Haar measure)."""
    q = rng.standard_normal((n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _mount(axis_b: np.ndarray, heading: float) -> np.ndarray:
    """``q_nb`` that points body vector ``axis_b`` up (nav -down), then turned by ``heading`` about the vertical."""
    a = np.asarray(axis_b, dtype=float) / np.linalg.norm(axis_b)
    up = np.array([0.0, 0.0, -1.0])
    c = float(a @ up)
    if c < -1 + 1e-12:  # pointing down: half a turn about any horizontal axis
        arc = np.array([0.0, 1.0, 0.0, 0.0])
    else:  # shortest arc a → up: axis a × up, angle acos(c); q = (1 + c, a × up) normalized
        arc = np.concatenate([[1.0 + c], np.cross(a, up)])
        arc /= np.linalg.norm(arc)
    return _qmul(_qz(heading), arc)


# ----------------------------------------------------------------------------------------------- sessions


@dataclass(frozen=True)
class Session:
    """A procedure's reference: the truth the unit sees, sample by sample.

    ``t`` (n,) s from 0; ``ref_gyro`` (n, 3) ``omega_ib_b`` rad/s; ``ref_accel`` (n, 3) ``f_ib_b`` m/s²;
    ``temp`` (n,) °C; ``rate_hz``; ``name``. Beyond what a rig file holds: ``q_nb`` (n, 4) the attitude
    the reference was computed from (scalar first) and ``static`` (n,) True on the samples of a
    commanded hold or table rest, for checks and plots.
    """

    t: np.ndarray
    ref_gyro: np.ndarray
    ref_accel: np.ndarray
    temp: np.ndarray
    rate_hz: float
    name: str
    q_nb: np.ndarray
    static: np.ndarray

    def __len__(self) -> int:
        return len(self.t)


def _reference(q_nb: np.ndarray, omega_nb_b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(omega_ib_b, f_ib_b)`` from the attitude and the rig's turning rate: Earth's rate and gravity
    are fixed in the nav frame, so the body sees them through ``C_bn``."""
    C_bn = np.swapaxes(_dcm(q_nb), -1, -2)
    return omega_nb_b + C_bn @ OMEGA_IE_N, C_bn @ GRAVITY_F_N


# A scripted procedure is a list of pieces, each exact in continuous time, sampled on one clock:
#   ("hold", T, q)                     still at q
#   ("move", T, q0, φ)                 q0 ⊗ exp(φ τ/T): constant body rate φ/T (rotation vector of q0* ⊗ q1)
#   ("table", T, q_m, ψ0, r0, s)       q_z(ψ) ⊗ q_m, ψ = ψ0 + r0 τ + s τ²/2 (rate r0 + s τ about +down)


class _Script:
    def __init__(self, q0: np.ndarray):
        self.pieces: list[tuple] = []
        self.q = np.asarray(q0, dtype=float)  # the attitude at the end of the script so far

    def hold(self, seconds: float) -> None:
        self.pieces.append(("hold", seconds, self.q))

    def move(self, q1: np.ndarray, seconds: float) -> None:
        phi = _qlog(_qmul(_qconj(self.q), q1))  # q1 = q ⊗ exp(φ): φ in body axes
        self.pieces.append(("move", seconds, self.q, phi))
        self.q = _qmul(self.q, _qexp(phi))  # = ±q1

    def table(self, rates: Sequence[float], dwell_s: float, accel: float) -> None:
        """From rest: rest, then ramp (at ``accel`` rad/s²) to each rate and dwell, ramp to 0, rest."""
        q_m, psi, r = self.q, 0.0, 0.0
        self.hold(REST_S)
        for target in [*rates, 0.0]:
            ramp = abs(target - r) / accel
            slope = np.sign(target - r) * accel
            self.pieces.append(("table", ramp, q_m, psi, r, slope))
            psi += r * ramp + slope * ramp**2 / 2  # the exact integral of the linear rate
            r = target
            if target != 0.0:
                self.pieces.append(("table", dwell_s, q_m, psi, r, 0.0))
                psi += r * dwell_s
        self.q = _qmul(_qz(psi), q_m)
        self.hold(REST_S)

    def sample(self, rate_hz: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(t, q_nb, omega_nb_b, static)`` at ``t = k / rate_hz`` over the script's length."""
        durations = np.array([p[1] for p in self.pieces])
        starts = np.concatenate([[0.0], np.cumsum(durations)])
        t = np.arange(int(np.floor(starts[-1] * rate_hz + 1e-9))) / rate_hz
        q, w = np.empty((len(t), 4)), np.zeros((len(t), 3))
        static = np.zeros(len(t), dtype=bool)
        edges = np.searchsorted(t, starts, side="left")  # piece j holds samples edges[j]:edges[j+1]
        for j, piece in enumerate(self.pieces):
            rows = slice(edges[j], edges[j + 1])
            tau = t[rows] - starts[j]
            if piece[0] == "hold":
                q[rows], static[rows] = piece[2], True
            elif piece[0] == "move":
                _, T, q0, phi = piece
                q[rows] = _qmul(q0, _qexp(np.outer(tau / T, phi)))
                w[rows] = phi / T
            else:
                _, T, q_m, psi0, r0, s = piece
                q[rows] = _qmul(_qz(psi0 + r0 * tau + s * tau**2 / 2), q_m)
                rate = r0 + s * tau
                # the table axis (nav down) in body axes, times the table rate
                w[rows] = rate[:, None] * np.swapaxes(_dcm(q[rows]), -1, -2)[:, :, 2]
                static[rows] = (r0 == 0.0) & (s == 0.0)
        return t, q, w, static


def _session(script: _Script, rate_hz: float, name: str, temp_of) -> Session:
    t, q, w_nb, static = script.sample(rate_hz)
    gyro, accel = _reference(q, w_nb)
    return Session(t, gyro, accel, temp_of(t), float(rate_hz), name, q, static)


def _table_rates(fractions: Sequence[float], max_rate_dps: float) -> list[float]:
    """+a, -a, +b, -b, … rad/s, in the order given."""
    return [s * x * max_rate_dps * DEG for x in fractions for s in (1.0, -1.0)]


def tumble_and_table(
    rate_hz: float = 100.0,
    seed: int = 0,
    holds: int = 30,
    hold_s: float = 8.0,
    move_s: float = 2.0,
    max_rate_dps: float = 250.0,
    mounts: int = 7,
    temp_range: tuple[float, float] = (10.0, 40.0),
) -> Session:
    """Tumble through ``holds`` random orientations, then a single-axis rate table in ``mounts`` mountings.

    Tumble: orientations uniform on SO(3), each held still ``hold_s``, turned from one to the next at
    the constant body rate that takes it there in ``move_s``. Table, about the local vertical: mounts
    with body +x, -x, +y, -y, +z, -z up, then the diagonal (1, 1, 1)/√3 up, then random axes up, each
    at a random heading and reached by a ``move_s`` turn; at each: rest 2 s, rates +0.1, -0.1, +0.3,
    -0.3, +0.6, -0.6, +1.0, -1.0 × ``max_rate_dps`` dwelling 4 s, ramps at 200 °/s², back to rest, rest 2 s.
    Temperature rises linearly from ``temp_range[0]`` to ``temp_range[1]`` over the session.
    """
    rng = np.random.default_rng(seed)
    attitudes = _random_quat(rng, holds)
    script = _Script(attitudes[0])
    script.hold(hold_s)
    for q1 in attitudes[1:]:
        script.move(q1, move_s)
        script.hold(hold_s)
    axes = [np.eye(3)[i // 2] * (1 - 2 * (i % 2)) for i in range(6)] + [np.ones(3) / np.sqrt(3)]
    axes += list(rng.standard_normal((max(mounts - 7, 0), 3)))
    rates = _table_rates((0.1, 0.3, 0.6, 1.0), max_rate_dps)
    for axis in axes[:mounts]:
        script.move(_mount(axis, rng.uniform(0, 2 * np.pi)), move_s)
        script.table(rates, dwell_s=4.0, accel=200.0 * DEG)
    lo, hi = temp_range
    return _session(script, rate_hz, "tumble_and_table", lambda t: lo + (hi - lo) * t / t[-1])


def faces_and_axis_table(
    rate_hz: float = 200.0,
    seed: int = 0,
    hold_s: float = 15.0,
    max_rate_dps: float = 300.0,
    temp_profile: str = "soak",
    move_s: float = 3.0,
) -> Session:
    """Six faces down, then a rate table with the unit x-up, y-up and z-up.

    Faces: +x, -x, +y, -y, +z, -z down in turn, level, at a random heading, still ``hold_s``, turned
    between at constant rate over ``move_s``. Table about the vertical: per mount (reached by a
    ``move_s`` turn) rest 2 s, rates ±0.05, ±0.2, ±0.5, ±1.0 × ``max_rate_dps`` (plus first) dwelling
    6 s, ramps at 150 °/s², back to rest, rest 2 s. ``temp_profile``: "soak" (20 °C for the first half,
    then a step to 35 °C approached first-order with τ = 120 s), "ramp" (15 → 35 °C linear),
    "constant" (20 °C).
    """
    if temp_profile not in ("soak", "ramp", "constant"):
        raise ValueError(f"temp_profile {temp_profile!r} is not one of 'soak', 'ramp', 'constant'")
    rng = np.random.default_rng(seed)
    faces = [np.eye(3)[i // 2] * (2 * (i % 2) - 1) for i in range(6)]  # -x up is +x down, …
    script = _Script(_mount(faces[0], rng.uniform(0, 2 * np.pi)))
    script.hold(hold_s)
    for axis in faces[1:]:
        script.move(_mount(axis, rng.uniform(0, 2 * np.pi)), move_s)
        script.hold(hold_s)
    rates = _table_rates((0.05, 0.2, 0.5, 1.0), max_rate_dps)
    for axis in np.eye(3):
        script.move(_mount(axis, rng.uniform(0, 2 * np.pi)), move_s)
        script.table(rates, dwell_s=6.0, accel=150.0 * DEG)

    def temp_of(t: np.ndarray) -> np.ndarray:
        if temp_profile == "constant":
            return np.full(len(t), 20.0)
        if temp_profile == "ramp":
            return 15.0 + 20.0 * t / t[-1]
        half = t[-1] / 2
        return np.where(t < half, 20.0, 35.0 - 15.0 * np.exp(-np.maximum(t - half, 0.0) / 120.0))

    return _session(script, rate_hz, "faces_and_axis_table", temp_of)


def continuous_tumble(
    rate_hz: float = 50.0,
    seed: int = 0,
    duration_s: float = 600.0,
    max_rate_dps: float = 200.0,
    temp_range: tuple[float, float] = (15.0, 30.0),
    substeps: int = 8,
) -> Session:
    """Continuous tumbling: each body rate a sum of three incommensurate sines with random phases.

    Frequencies f0·r_j·s_i with f0 = 0.0137 Hz, r = (1, √2, √5) and s = (1, 2^¼, 3^⅓) (23 to 73 s
    periods; irrational ratios, so the motion never repeats); each axis scaled so that its largest
    sampled |ω_i| is ``max_rate_dps``. The attitude starts at a random one and is integrated exactly
    over ``substeps`` sub-steps per sample, each a rotation by the sub-step's midpoint rate times its
    length (error per sample ~ h³|ω × ω̇|/(24 substeps²), ~1e-9 rad at the defaults). The temperature
    is a sine of period ``duration_s`` from ``temp_range[0]`` up to ``temp_range[1]`` and back.
    """
    rng = np.random.default_rng(seed)
    freq = 0.0137 * np.outer([1.0, 2**0.25, 3 ** (1 / 3)], [1.0, np.sqrt(2), np.sqrt(5)])  # (axis, sine)
    phase = rng.uniform(0, 2 * np.pi, (3, 3))
    n = int(round(duration_s * rate_hz))
    t = np.arange(n) / rate_hz

    def shape(tt: np.ndarray) -> np.ndarray:
        return np.sin(2 * np.pi * tt[:, None, None] * freq + phase).sum(axis=2)

    gain = max_rate_dps * DEG / np.abs(shape(t)).max(axis=0)
    h = 1.0 / (rate_hz * substeps)
    mid = (np.arange(n * substeps) + 0.5) * h  # sub-step midpoints
    dq = _qexp(gain * shape(mid) * h)
    dq = np.concatenate([_random_quat(rng, 1), dq[: (n - 1) * substeps]])
    q = _qcumprod(dq)[::substeps]
    w_nb = gain * shape(t)
    gyro, accel = _reference(q, w_nb)
    lo, hi = temp_range
    temp = lo + (hi - lo) * (1 - np.cos(2 * np.pi * t / duration_s)) / 2
    return Session(t, gyro, accel, temp, float(rate_hz), "continuous_tumble", q, np.zeros(n, dtype=bool))


# ----------------------------------------------------------------------------------------------- files

# sins's rig recording (sins/io.py, read_recording): a header row of names in any order, '#' comment
# lines above it; t s, gyro_* and ref_gyro_* rad/s, accel_* and ref_accel_* m/s², optional temp °C.
_COLUMNS = ("t", "gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z",
            "ref_gyro_x", "ref_gyro_y", "ref_gyro_z", "ref_accel_x", "ref_accel_y", "ref_accel_z", "temp")  # fmt: skip


def write_csv(
    path: str | Path,
    session: Session,
    gyro: np.ndarray,
    accel: np.ndarray,
    *,
    columns_order: str | Sequence[str] = "shuffled",
    digits: int = 10,
) -> tuple[str, ...]:
    """Write a rig recording with ``numpy.savetxt`` at ``digits`` significant digits; return the column order.

    ``columns_order``: "shuffled" (a fixed permutation, not sins's order, different from it), "sins"
    (t, gyro, accel, ref_gyro, ref_accel, temp) or the names in the order wanted. No ``phase`` column.
    """
    if columns_order == "shuffled":
        order = tuple(_COLUMNS[i] for i in np.random.default_rng(20240611).permutation(len(_COLUMNS)))
    elif columns_order == "sins":
        order = _COLUMNS
    else:
        order = tuple(columns_order)
        if sorted(order) != sorted(_COLUMNS):
            raise ValueError(f"columns_order must name each of {_COLUMNS} once, got {order}")
    values = dict(zip(_COLUMNS, [session.t, *np.asarray(gyro).T, *np.asarray(accel).T,
                                 *session.ref_gyro.T, *session.ref_accel.T, session.temp], strict=True))  # fmt: skip
    printed_t = np.array([float(f"{x:.{digits}g}") for x in session.t])
    if (np.diff(printed_t) <= 0).any():
        raise ValueError(f"{digits} significant digits do not keep the times increasing; use more")
    header = (
        f"# independent rig (tests/independent_rig.py, numpy.savetxt): {session.name}, "
        f"{session.rate_hz:g} Hz, {len(session)} rows, gyro rad/s, accel m/s², temp °C\n" + ",".join(order)
    )
    data = np.column_stack([values[c] for c in order])
    np.savetxt(path, data, fmt=f"%.{digits}g", delimiter=",", header=header, comments="", encoding="utf-8")
    return order
