"""From a continuous motion to its truth trajectory and its exact ideal IMU.

The ideal IMU in increment form is the integral of the continuous body rate
``omega_ib_b(t)`` and specific force ``f_ib_b(t)`` over each sample interval,
with Earth rate, transport rate, normal gravity and Coriolis. The integrals use
Simpson's rule on pieces: each sample interval is cut at the motion's
breakpoints (where a derivative jumps, so the integrands are smooth on every
piece) and into equal pieces no wider than :data:`MAX_SUBINTERVAL_S` (10 ms;
from 100 Hz up an interval is one piece). Simpson's error on a piece of width
``w`` is ``-w⁵ f⁗/2880``, so an interval of width ``h`` is off by at most
``h w⁴ max|f⁗| / 2880``: 8e-9 rad for a turn ramped from rest to 90 °/s in
0.5 s, about 1e-12 for the motions of the presets (``tests/test_trajectory.py``
compares it with a Gauss–Legendre reference and with scipy's adaptive
quadrature). Without the 10 ms cut the same ramp sampled at 4 Hz was off by
0.09° in one interval (cancelled by the ramp's end, where the errors
telescope), and a breakpoint between two samples broke the telescoping: 0.1° a
turn at 3 Hz (``docs/guide/core.md``). The piece edges include the sample
times, so the truth comes from the same evaluations. Position is integrated
from the velocity on the ellipsoid with the same rule, in one compiled pass.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numba
import numpy as np
from numpy.typing import NDArray

from sins.core import earth
from sins.core.series import ImuIncrements, ImuRates, NavSeries
from sins.nav.motion import Kinematics, Motion

Array = NDArray[np.float64]

#: Sample intervals generated per chunk; bounds memory, not results.
CHUNK = 8192
#: Widest Simpson sub-interval, s: a sample interval wider than this is cut into equal pieces (module
#: docstring).
MAX_SUBINTERVAL_S = 0.01

_earth = numba.njit(cache=True, inline="always")(earth.radii_and_gravity_from_sin2)


@numba.njit(cache=True, nogil=True)
def _ideal_imu(
    v_n: Array, a_n: Array, q_nb: Array, omega_nb_b: Array, lat: Array, h: Array
) -> tuple[Array, Array]:
    n = v_n.shape[0]
    omega = np.empty((n, 3))
    force = np.empty((n, 3))
    for k in range(n):
        vn, ve, vd = v_n[k, 0], v_n[k, 1], v_n[k, 2]
        slat, clat = np.sin(lat[k]), np.cos(lat[k])
        r_m, r_n, g = _earth(slat * slat, h[k])
        wie_n, wie_d = earth.OMEGA_IE * clat, -earth.OMEGA_IE * slat
        wen_n = ve / (r_n + h[k])
        wen_e = -vn / (r_m + h[k])
        wen_d = -ve * slat / clat / (r_n + h[k])
        win = (wie_n + wen_n, wen_e, wie_d + wen_d)
        c = (2.0 * wie_n + wen_n, wen_e, 2.0 * wie_d + wen_d)
        fn = a_n[k, 0] + c[1] * vd - c[2] * ve
        fe = a_n[k, 1] + c[2] * vn - c[0] * vd
        fd = a_n[k, 2] + c[0] * ve - c[1] * vn - g
        x, y, z, w = q_nb[k, 0], q_nb[k, 1], q_nb[k, 2], q_nb[k, 3]
        # C_bn = C_nbᵀ applied column by column.
        c00, c01, c02 = 1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)
        c10, c11, c12 = 2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)
        c20, c21, c22 = 2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)
        omega[k, 0] = omega_nb_b[k, 0] + c00 * win[0] + c10 * win[1] + c20 * win[2]
        omega[k, 1] = omega_nb_b[k, 1] + c01 * win[0] + c11 * win[1] + c21 * win[2]
        omega[k, 2] = omega_nb_b[k, 2] + c02 * win[0] + c12 * win[1] + c22 * win[2]
        force[k, 0] = c00 * fn + c10 * fe + c20 * fd
        force[k, 1] = c01 * fn + c11 * fe + c21 * fd
        force[k, 2] = c02 * fn + c12 * fe + c22 * fd
    return omega, force


@numba.njit(cache=True, nogil=True)
def _integrate_position(
    width: Array, v: Array, lat0: float, lon0: float, h0: float
) -> tuple[Array, Array, Array, Array, Array]:
    """Latitude, longitude, height at the edges and latitude, height at the midpoints.

    ``v`` holds the velocity at the ``ne`` edges, then at the ``ne - 1`` midpoints.
    Each interval is one Simpson step. The radii of curvature at the midpoint
    and the new edge are evaluated at Euler-predicted latitudes: the predictor
    is off by O(width² lat'') ≈ 1e-10 rad, which changes the radii by 1e-12
    relative and the step by ~1e-19 rad, below rounding, so no iteration is
    needed. The midpoint state is the cubic Hermite interpolant of the edge
    states and rates, accurate to O(width⁴).
    """
    ne = width.shape[0] + 1
    lat = np.empty(ne)
    lon = np.empty(ne)
    h = np.empty(ne)
    lat_m = np.empty(ne - 1)
    h_m = np.empty(ne - 1)
    lat[0], lon[0], h[0] = lat0, lon0, h0
    s0 = np.sin(lat0)
    r_m0, r_n0, _ = _earth(s0 * s0, 0.0)
    c0 = np.sqrt(1.0 - s0 * s0)
    for i in range(ne - 1):
        w = width[i]
        vd0, vdm, vd1 = v[i, 2], v[ne + i, 2], v[i + 1, 2]
        h1 = h[i] - w / 6.0 * (vd0 + 4.0 * vdm + vd1)
        hm = 0.5 * (h[i] + h1) - w * (vd0 - vd1) / 8.0
        dlat0 = v[i, 0] / (r_m0 + h[i])
        sm = np.sin(lat[i] + 0.5 * w * dlat0)
        r_mm, r_nm, _ = _earth(sm * sm, 0.0)
        s1 = np.sin(lat[i] + w * dlat0)
        r_m1, r_n1, _ = _earth(s1 * s1, 0.0)
        dlatm = v[ne + i, 0] / (r_mm + hm)
        dlat1 = v[i + 1, 0] / (r_m1 + h1)
        lat1 = lat[i] + w / 6.0 * (dlat0 + 4.0 * dlatm + dlat1)
        cm = np.sqrt(1.0 - sm * sm)
        c1 = np.sqrt(1.0 - s1 * s1)
        if cm <= 0.0 or c1 <= 0.0:  # at a pole the longitude has no rate: the rest is not defined
            lat[i + 1 :] = np.nan
            lon[i + 1 :] = np.nan
            h[i + 1 :] = np.nan
            lat_m[i:] = np.nan
            h_m[i:] = np.nan
            break
        dlon = v[i, 1] / ((r_n0 + h[i]) * c0) + 4.0 * v[ne + i, 1] / ((r_nm + hm) * cm)
        dlon += v[i + 1, 1] / ((r_n1 + h1) * c1)
        lat[i + 1], lon[i + 1], h[i + 1] = lat1, lon[i] + w / 6.0 * dlon, h1
        lat_m[i] = 0.5 * (lat[i] + lat1) + w * (dlat0 - dlat1) / 8.0
        h_m[i] = hm
        r_m0, r_n0, c0 = r_m1, r_n1, c1
    return lat, lon, h, lat_m, h_m


def specific_force_and_rate(kin: Kinematics, lat: Array, h: Array) -> tuple[Array, Array]:
    """Ideal ``omega_ib_b`` (rad/s) and ``f_ib_b`` (m/s²) from kinematics and position.

    ``omega_ib_b = omega_nb_b + C_bn (omega_ie_n + omega_en_n)``;
    ``f_ib_b = C_bn (a_n + (2 omega_ie_n + omega_en_n) × v_n - g_n)``.
    All inputs are time-major with ``n`` rows; ``lat`` in rad, ``h`` in m.
    """
    return _ideal_imu(
        *(np.ascontiguousarray(a, dtype=float) for a in (kin.v_n, kin.a_n, kin.q_nb, kin.omega_nb_b, lat, h))
    )


def interval_count(duration_s: float, rate_hz: float) -> int:
    """How many sampling intervals of ``1 / rate_hz`` fit in ``duration_s``: a run of that length has
    one sample more. A nanosecond's worth of rounding in ``duration_s · rate_hz`` (a 0.1 s step that
    does not add up to 1 s) counts as a whole interval. The one count of a run's samples: the
    trajectory's times and the scenario's size (:func:`sins.scenario.sample_count`) both take it."""
    return math.floor(duration_s * rate_hz + 1e-9)


def sample_times(motion: Motion, rate_hz: float) -> Array:
    """Sample times ``t_start + k / rate_hz`` that fit in the motion's span."""
    if not rate_hz > 0:
        raise ValueError(f"IMU rate must be positive, got {rate_hz}")
    n = interval_count(motion.t_end - motion.t_start, rate_hz)
    if n < 1:
        raise ValueError(f"the motion lasts {motion.t_end - motion.t_start:g} s, shorter than one sample")
    return motion.t_start + np.arange(n + 1) / rate_hz


def start_state(motion: Motion) -> NavSeries:
    """The truth at the motion's start, as a length-1 series."""
    kin = motion.kinematics(np.array([motion.t_start]))
    return NavSeries(
        t=np.array([motion.t_start]), lat=np.array([motion.lat0]), lon=np.array([motion.lon0]),
        h=np.array([motion.h0]), v_n=kin.v_n, q_nb=kin.q_nb,
    )  # fmt: skip


def generate_chunks(
    motion: Motion, rate_hz: float, chunk: int = CHUNK
) -> Iterator[tuple[NavSeries, ImuIncrements]]:
    """Truth and exact ideal IMU increments, ``chunk`` sample intervals at a time.

    Yields ``(truth, imu)`` per chunk: ``imu`` covers the intervals
    ``(t[k0], t[k1]]`` (``imu.t`` has ``k1 - k0 + 1`` times) and ``truth`` the
    states at ``imu.t[1:]``. The start state is :func:`start_state`. Memory
    stays bounded by the chunk, whatever the duration: a chunk holds ``chunk``
    Simpson pieces, so below 100 Hz, where each interval is cut in several, it
    holds fewer intervals.
    """
    if chunk < 1:
        raise ValueError(f"chunk must be >= 1, got {chunk}")
    t = sample_times(motion, rate_hz)
    n = len(t) - 1
    breaks = np.asarray(motion.breakpoints(), dtype=float)
    pieces = _pieces_per_interval(t)
    position = (motion.lat0, motion.lon0, motion.h0)
    span = max(1, chunk // pieces)
    for k0 in range(0, n, span):
        ts = t[k0 : min(n, k0 + span) + 1]
        truth, imu = _chunk(motion, ts, breaks, pieces, *position)
        position = (truth.lat[-1], truth.lon[-1], truth.h[-1])
        yield truth, imu


def generate(motion: Motion, rate_hz: float) -> tuple[NavSeries, ImuIncrements]:
    """Truth trajectory and exact ideal IMU increments of a motion.

    Parameters
    ----------
    motion : a :class:`sins.nav.motion.Motion`
    rate_hz : IMU sample rate, Hz

    Returns
    -------
    truth : NavSeries at the ``n + 1`` sample times (the first is the start)
    imu : ImuIncrements over the ``n`` sample intervals
    """
    first = start_state(motion)
    parts = list(generate_chunks(motion, rate_hz))
    truths = [first] + [p[0] for p in parts]
    join = lambda name: np.concatenate([getattr(x, name) for x in truths])  # noqa: E731
    truth = NavSeries(
        t=join("t"), lat=join("lat"), lon=join("lon"), h=join("h"), v_n=join("v_n"), q_nb=join("q_nb")
    )
    imu = ImuIncrements(
        t=truth.t,
        dtheta_b=np.concatenate([p[1].dtheta_b for p in parts]),
        dv_b=np.concatenate([p[1].dv_b for p in parts]),
    )
    return truth, imu


def ideal_rates(motion: Motion, truth: NavSeries) -> ImuRates:
    """Exact ideal IMU in rate form at the truth's times (instantaneous samples)."""
    kin = motion.kinematics(truth.t)
    omega, f = specific_force_and_rate(kin, truth.lat, truth.h)
    return ImuRates(t=truth.t, omega_ib_b=omega, f_ib_b=f)


def _off_grid(ts: Array, breaks: Array) -> Array:
    """The breakpoints within ``ts``'s span that are not within rounding of one of its samples."""
    inner = breaks[(breaks > ts[0]) & (breaks < ts[-1])]
    if inner.size:
        j = np.clip(np.searchsorted(ts, inner), 1, len(ts) - 1)
        near = np.minimum(np.abs(inner - ts[j - 1]), np.abs(ts[j] - inner)) < 1e-9 * (ts[1] - ts[0])
        inner = inner[~near]
    return inner


def _pieces_per_interval(t: Array) -> int:
    """Equal Simpson pieces per sample interval: as many as keep each within :data:`MAX_SUBINTERVAL_S`
    (one from 100 Hz up). Decided once for the motion, so every chunk splits alike."""
    return max(1, math.ceil((t[1] - t[0]) / MAX_SUBINTERVAL_S - 1e-9))


def _chunk(
    motion: Motion, ts: Array, breaks: Array, pieces: int, lat0: float, lon0: float, h0: float
) -> tuple[NavSeries, ImuIncrements]:
    """Truth at ``ts[1:]`` and increments over the intervals of ``ts``, from the position at ``ts[0]``."""
    m = len(ts) - 1
    # Sub-interval edges: the samples, each interval cut in ``pieces``, and any breakpoint not within
    # rounding of a sample.
    edges = ts
    if pieces > 1:
        cuts = ts[:-1, None] + np.arange(1, pieces) * (np.diff(ts)[:, None] / pieces)
        edges = np.union1d(edges, cuts.ravel())
    inner = _off_grid(ts, breaks)
    if inner.size:
        edges = np.union1d(edges, inner)
    ne = len(edges)
    sample_at = np.searchsorted(edges, ts)  # where each sample sits among the edges
    width = np.diff(edges)
    # One evaluation at every edge, then every midpoint.
    kin = motion.kinematics(np.concatenate([edges, edges[:-1] + 0.5 * width]))
    lat_e, lon_e, h_e, lat_m, h_m = _integrate_position(width, kin.v_n, lat0, lon0, h0)
    if not np.isfinite(lat_e).all():
        at_pole = float(edges[int(np.argmin(np.isfinite(lat_e)))])
        raise ValueError(
            f"the trajectory reaches a pole at t = {at_pole:g} s; the latitude/longitude mechanisation "
            "cannot pass one"
        )
    omega, f = specific_force_and_rate(kin, np.concatenate([lat_e, lat_m]), np.concatenate([h_e, h_m]))

    def simpson_sums(rate: Array) -> Array:
        """Simpson integrals per sample interval of a quantity given at edges then midpoints."""
        per_edge = (width / 6.0)[:, None] * (rate[: ne - 1] + 4.0 * rate[ne:] + rate[1:ne])
        return np.add.reduceat(per_edge, sample_at[:-1], axis=0)

    at = sample_at[1:]
    truth = NavSeries(t=ts[1:], lat=lat_e[at], lon=lon_e[at], h=h_e[at], v_n=kin.v_n[at], q_nb=kin.q_nb[at])
    assert len(truth.t) == m
    return truth, ImuIncrements(t=ts, dtheta_b=simpson_sums(omega), dv_b=simpson_sums(f))


__all__ = [
    "CHUNK",
    "MAX_SUBINTERVAL_S",
    "generate",
    "generate_chunks",
    "ideal_rates",
    "interval_count",
    "sample_times",
    "specific_force_and_rate",
    "start_state",
]
