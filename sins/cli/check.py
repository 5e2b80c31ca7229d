"""``sins check``: the compensation-quality gate, a suite or a campaign against its baseline."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING

from sins.cli.common import Subparsers, check_outputs, fixed_width, scenario_inputs
from sins.cli.progress import progress_bar, row_progress
from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.campaign.gate import Check
    from sins.campaign.quality import Figures, Suite


def _cmd_check(args: argparse.Namespace) -> int:
    from sins import scenario
    from sins.campaign import quality
    from sins.campaign.spec import is_campaign

    path = Path(args.suite)
    if not path.exists() and scenario.find_preset(args.suite, "campaign") is not None:
        path = scenario.resolve_preset(args.suite, "campaign")
    if is_campaign(path):
        return _check_campaign(args, path)
    suite = quality.load_suite(path)
    baseline = None
    if args.update_baseline:
        # Before the runs, not after them; every file the cases read is an input (their scenarios, IMU
        # and rig files), not the suite file alone.
        inputs: list[Path | None] = [path]
        for case in suite.cases:
            inputs += scenario_inputs(scenario.load(case.scenario))
        check_outputs({"--baseline": args.baseline}, inputs, kinds={"--baseline": quality.BASELINE_FORMAT})
    elif not Path(args.baseline).exists():
        raise SinsInputError(f"{args.baseline}: no such quality baseline; create it with --update-baseline")
    else:
        baseline = quality.read_baseline(args.baseline, suite)  # refuse early, before the runs
    with progress_bar(f"quality suite {path.name}, {len(suite.seeds)} seeds", "runs") as bar:
        measured = quality.measure(suite, row_progress(bar))
    if baseline is None:
        quality.write_baseline(args.baseline, measured, suite)
        print(f"wrote {args.baseline}: {measured.count()} metrics of {len(measured.cases)} cases, "
              f"{len(measured.seeds)} seeds each")  # fmt: skip
        return 0
    return _report_suite(quality.compare(baseline, measured, suite.tolerances), baseline, measured, suite)


def _report_suite(checks: list[Check], baseline: Figures, measured: Figures, suite: Suite) -> int:
    """Print the suite's verdicts; 1 if a figure regressed or went missing."""
    from sins.campaign import quality
    from sins.campaign.gate import FALSE_ALARM

    rows = [
        [c.group, c.figure, c.test or "-", f"{c.median_ratio:.4g}", f"{c.p_value:.3g}", c.verdict]
        for c in checks
    ]
    print(fixed_width(["case/strategy", "metric", "test", "median now/base", "p", "verdict"], rows))
    for name in quality.unjudged(baseline, measured):
        print(f"not in the baseline, not judged: {name}")
    if not set(measured.seeds) <= set(baseline.seeds):
        print("the baseline's seeds are not the suite's: two-sample tests, weaker than paired ones")
    each = FALSE_ALARM / max(1, len(checks))
    tol = ", ".join(f"{k} {100 * v:g} %" for k, v in suite.tolerances.items())
    level = (f"{len(measured.seeds)} seeds; growth beyond the tolerances ({tol}) tested at a false-alarm "
             f"rate of {FALSE_ALARM:g} over the {len(checks)} figures, each at {each:.2g}")  # fmt: skip
    bad = [c for c in checks if c.verdict != "holds"]
    if bad:
        print(f"\n{len(bad)} of {len(checks)} metrics regressed or went missing ({level})")
        for c in bad:
            growth = "" if math.isnan(c.median_ratio) else f", median {100 * (c.median_ratio - 1):+.2f} %"
            print(f"  {c.group} {c.figure}: {c.verdict} (p = {c.p_value:.3g}{growth})")
        return 1
    print(f"\nall {len(checks)} metrics hold ({level})")
    return 0


def _check_campaign(args: argparse.Namespace, path: Path) -> int:
    """``sins check`` on a campaign: its distributions against a baseline summary (sins.campaign.gate)."""
    import tempfile

    from sins import campaign, io
    from sins.campaign import engine, gate, results

    spec = campaign.load(path)
    baseline = None
    if args.update_baseline:
        inputs = [spec.source, spec.imu.source, spec.compensation.rig]
        for sc in spec.scenarios:
            inputs += scenario_inputs(sc)
        # before the campaign, not after it; a quality baseline is not replaced by a campaign's, nor this
        check_outputs({"--baseline": args.baseline}, inputs, kinds={"--baseline": results.SUMMARY_FORMAT})
    elif not Path(args.baseline).exists():
        raise SinsInputError(f"{args.baseline}: no such campaign baseline; create it with --update-baseline")
    else:  # the whole baseline checked before any work: one that tests nothing or drops a figure is refused
        baseline = results.read_summary(args.baseline)
        gate.check_baseline(baseline, args.baseline, spec)
        gate.check_power(baseline, args.baseline)
    with tempfile.TemporaryDirectory() as tmp, progress_bar(f"campaign {spec.name}", "unit") as bar:
        done = engine.run(spec, Path(tmp) / "out", progress=row_progress(bar))
    if baseline is None:
        new = gate.baseline_of(done.summary)
        try:
            gate.check_baseline(new, args.baseline, spec)
            gate.check_power(new, args.baseline)
        except SinsInputError as exc:
            raise SinsInputError(f"the campaign's figures cannot be a baseline: {exc}") from None
        io.write_json(args.baseline, new)
        print(f"wrote {args.baseline}: {len(done.summary['groups'])} groups of {spec.count} units")
        return 0
    checks = gate.compare(baseline, done.summary)
    rows = [
        [c.group, c.figure, c.test or "-", f"{c.median_ratio:.4g}", f"{c.p_value:.3g}", c.verdict]
        for c in checks
    ]
    print(fixed_width(["scenario/strategy", "figure", "test", "median now/base", "p", "verdict"], rows))
    for name in gate.unjudged(baseline, done.summary):
        print(f"not in the baseline, not judged: {name}")
    bad = [c for c in checks if c.verdict != "holds"]
    each = gate.FALSE_ALARM / max(1, len(checks))
    level = f"false-alarm rate {gate.FALSE_ALARM:g} over the {len(checks)} tests, each at {each:.2g}"
    if bad:
        print(f"\n{len(bad)} of {len(checks)} figures regressed or went missing ({level})")
        for c in bad:
            print(f"  {c.group} {c.figure}: {c.verdict} (p = {c.p_value:.3g}, median x{c.median_ratio:.4g})")
        return 1
    print(f"\nall {len(checks)} figures hold ({level})")
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins check`` to ``sub``."""
    p = sub.add_parser(
        "check", help="the compensation-quality gate: a suite or a campaign against its baseline"
    )
    p.add_argument(
        "suite", metavar="SUITE.toml",
        help="a quality suite, or a campaign file or preset (its distributions gated: sins.campaign.gate)",
    )  # fmt: skip
    p.add_argument(
        "--baseline", type=Path, required=True, metavar="BASELINE.json",
        help="the figures the suite is held to (written by --update-baseline)",
    )  # fmt: skip
    p.add_argument(
        "--update-baseline", action="store_true", help="write the measured metrics as the baseline"
    )
    p.set_defaults(func=_cmd_check)


__all__ = [
    "add",
]
