"""What a sins CSV says of where its readings came from: the unit that read them, the model that
corrected them, and the clock its times count from.

Comment lines at the top of a sins CSV, among any free comment, carry it (``#`` lines before the
header; other readers skip them as comments)::

    # sensor: simulated tactical unit (unit seed 1, content 75019f66)
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
whatever the file's name or path; and by their marks (:func:`readings_marks`, ``fitted_on_["marks"]``),
so that a judgement on a part of one (a recording cut from it) is said to be one too.
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


#: A mark is made of this many consecutive readings (a run of a still, quantised unit's identical readings
#: is shorter than this in any recording with noise) ...
MARK_ROWS = 16
#: ... and about one window in this many is a mark: 300 marks for EuRoC's six training recordings.
MARK_EVERY = 512
#: The least number of marks a recording must have for its share in a fit to be told (~ 10 s at 200 Hz).
MIN_MARKS = 4
#: A recording with at least this share of its marks among another's is a part of it (a share of
#: unrelated recordings' marks is 0: 64-bit hashes of 16 readings do not meet by chance).
PART_SHARE = 0.5

_MIX = np.uint64(0x9E3779B97F4A7C15)


def _mixed(x: np.ndarray) -> np.ndarray:
    """A 64-bit finaliser (SplitMix64's): every bit of ``x`` moves every bit of the result."""
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def readings_marks(*readings: np.ndarray) -> list[str]:
    """The readings' marks: the 64-bit hashes (16 hex digits, sorted) of those windows of
    :data:`MARK_ROWS` consecutive rows (the values as float64 bits: a rig's ``gyro, accel``, a recording's
    increments ``dtheta_b, dv_b``) whose hash is a multiple of :data:`MARK_EVERY`. Chosen by their content,
    not their place, and without the time stamps (a reader makes a file's times relative to its first),
    so a part cut from a recording holds the marks of that part of it wherever it starts: a recording's
    share of marks in another's says how much of it the other holds (:func:`shared_share`)."""
    n = min(len(r) for r in readings)
    if n < MARK_ROWS:
        return []
    columns = [np.asarray(r, dtype=np.float64).reshape(len(r), -1)[:n] for r in readings]
    words = np.ascontiguousarray(np.hstack(columns)).view(np.uint64)
    with np.errstate(over="ignore"):
        row = np.zeros(n, dtype=np.uint64)
        for c in range(words.shape[1]):
            row = _mixed(row ^ words[:, c]) * _MIX
        window = np.zeros(n - MARK_ROWS + 1, dtype=np.uint64)
        for j in range(MARK_ROWS):
            window = window * _MIX + row[j : n - MARK_ROWS + 1 + j]
        window = _mixed(window)
    kept = np.unique(window[window % np.uint64(MARK_EVERY) == 0])
    return [f"{int(h):016x}" for h in kept]


def shared_share(marks: list[str], held: list[list[str]]) -> float | None:
    """The share of ``marks`` (a recording's, :func:`readings_marks`) found among ``held`` (those of the
    recordings a model was fitted on): about the share of its readings the fit took; None where it has
    fewer than :data:`MIN_MARKS` marks (too short to tell)."""
    if len(marks) < MIN_MARKS:
        return None
    known = {m for part in held for m in part}
    return sum(m in known for m in marks) / len(marks)


__all__ = [
    "CORRECTED_KEY",
    "MARK_EVERY",
    "MARK_ROWS",
    "MAX_COMMENT_LINES",
    "MIN_MARKS",
    "PART_SHARE",
    "SENSOR_KEY",
    "TIME_ORIGIN_KEY",
    "Provenance",
    "corrected_line",
    "read_provenance",
    "readings_digest",
    "readings_marks",
    "shared_share",
    "time_origin_line",
]
