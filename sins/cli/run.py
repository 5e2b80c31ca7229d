"""``sins run``: a scenario simulated, integrated and summarised per strategy; shown in Rerun."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.cli.common import (
    DATA_PORT,
    WEB_PORT,
    Subparsers,
    check_finite,
    check_outputs,
    check_plot,
    check_viewer_args,
    display_unit,
    fixed_width,
    format_table,
    save_plot,
    scenario_inputs,
    show,
)
from sins.cli.options import add_plot, count, seed
from sins.cli.progress import progress_bar, row_progress
from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.scenario import AidingSpec, Scenario


def _cmd_run(args: argparse.Namespace) -> int:
    check_viewer_args(args)  # before the imports below: --spawn without a display is refused at once
    if args.serve:
        _check_ports(args.web_port or WEB_PORT, DATA_PORT)
    check_plot(args)
    from sins import io, scenario
    from sins.runs import pipeline
    from sins.scenario.budget import check_scenario_size

    path = pipeline.resolve_scenario(args.scenario)
    sc = pipeline.with_unit(scenario.load(path), args.imu, args.seed)
    check_outputs({"--json": args.json, "--plot": args.plot, "--rerun": args.rerun}, scenario_inputs(sc))
    check_scenario_size(sc, path, "running")
    try:
        unit = None
        if sc.imu_model is not None:
            with progress_bar("fitting the strategies on the rig", "strategies") as bar:
                unit = pipeline.fit_unit(scenario.load_imu(sc.imu_model), sc.compensation, row_progress(bar))
        # With [gnss], each aided filter counts as the samples again (pipeline.run_units).
        then = "" if sc.aiding is None else " (its samples, then each aided filter's)"
        with progress_bar(f"running {sc.name}{then}", "samples") as bar:
            result = pipeline.run_scenario(sc, unit=unit, progress=row_progress(bar))
    except ValueError as exc:  # a rig session that cannot be fitted, say
        if isinstance(exc, SinsInputError):
            raise
        raise SinsInputError(f"{path}: {exc}") from None
    scenario.check_latitude(sc, result.truth)
    for note in [scenario.unsampled_end(sc), *scenario.idle_outages(sc)]:
        if note:
            print(f"sins: note: {path}: {note}", file=sys.stderr)
    summaries: dict[str, dict[str, Any]] = {name: run.summary.to_dict() for name, run in result.runs.items()}
    for name, summary in summaries.items():
        check_finite(summary, f"{path}: strategy {name}")
    n = result.samples
    imu_note = f", IMU {sc.imu_model.stem} (seed {sc.imu_seed})" if sc.imu_model else ", ideal IMU"
    report = [
        f"scenario {sc.name}: {sc.description or path}\n"
        f"{n} sample{'s' * (n != 1)} at {sc.rate_hz:g} Hz ({n / sc.rate_hz:g} s){imu_note}, vertical channel "
        f"{sc.vertical}; "
        "errors are estimate - truth",
        format_table(summaries),
    ]
    residuals = {name: run.residual_rms for name, run in result.runs.items() if run.residual_rms is not None}
    if residuals:
        report.append("\nresidual sensor error on the rig data held back from the fit (RMS per sample)")
        report.append(format_residuals(residuals))
        report += guard_notes(unit.strategies if unit is not None else {})
    aided, outages = result.aided_dicts()
    for name, summary in aided.items():
        check_finite(summary, f"{path}: aided strategy {name}")
    if aided:
        grade = next(iter(result.aided.values())).filter_grade
        report.append(_aided_report(sc, aided, outages, grade, float(result.truth.t[-1])))
    print("\n".join(report))
    if args.json:
        io.write_report(args.json, result.to_dict(str(path)))
    if args.plot:
        from sins.viz import plots  # matplotlib, only for a plot

        save_plot(args.plot, lambda: plots.run_figure(result), f"sins run {sc.name}")
    show(args, result, "\n".join(report))
    return 0


def _port(text: str) -> int:
    """An argument type: a TCP port, 1 to 65535 (a larger one had failed after the whole run)."""
    value = count(text)
    if value > 65535:
        raise argparse.ArgumentTypeError(f"must be a port, 1 to 65535, got {text}")
    return value


def _check_ports(*ports: int) -> None:
    """``--serve``'s ports free before the run, not after it (an hour's drive had run to be refused)."""
    import socket

    for port in ports:
        with socket.socket() as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as rerun's: a closed one's wait
            try:
                probe.bind(("0.0.0.0", port))  # where rerun's servers listen
            except OSError as exc:
                raise SinsInputError(f"--serve: port {port} is taken ({exc.strerror or exc})") from None


def guard_notes(strategies: dict[str, Any]) -> list[str]:
    """A line for each learned strategy saying where its guard kept regression (and the physics terms):
    a row equal to regression's is then the guard's verdict, not a learner that learnt nothing."""
    lines = []
    for name, strategy in strategies.items():
        guard = getattr(strategy, "guard_", None)
        if not isinstance(guard, dict):
            continue
        learned = [ch for ch, g in guard.items() if g.get("earns_its_place")]
        if not learned:
            lines.append(
                f"{name}: the guard kept regression and its term groups on every channel (the learner did "
                "not beat them on held-back rig blocks)"
            )
        elif len(learned) < len(guard):
            lines.append(f"{name}: learned on {', '.join(learned)}; the guard kept regression on the others")
    return lines


def format_residuals(residuals: dict[str, dict[str, float]]) -> str:
    """Strategy × channel residual RMS (°/h, mg) and the mean ratio to the oracle's (nan without one)."""
    from sins.imu import CHANNELS as _CHANNELS

    head = ["strategy", *(f"{c} {display_unit(c)[1]}" for c in _CHANNELS), "× oracle"]
    oracle = residuals.get("oracle")
    rows = []
    for name, ch in residuals.items():
        cells = [f"{ch[c] / display_unit(c)[0]:.3f}" for c in _CHANNELS]
        # Over the channels the oracle leaves any error on (a noiseless channel's floor is 0).
        ratios = [ch[c] / oracle[c] for c in _CHANNELS if oracle and oracle[c] > 0]
        ratio = sum(ratios) / len(ratios) if ratios else float("nan")
        rows.append([name, *cells, f"{ratio:.3f}"])
    return fixed_width(head, rows)


def _aided_report(
    sc: Scenario, aided: dict[str, dict[str, Any]], outages: dict[str, list[dict[str, float]]], grade: str,
    end_s: float,
) -> str:  # fmt: skip
    """The aided runs' table and, if any, the errors per outage (one past the run's end ``end_s``, s,
    shown to that end)."""
    a = sc.aiding
    assert a is not None  # only aided scenarios have aided runs
    start = _alignment_text(a, next(iter(aided.values())))
    columns: tuple[tuple[str, str, str], ...]
    columns = (("final hor m", "final_horizontal_m", "{:.3f}"), ("max hor m", "max_horizontal_m", "{:.3f}"),
               ("rms hor m", "rms_horizontal_m", "{:.3f}"), ("final D m", "final_down_m", "{:.3f}"),
               ("yaw °", "final_yaw_deg", "{:.4f}"), ("fixes", "fixes", "{:d}"),
               ("rejected", "rejected_fixes", "{:d}"))  # fmt: skip
    if a.sigma_vel_mps is not None:
        columns += (("rejected v", "rejected_velocity_fixes", "{:d}"),)
    head = ["strategy"] + [c[0] for c in columns]
    rows = [[name] + [fmt.format(s[key]) for _, key, fmt in columns] for name, s in aided.items()]
    text = [
        f"\naided by GNSS at {a.rate_hz:g} Hz ({len(a.outages)} outage{'' if len(a.outages) == 1 else 's'}), "
        f"filter tuned to the {grade} grade, "
        f"started {start}",
        fixed_width(head, rows),
    ]
    for name, s in aided.items():
        if s.get("filter_restarts_s"):
            times = ", ".join(f"{t:g}" for t in s["filter_restarts_s"])
            text.append(f"{name}: the filter diverged and started again from the fixes at {times} s")
    windows = [(name, o) for name, items in outages.items() for o in items]
    if windows:
        text.append("\nposition error per outage (horizontal, before the first fix after it)")
        rows = []
        for name, o in windows:
            past = " (the run's end)" if o["end_s"] > end_s else ""
            label = f"{o['start_s']:g}-{min(o['end_s'], end_s):g} s{past}"
            rows.append([name, label, f"{o['final_horizontal_m']:.3f}", f"{o['max_horizontal_m']:.3f}"])
        text.append(fixed_width(["strategy", "outage", "at end m", "max m"], rows))
    return "\n".join(text)


def _alignment_text(a: AidingSpec, run: dict[str, Any]) -> str:
    """How the aided runs started (the alignment that ran), for the report's heading line."""
    if run["alignment"] == "static":
        where = " (heading from elsewhere)" if a.heading_sigma_rad is not None else ""
        return f"aligned over the first {run['alignment_static_s']:g} s{where}"
    if run["alignment"] == "gnss_velocity":
        return (
            f"aligned in motion at {run['alignment_start_s']:g} s, heading from the GNSS velocity "
            f"(1σ {run['alignment_heading_sigma_deg']:.2f}°); errors from then"
        )
    return "from the truth's first state"


def add(sub: Subparsers) -> None:
    """Add ``sins run`` to ``sub``."""
    p = sub.add_parser(
        "run",
        help="simulate a scenario, integrate it and print the drift per strategy (with [gnss], aided through "
        "outages); draw it, or show it in Rerun",
    )
    p.add_argument("scenario", nargs="?", help="scenario file or preset name (default: car_drive)")
    p.add_argument(
        "--imu", metavar="GRADE|IMU.toml",
        help="the unit to drive: an IMU preset (consumer, industrial, tactical, navigation, ...) or an IMU "
        "file, instead of the scenario's [imu] model",
    )  # fmt: skip
    p.add_argument(
        "--seed", type=seed, metavar="N", help="the navigation run's power-on, instead of [imu] seed"
    )
    p.add_argument("--json", type=Path, metavar="OUT.json", help="also write the summary as JSON")
    p.add_argument("--rerun", type=Path, metavar="OUT.rrd", help="save the run as a Rerun recording")
    p.add_argument("--spawn", action="store_true", help="show the run in the native Rerun viewer")
    p.add_argument(
        "--serve", action="store_true",
        help="serve the run to the Rerun web viewer (prints the address; Ctrl-C stops)",
    )  # fmt: skip
    p.add_argument(
        "--web-port", type=_port, metavar="N", help=f"port of --serve's web viewer (default {WEB_PORT})"
    )
    add_plot(p, "the errors against time, per strategy")
    p.set_defaults(func=_cmd_run)


__all__ = [
    "add",
    "format_residuals",
    "guard_notes",
]
