"""A calibration rig's recording: the IMU's readings beside the rig's reference, in rate form, as CSV.

Columns (in any order; other columns are ignored, not even parsed)::

    t, gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z,                  s, rad/s, m/s²
    ref_gyro_x, ref_gyro_y, ref_gyro_z, ref_accel_x, ref_accel_y, ref_accel_z, rad/s, m/s²
    [temp]   °C
    [phase]  integer phase index per row (-1: outside any phase); the rows of one phase are contiguous

The ``ref_`` columns alone may hold NaN: no per-sample reference there (a hand-turned rotation, say).
The phases' names and kinds, and a rotation's known angle, are comment lines at the top, one per phase,
written after any free comment::

    # phase 3: name=rate +z 100 dps; kind=rotation; angle_rad=0.0,0.0,-6.283185307179586

``N`` is the value in the phase column; fields are ``key=value`` separated by ``;``, each optional
(name defaults to "phase N"; kind to "static" when the reference rate is known and ~0 through the
phase, else "rotation"); angle_rad is three repr() floats, rad, body axes. In the name, ``%``, ``;``,
``"``, unprintable characters and leading/trailing white space are percent-encoded as UTF-8 (``%3B``
for ``;``), so any name survives the round trip. A top comment line of the form ``# phase N: ...`` is
always such a directive.
"""

from __future__ import annotations

import os
import re
import urllib.parse
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np

from sins.core.series import CalibrationData, RigPhase
from sins.errors import SinsInputError
from sins.io.formats import RATE_COLUMNS, check_readings, imu_form
from sins.io.tables import (
    Table,
    format_number,
    line_of_row,
    open_text,
    read_columns,
    read_header,
    read_table,
    write_table,
)

REF_COLUMNS = ("ref_gyro_x", "ref_gyro_y", "ref_gyro_z", "ref_accel_x", "ref_accel_y", "ref_accel_z")
RECORDING_COLUMNS = RATE_COLUMNS + REF_COLUMNS
PHASE_KINDS = ("static", "rotation")
#: Reference rate below which a phase without a ``kind`` field is "static", rad/s (0.057 °/s): well
#: above Earth's rate (7.3e-5 rad/s), which a rig's static reference may include, and below any table rate.
STATIC_RATE_TOL = 1e-3

_PHASE_DIRECTIVE = re.compile(r"#\s*phase\s+([0-9]+)\s*:(.*)")


class _Directive(NamedTuple):
    """What one ``# phase N:`` line gives; None where it leaves a field out."""

    line: int
    name: str | None
    kind: str | None
    angle_rad: tuple[float, float, float] | None


def write_recording(
    path: str | os.PathLike[str],
    data: CalibrationData,
    comment: str = "",
    progress: Callable[[int, int], None] | None = None,
) -> None:
    """Write a rig recording (the module's format), 17 significant digits, atomically.

    Parameters
    ----------
    path : the CSV file to write
    data : the recording; ``t`` (n,) s, ``gyro``/``ref_gyro`` (n, 3) rad/s, ``accel``/``ref_accel``
        (n, 3) m/s², ``temp`` (n,) °C or None. A ``phase`` column is written when ``data.phases`` is
        non-empty (-1 on rows outside every phase), with one ``# phase N:`` line per phase.
    comment : free text, written as ``#`` lines before the phase lines
    progress : called as ``progress(rows_written, rows)`` as blocks of rows are written

    Raises
    ------
    ValueError
        when ``data`` could not be read back as written: shapes that disagree, NaN or inf outside the
        ``ref_`` columns, inf in them, time not increasing, phases empty, overlapping, out of range
        or not in time order, a kind other than "static" or "rotation", a non-finite angle, or a
        comment line that looks like a phase directive.

    Notes
    -----
    Every float comes back bit for bit from :func:`_read_rig`, except that a NaN comes back as
    the canonical quiet NaN (``numpy.nan``) whatever its sign and payload.
    """
    _check_recording(data)
    for line in comment.splitlines():
        if _PHASE_DIRECTIVE.fullmatch(f"# {line}".rstrip()):
            raise ValueError(f"comment line {line!r} would read back as a phase directive")
    n = len(data.t)
    columns = list(RECORDING_COLUMNS)
    values = [data.t, *np.asarray(data.gyro).T, *np.asarray(data.accel).T,
              *np.asarray(data.ref_gyro).T, *np.asarray(data.ref_accel).T]  # fmt: skip
    if data.temp is not None:
        columns.append("temp")
        values.append(np.asarray(data.temp, dtype=float))
    lines = comment.splitlines()
    if data.phases:
        index = np.full(n, -1.0)
        for i, phase in enumerate(data.phases):
            index[phase.start : phase.stop] = i
            lines.append(_phase_directive(i, phase))
        columns.append("phase")
        values.append(index)
    write_table(path, columns, np.column_stack(values), "\n".join(lines), progress)


def is_rig_csv(path: Path) -> bool:
    """Whether ``path`` is a CSV file whose header has ``ref_`` columns (a rig recording's)."""
    if not path.is_file() or path.suffix.lower() != ".csv":
        return False
    return any(c.startswith("ref_") for c in read_columns(path))


def _read_rig(path: str | os.PathLike[str]) -> CalibrationData:
    """Read a rig recording (the module's format) into :class:`~sins.core.series.CalibrationData`.

    Returns
    -------
    CalibrationData
        ``t`` (n,) s; ``gyro``, ``ref_gyro`` (n, 3) rad/s; ``accel``, ``ref_accel`` (n, 3) m/s²
        (the ``ref_`` arrays NaN where the file has NaN); ``temp`` (n,) °C or None; ``phases``
        rebuilt from the ``phase`` column and the ``# phase N:`` lines, in time order; ``source``
        the path as a string.

    Raises
    ------
    SinsInputError
        one line naming the file, and the line and column where it applies: a missing IMU or
        reference column, increment-form columns, a non-numeric value, NaN outside the ``ref_``
        columns, inf anywhere, time not increasing, a phase index that is not an integer >= -1 or
        whose rows are not contiguous, a malformed ``# phase`` line or one naming a phase with no rows.
    """
    path = Path(path)
    header_line, header = read_header(path)
    if imu_form(header, path, header_line=header_line) == "increment":
        raise SinsInputError(
            f"{path}:{header_line}: a rig recording is in rate form ({', '.join(RATE_COLUMNS)}), "
            "not increment form"
        )
    for name in RATE_COLUMNS:
        if name not in header:
            raise SinsInputError(
                f"{path}:{header_line}: missing required column {name!r} (header has {', '.join(header)})"
            )
    for name in REF_COLUMNS:
        if name not in header:
            raise SinsInputError(
                f"{path}:{header_line}: missing column {name!r}: a rig recording needs reference columns "
                f"{', '.join(REF_COLUMNS)} (NaN where the rig gives no reference)"
            )
    select = RECORDING_COLUMNS + tuple(c for c in ("temp", "phase") if c in header)
    table = read_table(path, select=select, nan_ok=REF_COLUMNS)
    d = table.data
    directives = _read_phase_directives(path, header_line)
    if table.has("phase"):
        phases = _phases_from_column(table, directives)
    elif directives:
        number = min(directive.line for directive in directives.values())
        raise SinsInputError(f"{path}:{number}: a '# phase' line, but the header has no 'phase' column")
    else:
        phases = ()
    return CalibrationData(
        t=d[:, 0].copy(),
        gyro=d[:, 1:4].copy(),
        accel=d[:, 4:7].copy(),
        ref_gyro=d[:, 7:10].copy(),
        ref_accel=d[:, 10:13].copy(),
        temp=table.column("temp").copy() if table.has("temp") else None,
        phases=phases,
        source=str(path),
    )


def check_recording_range(path: str | os.PathLike[str], data: CalibrationData) -> None:
    """Refuse a recording read by :func:`_read_rig` whose readings or references lie beyond the
    physical ranges of IMU files (:data:`~sins.io.formats.MAX_RATE_RADPS`,
    :data:`~sins.io.formats.MAX_FORCE_MPS2`, :data:`~sins.io.formats.TEMP_DEGC`,
    :data:`~sins.io.formats.MAX_TIME_S`), naming the line and column.

    :func:`_read_rig` itself reads any finite value back (the format round-trips every float);
    the commands that compute with a recording (``sins fit``, ``evaluate``, ``gap``) call this.
    """
    path = Path(path)
    header_line, _ = read_header(path)
    columns = ("t", *RECORDING_COLUMNS[1:], *(("temp",) if data.temp is not None else ()))
    values = np.column_stack([data.t, data.gyro, data.accel, data.ref_gyro, data.ref_accel,
                              *((data.temp,) if data.temp is not None else ())])  # fmt: skip
    table = Table(path=path, columns=columns, data=values, first_data_line=header_line + 1)
    check_readings(table, RECORDING_COLUMNS[1:])


def _check_recording(data: CalibrationData) -> None:
    """Refuse (ValueError) what :func:`_read_rig` would refuse, before anything is written."""
    t = np.asarray(data.t, dtype=float)
    n = len(t)
    if t.ndim != 1 or n == 0:
        raise ValueError(f"t must be a non-empty (n,) array, got shape {t.shape}")
    for name in ("gyro", "accel", "ref_gyro", "ref_accel"):
        shape = np.shape(getattr(data, name))
        if shape != (n, 3):
            raise ValueError(f"{name} must have shape ({n}, 3), got {shape}")
    if data.temp is not None and np.shape(data.temp) != (n,):
        raise ValueError(f"temp must have shape ({n},), got {np.shape(data.temp)}")
    for name in ("t", "gyro", "accel", "temp"):
        values = getattr(data, name)
        if values is not None and not np.isfinite(values).all():
            raise ValueError(f"{name} has NaN or inf values; only the reference may be NaN")
    for name in ("ref_gyro", "ref_accel"):
        if np.isinf(getattr(data, name)).any():
            raise ValueError(f"{name} has inf values (NaN marks a missing reference)")
    if (np.diff(t) <= 0).any():
        raise ValueError("t does not increase")
    previous = 0
    for phase in data.phases:
        if not previous <= phase.start < phase.stop <= n:
            raise ValueError(
                f"phase {phase.name!r}: rows {phase.start}:{phase.stop} are empty, out of 0:{n}, "
                "or not after the previous phase (phases must be in time order, without overlap)"
            )
        if phase.kind not in PHASE_KINDS:
            raise ValueError(f"phase {phase.name!r}: kind {phase.kind!r} is not one of {PHASE_KINDS}")
        if phase.angle_rad is not None and (
            len(phase.angle_rad) != 3 or not np.isfinite(np.asarray(phase.angle_rad, dtype=float)).all()
        ):
            raise ValueError(f"phase {phase.name!r}: angle_rad must be three finite floats")
        previous = phase.stop


def _phase_directive(index: int, phase: RigPhase) -> str:
    """The comment text (without ``# ``) that describes ``phase``."""
    fields = [f"name={_encode_field(phase.name)}", f"kind={phase.kind}"]
    if phase.angle_rad is not None:
        fields.append("angle_rad=" + ",".join(repr(float(a)) for a in phase.angle_rad))
    return f"phase {index}: " + "; ".join(fields)


def _encode_field(text: str) -> str:
    """Percent-encode what the directive syntax or a CSV reader would misread; keep the rest readable."""
    out = []
    for i, ch in enumerate(text):
        # The reader strips each field, so white space at either end is encoded; '"' is, so that
        # a CSV tool that honours quotes even in comment lines cannot run one line into the next.
        edge = ch.isspace() and (i == 0 or i == len(text) - 1)
        if ch in '%;"' or not ch.isprintable() or edge:
            out.append("".join(f"%{b:02X}" for b in ch.encode("utf-8")))
        else:
            out.append(ch)
    return "".join(out)


def _read_phase_directives(path: Path, header_line: int) -> dict[int, _Directive]:
    """``{N: directive}`` from the ``# phase N:`` lines above the header."""
    out: dict[int, _Directive] = {}
    with open_text(path) as fh:
        for number, text in enumerate(fh, start=1):
            if number >= header_line:
                break
            match = _PHASE_DIRECTIVE.fullmatch(text.strip())
            if match is None:
                continue
            index = int(match.group(1))
            if index in out:
                raise SinsInputError(
                    f"{path}:{number}: phase {index} is described twice (first on line {out[index].line})"
                )
            out[index] = _parse_directive(path, number, index, match.group(2))
    return out


def _parse_directive(path: Path, number: int, index: int, body: str) -> _Directive:
    where = f"{path}:{number}: phase {index}"
    fields: dict[str, str] = {}
    for part in body.split(";"):
        if not part.strip():
            continue
        key, sep, value = part.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or key not in ("name", "kind", "angle_rad"):
            raise SinsInputError(
                f"{where}: expected 'key=value' fields separated by ';' with keys name, kind, angle_rad, "
                f"found {part.strip()!r}"
            )
        if key in fields:
            raise SinsInputError(f"{where}: field {key!r} appears twice")
        fields[key] = value
    name = None
    if "name" in fields:
        try:
            name = urllib.parse.unquote(fields["name"], errors="strict")
        except UnicodeDecodeError:
            raise SinsInputError(f"{where}: name {fields['name']!r} has a bad %-escape") from None
    kind = fields.get("kind")
    if kind is not None and kind not in PHASE_KINDS:
        raise SinsInputError(f"{where}: kind {kind!r} is not one of {', '.join(PHASE_KINDS)}")
    angle: tuple[float, float, float] | None = None
    if "angle_rad" in fields:
        cells = fields["angle_rad"].split(",")
        try:
            if len(cells) != 3 or any("_" in c for c in cells):
                raise ValueError
            a, b, c = (float(x) for x in cells)
        except ValueError:
            raise SinsInputError(
                f"{where}: angle_rad {fields['angle_rad']!r} is not three comma-separated numbers"
            ) from None
        if not np.isfinite([a, b, c]).all():
            raise SinsInputError(f"{where}: angle_rad {fields['angle_rad']!r} is not finite")
        angle = (a, b, c)
    return _Directive(line=number, name=name, kind=kind, angle_rad=angle)


def _phases_from_column(table: Table, directives: dict[int, _Directive]) -> tuple[RigPhase, ...]:
    """Phases from the ``phase`` column (validated) and the directives, in time order."""
    path, header_line = table.path, table.first_data_line - 1
    p = table.column("phase")
    bad = (p != np.floor(p)) | (p < -1) | (p > np.iinfo(np.int32).max)
    if bad.any():
        r = int(np.argmax(bad))
        raise SinsInputError(
            f"{path}:{line_of_row(path, header_line, r)}: column 'phase': {format_number(p[r])} is not a "
            "phase index (an integer >= -1; -1 marks a row outside every phase)"
        )
    index = p.astype(np.int64)
    # Runs of equal values; a value that starts a second run is a phase that is not contiguous.
    starts = np.flatnonzero(np.r_[True, index[1:] != index[:-1]])
    ends = np.r_[starts[1:], len(index)]
    runs: dict[int, tuple[int, int]] = {}  # phase index -> its rows start:stop
    for row, end in zip(starts.tolist(), ends.tolist(), strict=True):
        value = int(index[row])
        if value in runs and value >= 0:
            raise SinsInputError(
                f"{path}:{line_of_row(path, header_line, row)}: column 'phase': phase {value} "
                f"resumes after other rows (its rows must be contiguous; it began on line "
                f"{line_of_row(path, header_line, runs[value][0])})"
            )
        runs.setdefault(value, (row, end))
    for value, directive in directives.items():
        if value not in runs:
            raise SinsInputError(
                f"{path}:{directive.line}: '# phase {value}' describes a phase with no rows in column 'phase'"
            )
    with np.errstate(over="ignore"):  # a reading beyond every range (1e300) is refused later, in one line
        ref_rate = np.linalg.norm(table.data[:, [table.columns.index(c) for c in REF_COLUMNS[:3]]], axis=1)
    phases = []
    for value, (start, stop) in sorted(runs.items(), key=lambda item: item[1]):
        if value < 0:
            continue
        given = directives.get(value, _Directive(0, None, None, None))
        kind = given.kind
        if kind is None:
            # NaN compares False, so a phase without a known reference rate is a rotation.
            kind = "static" if bool(np.all(ref_rate[start:stop] <= STATIC_RATE_TOL)) else "rotation"
        name = f"phase {value}" if given.name is None else given.name
        phases.append(RigPhase(name, start, stop, kind, given.angle_rad))
    return tuple(phases)


__all__ = [
    "PHASE_KINDS",
    "RECORDING_COLUMNS",
    "REF_COLUMNS",
    "STATIC_RATE_TOL",
    "check_recording_range",
    "is_rig_csv",
    "write_recording",
]
