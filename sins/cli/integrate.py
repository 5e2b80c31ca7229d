"""``sins integrate``: a recorded IMU file integrated against its truth."""

from __future__ import annotations

import argparse
from pathlib import Path

from sins.cli.common import Subparsers, check_finite, format_table, positive
from sins.nav.vertical import VERTICAL_MODES


def _cmd_integrate(args: argparse.Namespace) -> int:
    from sins import io, pipeline

    run = pipeline.integrate_recording(args.imu, args.truth, args.vertical, args.vertical_tau_s)
    summary = run.summary.to_dict()
    check_finite(summary, f"{args.imu}: against {args.truth}")
    print(
        f"{args.imu}: {len(run.solution.t) - 1} intervals against {args.truth}; errors are estimate - truth"
    )
    print(format_table({"none": summary}))
    if args.json:
        io.write_json(args.json, {"imu": str(args.imu), "truth": str(args.truth), **summary})
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins integrate`` to ``sub``."""
    p = sub.add_parser("integrate", help="integrate a recorded IMU CSV against its truth CSV")
    p.add_argument("imu", type=Path, metavar="IMU.csv")
    p.add_argument("--truth", type=Path, required=True, metavar="TRUTH.csv")
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
    p.set_defaults(func=_cmd_integrate)
