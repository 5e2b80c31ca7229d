"""The imucal Ferraris sessions (``imucal_ferraris/``; MIT licence, MaD Lab, FAU Erlangen-Nürnberg,
github.com/mad-lab-fau/imucal)
    Hand-performed Ferraris calibrations of unnamed MEMS IMUs: six static
    holds with each axis up and down, then one turn about each axis.
    :func:`_read_ferraris` returns the example session (physical units, a
    continuous recording with a section list) and :func:`_read_ferraris_annotated`
    the annotated session (raw counts, only the sections) as
    :class:`~sins.core.series.CalibrationData`.
"""

from __future__ import annotations

import itertools
import json
import math
import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sins.core import earth
from sins.core.series import CalibrationData, RigPhase
from sins.errors import SinsInputError
from sins.io import formats, tables
from sins.io.datasets.root import dataset_file
from sins.io.documents import read_json
from sins.io.formats import MAX_FORCE_MPS2, MAX_RATE_RADPS

Array = NDArray[np.float64]

FERRARIS_FOLDER = "imucal_ferraris"
#: Sample rate of the example session, Hz. SOURCE.md cites imucal's ``examples/basic_ferraris.py``
#: for it, but the versions of that file we could read pass 204.8 Hz (the rate of the annotated raw
#: session) to ``compute``. The data decide: the three hand turns, meant as -360°, integrate to
#: -370°, -354° and -359° at 102.4 Hz, and would be half that at 204.8 Hz.
FERRARIS_RATE_HZ = 102.4
#: Assumed latitude of the recording, deg: Erlangen, where the lab is. The file does not say; any
#: latitude in Europe moves normal gravity by < 3 mm/s², and 49.6° against the 9.81 m/s² imucal
#: assumes by 0.3 mm/s², far below this uncalibrated unit's offsets (about 0.5 m/s²).
FERRARIS_LAT_DEG = 49.6
#: Assumed height above the ellipsoid, m: 0. Erlangen's ≈ 330 m would lower g by ≈ 1 mm/s², again far
#: below the unit's offsets and about the noise of one static section's mean.
FERRARIS_HEIGHT_M = 0.0
#: The sections of a Ferraris session, as imucal names them.
FERRARIS_SECTIONS = ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a", "x_rot", "y_rot", "z_rot")
_FERRARIS_COLUMNS = ("n_samples", "gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z")

#: Sample rate of the annotated session, Hz: imucal's ``tests/test_calibration_calculation.py`` passes
#: 204.8 Hz when it calibrates it (SOURCE.md), and its turns then integrate to 354–367°.
ANNOTATED_RATE_HZ = 204.8
#: One accelerometer count of the annotated session, m/s²: 9.81/2048, a 16-bit reading over ±16 g.
#: The lab's own conversion: every reading of its example session is a whole multiple of it (to 2e-13).
ANNOTATED_ACCEL_MPS2_PER_COUNT = 9.81 / 2048.0
#: One gyro count of the annotated session, °/s: 2000/2¹⁵, a 16-bit reading over ±2000 °/s; again the
#: conversion behind the example session (its gyro readings are whole multiples, to 2e-12).
ANNOTATED_GYRO_DPS_PER_COUNT = 2000.0 / 32768.0
#: The annotated session's turns, deg: +360 about each axis (see :func:`_read_ferraris_annotated`).
ANNOTATED_TURN_DEG = 360.0
_ANNOTATED_COLUMNS = ("samples", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")


def _read_ferraris(
    root: str | os.PathLike[str] | None = None, *, session: str = "example"
) -> CalibrationData:
    """The imucal Ferraris session ``<session>_ferraris_session.csv`` with its section list.

    Readings: the CSV's gyro (deg/s) converted to rad/s, its accelerometer
    (m/s²) as is; both already in physical units but uncalibrated. Time is
    ``n_samples / 102.4`` s (the file has no time stamps). Temperature is not
    recorded (``temp`` is None).

    Phases, one per section of ``<session>_ferraris_session_list.json``, in
    time order, rows ``start:end`` with ``end`` exclusive, as imucal slices them
    (``data.iloc[start:end]`` in ``imucal.calibration_gui``); the indices are row
    positions, which here equal ``n_samples``.

    Reference, body axes (the sensor's own axes, taken as they are):

    * static sections ``x_p … z_a``: specific force ``+g`` along the axis for
      ``*_p`` (that axis points up: at rest an accelerometer reads the reaction
      to gravity, and the data show ``x_p`` reading ≈ +10.3 m/s² on x) and
      ``-g`` for ``*_a``, with ``g`` the WGS84 normal gravity at the assumed
      :data:`FERRARIS_LAT_DEG`, :data:`FERRARIS_HEIGHT_M`; angular rate 0:
      Earth's rate (≤ 15 °/h, 7.3e-5 rad/s) is ignored, as imucal does, being
      far below this unit's noise and its 0.061 °/s resolution.
    * rotation sections ``x_rot, y_rot, z_rot``: the unit is turned by hand, so
      neither the rate nor the specific force is known per sample (NaN); the
      phase's ``angle_rad`` is the whole turn, −2π about that axis (imucal's
      convention: clockwise, the gyro reads negative; accurate to a few degrees).
    * rows outside every section: NaN, and no phase.

    Parameters
    ----------
    root : the data root, or None for :func:`data_root`
    session : the file-name prefix of the session; imucal ships ``"example"``

    Returns
    -------
    CalibrationData
        ``t`` (n,) s, ``gyro`` (n, 3) rad/s, ``accel`` (n, 3) m/s², ``ref_gyro``
        (n, 3) rad/s, ``ref_accel`` (n, 3) m/s², nine phases; ``source`` the CSV path.

    Raises
    ------
    SinsInputError
        one line: a missing folder or file (saying how to point at the data),
        a malformed CSV or section list.
    """
    if not session or Path(session).name != session or session in (".", ".."):
        raise SinsInputError(f"session {session!r}: expected a file-name prefix such as 'example'")
    csv_path = dataset_file(FERRARIS_FOLDER, f"{session}_ferraris_session.csv", root)
    json_path = dataset_file(FERRARIS_FOLDER, f"{session}_ferraris_session_list.json", root)

    table = tables.read_table(csv_path, required=_FERRARIS_COLUMNS, select=_FERRARIS_COLUMNS)
    d = table.data
    n = len(d)
    samples = d[:, 0]
    bad = (samples != np.floor(samples)) | np.r_[False, np.diff(samples) <= 0]
    if bad.any():
        r = int(np.argmax(bad))
        raise SinsInputError(
            f"{csv_path}:{tables.line_of_row(csv_path, table.first_data_line - 1, r)}: column 'n_samples': "
            f"{tables.format_number(samples[r])} is not an integer sample index greater than the previous one"
        )
    sections = _ferraris_sections(json_path, n)
    for i, name in enumerate(_FERRARIS_COLUMNS[1:]):
        limit = np.degrees(MAX_RATE_RADPS) if name.startswith("gyr") else MAX_FORCE_MPS2
        formats.check_range(table, name, d[:, i + 1], -limit, limit, "reading", "°/s" if i < 3 else "m/s²")

    return _session(
        samples / FERRARIS_RATE_HZ, np.radians(d[:, 1:4]), d[:, 4:7].copy(), sections, -360.0, str(csv_path)
    )


def _session(
    t: Array, gyro: Array, accel: Array, sections: dict[str, tuple[int, int]], turn_deg: float, source: str
) -> CalibrationData:
    """The readings with the Ferraris references: ``±g`` and rate 0 in the holds, a turn of ``turn_deg``
    about each rotation section's own axis, NaN elsewhere (see :func:`_read_ferraris`)."""
    n = len(t)
    g = float(earth.normal_gravity(math.radians(FERRARIS_LAT_DEG), FERRARIS_HEIGHT_M))
    ref_gyro = np.full((n, 3), np.nan)
    ref_accel = np.full((n, 3), np.nan)
    phases = []
    for name, (start, stop) in sorted(sections.items(), key=lambda item: item[1]):
        axis = "xyz".index(name[0])
        if name.endswith("_rot"):
            angle = [0.0, 0.0, 0.0]
            angle[axis] = math.radians(turn_deg)
            phases.append(RigPhase(name, start, stop, "rotation", (angle[0], angle[1], angle[2])))
        else:
            ref_gyro[start:stop] = 0.0
            ref_accel[start:stop] = 0.0
            ref_accel[start:stop, axis] = g if name.endswith("_p") else -g
            phases.append(RigPhase(name, start, stop, "static"))
    return CalibrationData(
        t=t, gyro=gyro, accel=accel, ref_gyro=ref_gyro, ref_accel=ref_accel, temp=None,
        phases=tuple(phases), source=source,
    )  # fmt: skip


def _read_ferraris_annotated(
    root: str | os.PathLike[str] | None = None, *, turn_deg: float = ANNOTATED_TURN_DEG
) -> CalibrationData:
    """imucal's annotated Ferraris session ``annotated_session.csv``: raw counts, sections named per row.

    The file holds only the nine sections, its rows grouped by name; ``samples`` numbers them 0, 1, …
    with the sections laid end to end in the order x_p, x_a, … z_rot. Rows are returned in that order
    and ``t = samples / 204.8`` s (:data:`ANNOTATED_RATE_HZ`): the time between sections in the original
    recording is not in the file, so the phases abut and no motion lies between them.

    Readings: the counts times the lab's own conversion of its example session (a 16-bit unit at ±16 g
    and ±2000 °/s: :data:`ANNOTATED_ACCEL_MPS2_PER_COUNT`, :data:`ANNOTATED_GYRO_DPS_PER_COUNT`), so
    that a calibration finds percent-sized errors, not a unit conversion; uncalibrated. No temperature.

    Reference: as :func:`_read_ferraris`'s, except the turns' angle, ``turn_deg`` about each rotation's
    axis. imucal's convention is −360° (clockwise seen from the axis's tip), but this session's turns
    read +367°, +354° and +355°: taken as −360°, the gyro's scale-and-misalignment matrix has
    determinant −1 (imucal's own snapshot calibration of this file has ``R_g`` ≈ −I), a gyro triad
    left-handed against its accelerometer, which no IMU is built as. These turns went the other way,
    and the default is +360°.

    Parameters
    ----------
    root : the data root, or None for :func:`data_root`
    turn_deg : the angle of each turn about its own axis, deg

    Returns
    -------
    CalibrationData
        ``t`` (n,) s, ``gyro`` (n, 3) rad/s, ``accel`` (n, 3) m/s², references as in
        :func:`_read_ferraris`, nine phases; ``source`` the CSV path.

    Raises
    ------
    SinsInputError
        one line naming the file and line: a missing file or column, an unknown or missing section,
        a section whose rows are not contiguous in ``samples``, ``samples`` not 0, 1, … n−1.
    """
    csv_path = dataset_file(FERRARIS_FOLDER, "annotated_session.csv", root)
    table = tables.read_table(csv_path, required=("part", *_ANNOTATED_COLUMNS), select=_ANNOTATED_COLUMNS)
    parts = _read_parts(csv_path, table)
    d = table.data
    n = len(d)
    samples = d[:, 0]
    order = np.argsort(samples, kind="stable")
    expected = np.arange(n)
    if not np.array_equal(samples[order], expected):
        r = int(order[np.argmax(samples[order] != expected)])
        raise SinsInputError(
            f"{csv_path}:{tables.line_of_row(csv_path, table.first_data_line - 1, r)}: column 'samples': "
            f"{tables.format_number(samples[r])}: the samples must number the {n} rows 0, 1, … {n - 1}, "
            "each once"
        )
    accel = d[:, 1:4] * ANNOTATED_ACCEL_MPS2_PER_COUNT
    gyro = np.radians(d[:, 4:7] * ANNOTATED_GYRO_DPS_PER_COUNT)
    for i, name in enumerate(_ANNOTATED_COLUMNS[1:]):
        limit, unit = (MAX_FORCE_MPS2, "m/s²") if i < 3 else (MAX_RATE_RADPS, "rad/s")
        values = accel[:, i] if i < 3 else gyro[:, i - 3]
        formats.check_range(table, name, values, -limit, limit, "reading (converted)", unit)
    sections = _annotated_sections(csv_path, table, parts, order)
    t = expected / ANNOTATED_RATE_HZ
    return _session(t, gyro[order], accel[order], sections, turn_deg, str(csv_path))


def _read_parts(path: Path, table: tables.Table) -> list[str]:
    """The ``part`` cell of every data row of ``table`` (blank and ``#`` lines skipped, as read_table)."""
    column = tables.read_columns(path).index("part")
    parts: list[str] = []
    with open(path, encoding="utf-8-sig") as fh:
        for number, text in enumerate(fh, start=1):
            if number < table.first_data_line or not text.strip() or text.lstrip().startswith("#"):
                continue
            parts.append(text.rstrip("\r\n").split(",")[column].strip())
    if len(parts) != len(table.data):  # read_table has checked every row; this guards the two parsers
        raise SinsInputError(f"{path}: {len(parts)} rows of column 'part' for {len(table.data)} data rows")
    return parts


def _annotated_sections(
    path: Path, table: tables.Table, parts: list[str], order: NDArray[np.intp]
) -> dict[str, tuple[int, int]]:
    """``{section: (start, stop)}`` rows, in ``samples`` order, of the annotated file's ``part`` column."""

    def where(row: int) -> str:
        return f"{path}:{tables.line_of_row(path, table.first_data_line - 1, row)}"

    known = set(FERRARIS_SECTIONS)
    for r, name in enumerate(parts):
        if name not in known:
            raise SinsInputError(
                f"{where(r)}: column 'part': unknown section {name!r} "
                f"(expected {', '.join(FERRARIS_SECTIONS)})"
            )
    ordered = [parts[r] for r in order]
    out: dict[str, tuple[int, int]] = {}
    start = 0
    for k in range(1, len(ordered) + 1):
        if k == len(ordered) or ordered[k] != ordered[start]:
            name = ordered[start]
            if name in out:
                raise SinsInputError(
                    f"{where(int(order[start]))}: column 'part': section {name!r} is not one run of "
                    f"consecutive samples (it resumes at sample {start})"
                )
            out[name] = (start, k)
            start = k
    for name in FERRARIS_SECTIONS:
        if name not in out:
            raise SinsInputError(f"{path}: column 'part': missing section {name!r}")
    return out


def _ferraris_sections(path: Path, n_rows: int) -> dict[str, tuple[int, int]]:
    """``{section: (start, stop)}`` rows from imucal's section list, validated against ``n_rows``."""
    raw = read_json(path, "JSON section list", sins=False)
    if not isinstance(raw, dict):
        raise SinsInputError(f"{path}: expected an object of sections, found {type(raw).__name__}")
    extra = sorted(set(raw) - set(FERRARIS_SECTIONS))
    if extra:
        raise SinsInputError(
            f"{path}: unknown section {extra[0]!r} (expected {', '.join(FERRARIS_SECTIONS)})"
        )
    out: dict[str, tuple[int, int]] = {}
    for name in FERRARIS_SECTIONS:
        if name not in raw:
            raise SinsInputError(f"{path}: missing section {name!r}")
        entry = raw[name]
        start = entry.get("start") if isinstance(entry, dict) else None
        end = entry.get("end") if isinstance(entry, dict) else None
        if not (
            isinstance(entry, dict)
            and set(entry) == {"start", "end"}
            and isinstance(start, int)
            and isinstance(end, int)
            and not isinstance(start, bool)
            and not isinstance(end, bool)
        ):
            raise SinsInputError(
                f'{path}: section {name!r}: expected {{"start": int, "end": int}}, found {json.dumps(entry)}'
            )
        if not 0 <= start < end <= n_rows:
            raise SinsInputError(
                f"{path}: section {name!r}: rows {start}:{end} are empty or beyond the {n_rows} rows"
            )
        out[name] = (start, end)
    ordered = sorted(out.items(), key=lambda item: item[1])
    for (a, (_, a_end)), (b, (b_start, _)) in itertools.pairwise(ordered):
        if b_start < a_end:
            raise SinsInputError(f"{path}: sections {a!r} and {b!r} overlap")
    return out


__all__ = [
    "ANNOTATED_ACCEL_MPS2_PER_COUNT",
    "ANNOTATED_GYRO_DPS_PER_COUNT",
    "ANNOTATED_RATE_HZ",
    "ANNOTATED_TURN_DEG",
    "FERRARIS_FOLDER",
    "FERRARIS_HEIGHT_M",
    "FERRARIS_LAT_DEG",
    "FERRARIS_RATE_HZ",
    "FERRARIS_SECTIONS",
]
