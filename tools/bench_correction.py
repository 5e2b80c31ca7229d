"""How fast a model fitted on several recordings corrects a recording: samples a second.

Usage::

    .venv/bin/python tools/bench_correction.py MODEL.json [MODEL.json ...] [--samples 1000000] [--repeat 5]

Each model (``sins fit --dataset ... --out MODEL.json``) corrects a recording of ``--samples`` readings at
200 Hz (EuRoC's V1_01_easy repeated end to end, or a seeded random walk without the data) through
``Strategy.correct_recording``, the path ``sins evaluate`` and ``sins correct`` take: the seed model, the
learner where there is one, and the rule for the recording's own bias. Prints the median over
``--repeat`` runs and the samples a second; the first run (imports, numba's compilation) is not counted.
``--matrix-nearest`` also times every ``kohonen`` model with its maps' nearest-node search through the
(n, k) distance matrix (the training's :func:`sins.compensation.kohonen._nearest`) instead of the k-d
tree, alternated with it in the same run, and says whether both corrections agree to the last bit.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from sins import compensation, io
from sins.core.series import ImuIncrements


def _readings(samples: int) -> ImuIncrements:
    try:
        rec = io.read(dataset="euroc/V1_01_easy").beside_reference().imu
        reps = -(-samples // len(rec.dtheta_b))
        dtheta = np.tile(rec.dtheta_b, (reps, 1))[:samples]
        dv = np.tile(rec.dv_b, (reps, 1))[:samples]
    except Exception:
        rng = np.random.default_rng(0)
        dtheta = np.cumsum(rng.normal(0, 1e-4, (samples, 3)), axis=0) * 1e-2 + 4e-4
        dv = np.tile([0.0, 0.0, -9.81 / 200.0], (samples, 1)) + rng.normal(0, 1e-3, (samples, 3))
    return ImuIncrements(t=np.arange(samples + 1) / 200.0, dtheta_b=dtheta, dv_b=dv)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("models", nargs="+", type=Path)
    p.add_argument("--samples", type=int, default=1_000_000)
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--matrix-nearest", action="store_true", help="also time kohonen's distance-matrix search")
    args = p.parse_args(argv)
    imu = _readings(args.samples)
    print(f"{args.samples} readings at 200 Hz; median of {args.repeat} runs after one not counted")
    for path in args.models:
        model = compensation.load(path)
        model.correct_recording(imu)  # imports and compilation
        times = []
        for _ in range(args.repeat):
            start = time.perf_counter()
            model.correct_recording(imu)
            times.append(time.perf_counter() - start)
        med = statistics.median(times)
        rule = getattr(model, "unit_bias_", {}).get("mode", "-")
        print(
            f"{path.name}: {model.label}, bias rule {rule}: {med:.3f} s, "
            f"{args.samples / med / 1e6:.2f} M samples/s"
        )
        if args.matrix_nearest and model.label == "kohonen":
            _compare_nearest(path, imu, args.repeat)
    return 0


def _compare_nearest(path: Path, imu: ImuIncrements, repeat: int) -> None:
    """The k-d tree against the distance matrix, alternated run by run; medians and bit-equality."""
    from sins.compensation import kohonen

    tree = kohonen._Map.winners
    paths = {"k-d tree": tree, "distance matrix": lambda self, x: kohonen._nearest(x, self.codebook)}
    times: dict[str, list[float]] = {name: [] for name in paths}
    outs = {}
    try:
        for _ in range(repeat):
            for name, winners in paths.items():
                kohonen._Map.winners = winners  # type: ignore[method-assign]
                model = compensation.load(path)  # a fresh model: no tree built by the other path
                model.correct_recording(imu)
                start = time.perf_counter()
                outs[name] = model.correct_recording(imu)
                times[name].append(time.perf_counter() - start)
    finally:
        kohonen._Map.winners = tree  # type: ignore[method-assign]
    a, b = (np.hstack([o.dtheta_b, o.dv_b]) for o in outs.values() if isinstance(o, ImuIncrements))
    same = np.array_equal(a, b)
    for name, ts in times.items():
        print(f"  nearest node by the {name}: {statistics.median(ts):.3f} s")
    print(f"  the two corrections {'agree to the last bit' if same else 'DIFFER'}")


if __name__ == "__main__":
    sys.exit(main())
