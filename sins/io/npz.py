"""Recordings in NumPy's ``.npz`` form: readings beside a reference at every reading, in a room frame.

The form is that of ``shared/data/euroc`` (its SOURCE.md): one ``NAME.npz`` per recording with the keys

========== ====== ================================================================
key        shape  meaning
========== ====== ================================================================
t_s        (n,)   time, s, increasing (absolute stamps or from the start)
gyro_rad_s (n, 3) angular rate, rad/s, the sensor's own axes
accel_m_s2 (n, 3) specific force, m/s², the sensor's own axes
q_wxyz     (n, 4) reference attitude of the sensor's axes in the world frame, w first
v_m_s      (n, 3) reference velocity, world frame, m/s
p_m        (n, 3) reference position, world frame, m
========== ====== ================================================================

The reference keys are all present or all absent (readings alone). The world frame is gravity-aligned
with z up; where north lies in it and at what latitude it was recorded are not known. sins takes it as
ENU at 45° N, 0° E, 0 m (:data:`sins.io.local.NOMINAL_ORIGIN`: its normal gravity is within 0.026
m/s² of any site's), or at the origin given for the place (``--origin``), and says so: the recording's
:attr:`~sins.io.Recording.heading_known` is False, and :attr:`~sins.io.Recording.latitude_known` too
without an origin, so that Earth's rate, which cannot be placed in such a frame, is left out of what is
judged against it (the published open-loop figures leave it out too). A world frame whose up lies along
another of its axes (y up, as motion capture often writes it; z down) is read turned to z up, and the
notes say so (:func:`sins.io.local.levelled`). Times are made relative to the first reading
(``t0_ns`` keeps the absolute stamp).
"""

from __future__ import annotations

import os
import zipfile
import zlib
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sins.core.series import ImuRates, NavSeries
from sins.errors import SinsInputError
from sins.io import axes, formats, local

Array = NDArray[np.float64]

#: The readings' keys, always present.
READING_KEYS = ("t_s", "gyro_rad_s", "accel_m_s2")
#: The reference's keys, all present or all absent.
REFERENCE_KEYS = ("q_wxyz", "v_m_s", "p_m")
#: Columns of each key.
WIDTH = {"t_s": 1, "gyro_rad_s": 3, "accel_m_s2": 3, "q_wxyz": 4, "v_m_s": 3, "p_m": 3}
#: The largest recording read, rows: 2^26 (a day at 777 Hz), about 3.5 GB of float64 once converted.
MAX_ROWS = 1 << 26
#: The largest reference position and speed taken as physical (:mod:`sins.io.formats`'s, as every reader).
MAX_POSITION_M, MAX_SPEED_MPS = formats.MAX_POSITION_M, formats.MAX_SPEED_MPS


def is_npz(path: Path) -> bool:
    """Whether ``path`` is a file that reads as an ``.npz`` (its name, then a zip archive's first bytes: a
    cut or damaged archive is then refused as one, not read as a CSV that is "not UTF-8")."""
    if path.suffix.lower() != ".npz" or not path.is_file():
        return False
    try:
        with open(path, "rb") as fh:
            return fh.read(4) in (b"PK\x03\x04", b"PK\x05\x06")
    except OSError:
        return False


def _read_npz(
    path: str | os.PathLike[str],
    *,
    frame: str = axes.FRD,
    origin: tuple[float, float, float] | None = None,
) -> tuple[ImuRates, NavSeries | None, float, tuple[str, ...]]:
    """An ``.npz`` recording (see the module docstring): readings in rate form, the reference as a
    trajectory on the ellipsoid (None without one), the absolute time of ``t = 0`` in s, and notes for
    the user. ``frame`` names the sensor's axes in body terms (:mod:`sins.io.axes`); the default takes
    them as they are, and the reference's attitude is of the same axes. ``origin``: ``(lat, lon, h)``
    (rad, rad, m) of the world frame's origin; None: :data:`sins.io.local.NOMINAL_ORIGIN`.

    Raises
    ------
    SinsInputError
        one line naming the file and the key: not an ``.npz`` archive, a missing key, a key of the wrong
        shape, lengths that differ, a value that is not finite or beyond sins's ranges, time that does
        not increase, a quaternion that is not of unit length, more than :data:`MAX_ROWS` rows.
    """
    path = Path(path)
    arrays, unread = _load(path)
    t_abs = arrays["t_s"].reshape(-1)
    if (k := formats.first_not_increasing(t_abs)) is not None:
        raise SinsInputError(
            f"{path}: t_s: row {k + 1}: {float(t_abs[k])!r} s does not increase "
            f"(row {k}: {float(t_abs[k - 1])!r} s)"
        )
    t = t_abs - t_abs[0]
    _check_range(path, "gyro_rad_s", arrays["gyro_rad_s"], formats.MAX_RATE_RADPS, "rad/s")
    _check_range(path, "accel_m_s2", arrays["accel_m_s2"], formats.MAX_FORCE_MPS2, "m/s²")
    m = axes.frame_matrix(frame)
    imu = ImuRates(
        t=t, omega_ib_b=axes.to_frd(arrays["gyro_rad_s"], m), f_ib_b=axes.to_frd(arrays["accel_m_s2"], m)
    )
    notes = [f"{path}: {len(t)} readings on the sensor's axes, taken as {frame.lower()}"]
    if unread:
        notes.append(f"{path}: not read (not of the form): {', '.join(unread)}")
    truth = None
    if "q_wxyz" in arrays:
        _check_range(path, "p_m", arrays["p_m"], MAX_POSITION_M, "m")
        _check_range(path, "v_m_s", arrays["v_m_s"], MAX_SPEED_MPS, "m/s")
        q = arrays["q_wxyz"]
        with np.errstate(over="ignore"):  # a quaternion of 1e300: its norm overflows to inf, refused below
            norm = np.linalg.norm(q, axis=1)
        off = np.flatnonzero(np.abs(norm - 1.0) > 1e-3)
        if off.size:
            k = int(off[0])
            raise SinsInputError(f"{path}: q_wxyz: row {k + 1} has norm {norm[k]:.6g}, not a unit quaternion")
        q_xyzw = np.column_stack([q[:, 1:], q[:, 0]]) / norm[:, None]
        q_xyzw, v_w, p_w, turned = local.levelled(
            t, arrays["accel_m_s2"], q_xyzw, arrays["v_m_s"], arrays["p_m"]
        )
        if turned:
            notes.append(f"{path}: {turned}")
        v_w, lagged = local.on_positions_clock(t, v_w, p_w)
        if lagged:
            notes.append(f"{path}: {lagged}")
        truth = local.enu_track(
            t,
            p_w,
            local.NOMINAL_ORIGIN if origin is None else origin,
            q_enu_body=q_xyzw,
            v_enu=v_w,
            body_to_frd=m,
            source=str(path),
        )
        place = (
            local.NOMINAL_PLACE if origin is None else f"the given origin ({local.describe_origin(origin)})"
        )
        placed = f"taken as ENU at {place}: {local.room_frame_rate(origin is not None)}"
        notes.append(f"reference at every reading; its world frame (z up) {placed}")
    return imu, truth, float(t_abs[0]), tuple(notes)


def _load(path: Path) -> tuple[dict[str, Array], list[str]]:
    """The arrays of ``path`` as float64, checked for presence, shape, length and finiteness; and the
    keys that are not of the form (not read, said in the notes)."""
    try:
        with np.load(path, allow_pickle=False) as archive:
            names = set(archive.files)
            missing = [k for k in READING_KEYS if k not in names]
            if missing:
                raise SinsInputError(
                    f"{path}: no key {missing[0]!r} (an .npz recording holds {', '.join(READING_KEYS)}, and "
                    f"for a reference {', '.join(REFERENCE_KEYS)})"
                )
            have_ref = [k for k in REFERENCE_KEYS if k in names]
            if have_ref and len(have_ref) < len(REFERENCE_KEYS):
                lacking = next(k for k in REFERENCE_KEYS if k not in names)
                raise SinsInputError(
                    f"{path}: has {have_ref[0]!r} but no {lacking!r}: the reference needs all of "
                    f"{', '.join(REFERENCE_KEYS)}"
                )
            out = {k: _array(path, archive, k) for k in (*READING_KEYS, *have_ref)}
            unread = sorted(names - set(WIDTH))
    except SinsInputError:
        raise  # already one line naming the file and the key (it is a ValueError too)
    except (OSError, ValueError, EOFError, RuntimeError, zlib.error, zipfile.BadZipFile) as exc:
        # RuntimeError: a member flagged encrypted ("password required"); zlib.error, EOFError: a
        # compressed member damaged
        raise SinsInputError(f"{path}: not a readable .npz archive ({exc})") from None
    n = len(out["t_s"])
    for key, value in out.items():
        if len(value) != n:
            raise SinsInputError(f"{path}: {key} has {len(value)} rows; t_s has {n}")
    if n < 2:
        raise SinsInputError(f"{path}: {n} reading(s); at least two are needed")
    return out, unread


def _claimed(path: Path, archive: np.lib.npyio.NpzFile, key: str) -> None:
    """Refuse a member whose header asks for more rows than sins reads, or more bytes than the member
    holds, before numpy allocates them: a 5 kB file whose header claims 1e12 rows had asked for 7 TiB."""
    members = archive.zip
    if members is None:  # (np.load of a path always opens its zip; closed, the read below says so)
        return
    info = members.getinfo(f"{key}.npy")
    with members.open(info) as member:
        fmt = np.lib.format
        read = fmt.read_array_header_1_0 if fmt.read_magic(member) == (1, 0) else fmt.read_array_header_2_0
        shape, _, dtype = read(member)
    rows = int(shape[0]) if shape else 1
    need = int(np.prod(shape, dtype=object)) * dtype.itemsize
    if rows > MAX_ROWS:
        raise SinsInputError(f"{path}: {key} has {rows} rows; sins reads at most {MAX_ROWS}")
    if need > info.file_size:
        raise SinsInputError(
            f"{path}: {key}'s header claims shape {shape} ({need} bytes); the member holds {info.file_size}"
        )


def _array(path: Path, archive: np.lib.npyio.NpzFile, key: str) -> Array:
    """One key as a float64 array of its :data:`WIDTH` columns, every value finite."""
    _claimed(path, archive, key)
    raw = archive[key]
    width = WIDTH[key]
    shape_ok = raw.ndim == 1 if width == 1 else raw.ndim == 2 and raw.shape[1] == width
    if not shape_ok:
        want = "(n,)" if width == 1 else f"(n, {width})"
        raise SinsInputError(f"{path}: {key} has shape {raw.shape}; expected {want}")
    if raw.dtype.kind not in "fiu":
        raise SinsInputError(f"{path}: {key} holds {raw.dtype} values; expected numbers")
    if len(raw) > MAX_ROWS:
        raise SinsInputError(f"{path}: {key} has {len(raw)} rows; sins reads at most {MAX_ROWS}")
    value = np.asarray(raw, dtype=np.float64)
    bad = ~np.isfinite(value)
    if bad.any():
        r = int(np.argwhere(bad)[0][0])
        raise SinsInputError(f"{path}: {key}: row {r + 1} is not finite")
    if key == "t_s" and raw.dtype.kind == "f" and raw.dtype.itemsize < 8 and np.any(np.diff(value) <= 0.0):
        # Absolute stamps in float32 (EuRoC's readings are float32; its times must not be) collapse.
        top = float(np.abs(value).max())
        step = float(np.spacing(raw.dtype.type(top)))
        raise SinsInputError(
            f"{path}: t_s is {raw.dtype}, whose steps at {top:.4g} s are {step:.3g} s: its stamps do not "
            "increase; write t_s as float64"
        )
    return value


def _check_range(path: Path, key: str, value: Array, limit: float, unit: str) -> None:
    found = formats.first_beyond(value, limit)
    if found is not None:
        r, c = found
        raise SinsInputError(
            f"{path}: {key}: row {r + 1}, column {c + 1}: {value[r, c]:g} {unit} is beyond ±{limit:g}, "
            "outside any physical range"
        )


__all__ = [
    "MAX_POSITION_M",
    "MAX_ROWS",
    "MAX_SPEED_MPS",
    "READING_KEYS",
    "REFERENCE_KEYS",
    "WIDTH",
    "is_npz",
]
