"""The gap diagnosis's generalisation benchmark: recordings sins did not make (issue 19, item 3).

Usage::

    .venv/bin/python tools/bench_gap_independent.py [--seeds 5] [--effects NAME ...] [--controls NAME ...]
        [--jobs 2] [--timing] [--verbose] [--save CASES.json]
    .venv/bin/python tools/bench_gap_independent.py --load CASES.json [MORE.json ...] [--effects ...]

Every recording is written by ``tests/numpy_gap.py`` with numpy alone, on numpy_rigs's unit (the
issue's baseline: 0.05 °/s gyro bias, 2e-3 scale and misalignment, 0.02 °/s/g g-sensitivity, white
noise of 0.01 °/s and 1 mg per sample at 100 Hz) plus one effect of sins's library at a tactical unit's
size (as sins's ``typical_effect`` states it), over a phase-less procedure drawn per case: random
orientations then a table in several mounts, the six faces then an axis table, or continuous tumbling
(closed-form, or numpy_rigs's own), at 50-400 Hz for 5-30 minutes (at most 180,000 rows), under a
chamber cycle, a soak, a ramp or a constant temperature. Each is printed at 10 significant digits with
columns in an order of its own and no phase column, read by sins's reader as ``sins gap RECORDING.csv``
reads it, and diagnosed with the baseline model (holdout 0.3: the recording's last 30 %).

Besides every library effect, the two cases the issue names: ``gyro.saturation (tail)``, gyros clipped
at 200 °/s where only the table's last mount reaches 250 °/s, in the recording's last minutes; and
``gyro.quantization (0.06 °/s)``, gyros quantised to 0.06 °/s under 0.01 °/s of noise at 100 Hz, rates
from Earth's to 250 °/s. Controls: the baseline alone (``diagnosis`` should be empty) and two
disturbances outside the library on gyro x, a 0.3 °/s sinusoid (37 s) and a 20 °/h bias step half-way
(``gyro.x`` should be ``unexplained``, nothing diagnosed).

Whether an effect could be found at all is judged by ``numpy_gap.oracle_nats``: its own contribution
to the readings (noise-free, with and without it) less what the baseline's columns absorb by least
squares over the recording, in units of the white noise, a 30 % share (the withheld rows lie all
through it); half its sum of squares is what a model that knew it would gain there, in nats. Below
``numpy_gap.OBSERVABLE_NATS`` (9) the case is "unobservable". Whether it could be told from the library
effect most like it is judged the same way (``numpy_gap.identifiable_nats``): beyond its closest rival's
columns as well, or, for a Gauss-Markov bias, the Kullback-Leibler divergence from the random walk it
tends to, ``T / (4 τ)`` per channel; below the same threshold the case is "unidentifiable".

Prints per injected effect the rank-1 rate (overall, and over observable cases), how often it was
accepted and named at all, the worst ``rms_after``/floor on its sensor's channels where accepted, and
what was diagnosed first; the controls' clean rate and the disturbances' rate; the overall rank-1 rates;
and one line per effect that was missed, naming what came first instead. ``--timing`` diagnoses one
30-minute, 100 Hz phase-less recording and prints the wall time. ``--save`` writes every case's result;
``--load`` summarises saved results without running anything (a later file's case replacing an earlier
one's).
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import numpy_gap as ng
from bench_gap import run_cases  # the same runner as sins's own rig bench (tools/ is on the path)

from sins import gap, io
from sins.runs import pipeline

FORMAT = "sins-bench-gap-independent"


def _diagnosed(built: ng.Built, folder: Path) -> tuple[gap.GapReport, float]:
    """``sins gap`` on the case's file: written as numpy_rigs prints, read as the CLI reads it."""
    path = ng.write(built, folder / "recording.csv")
    data, _ = pipeline.gap_data(io.read(path))
    started = time.perf_counter()
    report = gap.diagnose(data, holdout=ng.HOLDOUT)
    return report, time.perf_counter() - started


def run_case(name: str, seed: int) -> dict[str, Any]:
    """Build one case of ``name`` (an effect, one of the issue's cases, or a control), diagnose it."""
    case = ng.draw_case(name, seed)
    built = ng.build(case)
    ident, rival = built.identifiable()
    with tempfile.TemporaryDirectory() as folder:
        report, seconds = _diagnosed(built, Path(folder))
    effect = case.effect_name
    sensor = effect.split(".")[0] if effect else ""
    ranked = report.effects[0].name if report.effects and report.effects[0].score > 0 else "-"
    after = [
        v["rms_after"] / v["noise_floor"]
        for ch, v in report.channels.items()
        if effect and ch.startswith(sensor) and effect in report.diagnosis
    ]
    return {
        "name": name,
        "seed": seed,
        "procedure": case.procedure,
        "rate_hz": case.rate_hz,
        "minutes": case.minutes,
        "temp": case.temp,
        "effect": effect or "-",
        "ranked": ranked,
        "first": report.diagnosis[0] if report.diagnosis else "-",
        "named": bool(effect) and any(e.name == effect for e in report.effects),
        "diagnosis": report.diagnosis,
        "unexplained": report.unexplained,
        "outside": [o.to_dict() for o in report.outside],
        "best": (report.effects[0].name, report.effects[0].score) if report.effects else ("-", float("nan")),
        "oracle": built.oracle(),
        "identifiable": ident,
        "rival": rival,
        "after": max(after, default=float("nan")),
        "rows": len(built.proc.session.t),
        "seconds": seconds,
    }


def _passed(case: dict[str, Any]) -> bool:
    if case["name"] == "control":
        return not case["diagnosis"]
    if "outside" in case["name"]:
        return "gyro.x" in case["unexplained"] and not case["diagnosis"]
    return bool(case["ranked"] == case["effect"])


def _observable(case: dict[str, Any]) -> bool:
    return bool(case["oracle"] >= ng.OBSERVABLE_NATS)


def _identifiable(case: dict[str, Any]) -> bool:
    """Observable, and told from its closest rival by as much (cases saved before the rival oracle
    count as identifiable)."""
    return _observable(case) and bool(case.get("identifiable", np.inf) >= ng.OBSERVABLE_NATS)


def _why(case: dict[str, Any]) -> str:
    if not _observable(case):
        return " [unobs.]"
    if not _identifiable(case):
        return f" [unident.: {case['identifiable']:.1f} beyond {case['rival']}]"
    return ""


def _share(cases: list[dict[str, Any]]) -> str:
    return f"{sum(_passed(c) for c in cases)}/{len(cases)}" if cases else "-"


def _effect_line(name: str, cases: list[dict[str, Any]]) -> str:
    seen = [c for c in cases if _observable(c)]
    unseen = len(cases) - len(seen)
    observable = _share(seen) + (f" ({unseen} unobs.)" if unseen else "")
    accepted = sum(c["effect"] in c["diagnosis"] for c in cases)
    named = sum(c["named"] for c in cases)
    after = [c["after"] for c in cases if np.isfinite(c["after"])]
    af = f"{min(after):.3f}-{max(after):.3f}" if after else "-"
    firsts = collections.Counter(c["first"] for c in cases)
    return (
        f"{name:<30} {len(cases):>3} {_share(cases):>8} {observable:>18} {accepted:>9} {named:>6} {af:>12}  "
        + ", ".join(f"{k} {v}" for k, v in firsts.most_common(3))
    )


def _control_line(name: str, cases: list[dict[str, Any]]) -> str:
    what = "clean (diagnosis empty)" if name == "control" else "gyro.x unexplained, nothing diagnosed"
    top = max(cases, key=lambda c: c["best"][1] if np.isfinite(c["best"][1]) else -np.inf)["best"]
    diagnosed = collections.Counter(n for c in cases for n in c["diagnosis"])
    also = (
        f"; diagnosed instead: {', '.join(f'{k} {v}' for k, v in diagnosed.most_common(3))}"
        if diagnosed
        else ""
    )
    return (
        f"{name}: {what} in {_share(cases)}; best candidate's score highest {top[1]:.1f} nats ({top[0]})"
        + also
    )


def _case_line(case: dict[str, Any]) -> str:
    return (
        f"  {case['name']:<30} seed {case['seed']} {case['procedure']} {case['rate_hz']:g} Hz "
        f"{case['minutes']:g} min {case['temp']}: ranked {case['ranked']}, diagnosis {case['diagnosis']}, "
        f"unexplained {case['unexplained']}, after/floor {case['after']:.3f}, oracle {case['oracle']:.3g} "
        f"nats, best {case['best'][0]} {case['best'][1]:.1f}, {case['rows']} rows in {case['seconds']:.1f} s"
    )


def _report(names: list[str], cases: list[dict[str, Any]]) -> None:
    """Per-effect lines, the controls' rates, the overall rank-1 rates and the misses."""
    results = {n: [c for c in cases if c["name"] == n] for n in names}
    effects = [n for n in names if n not in ng.CONTROLS and results[n]]
    if effects:
        print(
            f"{'injected':<30} {'n':>3} {'rank 1':>8} {'rank 1 observable':>18} {'accepted':>9} "
            f"{'named':>6} {'after/floor':>12}  diagnosed first"
        )
        for name in effects:
            print(_effect_line(name, results[name]))
    print()
    for name in names:
        if name in ng.CONTROLS and results[name]:
            print(_control_line(name, results[name]))
    for label, keep in (
        ("all cases", lambda c: True),
        ("observable cases", _observable),
        ("observable and identifiable cases", _identifiable),
    ):
        chosen = [c for n in effects for c in results[n] if keep(c)]
        if chosen:
            k, n = sum(_passed(c) for c in chosen), len(chosen)
            print(f"\n{label}: injected effect ranked first in {k}/{n} ({100 * k / n:.1f} %)")
    misses = [n for n in effects if any(not _passed(c) for c in results[n])]
    if misses:
        print(
            "\nmisses: injected -> ranked first instead (- = nothing above 0), count; [unobservable], "
            "[unidentifiable: beyond its rival, nats]"
        )
        for name in misses:
            missed = collections.Counter((c["ranked"], _why(c)) for c in results[name] if not _passed(c))
            print(f"  {name:<30} " + ", ".join(f"{r}{u} {k}" for (r, u), k in missed.most_common()))
    seconds = [c["seconds"] for c in cases]
    if seconds:
        median, most = statistics.median(seconds), max(seconds)
        print(f"\ndiagnosis wall time per case: median {median:.1f} s, max {most:.1f} s")


def _load(paths: list[str]) -> list[dict[str, Any]]:
    cases: dict[tuple[str, int], dict[str, Any]] = {}
    for path in paths:
        try:
            doc = json.loads(Path(path).read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as exc:
            raise SystemExit(f"{path}: cannot read saved cases ({exc})") from None
        if not isinstance(doc, dict) or doc.get("format") != FORMAT:
            raise SystemExit(
                f'{path}: not saved by bench_gap_independent.py --save (no "format": "{FORMAT}")'
            )
        for case in doc["cases"]:
            cases[case["name"], case["seed"]] = case
    return list(cases.values())


def _timing() -> None:
    """One 30-minute, 100 Hz phase-less recording of the baseline unit, diagnosed."""
    case = ng.Case("control", 0, "tumble_and_table", 100.0, 30.0)
    built = ng.build(case)
    with tempfile.TemporaryDirectory() as folder:
        started = time.perf_counter()
        report, seconds = _diagnosed(built, Path(folder))
        total = time.perf_counter() - started
    rows = len(built.proc.session.t)
    print(
        f"timing: {rows} rows ({built.proc.session.t[-1] / 60:.1f} min at 100 Hz, no phases) diagnosed in "
        f"{seconds:.1f} s ({total:.1f} s with writing and reading the file); diagnosis {report.diagnosis}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--effects", nargs="*", default=[*ng.EFFECTS, *ng.ISSUE_CASES])
    parser.add_argument("--controls", nargs="*", default=list(ng.CONTROLS))
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--verbose", action="store_true", help="print every case as it finishes")
    parser.add_argument("--timing", action="store_true")
    parser.add_argument("--save", metavar="CASES.json", help="write every case's result here")
    parser.add_argument(
        "--load", metavar="CASES.json", nargs="+",
        help="summarise cases saved by --save instead of running any (later files replace earlier cases)",
    )  # fmt: skip
    args = parser.parse_args()
    for name in [*args.effects, *args.controls]:
        if name not in (*ng.EFFECTS, *ng.ISSUE_CASES, *ng.CONTROLS):
            parser.error(f"unknown case {name!r}")
    names = args.effects + [n for n in ng.CONTROLS if n in args.controls]
    if args.load:
        cases = [c for c in _load(args.load) if c["name"] in names]
        print(f"{len(cases)} cases from {', '.join(args.load)}\n")
        _report(names, cases)
        return
    if args.timing:
        _timing()
    jobs = [(name, seed) for name in names for seed in range(args.seeds)]
    if not jobs:
        return
    cases = run_cases(run_case, jobs, args.jobs, _case_line if args.verbose else None)
    if args.save:
        io.write_json(args.save, {"format": FORMAT, "cases": cases})
    _report(names, cases)


if __name__ == "__main__":
    main()
