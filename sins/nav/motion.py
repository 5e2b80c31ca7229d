"""Continuous motions: the vehicle's velocity and attitude as smooth functions of time.

A motion answers, for any array of times, the kinematics the ideal IMU is made
from: ``v_n`` and its time derivative ``a_n``, the attitude ``q_nb`` and the
body rate ``omega_nb_b``. It also lists its *breakpoints*, the times at which
some derivative is discontinuous, so that quadrature never straddles one.
Position is not part of a motion: :mod:`sins.nav.trajectory` integrates it from
``v_n`` on the ellipsoid, so that it is consistent with the velocity by
construction.

Three kinds:

* :class:`SegmentMotion` – speed, course, flight-path angle and attitude
  offsets, each a :class:`~sins.nav.pulses.Channel` built from smooth pulses (segments) and
  sinusoids (a seaway);
* :class:`WaypointMotion` – a C2 quintic Hermite path through local waypoints
  at given speeds, attitude following the velocity;
* :class:`RecordedMotion` – splines through a recorded truth (velocity and
  attitude samples).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Final, Literal, Protocol, get_args

import numba
import numpy as np
from numpy.typing import NDArray

from sins.core import rotation
from sins.core.earth import E2, G0, check_latitude, radii
from sins.nav.pulses import Channel

if TYPE_CHECKING:
    from sins.core.series import NavSeries

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Kinematics:
    """Kinematics at an array of ``n`` times.

    Attributes
    ----------
    v_n : (n, 3) velocity relative to Earth in NED, m/s
    a_n : (n, 3) time derivative of ``v_n`` (components in n), m/s²
    q_nb : (n, 4) attitude quaternion
    omega_nb_b : (n, 3) angular rate of b relative to n, resolved in b, rad/s
    """

    v_n: Array
    a_n: Array
    q_nb: Array
    omega_nb_b: Array


class Motion(Protocol):
    """What :func:`sins.nav.trajectory.generate` needs of a motion."""

    @property
    def t_start(self) -> float:
        """First time the motion covers, s."""
        ...

    @property
    def t_end(self) -> float:
        """Last time the motion covers, s."""
        ...

    @property
    def lat0(self) -> float:
        """Latitude at ``t_start``, rad."""
        ...

    @property
    def lon0(self) -> float:
        """Longitude at ``t_start``, rad."""
        ...

    @property
    def h0(self) -> float:
        """Height above the WGS84 ellipsoid at ``t_start``, m."""
        ...

    def kinematics(self, t: Array) -> Kinematics:
        """``v_n``, ``a_n``, ``q_nb`` and ``omega_nb_b`` at times ``t`` (s)."""
        ...

    def breakpoints(self) -> Array:
        """Times (s) where some derivative jumps; quadrature intervals end there."""
        ...


# --------------------------------------------------------------------------- segment motion


@dataclass(frozen=True)
class Start:
    """Initial state of a segment motion: position (rad, rad, m), speed (m/s), attitude (rad).

    The velocity points along the body x axis: course = yaw, flight-path angle = pitch.
    """

    lat: float
    lon: float
    h: float
    speed: float = 0.0
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0

    def __post_init__(self) -> None:
        check_latitude(self.lat, "Start.lat")
        for name in ("lon", "h", "speed", "roll", "pitch", "yaw"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"Start.{name} is {getattr(self, name)!r}, not finite")


@dataclass(frozen=True)
class Hold:
    """Keep velocity and attitude for ``duration`` s."""

    duration: float


@dataclass(frozen=True)
class Accelerate:
    """Change speed by ``delta_speed`` m/s; the acceleration is a smooth trapezoid."""

    duration: float
    delta_speed: float
    ramp: float


@dataclass(frozen=True)
class Turn:
    """Turn at ``rate`` rad/s (positive: to the right) once ramped in; heading changes by
    ``rate * (duration - ramp)``. ``coordinated`` banks the body as an aircraft does."""

    duration: float
    rate: float
    ramp: float
    coordinated: bool = False


@dataclass(frozen=True)
class Climb:
    """Fly at flight-path angle ``angle`` rad (negative descends) between smooth pull-up
    and push-over ramps; level again at the end."""

    duration: float
    angle: float
    ramp: float


@dataclass(frozen=True)
class Rotate:
    """Change the body attitude relative to the velocity by ``d_roll``, ``d_pitch``,
    ``d_yaw`` rad (rate pulses; the velocity keeps its direction)."""

    duration: float
    d_roll: float
    d_pitch: float
    d_yaw: float
    ramp: float


Segment = Hold | Accelerate | Turn | Climb | Rotate


#: The shortest ramp a segment may have, s. The ramp's acceleration grows as ``delta/ramp`` and the
#: evaluation divides by ``ramp²`` (which underflows to zero for ramps below 1e-154 s); below a
#: millisecond no vehicle changes speed, rate or attitude.
MIN_RAMP_S = 1e-3


#: The channel an oscillation moves: an attitude angle or the height.
OscillationChannel = Literal["roll", "pitch", "yaw", "heave"]

#: The channels in the order the messages list them.
OSCILLATION_CHANNELS: Final[tuple[OscillationChannel, ...]] = get_args(OscillationChannel)


@dataclass(frozen=True)
class Oscillation:
    """A sinusoid ``amplitude * sin(2π t / period + phase)`` on ``channel`` for the whole run.

    ``channel`` is "roll", "pitch", "yaw" (amplitude in rad) or "heave" (m, upwards).
    """

    channel: OscillationChannel
    amplitude: float
    period: float
    phase: float = 0.0


def _build_channel(
    edges: Array, start: float, rate_amp: Array, value_amp: Array, ramp: Array, sines: list[Oscillation]
) -> Channel:
    lengths = np.diff(edges)
    gain = rate_amp * (lengths - ramp)
    base = start + np.concatenate([[0.0], np.cumsum(gain)[:-1]])
    return Channel(
        edges=edges,
        base=base,
        rate_amp=rate_amp,
        value_amp=value_amp,
        ramp=ramp,
        sin_amplitude=np.array([o.amplitude for o in sines], dtype=float),
        sin_period=np.array([o.period for o in sines], dtype=float),
        sin_phase=np.array([o.phase for o in sines], dtype=float),
    )


@dataclass(frozen=True)
class SegmentMotion:
    """Motion from channels: speed, course, flight-path angle, attitude offsets, heave.

    ``v_n = speed * [cos γ cos ψ, cos γ sin ψ, -sin γ] + [0, 0, -d(heave)/dt]``;
    body yaw = ψ + ``yaw_offset``, pitch = γ + ``pitch_offset``, roll = ``roll``
    plus, where ``coordinated`` is true, the bank of a coordinated turn
    ``atan(speed · dψ/dt / g0)``. Angles in radians, speed in m/s, heave
    (upwards) in m. Pitch must stay within ±90°.
    """

    lat0: float
    lon0: float
    h0: float
    speed: Channel
    course: Channel
    path: Channel
    roll: Channel
    pitch_offset: Channel
    yaw_offset: Channel
    heave: Channel
    coordinated: Channel  # value 1 inside coordinated-turn pieces, else 0; only its value is used

    @classmethod
    def from_segments(
        cls,
        start: Start,
        segments: list[Segment] | tuple[Segment, ...],
        oscillations: list[Oscillation] | tuple[Oscillation, ...] = (),
        t_start: float = 0.0,
    ) -> SegmentMotion:
        """Compile segments (played back to back from ``t_start``) and oscillations into channels.

        Raises ``ValueError`` naming the segment (1-based) for an impossible
        segment: non-positive duration, a ramp shorter than :data:`MIN_RAMP_S` or longer
        than half the segment, a speed that would turn negative.
        """
        if not segments:
            raise ValueError("a segment motion needs at least one segment")
        m = len(segments)
        dur = np.empty(m)
        ramp = np.zeros(m)
        amp = {name: np.zeros(m) for name in ("speed", "course", "roll", "pitch", "yaw")}
        climb = np.zeros(m)
        coordinated = np.zeros(m)
        speed = start.speed
        for i, seg in enumerate(segments):
            where = f"segment {i + 1} ({type(seg).__name__.lower()})"
            if not seg.duration > 0:
                raise ValueError(f"{where}: duration must be positive, got {seg.duration:g} s")
            dur[i] = seg.duration
            if isinstance(seg, Hold):
                continue
            if not MIN_RAMP_S <= seg.ramp <= seg.duration / 2:
                raise ValueError(
                    f"{where}: ramp must be in [{MIN_RAMP_S:g}, {seg.duration / 2:g}] s (at least "
                    f"{MIN_RAMP_S:g} s, at most half the duration), got {seg.ramp:g}"
                )
            ramp[i] = seg.ramp
            plateau = seg.duration - seg.ramp
            if isinstance(seg, Accelerate):
                amp["speed"][i] = seg.delta_speed / plateau
                speed += seg.delta_speed
                if speed < -1e-9:
                    raise ValueError(f"{where}: speed would become negative ({speed:g} m/s)")
            elif isinstance(seg, Turn):
                amp["course"][i] = seg.rate
                coordinated[i] = float(seg.coordinated)
            elif isinstance(seg, Climb):
                if not abs(seg.angle) < np.pi / 2:
                    raise ValueError(f"{where}: flight-path angle must be within ±90°")
                climb[i] = seg.angle
            elif isinstance(seg, Rotate):
                amp["roll"][i] = seg.d_roll / plateau
                amp["pitch"][i] = seg.d_pitch / plateau
                amp["yaw"][i] = seg.d_yaw / plateau
        for o in oscillations:
            if o.channel not in OSCILLATION_CHANNELS:
                raise ValueError(f"oscillation channel must be one of {', '.join(OSCILLATION_CHANNELS)}")
            if not o.period > 0:
                raise ValueError(f"oscillation on {o.channel}: period must be positive, got {o.period:g} s")
        edges = t_start + np.concatenate([[0.0], np.cumsum(dur)])
        zero = np.zeros(m)

        def sines(name: OscillationChannel) -> list[Oscillation]:
            return [o for o in oscillations if o.channel == name]

        return cls(
            lat0=start.lat,
            lon0=start.lon,
            h0=start.h,
            speed=_build_channel(edges, start.speed, amp["speed"], zero, ramp, []),
            course=_build_channel(edges, start.yaw, amp["course"], zero, ramp, []),
            path=_build_channel(edges, start.pitch, zero, climb, ramp, []),
            roll=_build_channel(edges, start.roll, amp["roll"], zero, ramp, sines("roll")),
            pitch_offset=_build_channel(edges, 0.0, amp["pitch"], zero, ramp, sines("pitch")),
            yaw_offset=_build_channel(edges, 0.0, amp["yaw"], zero, ramp, sines("yaw")),
            heave=_build_channel(edges, 0.0, zero, zero, ramp, sines("heave")),
            coordinated=Channel(edges=edges, base=coordinated, rate_amp=zero, value_amp=zero, ramp=zero),
        )

    @property
    def t_start(self) -> float:
        """Start of the first segment, s."""
        return float(self.speed.edges[0])

    @property
    def t_end(self) -> float:
        """End of the last segment, s."""
        return float(self.speed.edges[-1])

    def _channels(self) -> tuple[Channel, ...]:
        return (self.speed, self.course, self.path, self.roll, self.pitch_offset, self.yaw_offset, self.heave)

    def breakpoints(self) -> Array:
        """Its channels' breakpoints (piece edges and ramp ends), merged and sorted."""
        return np.unique(np.concatenate([c.breakpoints() for c in self._channels()]))

    def kinematics(self, t: Array) -> Kinematics:
        """Kinematics from the channels at times ``t``, banked where a turn is coordinated."""
        t = np.ascontiguousarray(t, dtype=float)
        coordinated = self.coordinated.evaluate(t)[0] > 0.5
        v_n, a_n, q_nb, omega_nb_b = _segment_kinematics(
            *self.speed.evaluate(t)[:2],
            *self.course.evaluate(t),
            *self.path.evaluate(t)[:2],
            *self.roll.evaluate(t)[:2],
            *self.pitch_offset.evaluate(t)[:2],
            *self.yaw_offset.evaluate(t)[:2],
            *self.heave.evaluate(t)[1:],
            coordinated,
        )
        return Kinematics(v_n=v_n, a_n=a_n, q_nb=q_nb, omega_nb_b=omega_nb_b)


@numba.njit(cache=True, nogil=True)
def _segment_kinematics(
    s: Array, ds: Array, psi: Array, dpsi: Array, d2psi: Array, gam: Array, dgam: Array,
    roll_c: Array, droll_c: Array, dth: Array, ddth: Array, dps: Array, ddps: Array,
    dz: Array, d2z: Array, coordinated: NDArray[np.bool_],
) -> tuple[Array, Array, Array, Array]:  # fmt: skip
    n = s.shape[0]
    v_n = np.empty((n, 3))
    a_n = np.empty((n, 3))
    q_nb = np.empty((n, 4))
    omega = np.empty((n, 3))
    for k in range(n):
        cg, sg = np.cos(gam[k]), np.sin(gam[k])
        cp, sp = np.cos(psi[k]), np.sin(psi[k])
        u0, u1, u2 = cg * cp, cg * sp, -sg
        du0 = -sg * dgam[k] * cp - cg * sp * dpsi[k]
        du1 = -sg * dgam[k] * sp + cg * cp * dpsi[k]
        du2 = -cg * dgam[k]
        v_n[k, 0], v_n[k, 1], v_n[k, 2] = s[k] * u0, s[k] * u1, s[k] * u2 - dz[k]
        a_n[k, 0] = ds[k] * u0 + s[k] * du0
        a_n[k, 1] = ds[k] * u1 + s[k] * du1
        a_n[k, 2] = ds[k] * u2 + s[k] * du2 - d2z[k]
        roll, droll = roll_c[k], droll_c[k]
        if coordinated[k]:
            x = s[k] * dpsi[k] / G0
            dx = (ds[k] * dpsi[k] + s[k] * d2psi[k]) / G0
            roll += np.arctan(x)
            droll += dx / (1.0 + x * x)
        pitch, dpitch = gam[k] + dth[k], dgam[k] + ddth[k]
        yaw, dyaw = psi[k] + dps[k], dpsi[k] + ddps[k]
        cr, sr = np.cos(0.5 * roll), np.sin(0.5 * roll)
        cq, sq = np.cos(0.5 * pitch), np.sin(0.5 * pitch)
        cy, sy = np.cos(0.5 * yaw), np.sin(0.5 * yaw)
        sign = 1.0 if cr * cq * cy + sr * sq * sy >= 0.0 else -1.0
        q_nb[k, 0] = sign * (sr * cq * cy - cr * sq * sy)
        q_nb[k, 1] = sign * (cr * sq * cy + sr * cq * sy)
        q_nb[k, 2] = sign * (cr * cq * sy - sr * sq * cy)
        q_nb[k, 3] = sign * (cr * cq * cy + sr * sq * sy)
        s_r, c_r = np.sin(roll), np.cos(roll)
        s_p, c_p = np.sin(pitch), np.cos(pitch)
        omega[k, 0] = droll - dyaw * s_p
        omega[k, 1] = dpitch * c_r + dyaw * s_r * c_p
        omega[k, 2] = -dpitch * s_r + dyaw * c_r * c_p
    return v_n, a_n, q_nb, omega


# --------------------------------------------------------------------------- waypoint motion


def _attitude_from_velocity(v_n: Array, a_n: Array) -> tuple[Array, Array]:
    """Level-roll attitude along the velocity, and its body rate."""
    vn, ve, vd = v_n[:, 0], v_n[:, 1], v_n[:, 2]
    an, ae, ad = a_n[:, 0], a_n[:, 1], a_n[:, 2]
    vh2 = vn * vn + ve * ve
    vh = np.sqrt(vh2)
    yaw = np.arctan2(ve, vn)
    pitch = np.arctan2(-vd, vh)
    dyaw = (vn * ae - ve * an) / vh2
    dvh = (vn * an + ve * ae) / vh
    dpitch = (vd * dvh - vh * ad) / (vh2 + vd * vd)
    zero = np.zeros_like(yaw)
    q = rotation.quat_from_euler(zero, pitch, yaw)
    return q, rotation.euler_rates_to_body_rate(zero, pitch, zero, dpitch, dyaw)


@dataclass(frozen=True)
class WaypointMotion:
    """A smooth path through geodetic waypoints at given speeds.

    The path is a piecewise quintic Hermite polynomial, C2 at the waypoints, in
    geodetic coordinates scaled to metres at the first waypoint:
    ``y = (lat - lat0)(R_M0 + h0)``, ``x = (lon - lon0)(R_N0 + h0) cos lat0``,
    ``z = h0 - h``. Velocity and acceleration in NED follow exactly from the
    latitude, longitude and height and their derivatives, so integrating the
    velocity passes through every waypoint. Each waypoint is passed at its speed
    along the chord of its neighbours. Body attitude follows the velocity with
    zero roll. Build it with :meth:`from_waypoints`.
    """

    lat0: float
    lon0: float
    h0: float
    knots: Array  # (m,) times, s
    coeffs: Array  # (m-1, 6, 3) power-series coefficients of each piece in (t - knot), scaled metres

    @classmethod
    def from_waypoints(
        cls, lat0: float, lon0: float, h0: float, points_ned: Array, speeds: Array, t_start: float = 0.0
    ) -> WaypointMotion:
        """Build from waypoints and speeds.

        Parameters
        ----------
        lat0, lon0, h0 : the first waypoint, rad and m
        points_ned : (m, 3) offsets in metres; north and east are converted to
            latitude and longitude with the radii of curvature at the first
            waypoint, down to height
        speeds : (m,) speed at each waypoint, m/s, > 0
        """
        p = np.asarray(points_ned, dtype=float)
        s = np.asarray(speeds, dtype=float)
        # The scenario reader checks these for its files; called directly, a negative speed had run the
        # path backwards, a repeated point given NaN, degrees for lat0 a path beyond the pole.
        if p.ndim != 2 or p.shape[1] != 3 or len(p) < 2 or s.shape != (len(p),):
            raise ValueError(f"waypoints: (m, 3) points, m >= 2, and m speeds, got {p.shape} and {s.shape}")
        p = p - p[0]
        chord = np.diff(p, axis=0)
        dist = np.linalg.norm(chord, axis=1)
        if not (np.isfinite(p).all() and np.isfinite(s).all() and (s > 0).all() and (dist > 0).all()):
            raise ValueError("waypoints: finite points, each apart from the one before, and speeds > 0 m/s")
        check_latitude(lat0, "waypoints: lat0")
        dt = dist / (0.5 * (s[:-1] + s[1:]))
        knots = t_start + np.concatenate([[0.0], np.cumsum(dt)])
        direction = np.empty_like(p)
        direction[0] = chord[0]
        direction[-1] = chord[-1]
        direction[1:-1] = p[2:] - p[:-2]
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        # Physical velocity at the knots, in the scaled coordinates' units.
        scale = _metric_scale(lat0, h0, lat0 + p[:, 0] / _radius_m(lat0, h0), h0 - p[:, 2])
        vel = s[:, None] * direction / scale
        acc = np.zeros_like(p)
        if len(p) > 2:
            acc[1:-1] = (vel[2:] - vel[:-2]) / (knots[2:] - knots[:-2])[:, None]
        coeffs = np.empty((len(p) - 1, 6, 3))
        for i in range(len(p) - 1):
            coeffs[i] = _quintic_hermite(p[i], vel[i], acc[i], p[i + 1], vel[i + 1], acc[i + 1], dt[i])
        return cls(lat0=lat0, lon0=lon0, h0=h0, knots=knots, coeffs=coeffs)

    @property
    def t_start(self) -> float:
        """Time at the first waypoint, s."""
        return float(self.knots[0])

    @property
    def t_end(self) -> float:
        """Time at the last waypoint, s."""
        return float(self.knots[-1])

    def breakpoints(self) -> Array:
        """The knots (waypoint times, s), where the quintic pieces meet."""
        return self.knots

    def geodetic(self, t: Array) -> tuple[Array, Array, Array]:
        """Latitude, longitude (rad) and height (m) of the path at times ``t``."""
        p = self._eval(t)[0]
        r_m0, r_n0 = radii(self.lat0)
        lat = self.lat0 + p[:, 0] / (r_m0 + self.h0)
        lon = self.lon0 + p[:, 1] / ((r_n0 + self.h0) * np.cos(self.lat0))
        return lat, lon, self.h0 - p[:, 2]

    def _eval(self, t: Array) -> tuple[Array, Array, Array]:
        idx = np.clip(np.searchsorted(self.knots, t, side="right") - 1, 0, len(self.coeffs) - 1)
        x = (np.asarray(t, dtype=float) - self.knots[idx])[:, None]
        c = self.coeffs[idx]
        p = c[:, 0] + x * (c[:, 1] + x * (c[:, 2] + x * (c[:, 3] + x * (c[:, 4] + x * c[:, 5]))))
        dp = c[:, 1] + x * (2 * c[:, 2] + x * (3 * c[:, 3] + x * (4 * c[:, 4] + x * 5 * c[:, 5])))
        d2p = 2 * c[:, 2] + x * (6 * c[:, 3] + x * (12 * c[:, 4] + x * 20 * c[:, 5]))
        return p, dp, d2p

    def kinematics(self, t: Array) -> Kinematics:
        """Kinematics at times ``t``: NED velocity from the path, attitude along it, zero roll."""
        p, dp, d2p = self._eval(t)
        r_m0, r_n0 = radii(self.lat0)
        ky = 1.0 / (r_m0 + self.h0)
        kx = 1.0 / ((r_n0 + self.h0) * np.cos(self.lat0))
        lat, dlat, d2lat = self.lat0 + p[:, 0] * ky, dp[:, 0] * ky, d2p[:, 0] * ky
        dlon, d2lon = dp[:, 1] * kx, d2p[:, 1] * kx
        h, dh, d2h = self.h0 - p[:, 2], -dp[:, 2], -d2p[:, 2]
        r_m, r_n = radii(lat)
        sl, cl = np.sin(lat), np.cos(lat)
        w = 1.0 - E2 * sl * sl
        dr_n = r_n * E2 * sl * cl / w * dlat  # d(R_N)/dt
        dr_m = 3.0 * r_m * E2 * sl * cl / w * dlat  # d(R_M)/dt
        v_n = np.column_stack([dlat * (r_m + h), dlon * (r_n + h) * cl, -dh])
        a_n = np.column_stack(
            [
                d2lat * (r_m + h) + dlat * (dr_m + dh),
                d2lon * (r_n + h) * cl + dlon * ((dr_n + dh) * cl - (r_n + h) * sl * dlat),
                -d2h,
            ]
        )
        q_nb, omega_nb_b = _attitude_from_velocity(v_n, a_n)
        return Kinematics(v_n=v_n, a_n=a_n, q_nb=q_nb, omega_nb_b=omega_nb_b)


def _radius_m(lat: float, h: float) -> float:
    return float(radii(lat)[0] + h)


def _metric_scale(lat0: float, h0: float, lat: Array, h: Array) -> Array:
    """Physical metres per scaled metre along north, east, down at ``lat``, ``h``."""
    r_m0, r_n0 = radii(lat0)
    r_m, r_n = radii(lat)
    return np.column_stack(
        [(r_m + h) / (r_m0 + h0), (r_n + h) * np.cos(lat) / ((r_n0 + h0) * np.cos(lat0)), np.ones_like(h)]
    )


def _quintic_hermite(p0: Array, v0: Array, a0: Array, p1: Array, v1: Array, a1: Array, h: float) -> Array:
    """Power-series coefficients (6, 3) of the quintic matching position, velocity, acceleration."""
    c0, c1, c2 = p0, v0, 0.5 * a0
    # Solve the remaining three coefficients from the end conditions at x = h.
    d0 = p1 - (c0 + c1 * h + c2 * h * h)
    d1 = v1 - (c1 + 2 * c2 * h)
    d2 = a1 - 2 * c2
    h2, h3 = h * h, h * h * h
    c3 = (10 * d0 - 4 * d1 * h + 0.5 * d2 * h2) / h3
    c4 = (-15 * d0 + 7 * d1 * h - d2 * h2) / (h3 * h)
    c5 = (6 * d0 - 3 * d1 * h + 0.5 * d2 * h2) / (h3 * h2)
    return np.stack([c0, c1, c2, c3, c4, c5])


# --------------------------------------------------------------------------- recorded motion


@dataclass(frozen=True)
class RecordedMotion:
    """Motion through recorded truth samples: cubic splines of velocity and attitude.

    Velocity is a not-a-knot cubic spline of the recorded NED velocity (so
    ``a_n`` is continuous); attitude is scipy's ``RotationSpline`` (continuous
    angular rate and acceleration). The recorded positions are used only for
    the start point: positions are re-integrated from the velocity spline.
    """

    t: Array
    lat0: float
    lon0: float
    h0: float
    v_n: Array
    q_nb: Array

    @classmethod
    def from_series(cls, truth: NavSeries) -> RecordedMotion:
        """The motion through a recorded truth trajectory (its first position is the start)."""
        return cls(
            t=truth.t, lat0=float(truth.lat[0]), lon0=float(truth.lon[0]), h0=float(truth.h[0]),
            v_n=truth.v_n, q_nb=truth.q_nb,
        )  # fmt: skip

    @property
    def t_start(self) -> float:
        """First recorded time, s."""
        return float(self.t[0])

    @property
    def t_end(self) -> float:
        """Last recorded time, s."""
        return float(self.t[-1])

    def breakpoints(self) -> Array:
        """The recorded times (the splines' knots), s."""
        return self.t

    def kinematics(self, t: Array) -> Kinematics:
        """The splines' velocity, its derivative, attitude and body rate at times ``t``."""
        spline_v, spline_q = self._splines()
        # RotationSpline's first derivative is the angular rate in the rotated (b) frame.
        return Kinematics(
            v_n=spline_v(t), a_n=spline_v(t, 1), q_nb=spline_q(t).as_quat(), omega_nb_b=spline_q(t, 1)
        )

    def _splines(self):  # type: ignore[no-untyped-def]
        cached = self.__dict__.get("_cached_splines")
        if cached is None:
            from scipy.interpolate import CubicSpline
            from scipy.spatial.transform import Rotation, RotationSpline

            cached = (
                CubicSpline(self.t, self.v_n, axis=0),
                RotationSpline(self.t, Rotation.from_quat(self.q_nb)),
            )
            object.__setattr__(self, "_cached_splines", cached)
        return cached


__all__ = [
    "MIN_RAMP_S",
    "OSCILLATION_CHANNELS",
    "Accelerate",
    "Climb",
    "Hold",
    "Kinematics",
    "Motion",
    "Oscillation",
    "OscillationChannel",
    "RecordedMotion",
    "Rotate",
    "Segment",
    "SegmentMotion",
    "Start",
    "Turn",
    "WaypointMotion",
]
