"""The campaign gate's false alarms on real campaigns: the shipped campaign reseeded, against its baseline;
with ``--compare``, the time one comparison takes.

Usage::

    .venv/bin/python tools/bench_campaign_gate.py [--runs 20] [--workers 2]
    .venv/bin/python tools/bench_campaign_gate.py --compare [--repeat 200]

Run ``k`` (1 … ``--runs``) is ``tactical_drives`` with ``first_seed = 1 + 40 k`` (40 new units each, none
shared with the baseline's or another run's), checked against the shipped baseline with two-sample
tests. An unchanged strategy should fail at most at the gate's false-alarm rate (1 %): over 20 runs,
expect 0 failures, and 1 is within chance (the chance of at least one at 1 % is 18 %).

``--compare`` times :func:`sins.campaign.gate.compare` on made-up summaries of the shipped campaign's
shape (three groups, every gated figure, 40 units; reseeded and paired), median over ``--repeat``
comparisons, beside one scipy call per figure (what the gate made before it batched them), in one run:
compare the ratio, not the figures across machines.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy import stats

from sins import campaign, scenario
from sins.campaign import engine, gate, results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--compare", action="store_true", help="time one comparison instead")
    parser.add_argument("--repeat", type=int, default=200)
    args = parser.parse_args()
    if args.compare:
        time_compare(args.repeat)
        return
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


def time_compare(repeat: int) -> None:
    """Median wall time of one :func:`gate.compare`, and of one scipy call per figure of the same."""
    rng = np.random.default_rng(0)

    def summary(seeds: list[int]) -> dict:
        values = {f: rng.lognormal(0.0, 0.6, len(seeds)).tolist() for f in gate.GATED}
        return {"groups": {g: {"values": {"unit_seed": seeds, **values}} for g in ("a/none", "a/x", "a/y")}}

    for kind, now_seeds in (("reseeded", list(range(40, 80))), ("paired", list(range(40)))):
        base, now = summary(list(range(40))), summary(now_seeds)
        batched, alone = [], []
        for _ in range(repeat):
            t0 = time.perf_counter()
            gate.compare(base, now)
            t1 = time.perf_counter()
            for group, figures in base["groups"].items():
                for figure, b in figures["values"].items():
                    if figure == "unit_seed":
                        continue
                    n = np.asarray(now["groups"][group]["values"][figure])
                    if kind == "paired":
                        stats.wilcoxon(n - np.asarray(b), alternative="greater", zero_method="zsplit")
                    else:
                        stats.mannwhitneyu(n, np.asarray(b), alternative="greater")
            batched.append(t1 - t0)
            alone.append(time.perf_counter() - t1)
        tests = sum(len(g["values"]) - 1 for g in base["groups"].values())
        b_ms, a_ms = 1e3 * statistics.median(batched), 1e3 * statistics.median(alone)
        print(
            f"{kind}: {tests} figures; gate.compare {b_ms:.2f} ms (median of {repeat}); "
            f"scipy's test once a figure {a_ms:.2f} ms: {a_ms / b_ms:.1f}x",
            flush=True,
        )


if __name__ == "__main__":
    main()
