"""Wall time and memory of a command and every process under it: ``make test`` by default.

Usage::

    SINS_DATA=../shared/data .venv/bin/python tools/bench_suite_memory.py [-- COMMAND ...]

The process tree is sampled every ``--every`` seconds (0.5 by default) from ``/proc/PID/smaps_rollup``
(Linux only). Printed at the end: the wall time, the exit status, and three peaks, each the largest
over the samples: the tree's PSS (shared pages, such as a library's code mapped by both test workers,
counted once between the processes that share them: the closest figure to what the tree takes from
the machine), the tree's plain sum of RSS (shared pages counted in every process), and the largest
single process's RSS (what ``/usr/bin/time -v`` reports as "Maximum resident set size" for a tree,
and the figure the ``make test`` bar of issue 33 is stated in). A process that lives less than one
sampling interval can be missed; ``/usr/bin/time -v`` beside it catches the largest process exactly.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
KIB_PER_GIB = 2**20


def _children() -> dict[int, list[int]]:
    """Every process's children, by parent pid, from one pass over ``/proc``."""
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            # the command name (in parentheses) may hold spaces: the fields after its ")" are fixed
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:  # the process ended between the listing and the read
            continue
        parent = int(stat.rsplit(")", 1)[1].split()[1])
        children.setdefault(parent, []).append(int(entry))
    return children


def tree(root: int) -> list[int]:
    """``root`` and all its descendants now."""
    children = _children()
    pids = [root]
    for pid in pids:  # grows as it goes: breadth first
        pids.extend(children.get(pid, []))
    return pids


def rss_pss_kib(pid: int) -> tuple[int, int]:
    """A process's resident and proportional set sizes (KiB); zeros if it has ended."""
    rss = pss = 0
    try:
        with open(f"/proc/{pid}/smaps_rollup") as rollup:
            for line in rollup:
                if line.startswith("Rss:"):
                    rss = int(line.split()[1])
                elif line.startswith("Pss:"):
                    pss = int(line.split()[1])
    except OSError:
        pass
    return rss, pss


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--every", type=float, default=0.5, help="sampling interval, s (default 0.5)")
    parser.add_argument("command", nargs="*", default=["make", "test"], help="default: make test")
    args = parser.parse_args()
    if not Path("/proc/self/smaps_rollup").exists():
        sys.exit("bench_suite_memory: needs Linux's /proc/PID/smaps_rollup")
    start = time.monotonic()
    process = subprocess.Popen(args.command, cwd=ROOT)
    peak_pss = peak_rss_sum = peak_largest = 0
    while process.poll() is None:
        sizes = [rss_pss_kib(pid) for pid in tree(process.pid)]
        peak_rss_sum = max(peak_rss_sum, sum(rss for rss, _ in sizes))
        peak_pss = max(peak_pss, sum(pss for _, pss in sizes))
        peak_largest = max([peak_largest] + [rss for rss, _ in sizes])
        time.sleep(args.every)
    wall = time.monotonic() - start
    print(
        f"{' '.join(args.command)}: {wall / 60:.1f} min, exit {process.returncode}; peaks: "
        f"tree PSS {peak_pss / KIB_PER_GIB:.2f} GiB, tree RSS sum {peak_rss_sum / KIB_PER_GIB:.2f} GiB, "
        f"largest process {peak_largest / KIB_PER_GIB:.2f} GiB ({peak_largest:,} KiB)"
    )
    return process.returncode


if __name__ == "__main__":
    sys.exit(main())
