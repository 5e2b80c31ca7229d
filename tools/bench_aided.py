"""Benchmark of the aided filter: 1 h of 100 Hz IMU with 1 Hz GNSS, the whole process and its stages.

Usage::

    .venv/bin/python tools/bench_aided.py [--repeat 5] [--scenario car_drive] [--grade tactical]

Each repetition is a fresh process (after one warm-up that fills numba's cache) that loads the
scenario, simulates the truth and the ideal IMU, corrupts it with a unit of the grade, simulates the
receiver (1 Hz, one 60 s outage) and runs the closed-loop filter from the truth's first state; it
prints its stages' times, and the parent prints the medians and the whole process's wall time.
Timings on a shared machine are noisy: compare figures from one run of this script.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def child(scenario_name: str, grade: str) -> None:
    """One whole run; prints its stages' times as JSON."""
    stages: dict[str, float] = {}
    t0 = time.perf_counter()
    import numpy as np

    from sins import scenario
    from sins.aiding import ekf, gnss
    from sins.imu import spec
    from sins.nav import strapdown
    from sins.runs import pipeline

    stages["imports"] = time.perf_counter() - t0
    t = time.perf_counter()
    sc = scenario.load(pipeline.resolve_scenario(scenario_name))
    truth, ideal = pipeline.simulate(sc)
    stages["truth and ideal IMU"] = time.perf_counter() - t
    t = time.perf_counter()
    readings = spec.draw_unit(grade, unit_seed=1, run_seed=2).corrupt_increments(ideal, seed=3)
    stages["corrupt"] = time.perf_counter() - t
    t = time.perf_counter()
    receiver = gnss.GnssConfig(rate_hz=1.0, outages=(gnss.Outage(1800.0, 1860.0),))
    fixes = gnss.simulate(truth, receiver, seed=4)
    stages["gnss"] = time.perf_counter() - t
    t = time.perf_counter()
    config = ekf.FilterConfig.for_grade(grade)
    result = ekf.run(readings, fixes, config, strapdown.InitialState.from_series(truth))
    stages["filter"] = time.perf_counter() - t
    error = ekf.nav_error_state(result.nav, truth)
    stages["samples"] = float(len(ideal))
    stages["fixes"] = float(len(fixes))
    stages["rejected"] = float(result.rejected)
    stages["max horizontal error m"] = float(np.max(np.hypot(error[:, 0], error[:, 1])))
    print(json.dumps(stages))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--scenario", default="car_drive")
    parser.add_argument("--grade", default="tactical")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.scenario, args.grade)
        return
    command = [sys.executable, __file__, "--child", "--scenario", args.scenario, "--grade", args.grade]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)  # warm numba's cache
    walls, runs = [], []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        out = subprocess.run(command, check=True, capture_output=True, text=True, cwd=ROOT)
        walls.append(time.perf_counter() - t0)
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    first = runs[0]
    print(
        f"{args.scenario}: {first['samples']:.0f} IMU samples, {first['fixes']:.0f} GNSS fixes "
        f"(1 Hz, one 60 s outage), {args.grade} unit; {first['rejected']:.0f} rejected, max horizontal error "
        f"{first['max horizontal error m']:.2f} m"
    )
    for stage in ("imports", "truth and ideal IMU", "corrupt", "gnss", "filter"):
        values = [r[stage] for r in runs]
        spread = f"(min {min(values):.2f}, max {max(values):.2f})"
        print(f"  {stage:<22} median {statistics.median(values):6.2f} s  {spread}")
    print(
        f"  {'whole process':<22} median {statistics.median(walls):6.2f} s  (min {min(walls):.2f}, "
        f"max {max(walls):.2f}, n={args.repeat})"
    )


if __name__ == "__main__":
    main()
