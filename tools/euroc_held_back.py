"""The learned strategies with their guard lifted, judged on EuRoC's held-back training recordings.

Usage::

    .venv/bin/python tools/euroc_held_back.py [--strategies regression kohonen mlp] [--guard]
        [--folder euroc] [--channels]

Each of the published split's six training recordings is held back in turn (the references levelled
first where their world frame tilts from gravity, as ``sins fit`` levels them): every strategy is fitted on
the other five (``sins.compensation.referenced.fit_several``, its own bias rule chosen on them), the
learners with their guard lifted unless ``--guard`` (with it, the seed paper's networks are fitted as
``sins fit`` fits them, ``sins.compensation.fitting.fit_several``: their own guard holds each of the five
back in turn, and the line says what it wrote), and the held-back recording is corrected as ``sins
evaluate`` corrects it (``correct_recording``: the model, then its rule for the recording's own bias) and
judged by its open-loop attitude (AOE, ``sins.compensation.unit_bias.open_loop_deg``). It says what a
rule fitted on the training recordings alone can know of lifting the guard; no judged sequence is read.
Prints each recording's AOE per strategy, their means, and each learner's mean difference from the first
strategy with its standard error. With ``--channels``, also what each model leaves of every channel on
the held-back recording, as ``tools/euroc_channels.py`` takes it on the judged ones (the RMS over the
reference's intervals of about 1 s, less the recording's own mean: the gyro's turn in millidegrees, the
accelerometer's velocity change in mm/s), and each strategy's mean difference from the first, per channel,
with its standard error over the recordings: the open-loop attitude judges the gyro alone, and the
networks correct the accelerometer too. About 10 min on 2 cores.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np
from euroc_benchmark import TRAIN  # the published split's training sequences (tools/ is on the path)
from euroc_channels import CHANNELS, SCALE, residuals

from sins import io
from sins.compensation import fitting, network_guard, referenced, registry, unit_bias, world_tilt


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--strategies", nargs="+", default=["regression", "kohonen", "mlp"])
    p.add_argument("--guard", action="store_true", help="keep the learners' guard (as sins fit does)")
    p.add_argument("--folder", default="euroc", help="the data root's folder of the .npz recordings")
    p.add_argument("--channels", action="store_true", help="also every channel on the intervals")
    args = p.parse_args()
    # Each reference levelled where its world frame tilts from gravity, as sins fit levels them before its
    # fits and its guards' folds (fitting.fit_several).
    recs = [
        world_tilt.levelled(io.read(dataset=f"{args.folder}/{n}").beside_reference(), 1.0)[0] for n in TRAIN
    ]
    guarded = set(registry.strategy_names(taking="guard"))
    aoe: dict[str, list[float]] = {s: [] for s in args.strategies}
    left: dict[str, list[np.ndarray]] = {s: [] for s in args.strategies}  # per channel, less the mean
    for k, (name, rec) in enumerate(zip(TRAIN, recs, strict=True)):
        others = [r for i, r in enumerate(recs) if i != k]
        for s in args.strategies:
            started = time.perf_counter()
            params = {"guard": False} if s in guarded and not args.guard else None
            written = ""
            if args.guard and network_guard.guards(s):  # as sins fit writes it, its guard five-fold
                names = [n for i, n in enumerate(TRAIN) if i != k]
                model = fitting.fit_several(s, others, names).strategy
                written = f"  wrote {model.name}" + (f", {_parts(model)}" if model.name == s else "")
            else:
                model = referenced.fit_several(s, others, params=params).strategy
            aoe[s].append(unit_bias.open_loop_deg(model.correct_recording(rec.imu), rec))
            if args.channels:
                left[s].append(np.std(residuals(model, rec) * SCALE, axis=0))
            took = time.perf_counter() - started
            print(f"{name:<16} {s:<12} {aoe[s][-1]:7.3f}°  ({took:.0f} s){written}", flush=True)
    first = args.strategies[0]
    for s, values in aoe.items():
        print(f"{s:<12} " + " ".join(f"{v:6.2f}" for v in values) + f"   mean {np.mean(values):.2f}°")
    for s in args.strategies[1:]:
        d = np.array(aoe[s]) - np.array(aoe[first])
        se = d.std(ddof=1) / np.sqrt(len(d))
        print(f"{s} - {first}: {d.mean():+.2f}° ± {se:.2f}° (mean ± standard error)")
    if args.channels:
        _channels(left, first)


def _channels(left: dict[str, list[np.ndarray]], first: str) -> None:
    """Each strategy's mean per channel over the held-back recordings, and its difference from ``first``'s
    in per cent of ``first``'s mean, ± the standard error of that difference over the recordings."""
    print("per channel, less each recording's mean (gyro mdeg, accel mm/s per interval), mean over them:")
    base = np.array(left[first])
    for s, values in left.items():
        mine = np.array(values)
        cells = []
        for c, channel in enumerate(CHANNELS):
            cell = f"{channel} {mine[:, c].mean():6.1f}"
            if s != first:
                d = 100.0 * (mine[:, c] - base[:, c]) / base[:, c].mean()
                cell += f" ({d.mean():+.1f} ± {d.std(ddof=1) / np.sqrt(len(d)):.1f} %)"
            cells.append(cell)
        print(f"  {s:<12} " + "  ".join(cells))


def _parts(model: Any) -> str:
    """Which of a network its guard wrote: whole, its gyro with least squares' accelerometer, or its
    accelerometer beside least squares' gyro and bias rule (``network_guard``)."""
    if "gyro_seed_" in vars(model):
        return "its accelerometer beside least squares' gyro"
    if "accel_seed_" in vars(model):
        return "its gyro with least squares' accelerometer"
    return "whole"


if __name__ == "__main__":
    main()
