"""What compensation buys on real sensors: every strategy fitted against a reference and judged on data it
was not fitted on.

Usage::

    .venv/bin/python tools/real_sensors.py [--strategies NAME ...] [--interval-s 1.0] [--json OUT.json]
        [--skip-broad] [--skip-psins]

* **BROAD** (unit B, optical motion capture): fitted on trial 05, judged on 18, and the other way round:
  the gyro integrated alone from the first optical orientation, BROAD's total / heading / inclination
  RMSE over the movement rows (``sins.compensation.judging.open_loop_attitude``), as fitted and with the
  gyro bias
  taken again from the judged trial's opening rest (what a user does with a calibration from another
  day). The time to fit on one trial and judge the other is printed beside each strategy.
* **PSINS drive** (MEMS against the FOG-INS): fitted on the first 70 s, judged over the last 30 s: the
  corrected MEMS navigating free inertial from the FOG-INS state at 70 s (vertical held), RMS attitude and
  velocity errors and the horizontal error at the end (``sins.compensation.judging.drive_errors``);
  beside the raw
  MEMS, the file's own ``eb0``/``db0`` and ``bias_only`` (the PSINS demo filter's model fitted here).

Every figure is a judgement on readings the fit did not see. The VQF and Madgwick figures beside BROAD's
are ``tools/broad_reference.py``'s; the Ferraris calibration against imucal is
``tools/ferraris_vs_imucal.py``'s.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

import numpy as np

from sins import io
from sins.compensation import Regression, judging, referenced
from sins.errors import SinsInputError
from sins.imu.calibration import SeedModelFit
from sins.io.formats import write_json

STRATEGIES = (
    "none", "bias_only", "regression", "regression_robust", "regression_extended", "regression_rest",
    "regression_window", "mlp", "kohonen", "mlp_pure", "mlp_seed", "kohonen_pure",
)  # fmt: skip


def broad(strategies: tuple[str, ...], interval_s: float) -> dict[str, Any]:
    trials = {n: io.read(dataset=f"broad_{n}").beside_reference() for n in ("05", "18")}
    out: dict[str, Any] = {}
    print("BROAD, unit B: fitted on one trial, judged on the other; total / heading / inclination RMSE, deg")
    columns = ("05 → 18", "18 → 05", "05 → 18, rest bias", "18 → 05, rest bias")
    print(f"{'strategy':<22} " + " ".join(f"{c:>22}" for c in columns) + f" {'s':>6}")
    for name in strategies:
        row: dict[str, Any] = {}
        start = time.perf_counter()
        for fit_on, judge in (("05", "18"), ("18", "05")):
            fit_rec, judge_rec = trials[fit_on], trials[judge]
            assert fit_rec is not None and judge_rec is not None
            try:
                strategy = (
                    None if name == "none" else referenced.fit(name, fit_rec, interval_s=interval_s).strategy
                )
            except SinsInputError as exc:
                row[f"{fit_on}_{judge}"] = {"error": str(exc)}
                continue
            row[f"{fit_on}_{judge}"] = judging.open_loop_attitude(strategy, judge_rec).to_dict()
            row[f"{fit_on}_{judge}_rest_bias"] = judging.open_loop_attitude(
                strategy, judge_rec, bias_from_rest=True
            ).to_dict()
        row["seconds"] = time.perf_counter() - start
        out[name] = row
        cells = [_cell(row.get(k)) for k in ("05_18", "18_05", "05_18_rest_bias", "18_05_rest_bias")]
        print(f"{name:<22} {cells[0]:>22} {cells[1]:>22} {cells[2]:>22} {cells[3]:>22} {row['seconds']:6.1f}")
    return out


def _cell(r: dict[str, Any] | None) -> str:
    if r is None:
        return "-"
    if "error" in r:
        return "not fitted"
    return f"{r['total_deg']:.2f} / {r['heading_deg']:.2f} / {r['inclination_deg']:.2f}"


def psins(strategies: tuple[str, ...], interval_s: float) -> dict[str, Any]:
    from sins.io.datasets.psins_reference import psins_file_biases

    rec = io.read(dataset="psins_vehicle").beside_reference()
    assert rec is not None
    train = judging.between(rec, rec.imu.t[0], 70.0)
    eb0, db0 = psins_file_biases()
    z, nan3 = np.zeros((3, 3)), np.full(3, np.nan)
    file_model = Regression(g_sensitivity=False).set_fit(
        SeedModelFit(eb0, z, z, db0, z, nan3, z, z, nan3, z, np.zeros(6))
    )
    print(
        "\nPSINS drive: fitted on 0-70 s, free inertial from the FOG-INS state over 70-100 s (vertical held)"
    )
    print(
        f"{'strategy':<22} {'roll/pitch/yaw RMS °':>26} {'vN/vE/vD RMS m/s':>24} {'hor end m':>10} {'s':>6}"
    )
    out: dict[str, Any] = {}
    rows: list[tuple[str, Any]] = [("file eb0/db0", file_model)]
    for name, strategy in rows + [(n, n) for n in strategies]:
        start = time.perf_counter()
        try:
            if isinstance(strategy, str):
                strategy = (
                    None
                    if strategy == "none"
                    else referenced.fit(strategy, train, interval_s=interval_s).strategy
                )
        except SinsInputError as exc:
            out[name] = {"error": str(exc)}
            print(f"{name:<22} not fitted: {exc}")
            continue
        d = judging.drive_errors(strategy, rec, 70.0, 100.0)
        seconds = time.perf_counter() - start
        out[name] = {**d.to_dict(), "seconds": seconds}
        att = " / ".join(f"{x:.3f}" for x in d.attitude_rms_deg)
        vel = " / ".join(f"{x:.3f}" for x in d.velocity_rms_mps)
        print(f"{name:<22} {att:>26} {vel:>24} {d.horizontal_final_m:10.2f} {seconds:6.1f}")
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--strategies", nargs="+", default=list(STRATEGIES), metavar="NAME")
    parser.add_argument("--interval-s", type=float, default=1.0)
    parser.add_argument("--json", metavar="OUT.json")
    parser.add_argument("--skip-broad", action="store_true")
    parser.add_argument("--skip-psins", action="store_true")
    args = parser.parse_args()
    strategies = tuple(args.strategies)
    document: dict[str, Any] = {"interval_s": args.interval_s}
    try:
        if not args.skip_broad:
            document["broad"] = broad(strategies, args.interval_s)
        if not args.skip_psins:
            document["psins"] = psins(strategies, args.interval_s)
    except SinsInputError as exc:
        print(f"real_sensors: error: {exc}", file=sys.stderr)
        return 2
    if args.json:
        write_json(args.json, document)
        print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
