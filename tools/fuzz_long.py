"""The long fuzzing profile: the targets of ``tests/test_fuzz.py`` with many more examples, fresh randomness.

Usage::

    OMP_NUM_THREADS=1 .venv/bin/python tools/fuzz_long.py [--minutes 3] [--targets a,b] [--keep DIR]
        [--seed N]

The budget is shared evenly by the targets. Each example is checked for the suite's property (exit 0
with a sound result, or exit 2 with one line naming the file; no traceback, hang or file left behind);
unlike the CI tests a failure does not stop the run: every distinct failure (by exception type and the
deepest frame in ``sins/``) is counted and its first message printed, and ``--keep DIR`` copies the
files of each failing example there. Prints per target the examples run and the failures found; exits 1
when any failure was found.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import traceback
from collections import Counter
from pathlib import Path

from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import test_fuzz


class _Spent(Exception):
    """The target's time budget is spent: ends hypothesis's run."""


def _signature(exc: BaseException) -> str:
    """Exception type and the deepest frame in sins/ (else the last frame): one per distinct bug."""
    frames = traceback.extract_tb(exc.__traceback__)
    ours = [f for f in frames if "/sins/" in f.filename] or frames[-1:]
    where = f"{Path(ours[-1].filename).name}:{ours[-1].lineno} {ours[-1].name}" if ours else "?"
    return f"{type(exc).__name__} at {where}"


def fuzz(
    name: str, base: test_fuzz.Base, seconds: float, seed: int | None
) -> tuple[int, Counter[str], dict[str, str]]:
    """Run target ``name`` for about ``seconds``: examples run, failures by signature, first messages."""
    failures: Counter[str] = Counter()
    first: dict[str, str] = {}
    deadline = time.monotonic() + seconds
    before = test_fuzz.EXAMPLES[name]

    @settings(
        max_examples=10**9,
        deadline=None,
        database=None,
        derandomize=False,
        phases=[Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    @given(data=st.data())
    def body(data: st.DataObject) -> None:
        if time.monotonic() > deadline:
            raise _Spent
        try:
            test_fuzz.run_target(name, base, data)
        except (Exception, test_fuzz.Hang) as exc:
            key = _signature(exc)
            failures[key] += 1
            first.setdefault(key, " ".join(str(exc).split())[:400])

    if seed is not None:
        from hypothesis import seed as hypothesis_seed

        body = hypothesis_seed(seed)(body)
    try:
        body()
    except KeyboardInterrupt:
        raise
    except BaseException as exc:  # hypothesis's own errors (a flaky strategy, say) are failures too
        if isinstance(exc, _Spent) or time.monotonic() > deadline:  # the replay after _Spent ends early
            return test_fuzz.EXAMPLES[name] - before, failures, first
        failures[_signature(exc)] += 1
        first.setdefault(_signature(exc), " ".join(str(exc).split())[:400])
    return test_fuzz.EXAMPLES[name] - before, failures, first


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=3.0, help="total budget, shared by the targets")
    parser.add_argument("--targets", default=",".join(test_fuzz.TARGETS), help="comma-separated targets")
    parser.add_argument("--keep", type=Path, help="copy the files of failing examples into this folder")
    parser.add_argument("--seed", type=int, help="seed hypothesis (default: fresh randomness)")
    args = parser.parse_args()
    names = [n.strip() for n in args.targets.split(",") if n.strip()]
    unknown = [n for n in names if n not in test_fuzz.TARGETS]
    if unknown:
        parser.error(f"unknown targets {unknown}; known: {', '.join(test_fuzz.TARGETS)}")
    if args.keep:
        args.keep.mkdir(parents=True, exist_ok=True)
        test_fuzz.KEEP_FAILURES.append(args.keep)
    with tempfile.TemporaryDirectory() as folder:
        base = test_fuzz.make_base(Path(folder))
        seconds = 60.0 * args.minutes / len(names)
        total = 0
        print(f"{'target':<22} {'examples':>9} {'failures':>9}  (about {seconds:.0f} s each)")
        for name in names:
            count, failures, first = fuzz(name, base, seconds, args.seed)
            total += sum(failures.values())
            print(f"{name:<22} {count:>9} {sum(failures.values()):>9}", flush=True)
            for key, n in failures.most_common():
                print(f"    {n:>4} x {key}: {first[key]}", flush=True)
    print(f"{total} failing examples" if total else "no failures")
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
