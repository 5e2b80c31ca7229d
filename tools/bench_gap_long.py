"""``sins gap`` on a long rig recording: wall time and peak memory of the whole command (issue 32).

Usage::

    .venv/bin/python tools/bench_gap_long.py [--minutes 297.5] [--rate 200] [--procedure continuous_tumble]
        [--effect accel.time_offset] [--seed 0] [--csv RECORDING.csv] [--repeats 1] [--where]

Writes a phase-less rig recording with numpy alone (``tests/numpy_gap.py``: the baseline unit plus one
effect at its typical size, printed at 10 significant digits with columns in an order of its own), by
default the issue's: 297.5 minutes at 200 Hz, 3,570,000 rows, an accelerometer time offset withheld;
then runs ``sins gap RECORDING.csv --json`` in a fresh process, as a user would, and prints its wall
time, its peak resident memory (``ru_maxrss`` of the child), the diagnosis and each channel's withheld
RMS against its floor before and after. ``--csv`` keeps the recording there and reuses it when it
exists (writing 3.57 M rows takes about two minutes). ``--where`` runs ``sins gap`` in this process
instead and prints sins's innermost frames at the peak of its resident memory (where to look next).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import numpy_gap as ng

ROOT = Path(__file__).resolve().parents[1]


def _recording(args: argparse.Namespace, folder: Path) -> Path:
    path = Path(args.csv) if args.csv else folder / "long.csv"
    if path.exists():
        print(f"{path}: reused")
        return path
    started = time.perf_counter()
    case = ng.Case(args.effect or "control", args.seed, args.procedure, args.rate, args.minutes, args.temp)
    built = ng.build(case)
    ng.write(built, path)
    rows = len(built.proc.session.t)
    print(f"{path}: {rows} rows ({rows / args.rate / 3600:.2f} h at {args.rate:g} Hz, {case.label}), "
          f"written in {time.perf_counter() - started:.0f} s")  # fmt: skip
    return path


def _run(path: Path, report: Path) -> tuple[float, float, float, str]:
    """``sins gap`` on ``path`` in a fresh process: wall seconds, CPU seconds (user and system), peak
    RSS in MB, and its output."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    before, cpu = usage.ru_maxrss, usage.ru_utime + usage.ru_stime
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "sins.cli", "gap", str(path), "--json", str(report)],
        cwd=ROOT, capture_output=True, text=True, check=False,
    )  # fmt: skip
    seconds = time.perf_counter() - started
    if done.returncode != 0:
        raise SystemExit(f"sins gap failed ({done.returncode}):\n{done.stderr}")
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    if usage.ru_maxrss <= before:
        print("(the peak is no higher than an earlier child's: run one repeat per process to read it)")
    return seconds, usage.ru_utime + usage.ru_stime - cpu, usage.ru_maxrss / 1024.0, done.stdout


def _resident_mb() -> float:
    with open("/proc/self/statm", encoding="ascii") as f:
        return int(f.read().split()[1]) * resource.getpagesize() / 2**20  # as ru_maxrss / 1024


def _run_here(path: Path, report: Path) -> tuple[float, float, float, str]:
    """``sins gap`` in this process, its resident memory read every 20 ms (Linux's ``/proc``): as
    :func:`_run`, and the innermost frames of sins at the peak printed (where to look next)."""
    from sins.cli import main as sins_main

    main_thread, peak, where = threading.get_ident(), [0.0], [""]
    done = threading.Event()

    def watch() -> None:
        while not done.wait(0.02):
            rss = _resident_mb()
            if rss > peak[0]:
                frame = sys._current_frames().get(main_thread)
                stack = [f for f in traceback.extract_stack(frame) if "/sins/" in f.filename][-6:]
                peak[0], where[0] = (
                    rss,
                    " > ".join(f"{Path(f.filename).stem}.{f.name}:{f.lineno}" for f in stack),
                )

    threading.Thread(target=watch, daemon=True).start()
    started, cpu = time.perf_counter(), time.process_time()
    try:
        sins_main(["gap", str(path), "--json", str(report)])
    finally:
        done.set()
    seconds, cpu_s = time.perf_counter() - started, time.process_time() - cpu
    print(f"peak {peak[0]:.0f} MB (sampled) at {where[0]}")
    return seconds, cpu_s, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, ""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=297.5)
    parser.add_argument("--rate", type=float, default=200.0)
    parser.add_argument("--procedure", default="continuous_tumble", choices=list(ng.CLOSED_FORM))
    parser.add_argument("--effect", default="accel.time_offset", help="an effect of numpy_gap.EFFECTS, or ''")
    parser.add_argument("--temp", default="cycle")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--csv", help="keep the recording here (reused if it exists)")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument(
        "--where", action="store_true",
        help="run sins gap in this process instead, and print sins's frames at its peak resident memory",
    )  # fmt: skip
    args = parser.parse_args()
    if args.effect and args.effect not in ng.EFFECTS:
        parser.error(f"unknown effect {args.effect!r}")
    with tempfile.TemporaryDirectory() as folder:
        path = _recording(args, Path(folder))
        for repeat in range(args.repeats):
            run = _run_here if args.where else _run
            seconds, cpu_s, peak_mb, _ = run(path, Path(folder) / "gap.json")
            doc = json.loads((Path(folder) / "gap.json").read_text(encoding="utf-8"))
            took = f"{seconds:.1f} s ({cpu_s:.1f} s of CPU), peak RSS {peak_mb:.0f} MB"
            found = f"diagnosis {doc['diagnosis']}, unexplained {doc['unexplained']}"
            print(f"run {repeat + 1}: sins gap in {took}; {found}")
            for ch, v in doc["channels"].items():
                before, after = v["rms_before"] / v["noise_floor"], v["rms_after"] / v["noise_floor"]
                print(f"  {ch}: before {before:.3f}, after {after:.3f} x the floor")


if __name__ == "__main__":
    main()
