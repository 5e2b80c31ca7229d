"""``sins integrate``: a recorded IMU file integrated against its truth."""

from __future__ import annotations

import argparse
from pathlib import Path

from sins.cli.common import (
    Subparsers,
    add_recording_options,
    check_finite,
    format_table,
    positive,
    progress_bar,
    recording_options,
    row_progress,
)
from sins.nav.vertical import VERTICAL_MODES


def _cmd_integrate(args: argparse.Namespace) -> int:
    from sins import io, pipeline

    with progress_bar("reading", "messages") as bar:  # a long bag takes a while (25,000 messages/s)
        reading = {**recording_options(args), "progress": row_progress(bar)}
        run = pipeline.integrate_recording(args.imu, args.truth, args.vertical, args.vertical_tau_s, reading)
    summary = run.summary.to_dict()
    against = args.truth or "its own reference"
    check_finite(summary, f"{args.imu}: against {against}")
    print(f"{args.imu}: {len(run.solution.t) - 1} intervals against {against}; errors are estimate - truth")
    print(format_table({"none": summary}))
    if args.json:
        truth = None if args.truth is None else str(args.truth)
        io.write_json(args.json, {"imu": str(args.imu), "truth": truth, **summary})
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
