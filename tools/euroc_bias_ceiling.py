"""How much of a model's open-loop attitude error on EuRoC is its bias rule's: the rule against the best
constant bias, per sequence.

Usage::

    .venv/bin/python tools/euroc_bias_ceiling.py MODEL.json [MODEL.json ...] [--sequences A B ...]
        [--folder euroc]

Each model (``sins fit --dataset euroc/... --out MODEL.json``, or ``tools/euroc_benchmark.py --models
DIR``) corrects each sequence (by default the five judged ones of ``tools/euroc_benchmark.py``) and is
judged by its absolute orientation error (AOE, ``sins.compensation.unit_bias.open_loop_deg``) twice: with
the bias its rule estimates from the readings before each one (what ``sins evaluate`` does), and with the
one constant bias that gives the least AOE, found by Nelder–Mead on the AOE itself, against the
sequence's reference. The second is an oracle, not a method: it reads the judged sequence's reference,
and says how far a perfect estimate of a constant bias would take the model. The gap between the two
columns is the rule's share of the error; what is left in the second, the model's (and the bias's drift
within the sequence). Two more columns split the rule's share by axis: the rule's estimate across
gravity with the best constant's along it, and the other way round (gravity's direction in the body:
the mean specific force over the sequence).
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

import numpy as np
from euroc_benchmark import JUDGE  # the published split's judged sequences (tools/ is on the path)
from scipy.optimize import minimize

from sins import compensation, io
from sins.compensation import unit_bias
from sins.core.series import ImuIncrements


def _without(readings: ImuIncrements, bias_rad_s: np.ndarray) -> ImuIncrements:
    """``readings`` less a bias (constant (3,) or one per step (n, 3)), rad/s."""
    dt = np.diff(readings.t)[:, None]
    return ImuIncrements(t=readings.t, dtheta_b=readings.dtheta_b - bias_rad_s * dt, dv_b=readings.dv_b)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("models", nargs="+", type=Path)
    p.add_argument("--sequences", nargs="+", default=JUDGE)
    p.add_argument("--folder", default="euroc")
    args = p.parse_args(argv)
    for path in args.models:
        model = compensation.load(path)
        rule_doc = getattr(model, "unit_bias_", None)
        if not isinstance(rule_doc, dict):
            raise SystemExit(f"{path}: not fitted on several recordings (no bias rule)")
        rule = unit_bias.BiasRule.from_dict(rule_doc)
        if rule.mode == unit_bias.READINGS:
            raise SystemExit(f"{path}: leaves the gyro as read (bias rule {rule.mode}): no rule to judge")
        print(f"{path.name}: {model.label}, bias rule {rule.mode}")
        print(f"  {'sequence':<18} {'rule':>7} {'best constant':>14} {'rule across':>12} {'rule along':>11}"
              "  best bias, mrad/s")  # fmt: skip
        by_rule, best, across, along = [], [], [], []
        for name in args.sequences:
            rec = io.read(dataset=f"{args.folder}/{name}").beside_reference()
            out = model.correct_increments(rec.imu)
            track = unit_bias.bias_track(rule, out)
            by_rule.append(unit_bias.open_loop_deg(_without(out, track), rec))
            found = minimize(
                lambda b_mrad_s: unit_bias.open_loop_deg(_without(out, np.asarray(b_mrad_s) * 1e-3), rec),  # noqa: B023
                track[-1] * 1e3,  # the rule's last estimate, a start near the answer
                method="Nelder-Mead",
                options={"xatol": 1e-3, "fatol": 1e-3, "maxfev": 600},
            )
            best.append(float(found.fun))
            up = out.dv_b.sum(axis=0) / np.linalg.norm(out.dv_b.sum(axis=0))  # gravity's reaction, body
            oracle = np.asarray(found.x) * 1e-3
            rule_along, oracle_along = np.outer(track @ up, up), np.outer(oracle @ up, up)
            across.append(unit_bias.open_loop_deg(_without(out, track - rule_along + oracle @ up * up), rec))
            along.append(unit_bias.open_loop_deg(_without(out, oracle - oracle_along + rule_along), rec))
            print(f"  {name:<18} {by_rule[-1]:7.2f} {best[-1]:14.2f} {across[-1]:12.2f} {along[-1]:11.2f}"
                  f"  {np.round(found.x, 3).tolist()}")  # fmt: skip
        print(f"  {'mean':<18} {statistics.fmean(by_rule):7.2f} {statistics.fmean(best):14.2f} "
              f"{statistics.fmean(across):12.2f} {statistics.fmean(along):11.2f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
