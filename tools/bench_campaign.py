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
import dataclasses
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
    """One stream's hour, stage by stage, chunk by chunk as ``sins run`` and a campaign go."""
    sc = scenario.load(scenario.resolve_preset("car_drive"))
    spec = scenario.load_imu(scenario.resolve_preset("tactical", "imu"))
    comp = scenario.CompensationSpec(
        scenario.resolve_preset("24pos_ratetable", "rig"), 0.3, 2, ("regression",)
    )
    regression = pipeline.fit_unit(spec, comp).strategies["regression"]
    model = spec.model(run_seed=1)
    motion = scenario.build_motion(sc)
    times: dict[str, list[float]] = {k: [] for k in ("generate", "corrupt", "correct", "integrate", "reduce")}
    n = 0
    for _ in range(repeats):
        spent = dict.fromkeys(times, 0.0)
        t0 = time.perf_counter()
        chunks = list(trajectory.generate_chunks(motion, sc.rate_hz))
        spent["generate"] = time.perf_counter() - t0
        stream = IncrementStream(model, 1, 1.0 / sc.rate_hz)
        state = strapdown.start(strapdown.InitialState.from_series(trajectory.start_state(motion)))
        n = 0
        for truth_c, ideal_c in chunks:
            t1 = time.perf_counter()
            # The stream writes an interval once its neighbours have come: compare like with like below.
            corrupted = stream.push(ideal_c, np.full(len(ideal_c.t), 20.0))
            t2 = time.perf_counter()
            corrected = regression.correct_increments(corrupted, np.full(len(corrupted.t), 20.0))
            t3 = time.perf_counter()
            solution, state = strapdown.advance(state, corrected)
            t4 = time.perf_counter()
            m = len(solution.t)
            nav_errors(
                solution, truth_c.at(np.arange(min(m, len(truth_c.t)))) if m <= len(truth_c.t) else truth_c
            )
            t5 = time.perf_counter()
            for k, v in zip(
                ("corrupt", "correct", "integrate", "reduce"),
                (t2 - t1, t3 - t2, t4 - t3, t5 - t4),
                strict=True,
            ):
                spent[k] += v
            n += m
        for k, v in spent.items():
            times[k].append(v)
    total = sum(statistics.median(v) for v in times.values())
    print(f"one stream, 1 h at 100 Hz ({n} samples, {len(chunks)} chunks), medians of {repeats}:")
    for k, v in times.items():
        m = statistics.median(v)
        print(f"  {k:<10} {m:6.3f} s  {m / n * 1e9:6.0f} ns/sample  {100 * m / total:4.0f} %")
    print(f"  {'total':<10} {total:6.3f} s  {total / n * 1e9:6.0f} ns/sample")


def sharing(units: int = 8) -> None:
    """Per unit-hour, ``units`` units driven one call each against all in one call sharing the trajectory."""
    sc = scenario.load(scenario.resolve_preset("car_drive"))
    spec = scenario.load_imu(scenario.resolve_preset("tactical", "imu"))
    comp = scenario.CompensationSpec(
        scenario.resolve_preset("24pos_ratetable", "rig"), 0.3, 2, ("regression",)
    )
    fitted = [pipeline.fit_unit(dataclasses.replace(spec, unit_seed=u), comp) for u in range(1, units + 1)]
    seeds = list(range(1, units + 1))
    t0 = time.perf_counter()
    for f, seed in zip(fitted, seeds, strict=True):
        pipeline.run_units(sc, [f], [seed], keep_hz=0.01)
    alone = (time.perf_counter() - t0) / units
    t0 = time.perf_counter()
    pipeline.run_units(sc, fitted, seeds, keep_hz=0.01)
    shared = (time.perf_counter() - t0) / units
    per_sample_ns = shared / 3 * 1e9 / 360_000  # three streams: none, the oracle, regression
    print(
        f"{units} units of 1 h (3 streams each) on one core: {alone:.2f} s a unit driven alone, "
        f"{shared:.2f} s sharing one trajectory ({alone / shared:.2f}x; "
        f"{per_sample_ns:.0f} ns per stream-sample)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=8)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--strategies", nargs="+", default=["none", "regression"])
    args = parser.parse_args()
    stages()
    sharing()
    cluster_rates(args.units, args.workers, args.strategies)


if __name__ == "__main__":
    main()
