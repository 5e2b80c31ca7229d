"""How long ``sins gap`` takes on a real 150 s, 200 Hz recording (issue 42's bar: 60 s on 2 cores).

Usage::

    .venv/bin/python tools/bench_gap_real.py [--dataset euroc/MH_02_easy] [--repeats 2] [--statistic auto]

Runs ``sins gap --dataset NAME --json OUT`` in a process of its own, as a user does (reading the
recording, choosing the statistic, the diagnosis, the report), ``--repeats`` times, and prints each run's
wall time, its CPU time (user and system, the process and its children) and its largest resident set.
EuRoC's MH_02_easy is 150.0 s at 200 Hz (29,992 rows); the data root is ``SINS_DATA`` or ``../shared/data``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_once(dataset: str, statistic: str, out: Path) -> tuple[float, float, float, dict]:
    """One ``sins gap`` process: wall s, CPU s, peak RSS MB, and its report."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run(
        [str(ROOT / ".venv" / "bin" / "sins"), "gap", "--dataset", dataset, "--statistic", statistic,
         "--json", str(out)],
        check=True, capture_output=True, env={**os.environ, "OMP_NUM_THREADS": "1"},
    )  # fmt: skip
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, after.ru_maxrss / 1024.0, json.loads(out.read_text())


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dataset", default="euroc/MH_02_easy")
    p.add_argument("--repeats", type=int, default=2)
    p.add_argument("--statistic", default="auto", choices=("auto", "samples", "intervals"))
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.repeats):
            wall, cpu, rss, report = run_once(args.dataset, args.statistic, Path(tmp) / "gap.json")
            print(
                f"run {k + 1}: {wall:.1f} s wall, {cpu:.1f} s CPU, peak {rss:.0f} MB; statistic "
                f"{report['statistic']['kind']}, diagnosis {', '.join(report['diagnosis']) or 'nothing'}"
            )
    print(f"({os.cpu_count()} CPUs; load average {', '.join(f'{x:.2f}' for x in os.getloadavg())})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
