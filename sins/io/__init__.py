"""Files: sins's CSV formats (:mod:`~sins.io.formats`: IMU and truth files; :mod:`~sins.io.rig`: rig
recordings; :mod:`~sins.io.tables`: the numeric tables under them), its JSON files
(:mod:`~sins.io.json_files`), writes that never leave half a file (:mod:`~sins.io.atomic`), recordings in
other formats (:func:`~sins.io.recording.read_recording_any`: ROS bags, MCAP, EuRoC/TUM-VI, CSVs with their
own columns), and readers of real recordings (:mod:`~sins.io.datasets`).

Those modules' main names are importable from here (``from sins import io; io.read_imu(path)``).
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
    read_imu,
    read_truth,
    write_imu,
    write_truth,
)
from sins.io.json_files import read_json_document, write_json
from sins.io.recording import KINDS, Recording, beside_reference, read_recording_any
from sins.io.rig import (
    PHASE_KINDS,
    RECORDING_COLUMNS,
    REF_COLUMNS,
    STATIC_RATE_TOL,
    check_recording_range,
    read_recording,
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
    "beside_reference",
    "check_range",
    "check_recording_range",
    "format_number",
    "imu_form",
    "increments_from_table",
    "line_of_row",
    "rates_from_table",
    "read_columns",
    "read_imu",
    "read_json_document",
    "read_recording",
    "read_recording_any",
    "read_table",
    "read_truth",
    "write_imu",
    "write_json",
    "write_recording",
    "write_table",
    "write_truth",
]
