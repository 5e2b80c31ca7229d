"""Which coefficients a recording determines, and whether a fitted model is one a unit of its class can have.

A least-squares fit writes a number for every column it is given, determined or not. A still recording
cannot tell a gyro's scale factor (its readings never leave the Earth's rate) from its bias; a car that
only yaws cannot tell the roll and pitch gyros' scale factors; a level unit cannot tell the vertical
accelerometer's scale factor from its bias (gravity is a constant there). Column scaling hides this
from a rank test, and Gauss–Newton then wanders: 6.5e10 ppm of gyro scale factor with an "error" of 19
ppm. So a fit here is judged in physical units, against the class of unit it is of:

* **determined** (:func:`assess`, before the fit): each coefficient's standard error is predicted from
  what the unit truly underwent (the reference's turns, forces and their changes between interval
  ends: a design without the readings' noise, which a regression on the readings would mistake for
  excitation, since a model that zeroes the readings "explains" them), and the noise the intervals
  leave (:func:`determined`). A coefficient is kept only if the data pin it down better than the
  class's own unit-to-unit spread does (a standard error at most that spread, :data:`GRADES`' 1σ), and
  the columns kept are well conditioned. The others are held at zero, the class's mean, one at a
  time: the least determined of the highest order first (time offsets, lever arm and g-sensitivity,
  then scale factors and misalignments, then biases: a bias is the last to go, so a level unit keeps
  its vertical accelerometer bias and loses the scale factor it cannot tell from it). Each is given a
  reason: too little excitation (its standard error alone is already beyond the spread) or confounded
  with another coefficient (named). The fit then holds them (``holds`` of
  :func:`sins.compensation.interval_fit.fit_intervals`).
* **bounds** (:func:`review`): before a model is saved, every coefficient kept must have a finite
  standard error and a value a unit of its class can have (:class:`ClassBounds`: five times the class's
  spread; for consumer parts, biases up to their datasheets' initial tolerances); else the fit is
  refused, naming the coefficient, its value and the bound.

A recording's class is what the user says it is (``sins fit --grade``); without that, ``consumer``,
the loosest.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

from sins.compensation.intervals import Intervals, choose_intervals, dcm, expected_dv
from sins.core import earth, rotation
from sins.core.earth import G0
from sins.core.series import ReferencedRecording
from sins.errors import SinsInputError
from sins.imu import DEG, DEG_PER_H, MG, ImuModel
from sins.imu.calibration import SeedModelFit
from sins.imu.spec import GRADES
from sins.nav import attitude

Array = NDArray[np.float64]
_F = TypeVar("_F", bound="_IntervalFit")

#: The class assumed when the user names none: the loosest bounds.
DEFAULT_GRADE = "consumer"
#: A bound's multiple of the class's unit-to-unit spread (1σ): a unit beyond it is not of the class.
BOUND_SIGMAS = 5.0
#: Phone-class parts' initial tolerances, wider than five spreads of sins's consumer grade: zero-rate
#: output up to ±20 °/s and zero-g output up to ±80 mg (InvenSense MPU-6050 datasheet, at 25 °C), the
#: accelerometer's taken to 100 mg for temperature.
WIDER_BIASES = {"consumer": {"gyro": 20.0 * DEG, "accel": 100.0 * MG}}
#: A time offset's standard error beyond which it is not determined, s, and the largest it may be.
TIME_OFFSET_SE_S, TIME_OFFSET_BOUND_S = 0.01, 0.5
#: The lever arm's standard error beyond which it is not determined, m, and the largest it may be.
LEVER_ARM_SE_M, LEVER_ARM_BOUND_M = 0.1, 10.0
#: Columns scaled to unit RMS whose smallest singular value is below this fraction of the largest are
#: collinear: the coefficient loading most on that direction is held first.
CONDITION = 1e-8
#: Orders: the higher is held first (a bias last).
_ORDER = {"bias": 0, "scale": 1, "misalignment": 1, "g_sensitivity": 2, "lever_arm": 2, "time_offset": 2}
_AXES = "xyz"
GYRO, ACCEL = "gyro", "accel"
#: The seed model's bias and g-sensitivity terms (words an IMU effect's name shares).
BIAS, G_SENSITIVITY = "bias", "g_sensitivity"


@dataclass(frozen=True)
class ClassBounds:
    """A class of unit (a grade of :data:`sins.imu.spec.GRADES`): each term's spread (1σ unit to unit,
    SI: rad/s, m/s², fractions, rad/s per m/s²) and the largest value a unit of the class can have."""

    grade: str
    spread: dict[str, float]
    bound: dict[str, float]

    def limit(self, name: str) -> float:
        """The standard error beyond which coefficient ``name`` is not determined (see the module)."""
        term = _term(name)
        if term == "time_offset":
            return TIME_OFFSET_SE_S
        if term == "lever_arm":
            return LEVER_ARM_SE_M
        return self.spread[f"{_sensor(name)}.{term}"]

    def largest(self, name: str) -> float:
        """The largest magnitude coefficient ``name`` may have."""
        term = _term(name)
        if term == "time_offset":
            return TIME_OFFSET_BOUND_S
        if term == "lever_arm":
            return LEVER_ARM_BOUND_M
        return self.bound[f"{_sensor(name)}.{term}"]


def class_bounds(grade: str = DEFAULT_GRADE) -> ClassBounds:
    """The bounds of ``grade`` (a name of :data:`sins.imu.spec.GRADES`).

    Raises
    ------
    SinsInputError
        an unknown grade, naming the known ones.
    """
    if grade not in GRADES:
        raise SinsInputError(f"unknown grade {grade!r} (known: {', '.join(GRADES)})")
    g = GRADES[grade]
    spread = {
        _key(GYRO, BIAS): math.hypot(g.gyro_bias_dph, g.gyro_turn_on_dph) * DEG_PER_H,
        _key(GYRO, "scale"): g.gyro_scale_ppm * 1e-6,
        _key(GYRO, "misalignment"): g.gyro_misalignment_ppm * 1e-6,
        _key(GYRO, G_SENSITIVITY): g.g_sensitivity_dph_per_g * DEG_PER_H / G0,
        _key(ACCEL, BIAS): math.hypot(g.accel_bias_mg, g.accel_turn_on_mg) * MG,
        _key(ACCEL, "scale"): g.accel_scale_ppm * 1e-6,
        _key(ACCEL, "misalignment"): g.accel_misalignment_ppm * 1e-6,
    }
    bound = {k: BOUND_SIGMAS * v for k, v in spread.items()}
    for sensor, value in WIDER_BIASES.get(grade, {}).items():
        bound[_key(sensor, BIAS)] = max(bound[_key(sensor, BIAS)], value)
    return ClassBounds(grade, spread, bound)


# --------------------------------------------------------------------------- the interval fit's columns


def gyro_names(g_sensitivity: bool, time_offset: bool) -> tuple[str, ...]:
    """The gyro's columns in the interval fit's order: B0, B and K row-major, the time offset."""
    names = [*bias_names(GYRO), *_matrix(GYRO, "scale")]
    if g_sensitivity:
        names += _g_sensitivity_names()
    return tuple(names + ([_key(GYRO, "time_offset")] if time_offset else []))


def accel_names(time_offset: bool) -> tuple[str, ...]:
    """The accelerometer's columns in the interval fit's order: A0, A row-major, the lever arm, the
    time offset."""
    names = [*bias_names(ACCEL), *_matrix(ACCEL, "scale")]
    names += [_key(ACCEL, "lever_arm", a) for a in _AXES]
    return tuple(names + ([_key(ACCEL, "time_offset")] if time_offset else []))


def bias_names(sensor: str) -> tuple[str, ...]:
    """A sensor's three biases."""
    return tuple(_key(sensor, BIAS, a) for a in _AXES)


def _g_sensitivity_names() -> list[str]:
    return [_key(GYRO, G_SENSITIVITY, f"{r}←{c}") for r in _AXES for c in _AXES]


def _key(sensor: str, term: str, axis: str = "") -> str:
    """A coefficient's name, ``SENSOR.TERM.AXIS`` (or a term's, ``SENSOR.TERM``). Built from its parts:
    the seed model's terms share their words with the IMU effects' names, which only the effect
    registry spells out (tests/test_vocabulary.py)."""
    return ".".join(p for p in (sensor, term, axis) if p)


def _matrix(sensor: str, _: str) -> list[str]:
    """A 3 × 3 matrix's coefficients, row-major: the diagonal its scale factors, the rest misalignments
    (``x←y``: the x channel's response to the y input)."""
    return [
        f"{sensor}.scale.{r}" if r == c else f"{sensor}.misalignment.{r}←{c}" for r in _AXES for c in _AXES
    ]


def _sensor(name: str) -> str:
    return name.split(".")[0]


def _term(name: str) -> str:
    return name.split(".")[1]


# --------------------------------------------------------------------------- what the data determine


@dataclass
class Holds:
    """The coefficients held at zero in a fit, by name, with the reason, and the class whose bounds
    judged them (:func:`assess` fills it; the interval fit holds them)."""

    bounds: ClassBounds
    reasons: dict[str, str] = field(default_factory=dict)

    def free(self, names: tuple[str, ...]) -> NDArray[np.bool_]:
        """Which of ``names`` are fitted (not held)."""
        return np.array([n not in self.reasons for n in names], dtype=bool)


def assess(rec: ReferencedRecording, interval_s: float, bounds: ClassBounds) -> Holds:
    """The coefficients of the interval fit (:func:`gyro_names` with the g-sensitivity and the time
    offset, :func:`accel_names` with the time offset) that ``rec`` does not determine for a unit of
    ``bounds``' class, each with its reason (see the module docstring).

    Raises
    ------
    ValueError
        as :func:`sins.compensation.intervals.choose_intervals` (too few intervals).
    """
    iv = choose_intervals(rec, interval_s)
    holds = Holds(bounds)
    for names, (x, y) in (
        (gyro_names(True, True), _gyro_design(rec, iv)),
        (accel_names(True), _accel_design(rec, iv)),
    ):
        free, reasons = determined(x, y, names, bounds)
        holds.reasons.update({n: reasons[n] for n, kept in zip(names, free, strict=True) if not kept})
    return holds


def assess_several(recs: list[ReferencedRecording], interval_s: float, bounds: ClassBounds) -> Holds:
    """:func:`assess` for a fit on several recordings of one unit: what their intervals together
    determine of the shared coefficients (each recording's biases are its own and always fitted).

    Raises
    ------
    ValueError
        as :func:`sins.compensation.intervals.choose_intervals` (too few intervals in one).
    """
    holds = Holds(bounds)
    ivs = [choose_intervals(rec, interval_s) for rec in recs]
    for names, design in (
        (gyro_names(True, True), _gyro_design),
        (accel_names(True), _accel_design),
    ):
        parts = [design(rec, iv) for rec, iv in zip(recs, ivs, strict=True)]
        x, y = np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
        free, reasons = determined(x, y, names, bounds)
        holds.reasons.update({n: reasons[n] for n, kept in zip(names, free, strict=True)
                              if not kept and _term(n) != BIAS})  # fmt: skip
    return holds


def _ends(rec: ReferencedRecording, iv: Intervals) -> tuple[Array, Array, Array, Array]:
    """The reference's body rate (body axes) and specific force (NED) at each interval's two ends, from
    its attitude and velocity over ±a tenth of the interval (what a time offset and a lever arm are read
    from; the reference's noise in them is the window's, not a frame's)."""
    t, ref = rec.imu.t, rec.reference
    span = t[iv.stop] - t[iv.start]
    half = np.maximum(0.1 * span, 1e-6)
    out = []
    for at in (t[iv.start], t[iv.stop]):
        lo = np.clip(at - half, ref.t[0], ref.t[-1])
        hi = np.clip(at + half, ref.t[0], ref.t[-1])
        width = np.maximum(hi - lo, 1e-9)[:, None]
        a, b = ref.interpolate(lo), ref.interpolate(hi)
        turn = rotation.quat_multiply(rotation.quat_conjugate(a.q_nb), b.q_nb)
        rate_b = rotation.rotvec_from_quat(turn) / width
        g = np.asarray(earth.normal_gravity(a.lat, a.h), dtype=float)
        force_n = (b.v_n - a.v_n) / width - np.c_[np.zeros((len(g), 2)), g]
        out += [rate_b, force_n]
    return out[0], out[1], out[2], out[3]


def _gyro_design(rec: ReferencedRecording, iv: Intervals) -> tuple[Array, Array]:
    """The gyro's columns (B0, B, K, τ) from the reference, first order in each interval's body axes,
    and the intervals' turn left by the raw readings (what the least squares would fit)."""
    imu, dt = rec.imu, np.diff(rec.imu.t)
    span = iv.seconds(dt)
    r_ref = iv.body_turn()
    theta = rotation.rotvec_from_quat(rotation.quat_from_dcm(r_ref))
    force_b = np.einsum("kji,kj->ki", dcm(iv.q_start), expected_dv(iv, dt))
    rate_a, _, rate_b, _ = _ends(rec, iv)
    x = np.zeros((len(iv), 3, 22))
    x[:, :, :3] = span[:, None, None] * np.eye(3)
    for r in range(3):
        x[:, r, 3 + 3 * r : 6 + 3 * r] = theta
        x[:, r, 12 + 3 * r : 15 + 3 * r] = force_b
    x[:, :, 21] = rate_b - rate_a
    q = attitude.propagate_increments(imu.dtheta_b, np.array([0.0, 0.0, 0.0, 1.0]))
    rot = dcm(q)
    r_meas = np.einsum("kji,kjl->kil", rot[iv.start], rot[iv.stop])
    y = rotation.rotvec_from_quat(rotation.quat_from_dcm(np.einsum("kji,kjl->kil", r_meas, r_ref)))
    return x, y


def _accel_design(rec: ReferencedRecording, iv: Intervals) -> tuple[Array, Array]:
    """The accelerometer's columns (A0, A, lever arm, τ) from the reference, first order in NED, and the
    intervals' velocity change left by the raw readings turned by the reference's attitude."""
    imu, dt = rec.imu, np.diff(rec.imu.t)
    span = iv.seconds(dt)
    c_a, c_b = dcm(iv.q_start), dcm(iv.q_stop)
    c_mid = 0.5 * (c_a + c_b)
    expected = expected_dv(iv, dt)
    force_b = np.einsum("kji,kj->ki", c_mid, expected)
    rate_a, force_a, rate_b, force_b_end = _ends(rec, iv)
    x = np.zeros((len(iv), 3, 16))
    x[:, :, :3] = c_mid * span[:, None, None]
    for r in range(3):
        x[:, :, 3 + 3 * r : 6 + 3 * r] = c_mid[:, :, r : r + 1] * force_b[:, None, :]
    x[:, :, 12:15] = np.einsum("kab,kbc->kac", c_b, rotation.skew(rate_b)) - np.einsum(
        "kab,kbc->kac", c_a, rotation.skew(rate_a)
    )
    x[:, :, 15] = force_b_end - force_a
    q = attitude.propagate_increments(imu.dtheta_b, np.array([0.0, 0.0, 0.0, 1.0]))
    rot = dcm(q)
    y = np.empty((len(iv), 3))
    for k, (a, b) in enumerate(zip(iv.start, iv.stop, strict=True)):
        c_nb = c_a[k] @ rot[a].T @ (0.5 * (rot[a:b] + rot[a + 1 : b + 1]))
        y[k] = expected[k] - np.einsum("jab,jb->a", c_nb, imu.dv_b[a:b])
    return x, y


def determined(
    x: Array, y: Array, names: tuple[str, ...], bounds: ClassBounds
) -> tuple[NDArray[np.bool_], dict[str, str]]:
    """Which columns of the linearised least squares ``y ≈ x θ`` the data determine (see the module).

    Parameters
    ----------
    x : (k, 3, p) or (m, p) the design, in the coefficients' SI units
    y : (k, 3) or (m,) the observations
    names : the p coefficients' names (:func:`gyro_names`, :func:`accel_names`, :func:`bias_names`)
    bounds : the class whose spreads are the limits

    Returns
    -------
    the columns kept (p,), and the reason of each held one by name
    """
    p = x.shape[-1]
    a, b = x.reshape(-1, p), y.reshape(-1)
    limits = np.array([bounds.limit(n) for n in names])
    order = np.array([_ORDER[_term(n)] for n in names])
    sigma2 = _noise(a, b)
    free = np.ones(p, dtype=bool)
    reasons: dict[str, str] = {}
    while free.any():
        cols = np.flatnonzero(free)
        scale = np.sqrt(np.mean(a[:, cols] ** 2, axis=0))
        scale = np.where(scale > 0.0, scale, 1.0)
        _, s, vt = np.linalg.svd(a[:, cols] / scale, full_matrices=False)
        if s[0] == 0.0 or s[-1] < CONDITION * s[0]:
            loading = np.abs(vt[-1])
            involved = loading > 0.1 * loading.max()
            pick = _worst(order[cols], loading, involved)
            j = int(cols[pick])
            others = [names[int(c)] for c in cols[involved] if c != j]
            reasons[names[j]] = (
                f"confounded with {_listed(others)} (the recording cannot tell them apart)"
                if others and s[0] > 0.0
                else "not excited at all by the recording"
            )
            free[j] = False
            continue
        se = np.sqrt(sigma2 * np.sum((vt.T / s) ** 2, axis=1)) / scale
        ratio = se / limits[cols]
        bad = ~(ratio <= 1.0)
        if not bad.any():
            break
        pick = _worst(order[cols], np.where(np.isfinite(ratio), ratio, np.inf), bad)
        j = int(cols[pick])
        reasons[names[j]] = _why(a, j, cols, se[pick], limits[j], sigma2, names, bounds.grade)
        free[j] = False
    for index in np.flatnonzero(~free):
        reasons.setdefault(names[int(index)], "not determined by the recording")
    return free, reasons


def _noise(a: Array, b: Array) -> float:
    """The observations' noise variance from the least squares on every column (minimum norm)."""
    theta, _, rank, _ = np.linalg.lstsq(a, b, rcond=None)
    dof = len(b) - int(rank)
    if dof <= 0:
        return math.inf
    r = b - a @ theta
    return float(r @ r) / dof


def _worst(order: NDArray[np.int_], badness: Array, among: NDArray[np.bool_]) -> int:
    """Among ``among``, the highest order, then the largest ``badness``: the index to hold."""
    top = order[among].max()
    candidates = among & (order == top)
    return int(np.flatnonzero(candidates)[np.argmax(badness[candidates])])


#: A column whose standard error alone exceeds the spread by this much is not excited at all (at rest, a
#: time offset's column is the rounding of a constant rate's change).
_UNEXCITED = 1e6


def _why(
    a: Array, j: int, cols: NDArray[np.int_], se: float, limit: float, sigma2: float,
    names: tuple[str, ...], grade: str,
) -> str:  # fmt: skip
    """Why column ``j`` is held: too little excitation, or confounded with the column it follows most."""
    column = a[:, j]
    energy = float(column @ column)
    alone = math.sqrt(sigma2 / energy) if energy > 0.0 else math.inf
    beyond = (
        f"its standard error {_shown(names[j], se)} exceeds a {grade} unit's spread {_shown(names[j], limit)}"
    )
    if not alone <= _UNEXCITED * limit:  # the column at its rounding: an error of 1e33 ms says nothing
        return "not excited at all by the recording"
    if not alone <= limit:
        return f"too little excitation: {beyond}"
    others = [int(c) for c in cols if c != j]
    norms = np.linalg.norm(a[:, others], axis=0) * math.sqrt(energy)
    corr = np.abs(column @ a[:, others]) / np.where(norms > 0.0, norms, 1.0)
    partner = names[others[int(np.argmax(corr))]] if others else "the others"
    return f"confounded with {_pretty(partner)}: {beyond}"


def _listed(names: list[str]) -> str:
    shown = [_pretty(n) for n in names[:3]]
    return ", ".join(shown) + (f" and {len(names) - 3} more" if len(names) > 3 else "")


def _pretty(name: str) -> str:
    """``gyro.scale.x`` as ``gyro scale x``."""
    return name.replace(".", " ").replace("_", " ")


#: Display units by term: factor from SI and the unit's name.
_UNITS = {
    _key(GYRO, BIAS): (DEG_PER_H, "°/h"), _key(ACCEL, BIAS): (1e-6 * G0, "µg"), "scale": (1e-6, "ppm"),
    "misalignment": (1e-3, "mrad"), "g_sensitivity": (DEG_PER_H / G0, "°/h/g"), "time_offset": (1e-3, "ms"),
    "lever_arm": (1e-3, "mm"),
}  # fmt: skip


def _shown(name: str, value: float) -> str:
    """``value`` (SI) of coefficient ``name`` in its datasheet unit."""
    key = _key(_sensor(name), BIAS) if _term(name) == BIAS else _term(name)
    factor, unit = _UNITS[key]
    return f"{value / factor:.3g} {unit}"


# --------------------------------------------------------------------------- a fitted model judged


@dataclass(frozen=True)
class Review:
    """What :func:`review` found: the class, and the coefficients held at zero with their reasons."""

    grade: str
    held: dict[str, str]

    def lines(self) -> list[str]:
        """One line per reason, naming the coefficients it holds at zero, for reports."""
        by_reason: dict[str, list[str]] = {}
        for name, why in self.held.items():
            by_reason.setdefault(why, []).append(_pretty(name))
        return [f"{', '.join(names)}: {why}" for why, names in by_reason.items()]

    def to_dict(self) -> dict[str, object]:
        """As a model file records it: the class its bounds were checked against, what was held."""
        return {"grade": self.grade, "held": dict(self.held)}


def seed_values(seed: SeedModelFit) -> dict[str, tuple[float, float]]:
    """Every coefficient of a seed model by name: ``(value, standard error)``, SI."""
    out: dict[str, tuple[float, float]] = {}
    for sensor, bias, bias_se, matrix, matrix_se in (
        ("gyro", seed.B0, seed.B0_se, seed.B, seed.B_se),
        ("accel", seed.A0, seed.A0_se, seed.A, seed.A_se),
    ):
        for i, name in enumerate(bias_names(sensor)):
            out[name] = (float(bias[i]), float(bias_se[i]))
        for k, name in enumerate(_matrix(sensor, "")):
            out[name] = (float(matrix.flat[k]), float(matrix_se.flat[k]))
    for k, name in enumerate(_g_sensitivity_names()):
        out[name] = (float(seed.K.flat[k]), float(seed.K_se.flat[k]))
    return out


def loose(values: Mapping[str, tuple[float, float | None]], holds: Holds) -> dict[str, str]:
    """The coefficients a fit kept whose standard error came out beyond the class's spread (the
    prediction of :func:`assess` is first order and leaves out the residuals' correlation), with the
    reason to hold them in the next fit."""
    out = {}
    for name, (_, se) in values.items():
        limit = holds.bounds.limit(name)
        if name not in holds.reasons and se is not None and math.isfinite(se) and se > limit:
            out[name] = (
                f"its standard error in the fit, {_shown(name, se)}, exceeds a {holds.bounds.grade} unit's "
                f"spread {_shown(name, limit)}"
            )
    return out


class _IntervalFit(Protocol):
    """What :func:`fit_determined` reads of an interval fit
    (:class:`~sins.compensation.interval_fit.IntervalFit`)."""

    @property
    def seed(self) -> SeedModelFit: ...
    @property
    def time_offset_s(self) -> float: ...
    @property
    def time_offset_se_s(self) -> float: ...
    @property
    def accel_time_offset_s(self) -> float: ...
    @property
    def accel_time_offset_se_s(self) -> float: ...
    @property
    def lever_arm_m(self) -> Array: ...


#: Fits at most, when a coefficient kept comes out less determined than predicted and is held.
REFITS = 3


def fit_determined(
    fit: Callable[[Holds], _F], rec: ReferencedRecording, interval_s: float, grade: str, where: str,
    *, biases_only: bool = False,
) -> tuple[_F, Review]:  # fmt: skip
    """``fit(holds)`` (an interval fit) with the coefficients ``rec`` does not determine for a unit of
    ``grade`` held (:func:`assess`), made again holding any kept one that came out less determined than
    predicted (:func:`loose`, at most :data:`REFITS` fits), then judged (:func:`review`).

    Raises
    ------
    SinsInputError
        as :func:`review`, naming ``where``.
    """
    holds = assess(rec, interval_s, class_bounds(grade))
    for _ in range(REFITS):
        fitted = fit(holds)
        values = interval_values(fitted, biases_only)
        more = loose(values, holds)
        if not more:
            break
        holds.reasons.update(more)
    return fitted, review(values, holds.bounds, where, holds.reasons)


def interval_values(fit: _IntervalFit, biases_only: bool = False) -> dict[str, tuple[float, float | None]]:
    """An interval fit's coefficients by name: the seed model's, the time offsets and the lever arm
    (whose standard error the fit does not give: None); with ``biases_only``, the biases alone."""
    values: dict[str, tuple[float, float | None]] = dict(seed_values(fit.seed))
    if biases_only:
        return {k: v for k, v in values.items() if _term(k) == "bias"}
    values[_key(GYRO, "time_offset")] = (fit.time_offset_s, fit.time_offset_se_s)
    values[_key(ACCEL, "time_offset")] = (fit.accel_time_offset_s, fit.accel_time_offset_se_s)
    for axis, arm in zip(_AXES, fit.lever_arm_m, strict=True):
        values[_key(ACCEL, "lever_arm", axis)] = (float(arm), None)
    return values


def seed_values_of_model(model: ImuModel) -> dict[str, float]:
    """A simulated unit's own seed-model coefficients by name (SI): the affine terms of its effects
    (bias, scale and misalignment, g-sensitivity), what a fit of it should find."""
    terms = {s: [np.zeros(3), np.zeros((3, 3)), np.zeros((3, 3))] for s in ("gyro", "accel")}
    for sensor in terms:
        for effect in model.effects_of(sensor):
            if getattr(effect, "affine", False):
                for total, part in zip(terms[sensor], effect.affine_terms(), strict=True):
                    total += part
    g0, g, _ = terms["gyro"]
    a0, a, _ = terms["accel"]
    k = terms["gyro"][2]
    seed = SeedModelFit(
        B0=g0, B=g, K=k, A0=a0, A=a, B0_se=g0, B_se=g, K_se=k, A0_se=a0, A_se=a, residual_rms=np.zeros(6)
    )
    return {name: value for name, (value, _) in seed_values(seed).items()}


def review(
    values: Mapping[str, tuple[float, float | None]],
    bounds: ClassBounds,
    where: str,
    held: dict[str, str] | None = None,
) -> Review:
    """Judge a fitted model before it is saved: a coefficient ``held`` is zero; every other one has a
    finite value within its class's bound and a finite standard error within the class's spread (a
    standard error of None: not known, the value alone is judged; NaN beside a value of zero: not part
    of this model, a g-sensitivity left out, say).

    Raises
    ------
    SinsInputError
        naming ``where``, the coefficient, its value ± standard error and the bound it breaks.
    """
    held = dict(held or {})
    for name, (value, se) in values.items():
        if name in held:
            if value != 0.0:
                raise SinsInputError(
                    f"{where}: {_pretty(name)} was held at zero and then moved to {_shown(name, value)}: the "
                    "fit is unstable on this recording"
                )
            continue
        if se is not None and math.isnan(se) and value == 0.0:
            continue
        _judge(name, value, se, bounds, where)
    return Review(bounds.grade, held)


def beyond_spread(values: Mapping[str, tuple[float, float | None]], bounds: ClassBounds) -> list[str]:
    """The coefficients of ``values`` (``name: (value, standard error or None)``, SI) whose standard error
    exceeds the class's spread, each as ``NAME ± SE`` in its datasheet unit: what :func:`review`
    refuses in a model, said of a recording's own biases, which are not the model's."""
    return [
        f"{_pretty(n)} ± {_shown(n, se)} against {_shown(n, bounds.limit(n))}"
        for n, (_, se) in values.items()
        if se is not None and se > bounds.limit(n)
    ]


def _judge(name: str, value: float, se: float | None, bounds: ClassBounds, where: str) -> None:
    """Refuse one coefficient that is not finite, not determined or beyond the class's bound."""
    if not (math.isfinite(value) and (se is None or math.isfinite(se))):
        raise SinsInputError(
            f"{where}: {_pretty(name)} came out {_shown(name, value)}"
            + ("" if se is None else f" with a standard error of {_shown(name, se)}")
            + ": the recording does not determine it"
        )
    text = f"{_pretty(name)} came out {_shown(name, value)}" + (
        "" if se is None else f" ± {_shown(name, se)}"
    )
    if se is not None and se > bounds.limit(name):
        raise SinsInputError(
            f"{where}: {text}: not determined (a {bounds.grade} unit's spread is "
            f"{_shown(name, bounds.limit(name))}); the recording does not excite it enough"
        )
    if abs(value) > bounds.largest(name):
        raise SinsInputError(
            f"{where}: {text}, beyond what a {bounds.grade} unit has ({_shown(name, bounds.largest(name))}); "
            "check the recording's units, axes and reference, or give the unit's --grade"
        )


__all__ = [
    "ACCEL",
    "BIAS",
    "BOUND_SIGMAS",
    "CONDITION",
    "DEFAULT_GRADE",
    "GYRO",
    "G_SENSITIVITY",
    "LEVER_ARM_BOUND_M",
    "LEVER_ARM_SE_M",
    "REFITS",
    "TIME_OFFSET_BOUND_S",
    "TIME_OFFSET_SE_S",
    "WIDER_BIASES",
    "ClassBounds",
    "Holds",
    "Review",
    "accel_names",
    "assess",
    "assess_several",
    "beyond_spread",
    "bias_names",
    "class_bounds",
    "determined",
    "fit_determined",
    "gyro_names",
    "interval_values",
    "loose",
    "review",
    "seed_values",
    "seed_values_of_model",
]
