"""``sins evaluate`` against a trajectory names the gyro scale and misalignment a model leaves of the
judged recording (sins.compensation.terms_left), judged on recordings written with numpy alone
(tests/numpy_unit_gap.py: one unit, its errors drawn from ``unit_seed``, over several motions)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy_unit_gap as nu
import pytest

from sins.cli import main
from sins.compensation import terms_left


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Least squares fitted on two motions of the unit (``sins fit a.npz b.npz``)."""
    folder = tmp_path_factory.mktemp("unit")
    paths = [nu.write(folder / f"m{m}.npz", nu.recording(m, duration_s=90.0)) for m in (3, 4)]
    out = folder / "m.json"
    assert main(["fit", *map(str, paths), "--strategy", "regression", "--out", str(out)]) == 0
    return out


def _left(model: Path, tmp_path: Path, effect: str) -> dict:
    judged = nu.write(tmp_path / "judged.npz", nu.recording(5, effect, duration_s=90.0))
    out = tmp_path / "e.json"
    assert main(["evaluate", str(model), str(judged), "--json", str(out)]) == 0
    return json.loads(out.read_text())["gyro_terms_left"]


def test_a_recording_of_the_unit_is_left_no_term(model: Path, tmp_path: Path) -> None:
    """A third motion of the unit the model was fitted on: every gyro term within a unit's spread."""
    left = _left(model, tmp_path, "clean")
    assert left["terms"] == [] and left["intervals"] > 50


def test_a_recordings_own_misalignment_is_named_with_its_size(
    model: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same motion with 20 mrad more of its x rate read on gyro y: that term alone is named, within
    2 mrad of the 20 added (measured 20.16 ± 0.18), and said on the report."""
    left = _left(model, tmp_path, "gyro y←x")
    assert [t["name"] for t in left["terms"]] == ["gyro misalignment y←x"]
    term = left["terms"][0]
    assert term["unit"] == "mrad" and term["value"] == pytest.approx(20.0, abs=2.0)
    assert abs(term["value"]) > terms_left.Z_DETERMINED * term["se"]
    assert "the model leaves this recording's gyro misalignment y←x" in capsys.readouterr().out


def test_several_judged_say_which_are_left_a_term(
    model: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Judged together, the recordings left a term are named side by side under the mean
    (``gyro_terms_left_on``); the clean one is not among them."""
    clean = nu.write(tmp_path / "clean.npz", nu.recording(5, duration_s=90.0))
    own = nu.write(tmp_path / "own.npz", nu.recording(5, "gyro y←x", duration_s=90.0))
    out = tmp_path / "both.json"
    assert main(["evaluate", str(model), str(clean), str(own), "--json", str(out)]) == 0
    assert json.loads(out.read_text())["gyro_terms_left_on"] == [str(own)]
    printed = capsys.readouterr().out
    assert f"gyro terms the model leaves beyond a unit's spread: {own} (gyro misalignment y←x 20" in printed
