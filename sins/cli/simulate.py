"""``sins simulate``: a scenario's IMU readings (its unit's, or the ideal ones) and truth written as CSV."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from sins import __version__
from sins.cli.common import Subparsers, check_outputs, scenario_inputs, simulated_unit
from sins.cli.options import seed
from sins.cli.progress import progress_bar, row_progress
from sins.errors import SinsInputError


def _cmd_simulate(args: argparse.Namespace) -> int:
    from sins import io, scenario
    from sins.runs import pipeline
    from sins.scenario.budget import check_scenario_size

    if args.ideal and (args.model or args.seed is not None):
        raise SinsInputError("--ideal: the ideal IMU has no unit to draw; leave out --model and --seed")
    path = pipeline.resolve_scenario(args.scenario)
    sc = pipeline.with_unit(scenario.load(path), args.model, args.seed)
    check_outputs({"--imu": args.imu, "--truth": args.truth}, scenario_inputs(sc))
    columns = len(io.RATE_COLUMNS if args.form == "rate" else io.INCREMENT_COLUMNS) + 1
    check_scenario_size(sc, path, "simulating", {args.imu: columns, args.truth: len(io.TRUTH_COLUMNS)})
    with progress_bar(f"simulating {sc.name}", ""):
        sim = pipeline.simulate_readings(sc, args.form, ideal=args.ideal)
    scenario.check_latitude(sc, sim.truth)
    if note := scenario.unsampled_end(sc):
        print(f"sins: note: {path}: {note}", file=sys.stderr)
    unit = "ideal IMU" if sim.model is None else f"IMU {sim.model.stem} (power-on seed {sim.seed})"
    model = "" if sim.model is None else f", IMU file {sim.model}"
    note = f"sins {__version__}: {unit} of scenario {sc.name} ({path}{model})"
    truth_note = f"sins {__version__}: truth of scenario {sc.name} ({path}), beside {args.imu.name}'s"
    note += f"\nsensor: {simulated_unit(sim.model)}"  # the readings', not the truth's
    extra = None if sim.temp is None else {"temp": sim.temp}
    with progress_bar(f"writing {args.imu}", "row") as bar:
        io.write_imu(args.imu, sim.readings, extra, comment=note, progress=row_progress(bar))
    with progress_bar(f"writing {args.truth}", "row") as bar:
        io.write_truth(args.truth, sim.truth, comment=truth_note, progress=row_progress(bar))
    print(
        f"wrote {args.imu} ({args.form} form, {len(sim.readings)} rows, {unit}) and {args.truth} "
        f"({len(sim.truth)} rows)"
    )
    if sc.vertical != "free":  # sins integrate's default is free: say how to integrate as sins run does
        tau = f" --vertical-tau-s {sc.vertical_tau_s:g}" if sc.vertical == "damp" else ""
        flags = f"--vertical {sc.vertical}{tau}"
        print(f"sins: note: the scenario's vertical channel is {sc.vertical}: sins integrate {args.imu} "
              f"--truth {args.truth} {flags} integrates as sins run does", file=sys.stderr)  # fmt: skip
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins simulate`` to ``sub``."""
    p = sub.add_parser(
        "simulate", help="write the readings of a scenario's IMU (its [imu] model, or ideal) and the truth"
    )
    p.add_argument("scenario", nargs="?", help="scenario file or preset name (default: car_drive)")
    p.add_argument("--imu", type=Path, required=True, metavar="IMU.csv", help="the readings to write")
    p.add_argument("--truth", type=Path, required=True, metavar="TRUTH.csv", help="the truth to write")
    p.add_argument("--form", choices=("increment", "rate"), default="increment")
    p.add_argument(
        "--model", metavar="GRADE|IMU.toml",
        help="the unit that reads: an IMU preset (consumer, industrial, tactical, navigation, ...) or file, "
        "instead of the scenario's [imu] model",
    )  # fmt: skip
    p.add_argument("--seed", type=seed, metavar="N", help="the unit's power-on, instead of [imu] seed")
    p.add_argument(
        "--ideal", action="store_true", help="write the exact ideal readings, not the scenario unit's"
    )
    p.set_defaults(func=_cmd_simulate)


__all__ = [
    "add",
]
