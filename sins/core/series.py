"""Time-series containers that cross module boundaries: navigation states and IMU samples.

Frozen dataclasses of plain arrays. A :class:`NavSeries` is both a truth
trajectory and an integrated solution; IMU data come in the two forms of the
package docstring, :class:`ImuIncrements` and :class:`ImuRates`. A rig's
readings beside per-sample reference inputs are :class:`CalibrationData`; a
real unit's readings beside a reference trajectory at the reference's own
epochs are a :class:`ReferencedRecording`.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sins.core import rotation

Array = NDArray[np.float64]

#: A row's reference is steady where its rate moved less than this from the previous row's, rad/s.
STEADY_RATE = 1e-5
#: ... and its specific force less than this, m/s².
STEADY_FORCE = 1e-4
#: Runs of one kind shorter than this join the stretch before them, s.
STRETCH_SHORTEST_S = 0.5
#: Stretches longer than this are cut into equal parts no longer, s.
STRETCH_LONGEST_S = 60.0


def _check_shapes(kind: str, rows: int, **fields: tuple[Array, tuple[int, ...]]) -> None:
    """Refuse fields whose shapes are not the ones given (``rows`` the series' length): ``ValueError``
    naming the container, the field and both shapes. Shapes only, no copy: a container is made for every
    chunk of a stream. A mismatch had been taken and failed later in numpy's words, or gave a figure (a
    NavSeries whose ``q_nb`` had 3 columns)."""
    for name, (value, shape) in fields.items():
        got = np.shape(value)
        if got != shape:
            raise ValueError(f"{kind}.{name}: expected shape {shape} for {rows} rows, got {got}")


def check_increasing(t: Array, what: str) -> None:
    """Refuse times that do not increase from each sample to the next: ``ValueError`` naming ``what`` and
    the first row. Integrating or differentiating over a zero or backward step had given NaN readings, or
    increments of the wrong sign, without a word (the containers check shapes only)."""
    steps = np.diff(np.asarray(t, dtype=float))
    bad = np.flatnonzero(~(steps > 0.0))
    if bad.size:
        k = int(bad[0])
        raise ValueError(f"{what}: t must increase from each sample to the next (row {k + 1}: "
                         f"{float(t[k]):.9g} s, then {float(t[k + 1]):.9g} s)")  # fmt: skip


#: How far from 1 a :class:`NavSeries` quaternion's norm may lie: a thousand times what a reference printed
#: to six or seven digits, or read as single precision, is off by.
QUAT_NORM_TOL = 1e-3


@dataclass(frozen=True)
class NavSeries:
    """Navigation states at ``n`` times.

    Attributes
    ----------
    t : (n,) s
    lat, lon : (n,) rad
    h : (n,) m, height above the WGS84 ellipsoid
    v_n : (n, 3) m/s, NED velocity relative to Earth
    q_nb : (n, 4) attitude quaternion, scalar-last
    """

    t: Array
    lat: Array
    lon: Array
    h: Array
    v_n: Array
    q_nb: Array

    def __post_init__(self) -> None:
        n = len(self.t)
        _check_shapes("NavSeries", n, t=(self.t, (n,)), lat=(self.lat, (n,)), lon=(self.lon, (n,)),
                      h=(self.h, (n,)), v_n=(self.v_n, (n, 3)), q_nb=(self.q_nb, (n, 4)))  # fmt: skip
        # Unit quaternions, to within what a printed or single-precision one keeps (1e-6): twice one had
        # been taken as given, its Euler angles off by 0.86 rad; 1.001 times one made 0.12° of error.
        off = np.abs(np.einsum("ij,ij->i", self.q_nb, self.q_nb) - 1.0) > 2 * QUAT_NORM_TOL
        if off.any():
            k = int(np.argmax(off))
            norm = float(np.linalg.norm(self.q_nb[k]))
            raise ValueError(f"NavSeries.q_nb: row {k} has norm {norm:.9g}, not 1 (a unit quaternion each)")

    def __len__(self) -> int:
        return len(self.t)

    def euler(self) -> tuple[Array, Array, Array]:
        """``(roll, pitch, yaw)`` in radians, each (n,)."""
        return rotation.euler_from_quat(self.q_nb)

    def at(self, index: int | slice | NDArray[np.integer]) -> NavSeries:
        """The states at ``index`` (an int keeps a length-1 series)."""
        if isinstance(index, int | np.integer):
            if not -len(self.t) <= index < len(self.t):  # a row past the end had given an empty series
                raise IndexError(f"NavSeries.at({index}): the series has {len(self.t)} rows")
            index = slice(index, index + 1 if index != -1 else None)
        return NavSeries(
            t=self.t[index],
            lat=self.lat[index],
            lon=self.lon[index],
            h=self.h[index],
            v_n=self.v_n[index],
            q_nb=self.q_nb[index],
        )

    def interpolate(self, t: Array) -> NavSeries:
        """States at times ``t`` (within the span): linear in position and velocity, slerp in attitude."""
        t = np.asarray(t, dtype=float)
        if t.ndim != 1 or len(self.t) < 2:  # a scalar had been an IndexError, one row NaN
            raise ValueError(f"interpolate: t must be 1-D (got {t.ndim}-D) and the series 2 rows or more")
        # By the extremes, not the ends: unsorted times beyond the span had been extrapolated.
        if t.size and (t.min() < self.t[0] - 1e-9 or t.max() > self.t[-1] + 1e-9):
            raise ValueError(f"cannot interpolate at {t.min():.6g}..{t.max():.6g} s outside "
                             f"{self.t[0]:.6g}..{self.t[-1]:.6g} s")  # fmt: skip
        i = np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, len(self.t) - 2)
        w = (t - self.t[i]) / (self.t[i + 1] - self.t[i])
        lerp = lambda a: a[i] + (a[i + 1] - a[i]) * (w if a.ndim == 1 else w[:, None])  # noqa: E731
        return NavSeries(
            t=t,
            lat=lerp(self.lat),
            lon=lerp(self.lon),
            h=lerp(self.h),
            v_n=lerp(self.v_n),
            q_nb=rotation.slerp(self.q_nb[i], self.q_nb[i + 1], w),
        )


@dataclass(frozen=True)
class ImuIncrements:
    """IMU output in increment form (the convention: :mod:`sins`'s docstring, "IMU samples").

    Attributes
    ----------
    t : (n+1,) s, the step boundaries
    dtheta_b : (n, 3) rad, integral of ``omega_ib_b`` over each interval
    dv_b : (n, 3) m/s, integral of ``f_ib_b`` over each interval
    """

    t: Array
    dtheta_b: Array
    dv_b: Array

    def __post_init__(self) -> None:
        n = len(self.dtheta_b)
        edges = (0,) if n == 0 and len(self.t) == 0 else (n + 1,)  # no rows: no boundary needed either
        _check_shapes("ImuIncrements", n, t=(self.t, edges), dtheta_b=(self.dtheta_b, (n, 3)),
                      dv_b=(self.dv_b, (n, 3)))  # fmt: skip

    def __len__(self) -> int:
        return len(self.dtheta_b)

    def mean_rates(self) -> tuple[Array, Array, Array]:
        """``(t, omega_ib_b, f_ib_b)``: each increment divided by its interval, at the interval's
        midpoint (s, rad/s, m/s²)."""
        dt = np.diff(self.t)[:, None]
        mid = 0.5 * (self.t[:-1] + self.t[1:])
        return mid, self.dtheta_b / dt, self.dv_b / dt

    def steps(self, a: int = 0, b: int | None = None) -> ImuIncrements:
        """The intervals ``a`` to ``b`` (exclusive; None: to the end): their increments and the ``b - a + 1``
        times that bound them (``t[a : b + 1]``, where a plain slice of ``t`` alike is one short)."""
        b = len(self) if b is None else b
        return ImuIncrements(t=self.t[a : b + 1], dtheta_b=self.dtheta_b[a:b], dv_b=self.dv_b[a:b])


@dataclass(frozen=True)
class ImuRates:
    """IMU output in rate form: instantaneous samples.

    Attributes
    ----------
    t : (n,) s
    omega_ib_b : (n, 3) rad/s
    f_ib_b : (n, 3) m/s²
    """

    t: Array
    omega_ib_b: Array
    f_ib_b: Array

    def __post_init__(self) -> None:
        n = len(self.t)
        _check_shapes("ImuRates", n, t=(self.t, (n,)), omega_ib_b=(self.omega_ib_b, (n, 3)),
                      f_ib_b=(self.f_ib_b, (n, 3)))  # fmt: skip

    def __len__(self) -> int:
        return len(self.t)

    def to_increments(self) -> ImuIncrements:
        """Integrate to increments over the intervals between samples.

        Four-point cubic quadrature ``dt/24 (-x[k-1] + 13 x[k] + 13 x[k+1] - x[k+2])``
        on uniform interior intervals (fourth order), the trapezoid rule at the
        two ends and wherever the step varies by more than 1 ppm.
        """
        if len(self.t) < 2:
            raise ValueError("rate-form IMU data need at least two samples to form an interval")
        check_increasing(self.t, "ImuRates.to_increments")
        dt = np.diff(self.t)
        out = []
        for x in (self.omega_ib_b, self.f_ib_b):
            inc = 0.5 * (x[:-1] + x[1:]) * dt[:, None]
            if len(x) >= 4:
                # Uniform to the rounding of the time stamps, which grows with |t|
                # (time-of-day or GPS-second stamps), plus one part per million.
                tol = 1e-6 * dt[1:-1] + 8.0 * np.finfo(float).eps * np.abs(self.t[2:-1])
                uniform = np.abs(dt[1:-1] - dt[:-2]) + np.abs(dt[2:] - dt[1:-1]) < tol
                cubic = (dt[1:-1] / 24.0)[:, None] * (-x[:-3] + 13.0 * x[1:-2] + 13.0 * x[2:-1] - x[3:])
                inc[1:-1] = np.where(uniform[:, None], cubic, inc[1:-1])
            out.append(inc)
        return ImuIncrements(t=self.t, dtheta_b=out[0], dv_b=out[1])


@dataclass(frozen=True)
class RigPhase:
    """One phase of a calibration session: rows ``start:stop`` of the recording.

    ``kind`` is "static" (the IMU at rest in one orientation) or "rotation"
    (turning). ``angle_rad`` is the known integrated rotation of a rotation
    phase in body axes (rad) when the rig gives no per-sample reference rate,
    as in a hand-turned Ferraris session; otherwise ``None``.
    """

    name: str
    start: int
    stop: int
    kind: str
    angle_rad: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class CalibrationData:
    """IMU readings beside the rig's reference inputs, in rate form, body axes.

    Attributes
    ----------
    t : (n,) s, increasing
    gyro, accel : (n, 3) the IMU's readings, rad/s and m/s²
    ref_gyro, ref_accel : (n, 3) the reference angular rate ``omega_ib_b`` and
        specific force, rad/s and m/s²; NaN where the rig gives no per-sample
        reference (then the phase's ``angle_rad`` may constrain the integral)
    temp : (n,) °C, or None when not recorded
    phases : the session's phases, in time order (may be empty)
    source : where the data came from, for messages
    """

    t: Array
    gyro: Array
    accel: Array
    ref_gyro: Array
    ref_accel: Array
    temp: Array | None = None
    phases: tuple[RigPhase, ...] = ()
    source: str = ""

    def __post_init__(self) -> None:
        n, three = len(self.t), (len(self.t), 3)
        temp = {} if self.temp is None else {"temp": (self.temp, (n,))}
        _check_shapes("CalibrationData", n, t=(self.t, (n,)), gyro=(self.gyro, three),
                      accel=(self.accel, three), ref_gyro=(self.ref_gyro, three),
                      ref_accel=(self.ref_accel, three), **temp)  # fmt: skip

    def __len__(self) -> int:
        return len(self.t)

    def check_readings(self) -> None:
        """Refuse readings a fit cannot take: a time, gyro, accelerometer or temperature value that is not
        finite (a NaN reading made every coefficient NaN, and the model it gave corrected every reading to
        NaN). The reference may be NaN where the rig gives none (the class docstring).

        Raises
        ------
        ValueError
            naming how many rows and the first one's time.
        """
        columns = [self.t[:, None], self.gyro, self.accel] + (
            [] if self.temp is None else [self.temp[:, None]]
        )
        bad = ~np.all(np.hstack([np.isfinite(c) for c in columns]), axis=1)
        if bad.any():
            first = int(np.argmax(bad))
            raise ValueError(
                f"{self.source or 'recording'}: {int(bad.sum())} row(s) of readings not finite (the first, "
                f"row {first}, at t = {self.t[first]:g} s): drop them before fitting"
            )

    def rows(self, index: NDArray[np.integer] | slice) -> CalibrationData:
        """The rows at ``index`` (phases are dropped: their row ranges no longer apply)."""
        return CalibrationData(
            t=self.t[index],
            gyro=self.gyro[index],
            accel=self.accel[index],
            ref_gyro=self.ref_gyro[index],
            ref_accel=self.ref_accel[index],
            temp=None if self.temp is None else self.temp[index],
            source=self.source,
        )

    def split(self, validation: float, *, by_phase: bool = True) -> tuple[CalibrationData, CalibrationData]:
        """Fit and validation portions, in contiguous time blocks (see :meth:`held_back`).

        Phases are kept, re-indexed, in both portions.
        """
        held = self.held_back(validation, by_phase=by_phase)
        return self._subset(np.flatnonzero(~held)), self._subset(np.flatnonzero(held))

    def held_back(
        self, validation: float, *, by_phase: bool = True, like_input: bool = False
    ) -> NDArray[np.bool_]:
        """Which rows :meth:`split` holds back for validation.

        With ``by_phase`` and phases present, the last ``validation`` fraction
        (rounded half up, at least one row and at most all but one) of every
        phase of two or more rows is held back, so each orientation and rate is
        seen in both portions yet no validation sample sits between fit samples
        of the same phase. Without phases, with ``like_input``, the same of
        every one of :meth:`stretches`; otherwise the last fraction of the
        whole recording.
        """
        if not 0.0 < validation < 1.0:
            raise ValueError(f"validation fraction must be in (0, 1), got {validation}")
        n = len(self.t)
        blocks = [(0, n)]
        if by_phase and self.phases:
            blocks = [(p.start, p.stop) for p in self.phases]
        elif like_input:
            blocks = self.stretches()
        held = np.zeros(n, dtype=bool)
        for start, stop in blocks:
            length = stop - start
            # At least one row each way for any block of two or more rows.
            held_rows = min(max(int(np.floor(validation * length + 0.5)), 1), length - 1) if length > 1 else 0
            held[stop - held_rows : stop] = True
        if held.all() or not held.any():
            raise ValueError(f"{self.source or 'recording'}: too short to split ({n} rows)")
        return held

    def stretches(self, longest_s: float = STRETCH_LONGEST_S) -> list[tuple[int, int]]:
        """Rows ``(start, stop)`` of stretches of like input, in time order, covering the recording: the
        phases a recording without them would have had.

        A row is *steady* where its reference rate and force moved from the previous row's by less
        than :data:`STEADY_RATE` and :data:`STEADY_FORCE` (static holds, constant table rates) and
        *moving* otherwise (transitions, tumbling, a drive); rows without a reference are a third
        kind. A stretch is a run of one kind, shorter runs than :data:`STRETCH_SHORTEST_S` aside: a
        short steady run inside motion is part of the motion; a short moving run that takes the
        reference to another level (a fast turn, a rate stepped without a ramp) is a stretch of its
        own, as it would be a phase of its own, and one that returns to the same level (a reference
        flickering about the threshold) joins the stretch before it. A stretch longer than
        ``longest_s`` is cut into equal parts no longer, so that continuous motion is withheld in
        interleaved blocks rather than at its end.
        """
        n = len(self.t)
        if n < 2:
            return [(0, n)]
        # A sensor at a time: no (n, 6) copies of a long recording's references.
        rate_step = np.linalg.norm(np.diff(self.ref_gyro, axis=0), axis=1)
        force_step = np.linalg.norm(np.diff(self.ref_accel, axis=0), axis=1)
        # Relative slack as well: a fast table's rate printed to ten digits moves in its last one.
        rate_tol = STEADY_RATE + 1e-6 * np.linalg.norm(self.ref_gyro[1:], axis=1)
        force_tol = STEADY_FORCE + 1e-6 * np.linalg.norm(self.ref_accel[1:], axis=1)
        kind = np.where((rate_step <= rate_tol) & (force_step <= force_tol), 0, 1)
        kind = np.concatenate([kind[:1], kind])
        kind[~self.has_reference] = 2
        dt = float(np.median(np.diff(self.t)))
        shortest = max(2, round(STRETCH_SHORTEST_S / dt))
        # A steady run too short to be a stretch is a pause in motion: it takes the moving kind. A short
        # moving run between steady levels is a transition of its own (a fast turn, a rate stepped
        # without a ramp): joined to the level before, its rows would all lie in that stretch's
        # withheld end, and nothing fitted would see the input change (an accelerometer's delay
        # shows only while the force turns). A flicker of a still reference (back to its level) joins
        # the level.
        edges = np.concatenate([[0], np.flatnonzero(np.diff(kind)) + 1, [n]])
        for start, stop in itertools.pairwise(edges):
            if stop - start < shortest and kind[start] == 0:
                kind[start:stop] = kind[start - 1]
        edges = np.concatenate([[0], np.flatnonzero(np.diff(kind)) + 1, [n]])
        runs: list[tuple[int, int]] = []
        level_row = 0  # the last row of the latest stretch's own run, before any short run joined it
        for start, stop in zip(edges[:-1].tolist(), edges[1:].tolist(), strict=True):
            if runs and stop - start < shortest:
                runs[-1] = (runs[-1][0], stop)
                continue
            if runs and kind[start] == kind[level_row] == 0:
                if (
                    np.linalg.norm(self.ref_gyro[start] - self.ref_gyro[level_row]) <= rate_tol[start - 1]
                    and np.linalg.norm(self.ref_accel[start] - self.ref_accel[level_row])
                    <= force_tol[start - 1]
                ):
                    runs[-1], level_row = (runs[-1][0], stop), stop - 1
                    continue
            if runs and kind[level_row] == 0 and level_row + 1 < start:  # a transition joined the level
                runs[-1] = (runs[-1][0], level_row + 1)
                runs.append((level_row + 1, start))
            runs.append((start, stop))
            level_row = stop - 1
        out = []
        longest = max(2, round(longest_s / dt))
        for start, stop in runs:
            parts = -(-(stop - start) // longest)
            cuts = np.linspace(start, stop, parts + 1).round().astype(int)
            out += [(int(a), int(b)) for a, b in itertools.pairwise(cuts)]
        return out

    @property
    def has_reference(self) -> NDArray[np.bool_]:
        """Per row, whether it has a per-sample reference (finite ``ref_gyro`` and ``ref_accel``); a
        hand-turned rotation's rows have none and say nothing of the errors."""
        ok = np.isfinite(self.ref_gyro).all(axis=1) & np.isfinite(self.ref_accel).all(axis=1)
        return np.asarray(ok, dtype=bool)

    def rows_with_reference(self) -> CalibrationData:
        """The rows with a per-sample reference (:attr:`has_reference`), phases kept."""
        ok = self.has_reference
        return self if ok.all() else self._subset(np.flatnonzero(ok))

    def _subset(self, rows: NDArray[np.integer]) -> CalibrationData:
        """Rows (sorted) with the phases that survive, re-indexed."""
        position = np.full(len(self.t) + 1, -1)
        position[rows] = np.arange(len(rows))
        phases = []
        for p in self.phases:
            kept = rows[(rows >= p.start) & (rows < p.stop)]
            if kept.size:
                # A rotation's known angle is for the whole phase: keep it only if the phase is whole.
                whole = kept.size == p.stop - p.start
                phases.append(
                    RigPhase(p.name, int(position[kept[0]]), int(position[kept[-1]]) + 1, p.kind,
                             p.angle_rad if whole else None)
                )  # fmt: skip
        part = self.rows(rows)
        return CalibrationData(
            t=part.t, gyro=part.gyro, accel=part.accel, ref_gyro=part.ref_gyro, ref_accel=part.ref_accel,
            temp=part.temp, phases=tuple(phases), source=self.source,
        )  # fmt: skip


@dataclass(frozen=True)
class ReferencedRecording:
    """A real unit's readings beside a reference trajectory sampled at its own epochs.

    The reference knows where the unit was and how it was turned (an optical motion capture, a
    better INS), not what the sensors should have read: rates and specific forces follow from it
    only by differentiation, which raises its noise, so compensation on such a recording is fitted
    on the angle and velocity changes between reference epochs (:mod:`sins.compensation.interval_fit`).

    Attributes
    ----------
    imu : the readings as increments in the unit's own axes (rate-form recordings are integrated by
        the trapezoid rule between samples); ``imu.t`` (n+1,) are the step boundaries
    reference : the reference at its epochs (m,), in the navigation frame (NED) of the package, the
        attitude that of the unit's own axes; every state finite, epochs within ``imu.t``'s span
    judged : (n+1,) bool, at the step boundaries ``imu.t``: the times figures are judged at (BROAD's
        movement phases), or None for all
    sensor : the unit's identity where the recording gives one ("BROAD IMU B"), else ""
    reference_name : what the reference is, for reports
    source : where the data came from, for messages
    heading_known : whether the reference's north is true north; where it is not (a motion capture's
        room frame), only the vertical part of Earth's rate is known in its axes
    latitude_known : whether the reference's latitude is where the unit was; where it is not (a room
        frame placed at a nominal origin), Earth's rate is not known in its axes at all and is left out
    frame : the file's axes the readings were read on (:mod:`sins.io.axes` letters, ``frd``: taken as
        they are), "" where not said: a model fitted on one reading of the axes is refused on another
    """

    imu: ImuIncrements
    reference: NavSeries
    judged: NDArray[np.bool_] | None = None
    sensor: str = ""
    reference_name: str = "reference"
    source: str = ""
    heading_known: bool = True
    latitude_known: bool = True
    frame: str = ""

    @property
    def rate_hz(self) -> float:
        """The readings' median sample rate, Hz."""
        return float(1.0 / np.median(np.diff(self.imu.t)))


__all__ = [
    "QUAT_NORM_TOL",
    "STEADY_FORCE",
    "STEADY_RATE",
    "STRETCH_LONGEST_S",
    "STRETCH_SHORTEST_S",
    "CalibrationData",
    "ImuIncrements",
    "ImuRates",
    "NavSeries",
    "ReferencedRecording",
    "RigPhase",
    "check_increasing",
]
