"""``sins evaluate``: a fitted model judged on a recording, channel by channel."""

from __future__ import annotations

import argparse
from pathlib import Path

from sins.cli.common import Subparsers, add_plot, check_finite, check_plot, display_unit, fraction, save_plot
from sins.errors import SinsInputError


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from sins import compensation, io

    check_plot(args)
    strategy = compensation.load(args.model)
    data = io.read_recording(args.recording)
    io.check_recording_range(args.recording, data)
    if args.last:
        try:
            _, data = data.split(args.last)
        except ValueError as exc:
            raise SinsInputError(f"{args.recording}: {exc}") from None
    channels = compensation.residual_rms(strategy, data)
    for name, v in channels.items():
        check_finite(v, f"{args.model} on {args.recording}: {name}")
    scope = f"the last {args.last:g} of each phase" if args.last else "the whole recording"
    print(f"{args.model} ({strategy.name}) on {args.recording}, {scope}: RMS of reading - reference")
    print(f"{'channel':<8} {'before':>12} {'after':>12}  unit")
    for name, v in channels.items():
        size, unit = display_unit(name)
        print(f"{name:<8} {v['rms_before'] / size:12.4f} {v['rms_after'] / size:12.4f}  {unit}")
    if args.json:
        io.write_json(
            args.json, {"model": str(args.model), "recording": str(args.recording), "channels": channels}
        )
    if args.plot:
        from sins import plots

        title = f"{args.model} ({strategy.name}) on {args.recording}, {scope}"
        save_plot(args.plot, lambda: plots.evaluate_figure(channels, title), title)
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins evaluate`` to ``sub``."""
    p = sub.add_parser("evaluate", help="RMS reading error per channel before and after a fitted model")
    p.add_argument("model", type=Path, metavar="MODEL.json")
    p.add_argument("recording", type=Path, metavar="RECORDING.csv")
    p.add_argument(
        "--last", type=fraction, metavar="FRACTION",
        help="judge only the last FRACTION of every phase (of the whole recording if it has no phases)",
    )  # fmt: skip
    p.add_argument("--json", type=Path, metavar="OUT.json")
    add_plot(p, "the RMS error per channel before and after")
    p.set_defaults(func=_cmd_evaluate)
