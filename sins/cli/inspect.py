"""``sins inspect``: a recording's rate, jitter, gaps, clipping, and the unit and frame mistakes it shows;
beside a reference trajectory, how its clock sits and how its world frame stands against gravity."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from sins.cli.common import Subparsers, check_outputs
from sins.cli.options import add_dataset, add_recording_options, dataset_inputs, read_recording
from sins.cli.progress import progress_bar, row_progress

if TYPE_CHECKING:
    from sins.compensation.world_tilt import WorldTilt
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
    with progress_bar("the reference's world frame against gravity", ""):  # a fit on its intervals
        tilt = reference_tilt(rec, result)
    print(format_inspection(rec, result, tilt))
    if args.json:
        io.write_report(
            args.json,
            {
                "format": "sins-inspection", **result.to_dict(), "notes": list(rec.notes),
                "reference_tilt": None if tilt is None else tilt.to_dict(),
            },
        )  # fmt: skip
    return 0


def reference_tilt(rec: Recording, result: Inspection) -> WorldTilt | None:
    """How the reference's world frame stands against gravity, as ``sins fit`` and ``sins gap`` read it
    (:func:`sins.compensation.world_tilt.levelled`: its filled spans set aside), where the recording has
    a reference whose attitude is of the readings' axes (its clock found: ``result.reference_lag``);
    None elsewhere. A floor-set frame 0.5° from level puts 9 mg of gravity in its horizontal axes, which
    every fit against it would read as the accelerometer's (EuRoC's second Vicon room: 0.55-0.57°)."""
    if result.reference_lag is None:
        return None
    from sins.compensation import world_tilt
    from sins.errors import SinsInputError

    try:
        referenced = rec.beside_reference()
    except SinsInputError:  # a reference apart from the readings: nothing to stand it against
        return None
    return world_tilt.levelled(referenced)[1]


def format_inspection(rec: Recording, result: Inspection, tilt: WorldTilt | None = None) -> str:
    """The report: what was read, the figures (with ``tilt``, the reference's world frame against
    gravity), then each likely mistake with what to pass instead."""
    lines = [
        f"{result.source}: {rec.kind}, {result.form} form, {result.rows} rows over {result.span_s:.6g} s "
        f"at {result.rate_hz:.6g} Hz (interval jitter {100 * result.jitter:.2f} % RMS), "
        f"{len(result.gaps)} gap(s)"
    ]
    lines += [f"  {note}" for note in rec.notes]
    if result.rest is None:
        beside = " (beside the reference: where it shows the unit neither turning nor travelling)"
        said = beside if rec.truth is not None else ""
        lines.append("at rest: no stretch of two seconds or more found" + said)
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
    if tilt is not None:
        lines.append(f"the reference, as sins fit and sins gap read it: {tilt.says}")
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
    "reference_tilt",
]
