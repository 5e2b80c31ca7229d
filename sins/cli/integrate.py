"""``sins integrate``: a recorded IMU integrated against its truth; the solution written if asked."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from sins.cli.common import (
    Subparsers,
    add_recording_options,
    check_finite,
    check_outputs,
    format_table,
    positive,
    progress_bar,
    recording_options,
    row_progress,
)
from sins.nav.vertical import VERTICAL_MODES


def _cmd_integrate(args: argparse.Namespace) -> int:
    from sins import io, pipeline
    from sins.io import solution

    if args.out:
        solution.check_solution_path(args.out)  # before the work, not after
    check_outputs({"--out": args.out, "--json": args.json}, [args.imu, args.truth])
    with progress_bar("reading", "messages") as bar:  # a long bag takes a while (25,000 messages/s)
        reading = {**recording_options(args), "progress": row_progress(bar)}
        rec = pipeline.load_recording(args.imu, args.truth, args.within_truth, reading)
    run = pipeline.navigate(rec.imu, rec.truth, args.vertical, args.vertical_tau_s)
    summary = run.summary.to_dict()
    against = args.truth or "its own reference"
    check_finite(summary, f"{args.imu}: against {against}")
    if len(rec.imu) < rec.intervals:
        print(
            f"sins: note: {args.imu}: integrating the first {len(rec.imu)} of {rec.intervals} intervals, "
            f"to {rec.imu.t[-1]:g} s where {against} ends (--within-truth)",
            file=sys.stderr,
        )
    print(f"{args.imu}: {len(rec.imu)} intervals against {against}; errors are estimate - truth")
    print(format_table({"none": summary}))
    if args.json:
        truth = None if args.truth is None else str(args.truth)
        io.write_json(args.json, {"imu": str(args.imu), "truth": truth, **summary})
    if args.out:
        solution.write_solution(args.out, run.solution, comment=f"solution of {args.imu} from {against}")
        print(f"wrote {args.out} ({len(run.solution.t)} rows)")
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins integrate`` to ``sub``."""
    p = sub.add_parser("integrate", help="integrate a recorded IMU against its truth")
    p.add_argument("imu", type=Path, metavar="RECORDING")
    p.add_argument(
        "--truth", type=Path, metavar="TRUTH.csv", help="the truth (default: the recording's own reference)"
    )
    p.add_argument("--json", type=Path, metavar="OUT.json")
    p.add_argument(
        "--out", type=Path, metavar="SOLUTION.csv|.parquet",
        help="write the solution, one row per IMU time: t, lat_deg, lon_deg, h_m, vn, ve, vd, roll_deg, "
        "pitch_deg, yaw_deg "
        "(s, °, °, m, m/s NED, ° ZYX), the columns of a truth file",
    )  # fmt: skip
    p.add_argument(
        "--within-truth", action="store_true",
        help="integrate only the IMU intervals inside the truth's span (without it, an IMU that runs past "
        "a truth file's end is refused; past the recording's own reference, a tail of up to 1 s or 1 %% of "
        "the recording is cut with a note, a longer one refused)",
    )  # fmt: skip
    p.add_argument(
        "--vertical",
        choices=VERTICAL_MODES,
        default="free",
        help="vertical channel: free inertial, held to, or damped towards the truth height",
    )
    p.add_argument(
        "--vertical-tau-s", type=positive, default=10.0, help="time constant of 'damp', s (default 10)"
    )
    add_recording_options(p)
    p.set_defaults(func=_cmd_integrate)


__all__ = [
    "add",
]
