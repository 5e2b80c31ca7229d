"""Benchmark of `sins characterise`: a 6-hour, 100 Hz static recording in memory, and the command on a
long CSV.

Usage::

    .venv/bin/python tools/bench_characterise.py [--hours 6] [--rate 100]
    .venv/bin/python tools/bench_characterise.py --csv-rows 10000000 [--constant]

In memory: the recording is generated with numpy (white noise, a Gauss–Markov bias, a rate random walk on
each channel) and held in memory (reading a CSV of that size is the file reader's cost, not this one's).
Prints the wall time of the characterisation (Allan curves, ramps, the terms' selection), of the model
file and of the closing check (the model simulated for the whole length through sins's IMU stream), and
the process's peak resident memory (the recording itself included). Issue 32's target: 6 hours at 100 Hz
in 15 s or less and 1 GB or less.

``--csv-rows N``: writes a static recording of ``N`` rows at 100 Hz (pyarrow's CSV writer, in a temporary
folder; ``--constant``: every row the same, issue 35's case, which is refused at once) and runs
``sins characterise FILE --static`` on it in a child process: its wall time and peak resident memory.
"""

from __future__ import annotations

import argparse
import math
import resource
import subprocess
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


def _peak_mb(who: int = resource.RUSAGE_SELF) -> float:
    peak = resource.getrusage(who).ru_maxrss
    return peak / (1024.0 * 1024.0) if sys.platform == "darwin" else peak / 1024.0


def in_memory(hours: float, rate: float) -> None:
    """Characterise a generated recording held in memory; print the figures."""
    dt = 1.0 / rate
    rows = int(hours * 3600.0 * rate)
    x = _recording(rows, dt)
    print(f"{rows} rows ({hours:g} h at {rate:g} Hz), 6 channels; after generating: {_peak_mb():.0f} MB")
    t0, cpu0 = time.perf_counter(), time.process_time()
    res = analysis.residual(np.arange(rows) * dt, x, None, "bench")
    result = analysis.characterise(res)
    t1 = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        model_file.write_model(Path(folder) / "unit.toml", result)
    model = model_file.imu_model(result)
    t2 = time.perf_counter()
    closing = check.closing_check(result, model)
    t3 = time.perf_counter()
    print(f"characterise (Allan curves, ramps, terms of 6 channels): {t1 - t0:.2f} s")
    print(f"model file: {t2 - t1:.3f} s")
    print(f"closing check (simulate {hours:g} h, Allan curves, compare): {t3 - t2:.2f} s")
    cpu = time.process_time() - cpu0  # beside the wall time: on a shared machine the two part
    print(f"total: {t3 - t0:.2f} s ({cpu:.2f} s of CPU); peak resident memory {_peak_mb():.0f} MB; "
          f"partings: {len(closing.partings)}")  # fmt: skip


def on_csv(rows: int, constant: bool) -> None:
    """Write a static CSV of ``rows`` rows and run the command on it in a child; print the figures."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    rng = np.random.default_rng(7)
    columns = {"t": np.arange(rows) * 0.01}
    for i, name in enumerate(("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")):
        level = (7e-5, 0.0, 3e-5, 0.0, 0.0, -9.8)[i]
        noise = np.zeros(rows) if constant else (3e-4 if i < 3 else 1e-2) * rng.standard_normal(rows)
        columns[name] = level + noise
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "static.csv"
        start = time.perf_counter()
        with path.open("wb") as fh:  # pyarrow quotes the names of its own header, which sins refuses
            fh.write((",".join(columns) + "\n").encode())
            pacsv.write_csv(pa.table(columns), fh, pacsv.WriteOptions(include_header=False))
        del columns
        print(
            f"wrote {rows} rows ({path.stat().st_size / 1e6:.0f} MB) in {time.perf_counter() - start:.1f} s"
        )
        start = time.perf_counter()
        cmd = [sys.executable, "-m", "sins.cli", "characterise", str(path), "--static"]
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        wall = time.perf_counter() - start
    last = (proc.stderr.strip() or proc.stdout.strip()).splitlines()[-1:]
    print(f"sins characterise --static: exit {proc.returncode} in {wall:.1f} s, peak resident memory "
          f"{_peak_mb(resource.RUSAGE_CHILDREN):.0f} MB; {last[0] if last else ''}")  # fmt: skip


def main() -> None:
    """Run the benchmark and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--hours", type=float, default=6.0)
    parser.add_argument("--rate", type=float, default=100.0)
    parser.add_argument("--csv-rows", type=int, default=0)
    parser.add_argument("--constant", action="store_true")
    args = parser.parse_args()
    if args.csv_rows:
        on_csv(args.csv_rows, args.constant)
    else:
        in_memory(args.hours, args.rate)


if __name__ == "__main__":
    main()
