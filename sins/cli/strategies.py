"""``sins strategies``: the compensation strategies ``sins fit`` knows, one name a line."""

from __future__ import annotations

import argparse

from sins.cli.common import Subparsers


def _cmd_strategies(args: argparse.Namespace) -> int:
    from sins.compensation import DESCRIPTIONS

    width = max(map(len, DESCRIPTIONS))
    for name, what in DESCRIPTIONS.items():
        print(f"{name:<{width}}  {what}" if args.long else name)
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins strategies`` to ``sub``."""
    p = sub.add_parser("strategies", help="list the compensation strategies sins fit knows, one a line")
    p.add_argument("--long", action="store_true", help="say what each one is beside its name")
    p.set_defaults(func=_cmd_strategies)


__all__ = [
    "add",
]
