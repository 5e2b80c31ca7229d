"""``sins scenarios``: the presets shipped with sins."""

from __future__ import annotations

import argparse

from sins.cli.common import Subparsers


def _cmd_scenarios(args: argparse.Namespace) -> int:
    from sins import scenario
    from sins.runs import pipeline

    shipped = scenario.presets()
    width = max(map(len, shipped), default=0)
    for name, path in shipped.items():
        sc = scenario.load(path)
        marker = " (default)" if name == pipeline.DEFAULT_SCENARIO else ""
        print(f"{name:<{width}}  {sc.description}{marker}")
    print(f"rig procedures (sins calibrate RIG): {', '.join(scenario.presets('rig'))}")
    imu_models = ", ".join(scenario.presets("imu"))
    print(f"IMU models (run and calibrate --imu, simulate and gap --model): {imu_models}")
    print(f"campaigns (sins campaign NAME): {', '.join(scenario.presets('campaign'))}")
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins scenarios`` to ``sub``."""
    p = sub.add_parser("scenarios", help="list the preset scenarios shipped with sins")
    p.set_defaults(func=_cmd_scenarios)


__all__ = [
    "add",
]
