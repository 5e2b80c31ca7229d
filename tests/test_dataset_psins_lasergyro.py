"""The PSINS static ring-laser-gyro record (../shared/data/psins_lasergyro_static), read by
:func:`sins.io.datasets.psins_lasergyro._read_psins_lasergyro`.

The figures checked against the real record are those of the folder's SOURCE.md (an independent numpy
script) measured again through the reader; those tests skip when the data are absent. The refusals and
the conventions (axes, units, time, heading) are also checked on small synthetic files, which need no data.

The dataset module's own reader is private (``sins.io.read(dataset=...)`` is the public way in); these
tests call it to give it a data root of their own files and options the public call does not take.
"""

from __future__ import annotations

import lzma
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import dataset_folder, refusal

from sins.core import earth
from sins.core.series import CalibrationData
from sins.io.datasets.psins_lasergyro import (
    PSINS_LASERGYRO_FILE,
    PSINS_LASERGYRO_FOLDER,
    _read_psins_lasergyro,
)

FOLDER = dataset_folder(PSINS_LASERGYRO_FOLDER)
PATH = FOLDER / PSINS_LASERGYRO_FILE

N_ROWS = 184718
LAT = math.radians(34.246048)
H = 380.0
DEG_H = math.radians(1.0) / 3600.0  # 1 °/h in rad/s
UG = 1e-6 * 9.780327  # PSINS's µg: 1e-6 × the header's g
QUIET_S = ((600.0, 960.0), (1020.0, 1500.0))  # SOURCE.md's quietest stretches


@pytest.fixture(scope="module")
def record() -> CalibrationData:
    if not PATH.is_file():
        pytest.skip(
            f"PSINS laser-gyro data not found: no {PATH}; set SINS_DATA to the folder that holds "
            f"{PSINS_LASERGYRO_FOLDER}/ (the project's ../shared/data)"
        )
    return _read_psins_lasergyro()


def _rows(data: CalibrationData, start_s: float, stop_s: float) -> slice:
    return slice(int(np.searchsorted(data.t, start_s)), int(np.searchsorted(data.t, stop_s)))


def _gyrocompass_deg(f: np.ndarray, w: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw (deg, ZYX, NED) of a static FRD unit from its mean specific force and rate."""
    roll = math.atan2(-f[1], -f[2])
    pitch = math.atan2(f[0], math.hypot(f[1], f[2]))
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    north = cp * w[0] + sp * sr * w[1] + sp * cr * w[2]  # the rate levelled, heading not yet applied
    east_neg = cr * w[1] - sr * w[2]
    return math.degrees(roll), math.degrees(pitch), math.degrees(math.atan2(-east_neg, north))


# --------------------------------------------------------------------------- the real record


def test_rows_time_and_units(record: CalibrationData) -> None:
    assert len(record) == N_ROWS
    for a in (record.gyro, record.accel, record.ref_gyro, record.ref_accel):
        assert a.shape == (N_ROWS, 3) and a.dtype == np.float64 and np.isfinite(a).all()
    # No time column: 10 ms rows (header), stamped at each interval's midpoint; 1847.18 s in all.
    assert record.t.shape == (N_ROWS,)
    assert np.allclose(record.t, 0.005 + 0.01 * np.arange(N_ROWS), rtol=0.0, atol=1e-9)
    assert np.allclose(np.diff(record.t), 0.01, rtol=0.0, atol=1e-9)
    assert record.temp is None and record.phases == () and record.source == str(PATH)
    # First data row "0 0 2 0 0 80" (x-right, y-forward, z-up LSB): 2 × 0.1 arcsec and 80 × 125 µg·s
    # over 10 ms, on FRD's z (down, so negated).
    arcsec = math.radians(1.0 / 3600.0)
    assert np.allclose(record.gyro[0], [0.0, 0.0, -2 * 0.1 * arcsec / 0.01], rtol=1e-12, atol=0.0)
    assert np.allclose(record.accel[0], [0.0, 0.0, -80 * 125 * UG / 0.01], rtol=1e-12, atol=0.0)
    # LSB in rate form: 10 °/h and 12.5 mg; every reading is a whole number of them.
    assert np.allclose(record.gyro / (10.0 * DEG_H), np.round(record.gyro / (10.0 * DEG_H)), atol=1e-6)
    assert np.allclose(record.accel / (0.0125 * 9.780327), np.round(record.accel / (0.0125 * 9.780327)))


def test_means_match_source_md(record: CalibrationData) -> None:
    """SOURCE.md: mean f = [-0.0612, 0.1585, 9.7940] m/s², |f| = 9.79548 m/s², mean gyro = [-12.27, 0.44,
    8.36] °/h, |ω| = 14.85 °/h; all in PSINS's x-right, y-forward, z-up, here in FRD (y, x, -z)."""
    f = record.accel.mean(axis=0)
    w = record.gyro.mean(axis=0) / DEG_H
    assert np.allclose(f, [0.1585, -0.0612, -9.7940], atol=1e-4), f
    assert abs(np.linalg.norm(f) - 9.79548) < 1e-5
    assert np.allclose(w, [0.44, -12.27, -8.36], atol=0.01), w
    assert abs(np.linalg.norm(w) - 14.85) < 0.01
    # Physical checks of units and rate: |f| is normal gravity at the header's place to -4 µg (a wrong
    # interval would scale it), |ω| Earth's rate to 1.3 %, and to 0.5 % over the quiet 600-960 s.
    g = float(earth.normal_gravity(LAT, H))
    assert abs(np.linalg.norm(f) - g) < 10 * UG
    quiet = record.gyro[_rows(record, *QUIET_S[0])].mean(axis=0)
    assert abs(np.linalg.norm(quiet) / earth.OMEGA_IE - 1.0) < 0.006


def test_reference_is_earth_rate_and_normal_gravity(record: CalibrationData) -> None:
    assert (record.ref_gyro == record.ref_gyro[0]).all() and (record.ref_accel == record.ref_accel[0]).all()
    g = float(earth.normal_gravity(LAT, H))
    assert abs(g - 9.79553) < 1e-5  # SOURCE.md's figure
    assert math.isclose(np.linalg.norm(record.ref_accel[0]), g, rel_tol=1e-12)
    assert math.isclose(np.linalg.norm(record.ref_gyro[0]), earth.OMEGA_IE, rel_tol=1e-12)
    assert abs(earth.OMEGA_IE / DEG_H - 15.041) < 1e-3
    # Vertical part of Earth's rate (along f, which points up at rest): Ω sin(lat) = 8.464 °/h.
    up = record.ref_accel[0] / g
    assert math.isclose(record.ref_gyro[0] @ up / DEG_H, 8.464, abs_tol=1e-3)
    # The attitude behind the reference: tilt from the record's mean f, heading 90.6° from the header.
    roll, pitch, yaw = _gyrocompass_deg(record.ref_accel[0], record.ref_gyro[0])
    assert np.allclose([roll, pitch], [0.3581, 0.9269], atol=1e-4), (roll, pitch)
    assert math.isclose(yaw, 90.6, abs_tol=1e-9)


def test_readings_means_within_the_units_bias(record: CalibrationData) -> None:
    """The record's means against the reference, within what the unit's biases (and the base) allow.

    Accelerometers: across f the mean equals the reference by construction (the tilt is taken from it,
    absorbing the horizontal biases); along f, |f̄| − g is −4 µg. Bound 100 µg: the grade is not stated,
    but an INS with 0.1″ and 125 µg·s resolution carries navigation or tactical accelerometers of
    10–100 µg bias, and normal gravity differs from the true one by the local anomaly (tens of mGal,
    i.e. tens of µg), which the vertical channel cannot tell from a bias.

    Gyros: the heading is the header's, so nothing is absorbed. Over the quiet stretches the means are
    within 0.13 °/h; bound 0.3 °/h: SOURCE.md's 60 s Allan deviation (≤ 0.18 °/h, the size of what a
    segment's mean can wander) plus 0.5° of heading doubt (0.11 °/h on the east axis). Over the whole
    record the forward (≈ east) axis is 0.43 °/h off: the base turns in the disturbed minutes (60 s
    means swing by ±10 °/h) and does not all come back; bound 1 °/h.
    """
    ref_g, ref_f = record.ref_gyro[0], record.ref_accel[0]
    up = ref_f / np.linalg.norm(ref_f)
    df = record.accel.mean(axis=0) - ref_f
    assert np.linalg.norm(df - (df @ up) * up) < 1e-9
    assert abs(df @ up) < 100 * UG, df @ up / UG
    assert abs(df @ up / UG + 4.4) < 0.5  # SOURCE.md: −4 µg
    assert np.all(np.abs(record.gyro.mean(axis=0) - ref_g) < 1.0 * DEG_H)
    for start, stop in QUIET_S:
        dw = record.gyro[_rows(record, start, stop)].mean(axis=0) - ref_g
        assert np.all(np.abs(dw) < 0.3 * DEG_H), (start, stop, dw / DEG_H)


def test_header_heading_agrees_with_gyrocompass_where_the_base_is_quiet(record: CalibrationData) -> None:
    """Gyrocompassing over the quiet stretches gives 90.8° and 90.3°, the header 90.6°; over the whole
    record 88.6° (SOURCE.md: PSINS yaw −88.6°), pulled off by the base's disturbances."""
    for start, stop in QUIET_S:
        rows = _rows(record, start, stop)
        _, _, yaw = _gyrocompass_deg(record.accel[rows].mean(axis=0), record.gyro[rows].mean(axis=0))
        assert abs(yaw - 90.6) < 0.5, (start, stop, yaw)
    _, _, yaw = _gyrocompass_deg(record.accel.mean(axis=0), record.gyro.mean(axis=0))
    assert abs(yaw - 88.6) < 0.1, yaw


# --------------------------------------------------------------------------- synthetic files (no data)

_HEADER = (
    "% PSINS-format SIMU log file. (DO NOT EDIT!)\n% synthetic, for the tests\n\n{att}\n{pos}\n{scales}\n\n"
)
# At the equator, facing east, level: Earth's rate points north = the body's left (x-right: −Ω), f up.
_ARCSEC_S = earth.OMEGA_IE * 180.0 * 3600.0 / math.pi  # Ω in arcsec/s, 15.041
_G0 = float(earth.normal_gravity(0.0, 0.0))


def _write(root: Path, rows: str, *, att: str = "0 0 -90 0 0 0", pos: str = "", scales: str = "") -> Path:
    """A compressed SIMU file under ``root``: 1 s rows, 0.001″ and 1 µg·s LSB, µg of the equator's g."""
    folder = root / PSINS_LASERGYRO_FOLDER
    folder.mkdir(exist_ok=True)
    path = folder / PSINS_LASERGYRO_FILE
    pos = pos or f"0 0 0 10 1000 {_G0!r}"
    scales = scales or "0.001 0.001 0.001 1 1 1"
    with lzma.open(path, "wt", encoding="ascii") as fh:
        fh.write(_HEADER.format(att=att, pos=pos, scales=scales) + rows)
    return path


def _static_rows(n: int = 4) -> str:
    gyro_x = -round(_ARCSEC_S / 0.001)  # 1 s of Earth rate, right axis = south
    return f"{gyro_x} 0 0 0 0 1000000\n" * n


def test_synthetic_east_facing_unit(tmp_path: Path) -> None:
    path = _write(tmp_path, _static_rows())
    data = _read_psins_lasergyro(tmp_path)
    assert data.source == str(path)
    assert np.allclose(data.t, [10.5, 11.5, 12.5, 13.5])  # t0 = 10 s, 1 s rows, midpoints
    # FRD: forward = east, right = south; Earth's rate north = −right, f up = −down.
    assert np.allclose(
        data.gyro, [0.0, -earth.OMEGA_IE, 0.0], rtol=0.0, atol=1e-3 * DEG_H
    )  # within one LSB (0.001″ in 1 s)
    assert np.allclose(data.accel, [0.0, 0.0, -_G0], rtol=1e-15, atol=0.0)
    assert np.allclose(data.ref_gyro, [0.0, -earth.OMEGA_IE, 0.0], rtol=0.0, atol=1e-20)
    assert np.allclose(data.ref_accel, [0.0, 0.0, -_G0], rtol=1e-15, atol=1e-15)
    # Header heading −90° is PSINS's counter-clockwise yaw; +90° (west) would flip the reference.
    _write(tmp_path, _static_rows(), att="0 0 90 0 0 0")
    assert np.allclose(_read_psins_lasergyro(tmp_path).ref_gyro, [0.0, earth.OMEGA_IE, 0.0], atol=1e-20)


def test_missing_data_refused(tmp_path: Path) -> None:
    folder = tmp_path / PSINS_LASERGYRO_FOLDER
    refusal(lambda: _read_psins_lasergyro(tmp_path), str(folder), "no such data folder", "SINS_DATA", "root=")
    folder.mkdir()
    path = folder / PSINS_LASERGYRO_FILE
    refusal(lambda: _read_psins_lasergyro(tmp_path), str(path), "no such file", "SINS_DATA")


def test_corrupt_file_refused(tmp_path: Path) -> None:
    folder = tmp_path / PSINS_LASERGYRO_FOLDER
    folder.mkdir()
    path = folder / PSINS_LASERGYRO_FILE
    path.write_bytes(b"0 0 2 0 0 80\n")  # not compressed
    refusal(lambda: _read_psins_lasergyro(tmp_path), str(path), "not a readable xz file")
    good = lzma.compress((_HEADER.format(att="0 0 -90 0 0 0", pos="0 0 0 0 1000 9.78", scales="1 1 1 1 1 1")
                          + _static_rows(200)).encode())  # fmt: skip
    path.write_bytes(good[: len(good) // 2])  # truncated
    refusal(lambda: _read_psins_lasergyro(tmp_path), str(path), "not a readable xz file")
    path.write_bytes(lzma.compress(b"% PSINS SIMU\n\xff\xfe\n"))
    refusal(lambda: _read_psins_lasergyro(tmp_path), str(path), "not ASCII text")


@pytest.mark.parametrize(
    ("kwargs", "rows", "fragments"),
    [
        ({}, "", ("the 3 header lines and no data rows",)),
        ({"scales": "%"}, "", ("2 of the 3 header lines and no data rows",)),
        ({"att": "0 0 -90 0 0"}, _static_rows(), (":4:", "expected 6 numbers", "pitch0")),
        ({"pos": "0 0 0 10 0 9.78"}, _static_rows(), (":5:", "interval 0 ms")),
        ({"pos": "95 0 0 10 1000 9.78"}, _static_rows(), (":5:", "latitude 95°")),
        ({"pos": "0 0 0 10 1000 nan"}, _static_rows(), (":5:", "expected 6 numbers")),
        ({"scales": "0.001 0.001 0.001 1 1 -1"}, _static_rows(), (":6:", "scales must be positive")),
        (
            {},
            _static_rows(2) + "1 2 3 4 5\n" + _static_rows(2),
            (":10:", "expected 6 integers", "'1 2 3 4 5'"),
        ),
        ({}, _static_rows(2) + "1 2 3 4 5 6.5\n", (":10:", "expected 6 integers", "6.5")),
        ({}, _static_rows(2) + "1 2 3 4 5 6 0\n", (":10:", "expected 6 integers")),  # PSINS's dither column
        ({}, "1 2 3 4 5 99999999999999999999\n", ("does not fit a 64-bit integer",)),
        ({"pos": f"0 0 0 10 2000 {_G0!r}"}, _static_rows(), ("not normal gravity", "-50", "2000 ms")),
    ],
)
def test_malformed_file_refused(
    tmp_path: Path, kwargs: dict[str, str], rows: str, fragments: tuple[str, ...]
) -> None:
    path = _write(tmp_path, rows, **kwargs)
    refusal(lambda: _read_psins_lasergyro(tmp_path), str(path), *fragments)


def test_not_a_psins_file_refused(tmp_path: Path) -> None:
    path = _write(tmp_path, _static_rows())
    text = lzma.decompress(path.read_bytes()).decode().replace("PSINS-format", "Some")
    path.write_bytes(lzma.compress(text.encode()))
    refusal(lambda: _read_psins_lasergyro(tmp_path), f"{path}:1:", "not a PSINS SIMU text file")
    path.write_bytes(lzma.compress(b""))
    refusal(lambda: _read_psins_lasergyro(tmp_path), f"{path}:1:", "not a PSINS SIMU text file")
