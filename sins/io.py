"""The CSV files that cross the project's edge: IMU recordings and truth trajectories.

Formats (one header row, one row per sample, comma separated, ``#`` comment
lines allowed at the top):

* IMU, rate form: ``t, gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z``
  (s, rad/s, m/s²), instantaneous samples, body frame FRD;
* IMU, increment form: ``t, dtheta_x, dtheta_y, dtheta_z, dv_x, dv_y, dv_z``
  (s, rad, m/s), each row the integral over ``(t_prev, t]``; the first row's
  interval starts at the truth's first time;
* truth: ``t, lat, lon, alt, vn, ve, vd, roll, pitch, yaw`` (s, deg, deg, m,
  m/s NED, deg ZYX).

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
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

import numpy as np
from numpy.typing import NDArray

from sins import rotation
from sins.errors import SinsInputError
from sins.series import ImuIncrements, ImuRates, NavSeries

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
        return self.data[:, self.columns.index(name)]

    def has(self, name: str) -> bool:
        return name in self.columns


def read_table(path: str | os.PathLike[str], required: tuple[str, ...] = ()) -> Table:
    """Read a numeric CSV with a header; validate values and the time column.

    The fast path is pyarrow's multi-threaded CSV reader (correctly rounded,
    so values written by :func:`write_table` come back bit for bit); anything it
    cannot take goes through a strict Python parser that either reads the file
    (comment or blank lines in the body, say) or names the bad cell.

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
    data = _read_fast(path, header_line, columns)
    if data is None:
        data = _read_slow(path, header_line, columns)
    if len(data) == 0:
        raise SinsInputError(f"{path}: no data rows after the header")
    bad = ~np.isfinite(data)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise SinsInputError(
            f"{path}:{_line_of_row(path, header_line, int(r))}: column {columns[c]!r}: "
            f"non-finite value {_text(data[r, c])}"
        )
    if "t" in columns:
        t = data[:, columns.index("t")]
        dt = np.diff(t)
        if (dt <= 0).any():
            r = int(np.argmax(dt <= 0)) + 1
            raise SinsInputError(
                f"{path}:{_line_of_row(path, header_line, r)}: column 't': time {_text(t[r])} "
                f"does not increase (previous {_text(t[r - 1])})"
            )
    return Table(path=path, columns=columns, data=data, first_data_line=header_line + 1)


def _text(value: float) -> str:
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


def _read_fast(path: Path, header_line: int, columns: tuple[str, ...]) -> Array | None:
    """The data via pyarrow, or None when the file needs the careful parser."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    try:
        table = pacsv.read_csv(
            path,
            read_options=pacsv.ReadOptions(skip_rows=header_line - 1),
            convert_options=pacsv.ConvertOptions(
                column_types=dict.fromkeys(columns, pa.float64()), null_values=[], strings_can_be_null=False
            ),
        )
    except (pa.ArrowInvalid, pa.ArrowTypeError, UnicodeDecodeError, OSError):
        return None
    if tuple(table.column_names) != columns:
        return None
    data = np.empty((table.num_rows, len(columns)))
    for i, column in enumerate(table.columns):
        data[:, i] = column.to_numpy()
    return data


def _read_slow(path: Path, header_line: int, columns: tuple[str, ...]) -> Array:
    """Parse row by row; raise naming the first bad cell."""
    rows: list[list[float]] = []
    for number, text in _data_lines(path, header_line):
        cells = text.rstrip("\r\n").split(",")
        if len(cells) != len(columns):
            raise SinsInputError(f"{path}:{number}: expected {len(columns)} values, found {len(cells)}")
        row = []
        for name, cell in zip(columns, cells, strict=True):
            try:
                if "_" in cell:  # Python's float() takes 1_000; other tools do not
                    raise ValueError
                row.append(float(cell))
            except ValueError:
                raise SinsInputError(
                    f"{path}:{number}: column {name!r}: not a number: {cell.strip()!r}"
                ) from None
        rows.append(row)
    return np.array(rows, dtype=float).reshape(len(rows), len(columns))


def _line_of_row(path: Path, header_line: int, row: int) -> int:
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


def rates_from_table(table: Table) -> ImuRates:
    idx = [table.columns.index(c) for c in RATE_COLUMNS]
    d = table.data[:, idx]
    return ImuRates(t=d[:, 0].copy(), omega_ib_b=d[:, 1:4].copy(), f_ib_b=d[:, 4:7].copy())


def increments_from_table(table: Table, t_start: float) -> ImuIncrements:
    """Increment-form samples whose first interval starts at ``t_start``."""
    idx = [table.columns.index(c) for c in INCREMENT_COLUMNS]
    d = table.data[:, idx]
    if not t_start < d[0, 0]:
        raise SinsInputError(
            f"{table.path}:{_line_of_row(table.path, table.first_data_line - 1, 0)}: column 't': first "
            f"increment ends at {_text(d[0, 0])} s, not after the start time {_text(t_start)} s"
        )
    return ImuIncrements(
        t=np.concatenate([[t_start], d[:, 0]]), dtheta_b=d[:, 1:4].copy(), dv_b=d[:, 4:7].copy()
    )


def write_imu(
    path: str | os.PathLike[str],
    imu: ImuRates | ImuIncrements,
    extra: dict[str, Array] | None = None,
    comment: str = "",
) -> None:
    """Write an IMU recording (its form follows the type), atomically.

    For increments the rows are the intervals' end times ``imu.t[1:]``.
    ``extra`` adds columns (``temp``, ``ref_gyro_x`` …), one value per row.
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
    write_table(path, cols, np.column_stack(data), comment)


# --------------------------------------------------------------------------- truth files


def read_truth(path: str | os.PathLike[str]) -> NavSeries:
    """Read a truth trajectory CSV into a :class:`NavSeries` (SI units, radians)."""
    table = read_table(path, required=TRUTH_COLUMNS)
    d = table.data[:, [table.columns.index(c) for c in TRUTH_COLUMNS]]
    lat = np.radians(d[:, 1])
    if (np.abs(lat) > np.pi / 2).any():
        r = int(np.argmax(np.abs(lat) > np.pi / 2))
        line = _line_of_row(table.path, table.first_data_line - 1, r)
        raise SinsInputError(
            f"{table.path}:{line}: column 'lat': {_text(d[r, 1])} is outside [-90, 90] degrees"
        )
    q = rotation.quat_from_euler(np.radians(d[:, 7]), np.radians(d[:, 8]), np.radians(d[:, 9]))
    return NavSeries(
        t=d[:, 0].copy(), lat=lat, lon=np.radians(d[:, 2]), h=d[:, 3].copy(), v_n=d[:, 4:7].copy(), q_nb=q
    )


def write_truth(path: str | os.PathLike[str], truth: NavSeries, comment: str = "") -> None:
    """Write a truth trajectory CSV (degrees for angles), atomically."""
    roll, pitch, yaw = truth.euler()
    data = np.column_stack(
        [truth.t, np.degrees(truth.lat), np.degrees(truth.lon), truth.h, truth.v_n,
         np.degrees(roll), np.degrees(pitch), np.degrees(yaw)]
    )  # fmt: skip
    write_table(path, list(TRUTH_COLUMNS), data, comment)


# --------------------------------------------------------------------------- writing


def write_table(path: str | os.PathLike[str], columns: list[str], data: Array, comment: str = "") -> None:
    """Write a CSV with a header, 17 significant digits, to a temporary name then rename."""
    header = "".join(f"# {line}\n" for line in comment.splitlines()) + ",".join(columns)
    with _atomic(path) as fh:
        np.savetxt(fh, data, delimiter=",", fmt="%.17g", header=header, comments="")


def write_json(path: str | os.PathLike[str], obj: Any) -> None:
    """Write JSON (indented, keys in insertion order) to a temporary name then rename."""
    with _atomic(path) as fh:
        json.dump(obj, fh, indent=2, allow_nan=True)
        fh.write("\n")


@contextlib.contextmanager
def _atomic(path: str | os.PathLike[str]) -> Iterator[TextIO]:
    path = Path(path)
    directory = path.parent
    if not directory.is_dir():
        raise SinsInputError(f"{path}: directory {directory} does not exist")
    if path.is_dir():
        raise SinsInputError(f"{path}: is a directory, expected a file name to write")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            yield fh
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
