"""What every command shares: tables, the viewer and pictures, the checks before the work."""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.cli.progress import progress_bar
from sins.core.text import fixed_width
from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.io.recording import Recording
    from sins.runs.pipeline import ScenarioRun
    from sins.scenario import Scenario

#: The object ``add_subparsers`` returns, to which each subcommand adds its parser.
Subparsers = argparse._SubParsersAction

_COLUMNS = (
    ("final N m", "final_north_m", "{:.3f}"),
    ("final E m", "final_east_m", "{:.3f}"),
    ("final D m", "final_down_m", "{:.3f}"),
    ("final hor m", "final_horizontal_m", "{:.3f}"),
    ("max hor m", "max_horizontal_m", "{:.3f}"),
    ("roll °", "final_roll_deg", "{:.4f}"),
    ("pitch °", "final_pitch_deg", "{:.4f}"),
    ("yaw °", "final_yaw_deg", "{:.4f}"),
    ("m/h", "drift_rate_m_per_h", "{:.3f}"),
    ("nmi/h", "drift_rate_nmi_per_h", "{:.4f}"),
)


#: Per-hour drift rates (the final horizontal error over the duration) are withheld for runs shorter than
#: this, s: a drift that grows as t² or t³ scaled from minutes to an hour says nothing (a 60 s bag's
#: 1.2 km reads 73,700 m/h) ...
MIN_RATE_S = 600.0
#: ... and marked as extrapolated for runs shorter than an hour.
HOUR_S = 3600.0
_RATE_KEYS = ("drift_rate_m_per_h", "drift_rate_nmi_per_h")


def format_table(summaries: dict[str, dict[str, Any]]) -> str:
    """A fixed-width table: one row per strategy, the headline errors as columns. The per-hour rates of a
    run under :data:`MIN_RATE_S` read "-", of one under an hour end in "*" (an extrapolation), each with
    a line below saying so."""
    head = ["strategy"] + [c[0] for c in _COLUMNS]
    rows, notes = [], set()
    for name, s in summaries.items():
        duration = float(s.get("duration_s", HOUR_S))
        cells = [name]
        for _, key, fmt in _COLUMNS:
            cell = fmt.format(s[key])
            if key in _RATE_KEYS and duration < MIN_RATE_S:
                cell = "-"
                notes.add(f"m/h, nmi/h: withheld for a run under {MIN_RATE_S / 60:g} min ({duration:.4g} s)")
            elif key in _RATE_KEYS and duration < HOUR_S:
                cell += "*"
                notes.add(
                    f"* the {duration:.4g} s run's final horizontal error scaled to an hour: an extrapolation"
                )
            cells.append(cell)
        rows.append(cells)
    return "\n".join([fixed_width(head, rows), *sorted(notes)])


def check_finite(values: dict[str, Any], where: str) -> None:
    """Refuse a result with a non-finite number rather than print it: the inputs took the computation
    beyond what floating point holds (readings near the physical limits, held for long)."""
    for key, value in values.items():
        if isinstance(value, float) and not math.isfinite(value):
            raise SinsInputError(
                f"{where}: {key} came out {value}; the inputs drive the computation beyond finite numbers "
                "(check the values they hold)"
            )


def display_unit(channel: str) -> tuple[float, str]:
    """:func:`sins.imu.display_unit`, imported when a table needs it (the CLI starts without numpy)."""
    from sins.imu import display_unit

    return display_unit(channel)


#: Why ``--spawn`` cannot open the native viewer (:func:`has_display`).
NO_DISPLAY = "no display to open the native viewer on (DISPLAY and WAYLAND_DISPLAY are unset)"


def has_display() -> bool:
    """Whether a native window can open here (always on macOS and Windows; X11 or Wayland elsewhere):
    :func:`sins.viz.viewer.has_display`, asked without importing the viewer's bridge (rerun takes seconds to
    import, and ``--spawn`` without a display is refused before any work)."""
    if sys.platform in ("darwin", "win32"):
        return True
    import os

    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def check_viewer_args(args: argparse.Namespace) -> None:
    """Refuse what cannot work before the run, not after it: ``--spawn`` without a display at once, a
    ``--web-port`` without ``--serve`` (which alone reads it)."""
    if getattr(args, "web_port", None) is not None and not args.serve:
        raise SinsInputError("--web-port goes with --serve")
    if not (args.rerun or args.spawn or args.serve):
        return
    if args.spawn and not has_display():
        raise SinsInputError(
            f"--spawn: {NO_DISPLAY}; use --rerun OUT.rrd to save a recording, or --serve for the web viewer"
        )
    if args.rerun:
        from sins.viz import viewer as viz

        viz.check_rrd_path(args.rerun, "--rerun")  # its suffix; the place is check_outputs's


WEB_PORT, DATA_PORT = 9090, 9876  # --serve's: the web viewer's (--web-port's default), the data's


def show(args: argparse.Namespace, result: ScenarioRun, summary: str) -> None:
    """Hand the run to Rerun as the flags ask: save, spawn the native viewer, serve the web viewer."""
    if not (args.rerun or args.spawn or args.serve):
        return
    from sins.viz import viewer as viz

    if args.rerun:
        viz.save(result, args.rerun, summary=summary)
        print(f"wrote {args.rerun} (open it with: rerun {args.rerun})")
    if args.spawn:
        viz.spawn(result, summary=summary)
    if args.serve:
        try:
            web = args.web_port or WEB_PORT
            address = viz.serve(result, summary=summary, web_port=web, grpc_port=DATA_PORT)
        except SinsInputError as exc:
            raise SinsInputError(f"--serve: {exc}") from None
        from sins.core import deferred

        deferred.land()  # the outputs said to be written are, before the wait only an interrupt ends
        print(f"serving the Rerun web viewer at {address}  (Ctrl-C stops)", flush=True)
        import time

        while True:  # the servers live as long as this process
            time.sleep(3600)


def check_outputs(
    outputs: dict[str, Path | None],
    inputs: Iterable[str | os.PathLike[str] | None] = (),
    folders: dict[str, Path | None] | None = None,
    kinds: dict[str, str] | None = None,
) -> None:
    """The one check of a command's outputs, before the work (:func:`sins.io.paths.check_outputs`):
    each can be written, none is an input (``inputs``: every file and folder the command reads) or
    another output, and none replaces a file holding what it never is (a recording where JSON goes).
    ``outputs`` and ``folders`` map each flag to its path (None: not asked for); ``kinds`` what a flag
    writes where :func:`output_kind` would not tell (``sins fit --out``: JSON, whatever its name)."""
    from sins.io.euroc import read_beside
    from sins.io.paths import check_outputs as check

    read = [p for p in inputs if p is not None]
    read += [beside for p in read if (beside := read_beside(p)) is not None]  # an ASL file's mav0
    told = kinds or {}
    of = {flag: told.get(flag) or output_kind(flag) for flag, path in outputs.items() if path is not None}
    check(outputs, read, folders, of)


def output_kind(flag: str) -> str:
    """What a command's output flag writes (:data:`sins.io.paths.KINDS`): ``--json`` and ``--baseline``
    JSON, ``--plot`` an image (or its HTML page), ``--rerun`` a Rerun recording; the others (``--out``,
    ``--imu``, ``--truth``) a CSV table, unless the command says otherwise (``check_outputs``'
    ``kinds``: ``sins integrate --out X.parquet``, ``sins characterise --out IMU.toml``)."""
    fixed = {"--json": "json", "--baseline": "json", "--plot": "image", "--rerun": "rrd"}
    return fixed.get(flag, "csv")


def unit_of(rec: Recording) -> str:
    """The unit a recording or dataset was read from ("" where it does not say): its named sensor (a
    dataset's, a sins CSV's ``# sensor:`` line, :mod:`sins.io.provenance`), else a dataset's name."""
    if rec.sensor or not rec.dataset:
        return rec.sensor
    return f"the {rec.dataset} dataset's unit"


def simulated_unit(imu_file: Path | None) -> str:
    """What a file of a simulated unit's readings says of the unit (its ``# sensor:`` line): the IMU file,
    the unit it draws (a power-on seed is the same unit again) and its content's digest (a unit told by
    its file's name alone had let a model of the tactical preset correct a consumer unit's file named
    ``tactical.toml``)."""
    if imu_file is None:
        return "ideal IMU (simulated)"
    from sins import scenario

    spec = scenario.load_imu(imu_file)
    return f"simulated {imu_file.stem} unit (unit seed {spec.unit_seed}, content {spec.digest()})"


def scenario_inputs(sc: Scenario) -> list[Path | None]:
    """The files a scenario reads: its own, its IMU and rig files, its truth file."""
    from sins.scenario import TruthFileSpec

    truth = sc.trajectory.path if isinstance(sc.trajectory, TruthFileSpec) else None
    rig = sc.compensation.rig if sc.compensation is not None else None
    return [sc.source, sc.imu_model, rig, truth]


def check_plot(args: argparse.Namespace) -> None:
    """Refuse a ``--plot`` path that cannot be written, before the work."""
    if getattr(args, "plot", None):
        from sins.viz import plots

        plots.check_plot_path(args.plot)


def save_plot(path: Path, figure: Callable[[], Any], title: str) -> None:
    """Build the figure (``figure()``, a :mod:`sins.viz.plots` call) and save it at ``path``."""
    with progress_bar(f"drawing {path}", ""):  # matplotlib's import and a grid's layout take seconds
        from sins.viz import plots

        plots.save(figure(), path, title)
    print(f"wrote {path}")


__all__ = [
    "DATA_PORT",
    "HOUR_S",
    "MIN_RATE_S",
    "NO_DISPLAY",
    "WEB_PORT",
    "Subparsers",
    "check_finite",
    "check_outputs",
    "check_plot",
    "check_viewer_args",
    "display_unit",
    "fixed_width",
    "format_table",
    "has_display",
    "output_kind",
    "save_plot",
    "scenario_inputs",
    "show",
    "simulated_unit",
    "unit_of",
]
