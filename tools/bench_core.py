"""Benchmark of the navigation core: whole-process run and integrate, kernel throughput, peak memory.

Usage::

    .venv/bin/python tools/bench_core.py [--repeat 7] [--out DIR]

Prints medians (and the spread) of repeated measurements, each in a fresh
process after one warm-up run that fills numba's cache. Timings on a shared
machine are noisy: compare figures from one run of this script, not across
runs. Peak memory is the maximum resident set size of the child process.
"""

from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _child_run(args: list[str]) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB) of one child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.perf_counter()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    # ru_maxrss of children is the maximum over all children so far, in KB.
    return wall, max(after, before) / 1024.0


def _peak_rss_mb(args: list[str]) -> float:
    """Peak RSS of one child, measured alone with GNU time's %M when available."""
    try:
        out = subprocess.run(
            ["/usr/bin/time", "-f", "%M", *args], check=True, stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE, text=True, cwd=ROOT,
        )  # fmt: skip
        return int(out.stderr.strip().splitlines()[-1]) / 1024.0
    except (FileNotFoundError, ValueError, subprocess.CalledProcessError):
        return float("nan")


def _median(label: str, args: list[str], repeat: int) -> None:
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)  # warm numba's cache
    times = [_child_run(args)[0] for _ in range(repeat)]
    peak = _peak_rss_mb(args)
    print(
        f"{label:<44} median {statistics.median(times):6.2f} s  (min {min(times):.2f}, max {max(times):.2f}, "
        f"n={repeat})  peak RSS {peak:6.0f} MB"
    )


def _kernel_throughput(repeat: int) -> None:
    from sins import scenario
    from sins.nav import strapdown
    from sins.runs import pipeline

    sc = scenario.load(pipeline.resolve_scenario(pipeline.DEFAULT_SCENARIO))
    truth, imu = pipeline.simulate(sc)
    init = strapdown.InitialState.from_series(truth)
    strapdown.integrate(imu, init)  # load the kernel
    rates = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        strapdown.integrate(imu, init)
        rates.append(len(imu) / (time.perf_counter() - t0))
    label = "integration kernel, one core (car_drive, 360k)"
    print(
        f"{label:<44} median {statistics.median(rates) / 1e6:6.1f} "
        f"M samples/s (min {min(rates) / 1e6:.1f}, max {max(rates) / 1e6:.1f})"
    )
    streams = 8
    dth = np.repeat(imu.dtheta_b[None], streams, axis=0)
    dv = np.repeat(imu.dv_b[None], streams, axis=0)
    strapdown.integrate_batch(imu.t[:1001], dth[:, :1000], dv[:, :1000], init)  # load the kernel
    t0 = time.perf_counter()
    strapdown.integrate_batch(imu.t, dth, dv, init)
    rate = streams * len(imu) / (time.perf_counter() - t0)
    print(f"{'batched kernel, 8 streams, all cores':<44} {rate / 1e6:13.1f} M samples/s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--out", type=Path, help="folder for the 1-hour CSV files (default: a temporary one)")
    args = parser.parse_args()
    sins = [sys.executable, "-m", "sins.cli"]
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}; 1 h at 100 Hz = 360,000 samples")
    _median("sins run (car_drive, 1 h, 100 Hz)", [*sins, "run"], args.repeat)
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or Path(tmp)
        imu, truth = out / "imu.csv", out / "truth.csv"
        subprocess.run([*sins, "simulate", "--imu", str(imu), "--truth", str(truth)], check=True,
                       stdout=subprocess.DEVNULL, cwd=ROOT)  # fmt: skip
        size = (imu.stat().st_size + truth.stat().st_size) / 1e6
        _median(f"sins integrate (360k rows, {size:.0f} MB of CSV)", [*sins, "integrate", str(imu), "--truth",
                str(truth)], args.repeat)  # fmt: skip
    _kernel_throughput(args.repeat)


if __name__ == "__main__":
    main()
