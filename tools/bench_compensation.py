"""Benchmark of fitting the compensation strategies on about 100,000 calibration samples.

Usage::

    .venv/bin/python tools/bench_compensation.py [--repeat 3] [--threads N]

A 24-position + rate-table session of a tactical unit with scale nonlinearity and
g² sensitivity; prints the median fit time per strategy and the residual on the
held-back blocks, relative to the oracle.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from sins import calibration, compensation, imu, imu_spec


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--threads", type=int, default=0, help="torch threads (0: torch's default)")
    args = parser.parse_args()
    import torch

    if args.threads:
        torch.set_num_threads(args.threads)
    rng = np.random.default_rng(0)
    model = (
        imu_spec.draw_unit("tactical", 0, 100)
        .only(*imu.BASELINE)
        .with_effects(
            imu.ScaleNonlinearity("gyro", rng.normal(0.0, 3e-3, 3)),
            imu.G2Sensitivity("gyro", rng.normal(0.0, 2e-6, (3, 3, 3))),
        )
    )
    rig = calibration.RigProcedure(
        position_dwell_s=25.0,
        rate_table=calibration.RateTable(rates_dps=(10, 30, 60, 100, 150, 200), dwell_s=12.0),
    )
    data = calibration.simulate_rig(rig, model, seed=0)
    fit, val = data.split(0.2)
    print(f"{len(fit)} fit samples, {len(val)} held back; torch threads {torch.get_num_threads()}")
    oracle = np.array(
        [v["rms_after"] for v in compensation.residual_rms(compensation.Oracle(model), val).values()]
    )
    for name in ("regression", "regression_robust", "kohonen", "mlp"):
        times = []
        for _ in range(args.repeat):
            strategy = compensation.make(name)
            t0 = time.perf_counter()
            strategy.fit(fit)
            times.append(time.perf_counter() - t0)
        after = np.array([v["rms_after"] for v in compensation.residual_rms(strategy, val).values()])
        ratio = after / oracle
        spread = f"(min {min(times):.2f}, max {max(times):.2f})"
        print(
            f"{name:<18} fit median {statistics.median(times):7.2f} s {spread}  "
            f"residual / oracle: gyro {np.round(ratio[:3], 2)}, accel {np.round(ratio[3:], 2)}"
        )


if __name__ == "__main__":
    main()
