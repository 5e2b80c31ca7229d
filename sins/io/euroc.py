"""The EuRoC MAV and TUM-VI folder layout (ASL format): ``mav0/imu0/data.csv`` and a reference.

``imu0/data.csv``: a header line ``#timestamp [ns],w_RS_S_x [rad s^-1],…,a_RS_S_z [m s^-2]``, then one
row per reading: integer nanoseconds, three rates (rad/s), three specific forces (m/s²), on the
sensor's own axes S. ``imu0/sensor.yaml``'s ``rate_hz`` is the nominal rate. The reference, the first
present of ``state_groundtruth_estimate0`` (EuRoC: position, attitude ``q_RS`` w-first, velocity),
``mocap0`` (TUM-VI) or ``vicon0`` (EuRoC's Vicon rooms): the pose of S in a room frame R whose z points
up. R is taken as ENU (the datasets do not say where north is: headings are relative to R's y axis)
and placed on the ellipsoid at a given origin (:func:`sins.io.local.enu_track`); velocities the
reference lacks are differentiated from its positions. Times are seconds from the first reading's
stamp (``t0_ns``). The readings stay on S unless another frame is named: S is not FRD (EuRoC's x axis
points up at rest), and the reference's attitude is of the same axes, so a run integrates them as they
are.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sins.core.series import ImuRates, NavSeries
from sins.errors import SinsInputError
from sins.io import axes, formats, local
from sins.io.paths import check_input

Array = NDArray[np.float64]

#: Reference folders in the order they are looked for, and the columns each has after the time.
#: The largest nanosecond stamp read (int64's largest: the year 2262).
MAX_STAMP_NS = 2**63 - 1
REFERENCES = {"state_groundtruth_estimate0": 16, "mocap0": 7, "vicon0": 7}


@dataclass(frozen=True)
class EurocRead:
    """What :func:`_read_euroc` read: readings (SI, FRD after ``frame``), the first stamp, the nominal
    rate (None without ``sensor.yaml``), the reference (None without one), notes."""

    imu: ImuRates
    t0_ns: int
    rate_hz: float | None
    truth: NavSeries | None
    notes: tuple[str, ...]


def read_beside(path: str | os.PathLike[str]) -> Path | None:
    """The ``mav0`` folder whose files an ASL IMU file's reader also reads (its reference folders and
    ``imu0/sensor.yaml``), where ``path`` is ``mav0/imu0/data.csv``; else None. Those files are inputs
    too: no output may replace them."""
    path = Path(path)
    return path.parent.parent if path.name == "data.csv" and path.parent.name == "imu0" else None


def locate(path: Path) -> tuple[Path, Path | None] | None:
    """``(imu0/data.csv, mav0)`` of a EuRoC/TUM-VI recording at ``path`` (the folder above ``mav0``,
    ``mav0`` itself, or an ASL IMU file: ``mav0`` is then None unless the file sits in ``mav0/imu0``),
    or None when ``path`` is none of these."""
    if path.is_dir():
        for mav in (path / "mav0", path):
            if (mav / "imu0" / "data.csv").is_file():
                return mav / "imu0" / "data.csv", mav
        return None
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as fh:
            if not fh.readline().startswith("#timestamp"):
                return None
    except OSError:
        return None
    return path, path.parent.parent if path.parent.name == "imu0" else None


def _read_euroc(
    path: str | os.PathLike[str],
    *,
    frame: str = axes.FRD,
    origin: tuple[float, float, float] = local.NOMINAL_ORIGIN,
) -> EurocRead:
    """Read a EuRoC/TUM-VI recording (see the module docstring).

    Parameters
    ----------
    path : the folder above ``mav0``, ``mav0``, or an ASL IMU file (``mav0/imu0/data.csv``)
    frame : the axes of S in body terms (:mod:`sins.io.axes`); the default takes S as it is
    origin : ``(lat, lon, h)`` (rad, rad, m) of the reference frame R's origin

    Raises
    ------
    SinsInputError
        no ``imu0/data.csv``; a header that is not the ASL one; a cell that is not a number (naming
        file, line and column); stamps that do not increase; readings beyond sins's ranges.
    """
    path = Path(path)
    found = locate(path)
    if found is None:
        raise SinsInputError(f"{path}: not a EuRoC/TUM-VI recording (no mav0/imu0/data.csv)")
    csv, mav = found
    m = axes.frame_matrix(frame)
    stamps, values = _read_asl_csv(csv, 6)
    t0 = int(stamps[0])
    _check_readings(csv, values)
    imu = ImuRates(t=(stamps - t0) / 1e9, omega_ib_b=axes.to_frd(values[:, :3], m),
                   f_ib_b=axes.to_frd(values[:, 3:], m))  # fmt: skip
    notes = [f"{csv}: {len(stamps)} readings on the sensor's axes S, taken as {frame}"]
    truth = None
    for folder, width in REFERENCES.items():
        ref = (mav or csv.parent) / folder / "data.csv"
        # A folder, a FIFO or a broken link where the reference's file should be is refused by name
        # (check_input), not taken for a recording without a reference.
        if mav is not None and (ref.exists() or ref.is_symlink()):
            truth, turned = _reference(ref, width, t0, origin, m, (stamps, values[:, 3:]))
            nominal = origin == local.NOMINAL_ORIGIN  # R's heading is never known (the module docstring)
            notes.append(
                f"reference {ref}: {len(truth.t)} poses, room frame R taken as ENU at "
                + (local.NOMINAL_PLACE if nominal else local.describe_origin(origin))
                + f": {local.room_frame_rate(not nominal)}"
            )
            if turned:
                notes.append(f"{ref}: {turned}")
            break
    return EurocRead(imu, t0, _rate(csv.parent / "sensor.yaml"), truth, tuple(notes))


def _read_asl_csv(path: Path, width: int) -> tuple[NDArray[np.int64], Array]:
    """An ASL CSV: integer nanosecond stamps (n,) and ``width`` float columns (n, width).

    Raises
    ------
    SinsInputError
        a header not starting with ``#timestamp``; a row with another number of cells; a cell that
        is not a number or not finite (naming the line and column); stamps that do not increase.
    """
    lines = _lines(path)
    header = lines[0] if lines else ""
    if not header.lstrip("\ufeff").startswith("#timestamp"):
        raise SinsInputError(
            f"{path}:1: expected the ASL header '#timestamp [ns],...', found {header[:40]!r}"
        )
    names = [c.strip() for c in header.split(",")]
    if len(names) < width + 1:
        raise SinsInputError(f"{path}:1: expected {width + 1} or more columns, the header has {len(names)}")
    stamps: list[int] = []
    rows: list[list[float]] = []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        cells = line.split(",")
        if len(cells) != len(names):
            raise SinsInputError(f"{path}:{number}: expected {len(names)} values, found {len(cells)}")
        stamps.append(_int_cell(path, number, names[0], cells[0]))
        rows.append([_float_cell(path, number, names[i + 1], cells[i + 1]) for i in range(width)])
    if not stamps:
        raise SinsInputError(f"{path}: no data rows after the header")
    t = np.array(stamps, dtype=np.int64)
    if (k := formats.first_not_increasing(t)) is not None:
        raise SinsInputError(
            f"{path}:{k + 2}: column {names[0]!r}: stamp {t[k]} ns does not increase (previous {t[k - 1]} ns)"
        )
    return t, np.array(rows, dtype=float).reshape(len(rows), width)


def _lines(path: Path) -> list[str]:
    """``path``'s lines, or a one-line error (missing, a folder, not a regular file, unreadable, not
    UTF-8)."""
    check_input(path)
    try:
        return path.read_text(encoding="utf-8-sig").splitlines()
    except FileNotFoundError:
        raise SinsInputError(f"{path}: no such file") from None
    except UnicodeDecodeError as exc:
        raise SinsInputError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise SinsInputError(f"{path}: cannot read: {exc.strerror or exc}") from None


def _int_cell(path: Path, number: int, name: str, cell: str) -> int:
    text = cell.strip()
    if not re.fullmatch(r"[0-9]+", text):
        raise SinsInputError(f"{path}:{number}: column {name!r}: not a whole number of nanoseconds: {text!r}")
    if len(text) > 19 or int(text) > MAX_STAMP_NS:
        raise SinsInputError(
            f"{path}:{number}: column {name!r}: stamp {text[:30]} ns is beyond {MAX_STAMP_NS} ns (the year "
            "2262, the largest 64-bit nanosecond stamp)"
        )
    return int(text)


def _float_cell(path: Path, number: int, name: str, cell: str) -> float:
    try:
        if "_" in cell:
            raise ValueError
        value = float(cell)
    except ValueError:
        raise SinsInputError(f"{path}:{number}: column {name!r}: not a number: {cell.strip()!r}") from None
    if not np.isfinite(value):
        raise SinsInputError(f"{path}:{number}: column {name!r}: non-finite value {value!r}")
    return value


def _check_readings(path: Path, values: Array) -> None:
    limits = np.repeat([formats.MAX_RATE_RADPS, formats.MAX_FORCE_MPS2], 3)
    bad = np.abs(values) > limits
    if bad.any():
        r, c = (int(i) for i in np.argwhere(bad)[0])
        raise SinsInputError(
            f"{path}:{r + 2}: column {c + 2}: {values[r, c]!r} {'rad/s' if c < 3 else 'm/s²'} is beyond "
            f"±{limits[c]:g}, outside any physical range"
        )


def _reference(
    path: Path, width: int, t0: int, origin: tuple[float, float, float], m: Array,
    readings: tuple[NDArray[np.int64], Array],
) -> tuple[NavSeries, str]:  # fmt: skip
    """The poses of S in R (ENU) as a geodetic trajectory of the body on the axes ``m`` names, R turned to
    put its up at z where it lies along another of its axes (:func:`sins.io.local.levelled`, judged by
    the specific force of ``readings``, S's stamps and forces), and the note that says so (else "")."""
    stamps, a = _read_asl_csv(path, width)
    q_xyzw = np.column_stack([a[:, 4:7], a[:, 3]])
    norm = np.linalg.norm(q_xyzw, axis=1)
    if (np.abs(norm - 1.0) > 1e-3).any():
        k = int(np.argmax(np.abs(norm - 1.0) > 1e-3))
        raise SinsInputError(f"{path}:{k + 2}: q_RS has norm {norm[k]:.6g}, not a unit quaternion")
    t = (stamps - t0) / 1e9
    _check_range(path, a[:, :3], 0, formats.MAX_POSITION_M, "m")
    if width >= 10:
        _check_range(path, a[:, 7:10], 7, formats.MAX_SPEED_MPS, "m/s")
    p = a[:, :3]
    v = a[:, 7:10] if width >= 10 else (np.gradient(p, t, axis=0) if len(t) > 1 else np.zeros_like(p))
    t_imu, f_imu = (readings[0] - t0) / 1e9, readings[1]
    f_s = np.column_stack([np.interp(t, t_imu, f_imu[:, i]) for i in range(3)])
    q_xyzw, v_w, p_w, turned = local.levelled(t, f_s, q_xyzw / norm[:, None], v, p)
    track = local.enu_track(
        t, p_w, origin, q_enu_body=q_xyzw, v_enu=v_w if width >= 10 else None, body_to_frd=m,
        source=str(path),
    )  # fmt: skip
    return track, turned


def _check_range(path: Path, values: Array, first: int, limit: float, unit: str) -> None:
    """Refuse a reference's position or velocity (``values``, its columns from ``first`` after the
    stamp) beyond ``limit``, naming the line and column, as the ``.npz`` reader does: one row at 1e300 m
    had fitted a model, and 1e30 m/s integrated to a drift table."""
    found = formats.first_beyond(values, limit)
    if found is not None:
        r, c = found
        raise SinsInputError(
            f"{path}:{r + 2}: column {first + c + 2}: {values[r, c]:g} {unit} is beyond ±{limit:g}, outside "
            "any physical range"
        )


def _rate(path: Path) -> float | None:
    """``rate_hz`` from a ``sensor.yaml``, or None."""
    try:
        check_input(path)
        text = path.read_text(encoding="utf-8", errors="replace")
    except (OSError, SinsInputError):
        return None
    match = re.search(r"^\s*rate_hz\s*:\s*([0-9.eE+-]+)\s*$", text, flags=re.MULTILINE)
    try:
        rate = float(match.group(1)) if match else None
    except ValueError:
        return None
    return rate if rate is not None and np.isfinite(rate) and rate > 0 else None


__all__ = [
    "MAX_STAMP_NS",
    "REFERENCES",
    "EurocRead",
    "locate",
    "read_beside",
]
