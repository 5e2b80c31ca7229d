"""``sins gap``: the sim-to-real diagnosis of a recording."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.cli.common import Subparsers, check_outputs, display_unit, fixed_width
from sins.cli.options import (
    add_dataset,
    add_recording_options,
    check_distinct,
    count,
    dataset_inputs,
    fraction,
    positive,
    recording_options,
)
from sins.cli.progress import advance, progress_bar
from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.gap import GapReport


def _cmd_gap(args: argparse.Namespace) -> int:
    from sins import io

    if args.rerun:
        from sins.viz import viewer as viz

        viz.check_rrd_path(args.rerun, "--rerun")
    read = [*(args.recording or []), args.truth, args.model]
    read += [p for d in (args.dataset or []) for p in dataset_inputs(d)]
    check_outputs({"--json": args.json, "--rerun": args.rerun}, read)
    inputs, model = _gap_inputs(args)
    results = [_diagnose(args, inp, model) for inp in inputs]
    document = _one_document(results[0]) if len(results) == 1 else _several_document(args, inputs, results)
    if args.json:
        io.write_report(args.json, document)
    if args.rerun:
        viz.save_gap({r.name: r.report for r in results}, args.rerun)
        print(f"wrote {args.rerun}")
    return 0


def _diagnose(args: argparse.Namespace, inp: Any, model: tuple[str, ...]) -> Any:
    """One recording's diagnosis, behind a progress bar, printed."""
    from sins.unit_gap import run

    with progress_bar(f"diagnosing {inp.name}", "candidate") as bar:

        def progress(name: str) -> None:
            assert bar is not None  # passed only when there is a bar
            bar.set_postfix_str(name)
            advance(bar, bar.n + 1)

        result = run.diagnose_one(
            inp, args.holdout, model, args.statistic, args.interval_s, progress if bar is not None else None
        )
    _print_gap_report(result.name, result.rows, result.report, args.top)
    return result


def _one_document(result: Any) -> dict[str, Any]:
    from sins.gap.navigation import gap_navigation

    document: dict[str, Any] = {"recording": result.name, **result.report.to_dict()}
    data, truth = result.samples if result.samples is not None else (None, None)
    if data is not None and truth is not None and not result.report.unreferenced:
        nav = gap_navigation(data, truth, result.report)
        print(
            "\nnavigation over the recording (vertical held to the truth), final horizontal error:\n"
            f"  real unit {nav['real_m']:.3f} m; simulated unit {nav['simulated_before_m']:.3f} m with "
            f"the model, {nav['simulated_after_m']:.3f} m with the accepted effects\n"
            f"  simulated against real at the end: {nav['sim_to_real_before_m']:.3f} m before, "
            f"{nav['sim_to_real_after_m']:.3f} m after"
        )
        document["navigation"] = nav
    return document


def _several_document(args: argparse.Namespace, inputs: list[Any], results: list[Any]) -> dict[str, Any]:
    """Several recordings of one unit: the verdicts across them and each model's shrink on another."""
    from sins.unit_gap import across, run, shrink

    verdicts = run.verdicts(results)
    print("\n".join(across.lines(verdicts)))
    judged = run.shrinks(inputs, results, args.interval_s)
    print("\n".join(shrink.lines(judged)))
    return {
        "recordings": [{"recording": r.name, **r.report.to_dict()} for r in results],
        "across": verdicts,
        "shrink": judged,
    }


def _gap_inputs(args: argparse.Namespace) -> tuple[list[Any], tuple[str, ...]]:
    """``sins gap``'s recordings (files, datasets by name, or both), each with its reference, and the
    model's effects."""
    from sins import imu, scenario
    from sins.unit_gap.inputs import check_one_unit, read_gap_input

    paths, names = list(args.recording or []), list(args.dataset or [])
    if not paths and not names:
        raise SinsInputError("gap: give a RECORDING or --dataset NAME (one or more)")
    if not 0.0 < args.holdout < 1.0:
        raise SinsInputError(f"--holdout must be in (0, 1), got {args.holdout}")
    if args.truth is not None and (names or len(paths) != 1):
        raise SinsInputError("gap: --truth goes with one RECORDING, not with --dataset or several")
    check_distinct([str(p) for p in paths], names, "gap")
    options = recording_options(args)
    inputs = [read_gap_input(p, truth=args.truth, options=options) for p in paths]
    inputs += [read_gap_input(None, dataset=n, options=options) for n in names]  # one not applying: refused
    check_one_unit(inputs)
    model: tuple[str, ...] = imu.BASELINE
    if args.model:
        spec = scenario.load_imu(scenario.resolve_preset(args.model, "imu"))
        model = tuple(e.name for e in spec.model().effects)
    return inputs, model


def _print_statistic(statistic: dict[str, Any], intervals: bool) -> None:
    """Which statistic the verdicts were reached on and why, and what the reference limits."""
    if not statistic:
        return
    what = "integrated rotation and velocity change over intervals" if intervals else "per-sample residuals"
    print(f"statistic: {what}; {statistic.get('why', '')}")
    key = "reference_limits" if intervals else "interval_quality"
    if key in statistic:
        print(f"  reference: {statistic[key]}")
    for key in ("reference_tilt", "reference_clock", "reference_filled"):
        if key in statistic:
            print(f"  reference: {statistic[key]['says']}")
    for key in ("accel_with_gyro_corrected", "delays_per_sample"):
        if key in statistic:
            print(f"  {statistic[key]['says']}")


def _print_gap_report(name: str, n_rows: int, report: GapReport, top: int = 8) -> None:
    """The report as ``sins gap`` prints it: the rows, the statistic and why, the residuals against the
    floor, where the gap is, the candidates, the diagnosis and what is left unexplained."""
    from sins import gap

    _, held_rows = report.rows
    skipped = (
        f" ({report.unreferenced} without a per-sample reference left out)" if report.unreferenced else ""
    )
    intervals = report.statistic.get("kind") == "intervals"
    held = f"{held_rows} intervals withheld" if intervals else f"{held_rows} withheld"
    print(f"{name}: {n_rows} rows{skipped}, {held}: {report.withholding}")
    _print_statistic(report.statistic, intervals)
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
    print(
        "RMS of reading - model on the withheld intervals, as mean rates over each"
        if intervals
        else "RMS of reading - model on the withheld rows"
    )
    print(fixed_width(head, rows))
    if report.where:
        print("\nwhere the gap is (channels above their noise floor, largest first):")
        for w in report.where:
            print(f"  {w['channel']}: {w['excess']:.3f}x the floor; " + ("; ".join(w["concentrates"]) or "-"))
    else:
        print("\nno channel is significantly above its noise floor: the model explains the data")
    threshold = f"{gap.SIGNIFICANT_NATS:.1f} nats"
    print(f"\ncandidate effects (withheld log-likelihood gain less {threshold}, and a random bias's")
    print("allowance; of those above 0, the one of greatest gain is accepted, the rest scored beside it):")
    for e in report.effects[:top]:
        mark = "accepted" if e.accepted else ""
        if e.not_accepted_because:
            mark = f"not accepted: {e.not_accepted_because}"
        if e.indistinguishable:
            mark += f" (this data cannot tell it from {' or '.join(e.indistinguishable)})"
        print(f"  {e.name:<26} {e.score:14.1f}  {mark}")
    for name, why in report.unfitted.items():
        print(f"  {name:<26} {'not fitted':>14}  {why}")
    odd = " (at a size no unit has: below)"
    named = [e + (odd if e in report.implausible else "") for e in report.diagnosis]
    print(f"\ndiagnosis: {', '.join(named) or 'nothing to add'}")
    print(f"unexplained: {', '.join(report.unexplained) or 'none'}")
    for o in report.outside:
        print(f"  {o.channel}: {o.what()}, which no library effect explains as well")
    from sins.unit_gap.across import size_lines

    for line in size_lines(report):
        print(f"  {line}")


def add(sub: Subparsers) -> None:
    """Add ``sins gap`` to ``sub``."""
    p = sub.add_parser("gap", help="sim-to-real gap: where the model fails, which effect explains it")
    p.add_argument(
        "recording", nargs="*", metavar="RECORDING",
        help="a rig CSV, a recording with --truth, or one with its own reference (.npz, EuRoC/TUM-VI "
        "folder, bag)",
    )  # fmt: skip
    add_dataset(p, repeat="to diagnose several recordings of one unit and set their verdicts side by side")
    p.add_argument("--truth", type=Path, metavar="TRUTH.csv", help="the trajectory of an IMU recording")
    p.add_argument(
        "--statistic", choices=("auto", "samples", "intervals"), default="auto",
        help="per-sample residuals, or integrated rotation and velocity change over the reference's "
        "intervals (default auto: intervals where the differentiated reference adds to the sensor's noise)",
    )  # fmt: skip
    p.add_argument(
        "--interval-s", type=positive, metavar="S",
        help="with the interval statistic: the interval between the reference epochs compared (default 1)",
    )  # fmt: skip
    p.add_argument("--model", metavar="IMU.toml", help="the simulation's IMU model (default: the baseline)")
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
        help="log the residuals before and after, their Allan deviations and the excess by input quartile "
        "(several recordings: a tab each)",
    )  # fmt: skip
    p.add_argument(
        "--top", type=count, default=8, metavar="N", help="how many candidates to print (default 8)"
    )
    add_recording_options(p)
    p.set_defaults(func=_cmd_gap)


__all__ = [
    "add",
]
