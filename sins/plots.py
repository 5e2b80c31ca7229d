"""Pictures without a display: a run's drift, a model's residuals, a campaign's spread and a unit's
Allan curves as PNG images (matplotlib's Agg renderer), or as a small HTML page holding the PNG.

The only module that imports matplotlib. Each ``*_figure`` function builds a
:class:`matplotlib.figure.Figure` from a result a library call returned (no global pyplot state, so it
works in threads and headless); :func:`save` writes it. Errors are shown in the project's display units:
metres and degrees for navigation, °/h and mg for residual readings, °/h and µg for Allan deviations.

``OUT.html`` is a self-contained page: a heading and the PNG embedded as base64 (``<img src="data:...">``),
no scripts and nothing fetched, so it opens in any browser, attaches to a mail, and serves from CI.
"""

from __future__ import annotations

import base64
import html
import io as _bytes
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from sins.errors import SinsInputError
from sins.io import atomic_path

if TYPE_CHECKING:
    from sins.characterise.analysis import Characterisation
    from sins.characterise.check import ClosingCheck
    from sins.pipeline import ScenarioRun
    from sins.referenced import OpenLoop

#: The file kinds :func:`save` writes, by suffix.
SUFFIXES = (".png", ".html")
#: Size of every image, inches, and its resolution: 1500 × 1000 pixels for two panels and more.
WIDTH_IN, PANEL_HEIGHT_IN, DPI = 10.0, 3.0, 150
#: The channels' order and their display units (°/h for gyros, mg for accelerometers).
CHANNELS = ("gyro.x", "gyro.y", "gyro.z", "accel.x", "accel.y", "accel.z")
_DEG_PER_H = np.pi / 180.0 / 3600.0
_MG = 9.80665e-3


def check_plot_path(path: str | os.PathLike[str]) -> None:
    """Refuse a picture path :func:`save` cannot write, before any work is done: its kind (the place
    is :func:`sins.io.paths.check_outputs`'s, which the commands call with every output).

    Raises
    ------
    SinsInputError
        a suffix other than ``.png`` or ``.html``.
    """
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise SinsInputError(
            f"{path}: --plot writes .png or .html, not {path.suffix or 'a file without a suffix'}"
        )


def save(fig: Figure, path: str | os.PathLike[str], title: str = "") -> Path:
    """Write ``fig`` as a PNG, or as an HTML page holding the PNG (by the suffix), atomically.

    Raises
    ------
    SinsInputError
        as :func:`check_plot_path`.
    """
    check_plot_path(path)
    path = Path(path)
    buffer = _bytes.BytesIO()
    FigureCanvasAgg(fig)
    fig.savefig(buffer, format="png", dpi=DPI, metadata={"Software": "sins"})
    png = buffer.getvalue()
    with atomic_path(path) as tmp:
        if path.suffix.lower() == ".png":
            tmp.write_bytes(png)
        else:
            encoded = base64.b64encode(png).decode("ascii")
            name = html.escape(title or path.stem)
            tmp.write_text(
                f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{name}</title></head>\n'
                f'<body><h1 style="font-family: sans-serif; font-size: 1.2em">{name}</h1>\n'
                f'<img alt="{name}" style="max-width: 100%" src="data:image/png;base64,{encoded}">\n'
                "</body></html>\n",
                encoding="utf-8",
            )
    return path


def _figure(panels: int, title: str) -> tuple[Figure, list[Any]]:
    fig = Figure(figsize=(WIDTH_IN, PANEL_HEIGHT_IN * panels + 0.6), layout="constrained")
    axes = list(np.atleast_1d(fig.subplots(panels, 1, squeeze=False)[:, 0]))
    fig.suptitle(title)
    return fig, axes


def run_figure(result: ScenarioRun) -> Figure:
    """``sins run``: per strategy, the horizontal and down position errors and the yaw error against
    time (m, m, °); with ``[gnss]``, a fourth panel of the aided horizontal errors, outages shaded."""
    sc = result.scenario
    aided = {name: run for name, run in result.aided.items() if run.errors is not None}
    fig, axes = _figure(4 if aided else 3, f"scenario {sc.name}: errors (estimate - truth)")
    for name, run in result.runs.items():
        e = run.errors
        axes[0].plot(e.t, e.horizontal_m, label=name)
        axes[1].plot(e.t, e.pos_ned_m[:, 2], label=name)
        axes[2].plot(e.t, np.degrees(e.att_rpy_rad[:, 2]), label=name)
    labels = ("horizontal error, m", "down error, m", "yaw error, °")
    for ax, label in zip(axes, labels, strict=False):
        ax.set_ylabel(label)
    if aided:
        for name, aided_run in aided.items():
            assert aided_run.errors is not None
            axes[3].plot(aided_run.errors.t, aided_run.errors.horizontal_m, label=name)
        assert sc.aiding is not None
        for start, end in sc.aiding.outages:
            axes[3].axvspan(start, end, color="0.85", zorder=0)
        axes[3].set_ylabel("aided horizontal error, m")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left", fontsize="small")
    axes[-1].set_xlabel("time, s")
    return fig


def evaluate_figure(channels: Mapping[str, Mapping[str, float]], title: str) -> Figure:
    """``sins evaluate``: each channel's RMS reading error before and after the model (°/h, mg); two
    panels, the gyros and the accelerometers. ``channels`` maps a channel to ``rms_before`` and
    ``rms_after`` in SI units (:func:`sins.compensation.residual_rms`)."""
    fig, axes = _figure(2, title)
    for ax, sensor, size, unit in ((axes[0], "gyro", _DEG_PER_H, "°/h"), (axes[1], "accel", _MG, "mg")):
        names = [c for c in CHANNELS if c.startswith(sensor) and c in channels]
        x = np.arange(len(names))
        for offset, key, label in ((-0.2, "rms_before", "before"), (0.2, "rms_after", "after")):
            ax.bar(x + offset, [channels[c][key] / size for c in names], width=0.4, label=label)
        ax.set_xticks(x, names)
        ax.set_ylabel(f"RMS reading error, {unit}")
        ax.grid(True, axis="y", alpha=0.3)
        ax.legend(fontsize="small")
    return fig


def open_loop_figure(runs: Mapping[str, OpenLoop], title: str) -> Figure:
    """``sins evaluate`` against a trajectory: per correction, the open-loop attitude's total, heading and
    inclination errors against time, degrees (:func:`sins.referenced.open_loop`; blank where not judged)."""
    fig, axes = _figure(3, title)
    for name, run in runs.items():
        for ax, part in zip(axes, ("total", "heading", "inclination"), strict=True):
            ax.plot(run.t, np.degrees(np.where(run.judged, getattr(run, part), np.nan)), label=name)
    for ax, part in zip(axes, ("total", "heading", "inclination"), strict=True):
        ax.set_ylabel(f"{part} error, °")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left", fontsize="small")
    axes[-1].set_xlabel("time, s")
    return fig


def campaign_figure(rows: Mapping[str, Sequence[Any]], title: str) -> Figure:
    """``sins campaign``: per scenario, the spread over the units of each strategy's final horizontal
    error (box: quartiles; whiskers: 1.5 IQR), and of the aided one where the scenario has it.
    ``rows`` is the results table as columns (``results.parquet``'s ``to_pydict()``)."""
    scenarios = list(dict.fromkeys(rows["scenario"]))
    strategies = list(dict.fromkeys(rows["strategy"]))
    panels: list[tuple[str, str]] = []
    for sc in scenarios:
        panels.append((sc, "final_horizontal_m"))
        aided = rows.get("aided_final_horizontal_m")
        if aided is not None and any(
            v is not None and np.isfinite(v) for s, v in zip(rows["scenario"], aided, strict=True) if s == sc
        ):
            panels.append((sc, "aided_final_horizontal_m"))
    fig, axes = _figure(len(panels), title)
    for ax, (sc, column) in zip(axes, panels, strict=True):
        data = []
        for st in strategies:
            values = [v for s, g, v in zip(rows["scenario"], rows["strategy"], rows[column], strict=True)
                      if s == sc and g == st and v is not None]  # fmt: skip
            data.append(np.asarray(values, dtype=float))
        ax.boxplot(data, tick_labels=strategies)
        ax.set_ylabel(("aided " if column.startswith("aided") else "") + "final horizontal error, m")
        ax.set_title(sc, fontsize="medium")
        ax.grid(True, axis="y", alpha=0.3)
    return fig


def characterise_figure(result: Characterisation, closing: ClosingCheck) -> Figure:
    """``sins characterise``: each channel's Allan deviation (°/h, µg) against the cluster time, the
    real curve with its band, and the simulated unit's dashed; two panels, gyros and accelerometers."""
    fig, axes = _figure(2, f"{result.source}: Allan deviation, real (band) and simulated (dashed)")
    for ax, sensor, size, unit in (
        (axes[0], "gyro", _DEG_PER_H, "°/h"),
        (axes[1], "accel", 1e-6 * 9.80665, "µg"),
    ):
        for colour, (channel, r) in enumerate(
            (c, r) for c, r in result.channels.items() if r.sensor == sensor
        ):
            tau = r.curve.tau_s
            low, high = r.curve.interval()
            line = ax.loglog(tau, r.curve.adev / size, color=f"C{colour}", label=channel)[0]
            ax.fill_between(tau, low / size, high / size, color=line.get_color(), alpha=0.2)
            sim = np.asarray(closing.channels[channel]["sim_adev"], dtype=float)
            ax.loglog(
                np.asarray(closing.channels[channel]["tau_s"]), sim / size, "--", color=line.get_color()
            )
        ax.set_ylabel(f"Allan deviation, {unit}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize="small")
    axes[-1].set_xlabel("cluster time τ, s")
    return fig


__all__ = [
    "CHANNELS",
    "DPI",
    "PANEL_HEIGHT_IN",
    "SUFFIXES",
    "WIDTH_IN",
    "campaign_figure",
    "characterise_figure",
    "check_plot_path",
    "evaluate_figure",
    "open_loop_figure",
    "run_figure",
    "save",
]
