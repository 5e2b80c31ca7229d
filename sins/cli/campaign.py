"""``sins campaign``: a Monte-Carlo campaign of many units on a dask cluster."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from sins.cli.common import Subparsers, check_outputs, check_plot, save_plot, scenario_inputs
from sins.cli.options import add_plot, count
from sins.cli.progress import progress_bar, row_progress
from sins.errors import SinsInputError


def _cmd_campaign(args: argparse.Namespace) -> int:
    from sins import campaign
    from sins.campaign import engine, folder, results

    if args.workers is not None and args.scheduler:
        raise SinsInputError("--workers: the scheduler's cluster has its own workers; give one of the two")
    from sins import scenario

    spec = campaign.load(scenario.resolve_preset(args.campaign, "campaign"))
    out = args.out or Path(f"{spec.name}-campaign")
    if args.rerun:
        from sins.viz import viewer as viz

        viz.check_rrd_path(args.rerun, "--rerun")
    check_plot(args)
    inputs = [spec.source, spec.imu.source, spec.compensation.rig]
    for sc in spec.scenarios:
        inputs += scenario_inputs(sc)
    # The outputs' places, before the work, not after it; a folder of the user's own is not taken over.
    check_outputs({"--rerun": args.rerun, "--plot": args.plot}, inputs, {"--out": out})
    folder.check_owned(out)
    strategies = dict.fromkeys(["none", *spec.compensation.strategies])
    print(
        f"campaign {spec.name}: {spec.count} units x {len(spec.scenarios)} scenarios x "
        f"{len(strategies)} strategies -> {out}"
    )
    with progress_bar(f"campaign {spec.name}", "unit") as bar:
        done = engine.run(spec, out, args.workers, args.scheduler, args.resume, row_progress(bar))
    for line in done.rejected:
        print(f"campaign: part {line}", file=sys.stderr)
    resumed = f" ({done.units_resumed} already done)" if done.units_resumed else ""
    print(f"ran {done.units_run} units in {done.wall_s:.1f} s{resumed}")
    for line in results.table_lines(done.summary):
        print(line)
    written = f"{out / 'results.parquet'} and {out / 'summary.json'}"
    if args.rerun:
        import pyarrow.parquet as pq

        from sins.viz import viewer as viz

        viz.save_campaign(pq.read_table(out / "results.parquet").to_pydict(), args.rerun)
        written = f"{out / 'results.parquet'}, {out / 'summary.json'} and {args.rerun}"
    print(f"wrote {written}")
    if args.plot:
        import pyarrow.parquet as pq

        from sins.viz import plots

        rows = pq.read_table(out / "results.parquet").to_pydict()
        title = f"campaign {spec.name}: {spec.count} units"
        save_plot(args.plot, lambda: plots.campaign_figure(rows, title), title)
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins campaign`` to ``sub``."""
    p = sub.add_parser(
        "campaign", help="Monte-Carlo campaign: units x scenarios x strategies, on a dask cluster"
    )
    p.add_argument("campaign", metavar="CAMPAIGN.toml", help="campaign file or preset (e.g. tactical_drives)")
    p.add_argument(
        "--workers",
        type=count,
        metavar="N",
        help="processes of the local cluster (default: the machine's cores)",
    )
    p.add_argument("--scheduler", metavar="ADDRESS", help="run on an existing dask cluster (tcp://HOST:PORT)")
    p.add_argument("--out", type=Path, metavar="DIR", help="results folder (default: NAME-campaign)")
    p.add_argument("--resume", action="store_true", help="continue the campaign from what --out holds")
    p.add_argument(
        "--rerun", type=Path, metavar="OUT.rrd",
        help="log the spread: percentile bands of horizontal error over time, each unit's final error",
    )  # fmt: skip
    add_plot(p, "each scenario's spread of final errors per strategy")
    p.set_defaults(func=_cmd_campaign)


__all__ = [
    "add",
]
