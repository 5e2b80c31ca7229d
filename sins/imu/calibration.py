"""Calibration rig procedures, their simulation, and the least-squares fit of the seed model.

A rig session is a sequence of phases at a fixed place on Earth:

* multi-position static: the IMU rests with each face down in turn, at 1, 2
  or 4 headings (6, 12 or 24 orientations), for ``dwell_s`` each; or tilted
  as well, with each edge (18) and each corner (26) down, so that gravity also
  lies between the axes (0.71 g and 0.58 g on each) and the effects that are
  the same column at 0 and ±1 g (``|f|`` and ``f²``, a scale and a clip at
  0.95 g, the cross products of ``f``) come apart;
* rate table: a single-axis table with a vertical axis; the IMU is mounted
  with its x, y or z axis up or down and the table steps through rates of both
  signs, ramping between them at a finite angular acceleration;
* temperature: a chamber profile (ramps and soaks) over the whole session.

The rig knows its nominal orientation and rate; its own errors (orientation
accuracy, rate accuracy) make the truth the IMU sees differ from the
reference it records. :func:`fit_seed_model` fits the seed paper's 33
coefficients, ``Δω = B0 + B ω + K n`` and ``Δn = A0 + A n``, by least squares
on the reference inputs, with standard errors from the residuals.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable
from dataclasses import dataclass, field, fields

import numba
import numpy as np
from numpy.typing import NDArray

from sins.core import earth, rotation
from sins.core.series import CalibrationData, ImuRates, RigPhase
from sins.imu import ImuModel

Array = NDArray[np.float64]

_AXES = {"x": 0, "y": 1, "z": 2}
#: The static position counts :func:`static_orientations` knows.
POSITION_COUNTS = (0, 6, 12, 18, 24, 26)

#: A table's rate (rad/s) and angle (rad) against time since the phase began.
RateProfile = Callable[[Array], tuple[Array, Array]]


@dataclass(frozen=True)
class RateTable:
    """Rate-table runs: for every mounted axis and orientation, each rate of both signs.

    ``rates_dps`` are magnitudes; the table ramps between consecutive rates at
    ``accel_dps2`` and dwells ``dwell_s`` at each.
    """

    rates_dps: tuple[float, ...] = (10.0, 50.0, 100.0, 200.0)
    axes: tuple[str, ...] = ("x", "y", "z")
    orientations: tuple[str, ...] = ("up", "down")
    dwell_s: float = 10.0
    accel_dps2: float = 100.0


@dataclass(frozen=True)
class TemperatureProfile:
    """Chamber temperature, piecewise linear through ``(times_s, temps_degc)``; constant outside."""

    times_s: tuple[float, ...] = (0.0,)
    temps_degc: tuple[float, ...] = (20.0,)

    def at(self, t: Array) -> Array:
        """Chamber temperature, °C, at times ``t`` (s)."""
        return np.interp(t, self.times_s, self.temps_degc)


@dataclass(frozen=True)
class RigProcedure:
    """A calibration session.

    ``positions`` is 0, 6, 12, 24 (faces down) or 18, 26 (faces, edges and corners down; see
    :func:`static_orientations`); ``orientation_error_deg`` is the 1σ error
    of each static orientation (and of each mounting on the table) about every
    axis; ``rate_error_ppm`` is the 1σ scale error of the table's rate.
    """

    lat_deg: float = 45.0
    lon_deg: float = 0.0
    h_m: float = 100.0  # height above the ellipsoid (the rig file's ``alt_m``)
    rate_hz: float = 100.0
    positions: int = 24
    position_dwell_s: float = 20.0
    rate_table: RateTable | None = field(default_factory=RateTable)
    temperature: TemperatureProfile = field(default_factory=TemperatureProfile)
    orientation_error_deg: float = 0.0
    rate_error_ppm: float = 0.0

    def __post_init__(self) -> None:
        if self.positions not in POSITION_COUNTS:
            raise ValueError(
                f"positions must be one of {', '.join(map(str, POSITION_COUNTS))}, got {self.positions}"
            )
        if not self.rate_hz > 0 or not self.position_dwell_s > 0:
            raise ValueError("rate_hz and position_dwell_s must be positive")
        if self.rate_table is not None:
            rt = self.rate_table
            if not rt.dwell_s > 0 or not rt.accel_dps2 > 0 or any(r <= 0 for r in rt.rates_dps):
                raise ValueError("rate table: dwell_s, accel_dps2 and rates_dps must be positive")
            for a in rt.axes:
                if a not in _AXES:
                    raise ValueError(f"rate table: axes must be x, y or z, got {a!r}")
            for o in rt.orientations:
                if o not in ("up", "down"):
                    raise ValueError(f"rate table: orientations must be up or down, got {o!r}")
        if self.positions == 0 and self.rate_table is None:
            raise ValueError("a rig procedure needs static positions, a rate table, or both")


def _face_down(axis: int, sign: float) -> Array:
    """``C_nb`` with body axis ``sign·e_axis`` pointing down and the rest level."""
    target = np.zeros(3)
    target[axis] = sign
    return _down(target)


def _down(target: Array) -> Array:
    """``C_nb`` turning the body unit vector ``target`` onto the down axis by the shortest rotation."""
    target = target / np.linalg.norm(target)
    # Rotate body vector `target` onto the down axis [0, 0, 1].
    down = np.array([0.0, 0.0, 1.0])
    v = np.cross(target, down)
    c = float(target @ down)
    if np.linalg.norm(v) < 1e-12:
        return np.eye(3) if c > 0 else rotation.dcm_from_euler(np.pi, 0.0, 0.0)
    k = rotation.skew(v)
    return np.eye(3) + k + k @ k / (1.0 + c)


def static_orientations(count: int) -> list[tuple[str, Array]]:
    """``(name, C_nb)`` of the static positions.

    6, 12 or 24: each face down at 1, 2 or 4 headings. 18: each face, then each of the 12 edges
    down (the two body axes either side of it at 45°). 26: those and each of the 8 corners down
    (all three axes at 35.3° from the vertical).
    """
    if count in (18, 26):
        out = static_orientations(6)
        signs = ((1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0))
        for a, b in ((0, 1), (0, 2), (1, 2)):
            for sa, sb in signs:
                v = np.zeros(3)
                v[a], v[b] = sa, sb
                out.append((f"{_label(v)} edge down", _down(v)))
        if count == 26:
            for signs3 in itertools.product((1.0, -1.0), repeat=3):
                corner = np.array(signs3)
                out.append((f"{_label(corner)} corner down", _down(corner)))
        return out
    headings = {6: (0.0,), 12: (0.0, 90.0), 24: (0.0, 90.0, 180.0, 270.0)}[count]
    out = []
    for axis, label in enumerate("xyz"):
        for sign, s in ((1.0, "+"), (-1.0, "-")):
            base = _face_down(axis, sign)
            for h in headings:
                out.append(
                    (
                        f"{s}{label} down, heading {h:g}°",
                        rotation.dcm_from_euler(0.0, 0.0, np.radians(h)) @ base,
                    )
                )
    return out


def _label(v: Array) -> str:
    return "".join(("+" if c > 0 else "-") + a for c, a in zip(v, "xyz", strict=True) if c != 0)


def _small_rotation(rng: np.random.Generator, sigma_rad: float) -> Array:
    if sigma_rad == 0.0:
        return np.eye(3)
    return rotation.dcm_from_quat(rotation.quat_from_rotvec(rng.normal(0.0, sigma_rad, 3)))


@dataclass
class _Timeline:
    """Truth and reference accumulated phase by phase."""

    rate_hz: float
    t: list[Array] = field(default_factory=list)
    omega: list[Array] = field(default_factory=list)
    f: list[Array] = field(default_factory=list)
    ref_omega: list[Array] = field(default_factory=list)
    ref_f: list[Array] = field(default_factory=list)
    phases: list[RigPhase] = field(default_factory=list)
    n: int = 0
    time: float = 0.0

    def add(
        self, name: str, kind: str, duration: float, c_nb: Array, c_nb_ref: Array,
        table_rate: RateProfile, table_rate_ref: RateProfile,
        pieces: list[tuple[float, float, str]] | None = None,
    ) -> None:  # fmt: skip
        """A phase (or, with ``pieces``, one phase per piece): the mounting ``C_nb`` (3, 3) of the truth
        and of the reference, and their table rates."""
        m = round(duration * self.rate_hz)
        tt = self.time + np.arange(m) / self.rate_hz
        self.t.append(tt)
        for start, end, label in pieces or [(0.0, duration, "")]:
            i0, i1 = round(start * self.rate_hz), min(round(end * self.rate_hz), m)
            if i1 > i0:
                self.phases.append(RigPhase(f"{name} {label}".strip(), self.n + i0, self.n + i1, kind))
        self.n += m
        self.time += m / self.rate_hz
        local = tt - tt[0]
        for sink_w, sink_f, c, rate in (
            (self.omega, self.f, c_nb, table_rate),
            (self.ref_omega, self.ref_f, c_nb_ref, table_rate_ref),
        ):
            w_table, angle = rate(local)
            # The table turns about the local vertical: C_nb(t) = Rz(angle) C_mount.
            c_t = rotation.dcm_from_euler(0.0, 0.0, angle) @ c  # (m, 3, 3)
            c_bn = np.swapaxes(c_t, -1, -2)
            sink_w.append(c_bn @ self._w_ie + (c.T @ np.array([0.0, 0.0, 1.0]))[None, :] * w_table[:, None])
            sink_f.append(c_bn @ self._f_n)

    def setup(self, lat: float, h: float) -> None:
        self._w_ie = np.array(earth.earth_rate_n(lat), dtype=float)
        self._f_n = np.array([0.0, 0.0, -earth.normal_gravity(lat, h)])


def _still(local: Array) -> tuple[Array, Array]:
    return np.zeros_like(local), np.zeros_like(local)


def _rate_profile(
    rates_rad: list[float], dwell: float, accel: float
) -> tuple[RateProfile, float, list[tuple[float, float, str]]]:
    """Table rate and angle for a run: from rest, ramp at ``accel`` to each rate, dwell, … back to rest.

    Also returns the run's pieces ``(start, end, label)``: each ramp and each dwell.
    """
    knots_t, knots_w = [0.0], [0.0]
    pieces: list[tuple[float, float, str]] = []
    for w in [*rates_rad, 0.0]:
        ramp = abs(w - knots_w[-1]) / accel
        t0 = knots_t[-1]
        knots_t += [t0 + ramp, t0 + ramp + (dwell if w != 0.0 else 0.0)]
        knots_w += [w, w]
        pieces.append((t0, t0 + ramp, f"ramp to {np.degrees(w):+g} °/s"))
        if w != 0.0:
            pieces.append((t0 + ramp, t0 + ramp + dwell, f"{np.degrees(w):+g} °/s"))
    kt, kw = np.array(knots_t), np.array(knots_w)
    # Exact angle of a piecewise-linear rate: trapezoids up to each knot, then the partial piece.
    kangle = np.concatenate([[0.0], np.cumsum(0.5 * (kw[1:] + kw[:-1]) * np.diff(kt))])

    def profile(local: Array) -> tuple[Array, Array]:
        w = np.interp(local, kt, kw)
        i = np.clip(np.searchsorted(kt, local, side="right") - 1, 0, len(kt) - 2)
        angle = kangle[i] + 0.5 * (kw[i] + w) * (local - kt[i])
        return w, angle

    return profile, float(kt[-1]), pieces


def simulate_rig(procedure: RigProcedure, model: ImuModel, seed: int | None = None) -> CalibrationData:
    """Simulate a calibration session: the rig's reference, the truth, the IMU's readings.

    Parameters
    ----------
    procedure : what the rig does
    model : the IMU's error model (see :mod:`sins.imu`)
    seed : seeds the rig's own errors and the IMU's stochastic effects

    Returns
    -------
    CalibrationData with one phase per static position and per rate-table run
    """
    motion = rig_motion(procedure, seed)
    readings = model.corrupt_rates(
        ImuRates(t=motion.t, omega_ib_b=motion.omega_ib_b, f_ib_b=motion.f_ib_b), temp=motion.temp, seed=seed
    )
    return CalibrationData(  # copies of the shared motion: a session is the caller's to change
        t=motion.t.copy(),
        gyro=readings.omega_ib_b,
        accel=readings.f_ib_b,
        ref_gyro=motion.ref_omega_ib_b.copy(),
        ref_accel=motion.ref_f_ib_b.copy(),
        temp=motion.temp.copy(),
        phases=motion.phases,
        source="simulated rig",
    )


@dataclass(frozen=True)
class RigMotion:
    """What a rig session's unit undergoes and what the rig says it does: times (s), the true and the
    reference angular rate (rad/s) and specific force (m/s²) in the body frame, (n, 3) each, the
    chamber temperature (°C) and the phases. Its arrays are read-only: sessions share them, and each
    :func:`simulate_rig` hands its caller copies."""

    t: Array
    omega_ib_b: Array
    f_ib_b: Array
    ref_omega_ib_b: Array
    ref_f_ib_b: Array
    temp: Array
    phases: tuple[RigPhase, ...]


def rig_motion(procedure: RigProcedure, seed: int | None = None) -> RigMotion:
    """The session's motion: the rig's own errors drawn from ``seed``.

    A rig without errors of its own (``orientation_error_deg`` and ``rate_error_ppm`` zero) moves
    every unit alike, so a campaign's units share one computation of it (the last few are kept).
    """
    errors = procedure.orientation_error_deg != 0.0 or procedure.rate_error_ppm != 0.0
    return _rig_motion(procedure, seed if errors else None)


@functools.lru_cache(maxsize=4)
def _rig_motion(procedure: RigProcedure, seed: int | None) -> RigMotion:
    rng = np.random.default_rng([0 if seed is None else seed, 7])
    sigma = np.radians(procedure.orientation_error_deg)
    lat = np.radians(procedure.lat_deg)
    line = _Timeline(procedure.rate_hz)
    line.setup(lat, procedure.h_m)
    if procedure.positions:
        for name, c in static_orientations(procedure.positions):
            true_c = _small_rotation(rng, sigma) @ c
            line.add(name, "static", procedure.position_dwell_s, true_c, c, _still, _still)
    rt = procedure.rate_table
    if rt is not None:
        for axis in rt.axes:
            for orient in rt.orientations:
                # Mounted with body axis `axis` up (its negative down) or down.
                c = _face_down(_AXES[axis], -1.0 if orient == "up" else 1.0)
                true_c = _small_rotation(rng, sigma) @ c
                rates = [s * np.radians(r) for r in rt.rates_dps for s in (1.0, -1.0)]
                nominal, duration, pieces = _rate_profile(rates, rt.dwell_s, np.radians(rt.accel_dps2))
                scale = 1.0 + rng.normal(0.0, procedure.rate_error_ppm * 1e-6)

                def actual(
                    local: Array, nominal: RateProfile = nominal, scale: float = scale
                ) -> tuple[Array, Array]:
                    w, angle = nominal(local)
                    return w * scale, angle * scale

                line.add(f"table {axis} {orient}", "rotation", duration, true_c, c, actual, nominal, pieces)
    t = np.concatenate(line.t)
    motion = RigMotion(
        t=t,
        omega_ib_b=np.concatenate(line.omega),
        f_ib_b=np.concatenate(line.f),
        ref_omega_ib_b=np.concatenate(line.ref_omega),
        ref_f_ib_b=np.concatenate(line.ref_f),
        temp=procedure.temperature.at(t),
        phases=tuple(line.phases),
    )
    for f in fields(motion):
        value = getattr(motion, f.name)
        if isinstance(value, np.ndarray):
            value.flags.writeable = False
    return motion


# --------------------------------------------------------------------------- the seed model's fit


@dataclass(frozen=True)
class SeedModelFit:
    """The seed paper's 33 coefficients with their standard errors.

    ``Δω = B0 + B ω + K n`` (gyro: 3 + 9 + 9), ``Δn = A0 + A n`` (accel: 3 + 9);
    errors are reading − reference; SI units. ``*_se`` are standard errors;
    ``residual_rms`` (6,) the per-channel RMS of the fit residual.
    """

    B0: Array
    B: Array
    K: Array
    A0: Array
    A: Array
    B0_se: Array
    B_se: Array
    K_se: Array
    A0_se: Array
    A_se: Array
    residual_rms: Array

    def vector(self) -> Array:
        """The 33 coefficients in the order B0, B, K, A0, A (row-major)."""
        return np.concatenate([self.B0, self.B.ravel(), self.K.ravel(), self.A0, self.A.ravel()])

    def standard_errors(self) -> Array:
        """Standard errors of the 33 coefficients, in :meth:`vector`'s order."""
        return np.concatenate(
            [self.B0_se, self.B_se.ravel(), self.K_se.ravel(), self.A0_se, self.A_se.ravel()]
        )

    def correct(self, gyro: Array, accel: Array) -> tuple[Array, Array]:
        """Invert the fitted model: the inputs that give these readings (rate form)."""
        return invert_seed_model(self.B0, self.B, self.K, self.A0, self.A, gyro, accel)


def invert_seed_model(
    B0: Array, B: Array, K: Array, A0: Array, A: Array, gyro: Array, accel: Array, dt: Array | None = None
) -> tuple[Array, Array]:
    """The angular rate and specific force (n, 3) that the seed model maps to these readings.

    ``accel = n + A0 + A n`` is solved for ``n`` first; then
    ``gyro = ω + B0 + B ω + K n`` for ``ω``. With ``dt`` (n,), s, the readings are increments over
    intervals of those lengths and so is the answer: the model is affine, so an interval's integral
    obeys it with the biases times ``dt``.
    """
    gyro, accel = np.ascontiguousarray(gyro, dtype=float), np.ascontiguousarray(accel, dtype=float)
    if gyro.shape != accel.shape or gyro.ndim != 2 or gyro.shape[1] != 3:
        raise ValueError(f"gyro and accel must both be (n, 3), got {gyro.shape} and {accel.shape}")
    step = np.zeros(0) if dt is None else np.ascontiguousarray(dt, dtype=float)
    if dt is not None and step.shape != (len(gyro),):
        raise ValueError(f"dt must be ({len(gyro)},), got {step.shape}")
    w, n = np.empty_like(gyro), np.empty_like(accel)
    coefficients = {"B0": B0, "B": B, "K": K, "A0": A0, "A": A}
    for name, value in coefficients.items():
        shape = (3,) if name.endswith("0") else (3, 3)
        if np.shape(value) != shape:
            raise ValueError(f"{name} must be of shape {shape}, got {np.shape(value)}")
    b_inv = np.asarray(np.linalg.inv(np.eye(3) + B), dtype=np.float64)
    a_inv = np.asarray(np.linalg.inv(np.eye(3) + A), dtype=np.float64)
    b0, k, a0 = (np.ascontiguousarray(x, dtype=np.float64) for x in (B0, K, A0))
    _invert_kernel(b_inv, a_inv, b0, k, a0, gyro, accel, step, w, n)
    return w, n


# "contract" fuses multiply-adds: it changes only last bits (as in sins.nav.strapdown's kernel).
@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def _invert_kernel(
    b_inv: Array, a_inv: Array, b0: Array, k: Array, a0: Array, gyro: Array, accel: Array, dt: Array,
    w: Array, n: Array,
) -> None:  # fmt: skip
    """:func:`invert_seed_model` row by row, in one pass: ``n = (I + A)⁻¹ (accel − A0)``, then
    ``w = (I + B)⁻¹ (gyro − B0 − K n)``, the biases times ``dt[r]`` (``dt`` with no rows: rates)."""
    increments = dt.shape[0] > 0
    for r in range(gyro.shape[0]):
        scale = dt[r] if increments else 1.0
        a_x, a_y, a_z = accel[r, 0] - a0[0] * scale, accel[r, 1] - a0[1] * scale, accel[r, 2] - a0[2] * scale
        n_x = a_inv[0, 0] * a_x + a_inv[0, 1] * a_y + a_inv[0, 2] * a_z
        n_y = a_inv[1, 0] * a_x + a_inv[1, 1] * a_y + a_inv[1, 2] * a_z
        n_z = a_inv[2, 0] * a_x + a_inv[2, 1] * a_y + a_inv[2, 2] * a_z
        g_x = gyro[r, 0] - b0[0] * scale - (k[0, 0] * n_x + k[0, 1] * n_y + k[0, 2] * n_z)
        g_y = gyro[r, 1] - b0[1] * scale - (k[1, 0] * n_x + k[1, 1] * n_y + k[1, 2] * n_z)
        g_z = gyro[r, 2] - b0[2] * scale - (k[2, 0] * n_x + k[2, 1] * n_y + k[2, 2] * n_z)
        n[r, 0], n[r, 1], n[r, 2] = n_x, n_y, n_z
        w[r, 0] = b_inv[0, 0] * g_x + b_inv[0, 1] * g_y + b_inv[0, 2] * g_z
        w[r, 1] = b_inv[1, 0] * g_x + b_inv[1, 1] * g_y + b_inv[1, 2] * g_z
        w[r, 2] = b_inv[2, 0] * g_x + b_inv[2, 1] * g_y + b_inv[2, 2] * g_z


def fit_seed_model(
    data: CalibrationData,
    *,
    g_sensitivity: bool = True,
    sensors: tuple[str, ...] = ("gyro", "accel"),
    weights: Array | None = None,
) -> SeedModelFit:
    """Least-squares fit of the seed model on a calibration recording.

    Every row with a finite reference is one observation per channel. A
    rotation phase without per-sample reference but with a known integrated
    angle (``RigPhase.angle_rad``) adds one observation per gyro channel: the
    integrated reading equals ``(I + B) angle + B0 T`` (``K`` is not
    identifiable there and must be off: ``g_sensitivity=False``), weighted as
    one sample. Standard errors are ``σ̂² (XᵀX)⁻¹`` with ``σ̂²`` the residual
    variance, valid for white measurement noise. A sensor left out of
    ``sensors`` gets zero coefficients and NaN standard errors. ``weights``
    (n,), one per row, turn it into weighted least squares (both sides of each
    row's equation scaled by the square root of its weight).

    Raises
    ------
    ValueError
        when the recording cannot determine the coefficients (too few distinct
        orientations or rates).
    """
    for sensor in sensors:
        if sensor not in ("gyro", "accel"):
            raise ValueError(f"sensors must be gyro and/or accel, got {sensor!r}")
    data.check_readings()
    ok = data.has_reference
    w_ref, n_ref = data.ref_gyro[ok], data.ref_accel[ok]
    ones = np.ones((len(w_ref), 1))
    root = (
        np.ones((len(w_ref), 1))
        if weights is None
        else np.sqrt(np.asarray(weights, dtype=float)[ok])[:, None]
    )
    width = 7 if g_sensitivity else 4
    coef_g, se_g, rms_g = np.zeros((width, 3)), np.full((width, 3), np.nan), np.full(3, np.nan)
    if "gyro" in sensors:
        x_gyro = root * np.hstack([ones, w_ref, n_ref] if g_sensitivity else [ones, w_ref])
        y_gyro = root * (data.gyro[ok] - w_ref)
        dt = np.median(np.diff(data.t)) if len(data.t) > 1 else 1.0
        extra_x, extra_y = [], []
        for p in data.phases:
            if p.angle_rad is None:
                continue
            if g_sensitivity:
                raise ValueError(
                    f"phase {p.name!r} gives only its turn's angle, which cannot tell the gyro's "
                    "g-sensitivity: leave the g-sensitivity out of the model (g_sensitivity off)"
                )
            span = data.t[p.stop - 1] - data.t[p.start] + dt
            angle = np.asarray(p.angle_rad)
            # Readings summed over the phase (rectangle rule at the sample interval) against the known angle.
            total = data.gyro[p.start : p.stop].sum(axis=0) * dt
            scale = 1.0 / (np.sqrt(p.stop - p.start) * dt)  # one-sample weight
            extra_x.append(scale * np.concatenate([[span], angle]))
            extra_y.append(scale * (total - angle))
        if extra_x:
            x_gyro = np.vstack([x_gyro, np.array(extra_x)])
            y_gyro = np.vstack([y_gyro, np.array(extra_y)])
        coef_g, se_g, rms_g = _lstsq(x_gyro, y_gyro, "gyro", data.source)
    coef_a, se_a, rms_a = np.zeros((4, 3)), np.full((4, 3), np.nan), np.full(3, np.nan)
    if "accel" in sensors:
        x_acc, y_acc = root * np.hstack([ones, n_ref]), root * (data.accel[ok] - n_ref)
        coef_a, se_a, rms_a = _lstsq(x_acc, y_acc, "accel", data.source)
    zeros = np.zeros((3, 3))
    return SeedModelFit(
        B0=coef_g[0], B=coef_g[1:4].T, K=coef_g[4:7].T if g_sensitivity else zeros,
        A0=coef_a[0], A=coef_a[1:4].T,
        B0_se=se_g[0], B_se=se_g[1:4].T, K_se=se_g[4:7].T if g_sensitivity else zeros,
        A0_se=se_a[0], A_se=se_a[1:4].T,
        residual_rms=np.concatenate([rms_g, rms_a]),
    )  # fmt: skip


def _lstsq(x: Array, y: Array, sensor: str, source: str) -> tuple[Array, Array, Array]:
    m, p = x.shape
    if m <= p:
        raise ValueError(
            f"{source or 'recording'}: {m} usable {sensor} samples for {p} coefficients per channel"
        )
    coef, _, rank, _ = np.linalg.lstsq(x, y, rcond=None)
    # Judge identifiability on unit-RMS columns: a rate seen only as the Earth's
    # 7e-5 rad/s is collinear with the bias column, whatever its raw scale.
    scale = np.sqrt(np.mean(x * x, axis=0))
    sv = np.linalg.svd(x / np.where(scale > 0, scale, 1.0), compute_uv=False)
    if rank < p or sv[-1] < 1e-6 * sv[0]:
        raise ValueError(
            f"{source or 'recording'}: the {sensor} coefficients are not determined by this recording "
            "(add orientations or rates)"
        )
    resid = y - x @ coef
    sigma2 = (resid * resid).sum(axis=0) / (m - p)
    cov_unit = np.linalg.inv(x.T @ x)
    se = np.sqrt(np.outer(np.diag(cov_unit), sigma2))
    rms: Array = np.sqrt((resid * resid).mean(axis=0))
    return np.asarray(coef, dtype=float), np.asarray(se, dtype=float), rms


__all__ = [
    "POSITION_COUNTS",
    "RateProfile",
    "RateTable",
    "RigMotion",
    "RigProcedure",
    "SeedModelFit",
    "TemperatureProfile",
    "fit_seed_model",
    "invert_seed_model",
    "rig_motion",
    "simulate_rig",
    "static_orientations",
]
