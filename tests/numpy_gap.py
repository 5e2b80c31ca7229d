"""Every effect of sins's library written from its textbook form with numpy alone (no ``sins``): the data
of the gap diagnosis's generalisation suite (issue 19, item 3).

Conventions are ``tests/numpy_rigs.py``'s, stated here once: SI units (rad/s, m/s², s, °C); body axes
forward-right-down, the navigation frame north-east-down and fixed to the Earth; ``C_nb`` turns body
vectors into navigation ones; the specific force is ``C_bn (0, 0, -G)`` (no lever arm, no linear motion)
and the angular rate ``ω_ib = C_bn ω_ie + ω_nb`` at latitude 45°; a table turns about +down.

The procedures here are closed-form functions of time (attitude, body rate and angular acceleration at
any instant), modelled on numpy_rigs's three: random orientations held and joined by smooth moves then a
table in several mounts, the six faces then a table with each axis up, and continuous tumbling (ZYX
Euler angles each a sum of sines). Every rate is continuous (a move's rate rises and falls as a versine;
a table ramps at a constant acceleration), so that an angular acceleration ``ω̇`` (the size effect's)
exists at every sample and the reference at ``t - τ`` (a time offset's) is the procedure evaluated
there, not an interpolation. numpy_rigs's own three procedures (``rigs.*``), whose moves start and stop
in a sample, serve every effect but those two.

A recording is the reference plus numpy_rigs's :class:`~numpy_rigs.Unit` (the issue's baseline unit:
bias, scale and misalignment, g-sensitivity, white noise) plus one effect, in the order a sensor forms
its output: the input at ``t - τ``; the deterministic errors; the random biases; the white noise; the
clip at ``± limit``; the rounding to integer counts of the step. Each effect's size is a tactical unit's,
as sins's ``imu.spec.typical_effect`` states it (read, not imported), times ``scale``. Controls hold the
baseline alone; two disturbances lie outside the library: a 0.3 °/s sinusoid (period 37 s) and a 20 °/h
bias step on gyro x. Files are written by :func:`numpy_rigs.write_csv`: 10 significant digits, columns
in an order of its own, no phases.

The oracle (:func:`oracle_nats`) says whether a case's effect could be found at all: its own
contribution to the readings (noise-free readings with and without it), less what the baseline's
least-squares columns absorb over the whole recording, in units of the white noise, a 30 % share of it
(the diagnosis withholds the end of every stretch of like input): half its sum of squares is the withheld
log-likelihood gain a model that knew the effect would make, in nats. Below :data:`OBSERVABLE_NATS` a
case is "unobservable"; below it beyond its closest rival (:func:`identifiable_nats`: another regressor
of its sensor, or for a Gauss-Markov bias the random walk), "unidentifiable".
"""

from __future__ import annotations

import dataclasses
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy_rigs as nr

G = nr.G
DEG = nr.DEG
DEG_PER_H = DEG / 3600.0
MG = 1e-3 * G
#: A case's effect is observable where the oracle's withheld gain reaches this, in nats.
OBSERVABLE_NATS = 9.0
#: The fraction of a recording the diagnosis withholds (the end of every stretch of like input).
HOLDOUT = 0.3

#: The effect vocabulary of sins's library beyond the baseline (``sins effects``).
EFFECTS = (
    "gyro.scale_nonlinearity", "gyro.scale_asymmetry", "gyro.g2_sensitivity", "gyro.temperature_bias",
    "gyro.temperature_scale", "gyro.time_offset", "gyro.bias_instability", "gyro.rate_random_walk",
    "gyro.quantization", "gyro.saturation",
    "accel.scale_nonlinearity", "accel.scale_asymmetry", "accel.size_effect", "accel.temperature_bias",
    "accel.temperature_scale", "accel.time_offset", "accel.bias_instability", "accel.rate_random_walk",
    "accel.quantization", "accel.saturation",
)  # fmt: skip
#: The baseline alone, and two disturbances outside the library on gyro x.
CONTROLS = ("control", "sinusoid (outside)", "bias step (outside)")
#: The two cases issue 19 names: a gyro clipped only in the recording's last minutes, and a gyro
#: quantised to 0.06 °/s under 0.01 °/s of noise (100 Hz), printed at 10 significant digits; and issue
#: 32's: an accelerometer delay on a rig that turns between its holds in 0.3 s.
ISSUE_CASES = ("gyro.saturation (tail)", "gyro.quantization (0.06 °/s)", "accel.time_offset (fast turns)")


# ----------------------------------------------------------------------------- closed-form motion


def _conj(q: np.ndarray) -> np.ndarray:
    return q * np.array([1.0, -1.0, -1.0, -1.0])


class _Hold:
    """The unit held at attitude ``q``."""

    def __init__(self, q: np.ndarray, duration: float) -> None:
        self.q, self.duration = q, duration

    def state(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Attitude ``q_nb``, body turn rate ``ω_nb`` and its derivative at local times ``s``."""
        z = np.zeros((len(s), 3))
        return np.tile(self.q, (len(s), 1)), z, z.copy()

    def end(self) -> np.ndarray:
        return self.q


class _Move:
    """From ``q0`` to ``q1`` about a fixed body axis, the rate a versine: ``θ/T (1 - cos 2πs/T)``,
    zero at both ends with its derivative continuous."""

    def __init__(self, q0: np.ndarray, q1: np.ndarray, duration: float) -> None:
        rel = nr._qmul(_conj(q0), q1)
        rel = rel if rel[0] >= 0 else -rel
        self.angle = 2.0 * float(np.arctan2(np.linalg.norm(rel[1:]), rel[0]))
        self.axis = rel[1:] / max(float(np.linalg.norm(rel[1:])), 1e-15)
        self.q0, self.q1, self.duration = q0, q1, duration

    def state(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Attitude, body turn rate and its derivative at local times ``s``."""
        T, th = self.duration, self.angle
        x = 2.0 * np.pi * np.clip(s, 0.0, T) / T
        angle = th * (x - np.sin(x)) / (2.0 * np.pi)
        rate = th / T * (1.0 - np.cos(x))
        accel = th / T * (2.0 * np.pi / T) * np.sin(x)
        q = nr._qmul(self.q0, nr._qrotvec(angle[:, None] * self.axis))
        return q, rate[:, None] * self.axis, accel[:, None] * self.axis

    def end(self) -> np.ndarray:
        return self.q1


class _Table:
    """A table about +down with the unit at ``q_mount``, from rest through ``rates`` (rad/s), each
    reached by a ramp at ``accel`` and held ``dwell_s``, back to rest."""

    def __init__(self, q_mount: np.ndarray, rates: list[float], dwell_s: float, accel: float) -> None:
        kt, kw = [0.0], [0.0]
        for w in [*rates, 0.0]:
            if w != kw[-1]:
                kt.append(kt[-1] + abs(w - kw[-1]) / accel)
                kw.append(w)
            if w != 0.0:
                kt.append(kt[-1] + dwell_s)
                kw.append(w)
        self.kt, self.kw = np.array(kt), np.array(kw)
        self.kangle = np.concatenate(
            [[0.0], np.cumsum(0.5 * (self.kw[1:] + self.kw[:-1]) * np.diff(self.kt))]
        )
        self.q_mount, self.duration = q_mount, float(self.kt[-1])
        self.up_b = nr._dcm(q_mount).T @ np.array([0.0, 0.0, 1.0])  # +down in body axes: fixed on the table

    def state(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Attitude, body turn rate and its derivative at local times ``s``."""
        s = np.clip(s, 0.0, self.duration)
        i = np.clip(np.searchsorted(self.kt, s, side="right") - 1, 0, len(self.kt) - 2)
        slope = (self.kw[i + 1] - self.kw[i]) / (self.kt[i + 1] - self.kt[i])
        ds = s - self.kt[i]
        rate = self.kw[i] + slope * ds
        angle = self.kangle[i] + self.kw[i] * ds + 0.5 * slope * ds * ds
        q = nr._qmul(nr._qrotvec(angle[:, None] * np.array([0.0, 0.0, 1.0])), self.q_mount)
        return q, rate[:, None] * self.up_b, slope[:, None] * self.up_b

    def end(self) -> np.ndarray:
        return nr._qmul(nr._qrotvec(self.kangle[-1] * np.array([0.0, 0.0, 1.0])), self.q_mount)


class _Euler:
    """Continuous tumbling: ``C_nb = R_z(ψ) R_y(θ) R_x(φ)``, each angle a constant plus three sines of
    random periods (4-40 s) and phases whose rate amplitudes are 0.5, 0.3 and 0.2 of ``max_rate``."""

    def __init__(self, rng: np.random.Generator, duration: float, max_rate: float) -> None:
        self.period = rng.uniform(4.0, 40.0, (3, 3))
        self.phase = rng.uniform(0.0, 2 * np.pi, (3, 3))
        self.amp = np.array([0.5, 0.3, 0.2]) * max_rate * self.period / (2 * np.pi)  # angle amplitudes
        self.start = rng.uniform(-np.pi, np.pi, 3)
        self.duration = duration

    def state(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Attitude, body turn rate and its derivative at times ``s`` (any, unclipped)."""
        k = 2 * np.pi / self.period  # (angle, term)
        arg = s[:, None, None] * k + self.phase
        a = self.start + np.sum(self.amp * np.sin(arg), axis=2)  # (n, 3): φ, θ, ψ
        da = np.sum(self.amp * k * np.cos(arg), axis=2)
        dda = -np.sum(self.amp * k * k * np.sin(arg), axis=2)
        phi, th, psi = a.T
        dphi, dth, dpsi = da.T
        ddphi, ddth, ddpsi = dda.T
        e = np.eye(3)
        q = nr._qmul(nr._qmul(nr._qrotvec(psi[:, None] * e[2]), nr._qrotvec(th[:, None] * e[1])),
                     nr._qrotvec(phi[:, None] * e[0]))  # fmt: skip
        sf, cf, st, ct = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th)
        w = np.stack([dphi - dpsi * st, dth * cf + dpsi * sf * ct, -dth * sf + dpsi * cf * ct], axis=1)
        wd = np.stack(
            [
                ddphi - ddpsi * st - dpsi * dth * ct,
                ddth * cf - dth * dphi * sf + ddpsi * sf * ct + dpsi * dphi * cf * ct - dpsi * dth * sf * st,
                -ddth * sf - dth * dphi * cf + ddpsi * cf * ct - dpsi * dphi * sf * ct - dpsi * dth * cf * st,
            ],
            axis=1,
        )
        return q, w, wd


@dataclass(frozen=True)
class Motion:
    """A procedure in closed form: pieces one after another, and a temperature profile."""

    name: str
    pieces: tuple[Any, ...]
    temp: str  # see :func:`temperature`

    @property
    def duration(self) -> float:
        return float(sum(p.duration for p in self.pieces))

    def inputs(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Angular rate ``ω_ib``, specific force and angular acceleration ``ω̇_ib`` (body axes) at times
        ``t``; before the start and after the end the procedure is held at its ends."""
        starts = np.concatenate([[0.0], np.cumsum([p.duration for p in self.pieces])])
        which = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.pieces) - 1)
        q, w_turn, wd_turn = np.empty((len(t), 4)), np.empty((len(t), 3)), np.empty((len(t), 3))
        for k, piece in enumerate(self.pieces):
            rows = which == k
            if rows.any():
                q[rows], w_turn[rows], wd_turn[rows] = piece.state(t[rows] - starts[k])
        c_bn = np.swapaxes(nr._dcm(q), -1, -2)
        w_ie = c_bn @ (nr.EARTH_RATE * np.array([np.cos(nr.LAT), 0.0, -np.sin(nr.LAT)]))
        f = c_bn @ np.array([0.0, 0.0, -G])
        # d/dt (C_bn ω_ie) = -ω_nb × (C_bn ω_ie): Earth's rate turns in body axes as the unit does.
        return w_ie + w_turn, f, wd_turn - np.cross(w_turn, w_ie)


def temperature(profile: str, t: np.ndarray, total: float) -> np.ndarray:
    """Chamber temperature, °C: ``cycle`` (10 -> 40 -> 20 °C, piecewise linear), ``soak`` (20 °C, then a
    first-order approach to 35 °C with τ = total / 8 from a third of the way), ``ramp`` (15 -> 35 °C)
    or ``constant`` (20 °C)."""
    if profile == "cycle":
        return np.interp(t, [0.0, 0.5 * total, total], [10.0, 40.0, 20.0])
    if profile == "soak":
        start = total / 3.0
        return np.where(t < start, 20.0, 35.0 - 15.0 * np.exp(-(t - start) / (total / 8.0)))
    if profile == "ramp":
        return np.interp(t, [0.0, total], [15.0, 35.0])
    if profile == "constant":
        return np.full_like(t, 20.0)
    raise ValueError(f"unknown temperature profile {profile!r}")


def _random_quats(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.standard_normal((n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _joined(pieces: list[Any], move_s: float) -> list[Any]:
    """The pieces with a smooth move from each one's end to the next one's start between them."""
    out = [pieces[0]]
    for p in pieces[1:]:
        start = p.state(np.zeros(1))[0][0]
        out += [_Move(out[-1].end(), start, move_s), p]
    return out


def _table_rates(max_rate: float, fractions: tuple[float, ...]) -> list[float]:
    return [s * r * max_rate for r in fractions for s in (1.0, -1.0)]


def tumble_and_table(
    seed: int = 0, minutes: float = 10.0, temp: str = "cycle", hold_s: float = 8.0, move_s: float = 3.0,
    mounts: int = 4, max_rate_dps: float = 250.0, top_mounts: int | None = None,
) -> Motion:  # fmt: skip
    """Random orientations (uniform on the rotations) held ``hold_s`` and joined by ``move_s`` moves,
    then a table to ``max_rate_dps`` with the unit in ``mounts`` mounts (an axis up and a random
    vector up, alternately), as many holds as fill ``minutes``. With ``top_mounts``, only the last
    that many mounts (each an axis up) reach the top rate, the others 0.6 of it at most."""
    rng = np.random.default_rng([seed, 21])
    top, lower = (0.1, 0.3, 0.6, 1.0), (0.1, 0.3, 0.6)
    tables = []
    for k in range(mounts):
        late = top_mounts is not None and k >= mounts - top_mounts
        axis_up = k % 2 == 0 or late  # an axis up (the top rate all on one channel), or a random mount
        up = np.eye(3)[(k // 2) % 3] * rng.choice([-1.0, 1.0]) if axis_up else rng.standard_normal(3)
        reach = top if top_mounts is None or late else lower
        tables.append(_Table(nr._up(up), _table_rates(max_rate_dps * DEG, reach), 4.0, 200.0 * DEG))
    table_s = sum(t.duration for t in tables) + move_s * mounts
    holds = max(2, round((60.0 * minutes - table_s + move_s) / (hold_s + move_s)))
    pieces = [_Hold(q, hold_s) for q in _random_quats(rng, holds)] + tables
    return Motion("tumble_and_table", tuple(_joined(pieces, move_s)), temp)


def faces_and_axis_table(
    seed: int = 0, minutes: float = 10.0, temp: str = "soak", max_rate_dps: float = 300.0
) -> Motion:
    """Six faces down in a random order, each held as long as fills ``minutes``, then a table to
    ``max_rate_dps`` with the x, y and z axes up in turn; moves of 3 s between."""
    rng = np.random.default_rng([seed, 22])
    faces = [nr._up(np.eye(3)[i] * s) for i in range(3) for s in (1.0, -1.0)]
    faces = [faces[i] for i in rng.permutation(6)]
    rates = _table_rates(max_rate_dps * DEG, (0.05, 0.2, 0.5, 1.0))
    tables = [_Table(nr._up(np.eye(3)[i]), rates, 6.0, 150.0 * DEG) for i in range(3)]
    hold_s = max(5.0, (60.0 * minutes - sum(t.duration for t in tables) - 3.0 * 8) / 6.0)
    pieces = [_Hold(q, hold_s) for q in faces] + tables
    return Motion("faces_and_axis_table", tuple(_joined(pieces, 3.0)), temp)


def continuous_tumble(
    seed: int = 0, minutes: float = 10.0, temp: str = "cycle", max_rate_dps: float = 200.0
) -> Motion:
    """Continuous tumbling over ``minutes`` (see :class:`_Euler`), rates near ``max_rate_dps`` at peak."""
    rng = np.random.default_rng([seed, 23])
    return Motion("continuous_tumble", (_Euler(rng, 60.0 * minutes, max_rate_dps * DEG),), temp)


# ----------------------------------------------------------------------------- procedures as sampled


@dataclass(frozen=True)
class Procedure:
    """A sampled procedure: numpy_rigs's session, and where known the angular acceleration at each row
    and the closed form (None for numpy_rigs's own procedures, whose rates step between samples)."""

    session: nr.Session
    omega_dot: np.ndarray | None = None
    motion: Motion | None = None


def sampled(motion: Motion, rate_hz: float) -> Procedure:
    """A closed-form procedure sampled at ``rate_hz`` from t = 0."""
    t = np.arange(round(motion.duration * rate_hz)) / rate_hz
    w, f, wd = motion.inputs(t)
    temp = temperature(motion.temp, t, motion.duration)
    return Procedure(nr.Session(t, w, f, temp, rate_hz, motion.name), wd, motion)


def _rigs_tumble(rate_hz: float, seed: int, minutes: float, temp: str) -> Procedure:
    # numpy_rigs's table: 7 mounts of 8 rates, about 300 s; holds of 8 s and moves of 2 s fill the rest.
    # Its temperature is its own (a ramp over 10-40 °C), as is its continuous tumble's (one slow sine).
    holds = max(3, round((60.0 * minutes - 300.0) / 10.0))
    return Procedure(nr.tumble_and_table(rate_hz, seed, holds=holds, hold_s=8.0))


def _rigs_faces(rate_hz: float, seed: int, minutes: float, temp: str) -> Procedure:
    # numpy_rigs's tables: 3 mounts of 8 rates to 300 °/s, about 170 s; six faces fill the rest.
    profile = temp if temp in ("soak", "ramp", "constant") else "soak"
    hold_s = max(5.0, (60.0 * minutes - 170.0) / 6.0)
    return Procedure(nr.faces_and_axis_table(rate_hz, seed, hold_s=hold_s, temp_profile=profile))


def _rigs_continuous(rate_hz: float, seed: int, minutes: float, temp: str) -> Procedure:
    return Procedure(nr.continuous_tumble(rate_hz, seed, duration_s=60.0 * minutes))


def _closed(build: Callable[..., Motion]) -> Callable[[float, int, float, str], Procedure]:
    return lambda rate_hz, seed, minutes, temp: sampled(build(seed, minutes, temp), rate_hz)


#: Procedure builders ``(rate_hz, seed, minutes, temp) -> Procedure``: the closed-form ones and
#: numpy_rigs's own (``rigs.*``, temperature their own).
PROCEDURES: dict[str, Callable[[float, int, float, str], Procedure]] = {
    "tumble_and_table": _closed(tumble_and_table),
    "faces_and_axis_table": _closed(faces_and_axis_table),
    "continuous_tumble": _closed(continuous_tumble),
    "rigs.tumble_and_table": _rigs_tumble,
    "rigs.faces_and_axis_table": _rigs_faces,
    "rigs.continuous_tumble": _rigs_continuous,
}
#: Those that give the angular acceleration and the reference at any time.
CLOSED_FORM = ("tumble_and_table", "faces_and_axis_table", "continuous_tumble")


# ----------------------------------------------------------------------------- effects


@dataclass(frozen=True)
class Effect:
    """One effect by sins's name, its parameters SI (per axis unless stated)."""

    name: str
    params: dict[str, Any]

    @property
    def sensor(self) -> str:
        return self.name.split(".")[0]

    @property
    def kind(self) -> str:
        return self.name.split(".")[1]


def _signs(rng: np.random.Generator, shape: tuple[int, ...] = (3,)) -> np.ndarray:
    """Magnitudes between 0.5 and 1 of the typical one, random signs (as sins draws them)."""
    return rng.uniform(0.5, 1.0, shape) * rng.choice([-1.0, 1.0], shape)


def typical_effect(name: str, rng: np.random.Generator, scale: float = 1.0) -> Effect:
    """``name`` at a tactical unit's size times ``scale``: the sizes of sins's ``typical_effect``."""
    s, dps = scale, DEG
    sizes: dict[str, Callable[[], dict[str, Any]]] = {
        "gyro.scale_nonlinearity": lambda: {"k2": s * 1e-6 / dps * _signs(rng)},  # 1 ppm/(°/s)
        "accel.scale_nonlinearity": lambda: {"k2": s * 100e-6 / G * _signs(rng)},  # 100 ppm/g
        "gyro.scale_asymmetry": lambda: {"ka": s * 300e-6 * _signs(rng)},
        "accel.scale_asymmetry": lambda: {"ka": s * 300e-6 * _signs(rng)},
        "gyro.g2_sensitivity": lambda: {"tensor": s * 3.0 * DEG_PER_H / G**2 * _signs(rng, (3, 3, 3))},
        "gyro.temperature_bias": lambda: {"c1": s * 0.5 * DEG_PER_H * _signs(rng)},  # per °C
        "accel.temperature_bias": lambda: {"c1": s * 0.02 * MG * _signs(rng)},
        "gyro.temperature_scale": lambda: {"s1": s * 10e-6 * _signs(rng)},  # per °C
        "accel.temperature_scale": lambda: {"s1": s * 10e-6 * _signs(rng)},
        "gyro.time_offset": lambda: {"delay": s * 1e-3},
        "accel.time_offset": lambda: {"delay": s * 1e-3},
        "gyro.quantization": lambda: {"step": s * 0.05 * dps},
        "accel.quantization": lambda: {"step": s * 2.0 * MG},
        "gyro.saturation": lambda: {"limit": 150.0 * dps / s},
        "accel.saturation": lambda: {"limit": 0.95 * G / s},
        "accel.size_effect": lambda: {"lever_arms": s * 2e-3 * _signs(rng, (3, 3))},  # row i: accel i
        "gyro.bias_instability": lambda: {"sigma": s * 5.0 * DEG_PER_H, "tau": 100.0},
        "accel.bias_instability": lambda: {"sigma": s * 0.1 * MG, "tau": 100.0},
        "gyro.rate_random_walk": lambda: {"density": s * 20.0 * DEG_PER_H / 60.0},  # 20 °/h/√h
        "accel.rate_random_walk": lambda: {"density": s * 50e-6 * G},  # 50 µg/√s
    }
    if name not in sizes:
        raise ValueError(f"no typical size for {name!r}")
    return Effect(name, sizes[name]())


def gauss_markov(t: np.ndarray, sigma: float, tau: float, rng: np.random.Generator) -> np.ndarray:
    """A first-order Gauss–Markov bias (n, 3), started from its stationary law, exact at each step:
    ``b_k = φ b_{k-1} + σ √(1 - φ²) ξ_k`` with ``φ = exp(-Δt/τ)``, uniform steps."""
    n = len(t)
    dt = float(t[1] - t[0])
    phi = np.exp(-dt / tau)
    drive = sigma * np.sqrt(1.0 - phi * phi) * rng.standard_normal((n, 3))
    drive[0] = sigma * rng.standard_normal(3)
    # b_k = φ^k Σ_{j≤k} φ^-j e_j, in blocks short enough that φ^-j stays well within range.
    out = np.empty((n, 3))
    block = max(1, int(20.0 * tau / dt))
    level = np.zeros(3)
    for start in range(0, n, block):
        e = drive[start : start + block]
        j = np.arange(1, len(e) + 1)[:, None]
        grow = phi ** (-(j - 1.0))
        out[start : start + len(e)] = (phi**j) * level + (phi ** (j - 1.0)) * np.cumsum(e * grow, axis=0)
        level = out[start + len(e) - 1]
    return out


def random_walk(t: np.ndarray, density: float, rng: np.random.Generator) -> np.ndarray:
    """A random-walk bias (n, 3) from 0 at ``t[0]``: increments ``density √Δt ξ``."""
    steps = density * np.sqrt(np.diff(t))[:, None] * rng.standard_normal((len(t) - 1, 3))
    return np.vstack([np.zeros((1, 3)), np.cumsum(steps, axis=0)])


def size_effect(w: np.ndarray, wd: np.ndarray, lever_arms: np.ndarray) -> np.ndarray:
    """Accelerometer ``i`` at lever arm ``r_i`` (row ``i``) from the reference point reads the specific
    force there, ``f + ω̇ × r_i + ω × (ω × r_i)``, along its own axis: the error (n, 3)."""
    out = np.empty_like(w)
    for i in range(3):
        r = lever_arms[i]
        out[:, i] = (np.cross(wd, r) + np.cross(w, np.cross(w, r)))[:, i]
    return out


def _stream(seed: int, what: str) -> np.random.Generator:
    return np.random.default_rng([seed, zlib.crc32(what.encode())])


def _with_unit_effect(unit: nr.Unit, effect: Effect) -> nr.Unit:
    """The unit with an effect numpy_rigs's Unit already writes out (k2 u², ka |u|, G2 f f, c1 ΔT,
    s1 ΔT u; ΔT from 20 °C), or the unit unchanged."""
    field = {"scale_nonlinearity": "k2", "scale_asymmetry": "ka", "g2_sensitivity": "g2",
             "temperature_bias": "tc1", "temperature_scale": "ts"}.get(effect.kind)  # fmt: skip
    if field is None:
        return unit
    changes: dict[str, Any] = {f"{effect.sensor}_{field}": np.array(next(iter(effect.params.values())))}
    return dataclasses.replace(unit, **changes)


def record(
    proc: Procedure, unit: nr.Unit, effect: Effect | None, seed: int, noisy: bool = True,
    disturbance: str | None = None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Gyro and accelerometer readings (n, 3) of ``unit`` with ``effect`` over a procedure; without
    white noise unless ``noisy``. Random biases and noise draw from streams of their own (the same
    with and without the effect). ``disturbance``: one of :data:`CONTROLS`' outside ones, on gyro x."""
    s = proc.session
    t, temp = s.t, s.temp
    inputs = {
        "gyro": (s.ref_gyro, s.ref_accel, proc.omega_dot),
        "accel": (s.ref_gyro, s.ref_accel, proc.omega_dot),
    }
    if effect is not None and effect.kind == "time_offset":
        if proc.motion is None:
            raise ValueError(
                f"{s.name}: a time offset needs the reference at any time (a closed-form procedure)"
            )
        inputs[effect.sensor] = proc.motion.inputs(t - effect.params["delay"])  # the input τ late
    if effect is not None:
        unit = _with_unit_effect(unit, effect)
    w, f, _ = inputs["gyro"]
    gyro = w + unit.errors(w, f, temp)[0]
    w, f, wd = inputs["accel"]
    accel = f + unit.errors(w, f, temp)[1]
    out = {"gyro": gyro, "accel": accel}
    if effect is not None:
        p, y = effect.params, out[effect.sensor]
        if effect.kind == "size_effect":
            if wd is None:
                raise ValueError(f"{s.name}: the size effect needs the angular acceleration")
            y += size_effect(w, wd, np.asarray(p["lever_arms"]))
        elif effect.kind == "bias_instability":
            y += gauss_markov(t, p["sigma"], p["tau"], _stream(seed, effect.name))
        elif effect.kind == "rate_random_walk":
            y += random_walk(t, p["density"], _stream(seed, effect.name))
    if disturbance == "sinusoid (outside)":
        gyro[:, 0] += 0.3 * DEG * np.sin(2 * np.pi * t / 37.0)
    elif disturbance == "bias step (outside)":
        gyro[:, 0] += 20.0 * DEG_PER_H * (t > 0.5 * t[-1])
    elif disturbance is not None:
        raise ValueError(f"unknown disturbance {disturbance!r}")
    if noisy:
        root = np.sqrt(s.rate_hz)
        gyro += unit.gyro_noise * root * _stream(seed, "gyro.noise").standard_normal(gyro.shape)
        accel += unit.accel_noise * root * _stream(seed, "accel.noise").standard_normal(accel.shape)
    if effect is not None and effect.kind == "saturation":
        y = out[effect.sensor]
        y[:] = np.clip(y, -effect.params["limit"], effect.params["limit"])
    if effect is not None and effect.kind == "quantization":
        y = out[effect.sensor]
        y[:] = np.round(y / effect.params["step"]) * effect.params["step"]  # integer counts of the step
    return gyro, accel


# ----------------------------------------------------------------------------- the oracle


def baseline_columns(sensor: str, w: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The baseline's least-squares columns of a channel: 1, the sensor's input, and the gyro's ``f``."""
    u = w if sensor == "gyro" else f
    cols = [np.ones(len(u)), *u.T] + ([*f.T] if sensor == "gyro" else [])
    return np.column_stack(cols)


def white_sigma(unit: nr.Unit, sensor: str, rate_hz: float) -> float:
    """A reading's white-noise standard deviation at ``rate_hz``."""
    return float((unit.gyro_noise if sensor == "gyro" else unit.accel_noise) * np.sqrt(rate_hz))


def oracle_nats(
    proc: Procedure,
    unit: nr.Unit,
    effect: Effect,
    seed: int,
    holdout: float = HOLDOUT,
    rival: str | None = None,
) -> float:
    """What a model that knew ``effect`` would gain on the withheld rows, in nats (see the module):
    beyond the baseline's columns, and beyond a ``rival`` regressor effect's as well (its columns
    fitted per channel beside them)."""
    with_it = record(proc, unit, effect, seed, noisy=False)
    without = record(proc, unit, None, seed, noisy=False)
    k = 0 if effect.sensor == "gyro" else 1
    delta = with_it[k] - without[k]
    s = proc.session
    base = baseline_columns(effect.sensor, s.ref_gyro, s.ref_accel)
    sigma = white_sigma(unit, effect.sensor, s.rate_hz)
    total = 0.0
    for i in range(3):
        a = base if rival is None else np.column_stack([base, rival_columns(rival, proc, i)])
        a = a / np.maximum(np.abs(a).max(axis=0), 1e-300)
        left = delta[:, i] - a @ np.linalg.lstsq(a, delta[:, i], rcond=None)[0]
        # The withheld rows are the ends of stretches all through the recording: a share ``holdout``
        # of the evidence, wherever it lies.
        total += 0.5 * holdout * float(np.sum((left / sigma) ** 2))
    return total


#: The regressor effects of each sensor, rivals of one another.
REGRESSORS = {
    "gyro": (
        "scale_nonlinearity",
        "scale_asymmetry",
        "g2_sensitivity",
        "temperature_bias",
        "temperature_scale",
    ),
    "accel": (
        "scale_nonlinearity",
        "scale_asymmetry",
        "temperature_bias",
        "temperature_scale",
        "size_effect",
    ),
}


def rival_columns(name: str, proc: Procedure, axis: int) -> np.ndarray:
    """The least-squares columns of regressor effect ``name`` on one channel (n, k), from its
    textbook form: ``u²``, ``|u|``, the products ``f_j f_k``, ``ΔT`` and ``ΔT²``, ``ΔT u``, and the
    lever arms' terms ``(ω̇ × e_j + ω × (ω × e_j))`` of the channel."""
    s = proc.session
    sensor, kind = name.split(".")
    u = (s.ref_gyro if sensor == "gyro" else s.ref_accel)[:, axis]
    d_t = s.temp - 20.0
    if kind == "scale_nonlinearity":
        return u[:, None] ** 2
    if kind == "scale_asymmetry":
        return np.abs(u)[:, None]
    if kind == "g2_sensitivity":
        f = s.ref_accel
        return np.column_stack([f[:, j] * f[:, k] for j in range(3) for k in range(j, 3)])
    if kind == "temperature_bias":
        return np.column_stack([d_t, d_t**2])
    if kind == "temperature_scale":
        return (d_t * u)[:, None]
    if kind == "size_effect":
        w, wd = s.ref_gyro, proc.omega_dot if proc.omega_dot is not None else np.zeros_like(s.ref_gyro)
        return np.column_stack(
            [size_effect(w, wd, np.eye(3)[j][None].repeat(3, 0))[:, axis] for j in range(3)]
        )
    raise ValueError(f"not a regressor effect: {name}")


def identifiable_nats(proc: Procedure, unit: nr.Unit, effect: Effect, seed: int) -> tuple[float, str]:
    """What the effect gains beyond its closest rival, in nats, and that rival: a regressor effect
    beyond each other regressor of its sensor (:func:`oracle_nats` with the rival's columns); a
    Gauss-Markov bias beyond the random walk it tends to for τ → ∞, the Kullback-Leibler divergence of
    the two processes' path laws observed without noise, ``T / (4 τ)`` per channel (an upper bound);
    other effects have no rival in the library (infinity)."""
    if effect.kind == "bias_instability":
        tau = np.broadcast_to(np.asarray(effect.params["tau"], dtype=float), (3,))
        duration = float(proc.session.t[-1] - proc.session.t[0])
        return float(np.sum(duration / (4.0 * tau))), f"{effect.sensor}.rate_random_walk"
    if effect.kind not in REGRESSORS[effect.sensor]:
        return float("inf"), ""
    gains = {}
    for kind in REGRESSORS[effect.sensor]:
        name = f"{effect.sensor}.{kind}"
        if kind != effect.kind and not (kind == "size_effect" and proc.omega_dot is None):
            gains[name] = oracle_nats(proc, unit, effect, seed, rival=name)
    rival = min(gains, key=lambda n: gains[n])
    return gains[rival], rival


# ----------------------------------------------------------------------------- cases


@dataclass(frozen=True)
class Case:
    """One recording of the suite: what is injected (an effect's name, a control's, or one of
    :data:`ISSUE_CASES`), on which procedure, at which rate, for how long, under which temperature."""

    name: str
    seed: int
    procedure: str
    rate_hz: float
    minutes: float
    temp: str = "cycle"
    scale: float = 1.0

    @property
    def effect_name(self) -> str | None:
        """The library effect injected, or None for a control."""
        head = self.name.split(" ")[0]
        return head if head in EFFECTS else None

    @property
    def label(self) -> str:
        return (
            f"{self.name} on {self.procedure} at {self.rate_hz:g} Hz for {self.minutes:g} min, "
            f"{self.temp}, seed {self.seed}, ×{self.scale:g}"
        )


#: Rates and durations a case draws from: 50-400 Hz, 5-30 min, at most 180,000 rows.
RATES_MINUTES = ((50.0, 30.0), (50.0, 20.0), (100.0, 15.0), (100.0, 10.0), (200.0, 8.0), (400.0, 5.0))


def draw_case(name: str, seed: int) -> Case:
    """The case of ``name`` and ``seed``: a procedure, rate, duration and temperature drawn at random
    (a procedure that can carry the effect; a varying temperature for a temperature effect)."""
    if name == ISSUE_CASES[0]:
        return clipped_tail_case(seed)
    if name == ISSUE_CASES[1]:
        return quantized_case(seed)
    if name == ISSUE_CASES[2]:
        return fast_turns_case(seed)
    if name not in EFFECTS and name not in CONTROLS:
        raise ValueError(f"unknown case {name!r}")
    rng = np.random.default_rng([seed, zlib.crc32(name.encode())])
    kind = name.split(".")[-1]
    choices = list(CLOSED_FORM) if kind in ("time_offset", "size_effect") else list(PROCEDURES)
    procedure = str(rng.choice(choices))
    rate, minutes = RATES_MINUTES[rng.integers(len(RATES_MINUTES))]
    temps = ["cycle", "soak", "ramp"] + ([] if "temperature" in name else ["constant"])
    temp = str(rng.choice(temps))
    # numpy_rigs's procedures have temperatures of their own: its faces take a soak, a ramp or none.
    own = {"rigs.tumble_and_table": "ramp", "rigs.continuous_tumble": "cycle"}
    temp = own.get(
        procedure, "soak" if procedure == "rigs.faces_and_axis_table" and temp == "cycle" else temp
    )
    return Case(name, seed, procedure, rate, minutes, temp)


def clipped_tail_case(seed: int = 0, rate_hz: float = 100.0, minutes: float = 10.0) -> Case:
    """Issue 19's case (a): gyros clipped at 200 °/s, the table's top rate (250 °/s) reached only in its
    last mount, in the recording's last minutes; every other rate stays below the clip."""
    return Case(ISSUE_CASES[0], seed, "tumble_and_table (top rate last)", rate_hz, minutes, "cycle", 0.75)


def quantized_case(seed: int = 0, rate_hz: float = 100.0, minutes: float = 10.0) -> Case:
    """Issue 19's case (b): gyros quantised to 0.06 °/s (1.2 × the typical step) under 0.01 °/s of
    noise (100 Hz), rates from Earth's to 250 °/s."""
    return Case(ISSUE_CASES[1], seed, "tumble_and_table", rate_hz, minutes, "cycle", 1.2)


def fast_turns_case(seed: int = 0, rate_hz: float = 100.0, minutes: float = 4.0) -> Case:
    """Issue 32's case: an accelerometer delay at its typical size (1 ms) on random orientations held
    8 s and a table in four mounts, every turn between them taking 0.3 s (a half turn peaks at
    1,200 °/s): the force changes only during the turns, each shorter than a stretch of like input
    may be (0.5 s)."""
    return Case(ISSUE_CASES[2], seed, "tumble_and_table (fast turns)", rate_hz, minutes, "cycle")


@dataclass(frozen=True)
class Built:
    """A case's procedure, unit, effect and noisy readings."""

    case: Case
    proc: Procedure
    unit: nr.Unit
    effect: Effect | None
    gyro: np.ndarray
    accel: np.ndarray

    def oracle(self) -> float:
        """:func:`oracle_nats` of the case's effect (NaN for a control)."""
        if self.effect is None:
            return float("nan")
        return oracle_nats(self.proc, self.unit, self.effect, self.case.seed)

    def identifiable(self) -> tuple[float, str]:
        """:func:`identifiable_nats` of the case's effect (NaN for a control)."""
        if self.effect is None:
            return float("nan"), ""
        return identifiable_nats(self.proc, self.unit, self.effect, self.case.seed)


def procedure_of(case: Case) -> Procedure:
    """The sampled procedure of a case."""
    if case.procedure == "tumble_and_table (top rate last)":
        motion = tumble_and_table(case.seed, case.minutes, case.temp, mounts=4, top_mounts=1)
        return sampled(motion, case.rate_hz)
    if case.procedure == "tumble_and_table (fast turns)":
        return sampled(tumble_and_table(case.seed, case.minutes, case.temp, move_s=0.3), case.rate_hz)
    return PROCEDURES[case.procedure](case.rate_hz, case.seed, case.minutes, case.temp)


def build(case: Case) -> Built:
    """Draw a case's unit and effect and record its readings."""
    proc = procedure_of(case)
    unit = nr.baseline_unit(np.random.default_rng([case.seed, 31]))
    name = case.effect_name
    effect = typical_effect(name, np.random.default_rng([case.seed, 32]), case.scale) if name else None
    disturbance = case.name if "outside" in case.name else None
    gyro, accel = record(proc, unit, effect, case.seed, disturbance=disturbance)
    return Built(case, proc, unit, effect, gyro, accel)


def write(built: Built, path: Path) -> Path:
    """The case's recording as numpy_rigs prints one (10 significant digits, no phases)."""
    nr.write_csv(path, built.proc.session, built.gyro, built.accel)
    return path
