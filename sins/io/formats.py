"""The CSV files that cross the project's edge: IMU recordings and truth trajectories.

Formats (one header row, one row per sample, comma separated, ``#`` comment
lines allowed at the top):

* IMU, rate form: ``t, gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z``
  (s, rad/s, m/s²), instantaneous samples, body frame FRD;
* IMU, increment form: ``t, dtheta_x, dtheta_y, dtheta_z, dv_x, dv_y, dv_z``
  (s, rad, m/s), each row the integral over ``(t_prev, t]``; the first row's
  interval starts at the truth's first time;
* truth: ``t, lat_deg, lon_deg, h_m, vn, ve, vd, roll_deg, pitch_deg, yaw_deg``
  (s, deg, deg, m above the WGS84 ellipsoid, m/s NED, deg ZYX); files with the
  names before (``lat, lon, alt, roll, pitch, yaw``) are read as well;
* rig recording (calibration data): the rate form plus ``ref_gyro_x`` …
  ``ref_accel_z`` (the rig's reference, NaN where it has none), optional
  ``temp`` and ``phase`` columns, ``# phase N:`` lines naming the phases; see
  :mod:`sins.io.rig`.

Extra columns (``temp``, ``ref_*``) are kept in the returned table. Readers
refuse a file with one line naming the file, line and column: a missing
required column, a non-numeric or non-finite value, non-increasing time, or a
header mixing the two IMU forms. Writers write to a temporary name and rename,
so a failed write never leaves a half-written file. Values are written with 17
significant digits, which round-trips every float64 exactly.

This module holds the IMU and truth forms and the physical ranges their values must keep; the tables
under them are :mod:`sins.io.tables`, rig recordings :mod:`sins.io.rig`, atomic writes
:mod:`sins.io.atomic` and JSON files :mod:`sins.io.json_files` (the names that moved there are still
importable from here).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sins.core import rotation
from sins.core.series import ImuIncrements, ImuRates, NavSeries
from sins.errors import LateStartError, SinsInputError

# These lived here before the tables, atomic writes and JSON files had modules of their own.
from sins.io.atomic import atomic_path as atomic_path
from sins.io.json_files import read_json_document as read_json_document
from sins.io.json_files import write_json as write_json
from sins.io.tables import WRITE_BLOCK_ROWS as WRITE_BLOCK_ROWS
from sins.io.tables import Table, format_number, line_of_row, read_header, read_table, write_table
from sins.io.tables import first_not_increasing as first_not_increasing
from sins.io.tables import read_columns as read_columns

Array = NDArray[np.float64]

RATE_COLUMNS = ("t", "gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
INCREMENT_COLUMNS = ("t", "dtheta_x", "dtheta_y", "dtheta_z", "dv_x", "dv_y", "dv_z")
TRUTH_COLUMNS = ("t", "lat_deg", "lon_deg", "h_m", "vn", "ve", "vd", "roll_deg", "pitch_deg", "yaw_deg")
#: The truth columns' names before they carried their units (issue 34), still read: each column is read
#: by its name in :data:`TRUTH_COLUMNS` or, where the header lacks it, by its name here.
TRUTH_COLUMNS_UNSUFFIXED = ("t", "lat", "lon", "alt", "vn", "ve", "vd", "roll", "pitch", "yaw")


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


def _read_imu(path: str | os.PathLike[str]) -> tuple[ImuRates | ImuIncrements, Table]:
    """Read an IMU recording in either form.

    Returns the samples and the whole table (for extra columns such as
    ``temp`` or ``ref_*``). For the increment form the returned
    ``ImuIncrements.t`` has the rows' end times only, with ``t[0]`` set to
    ``t_row0 - (t_row1 - t_row0)``; callers that know the start time (the
    truth's first time) use :func:`increments_from_table` instead.
    """
    path = Path(path)
    header_line, header = read_header(path)
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
#: The largest reference position and speed taken as physical (a room frame: 1000 km, 1000 m/s).
MAX_POSITION_M = 1e6
MAX_SPEED_MPS = 1e3
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


def first_beyond(values: Array, limit: float) -> tuple[int, int] | None:
    """The row and column of the first value of ``values`` (n, k) beyond ``±limit``, or None: what a
    reader's refusal names (the ``.npz`` reader's by row, a EuRoC reference's by line)."""
    bad = np.abs(values) > limit
    if not bad.any():
        return None
    r, c = (int(i) for i in np.argwhere(bad)[0])
    return r, c


def _check_time(table: Table) -> None:
    check_range(table, "t", table.column("t"), -MAX_TIME_S, MAX_TIME_S, "time", "s")


def check_readings(table: Table, names: tuple[str, ...], dt: Array | None = None) -> None:
    """Refuse an IMU table's first value out of range, naming its line and column: the time within
    :data:`MAX_TIME_S`; the gyro columns of ``names`` within :data:`MAX_RATE_RADPS`, the accelerometer
    ones within :data:`MAX_FORCE_MPS2` (increments divided by their interval ``dt``, s); a ``temp``
    column within :data:`TEMP_DEGC`.

    Raises
    ------
    SinsInputError
        naming the file, line and column of the first value out of range.
    """
    _check_time(table)
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
    check_readings(table, RATE_COLUMNS[1:])
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
        raise LateStartError(
            f"{table.path}:{line}: column 't': first increment ends at {format_number(d[0, 0])} s, "
            f"not after the start time {format_number(t_start)} s",
            float(d[0, 0]),
        )
    check_readings(table, INCREMENT_COLUMNS[1:], np.diff(np.concatenate([[t_start], d[:, 0]])))
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
    """Read a truth trajectory CSV (or a solution written as Parquet, ``sins integrate --out X.parquet``)
    into a :class:`NavSeries` (SI units, radians).

    Raises
    ------
    SinsInputError
        as :func:`read_table`, and for a latitude outside [-90, 90]°, a time beyond
        :data:`MAX_TIME_S`, a height outside :data:`TRUTH_ALT_M`, a velocity component beyond
        :data:`MAX_TRUTH_SPEED_MPS` or an angle beyond :data:`MAX_ANGLE_DEG` (naming line and column).
    """
    path = Path(path)
    header = read_table(path).columns if path.suffix.lower() == ".parquet" else read_header(path)[1]
    names = tuple(
        old if new not in header and old in header else new
        for new, old in zip(TRUTH_COLUMNS, TRUTH_COLUMNS_UNSUFFIXED, strict=True)
    )
    table = read_table(path, required=names)
    _check_time(table)
    check_range(table, names[3], table.column(names[3]), *TRUTH_ALT_M, "height", "m")
    for name in names[4:7]:
        check_range(
            table, name, table.column(name), -MAX_TRUTH_SPEED_MPS, MAX_TRUTH_SPEED_MPS, "velocity", "m/s"
        )
    for name in (names[2], *names[7:]):
        check_range(table, name, table.column(name), -MAX_ANGLE_DEG, MAX_ANGLE_DEG, "angle", "°")
    d = table.data[:, [table.columns.index(c) for c in names]]
    lat = np.radians(d[:, 1])
    if (np.abs(lat) > np.pi / 2).any():
        r = int(np.argmax(np.abs(lat) > np.pi / 2))
        line = line_of_row(table.path, table.first_data_line - 1, r)
        raise SinsInputError(
            f"{table.path}:{line}: column {names[1]!r}: {format_number(d[r, 1])} is outside [-90, 90] degrees"
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


__all__ = [
    "INCREMENT_COLUMNS",
    "MAX_ANGLE_DEG",
    "MAX_FORCE_MPS2",
    "MAX_POSITION_M",
    "MAX_RATE_RADPS",
    "MAX_SPEED_MPS",
    "MAX_TIME_S",
    "MAX_TRUTH_SPEED_MPS",
    "RATE_COLUMNS",
    "TEMP_DEGC",
    "TRUTH_ALT_M",
    "TRUTH_COLUMNS",
    "TRUTH_COLUMNS_UNSUFFIXED",
    "check_range",
    "check_readings",
    "first_beyond",
    "imu_form",
    "increments_from_table",
    "rates_from_table",
    "read_truth",
    "write_imu",
    "write_truth",
]
