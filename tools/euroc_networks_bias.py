"""Where the seed paper's networks gain over least squares on EuRoC's held-back training recordings: through
the bias or beyond it.

Usage::

    .venv/bin/python tools/euroc_networks_bias.py [--strategies mlp_seed kohonen_pure mlp_pure]
        [--folder euroc] [--recordings NAME ...] [--json OUT.json]

Each of the published split's six training recordings is held back in turn (their references levelled
first where their world frame tilts from gravity, as ``sins fit`` levels them); least squares
(``regression``) and each network, its guard lifted, are fitted on the other five
(``sins.compensation.referenced.fit_several``, each its own bias rule) and the held-back recording's
open-loop attitude (AOE) is taken three ways: with each model's own rule for the recording's bias (what
``sins evaluate`` does); with least squares' rule's bias track for every model (the same bias taken out
of each); and with the one constant bias that gives each model the least AOE, found against the
held-back recording's own reference (an oracle, not a method: what the model leaves once the bias is
perfect, as ``tools/euroc_bias_ceiling.py`` finds it). Prints each recording's figures and, per way,
each network's mean gain over least squares (positive: the network is better) with its standard error
over the six. No judged sequence is read. About 3 min on 2 cores. ``--recordings`` (names in
``--folder``) holds other recordings back in turn: a unit's parts that ``tools/another_unit.py --keep
DIR`` wrote, say.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from euroc_benchmark import TRAIN  # the published split's training sequences (tools/ is on the path)
from euroc_bias_ceiling import best_constant, without

from sins import io
from sins.compensation import referenced, registry, unit_bias, world_tilt

WAYS = ("own rule", "least squares' track", "oracle constant")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--strategies", nargs="+", default=["mlp_seed", "kohonen_pure", "mlp_pure"])
    p.add_argument("--folder", default="euroc", help="the data root's folder of the .npz recordings")
    p.add_argument("--recordings", nargs="+", default=TRAIN, help="held back in turn (default: EuRoC's six)")
    p.add_argument("--json", type=Path, help="write every figure here")
    args = p.parse_args()
    strategies = ["regression", *args.strategies]
    names = list(args.recordings)
    # Each reference levelled where its world frame tilts from gravity, as sins fit levels them before
    # its fits and its guard's folds (fitting.fit_several).
    recs = [
        world_tilt.levelled(io.read(dataset=f"{args.folder}/{n}").beside_reference(), 1.0)[0] for n in names
    ]
    guarded = set(registry.strategy_names(taking="guard"))
    aoe = {s: {w: [] for w in WAYS} for s in strategies}
    for k, (name, rec) in enumerate(zip(names, recs, strict=True)):
        others = [r for i, r in enumerate(recs) if i != k]
        ls_track = np.zeros(0)
        for s in strategies:
            started = time.perf_counter()
            params = {"guard": False} if s in guarded else None
            model = referenced.fit_several(s, others, params=params).strategy
            corrected = model.correct_increments(rec.imu)
            if s == "regression":  # first: its rule's track is every model's in the second way
                ls_track = unit_bias.bias_track(unit_bias.BiasRule.from_dict(model.unit_bias_), corrected)
            figures = (
                unit_bias.open_loop_deg(model.correct_recording(rec.imu), rec),
                unit_bias.open_loop_deg(without(corrected, ls_track), rec),
                float(best_constant(corrected, rec, ls_track[-1]).fun),
            )
            for way, value in zip(WAYS, figures, strict=True):
                aoe[s][way].append(value)
            took = time.perf_counter() - started
            cells = "  ".join(f"{w} {v:6.3f}°" for w, v in zip(WAYS, figures, strict=True))
            print(f"{name:<16} {s:<13} {cells}  ({took:.0f} s)", flush=True)
    for way in WAYS:
        base = np.array(aoe["regression"][way])
        for s in args.strategies:
            gain = base - np.array(aoe[s][way])
            se = gain.std(ddof=1) / np.sqrt(len(gain))
            print(f"{way:<21} {s:<13} gain over least squares {gain.mean():+.3f}° ± {se:.3f}° "
                  f"({gain.mean() / se:.1f} standard errors)")  # fmt: skip
    if args.json:
        io.write_report(args.json, {"recordings": names, "aoe_deg": aoe})  # atomic; never a user's own file


if __name__ == "__main__":
    main()
