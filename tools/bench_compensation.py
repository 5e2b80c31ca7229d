"""Benchmark of the compensation strategies' cost: fitting on about 100,000 samples, correcting an hour.

Usage::

    .venv/bin/python tools/bench_compensation.py [--repeat 3] [--threads N] [--strategies ...]

The fitting session is another tool's procedure (``tests/numpy_rigs.py``, numpy alone):
46 random orientations and a table to 250 °/s in seven mounts, 10 -> 40 °C, 100 Hz,
about 100,000 rows, of the issue's baseline unit with a gyro scale nonlinearity
(so that the learners have something to learn). Prints per strategy the median fit
time and the median time to correct one hour of 100 Hz readings (360,000 rows, rate
form, with temperature), over ``--repeat`` runs.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import numpy_rigs

from sins import compensation
from sins.series import CalibrationData

STRATEGIES = ("regression", "regression_robust", "regression_extended", "mlp", "kohonen", "mlp_pure",
              "kohonen_pure")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--threads", type=int, default=0, help="torch threads (0: torch's default)")
    parser.add_argument("--strategies", nargs="+", default=list(STRATEGIES))
    args = parser.parse_args()
    import torch

    if args.threads:
        torch.set_num_threads(args.threads)
    rng = np.random.default_rng(0)
    unit = dataclasses.replace(numpy_rigs.baseline_unit(rng), gyro_k2=np.array([0.0, 2e-5, 0.0]))
    session = numpy_rigs.tumble_and_table(rate_hz=100.0, seed=0, holds=46, hold_s=12.0)
    gyro, accel = unit.read(session.ref_gyro, session.ref_accel, session.temp, 100.0, rng)
    data = CalibrationData(session.t, gyro, accel, session.ref_gyro, session.ref_accel, session.temp)
    hour = 360_000
    index = np.arange(hour) % len(data)
    print(f"{len(data)} fitting rows; correcting {hour} rows; torch threads {torch.get_num_threads()}")
    for name in args.strategies:
        fit_s, correct_s = [], []
        for _ in range(args.repeat):
            strategy = compensation.make(name)
            t0 = time.perf_counter()
            strategy.fit(data)
            fit_s.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            strategy.correct(gyro[index], accel[index], session.temp[index])
            correct_s.append(time.perf_counter() - t0)
        print(
            f"{name:<20} fit median {statistics.median(fit_s):7.2f} s (min {min(fit_s):.2f}, max "
            f"{max(fit_s):.2f})   correct 1 h median {statistics.median(correct_s):6.3f} s"
        )


if __name__ == "__main__":
    main()
