"""``sins integrate``: a recorded IMU integrated against its truth, or from a start it is given or aligns
on (no truth); the solution written if asked."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.cli.common import Subparsers, check_finite, check_outputs, check_plot, format_table, save_plot
from sins.cli.options import (
    add_dataset,
    add_plot,
    add_recording_options,
    dataset_inputs,
    finite,
    positive,
    read_recording,
    recording_options,
    vertical_tau,
)
from sins.cli.progress import progress_bar, row_progress
from sins.errors import MissingInputError, SinsInputError

if TYPE_CHECKING:
    from sins.core.series import NavSeries

#: ``--vertical``'s choices: :data:`sins.nav.vertical.VERTICAL_MODES`, written out so that the parser is
#: built without numpy (the test suite holds them equal).
VERTICAL_MODES = ("free", "hold", "damp")
#: ``--grade``'s choices: :data:`sins.imu.spec.GRADES` (held equal by the test suite).
GRADES = ("consumer", "industrial", "tactical", "navigation")
#: The hint a recording without a reference gets.
NO_REFERENCE = (
    "give it with --truth TRUTH.csv, or start without one from --origin LAT,LON,H with --attitude R,P,Y or "
    "--align SECONDS"
)


def _cmd_integrate(args: argparse.Namespace) -> int:
    from sins import io
    from sins.io import solution
    from sins.io.inspection import gaps_note
    from sins.runs import pipeline

    kinds = {"--out": solution.check_solution_path(args.out, "--out")} if args.out else None  # before work
    check_plot(args)
    inputs = [args.imu, args.truth, *dataset_inputs(args.dataset)]
    check_outputs({"--out": args.out, "--json": args.json, "--plot": args.plot}, inputs, kinds=kinds)
    if args.attitude is not None or args.align is not None:
        return _integrate_free(args)
    for flag, given in (("--heading", args.heading), ("--grade", args.grade)):
        if given is not None:
            raise SinsInputError(f"{flag} goes with --align SECONDS")
    if args.origin is not None and _free_options(args)["origin"] is None:  # a start, not a frame's place
        if args.truth is not None:  # it would have asked for --attitude, which --truth then refused
            raise SinsInputError("--origin starts a recording without a reference; --truth gives its start")
        raise SinsInputError(f"--origin starts {args.imu} without a reference: give --attitude R,P,Y or "
                             "--align SECONDS with it")  # fmt: skip
    with progress_bar("reading", "messages") as bar:  # a long bag takes a while (25,000 messages/s)
        try:
            read = read_recording(args, args.imu, args.dataset, args.truth, row_progress(bar))
            rec = pipeline.run_inputs(read, args.within_truth)
        except MissingInputError as exc:
            if exc.needs != "truth":  # a bag with several pose topics: the one to read, named
                raise
            raise SinsInputError(f"{exc}; {NO_REFERENCE}") from None
        bar.set_description("integrating")
        run = pipeline.navigate(rec.imu, rec.truth, args.vertical, vertical_tau(args, rec.imu.t))
    where = read.name
    if note := gaps_note(rec.imu.t):
        print(f"sins: note: {where}: {note}", file=sys.stderr)
    summary = run.summary.to_dict()
    against = args.truth or "its own reference"
    check_finite(summary, f"{where}: against {against}")
    if rec.before_truth:
        print(f"sins: note: {where}: the first {rec.before_truth} intervals come before {against} begins "
              f"at {rec.imu.t[0]:g} s; integrating from there", file=sys.stderr)  # fmt: skip
    if len(rec.imu) + rec.before_truth < rec.intervals:
        first = "" if rec.before_truth else "the first "
        print(f"sins: note: {where}: integrating {first}{len(rec.imu)} of {rec.intervals} intervals, to "
              f"{rec.imu.t[-1]:g} s where {against} ends (--within-truth)", file=sys.stderr)  # fmt: skip
    print(f"{where}: {len(rec.imu)} intervals against {against}; errors are estimate - truth")
    print(format_table({"none": summary}))
    if args.json:
        truth = None if args.truth is None else str(args.truth)
        io.write_report(args.json, {"imu": where, "truth": truth, **summary})
    _write_solution(args, run.solution, f"solution of {where} from {against}")
    if args.plot:
        from sins.viz import plots

        title = f"sins integrate {where} against {against}"
        save_plot(args.plot, lambda: plots.errors_figure({"none": run.errors}, title), title)
    return 0


def _write_solution(args: argparse.Namespace, sol: NavSeries, comment: str) -> None:
    from sins import __version__
    from sins.io import solution

    if not args.out:
        return
    with progress_bar(f"writing {args.out}", "") as bar:  # 360,000 rows of text take tens of seconds
        solution.write_solution(args.out, sol, comment=f"sins {__version__}: {comment}")
        bar.set_description(f"wrote {args.out}")
    print(f"wrote {args.out} ({len(sol.t)} rows)")


def _integrate_free(args: argparse.Namespace) -> int:
    """No reference: from ``--origin`` in ``--attitude``, or aligned on the opening rest (``--align``)."""
    from sins import io
    from sins.cli.bias import angles
    from sins.io.inspection import gaps_note
    from sins.runs import free_report, replay

    _check_free(args)
    with progress_bar("reading", "messages") as bar:
        rec = read_recording(args, args.imu, args.dataset, None, row_progress(bar), _free_options(args))
    where = rec.name
    if rec.has_trajectory:
        raise SinsInputError(
            f"{where}: the recording has its own reference; integrate it against that (without "
            "--attitude or --align)"
        )
    if note := gaps_note(rec.imu.t):
        print(f"sins: note: {where}: {note}", file=sys.stderr)
    origin = free_report.start_position(rec, recording_options(args)["origin"])
    imu = free_report.increments(rec)
    attitude = None if args.attitude is None else angles(args.attitude, "--attitude")
    heading = None if args.heading is None else math.radians(args.heading)
    with progress_bar("aligning" if args.align else "integrating", "") as bar:
        levels = free_report.grade_levels(args.grade)
        start = replay.free_start(imu, origin, attitude=attitude, align_s=args.align, heading=heading,
                                  levels=levels, source=where)  # fmt: skip
        bar.set_description("integrating")
        vertical = (args.vertical, vertical_tau(args, imu.t))
        sol = replay.navigate_free(imu, start, *vertical)
    free_report.check_solution(sol, where, args.vertical)  # NaN, inf: what likely took it there
    report = free_report.free_report(
        where, start, sol, args.align, args.grade, heading_given=args.heading is not None, vertical=vertical
    )
    print("\n".join(report.lines))
    if args.json:
        io.write_report(args.json, report.to_dict())
    _write_solution(args, sol, f"solution of {where} from {start.how} start")
    if args.plot:
        from sins.viz import plots

        title = f"sins integrate {where}: no reference, {start.how} start"
        growth = free_report.expected_growth(start, sol, vertical)
        save_plot(args.plot, lambda: plots.solution_figure(sol, title, growth), title)
    return 0


def _check_free(args: argparse.Namespace) -> None:
    """Refuse the combinations a start without a reference cannot use."""
    if args.attitude is not None and args.align is not None:
        raise SinsInputError("--attitude and --align exclude each other: a given attitude, or an alignment")
    if args.truth is not None:
        raise SinsInputError(
            "--attitude and --align start a recording without a reference; --truth gives one"
        )
    if args.align is None:
        for flag, given in (("--heading", args.heading), ("--grade", args.grade)):
            if given is not None:
                raise SinsInputError(f"{flag} goes with --align SECONDS")


def _free_options(args: argparse.Namespace) -> dict[str, Any]:
    """The reader's options: ``--origin`` goes to the readers that place a local frame (bags, EuRoC) and
    is the start for the others."""
    from sins.io.recording import recording_kind

    options = recording_options(args)
    if args.imu is not None and recording_kind(Path(args.imu)) in ("sins csv",):
        options["origin"] = None
    return options


def add(sub: Subparsers) -> None:
    """Add ``sins integrate`` to ``sub``."""
    p = sub.add_parser(
        "integrate", help="integrate a recorded IMU against its truth, or from a given or aligned start"
    )
    p.add_argument("imu", type=Path, nargs="?", metavar="RECORDING")
    add_dataset(p)
    p.add_argument(
        "--truth", type=Path, metavar="TRUTH.csv", help="the truth (default: the recording's own reference)"
    )
    p.add_argument("--json", type=Path, metavar="OUT.json", help="write the drift summary as JSON")
    p.add_argument(
        "--out", type=Path, metavar="SOLUTION.csv|.parquet",
        help="write the solution, one row per IMU time: t, lat_deg, lon_deg, h_m, vn, ve, vd, roll_deg, "
        "pitch_deg, yaw_deg "
        "(s, °, °, m, m/s NED, ° ZYX), the columns of a truth file",
    )  # fmt: skip
    p.add_argument(
        "--within-truth", action="store_true",
        help="integrate only the IMU intervals inside the truth's span (without it, an IMU that starts "
        "before or runs past a truth file is refused; past the recording's own reference, a tail of up to "
        "1 s or 1 %% of the recording is cut with a note, a longer one refused; readings before the "
        "recording's own reference begins are left out with a note)",
    )  # fmt: skip
    p.add_argument(
        "--vertical", choices=VERTICAL_MODES, default="free",
        help="vertical channel: free inertial, held to, or damped towards the truth height (the start's "
        "without a truth)",
    )  # fmt: skip
    p.add_argument("--vertical-tau-s", type=positive, metavar="S",
                   help="time constant of 'damp', s (default 10)")  # fmt: skip
    g = p.add_argument_group(
        "without a reference",
        "start a unit at rest at --origin LAT,LON,H (default: a bag's first fix) in a given attitude, or "
        "in the one its opening rest implies",
    )
    g.add_argument(
        "--attitude", metavar="R,P,Y", help="the start's roll, pitch, yaw, degrees (yaw from north)"
    )
    g.add_argument(
        "--align", type=positive, metavar="SECONDS",
        help="align on the first SECONDS at rest (roll and pitch from the accelerometers, the heading by "
        "gyrocompassing where the gyros resolve it) and navigate from there; the accuracy is printed",
    )  # fmt: skip
    g.add_argument(
        "--heading",
        type=finite,
        metavar="DEG",
        help="with --align: the heading, where the gyros cannot find it",
    )
    g.add_argument(
        "--grade", choices=GRADES,
        help="with --align: the unit's grade, whose bias levels the stated accuracy counts (default: the "
        "noise's part alone)",
    )  # fmt: skip
    add_plot(p, "the errors (without a reference: the solution and the growth its rest's biases predict)")
    add_recording_options(p)
    p.set_defaults(func=_cmd_integrate)


__all__ = [
    "GRADES",
    "NO_REFERENCE",
    "VERTICAL_MODES",
    "add",
]
