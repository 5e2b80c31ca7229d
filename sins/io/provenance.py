"""What a sins CSV says of where its readings came from: the unit that read them, the model that
corrected them, and the clock its times count from.

Comment lines at the top of a sins CSV, among any free comment, carry it (``#`` lines before the
header; other readers skip them as comments)::

    # sensor: simulated tactical unit (unit seed 1)
    # corrected by: regression model m.json (sha256 3f1c…), fitted on rig.csv
    # time origin: 1413393212255760384 ns

``sins simulate`` and ``sins calibrate`` write the first; ``sins correct`` keeps the recording's
``sensor`` line and adds the second, so that a corrected file says so, and by which model, and a second
correction is refused unless asked for (``sins correct --again``). Where the recording's times were
stamps (a EuRoC folder's nanoseconds, a bag's, an ``.npz``'s seconds), made relative to its first on
reading, ``sins correct`` adds the third: the stamp of ``t = 0``, ns, by which the corrected readings line
up with the rest of the user's data again. :func:`read_provenance` reads them back.

A model file says which readings it was fitted on by their digest (:func:`readings_digest`, kept in
``fitted_on_["readings"]``), so that a judgement on one of them is said to be no held-back judgement,
whatever the file's name or path.
"""

from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sins.io.documents import printable
from sins.io.tables import open_text

#: The comment keys, as written (``# KEY: value``).
SENSOR_KEY = "sensor"
CORRECTED_KEY = "corrected by"
TIME_ORIGIN_KEY = "time origin"
#: The most comment lines read at the top of a file (a file of comments only is not scanned whole).
MAX_COMMENT_LINES = 1000


@dataclass(frozen=True)
class Provenance:
    """A sins CSV's ``sensor`` and ``corrected by`` lines ("" where absent); ``corrections`` counts the
    ``corrected by`` lines (one per correction); ``t0_ns`` its ``time origin`` (None where absent)."""

    sensor: str = ""
    corrected_by: str = ""
    corrections: int = 0
    t0_ns: int | None = None


def read_provenance(path: str | os.PathLike[str]) -> Provenance:
    """The ``sensor``, ``corrected by`` and ``time origin`` comment lines of a CSV (before its header);
    a file that cannot be read as text has none (its reader says why); a time origin that is not a
    whole number of nanoseconds is none."""
    sensor, corrected, count, t0_ns = "", "", 0, None
    try:
        with open_text(Path(path)) as fh:
            for number, line in enumerate(fh):
                text = line.strip()
                if number >= MAX_COMMENT_LINES or (text and not text.startswith("#")):
                    break
                key, _, value = text.lstrip("#").strip().partition(":")
                if key.strip().lower() == SENSOR_KEY and not sensor:
                    sensor = printable(value.strip())[:200]
                elif key.strip().lower() == CORRECTED_KEY:
                    corrected, count = printable(value.strip())[:300], count + 1
                elif key.strip().lower() == TIME_ORIGIN_KEY and t0_ns is None:
                    t0_ns = _nanoseconds(value)
    except (ValueError, OSError):  # SinsInputError is a ValueError; a UnicodeDecodeError too
        return Provenance()
    return Provenance(sensor, corrected, count, t0_ns)


def _nanoseconds(value: str) -> int | None:
    """A ``time origin`` line's value, ``N ns``, as N (None where it is not a whole number of ns)."""
    number, _, unit = value.strip().partition(" ")
    if unit.strip() != "ns" or re.fullmatch(r"-?[0-9]{1,25}", number) is None:
        return None
    return int(number)


def time_origin_line(t0_ns: int) -> str:
    """The ``time origin`` line's text: the stamp of ``t = 0``, ns."""
    return f"{TIME_ORIGIN_KEY}: {int(t0_ns)} ns"


def corrected_line(model: str | os.PathLike[str], label: str, fitted_on: str = "") -> str:
    """The ``corrected by`` line's text for a correction by the model file ``model`` (strategy
    ``label``), with the file's SHA-256 (its first 16 hex digits) and what it was fitted on."""
    digest = hashlib.sha256(Path(model).read_bytes()).hexdigest()[:16]
    on = f", fitted on {fitted_on}" if fitted_on else ""
    return f"{CORRECTED_KEY}: {label} model {model} (sha256 {digest}){on}"


def readings_digest(t: np.ndarray, *readings: np.ndarray) -> str:
    """The first 16 hex digits of the SHA-256 of the readings' times and values as float64 (a rig's
    ``t, gyro, accel``; a recording's increments ``t, dtheta_b, dv_b``): the same readings read from any
    copy, path or name of their file give the same digest."""
    h = hashlib.sha256()
    for a in (t, *readings):
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return h.hexdigest()[:16]


__all__ = [
    "CORRECTED_KEY",
    "MAX_COMMENT_LINES",
    "SENSOR_KEY",
    "TIME_ORIGIN_KEY",
    "Provenance",
    "corrected_line",
    "read_provenance",
    "readings_digest",
    "time_origin_line",
]
