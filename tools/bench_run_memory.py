"""Wall time and peak memory of ``sins run`` with an IMU model and compensation, for any duration.

Usage::

    .venv/bin/python tools/bench_run_memory.py [--scenario car_drive_compensated] [--hours 1 6]
        [--repeats 3] [--source TREE]

Each duration is the scenario's segments repeated that many times (the shipped drive lasts an hour),
run as a fresh process under ``/usr/bin/time -v`` (``--repeats`` times; the median wall time and the
largest peak RSS are printed). ``--source`` runs another checkout of sins instead (``PYTHONPATH``), to
compare two versions in one sitting: the machine is shared, so compare figures of one run only.
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def stretched(scenario: Path, hours: int, folder: Path) -> Path:
    """The scenario with its segments repeated ``hours`` times (a one-hour drive made ``hours`` long)."""
    text = scenario.read_text()
    head, _, segments = text.partition("[[segment]]")
    out = folder / f"{scenario.stem}_{hours}x.toml"
    out.write_text(head + "\n".join(["[[segment]]" + segments] * hours))
    return out


def measure(path: Path, source: Path | None) -> tuple[float, float]:
    """Wall seconds and peak RSS (MB) of one ``sins run`` process."""
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    if source is not None:
        env["PYTHONPATH"] = str(source)
    cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "sins.cli", "run", str(path)]
    # Run beside the scenario, not in a checkout: ``python -m`` puts the working directory first on
    # the path, which would import that checkout's sins whatever PYTHONPATH says.
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=path.parent)
    if done.returncode != 0:
        raise SystemExit(f"sins run {path} failed:\n{done.stderr[-2000:]}")
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\d+):([\d.]+)", done.stderr)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr)
    assert wall and rss, done.stderr[-500:]
    return 60.0 * float(wall.group(1)) + float(wall.group(2)), int(rss.group(1)) / 1024.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="car_drive_compensated")
    parser.add_argument("--hours", type=int, nargs="+", default=[1, 6])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--source", type=Path, help="another sins checkout to run instead")
    args = parser.parse_args()
    scenario = ROOT / "scenarios" / f"{args.scenario}.toml"
    print(f"sins run {args.scenario} ({args.source or ROOT}), {args.repeats} fresh processes per duration")
    print(f"{'hours':>5}  {'median s':>9}  {'range s':>13}  {'peak RSS MB':>11}")
    with tempfile.TemporaryDirectory() as tmp:
        for hours in args.hours:
            path = stretched(scenario, hours, Path(tmp))
            runs = [measure(path, args.source) for _ in range(args.repeats)]
            walls = [w for w, _ in runs]
            print(
                f"{hours:>5}  {statistics.median(walls):9.1f}  {min(walls):6.1f}-{max(walls):6.1f}"
                f"  {max(r for _, r in runs):11.0f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
