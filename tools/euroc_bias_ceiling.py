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
the mean specific force over the sequence). The last, ``own matrix``, is a second oracle: a bias and a
gyro matrix (scale and misalignment, error = b + M ω) fitted by least squares on the sequence's own
reference (rotation residuals over its 0.2 s intervals against their mean rate, on top of the model's
correction), its bias then the best constant as above, and its largest term: what is left where the
sequence's gyro differs from the model's beyond a bias. Run on the training sequences (``--sequences``)
it says whether such a matrix of a recording's own would have been worth estimating at all.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path
from typing import Any

import numpy as np
from euroc_benchmark import JUDGE  # the published split's judged sequences (tools/ is on the path)
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from sins import compensation, io
from sins.compensation import unit_bias
from sins.core.series import ImuIncrements, ReferencedRecording
from sins.nav import attitude

#: The oracle matrix's intervals, s: long enough that the reference's noise is small against their turn.
_OWN_SPAN_S = 0.2


def without(readings: ImuIncrements, bias_rad_s: np.ndarray) -> ImuIncrements:
    """``readings`` less a bias (constant (3,) or one per step (n, 3)), rad/s."""
    dt = np.diff(readings.t)[:, None]
    return ImuIncrements(t=readings.t, dtheta_b=readings.dtheta_b - bias_rad_s * dt, dv_b=readings.dv_b)


def _own_matrix(readings: ImuIncrements, rec: ReferencedRecording) -> tuple[float, str]:
    """AOE with a bias and gyro matrix fitted on ``rec``'s own reference (an oracle), and the matrix's
    largest term, ``"y←x 26.2 mrad"``."""
    first = int(np.searchsorted(readings.t, rec.reference.t[0]))
    q_nb = attitude.propagate_increments(readings.dtheta_b[first:], rec.reference.q_nb[0])
    t_ref = rec.reference.t
    at = np.clip(np.searchsorted(readings.t, t_ref) - first, 0, len(q_nb) - 1)
    pick = np.unique(np.searchsorted(t_ref, np.arange(t_ref[0], t_ref[-1], _OWN_SPAN_S)))
    a, b = pick[:-1], pick[1:]
    est, ref = Rotation.from_quat(q_nb[at]), Rotation.from_quat(rec.reference.q_nb)
    turn = est[a].inv() * est[b]
    span = (t_ref[b] - t_ref[a])[:, None]
    residual = ((ref[a].inv() * ref[b]).inv() * turn).as_rotvec() / span
    rows = np.column_stack([np.ones(len(a)), turn.as_rotvec() / span])
    coef = np.linalg.lstsq(rows, residual, rcond=None)[0]  # (4, 3): the bias, then M transposed
    m = coef[1:].T
    scaled = ImuIncrements(readings.t, readings.dtheta_b - readings.dtheta_b @ m.T, readings.dv_b)
    i, j = np.unravel_index(int(np.argmax(np.abs(m))), m.shape)
    return best_constant(scaled, rec, coef[0]).fun, f"{'xyz'[i]}←{'xyz'[j]} {m[i, j] * 1e3:.1f} mrad"


def best_constant(readings: ImuIncrements, rec: ReferencedRecording, start_rad_s: np.ndarray) -> Any:
    """The constant bias of least AOE (Nelder–Mead on the AOE itself, from ``start_rad_s``)."""
    return minimize(
        lambda b_mrad_s: unit_bias.open_loop_deg(without(readings, np.asarray(b_mrad_s) * 1e-3), rec),
        start_rad_s * 1e3,
        method="Nelder-Mead",
        options={"xatol": 1e-3, "fatol": 1e-3, "maxfev": 600},
    )


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
              f" {'own matrix':>11}  largest term    best bias, mrad/s")  # fmt: skip
        by_rule, best, across, along, own = [], [], [], [], []
        for name in args.sequences:
            rec = io.read(dataset=f"{args.folder}/{name}").beside_reference()
            out = model.correct_increments(rec.imu)
            track = unit_bias.bias_track(rule, out)
            by_rule.append(unit_bias.open_loop_deg(without(out, track), rec))
            found = best_constant(out, rec, track[-1])  # the rule's last estimate, a start near the answer
            best.append(float(found.fun))
            up = out.dv_b.sum(axis=0) / np.linalg.norm(out.dv_b.sum(axis=0))  # gravity's reaction, body
            oracle = np.asarray(found.x) * 1e-3
            rule_along, oracle_along = np.outer(track @ up, up), np.outer(oracle @ up, up)
            across.append(unit_bias.open_loop_deg(without(out, track - rule_along + oracle @ up * up), rec))
            along.append(unit_bias.open_loop_deg(without(out, oracle - oracle_along + rule_along), rec))
            own_deg, largest = _own_matrix(out, rec)
            own.append(own_deg)
            print(f"  {name:<18} {by_rule[-1]:7.2f} {best[-1]:14.2f} {across[-1]:12.2f} {along[-1]:11.2f}"
                  f" {own_deg:11.2f}  {largest:<15} {np.round(found.x, 3).tolist()}")  # fmt: skip
        means = [statistics.fmean(v) for v in (by_rule, best, across, along, own)]
        widths = (7, 14, 12, 11, 11)
        print(f"  {'mean':<18} " + " ".join(f"{m:{w}.2f}" for m, w in zip(means, widths, strict=True)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
