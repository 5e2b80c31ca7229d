"""The compensation-quality gate: a suite of scenarios × strategies checked against a baseline.

A suite file lists cases, each a scenario with an IMU model and a
``[compensation]`` table (so with fixed seeds); every case is run and, for
each strategy, the headline metrics are collected: final and maximum
horizontal error and, per channel, the residual sensor error on held-back rig
data. All are errors, lower is better: a metric regresses when it grows by
more than its relative tolerance plus a small absolute floor. Suite file::

    [[case]]
    name = "linear"
    scenario = "linear.toml"      # relative to the suite file
    [tolerance]                   # relative growth allowed, per metric family
    horizontal = 0.10
    residual = 0.05
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sins.errors import SinsInputError
from sins.io.documents import printable, short

#: Absolute floors below which a change is not judged (metres, SI residual units).
FLOORS = {"horizontal": 0.5, "residual": 1e-9}
DEFAULT_TOLERANCES = {"horizontal": 0.10, "residual": 0.05}
BASELINE_FORMAT = "sins.quality-baseline"
#: The largest relative tolerance a suite may give (a metric may grow 100-fold): beyond it no change
#: is judged, and the gate tests nothing.
MAX_TOLERANCE = 100.0


@dataclass(frozen=True)
class Case:
    """One suite case: its name and scenario file (resolved against the suite file's folder)."""

    name: str
    scenario: Path


@dataclass(frozen=True)
class Suite:
    """A suite file read: its path, its cases and the relative tolerance per metric family."""

    source: Path
    cases: tuple[Case, ...]
    tolerances: dict[str, float]


@dataclass(frozen=True)
class Change:
    """One metric of one strategy of one case, against the baseline."""

    case: str
    strategy: str
    metric: str
    baseline: float | None
    value: float | None
    verdict: str  # held | improved | regressed | new | missing

    @property
    def relative(self) -> float | None:
        """Relative growth ``value / baseline - 1``; None if either is missing or the baseline is 0."""
        if self.baseline is None or self.value is None or self.baseline == 0:
            return None
        return self.value / self.baseline - 1.0


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
    top.done()
    return Suite(source=path, cases=tuple(cases), tolerances=tolerances)


def _check_case(path: Path) -> None:
    """Refuse, before any case runs, a case's scenario that would not run as a case: one that does not
    validate, has no IMU model and compensation, or that ``sins run`` would refuse before its work."""
    from sins import pipeline, scenario
    from sins.scenario.budget import check_scenario_size

    sc = scenario.load(path)
    if sc.compensation is None or sc.imu_model is None:
        raise SinsInputError(f"{path}: a suite case needs an [imu] model and a [compensation] table")
    check_scenario_size(sc, path, "running")
    pipeline.check_runnable(sc, scenario.load_imu(sc.imu_model).grade)


def measure(
    suite: Suite, progress: Callable[[int, int], None] | None = None
) -> dict[str, dict[str, dict[str, float]]]:
    """Run every case: ``{case: {strategy: {metric: value}}}``; ``progress(cases_done, cases)`` after each."""
    from sins import pipeline, scenario

    out: dict[str, dict[str, dict[str, float]]] = {}
    for case in suite.cases:
        sc = scenario.load(case.scenario)
        if sc.compensation is None:
            raise SinsInputError(
                f"{case.scenario}: a suite case needs an [imu] model and a [compensation] table"
            )
        result = pipeline.run_scenario(sc)
        metrics: dict[str, dict[str, float]] = {}
        for name, run in result.runs.items():
            m = {
                "final_horizontal_m": run.summary.final_horizontal_m,
                "max_horizontal_m": run.summary.max_horizontal_m,
            }
            for channel, value in (run.residual_rms or {}).items():
                m[f"residual_rms.{channel}"] = value
            metrics[name] = m
        out[case.name] = metrics
        if progress is not None:
            progress(len(out), len(suite.cases))
    return out


def _family(metric: str) -> str:
    return "residual" if metric.startswith("residual") else "horizontal"


def compare(
    baseline: dict[str, dict[str, dict[str, float]]],
    measured: dict[str, dict[str, dict[str, float]]],
    tolerances: dict[str, float],
) -> list[Change]:
    """Every metric's verdict; a regression is growth beyond tolerance × baseline + floor."""
    changes = []
    for case in sorted(set(baseline) | set(measured)):
        base_c, new_c = baseline.get(case, {}), measured.get(case, {})
        for strategy in sorted(set(base_c) | set(new_c)):
            base_s, new_s = base_c.get(strategy, {}), new_c.get(strategy, {})
            for metric in sorted(set(base_s) | set(new_s)):
                b, v = base_s.get(metric), new_s.get(metric)
                if b is None:
                    verdict = "new"
                elif v is None:
                    verdict = "missing"
                else:
                    family = _family(metric)
                    slack = tolerances[family] * abs(b) + FLOORS[family]
                    verdict = "regressed" if v > b + slack else "improved" if v < b - slack else "held"
                changes.append(Change(case, strategy, metric, b, v, verdict))
    return changes


def read_baseline(
    path: str | os.PathLike[str], suite: Suite | None = None
) -> dict[str, dict[str, dict[str, float]]]:
    """A baseline file's ``cases``: ``{case: {strategy: {metric: value}}}``, every value a finite number.

    Refused, so that a gate never tests less than it says: no cases; a case or strategy with nothing
    in it; a strategy without ``final_horizontal_m`` and ``max_horizontal_m``; a metric that is not one
    the suite measures; with ``suite``, a case the suite does not have.

    Raises
    ------
    SinsInputError
        one line naming the file and the place (``cases.CASE.STRATEGY.METRIC``) of a malformed entry.
    """
    from sins import io

    path = Path(path)
    doc = io.read_json_document(path, "quality baseline", BASELINE_FORMAT)
    if not isinstance(doc.get("cases"), dict) or not doc["cases"]:
        raise SinsInputError(f'{path}: a quality baseline needs a "cases" table with at least one case')
    names = None if suite is None else {c.name for c in suite.cases}
    cases: dict[str, dict[str, dict[str, float]]] = {}
    for case, strategies in doc["cases"].items():
        where = f"{path}: cases.{printable(case)}"
        if names is not None and case not in names:
            raise SinsInputError(f"{where}: the suite {suite.source if suite else ''} has no such case")
        if not isinstance(strategies, dict) or not strategies:
            raise SinsInputError(f"{where}: expected a table of strategies, got {short(strategies)}")
        cases[case] = {s: _metrics(f"{where}.{printable(s)}", m) for s, m in strategies.items()}
    return cases


def _metrics(where: str, metrics: Any) -> dict[str, float]:
    """One strategy's metrics of a baseline, checked (see :func:`read_baseline`)."""
    if not isinstance(metrics, dict) or not metrics:
        raise SinsInputError(f"{where}: expected a table of metrics, got {short(metrics)}")
    for metric in ("final_horizontal_m", "max_horizontal_m"):
        if metric not in metrics:
            raise SinsInputError(f"{where}: has no {metric} (a baseline holds every metric it gates)")
    for metric, value in metrics.items():
        if metric not in _METRICS:
            raise SinsInputError(f"{where}.{printable(metric)}: not a metric the suite measures")
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise SinsInputError(f"{where}.{metric}: expected a finite number, got {short(value)}")
    return {metric: float(value) for metric, value in metrics.items()}


#: The metrics a suite measures per strategy (the channels are :data:`sins.imu.CHANNELS`).
_CHANNELS = ("gyro.x", "gyro.y", "gyro.z", "accel.x", "accel.y", "accel.z")
_METRICS = ("final_horizontal_m", "max_horizontal_m", *(f"residual_rms.{c}" for c in _CHANNELS))


def write_baseline(path: str | os.PathLike[str], measured: dict[str, Any], suite: Suite) -> None:
    """Write ``measured`` as the new baseline, tagged with the sins version and the suite's name."""
    from sins import __version__, io

    io.write_json(path, {"format": BASELINE_FORMAT, "sins": __version__, "suite": str(suite.source.name),
                         "cases": measured})  # fmt: skip


__all__ = [
    "BASELINE_FORMAT",
    "DEFAULT_TOLERANCES",
    "FLOORS",
    "MAX_TOLERANCE",
    "Case",
    "Change",
    "Suite",
    "compare",
    "load_suite",
    "measure",
    "read_baseline",
    "write_baseline",
]
