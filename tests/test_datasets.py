"""Real datasets beside the project: the imucal Ferraris session (../shared/data/imucal_ferraris).

The figures checked here are those of the folder's SOURCE.md (an independent numpy script), measured
again through :func:`sins.io.datasets._read_ferraris`.

The dataset module's own reader is private (``sins.io.read(dataset=...)`` is the public way in); these
tests call it to give it a data root of their own files and options the public call does not take.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import dataset_folder, refusal

import sins
from sins import io
from sins.core import earth
from sins.core.series import CalibrationData
from sins.io import datasets

FOLDER = dataset_folder(datasets.FERRARIS_FOLDER)
FILES = ("example_ferraris_session.csv", "example_ferraris_session_list.json")
if not all((FOLDER / name).is_file() for name in FILES):
    pytest.skip(
        f"imucal Ferraris data not found in {FOLDER}: set SINS_DATA to the folder that holds "
        f"{datasets.FERRARIS_FOLDER}/ (the project's ../shared/data)",
        allow_module_level=True,
    )

STATIC = ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")
ROTATIONS = ("x_rot", "y_rot", "z_rot")


@pytest.fixture(scope="module")
def session() -> CalibrationData:
    return datasets._read_ferraris()


def _rows(data: CalibrationData, name: str) -> slice:
    (phase,) = [p for p in data.phases if p.name == name]
    return slice(phase.start, phase.stop)


def _static_gyro_bias(data: CalibrationData) -> np.ndarray:
    """Gyro bias, rad/s: the mean over all samples of the six static sections pooled (imucal's ``b_g``)."""
    return np.vstack([data.gyro[_rows(data, name)] for name in STATIC]).mean(axis=0)


# --------------------------------------------------------------------------- structure


def test_phases_rows_time_and_units(session: CalibrationData) -> None:
    sections = json.loads((FOLDER / FILES[1]).read_text())
    assert len(session) == 10376
    assert [p.name for p in session.phases] == [*STATIC, *ROTATIONS]
    assert [p.kind for p in session.phases] == ["static"] * 6 + ["rotation"] * 3
    # end is exclusive, as imucal slices (data.iloc[start:end]); the phases are in time order.
    assert [(p.start, p.stop) for p in session.phases] == [
        (sections[p.name]["start"], sections[p.name]["end"]) for p in session.phases
    ]
    assert all(a.stop <= b.start for a, b in zip(session.phases, session.phases[1:], strict=False))
    assert np.array_equal(session.t, np.arange(10376) / 102.4)
    # deg/s in the file, rad/s here: the first row's gyro_x is -0.6103515625 deg/s.
    assert session.gyro[0, 0] == np.radians(-0.6103515625)
    assert session.accel[0, 0] == 10.332114257812501
    assert session.temp is None
    assert session.source == str(FOLDER / FILES[0])


def test_reference(session: CalibrationData) -> None:
    g = earth.normal_gravity(math.radians(49.6), 0.0)
    assert abs(g - 9.81) < 5e-4
    for k, name in enumerate(STATIC):
        rows = _rows(session, name)
        expected = np.zeros(3)
        expected[k // 2] = g if name.endswith("_p") else -g
        assert (session.ref_accel[rows] == expected).all(), name
        assert (session.ref_gyro[rows] == 0.0).all(), name
        # The sign convention against the data: the reading points the same way as the reference.
        mean = session.accel[rows].mean(axis=0)
        assert mean @ expected / (np.linalg.norm(mean) * g) > 0.99, name
    for k, name in enumerate(ROTATIONS):
        (phase,) = [p for p in session.phases if p.name == name]
        expected_angle = [0.0, 0.0, 0.0]
        expected_angle[k] = -2.0 * math.pi
        assert phase.angle_rad == tuple(expected_angle)
        assert np.isnan(session.ref_gyro[phase.start : phase.stop]).all()
        assert np.isnan(session.ref_accel[phase.start : phase.stop]).all()
    outside = np.ones(len(session), dtype=bool)
    for p in session.phases:
        outside[p.start : p.stop] = False
    assert outside.sum() == 10376 - sum(p.stop - p.start for p in session.phases)
    assert np.isnan(session.ref_gyro[outside]).all() and np.isnan(session.ref_accel[outside]).all()


# --------------------------------------------------------------------------- the SOURCE.md figures


def test_static_accel_magnitudes(session: CalibrationData) -> None:
    """|mean acc| per static section (uncalibrated, so 9.2..10.5 m/s² rather than g)."""
    source_md = {"x_p": 10.341, "x_a": 9.270, "y_p": 9.235, "y_a": 10.478, "z_p": 10.467, "z_a": 9.682}
    for name, value in source_md.items():
        measured = np.linalg.norm(session.accel[_rows(session, name)].mean(axis=0))
        assert abs(measured - value) < 0.01, (name, measured)


def test_static_gyro_bias(session: CalibrationData) -> None:
    """≈ [-0.60, -0.37, +0.06] deg/s, the same in every position (measured spread ≤ 0.01 deg/s)."""
    bias_dps = np.degrees(_static_gyro_bias(session))
    assert np.allclose(bias_dps, [-0.60, -0.37, 0.06], atol=0.01), bias_dps
    for name in STATIC:
        mean_dps = np.degrees(session.gyro[_rows(session, name)].mean(axis=0))
        assert np.allclose(mean_dps, bias_dps, atol=0.015), (name, mean_dps)


def test_rotation_angles(session: CalibrationData) -> None:
    """Bias-removed integrated turns ≈ x -370.0°, y -353.7°, z -359.4° (SOURCE.md).

    The bias is the pooled mean of the six static sections (imucal's ``b_g``) and the integral imucal's
    rectangle sum over the section's rows divided by 102.4 Hz. Without the bias x reads -371.9°, so where
    the bias comes from matters at the 1° tolerance.
    """
    bias = _static_gyro_bias(session)
    expected_deg = {"x_rot": -370.0, "y_rot": -353.7, "z_rot": -359.4}
    for k, (name, value) in enumerate(expected_deg.items()):
        rows = _rows(session, name)
        angle_deg = np.degrees((session.gyro[rows] - bias).sum(axis=0) / datasets.FERRARIS_RATE_HZ)
        assert abs(angle_deg[k] - value) < 1.0, (name, angle_deg)
        assert np.all(np.abs(np.delete(angle_deg, k)) < 5.0), (name, angle_deg)  # a turn about one axis


def test_round_trip_through_a_rig_recording(session: CalibrationData, tmp_path: Path) -> None:
    path = tmp_path / "ferraris.csv"
    io.write_recording(path, session, comment="imucal example Ferraris session (MIT, MaD Lab)")
    back = io.read(path).rig
    for name in ("t", "gyro", "accel", "ref_gyro", "ref_accel"):
        assert np.array_equal(getattr(back, name), getattr(session, name), equal_nan=True), name
    assert back.phases == session.phases


# --------------------------------------------------------------------------- data root and refusals


def test_data_root_order(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("SINS_DATA", str(tmp_path / "env"))
    assert datasets.data_root() == tmp_path / "env"
    assert datasets.data_root(tmp_path / "given") == tmp_path / "given"
    monkeypatch.setenv("SINS_DATA", "")  # empty counts as unset
    (tmp_path / "shared" / "data").mkdir(parents=True)
    (tmp_path / "project").mkdir()
    monkeypatch.chdir(tmp_path / "project")
    assert datasets.data_root() == (tmp_path / "shared" / "data").resolve()
    monkeypatch.delenv("SINS_DATA")
    (tmp_path / "project" / "sub").mkdir()
    monkeypatch.chdir(tmp_path / "project" / "sub")  # no ../shared/data from here: the repository's
    repo = Path(sins.__file__).resolve().parent.parent
    assert datasets.data_root() == (repo / ".." / "shared" / "data").resolve()


def test_missing_data_is_refused_with_a_hint(tmp_path: Path) -> None:
    refusal(lambda: datasets._read_ferraris(tmp_path), str(tmp_path / "imucal_ferraris"), "SINS_DATA", "root")
    folder = tmp_path / "imucal_ferraris"
    folder.mkdir()
    (folder / FILES[0]).write_text("n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n0,0,0,0,0,0,9.8\n")
    refusal(lambda: datasets._read_ferraris(tmp_path), str(folder / FILES[1]), "no such file", "SINS_DATA")
    refusal(lambda: datasets._read_ferraris(tmp_path, session="../x"), "session")


def test_bad_section_lists_are_refused(tmp_path: Path) -> None:
    folder = tmp_path / "imucal_ferraris"
    folder.mkdir()
    rows = "\n".join(f"{k},0,0,0,0,0,9.8" for k in range(100))
    (folder / FILES[0]).write_text(f"n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n{rows}\n")
    good = {name: {"start": 10 * k, "end": 10 * k + 5} for k, name in enumerate(datasets.FERRARIS_SECTIONS)}
    (folder / FILES[1]).write_text(json.dumps(good))
    assert len(datasets._read_ferraris(tmp_path).phases) == 9
    cases = [
        ({**good, "y_a": {"start": 2, "end": 12}}, "overlap"),
        ({**good, "z_rot": {"start": 95, "end": 101}}, "beyond the 100 rows"),
        ({**good, "x_p": {"start": 5, "end": 5}}, "empty"),
        ({**good, "x_p": {"start": "0", "end": 5}}, "expected"),
        ({k: v for k, v in good.items() if k != "y_rot"}, "missing section 'y_rot'"),
        ({**good, "w_p": {"start": 96, "end": 99}}, "unknown section 'w_p'"),
    ]
    for sections, fragment in cases:
        (folder / FILES[1]).write_text(json.dumps(sections))
        refusal(lambda: datasets._read_ferraris(tmp_path), str(folder / FILES[1]), fragment)
    (folder / FILES[1]).write_text('{"x_p": ')
    refusal(lambda: datasets._read_ferraris(tmp_path), f"{folder / FILES[1]}:1:", "not JSON")
