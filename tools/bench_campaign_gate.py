"""The campaign gate's false alarms on real campaigns: the shipped campaign reseeded, against its baseline.

Usage::

    .venv/bin/python tools/bench_campaign_gate.py [--runs 20] [--workers 2]

Run ``k`` (1 … ``--runs``) is ``tactical_drives`` with ``first_seed = 1 + 40 k`` (40 new units each, none
shared with the baseline's or another run's), checked against the shipped baseline with two-sample
tests. An unchanged strategy should fail at most at the gate's false-alarm rate (1 %): over 20 runs,
expect 0 failures, and 1 is within chance (the chance of at least one at 1 % is 18 %).
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from pathlib import Path

from sins import campaign, scenario
from sins.campaign import engine, gate, results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    folder = scenario.preset_dir() / "campaign"
    base_spec = campaign.load(folder / "tactical_drives.toml")
    baseline = results.read_summary(folder / "tactical_drives_baseline.json")
    failures = 0
    for k in range(1, args.runs + 1):
        spec = dataclasses.replace(base_spec, first_seed=base_spec.first_seed + base_spec.count * k)
        with tempfile.TemporaryDirectory() as tmp:
            run = engine.run(spec, Path(tmp) / "out", workers=args.workers)
        checks = gate.compare(baseline, run.summary)
        bad = [c for c in checks if c.verdict != "holds"]
        smallest = min(checks, key=lambda c: c.p_value)
        failures += bool(bad)
        print(
            f"run {k:2d} (units {spec.first_seed}-{spec.first_seed + spec.count - 1}): "
            f"{'FAILS ' + ', '.join(f'{c.group} {c.figure}' for c in bad) if bad else 'holds'}; "
            f"smallest p {smallest.p_value:.3g} ({smallest.group} {smallest.figure}), {run.wall_s:.0f} s",
            flush=True,
        )
    rate = gate.FALSE_ALARM
    print(f"{failures} of {args.runs} reseeded campaigns failed the gate (its false-alarm rate: {rate:g})")


if __name__ == "__main__":
    main()
