"""Withheld-effect validation of the sim-to-real gap diagnosis (``sins gap``).

Usage::

    .venv/bin/python tools/bench_gap.py [--seeds 3] [--control-seeds 20] [--scales 1 3] [--effects NAME ...]
        [--controls NAME ...] [--rigs NAME ...] [--jobs 2] [--timing] [--verbose] [--save CASES.json]
        [--load CASES.json ...] [--against REFERENCE.json]
    .venv/bin/python tools/bench_gap.py --load CASES.json [MORE.json ...] [--effects ...] [--rigs ...]

For every library effect beyond the baseline, every seed, magnitude (``imu_spec.typical_effect``
times ``scale``) and rig procedure: simulate a tactical unit's session with the baseline plus that
effect, diagnose it with the baseline model (the effect withheld), and record what was ranked first
and accepted, and the share of the withheld excess (rms² − floor²) removed. Controls: the baseline
alone (``diagnosis`` should be empty) and two disturbances outside the library (a 0.3 °/s sinusoid
and a 20 °/h bias step on gyro x, which should land in ``unexplained``), over ``--control-seeds``
seeds each: the target for the controls is a rate (≥ 95 % empty), and six cases cannot show one, so
each control's line gives the one-sided 95 % Clopper–Pearson lower bound on its pass rate, and how far
below zero its best candidate's score stayed. Prints one line per injected effect, then the confusion
matrix (injected × first diagnosed). ``--timing`` diagnoses one 30-minute, 100 Hz recording and
prints the wall time. ``--save`` writes every case's result; ``--load`` summarises saved results
without running anything, a later file's case replacing an earlier one's (a rig rerun after a
change, merged with the rest). ``--against`` compares case by case with a saved run (the reference
run of the current figures is ``tools/reference/bench_gap_cases.json``): the cases it passed that
these do not are listed as lost.

Every rig procedure turns the unit as well as holding it still: an effect a rig never excites (a gyro
scale factor under Earth rate alone) leaves the readings a baseline unit's, so its case would test
nothing beyond the controls (``tests/test_gap.py::test_effects_a_rig_never_excites_are_not_diagnosed``).

Whether a case's effect could be found at all is judged by an oracle that knows it, independently of
the diagnosis: the effect's own contribution to the readings (the session simulated without white
noise, with and without it), less what the baseline's columns (bias, scale and misalignment,
g-sensitivity) absorb by least squares over the whole session, in units of the white noise on the
withheld rows. Its half sum of squares is the withheld log-likelihood gain an oracle model would make
under white noise; below :data:`OBSERVABLE_NATS` no model could pass the diagnosis's significance
threshold (``gap.SIGNIFICANT_NATS``, 6.0 nats) with strong evidence to spare (``gap.TIE_NATS``, 3),
and the case is "unobservable".

Whether it could be told from the library effect most like it is judged the same way: what is left of
its contribution once the baseline's columns *and* a rival's (every other regressor effect of the
sensor, fitted per channel) have absorbed what they can. A Gauss–Markov bias's rival is the random walk
it tends to for τ → ∞; there the oracle is the Kullback–Leibler divergence of the two processes' path
laws, ``T / (4 τ)`` per channel over a session of ``T`` seconds (Girsanov, observed without noise: an
upper bound). Below :data:`OBSERVABLE_NATS` against some rival, the case is "unidentifiable": ranking
the injected effect first there is a coin toss, and the diagnosis should report the two as tied.
"""

from __future__ import annotations

import argparse
import collections
import concurrent.futures
import dataclasses
import json
import os
import statistics
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import tqdm
from scipy import stats

from sins import gap, imu, io
from sins.imu import calibration
from sins.imu import spec as imu_spec

RIGS = {
    "24pos+table": calibration.RigProcedure(
        position_dwell_s=10.0,
        rate_table=calibration.RateTable(dwell_s=5.0),
        # A chamber cycle, not a ramp: a temperature monotonic in time cannot be told from a drift.
        temperature=calibration.TemperatureProfile((0.0, 300.0, 600.0), (10.0, 40.0, 20.0)),
    ),
    # Faces and edges down: gravity also at 0.71 g on two axes.
    "18pos+fast table": calibration.RigProcedure(
        rate_hz=200.0,
        positions=18,
        position_dwell_s=10.0,
        rate_table=calibration.RateTable(rates_dps=(30.0, 150.0, 300.0), dwell_s=8.0, accel_dps2=300.0),
        temperature=calibration.TemperatureProfile((0.0, 150.0, 400.0), (25.0, 40.0, 10.0)),
    ),
    # An hour of static holds at 10 Hz (the session a random bias's correlation time needs), with
    # faces, edges and corners down, then four minutes on the table while the chamber warms: without
    # them the rig never turns, and no rate-dependent effect could show in its readings.
    "26pos hour + table": calibration.RigProcedure(
        rate_hz=10.0,
        positions=26,
        position_dwell_s=3600.0 / 26,
        rate_table=calibration.RateTable(rates_dps=(20.0, 100.0, 200.0), dwell_s=5.0),
        temperature=calibration.TemperatureProfile(
            (0.0, 1200.0, 2400.0, 3600.0, 3900.0), (20.0, 40.0, 10.0, 30.0, 40.0)
        ),
    ),
}
CONTROLS = ("control", "sinusoid (outside)", "bias step (outside)")
#: The fraction of every phase withheld, by the diagnosis and the oracle alike.
HOLDOUT = 0.3
#: The oracle's withheld gain below which an effect counts as unobservable on a rig (see above).
OBSERVABLE_NATS = 10.0


def oracle_gains(unit: imu.ImuModel, effect: imu.Effect, rig: str, seed: int) -> tuple[float, float, str]:
    """What a model that knew ``effect`` would gain on the withheld rows, in nats: beyond the
    baseline's columns, and beyond them and its closest rival (also returned)."""
    quiet = unit.only(*(n for n in imu.BASELINE if not n.endswith(".noise")))
    with_effect = calibration.simulate_rig(RIGS[rig], quiet.with_effects(effect), seed=seed)
    without = calibration.simulate_rig(RIGS[rig], quiet, seed=seed)
    sensor = effect.sensor
    delta = getattr(with_effect, sensor) - getattr(without, sensor)
    base = gap.baseline_columns(sensor, with_effect.ref_gyro, with_effect.ref_accel)
    withheld = with_effect.held_back(HOLDOUT)
    white = unit.get(f"{sensor}.noise")
    assert isinstance(white, imu.Noise)
    noise = white.density * np.sqrt(RIGS[rig].rate_hz)  # per sample

    def gain(columns: list[np.ndarray]) -> float:
        total = 0.0
        for i, extra in enumerate(columns):
            a = np.hstack([base, extra])
            a = a / np.maximum(np.abs(a).max(axis=0), 1e-300)
            left = delta[:, i] - a @ np.linalg.lstsq(a, delta[:, i], rcond=None)[0]
            total += 0.5 * float(np.sum((left[withheld] / noise[i]) ** 2))
        return total

    observable = gain([np.empty((len(delta), 0))] * 3)
    rivals: dict[str, float] = {}
    if isinstance(effect, imu.BiasInstability):
        rivals[f"{sensor}.rate_random_walk"] = float(np.sum(with_effect.t[-1] / (4.0 * effect.tau)))
    for name, cand in gap.CANDIDATES.items():
        if cand.sensor != sensor or cand.kind != "regressors" or name == f"{sensor}.{effect.kind}":
            continue
        if "temperature" not in name or with_effect.temp is not None:
            rivals[name] = gain(gap.regressors_of(name, with_effect))
    rival = min(rivals, key=lambda n: rivals[n])
    return observable, min(observable, rivals[rival]), rival


def _excess_removed(report: gap.GapReport, sensor: str) -> float:
    before = after = 0.0
    for ch, v in report.channels.items():
        if ch.startswith(sensor):
            before += max(v["rms_before"] ** 2 - v["noise_floor"] ** 2, 0.0)
            after += max(v["rms_after"] ** 2 - v["noise_floor"] ** 2, 0.0)
    return 1.0 - after / before if before > 0 else float("nan")


def run_case(name: str, rig: str, seed: int, scale: float) -> dict[str, Any]:
    """Simulate one session with ``name`` injected (or a control), diagnose it with the baseline."""
    unit = imu_spec.draw_unit("tactical", seed)
    model = unit.only(*imu.BASELINE)
    effect = None
    if name in gap.CANDIDATES:
        effect = imu_spec.typical_effect(name, np.random.default_rng([seed, 5]), scale)
        model = model.with_effects(effect)
    data = calibration.simulate_rig(RIGS[rig], model, seed=seed)
    if "outside" in name:
        gyro = data.gyro.copy()
        if name.startswith("sinusoid"):
            gyro[:, 0] += np.radians(0.3) * np.sin(2 * np.pi * data.t / 37.0)
        else:
            gyro[:, 0] += 20.0 * imu.DEG_PER_H * (data.t > 0.5 * data.t[-1])
        data = dataclasses.replace(data, gyro=gyro)
    report = gap.diagnose(data, holdout=HOLDOUT)
    sensor = name.split(".")[0]
    gains = oracle_gains(unit, effect, rig, seed) if effect is not None else (float("nan"), float("nan"), "-")
    ranked = report.effects[0].name if report.effects and report.effects[0].score > 0 else "-"
    tied = list(report.effects[0].indistinguishable) if ranked != "-" else []
    return {
        "name": name,
        "rig": rig,
        "seed": seed,
        "scale": scale,
        "ranked": ranked,
        "tied": tied,
        **dict(zip(("oracle", "identifiable", "rival"), gains, strict=True)),
        "first": report.diagnosis[0] if report.diagnosis else "-",
        "best": (report.effects[0].name, report.effects[0].score) if report.effects else ("-", float("nan")),
        "diagnosis": report.diagnosis,
        "unexplained": report.unexplained,
        "removed": _excess_removed(report, sensor) if name in gap.CANDIDATES else float("nan"),
        "after": max(
            (v["rms_after"] / v["noise_floor"] for ch, v in report.channels.items() if ch.startswith(sensor)),
            default=float("nan"),
        ),
    }


def _passed(case: dict[str, Any], ties: bool = False) -> bool:
    """Whether a case met its target; with ``ties``, an effect tied with the first counts as first."""
    if case["name"] == "control":
        return not case["diagnosis"]
    if "outside" in case["name"]:
        return "gyro.x" in case["unexplained"] and not case["diagnosis"]
    return bool(case["ranked"] == case["name"] or (ties and case["name"] in case["tied"]))


def _observable(case: dict[str, Any]) -> bool:
    return bool(case["oracle"] >= OBSERVABLE_NATS)


def _identifiable(case: dict[str, Any]) -> bool:
    return bool(case["identifiable"] >= OBSERVABLE_NATS)


def _summary_line(name: str, cases: list[dict[str, Any]]) -> str:
    passed = sum(_passed(c) for c in cases)
    label = {"control": " (empty)", "sinusoid (outside)": " (unexpl.)", "bias step (outside)": " (unexpl.)"}
    share = f"{passed}/{len(cases)}" + label.get(name, "")
    tied = sum(_passed(c, ties=True) for c in cases) - passed
    share += f" +{tied} tied" if tied else ""
    if name in gap.CANDIDATES:
        unseen = sum(not _observable(c) for c in cases)
        alike = sum(_observable(c) and not _identifiable(c) for c in cases)
        notes = [f"{unseen} unobservable"] * bool(unseen) + [f"{alike} unidentifiable"] * bool(alike)
        share += f" ({', '.join(notes)})" if notes else ""
    accepted = str(sum(name in c["diagnosis"] for c in cases)) if name in gap.CANDIDATES else ""
    removed = [c["removed"] for c in cases if np.isfinite(c["removed"])]
    rm = f"{100 * statistics.median(removed):.0f} %" if removed else "-"
    after = [c["after"] for c in cases if name in gap.CANDIDATES and name in c["diagnosis"]]
    af = f"{max(after):.3f}" if after else "-"
    seen = collections.Counter(c["first"] for c in cases)
    return f"{name:<26} {len(cases):>3} {share:>44} {accepted:>9} {rm:>15} {af:>12}  " + ", ".join(
        f"{k} {v}" for k, v in seen.most_common(3)
    )


def _control_line(name: str, cases: list[dict[str, Any]]) -> str:
    """A control's pass rate with its one-sided 95 % Clopper–Pearson lower bound, and the margin by
    which its best candidate stayed below acceptance."""
    n, passed = len(cases), sum(_passed(c) for c in cases)
    bound = float(stats.beta.ppf(0.05, passed, n - passed + 1)) if passed else 0.0
    median = statistics.median(c["best"][1] for c in cases)
    top = max(cases, key=lambda c: c["best"][1])["best"]
    return (
        f"{name}: passed {passed}/{n} (one-sided 95 % lower bound on the rate {100 * bound:.1f} %); best "
        f"candidate's score: median {median:.1f}, highest {top[1]:.1f} nats ({top[0]})"
    )


def _confusion(effects: list[str], results: dict[str, list[dict[str, Any]]]) -> None:
    def short(n: str) -> str:
        if n == "-":
            return "-"
        sensor, kind = n.split(".")
        return sensor[0] + "." + "".join(w[:2] for w in kind.split("_"))

    columns = sorted({c["first"] for n in effects for c in results[n]}, key=lambda n: (n == "-", n))
    print("\nconfusion matrix: injected (rows) × first diagnosed (columns; - = nothing)")
    print("injected".ljust(26) + "".join(f"{short(c):>9}" for c in columns))
    for n in effects:
        counts = collections.Counter(c["first"] for c in results[n])
        print(f"{n:<26}" + "".join(f"{counts.get(c, 0) or '.':>9}" for c in columns))


def _case_line(case: dict[str, Any]) -> str:
    return (
        f"  {case['name']:<26} {case['rig']:<16} seed {case['seed']} ×{case['scale']:g}: "
        f"ranked {case['ranked']} (tied {case['tied']}), diagnosis {case['diagnosis']}, "
        f"unexplained {case['unexplained']}, after/floor {case['after']:.3f}, "
        f"oracle {case['oracle']:.3g} nats, {case['identifiable']:.3g} beside {case['rival']}, "
        f"removed {case['removed']:.3f}, best {case['best'][0]} {case['best'][1]:.1f}"
    )


def _load(paths: list[str]) -> list[dict[str, Any]]:
    """Cases saved by ``--save``; a later file's case replaces an earlier one's of the same name, rig,
    seed and scale (a rig rerun after a change, merged with the rest)."""
    cases: dict[tuple[Any, ...], dict[str, Any]] = {}
    for path in paths:
        try:
            with open(path, encoding="utf-8") as fh:
                doc = json.load(fh)
        except (OSError, json.JSONDecodeError) as exc:
            raise SystemExit(f"{path}: cannot read saved cases ({exc})") from None
        if not isinstance(doc, dict) or doc.get("format") != "sins-bench-gap":
            raise SystemExit(f'{path}: not saved by bench_gap.py --save (no "format": "sins-bench-gap")')
        for case in doc["cases"]:
            cases[case["name"], case["rig"], case["seed"], case["scale"]] = case
    return list(cases.values())


def _report(names: list[str], cases: list[dict[str, Any]]) -> None:
    """The summary lines, the controls' rates, the shares ranked first and the confusion matrix."""
    results: dict[str, list[dict[str, Any]]] = {n: [c for c in cases if c["name"] == n] for n in names}
    print(
        f"{'injected':<26} {'n':>3} {'passed':>44} {'accepted':>9} {'excess removed':>15} "
        f"{'after/floor':>12}  diagnosed first"
    )
    for name in names:
        print(_summary_line(name, results[name]))
    print()
    for name in names:
        if name not in gap.CANDIDATES:
            print(_control_line(name, results[name]))
    effects = [n for n in names if n in gap.CANDIDATES]
    for label, keep in (
        ("all cases", lambda c: True),
        ("observable cases", _observable),
        ("identifiable cases", _identifiable),
    ):
        chosen = [c for n in effects for c in results[n] if keep(c)]
        if not chosen:
            continue
        n = len(chosen)
        ranked, tied = sum(_passed(c) for c in chosen), sum(_passed(c, ties=True) for c in chosen)
        print(
            f"\n{label}: injected effect ranked first in {ranked}/{n} ({100 * ranked / n:.1f} %); first or "
            f"indistinguishable from the first (withheld gains within {gap.TIE_NATS:g} nats) in "
            f"{tied}/{n} ({100 * tied / n:.1f} %)"
        )
    if effects:
        _confusion(effects, results)


def run_cases(
    run: Callable[..., dict[str, Any]],
    jobs: list[tuple[Any, ...]],
    processes: int,
    line: Callable[[dict[str, Any]], str] | None = None,
) -> list[dict[str, Any]]:
    """``run(*job)`` for every job on ``processes`` processes, in order, with a bar on a terminal only
    (logs get the summary) and, given ``line``, each case printed above it; then the total time."""
    cases = []
    started = time.perf_counter()
    bar = tqdm.tqdm(total=len(jobs), unit=" case", file=sys.stderr, disable=not sys.stderr.isatty())
    with concurrent.futures.ProcessPoolExecutor(processes) as pool, bar:
        for case in pool.map(run, *zip(*jobs, strict=True)):
            cases.append(case)
            bar.update()
            if line is not None:
                bar.write(line(case))
    print(f"\n{len(jobs)} cases in {time.perf_counter() - started:.0f} s on {processes} processes\n")
    return cases


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--control-seeds", type=int, help="seeds for the controls (default: --seeds)")
    parser.add_argument("--scales", type=float, nargs="+", default=[1.0, 3.0])
    parser.add_argument("--effects", nargs="*", default=list(gap.CANDIDATES))
    parser.add_argument("--controls", nargs="*", default=list(CONTROLS))
    parser.add_argument("--rigs", nargs="*", default=list(RIGS), choices=list(RIGS))
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--verbose", action="store_true", help="print every case as it finishes")
    parser.add_argument("--timing", action="store_true")
    parser.add_argument("--save", metavar="CASES.json", help="write every case's result here")
    parser.add_argument(
        "--load", metavar="CASES.json", nargs="+",
        help="summarise cases saved by --save instead of running any (later files replace earlier cases)",
    )  # fmt: skip
    parser.add_argument(
        "--against", metavar="REFERENCE.json",
        help="compare case by case with a saved run: every case it passed that this one does not is listed",
    )  # fmt: skip
    args = parser.parse_args()

    names = (["control"] if "control" in args.controls else []) + args.effects
    names += [n for n in CONTROLS[1:] if n in args.controls]
    if args.load:
        cases = [c for c in _load(args.load) if c["name"] in names and c["rig"] in args.rigs]
        print(f"{len(cases)} cases from {', '.join(args.load)}\n")
        _report([n for n in names if any(c["name"] == n for c in cases)], cases)
        if args.against:
            _compare(_load([args.against]), cases)
        return

    if args.timing:
        rig = calibration.RigProcedure(position_dwell_s=40.0, rate_table=calibration.RateTable(dwell_s=20.0))
        data = calibration.simulate_rig(rig, imu_spec.draw_unit("tactical", 0).only(*imu.BASELINE), seed=0)
        started = time.perf_counter()
        gap.diagnose(data)
        elapsed = time.perf_counter() - started
        print(f"timing: {len(data)} rows ({data.t[-1] / 60:.1f} min at 100 Hz) diagnosed in {elapsed:.1f} s")

    jobs = [
        (name, rig, seed, scale)
        for name in names
        for rig in args.rigs
        for seed in range(args.seeds if name in gap.CANDIDATES else (args.control_seeds or args.seeds))
        for scale in (args.scales if name in gap.CANDIDATES else [1.0])
    ]
    cases = run_cases(run_case, jobs, args.jobs, _case_line if args.verbose else None)
    if args.save:
        io.write_json(args.save, {"format": "sins-bench-gap", "cases": cases})
    _report(names, cases)
    if args.against:
        _compare(_load([args.against]), cases)


def _compare(reference: list[dict[str, Any]], cases: list[dict[str, Any]]) -> None:
    """Case by case against a saved run: the cases it passed that these do not, and the reverse."""
    key = lambda c: (c["name"], c["rig"], c["seed"], c["scale"])  # noqa: E731
    now = {key(c): c for c in cases}
    shared = [c for c in reference if key(c) in now]
    lost = [c for c in shared if _passed(c) and not _passed(now[key(c)])]
    gained = [c for c in shared if not _passed(c) and _passed(now[key(c)])]
    print(f"\nagainst the reference: {len(shared)} cases in both; {len(lost)} lost, {len(gained)} gained")
    for label, group in (("lost", lost), ("gained", gained)):
        for c in group:
            print(f"  {label}: {_case_line(now[key(c)]).strip()}")


if __name__ == "__main__":
    main()
