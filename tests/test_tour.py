"""The newcomer's test: the README's five-minute tour, read from the README itself, run in order.

Each command runs as printed, in a fresh directory, with the project's environment on ``PATH`` (as
``source .venv/bin/activate`` puts it there), so the front page cannot promise a command that fails.
Two lines cannot run here and are checked for what they need instead: ``rerun FILE`` opens a viewer
window (the test asserts the file it would open is a Rerun recording), and a ``--dataset`` line needs
the real recordings under the data root (run when they are there, as the datasets' tests do).
"""

from __future__ import annotations

import os
import shlex
import sys
from pathlib import Path

import pytest
from conftest import run_process

from sins.io.datasets import data_root

ROOT = Path(__file__).resolve().parents[1]


def tour_commands() -> list[str]:
    """The tour's command lines, comments and the activation line removed."""
    readme = (ROOT / "README.md").read_text()
    section = readme.split("## A five-minute tour", 1)[1]
    block = section.split("```sh\n", 1)[1].split("```", 1)[0]
    lines = [line.split("#", 1)[0].strip() for line in block.splitlines()]
    return [line for line in lines if line and not line.startswith("source ")]


def test_the_tour_is_there_and_covers_the_promised_steps():
    words = [shlex.split(line)[:2] for line in tour_commands()]
    # simulate → calibrate → fit → evaluate → run with compensation → look in Rerun → diagnose
    assert [w[1] if w[0] == "sins" else w[0] for w in words][:7] == [
        "run",
        "calibrate",
        "fit",
        "evaluate",
        "run",
        "rerun",
        "gap",
    ], words


def test_the_readmes_tour_runs_in_order(tmp_path):
    env = {
        **os.environ,
        "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",
        "OMP_NUM_THREADS": "1",
    }
    ran = []
    for line in tour_commands():
        argv = shlex.split(line)
        if argv[0] == "rerun":
            recording = tmp_path / argv[1]
            # What the viewer would open: a Rerun recording file ("RRF2" is its magic number).
            assert recording.read_bytes()[:4] == b"RRF2", line
            continue
        if "--dataset" in argv and not data_root().exists():
            continue
        done = run_process(argv, cwd=tmp_path, env=env, capture_output=True, text=True)
        assert done.returncode == 0, (line, done.stderr[-2000:])
        assert done.stdout.strip(), f"{line!r} printed nothing"
        ran.append(argv[1])
    assert ran.count("run") == 2 and "fit" in ran and "gap" in ran, ran


if __name__ == "__main__":
    pytest.main([__file__, "-q"])
