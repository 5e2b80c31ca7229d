"""Benchmark of `sins characterise` on a 6-hour, 100 Hz static recording (2.16 million rows, six channels).

Usage::

    .venv/bin/python tools/bench_characterise.py [--hours 6] [--rate 100]

The recording is generated with numpy (white noise, a Gauss–Markov bias, a rate random walk on each
channel) and held in memory: reading a CSV of that size is the file reader's cost, not this one's. Prints
the wall time of the characterisation (Allan curves, the joint fits), of the model file and of the closing
check (the model simulated for 6 hours through sins's IMU stream), and the process's peak resident memory
(the recording itself included).
"""

from __future__ import annotations

import argparse
import math
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.signal import lfilter

from sins.characterise import analysis, check, model_file


def _recording(rows: int, dt: float) -> np.ndarray:
    rng = np.random.default_rng(6)
    out = np.empty((rows, 6))
    for i in range(6):
        scale = 1.0 if i < 3 else 30.0
        phi = math.exp(-dt / 300.0)
        gm = lfilter([1.0], [1.0, -phi], 1e-5 * math.sqrt(1 - phi * phi) * rng.standard_normal(rows))
        out[:, i] = scale * (
            3e-5 / math.sqrt(dt) * rng.standard_normal(rows)
            + gm
            + np.cumsum(1e-8 * math.sqrt(dt) * rng.standard_normal(rows))
        )
    return out


def _peak_mb() -> float:
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / (1024.0 * 1024.0) if sys.platform == "darwin" else peak / 1024.0


def main() -> None:
    """Run the benchmark and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--hours", type=float, default=6.0)
    parser.add_argument("--rate", type=float, default=100.0)
    args = parser.parse_args()
    dt = 1.0 / args.rate
    rows = int(args.hours * 3600.0 * args.rate)
    x = _recording(rows, dt)
    size = f"{rows} rows ({args.hours:g} h at {args.rate:g} Hz), 6 channels"
    print(f"{size}; after generating: {_peak_mb():.0f} MB")
    t0 = time.perf_counter()
    res = analysis.residual(np.arange(rows) * dt, x, None, "bench")
    result = analysis.characterise(res)
    t1 = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        model_file.write_model(Path(folder) / "unit.toml", result)
    model = model_file.imu_model(result)
    t2 = time.perf_counter()
    closing = check.closing_check(result, model)
    t3 = time.perf_counter()
    print(f"characterise (Allan curves and fits, 6 channels): {t1 - t0:.2f} s")
    print(f"model file: {t2 - t1:.3f} s")
    print(f"closing check (simulate {args.hours:g} h, Allan curves, compare): {t3 - t2:.2f} s")
    print(
        f"total: {t3 - t0:.2f} s; peak resident memory {_peak_mb():.0f} MB; partings: {len(closing.partings)}"
    )


if __name__ == "__main__":
    main()
