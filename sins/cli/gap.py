"""``sins gap``: the sim-to-real diagnosis of a recording."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.cli.common import (
    Subparsers,
    add_dataset,
    advance,
    check_outputs,
    dataset_inputs,
    display_unit,
    fixed_width,
    fraction,
    progress_bar,
)
from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.gap import GapReport
    from sins.series import CalibrationData


def _cmd_gap(args: argparse.Namespace) -> int:
    from sins import gap, io, pipeline

    if args.rerun:
        from sins import viz

        viz.check_rrd_path(args.rerun)
    inputs = [args.recording, args.truth, args.model, *dataset_inputs(args.dataset)]
    check_outputs({"--json": args.json, "--rerun": args.rerun}, inputs)
    data, truth, model = _gap_inputs(args)
    with progress_bar("diagnosing", "candidate") as bar:

        def progress(name: str) -> None:
            assert bar is not None  # passed only when there is a bar
            bar.set_postfix_str(name)
            advance(bar, bar.n + 1)

        report = gap.diagnose(data, args.holdout, model, progress if bar is not None else None)
    _print_gap_report(args, data, report)
    document = {"recording": str(args.recording), **report.to_dict()}
    if truth is not None and not report.unreferenced:
        nav = pipeline.gap_navigation(data, truth, report)
        print(
            "\nnavigation over the recording (vertical held to the truth), final horizontal error:\n"
            f"  real unit {nav['real_m']:.3f} m; simulated unit {nav['simulated_before_m']:.3f} m with the "
            f"model, {nav['simulated_after_m']:.3f} m with the accepted effects\n"
            f"  simulated against real at the end: {nav['sim_to_real_before_m']:.3f} m before, "
            f"{nav['sim_to_real_after_m']:.3f} m after"
        )
        document["navigation"] = nav
    if args.json:
        io.write_json(args.json, document)
    if args.rerun:
        viz.save_gap(report, args.rerun)
        print(f"wrote {args.rerun}")
    return 0


def _gap_inputs(args: argparse.Namespace) -> tuple[Any, Any, tuple[str, ...]]:
    """``sins gap``'s recording (a file, or a dataset by name), its truth if any, and the model's effects."""
    from sins import imu, io, pipeline, scenario

    if (args.recording is None) == (args.dataset is None):
        raise SinsInputError("gap: give a RECORDING.csv or --dataset NAME (one of them)")
    if not 0.0 < args.holdout < 1.0:
        raise SinsInputError(f"--holdout must be in (0, 1), got {args.holdout}")
    if args.dataset is not None:
        from sins.io import datasets

        if args.truth is not None:
            raise SinsInputError("gap: --truth goes with a RECORDING.csv, not with --dataset")
        data, truth = datasets.load_with_truth(args.dataset)
        args.recording = args.dataset
    else:
        data, truth = pipeline.gap_data(args.recording, args.truth)
        if args.truth is None:
            io.check_recording_range(args.recording, data)
    model: tuple[str, ...] = imu.BASELINE
    if args.model:
        spec = scenario.load_imu(scenario.resolve_preset(args.model, "imu"))
        model = tuple(e.name for e in spec.model().effects)
    return data, truth, model


def _print_gap_report(args: argparse.Namespace, data: CalibrationData, report: GapReport) -> None:
    """The report as ``sins gap`` prints it: the rows, the residuals against the floor, where the gap
    is, the candidates, the diagnosis and what is left unexplained."""
    from sins import gap

    _, held_rows = report.rows
    skipped = (
        f" ({report.unreferenced} without a per-sample reference left out)" if report.unreferenced else ""
    )
    print(f"{args.recording}: {len(data)} rows{skipped}, {held_rows} withheld: {report.withholding}")
    print(f"model: {', '.join(report.model)}")
    head = ["channel", "unit", "before", "after", "noise floor", "before/floor", "after/floor"]
    rows = []
    for ch, v in report.channels.items():
        size, unit = display_unit(ch)
        rows.append([
            ch, unit, f"{v['rms_before'] / size:.4f}", f"{v['rms_after'] / size:.4f}",
            f"{v['noise_floor'] / size:.4f}", f"{v['rms_before'] / v['noise_floor']:.3f}",
            f"{v['rms_after'] / v['noise_floor']:.3f}",
        ])  # fmt: skip
    print("RMS of reading - model on the withheld rows")
    print(fixed_width(head, rows))
    if report.where:
        print("\nwhere the gap is (channels above their noise floor, largest first):")
        for w in report.where:
            print(f"  {w['channel']}: {w['excess']:.3f}x the floor; " + ("; ".join(w["concentrates"]) or "-"))
    else:
        print("\nno channel is significantly above its noise floor: the model explains the data")
    threshold = f"{gap.SIGNIFICANT_NATS:.1f} nats"
    print(f"\ncandidate effects (withheld log-likelihood gain less {threshold}, and a random bias's")
    print("allowance; the best above 0 is accepted, then the rest are scored again beside it):")
    for e in report.effects[: args.top]:
        mark = "accepted" if e.accepted else ""
        if e.not_accepted_because:
            mark = f"not accepted: {e.not_accepted_because}"
        if e.indistinguishable:
            mark += f" (this data cannot tell it from {' or '.join(e.indistinguishable)})"
        print(f"  {e.name:<26} {e.score:14.1f}  {mark}")
    for name, why in report.unfitted.items():
        print(f"  {name:<26} {'not fitted':>14}  {why}")
    print(f"\ndiagnosis: {', '.join(report.diagnosis) or 'nothing to add'}")
    print(f"unexplained: {', '.join(report.unexplained) or 'none'}")
    for o in report.outside:
        print(f"  {o.channel}: {o.what()}, which no library effect explains as well")


def add(sub: Subparsers) -> None:
    """Add ``sins gap`` to ``sub``."""
    p = sub.add_parser("gap", help="sim-to-real gap: where the model fails, which effect explains it")
    p.add_argument("recording", type=Path, nargs="?", metavar="RECORDING.csv")
    add_dataset(p)
    p.add_argument("--truth", type=Path, metavar="TRUTH.csv", help="the trajectory of an IMU recording")
    p.add_argument("--model", metavar="MODEL.toml", help="the simulation's IMU model (default: the baseline)")
    p.add_argument(
        "--holdout", type=fraction, default=0.3, metavar="FRACTION",
        help="withhold the last FRACTION of every phase (default 0.3); every verdict is judged on it",
    )  # fmt: skip
    p.add_argument(
        "--json", type=Path, metavar="REPORT.json",
        help="write the report: channels, where, effects, diagnosis, unexplained, outside, allan "
        "(and navigation, with a trajectory)",
    )  # fmt: skip
    p.add_argument(
        "--rerun", type=Path, metavar="OUT.rrd",
        help="log the residuals before and after, their Allan deviations and the excess by input quartile",
    )  # fmt: skip
    p.add_argument("--top", type=int, default=8, help="how many candidates to print (default 8)")
    p.set_defaults(func=_cmd_gap)


__all__ = [
    "add",
]
