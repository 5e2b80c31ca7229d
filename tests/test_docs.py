"""The documentation site builds with ``--strict``: a broken link, a missing page or an API entry that no
longer exists fails here, as in ``make docs``."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from conftest import run_process

ROOT = Path(__file__).resolve().parents[1]


def test_the_site_builds_strictly(tmp_path):
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    command = [
        sys.executable,
        "-m",
        "mkdocs",
        "build",
        "--strict",
        "--quiet",
        "--site-dir",
        str(tmp_path / "site"),
    ]
    done = run_process(command, cwd=ROOT, capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr[-3000:]
    api = (tmp_path / "site" / "api" / "index.html").read_text()
    # The reference is generated from the docstrings, not empty: the integrator's entry point is there.
    assert "sins.nav.strapdown.integrate" in api


def test_every_page_is_in_the_navigation():
    import yaml  # mkdocs's own dependency

    nav = yaml.safe_load((ROOT / "mkdocs.yml").read_text().replace("!!python", "#"))["nav"]

    def pages(items: list) -> set[str]:
        out: set[str] = set()
        for item in items:
            for value in item.values():
                out |= pages(value) if isinstance(value, list) else {value}
        return out

    on_disk = {str(p.relative_to(ROOT / "docs")) for p in (ROOT / "docs").rglob("*.md")}
    assert on_disk == pages(nav)


def test_every_whole_scenario_the_guides_show_loads(tmp_path):
    """A guide's scenario file (a ```toml block with a trajectory) loads as shown: the scenarios guide's
    first example had kept ``vertical_tau_s`` beside a free channel once sins refused that pairing."""
    import re

    from sins import scenario

    shown = 0
    for page in sorted((ROOT / "docs").rglob("*.md")):
        for k, block in enumerate(re.findall(r"```toml\n(.*?)```", page.read_text(), re.S)):
            if not re.search(r"^\[\[(segment|waypoint)\]\]|^\[truth\]", block, re.M) or "model =" in block:
                continue  # a fragment, or one naming files of its own
            path = tmp_path / f"{page.stem}_{k}.toml"
            path.write_text(block)
            scenario.load(path)
            shown += 1
    assert shown >= 1
