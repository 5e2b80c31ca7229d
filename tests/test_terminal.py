"""A quiet, honest terminal: ``sins --help`` starts without the numerical libraries, ``--spawn`` without a
display is refused before any work, every step that can take seconds shows a line, and no label
contradicts what the command wrote (``bias_only`` is ``bias_only``; a per-hour rate of a minute's run is
withheld or marked; ``correct`` writes the form its help names)."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from numpy_referenced import session, typical_unit
from test_referenced import _write_truth

from sins import compensation, io
from sins.cli import common, main

HEAVY = ("numpy", "scipy", "torch", "numba", "matplotlib", "rerun", "pandas", "pyarrow")


def _loaded_after(argv: list[str], env: dict[str, str] | None = None) -> tuple[list[str], str]:
    """The heavy libraries a fresh interpreter holds after ``sins ARGV``, and what it wrote on stderr."""
    code = (
        "import sys\nfrom sins.cli import main\ntry:\n    main(sys.argv[1:])\nexcept SystemExit:\n    pass\n"
        f"print('LOADED:' + ','.join(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, *argv], capture_output=True, text=True, env=env, check=True
    )
    last = next(line for line in done.stdout.splitlines() if line.startswith("LOADED:"))
    return [m for m in last.removeprefix("LOADED:").split(",") if m], done.stderr


@pytest.mark.parametrize("argv", [["--help"], ["--version"], ["bias", "--help"], ["integrate", "--help"]])
def test_help_and_version_import_no_numerical_library(argv: list[str]) -> None:
    loaded, _ = _loaded_after(argv)
    assert loaded == []


def test_choices_the_cli_writes_out_are_the_librarys() -> None:
    from sins.cli import integrate
    from sins.imu import spec
    from sins.nav.vertical import VERTICAL_MODES

    assert integrate.VERTICAL_MODES == tuple(VERTICAL_MODES)
    assert integrate.GRADES == tuple(spec.GRADES)


def test_spawn_without_a_display_is_refused_before_any_work(tmp_path: Path) -> None:
    """Refused before the scenario is even looked for (it does not exist), with nothing heavy imported."""
    env = {k: v for k, v in __import__("os").environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    loaded, err = _loaded_after(["run", str(tmp_path / "no_such.toml"), "--spawn"], env)
    assert err.startswith("sins: error: --spawn: no display") and err.count("\n") == 1, err
    assert loaded == []


def test_the_cli_and_the_viewer_bridge_agree_on_a_display(monkeypatch: pytest.MonkeyPatch) -> None:
    from sins.viz import viewer as viz

    assert common.NO_DISPLAY == viz.NO_DISPLAY
    for env in ({}, {"DISPLAY": ":0"}, {"WAYLAND_DISPLAY": "wayland-0"}):
        monkeypatch.delenv("DISPLAY", raising=False)
        monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
        for k, v in env.items():
            monkeypatch.setenv(k, v)
        assert common.has_display() == viz.has_display()


def test_the_viewer_sins_spawns_runs_without_analytics(monkeypatch: pytest.MonkeyPatch) -> None:
    """rerun's viewer collects nothing and prints no first-run banner where CI is set: sins sets it for
    the child it spawns, and leaves its own environment as it was."""
    from sins.viz import viewer as viz

    seen: dict[str, str | None] = {}
    monkeypatch.setattr(viz, "has_display", lambda: True)
    monkeypatch.setattr(viz.rr, "spawn", lambda **_: seen.update(CI=__import__("os").environ.get("CI")))
    monkeypatch.setattr(viz, "log_scenario_run", lambda *a, **k: None)
    stream = type("R", (), {"flush": lambda self: None, "send_recording_name": lambda self, name: None})
    monkeypatch.setattr(viz, "_recording", lambda result: (stream(), None))
    monkeypatch.delenv("CI", raising=False)
    viz.spawn(SimpleNamespace(scenario=SimpleNamespace(name="s")))  # type: ignore[arg-type]
    assert seen == {"CI": "1"} and "CI" not in __import__("os").environ


# --------------------------------------------------------------------------- progress on every long step


class _Steps:
    """Stands in for :func:`sins.cli.progress.progress_bar` and records each step's descriptions."""

    def __init__(self) -> None:
        self.names: list[str] = []

    @contextmanager
    def __call__(self, description: str, unit: str) -> Iterator[Any]:
        steps = self

        class Bar:
            n, total = 0, None

            def update(self, count: int = 1) -> None:
                self.n += count

            def set_description(self, text: str) -> None:
                steps.names.append(text)

            def set_postfix_str(self, text: str) -> None:
                pass

        self.names.append(description)
        yield Bar()


@pytest.fixture
def steps(monkeypatch: pytest.MonkeyPatch) -> _Steps:
    from sins.cli import bias, correct, evaluate, fit, integrate

    recorder = _Steps()
    for module in (common, bias, correct, evaluate, fit, integrate):
        monkeypatch.setattr(module, "progress_bar", recorder)
    return recorder


@pytest.fixture(scope="module")
def referenced_files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    rng = np.random.default_rng(7)
    s = session(rng, typical_unit(rng), duration_s=60.0)
    folder = tmp_path_factory.mktemp("ref")
    imu, truth = folder / "imu.csv", folder / "truth.csv"
    rows = np.column_stack([s.t, s.gyro, s.accel])
    np.savetxt(imu, rows, delimiter=",", header="t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z", comments="")
    _write_truth(truth, s)
    return imu, truth


def test_bias_only_is_named_so_and_lists_its_six_biases(
    tmp_path: Path, referenced_files: tuple[Path, Path], steps: _Steps, capsys: pytest.CaptureFixture[str]
) -> None:
    imu, truth = referenced_files
    model, report = tmp_path / "m.json", tmp_path / "fit.json"
    argv = [
        "fit",
        str(imu),
        "--truth",
        str(truth),
        "--strategy",
        "bias_only",
        "--out",
        str(model),
        "--json",
        str(report),
    ]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "fitted bias_only on" in out and "fitted regression" not in out
    assert "scale" not in out and "misalignment" not in out
    saved = json.loads(model.read_text(encoding="utf-8"))
    assert saved["variant"] == "bias_only" and compensation.load(model).label == "bias_only"
    doc = json.loads(report.read_text(encoding="utf-8"))
    assert doc["strategy"] == "bias_only" and [c["term"] for c in doc["coefficients"]] == ["bias"] * 6
    assert main(["evaluate", str(model), str(imu), "--truth", str(truth)]) == 0
    assert f"{model} (bias_only)" in capsys.readouterr().out
    # Every step that reads or works for seconds says so.
    assert steps.names[:2] == [f"reading {imu}", "fitting bias_only"]
    assert f"reading {imu}" in steps.names[2:] and any(n.startswith("open loop: ") for n in steps.names)


def test_correct_writes_the_form_its_help_names_and_shows_each_step(
    tmp_path: Path, referenced_files: tuple[Path, Path], steps: _Steps, capsys: pytest.CaptureFixture[str]
) -> None:
    imu, truth = referenced_files
    model = tmp_path / "m.json"
    assert (
        main(["fit", str(imu), "--truth", str(truth), "--strategy", "regression", "--out", str(model)]) == 0
    )
    steps.names.clear()
    out = tmp_path / "corrected.csv"
    assert main(["correct", str(model), str(imu), "--out", str(out)]) == 0
    assert "in rate form" in capsys.readouterr().out
    header = next(line for line in out.read_text().splitlines() if not line.startswith("#"))
    assert header == "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"
    assert steps.names == [f"reading {imu}", f"correcting {imu}", f"writing {out}"]
    with pytest.raises(SystemExit):
        main(["correct", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "rates for a rig recording or a rate file" in text
    assert (
        "increments for an increment file and for a recording read with a trajectory (its own: a EuRoC"
        in text
    )


def test_integrate_shows_the_writing_and_withholds_a_minutes_per_hour_rate(
    tmp_path: Path, steps: _Steps, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "short.toml").write_text(
        '[imu]\nrate_hz = 50\nmodel = "tactical"\n[initial]\nlat_deg = 45\nspeed_mps = 5\n'
        '[[segment]]\ntype = "turn"\nduration_s = 60\nrate_dps = 3\n',
        encoding="utf-8",
    )
    imu, truth, sol = tmp_path / "imu.csv", tmp_path / "truth.csv", tmp_path / "sol.csv"
    assert main(["simulate", str(tmp_path / "short.toml"), "--imu", str(imu), "--truth", str(truth)]) == 0
    capsys.readouterr()
    assert main(["integrate", str(imu), "--truth", str(truth), "--out", str(sol)]) == 0
    out = capsys.readouterr().out
    assert f"writing {sol}" in steps.names
    row = next(line for line in out.splitlines() if line.startswith("none "))
    assert row.split()[-2:] == ["-", "-"]
    assert "m/h, nmi/h: withheld for a run under 10 min (60 s)" in out


def test_per_hour_rates_are_marked_below_an_hour_and_plain_from_one() -> None:
    summary = {"final_north_m": 1.0, "final_east_m": 0.0, "final_down_m": 0.0, "final_horizontal_m": 1.0,
               "max_horizontal_m": 1.0, "final_roll_deg": 0.0, "final_pitch_deg": 0.0, "final_yaw_deg": 0.0,
               "drift_rate_m_per_h": 2.0, "drift_rate_nmi_per_h": 0.001}  # fmt: skip
    half = common.format_table({"none": {**summary, "duration_s": 1800.0}})
    assert "2.000*" in half and "0.0011*" not in half and "0.0010*" in half
    assert "* the 1800 s run's final horizontal error scaled to an hour: an extrapolation" in half
    hour = common.format_table({"none": {**summary, "duration_s": 3600.0}})
    assert "*" not in hour and hour.splitlines()[-1].split()[-2:] == ["2.000", "0.0010"]


def test_bias_shows_its_steps(tmp_path: Path, steps: _Steps, capsys: pytest.CaptureFixture[str]) -> None:
    from test_bias import still_unit

    imu, _ = still_unit(20.0, np.zeros(3), np.zeros(3), np.r_[[3e-4] * 3, [0.01] * 3])
    io.write_imu(tmp_path / "still.csv", imu)
    assert main(["bias", str(tmp_path / "still.csv"), "--lat", "45", "--plot", str(tmp_path / "b.png")]) == 0
    assert steps.names == ["reading", "fitting the noise", f"drawing {tmp_path / 'b.png'}"]
