"""Start-up of the ``sins`` command: ``sins --version``, ``sins --help`` and a subcommand's ``--help``,
whole process, and where ``python -X importtime`` says the import time goes.

Usage::

    .venv/bin/python tools/bench_startup.py [--repeat 9]

Prints, for each command, the median and spread of the wall time of fresh processes (the venv's
``sins`` entry point, after one warm-up that fills the file cache), then the ten slowest imports of
``sins --help`` by cumulative time and whether numpy, scipy, torch, numba or matplotlib were loaded.
The target is 1 s for ``--version`` and ``--help`` (docs/speed.md); timings on a shared machine are
noisy, so compare figures within one run of this script.

Then, per command, what its handler imports before its work (:data:`WORK`), timed in fresh
interpreters (median), and which heavy libraries came in with it: every command, every dask worker of a
campaign and every test that runs a command as a process pays these first, and for a small recording
they are most of the command's time. Each heavy library should come in only where it is used.

Last, a campaign worker's first unit in fresh interpreters (import, and one unit of a one-unit campaign
from its pickled description), and which heavy libraries its work brought.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SINS = Path(sys.executable).with_name("sins")
COMMANDS = (["--version"], ["--help"], ["run", "--help"], ["bias", "--help"])
HEAVY = ("numpy", "scipy", "torch", "numba", "matplotlib", "rerun")
#: What each command's handler imports before its work (its first imports).
WORK = {
    "inspect": ["sins.cli", "sins.io.reader"],
    "run": ["sins.cli", "sins.io", "sins.scenario", "sins.runs.pipeline", "sins.scenario.budget"],
    "fit": ["sins.cli", "sins.io.reader", "sins.compensation.registry"],
    "gap": ["sins.cli", "sins.io.reader", "sins.unit_gap.inputs"],
    "campaign worker": ["sins.campaign.unit"],
}
WORK_HEAVY = ("torch", "matplotlib", "pandas", "scipy.signal", "scipy.stats", "scipy.interpolate")
#: A campaign of one tactical unit on the 5 min drive, fitted on the 24-position rig: the unit a worker runs
#: first (:func:`_first_unit`).
UNIT_CAMPAIGN = """name = "startup"
[units]
imu = "tactical"
count = 1
first_seed = 5
[compensation]
rig = "24pos_ratetable"
strategies = ["none", "regression"]
[[scenario]]
file = "car_drive_5min"
"""
_UNIT_PROBE = """
import json, pickle, sys, time
wall, cpu = time.perf_counter(), time.process_time()
import sins.campaign.unit as unit
unit.run_unit(pickle.loads(open({spec!r}, "rb").read()), 0)
print(json.dumps([time.perf_counter() - wall, time.process_time() - cpu,
                  [m for m in {heavy!r} if m in sys.modules]]))
"""
_PROBE = """
import json, sys, time
start = time.perf_counter()
for name in {modules!r}:
    __import__(name)
print(json.dumps([time.perf_counter() - start, [m for m in {heavy!r} if m in sys.modules]]))
"""


def _wall(args: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run([str(SINS), *args], check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
    return time.perf_counter() - t0


def _imports() -> tuple[list[tuple[int, str]], list[str]]:
    """``sins --help``'s imports by cumulative µs (largest first) and the heavy ones it loaded."""
    code = "import sys\nfrom sins.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
    done = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    )
    rows = []
    for line in done.stderr.splitlines():
        if not line.startswith("import time:") or "cumulative" in line:
            continue
        _, cumulative, name = (part.strip() for part in line.removeprefix("import time:").split("|"))
        rows.append((int(cumulative), name))
    loaded = sorted({name.split(".")[0] for _, name in rows} & set(HEAVY))
    return sorted(rows, reverse=True), loaded


def _work(modules: list[str], repeat: int) -> tuple[list[float], list[str]]:
    """Seconds to import ``modules`` in each of ``repeat`` fresh interpreters, and the heavy libraries
    of :data:`WORK_HEAVY` they brought."""
    times, brought = [], []
    for _ in range(repeat):
        code = _PROBE.format(modules=modules, heavy=WORK_HEAVY)
        done = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
        )
        seconds, brought = json.loads(done.stdout)
        times.append(seconds)
    return times, brought


def _first_unit(repeat: int) -> tuple[list[float], list[float], list[str]]:
    """Wall and CPU seconds of a fresh interpreter that imports the worker's task module and runs one unit
    of :data:`UNIT_CAMPAIGN` from its pickled description (what a dask worker receives), and the heavy
    libraries (:data:`WORK_HEAVY`, filterpy) loaded by then; one warm-up run first (numba's cache)."""
    import pickle
    import tempfile

    from sins import campaign

    with tempfile.TemporaryDirectory() as tmp:
        toml, spec = Path(tmp) / "c.toml", Path(tmp) / "spec.pkl"
        toml.write_text(UNIT_CAMPAIGN)
        spec.write_bytes(pickle.dumps(campaign.load(toml)))
        code = _UNIT_PROBE.format(spec=str(spec), heavy=(*WORK_HEAVY, "filterpy"))
        walls, cpus, brought = [], [], []
        for i in range(repeat + 1):
            done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
            wall, cpu, brought = json.loads(done.stdout.splitlines()[-1])
            if i:
                walls.append(wall)
                cpus.append(cpu)
    return walls, cpus, brought


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=9)
    args = parser.parse_args()
    for command in COMMANDS:
        _wall(command)  # warm the file cache
        times = [_wall(command) for _ in range(args.repeat)]
        print(
            f"sins {' '.join(command):<14} median {statistics.median(times):.3f} s "
            f"(spread {min(times):.3f}-{max(times):.3f} s, {args.repeat} fresh processes)"
        )
    rows, loaded = _imports()
    print(f"\nsins --help imports {len(rows)} modules; heavy ones loaded: {', '.join(loaded) or 'none'}")
    print("slowest imports (cumulative):")
    for cumulative, name in rows[:10]:
        print(f"  {cumulative / 1000:8.1f} ms  {name}")
    print("\nwhat each command imports before its work (fresh interpreters):")
    for command, modules in WORK.items():
        times, brought = _work(modules, args.repeat)
        print(
            f"  {command:<16} median {statistics.median(times):.3f} s "
            f"(spread {min(times):.3f}-{max(times):.3f} s)"
            f"   brings {', '.join(brought) or 'none of ' + ', '.join(WORK_HEAVY)}"
        )
    walls, cpus, brought = _first_unit(args.repeat)
    print(
        f"\na campaign worker's first unit (import and one unit, fresh interpreters): median wall "
        f"{statistics.median(walls):.2f} s, CPU {statistics.median(cpus):.2f} s "
        f"(spread {min(cpus):.2f}-{max(cpus):.2f} s); loaded by then: {', '.join(brought) or 'none of them'}"
    )


if __name__ == "__main__":
    main()
