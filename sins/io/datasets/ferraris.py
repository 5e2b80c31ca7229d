"""The imucal Ferraris session (``imucal_ferraris/``; MIT licence, MaD Lab, FAU Erlangen-Nürnberg,
github.com/mad-lab-fau/imucal)
    A hand-performed Ferraris calibration of an unnamed MEMS IMU: six static
    holds with each axis up and down, then one turn about each axis.
    :func:`read_ferraris` returns it as :class:`~sins.series.CalibrationData`.
"""

from __future__ import annotations

import itertools
import json
import math
import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sins import io
from sins.errors import SinsInputError
from sins.io.datasets.root import dataset_file
from sins.io.documents import read_json
from sins.io.formats import MAX_FORCE_MPS2, MAX_RATE_RADPS
from sins.nav import earth
from sins.series import CalibrationData, RigPhase

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


def read_ferraris(root: str | os.PathLike[str] | None = None, *, session: str = "example") -> CalibrationData:
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

    table = io.read_table(csv_path, required=_FERRARIS_COLUMNS, select=_FERRARIS_COLUMNS)
    d = table.data
    n = len(d)
    samples = d[:, 0]
    bad = (samples != np.floor(samples)) | np.r_[False, np.diff(samples) <= 0]
    if bad.any():
        r = int(np.argmax(bad))
        raise SinsInputError(
            f"{csv_path}:{io.line_of_row(csv_path, table.first_data_line - 1, r)}: column 'n_samples': "
            f"{io.format_number(samples[r])} is not an integer sample index greater than the previous one"
        )
    sections = _ferraris_sections(json_path, n)
    for i, name in enumerate(_FERRARIS_COLUMNS[1:]):
        limit = np.degrees(MAX_RATE_RADPS) if name.startswith("gyr") else MAX_FORCE_MPS2
        io.check_range(table, name, d[:, i + 1], -limit, limit, "reading", "°/s" if i < 3 else "m/s²")

    g = float(earth.normal_gravity(math.radians(FERRARIS_LAT_DEG), FERRARIS_HEIGHT_M))
    ref_gyro = np.full((n, 3), np.nan)
    ref_accel = np.full((n, 3), np.nan)
    phases = []
    for name, (start, stop) in sorted(sections.items(), key=lambda item: item[1]):
        axis = "xyz".index(name[0])
        if name.endswith("_rot"):
            angle = [0.0, 0.0, 0.0]
            angle[axis] = -2.0 * math.pi
            phases.append(RigPhase(name, start, stop, "rotation", (angle[0], angle[1], angle[2])))
        else:
            ref_gyro[start:stop] = 0.0
            ref_accel[start:stop] = 0.0
            ref_accel[start:stop, axis] = g if name.endswith("_p") else -g
            phases.append(RigPhase(name, start, stop, "static"))
    return CalibrationData(
        t=samples / FERRARIS_RATE_HZ,
        gyro=np.radians(d[:, 1:4]),
        accel=d[:, 4:7].copy(),
        ref_gyro=ref_gyro,
        ref_accel=ref_accel,
        temp=None,
        phases=tuple(phases),
        source=str(csv_path),
    )


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
