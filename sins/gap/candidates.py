"""The gap diagnosis's candidates: every effect of the vocabulary beyond the baseline, and their columns.

The model of a channel's reading error ``e = reading − reference`` starts as the baseline (the seed
model's bias, scale/misalignment and g-sensitivity rows, :func:`baseline_columns`, plus white noise).
Every effect not in the model whose class declares a candidate kind (:attr:`sins.imu.Effect.candidate`)
is a candidate (:data:`CANDIDATES`, read from the vocabulary when asked, so an effect registered later
is offered too), of one of four kinds (how the channel model holds and fits each:
:mod:`sins.gap.channel`):

- *regressors*: columns added to the channel's least-squares fit, the effect's own
  (:meth:`sins.imu.Effect.columns`), built from the reference inputs of every row
  (:class:`ReferenceInputs`; :func:`regressors_of` gives them);
- *delay*: the reading is the reference at ``t − τ`` (:meth:`ReferenceInputs.lag`);
- *process*: a random bias under the white noise; a sensor's model holds one at most
  (:func:`processes`);
- *output* maps: a map of the reading; one at most (:func:`outputs`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from functools import partial

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PPoly

from sins.core.series import CalibrationData
from sins.imu import vocabulary
from sins.imu.numerics import hermite_slopes

Array = NDArray[np.float64]


def processes() -> tuple[str, ...]:
    """The random-bias candidates' kinds (``process``): a sensor's model has at most one."""
    return tuple(t.kind for t in vocabulary.effect_types() if t.candidate == "process")


def outputs() -> tuple[str, ...]:
    """The output-map candidates' kinds (``output``): a sensor's model has at most one."""
    return tuple(t.kind for t in vocabulary.effect_types() if t.candidate == "output")


@dataclass(frozen=True)
class Candidate:
    """One library effect as the diagnosis sees it: its name, its channels and its kind."""

    name: str
    sensor: str
    kind: str  # "regressors" | "delay" | "process" | "output"
    columns: Callable[[ReferenceInputs, int], Array] | None = None  # (n, k) extra regressors of axis i


#: Rows a long recording's row-by-row work takes at a time (a chunk of six float columns is 3 MB).
CHUNK_ROWS = 1 << 16


def spans(n: int, size: int | None = None) -> list[tuple[int, int]]:
    """Rows ``0 … n`` in consecutive ``(start, stop)`` chunks of at most ``size`` rows
    (:data:`CHUNK_ROWS`, read when called)."""
    size = size or CHUNK_ROWS
    return [(lo, min(lo + size, n)) for lo in range(0, n, size)]


@dataclass(frozen=True)
class Kinks:
    """The rows of one reference axis where a cubic Hermite curve through the rows leaves and enters
    with one-sided slopes (:func:`sins.imu.numerics.hermite_slopes`), and those slopes: everywhere else
    both are the central ones. A rig's reference has a few, at the corners of its rate profile."""

    rows: NDArray[np.int64]
    right: Array  # the slope the curve leaves each row with
    left: Array  # the slope the curve enters each row with


@dataclass(frozen=True, eq=False)
class ReferenceInputs:
    """The reference inputs of every row, and what the regressors and the delay are built from.

    Attributes
    ----------
    t : (n,) s
    omega_ib_b, f_ib_b : (n, 3) the reference angular rate (rad/s) and specific force (m/s²)
    temp : (n,) °C, or None
    step_s : the median sampling step, s
    kinks : per sensor and axis, the rows where the cubic Hermite curve of its reference through
        the rows takes one-sided slopes (for :meth:`lag`; see :func:`kinked_hermite`)
    temp_mean : the mean temperature of the whole recording, °C (None without one): the
        temperature columns' origin, the same in every chunk of rows (:meth:`rows`)
    start, whole : for a chunk of rows (:meth:`rows`), its first row's index in the whole
        recording and the whole recording's inputs (None: these are the whole recording's)

    The rates of change (:meth:`rate`, :attr:`omega_dot_b`) are computed when asked for, from the
    whole recording's rows: held, they would be six more columns as long as the recording.
    """

    t: Array
    omega_ib_b: Array
    f_ib_b: Array
    temp: Array | None
    step_s: float
    kinks: dict[tuple[str, int], Kinks]
    temp_mean: float | None = None
    start: int = 0
    whole: ReferenceInputs | None = None

    def of(self, sensor: str) -> Array:
        """The reference ``sensor`` measures: ``omega`` for "gyro", ``f`` for "accel"."""
        return self.omega_ib_b if sensor == "gyro" else self.f_ib_b

    def rate(self, sensor: str, axis: int | None = None) -> Array:
        """(n, 3) the rate of change of ``sensor``'s reference, or (n,) of one ``axis``
        (:func:`central_differences` over the whole recording: a chunk's first and last rows take
        their neighbours outside it)."""
        whole = self.whole or self
        lo, n = self.start, len(whole.t)
        hi = lo + len(self.t)
        a, b = max(lo - 1, 0), min(hi + 1, n)
        u = whole.of(sensor)[a:b] if axis is None else whole.of(sensor)[a:b, axis : axis + 1]
        if n < 3:
            out = np.zeros_like(u[lo - a : hi - a])
        else:
            out = central_differences(u, whole.t[a:b])[lo - a : hi - a]
        return out if axis is None else out[:, 0]

    @property
    def temp_offset(self) -> Array | None:
        """(n,) the temperature about the whole recording's mean, °C (None without one): the
        temperature columns' origin, the same in every chunk of rows."""
        return None if self.temp is None or self.temp_mean is None else self.temp - self.temp_mean

    @property
    def omega_dot_b(self) -> Array:
        """(n, 3) the reference's angular acceleration, rad/s² (:meth:`rate` of the gyro's)."""
        return self.rate("gyro")

    def rows(self, start: int, stop: int) -> ReferenceInputs:
        """Rows ``start … stop`` (views, no copies): what the regressors of a chunk are built from.
        Its ``kinks`` are the whole recording's, and :meth:`lag` is for the whole recording only."""
        part = slice(start, stop)
        return dataclasses.replace(
            self,
            t=self.t[part],
            omega_ib_b=self.omega_ib_b[part],
            f_ib_b=self.f_ib_b[part],
            temp=None if self.temp is None else self.temp[part],
            start=self.start + start,
            whole=self.whole or self,
        )

    def lag(self, sensor: str, axis: int, delay_s: float) -> Array:
        """``u(t − τ) − u(t)`` of the reference ``u`` of one axis at every row: cubic Hermite between
        the rows (:func:`kinked_hermite`), held at the ends; made a chunk of rows at a time
        (:meth:`lag_rows`). A search over τ builds the curve once (:meth:`curve`) and asks it each
        lag: the same values to the last bit."""
        n = len(self.t)
        out = np.empty(n)
        for lo, hi in spans(n):
            out[lo:hi] = self.lag_rows(sensor, axis, delay_s, lo, hi)
        return out

    def lag_rows(self, sensor: str, axis: int | None, delay_s: float, start: int, stop: int) -> Array:
        """:meth:`lag` of rows ``start … stop`` alone, (m,) of one ``axis`` or (m, 3) of every axis
        (None: the rows' intervals found once for the three), from the curve's pieces those rows
        reach back into (built for them: the whole curve is four floats a row)."""
        assert self.whole is None, "the lag of the whole recording's rows"
        t = self.t
        u = self.of(sensor) if axis is None else self.of(sensor)[:, axis : axis + 1]
        if len(t) < 2:
            out = np.zeros((stop - start, u.shape[1]))
        else:
            when, i = _reached(t, delay_s, self.step_s, start, stop)
            first = int(i.min()) if len(i) else 0
            last = int(i.max()) + 1 if len(i) else 0
            coef = self._coefficients(sensor, axis, first, last)
            out = _hermite_values(coef, i - first, (when - t[i])[:, None]) - u[start:stop]
        return out if axis is None else out[:, 0]

    def curve(self, sensor: str, axis: int) -> HermiteCurve:
        """The cubic Hermite curve of one axis of ``sensor``'s reference through the rows
        (:func:`kinked_hermite`'s: the same coefficients to the last bit), built a chunk of rows at a
        time (each row's slope the whole recording's :meth:`rate`: its neighbours either side are
        taken in)."""
        assert self.whole is None, "the curve of the whole recording's rows"
        n = len(self.t)
        coef = np.empty((4, max(n - 1, 0)))
        for lo, hi in spans(n - 1):
            coef[:, lo:hi] = self._coefficients(sensor, axis, lo, hi)[:, :, 0]
        return HermiteCurve(self.t, self.of(sensor)[:, axis], coef, self.step_s)

    def _coefficients(self, sensor: str, axis: int | None, start: int, stop: int) -> Array:
        """(4, stop − start, k) the curve's coefficients of the intervals ``start … stop − 1`` of one
        ``axis`` (k = 1) or of every axis (None, k = 3); each interval's alone: the same bits whichever
        intervals and axes are built together."""
        axes = range(3) if axis is None else [axis]
        u = self.of(sensor) if axis is None else self.of(sensor)[:, axis : axis + 1]
        if stop <= start:
            return np.empty((4, 0, len(axes)))
        piece = slice(start, stop + 1)  # the intervals and the rows that bound them
        right = self.rows(start, stop + 1).rate(sensor, axis).reshape(stop + 1 - start, -1)
        left = right.copy()
        for j, a in enumerate(axes):
            kinks = self.kinks[sensor, a]
            at = slice(*np.searchsorted(kinks.rows, [start, stop + 1]))
            right[kinks.rows[at] - start, j], left[kinks.rows[at] - start, j] = (
                kinks.right[at],
                kinks.left[at],
            )
        return _hermite_coefficients(self.t[piece], u[piece], right, left)


@dataclass(frozen=True, eq=False)
class DelayedInputs:
    """The reference inputs at ``t − τ`` (the rate and the force of every axis along their Hermite
    curves, :meth:`ReferenceInputs.lag`), made a chunk of rows at a time when asked for (:meth:`rows`)
    or whole for the passes of one fit (:meth:`whole`): a model that keeps them keeps only how to make
    them (whole, they were two more (n, 3) arrays per delayed channel, 171 MB each at 3.57 M rows).
    Their rates of change are those of the delayed inputs themselves. Either way the same values to
    the last bit."""

    x: ReferenceInputs
    delay_s: float

    @property
    def t(self) -> Array:
        """(n,) s, the rows' times (the undelayed reference's)."""
        return self.x.t

    def whole(self) -> ReferenceInputs:
        """The delayed inputs of every row, made a chunk at a time (the curve's pieces of one chunk at
        a time): for the many passes over the rows of one fit, which would make them again each pass."""
        n = len(self.x.t)
        omega, force = np.empty((n, 3)), np.empty((n, 3))
        for lo, hi in spans(n):
            omega[lo:hi], force[lo:hi] = self._made(lo, hi)
        return dataclasses.replace(self.x, omega_ib_b=omega, f_ib_b=force)

    def rows(self, start: int, stop: int) -> ReferenceInputs:
        """Rows ``start … stop`` of the delayed inputs, made with two rows either side (a row's rate of
        change takes its neighbours, and a recording of three rows or more gives three here)."""
        a, b = max(start - 2, 0), min(stop + 2, len(self.x.t))
        omega, force = self._made(a, b)
        near = dataclasses.replace(self.x.rows(a, b), omega_ib_b=omega, f_ib_b=force, start=0, whole=None)
        return near.rows(start - a, stop - a)

    def _made(self, start: int, stop: int) -> tuple[Array, Array]:
        """The rate and the force at ``t − τ`` of rows ``start … stop``, (m, 3) each: the reference plus
        its lag (:meth:`ReferenceInputs.lag_rows`)."""
        x, tau = self.x, self.delay_s
        omega = x.omega_ib_b[start:stop] + x.lag_rows("gyro", None, tau, start, stop)
        force = x.f_ib_b[start:stop] + x.lag_rows("accel", None, tau, start, stop)
        return omega, force


@dataclass(frozen=True, eq=False)
class HermiteCurve:
    """A cubic Hermite curve through the rows ``(t, u)`` in power form, ``coef`` (4, n − 1) as scipy's
    ``PPoly`` holds it (highest power first): a reference axis's (:meth:`ReferenceInputs.curve`).
    Held whole, four floats a row of one axis (23 MB for an hour at 200 Hz; ``t`` and ``u`` are views
    of the inputs); evaluated a chunk of rows at a time."""

    t: Array
    u: Array
    coef: Array
    step_s: float

    def lag(self, delay_s: float) -> Array:
        """``u(t − τ) − u(t)`` at every row, the curve held at its ends: ``PPoly``'s values to the last
        bit (its interval for each time and its sum of powers, in its order), without its search of
        the breakpoints for each time (a row's interval is found from its neighbour's by the delay in
        rows, then stepped to the right one)."""
        t, n = self.t, len(self.t)
        out = np.empty(n)
        if n < 2:
            out[:] = 0.0
            return out
        for lo, hi in spans(n):
            when, i = _reached(t, delay_s, self.step_s, lo, hi)
            out[lo:hi] = _hermite_values(self.coef, i, when - t[i]) - self.u[lo:hi]
        return out


def _reached(
    t: Array, delay_s: float, step_s: float, start: int, stop: int
) -> tuple[Array, NDArray[np.intp]]:
    """The times ``t − τ`` of rows ``start … stop`` (held within ``t[0] … t[-1]``) and the interval
    of the curve each falls in (a row's found from its own by the delay in rows where the rows are
    evenly spaced, then stepped to the right one: ``PPoly``'s search without its cost)."""
    when = np.clip(t[start:stop] - delay_s, t[0], t[-1])
    shift = math.ceil(delay_s / step_s)
    return when, _intervals(t, when, np.arange(start, stop) - shift)


def _hermite_values(c: Array, i: NDArray[np.intp], s: Array) -> Array:
    """The power form ``c`` of intervals ``i`` at ``s`` past each interval's start: ``PPoly``'s sum of
    powers, in its order (the same bits)."""
    value = c[3, i] + c[2, i] * s
    s2 = s * s
    value += c[1, i] * s2
    value += c[0, i] * (s2 * s)
    return value


def _intervals(t: Array, when: Array, guess: NDArray[np.intp]) -> NDArray[np.intp]:
    """For each time of ``when`` (within ``t[0] … t[-1]``), the interval ``i`` of the increasing
    breakpoints ``t`` with ``t[i] ≤ when < t[i + 1]`` (the last for ``t[-1]``): ``PPoly``'s, and
    ``searchsorted``'s less one. Stepped from ``guess`` while a few steps settle it (sampling
    jitter), else searched."""
    last = len(t) - 2
    i = np.clip(guess, 0, last)
    for _ in range(4):
        up = (i < last) & (t[np.minimum(i + 1, last + 1)] <= when)
        down = (i > 0) & (t[i] > when)
        if not (up.any() or down.any()):
            return i
        i = i + up - down
    return np.clip(np.searchsorted(t, when, side="right") - 1, 0, last)


def central_differences(a: Array, t: Array) -> Array:
    """``d a / d t`` of an (n, k) series at unevenly spaced times ``t``: the second-order central
    differences inside and one-sided ones at the ends, ``numpy.gradient``'s formulas for uneven
    spacing written out (it takes others where ``t`` happens to be even, which would make a chunk's
    values depend on its neighbours' spacing). Needs two rows at least."""
    dx = np.diff(t)[:, None]
    out = np.empty_like(a)
    if len(t) > 2:
        dx1, dx2 = dx[:-1], dx[1:]
        first = -dx2 / (dx1 * (dx1 + dx2))
        middle = (dx2 - dx1) / (dx1 * dx2)
        last = dx1 / (dx2 * (dx1 + dx2))
        out[1:-1] = first * a[:-2] + middle * a[1:-1] + last * a[2:]
    out[0] = (a[1] - a[0]) / dx[0]
    out[-1] = (a[-1] - a[-2]) / dx[-1]
    return out


def _kinks(x: ReferenceInputs, sensor: str) -> list[Kinks]:
    """The kinks of each axis of ``sensor``'s reference: :func:`sins.imu.numerics.hermite_slopes` a
    chunk at a time, each with three rows either side (its stencils reach two), so each row's
    slopes are the whole recording's."""
    found: list[list[tuple[NDArray[np.int64], Array, Array]]] = [[], [], []]
    n = len(x.t)
    for lo, hi in spans(n):
        a, b = max(lo - 3, 0), min(hi + 3, n)
        part = x.rows(a, b)
        central = part.rate(sensor)
        right, left = hermite_slopes(part.t, part.of(sensor), central)
        own = slice(lo - a, hi - a)
        right, left, base = right[own], left[own], central[own]
        for j in range(3):
            rows = np.flatnonzero((right[:, j] != base[:, j]) | (left[:, j] != base[:, j]))
            found[j].append((rows + lo, right[rows, j], left[rows, j]))
    return [Kinks(*(np.concatenate([part[k] for part in parts]) for k in range(3))) for parts in found]


def reference_inputs(data: CalibrationData) -> ReferenceInputs:
    """The reference inputs of every row of ``data``, and the kinks of their Hermite curves."""
    t = data.t
    x = ReferenceInputs(
        t=t,
        omega_ib_b=data.ref_gyro,
        f_ib_b=data.ref_accel,
        temp=data.temp,
        step_s=float(np.median(np.diff(t))),
        kinks={},
        temp_mean=None if data.temp is None else float(np.mean(data.temp)),
    )
    for sensor in ("gyro", "accel"):
        for axis, k in enumerate(_kinks(x, sensor)):
            x.kinks[sensor, axis] = k
    return x


def _hermite_coefficients(t: Array, u: Array, right: Array, left: Array) -> Array:
    """The power-form coefficients (4, n − 1) of the cubic Hermite curve through ``(t, u)`` that
    leaves each row with slope ``right`` and enters it with ``left``, as scipy's
    ``CubicHermiteSpline`` builds them with one slope a row; (4, n − 1, k) for k axes side by side."""
    dx = np.diff(t) if u.ndim == 1 else np.diff(t)[:, None]
    slope = np.diff(u, axis=0) / dx
    tt = (right[:-1] + left[1:] - 2 * slope) / dx
    c = np.empty((4, *slope.shape))
    c[0] = tt / dx
    c[1] = (slope - right[:-1]) / dx - tt
    c[2] = right[:-1]
    c[3] = u[:-1]
    return c


def kinked_hermite(t: Array, u: Array, central: Array) -> PPoly:
    """The cubic Hermite curve through ``(t, u)`` with the slopes of
    :func:`sins.imu.numerics.hermite_slopes` (central, but one-sided on each side of a kink), as a
    scipy ``PPoly``: the curve the simulator delays its rate samples along, so that a delay is
    diagnosed on the curve it was made on. Where no row is a kink it is scipy's
    ``CubicHermiteSpline`` with the central slopes, to the last bit (the same coefficients)."""
    right, left = hermite_slopes(t, u[:, None], central[:, None])
    return PPoly(_hermite_coefficients(t, u, right[:, 0], left[:, 0]), t)


def baseline_columns(sensor: str, omega: Array, f: Array) -> Array:
    """The baseline's regressors of one channel: bias and scale/misalignment, and the gyro's g-sensitivity."""
    u = omega if sensor == "gyro" else f
    base = [np.ones(len(u)), u[:, 0], u[:, 1], u[:, 2]]
    if sensor == "gyro":
        base += [f[:, 0], f[:, 1], f[:, 2]]
    return np.stack(base, axis=1)


def _effect_columns(cls: type[vocabulary.Effect], sensor: str, x: ReferenceInputs, axis: int) -> Array:
    return cls.columns(x, sensor, axis)


def _candidates() -> dict[str, Candidate]:
    """Every effect of the vocabulary whose class declares a candidate kind, in the vocabulary's order."""
    out = {}
    for name, cls in vocabulary.effects_where(lambda t: t.candidate is not None):
        sensor = name.split(".")[0]
        assert cls.candidate is not None
        columns = partial(_effect_columns, cls, sensor) if cls.candidate == "regressors" else None
        out[name] = Candidate(name, sensor, cls.candidate, columns)
    return out


class _Live(Mapping[str, Candidate]):
    """The candidates as the vocabulary has them when asked (an effect registered later included)."""

    def __getitem__(self, name: str) -> Candidate:
        return _candidates()[name]

    def __iter__(self) -> Iterator[str]:
        return iter(_candidates())

    def __len__(self) -> int:
        return len(_candidates())


#: Every candidate the diagnosis knows, by effect name (every effect beyond the baseline whose class
#: declares a candidate kind; the IEEE quantization term's white noise declares none).
CANDIDATES: Mapping[str, Candidate] = _Live()


def regressors_of(name: str, data: CalibrationData) -> list[Array]:
    """The columns the regressor candidate ``name`` adds to each of its sensor's three channels.

    What the diagnosis fits beside the baseline's columns; exposed for oracles that ask what a
    candidate could absorb (``tools/bench_gap.py``).
    """
    cand = CANDIDATES.get(name)
    if cand is None or cand.columns is None:
        raise ValueError(f"{name!r} is not a regressor candidate")
    if vocabulary.effect_class(name).needs_temp and data.temp is None:
        where = data.source or "the recording"
        raise ValueError(f"{name!r} needs a temperature column, and {where} has none")
    x = reference_inputs(data)
    return [cand.columns(x, i) for i in range(3)]


__all__ = [
    "CANDIDATES",
    "CHUNK_ROWS",
    "Candidate",
    "DelayedInputs",
    "HermiteCurve",
    "Kinks",
    "ReferenceInputs",
    "baseline_columns",
    "central_differences",
    "kinked_hermite",
    "outputs",
    "processes",
    "reference_inputs",
    "regressors_of",
    "spans",
]
