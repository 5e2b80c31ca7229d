"""``sins correct``: a fitted model applied to a recording, the corrected readings written out."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.cli.common import Subparsers, check_outputs, unit_of
from sins.cli.options import add_dataset, add_recording_options, dataset_inputs, read_recording
from sins.cli.progress import progress_bar, row_progress
from sins.errors import SinsInputError

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from sins.compensation import Strategy
    from sins.core.series import ImuIncrements, ImuRates
    from sins.io.recording import Recording

    Array = NDArray[np.float64]


def _cmd_correct(args: argparse.Namespace) -> int:
    from sins import __version__, compensation, io
    from sins.core.series import ImuRates
    from sins.io import provenance

    check_outputs({"--out": args.out}, [args.model, args.recording, *dataset_inputs(args.dataset)])
    strategy = compensation.load(args.model)
    where = args.dataset or str(args.recording)
    said = provenance.Provenance() if args.recording is None else provenance.read_provenance(args.recording)
    if said.corrected_by and not args.again:
        raise SinsInputError(
            f"{where}: already corrected ({said.corrected_by}); correcting again applies the model twice: "
            "give the raw recording, or --again if that is meant"
        )
    with progress_bar(f"reading {where}", "") as bar:
        rec = read_recording(args, args.recording, args.dataset)
        unit = unit_of(rec)
        bar.set_description(f"correcting {where}")
        out, extra, beyond = _corrected(args, strategy, rec, where, unit)
    fitted_on = getattr(strategy, "fitted_on_", {}) or {}
    lines = [
        f"sins {__version__}: {where} corrected by {args.model} ({strategy.label})",
        *([f"{provenance.SENSOR_KEY}: {unit}"] if unit else []),
        *([f"{provenance.CORRECTED_KEY}: {said.corrected_by}"] * said.corrections),
        provenance.corrected_line(args.model, strategy.label, str(fitted_on.get("sensor") or "")),
        *([provenance.time_origin_line(rec.t0_ns)] if rec.t0_ns is not None else []),
    ]
    with progress_bar(f"writing {args.out}", "row") as bar:
        io.write_imu(args.out, out, extra=extra, comment="\n".join(lines), progress=row_progress(bar))
    form = "rate" if isinstance(out, ImuRates) else "increment"
    # What the corrected file does not hold, said: a user must not take it for the whole recording.
    left = (
        "the rig's reference and phases"
        if rec.rig is not None
        else "its reference"
        if rec.has_trajectory
        else ""
    )
    dropped = f"; the readings only, not {left} (judge the model on the original)" if left else ""
    print(f"wrote {args.out}: {len(out)} rows in {form} form, {where} corrected by {strategy.label}{dropped}")
    if beyond:
        print(beyond)
    if strategy.leaves_gyro_as_read():
        print("its gyro as read: the model's fit found every bias rule worse than the raw readings held back")
    return 0


def _corrected(
    args: argparse.Namespace, strategy: Strategy, rec: Recording, where: str, unit: str
) -> tuple[ImuRates | ImuIncrements, dict[str, Any] | None, str]:
    """The readings corrected in the form sins holds them in, the temperature column to keep, and where
    a learned part read beyond its training inputs (:func:`sins.compensation.evaluation.beyond_training`;
    the model refused first if it was fitted on another unit: ``unit``, or the recording's own)."""
    from sins.compensation import evaluation, fitted_on

    fitted_on.check_fitted_on(strategy, rec, f"{args.model} on {where}", sensor=unit)
    imu, temp, rows_temp = _readings(rec)
    try:
        out = strategy.correct_recording(imu, temp)  # a model fitted on several: its bias rule too
    except ValueError as exc:
        raise SinsInputError(f"{args.model} on {where}: {exc}") from None
    _check_readable(out, f"{args.model} on {where}")
    beyond = evaluation.beyond_training(strategy, imu, temp)[1]
    return out, None if rows_temp is None else {"temp": rows_temp}, beyond


def _check_readable(out: ImuRates | ImuIncrements, where: str) -> None:
    """Refuse corrected readings that no reader of sins would read back (beyond its rate and force
    limits, or not finite): a model whose bias is 1e11 rad/s (within a model file's bounds) had written a
    file that ``sins inspect`` then refused."""
    import numpy as np

    from sins.core.series import ImuRates
    from sins.io.formats import MAX_FORCE_MPS2, MAX_RATE_RADPS

    _, gyro, accel = (out.t, out.omega_ib_b, out.f_ib_b) if isinstance(out, ImuRates) else out.mean_rates()
    for what, values, limit, unit in (("rate", gyro, MAX_RATE_RADPS, "rad/s"),
                                      ("specific force", accel, MAX_FORCE_MPS2, "m/s²")):  # fmt: skip
        worst = float(np.max(np.abs(values), initial=0.0))
        if not worst <= limit:  # NaN too
            raise SinsInputError(
                f"{where}: the corrected readings reach a {what} of {worst:g} {unit}, beyond the {limit:g} "
                f"{unit} a recording may hold: a damaged model? (nothing written)"
            )


def _readings(rec: Recording) -> tuple[ImuRates | ImuIncrements, Array | None, Array | None]:
    """The readings to correct, their temperature at the readings' times (increments: at each step's
    boundaries, the first step's own taken at its start) and per written row (None without one): a rig
    recording's rates; a recording beside its reference trajectory as the increments it is fitted and
    judged in."""
    import numpy as np

    from sins.core.series import ImuRates

    if rec.rig is None and rec.has_trajectory:
        return rec.beside_reference().imu, None, None
    temp = rec.temp
    if temp is None or isinstance(rec.imu, ImuRates):
        return rec.imu, temp, temp
    # Increments: one temperature per row (the step it ends); at the boundaries the first step's own.
    return rec.imu, np.concatenate([temp[:1], temp]), temp


def add(sub: Subparsers) -> None:
    """Add ``sins correct`` to ``sub``."""
    p = sub.add_parser("correct", help="apply a fitted model to a recording and write the corrected readings")
    p.add_argument("model", type=Path, metavar="MODEL.json")
    p.add_argument(
        "recording", nargs="?", metavar="RECORDING", help="any recording sins reads (formats guide)"
    )
    add_dataset(p)
    p.add_argument(
        "--out", type=Path, required=True, metavar="CORRECTED.csv",
        help="the corrected readings in sins's CSV columns, in the form sins reads the recording in: rates "
        "for a rig recording or a rate file read without a trajectory (a CSV, a bag), increments for an "
        "increment file and for a recording read with a trajectory (its own: a EuRoC folder, an .npz, "
        "--dataset FOLDER/NAME, broad_NN, psins_vehicle; or --truth), which sins holds as increments",
    )  # fmt: skip
    p.add_argument(
        "--again", action="store_true",
        help="correct a recording that sins has corrected already (its '# corrected by' line): refused "
        "without it, as the model would be applied twice",
    )  # fmt: skip
    add_recording_options(p)
    p.set_defaults(func=_cmd_correct)


__all__ = [
    "add",
]
