"""The PSINS static ring-laser-gyro record (``psins_lasergyro_static/``; BSD 2-clause, Gongmin Yan,
NWPU Xi'an, from the PSINS toolbox's ``data/lasergyro.imu``)
    31 min of a ring-laser-gyro strapdown INS standing still at 34.246°N, 380 m,
    100 Hz angle and velocity increments in the toolbox's compact SIMU text,
    kept xz-compressed. :func:`_read_psins_lasergyro` returns it as
    :class:`~sins.core.series.CalibrationData` with Earth rate and normal gravity as
    the reference.

The file's rows are integers in LSB (0.1 arcsec for the gyros, 125 µg·s for the accelerometers, µg
being 1e-6 × the header's g = 9.780327 m/s², PSINS ``glv.g0``), one row per 10 ms interval, in PSINS's
x-right, y-forward, z-up body axes. What the data show through this reader (units, rate, Earth rate,
attitude, the base's motion, the bursty output) and what its reference can judge are in
``docs/guide/datasets.md``.
"""

from __future__ import annotations

import lzma
import math
import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sins.core import earth, rotation
from sins.core.series import CalibrationData
from sins.errors import SinsInputError
from sins.io.datasets.root import check_magnitude, dataset_file
from sins.io.formats import MAX_FORCE_MPS2, MAX_RATE_RADPS

Array = NDArray[np.float64]

PSINS_LASERGYRO_FOLDER = "psins_lasergyro_static"
PSINS_LASERGYRO_FILE = "lasergyro.imu.xz"
#: Body axes: PSINS's x-right, y-forward, z-up to the package's x-forward, y-right, z-down
#: (``v_frd = PSINS_TO_FRD @ v_psins``; a proper rotation, determinant +1, so rates keep their sign rule).
PSINS_TO_FRD: Array = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: Refuse the record when its mean specific force is off normal gravity at the header's position by more
#: than this fraction: then it is not a static record in the units the header states (this one: −4.4e-6).
#: A wrong interval or scale shows as a percent-level or larger error; the local gravity anomaly
#: (tens of mGal, 1e-5 g) and a navigation or tactical accelerometer's bias (≤ 1 mg) stay far below it.
MAX_GRAVITY_MISMATCH = 0.01
#: The first line of a PSINS SIMU text file names it so; the toolbox's ``imufile.m`` checks both words.
_MAGIC = ("PSINS", "SIMU")
_ARCSEC_RAD = math.pi / (180.0 * 3600.0)


def _read_psins_lasergyro(root: str | os.PathLike[str] | None = None) -> CalibrationData:
    """The static ring-laser-gyro record ``psins_lasergyro_static/lasergyro.imu.xz``.

    Readings: the file's angle and velocity increments (LSB × the header's
    scale: 0.1 arcsec, 125 µg·s) divided by the 10 ms sample interval, i.e.
    each row's mean rate and specific force over its interval, in rad/s and
    m/s², rotated from PSINS's x-right, y-forward, z-up body axes to FRD
    (:data:`PSINS_TO_FRD`). Time: the file has none; PSINS stamps row ``k``
    (from 1) at ``t0 + k·ts``, the end of its interval; here it is the
    interval's midpoint ``t0 + (k − ½)·ts``, where an interval mean equals the
    instantaneous rate to second order (the package's rate form), so ``t``
    runs 0.005, 0.015, … s. Temperature is not recorded (``temp`` is None);
    no phases.

    Reference, constant, body axes: the unit stands still at the header's
    34.246048°N, 380 m, so ``ref_gyro = C_nbᵀ ω_ie_n(lat)`` (15.04 °/h) and
    ``ref_accel = C_nbᵀ (0, 0, −g)`` with WGS84 normal gravity
    ``g(lat, h) = 9.79553 m/s²``. The attitude ``C_nb``:

    * roll and pitch from the record's mean specific force (a coarse
      levelling), not the header's (zeros the data contradict: placeholders).
    * heading from the header, 90.6° (PSINS's yaw −90.6°, counter-clockwise
      from north; the body faces east). It is not measured here.

    The tilt so taken absorbs the horizontal accelerometers' constant biases, and one static
    orientation cannot tell a bias from a scale or misalignment error: what this reference can and
    cannot judge, with the heading checked by gyrocompassing, is in ``docs/guide/datasets.md``.

    Parameters
    ----------
    root : the data root, or None for :func:`data_root`

    Returns
    -------
    CalibrationData
        ``t`` (184718,) s, ``gyro`` and ``accel`` (184718, 3) rad/s and m/s²,
        ``ref_gyro`` and ``ref_accel`` (184718, 3), the same row repeated;
        ``temp`` None; no phases; ``source`` the ``.xz`` path.

    Raises
    ------
    SinsInputError
        one line: a missing folder or file (saying how to point at the data),
        a file that is not xz or not a PSINS SIMU text, a malformed header or
        data line (with its line number), a record whose mean specific force
        is not gravity (not static, or not in the stated units).
    """
    path = dataset_file(PSINS_LASERGYRO_FOLDER, PSINS_LASERGYRO_FILE, root)
    header, increments = _read_simu(path)
    (_pitch0, _roll0, yaw0_deg, *_), (lat_deg, _lon, h, t0, ts_ms, g_unit), scales = header

    ts = ts_ms / 1000.0
    to_si = np.r_[np.asarray(scales[:3]) * _ARCSEC_RAD, np.asarray(scales[3:]) * 1e-6 * g_unit] / ts
    rates = increments * to_si
    check_magnitude(path, "gyro rate (increment × scale / interval)", rates[:, :3], MAX_RATE_RADPS, "rad/s")
    check_magnitude(
        path, "specific force (increment × scale / interval)", rates[:, 3:], MAX_FORCE_MPS2, "m/s²"
    )
    gyro = rates[:, :3] @ PSINS_TO_FRD.T
    accel = rates[:, 3:] @ PSINS_TO_FRD.T
    n = len(rates)

    lat = math.radians(lat_deg)
    g = float(earth.normal_gravity(lat, h))
    f_mean = accel.mean(axis=0)
    mismatch = float(np.linalg.norm(f_mean)) / g - 1.0
    if abs(mismatch) > MAX_GRAVITY_MISMATCH:
        raise SinsInputError(
            f"{path}: the mean specific force {np.linalg.norm(f_mean):.6g} m/s² is not normal gravity "
            f"{g:.6g} m/s² at {lat_deg:g}° {h:g} m ({100 * mismatch:+.3g} %): not a static record in the "
            f"header's units ({ts_ms:g} ms, scales {' '.join(f'{s:g}' for s in scales)})"
        )
    # Coarse levelling: at rest f_b = C_nbᵀ (0, 0, −g) = g (sin θ, −sin φ cos θ, −cos φ cos θ).
    roll = math.atan2(-f_mean[1], -f_mean[2])
    pitch = math.atan2(f_mean[0], math.hypot(f_mean[1], f_mean[2]))
    C_nb = rotation.dcm_from_euler(roll, pitch, -math.radians(yaw0_deg))  # PSINS yaw: counter-clockwise
    ref_gyro = C_nb.T @ np.array(earth.earth_rate_n(lat), dtype=float)
    ref_accel = C_nb.T @ np.array([0.0, 0.0, -g])
    return CalibrationData(
        t=t0 + (np.arange(n, dtype=float) + 0.5) * ts,
        gyro=gyro,
        accel=accel,
        ref_gyro=np.tile(ref_gyro, (n, 1)),
        ref_accel=np.tile(ref_accel, (n, 1)),
        temp=None,
        phases=(),
        source=str(path),
    )


def _read_simu(path: Path) -> tuple[tuple[tuple[float, ...], ...], Array]:
    """The three header lines (six numbers each) and the (n, 6) increments in LSB of a PSINS SIMU text.

    ``%`` starts a comment (to the end of the line, as MATLAB's ``load`` reads it); blank lines are
    skipped. Validated: the magic words on line 1, six numbers per header line, a positive interval, a
    latitude in [−90°, 90°], positive scales and g, six integers on every data line, at least one.
    """
    try:
        with lzma.open(path, "rt", encoding="ascii") as fh:
            text = fh.read()
    except (lzma.LZMAError, EOFError) as exc:
        raise SinsInputError(f"{path}: not a readable xz file: {exc}") from None
    except UnicodeDecodeError as exc:
        raise SinsInputError(f"{path}: not ASCII text after decompression: {exc.reason}") from None
    except OSError as exc:
        raise SinsInputError(f"{path}: cannot read: {exc}") from None
    lines = text.splitlines()
    first = lines[0] if lines else ""
    if not all(word in first for word in _MAGIC):
        raise SinsInputError(
            f"{path}:1: not a PSINS SIMU text file (its first line does not name both PSINS and SIMU)"
        )
    numbered = [(i + 1, body) for i, line in enumerate(lines) if (body := line.split("%", 1)[0].strip())]
    if len(numbered) < 4:
        found = f"{len(numbered)} of the 3 header lines" if len(numbered) < 3 else "the 3 header lines"
        raise SinsInputError(f"{path}: {found} and no data rows; a SIMU text needs both")

    what = (
        "pitch0 roll0 yaw0 (deg) VE0 VN0 VU0 (m/s)",
        "lat0 lon0 (deg) h0 (m) t0 (s) interval (ms) g (m/s²)",
        "gyro scales (arcsec/LSB) accelerometer scales (µg·s/LSB)",
    )
    header: list[tuple[float, ...]] = []
    for (number, body), names in zip(numbered[:3], what, strict=True):
        try:
            values = tuple(float(v) for v in body.split())
        except ValueError:
            values = ()
        if len(values) != 6 or not all(math.isfinite(v) for v in values):
            raise SinsInputError(f"{path}:{number}: expected 6 numbers ({names}), found {body[:80]!r}")
        header.append(values)
    number = numbered[1][0]
    lat_deg, ts_ms, g_unit = header[1][0], header[1][4], header[1][5]
    if not (-90.0 <= lat_deg <= 90.0 and ts_ms > 0.0 and g_unit > 0.0):
        raise SinsInputError(
            f"{path}:{number}: latitude {lat_deg:g}° must be in [-90, 90], the interval {ts_ms:g} ms and "
            f"g {g_unit:g} m/s² positive"
        )
    if not all(s > 0.0 for s in header[2]):
        raise SinsInputError(f"{path}:{numbered[2][0]}: scales must be positive, found {header[2]}")

    data = numbered[3:]
    try:
        flat = np.array(" ".join(body for _, body in data).split(), dtype=np.int64)
    except (ValueError, OverflowError):
        flat = np.zeros(0, dtype=np.int64)
    if flat.size != 6 * len(data):
        for number, body in data:
            fields = body.split()
            if len(fields) != 6 or not all(_is_int(f) for f in fields):
                raise SinsInputError(
                    f"{path}:{number}: expected 6 integers (gyro x y z, accelerometer x y z increments in "
                    f"LSB), found {body[:80]!r}"
                )
        raise SinsInputError(f"{path}: an increment does not fit a 64-bit integer")
    return tuple(header), flat.reshape(-1, 6).astype(float)


def _is_int(field: str) -> bool:
    try:
        int(field)
    except ValueError:
        return False
    return True


__all__ = [
    "MAX_GRAVITY_MISMATCH",
    "PSINS_LASERGYRO_FILE",
    "PSINS_LASERGYRO_FOLDER",
    "PSINS_TO_FRD",
]
