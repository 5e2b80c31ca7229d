"""``sins fit``: a compensation strategy fitted on a recording and saved as a model file."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from sins.cli.common import Subparsers, check_outputs, unit_of
from sins.cli.options import (
    add_dataset,
    add_recording_options,
    check_distinct,
    dataset_inputs,
    fraction,
    positive,
    read_recording,
)
from sins.cli.progress import progress_bar, row_progress
from sins.errors import SinsInputError

#: The classes of unit ``--grade`` takes (``sins.imu.spec.GRADES``, written out: importing it would slow
#: every command's start).
GRADES = ("consumer", "industrial", "tactical", "navigation")

if TYPE_CHECKING:
    from sins.compensation.fitting import FitOutcome

#: Why a fit refuses readings a model corrected already (:func:`sins.cli.options.read_recording`).
_FIT_RAW = "a model fitted on them is of what that correction left, and would pass for the unit's whole model"


def _cmd_fit(args: argparse.Namespace) -> int:
    from sins import compensation, io

    _check_args(args)
    datasets = [*(args.dataset or [])]
    read = [*args.recording, args.truth, *(p for d in datasets for p in dataset_inputs(d))]
    # Before a fit that may take minutes; the model is one whatever its name.
    check_outputs({"--out": args.out, "--json": args.json}, read, kinds={"--out": "sins.compensation"})
    sources = [*args.recording, *datasets]
    if not sources:
        raise SinsInputError("give a RECORDING or --dataset NAME (once per recording to fit on several)")
    if len(sources) > 1:
        outcome = _fit_several(args)
        where = " + ".join(sources)
    else:
        recording = args.recording[0] if args.recording else None
        dataset = args.dataset[0] if args.dataset else None
        where = dataset or str(recording)
        outcome = _fit_one(args, recording, dataset, where)
    print("\n".join(outcome.lines))
    compensation.save(outcome.strategy, args.out)
    if args.json:
        io.write_report(args.json, {"model": str(args.out), "recording": where, **outcome.to_dict()})
    print(f"wrote {args.out}")
    return 0


def _fit_several(args: argparse.Namespace) -> FitOutcome:
    """Several recordings of one unit: each read with its own reference, then one fit on all of them."""
    from sins.compensation import fitting

    if args.truth is not None:
        raise SinsInputError(
            "--truth goes with one RECORDING; to fit on several, give recordings with their "
            "own references (a dataset, an .npz, a bag or EuRoC folder with ground truth)"
        )
    if args.validation:
        raise SinsInputError(
            "--validation holds back part of one recording; to judge a fit on several, "
            "leave recordings out of it and judge them with sins evaluate"
        )
    recs = []
    named = [("path", r) for r in args.recording] + [("dataset", d) for d in args.dataset or []]
    check_distinct(list(args.recording), list(args.dataset or []), "fit")
    with progress_bar(f"fitting {args.strategy}", "") as bar:
        for kind, name in named:
            bar.set_description(f"reading {name}")
            if kind == "path":
                got = read_recording(args, name, None, raw=_FIT_RAW)
            else:  # the format options given are for the paths beside it
                got = read_recording(args, None, name)  # a reader option not applying: refused
            if got.rig is not None or not got.has_trajectory:
                raise SinsInputError(
                    f"{name}: a fit on several recordings needs each beside its reference trajectory (a "
                    "rig recording or a recording without a reference cannot be one of them)"
                )
            recs.append(got.beside_reference())
        return fitting.fit_several(
            args.strategy, recs, [n for _, n in named], interval_s=args.interval_s, guard=not args.no_guard,
            rule_mode=args.bias_rule, grade=args.grade, progress=row_progress(bar), stage=bar.set_description,
            screen=args.screen,
        )  # fmt: skip


def _check_args(args: argparse.Namespace) -> None:
    """Refuse what cannot work before reading anything."""
    if args.strategy == "oracle":
        raise SinsInputError(
            "the oracle knows a simulated unit's true model; it cannot be fitted to a recording"
        )
    from sins.compensation import network_guard, strategy_names

    if args.strategy not in strategy_names():
        raise SinsInputError(
            f"unknown strategy {args.strategy!r} (known: {', '.join(strategy_names())}; "
            "sins strategies lists them)"
        )
    if not args.no_guard:
        return
    guarded = strategy_names(taking="guard")  # imports them all: only where --no-guard is given
    several = len(args.recording) + len(args.dataset or []) > 1
    if args.strategy not in guarded and not (several and network_guard.guards(args.strategy)):
        raise SinsInputError(
            f"--no-guard: {args.strategy} has no guard (only {', '.join(guarded)} do; "
            "mlp_pure, mlp_seed and kohonen_pure on several recordings)"
        )


def _fit_one(args: argparse.Namespace, recording: str | None, dataset: str | None, where: str) -> FitOutcome:
    """One recording: a rig session's rows, or a recording beside its reference trajectory."""
    from sins import io
    from sins.compensation import fitting

    with progress_bar(f"reading {where}", ""):  # a dataset or a long bag takes seconds
        rec = read_recording(args, recording, dataset, args.truth, raw=_FIT_RAW)
    if rec.rig is not None:
        if args.screen != "refused":
            raise SinsInputError(
                f"--screen {args.screen}: {where} is a rig recording, fitted on its rows, which are not "
                "screened"
            )
        with progress_bar(f"fitting {args.strategy}", fitting.progress_unit(args.strategy)) as bar:
            return fitting.fit_rig(
                args.strategy, rec.rig, where=where, sensor=unit_of(rec),
                validation=args.validation, guard=not args.no_guard, grade=args.grade,
                progress=row_progress(bar),
            )  # fmt: skip
    if rec.has_trajectory:
        with progress_bar(f"fitting {args.strategy}", "training") as bar:
            return fitting.fit_referenced(
                args.strategy, rec.beside_reference(), where=where, validation=args.validation,
                interval_s=args.interval_s, guard=not args.no_guard, grade=args.grade,
                progress=row_progress(bar), screen=args.screen,
            )  # fmt: skip
    missing = io.recording.missing_reference(rec)
    if missing.needs == "truth_topic":  # a bag with several pose topics: name one
        raise missing
    raise SinsInputError(
        f"{where}: no reference to fit against; give the recording's trajectory with --truth "
        "TRUTH.csv (or a rig recording with ref_ columns, or a bag or EuRoC folder with ground truth)"
    )


def add(sub: Subparsers) -> None:
    """Add ``sins fit`` to ``sub``."""
    p = sub.add_parser(
        "fit", help="fit a compensation strategy on a rig recording or a recording beside its reference"
    )
    p.add_argument(
        "recording", nargs="*", metavar="RECORDING",
        help="a rig CSV, or a recording with --truth or its own reference; several recordings of one unit "
        "(each with its own reference) are fitted together",
    )  # fmt: skip
    add_dataset(p, repeat="to fit on several recordings of one unit")
    p.add_argument(
        "--truth", type=Path, metavar="TRUTH.csv",
        help="the recording's reference trajectory (attitude and velocity): the fit is made on intervals",
    )  # fmt: skip
    p.add_argument(
        "--strategy", required=True,
        help="the strategy to fit: sins strategies lists them (regression, mlp, kohonen, ...)",
    )  # fmt: skip
    p.add_argument(
        "--validation", type=fraction, metavar="FRACTION",
        help="hold back the last FRACTION of every phase (of the whole recording if it has no phases)",
    )  # fmt: skip
    p.add_argument(
        "--interval-s", type=positive, default=1.0, metavar="S",
        help="against a reference trajectory: the interval between the reference epochs compared (default 1)",
    )  # fmt: skip
    p.add_argument(
        "--no-guard", action="store_true",
        help="mlp, kohonen, mlp_window: use the learned correction on every channel, even where it does not "
        "beat regression on held-back blocks (recordings); mlp_pure, mlp_seed, kohonen_pure on several "
        "recordings: write the network without judging it against regression on held-back recordings",
    )  # fmt: skip
    p.add_argument(
        "--screen", choices=("refused", "always", "never"), default="refused",
        help="against a reference trajectory: when intervals a robust fit puts beyond 20 robust standard "
        "deviations are set aside as the reference's gross errors (a glitch, a gap filled by interpolation): "
        "where the fit is refused without (default), before every fit, or never (nor spans the reference "
        "alone shows filled by interpolation, set aside otherwise)",
    )  # fmt: skip
    p.add_argument(
        "--grade", choices=GRADES, default="consumer",
        help="the class of unit recorded: what its coefficients can be, and how well the data must determine "
        "them to be fitted rather than held at zero (default consumer, the loosest; guide: compensation)",
    )  # fmt: skip
    p.add_argument(
        "--bias-rule", choices=("pooled", "rest", "online", "rest+online", "nearest", "nearest+online"),
        help="several recordings: how a new recording's gyro bias is taken (default: the one that does best "
        "on held-back recordings, the online modes also from a mixture of the training recordings' biases; "
        "the gyro left as read where each leaves one worse than its raw readings)",
    )  # fmt: skip
    p.add_argument(
        "--json", type=Path, metavar="OUT.json", help="also write the coefficients and the fit's figures"
    )
    p.add_argument("--out", type=Path, required=True, metavar="MODEL.json")
    add_recording_options(p)
    p.set_defaults(func=_cmd_fit)


__all__ = [
    "GRADES",
    "add",
]
