"""How long logging a scenario run to Rerun takes (the run itself is not timed).

Usage::

    .venv/bin/python tools/bench_viz.py [--scenario car_drive_compensated] [--repeat 5]

Runs the scenario once with four strategies (``none``, ``oracle``, ``regression``,
``regression_robust``: what is logged does not depend on which, and these fit in
seconds), then writes it to a ``.rrd`` file ``--repeat`` times with
:func:`sins.viz.viewer.save` and prints the median and range of the wall time, the file
size and how many rows went out.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import tempfile
import time
from pathlib import Path

from sins import scenario
from sins.runs import pipeline
from sins.viz import viewer as viz


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="car_drive_compensated")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    sc = scenario.load(pipeline.resolve_scenario(args.scenario))
    if sc.compensation is not None:
        strategies = ("none", "oracle", "regression", "regression_robust")
        sc = dataclasses.replace(sc, compensation=dataclasses.replace(sc.compensation, strategies=strategies))
    started = time.perf_counter()
    result = pipeline.run_scenario(sc)
    print(f"{sc.name}: {result.samples} samples at {sc.rate_hz:g} Hz, strategies {', '.join(result.runs)}")
    print(f"run (not part of the logging figure): {time.perf_counter() - started:.1f} s")
    rows = len(result.truth.t) * (1 + len(result.runs) * (1 + len(viz.ERROR_PANELS)))
    if result.sensor_t is not None:
        rows += len(result.sensor_t) * len(result.runs) * 6
    times = []
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "run.rrd"
        for _ in range(args.repeat):
            started = time.perf_counter()
            viz.save(result, out, summary="summary")
            times.append(time.perf_counter() - started)
        size_mb = out.stat().st_size / 1e6
    print(
        f"viz.save: median {statistics.median(times):.2f} s (range {min(times):.2f}-{max(times):.2f}, "
        f"{args.repeat} runs); {rows:,} time-indexed rows; {size_mb:.0f} MB"
    )


if __name__ == "__main__":
    main()
