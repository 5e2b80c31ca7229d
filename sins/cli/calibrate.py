"""``sins calibrate``: a simulated calibration-rig session written as a recording."""

from __future__ import annotations

import argparse
from pathlib import Path

from sins import __version__
from sins.cli.common import Subparsers, check_outputs, simulated_unit
from sins.cli.options import seed
from sins.cli.progress import progress_bar, row_progress


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from sins import io, scenario
    from sins.imu import calibration
    from sins.scenario.budget import check_rig_size

    rig_path = scenario.resolve_preset(args.rig, "rig")
    rig = scenario.load_rig(rig_path)
    imu_path = scenario.resolve_preset(args.imu, "imu")
    spec = scenario.load_imu(imu_path)
    check_outputs({"--out": args.out}, [rig_path, imu_path])
    check_rig_size(rig, rig_path, {args.out: len(io.RECORDING_COLUMNS) + 2})
    data = calibration.simulate_rig(rig, spec.model(run_seed=args.seed), seed=args.seed)
    note = (
        f"sins {__version__}: simulated rig {args.rig} with IMU {args.imu}, seed {args.seed}\n"
        f"effects: {', '.join(spec.model(run_seed=args.seed).names) or 'none'}\n"
        f"sensor: {simulated_unit(imu_path)}"
    )
    with progress_bar(f"writing {args.out}", "row") as bar:
        io.write_recording(args.out, data, comment=note, progress=row_progress(bar))
    print(
        f"wrote {args.out}: {len(data)} rows, {data.t[-1] - data.t[0]:.1f} s at {rig.rate_hz:g} Hz, "
        f"{len(data.phases)} phases"
    )
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins calibrate`` to ``sub``."""
    p = sub.add_parser("calibrate", help="simulate a calibration rig session and write the recording")
    p.add_argument("rig", metavar="RIG.toml", help="rig file or preset (e.g. 24pos_ratetable)")
    p.add_argument("--imu", required=True, metavar="IMU.toml", help="IMU file or preset (e.g. tactical)")
    p.add_argument("--out", type=Path, required=True, metavar="RECORDING.csv")
    p.add_argument(
        "--seed",
        type=seed,
        default=0,
        metavar="N",
        help="seeds the rig's errors and the IMU's run (default 0)",
    )
    p.set_defaults(func=_cmd_calibrate)


__all__ = [
    "add",
]
