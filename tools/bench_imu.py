"""Benchmark of the IMU error model and the rig: corrupting 1 h at 100 Hz, a rig session and its fit.

Usage::

    .venv/bin/python tools/bench_imu.py [--repeat 7]

Prints medians and spreads of in-process timings (after one warm-up each).
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np

from sins import imu, scenario
from sins.imu import calibration
from sins.imu import spec as imu_spec
from sins.nav import trajectory
from sins.runs import pipeline


def _time(label: str, call: Callable[[], object], repeat: int) -> None:
    call()
    runs = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        call()
        runs.append(time.perf_counter() - t0)
    print(f"{label:<58} median {statistics.median(runs):6.3f} s  (min {min(runs):.3f}, max {max(runs):.3f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    sc = scenario.load(pipeline.resolve_scenario("car_drive"))
    truth, ideal = trajectory.generate(scenario.build_motion(sc), sc.rate_hz)
    rates = trajectory.ideal_rates(scenario.build_motion(sc), truth)
    print(f"car_drive: {len(ideal)} samples (1 h at 100 Hz)")
    baseline = imu_spec.draw_unit("tactical", 1, 1).only(*imu.BASELINE)
    grade = imu_spec.draw_unit("tactical", 1, 1)
    rich = grade.with_effects(
        imu.ScaleNonlinearity("gyro", np.full(3, 1e-4)),
        imu.ScaleAsymmetry("accel", np.full(3, 1e-4)),
        imu.G2Sensitivity("gyro", np.full((3, 3, 3), 1e-8)),
        imu.Quantization("gyro", np.full(3, 1e-6)),
    )
    models = (("baseline", baseline), ("grade (+ bias instability)", grade), ("grade + 4 more", rich))
    for name, model in models:
        _time(f"corrupt increments, {name}", lambda m=model: m.corrupt_increments(ideal, seed=3), args.repeat)
        _time(f"corrupt rates, {name}", lambda m=model: m.corrupt_rates(rates, seed=3), args.repeat)
    proc = calibration.RigProcedure()
    data = calibration.simulate_rig(proc, baseline, seed=1)
    print(f"rig session 24pos_ratetable: {len(data)} samples, {len(data.phases)} phases")
    _time("simulate the rig session", lambda: calibration.simulate_rig(proc, baseline, seed=1), args.repeat)
    _time("fit the 33 seed coefficients", lambda: calibration.fit_seed_model(data), args.repeat)


if __name__ == "__main__":
    main()
