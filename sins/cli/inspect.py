"""``sins inspect``: a recording's rate, jitter, gaps, clipping, and the unit and frame mistakes it shows."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from sins.cli.common import Subparsers, check_outputs
from sins.cli.options import add_dataset, add_recording_options, dataset_inputs, read_recording
from sins.cli.progress import progress_bar, row_progress

if TYPE_CHECKING:
    from sins.io.inspection import Finding, Inspection
    from sins.io.recording import Recording

#: The flag each reader option is given with.
FLAGS = {"units": "--units", "frame": "--frame", "columns": "--columns", "rate": "--rate", "topic": "--topic"}


def _cmd_inspect(args: argparse.Namespace) -> int:
    from sins import io
    from sins.io import inspection

    check_outputs({"--json": args.json}, [args.recording, *dataset_inputs(args.dataset)])
    with progress_bar("reading", "messages") as bar:
        rec = read_recording(args, args.recording, args.dataset, progress=row_progress(bar))
    result = inspection.inspect(rec)
    print(format_inspection(rec, result))
    if args.json:
        io.write_report(
            args.json, {"format": "sins-inspection", **result.to_dict(), "notes": list(rec.notes)}
        )
    return 0


def format_inspection(rec: Recording, result: Inspection) -> str:
    """The report: what was read, the figures, then each likely mistake with what to pass instead."""
    lines = [
        f"{result.source}: {rec.kind}, {result.form} form, {result.rows} rows over {result.span_s:.6g} s "
        f"at {result.rate_hz:.6g} Hz (interval jitter {100 * result.jitter:.2f} % RMS), "
        f"{len(result.gaps)} gap(s)"
    ]
    lines += [f"  {note}" for note in rec.notes]
    if result.rest is None:
        lines.append("at rest: no stretch of two seconds or more found")
    else:
        r = result.rest
        resolved = "" if r.rate_resolved else ", not resolved"
        lines.append(
            f"at rest {r.seconds:.4g} s: |f| {r.gravity_ratio:.4g} × gravity (9.806 m/s²), |ω| "
            f"{r.earth_rate_ratio:.3g} × Earth's rate (7.29e-5 rad/s{resolved})"
        )
    if result.axes is not None:
        lines.append(f"axes as the data show them (after the reading): {result.axes} (_: not shown)")
    if result.reference_lag is not None:
        from sins.io import frame_check  # read by now: the recording was

        lag = result.reference_lag
        lines.append(
            f"the reference's clock: {frame_check.clock_sits(lag.lag_s)} (its turns agree best with the "
            f"gyro's there, correlation {lag.agreement:.4f}; {lag.as_stamped:.4f} as stamped)"
        )
    if not result.findings:
        lines.append("no likely mistakes found")
        return "\n".join(lines)
    lines.append(f"{len(result.findings)} likely mistake(s):")
    lines += [f"  {_finding(f)}" for f in result.findings]
    return "\n".join(lines)


def _finding(f: Finding) -> str:
    if f.option is not None:
        return f"{f.code}: {f.what}; pass {FLAGS.get(f.option, '--' + f.option)} {f.value}"
    return f"{f.code}: {f.what}; {f.advice}"


def add(sub: Subparsers) -> None:
    """Add ``sins inspect`` to ``sub``."""
    p = sub.add_parser(
        "inspect",
        help="a recording's rate, gaps, clipping and likely unit and frame mistakes, found from its data",
    )
    p.add_argument("recording", type=Path, nargs="?", metavar="RECORDING")
    add_dataset(p)
    p.add_argument("--json", type=Path, metavar="OUT.json", help="write the figures and findings (SI units)")
    add_recording_options(p)
    p.set_defaults(func=_cmd_inspect)


__all__ = [
    "FLAGS",
    "add",
    "format_inspection",
]
