"""``sins evaluate``: a fitted model judged on a recording: channel by channel on a rig recording; by the
attitude its corrected gyro holds open loop, and the drift of the corrected unit, against a reference
trajectory."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.cli.common import (
    Subparsers,
    check_finite,
    check_outputs,
    check_plot,
    display_unit,
    fixed_width,
    save_plot,
    unit_of,
)
from sins.cli.options import (
    add_dataset,
    add_plot,
    add_recording_options,
    dataset_inputs,
    fraction,
    read_recording,
)
from sins.cli.progress import progress_bar
from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.compensation import Strategy
    from sins.core.series import CalibrationData, ReferencedRecording


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from sins import compensation, io
    from sins.compensation import referenced

    check_plot(args)
    if args.rerun:
        from sins.viz import viewer as viz

        viz.check_rrd_path(args.rerun)
    outputs = {"--json": args.json, "--plot": args.plot, "--rerun": args.rerun}
    check_outputs(outputs, [args.model, args.recording, args.truth, *dataset_inputs(args.dataset)])
    strategy = compensation.load(args.model)
    where = args.dataset or str(args.recording)
    with progress_bar(f"reading {where}", ""):  # a dataset or a long bag takes seconds
        rec = read_recording(args, args.recording, args.dataset, args.truth)
    referenced.check_fitted_on(strategy, rec, f"{args.model} on {where}", sensor=unit_of(rec))
    if rec.rig is not None:
        document = _evaluate_rig(args, strategy, rec.rig, where)
    elif rec.has_trajectory:
        document = _evaluate_referenced(args, strategy, rec.beside_reference(), where)
    else:
        missing = io.recording.missing_reference(rec)
        if missing.needs == "truth_topic":  # a bag with several pose topics: name one
            raise missing
        raise SinsInputError(
            f"{where}: no reference to judge against; give the recording's trajectory with --truth TRUTH.csv"
        )
    if args.json:
        io.write_json(
            args.json, {"model": str(args.model), "strategy": strategy.label, "recording": where, **document}
        )
    return 0


def _evaluate_rig(
    args: argparse.Namespace, strategy: Strategy, data: CalibrationData, where: str
) -> dict[str, Any]:
    """Per channel: RMS before and after, the bias left, and what is left beyond the white noise."""
    from sins import compensation

    if args.bias_from_rest or args.drive:
        raise SinsInputError(
            f"--bias-from-rest and --drive judge against a trajectory; {where} is a rig recording"
        )
    if args.last:
        try:
            _, data = data.split(args.last)
        except ValueError as exc:
            raise SinsInputError(f"{where}: {exc}") from None
    with progress_bar("judging", ""):
        channels = compensation.residual_rms(strategy, data)
    for name, v in channels.items():
        check_finite(v, f"{args.model} on {where}: {name}")
    scope = f"the last {args.last:g} of each phase" if args.last else "the whole recording"
    print(f"{args.model} ({strategy.label}) on {where}, {scope}: reading - reference")
    rows = []
    for name, v in channels.items():
        size, unit = display_unit(name)
        rows.append([
            name, unit, f"{v['rms_before'] / size:.4f}", f"{v['rms_after'] / size:.4f}",
            f"{v['mean_after'] / size:+.4f}", f"{v['beyond_noise'] / size:.4f}",
        ])  # fmt: skip
    print(fixed_width(["channel", "unit", "rms before", "rms after", "bias left", "beyond noise"], rows))
    print("beyond noise: the RMS left after the white noise (from the residual's sample-to-sample changes)")
    if args.plot:
        from sins.viz import plots

        title = f"{args.model} ({strategy.label}) on {where}, {scope}"
        save_plot(args.plot, lambda: plots.evaluate_figure(channels, title), title)
    return {"channels": channels}


def _evaluate_referenced(
    args: argparse.Namespace, strategy: Strategy, rec: ReferencedRecording, where: str
) -> dict[str, Any]:
    """Open-loop attitude of the corrected gyro (and of the raw one, and with the bias from the opening
    rest), and with ``--drive`` the corrected unit's free-inertial drift over a window."""
    from sins.compensation import referenced

    if args.last:
        span = rec.imu.t[-1] - rec.imu.t[0]
        rec = referenced.between(rec, rec.imu.t[-1] - args.last * span, rec.imu.t[-1])
    rows, attitude, runs = [], {}, {}
    variants: list[tuple[str, Strategy | None, bool]] = [
        ("none (raw readings)", None, False),
        (strategy.label, strategy, False),
    ]
    if args.bias_from_rest:
        variants.append((f"{strategy.label}, gyro bias from the opening rest", strategy, True))
    for label, s, rest in variants:
        with progress_bar(f"open loop: {label}", ""):
            runs[label] = referenced.open_loop(s, rec, bias_from_rest=rest)
        r = runs[label].rmse()
        aoe = runs[label].aoe_deg()
        attitude[label] = {**r.to_dict(), "aoe_deg": aoe}
        rows.append(
            [label, f"{r.total_deg:.3f}", f"{r.heading_deg:.3f}", f"{r.inclination_deg:.3f}", f"{aoe:.3f}"]
        )
    judged = "the judged rows (movement phases)" if rec.judged is not None else "every reference epoch"
    print(
        f"{args.model} ({strategy.label}) on {where}: the gyro integrated alone from the reference's first "
        f"attitude, RMS error against {rec.reference_name} over {judged}, degrees (AOE: over every epoch)"
    )
    if not rec.latitude_known:
        print("the reference's frame has no known latitude or heading: Earth's rate is left out")
    elif not rec.heading_known:
        print("the reference's frame has no known north: only the vertical part of Earth's rate is put in")
    print(fixed_width(["readings", "total", "heading", "inclination", "AOE"], rows))
    document: dict[str, Any] = {
        "open_loop_attitude": attitude[strategy.label],
        "open_loop_attitude_raw": attitude["none (raw readings)"],
    }
    if args.bias_from_rest:
        document["open_loop_attitude_bias_from_rest"] = attitude[variants[-1][0]]
    if args.drive:
        document["drive"] = _drive(args, strategy, rec)
    if args.rerun:
        from sins.viz import viewer as viz

        summary = f"{args.model} ({strategy.label}) on {where}\n\n" + fixed_width(
            ["readings", "total", "heading", "inclination", "AOE"], rows
        )
        viz.save_open_loop(runs, args.rerun, summary=summary)
        print(f"wrote {args.rerun} (open it with: rerun {args.rerun})")
    if args.plot:
        from sins.viz import plots

        title = f"{args.model} ({strategy.label}) on {where}: open-loop attitude error"
        save_plot(args.plot, lambda: plots.open_loop_figure(runs, title), title)
    return document


def _drive(args: argparse.Namespace, strategy: Strategy, rec: ReferencedRecording) -> dict[str, Any]:
    from sins.compensation import referenced

    try:
        start, end = (float(x) for x in args.drive.split(":"))
    except ValueError:
        raise SinsInputError(f"--drive {args.drive!r}: expected START:END in seconds") from None
    out, rows = {}, []
    for label, s in (("none (raw readings)", None), (strategy.label, strategy)):
        with progress_bar(f"free inertial: {label}", ""):
            d = referenced.drive_errors(s, rec, start, end)
        out[label] = d.to_dict()
        figures = [*d.attitude_rms_deg, *d.velocity_rms_mps]
        rows.append([label, *(f"{x:.4f}" for x in figures), f"{d.horizontal_final_m:.3f}"])
    print(
        f"\nfree inertial from the reference's state at {start:g} s to {end:g} s (vertical held), RMS errors"
    )
    head = ["readings", "roll °", "pitch °", "yaw °", "vN m/s", "vE m/s", "vD m/s", "hor end m"]
    print(fixed_width(head, rows))
    return out


def add(sub: Subparsers) -> None:
    """Add ``sins evaluate`` to ``sub``."""
    p = sub.add_parser(
        "evaluate",
        help="judge a fitted model: per channel on a rig recording, open loop against a trajectory",
    )
    p.add_argument("model", type=Path, metavar="MODEL.json")
    p.add_argument("recording", nargs="?", metavar="RECORDING", help="a rig CSV, or a recording with --truth")
    add_dataset(p)
    p.add_argument("--truth", type=Path, metavar="TRUTH.csv", help="the recording's reference trajectory")
    p.add_argument(
        "--last", type=fraction, metavar="FRACTION",
        help="judge only the last FRACTION of every phase (of the whole recording if it has no phases)",
    )  # fmt: skip
    p.add_argument(
        "--bias-from-rest", action="store_true",
        help="against a trajectory: also with the gyro bias taken again from the recording's opening rest",
    )  # fmt: skip
    p.add_argument(
        "--drive", metavar="START:END",
        help="against a trajectory: also navigate free inertial from the reference's state over START:END s",
    )  # fmt: skip
    p.add_argument("--json", type=Path, metavar="OUT.json")
    p.add_argument(
        "--rerun", type=Path, metavar="OUT.rrd",
        help="against a trajectory: log the open-loop attitude errors over time for the Rerun viewer",
    )  # fmt: skip
    add_plot(p, "the RMS error per channel before and after (against a trajectory: the open-loop attitude)")
    add_recording_options(p)
    p.set_defaults(func=_cmd_evaluate)


__all__ = [
    "add",
]
