"""``sins fit``: a compensation strategy fitted on a recording and saved as a model file."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.cli.common import (
    Subparsers,
    add_dataset,
    add_recording_options,
    check_outputs,
    dataset_inputs,
    fixed_width,
    fraction,
    positive,
    progress_bar,
    recording_options,
    row_progress,
    settings,
    unit_of,
)
from sins.errors import SinsInputError

#: The classes of unit ``--grade`` takes (``sins.imu.spec.GRADES``, written out: importing it would slow
#: every command's start).
GRADES = ("consumer", "industrial", "tactical", "navigation")

if TYPE_CHECKING:
    from sins.compensation import Strategy
    from sins.core.series import CalibrationData, ReferencedRecording


def _cmd_fit(args: argparse.Namespace) -> int:
    from sins import compensation, io
    from sins.compensation import referenced
    from sins.core.series import CalibrationData, ReferencedRecording

    _check_args(args)
    datasets = [*(args.dataset or [])]
    read = [*args.recording, args.truth, *(p for d in datasets for p in dataset_inputs(d))]
    check_outputs({"--out": args.out, "--json": args.json}, read)  # before a fit that may take minutes
    sources = [*args.recording, *datasets]
    if not sources:
        raise SinsInputError("give a RECORDING or --dataset NAME (once per recording to fit on several)")
    if len(sources) > 1:
        strategy, document = _fit_several(args)
        where = " + ".join(sources)
    else:
        recording = args.recording[0] if args.recording else None
        dataset = args.dataset[0] if args.dataset else None
        where = dataset or str(recording)
        with progress_bar(f"reading {where}", ""):  # a dataset or a long bag takes seconds
            inputs = referenced.read_inputs(
                recording, dataset=dataset, truth=args.truth, options=recording_options(args)
            )
        if isinstance(inputs, ReferencedRecording):
            strategy, document = _fit_referenced(args, inputs, where)
        elif isinstance(inputs, CalibrationData):
            strategy, document = _fit_rig(args, inputs, where, unit_of(recording, dataset, inputs))
        else:
            missing = io.recording.missing_reference(inputs)
            if missing.needs == "truth_topic":  # a bag with several pose topics: name one
                raise missing
            raise SinsInputError(
                f"{where}: no reference to fit against; give the recording's trajectory with --truth "
                "TRUTH.csv (or a rig recording with ref_ columns, or a bag or EuRoC folder with ground truth)"
            )
    compensation.save(strategy, args.out)
    if args.json:
        io.write_json(args.json, {"model": str(args.out), "recording": where, **document})
    print(f"wrote {args.out}")
    return 0


def _fit_several(args: argparse.Namespace) -> tuple[Strategy, dict[str, Any]]:
    """Several recordings of one unit: each read with its own reference, then one fit on all of them."""
    from sins.compensation import referenced
    from sins.core.series import ReferencedRecording

    if args.truth is not None:
        raise SinsInputError(
            "--truth goes with one RECORDING; to fit on several, give recordings with their "
            "own references (a dataset, an .npz, a bag or EuRoC folder with ground truth)"
        )
    if args.validation:
        raise SinsInputError(
            "--validation holds back part of one recording; to judge a fit on several, "
            "leave recordings out of it and judge them with sins evaluate"
        )
    recs = []
    named = [("path", r) for r in args.recording] + [("dataset", d) for d in args.dataset or []]
    params = {"guard": False} if args.no_guard else {}
    with progress_bar(f"fitting {args.strategy}", "") as bar:
        for kind, name in named:
            bar.set_description(f"reading {name}")
            got = referenced.read_inputs(
                name if kind == "path" else None, dataset=name if kind == "dataset" else None,
                options=recording_options(args) if kind == "path" else None,
            )  # fmt: skip
            if not isinstance(got, ReferencedRecording):
                raise SinsInputError(
                    f"{name}: a fit on several recordings needs each beside its reference trajectory (a "
                    "rig recording or a recording without a reference cannot be one of them)"
                )
            recs.append(got)
        fitted = referenced.fit_several(
            args.strategy, recs, interval_s=args.interval_s, params=params, progress=row_progress(bar),
            rule_mode=args.bias_rule, stage=bar.set_description, grade=args.grade,
        )  # fmt: skip
    document = _several_report(fitted, [n for _, n in named])
    held = fitted.review.held if fitted.review is not None else {}
    if held:
        print(f"held at zero, as the recordings do not determine them for a {args.grade} unit:")
        for line in fitted.review.lines() if fitted.review is not None else []:
            print(f"  {line}")
    document |= {"grade": args.grade, "held": held}
    return fitted.strategy, document


def _several_report(fitted: Any, names: list[str]) -> dict[str, Any]:
    """Print what a fit on several recordings found; return it as the ``--json`` document."""
    import numpy as np

    from sins.compensation import coefficients

    fit = fitted.several
    print(f"fitted {fitted.strategy.label} on {len(names)} recordings of one unit: "
          f"{sum(fit.intervals)} intervals of {fit.interval_s:g} s")  # fmt: skip
    table = coefficients.engineering(fit.seed, g_sensitivity=fit.g_sensitivity)
    _print_coefficients(table, "the shared seed model (± 1σ; the bias is the recordings' mean)")
    per_hour = np.degrees(1.0) * 3600.0
    rows, biases = [], []
    for name, b, se, a, n in zip(names, fit.gyro_bias, fit.gyro_bias_se, fit.accel_bias, fit.intervals,
                                 strict=True):  # fmt: skip
        rows.append(
            [name, str(n), *(f"{x * per_hour:.1f} ± {e * per_hour:.1f}" for x, e in zip(b, se, strict=True))]
        )
        biases.append({
            "recording": name, "intervals": n, "gyro_bias_deg_h": (b * per_hour).tolist(),
            "gyro_bias_se_deg_h": (se * per_hour).tolist(), "accel_bias_m_s2": a.tolist(),
        })  # fmt: skip
    print("each recording's own gyro bias, °/h (± 1σ)")
    print(fixed_width(["recording", "intervals", "x", "y", "z"], rows))
    spread = fit.bias_spread() * per_hour
    print(f"spread of the bias between recordings: {spread[0]:.1f}, {spread[1]:.1f}, {spread[2]:.1f} °/h")
    document: dict[str, Any] = {
        "strategy": fitted.strategy.label, "recordings": names, "intervals": list(fit.intervals),
        "interval_s": fit.interval_s, "coefficients": [c.to_dict() for c in table],
        "recording_biases": biases,
        "time_offset_ms": {"gyro": fit.time_offset_s * 1e3, "accel": fit.accel_time_offset_s * 1e3},
    }  # fmt: skip
    if fitted.rule is not None:
        rule = fitted.rule
        held = "; ".join(f"{m} {v:.2f}°" for m, v in rule.held_back_deg.items())
        judged = f" (open-loop attitude on held-back recordings: {held})" if held else ""
        print(f"a new recording's bias: {rule.mode}{judged}")
        document["bias_rule"] = rule.to_dict()
    return document


def _check_args(args: argparse.Namespace) -> None:
    """Refuse what cannot work before reading anything."""
    if args.strategy == "oracle":
        raise SinsInputError(
            "the oracle knows a simulated unit's true model; it cannot be fitted to a recording"
        )
    from sins.compensation import strategy_names

    if args.strategy not in strategy_names():
        raise SinsInputError(
            f"unknown strategy {args.strategy!r} (known: {', '.join(strategy_names())}; "
            "sins strategies lists them)"
        )
    if args.no_guard and args.strategy not in ("mlp", "kohonen", "mlp_window"):
        raise SinsInputError(
            f"--no-guard: {args.strategy} has no guard (only mlp, kohonen and mlp_window do)"
        )


def _fit_rig(
    args: argparse.Namespace, data: CalibrationData, where: str, sensor: str
) -> tuple[Strategy, dict[str, Any]]:
    """A rig recording (per-sample reference inputs): the strategy's own fit on its rows, its seed
    model checked against the unit's class before the model is written."""
    from sins import compensation
    from sins.compensation import coefficients, identifiability
    from sins.compensation.mlp import MLP
    from sins.compensation.regression import Regression
    from sins.compensation.residual import ResidualStrategy
    from sins.imu import calibration

    if args.strategy == "bias_only":
        raise SinsInputError(
            f"--strategy bias_only: fits a trajectory's reference; {where} is a rig recording"
        )
    angles = any(p.angle_rad is not None for p in data.phases)
    try:
        strategy = compensation.make(args.strategy, **({"guard": False} if args.no_guard else {}))
        if angles and isinstance(strategy, Regression) and strategy.g_sensitivity:
            # Turns known by their angles alone cannot tell the gyro's g-sensitivity: it is left out.
            strategy = compensation.make(args.strategy, g_sensitivity=False)
            print(f"{where}: its turns give only their angles, which cannot tell the g-sensitivity: left out")
        part = data.split(args.validation)[0] if args.validation else data
        unit = "epochs" if isinstance(strategy, MLP) else "trainings"
        with progress_bar(f"fitting {args.strategy}", unit) as bar:
            if isinstance(strategy, ResidualStrategy | MLP):  # the strategies whose fits take long
                strategy.progress = row_progress(bar)
            strategy.fit(part)
    except ValueError as exc:
        raise SinsInputError(f"{where}: {exc}") from None
    held = f" (the last {args.validation:g} of each phase held back)" if args.validation else ""
    print(f"fitted {strategy.label} on {len(part)} of {len(data)} rows of {where}{held}")
    document: dict[str, Any] = {"strategy": strategy.label, "rows": len(part)}
    if isinstance(strategy, ResidualStrategy):
        print(
            f"chosen on {strategy.cv_folds_} folds of {strategy.blocks_} held-back blocks: "
            + "; ".join(f"{s} {settings(c)}" for s, c in strategy.configs_.items())
        )
        print(strategy.guard_report())
    # The seed model's coefficients with their standard errors: the strategy's own for regression, the
    # stage the learners start from for the others.
    try:
        seed = calibration.fit_seed_model(part)
        with_k = True
    except ValueError:
        try:  # a session whose turns give only their angles (Ferraris) cannot tell K
            seed, with_k = calibration.fit_seed_model(part, g_sensitivity=False), False
        except ValueError:
            seed = None
    checks: dict[str, Any] = {"grade": args.grade, "held": {}}
    if strategy.name != "none" and seed is not None:
        table = coefficients.engineering(seed, g_sensitivity=with_k)
        _print_coefficients(table, "least squares of the seed model on the rows (± 1σ)")
        document["coefficients"] = [c.to_dict() for c in table]
        bounds = identifiability.class_bounds(args.grade)
        checks = identifiability.review(identifiability.seed_values(seed), bounds, where).to_dict()
    strategy.fitted_on_ = {"sensor": sensor, "rate_hz": None, "reference": "rig", "checks": checks}
    return strategy, document


def _fit_referenced(
    args: argparse.Namespace, rec: ReferencedRecording, where: str
) -> tuple[Strategy, dict[str, Any]]:
    """A recording beside its reference trajectory: the seed model on intervals, then the strategy."""
    import numpy as np

    from sins.compensation import coefficients, referenced

    part = rec
    if args.validation:
        span = rec.imu.t[-1] - rec.imu.t[0]
        part = referenced.between(rec, rec.imu.t[0], rec.imu.t[-1] - args.validation * span)
    params = {"guard": False} if args.no_guard else {}
    with progress_bar(f"fitting {args.strategy}", "training") as bar:
        fitted = referenced.fit(
            args.strategy, part, interval_s=args.interval_s, params=params, progress=row_progress(bar),
            grade=args.grade,
        )  # fmt: skip
    fit = fitted.intervals
    back = f", the last {args.validation:g} of its span held back" if args.validation else ""
    print(
        f"fitted {fitted.strategy.label} on {where} ({rec.sensor or 'unit'} against {rec.reference_name}"
        f"{back}): {fit.intervals} intervals of {fit.interval_s:g} s"
    )
    print(f"reference: {fit.quality.summary()}")
    table = coefficients.engineering(fit.seed, g_sensitivity=fit.g_sensitivity)
    if args.strategy == referenced.BIAS_ONLY:  # the other terms are not fitted: zeros, not estimates
        table = [c for c in table if c.term == "bias"]
    _print_coefficients(table, "the seed model on the intervals (± 1σ; held: not determined, zero)")
    held = fitted.review.held if fitted.review is not None else {}
    if held:
        print(f"held at zero, as the recording does not determine them for a {args.grade} unit:")
        for line in fitted.review.lines() if fitted.review is not None else []:
            print(f"  {line}")
    if fit.g_sensitivity_test is not None:
        kept, gain, se = fit.g_sensitivity_test
        verdict = "kept" if kept else "left out (zero)"
        print(f"g-sensitivity {verdict}: it predicts held-back intervals by {gain:.3g} ± {se:.3g} rad²")
    document: dict[str, Any] = {
        "strategy": fitted.strategy.label,
        "intervals": fit.intervals,
        "interval_s": fit.interval_s,
        "coefficients": [c.to_dict() for c in table],
        "reference_quality": fit.quality.__dict__,
        "g_sensitivity": fit.g_sensitivity,
        "grade": args.grade,
        "held": held,
    }
    if args.strategy != referenced.BIAS_ONLY:
        arm = np.asarray(fit.lever_arm_m) * 1e3
        offset = lambda tau, se: f"{tau * 1e3:.3f} ± {se * 1e3:.3f} ms" if np.isfinite(se) else "0 (held)"  # noqa: E731
        gyro, accel = (offset(fit.time_offset_s, fit.time_offset_se_s),
                       offset(fit.accel_time_offset_s, fit.accel_time_offset_se_s))  # fmt: skip
        print(
            f"time offsets (the readings lag the reference): gyro {gyro}, accelerometer {accel}; "
            "accelerometer "
            f"{arm[0]:.1f}, {arm[1]:.1f}, {arm[2]:.1f} mm from the reference's point"
        )
        finite = lambda se: se * 1e3 if np.isfinite(se) else None  # noqa: E731
        document |= {
            "time_offset_ms": {"gyro": fit.time_offset_s * 1e3, "accel": fit.accel_time_offset_s * 1e3},
            "time_offset_se_ms": {
                "gyro": finite(fit.time_offset_se_s),
                "accel": finite(fit.accel_time_offset_se_s),
            },
            "lever_arm_mm": arm.tolist(),
        }
    return fitted.strategy, document


def _print_coefficients(table: list[Any], title: str) -> None:
    from sins.compensation import coefficients

    print(title)
    print(fixed_width(["sensor", "term", "axis", "value", "unit"], coefficients.table_rows(table)))


def add(sub: Subparsers) -> None:
    """Add ``sins fit`` to ``sub``."""
    p = sub.add_parser(
        "fit", help="fit a compensation strategy on a rig recording or a recording beside its reference"
    )
    p.add_argument(
        "recording", nargs="*", metavar="RECORDING",
        help="a rig CSV, or a recording with --truth or its own reference; several recordings of one unit "
        "(each with its own reference) are fitted together",
    )  # fmt: skip
    add_dataset(p, repeat=True)
    p.add_argument(
        "--truth", type=Path, metavar="TRUTH.csv",
        help="the recording's reference trajectory (attitude and velocity): the fit is made on intervals",
    )  # fmt: skip
    p.add_argument(
        "--strategy", required=True,
        help="the strategy to fit: sins strategies lists them (regression, mlp, kohonen, ...)",
    )  # fmt: skip
    p.add_argument(
        "--validation", type=fraction, metavar="FRACTION",
        help="hold back the last FRACTION of every phase (of the whole recording if it has no phases)",
    )  # fmt: skip
    p.add_argument(
        "--interval-s", type=positive, default=1.0, metavar="S",
        help="against a reference trajectory: the interval between the reference epochs compared (default 1)",
    )  # fmt: skip
    p.add_argument(
        "--no-guard", action="store_true",
        help="mlp, kohonen, mlp_window: use the learned correction on every channel, even where it does not "
        "beat regression on held-back blocks (recordings)",
    )  # fmt: skip
    p.add_argument(
        "--grade", choices=GRADES, default="consumer",
        help="the class of unit recorded: what its coefficients can be, and how well the data must determine "
        "them to be fitted rather than held at zero (default consumer, the loosest; guide: compensation)",
    )  # fmt: skip
    p.add_argument(
        "--bias-rule", choices=("pooled", "rest", "online", "rest+online"),
        help="several recordings: how a new recording's gyro bias is taken (default: the one that does best "
        "on held-back recordings)",
    )  # fmt: skip
    p.add_argument(
        "--json", type=Path, metavar="OUT.json", help="also write the coefficients and the fit's figures"
    )
    p.add_argument("--out", type=Path, required=True, metavar="MODEL.json")
    add_recording_options(p)
    p.set_defaults(func=_cmd_fit)


__all__ = [
    "GRADES",
    "add",
]
