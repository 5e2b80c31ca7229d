"""Compensation judged in GNSS outages: the shipped outage campaigns, one table per regime.

Usage::

    .venv/bin/python tools/bench_outage_campaigns.py [--workers 2] [--units 20] [--out DIR]

Runs ``outages_linear`` (tactical units: the seed model's errors) and ``outages_nonlinear`` (tactical
units with scale nonlinearity and g² sensitivity) — each unit fitted on a 24-position + rate-table
session, aligned, aided by 1 Hz GNSS through a 10-minute drive with two 60 s outages — and prints, per
strategy, the horizontal error at each outage's end over the units: median and 95th percentile with
their bootstrap 95 % intervals (Markdown). ``--out`` keeps each campaign's results folder.
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from pathlib import Path
from typing import Any

from sins import campaign, scenario
from sins.campaign import engine


def _cell(stats: dict[str, Any], name: str) -> str:
    low, high = stats[f"{name}_ci95"]
    return f"{stats[name]:.1f} [{low:.1f}, {high:.1f}]"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--units", type=int, default=None, help="override the campaigns' unit count")
    parser.add_argument("--out", type=Path, help="keep the results folders here")
    args = parser.parse_args()
    folder = scenario.preset_dir() / "campaign"
    with tempfile.TemporaryDirectory() as tmp:
        base = args.out or Path(tmp)
        for regime in ("linear", "nonlinear"):
            spec = campaign.load(folder / f"outages_{regime}.toml")
            if args.units:
                spec = dataclasses.replace(spec, count=args.units)
            run = engine.run(spec, base / spec.name, workers=args.workers)
            groups = run.summary["groups"]
            print(f"\n{spec.name}: {spec.count} units, {run.wall_s:.0f} s on {args.workers} workers")
            print("| strategy | outage 1 end, median [95 % CI] m | p95 | outage 2 end, median | p95 |")
            print("|---|---|---|---|---|")
            for group in groups.values():
                o1, o2 = group["outage1_end_m"], group["outage2_end_m"]
                print(
                    f"| {group['strategy']} | {_cell(o1, 'median')} | {_cell(o1, 'p95')} | "
                    f"{_cell(o2, 'median')} | {_cell(o2, 'p95')} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
