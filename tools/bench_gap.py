"""Withheld-effect validation of the sim-to-real gap diagnosis (``sins gap``).

Usage::

    .venv/bin/python tools/bench_gap.py [--seeds 3] [--scales 1 3] [--effects NAME ...] [--timing]

For every library effect beyond the baseline, every seed, magnitude (``imu_spec.typical_effect``
times ``scale``) and rig procedure: simulate a tactical unit's session with the baseline plus that
effect, diagnose it with the baseline model (the effect withheld), and record what was ranked first
and accepted, and the share of the withheld excess (rms² − floor²) removed. Controls: the baseline
alone (``diagnosis`` should be empty) and two disturbances outside the library (a 0.3 °/s sinusoid
and a 20 °/h bias step on gyro x, which should land in ``unexplained``). ``--timing`` diagnoses one
30-minute, 100 Hz recording and prints the wall time.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import statistics
import time

import numpy as np

from sins import calibration, gap, imu, imu_spec

RIGS = {
    "24pos+table": calibration.RigProcedure(
        position_dwell_s=10.0,
        rate_table=calibration.RateTable(dwell_s=5.0),
        # A chamber cycle, not a ramp: a temperature monotonic in time cannot be told from a drift.
        temperature=calibration.TemperatureProfile((0.0, 300.0, 600.0), (10.0, 40.0, 20.0)),
    ),
    "6pos+fast table": calibration.RigProcedure(
        rate_hz=200.0,
        positions=6,
        position_dwell_s=30.0,
        rate_table=calibration.RateTable(rates_dps=(30.0, 150.0, 300.0), dwell_s=8.0, accel_dps2=300.0),
        temperature=calibration.TemperatureProfile((0.0, 150.0, 400.0), (25.0, 40.0, 10.0)),
    ),
}


def _excess_removed(report: gap.GapReport, sensor: str) -> float:
    before = after = 0.0
    for ch, v in report.channels.items():
        if ch.startswith(sensor):
            before += max(v["rms_before"] ** 2 - v["noise_floor"] ** 2, 0.0)
            after += max(v["rms_after"] ** 2 - v["noise_floor"] ** 2, 0.0)
    return 1.0 - after / before if before > 0 else float("nan")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--scales", type=float, nargs="+", default=[1.0, 3.0])
    parser.add_argument("--effects", nargs="+", default=list(gap.CANDIDATES))
    parser.add_argument("--timing", action="store_true")
    args = parser.parse_args()

    if args.timing:
        rig = calibration.RigProcedure(position_dwell_s=40.0, rate_table=calibration.RateTable(dwell_s=20.0))
        data = calibration.simulate_rig(rig, imu_spec.draw_unit("tactical", 0).only(*imu.BASELINE), seed=0)
        started = time.perf_counter()
        gap.diagnose(data)
        elapsed = time.perf_counter() - started
        print(f"timing: {len(data)} rows ({data.t[-1] / 60:.1f} min at 100 Hz) diagnosed in {elapsed:.1f} s")

    print(
        f"{'injected':<26} {'n':>3} {'ranked 1st':>10} {'accepted':>9} {'excess removed':>15} "
        f"{'after/floor':>12}  diagnosed"
    )
    for name in ["control", *args.effects, "sinusoid (outside)", "bias step (outside)"]:
        first = accepted = 0
        removed, after = [], []
        seen: collections.Counter[str] = collections.Counter()
        cases = 0
        for rig in RIGS.values():
            for seed in range(args.seeds):
                for scale in args.scales if name in gap.CANDIDATES else [1.0]:
                    model = imu_spec.draw_unit("tactical", seed).only(*imu.BASELINE)
                    if name in gap.CANDIDATES:
                        rng = np.random.default_rng([seed, 5])
                        model = model.with_effects(imu_spec.typical_effect(name, rng, scale))
                    data = calibration.simulate_rig(rig, model, seed=seed)
                    if "outside" in name:
                        gyro = data.gyro.copy()
                        if name.startswith("sinusoid"):
                            gyro[:, 0] += np.radians(0.3) * np.sin(2 * np.pi * data.t / 37.0)
                        else:
                            gyro[:, 0] += 20.0 * imu.DEG_PER_H * (data.t > 0.5 * data.t[-1])
                        data = dataclasses.replace(data, gyro=gyro)
                    report = gap.diagnose(data)
                    cases += 1
                    top = report.effects[0].name if report.effects and report.effects[0].score > 0 else "-"
                    seen[report.diagnosis[0] if report.diagnosis else "-"] += 1
                    if name in gap.CANDIDATES:
                        first += top == name
                        accepted += name in report.diagnosis
                        removed.append(_excess_removed(report, name.split(".")[0]))
                        sensor_after = [
                            v["rms_after"] / v["noise_floor"]
                            for ch, v in report.channels.items()
                            if ch.startswith(name.split(".")[0])
                        ]
                        after.append(max(sensor_after))
                    elif name == "control":
                        first += report.diagnosis == []
                    else:
                        first += "gyro.x" in report.unexplained
        removed_ok = [r for r in removed if np.isfinite(r)]
        rm = f"{100 * statistics.median(removed_ok):.0f} %" if removed_ok else "-"
        af = f"{max(after):.3f}" if after else "-"
        label = {"control": "(empty)", "sinusoid (outside)": "(unexpl.)", "bias step (outside)": "(unexpl.)"}
        share = f"{first}/{cases}" + (f" {label[name]}" if name in label else "")
        print(
            f"{name:<26} {cases:>3} {share:>10} {accepted if name in gap.CANDIDATES else '':>9} {rm:>15} "
            f"{af:>12}  " + ", ".join(f"{k} {v}" for k, v in seen.most_common(3)),
            flush=True,
        )


if __name__ == "__main__":
    main()
