"""The examples in ``examples/`` run as a user runs them, and say what their docstrings promise."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
from conftest import run_process

from sins.core.earth import G0

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _run(*args: str, cwd: Path = EXAMPLES.parent) -> str:
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    done = run_process(list(args), capture_output=True, text=True, env=env, cwd=cwd)
    assert done.returncode == 0, (args, done.stderr[-2000:])
    return done.stdout


def test_the_library_example_drifts_as_half_b_t_squared():
    out = _run(sys.executable, str(EXAMPLES / "library_drift.py"))
    error_m = float(out.split("final horizontal error")[1].split("m")[0])
    # ½ b t² over the 40 s drive; the last 20 s turn the biased axis through 90°, which can only shorten
    # the displacement (by at most ~(1 - 2/π)·¼ of it in the turn's half), so 0.8-1.0 of ½ b t².
    bound = 0.5 * 1e-3 * G0 * 40.0**2
    assert 0.8 * bound <= error_m <= 1.0 * bound, (error_m, bound)


def test_the_library_walkthrough_compensates_and_plots(tmp_path):
    """simulate → corrupt → compensate → integrate → plot, through ``import sins`` alone."""
    picture = tmp_path / "drift.png"
    out = _run(sys.executable, str(EXAMPLES / "library_walkthrough.py"), str(picture))
    rows = {line.split()[0]: np.array(line.split()[1:], dtype=float) for line in out.splitlines()[1:3]}
    assert set(rows) == {"raw", "regression"}, out
    t_s = 180.0  # the drive's length
    for name, row in rows.items():
        gyro_radps, accel_mps2 = np.radians(row[:3] / 3600.0), row[3:6] * 1e-3 * G0
        # A level vehicle: the horizontal sensors' biases drift the position by at most ½ b t² (the
        # accelerometers) and g ε t³ / 6 (a tilt that grows from the gyros); turns rotate the biases and
        # Schuler bends the growth, both only shortening it, within 180 s. The margin 1.1 holds the
        # scale-factor and misalignment errors over the accelerations and turns, a few metres at most.
        bound_m = 0.5 * np.hypot(*accel_mps2[:2]) * t_s**2 + G0 * np.hypot(*gyro_radps[:2]) * t_s**3 / 6
        assert 0.0 < row[6] <= 1.1 * bound_m, (name, row[6], bound_m)
    # The fitted seed model removes the unit's fixed errors; what it leaves is the navigation power-on's
    # own turn-on bias, a fraction of them, and the drift falls with it.
    assert (np.abs(rows["regression"][:6]) < np.abs(rows["raw"][:6])).all(), rows
    assert rows["regression"][6] < 0.1 * rows["raw"][6], rows
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_compensation_study_learns_the_nonlinearity_regression_cannot():
    out = _run(sys.executable, str(EXAMPLES / "compensation_study.py"))
    rows = {line.split()[0]: np.array(line.split()[1:], dtype=float) for line in out.splitlines()[1:]}
    assert set(rows) == {"none", "regression", "kohonen"}
    # gyro.y carries a k2·ω² error the linear model cannot hold; elsewhere the map keeps regression's.
    assert rows["kohonen"][1] < 0.1 * rows["regression"][1], rows
    others = [0, 2, 3, 4, 5]
    assert (rows["kohonen"][others] <= 1.02 * rows["regression"][others]).all(), rows


def test_the_diagnosis_example_names_the_withheld_effect():
    out = _run(sys.executable, str(EXAMPLES / "diagnosis.py"))
    assert out.strip().splitlines()[-1] == "first effect: gyro.temperature_bias", out


def test_the_aided_example_rides_out_its_outage():
    out = _run(sys.executable, str(EXAMPLES / "aided_drive.py"))
    rows = {line.split()[0]: np.array(line.split()[1:], dtype=float) for line in out.splitlines()[1:]}
    assert set(rows) == {"truth", "alignment"}
    for outage_m, sigma_m, final_m, rejected in rows.values():
        # Metres after 60 s, not tens; within 3σ of the filter's prediction (it does not model the unit's
        # scale factors and misalignments); back to decimetres once the fixes return; no fix refused.
        assert 1.0 < outage_m < 3.0 * sigma_m and final_m < 1.0 and rejected == 0, rows


def test_the_example_scenario_runs_with_every_strategy():
    out = _run(sys.executable, "-m", "sins.cli", "run", str(EXAMPLES / "short_drive.toml"))
    for name in ("none", "oracle", "regression", "kohonen"):
        assert any(line.split()[:1] == [name] for line in out.splitlines()), out


def test_the_readmes_python_blocks_run(tmp_path):
    """The README's library examples, exactly as printed there, run in a fresh directory."""
    readme = (EXAMPLES.parent / "README.md").read_text()
    blocks = [b.split("```", 1)[0] for b in readme.split("```python\n")[1:]]
    assert len(blocks) >= 2
    for i, block in enumerate(blocks):
        script = tmp_path / f"readme_{i}.py"
        script.write_text(block)
        _run(sys.executable, str(script), cwd=tmp_path)
