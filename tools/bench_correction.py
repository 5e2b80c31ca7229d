"""How fast a model fitted on several recordings corrects a recording: samples a second.

Usage::

    .venv/bin/python tools/bench_correction.py MODEL.json [MODEL.json ...] [--samples 1000000] [--repeat 5]

Each model (``sins fit --dataset ... --out MODEL.json``) corrects a recording of ``--samples`` readings at
200 Hz (EuRoC's V1_01_easy repeated end to end, or a seeded random walk without the data) through
``Strategy.correct_recording``, the path ``sins evaluate`` and ``sins correct`` take: the seed model, the
learner where there is one, and the rule for the recording's own bias. Prints the median over
``--repeat`` runs and the samples a second; the first run (imports, numba's compilation) is not counted.
``--jobs 2 1`` times the learned strategies on each number of threads (their ``n_jobs``; by default the
library's own choice: two from ``residual.THREADED_ROWS`` rows), alternated run by run.
``--matrix-nearest`` also times every ``kohonen`` model's nearest-node search three ways on one thread,
alternated: its winners kept between the fixed point's passes (the default), the k-d tree searched on
every pass, and the (n, k) distance matrix (the training's :func:`sins.compensation.kohonen._nearest`)
on every pass; and says whether the three corrections agree to the last bit.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import Any

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
    p.add_argument("--jobs", type=int, nargs="+", default=[None], help="threads of the learned strategies")
    p.add_argument("--matrix-nearest", action="store_true", help="also time kohonen's nearest-node searches")
    args = p.parse_args(argv)
    imu = _readings(args.samples)
    print(f"{args.samples} readings at 200 Hz; median of {args.repeat} runs after one not counted")
    for path in args.models:
        model = compensation.load(path)
        model.correct_recording(imu)  # imports and compilation
        learned = hasattr(model, "n_jobs")
        jobs = args.jobs if learned else [None]
        times: dict[int | None, list[float]] = {n: [] for n in jobs}
        for _ in range(args.repeat):
            for n in jobs:
                if learned:
                    model.n_jobs = n  # type: ignore[attr-defined]
                start = time.perf_counter()
                model.correct_recording(imu)
                times[n].append(time.perf_counter() - start)
        rule = getattr(model, "unit_bias_", {}).get("mode", "-")
        for n, ts in times.items():
            med = statistics.median(ts)
            threads = "" if not learned else f", n_jobs={n}"
            print(
                f"{path.name}: {model.label}{threads}, bias rule {rule}: {med:.3f} s, "
                f"{args.samples / med / 1e6:.2f} M samples/s"
            )
        if args.matrix_nearest and model.label == "kohonen":
            _compare_nearest(path, imu, args.repeat)
    return 0


def _compare_nearest(path: Path, imu: ImuIncrements, repeat: int) -> None:
    """A ``kohonen`` model's nearest-node search three ways, alternated run by run, on one thread: the
    winners kept between the fixed point's passes (the default: found by a compiled scan of every node
    up to ``kohonen._SCANNED_NODES``, the k-d tree beyond), the k-d tree searched on every pass, and the
    (n, k) distance matrix on every pass. Medians, and whether all agree to the last bit."""
    from sins.compensation import kohonen

    tree, kept = kohonen._Map.winners, kohonen._Map._kept

    def each_pass(self: Any, x: Any, memo: Any) -> Any:
        return self.winners(x[:, self.win_cols])

    def matrix(self: Any, x: Any) -> Any:
        return kohonen._nearest(x, self.codebook)

    paths = {
        "winners kept between passes (a scan or the k-d tree)": (tree, kept),
        "k-d tree searched each pass": (tree, each_pass),
        "distance matrix each pass": (matrix, each_pass),
    }
    times: dict[str, list[float]] = {name: [] for name in paths}
    outs = {}
    try:
        for _ in range(repeat):
            for name, (winners, keep) in paths.items():
                kohonen._Map.winners, kohonen._Map._kept = winners, keep  # type: ignore[method-assign]
                model = compensation.load(path)  # a fresh model: no tree built by another path
                model.n_jobs = 1  # type: ignore[attr-defined]
                model.correct_recording(imu)
                start = time.perf_counter()
                outs[name] = model.correct_recording(imu)
                times[name].append(time.perf_counter() - start)
    finally:
        kohonen._Map.winners, kohonen._Map._kept = tree, kept  # type: ignore[method-assign]
    flat = [np.hstack([o.dtheta_b, o.dv_b]) for o in outs.values() if isinstance(o, ImuIncrements)]
    same = all(np.array_equal(flat[0], f) for f in flat[1:])
    for name, ts in times.items():
        print(f"  {name}, one thread: {statistics.median(ts):.3f} s")
    print(f"  the three corrections {'agree to the last bit' if same else 'DIFFER'}")


if __name__ == "__main__":
    sys.exit(main())
