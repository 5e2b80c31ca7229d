"""Campaign throughput: unit-hours per second on a local dask cluster, and one stream's time by stage.

Usage::

    .venv/bin/python tools/bench_campaign.py [--units 8] [--workers 1 2] [--strategies none regression]

Part 1 runs a campaign of ``--units`` tactical units, each calibrated on the 24-position + rate-table
rig and driven through the one-hour ``car_drive`` once per strategy, on a local cluster of each
``--workers`` count, and prints the wall time, unit-hours per second (one unit-hour: one strategy's
hour of 100 Hz samples, corrupted, corrected, integrated and reduced), and the time 1,000 unit-hours
would take at that rate. Part 2 times one hour's stages in this process (medians of 3): generating
the truth and ideal IMU, corrupting, correcting with regression, integrating, reducing the errors.
The machine is shared: compare figures of one run only.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from sins import campaign, pipeline, scenario
from sins.campaign import engine
from sins.imu.stream import IncrementStream
from sins.nav import strapdown, trajectory
from sins.nav.metrics import nav_errors

CAMPAIGN = """name = "bench"
[units]
imu = "tactical"
count = {units}
first_seed = 1
[compensation]
rig = "24pos_ratetable"
strategies = {strategies}
[[scenario]]
file = "car_drive"
[keep]
series_hz = 0.01
"""


def cluster_rates(units: int, workers: list[int], strategies: list[str]) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.toml"
        path.write_text(CAMPAIGN.format(units=units, strategies=repr(strategies).replace("'", '"')))
        spec = campaign.load(path)
        streams = len(dict.fromkeys(["none", *spec.compensation.strategies]))
        for n in workers:
            run = engine.run(spec, Path(tmp) / f"out{n}", workers=n)
            unit_hours = units * streams
            rate = unit_hours / run.wall_s
            print(
                f"{n} worker(s): {units} units x {streams} streams of 1 h at 100 Hz in {run.wall_s:.1f} s: "
                f"{rate:.2f} unit-hours/s ({rate * 360_000 / 1e6:.2f} M samples/s); "
                f"1,000 unit-hours would take {1000 / rate:.0f} s"
            )


def stages(repeats: int = 3) -> None:
    sc = scenario.load(scenario.resolve_preset("car_drive"))
    spec = scenario.load_imu(scenario.resolve_preset("tactical", "imu"))
    comp = scenario.CompensationSpec(
        scenario.resolve_preset("24pos_ratetable", "rig"), 0.3, 2, ("regression",)
    )
    fitted = pipeline.fit_unit(spec, comp)
    regression = fitted.strategies["regression"]
    model = spec.model(run_seed=1)
    times: dict[str, list[float]] = {k: [] for k in ("generate", "corrupt", "correct", "integrate", "reduce")}
    for _ in range(repeats):
        t0 = time.perf_counter()
        truth, ideal = trajectory.generate(scenario.build_motion(sc), sc.rate_hz)
        t1 = time.perf_counter()
        stream = IncrementStream(model, 1, 1.0 / sc.rate_hz)
        temp = np.full(len(ideal.t), 20.0)
        parts = [stream.push(ideal, temp), stream.finish()]
        t2 = time.perf_counter()
        corrected = [regression.correct_increments(p, np.full(len(p.t), 20.0)) for p in parts if len(p)]
        t3 = time.perf_counter()
        state = strapdown.start(strapdown.InitialState.from_series(truth.at(np.array([0]))))
        solutions = []
        for c in corrected:
            sol, state = strapdown.advance(state, c)
            solutions.append(sol)
        t4 = time.perf_counter()
        start = 1
        for sol in solutions:
            nav_errors(sol, truth.at(np.arange(start, start + len(sol.t))))
            start += len(sol.t)
        t5 = time.perf_counter()
        for k, v in zip(times, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4), strict=True):
            times[k].append(v)
    n = len(truth.t) - 1
    total = sum(statistics.median(v) for v in times.values())
    print(f"one stream, 1 h at 100 Hz ({n} samples), medians of {repeats}:")
    for k, v in times.items():
        m = statistics.median(v)
        print(f"  {k:<10} {m:6.3f} s  {m / n * 1e9:6.0f} ns/sample  {100 * m / total:4.0f} %")
    print(f"  {'total':<10} {total:6.3f} s  {total / n * 1e9:6.0f} ns/sample")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=8)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--strategies", nargs="+", default=["none", "regression"])
    args = parser.parse_args()
    stages()
    cluster_rates(args.units, args.workers, args.strategies)


if __name__ == "__main__":
    main()
