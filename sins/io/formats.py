"""The CSV files that cross the project's edge: IMU recordings and truth trajectories.

Formats (one header row, one row per sample, comma separated, ``#`` comment
lines allowed at the top):

* IMU, rate form: ``t, gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z``
  (s, rad/s, m/s²), instantaneous samples, body frame FRD;
* IMU, increment form: ``t, dtheta_x, dtheta_y, dtheta_z, dv_x, dv_y, dv_z``
  (s, rad, m/s), each row the integral over ``(t_prev, t]``; the first row's
  interval starts at the truth's first time;
* truth: ``t, lat, lon, alt, vn, ve, vd, roll, pitch, yaw`` (s, deg, deg, m,
  m/s NED, deg ZYX);
* rig recording (calibration data): the rate form plus ``ref_gyro_x`` …
  ``ref_accel_z`` (the rig's reference, NaN where it has none), optional
  ``temp`` and ``phase`` columns, ``# phase N:`` lines naming the phases; see
  :func:`read_recording`.

Extra columns (``temp``, ``ref_*``) are kept in the returned table. Readers
refuse a file with one line naming the file, line and column: a missing
required column, a non-numeric or non-finite value, non-increasing time, or a
header mixing the two IMU forms. Writers write to a temporary name and rename,
so a failed write never leaves a half-written file. Values are written with 17
significant digits, which round-trips every float64 exactly.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import tempfile
import urllib.parse
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple, TextIO

import numpy as np
from numpy.typing import NDArray

from sins.errors import SinsInputError
from sins.io import documents
from sins.nav import rotation
from sins.series import CalibrationData, ImuIncrements, ImuRates, NavSeries, RigPhase

Array = NDArray[np.float64]

RATE_COLUMNS = ("t", "gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
INCREMENT_COLUMNS = ("t", "dtheta_x", "dtheta_y", "dtheta_z", "dv_x", "dv_y", "dv_z")
TRUTH_COLUMNS = ("t", "lat", "lon", "alt", "vn", "ve", "vd", "roll", "pitch", "yaw")


@dataclass(frozen=True)
class Table:
    """A numeric CSV table: column names and a (rows, columns) float array.

    ``first_data_line`` is the 1-based line number after the header, for messages.
    """

    path: Path
    columns: tuple[str, ...]
    data: Array
    first_data_line: int

    def column(self, name: str) -> Array:
        """The values (rows,) of column ``name``."""
        return self.data[:, self.columns.index(name)]

    def has(self, name: str) -> bool:
        """Whether the header has column ``name``."""
        return name in self.columns


def read_table(
    path: str | os.PathLike[str],
    required: tuple[str, ...] = (),
    *,
    select: tuple[str, ...] | None = None,
    nan_ok: tuple[str, ...] = (),
) -> Table:
    """Read a numeric CSV with a header; validate values and the time column.

    The fast path is pyarrow's multi-threaded CSV reader (correctly rounded,
    so values written by :func:`write_table` come back bit for bit); anything it
    cannot take goes through a strict Python parser that either reads the file
    (comment or blank lines in the body, say) or names the bad cell.

    Parameters
    ----------
    path : the CSV file
    required : columns the header must have
    select : parse only these columns, in this order (each must be in the
        header); the others are skipped unparsed, so they may hold text.
        ``None`` (the default) parses every column.
    nan_ok : columns where NaN is a value (a rig's missing reference, say);
        ±inf is still refused there, and NaN everywhere else.

    Raises
    ------
    SinsInputError
        one line naming the file, and the line and column where it applies.
    """
    path = Path(path)
    header_line, columns = _read_header(path)
    if len(set(columns)) != len(columns):
        dup = next(c for c in columns if columns.count(c) > 1)
        raise SinsInputError(f"{path}:{header_line}: column {dup!r} appears twice in the header")
    for name in required:
        if name not in columns:
            raise SinsInputError(
                f"{path}:{header_line}: missing required column {name!r} (header has {', '.join(columns)})"
            )
    wanted = columns if select is None else tuple(select)
    for name in wanted:
        if name not in columns:
            raise SinsInputError(
                f"{path}:{header_line}: missing required column {name!r} (header has {', '.join(columns)})"
            )
    data = _read_fast(path, header_line, columns, wanted)
    if data is None:
        data = _read_slow(path, header_line, columns, wanted)
    if len(data) == 0:
        raise SinsInputError(f"{path}: no data rows after the header")
    columns = wanted
    bad = ~np.isfinite(data)
    for name in nan_ok:
        if name in columns:
            c = columns.index(name)
            bad[:, c] = np.isinf(data[:, c])
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise SinsInputError(
            f"{path}:{line_of_row(path, header_line, int(r))}: column {columns[c]!r}: "
            f"non-finite value {format_number(data[r, c])}"
        )
    if "t" in columns:
        t = data[:, columns.index("t")]
        dt = np.diff(t)
        if (dt <= 0).any():
            r = int(np.argmax(dt <= 0)) + 1
            raise SinsInputError(
                f"{path}:{line_of_row(path, header_line, r)}: column 't': time {format_number(t[r])} "
                f"does not increase (previous {format_number(t[r - 1])})"
            )
    return Table(path=path, columns=columns, data=data, first_data_line=header_line + 1)


def format_number(value: float) -> str:
    """A float as text that reads back exactly (``repr``), for messages."""
    return repr(float(value))


def _open_text(path: Path) -> TextIO:
    try:
        return open(path, encoding="utf-8-sig")  # tolerate the byte-order mark spreadsheets write
    except FileNotFoundError:
        raise SinsInputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise SinsInputError(f"{path}: is a directory, expected a CSV file") from None
    except OSError as exc:
        raise SinsInputError(f"{path}: cannot read: {exc.strerror or exc}") from None


def _data_lines(path: Path, header_line: int) -> Iterator[tuple[int, str]]:
    """``(line number, text)`` of each data row (not blank, not a comment) after the header."""
    with _open_text(path) as fh:
        try:
            for number, text in enumerate(fh, start=1):
                if number > header_line and text.strip() and not text.lstrip().startswith("#"):
                    yield number, text
        except UnicodeDecodeError as exc:
            raise SinsInputError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None


def _read_header(path: Path) -> tuple[int, tuple[str, ...]]:
    """1-based line number of the header (after blank and ``#`` lines) and its column names."""
    with _open_text(path) as fh:
        try:
            for number, text in enumerate(fh, start=1):
                if text.strip() and not text.lstrip().startswith("#"):
                    return number, tuple(c.strip() for c in text.split(","))
        except UnicodeDecodeError as exc:
            raise SinsInputError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    raise SinsInputError(f"{path}: empty file, expected a header row")


def read_columns(path: str | os.PathLike[str]) -> tuple[str, ...]:
    """The column names of a CSV file's header, without reading its rows."""
    return _read_header(Path(path))[1]


def _read_fast(
    path: Path, header_line: int, columns: tuple[str, ...], wanted: tuple[str, ...] | None = None
) -> Array | None:
    """The ``wanted`` columns (default all) via pyarrow, or None when the file needs the careful parser."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    wanted = columns if wanted is None else wanted
    try:
        table = pacsv.read_csv(
            path,
            read_options=pacsv.ReadOptions(skip_rows=header_line - 1),
            convert_options=pacsv.ConvertOptions(
                column_types=dict.fromkeys(wanted, pa.float64()),
                null_values=[],
                strings_can_be_null=False,
                # Only when selecting: pyarrow then finds the columns by the header it parsed; one it
                # parsed differently from _read_header raises ArrowKeyError (the careful parser then reads).
                include_columns=list(wanted) if wanted != columns else None,
            ),
        )
    except (pa.ArrowInvalid, pa.ArrowTypeError, pa.ArrowKeyError, UnicodeDecodeError, OSError):
        return None
    if tuple(table.column_names) != wanted:
        return None
    data = np.empty((table.num_rows, len(wanted)))
    for i, column in enumerate(table.columns):
        data[:, i] = column.to_numpy()
    del table, column
    # pyarrow's allocator keeps what the parse took for its next table (300 MB after a 3.57 M-row rig
    # recording, beside the 400 MB of values): the values are numpy's now, so give it back.
    pa.default_memory_pool().release_unused()
    return data


def _read_slow(
    path: Path, header_line: int, columns: tuple[str, ...], wanted: tuple[str, ...] | None = None
) -> Array:
    """Parse the ``wanted`` columns (default all) row by row; raise naming the first bad cell."""
    wanted = columns if wanted is None else wanted
    picks = [columns.index(name) for name in wanted]
    rows: list[list[float]] = []
    for number, text in _data_lines(path, header_line):
        cells = text.rstrip("\r\n").split(",")
        if len(cells) != len(columns):
            raise SinsInputError(f"{path}:{number}: expected {len(columns)} values, found {len(cells)}")
        row = []
        for name, cell in zip(wanted, [cells[i] for i in picks], strict=True):
            try:
                if "_" in cell:  # Python's float() takes 1_000; other tools do not
                    raise ValueError
                row.append(float(cell))
            except ValueError:
                raise SinsInputError(
                    f"{path}:{number}: column {name!r}: not a number: {cell.strip()!r}"
                ) from None
        rows.append(row)
    return np.array(rows, dtype=float).reshape(len(rows), len(wanted))


def line_of_row(path: Path, header_line: int, row: int) -> int:
    """The file line holding data row ``row`` (0-based), counting blank and comment lines."""
    for i, (number, _) in enumerate(_data_lines(path, header_line)):
        if i == row:
            return number
    return header_line + 1 + row


# --------------------------------------------------------------------------- IMU files


def imu_form(columns: tuple[str, ...], path: Path, header_line: int = 1) -> str:
    """``"rate"`` or ``"increment"`` from a header; refuse mixed or missing forms."""
    has_rate = [c for c in RATE_COLUMNS[1:] if c in columns]
    has_inc = [c for c in INCREMENT_COLUMNS[1:] if c in columns]
    if has_rate and has_inc:
        raise SinsInputError(
            f"{path}:{header_line}: mixes rate columns ({', '.join(has_rate)}) "
            f"with increment columns ({', '.join(has_inc)}); use one form"
        )
    if not has_rate and not has_inc:
        raise SinsInputError(
            f"{path}:{header_line}: not an IMU file: expected columns {', '.join(RATE_COLUMNS)} "
            f"or {', '.join(INCREMENT_COLUMNS)}"
        )
    return "rate" if has_rate else "increment"


def read_imu(path: str | os.PathLike[str]) -> tuple[ImuRates | ImuIncrements, Table]:
    """Read an IMU recording in either form.

    Returns the samples and the whole table (for extra columns such as
    ``temp`` or ``ref_*``). For the increment form the returned
    ``ImuIncrements.t`` has the rows' end times only, with ``t[0]`` set to
    ``t_row0 - (t_row1 - t_row0)``; callers that know the start time (the
    truth's first time) use :func:`increments_from_table` instead.
    """
    path = Path(path)
    header_line, header = _read_header(path)
    form = imu_form(header, path, header_line=header_line)
    cols = RATE_COLUMNS if form == "rate" else INCREMENT_COLUMNS
    table = read_table(path, required=cols)
    if form == "rate":
        return rates_from_table(table), table
    t = table.column("t")
    start = t[0] - (t[1] - t[0]) if len(t) > 1 else t[0] - 1.0
    return increments_from_table(table, start), table


# --------------------------------------------------------------------------- physical ranges

#: The largest time stamp, s: Unix time (1.7e9 s now) fits, and stamps keep 2 µs resolution.
MAX_TIME_S = 1e10
#: The fastest angular rate an IMU file may hold, rad/s (573,000 °/s; the fastest gyros read 4000 °/s,
#: a spinning shell 100,000 °/s). Beyond it the integrator's attitude update loses meaning.
MAX_RATE_RADPS = 1e4
#: The largest specific force, m/s² (102,000 g; a gun launch reaches 50,000 g).
MAX_FORCE_MPS2 = 1e6
#: Truth files: the largest speed (m/s), the height range (m), the largest angle (degrees; yaw and
#: longitude may be unwrapped over many turns).
MAX_TRUTH_SPEED_MPS = 1e5
TRUTH_ALT_M = (-1e5, 1e8)
MAX_ANGLE_DEG = 1e6
#: Temperatures a file may give, °C: above absolute zero, below any IMU's destruction.
TEMP_DEGC = (-273.15, 1000.0)


def check_range(
    table: Table, column: str, values: Array, low: float, high: float, what: str, unit: str
) -> None:
    """Refuse the first value of ``values`` (one per row of ``table``, NaN passes) outside
    ``[low, high]``, naming the file, line and ``column``; ``what`` says what the value is."""
    outside = (values < low) | (values > high)
    if outside.any():
        r = int(np.argmax(outside))
        line = line_of_row(table.path, table.first_data_line - 1, r)
        raise SinsInputError(
            f"{table.path}:{line}: column {column!r}: {what} {format_number(values[r])} {unit} is outside "
            f"[{low:g}, {high:g}] {unit}, beyond any vehicle or sensor this simulator models"
        )


def _check_time(table: Table) -> None:
    check_range(table, "t", table.column("t"), -MAX_TIME_S, MAX_TIME_S, "time", "s")


def _check_readings(table: Table, names: tuple[str, ...], dt: Array | None = None) -> None:
    """Gyro columns within :data:`MAX_RATE_RADPS`, accelerometer ones within :data:`MAX_FORCE_MPS2`
    (increments divided by their interval ``dt``); a ``temp`` column within :data:`TEMP_DEGC`."""
    for name in names:
        rate = name.startswith(("gyro", "dtheta", "ref_gyro"))
        limit = MAX_RATE_RADPS if rate else MAX_FORCE_MPS2
        values = table.column(name) if dt is None else table.column(name) / dt
        what = ("rate" if rate else "specific force") + (" (increment / interval)" if dt is not None else "")
        check_range(table, name, values, -limit, limit, what, "rad/s" if rate else "m/s²")
    if table.has("temp"):
        check_range(table, "temp", table.column("temp"), *TEMP_DEGC, "temperature", "°C")


def rates_from_table(table: Table) -> ImuRates:
    """Rate-form samples (s, rad/s, m/s², body frame) from a table's :data:`RATE_COLUMNS`.

    Raises
    ------
    SinsInputError
        a time beyond :data:`MAX_TIME_S`, a rate beyond :data:`MAX_RATE_RADPS`, a specific force
        beyond :data:`MAX_FORCE_MPS2` (naming the line and column).
    """
    _check_time(table)
    _check_readings(table, RATE_COLUMNS[1:])
    idx = [table.columns.index(c) for c in RATE_COLUMNS]
    # Each field taken from the table itself: a (rows, 7) copy first held 560 MB more at 10 M rows.
    data = table.data
    return ImuRates(t=data[:, idx[0]].copy(), omega_ib_b=data[:, idx[1:4]], f_ib_b=data[:, idx[4:7]])


def increments_from_table(table: Table, t_start: float) -> ImuIncrements:
    """Increment-form samples whose first interval starts at ``t_start``.

    Raises
    ------
    SinsInputError
        the first row does not end after ``t_start``; a time beyond :data:`MAX_TIME_S`; an increment
        whose mean rate or specific force over its interval is beyond :data:`MAX_RATE_RADPS` or
        :data:`MAX_FORCE_MPS2` (naming the line and column).
    """
    idx = [table.columns.index(c) for c in INCREMENT_COLUMNS]
    d = table.data[:, idx]
    if not t_start < d[0, 0]:
        line = line_of_row(table.path, table.first_data_line - 1, 0)
        raise SinsInputError(
            f"{table.path}:{line}: column 't': first increment ends at {format_number(d[0, 0])} s, "
            f"not after the start time {format_number(t_start)} s"
        )
    _check_time(table)
    _check_readings(table, INCREMENT_COLUMNS[1:], np.diff(np.concatenate([[t_start], d[:, 0]])))
    return ImuIncrements(
        t=np.concatenate([[t_start], d[:, 0]]), dtheta_b=d[:, 1:4].copy(), dv_b=d[:, 4:7].copy()
    )


def write_imu(
    path: str | os.PathLike[str],
    imu: ImuRates | ImuIncrements,
    extra: dict[str, Array] | None = None,
    comment: str = "",
    progress: Callable[[int, int], None] | None = None,
) -> None:
    """Write an IMU recording (its form follows the type), atomically.

    For increments the rows are the intervals' end times ``imu.t[1:]``.
    ``extra`` adds columns (``temp``, ``ref_gyro_x`` …), one value per row; ``progress`` is called as
    ``progress(rows_written, rows)``.
    """
    if isinstance(imu, ImuRates):
        cols = list(RATE_COLUMNS)
        data = [imu.t, *imu.omega_ib_b.T, *imu.f_ib_b.T]
    else:
        cols = list(INCREMENT_COLUMNS)
        data = [imu.t[1:], *imu.dtheta_b.T, *imu.dv_b.T]
    for name, values in (extra or {}).items():
        cols.append(name)
        data.append(np.asarray(values, dtype=float))
    write_table(path, cols, np.column_stack(data), comment, progress)


# --------------------------------------------------------------------------- truth files


def read_truth(path: str | os.PathLike[str]) -> NavSeries:
    """Read a truth trajectory CSV into a :class:`NavSeries` (SI units, radians).

    Raises
    ------
    SinsInputError
        as :func:`read_table`, and for a latitude outside [-90, 90]°, a time beyond
        :data:`MAX_TIME_S`, a height outside :data:`TRUTH_ALT_M`, a velocity component beyond
        :data:`MAX_TRUTH_SPEED_MPS` or an angle beyond :data:`MAX_ANGLE_DEG` (naming line and column).
    """
    table = read_table(path, required=TRUTH_COLUMNS)
    _check_time(table)
    check_range(table, "alt", table.column("alt"), *TRUTH_ALT_M, "height", "m")
    for name in ("vn", "ve", "vd"):
        check_range(
            table, name, table.column(name), -MAX_TRUTH_SPEED_MPS, MAX_TRUTH_SPEED_MPS, "velocity", "m/s"
        )
    for name in ("lon", "roll", "pitch", "yaw"):
        check_range(table, name, table.column(name), -MAX_ANGLE_DEG, MAX_ANGLE_DEG, "angle", "°")
    d = table.data[:, [table.columns.index(c) for c in TRUTH_COLUMNS]]
    lat = np.radians(d[:, 1])
    if (np.abs(lat) > np.pi / 2).any():
        r = int(np.argmax(np.abs(lat) > np.pi / 2))
        line = line_of_row(table.path, table.first_data_line - 1, r)
        raise SinsInputError(
            f"{table.path}:{line}: column 'lat': {format_number(d[r, 1])} is outside [-90, 90] degrees"
        )
    q = rotation.quat_from_euler(np.radians(d[:, 7]), np.radians(d[:, 8]), np.radians(d[:, 9]))
    return NavSeries(
        t=d[:, 0].copy(), lat=lat, lon=np.radians(d[:, 2]), h=d[:, 3].copy(), v_n=d[:, 4:7].copy(), q_nb=q
    )


def write_truth(
    path: str | os.PathLike[str],
    truth: NavSeries,
    comment: str = "",
    progress: Callable[[int, int], None] | None = None,
) -> None:
    """Write a truth trajectory CSV (degrees for angles), atomically; ``progress`` as :func:`write_table`."""
    roll, pitch, yaw = truth.euler()
    data = np.column_stack(
        [truth.t, np.degrees(truth.lat), np.degrees(truth.lon), truth.h, truth.v_n,
         np.degrees(roll), np.degrees(pitch), np.degrees(yaw)]
    )  # fmt: skip
    write_table(path, list(TRUTH_COLUMNS), data, comment, progress)


# --------------------------------------------------------------------------- writing


#: Rows formatted per call when writing a table: progress every ~0.5 s, memory for the text bounded.
WRITE_BLOCK_ROWS = 100_000


def write_table(
    path: str | os.PathLike[str],
    columns: list[str],
    data: Array,
    comment: str = "",
    progress: Callable[[int, int], None] | None = None,
) -> None:
    """Write a CSV with a header, 17 significant digits, to a temporary name then rename.

    ``progress(rows_written, rows)`` is called after each block of :data:`WRITE_BLOCK_ROWS` rows.
    """
    header = "".join(f"# {line}\n" for line in comment.splitlines()) + ",".join(columns)
    n = len(data)
    with _atomic(path) as fh:
        fh.write(header + "\n")
        for start in range(0, n, WRITE_BLOCK_ROWS):
            np.savetxt(fh, data[start : start + WRITE_BLOCK_ROWS], delimiter=",", fmt="%.17g")
            if progress is not None:
                progress(min(start + WRITE_BLOCK_ROWS, n), n)


def write_json(path: str | os.PathLike[str], obj: Any) -> None:
    """Write JSON (indented, keys in insertion order) to a temporary name then rename."""
    with _atomic(path) as fh:
        json.dump(obj, fh, indent=2, allow_nan=True)
        fh.write("\n")


def read_json_document(
    path: str | os.PathLike[str], what: str, format_name: str, missing_hint: str = ""
) -> dict[str, Any]:
    """A JSON object whose ``"format"`` is ``format_name``; one-line errors for anything else.

    ``what`` names the kind of file in messages ("model file", "baseline");
    ``missing_hint`` is added when the file does not exist.
    """
    path = Path(path)
    doc = documents.read_json(path, what, missing_hint)  # the one reader: one line whatever the bytes
    if not isinstance(doc, dict) or doc.get("format") != format_name:
        raise SinsInputError(f'{path}: not a sins {what} (no "format": "{format_name}")')
    return doc


#: The process's umask, read once at import (reading it means setting it, which threads would race).
_UMASK = os.umask(0o022)
os.umask(_UMASK)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary file beside ``path`` to write, renamed to ``path`` when the block ends without an
    error and removed otherwise: a reader never sees half a file, and an interrupted run leaves none.

    The file gets the permissions a plain ``open`` would give it (``0o666`` less the umask), not the
    owner-only mode of a temporary file. An ``OSError`` while writing (a full disk, a folder not
    writable) is raised again with ``path`` as its file name, not the temporary one.
    """
    path = Path(path)
    directory = path.parent
    if not directory.is_dir():
        raise SinsInputError(f"{path}: directory {directory} does not exist")
    if path.is_dir():
        raise SinsInputError(f"{path}: is a directory, expected a file name to write")
    try:
        fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_UMASK)
        os.replace(tmp, path)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError):  # a full disk, say: the target named, not the temporary file
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
        raise


@contextlib.contextmanager
def _atomic(path: str | os.PathLike[str]) -> Iterator[TextIO]:
    with atomic_path(path) as tmp, tmp.open("w", encoding="utf-8") as fh:
        yield fh


# --------------------------------------------------------------------------- rig recordings
#
# A calibration rig's recording: the IMU's readings beside the rig's reference, in rate form.
#
#     t, gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z,                  s, rad/s, m/s²
#     ref_gyro_x, ref_gyro_y, ref_gyro_z, ref_accel_x, ref_accel_y, ref_accel_z, rad/s, m/s²
#     [temp]   °C
#     [phase]  integer phase index per row (-1: outside any phase); the rows of one phase are contiguous
#
# in any column order, other columns ignored (not even parsed). The ref_ columns alone may hold NaN:
# no per-sample reference there (a hand-turned rotation, say). The phases' names and kinds, and a
# rotation's known angle, are comment lines at the top, one per phase, written after any free comment:
#
#     # phase 3: name=rate +z 100 dps; kind=rotation; angle_rad=0.0,0.0,-6.283185307179586
#
# ``N`` is the value in the phase column; fields are ``key=value`` separated by ``;``, each optional
# (name defaults to "phase N"; kind to "static" when the reference rate is known and ~0 through the
# phase, else "rotation"); angle_rad is three repr() floats, rad, body axes. In the name, ``%``, ``;``,
# ``"``, unprintable characters and leading/trailing white space are percent-encoded as UTF-8 (``%3B``
# for ``;``), so any name survives the round trip. A top comment line of the form ``# phase N: ...`` is
# always such a directive.

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
    """Write a rig recording (the format above), 17 significant digits, atomically.

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
    Every float comes back bit for bit from :func:`read_recording`, except that a NaN comes back as
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


def read_recording(path: str | os.PathLike[str]) -> CalibrationData:
    """Read a rig recording (the format above) into :class:`~sins.series.CalibrationData`.

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
    header_line, header = _read_header(path)
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
    """Refuse a recording read by :func:`read_recording` whose readings or references lie beyond the
    physical ranges of IMU files (:data:`MAX_RATE_RADPS`, :data:`MAX_FORCE_MPS2`, :data:`TEMP_DEGC`,
    :data:`MAX_TIME_S`), naming the line and column.

    :func:`read_recording` itself reads any finite value back (the format round-trips every float);
    the commands that compute with a recording (``sins fit``, ``evaluate``, ``gap``) call this.
    """
    path = Path(path)
    header_line, _ = _read_header(path)
    columns = ("t", *RECORDING_COLUMNS[1:], *(("temp",) if data.temp is not None else ()))
    values = np.column_stack([data.t, data.gyro, data.accel, data.ref_gyro, data.ref_accel,
                              *((data.temp,) if data.temp is not None else ())])  # fmt: skip
    table = Table(path=path, columns=columns, data=values, first_data_line=header_line + 1)
    _check_time(table)
    _check_readings(table, RECORDING_COLUMNS[1:])


def _check_recording(data: CalibrationData) -> None:
    """Refuse (ValueError) what :func:`read_recording` would refuse, before anything is written."""
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
    with _open_text(path) as fh:
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
