"""The bridge to the Rerun viewer: the only module that imports ``rerun``.

What a run looks like in the viewer, against the ``sim_time`` timeline (seconds):

- ``world/<run>/path`` and ``world/<run>/vehicle``: the truth's and each strategy's trajectory as a 3D path
  in the start point's north-east-down frame (metres from the start point: a flat frame, so a path that
  drifted hundreds of km lies off by the Earth's curvature there, which the error panels do not), and the
  vehicle's pose along it (``C_nb`` as a rotation, drawn as body axes);
- ``errors/<quantity>/<strategy>``: horizontal and down position error (m), velocity error magnitude
  (m/s), roll, pitch and yaw error (°);
- ``imu/<channel>/<strategy>``: the error of the IMU stream each strategy integrated (reading − ideal;
  ``none`` is the raw error) in °/h and mg;
- ``scenario`` and ``summary``: the scenario's description and the run's table;
- with ``[gnss]`` (aided runs): ``aided/<axis>/<strategy>`` the aided north, east, down position and
  yaw errors, beside ``<strategy> ±3σ`` from the filter's covariance; ``aided/horizontal_m/<strategy>``
  with the ``fixes`` (points at 0) and the ``outages`` (a step over each window);
  ``aided/bias/<channel>/<strategy>`` the estimated bias beside the unit's ``true`` one, °/h and mg.

Display series are the :class:`~sins.runs.pipeline.ScenarioRun`'s thinned ones: navigation errors every
``round(rate / keep_hz)``-th sample plus the last (so the last logged error is the run's final error,
exactly), IMU errors as block means over as many intervals. Whole series go out in one ``send_columns``
call per entity.

:func:`log_run` logs one more run beside those already in a recording (a
campaign's Monte-Carlo members, say) under a path prefix of its own.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from numpy.typing import NDArray

from sins.characterise import Characterisation
from sins.characterise.check import ClosingCheck
from sins.compensation.judging import OpenLoop
from sins.core import earth
from sins.core.series import NavSeries
from sins.errors import SinsInputError
from sins.gap import GapReport
from sins.imu import CHANNELS, display_unit
from sins.io.atomic import atomic_path
from sins.io.paths import writes_in_place
from sins.runs.pipeline import AidedRun, ScenarioRun, StrategyRun

APPLICATION_ID = "sins"
TIMELINE = "sim_time"

#: Error panels: entity name, title, and how to get the series (estimate − truth) from a run.
ERROR_PANELS = ("horizontal_m", "down_m", "velocity_mps", "roll_deg", "pitch_deg", "yaw_deg")
_TITLES = {
    "horizontal_m": "horizontal position error, m",
    "down_m": "down position error, m",
    "velocity_mps": "velocity error magnitude, m/s",
    "roll_deg": "roll error, °",
    "pitch_deg": "pitch error, °",
    "yaw_deg": "yaw error, °",
}
RED, BLUE, GREEN = (228, 26, 28), (55, 126, 184), (77, 175, 74)  # the gap's before, after, model
_COLOURS = {
    "truth": (230, 230, 230),
    "none": (228, 26, 28),
    "oracle": (77, 175, 74),
    "regression": (55, 126, 184),
    "regression_robust": (31, 120, 180),
    "regression_extended": (0, 90, 160),
    "mlp": (255, 127, 0),
    "mlp_pure": (230, 150, 60),
    "mlp_seed": (200, 100, 0),
    "kohonen": (152, 78, 163),
    "kohonen_pure": (190, 140, 200),
}
_OTHER_COLOURS = ((166, 86, 40), (247, 129, 191), (153, 153, 153), (255, 255, 51))


def colour(name: str) -> tuple[int, int, int]:
    """A fixed colour per strategy, so every panel and every recording agree."""
    if name in _COLOURS:
        return _COLOURS[name]
    return _OTHER_COLOURS[sum(name.encode()) % len(_OTHER_COLOURS)]


def imu_entity(channel: str) -> str:
    """``gyro.x`` → ``gyro_x_deg_per_h``; ``accel.x`` → ``accel_x_mg``."""
    sensor, axis = channel.split(".")
    return f"{sensor}_{axis}_{'deg_per_h' if sensor == 'gyro' else 'mg'}"


def error_series(run: StrategyRun) -> dict[str, NDArray[np.float64]]:
    """The logged error series of a run, by :data:`ERROR_PANELS` name."""
    e = run.errors
    att_deg = np.degrees(e.att_rpy_rad)
    return {
        "horizontal_m": e.horizontal_m,
        "down_m": e.pos_ned_m[:, 2],
        "velocity_mps": np.linalg.norm(e.vel_ned_mps, axis=1),
        "roll_deg": att_deg[:, 0],
        "pitch_deg": att_deg[:, 1],
        "yaw_deg": att_deg[:, 2],
    }


def _time(t: NDArray[np.float64]) -> list[rr.TimeColumn]:
    return [rr.TimeColumn(TIMELINE, duration=np.asarray(t, dtype=np.float64))]


def _join(*parts: str) -> str:
    return "/".join(p.strip("/") for p in parts if p.strip("/"))


def log_path(
    rec: rr.RecordingStream,
    name: str,
    series: NavSeries,
    origin: tuple[float, float, float],
    *,
    prefix: str = "",
    axis_length_m: float = 1.0,
) -> None:
    """A trajectory as a 3D path in the start point's NED frame, and the vehicle's pose along it."""
    ned = earth.local_ned(series.lat, series.lon, series.h, *origin)
    base = _join(prefix, "world", name)
    rgb = colour(name)
    rec.log(f"{base}/path", rr.LineStrips3D([ned], colors=[rgb], radii=[-1.5]), static=True)
    rec.log(f"{base}/vehicle", rr.TransformAxes3D(axis_length=axis_length_m), static=True)
    rec.send_columns(
        f"{base}/vehicle",
        indexes=_time(series.t),
        columns=rr.Transform3D.columns(translation=ned, quaternion=series.q_nb),  # both scalar-last
    )


def log_run(
    rec: rr.RecordingStream,
    name: str,
    run: StrategyRun,
    origin: tuple[float, float, float],
    *,
    sensor_t: NDArray[np.float64] | None = None,
    prefix: str = "",
    axis_length_m: float = 1.0,
) -> None:
    """One strategy's run: its path, its error series and (with ``sensor_t``) its IMU error signals."""
    log_path(rec, name, run.solution, origin, prefix=prefix, axis_length_m=axis_length_m)
    rgb = colour(name)
    for panel, values in error_series(run).items():
        _line(rec, _join(prefix, "errors", panel, name), name, rgb, run.errors.t, values)
    if run.sensor_error is not None and sensor_t is not None:
        label = "raw" if name == "none" else name
        for i, channel in enumerate(CHANNELS):
            entity = _join(prefix, "imu", imu_entity(channel), label)
            _line(rec, entity, label, rgb, sensor_t, run.sensor_error[:, i] / display_unit(channel)[0])


#: Aided panels: entity name, title, the error series' column and the filter state's index (for ±3σ).
AIDED_PANELS = (
    ("north_m", "aided north error ±3σ, m", 0, 0),
    ("east_m", "aided east error ±3σ, m", 1, 1),
    ("down_m", "aided down error ±3σ, m", 2, 2),
    ("yaw_deg", "aided yaw error ±3σ, °", 5, 8),
)
GREY = (150, 150, 150)


def _line(
    rec: rr.RecordingStream, entity: str, label: str, rgb: tuple[int, int, int], t: Any, y: Any
) -> None:
    rec.log(entity, rr.SeriesLines(names=[label], colors=[rgb]), static=True)
    rec.send_columns(entity, indexes=_time(t), columns=rr.Scalars.columns(scalars=np.asarray(y, dtype=float)))


def log_aided(
    rec: rr.RecordingStream, name: str, run: AidedRun, *, prefix: str = "", outages: Any = ()
) -> None:
    """One strategy's aided run: its errors with the filter's ±3σ, the fixes and outages, its biases."""
    if run.errors is None or run.t_cov is None or run.sigma is None or run.bias is None:
        return
    rgb = colour(name)
    e = run.errors
    columns = np.hstack([e.pos_ned_m, np.degrees(e.att_rpy_rad)])
    for panel, _, column, state in AIDED_PANELS:
        scale = np.degrees(1.0) if panel.endswith("deg") else 1.0
        _line(rec, _join(prefix, "aided", panel, name), name, rgb, e.t, columns[:, column])
        for sign, label in ((1.0, "+3σ"), (-1.0, "-3σ")):
            entity = _join(prefix, "aided", panel, f"{name}_{'plus' if sign > 0 else 'minus'}_3sigma")
            _line(rec, entity, f"{name} {label}", GREY, run.t_cov, sign * 3.0 * scale * run.sigma[:, state])
    _line(rec, _join(prefix, "aided", "horizontal_m", name), name, rgb, e.t, e.horizontal_m)
    if run.fix_t is not None and len(run.fix_t):
        entity = _join(prefix, "aided", "horizontal_m", "fixes")
        rec.log(entity, rr.SeriesPoints(names=["fixes"], colors=[GREY], marker_sizes=[1.0]), static=True)
        rec.send_columns(
            entity, indexes=_time(run.fix_t), columns=rr.Scalars.columns(scalars=np.zeros(len(run.fix_t)))
        )
    if len(outages):
        top = float(np.max(e.horizontal_m)) if len(e.t) else 1.0
        t = [x for start, end in outages for x in (start, start, end, end)]
        y = [v for _ in outages for v in (0.0, top, top, 0.0)]
        _line(rec, _join(prefix, "aided", "horizontal_m", "outages"), "outages", GREY, t, y)
    for i, channel in enumerate(CHANNELS):
        unit = display_unit(channel)[0]
        base = _join(prefix, "aided", "bias", imu_entity(channel))
        _line(rec, _join(base, name), name, rgb, run.t_cov, run.bias[:, i] / unit)
        if run.true_bias is not None:
            ends = run.t_cov[[0, -1]]
            _line(rec, _join(base, "true"), "true", GREEN, ends, np.full(2, run.true_bias[i] / unit))


def log_scenario_run(
    rec: rr.RecordingStream, result: ScenarioRun, *, summary: str = "", prefix: str = ""
) -> None:
    """Everything of a scenario run: truth, every strategy, the description and the ``summary`` table."""
    truth = result.truth
    origin = (float(truth.lat[0]), float(truth.lon[0]), float(truth.h[0]))
    extent = np.ptp(earth.local_ned(truth.lat, truth.lon, truth.h, *origin), axis=0).max()
    axis_length_m = max(1.0, 0.03 * float(extent))
    rec.log(_join(prefix, "world") or "/", rr.ViewCoordinates.RIGHT_HAND_Z_DOWN, static=True)  # NED
    log_path(rec, "truth", truth, origin, prefix=prefix, axis_length_m=axis_length_m)
    for name, run in result.runs.items():
        log_run(rec, name, run, origin, sensor_t=result.sensor_t, prefix=prefix, axis_length_m=axis_length_m)
    windows = result.scenario.aiding.outages if result.scenario.aiding is not None else ()
    for name, aided in result.aided.items():
        log_aided(rec, name, aided, prefix=prefix, outages=windows)
    sc = result.scenario
    description = (
        f"# {sc.name}\n\n{sc.description or ''}\n\n"
        f"- {result.samples} samples at {sc.rate_hz:g} Hz ({result.samples / sc.rate_hz:g} s)\n"
        f"- IMU: {sc.imu_model.stem if sc.imu_model else 'ideal'}\n"
        f"- vertical channel: {sc.vertical}\n"
        f"- start: {np.degrees(origin[0]):.6f}° N, {np.degrees(origin[1]):.6f}° E, {origin[2]:.1f} m\n"
        f"- paths in metres from the start, north-east-down; errors are estimate − truth\n"
    )
    rec.log(_join(prefix, "scenario"), rr.TextDocument(description, media_type="text/markdown"), static=True)
    if summary:
        text = f"```\n{summary}\n```"
        rec.log(_join(prefix, "summary"), rr.TextDocument(text, media_type="text/markdown"), static=True)


def _whole_run() -> rrb.TimeAxis:
    """A plot's time axis showing the whole run, not the viewer's minute around the cursor."""
    whole = rrb.TimeRangeBoundary.infinite()
    return rrb.TimeAxis(view_range=rrb.TimeRange(start=whole, end=whole))


def blueprint(
    strategies: Sequence[str], *, with_imu: bool = True, prefix: str = "", with_aided: bool = False
) -> rrb.Blueprint:
    """The 3D paths beside the error panels; IMU errors and the summary in tabs below the errors.

    Every plot shows the whole run, not a window around the time cursor: drift is about the long run.
    """
    axis = _whole_run()
    errors = [
        rrb.TimeSeriesView(origin=_join(prefix, "errors", panel), name=_TITLES[panel], axis_x=axis)
        for panel in ERROR_PANELS
    ]
    tabs: list[rrb.View] = list(errors[2:])
    if with_imu:
        tabs += [
            rrb.TimeSeriesView(
                origin=_join(prefix, "imu", imu_entity(ch)),
                name=f"{ch} error, {display_unit(ch)[1]}",
                axis_x=axis,
            )
            for ch in CHANNELS
        ]
    if with_aided:
        tabs += [
            rrb.TimeSeriesView(origin=_join(prefix, "aided", panel), name=title, axis_x=axis)
            for panel, title, _, _ in AIDED_PANELS
        ]
        tabs.append(rrb.TimeSeriesView(
            origin=_join(prefix, "aided", "horizontal_m"), name="aided horizontal error, fixes, outages, m",
            axis_x=axis,
        ))  # fmt: skip
        tabs += [
            rrb.TimeSeriesView(
                origin=_join(prefix, "aided", "bias", imu_entity(ch)),
                name=f"{ch} bias estimated and true, {display_unit(ch)[1]}",
                axis_x=axis,
            )
            for ch in CHANNELS
        ]
    tabs += [
        rrb.TextDocumentView(origin=_join(prefix, "summary"), name="summary"),
        rrb.TextDocumentView(origin=_join(prefix, "scenario"), name="scenario"),
    ]
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(origin=_join(prefix, "world") or "/", name="paths: m from start, NED"),
            rrb.Vertical(errors[0], errors[1], rrb.Tabs(*tabs), row_shares=[2, 2, 3]),
            column_shares=[3, 2],
        ),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed"),
    )


def _recording(result: ScenarioRun) -> tuple[rr.RecordingStream, rrb.Blueprint]:
    rec = rr.RecordingStream(APPLICATION_ID)  # rerun's random id: files opened together stay apart
    return rec, blueprint(
        list(result.runs), with_imu=result.sensor_t is not None, with_aided=bool(result.aided)
    )


def check_rrd_path(path: str | os.PathLike[str], flag: str = "") -> Path:
    """``path`` as a Path if it names a ``.rrd`` (or ``/dev/null``, written in place), else one line that
    ``flag`` (``--rerun``) begins; its place is ``check_outputs``'s."""
    if not Path(path).name.endswith(".rrd") and not writes_in_place(Path(path)):
        raise SinsInputError(f"{f'{flag} ' if flag else ''}{path}: a Rerun recording's name must end in .rrd")
    return Path(path)


def _write(
    path: str | os.PathLike[str], rec: rr.RecordingStream, bp: rrb.Blueprint, log: Callable[[], None],
    name: str,
) -> Path:  # fmt: skip
    """Log into memory (a few MB: a one-hour drive's 8), then write through a temporary name by Python:
    a full disk is one line (rerun's file sink had hung in its flush past SIGINT, or raised a traceback).
    ``name``: the recording's in the viewer's list (each has rerun's random id: files opened together had
    been pooled into one recording where they shared one)."""
    path = check_rrd_path(path)
    stream = rec.binary_stream()
    rec.send_blueprint(bp, make_active=False, make_default=True)
    rec.send_recording_name(name)  # once the blueprint is sent, as spawn and serve send it
    log()
    data = stream.read(flush=True) or b""
    rec.disconnect()
    with atomic_path(path) as tmp:
        Path(tmp).write_bytes(data)
    return path


def save(result: ScenarioRun, path: str | os.PathLike[str], *, summary: str = "") -> Path:
    """Write the run to a ``.rrd`` file."""
    rec, bp = _recording(result)
    log = lambda: log_scenario_run(rec, result, summary=summary)  # noqa: E731
    return _write(path, rec, bp, log, result.scenario.name)


NO_DISPLAY = "no display to open the native viewer on (DISPLAY and WAYLAND_DISPLAY are unset)"


def has_display() -> bool:
    """Whether a native window can open here (always on macOS and Windows; X11 or Wayland elsewhere)."""
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


#: The environment the viewer sins spawns gets: rerun's viewer collects no usage data, and prints no
#: first-run banner announcing it, where ``CI`` is set (``re_analytics``'s native pipeline; checked with
#: rerun 0.41). ``rerun analytics disable`` turns it off for every viewer (docs/guide/rerun.md).
VIEWER_ENV = {"CI": "1"}


def spawn(result: ScenarioRun, *, summary: str = "") -> None:
    """Open the native viewer on the run (it stays open after this process ends), without rerun's
    analytics (:data:`VIEWER_ENV`)."""
    if not has_display():
        raise SinsInputError(NO_DISPLAY)
    viewer = Path(sys.executable).with_name("rerun")  # the venv's viewer, whatever PATH says
    rec, bp = _recording(result)
    saved = {k: os.environ.get(k) for k in VIEWER_ENV}
    os.environ.update({k: saved[k] or v for k, v in VIEWER_ENV.items()})  # the child inherits it
    try:
        rr.spawn(executable_path=str(viewer) if viewer.exists() else None, recording=rec,
                 default_blueprint=bp)  # fmt: skip
        rec.send_recording_name(result.scenario.name)  # after the blueprint (_write)
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    log_scenario_run(rec, result, summary=summary)
    rec.flush()


_SERVED: list[rr.RecordingStream] = []  # the streams serve() serves, held while the process lives


def serve(result: ScenarioRun, *, summary: str = "", web_port: int = 9090, grpc_port: int = 9876) -> str:
    """Serve the run to the web viewer; returns the address to open. The data are served for as long as
    the process lives."""
    rec, bp = _recording(result)
    try:
        grpc_url = rec.serve_grpc(grpc_port=grpc_port, default_blueprint=bp)
        rr.serve_web_viewer(web_port=web_port, open_browser=False, connect_to=grpc_url)
    except Exception as exc:  # rerun raises its own error types for a port in use
        raise SinsInputError(f"cannot serve the web viewer on ports {web_port}/{grpc_port}: {exc}") from None
    rec.send_recording_name(result.scenario.name)  # after the blueprint (_write)
    log_scenario_run(rec, result, summary=summary)
    rec.flush()
    _SERVED.append(rec)  # its gRPC server lives as long as the stream: a local had closed it on return
    from urllib.parse import quote

    return f"http://localhost:{web_port}/?url={quote(grpc_url, safe='')}"


def log_gap(rec: rr.RecordingStream, report: GapReport, *, prefix: str = "") -> None:
    """A gap diagnosis: per channel, the withheld residual before and after the accepted effects (°/h,
    mg), their noise floor, and the report as text."""
    t = report.t_withheld
    for i, channel in enumerate(CHANNELS):
        unit = display_unit(channel)[0]
        floor = report.channels[channel]["noise_floor"] / unit
        for label, residual, rgb in (
            ("before", report.residual_before, RED),
            ("after", report.residual_after, BLUE),
        ):
            entity = _join(prefix, "gap", imu_entity(channel), label)
            rec.log(entity, rr.SeriesPoints(names=[label], colors=[rgb], marker_sizes=[1.0]), static=True)
            rec.send_columns(
                entity, indexes=_time(t), columns=rr.Scalars.columns(scalars=residual[:, i] / unit)
            )
        for label, value in (("floor_plus", floor), ("floor_minus", -floor)):
            _line(rec, _join(prefix, "gap", imu_entity(channel), label), "noise floor", GREEN, t[[0, -1]],
                  np.full(2, value))  # fmt: skip
    _log_gap_localisation(rec, report, prefix)
    lines = ["| channel | before/floor | after/floor |", "|---|---|---|"]
    for channel, v in report.channels.items():
        before, after = v["rms_before"] / v["noise_floor"], v["rms_after"] / v["noise_floor"]
        lines.append(f"| {channel} | {before:.3f} | {after:.3f} |")
    lines += ["", f"diagnosis: {', '.join(report.diagnosis) or 'nothing to add'}"]
    lines += [f"unexplained: {', '.join(report.unexplained) or 'none'}"]
    lines += [f"- {o.channel}: {o.what()} (no library effect)" for o in report.outside]
    lines += ["", "where:"]
    lines += [f"- {w['channel']}: {w['excess']:.3f}× — {'; '.join(w['concentrates'])}" for w in report.where]
    rec.log(
        _join(prefix, "gap", "report"),
        rr.TextDocument("\n".join(lines), media_type="text/markdown"),
        static=True,
    )


#: The Allan-deviation plots' x axis: octaves of the cluster time, ``τ = step · 2^k``.
ALLAN_TIMELINE = "allan_octave"


def _log_gap_localisation(rec: rr.RecordingStream, report: GapReport, prefix: str) -> None:
    """Where each channel's gap lies: its residual's Allan deviation before and after the accepted
    effects against the model's white noise (log10 of °/h or mg, by octave of the cluster time),
    and the share of the withheld excess in each quartile of every input (bar charts)."""
    for channel in CHANNELS:
        unit = display_unit(channel)[0]
        allan = report.allan.get(channel)
        if allan:
            octave = rr.TimeColumn(ALLAN_TIMELINE, sequence=np.arange(len(allan["tau_s"])))
            for label, rgb in (("before", RED), ("after", BLUE), ("model", GREEN)):
                entity = _join(prefix, "gap", "allan", imu_entity(channel), label)
                rec.log(entity, rr.SeriesLines(names=[label], colors=[rgb]), static=True)
                values = np.log10(np.maximum(np.asarray(allan[label]) / unit, 1e-300))
                rec.send_columns(entity, indexes=[octave], columns=rr.Scalars.columns(scalars=values))
        for feature, shares in report.quartiles.get(channel, {}).items():
            entity = _join(prefix, "gap", "quartiles", imu_entity(channel), _slug(feature))
            rec.log(entity, rr.BarChart(np.asarray(shares, dtype=np.float64)), static=True)


def _slug(name: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in name.replace("|ω|", "omega").replace("|f|", "f")).strip(
        "_"
    )


def save_gap(reports: GapReport | dict[str, GapReport], path: str | os.PathLike[str]) -> Path:
    """Write a gap diagnosis to a ``.rrd`` file (through a temporary name). Several recordings' diagnoses
    (``{name: report}``, as ``sins gap --dataset A --dataset B``) go side by side, a tab each, every entity
    under the recording's name (``<name>/gap/...``); one report, or a dict of one, under ``gap/...``."""
    named = reports if isinstance(reports, dict) else {"": reports}
    assert named, "save_gap: no report to write"
    prefixes = {name: "" for name in named}
    if len(named) > 1:  # names that make one path (``a/b`` and ``a_b``) are told apart by their place
        for place, name in enumerate(named, 1):
            slug = _slug(name) or "recording"
            prefixes[name] = slug if slug not in prefixes.values() else f"{slug}_{place}"
    rec = rr.RecordingStream(APPLICATION_ID)
    panels = [_gap_panel(report, prefixes[name], name) for name, report in named.items()]
    bp = rrb.Blueprint(panels[0] if len(panels) == 1 else rrb.Tabs(*panels))

    def log() -> None:
        for name, report in named.items():
            log_gap(rec, report, prefix=prefixes[name])

    return _write(path, rec, bp, log, "gap")


def _gap_panel(report: GapReport, prefix: str, name: str) -> Any:
    """One diagnosis's views: its residuals, Allan deviations and quartiles as tabs, beside its report."""
    root = _join(prefix, "gap")
    views = [
        rrb.TimeSeriesView(origin=_join(root, imu_entity(ch)), name=f"{ch} residual", axis_x=_whole_run())
        for ch in CHANNELS
    ]
    allan = [
        rrb.TimeSeriesView(
            origin=_join(root, "allan", imu_entity(ch)),
            name=f"{ch} Allan deviation (log10; τ = {report.allan[ch]['tau_s'][0]:.3g} s · 2^k)",
        )
        for ch in CHANNELS
        if ch in report.allan
    ]
    quartiles = [
        rrb.BarChartView(
            origin=_join(root, "quartiles", imu_entity(ch), _slug(feature)), name=f"{ch}: {feature}"
        )
        for ch in CHANNELS
        for feature in report.quartiles.get(ch, {})
    ]
    tabs = [rrb.Grid(*views, name="withheld residuals")]
    tabs += [rrb.Grid(*allan, name="Allan deviation")] if allan else []
    tabs += [rrb.Grid(*quartiles, name="excess by input quartile")] if quartiles else []
    return rrb.Horizontal(
        rrb.Tabs(*tabs),
        rrb.TextDocumentView(origin=_join(root, "report"), name="report"),
        column_shares=[3, 1],
        name=name or None,
    )


def save_open_loop(runs: dict[str, OpenLoop], path: str | os.PathLike[str], *, summary: str = "") -> Path:
    """Open-loop attitude errors (:func:`sins.compensation.judging.open_loop`) of several corrections in
    a ``.rrd``
    file: per correction, its total, heading and inclination error over time, degrees (NaN outside the
    judged rows, so that the rests the benchmark does not count show as gaps)."""
    rec = rr.RecordingStream(APPLICATION_ID)
    axis = _whole_run()
    parts = ("total", "heading", "inclination")
    views = [
        rrb.TimeSeriesView(origin=f"open_loop/{part}", name=f"{part} error, °", axis_x=axis) for part in parts
    ]
    bp = rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(*views),
            rrb.TextDocumentView(origin="open_loop/report", name="report"),
            column_shares=[3, 1],
        )
    )

    def log() -> None:
        rec.log("open_loop/report", rr.TextDocument(summary), static=True)
        for label, run in runs.items():
            for part in parts:
                values = np.degrees(np.where(run.judged, getattr(run, part), np.nan))
                entity = _join("open_loop", part, _slug(label))
                rec.log(entity, rr.SeriesLines(colors=[colour(label)], names=[label]), static=True)
                rec.send_columns(entity, indexes=_time(run.t), columns=rr.Scalars.columns(scalars=values))

    return _write(path, rec, bp, log, "open_loop")


#: The percentiles of a campaign's horizontal error drawn over time, per strategy (a band and its median).
CAMPAIGN_PERCENTILES = (5, 25, 50, 75, 95)


def save_campaign(rows: dict[str, list[Any]], path: str | os.PathLike[str]) -> Path:
    """A campaign's spread in a ``.rrd`` file: per scenario, the percentiles of the horizontal error over
    time for each strategy (:data:`CAMPAIGN_PERCENTILES`), and each unit's final error as a point on a
    ``unit`` timeline.

    ``rows`` is the results table as columns (``pyarrow.Table.to_pydict()`` of ``results.parquet``); the
    series need the campaign's ``series_hz`` > 0.
    """
    rec = rr.RecordingStream(APPLICATION_ID)
    scenarios = list(dict.fromkeys(rows["scenario"]))
    strategies = list(dict.fromkeys(rows["strategy"]))
    views = []
    for sc in scenarios:
        views.append(
            rrb.TimeSeriesView(origin=f"campaign/{sc}/horizontal_m", name=f"{sc}: horizontal error (m)")
        )
        views.append(
            rrb.TimeSeriesView(origin=f"campaign/{sc}/final_m", name=f"{sc}: final error per unit (m)")
        )
    bp = rrb.Blueprint(rrb.Grid(*views), collapse_panels=True)

    def log() -> None:
        for sc in scenarios:
            for st in strategies:
                idx = [i for i, (s, g) in enumerate(zip(rows["scenario"], rows["strategy"], strict=True))
                       if (s, g) == (sc, st)]  # fmt: skip
                _log_campaign_group(rec, sc, st, rows, idx)

    return _write(path, rec, bp, log, "campaign")


def _log_campaign_group(
    rec: rr.RecordingStream, scenario: str, strategy: str, rows: dict[str, list[Any]], idx: list[int]
) -> None:
    rgb = colour(strategy)
    units = np.array([rows["unit"][i] for i in idx], dtype=np.int64)
    final = np.array([rows["final_horizontal_m"][i] for i in idx], dtype=np.float64)
    entity = f"campaign/{scenario}/final_m/{strategy}"
    rec.log(entity, rr.SeriesPoints(names=[strategy], colors=[rgb], marker_sizes=[3.0]), static=True)
    rec.send_columns(
        entity, indexes=[rr.TimeColumn("unit", sequence=units)], columns=rr.Scalars.columns(scalars=final)
    )
    if "series_horizontal_m" not in rows or not idx:
        return
    series = [np.asarray(rows["series_horizontal_m"][i], dtype=np.float64) for i in idx]
    n = min(len(s) for s in series)  # every unit of a scenario keeps the same times
    t = np.asarray(rows["series_t_s"][idx[0]][:n], dtype=np.float64)
    bands = np.percentile(np.vstack([s[:n] for s in series]), CAMPAIGN_PERCENTILES, axis=0)
    for q, band in zip(CAMPAIGN_PERCENTILES, bands, strict=True):
        entity = f"campaign/{scenario}/horizontal_m/{strategy}/p{q}"
        width = 2.0 if q == 50 else 0.75
        rec.log(entity, rr.SeriesLines(names=[f"{strategy} p{q}"], colors=[rgb], widths=[width]), static=True)
        rec.send_columns(entity, indexes=_time(t), columns=rr.Scalars.columns(scalars=band))


def log_characterisation(rec: rr.RecordingStream, result: Characterisation, closing: ClosingCheck) -> None:
    """A characterisation and its closing check: per channel, the real Allan deviation with its
    confidence band, the fitted model's and the simulated unit's (log10 of °/h or µg, by octave of the
    cluster time), and the partings as text."""
    from sins.characterise.analysis import ADEV_DISPLAY

    for channel, r in result.channels.items():
        size = ADEV_DISPLAY[r.sensor][0]
        low, high = r.curve.interval()
        curves = closing.channels[channel]
        octave = rr.TimeColumn(ALLAN_TIMELINE, sequence=np.arange(len(r.curve.tau_s)))
        for label, values, rgb in (
            ("real", r.curve.adev, RED),
            ("band_low", low, (240, 160, 160)),
            ("band_high", high, (240, 160, 160)),
            ("model", np.asarray(curves["model_adev"]), GREEN),
            ("simulated", np.asarray(curves["sim_adev"]), BLUE),
        ):
            entity = _join("characterise", imu_entity(channel), label)
            rec.log(entity, rr.SeriesLines(names=[label], colors=[rgb]), static=True)
            scalars = np.log10(np.maximum(np.asarray(values, dtype=np.float64) / size, 1e-300))
            rec.send_columns(entity, indexes=[octave], columns=rr.Scalars.columns(scalars=scalars))
    lines = [f"{result.source}: {result.rows} rows at {1.0 / result.dt:.6g} Hz", "", "partings:"]
    lines += [f"- {p.what()}" for p in closing.partings] or ["- none: within the bands everywhere"]
    rec.log("characterise/report", rr.TextDocument("\n".join(lines), media_type="text/markdown"), static=True)


def save_characterisation(
    result: Characterisation, closing: ClosingCheck, path: str | os.PathLike[str]
) -> Path:
    """Write a characterisation's Allan curves to a ``.rrd`` file (through a temporary name)."""
    rec = rr.RecordingStream(APPLICATION_ID)
    views = [
        rrb.TimeSeriesView(
            origin=f"characterise/{imu_entity(ch)}",
            name=f"{ch} Allan deviation (log10; τ = {result.dt:.3g} s · 2^k)",
        )
        for ch in result.channels
    ]
    bp = rrb.Blueprint(
        rrb.Horizontal(
            rrb.Grid(*views, name="Allan deviation: real, band, model, simulated"),
            rrb.TextDocumentView(origin="characterise/report", name="report"),
            column_shares=[3, 1],
        )
    )
    return _write(path, rec, bp, lambda: log_characterisation(rec, result, closing), "characterise")


__all__ = [
    "AIDED_PANELS",
    "ALLAN_TIMELINE",
    "APPLICATION_ID",
    "BLUE",
    "CAMPAIGN_PERCENTILES",
    "ERROR_PANELS",
    "GREEN",
    "GREY",
    "NO_DISPLAY",
    "RED",
    "TIMELINE",
    "VIEWER_ENV",
    "blueprint",
    "check_rrd_path",
    "colour",
    "error_series",
    "has_display",
    "imu_entity",
    "log_aided",
    "log_characterisation",
    "log_gap",
    "log_path",
    "log_run",
    "log_scenario_run",
    "save",
    "save_campaign",
    "save_characterisation",
    "save_gap",
    "save_open_loop",
    "serve",
    "spawn",
]
