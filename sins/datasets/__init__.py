"""Readers for the real IMU datasets kept beside the project (never copied into it).

Each dataset lives in a folder under the data root (see :func:`data_root`) with
a SOURCE.md giving its origin, licence, units and columns. Each reader, one
module per dataset, converts to the package's conventions (SI, radians) and
returns the package's types.
"""

from sins.datasets.ferraris import FERRARIS_FOLDER, FERRARIS_RATE_HZ, FERRARIS_SECTIONS, read_ferraris
from sins.datasets.root import ENV_VAR, data_root

__all__ = [
    "ENV_VAR",
    "FERRARIS_FOLDER",
    "FERRARIS_RATE_HZ",
    "FERRARIS_SECTIONS",
    "data_root",
    "read_ferraris",
]
