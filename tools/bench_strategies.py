"""The paper's question with numbers: strategies × error regimes over many units.

Usage::

    .venv/bin/python tools/bench_strategies.py [--units 20] [--minutes 10] [--regimes linear nonlinear ...]

For every regime and unit: a 24-position + rate-table rig session (the same unit,
another power-on for the grades), each strategy fitted on it, the residual sensor
error on the held-back blocks, and the horizontal drift of a drive of ``--minutes``
with the unit's corrupted IMU after each strategy's correction. Prints mean ±
standard deviation over the units: residual as a ratio to the oracle's (mean over
the six channels), and drift in metres.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

import numpy as np

from sins import compensation, imu
from sins.core.series import ImuIncrements, NavSeries
from sins.imu import calibration
from sins.imu import spec as imu_spec
from sins.nav import motion, strapdown, trajectory
from sins.nav.metrics import nav_errors, summarize

STRATEGIES = ("none", "regression", "regression_robust", "mlp", "kohonen", "mlp_pure", "kohonen_pure")


def unit(regime: str, seed: int) -> tuple[imu.ImuModel, imu.ImuModel]:
    """(rig power-on, drive power-on) models of one unit of a regime."""
    rng = np.random.default_rng([seed, 99])
    if regime in ("navigation", "tactical", "industrial", "consumer"):
        return (imu_spec.draw_unit(regime, seed, 1000 + seed).only(*imu.BASELINE),
                imu_spec.draw_unit(regime, seed, 2000 + seed).only(*imu.BASELINE))  # fmt: skip
    base = imu_spec.draw_unit("tactical", seed).only(*imu.BASELINE)  # no turn-on part: the same each power-on
    if regime == "nonlinear":
        base = base.with_effects(
            imu.ScaleNonlinearity("gyro", rng.normal(0.0, 3e-3, 3)),
            imu.ScaleNonlinearity("accel", rng.normal(0.0, 5e-4, 3)),
            imu.G2Sensitivity("gyro", rng.normal(0.0, 2e-6, (3, 3, 3))),
        )
    return base, base


def drive(minutes: float) -> tuple[NavSeries, ImuIncrements, np.ndarray]:
    """The benchmarks' drive at 100 Hz and 20 °C: 20 s speeding up to 15 m/s, an 81° right turn over
    30 s, then ``minutes`` straight on. Returns the truth, the ideal increments and every sample's
    temperature."""
    segs: list[motion.Segment] = [
        motion.Accelerate(20, 15.0, 2.0),
        motion.Turn(30, np.radians(3.0), 3.0),
        motion.Hold(60 * minutes),
    ]
    path = motion.SegmentMotion.from_segments(motion.Start(np.radians(45.0), 0.1, 200.0), segs)
    truth, ideal = trajectory.generate(path, 100.0)
    return truth, ideal, np.full(len(ideal.t), 20.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=20)
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument(
        "--regimes", nargs="+",
        default=["linear", "nonlinear", "outliers", "navigation", "tactical", "industrial", "consumer"],
    )  # fmt: skip
    args = parser.parse_args()
    import torch

    torch.set_num_threads(1)
    rig = calibration.RigProcedure(position_dwell_s=10.0, rate_table=calibration.RateTable(dwell_s=5.0))
    truth, ideal, temp = drive(args.minutes)
    print(
        f"{args.units} units per regime; drive {truth.t[-1] / 60:.1f} min at 100 Hz, vertical channel damped"
    )
    print(f"{'regime':<11} {'strategy':<18} {'residual × oracle':>20} {'drift m':>22}")
    for regime in args.regimes:
        started = time.perf_counter()
        residual: dict[str, list[float]] = {s: [] for s in ("oracle", *STRATEGIES)}
        drift: dict[str, list[float]] = {s: [] for s in ("oracle", *STRATEGIES)}
        for seed in range(args.units):
            rig_model, drive_model = unit(regime, seed)
            data = calibration.simulate_rig(rig, rig_model, seed=seed)
            fit, held = data.split(0.3)
            if regime == "outliers":  # 2 % gross glitches in the fit data only
                rng = np.random.default_rng(seed)
                bad = rng.choice(len(fit), len(fit) // 50, replace=False)
                gyro, accel = fit.gyro.copy(), fit.accel.copy()
                gyro[bad] += rng.normal(0.0, 0.05, (len(bad), 3))
                accel[bad] += rng.normal(0.0, 2.0, (len(bad), 3))
                fit = dataclasses.replace(fit, gyro=gyro, accel=accel)
            oracle_fit = compensation.residual_rms(compensation.Oracle(rig_model), held)
            oracle_rig = np.array([v["rms_after"] for v in oracle_fit.values()])
            # Another power-on: the drive's noise is not the rig's.
            corrupted = drive_model.corrupt_increments(ideal, temp=temp, seed=10_000 + seed)
            fitted = {s: compensation.make(s).fit(fit) for s in STRATEGIES}
            fitted_all: dict[str, compensation.Strategy] = {
                "oracle": compensation.Oracle(drive_model),
                **fitted,
            }
            for name, strategy in fitted_all.items():
                judged = compensation.Oracle(rig_model) if name == "oracle" else strategy
                rms = np.array([v["rms_after"] for v in compensation.residual_rms(judged, held).values()])
                residual[name].append(float(np.mean(rms / oracle_rig)))
                corrected = strategy.correct_increments(corrupted, temp)
                start = strapdown.InitialState.from_series(truth)
                sol = strapdown.integrate(corrected, start, vertical="damp", h_ref=truth.h)
                drift[name].append(summarize(nav_errors(sol, truth)).final_horizontal_m)
        for name in residual:
            r, d = residual[name], drift[name]
            print(f"{regime:<11} {name:<18} {statistics.mean(r):10.3f} ± {statistics.stdev(r):7.3f} "
                  f"{statistics.mean(d):12.1f} ± {statistics.stdev(d):8.1f}")  # fmt: skip
        print(f"{'':<11} ({time.perf_counter() - started:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
