"""BROAD, the Berlin Robust Orientation Estimation Assessment Dataset (``broad_mocap/``; CC BY 4.0;
D. Laidig, M. Caruso, A. Cereatti, T. Seel, Data 6(7), 2021, doi:10.3390/data6070072;
github.com/dlaidig/broad)
    A hand-moved MEMS IMU (myon aktos-t) with optical motion capture (OptiTrack, eight Flex13 cameras)
    of its orientation and position, both on one 285.714 Hz sample grid. :func:`_read_broad` returns a
    trial as :class:`~sins.core.series.CalibrationData`, the reference rate and specific force derived from
    the optical data.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

# scipy's io, signal and interpolate modules are imported in the functions that use them: ~0.6 s at
# import, which every command paid for any recording (tools/bench_startup.py).
import numpy as np
from numpy.typing import NDArray

from sins.core import earth, rotation
from sins.core.series import CalibrationData
from sins.errors import SinsInputError
from sins.io.datasets.matfile import check_mat_v5
from sins.io.datasets.root import check_magnitude, data_root, dataset_file
from sins.io.formats import MAX_FORCE_MPS2, MAX_RATE_RADPS

Array = NDArray[np.float64]

BROAD_FOLDER = "broad_mocap"
#: The trials copied beside the project (2 of BROAD's 39; SOURCE.md), by file stem.
BROAD_TRIALS = (
    "05_undisturbed_slow_rotation_with_breaks_B",
    "18_undisturbed_fast_translation_with_breaks_B",
)
#: Sample rate of every BROAD signal, Hz (the files' ``sampling_rate``, 2000/7 = 285.714…). The filter
#: windows below are set in seconds, but a file at another rate is not a BROAD trial: it is refused.
BROAD_RATE_HZ = 2000.0 / 7.0
#: Assumed latitude of the recording, deg: TU Berlin, where the dataset was recorded (the files do not
#: say). Normal gravity there, 9.8127 m/s², is 2.7 mm/s² above the 9.81 m/s² SOURCE.md's check used; both
#: are far below the optical specific force's noise (0.1–0.2 m/s² per sample at rest).
BROAD_LAT_DEG = 52.51
#: Assumed height above the ellipsoid, m: Berlin's ≈ 35 m above sea level plus a geoid height of
#: ≈ 40 m; 100 m of error would move g by 0.3 mm/s².
BROAD_HEIGHT_M = 75.0
#: Magnitude of gravity used for the reference specific force, m/s².
BROAD_GRAVITY = float(earth.normal_gravity(math.radians(BROAD_LAT_DEG), BROAD_HEIGHT_M))

# The optical data are OptiTrack's 120 Hz frames resampled to the IMU's grid (the autocorrelation of
# the position's second difference dips at lags 2–3 samples, 285.7/120 = 2.4), and differentiating
# them raises their noise by ω once for the rate and ω² for the acceleration. Savitzky–Golay filters
# give the smoothed value and its derivatives from one local polynomial fit: zero phase (no delay to
# confuse with the clock offset), exact for locally polynomial motion (a still or uniformly
# accelerating stretch keeps its mean, so |f| = g at rest is not biased), and no edge transient beyond
# half a window. The windows were chosen on the two trials by the RMS of gyro − reference after a
# constant bias (the gyro's own errors do not depend on the window, so that RMS falls as the
# reference's error falls), trading noise (slow trial 05 wants long windows) against attenuation of
# fast motion (trial 18 wants short ones):
#: Half-window of the orientation fit (cubic), s: 9 samples, 19 in all; gain of the derivative
#: filter −3 dB at 19 Hz, 1 % low at 7.4 Hz. The gyro's motion power is 98–99 % below 10 Hz.
_RATE_HALF_WINDOW_S = 9.0 / BROAD_RATE_HZ
_RATE_POLYORDER = 3
#: Half-window of the position fit (quintic), s: 15 samples, 31 in all; second-derivative gain −3 dB
#: at 13 Hz, 1 % low at 5 Hz. Above ≈ 10 Hz the differentiated optical noise outweighs the motion.
_ACCEL_HALF_WINDOW_S = 15.0 / BROAD_RATE_HZ
_ACCEL_POLYORDER = 5
#: Largest clock offset between the IMU and the optical data searched for, s.
_MAX_DELAY_S = 0.1
#: Peak correlation of |ω| (gyro against optical) below which the two are not taken to be one motion.
_MIN_CORRELATION = 0.5


def _read_broad(trial: str, root: str | os.PathLike[str] | None = None) -> CalibrationData:
    """One BROAD trial, ``broad_mocap/<stem>.mat``, with its reference from the optical data.

    ``trial`` is a trial's file stem or its number (``"05"``, ``"5"``, ``"18"``; see :func:`trials`).

    Readings: the file's ``imu_gyr`` (rad/s) and ``imu_acc`` (m/s²) as they are, in the IMU's own
    axes. Time is ``row / 285.714`` s with ``row`` the file's row (the file has no time stamps), so
    ``t`` keeps the recording's clock and the rows kept are ``round(t · BROAD_RATE_HZ)``. Temperature
    is not recorded (``temp`` is None); there are no phases, and the file's ``movement`` flag is not
    used.

    Rows: only the longest stretch of rows where the IMU readings and the optical orientation and
    position (NaN where the markers were not seen) are all finite, less 15 rows at each end (the
    half-window of the widest filter, so every reference comes from a centred fit), the rows kept
    moved by the clock offset rounded to a sample (the rows each trial keeps:
    ``docs/guide/datasets.md``).

    Reference, body axes (the dataset's ``opt_quat`` is the IMU frame's orientation in an ENU frame,
    aligned to the IMU by the dataset's authors; ``q = [w, x, y, z]`` rotates IMU-frame vectors into
    ENU):

    * angular rate ``ω_b = 2 vec(q* ⊗ q̇)``, ``q`` and ``q̇`` from a cubic Savitzky–Golay fit over
      19 samples (0.066 s). Earth's rate (≤ 0.004 °/s) is not added; the optical frame's heading
      is unknown and the term is far below the gyro's 0.2 °/s bias and the reference's noise.
    * specific force ``f_b = R(q)ᵀ (p̈ + [0, 0, g])`` with ``p̈`` from a quintic Savitzky–Golay fit
      of the optical position over 31 samples (0.109 s) and ``g`` = :data:`BROAD_GRAVITY` (ENU's z is
      up: at rest the accelerometer reads +9.82 m/s² along the body direction ``R(q)ᵀ [0, 0, 1]``).
      No lever arm is applied between the optical position and the accelerometer: one fitted on the
      trials does not repeat between them, and it is the very term of the diagnosis's
      ``accel.size_effect``, which is left to find it.
    * both evaluated at ``t − τ`` (cubic spline): the IMU lags the optical data by ``τ``, found per
      trial at the peak of the cross-correlation of ``|ω|`` (gyro against optical, means removed,
      parabolic sub-sample peak, searched within ±0.1 s; a peak correlation below 0.5 is refused).
      The accelerometer's own further delay is left for the diagnosis to find.

    The reference is noisier than the IMU (optical noise, differentiated), and its noise is smoothed
    over the filter windows: a gap diagnosis against it finds excess over the noise floor on every
    channel and a floor set by the reference rather than the IMU. The offsets, lever arms and the
    reference's quality measured on the two trials are in ``docs/guide/datasets.md``.

    Parameters
    ----------
    trial : a trial's file stem, or its leading number (:func:`trials`)
    root : the data root, or None for :func:`data_root`

    Returns
    -------
    CalibrationData
        ``t`` (n,) s, ``gyro`` (n, 3) rad/s, ``accel`` (n, 3) m/s², ``ref_gyro`` (n, 3) rad/s,
        ``ref_accel`` (n, 3) m/s², no NaN; no phases; ``source`` the MAT path.

    Raises
    ------
    SinsInputError
        one line: an unknown trial, a missing folder or file (saying how to point at the data), a file
        that is not a MATLAB v5 MAT file or lacks a variable, too few rows with an optical reference,
        or optical and inertial data that do not correlate.
    """
    from scipy.interpolate import CubicSpline
    from scipy.signal import savgol_filter

    stem = _stem(trial, root)
    path = dataset_file(BROAD_FOLDER, f"{stem}.mat", root)
    gyr, acc, quat, pos = _load(str(path))
    dt = 1.0 / BROAD_RATE_HZ
    rate_half = round(_RATE_HALF_WINDOW_S * BROAD_RATE_HZ)
    accel_half = round(_ACCEL_HALF_WINDOW_S * BROAD_RATE_HZ)
    edge = max(rate_half, accel_half)

    valid = np.asarray(np.isfinite(np.hstack([gyr, acc, quat, pos])).all(axis=1), dtype=np.bool_)
    start, stop = _longest_run(valid)
    if stop - start < 4 * edge + 2:
        raise SinsInputError(
            f"{path}: the longest stretch with an optical reference has {stop - start} rows; "
            f"at least {4 * edge + 2} are needed"
        )
    # Scalar-last, and one sign throughout, so that the fits see a continuous curve.
    q = quat[start:stop][:, [1, 2, 3, 0]]
    norm = np.linalg.norm(q, axis=1)
    if np.abs(norm - 1.0).max() > 1e-3:
        r = int(np.argmax(np.abs(norm - 1.0))) + start
        raise SinsInputError(
            f"{path}: 'opt_quat' row {r} has norm {norm[r - start]:.6g}, not a unit quaternion"
        )
    flips = np.cumsum(np.r_[False, np.sum(q[1:] * q[:-1], axis=1) < 0.0]) % 2 == 1
    q = np.where(flips[:, None], -q, q)

    # Body rate from the quaternion's derivative: ω_b = 2 vec(q* ⊗ q̇), divided by |q|² since the
    # fitted q is not exactly unit. Checked numerically: the body-frame rate (q[k-1]* ⊗ q[k+1]) follows
    # the gyro with correlation 0.974–0.997 per axis; the same in the world frame (q[k+1] ⊗ q[k-1]*)
    # only 0.29–0.98.
    n_rate = 2 * rate_half + 1
    qs = savgol_filter(q, n_rate, _RATE_POLYORDER, axis=0)
    qd = savgol_filter(q, n_rate, _RATE_POLYORDER, deriv=1, delta=dt, axis=0)
    q2 = np.sum(qs * qs, axis=1, keepdims=True)
    omega = 2.0 * rotation.quat_multiply(rotation.quat_conjugate(qs), qd)[:, :3] / q2
    a_n = savgol_filter(pos[start:stop], 2 * accel_half + 1, _ACCEL_POLYORDER, deriv=2, delta=dt, axis=0)
    q_unit = qs / np.sqrt(q2)
    f_b = rotation.rotate(rotation.quat_conjugate(q_unit), a_n + np.array([0.0, 0.0, BROAD_GRAVITY]))

    delay = _delay(str(path), gyr[start:stop], omega)
    rows = np.arange(start, stop)
    t_all = rows * dt
    t_ref = t_all - delay
    # Kept: rows whose delayed time rounds to a sample with a centred fit.
    keep = (t_ref >= t_all[edge] - 0.5 * dt) & (t_ref <= t_all[-1 - edge] + 0.5 * dt)
    ref = CubicSpline(t_all, np.hstack([omega, f_b]), axis=0)(t_ref[keep])
    kept = rows[keep]
    return CalibrationData(
        t=t_all[keep],
        gyro=gyr[kept].copy(),
        accel=acc[kept].copy(),
        ref_gyro=ref[:, :3],
        ref_accel=ref[:, 3:],
        temp=None,
        phases=(),
        source=str(path),
    )


def trials(root: str | os.PathLike[str] | None = None) -> dict[str, str]:
    """The BROAD trials in the data root's ``broad_mocap/``, by number: every ``NN_*.mat`` there.

    BROAD has 39 trials; the project keeps two (:data:`BROAD_TRIALS`). A user who has more puts them in
    the folder and each becomes ``broad_NN``. Without the folder, or with none there, the two kept trials
    are named (their readers then say the files are missing).

    Returns
    -------
    ``{"05": "05_undisturbed_slow_rotation_with_breaks_B", ...}`` in number order
    """
    folder = data_root(root) / BROAD_FOLDER
    found = {s[:2]: s for s in BROAD_TRIALS}
    if folder.is_dir():
        found = {
            p.stem[:2]: p.stem for p in folder.glob("*.mat") if re.fullmatch(r"\d\d_.+", p.stem)
        } or found
    return dict(sorted(found.items()))


def sensor_of(stem: str) -> str:
    """The IMU a trial was recorded with: the letter that ends its name (BROAD's units A–D), or "" when
    its name carries none (the combined and magnet trials)."""
    letter = re.search(r"_([A-D])$", stem)
    return f"BROAD IMU {letter.group(1)} (myon aktos-t)" if letter else ""


def _stem(trial: str, root: str | os.PathLike[str] | None = None) -> str:
    """The file stem of ``trial``: a trial's stem or its number."""
    text = str(trial).strip()
    known = trials(root)
    if text in known.values():
        return text
    if re.fullmatch(r"\d{1,2}", text) and f"{int(text):02d}" in known:
        return known[f"{int(text):02d}"]
    numbers = ", ".join(known)
    raise SinsInputError(
        f"trial {trial!r}: unknown BROAD trial in {data_root(root) / BROAD_FOLDER}; expected a trial's "
        f"number ({numbers}) or its file stem"
    )


def _load(path: str) -> tuple[Array, Array, Array, Array]:
    """``imu_gyr, imu_acc, opt_quat, opt_pos`` of a BROAD MAT file, shapes checked, rate checked."""
    import scipy.io

    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise SinsInputError(f"{path}: cannot read: {exc.strerror or exc}") from None
    check_mat_v5(path, raw, "not a readable MATLAB MAT file")  # scipy crashes on some damage
    try:
        mat = scipy.io.loadmat(path, squeeze_me=True)
    except NotImplementedError:  # scipy's answer to a v7.3 (HDF5) file
        raise SinsInputError(
            f"{path}: a MATLAB v7.3 (HDF5) file; this reader takes the v5 files of BROAD's data_mat/"
        ) from None
    # A damaged file fails inside scipy's parser with whatever it tripped on (OSError, ValueError,
    # IndexError, zlib.error, MatReadError were all seen), so any exception means "not readable".
    except Exception as exc:
        text = " ".join(str(exc).split()) or type(exc).__name__
        raise SinsInputError(f"{path}: not a readable MATLAB MAT file: {text}") from None
    out = []
    for name, width in (("imu_gyr", 3), ("imu_acc", 3), ("opt_quat", 4), ("opt_pos", 3)):
        if name not in mat:
            raise SinsInputError(f"{path}: no variable {name!r}")
        a = np.asarray(mat[name])
        if a.ndim != 2 or a.shape[1] != width or not np.issubdtype(a.dtype, np.number):
            raise SinsInputError(
                f"{path}: variable {name!r}: expected N × {width} numbers, found shape {a.shape} of {a.dtype}"
            )
        out.append(a.astype(float))
    # NaN marks a row without a reading or a marker (the longest finite stretch is kept); ±inf or an
    # absurd value is damage. The optical position is within a room: ±1 km is far beyond it.
    for name, a, limit, unit in zip(("imu_gyr", "imu_acc", "opt_quat", "opt_pos"), out,
                                    (MAX_RATE_RADPS, MAX_FORCE_MPS2, 2.0, 1000.0), ("rad/s", "m/s²", "", "m"),
                                    strict=True):  # fmt: skip
        check_magnitude(path, f"variable {name!r}", a, limit, unit, nan_ok=True)
    if len({len(a) for a in out}) != 1:
        raise SinsInputError(
            f"{path}: imu_gyr, imu_acc, opt_quat and opt_pos have {', '.join(str(len(a)) for a in out)} rows"
        )
    rate = mat.get("sampling_rate")
    try:
        rate_hz = float(np.asarray(rate, dtype=float).reshape(()))
    except (TypeError, ValueError):
        rate_hz = math.nan
    if not abs(rate_hz - BROAD_RATE_HZ) <= 1e-6 * BROAD_RATE_HZ:
        raise SinsInputError(f"{path}: sampling_rate is {rate!r}, expected BROAD's {BROAD_RATE_HZ:.6g} Hz")
    return out[0], out[1], out[2], out[3]


def _longest_run(mask: NDArray[np.bool_]) -> tuple[int, int]:
    """``(start, stop)`` of the longest run of True (the first of equal ones); ``(0, 0)`` if none."""
    edges = np.diff(np.r_[0, mask.astype(np.int8), 0])
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    if len(starts) == 0:
        return 0, 0
    k = int(np.argmax(stops - starts))
    return int(starts[k]), int(stops[k])


def _delay(path: str, gyro: Array, omega: Array) -> float:
    """How far the IMU lags the optical data, s: the peak of the cross-correlation of |ω|.

    ``c(L) = Σ x[k] y[k − L]`` over lags of up to :data:`_MAX_DELAY_S`, ``x`` the gyro's |ω| and ``y``
    the optical one (means removed); the peak is refined by a parabola through it and its neighbours.
    """
    x = np.linalg.norm(gyro, axis=1)
    y = np.linalg.norm(omega, axis=1)
    x, y = x - x.mean(), y - y.mean()
    m = round(_MAX_DELAY_S * BROAD_RATE_HZ)
    n = len(x)
    if n <= 4 * m:
        m = max((n - 1) // 4, 1)
    lags = np.arange(-m, m + 1)
    core = x[m : n - m]
    c = np.array([core @ y[m - lag : n - m - lag] for lag in lags])
    i = int(np.argmax(c))
    scale = math.sqrt(float(core @ core) * float(y[m : n - m] @ y[m : n - m]))
    peak = float(c[i]) / scale if scale > 0.0 else 0.0
    if peak < _MIN_CORRELATION or i in (0, len(lags) - 1):
        raise SinsInputError(
            f"{path}: |ω| of the gyro and of the optical orientation do not match within "
            f"±{_MAX_DELAY_S:g} s (peak correlation {peak:.2f} at {lags[i] / BROAD_RATE_HZ * 1e3:+.1f} ms); "
            "cannot align the clocks"
        )
    den = c[i - 1] - 2.0 * c[i] + c[i + 1]
    frac = 0.5 * (c[i - 1] - c[i + 1]) / den if den < 0.0 else 0.0
    return float((lags[i] + frac) / BROAD_RATE_HZ)


__all__ = [
    "BROAD_FOLDER",
    "BROAD_GRAVITY",
    "BROAD_HEIGHT_M",
    "BROAD_LAT_DEG",
    "BROAD_RATE_HZ",
    "BROAD_TRIALS",
    "sensor_of",
    "trials",
]
