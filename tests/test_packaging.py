"""The package as pip builds it: every preset file inside the wheel, and no setuptools warning on the way
(``make run``'s first install printed four "Package would be ignored" notices for the preset folders)."""

from __future__ import annotations

import shutil
import sys
import zipfile
from pathlib import Path

import pytest
from conftest import run_process

ROOT = Path(__file__).resolve().parents[1]


def test_the_wheel_holds_every_preset_and_builds_without_warnings(tmp_path: Path) -> None:
    setuptools = pytest.importorskip("setuptools")
    if int(setuptools.__version__.split(".")[0]) < 77:  # pyproject's build requirement; no download here
        pytest.skip(f"setuptools {setuptools.__version__} is older than the build needs (77)")
    source = tmp_path / "source"  # pip builds in the tree it is given: a copy, not the checkout
    for name in ("sins", "scenarios"):
        shutil.copytree(
            ROOT / name, source / name, symlinks=True, ignore=shutil.ignore_patterns("__pycache__")
        )
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, source / name)
    done = run_process(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index",
         "-w", str(tmp_path), str(source)],
        capture_output=True, text=True,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    output = done.stdout + done.stderr
    assert "would be ignored" not in output and "BuildBackendWarning" not in output, output[-2000:]
    (wheel,) = tmp_path.glob("sins-*.whl")
    inside = {n for n in zipfile.ZipFile(wheel).namelist() if n.startswith("sins/scenarios/")}
    presets = ROOT / "scenarios"
    shipped = {
        f"sins/scenarios/{p.relative_to(presets).as_posix()}" for p in presets.rglob("*") if p.is_file()
    }
    assert shipped and shipped == inside
