"""Start-up of the ``sins`` command: ``sins --version``, ``sins --help`` and a subcommand's ``--help``,
whole process, and where ``python -X importtime`` says the import time goes.

Usage::

    .venv/bin/python tools/bench_startup.py [--repeat 9]

Prints, for each command, the median and spread of the wall time of fresh processes (the venv's
``sins`` entry point, after one warm-up that fills the file cache), then the ten slowest imports of
``sins --help`` by cumulative time and whether numpy, scipy, torch, numba or matplotlib were loaded.
The target is 1 s for ``--version`` and ``--help`` (docs/speed.md); timings on a shared machine are
noisy, so compare figures within one run of this script.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SINS = Path(sys.executable).with_name("sins")
COMMANDS = (["--version"], ["--help"], ["run", "--help"], ["bias", "--help"])
HEAVY = ("numpy", "scipy", "torch", "numba", "matplotlib", "rerun")


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


if __name__ == "__main__":
    main()
