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
    from sins.characterise.analysis import ChannelResult, Characterisation
    from sins.characterise.bias import BiasEstimate
    from sins.characterise.check import ClosingCheck
    from sins.compensation.judging import OpenLoop
    from sins.core.series import NavSeries
    from sins.nav.metrics import NavErrors
    from sins.runs.results import AidedRun, ScenarioRun, StrategyRun

#: The file kinds :func:`save` writes, by suffix.
SUFFIXES = (".png", ".html")
#: Size of every image, inches, and its resolution: 1500 × 1000 pixels for two panels and more; a grid
#: of panels is :data:`COLUMN_WIDTH_IN` wide a column.
WIDTH_IN, PANEL_HEIGHT_IN, DPI = 10.0, 3.0, 150
COLUMN_WIDTH_IN = 5.0
#: Lines in one panel whose largest sizes differ more than this factor share a symmetric log scale.
SPREAD = 100.0
#: The channels' order and their display units (°/h for gyros, mg for accelerometers).
CHANNELS = ("gyro.x", "gyro.y", "gyro.z", "accel.x", "accel.y", "accel.z")
_DEG_PER_H = np.pi / 180.0 / 3600.0
_MG = 9.80665e-3
_UG = 9.80665e-6
#: The rows of a navigation error grid: quantity, :class:`~sins.nav.metrics.NavErrors` field, the three
#: components, the display scale and unit.
NAV_ROWS = (
    ("position", "pos_ned_m", ("north", "east", "down"), 1.0, "m"),
    ("velocity", "vel_ned_mps", ("north", "east", "down"), 1.0, "m/s"),
    ("attitude", "att_rpy_rad", ("roll", "pitch", "yaw"), float(np.degrees(1.0)), "°"),
)


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


def _panels(panels: int, title: str) -> tuple[Figure, list[Any]]:
    """A figure of ``panels`` panels stacked, each :data:`PANEL_HEIGHT_IN` high."""
    fig, axes = _grid(panels, 1, title)
    return fig, list(axes[:, 0])


def _grid(rows: int, cols: int, title: str) -> tuple[Figure, Any]:
    """A figure of ``rows`` × ``cols`` panels (an array of axes), :data:`WIDTH_IN` wide for one column
    and :data:`COLUMN_WIDTH_IN` a column for more."""
    width = WIDTH_IN if cols == 1 else COLUMN_WIDTH_IN * cols
    fig = Figure(figsize=(width, PANEL_HEIGHT_IN * rows + 0.6), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False)
    fig.suptitle(title)
    return fig, axes


def spread_scale(ax: Any, series: Sequence[Any]) -> None:
    """A symmetric log scale on ``ax`` where its lines' largest sizes span more than :data:`SPREAD` (a
    free vertical channel's kilometres beside a compensated unit's metres): linear up to the smallest
    line's largest size, logarithmic beyond, so each line keeps its sign and its shape."""
    peaks = [float(np.nanmax(np.abs(y))) for y in series if np.size(y) and np.isfinite(y).any()]
    peaks = [p for p in peaks if p > 0.0]
    if len(peaks) >= 2 and max(peaks) > SPREAD * min(peaks):
        ax.set_yscale("symlog", linthresh=min(peaks))


def _finish(axes: Any, legend_in: Sequence[Any] = ()) -> None:
    """Grid lines on every panel, a legend on those of ``legend_in``, the time axis named on the last
    row; panels left empty are hidden."""
    rows = np.atleast_2d(axes)
    for ax in rows.ravel():
        if not ax.lines and not ax.patches and not ax.collections:
            ax.set_axis_off()
            continue
        ax.grid(True, which="both", alpha=0.3)
    for ax in legend_in:
        ax.legend(loc="upper left", fontsize="small")
    for ax in rows[-1]:
        ax.set_xlabel("time, s")


def _error_rows(rows: Any, runs: Mapping[str, NavErrors]) -> None:
    """Position, velocity and attitude errors, one row each, their north, east, down (roll, pitch, yaw)
    components in the row's three panels, a line per run."""
    for row, (quantity, attr, parts, scale, unit) in zip(rows, NAV_ROWS, strict=True):
        for j, (ax, part) in enumerate(zip(row, parts, strict=True)):
            series = []
            for colour, (name, e) in enumerate(runs.items()):
                y = np.asarray(getattr(e, attr))[:, j] * scale
                ax.plot(e.t, y, color=f"C{colour}", label=name)
                series.append(y)
            ax.set_ylabel(f"{part} {quantity} error, {unit}")
            spread_scale(ax, series)


def errors_figure(runs: Mapping[str, NavErrors], title: str) -> Figure:
    """Navigation errors against time (estimate − truth): north, east and down position (m) and velocity
    (m/s), roll, pitch and yaw (°), a line per run; a panel whose lines span decades on a symmetric log
    scale (:func:`spread_scale`)."""
    fig, axes = _grid(3, 3, title)
    _error_rows(axes, runs)
    _finish(axes, [row[0] for row in axes])
    return fig


def run_figure(result: ScenarioRun) -> Figure:
    """``sins run``: per strategy, the north, east and down position and velocity errors and the roll,
    pitch and yaw errors against time (:func:`errors_figure`'s rows); with ``[gnss]``, two rows of the
    aided runs (north, east, down and yaw errors inside the filter's ±1σ and ±3σ envelopes, the horizontal
    error with the outages shaded, the estimated gyro biases beside the true ones); and a drift-budget
    panel per strategy with an IMU model (:func:`budget_panel`)."""
    sc = result.scenario
    aided = {n: r for n, r in result.aided.items() if r.errors is not None and r.sigma is not None}
    budget = (
        [(n, r) for n, r in result.runs.items() if r.sensor_error is not None]
        if result.sensor_t is not None
        else []
    )
    budget_rows = -(-len(budget) // 3)
    rows = 3 + (2 if aided else 0) + budget_rows
    fig, axes = _grid(rows, 3, f"scenario {sc.name}: errors (estimate - truth)")
    _error_rows(axes[:3], {name: run.errors for name, run in result.runs.items()})
    legends = [row[0] for row in axes[:3]]
    if aided:
        _aided_rows(axes[3:5], result, aided)
        legends += [axes[3][0], axes[4][1], axes[4][2]]
    for ax, (name, run) in zip(axes[rows - budget_rows :].ravel(), budget, strict=False):
        budget_panel(ax, name, run, float(result.truth.lat[0]), float(result.truth.h[0]))
        legends.append(ax)
    _finish(axes, legends)
    return fig


def _band(ax: Any, t: Any, sigma: Any, colour: str, name: str) -> None:
    """The ±1σ and ±3σ envelopes of ``sigma`` (already in the panel's unit) around 0."""
    ax.fill_between(t, -3.0 * sigma, 3.0 * sigma, color=colour, alpha=0.12, lw=0, label=f"{name} ±3σ")
    ax.fill_between(t, -sigma, sigma, color=colour, alpha=0.3, lw=0, label=f"{name} ±1σ")


def _aided_rows(rows: Any, result: ScenarioRun, aided: Mapping[str, AidedRun]) -> None:
    """The aided runs: their errors inside the filter's envelopes, the outages, the estimated biases."""
    top, bottom = rows
    for colour, (name, run) in enumerate(aided.items()):
        e, c = run.errors, f"C{colour}"
        assert e is not None and run.sigma is not None and run.t_cov is not None
        for j, part in enumerate(("north", "east", "down")):
            _band(top[j], run.t_cov, run.sigma[:, j], c, name)
            top[j].plot(e.t, e.pos_ned_m[:, j], color=c, label=name)
            top[j].set_ylabel(f"aided {part} error, m")
        _band(bottom[0], run.t_cov, np.degrees(run.sigma[:, 8]), c, name)
        bottom[0].plot(e.t, np.degrees(e.att_rpy_rad[:, 2]), color=c, label=name)
        bottom[1].plot(e.t, e.horizontal_m, color=c, label=name)
        if run.bias is not None:
            for i in range(3):
                bottom[2].plot(run.t_cov, run.bias[:, i] / _DEG_PER_H, color=f"C{i}",
                               label=f"{name} {CHANNELS[i]}" if colour == 0 else None)  # fmt: skip
                if run.true_bias is not None and colour == 0:
                    bottom[2].axhline(run.true_bias[i] / _DEG_PER_H, color=f"C{i}", ls="--", lw=0.8,
                                      label=f"true {CHANNELS[i]}")  # fmt: skip
    assert result.scenario.aiding is not None
    for start, end in result.scenario.aiding.outages:
        bottom[1].axvspan(
            start,
            end,
            color="0.85",
            zorder=0,
            label="outage" if start == result.scenario.aiding.outages[0][0] else None,
        )
    bottom[0].set_ylabel("aided yaw error, °")
    bottom[1].set_ylabel("aided horizontal error, m")
    bottom[2].set_ylabel("estimated gyro bias, °/h")


def budget_panel(ax: Any, name: str, run: StrategyRun, lat: float, h: float = 0.0) -> None:
    """A strategy's drift budget: its horizontal error against time on a log scale, beside the growth
    its own mean residual level biases would cause alone (:mod:`sins.nav.budget`: the gyro's
    ``ε R (t − sin ω_s t / ω_s)``, the accelerometer's ``b/ω_s² (1 − cos ω_s t)``, with the level part
    taken as the body's x and y: a first-order budget for a vehicle that stays near level; its turns
    rotate body-fixed biases, so the terms bound the drift rather than predict it)."""
    from sins.nav import budget

    e = run.errors
    t = e.t - e.t[0]
    ax.plot(e.t, e.horizontal_m, color="k", label="horizontal error")
    mean = np.zeros(6) if run.sensor_error is None else np.nanmean(run.sensor_error, axis=0)
    gyro, accel = float(np.hypot(mean[0], mean[1])), float(np.hypot(mean[3], mean[4]))
    if gyro > 0.0:
        ax.plot(e.t, budget.gyro_bias_growth(gyro, t, lat, h), "--", color="C3",
                label=f"gyro level bias {gyro / _DEG_PER_H:.3g} °/h")  # fmt: skip
    if accel > 0.0:
        ax.plot(e.t, budget.accel_bias_growth(accel, t, lat, h), ":", color="C2",
                label=f"accel level bias {accel / _UG:.3g} µg")  # fmt: skip
    _log_from(ax, e.horizontal_m)
    ax.set_title(f"{name}: drift budget", fontsize="medium")
    ax.set_ylabel("horizontal error, m")


def solution_figure(
    solution: NavSeries, title: str, expected: Sequence[tuple[str, Any, Any, str]] = ()
) -> Figure:
    """``sins integrate`` without a reference: the solution's north, east and down offsets from its first
    position (m), its velocity (m/s) and attitude (°) against time, and its horizontal and down offsets
    beside the growth ``expected`` (``(label, t, values, "horizontal" | "down")``: a still unit's bias
    terms, :mod:`sins.nav.budget`), the horizontal on a log scale."""
    from sins.core import earth, rotation

    fig, axes = _grid(4, 3, title)
    t = solution.t
    offset = earth.ned_offset(solution.lat, solution.lon, solution.h, solution.lat[0], solution.lon[0],
                              solution.h[0])  # fmt: skip
    attitude = np.degrees(np.column_stack(rotation.euler_from_quat(solution.q_nb)))
    for row, values, parts, what in (
        (axes[0], offset, ("north", "east", "down"), "offset from the start, m"),
        (axes[1], solution.v_n, ("north", "east", "down"), "velocity, m/s"),
        (axes[2], attitude, ("roll", "pitch", "yaw"), "angle, °"),
    ):
        for j, (ax, part) in enumerate(zip(row, parts, strict=True)):
            ax.plot(t, values[:, j], color="C0", label="solution")
            ax.set_ylabel(f"{part} {what}")
    horizontal = np.hypot(offset[:, 0], offset[:, 1])
    axes[3][0].plot(t, horizontal, color="k", label="solution")
    axes[3][1].plot(t, -offset[:, 2], color="k", label="solution")
    for k, (label, tx, values, panel) in enumerate(expected):
        ax = axes[3][0] if panel == "horizontal" else axes[3][1]
        ax.plot(tx, values, "--", color=f"C{k + 1}", label=label)
    _log_from(axes[3][0], horizontal)
    axes[3][0].set_ylabel("horizontal offset, m")
    axes[3][1].set_ylabel("height offset (up), m")
    _finish(axes, [axes[0][0], axes[3][0], axes[3][1]])
    return fig


def _log_from(ax: Any, values: Any, decades: float = 4.0) -> None:
    """A log scale on ``ax`` showing ``decades`` below the largest of ``values`` (an error that starts at
    zero would otherwise stretch the axis down to its first rounding)."""
    ax.set_yscale("log")
    top = float(np.nanmax(values)) if np.size(values) else 0.0
    if top > 0.0:
        ax.set_ylim(bottom=top * 10.0**-decades)


def evaluate_figure(channels: Mapping[str, Mapping[str, float]], title: str) -> Figure:
    """``sins evaluate``: each channel's RMS reading error before and after the model (°/h, mg) on a log
    scale, so that a correction to a tenth stays readable beside the raw error; two panels, the gyros and
    the accelerometers. ``channels`` maps a channel to ``rms_before`` and ``rms_after`` in SI units
    (:func:`sins.compensation.residual_rms`)."""
    fig, axes = _panels(2, title)
    for ax, sensor, size, unit in ((axes[0], "gyro", _DEG_PER_H, "°/h"), (axes[1], "accel", _MG, "mg")):
        names = [c for c in CHANNELS if c.startswith(sensor) and c in channels]
        x = np.arange(len(names))
        for offset, key, label in ((-0.2, "rms_before", "before"), (0.2, "rms_after", "after")):
            ax.bar(x + offset, [channels[c][key] / size for c in names], width=0.4, label=label)
        ax.set_xticks(x, names)
        ax.set_yscale("log")
        ax.set_ylabel(f"RMS reading error, {unit}")
        ax.grid(True, axis="y", which="both", alpha=0.3)
        ax.legend(fontsize="small")
    return fig


def open_loop_figure(runs: Mapping[str, OpenLoop], title: str) -> Figure:
    """``sins evaluate`` against a trajectory: per correction, in a panel of its own (so a correction to
    a degree stays readable below the raw readings' tens), the open-loop attitude's total, heading and
    inclination errors against time, degrees (:func:`sins.compensation.judging.open_loop`; blank where not
    judged)."""
    fig, axes = _panels(len(runs), title)
    for ax, (name, run) in zip(axes, runs.items(), strict=True):
        for part in ("total", "heading", "inclination"):
            ax.plot(run.t, np.degrees(np.where(run.judged, getattr(run, part), np.nan)), label=part)
        ax.set_title(name, fontsize="medium")
        ax.set_ylabel("attitude error, °")
    _finish(np.array(axes)[:, None], axes)
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
    fig, axes = _panels(len(panels), title)
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


#: Where each resolved noise term is marked on its line: the cluster time at which the Allan deviation
#: reads the term's value (N at 1 s, K at 3 s, Q at √3 s: IEEE Std 952's reading rules), or the flat
#: floor's own level (B, 0.664 B) at the curve's middle, the Gauss–Markov bump at its peak.
_MARK_TAU = {"quantization": np.sqrt(3.0), "white": 1.0, "rate_random_walk": 3.0}


def characterise_figure(result: Characterisation, closing: ClosingCheck) -> Figure:
    """``sins characterise``: each channel's Allan deviation (°/h, µg) against the cluster time, the
    real curve with its band, the simulated unit's dashed, and each resolved noise term's own line
    (dotted: Q, N, B, a Gauss–Markov bias, K, with their slopes −1, −½, 0, the bump, +½) marked with its
    value (:func:`allan_terms`); two panels, gyros and accelerometers."""
    fig, axes = _panels(
        2, f"{result.source}: Allan deviation, real (band), simulated (dashed), fitted terms (dotted)"
    )
    for ax, sensor in ((axes[0], "gyro"), (axes[1], "accel")):
        size, unit = (_DEG_PER_H, "°/h") if sensor == "gyro" else (_UG, "µg")
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
            allan_terms(ax, r, size, line.get_color())
        ax.set_ylabel(f"Allan deviation, {unit}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize="small")
    axes[-1].set_xlabel("cluster time τ, s")
    return fig


def allan_terms(ax: Any, r: ChannelResult, size: float, colour: str) -> None:
    """A channel's resolved noise terms on its Allan panel: each term's own Allan deviation over the
    curve's cluster times (dotted, labelled ``<channel> <symbol>``) and a marker with its value
    (``N 0.1 °/√h``) where the deviation reads it (:data:`_MARK_TAU`)."""
    from sins.characterise.analysis import DISPLAY, display
    from sins.characterise.noise_terms import NOISE_TERMS, SYMBOLS, basis

    tau = np.geomspace(r.curve.tau_s[0], r.curve.tau_s[-1], 64)
    columns = basis(tau, r.fit.tau_c_s)
    for k, name in enumerate(NOISE_TERMS):
        term = r.fit.terms[name]
        if not term.resolved or r.fit.coefficients[k] <= 0.0:
            continue
        adev = np.sqrt(columns[:, k] * r.fit.coefficients[k]) / size
        ax.loglog(tau, adev, ":", color=colour, lw=1.0, label=f"{r.channel} {SYMBOLS[name]}")
        if name in _MARK_TAU:
            at = float(np.clip(_MARK_TAU[name], tau[0], tau[-1]))
        elif name == "flicker":
            at = float(np.sqrt(tau[0] * tau[-1]))
        else:
            at = float(tau[int(np.argmax(adev))])
        y = float(np.interp(np.log(at), np.log(tau), adev))
        text = f"{SYMBOLS[name]} {display(r.sensor, name, term.value)} {DISPLAY[r.sensor][name][1]}"
        ax.plot([at], [y], "o", color=colour, ms=4)
        ax.annotate(
            text, (at, y), textcoords="offset points", xytext=(4, 4), fontsize="x-small", color=colour
        )


def bias_figure(estimate: BiasEstimate) -> Figure:
    """``sins bias``: per sensor, each axis's reading less Earth's rate and gravity over the rest (block
    means, °/h and µg), its bias (the mean: dashed) inside ±3σ (its standard error, the noise's colour
    counted) and its fitted trend (dotted)."""
    from sins.characterise.bias import DISPLAY

    fig, axes = _panels(2, f"{estimate.source}: biases at rest ({estimate.attitude.source} attitude)")
    t = estimate.block_t
    mid = 0.5 * (estimate.start_s + estimate.end_s)
    ends = np.array([estimate.start_s, estimate.end_s])
    for ax, sensor in zip(axes, ("gyro", "accel"), strict=True):
        size, unit = DISPLAY[sensor]
        for colour, axis in enumerate("xyz"):
            c = estimate.channels[f"{sensor}.{axis}"]
            i = CHANNELS.index(c.channel)
            ax.plot(t, estimate.block_bias[:, i] / size, color=f"C{colour}", lw=0.8, label=c.channel)
            ax.plot(ends, np.full(2, c.bias / size), "--", color=f"C{colour}",
                    label=f"bias {c.bias / size:+.4g} ± {c.sigma / size:.2g} {unit}")  # fmt: skip
            ax.fill_between(ends, (c.bias - 3 * c.sigma) / size, (c.bias + 3 * c.sigma) / size,
                            color=f"C{colour}", alpha=0.15, lw=0)  # fmt: skip
            ax.plot(ends, (c.bias + c.trend * (ends - mid)) / size, ":", color=f"C{colour}")
        taken = "Earth's rate" if sensor == "gyro" else "gravity"
        ax.set_ylabel(f"{sensor} reading − {taken}, {unit}")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="x-small", ncol=2)
    axes[-1].set_xlabel("time, s")
    return fig


__all__ = [
    "CHANNELS",
    "COLUMN_WIDTH_IN",
    "DPI",
    "NAV_ROWS",
    "PANEL_HEIGHT_IN",
    "SPREAD",
    "SUFFIXES",
    "WIDTH_IN",
    "allan_terms",
    "bias_figure",
    "budget_panel",
    "campaign_figure",
    "characterise_figure",
    "check_plot_path",
    "errors_figure",
    "evaluate_figure",
    "open_loop_figure",
    "run_figure",
    "save",
    "solution_figure",
    "spread_scale",
]
