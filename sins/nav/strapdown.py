"""Quaternion strapdown mechanisation in NED on WGS84, compiled with numba.

One step takes one row of increments, ``Δθ_k, Δv_k`` (row ``k``'s integrals over ``(t[k], t[k+1]]``,
the convention stated in :mod:`sins`), with the row before it, ``Δθ_{k-1}, Δv_{k-1}``:

* attitude: body rotation vector ``φ = Δθ_k + (1/12) Δθ_{k-1} × Δθ_k`` (two-sample
  coning correction), navigation-frame rotation ``ζ = (omega_ie_n + omega_en_n) Δt``
  at mid-interval, ``q_nb ← exp(-ζ) ⊗ q_nb ⊗ exp(φ)``;
* velocity: ``Δv_b + ½ Δθ × Δv + (1/12)(Δθ_{k-1} × Δv_k + Δv_{k-1} × Δθ_k)``
  (rotation and sculling), rotated by ``(I - ½[ζ×]) C_nb``, plus gravity and
  Coriolis at mid-interval;
* position: trapezoidal in velocity with radii of curvature at mid-interval.

Mid-interval latitude, height and velocity are extrapolated from the two
previous states, which keeps every term second order without a second pass.
The result converges at second order in the step (``tests/test_strapdown.py``
sweeps 50–400 Hz).

The vertical channel is unstable in free inertial navigation (time constant
``sqrt(R/2g)`` ≈ 570 s). ``vertical="free"`` leaves it so; ``"hold"`` sets
height and vertical velocity from a reference height series each step;
``"damp"`` feeds the height error back through a second-order loop (altitude
aiding) with time constant ``vertical_tau_s``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import NDArray

from sins.core import earth
from sins.core.series import ImuIncrements, NavSeries, check_increasing
from sins.nav.vertical import VERTICAL_MODES, VerticalMode

Array = NDArray[np.float64]

# The kernels' code for each vertical mode (they branch on 1 and 2).
_MODE_CODE: dict[VerticalMode, int] = {"free": 0, "hold": 1, "damp": 2}
_TWELFTH = 1.0 / 12.0

_earth = numba.njit(cache=True, inline="always")(earth.radii_and_gravity_from_sin2)


@numba.njit(cache=True, inline="always")
def _half_angle_terms(ang2: float) -> tuple[float, float]:
    """``sin(a/2)/a`` and ``cos(a/2)`` from ``a²``.

    Series through a⁶ below 0.02 rad (the next terms are < 1e-19, below
    rounding), which covers every step of a vehicle at 100 Hz and saves the
    trigonometry.
    """
    if ang2 < 4e-4:
        return (
            0.5 + ang2 * (-1.0 / 48.0 + ang2 * (1.0 / 3840.0 - ang2 * (1.0 / 645120.0))),
            1.0 + ang2 * (-0.125 + ang2 * (1.0 / 384.0 - ang2 * (1.0 / 46080.0))),
        )
    ang = np.sqrt(ang2)
    return np.sin(0.5 * ang) / ang, np.cos(0.5 * ang)


@dataclass(frozen=True)
class InitialState:
    """Where integration starts: position (rad, rad, m), ``v_n`` (m/s), ``q_nb``."""

    lat: float
    lon: float
    h: float
    v_n: Array
    q_nb: Array

    def __post_init__(self) -> None:
        # As motion.Start's: degrees for the latitude had integrated without a word; a zero quaternion has
        # no attitude (NaN through the run).
        earth.check_latitude(self.lat, "InitialState.lat")
        q = np.asarray(self.q_nb, dtype=float)
        if q.shape != (4,) or not np.isfinite(q).all() or not np.linalg.norm(q) > 0.0:
            raise ValueError(f"InitialState.q_nb must be 4 finite numbers, not all zero (x, y, z, w): {q!r}")

    @classmethod
    def from_series(cls, series: NavSeries, index: int = 0) -> InitialState:
        """The state at ``index`` of a series (typically a truth's first row)."""
        return cls(
            lat=float(series.lat[index]),
            lon=float(series.lon[index]),
            h=float(series.h[index]),
            v_n=np.array(series.v_n[index], dtype=float),
            q_nb=np.array(series.q_nb[index], dtype=float),
        )


# Layout of the state array that carries an integration across calls.
_LAT, _LON, _H, _V, _Q = 0, 1, 2, 3, 6
_LAT_P, _H_P, _V_P, _DT_P, _DTH_P, _DV_P, _STEPS, _COUNTDOWN = 10, 11, 12, 15, 16, 19, 22, 23
_SIN_LAT, _COS_LAT = 24, 25
_T_END = 26  # the last time integrated to (NaN before the first chunk): the next chunk must start there
STATE_SIZE = 27


@numba.njit(cache=True, inline="always")
def _turn(s: float, c: float, d: float) -> tuple[float, float]:
    """``(sin(a + d), cos(a + d))`` from ``(sin a, cos a)``.

    Latitude moves by < 1e-6 rad a step, where the series below are exact to
    rounding; the rounding walk stays below 1e-13 over 1e8 steps. Larger
    steps (a diverging solution) take the exact functions.
    """
    if abs(d) > 1e-4:
        sd, cd = np.sin(d), np.cos(d)
    else:
        d2 = d * d
        sd = d * (1.0 - d2 * (1.0 / 6.0))
        cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0))
    return s * cd + c * sd, c * cd - s * sd


# "contract" fuses multiply-adds and "arcp" turns divisions into reciprocal
# multiplications: both change only the last bit and keep IEEE semantics for
# special values; no approximate transcendental functions are allowed.
# One long loop on purpose, the exception to the house's screen-length rule: the steps (attitude,
# velocity, position, vertical channel) share the running state as scalars, which numba keeps in
# registers; split into functions they would pass it through tuples or arrays on every sample.
@numba.njit(cache=True, nogil=True, fastmath={"contract", "arcp"})
def _kernel(
    t: Array,
    dtheta: Array,
    dv: Array,
    state: Array,
    mode: int,
    h_ref: Array,
    k1: float,
    k2: float,
    every: int,
    out_lat: Array,
    out_lon: Array,
    out_h: Array,
    out_v: Array,
    out_q: Array,
) -> int:
    """Advance ``state`` over the intervals of ``t``; write every ``every``-th new state.

    Returns the number of rows written.
    """
    n = dtheta.shape[0]
    lat, lon, h = state[_LAT], state[_LON], state[_H]
    vn, ve, vd = state[_V], state[_V + 1], state[_V + 2]
    qx, qy, qz, qw = state[_Q], state[_Q + 1], state[_Q + 2], state[_Q + 3]
    lat_p, h_p, dt_p = state[_LAT_P], state[_H_P], state[_DT_P]
    vn_p, ve_p, vd_p = state[_V_P], state[_V_P + 1], state[_V_P + 2]
    ax, ay, az = state[_DTH_P], state[_DTH_P + 1], state[_DTH_P + 2]  # previous Δθ
    bx, by, bz = state[_DV_P], state[_DV_P + 1], state[_DV_P + 2]  # previous Δv
    started = state[_STEPS] > 0.0
    countdown = int(state[_COUNTDOWN])
    sin_lat, cos_lat = state[_SIN_LAT], state[_COS_LAT]
    row = 0
    for k in range(n):
        dt = t[k + 1] - t[k]
        gx, gy, gz = dtheta[k, 0], dtheta[k, 1], dtheta[k, 2]
        ux, uy, uz = dv[k, 0], dv[k, 1], dv[k, 2]

        # Mid-interval navigation quantities by linear extrapolation of the last step.
        e = 0.5 * dt / dt_p if started else 0.0
        lat_m = lat + e * (lat - lat_p)
        h_m = h + e * (h - h_p)
        vn_m = vn + e * (vn - vn_p)
        ve_m = ve + e * (ve - ve_p)
        vd_m = vd + e * (vd - vd_p)

        slat, clat = _turn(sin_lat, cos_lat, lat_m - lat)
        s2 = slat * slat
        r_m, r_n, g = _earth(s2, h_m)
        wie_n = earth.OMEGA_IE * clat
        wie_d = -earth.OMEGA_IE * slat
        inv_rn = 1.0 / (r_n + h_m)
        inv_rm = 1.0 / (r_m + h_m)
        inv_clat = 1.0 / clat
        wen_n = ve_m * inv_rn
        wen_e = -vn_m * inv_rm
        wen_d = -wen_n * slat * inv_clat
        zx = (wie_n + wen_n) * dt
        zy = wen_e * dt
        zz = (wie_d + wen_d) * dt

        # Body rotation vector with two-sample coning correction.
        px = gx + (ay * gz - az * gy) * _TWELFTH
        py = gy + (az * gx - ax * gz) * _TWELFTH
        pz = gz + (ax * gy - ay * gx) * _TWELFTH

        # Specific-force velocity increment in b: rotation + sculling.
        sx = ux + 0.5 * (gy * uz - gz * uy) + ((ay * uz - az * uy) + (by * gz - bz * gy)) * _TWELFTH
        sy = uy + 0.5 * (gz * ux - gx * uz) + ((az * ux - ax * uz) + (bz * gx - bx * gz)) * _TWELFTH
        sz = uz + 0.5 * (gx * uy - gy * ux) + ((ax * uy - ay * ux) + (bx * gy - by * gx)) * _TWELFTH

        # Rotate into n with the attitude at the start of the interval.
        c00 = 1.0 - 2.0 * (qy * qy + qz * qz)
        c01 = 2.0 * (qx * qy - qw * qz)
        c02 = 2.0 * (qx * qz + qw * qy)
        c10 = 2.0 * (qx * qy + qw * qz)
        c11 = 1.0 - 2.0 * (qx * qx + qz * qz)
        c12 = 2.0 * (qy * qz - qw * qx)
        c20 = 2.0 * (qx * qz - qw * qy)
        c21 = 2.0 * (qy * qz + qw * qx)
        c22 = 1.0 - 2.0 * (qx * qx + qy * qy)
        fx = c00 * sx + c01 * sy + c02 * sz
        fy = c10 * sx + c11 * sy + c12 * sz
        fz = c20 * sx + c21 * sy + c22 * sz
        # (I - ½[ζ×]) accounts for the navigation frame turning during the interval.
        fx2 = fx - 0.5 * (zy * fz - zz * fy)
        fy2 = fy - 0.5 * (zz * fx - zx * fz)
        fz2 = fz - 0.5 * (zx * fy - zy * fx)

        # Gravity and Coriolis at mid-interval.
        cx = 2.0 * wie_n + wen_n
        cy = wen_e
        cz = 2.0 * wie_d + wen_d
        vn_new = vn + fx2 - (cy * vd_m - cz * ve_m) * dt
        ve_new = ve + fy2 - (cz * vn_m - cx * vd_m) * dt
        vd_new = vd + fz2 - (cx * ve_m - cy * vn_m) * dt + g * dt

        # Position: trapezoidal in velocity, with the radii and cos(lat) of the
        # extrapolated mid-interval state; they differ from those of the
        # average of old and new states by O(dt²), which keeps second order.
        h_new = h - 0.5 * (vd + vd_new) * dt
        lat_new = lat + 0.5 * (vn + vn_new) * dt * inv_rm
        lon_new = lon + 0.5 * (ve + ve_new) * dt * inv_rn * inv_clat

        if mode == 1:
            h_new = h_ref[k + 1]
            vd_new = -(h_ref[k + 1] - h_ref[k]) / dt
        elif mode == 2:
            err = h_new - h_ref[k + 1]
            h_new -= k1 * err * dt
            vd_new += k2 * err * dt

        # Attitude: q ← exp(-ζ) ⊗ q ⊗ exp(φ).
        sk, ck = _half_angle_terms(px * px + py * py + pz * pz)
        rx, ry, rz, rw = sk * px, sk * py, sk * pz, ck
        tx = qw * rx + qx * rw + qy * rz - qz * ry
        ty = qw * ry - qx * rz + qy * rw + qz * rx
        tz = qw * rz + qx * ry - qy * rx + qz * rw
        tw = qw * rw - qx * rx - qy * ry - qz * rz
        sk, ck = _half_angle_terms(zx * zx + zy * zy + zz * zz)
        mx, my, mz, mw = -sk * zx, -sk * zy, -sk * zz, ck
        qx = mw * tx + mx * tw + my * tz - mz * ty
        qy = mw * ty - mx * tz + my * tw + mz * tx
        qz = mw * tz + mx * ty - my * tx + mz * tw
        qw = mw * tw - mx * tx - my * ty - mz * tz
        # The norm drifts from 1 only by rounding; one Newton step for 1/sqrt restores it.
        norm2 = qx * qx + qy * qy + qz * qz + qw * qw
        scale = 1.5 - 0.5 * norm2
        qx *= scale
        qy *= scale
        qz *= scale
        qw *= scale

        sin_lat, cos_lat = _turn(sin_lat, cos_lat, lat_new - lat)
        lat_p, h_p, vn_p, ve_p, vd_p, dt_p = lat, h, vn, ve, vd, dt
        lat, lon, h, vn, ve, vd = lat_new, lon_new, h_new, vn_new, ve_new, vd_new
        ax, ay, az, bx, by, bz = gx, gy, gz, ux, uy, uz
        started = True

        countdown -= 1
        if countdown == 0:
            countdown = every
            out_lat[row], out_lon[row], out_h[row] = lat, lon, h
            out_v[row, 0], out_v[row, 1], out_v[row, 2] = vn, ve, vd
            sign = -1.0 if qw < 0.0 else 1.0
            out_q[row, 0], out_q[row, 1], out_q[row, 2], out_q[row, 3] = (
                sign * qx,
                sign * qy,
                sign * qz,
                sign * qw,
            )
            row += 1

    state[_LAT], state[_LON], state[_H] = lat, lon, h
    state[_V], state[_V + 1], state[_V + 2] = vn, ve, vd
    state[_Q], state[_Q + 1], state[_Q + 2], state[_Q + 3] = qx, qy, qz, qw
    state[_LAT_P], state[_H_P], state[_DT_P] = lat_p, h_p, dt_p
    state[_V_P], state[_V_P + 1], state[_V_P + 2] = vn_p, ve_p, vd_p
    state[_DTH_P], state[_DTH_P + 1], state[_DTH_P + 2] = ax, ay, az
    state[_DV_P], state[_DV_P + 1], state[_DV_P + 2] = bx, by, bz
    state[_STEPS] += n
    state[_COUNTDOWN] = countdown
    state[_SIN_LAT], state[_COS_LAT] = sin_lat, cos_lat
    return row


@numba.njit(cache=True, parallel=True)
def _batch_kernel(
    t: Array,
    dtheta: Array,
    dv: Array,
    state: Array,
    mode: int,
    h_ref: Array,
    k1: float,
    k2: float,
    every: int,
    out_lat: Array,
    out_lon: Array,
    out_h: Array,
    out_v: Array,
    out_q: Array,
) -> None:
    for j in numba.prange(dtheta.shape[0]):
        _kernel(
            t, dtheta[j], dv[j], state[j], mode, h_ref, k1, k2, every,
            out_lat[j], out_lon[j], out_h[j], out_v[j], out_q[j],
        )  # fmt: skip


#: The "damp" loop's time constant spans at least this many IMU steps: its explicit update is unstable
#: below one step; two keep a margin.
MIN_TAU_SAMPLES = 2


def damp_loop_problem(vertical: str, tau_s: float, t: Array) -> str:
    """What is wrong with a "damp" loop of ``tau_s`` beside the sample times ``t`` ("" where nothing):
    it must span :data:`MIN_TAU_SAMPLES` steps at least (a step's rounding passes)."""
    step = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    if vertical != "damp" or tau_s >= MIN_TAU_SAMPLES * step * (1.0 - 1e-9):
        return ""
    shortest = MIN_TAU_SAMPLES * step
    return (f"with the vertical channel damped, at least {MIN_TAU_SAMPLES} IMU steps ({shortest:g} s at "
            f"{1.0 / step:g} Hz): a shorter damp loop is unstable")  # fmt: skip


def _vertical_args(
    vertical: VerticalMode, h_ref: Array | None, n: int, h0: float, tau_s: float, t: Array
) -> tuple[int, Array, float, float]:
    if vertical not in VERTICAL_MODES:
        raise ValueError(f"vertical must be one of {', '.join(VERTICAL_MODES)}, got {vertical!r}")
    mode = _MODE_CODE[vertical]
    if h_ref is None:
        h_ref = np.full(n + 1, h0)
    h_ref = np.ascontiguousarray(h_ref, dtype=float)
    if h_ref.shape != (n + 1,):
        raise ValueError(f"h_ref must have one height per sample time, shape ({n + 1},), got {h_ref.shape}")
    if not tau_s > 0:
        raise ValueError(f"vertical_tau_s must be positive, got {tau_s}")
    if problem := damp_loop_problem(vertical, tau_s, t):
        raise ValueError(f"vertical_tau_s {tau_s:g}: {problem}")
    # Critically damped: s² + 2s/τ + 1/τ², far faster than the 570 s instability.
    return mode, h_ref, 2.0 / tau_s, 1.0 / tau_s**2


def start(initial: InitialState, every: int = 1) -> Array:
    """A fresh integration state at ``initial``, for :func:`advance`.

    ``every`` is the decimation :func:`advance` will apply (the first state
    written is the ``every``-th after the start).
    """
    if every < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    state = np.zeros(STATE_SIZE)
    state[_LAT], state[_LON], state[_H] = initial.lat, initial.lon, initial.h
    state[_SIN_LAT], state[_COS_LAT] = np.sin(initial.lat), np.cos(initial.lat)
    state[_V : _V + 3] = initial.v_n
    q = np.asarray(initial.q_nb, dtype=float)
    state[_Q : _Q + 4] = q / np.linalg.norm(q)
    state[_COUNTDOWN] = every
    state[_T_END] = np.nan
    return state


def current(state: Array) -> InitialState:
    """The navigation state an integration state (from :func:`start` or :func:`advance`) holds now."""
    return InitialState(
        lat=float(state[_LAT]),
        lon=float(state[_LON]),
        h=float(state[_H]),
        v_n=np.array(state[_V : _V + 3]),
        q_nb=np.array(state[_Q : _Q + 4]),
    )


def moved(state: Array, to: InitialState) -> Array:
    """A copy of an integration state set to the navigation state ``to``: a filter's correction.

    The previous step's position and velocity move by the same amounts, so the next step's
    mid-interval extrapolation sees the vehicle's motion, not the jump; the previous increments
    (coning and sculling memory) are kept.
    """
    out = np.array(state, dtype=float)
    d_lat, d_h = to.lat - out[_LAT], to.h - out[_H]
    d_v = np.asarray(to.v_n, dtype=float) - out[_V : _V + 3]
    out[_LAT], out[_LON], out[_H] = to.lat, to.lon, to.h
    out[_V : _V + 3] = to.v_n
    out[_LAT_P] += d_lat
    out[_H_P] += d_h
    out[_V_P : _V_P + 3] += d_v
    q = np.asarray(to.q_nb, dtype=float)
    out[_Q : _Q + 4] = q / np.linalg.norm(q)
    out[_SIN_LAT], out[_COS_LAT] = np.sin(to.lat), np.cos(to.lat)
    return out


def _check_increments(imu: ImuIncrements) -> None:
    """Refuse increments the compiled kernel would read past the end of, or integrate backwards. The
    kernel checks no bounds (it is compiled for speed), so a mismatch gave results that changed from run
    to run, not an error. :class:`ImuIncrements` holds its own shapes but for one: no rows and no
    boundary either (a stream's empty chunk), which has no start to integrate from. Rates (most readers'
    form) are refused with what converts them, where they failed on a missing attribute."""
    if not isinstance(imu, ImuIncrements):
        raise TypeError(
            f"increments: expected ImuIncrements, got {type(imu).__name__} (rates: integrate "
            "rates.to_increments())"
        )
    if len(imu.t) != len(imu.dtheta_b) + 1:
        raise ValueError(f"increments: t must be (n+1,) for {len(imu.dtheta_b)} rows; got {np.shape(imu.t)}")
    check_increasing(imu.t, "increments")


def advance(
    state: Array,
    imu: ImuIncrements,
    *,
    vertical: VerticalMode = "free",
    h_ref: Array | None = None,
    vertical_tau_s: float = 10.0,
    every: int = 1,
) -> tuple[NavSeries, Array]:
    """Integrate one chunk of an IMU stream, continuing from ``state``.

    Chunks must follow each other, or ``ValueError`` (each chunk's ``imu.t[0]`` is the previous
    chunk's last time); the result is identical to integrating in one call.

    Parameters
    ----------
    state : (STATE_SIZE,) from :func:`start` or a previous :func:`advance`
    imu : the chunk's increments, ``n`` intervals
    vertical, vertical_tau_s : see the module docstring
    h_ref : (n+1,) reference height at ``imu.t`` for "hold"/"damp", m
    every : the decimation given to :func:`start`

    Returns
    -------
    states : NavSeries of the kept states after the chunk's steps
    state : the updated state (a new array)
    """
    _check_increments(imu)
    n = len(imu.dtheta_b)
    mode, h_ref_arr, k1, k2 = _vertical_args(vertical, h_ref, n, float(state[_H]), vertical_tau_s, imu.t)
    state = np.array(state, dtype=float)
    if len(state) != STATE_SIZE:
        raise ValueError(f"state must have {STATE_SIZE} values (from start or advance), got {len(state)}")
    end = state[_T_END]
    if np.isfinite(end) and n and abs(float(imu.t[0]) - end) > 1e-9 * max(1.0, abs(end)):
        # A gap or a step back between chunks had been integrated as if the chunks followed each other.
        raise ValueError(
            f"advance: the chunk starts at {float(imu.t[0])!r} s, not where the last ended ({end!r} s)"
        )
    if n:
        state[_T_END] = float(imu.t[-1])
    first = int(state[_COUNTDOWN])
    m = 0 if n < first else 1 + (n - first) // every
    lat, lon, h, v, q = _alloc(m)
    t = np.ascontiguousarray(imu.t, dtype=float)
    rows = _kernel(
        t, np.ascontiguousarray(imu.dtheta_b, dtype=float), np.ascontiguousarray(imu.dv_b, dtype=float),
        state, mode, h_ref_arr, k1, k2, every, lat, lon, h, v, q,
    )  # fmt: skip
    assert rows == m
    times = t[first::every][:m]
    return NavSeries(t=times, lat=lat, lon=lon, h=h, v_n=v, q_nb=q), state


def integrate(
    imu: ImuIncrements,
    initial: InitialState,
    *,
    vertical: VerticalMode = "free",
    h_ref: Array | None = None,
    vertical_tau_s: float = 10.0,
    every: int = 1,
) -> NavSeries:
    """Integrate one IMU stream from an initial state.

    Parameters
    ----------
    imu : ImuIncrements with ``n`` intervals
    initial : state at ``imu.t[0]``
    vertical : "free", "hold" or "damp" (see the module docstring)
    h_ref : (n+1,) reference height in m for "hold"/"damp"; defaults to the initial height
    vertical_tau_s : time constant of the "damp" loop, s
    every : keep every ``every``-th state (the start is always kept)

    Returns
    -------
    NavSeries at ``imu.t[::every]`` (``1 + n // every`` states)
    """
    states, _ = advance(
        start(initial, every), imu, vertical=vertical, h_ref=h_ref, vertical_tau_s=vertical_tau_s,
        every=every,
    )  # fmt: skip
    return NavSeries(
        t=np.concatenate([[imu.t[0]], states.t]),
        lat=np.concatenate([[initial.lat], states.lat]),
        lon=np.concatenate([[initial.lon], states.lon]),
        h=np.concatenate([[initial.h], states.h]),
        v_n=np.vstack([initial.v_n, states.v_n]),
        q_nb=np.vstack([start(initial)[_Q : _Q + 4], states.q_nb]),
    )


def integrate_batch(
    t: Array,
    dtheta_b: Array,
    dv_b: Array,
    initial: InitialState,
    *,
    vertical: VerticalMode = "free",
    h_ref: Array | None = None,
    vertical_tau_s: float = 10.0,
) -> list[NavSeries]:
    """Integrate many IMU streams that share a time base and a start, in parallel threads.

    Parameters
    ----------
    t : (n+1,) sample times, s
    dtheta_b, dv_b : (m, n, 3) increments of ``m`` streams
    initial, vertical, h_ref, vertical_tau_s : as :func:`integrate`

    Returns
    -------
    list of ``m`` NavSeries at ``t``, identical to ``m`` calls of :func:`integrate`
    """
    dtheta_b = np.ascontiguousarray(dtheta_b, dtype=float)
    dv_b = np.ascontiguousarray(dv_b, dtype=float)
    if dtheta_b.ndim != 3 or dtheta_b.shape != dv_b.shape or dtheta_b.shape[2] != 3:
        raise ValueError(
            f"dtheta_b and dv_b must both have shape (m, n, 3), got {dtheta_b.shape}, {dv_b.shape}"
        )
    streams, n, _ = dtheta_b.shape
    t = np.asarray(t, dtype=float)
    if t.shape != (n + 1,):  # the compiled kernel checks no bounds: a short t had been read past its end
        raise ValueError(f"t must have shape ({n + 1},) for {n} increments, got {t.shape}")
    check_increasing(t, "integrate_batch")  # as integrate's: a step back had integrated without a word
    if streams == 0:  # m calls of integrate, m = 0
        return []
    mode, h_ref_arr, k1, k2 = _vertical_args(vertical, h_ref, n, initial.h, vertical_tau_s, t)
    state = np.tile(start(initial), (streams, 1))
    lat = np.empty((streams, n + 1))
    lon = np.empty((streams, n + 1))
    h = np.empty((streams, n + 1))
    v = np.empty((streams, n + 1, 3))
    q = np.empty((streams, n + 1, 4))
    lat[:, 0], lon[:, 0], h[:, 0] = initial.lat, initial.lon, initial.h
    v[:, 0], q[:, 0] = initial.v_n, state[0, _Q : _Q + 4]
    _batch_kernel(
        np.ascontiguousarray(t, dtype=float), dtheta_b, dv_b, state, mode, h_ref_arr, k1, k2, 1,
        lat[:, 1:], lon[:, 1:], h[:, 1:], v[:, 1:], q[:, 1:],
    )  # fmt: skip
    tt = np.asarray(t, dtype=float)
    return [NavSeries(t=tt, lat=lat[j], lon=lon[j], h=h[j], v_n=v[j], q_nb=q[j]) for j in range(streams)]


def _alloc(m: int) -> tuple[Array, Array, Array, Array, Array]:
    return np.empty(m), np.empty(m), np.empty(m), np.empty((m, 3)), np.empty((m, 4))


__all__ = [
    "MIN_TAU_SAMPLES",
    "STATE_SIZE",
    "InitialState",
    "advance",
    "current",
    "damp_loop_problem",
    "integrate",
    "integrate_batch",
    "moved",
    "start",
]
