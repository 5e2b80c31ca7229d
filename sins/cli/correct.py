"""``sins correct``: a fitted model applied to a recording, the corrected readings written out."""

from __future__ import annotations

import argparse
from pathlib import Path

from sins.cli.common import (
    Subparsers,
    add_dataset,
    add_recording_options,
    check_outputs,
    progress_bar,
    recording_options,
    row_progress,
)
from sins.errors import SinsInputError


def _cmd_correct(args: argparse.Namespace) -> int:
    from sins import __version__, compensation, io, referenced
    from sins.io.recording import Recording
    from sins.series import CalibrationData, ImuIncrements, ImuRates, ReferencedRecording

    check_outputs(args.out)
    strategy = compensation.load(args.model)
    where = args.dataset or str(args.recording)
    inputs = referenced.read_inputs(args.recording, dataset=args.dataset, options=recording_options(args))
    referenced.check_fitted_on(strategy, inputs, f"{args.model} on {where}")
    temp = None
    if isinstance(inputs, ReferencedRecording):
        imu: ImuRates | ImuIncrements = inputs.imu
    elif isinstance(inputs, CalibrationData):
        imu, temp = ImuRates(t=inputs.t, omega_ib_b=inputs.gyro, f_ib_b=inputs.accel), inputs.temp
    else:
        assert isinstance(inputs, Recording)
        imu, temp = inputs.imu, inputs.temp
    try:
        out = (
            strategy.correct_rates(imu, temp)
            if isinstance(imu, ImuRates)
            else strategy.correct_increments(imu, temp)
        )
    except ValueError as exc:
        raise SinsInputError(f"{args.model} on {where}: {exc}") from None
    extra = None if temp is None else {"temp": temp if isinstance(imu, ImuRates) else temp[1:]}
    note = f"sins {__version__}: {where} corrected by {args.model} ({strategy.label})"
    with progress_bar(f"writing {args.out}", "row") as bar:
        io.write_imu(args.out, out, extra=extra, comment=note, progress=row_progress(bar))
    form = "rate" if isinstance(out, ImuRates) else "increment"
    print(f"wrote {args.out}: {len(out)} rows in {form} form, {where} corrected by {strategy.label}")
    return 0


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
        help="the corrected readings, in the recording's form (rates or increments), sins's CSV columns",
    )  # fmt: skip
    add_recording_options(p)
    p.set_defaults(func=_cmd_correct)


__all__ = [
    "add",
]
