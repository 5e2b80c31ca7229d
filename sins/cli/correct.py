"""``sins correct``: a fitted model applied to a recording, the corrected readings written out."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

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

if TYPE_CHECKING:
    from sins.compensation import Strategy
    from sins.series import ImuIncrements, ImuRates


def _cmd_correct(args: argparse.Namespace) -> int:
    from sins import __version__, compensation, io, referenced
    from sins.series import ImuRates

    check_outputs(args.out)
    strategy = compensation.load(args.model)
    where = args.dataset or str(args.recording)
    with progress_bar(f"reading {where}", "") as bar:
        inputs = referenced.read_inputs(args.recording, dataset=args.dataset, options=recording_options(args))
        bar.set_description(f"correcting {where}")
        out, extra = _corrected(args, strategy, inputs, where)
    note = f"sins {__version__}: {where} corrected by {args.model} ({strategy.label})"
    with progress_bar(f"writing {args.out}", "row") as bar:
        io.write_imu(args.out, out, extra=extra, comment=note, progress=row_progress(bar))
    form = "rate" if isinstance(out, ImuRates) else "increment"
    print(f"wrote {args.out}: {len(out)} rows in {form} form, {where} corrected by {strategy.label}")
    return 0


def _corrected(
    args: argparse.Namespace, strategy: Strategy, inputs: Any, where: str
) -> tuple[ImuRates | ImuIncrements, dict[str, Any] | None]:
    """The readings corrected in the form sins holds them in, and the temperature column to keep."""
    from sins import referenced
    from sins.io.recording import Recording
    from sins.series import CalibrationData, ImuRates, ReferencedRecording

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
        out = strategy.correct_recording(imu, temp)  # a model fitted on several: its bias rule too
    except ValueError as exc:
        raise SinsInputError(f"{args.model} on {where}: {exc}") from None
    extra = None if temp is None else {"temp": temp if isinstance(imu, ImuRates) else temp[1:]}
    return out, extra


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
        "for a rig recording or a rate file (a CSV, a bag, EuRoC), increments for an increment file and for "
        "a recording read against its reference trajectory (--dataset broad_NN or psins_vehicle), which "
        "sins holds as increments",
    )  # fmt: skip
    add_recording_options(p)
    p.set_defaults(func=_cmd_correct)


__all__ = [
    "add",
]
