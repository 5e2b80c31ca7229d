"""The long fuzzing profile: the targets of ``tests/test_fuzz.py``, ``tests/test_fuzz_surfaces.py`` and
``tests/test_fuzz_safety.py`` with many more examples, fresh randomness.

Usage::

    OMP_NUM_THREADS=1 .venv/bin/python tools/fuzz_long.py [--minutes 3] [--examples N] [--targets a,b]
        [--keep DIR] [--seed N]

The budget is shared evenly by the targets; ``--examples N`` ends a target after N examples if its
share of the time has not run out first. Each example is checked for the suite's property (exit 0 with a
sound result, or exit 2 with one line naming the file; no traceback, hang or file left behind); unlike
the CI tests a failure does not stop the run: every distinct failure (by exception type and the deepest
frame in ``sins/``) is counted and its first message printed, and ``--keep DIR`` copies the files of each
failing example there. Prints per target the examples run, the failures found and among them the hangs
(an example past its CPU budget or without progress), the inputs changed (every input is hashed before
and after each command) and the fitted models with a coefficient beyond its class's bounds, the wall
time and the peak resident memory so far of this process and of its children (a campaign's workers);
exits 1 when any failure was found. The memory figures are high-water marks: run a target alone (``--targets
model_files``) for its own peak.
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
import traceback
import warnings
from collections import Counter
from pathlib import Path
from types import ModuleType
from typing import Any

from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import test_fuzz
import test_fuzz_safety
import test_fuzz_surfaces

#: Each target's module (its ``run_target``, ``EXAMPLES`` and base files' maker).
MODULES: dict[str, ModuleType] = {
    **dict.fromkeys(test_fuzz.TARGETS, test_fuzz),
    **dict.fromkeys(test_fuzz_surfaces.TARGETS, test_fuzz_surfaces),
    **dict.fromkeys(test_fuzz_safety.TARGETS, test_fuzz_safety),
}
MAKERS = {
    test_fuzz: test_fuzz.make_base,
    test_fuzz_surfaces: test_fuzz_surfaces.make_surfaces,
    test_fuzz_safety: test_fuzz_safety.make_base,
}
#: Failures counted apart in the report, by the exception's name.
KINDS = {"hangs": "Hang", "inputs changed": "InputChanged", "beyond bounds": "BeyondBounds"}


class _Spent(Exception):
    """The target's time budget or examples are spent: ends hypothesis's run."""


def _signature(exc: BaseException) -> str:
    """Exception type and the deepest frame in sins/ (else the last frame): one per distinct bug."""
    frames = traceback.extract_tb(exc.__traceback__)
    ours = [f for f in frames if "/sins/" in f.filename] or frames[-1:]
    where = f"{Path(ours[-1].filename).name}:{ours[-1].lineno} {ours[-1].name}" if ours else "?"
    return f"{type(exc).__name__} at {where}"


def fuzz(
    name: str, base: Any, seconds: float, examples: int | None, seed: int | None
) -> tuple[int, Counter[str], dict[str, str]]:
    """Run target ``name`` for about ``seconds`` (at most ``examples``): examples run, failures by
    signature, first messages."""
    module = MODULES[name]
    failures: Counter[str] = Counter()
    first: dict[str, str] = {}
    deadline = time.monotonic() + seconds
    before = module.EXAMPLES[name]

    def spent() -> bool:
        return time.monotonic() > deadline or (
            examples is not None and module.EXAMPLES[name] - before >= examples
        )

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
        if spent():
            raise _Spent
        try:
            module.run_target(name, base, data)
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
        if isinstance(exc, _Spent) or spent():  # the replay after _Spent ends early
            return module.EXAMPLES[name] - before, failures, first
        failures[_signature(exc)] += 1
        first.setdefault(_signature(exc), " ".join(str(exc).split())[:400])
    return module.EXAMPLES[name] - before, failures, first


def _peak_mb() -> tuple[float, float]:
    """Peak resident memory so far of this process and of its waited-for children, MB."""
    kib = (resource.getrusage(who).ru_maxrss for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    return tuple(k / 1024 for k in kib)  # type: ignore[return-value]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=3.0, help="total budget, shared by the targets")
    parser.add_argument("--examples", type=int, help="at most this many examples per target")
    parser.add_argument("--targets", default=",".join(MODULES), help="comma-separated targets")
    parser.add_argument("--keep", type=Path, help="copy the files of failing examples into this folder")
    parser.add_argument("--seed", type=int, help="seed hypothesis (default: fresh randomness)")
    args = parser.parse_args()
    # Every warning printed, every time (Python's default prints each place once): a warning is a line
    # on the user's terminal, and an example that prints one before its error fails the property.
    warnings.simplefilter("always")
    names = [n.strip() for n in args.targets.split(",") if n.strip()]
    unknown = [n for n in names if n not in MODULES]
    if unknown:
        parser.error(f"unknown targets {unknown}; known: {', '.join(MODULES)}")
    if args.keep:
        args.keep.mkdir(parents=True, exist_ok=True)
        test_fuzz.KEEP_FAILURES.append(args.keep)
    with tempfile.TemporaryDirectory() as folder:
        bases: dict[ModuleType, Any] = {}
        seconds = 60.0 * args.minutes / len(names)
        total = examples = 0
        kinds = dict.fromkeys(KINDS, 0)
        print(f"{'target':<22} {'examples':>9} {'failures':>9} {'hangs':>6} {'changed':>8} {'beyond':>7} "
              f"{'wall s':>7} {'peak MB':>8} {'children':>8}  (about {seconds:.0f} s each)")  # fmt: skip
        for name in names:
            module = MODULES[name]
            if module not in bases:
                bases[module] = MAKERS[module](Path(tempfile.mkdtemp(dir=folder)))
            started = time.monotonic()
            count, failures, first = fuzz(name, bases[module], seconds, args.examples, args.seed)
            total += sum(failures.values())
            examples += count
            found = {
                k: sum(n for key, n in failures.items() if key.startswith(f"{e} ")) for k, e in KINDS.items()
            }
            for k, n in found.items():
                kinds[k] += n
            mine, children = _peak_mb()
            wall = time.monotonic() - started
            print(f"{name:<22} {count:>9} {sum(failures.values()):>9} {found['hangs']:>6} "
                  f"{found['inputs changed']:>8} {found['beyond bounds']:>7} {wall:>7.0f} {mine:>8.0f} "
                  f"{children:>8.0f}", flush=True)  # fmt: skip
            for key, n in failures.most_common():
                print(f"    {n:>4} x {key}: {first[key]}", flush=True)
    fits = test_fuzz_safety.FITS
    if fits["models"]:
        print(f"fits written and checked against their class: {fits['models']} models, {fits['kept']} "
              f"coefficients kept within the bounds, {fits['held']} held at zero")  # fmt: skip
    counted = ", ".join(f"{n} {k}" for k, n in kinds.items())
    print(
        f"{examples} examples, {total} failing ({counted})"
        if total
        else f"{examples} examples, no failures ({counted})"
    )
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
