"""A navigation solution written out: one row per IMU time, as CSV or Parquet.

The columns are those of a truth file (:data:`~sins.io.formats.TRUTH_COLUMNS`), so a solution reads back
with :func:`~sins.io.formats.read_truth` and compares with any other tool's trajectory:

| column | what | unit |
|---|---|---|
| t | time | s |
| lat_deg | geodetic latitude (WGS84) | ° |
| lon_deg | longitude | ° |
| h_m | ellipsoidal height | m |
| vn, ve, vd | velocity north, east, down | m/s |
| roll_deg, pitch_deg, yaw_deg | ZYX Euler angles of the body (FRD) from NED; yaw clockwise from north | ° |

A Parquet file holds the same columns as float64, each field's unit in its metadata (``unit``).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from sins.core.series import NavSeries
from sins.errors import SinsInputError
from sins.io.formats import TRUTH_COLUMNS, atomic_path, write_truth

#: Each solution column's unit (the table of the module docstring).
SOLUTION_UNITS = dict(
    zip(TRUTH_COLUMNS, ("s", "deg", "deg", "m", "m/s", "m/s", "m/s", "deg", "deg", "deg"), strict=True)
)
#: The file kinds a solution is written as, by suffix.
SUFFIXES = (".csv", ".parquet")


def check_solution_path(path: str | os.PathLike[str], flag: str = "") -> str:
    """Refuse a solution path with a suffix other than :data:`SUFFIXES` (before any work is done); the
    kind of file it names (:data:`sins.io.paths.KINDS`: ``"csv"`` or ``"parquet"``) where it is taken.

    Raises
    ------
    SinsInputError
        naming the path and the suffixes taken.
    """
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise SinsInputError(
            f"{flag + ' ' if flag else ''}{path}: a solution is written as .csv or .parquet, not "
            f"{suffix or 'a file without a suffix'}"
        )
    return suffix[1:]


def solution_columns(solution: NavSeries) -> dict[str, np.ndarray]:
    """The solution's columns in :data:`SOLUTION_UNITS` (degrees for angles)."""
    roll, pitch, yaw = solution.euler()
    values = (
        solution.t, np.degrees(solution.lat), np.degrees(solution.lon), solution.h, *solution.v_n.T,
        np.degrees(roll), np.degrees(pitch), np.degrees(yaw),
    )  # fmt: skip
    return {name: np.ascontiguousarray(v, dtype=float) for name, v in zip(TRUTH_COLUMNS, values, strict=True)}


def write_solution(path: str | os.PathLike[str], solution: NavSeries, comment: str = "") -> None:
    """Write ``solution`` as CSV or Parquet (by the suffix), atomically: a reader never sees half a file.

    Raises
    ------
    SinsInputError
        another suffix (:func:`check_solution_path`), or a folder that does not exist.
    """
    check_solution_path(path)
    if Path(path).suffix.lower() == ".csv":
        write_truth(path, solution, comment)
        return
    import pyarrow as pa
    import pyarrow.parquet as pq

    fields = [pa.field(name, pa.float64(), metadata={"unit": SOLUTION_UNITS[name]}) for name in TRUTH_COLUMNS]
    columns = solution_columns(solution)
    table = pa.table([columns[name] for name in TRUTH_COLUMNS], schema=pa.schema(fields))
    if comment:
        table = table.replace_schema_metadata({"comment": comment})
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)


__all__ = [
    "SOLUTION_UNITS",
    "SUFFIXES",
    "check_solution_path",
    "solution_columns",
    "write_solution",
]
