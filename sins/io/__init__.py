"""Files: sins's CSV formats (:mod:`~sins.io.formats`: IMU and truth files; :mod:`~sins.io.rig`: rig
recordings; :mod:`~sins.io.tables`: the numeric tables under them), its JSON files
(:mod:`~sins.io.json_files`), writes that never leave half a file (:mod:`~sins.io.atomic`), and the one way to
read an IMU recording, :func:`~sins.io.reader.read` (any format: sins's CSVs, rig recordings, ROS bags,
MCAP, EuRoC/TUM-VI, ``.npz``, CSVs with their own columns; or a real dataset by name,
:mod:`~sins.io.datasets`).

Those modules' main names are importable from here (``from sins import io; io.read(path)``).
"""

from sins.io.atomic import atomic_path
from sins.io.formats import (
    INCREMENT_COLUMNS,
    RATE_COLUMNS,
    TRUTH_COLUMNS,
    check_range,
    imu_form,
    increments_from_table,
    rates_from_table,
    read_truth,
    write_imu,
    write_truth,
)
from sins.io.json_files import read_json_document, write_json, write_report
from sins.io.reader import read
from sins.io.recording import KINDS, Recording
from sins.io.rig import (
    PHASE_KINDS,
    RECORDING_COLUMNS,
    REF_COLUMNS,
    STATIC_RATE_TOL,
    check_recording_range,
    write_recording,
)
from sins.io.tables import Table, format_number, line_of_row, read_columns, read_table, write_table

__all__ = [
    "INCREMENT_COLUMNS",
    "KINDS",
    "PHASE_KINDS",
    "RATE_COLUMNS",
    "RECORDING_COLUMNS",
    "REF_COLUMNS",
    "STATIC_RATE_TOL",
    "TRUTH_COLUMNS",
    "Recording",
    "Table",
    "atomic_path",
    "check_range",
    "check_recording_range",
    "format_number",
    "imu_form",
    "increments_from_table",
    "line_of_row",
    "rates_from_table",
    "read",
    "read_columns",
    "read_json_document",
    "read_table",
    "read_truth",
    "write_imu",
    "write_json",
    "write_recording",
    "write_report",
    "write_table",
    "write_truth",
]
