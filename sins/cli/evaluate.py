"""``sins evaluate``: a fitted model judged on a recording: channel by channel on a rig recording; by the
attitude its corrected gyro holds open loop, and the drift of the corrected unit, against a reference
trajectory."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from sins.cli.common import (
    Subparsers,
    check_finite,
    check_outputs,
    check_plot,
    save_plot,
    unit_of,
)
from sins.cli.options import (
    add_dataset,
    add_plot,
    add_recording_options,
    check_distinct,
    dataset_inputs,
    fraction,
    positive,
    read_recording,
)
from sins.cli.progress import progress_bar
from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.compensation import Strategy
    from sins.compensation.evaluation import Evaluation
    from sins.core.series import CalibrationData, ReferencedRecording

#: Why evaluate refuses readings a model corrected already (:func:`sins.cli.options.read_recording`).
_EVALUATE_RAW = "judging a model on them applies a correction twice, and calls the corrected readings raw"


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from sins import compensation, io
    from sins.compensation import fitted_on

    check_plot(args)
    if args.rerun:
        from sins.viz import viewer as viz

        viz.check_rrd_path(args.rerun, "--rerun")
    outputs = {"--json": args.json, "--plot": args.plot, "--rerun": args.rerun}
    paths, names = list(args.recording or []), list(args.dataset or [])
    check_outputs(outputs, [args.model, *paths, args.truth, *(p for d in names for p in dataset_inputs(d))])
    strategy = compensation.load(args.model)
    if len(paths) + len(names) > 1:
        return _evaluate_several(
            args, strategy, [*((p, p, None) for p in paths), *((n, None, n) for n in names)]
        )
    recording, dataset = (paths or [None])[0], (names or [None])[0]
    where = dataset or str(recording)
    with progress_bar(f"reading {where}", ""):  # a dataset or a long bag takes seconds
        rec = read_recording(args, recording, dataset, args.truth, raw=_EVALUATE_RAW)
    fitted_on.check_fitted_on(strategy, rec, f"{args.model} on {where}", sensor=unit_of(rec))
    if rec.rig is None and not rec.has_trajectory:
        missing = io.recording.missing_reference(rec)
        if missing.needs == "truth_topic":  # a bag with several pose topics: name one
            raise missing
        raise SinsInputError(
            f"{where}: no reference to judge against; give the recording's trajectory with --truth TRUTH.csv"
        )
    title = f"{args.model} ({strategy.label}) on {where}"
    if rec.rig is not None:
        result = _evaluate_rig(args, strategy, rec.rig, where, title)
    else:
        result = _evaluate_referenced(args, strategy, rec.beside_reference(), title)
    if args.json:
        document = {"model": str(args.model), "strategy": strategy.label, "recording": where}
        io.write_report(args.json, {**document, **result.to_dict()})
    return 0


def _evaluate_several(
    args: argparse.Namespace, strategy: Strategy, inputs: list[tuple[str, str | None, str | None]]
) -> int:
    """Several recordings (``(name, path, dataset)``), each judged open loop as one would be, then each
    one's AOE and the mean. Every recording is read and checked before any is judged: a bad one is
    refused before minutes of work."""
    from sins import io
    from sins.compensation import evaluation, fitted_on

    one_only = {"--truth": args.truth, "--plot": args.plot, "--rerun": args.rerun, "--drive": args.drive}
    given = [flag for flag, value in one_only.items() if value]
    if given:
        raise SinsInputError(f"evaluate: {', '.join(given)}: for one recording, not for several")
    check_distinct([p for _, p, _ in inputs if p], [d for _, _, d in inputs if d], "evaluate")
    recordings = {}
    for name, path, dataset in inputs:
        with progress_bar(f"reading {name}", ""):
            rec = read_recording(args, path, dataset, raw=_EVALUATE_RAW)
        fitted_on.check_fitted_on(strategy, rec, f"{args.model} on {name}", sensor=unit_of(rec))
        if not rec.has_trajectory:
            raise SinsInputError(
                f"{name}: several recordings are judged open loop against their trajectories, and this one "
                "has none (judge a rig recording alone)"
            )
        recordings[name] = rec.beside_reference()
    judged = {
        name: _evaluate_referenced(args, strategy, rec, f"{args.model} ({strategy.label}) on {name}")
        for name, rec in recordings.items()
    }
    result = evaluation.across(judged, strategy.label)
    print("\n".join(result.lines))
    if args.json:
        io.write_report(args.json, {"model": str(args.model), "strategy": strategy.label, **result.to_dict()})
    return 0


def _evaluate_rig(
    args: argparse.Namespace, strategy: Strategy, data: CalibrationData, where: str, title: str
) -> Evaluation:
    """Per channel: RMS before and after, the bias left, and what is left beyond the white noise."""
    from sins.compensation import evaluation

    given = [f for f, v in (("--bias-from-rest", args.bias_from_rest), ("--drive", args.drive),
                            ("--outage", args.outage), ("--rerun", args.rerun)) if v]  # fmt: skip
    if given:  # --rerun had been ignored: no file, exit 0
        raise SinsInputError(f"{', '.join(given)}: against a trajectory only; {where} is a rig recording")
    with progress_bar("judging", ""):
        result = evaluation.evaluate_rig(strategy, data, title, last=args.last)
    assert result.channels is not None  # a rig's judgement is by channel
    for name, v in result.channels.items():
        check_finite(v, f"{args.model} on {where}: {name}")
    print("\n".join(result.lines))
    if args.plot:
        from sins.viz import plots

        channels = result.channels
        plot_title = f"{title}, {result.scope}"
        save_plot(args.plot, lambda: plots.evaluate_figure(channels, plot_title), plot_title)
    return result


def _evaluate_referenced(
    args: argparse.Namespace, strategy: Strategy, rec: ReferencedRecording, title: str
) -> Evaluation:
    """Open-loop attitude of the corrected gyro (and of the raw one, and with the bias from the opening
    rest), and with ``--drive`` the corrected unit's free-inertial drift over a window."""
    from sins.compensation import evaluation

    drive = None
    if args.drive:
        try:
            start, end = (float(x) for x in args.drive.split(":"))
        except ValueError:
            raise SinsInputError(f"--drive {args.drive!r}: expected START:END in seconds") from None
        if not start < end:
            raise SinsInputError(f"--drive {args.drive!r}: START must come before END")
        drive = (start, end)
    with progress_bar("open loop", "") as bar:
        result = evaluation.evaluate_referenced(
            strategy, rec, title, last=args.last, bias_from_rest=args.bias_from_rest, drive=drive,
            outage_s=tuple(args.outage or ()), stage=bar.set_description,
        )  # fmt: skip
    print("\n".join(result.lines))
    if args.rerun:
        from sins.viz import viewer as viz

        viz.save_open_loop(result.runs, args.rerun, summary=f"{title}\n\n{result.table}")
        print(f"wrote {args.rerun} (open it with: rerun {args.rerun})")
    if args.plot:
        from sins.viz import plots

        plot_title = f"{title}: open-loop attitude error"
        save_plot(args.plot, lambda: plots.open_loop_figure(result.runs, plot_title), plot_title)
    return result


def add(sub: Subparsers) -> None:
    """Add ``sins evaluate`` to ``sub``."""
    p = sub.add_parser(
        "evaluate",
        help="judge a fitted model: per channel on a rig recording, open loop against a trajectory",
    )
    p.add_argument("model", type=Path, metavar="MODEL.json")
    p.add_argument(
        "recording", nargs="*", metavar="RECORDING",
        help="a rig CSV, or a recording with --truth; several (each with its own reference, or beside "
        "--dataset): each judged open loop, then their mean AOE",
    )  # fmt: skip
    add_dataset(p, repeat="to judge several recordings open loop, then their mean AOE")
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
    p.add_argument(
        "--outage", type=positive, action="append", metavar="SECONDS",
        help="against a trajectory: also navigate free inertial for SECONDS from every second of the "
        "reference and give the horizontal error at each end (RMS, median, 95 %%); repeat for several",
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
