"""An IMU recording in sins's terms (:class:`Recording`), and the readers of a path by its kind
(:func:`_read_path`, :func:`_rig_recording`) behind :func:`sins.io.read`.

A recording is named by its path or by a dataset's name (:mod:`sins.io.datasets`: ``broad_05``,
``ferraris``, ``euroc/V1_01_easy``). For a path, the reader is picked by what the path is: a folder with
``metadata.yaml`` (a ROS 2 bag), a ROS 1 bag or an MCAP file (by their first bytes, :mod:`sins.io.bags`),
a EuRoC/TUM-VI folder or ASL file (:mod:`sins.io.euroc`), an ``.npz`` recording (:mod:`sins.io.npz`), a
rig CSV (``ref_`` columns, :mod:`sins.io.rig`), else a CSV: sins's own IMU forms
(:mod:`sins.io.formats`) or, with ``columns`` or ``units``, one with its own columns and units
(:mod:`sins.io.columns`). Every recording comes back as a :class:`Recording`: readings in SI on FRD
axes, and its reference where it has one: a trajectory (its own, or a truth file given beside it) or
per-sample reference inputs (a rig's).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.core.series import CalibrationData, ImuIncrements, ImuRates, NavSeries, ReferencedRecording
from sins.errors import ArgumentError, MissingInputError, SinsInputError
from sins.io import axes, bags, euroc, formats, frame_check, local, npz, provenance, rig
from sins.io import columns as column_reader
from sins.io import units as unitdefs
from sins.io.paths import check_input

Array = NDArray[np.float64]

#: The sampling rates a recording may be stated or made at (``rate_hz``), Hz: from a slow logger's to
#: beyond any IMU's (a scenario's ``[imu] rate_hz`` takes 1 Hz to 100 kHz).
RATE_HZ_RANGE = (0.1, 1e5)
#: What :attr:`Recording.kind` may be.
KINDS = ("sins csv", "csv columns", "rig csv", "ros1 bag", "ros2 bag", "mcap", "euroc", "npz", "dataset")


@dataclass(frozen=True)
class Recording:
    """An IMU recording in sins's terms.

    Attributes
    ----------
    imu : the readings, SI, FRD body axes: :class:`ImuRates`, or :class:`ImuIncrements` (sins's
        increment form; ``t[0]`` as :func:`read`'s ``t_start`` says)
    source : the path, for messages (a dataset's: the file it was read from)
    kind : one of :data:`KINDS`
    truth : the reference trajectory at its own times (a bag's poses, a EuRoC reference, a dataset's, or
        the truth file given beside the readings: ``truth_from``), or None
    units : ``{key: unit}`` the file's readings were taken to be in (:mod:`sins.io.units`), every key of
        the form; what :func:`sins.io.inspection.inspect` reasons from
    frame : the axes the readings were taken to be on (:mod:`sins.io.axes`) before the turn into FRD
    notes : what was converted or left out, one line each, for the user
    t0_ns : the absolute stamp (ns since the epoch) of ``t = 0`` where the times were made relative to
        it (bags, EuRoC), else None
    stated_rate_hz, stated_by : a sampling rate stated beside the stamps (EuRoC's ``sensor.yaml``, a
        given rate) and by what, else None and ""
    receive_t : a bag's recorder times of the readings, s from ``t0_ns`` (another clock than the stamps)
    temp : (n,) °C, or None
    fixes : a bag's ``NavSatFix`` positions, or None
    time_from_rate : the times were made from a given rate (the file has no time column)
    column_map : a CSV's sins column names and the file columns read for them (``{}`` for other kinds)
    sensor, corrected_by : a CSV's ``# sensor:`` and ``# corrected by:`` lines (:mod:`sins.io.provenance`),
        "" where it has none
    heading_known : whether the reference's north is true north (False for a room frame: EuRoC, .npz,
        and a bag placed nowhere: without a fix or an origin)
    latitude_known : whether the reference's latitude is the recording's own (False where the frame was
        placed at a nominal origin: Earth's rate then cannot be placed in it and is left out)
    rig : the readings beside per-sample reference inputs where the recording has them (a rig CSV's
        ``ref_`` columns; the Ferraris and ring-laser datasets), else None
    truth_from : the truth file ``truth`` was read from, "" where it is the recording's own
    dataset : the dataset's name where the recording was read by it, else ""
    on_reference : a dataset's readings beside its trajectory as the dataset gives them (the phases it
        is judged in, its unit), else None: :meth:`beside_reference` makes them from ``truth``
    inputs_reader : how a dataset with a trajectory gives its readings beside per-sample reference
        inputs (read only when asked for, :meth:`reference_inputs`), else None
    """

    imu: ImuRates | ImuIncrements
    source: str
    kind: str
    truth: NavSeries | None = None
    units: Mapping[str, str] = field(default_factory=dict)
    frame: str = axes.FRD
    notes: tuple[str, ...] = ()
    t0_ns: int | None = None
    stated_rate_hz: float | None = None
    stated_by: str = ""
    receive_t: Array | None = None
    temp: Array | None = None
    fixes: bags.GeodeticFixes | None = None
    time_from_rate: bool = False
    column_map: Mapping[str, str] = field(default_factory=dict)
    sensor: str = ""
    corrected_by: str = ""
    heading_known: bool = True
    latitude_known: bool = True
    rig: CalibrationData | None = None
    truth_from: str = ""
    dataset: str = ""
    on_reference: ReferencedRecording | None = field(default=None, repr=False)
    inputs_reader: Callable[[], tuple[CalibrationData, NavSeries | None]] | None = field(
        default=None, repr=False, compare=False
    )

    @property
    def name(self) -> str:
        """What the user named the recording: the dataset's name, else the path."""
        return self.dataset or self.source

    @property
    def has_trajectory(self) -> bool:
        """Whether the recording has a reference trajectory (its own, a dataset's or a given truth)."""
        return self.truth is not None or self.on_reference is not None

    def beside_reference(self) -> ReferencedRecording:
        """The readings beside the reference trajectory, at its epochs (what interval fits and open loops
        work on): rate-form readings integrated between samples by the trapezoid rule; the reference cut
        to the readings' span.

        Raises
        ------
        MissingInputError
            without a reference trajectory (``needs`` says what would give one).
        SinsInputError
            a reference that does not overlap the readings in time, or whose attitude is not of the
            readings' axes (:func:`sins.io.frame_check.reference_findings`: everything judged against it
            would be wrong).
        """
        if self.on_reference is not None:
            return dataclasses.replace(self.on_reference, frame=self.frame)
        if self.truth is None:
            raise missing_reference(self)
        t, w, f = self.mean_rates()
        for finding in frame_check.reference_findings(self.truth, t, w, f):
            raise SinsInputError(f"{self.source}: {finding.what}; {finding.advice}")
        own = not self.truth_from
        return beside_trajectory(
            self.imu, self.truth, self.source, sensor=self.sensor,
            reference_name=f"its own reference ({self.kind})" if own else "truth",
            heading_known=self.heading_known, latitude_known=self.latitude_known, frame=self.frame,
        )  # fmt: skip

    def reference_inputs(self) -> tuple[CalibrationData, NavSeries | None]:
        """The readings beside per-sample reference inputs (a rig's, a dataset's), and the reference
        trajectory at their times where there is one.

        Raises
        ------
        MissingInputError
            a recording that holds none (a trajectory's per-sample form is the exact ideal IMU through
            it, made where it is needed: :mod:`sins.unit_gap`, :mod:`sins.runs.readings`).
        """
        if self.rig is not None:
            return self.rig, None
        if self.inputs_reader is not None:
            return self.inputs_reader()
        raise MissingInputError(f"{self.name}: no ref_ columns (per-sample reference inputs)", needs="truth")

    @property
    def form(self) -> str:
        """``"rate"`` or ``"increment"``."""
        return "rate" if isinstance(self.imu, ImuRates) else "increment"

    def mean_rates(self) -> tuple[Array, Array, Array]:
        """``(t, omega_ib_b, f_ib_b)``: the readings as rates (s, rad/s, m/s²); increments divided by
        their intervals, at the intervals' midpoints."""
        if isinstance(self.imu, ImuRates):
            return self.imu.t, self.imu.omega_ib_b, self.imu.f_ib_b
        return self.imu.mean_rates()


#: Suffixes that name a binary recording format (the bags, an ``.npz``), with what its file starts with
#: (a file that does not is refused, not read as a CSV).
_BINARY_SUFFIXES = {
    ".bag": ("a ROS 1 bag", "'#ROSBAG V2.0'"),
    ".mcap": ("an MCAP file", "MCAP's magic"),
    ".db3": ("a ROS 2 bag", "SQLite's header"),
    ".npz": ("a NumPy archive", "a zip archive's"),
}


def missing_reference(rec: Recording) -> MissingInputError:
    """The error for a recording without the reference a command needs: a bag with several pose topics
    wants one named (``needs="truth_topic"``); any other, a truth file (``needs="truth"``)."""
    several = next((n for n in rec.notes if n.startswith(bags.SEVERAL_POSES)), None)
    if several is not None:
        return MissingInputError(f"{rec.source}: {several}", needs="truth_topic")
    return MissingInputError(f"{rec.source}: the recording has no reference trajectory", needs="truth")


def beside_trajectory(
    imu: ImuRates | ImuIncrements,
    truth: NavSeries,
    source: str,
    reference_name: str = "truth",
    **fields: Any,
) -> ReferencedRecording:
    """Readings beside a reference trajectory as a :class:`~sins.core.series.ReferencedRecording` (its
    other ``fields`` as given): rate-form readings
    integrated between samples by the trapezoid rule, the reference cut to the readings' span.

    Raises
    ------
    SinsInputError
        naming ``source`` when the reference does not overlap the readings in time.
    """
    if isinstance(imu, ImuRates):
        dt = np.diff(imu.t)[:, None]
        imu = ImuIncrements(
            t=imu.t,
            dtheta_b=0.5 * (imu.omega_ib_b[:-1] + imu.omega_ib_b[1:]) * dt,
            dv_b=0.5 * (imu.f_ib_b[:-1] + imu.f_ib_b[1:]) * dt,
        )
    inside = np.flatnonzero((truth.t >= imu.t[0]) & (truth.t <= imu.t[-1]))
    if len(inside) < 2:
        raise SinsInputError(
            f"{source}: the reference ({truth.t[0]:.6g}..{truth.t[-1]:.6g} s) does not overlap the "
            f"readings ({imu.t[0]:.6g}..{imu.t[-1]:.6g} s)"
        )
    return ReferencedRecording(
        imu=imu,
        reference=truth.at(inside),
        judged=None,
        source=source,
        reference_name=reference_name,
        **fields,
    )


def ideal_inputs(rec: Recording) -> tuple[CalibrationData, NavSeries]:
    """A recording beside its own reference trajectory as readings beside per-sample reference inputs:
    the exact ideal IMU of the motion through the trajectory (splines, then the strapdown equations
    backwards) at the readings' times (mean rates at their middles for increments), and the trajectory
    there. Readings outside the trajectory's span are left out (a motion capture commonly starts and
    ends a little inside the IMU's recording).

    Raises
    ------
    SinsInputError
        without a reference trajectory, or with fewer than 4 readings within its span.
    """
    from sins.nav import motion, trajectory

    if rec.truth is None:
        raise SinsInputError(f"{rec.name}: the recording has no reference trajectory")
    t, gyro, accel = rec.mean_rates()
    inside = (t >= rec.truth.t[0]) & (t <= rec.truth.t[-1])
    t, gyro, accel = t[inside], gyro[inside], accel[inside]
    if len(t) < 4:
        raise SinsInputError(f"{rec.name}: fewer than 4 readings within the reference's time span")
    at = rec.truth.interpolate(t)
    ideal = trajectory.ideal_rates(motion.RecordedMotion.from_series(rec.truth), at)
    data = CalibrationData(
        t=t, gyro=gyro, accel=accel, ref_gyro=ideal.omega_ib_b, ref_accel=ideal.f_ib_b, source=rec.source
    )
    return data, at


def recording_kind(path: Path) -> str:
    """The :data:`KINDS` entry a path reads as (``"sins csv"`` standing for any CSV).

    Raises
    ------
    SinsInputError
        a path that does not exist, or a folder that is neither a ROS 2 bag nor a EuRoC/TUM-VI one.
    """
    check_input(path, folder=True)  # a FIFO, /dev/zero or a device refused before anything opens it
    kind = bags.bag_kind(path)
    if kind is not None:
        return kind
    if euroc.locate(path) is not None:
        return "euroc"
    if npz.is_npz(path):
        return "npz"
    named = _BINARY_SUFFIXES.get(path.suffix.lower())
    if named is not None and path.is_file():
        size = path.stat().st_size
        why = "it is empty" if size == 0 else f"its first bytes are not {named[1]}"
        raise SinsInputError(f"{path}: named as {named[0]}, but {why}; not read as a CSV")
    if path.is_dir():
        raise SinsInputError(
            f"{path}: a folder, but neither a ROS 2 bag (metadata.yaml) nor a EuRoC/TUM-VI recording "
            "(mav0/imu0/data.csv)"
        )
    return "sins csv"


def _rig_recording(path: Path) -> Recording:
    """A rig recording: its readings beside the rig's per-sample reference inputs (``ref_`` columns)."""
    data = rig._read_rig(path)
    rig.check_recording_range(path, data)
    said = provenance.read_provenance(path)
    imu = ImuRates(t=data.t, omega_ib_b=data.gyro, f_ib_b=data.accel)
    return Recording(imu, str(path), "rig csv", units=_si("rate"), temp=data.temp, rig=data,
                     column_map={n: n for n in rig.RECORDING_COLUMNS}, sensor=said.sensor,
                     corrected_by=said.corrected_by, t0_ns=said.t0_ns)  # fmt: skip


def _read_path(
    path: Path,
    topic: str | None = None,
    columns: str | Mapping[str, str] | None = None,
    units: str | Mapping[str, str] | None = None,
    *,
    frame: str | None = None,
    rate_hz: float | None = None,
    truth_topic: str | None = None,
    origin: tuple[float, float, float] | None = None,
    t_start: float | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Recording:
    """A recording's path read by the reader its kind needs (:func:`read`'s parameters)."""
    path = Path(path)
    if rate_hz is not None and not RATE_HZ_RANGE[0] <= rate_hz <= RATE_HZ_RANGE[1]:
        low, high = RATE_HZ_RANGE
        raise SinsInputError(
            f"{path}: a sampling rate of {rate_hz:g} Hz given; a rate is within {low:g} Hz to {high:g} Hz"
        )
    kind = recording_kind(path)
    _check_options(path, kind, topic=topic, columns=columns, truth_topic=truth_topic, origin=origin)
    chosen = _units(units)
    if kind == "sins csv" and (columns is not None or units is not None or rate_hz is not None):
        rec = _read_columns(path, columns, chosen, rate_hz, frame or axes.FRD, t_start)
    elif kind == "sins csv":
        rec = _read_sins(path, frame or axes.FRD, t_start)
    elif kind == "euroc":
        got = euroc._read_euroc(path, frame=frame or axes.FRD, origin=origin or local.NOMINAL_ORIGIN)
        rec = Recording(got.imu, str(path), kind, got.truth, _si("rate"), frame or axes.FRD, got.notes,
                        got.t0_ns, got.rate_hz, "imu0/sensor.yaml" if got.rate_hz else "",
                        heading_known=False, latitude_known=origin is not None)  # fmt: skip
    elif kind == "npz":
        imu, truth, t0_s, notes = npz._read_npz(path, frame=frame or axes.FRD, origin=origin)
        rec = Recording(imu, str(path), kind, truth, _si("rate"), frame or axes.FRD, notes, round(t0_s * 1e9),
                        heading_known=False, latitude_known=origin is not None)  # fmt: skip
    else:
        read = bags._read_bag(
            path, topic, truth_topic, frame=frame or axes.FLU, origin=origin, progress=progress
        )
        # The poses' frame is ENU (REP 103) at a fix or a given origin; placed at the nominal one, neither
        # its latitude nor so its Earth's rate is the unit's: left out, as a room's (bags._origin says so).
        placed = read.fixes is not None or origin is not None
        rec = Recording(read.imu, str(path), kind, read.truth, _si("rate"), frame or axes.FLU, read.notes,
                        read.t0_ns, receive_t=read.receive_t, fixes=read.fixes, heading_known=placed,
                        latitude_known=placed)  # fmt: skip
    if kind not in ("sins csv", "csv columns") and chosen:
        rec = _rescaled(rec, chosen)
    if rate_hz is not None and not rec.time_from_rate:
        rec = _with(rec, stated_rate_hz=float(rate_hz), stated_by="the given rate")
    return rec


def _si(form: str) -> dict[str, str]:
    return {k: unitdefs.SI[k] for k in unitdefs.FORM_KEYS[form] if k != "temp"}


def _units(spec: str | Mapping[str, str] | None) -> dict[str, str]:
    return unitdefs.parse_units(spec)


def _check_options(path: Path, kind: str, **given: object) -> None:
    """Refuse an option the path's kind has no use for, rather than ignore it."""
    applies = {
        "topic": ("ros1 bag", "ros2 bag", "mcap"),
        "truth_topic": ("ros1 bag", "ros2 bag", "mcap"),
        "columns": ("sins csv",),
        "origin": ("ros1 bag", "ros2 bag", "mcap", "euroc", "npz"),
    }
    for name, value in given.items():
        if value is not None and kind not in applies[name]:
            raise ArgumentError(f"{{names}}: does not apply to {path}, a {_described(kind)}", (name,))


def _described(kind: str) -> str:
    return {"sins csv": "CSV file", "euroc": "EuRoC/TUM-VI recording", "mcap": "MCAP file"}.get(kind, kind)


def _read_sins(path: Path, frame: str, t_start: float | None) -> Recording:
    """sins's own IMU CSV (either form), turned from ``frame`` into FRD."""
    samples, table = formats._read_imu(path)
    if isinstance(samples, ImuIncrements) and t_start is not None:
        samples = formats.increments_from_table(table, float(t_start))
    temp = table.column("temp").copy() if table.has("temp") else None
    form = "rate" if isinstance(samples, ImuRates) else "increment"
    names = formats.RATE_COLUMNS if form == "rate" else formats.INCREMENT_COLUMNS
    said = provenance.read_provenance(path)
    rec = Recording(samples, str(path), "sins csv", units=_si(form), frame=axes.FRD, temp=temp,
                    column_map={n: n for n in names}, sensor=said.sensor,
                    corrected_by=said.corrected_by, t0_ns=said.t0_ns)  # fmt: skip
    return _turned(rec, frame)


def _read_columns(
    path: Path, columns: str | Mapping[str, str] | None, chosen: dict[str, str], rate_hz: float | None,
    frame: str, t_start: float | None,
) -> Recording:  # fmt: skip
    """A CSV through :mod:`sins.io.columns`, turned from ``frame`` into FRD."""
    got = column_reader._read_columns_csv(path, columns, chosen, rate_hz)
    imu = got.imu
    if isinstance(imu, ImuIncrements) and t_start is not None:
        if not t_start < imu.t[1]:
            raise SinsInputError(
                f"{path}: the first increment ends at {formats.format_number(imu.t[1])} s, not after the "
                f"start time {formats.format_number(t_start)} s"
            )
        imu = ImuIncrements(t=np.concatenate([[t_start], imu.t[1:]]), dtheta_b=imu.dtheta_b, dv_b=imu.dv_b)
    said = provenance.read_provenance(path)
    renamed = {k: v for k, v in got.mapping.items() if k != v}
    notes = [f"columns {', '.join(f'{k}={v}' for k, v in renamed.items())}"] if renamed else []
    if any(v != unitdefs.SI[k] for k, v in got.units.items()):
        notes.append(f"units {unitdefs.spec_text(got.units)} converted to SI")
    if got.time_from_rate:
        notes.append(f"no time column: times are row / {rate_hz:g} Hz")
    rec = Recording(imu, str(path), "csv columns", units=got.units, temp=got.temp, notes=tuple(notes),
                    time_from_rate=got.time_from_rate,
                    stated_rate_hz=rate_hz if got.time_from_rate else None,
                    stated_by="the given rate" if got.time_from_rate else "",
                    column_map=got.mapping, sensor=said.sensor,
                    corrected_by=said.corrected_by, t0_ns=said.t0_ns)  # fmt: skip
    return _turned(rec, frame)


def _turned(rec: Recording, frame: str) -> Recording:
    """``rec`` (on FRD as read) taken to be on ``frame``: turned into FRD, the frame and a note kept."""
    m = axes.frame_matrix(frame)
    if frame.lower() == axes.FRD:
        return rec
    imu = rec.imu
    if isinstance(imu, ImuRates):
        imu = ImuRates(t=imu.t, omega_ib_b=axes.to_frd(imu.omega_ib_b, m), f_ib_b=axes.to_frd(imu.f_ib_b, m))
    else:
        imu = ImuIncrements(t=imu.t, dtheta_b=axes.to_frd(imu.dtheta_b, m), dv_b=axes.to_frd(imu.dv_b, m))
    return _with(
        rec, imu=imu, frame=frame.lower(), notes=(*rec.notes, f"axes {frame.lower()} turned into FRD")
    )


def _rescaled(rec: Recording, chosen: dict[str, str]) -> Recording:
    """A bag's or EuRoC's readings (SI by definition) rescaled as ``chosen`` says they really are."""
    unitdefs.check_form(chosen, rec.form, rec.source)
    for key, why in (("temp", "has no temperature"), ("t", "is stamped in nanoseconds by its format")):
        if key in chosen:
            raise SinsInputError(f"units: {key} does not apply: {rec.source} {why}")
    imu = rec.imu
    assert isinstance(imu, ImuRates)  # bags and EuRoC hold rates
    imu = ImuRates(t=imu.t, omega_ib_b=imu.omega_ib_b * unitdefs.factor(chosen, "gyro"),
                   f_ib_b=imu.f_ib_b * unitdefs.factor(chosen, "accel"))  # fmt: skip
    merged = {**rec.units, **chosen}
    note = f"units {unitdefs.spec_text(chosen)} converted to SI"
    return _with(rec, imu=imu, units=merged, notes=(*rec.notes, note))


def _with(rec: Recording, **changes: object) -> Recording:
    return dataclasses.replace(rec, **changes)  # type: ignore[arg-type]


__all__ = [
    "KINDS",
    "RATE_HZ_RANGE",
    "Recording",
    "beside_trajectory",
    "ideal_inputs",
    "missing_reference",
    "recording_kind",
]
