"""``sins fit``: a compensation strategy fitted on a recording and saved as a model file."""

from __future__ import annotations

import argparse
from pathlib import Path

from sins.cli.common import Subparsers, fraction, progress_bar, row_progress, settings
from sins.errors import SinsInputError


def _cmd_fit(args: argparse.Namespace) -> int:
    from sins import compensation, io
    from sins.compensation.mlp import MLP
    from sins.compensation.residual import ResidualStrategy

    data = io.read_recording(args.recording)
    io.check_recording_range(args.recording, data)
    if args.strategy == "oracle":
        raise SinsInputError(
            "the oracle knows a simulated unit's true model; it cannot be fitted to a recording"
        )
    if args.no_guard and args.strategy not in ("mlp", "kohonen"):
        raise SinsInputError(f"--no-guard: {args.strategy} has no guard (only mlp and kohonen do)")
    try:
        params = {"guard": False} if args.no_guard else {}
        strategy = compensation.make(args.strategy, **params)
        part = data
        if args.validation:
            part, _ = data.split(args.validation)
        unit = "epochs" if isinstance(strategy, MLP) else "trainings"
        with progress_bar(f"fitting {args.strategy}", unit) as bar:
            if isinstance(strategy, ResidualStrategy | MLP):  # the strategies whose fits take long
                strategy.progress = row_progress(bar)
            strategy.fit(part)
    except ValueError as exc:
        raise SinsInputError(f"{args.recording}: {exc}") from None
    compensation.save(strategy, args.out)
    held = f" (the last {args.validation:g} of each phase held back)" if args.validation else ""
    print(f"fitted {args.strategy} on {len(part)} of {len(data)} rows of {args.recording}{held}")
    if isinstance(strategy, ResidualStrategy):
        print(
            f"chosen on {strategy.cv_folds_} folds of {strategy.blocks_} held-back blocks: "
            + "; ".join(f"{s} {settings(c)}" for s, c in strategy.configs_.items())
        )
        print(strategy.guard_report())
    print(f"wrote {args.out}")
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins fit`` to ``sub``."""
    p = sub.add_parser("fit", help="fit a compensation strategy on a rig recording")
    p.add_argument("recording", type=Path, metavar="RECORDING.csv")
    p.add_argument(
        "--strategy", required=True,
        help="none, regression, regression_robust, regression_extended, mlp, kohonen "
        "(or the seed paper's mlp_pure, mlp_seed, kohonen_pure)",
    )  # fmt: skip
    p.add_argument(
        "--validation", type=fraction, metavar="FRACTION",
        help="hold back the last FRACTION of every phase (of the whole recording if it has no phases)",
    )  # fmt: skip
    p.add_argument(
        "--no-guard", action="store_true",
        help="mlp, kohonen: use the learned correction on every channel, even where it does not beat "
        "regression on held-back blocks",
    )  # fmt: skip
    p.add_argument("--out", type=Path, required=True, metavar="MODEL.json")
    p.set_defaults(func=_cmd_fit)
