"""How long a rig session must be for regression to drift like the oracle over an hour.

Usage::

    .venv/bin/python tools/bench_rig_length.py [--units 20] [--scales 1 4 16] [--minutes 60]

Units with only the seed model's linear errors plus white noise (tactical grade, the
same errors on every power-on). Each unit is calibrated on the 24-position +
rate-table rig with every dwell multiplied by ``scale`` (rig at 25 Hz: the fitted
coefficients' standard error depends on how long the rig dwells, not on its sampling
rate, since the noise is specified as a density). Regression is fitted on the fit
portion (70 % of every phase); the oracle knows the unit's coefficients. Both correct
the same corrupted stream of a drive (vertical channel damped), so the difference is
the calibration's alone. Prints, per rig length, the mean final horizontal error over
the units for each strategy and the ratio of the means; and, for the same units
without noise, the same ratio (the regression's exactness).
"""

from __future__ import annotations

import argparse
import statistics
import time

from bench_strategies import drive  # tools/ is on the path when a tool is run as a script

from sins import compensation, imu
from sins.imu import calibration
from sins.imu import spec as imu_spec
from sins.nav import strapdown
from sins.nav.metrics import nav_errors, summarize

SEED_LINEAR = tuple(name for name in imu.BASELINE if not name.endswith(".noise"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=20)
    parser.add_argument("--scales", type=float, nargs="+", default=[1.0, 4.0, 16.0])
    parser.add_argument("--minutes", type=float, default=60.0)
    args = parser.parse_args()

    truth, ideal, temp = drive(args.minutes)  # the drive bench_strategies.py measures
    start = strapdown.InitialState.from_series(truth)
    print(f"{args.units} tactical units, seed linear errors + white noise; drive {truth.t[-1] / 60:.1f} min")
    print(f"{'rig':>10} {'noise':>6} {'oracle m':>18} {'regression m':>18} {'ratio of means':>15}")

    def drift(strategy: compensation.Strategy, corrupted: object) -> float:
        corrected = strategy.correct_increments(corrupted, temp)  # type: ignore[arg-type]
        sol = strapdown.integrate(corrected, start, vertical="damp", h_ref=truth.h)
        return summarize(nav_errors(sol, truth)).final_horizontal_m

    for scale in args.scales:
        rig = calibration.RigProcedure(
            rate_hz=25.0,
            position_dwell_s=20.0 * scale,
            rate_table=calibration.RateTable(dwell_s=10.0 * scale),
        )
        for noisy in (True, False):
            if not noisy and scale != args.scales[0]:
                continue  # exactness does not depend on the rig's length
            started = time.perf_counter()
            oracle_m, regression_m = [], []
            for seed in range(args.units):
                model = imu_spec.draw_unit("tactical", seed).only(*(imu.BASELINE if noisy else SEED_LINEAR))
                data = calibration.simulate_rig(rig, model, seed=seed)
                fit, _ = data.split(0.3)
                # Another power-on: the drive's noise is not the rig's.
                corrupted = model.corrupt_increments(ideal, temp=temp, seed=10_000 + seed)
                oracle_m.append(drift(compensation.Oracle(model), corrupted))
                regression_m.append(drift(compensation.make("regression").fit(fit), corrupted))
            minutes = data.t[-1] / 60.0
            o, r = statistics.mean(oracle_m), statistics.mean(regression_m)
            print(
                f"{minutes:6.0f} min {'yes' if noisy else 'no':>6} "
                f"{o:9.4g} ± {statistics.stdev(oracle_m):6.3g} "
                f"{r:9.4g} ± {statistics.stdev(regression_m):6.3g} "
                f"{r / o:15.3f}   ({time.perf_counter() - started:.0f} s)",
                flush=True,
            )


if __name__ == "__main__":
    main()
