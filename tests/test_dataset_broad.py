"""BROAD (../shared/data/broad_mocap): an IMU beside optical motion capture, read by :func:`_read_broad`.

Two parts. A synthetic trial, written as a MAT file like BROAD's, with known rates, specific force,
clock offset and gaps, checks the reader's arithmetic without the real data. The real trials (skipped
when the folder is absent) are checked against physics and against the figures of the folder's
SOURCE.md (an independent numpy script).

The dataset module's own reader is private (``sins.io.read(dataset=...)`` is the public way in); these
tests call it to give it a data root of their own files and options the public call does not take.
"""

from __future__ import annotations

import math
from functools import partial
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from conftest import dataset_folder, refusal
from scipy.ndimage import maximum_filter1d
from scipy.spatial.transform import Rotation

from sins.core.series import CalibrationData
from sins.io.datasets.broad import (
    BROAD_FOLDER,
    BROAD_GRAVITY,
    BROAD_RATE_HZ,
    BROAD_TRIALS,
    _read_broad,
)

FOLDER = dataset_folder(BROAD_FOLDER)

# --------------------------------------------------------------------------- a synthetic trial

DELAY_S = 0.004  # the synthetic IMU lags the optical data by 4 ms, about BROAD's 4.2
N_ROWS = 6000
# Rows without an optical reference: the start, a short gap after a 10-row island, the end.
NAN_ROWS = (slice(0, 50), slice(60, 64), slice(5900, N_ROWS))


def _attitude(t: np.ndarray) -> Rotation:
    yaw = 0.8 * np.sin(2 * np.pi * 0.7 * t)
    pitch = 0.5 * np.sin(2 * np.pi * 1.1 * t + 0.3)
    roll = 0.6 * np.sin(2 * np.pi * 0.5 * t + 1.0) * np.sin(2 * np.pi * 0.13 * t)
    return Rotation.from_euler("ZYX", np.stack([yaw, pitch, roll], axis=1))


def _truth(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, Rotation, np.ndarray]:
    """Body rate (rad/s), specific force (m/s²), ENU attitude and position (m) at times ``t``."""
    h = 1e-6
    rate = (_attitude(t - h).inv() * _attitude(t + h)).as_rotvec() / (2 * h)
    w = 2 * np.pi * np.array([0.8, 1.3, 2.0])
    amp = np.array([0.2, 0.1, 0.05])
    pos = amp * np.sin(w * t[:, None]) + [0.0, 0.0, 1.5]
    acc = -amp * w**2 * np.sin(w * t[:, None])
    att = _attitude(t)
    f = att.inv().apply(acc + np.array([0.0, 0.0, BROAD_GRAVITY]))
    return rate, f, att, pos


def _write_trial(root: Path, stem: str = BROAD_TRIALS[0], **override: object) -> Path:
    t = np.arange(N_ROWS) / BROAD_RATE_HZ
    rate, f, _, _ = _truth(t - DELAY_S)
    _, _, att, pos = _truth(t)
    quat = att.as_quat()[:, [3, 0, 1, 2]]  # BROAD's [w, x, y, z]
    for rows in NAN_ROWS:
        quat[rows] = np.nan
        pos[rows] = np.nan
    content: dict[str, object] = {
        "imu_gyr": rate,
        "imu_acc": f,
        "imu_mag": np.zeros((N_ROWS, 3)),
        "opt_quat": quat,
        "opt_pos": pos,
        "movement": np.ones(N_ROWS, dtype=np.uint8),
        "sampling_rate": BROAD_RATE_HZ,
        "info": "synthetic",
    }
    content.update(override)
    folder = root / BROAD_FOLDER
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{stem}.mat"
    scipy.io.savemat(path, {k: v for k, v in content.items() if v is not None})
    return path


def test_synthetic_trial_recovers_the_truth(tmp_path: Path) -> None:
    path = _write_trial(tmp_path)
    data = _read_broad("05", root=tmp_path)
    assert data.source == str(path)
    rows = np.round(data.t * BROAD_RATE_HZ).astype(int)
    assert np.allclose(data.t, rows / BROAD_RATE_HZ, rtol=0, atol=1e-12)
    # The longest valid stretch is rows 64:5900; 15 rows at each end go for the filters' half-window,
    # and the 4 ms delay (1.14 samples, rounded) moves the rows kept 1 later.
    assert (rows[0], rows[-1] + 1) == (64 + 15 + 1, 5900 - 15 + 1)
    assert np.all(np.diff(rows) == 1)
    assert data.temp is None and data.phases == ()
    for name in ("gyro", "accel", "ref_gyro", "ref_accel"):
        assert getattr(data, name).shape == (len(rows), 3) and np.isfinite(getattr(data, name)).all()
    # The readings come through untouched.
    t_imu = rows / BROAD_RATE_HZ
    rate, f, _, _ = _truth(t_imu - DELAY_S)
    assert np.allclose(data.gyro, rate, rtol=0, atol=1e-12)
    assert np.allclose(data.accel, f, rtol=0, atol=1e-12)
    # The reference is the truth, delayed by the estimated clock offset. The filters' bias on motion
    # below 2 Hz is < 1e-4 of it; what is left is the error of the delay (0.06 ms here) times the
    # rate's derivative (up to 30 rad/s²) and the specific force's (up to ≈ 150 m/s³).
    assert np.abs(data.ref_gyro - rate).max() < 0.005  # rad/s, 0.3 °/s against up to 270 °/s; found 0.002
    assert np.abs(data.ref_accel - f).max() < 0.02  # m/s², found 0.009
    assert np.sqrt(np.mean((data.ref_gyro - rate) ** 2)) < 0.002  # found 0.0008
    # With no delay in the file, no shift and only the filters' half-window trimmed.
    _write_trial(tmp_path, imu_gyr=_truth(np.arange(N_ROWS) / BROAD_RATE_HZ)[0])
    # (accel still delayed: the clock offset is found from the rate alone)
    same = _read_broad("5", root=tmp_path)
    rows = np.round(same.t * BROAD_RATE_HZ).astype(int)
    assert (rows[0], rows[-1] + 1) == (64 + 15, 5900 - 15)
    rate_now = _truth(rows / BROAD_RATE_HZ)[0]
    assert np.abs(same.ref_gyro - rate_now).max() < 0.002


def test_trial_names(tmp_path: Path) -> None:
    path = _write_trial(tmp_path, stem=BROAD_TRIALS[1])
    for name in (BROAD_TRIALS[1], "18", " 18 "):
        assert _read_broad(name, root=tmp_path).source == str(path)
    assert BROAD_TRIALS == (
        "05_undisturbed_slow_rotation_with_breaks_B",
        "18_undisturbed_fast_translation_with_breaks_B",
    )


def test_refusals(tmp_path: Path) -> None:
    for trial in ("99", "abc", "", "05_undisturbed", "../05_undisturbed_slow_rotation_with_breaks_B"):
        refusal(partial(_read_broad, trial, root=tmp_path), repr(trial), "unknown BROAD trial", "05")
    refusal(
        lambda: _read_broad("05", root=tmp_path),
        str(tmp_path / BROAD_FOLDER),
        "no such data folder",
        "SINS_DATA",
    )
    (tmp_path / BROAD_FOLDER).mkdir()
    path = tmp_path / BROAD_FOLDER / f"{BROAD_TRIALS[0]}.mat"
    refusal(lambda: _read_broad("05", root=tmp_path), str(path), "no such file", "SINS_DATA")
    good = _write_trial(tmp_path).read_bytes()
    for damaged in (b"", b"hello, not a MAT file\n", good[: len(good) // 3], bytes(range(256)) * 40):
        path.write_bytes(damaged)
        refusal(lambda: _read_broad("05", root=tmp_path), str(path), "not a readable MATLAB MAT file")
    _write_trial(tmp_path, opt_pos=None)
    refusal(lambda: _read_broad("05", root=tmp_path), str(path), "no variable 'opt_pos'")
    _write_trial(tmp_path, imu_acc=np.zeros((N_ROWS, 2)))
    refusal(lambda: _read_broad("05", root=tmp_path), str(path), "'imu_acc'", "N × 3", f"({N_ROWS}, 2)")
    _write_trial(tmp_path, imu_mag=None, opt_quat=np.zeros((10, 4)))
    refusal(lambda: _read_broad("05", root=tmp_path), str(path), "rows")
    _write_trial(tmp_path, sampling_rate=100.0)
    refusal(lambda: _read_broad("05", root=tmp_path), str(path), "sampling_rate", "285.714")
    _write_trial(tmp_path, opt_pos=np.full((N_ROWS, 3), np.nan))
    refusal(lambda: _read_broad("05", root=tmp_path), str(path), "longest stretch", "0 rows")
    noise = np.random.default_rng(1).normal(0.0, 1.0, (N_ROWS, 3))
    _write_trial(tmp_path, imu_gyr=noise)
    refusal(lambda: _read_broad("05", root=tmp_path), str(path), "do not match", "cannot align")
    quat = np.tile([2.0, 0.0, 0.0, 0.0], (N_ROWS, 1))
    _write_trial(tmp_path, opt_quat=quat)
    refusal(lambda: _read_broad("05", root=tmp_path), str(path), "'opt_quat'", "not a unit quaternion")


# --------------------------------------------------------------------------- the real trials

#: Per trial: rows kept of the file (see _read_broad's docstring), the file's rows, and SOURCE.md's
#: gyro bias at rest (deg/s).
REAL = {
    "05": ((1206, 58355), 59212, (0.198, 0.119, -0.227)),
    "18": ((390, 51823), 53124, (0.212, 0.131, -0.234)),
}


@pytest.fixture(scope="module", params=sorted(REAL))
def trial(request: pytest.FixtureRequest) -> tuple[str, CalibrationData]:
    number = request.param
    stem = next(s for s in BROAD_TRIALS if s.startswith(number))
    if not (FOLDER / f"{stem}.mat").is_file():
        pytest.skip(
            f"BROAD data not found: no {stem}.mat in {FOLDER}; set SINS_DATA to the folder that holds "
            f"{BROAD_FOLDER}/ (the project's ../shared/data)"
        )
    return number, _read_broad(number)


def _still(data: CalibrationData) -> np.ndarray:
    """Rows where the gyro, less its bias, stays under 1.5 °/s for a second around them.

    The dataset's own rest marker is not used; these rows are the breaks of the trials (47 % of the
    rows, all inside the file's ``movement == 0``).
    """
    bias = np.median(data.gyro[: int(BROAD_RATE_HZ)], axis=0)  # both trials start at rest
    speed = np.degrees(np.linalg.norm(data.gyro - bias, axis=1))
    return maximum_filter1d(speed, int(BROAD_RATE_HZ)) < 1.5


def test_real_rows_time_and_source(trial: tuple[str, CalibrationData]) -> None:
    number, data = trial
    (start, stop), n_file, _ = REAL[number]
    rows = np.round(data.t * BROAD_RATE_HZ).astype(int)
    assert np.array_equal(rows, np.arange(start, stop))
    assert np.allclose(np.diff(data.t), 1.0 / BROAD_RATE_HZ, rtol=1e-9, atol=0)
    assert len(data) < n_file - 1600  # some 1650–2010 rows have no optical reference
    assert data.source.endswith(f"{BROAD_FOLDER}/{next(s for s in BROAD_TRIALS if s.startswith(number))}.mat")
    for name in ("gyro", "accel", "ref_gyro", "ref_accel"):
        a = getattr(data, name)
        assert a.shape == (len(data), 3) and a.dtype == np.float64 and np.isfinite(a).all(), name
    mat = scipy.io.loadmat(data.source, squeeze_me=True)
    assert np.array_equal(data.gyro, mat["imu_gyr"][start:stop])
    assert np.array_equal(data.accel, mat["imu_acc"][start:stop])


def test_real_still_specific_force_is_gravity(trial: tuple[str, CalibrationData]) -> None:
    number, data = trial
    still = _still(data)
    assert 0.4 < still.mean() < 0.55  # the three 10 s breaks plus the rest at both ends
    norm = np.linalg.norm(data.ref_accel[still], axis=1)
    # 9.8127 m/s² (Berlin's normal gravity); the optical noise (0.1–0.19 m/s² per axis) raises the
    # mean of a norm by ≈ σ²/g ≈ 2 mm/s², and the accelerometer itself reads 9.8197 (SOURCE.md).
    assert abs(norm.mean() - BROAD_GRAVITY) < 0.01
    assert abs(BROAD_GRAVITY - 9.8127) < 1e-4
    # The IMU's and the optical frames agree: at rest the accelerometer's mean against the reference
    # is within 0.05 m/s² per axis (0.3° of tilt, or a 5 mg bias; found: 0.007–0.035).
    assert np.abs((data.accel - data.ref_accel)[still].mean(axis=0)).max() < 0.05
    # At rest the reference rate is the optical noise alone: found 0.7–2.3 °/s RMS per axis.
    assert np.degrees(np.sqrt(np.mean(data.ref_gyro[still] ** 2, axis=0))).max() < 3.0
    # Gyro bias at rest, deg/s, as SOURCE.md measured it (so the readings are in rad/s, unscaled).
    _, _, bias = REAL[number]
    assert np.allclose(np.degrees(data.gyro[still].mean(axis=0)), bias, rtol=0, atol=0.03)


def test_real_gyro_agrees_with_reference(trial: tuple[str, CalibrationData]) -> None:
    _, data = trial
    err = data.gyro - data.ref_gyro
    err -= err.mean(axis=0)
    rms = np.degrees(np.sqrt(np.mean(err**2, axis=0)))
    # A MEMS gyro after its constant bias: noise 0.1 °/s and scale/misalignment of ≈ 1 % of rates
    # of 30–140 °/s RMS leave ≈ 0.5–1.5 °/s; the optical reference adds its noise (up to 2.3 °/s RMS
    # at rest, more in motion) and loses motion above 19 Hz. Found: 1.5–3.4 °/s (05), 2.6–5.3 (18).
    assert rms.max() < 7.0, rms
    for i in range(3):
        assert np.corrcoef(data.gyro[:, i], data.ref_gyro[:, i])[0, 1] > 0.99
    # Clock aligned: |ω| of the gyro and of the reference correlate best at lag 0, to within a
    # quarter sample (the reader shifted the reference by the 4.2 ms it found).
    x = np.linalg.norm(data.gyro, axis=1)
    y = np.linalg.norm(data.ref_gyro, axis=1)
    x, y = x - x.mean(), y - y.mean()
    m = 10
    c = np.array([x[m:-m] @ y[m - lag : len(y) - m - lag] for lag in range(-m, m + 1)])
    i = int(np.argmax(c))
    assert i == m
    assert abs(0.5 * (c[i - 1] - c[i + 1]) / (c[i - 1] - 2 * c[i] + c[i + 1])) < 0.25


def test_real_accel_agrees_with_reference(trial: tuple[str, CalibrationData]) -> None:
    _, data = trial
    err = data.accel - data.ref_accel
    err -= err.mean(axis=0)
    rms = np.sqrt(np.mean(err**2, axis=0))
    # The optical specific force is a second derivative of positions with ≈ 0.05 mm noise; smoothed
    # to 13 Hz it keeps 0.1–0.19 m/s² of noise at rest and loses fast motion. Found: 0.23–0.32 m/s²
    # (05), 0.48–0.65 m/s² (18, translations up to 6 m/s, 90 m/s²).
    assert rms.max() < 1.0, rms
    for i in range(3):
        assert np.corrcoef(data.accel[:, i], data.ref_accel[:, i])[0, 1] > 0.99
    assert math.isclose(float(np.median(np.linalg.norm(data.accel, axis=1))), 9.82, abs_tol=0.2)
