"""The compensation-quality gate: a suite of scenarios × strategies, over seeds, against a baseline.

A suite file lists cases, each a scenario with an IMU model and a ``[compensation]`` table. Every case
is run once per seed: seed ``u`` is a power-on pair of the case's unit, as a campaign's unit ``u``
(:func:`sins.campaign.spec.rig_seed` ``2u`` for the rig session, :func:`~sins.campaign.spec.nav_seed`
``2u + 1`` for the drive; they replace the scenario's ``[compensation] seed`` and ``[imu] seed``; the
unit itself stays the one its IMU file names). For each strategy the headline figures are collected
per seed: final and maximum horizontal error and, per channel, the residual sensor error on held-back
rig data. All are errors, lower is better. Suite file::

    [seeds]
    first = 1                     # seeds first, first + 1, ... (default 1)
    count = 8                     # at least 3 (default 8)

    [[case]]
    name = "linear"
    scenario = "linear.toml"      # relative to the suite file

    [tolerance]                   # relative growth never judged a regression, per metric family
    horizontal = 0.02
    residual = 0.01

A figure regresses when it grew, beyond chance, by more than its tolerance. Paired over seeds where
the baseline drew the same seeds: the logarithm of the growth past the allowance, seed by seed
``log(now / allowed)`` with ``allowed = baseline · (1 + tolerance) + floor``, is tested one-sided
against zero (one-sample t test; on the log scale, because a strategy made worse moves every seed's
figure by about the same factor, while the seeds' figures themselves spread over a factor of
several); two-sample otherwise (Welch's t test of ``log(now)`` against ``log(allowed)``), at
``FALSE_ALARM / figures`` (Bonferroni over every figure of the baseline,
:data:`sins.campaign.gate.FALSE_ALARM`), so that an unchanged strategy fails the gate at all with a
chance of at most that rate. Figures equal to the baseline's hold without a test; a figure gone NaN
regresses; one of the baseline missing now fails as "missing". The campaign gate ranks instead
(Wilcoxon, Mann-Whitney), which a suite cannot: with ``n`` seeds the smallest one-sided p-value a
signed-rank test can give is ``2**-n``, above the per-figure level of a hundred figures for fewer
than 14 seeds, so such a gate could never fail.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from sins.campaign.gate import FALSE_ALARM, Check
from sins.campaign.spec import nav_seed, rig_seed
from sins.errors import SinsInputError
from sins.io.documents import printable, short

#: Absolute floors below which a change is not judged (metres, SI residual units).
FLOORS = {"horizontal": 0.5, "residual": 1e-9}
DEFAULT_TOLERANCES = {"horizontal": 0.02, "residual": 0.01}
BASELINE_FORMAT = "sins.quality-baseline"
#: The largest relative tolerance a suite may give (a metric may grow 100-fold): beyond it no change
#: is judged, and the gate tests nothing.
MAX_TOLERANCE = 100.0
#: Seeds per case: the default, and the fewest a suite or baseline may hold (with two, a t test at the
#: gate's level fails only a growth over a thousand times its spread). With eight, a t test at 1e-4
#: fails a mean log growth of 2.5 times its spread over the seeds (11.2 times with four).
DEFAULT_SEEDS = 8
MIN_SEEDS = 3
MAX_SEEDS = 1000

#: Figures per strategy: ``{case: {strategy: {metric: [one value per seed]}}}``.
CaseFigures = dict[str, dict[str, dict[str, list[float]]]]


@dataclass(frozen=True)
class Case:
    """One suite case: its name and scenario file (resolved against the suite file's folder)."""

    name: str
    scenario: Path


@dataclass(frozen=True)
class Suite:
    """A suite file read: its path, its cases, the seeds each runs with and the relative tolerance
    per metric family."""

    source: Path
    cases: tuple[Case, ...]
    tolerances: dict[str, float]
    seeds: tuple[int, ...] = tuple(range(1, DEFAULT_SEEDS + 1))


@dataclass(frozen=True)
class Figures:
    """A suite's figures: the seeds, and each value per seed in their order (:data:`CaseFigures`)."""

    seeds: tuple[int, ...]
    cases: CaseFigures

    def count(self) -> int:
        """The number of figures (each a list over the seeds)."""
        return sum(len(m) for s in self.cases.values() for m in s.values())


def load_suite(path: str | os.PathLike[str]) -> Suite:
    """Read a suite file (see the module docstring); one-line errors name the file and key."""
    from sins.scenario import TomlKeys, read_toml

    path = Path(path)
    top = TomlKeys(str(path), "", read_toml(path, "suite"))
    cases = []
    for table in top.tables("case"):
        name = table.string("name")
        scenario = path.parent / table.string("scenario")
        if not scenario.exists():
            raise table.error(f"no such scenario file: {scenario}", "scenario")
        table.done()
        try:
            _check_case(scenario)
        except SinsInputError as exc:
            raise table.error(f"{exc}", "scenario") from None
        cases.append(Case(name, scenario))
    if not cases:
        raise top.error("needs at least one [[case]]", "case")
    if len({c.name for c in cases}) != len(cases):
        raise top.error("case names must be unique", "case")
    tol = top.sub("tolerance")
    tolerances = {k: tol.number(k, v, low=0.0, high=MAX_TOLERANCE) for k, v in DEFAULT_TOLERANCES.items()}
    tol.done()
    seeds = top.sub("seeds")
    count = seeds.integer("count", DEFAULT_SEEDS, low=MIN_SEEDS, high=MAX_SEEDS)
    # A seed u draws the power-ons 2u and 2u + 1: u up to half the largest seed a generator takes.
    first = seeds.integer("first", 1, high=(2**63 - 2) // 2 - count)
    seeds.done()
    top.done()
    return Suite(path, tuple(cases), tolerances, tuple(range(first, first + count)))


def _check_case(path: Path) -> None:
    """Refuse, before any case runs, a case's scenario that would not run as a case: one that does not
    validate, has no IMU model and compensation, or that ``sins run`` would refuse before its work."""
    from sins import scenario
    from sins.runs import pipeline
    from sins.scenario.budget import check_scenario_size

    sc = scenario.load(path)
    if sc.compensation is None or sc.imu_model is None:
        raise SinsInputError(f"{path}: a suite case needs an [imu] model and a [compensation] table")
    check_scenario_size(sc, path, "running")
    pipeline.check_runnable(sc, scenario.load_imu(sc.imu_model).grade)


def measure(suite: Suite, progress: Callable[[int, int], None] | None = None) -> Figures:
    """Run every case with every seed of the suite; ``progress(runs_done, runs)`` after each seed's fit
    (the fits are most of the time) and after each case's drives.

    Each seed's strategies are fitted on its own rig session (:func:`sins.runs.pipeline.fit_unit`), then
    the case's trajectory is generated once and driven by every seed's unit
    (:func:`sins.runs.pipeline.run_units`): each seed's figures are ``sins run``'s on that scenario with
    ``[compensation] seed = 2u`` and ``[imu] seed = 2u + 1``, to the last bit.
    """
    from sins import scenario
    from sins.runs import pipeline

    out: CaseFigures = {}
    total, done = len(suite.cases) * (len(suite.seeds) + 1), 0
    for case in suite.cases:
        sc = scenario.load(case.scenario)
        if sc.compensation is None or sc.imu_model is None:
            raise SinsInputError(
                f"{case.scenario}: a suite case needs an [imu] model and a [compensation] table"
            )
        spec = scenario.load_imu(sc.imu_model)
        units = []
        for seed in suite.seeds:
            units.append(pipeline.fit_unit(spec, dataclasses.replace(sc.compensation, seed=rig_seed(seed))))
            done += 1
            if progress is not None:
                progress(done, total)
        # The summary is over every sample whatever is kept: keep the series as thin as it goes.
        results = pipeline.run_units(sc, units, [nav_seed(s) for s in suite.seeds], 1.0 / sc.rate_hz,
                                     sensor_errors=False)  # fmt: skip
        out[case.name] = _case_figures(results)
        done += 1
        if progress is not None:
            progress(done, total)
    return Figures(suite.seeds, out)


def _case_figures(results: list[Any]) -> dict[str, dict[str, list[float]]]:
    """``{strategy: {metric: [per seed]}}`` of one case's runs (one :class:`ScenarioRun` per seed)."""
    figures: dict[str, dict[str, list[float]]] = {}
    for result in results:
        for name, run in result.runs.items():
            m = figures.setdefault(name, {})
            m.setdefault("final_horizontal_m", []).append(float(run.summary.final_horizontal_m))
            m.setdefault("max_horizontal_m", []).append(float(run.summary.max_horizontal_m))
            for channel, value in (run.residual_rms or {}).items():
                m.setdefault(f"residual_rms.{channel}", []).append(float(value))
    return figures


def _family(metric: str) -> str:
    return "residual" if metric.startswith("residual") else "horizontal"


def compare(
    baseline: Figures, measured: Figures, tolerances: dict[str, float], alpha: float = FALSE_ALARM
) -> list[Check]:
    """Every figure of ``baseline`` judged against ``measured`` (see the module docstring), in the
    baseline's order; each :class:`~sins.campaign.gate.Check`'s group is ``case/strategy``. Figures
    ``measured`` has and the baseline lacks are not judged (:func:`unjudged`). Paired where every seed
    of ``measured`` is one of the baseline's (a quick check on some of the suite's seeds is paired with
    the baseline's figures of those seeds), two-sample otherwise."""
    at = {u: i for i, u in enumerate(baseline.seeds)}
    paired = all(u in at for u in measured.seeds)
    pick = [at[u] for u in measured.seeds] if paired else list(range(len(baseline.seeds)))
    tests = [
        (case, strategy, metric, values)
        for case, strategies in baseline.cases.items()
        for strategy, metrics in strategies.items()
        for metric, values in metrics.items()
    ]
    level = alpha / max(1, len(tests))
    checks = []
    for case, strategy, metric, values in tests:
        now = measured.cases.get(case, {}).get(strategy, {}).get(metric)
        base = [values[i] for i in pick]
        family = _family(metric)
        slack = tolerances[family] * np.abs(base) + FLOORS[family]
        checks.append(_judge(f"{case}/{strategy}", metric, base, now, slack, paired, level))
    return checks


def unjudged(baseline: Figures, measured: Figures) -> list[str]:
    """``case/strategy metric`` of each figure measured that the baseline does not hold."""
    return [
        f"{case}/{strategy} {metric}"
        for case, strategies in measured.cases.items()
        for strategy, metrics in strategies.items()
        for metric in metrics
        if metric not in baseline.cases.get(case, {}).get(strategy, {})
    ]


def _judge(
    group: str,
    metric: str,
    base: list[float],
    now: list[float] | None,
    slack: Any,
    paired: bool,
    level: float,
) -> Check:
    """One figure: ``base`` and ``now`` per seed, ``slack`` the growth allowed per baseline seed."""
    if now is None:
        return Check(group, metric, "", math.nan, math.nan, "missing")
    b, n = np.asarray(base, dtype=float), np.asarray(now, dtype=float)
    if not np.isfinite(n).all():  # a seed's figure went NaN or infinite: worse than any number
        return Check(group, metric, "non-finite", math.nan, 0.0, "regressed")
    ratio = float(np.median(n) / np.median(b)) if np.median(b) > 0 else math.nan
    if paired:
        if np.array_equal(n, b):
            return Check(group, metric, "identical", ratio, 1.0, "holds")
    # On the log scale (a growth is a factor); below the floor nothing is judged: no less than it.
    log_now, log_allowed = np.log(np.maximum(n, FLOORS[_family(metric)])), np.log(b + slack)
    if paired:
        p, test = _p_paired(log_now - log_allowed), "paired"
    else:
        p, test = _p_welch(log_now, log_allowed), "two-sample"
    return Check(group, metric, test, ratio, p, "regressed" if p < level else "holds")


def _p_paired(excess: Any) -> float:
    """One-sided p-value that the mean of ``excess`` is above 0 (one-sample t test). Computed here so
    that equal differences (a constant growth on every seed, no spread) give the limit, 0 or 1, where
    scipy's ``ttest_1samp`` gives NaN."""
    mean, sd = float(np.mean(excess)), float(np.std(excess, ddof=1))
    if sd == 0.0:
        return 0.0 if mean > 0 else 1.0
    t = mean / (sd / math.sqrt(len(excess)))
    return float(stats.t.sf(t, len(excess) - 1))


def _p_welch(now: Any, allowed: Any) -> float:
    """One-sided p-value that ``now``'s mean is above ``allowed``'s (Welch's t test); the limit where
    neither has any spread."""
    var = float(np.var(now, ddof=1) / len(now) + np.var(allowed, ddof=1) / len(allowed))
    diff = float(np.mean(now) - np.mean(allowed))
    if var == 0.0:
        return 0.0 if diff > 0 else 1.0
    return float(stats.ttest_ind(now, allowed, equal_var=False, alternative="greater").pvalue)


def read_baseline(path: str | os.PathLike[str], suite: Suite | None = None) -> Figures:
    """A baseline file: its seeds and ``cases`` (``{case: {strategy: {metric: [per seed]}}}``).

    Refused, so that a gate never tests less than it says: seeds that are not at least
    :data:`MIN_SEEDS` distinct whole numbers; no cases; a case or strategy with nothing in it; a
    strategy without ``final_horizontal_m`` and ``max_horizontal_m``; a metric that is not one the
    suite measures; a metric's values that are not one finite number per seed (a baseline of single
    figures, from before the gate judged seeds, among them); with ``suite``, a case the suite does
    not have.

    Raises
    ------
    SinsInputError
        one line naming the file and the place (``cases.CASE.STRATEGY.METRIC[i]``) of a malformed entry.
    """
    from sins import io

    path = Path(path)
    doc = io.read_json_document(path, "quality baseline", BASELINE_FORMAT)
    seeds = doc.get("seeds")
    if not isinstance(seeds, list) or len(seeds) < MIN_SEEDS or not all(type(u) is int for u in seeds):
        raise SinsInputError(
            f"{path}: seeds: expected a list of at least {MIN_SEEDS} whole numbers, got {short(seeds)}"
            " (a baseline from before the gate judged seeds: re-measure it with --update-baseline)"
        )
    if len(set(seeds)) != len(seeds):
        raise SinsInputError(f"{path}: seeds: a seed appears twice")
    if not isinstance(doc.get("cases"), dict) or not doc["cases"]:
        raise SinsInputError(f'{path}: a quality baseline needs a "cases" table with at least one case')
    names = None if suite is None else {c.name for c in suite.cases}
    cases: CaseFigures = {}
    for case, strategies in doc["cases"].items():
        where = f"{path}: cases.{printable(case)}"
        if names is not None and case not in names:
            raise SinsInputError(f"{where}: the suite {suite.source if suite else ''} has no such case")
        if not isinstance(strategies, dict) or not strategies:
            raise SinsInputError(f"{where}: expected a table of strategies, got {short(strategies)}")
        cases[case] = {s: _metrics(f"{where}.{printable(s)}", m, len(seeds)) for s, m in strategies.items()}
    return Figures(tuple(seeds), cases)


def _metrics(where: str, metrics: Any, seeds: int) -> dict[str, list[float]]:
    """One strategy's metrics of a baseline, checked (see :func:`read_baseline`)."""
    if not isinstance(metrics, dict) or not metrics:
        raise SinsInputError(f"{where}: expected a table of metrics, got {short(metrics)}")
    for metric in ("final_horizontal_m", "max_horizontal_m"):
        if metric not in metrics:
            raise SinsInputError(f"{where}: has no {metric} (a baseline holds every metric it gates)")
    for metric, values in metrics.items():
        at = f"{where}.{printable(metric)}"
        if metric not in _METRICS:
            raise SinsInputError(f"{at}: not a metric the suite measures")
        if not isinstance(values, list) or len(values) != seeds:
            size = f"{len(values)} values" if isinstance(values, list) else short(values)
            raise SinsInputError(f"{at}: expected {seeds} numbers, one per seed, got {size}")
        for i, x in enumerate(values):
            if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
                raise SinsInputError(f"{at}[{i}]: expected a finite number, got {short(x)}")
    return {metric: [float(x) for x in values] for metric, values in metrics.items()}


#: The metrics a suite measures per strategy (the channels are :data:`sins.imu.CHANNELS`).
_CHANNELS = ("gyro.x", "gyro.y", "gyro.z", "accel.x", "accel.y", "accel.z")
_METRICS = ("final_horizontal_m", "max_horizontal_m", *(f"residual_rms.{c}" for c in _CHANNELS))


def write_baseline(path: str | os.PathLike[str], measured: Figures, suite: Suite) -> None:
    """Write ``measured`` as the new baseline, tagged with the sins version and the suite's name."""
    from sins import __version__, io

    io.write_json(path, {"format": BASELINE_FORMAT, "sins": __version__, "suite": str(suite.source.name),
                         "seeds": list(measured.seeds), "cases": measured.cases})  # fmt: skip


__all__ = [
    "BASELINE_FORMAT",
    "DEFAULT_SEEDS",
    "DEFAULT_TOLERANCES",
    "FLOORS",
    "MAX_SEEDS",
    "MAX_TOLERANCE",
    "MIN_SEEDS",
    "Case",
    "CaseFigures",
    "Figures",
    "Suite",
    "compare",
    "load_suite",
    "measure",
    "read_baseline",
    "unjudged",
    "write_baseline",
]
