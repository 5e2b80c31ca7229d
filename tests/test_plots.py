"""``--plot OUT.png|.html`` on ``sins run``, ``evaluate``, ``campaign`` and ``characterise``, run as a user
runs them (the CLI in a temporary folder, no display): each image has the size its panels give it and
something drawn in every panel; an HTML page holds the same PNG; a bad path is refused before the work."""

from __future__ import annotations

import base64
import re
from pathlib import Path

import numpy as np
import pytest
from matplotlib import image

from sins import compensation, io, plots
from sins.cli import main

SHORT = """\
name = "short"
[imu]
rate_hz = 50
model = "tactical"
[initial]
lat_deg = 45.0
speed_mps = 5.0
[[segment]]
type = "turn"
duration_s = 10
rate_dps = 5
"""

RIG = """\
[rig]
lat_deg = 45.0
rate_hz = 50
[positions]
count = 6
dwell_s = 10
[rate_table]
rates_dps = [50]
axes = ["x", "y", "z"]
orientations = ["up"]
dwell_s = 5
"""


@pytest.fixture
def folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("DISPLAY", raising=False)  # as on a server: nothing may need a display
    (tmp_path / "short.toml").write_text(SHORT, encoding="utf-8")
    return tmp_path


def _pixels(path: Path) -> np.ndarray:
    """The PNG's RGB pixels, from the file or from the page that embeds it."""
    if path.suffix == ".html":
        page = path.read_text(encoding="utf-8")
        match = re.search(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', page)
        assert match, "no embedded PNG"
        png = path.with_suffix(".from-html.png")
        png.write_bytes(base64.b64decode(match.group(1)))
        path = png
    return image.imread(path)[:, :, :3]


def _check_image(path: Path, panels: int) -> None:
    """Width and height are the figure's size at its resolution (the height grows with the panels);
    every panel's horizontal band holds coloured pixels (a curve, a bar or a box, not only the white
    page, black text and grey grid)."""
    rgb = _pixels(path)
    height = round((plots.PANEL_HEIGHT_IN * panels + 0.6) * plots.DPI)
    assert rgb.shape[:2] == (height, round(plots.WIDTH_IN * plots.DPI)), (path, rgb.shape)
    assert len(np.unique(rgb.reshape(-1, 3), axis=0)) > 50  # not one colour: lines, text, fills
    coloured = np.ptp(rgb, axis=2) > 0.2  # far from grey: white, black and the grid are grey
    band = (height - round(0.6 * plots.DPI)) // panels
    top = round(0.6 * plots.DPI)
    for k in range(panels):
        rows = coloured[top + k * band : top + (k + 1) * band]
        assert rows.mean() > 1e-3, f"{path}: panel {k + 1} of {panels} looks empty"


def test_run_plot_png_and_html(folder: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "short.toml", "--plot", "run.png"]) == 0
    assert main(["run", "short.toml", "--plot", "run.html"]) == 0
    assert "wrote run.html" in capsys.readouterr().out
    _check_image(folder / "run.png", 3)
    _check_image(folder / "run.html", 3)
    assert np.array_equal(_pixels(folder / "run.png"), _pixels(folder / "run.html"))
    assert "<title>sins run short</title>" in (folder / "run.html").read_text(encoding="utf-8")


def test_a_bad_plot_path_is_refused_before_the_work(folder: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for bad, fragment in (("run.jpg", "not .jpg"), ("no/such/run.png", "does not exist")):
        assert main(["run", "short.toml", "--json", "s.json", "--plot", bad]) == 2
        err = capsys.readouterr().err
        assert err.startswith("sins: error: ") and err.count("\n") == 1 and fragment in err, err
        assert not (folder / "s.json").exists()  # refused before the run


def test_evaluate_plot(folder: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (folder / "rig.toml").write_text(RIG, encoding="utf-8")
    assert main(["calibrate", "rig.toml", "--imu", "tactical", "--out", "rig.csv", "--seed", "1"]) == 0
    assert main(["fit", "rig.csv", "--strategy", "regression", "--out", "model.json"]) == 0
    assert main(["evaluate", "model.json", "rig.csv", "--plot", "ev.png"]) == 0
    capsys.readouterr()
    _check_image(folder / "ev.png", 2)
    # Two panels, three channels each, before and after: the library call behind it says so too.
    channels = compensation.residual_rms(compensation.load("model.json"), io.read_recording("rig.csv"))
    fig = plots.evaluate_figure(channels, "t")
    assert len(fig.axes) == 2 and [len(ax.patches) for ax in fig.axes] == [6, 6]


def test_characterise_plot(folder: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (folder / "still.toml").write_text(
        '[imu]\nrate_hz = 100\nmodel = "tactical"\n[initial]\nlat_deg = 45\n'
        '[[segment]]\ntype = "hold"\nduration_s = 120\n',
        encoding="utf-8",
    )
    assert main(["simulate", "still.toml", "--imu", "still.csv", "--truth", "truth.csv"]) == 0
    assert main(["characterise", "still.csv", "--static", "--plot", "allan.html"]) == 0
    capsys.readouterr()
    _check_image(folder / "allan.html", 2)


def test_campaign_plot(folder: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (folder / "c.toml").write_text(
        'name = "c"\n[units]\nimu = "tactical"\ncount = 3\n[compensation]\nrig = "rig.toml"\n'
        'strategies = ["none", "regression"]\n[[scenario]]\nfile = "short.toml"\n',
        encoding="utf-8",
    )
    (folder / "rig.toml").write_text(RIG, encoding="utf-8")
    assert main(["campaign", "c.toml", "--workers", "1", "--out", "out", "--plot", "spread.png"]) == 0
    capsys.readouterr()
    _check_image(folder / "spread.png", 1)
    # One box per strategy (the oracle, none, regression), each over the three units.
    import pyarrow.parquet as pq

    fig = plots.campaign_figure(pq.read_table(folder / "out" / "results.parquet").to_pydict(), "c")
    assert len(fig.axes) == 1 and [t.get_text() for t in fig.axes[0].get_xticklabels()] == [
        "oracle",
        "none",
        "regression",
    ]
