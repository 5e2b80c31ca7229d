"""Files: sins's CSV formats and JSON documents (:mod:`~sins.io.formats`), and readers of real recordings
(:mod:`~sins.io.datasets`).

The formats' public names are importable from here (``from sins import io; io.read_imu(path)``).
"""

from sins.io.formats import (
    INCREMENT_COLUMNS,
    PHASE_KINDS,
    RATE_COLUMNS,
    RECORDING_COLUMNS,
    REF_COLUMNS,
    STATIC_RATE_TOL,
    TRUTH_COLUMNS,
    Table,
    format_number,
    imu_form,
    increments_from_table,
    line_of_row,
    rates_from_table,
    read_columns,
    read_imu,
    read_json_document,
    read_recording,
    read_table,
    read_truth,
    write_imu,
    write_json,
    write_recording,
    write_table,
    write_truth,
)

__all__ = [
    "INCREMENT_COLUMNS",
    "PHASE_KINDS",
    "RATE_COLUMNS",
    "RECORDING_COLUMNS",
    "REF_COLUMNS",
    "STATIC_RATE_TOL",
    "TRUTH_COLUMNS",
    "Table",
    "format_number",
    "imu_form",
    "increments_from_table",
    "line_of_row",
    "rates_from_table",
    "read_columns",
    "read_imu",
    "read_json_document",
    "read_recording",
    "read_table",
    "read_truth",
    "write_imu",
    "write_json",
    "write_recording",
    "write_table",
    "write_truth",
]
