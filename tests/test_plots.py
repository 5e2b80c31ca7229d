"""``--plot OUT.png|.html`` on ``sins run``, ``integrate``, ``evaluate``, ``campaign``, ``characterise`` and
``bias``, run as a user runs them (the CLI in a temporary folder, no display): each image has the size its
panels give it and something drawn in every panel; an HTML page holds the same PNG; a bad path is refused
before the work. And what the figures hold, read from the matplotlib Figure the library returns: the
lines, labels, envelopes and scales an engineer would put in a report."""

from __future__ import annotations

import base64
import re
from pathlib import Path

import numpy as np
import pytest
from matplotlib import image

from sins import compensation, io
from sins.cli import main
from sins.viz import plots

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

STILL = """\
[imu]
rate_hz = 100
model = "tactical"
[initial]
lat_deg = 45
[[segment]]
type = "hold"
duration_s = {seconds}
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


def _check_image(path: Path, panels: int, cols: int = 1) -> None:
    """Width and height are the figure's size at its resolution (the height grows with the rows of
    panels, the width with their columns); every row's horizontal band holds coloured pixels (a curve, a
    bar or a box, not only the white page, black text and grey grid)."""
    rgb = _pixels(path)
    height = round((plots.PANEL_HEIGHT_IN * panels + 0.6) * plots.DPI)
    width = plots.WIDTH_IN if cols == 1 else plots.COLUMN_WIDTH_IN * cols
    assert rgb.shape[:2] == (height, round(width * plots.DPI)), (path, rgb.shape)
    # Not one colour: lines, text, fills. A PNG's channels are 8-bit, so each colour packs into one integer
    # exactly (np.unique over rows of floats sorts them lexically: seconds on a 3-column figure).
    rgba = np.zeros((rgb.shape[0] * rgb.shape[1], 4), dtype=np.uint8)
    rgba[:, :3] = np.round(rgb.reshape(-1, 3) * 255.0)
    assert len(np.unique(rgba.view(np.uint32))) > 50
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
    # Position, velocity and attitude errors in three rows of north, east, down; the drift budget below.
    _check_image(folder / "run.png", 4, 3)
    _check_image(folder / "run.html", 4, 3)
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
    channels = compensation.residual_rms(compensation.load("model.json"), io.read("rig.csv").rig)
    fig = plots.evaluate_figure(channels, "t")
    assert len(fig.axes) == 2 and [len(ax.patches) for ax in fig.axes] == [6, 6]
    # On a log scale: the corrected bars stay readable beside the raw ones a hundred times taller.
    assert [ax.get_yscale() for ax in fig.axes] == ["log", "log"]


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


# --------------------------------------------------------------------------- what the figures hold


def _labels(ax) -> list[str]:  # type: ignore[no-untyped-def]
    return [line.get_label() for line in ax.get_lines()]


def _errors(t: np.ndarray, scale: float):  # type: ignore[no-untyped-def]
    """Errors growing as t² to ``scale`` m at the end (down as large as north, yaw in degrees small)."""
    from sins.nav.metrics import NavErrors

    grow = (t / t[-1]) ** 2
    pos = np.column_stack([scale * grow, -0.5 * scale * grow, scale * grow])
    return NavErrors(
        t=t,
        pos_ned_m=pos,
        vel_ned_mps=np.gradient(pos, t, axis=0),
        att_rpy_rad=1e-4 * np.outer(grow, [1, 1, 1]),
    )


def test_the_error_grid_splits_north_east_down_and_goes_logarithmic_where_errors_span_decades() -> None:
    """A free vertical channel's 221 km beside a compensated unit's 5 m: each component in a panel of its
    own, and a panel whose lines differ more than a hundredfold on a symmetric log scale."""
    t = np.linspace(0.0, 3600.0, 361)
    free, compensated = _errors(t, 221e3), _errors(t, 5.0)
    fig = plots.errors_figure({"none": free, "regression": compensated}, "drive")
    axes = fig.axes
    assert len(axes) == 9
    names = [ax.get_ylabel() for ax in axes]
    assert names == [
        "north position error, m", "east position error, m", "down position error, m",
        "north velocity error, m/s", "east velocity error, m/s", "down velocity error, m/s",
        "roll attitude error, °", "pitch attitude error, °", "yaw attitude error, °",
    ]  # fmt: skip
    assert all(_labels(ax) == ["none", "regression"] for ax in axes)
    assert axes[2].get_yscale() == "symlog" and axes[0].get_yscale() == "symlog"
    same = plots.errors_figure({"a": _errors(t, 10.0), "b": _errors(t, 20.0)}, "alike")
    assert {ax.get_yscale() for ax in same.axes} == {"linear"}
    # The down panel draws the run's own numbers: the last point is the 221 km.
    assert axes[2].get_lines()[0].get_ydata()[-1] == pytest.approx(221e3)


@pytest.fixture(scope="module")
def aided_run():  # type: ignore[no-untyped-def]
    from test_aiding_scenario import DRIVE

    from sins.runs import pipeline
    from sins.scenario import from_dict

    return pipeline.run_scenario(from_dict(DRIVE))


def test_the_aided_rows_hold_the_filters_envelopes_and_the_budget_its_bias_terms(aided_run) -> None:  # type: ignore[no-untyped-def]
    fig = plots.run_figure(aided_run)
    axes = np.array(fig.axes).reshape(-1, 3)
    assert axes.shape == (6, 3)  # three error rows, two aided rows, one budget row
    run = aided_run.aided["none"]
    for j, part in enumerate(("north", "east", "down")):
        ax = axes[3][j]
        assert ax.get_ylabel() == f"aided {part} error, m"
        bands = {c.get_label(): c for c in ax.collections}
        assert set(bands) == {"none ±1σ", "none ±3σ"}
        # The 3σ envelope's upper edge is three times the filter's σ of that state.
        top = bands["none ±3σ"].get_paths()[0].vertices[:, 1].max()
        assert top == pytest.approx(3.0 * run.sigma[:, j].max(), rel=1e-9)
    assert axes[4][0].get_ylabel() == "aided yaw error, °" and len(axes[4][0].collections) == 2
    assert "outage" in [p.get_label() for p in axes[4][1].patches]
    assert any(label.startswith("true gyro") for label in _labels(axes[4][2]))
    budget = axes[5][0]
    assert budget.get_title() == "none: drift budget" and budget.get_yscale() == "log"
    labels = _labels(budget)
    assert labels[0] == "horizontal error"
    assert any(x.startswith("gyro level bias") for x in labels) and any(
        x.startswith("accel level bias") for x in labels
    )


def test_open_loop_runs_get_their_own_axes() -> None:
    """The raw readings' 34° and a correction's 1.2° in panels of their own: the corrected curve keeps
    its scale instead of lying flat under the raw one."""
    from sins.compensation.judging import OpenLoop

    t = np.linspace(0.0, 100.0, 101)
    raw = OpenLoop(t, np.radians(0.34 * t), np.radians(0.3 * t), np.radians(0.1 * t), np.ones(101, bool))
    fixed = OpenLoop(
        t, np.radians(0.012 * t), np.radians(0.01 * t), np.radians(0.005 * t), np.ones(101, bool)
    )
    fig = plots.open_loop_figure({"none (raw readings)": raw, "kohonen": fixed}, "t")
    assert len(fig.axes) == 2
    assert [ax.get_title() for ax in fig.axes] == ["none (raw readings)", "kohonen"]
    assert all(_labels(ax) == ["total", "heading", "inclination"] for ax in fig.axes)
    assert fig.axes[1].get_ylim()[1] < 0.1 * fig.axes[0].get_ylim()[1]


def test_integrate_plots_errors_with_a_truth_and_the_solution_without(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["simulate", "short.toml", "--imu", "imu.csv", "--truth", "truth.csv"]) == 0
    assert main(["integrate", "imu.csv", "--truth", "truth.csv", "--plot", "errors.png"]) == 0
    _check_image(folder / "errors.png", 3, 3)
    still = folder / "still.toml"
    still.write_text(STILL.format(seconds=40), encoding="utf-8")
    assert main(["simulate", "still.toml", "--imu", "still.csv", "--truth", "st.csv", "--form", "rate"]) == 0
    args = [
        "integrate",
        "still.csv",
        "--origin",
        "45,0,0",
        "--align",
        "20",
        "--heading",
        "0",
        "--plot",
        "free.png",
    ]
    assert main(args) == 0
    capsys.readouterr()
    _check_image(folder / "free.png", 4, 3)
    from sins import io as sins_io
    from sins.core.series import ImuRates
    from sins.runs import replay

    rec = sins_io.read(folder / "still.csv")
    assert isinstance(rec.imu, ImuRates)
    imu = rec.imu.to_increments()
    start = replay.free_start(imu, (np.radians(45.0), 0.0, 0.0), align_s=20.0, heading=0.0)
    sol = replay.navigate_free(imu, start)
    ned = replay.still_drift(start.rest, sol.t - sol.t[0])
    fig = plots.solution_figure(sol, "t", [("bias", sol.t, np.hypot(ned[:, 0], ned[:, 1]), "horizontal")])
    axes = np.array(fig.axes).reshape(4, 3)
    assert (
        axes[0][0].get_ylabel() == "north offset from the start, m"
        and axes[2][2].get_ylabel() == "yaw angle, °"
    )
    assert axes[3][0].get_yscale() == "log" and _labels(axes[3][0]) == ["solution", "bias"]
    assert not axes[3][2].axison  # the empty cell is hidden


def test_the_allan_plot_draws_each_resolved_term_with_its_value(
    folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (folder / "still.toml").write_text(STILL.format(seconds=120), encoding="utf-8")
    assert main(["simulate", "still.toml", "--imu", "still.csv", "--truth", "truth.csv"]) == 0
    from sins import characterise
    from sins.characterise import check, model_file

    t, w, f = sins_io_rates(folder / "still.csv")
    result = characterise.characterise(characterise.residual(t, np.hstack([w, f]), None, "still"))
    closing = check.closing_check(result, model_file.imu_model(result))
    fig = plots.characterise_figure(result, closing)
    gyro = fig.axes[0]
    white = result.channels["gyro.x"].fit.terms["white"]
    assert white.resolved
    # The white noise's own line, slope −½ on the log axes, through N at τ = 1 s.
    line = next(ln for ln in gyro.get_lines() if ln.get_label() == "gyro.x N")
    x, y = np.log(line.get_xdata()), np.log(line.get_ydata())
    assert np.polyfit(x, y, 1)[0] == pytest.approx(-0.5, abs=1e-9)
    n_display = white.value / (np.pi / 180.0 / 60.0)  # °/√h
    assert np.exp(np.interp(0.0, x, y)) == pytest.approx(n_display * 60.0, rel=1e-6)  # °/h at 1 s
    texts = [a.get_text() for a in gyro.texts]
    assert any(text.startswith("N ") and text.endswith("°/√h") for text in texts)


def sins_io_rates(path: Path):  # type: ignore[no-untyped-def]
    return io.read(path).mean_rates()


def test_the_bias_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from test_bias import ACCEL_UG, DPH, UG, still_unit

    imu, _ = still_unit(
        60.0, np.array([10.0, -5.0, 3.0]) * DPH, np.array(ACCEL_UG) * UG, np.r_[[3e-4] * 3, [0.01] * 3]
    )
    io.write_imu(tmp_path / "still.csv", imu)
    assert (
        main(
            [
                "bias",
                str(tmp_path / "still.csv"),
                "--lat",
                "45",
                "--attitude",
                "2,-1,30",
                "--plot",
                str(tmp_path / "b.png"),
            ]
        )
        == 0
    )
    capsys.readouterr()
    _check_image(tmp_path / "b.png", 2)
    from sins.characterise.bias import recording_bias

    est = recording_bias(
        io.read(tmp_path / "still.csv"),
        np.radians(45.0),
        0.0,
        tuple(np.radians([2.0, -1.0, 30.0])),
    )
    fig = plots.bias_figure(est)
    gyro, accel = fig.axes
    assert (
        gyro.get_ylabel() == "gyro reading − Earth's rate, °/h"
        and accel.get_ylabel() == "accel reading − gravity, µg"
    )
    labels = _labels(gyro)
    assert labels[0] == "gyro.x" and labels[1].startswith("bias ") and labels[1].endswith("°/h")
    # The dashed bias line sits at the estimate, in °/h.
    assert gyro.get_lines()[1].get_ydata()[0] == pytest.approx(est.channels["gyro.x"].bias / DPH)
