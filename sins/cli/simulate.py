"""``sins simulate``: a scenario's IMU readings and truth written as CSV."""

from __future__ import annotations

import argparse
from pathlib import Path

from sins import __version__
from sins.cli.common import Subparsers, progress_bar, row_progress
from sins.scenario.budget import check_scenario_size


def _cmd_simulate(args: argparse.Namespace) -> int:
    from sins import io, pipeline, scenario
    from sins.nav import trajectory

    path = pipeline.resolve_scenario(args.scenario)
    sc = scenario.load(path)
    columns = len(io.RATE_COLUMNS if args.form == "rate" else io.INCREMENT_COLUMNS)
    check_scenario_size(sc, path, "simulating", {args.imu: columns, args.truth: len(io.TRUTH_COLUMNS)})
    truth, imu = pipeline.simulate(sc)
    scenario.check_latitude(sc, truth)
    note = f"sins {__version__}: ideal IMU of scenario {sc.name} ({path})"
    samples = trajectory.ideal_rates(scenario.build_motion(sc), truth) if args.form == "rate" else imu
    with progress_bar(f"writing {args.imu}", "row") as bar:
        io.write_imu(args.imu, samples, comment=note, progress=row_progress(bar))
    with progress_bar(f"writing {args.truth}", "row") as bar:
        io.write_truth(args.truth, truth, comment=note, progress=row_progress(bar))
    print(f"wrote {args.imu} ({args.form} form, {len(samples)} rows) and {args.truth} ({len(truth)} rows)")
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins simulate`` to ``sub``."""
    p = sub.add_parser("simulate", help="write a scenario's ideal IMU and truth as CSV")
    p.add_argument("scenario", nargs="?", help="scenario file or preset name (default: car_drive)")
    p.add_argument("--imu", type=Path, required=True, metavar="IMU.csv")
    p.add_argument("--truth", type=Path, required=True, metavar="TRUTH.csv")
    p.add_argument("--form", choices=("increment", "rate"), default="increment")
    p.set_defaults(func=_cmd_simulate)
