"""``sins effects``: the IMU error effects, their parameters and units."""

from __future__ import annotations

import argparse

from sins.cli.common import Subparsers


def _cmd_effects(args: argparse.Namespace) -> int:
    from sins import imu
    from sins.imu import spec as imu_spec

    for name, spec in imu_spec.PARAMETERS.items():
        params = ", ".join(f"{p.key} [{p.unit}]" for p in spec.params)
        marker = "  (baseline)" if name in imu.BASELINE else ""
        print(f"{name:<26} {spec.description}{marker}\n{'':<26} {params}")
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins effects`` to ``sub``."""
    p = sub.add_parser("effects", help="list the IMU error effects, their parameters and units")
    p.set_defaults(func=_cmd_effects)
