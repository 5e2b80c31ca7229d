"""``sins bias``: a still unit's gyro and accelerometer biases, Earth's rate and gravity taken away, with
standard errors that count the noise's colour; the attitude they imply; a warm-up trend."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from sins.cli.common import Subparsers, check_outputs, check_plot, fixed_width, save_plot
from sins.cli.options import (
    add_dataset,
    add_plot,
    add_recording_options,
    dataset_inputs,
    positive,
    read_recording,
)
from sins.cli.progress import progress_bar, row_progress
from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.characterise.bias import BiasEstimate, RestAttitude


def _cmd_bias(args: argparse.Namespace) -> int:
    from sins import io
    from sins.core.earth import MAX_HEIGHT_M  # --origin's bound too (numpy: not at start-up)

    if (args.recording is None) == (args.dataset is None):
        raise SinsInputError("bias: give a RECORDING or --dataset NAME (one of them)")
    check_outputs({"--json": args.json, "--plot": args.plot}, [args.recording, *dataset_inputs(args.dataset)])
    check_plot(args)
    attitude = None if args.attitude is None else angles(args.attitude, "--attitude")
    lat = None if args.lat is None else latitude(args.lat)
    if args.height is not None and not abs(args.height) <= MAX_HEIGHT_M:
        raise SinsInputError(f"--height {args.height:g}: a height within ±1e5 m")
    estimate = _estimate(args, lat, attitude)
    print(format_bias(estimate))
    if args.json:
        io.write_report(args.json, estimate.to_dict())
    if args.plot:
        from sins.viz import plots

        save_plot(args.plot, lambda: plots.bias_figure(estimate), f"sins bias {estimate.source}")
    return 0


def _estimate(
    args: argparse.Namespace, lat: float | None, attitude: tuple[float, float, float] | None
) -> BiasEstimate:
    from sins.characterise import bias
    from sins.io.inspection import gaps_note

    if args.dataset is not None:
        if lat is not None or attitude is not None or args.height is not None:
            raise SinsInputError(
                "bias: --lat, --height and --attitude go with a RECORDING; a dataset has its own"
            )
        with progress_bar(f"reading {args.dataset}", "") as bar:
            rec = read_recording(args, None, args.dataset)
            data = rec.reference_inputs()[0]
            bar.set_description("fitting the noise")
            return bias.dataset_bias(data, args.dataset, progress=row_progress(bar),
                                     location=bias.location_of(rec), seconds=args.seconds)  # fmt: skip
    with progress_bar("reading", "messages") as bar:
        rec = read_recording(args, args.recording, None, progress=row_progress(bar))
    if note := gaps_note(rec.imu.t, "the rows on either side averaged as one rest"):
        print(f"sins: note: {rec.name}: {note}", file=sys.stderr)
    with progress_bar("fitting the noise", "channels") as bar:
        return bias.recording_bias(rec, lat, args.height, attitude, args.seconds, progress=row_progress(bar))


def angles(text: str, flag: str) -> tuple[float, float, float]:
    """``(roll, pitch, yaw)`` in rad from ``"R,P,Y"`` in degrees (ZYX: yaw clockwise from north)."""
    try:
        roll, pitch, yaw = (float(p) for p in text.split(","))
    except ValueError:
        raise SinsInputError(f"{flag} {text!r}: expected ROLL,PITCH,YAW in degrees") from None
    if not (abs(roll) <= 180.0 and abs(pitch) <= 90.0 and abs(yaw) <= 360.0):
        raise SinsInputError(f"{flag} {text!r}: roll within ±180°, pitch ±90°, yaw ±360°")
    return math.radians(roll), math.radians(pitch), math.radians(yaw)


def latitude(degrees: float) -> float:
    """A latitude in rad from degrees, refused beyond ±90°."""
    if not (math.isfinite(degrees) and abs(degrees) <= 90.0):
        raise SinsInputError(f"--lat {degrees:g}: a latitude lies within ±90°")
    return math.radians(degrees)


def format_attitude(a: RestAttitude, lat: float) -> list[str]:
    """The attitude the biases were taken in, and what a levelled one cannot tell."""
    from sins.core import earth
    from sins.imu import DEG_PER_H

    roll, pitch = math.degrees(a.roll), math.degrees(a.pitch)
    if a.source != "levelled":
        heading = f", yaw {math.degrees(a.yaw):.4f}°" if a.yaw is not None else ""
        heading += f" (heading not known: {a.heading_note})" if a.heading_note else ""
        return [f"attitude {a.source}: roll {roll:.4f}°, pitch {pitch:.4f}°{heading}"]
    per_mg = math.degrees(1e-3)  # b/g with b in g
    tilt = math.degrees(a.tilt_sigma)
    lines = [
        f"attitude from the data: roll {roll:.4f}°, pitch {pitch:.4f}° (1σ {tilt:.2g}° from the noise); a "
        f"level accelerometer bias tilts them by b/g ({per_mg:.4f}° per mg), which a still unit cannot tell "
        "apart: the level part of the accelerometer biases reads 0 by construction (give --attitude for it)"
    ]
    if a.yaw is None:
        lines.append(
            f"heading not resolved: {a.heading_note}; only the vertical part of Earth's rate is taken away "
            "(the column 'heading ±' bounds the level part left in each gyro)"
        )
        return lines
    per_dph = math.degrees(DEG_PER_H / (earth.OMEGA_IE * math.cos(lat)))
    yaw, yaw_sigma = math.degrees(a.yaw), math.degrees(a.yaw_sigma or 0.0)
    lines.append(
        f"heading {yaw:.3f}° by gyrocompassing (1σ {yaw_sigma:.2g}° from the noise); an east gyro bias turns "
        f"it by b/(Ω cos φ) ({per_dph:.3g}° per °/h): the east gyro bias reads 0 by construction"
    )
    return lines


def format_rests(e: BiasEstimate, where: str) -> list[str]:
    """Against a per-row reference: what it takes away, and each rest's own attitude and gravity (never
    their average: rests facing different ways average to no attitude and to less than gravity)."""
    from sins.core import earth
    from sins.core.earth import G0
    from sins.imu import DEG_PER_H

    g, rate = e.gravity, e.rest_figure("rate") / DEG_PER_H
    earth_dph = earth.OMEGA_IE / DEG_PER_H
    said = ("Earth's rate left out" if rate == 0.0 else "Earth's" if e.rate_is_earths()
            else f"not Earth's {earth_dph:.4g} °/h: the reference's own motion at rest")  # fmt: skip
    lines = [
        f"taken away, the reference's rate and specific force, row by row: {rate:.4g} °/h ({said}) and "
        f"{g:.6g} m/s² ({g / G0:.7g} g) at rest; {where}"
    ]
    if len(e.rests) == 1:
        return lines + format_attitude(e.rests[0].attitude, e.lat)
    lines.append(f"{len(e.rests)} rests pooled, each against its own reference:")
    for i, r in enumerate(e.rests, 1):
        a = r.attitude
        yaw = "" if a.yaw is None else f", yaw {math.degrees(a.yaw):.4f}°"
        lines.append(
            f"  rest {i}: {r.start_s:.6g}-{r.end_s:.6g} s, {r.rows} rows: roll {math.degrees(a.roll):.4f}°, "
            f"pitch {math.degrees(a.pitch):.4f}°{yaw}, gravity {r.gravity:.6g} m/s²"
        )
    return lines


def format_bias(e: BiasEstimate) -> str:
    """The report: what was averaged, where, in which attitude; each channel's bias ± 1σ and trend."""
    from sins.characterise.bias import DISPLAY
    from sins.core.earth import G0

    g = e.gravity
    where = f"at {math.degrees(e.lat):.4f}°" + (f", {e.h:g} m" if math.isfinite(e.h) else "")
    where = f"{where} ({e.location})" if math.isfinite(e.lat) else f"latitude {e.location}"
    lines = [
        f"{e.source}: {e.rows} rows at {e.rate_hz:.6g} Hz at rest, {e.start_s:.6g}-{e.end_s:.6g} s",
        *(f"  {note}" for note in e.notes),
    ]
    if e.rests:
        lines += format_rests(e, where)
    else:
        lines.append(f"Earth's rate and gravity ({g:.6g} m/s², {g / G0:.7g} g) {where}")
        lines += format_attitude(e.attitude, e.lat)
    bounded = any(c.heading_bound > 0 for c in e.channels.values())
    head = [
        "channel",
        "unit",
        "mean",
        "taken away",
        "bias",
        "1σ",
        "1σ if white",
        f"trend over {e.seconds:.4g} s",
    ]
    head += ["heading ±"] if bounded else []
    rows = []
    for ch, c in e.channels.items():
        size, unit = DISPLAY[c.sensor]
        trend = f"{c.trend * e.seconds / size:+.3g} ± {c.trend_sigma * e.seconds / size:.2g}"
        cells = [ch, unit, f"{c.mean / size:.6g}", f"{c.expected / size:.6g}", f"{c.bias / size:+.4g}",
                 f"{c.sigma / size:.3g}", f"{c.sigma_white / size:.3g}",
                 trend + (" significant" if c.trend_significant else "")]  # fmt: skip
        rows.append(cells + ([f"{c.heading_bound / size:.3g}" if c.heading_bound else ""] if bounded else []))
    lines.append(fixed_width(head, rows))
    lines.append(
        "1σ: the larger of the noise model's Allan deviation at the averaging time and the batch-means "
        "standard error of what is averaged (coloured noise averages down slower than white); 1σ if white: "
        "the spread about each rest's own mean over √rows; trend: the fitted line's rise over the rows, "
        "'significant' at 3σ of the slowest noise the Allan curve allows"
    )
    return "\n".join(lines)


def add(sub: Subparsers) -> None:
    """Add ``sins bias`` to ``sub``."""
    p = sub.add_parser(
        "bias",
        help="a still unit's gyro and accelerometer biases with their standard errors, Earth's rate and "
        "gravity taken away, and the attitude they imply",
    )
    p.add_argument("recording", type=Path, nargs="?", metavar="RECORDING", help="any recording sins reads")
    add_dataset(p)
    p.add_argument(
        "--lat", type=float, metavar="DEG",
        help="the latitude it stood at, degrees (default: the recording's fixes or reference)",
    )  # fmt: skip
    p.add_argument(
        "--height", type=float, metavar="M",
        help="its height above the ellipsoid, m (default: the recording's fixes or reference, else 0)",
    )  # fmt: skip
    p.add_argument(
        "--attitude", metavar="R,P,Y",
        help="the attitude it stood in, degrees (roll, pitch, yaw clockwise from north): every axis's bias; "
        "default: levelled from the data, the heading gyrocompassed where the gyro resolves it",
    )  # fmt: skip
    p.add_argument(
        "--seconds", type=positive, metavar="S",
        help="average only the first S seconds (S × rate rows; default: all at rest)",
    )  # fmt: skip
    p.add_argument(
        "--json", type=Path, metavar="OUT.json", help="write the biases and their errors (SI units)"
    )
    add_plot(p, "each axis's mean over the rest less Earth's rate and gravity, its bias ±3σ and its trend")
    add_recording_options(p)
    p.set_defaults(func=_cmd_bias)


__all__ = [
    "add",
    "angles",
    "format_attitude",
    "format_bias",
    "format_rests",
    "latitude",
]
