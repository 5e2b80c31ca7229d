"""Long jobs show a sign of life: a tqdm bar when stderr is a terminal, plain lines in a log (stderr a
file or a pipe) once the job runs past a few seconds, and nothing for a short job."""

from __future__ import annotations

import fcntl
import os
import pty
import re
import struct
import subprocess
import sys
import termios
import time
from pathlib import Path

import numpy as np
import pytest

from sins.cli import main
from sins.cli import progress as bars
from sins.core.series import CalibrationData

STILL = """\
[imu]
rate_hz = 100
model = "tactical"
[initial]
lat_deg = 45
[[segment]]
type = "hold"
duration_s = 60
"""


def test_log_lines_come_after_the_first_seconds_then_regularly(
    monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    """A job of 0.5 s with the first line due at 0.1 s and then every 0.1 s: about four lines naming the
    count done of the total, then a closing one; a job shorter than the first line writes nothing."""
    monkeypatch.setattr(bars, "LOG_FIRST_S", 0.1)
    monkeypatch.setattr(bars, "LOG_EVERY_S", 0.1)
    with bars.progress_bar("working hard", "row") as bar:
        for k in range(5):
            bars.advance(bar, k + 1, 5)
            time.sleep(0.1)
    err = capsys.readouterr().err.splitlines()
    assert 2 <= len(err) <= 7, err  # 4 due; the scheduler of a loaded machine may shift one
    assert all(re.fullmatch(r"working hard: \d/5 rows \(\d+ s\)", line) for line in err[:-1]), err
    assert err[-1].startswith("working hard: done, 5 rows")
    with bars.progress_bar("quick", "row") as bar:
        bars.advance(bar, 1, 1)
    assert capsys.readouterr().err == ""


def test_a_failed_job_ends_on_its_error_not_on_done(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    monkeypatch.setattr(bars, "LOG_FIRST_S", 0.05)
    with pytest.raises(RuntimeError), bars.progress_bar("failing", "row"):
        time.sleep(0.2)
        raise RuntimeError("boom")
    err = capsys.readouterr().err
    assert "failing: working" in err and "done" not in err


def test_a_command_logs_its_progress(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``sins characterise`` run as in a log (stderr captured, not a terminal), with the lines due from
    the start: its stages and channel counts, each job closed with "done"; stdout holds the results only."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(bars, "LOG_FIRST_S", 0.0)
    monkeypatch.setattr(bars, "LOG_EVERY_S", 0.05)
    (tmp_path / "still.toml").write_text(STILL, encoding="utf-8")
    assert main(["simulate", "still.toml", "--imu", "imu.csv", "--truth", "truth.csv"]) == 0
    capsys.readouterr()
    assert main(["characterise", "imu.csv", "--static"]) == 0
    captured = capsys.readouterr()
    assert re.search(r"^characterising: [0-6]/6 channels \(\d+ s\)$", captured.err, re.M), captured.err
    assert re.search(r"^closing check: done, 6 channels", captured.err, re.M), captured.err
    assert "channels (" not in captured.out


def test_the_seed_papers_network_reports_each_epoch() -> None:
    """``sins fit --strategy mlp_seed`` trains epoch by epoch for minutes: each epoch is reported."""
    from sins.compensation.mlp import MLP

    rng = np.random.default_rng(0)
    gyro, accel = rng.normal(size=(200, 3)), rng.normal(size=(200, 3))
    data = CalibrationData(
        t=np.arange(200.0), gyro=gyro, accel=accel, ref_gyro=0.99 * gyro, ref_accel=0.98 * accel
    )
    for mode in ("seed", "modern"):
        seen: list[tuple[int, int]] = []
        net = MLP(mode=mode, hidden=(4,), max_epochs=3, patience=10, residual=0.0)
        net.progress = lambda done, total, seen=seen: seen.append((done, total))
        net.fit(data)
        assert seen == [(1, 3), (2, 3), (3, 3)], mode


def test_a_terminal_gets_a_bar(tmp_path: Path) -> None:
    """On a terminal (a pseudo-terminal here) the bar is tqdm's: its rate and count on stderr."""
    (tmp_path / "still.toml").write_text(STILL, encoding="utf-8")
    leader, follower = pty.openpty()
    # A terminal 100 columns wide: tqdm draws nothing on one of 0 columns (a pty's size until it is set).
    fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))
    proc = subprocess.Popen(
        [sys.executable, "-m", "sins.cli", "simulate", "still.toml", "--imu", "imu.csv", "--truth", "t.csv"],
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=follower, stdin=subprocess.DEVNULL,
    )  # fmt: skip
    os.close(follower)
    chunks = []
    while True:
        try:
            chunk = os.read(leader, 4096)
        except OSError:  # the terminal closed with the process
            break
        if not chunk:
            break
        chunks.append(chunk)
    assert proc.wait(120) == 0
    os.close(leader)
    text = b"".join(chunks).decode("utf-8", "replace")
    assert "simulating still: 00:00" in text, text  # a stage: its name and time taken
    # tqdm's bar: the count and the rate (a file this short is written before its first redraw).
    assert re.search(r"writing imu\.csv: \d+ row \[[0-9:]+, [?0-9.]+ row/s\]", text), text
