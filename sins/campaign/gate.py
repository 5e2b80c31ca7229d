"""The campaign gate: does a strategy do worse than its baseline campaign, beyond chance?

A single seed moving says nothing; a distribution moving does. For every scenario × strategy of the
baseline and every gated figure (:data:`GATED`), the units' values now are tested against the
baseline's, one-sided (worse = larger):

* **paired**, when both campaigns drew the same units (same ``unit_seed`` list): the Wilcoxon
  signed-rank test on the differences. Identical values (an unchanged strategy, run again) hold.
* **two-sample**, when the units differ (a reseeded campaign): the Mann–Whitney U test.

A figure regresses when its p-value is below ``alpha / tests`` (Bonferroni over every test of the
comparison), so the chance that a campaign of an unchanged strategy fails the gate at all is at most
``alpha`` (:data:`FALSE_ALARM`). A group of the baseline missing now fails as "missing", a figure gone
NaN as "regressed". Every figure of the baseline is tested: a baseline that would test nothing, or
drop a figure (null, NaN, an empty list), is refused before any work (:func:`check_baseline`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
from scipy import stats

from sins.campaign.folder import AIDED_COLUMN
from sins.campaign.results import SUMMARISED
from sins.campaign.spec import CampaignSpec
from sins.errors import SinsInputError
from sins.io.documents import printable, short

#: The campaign-wide false-alarm rate: the chance an unchanged strategy fails the gate.
FALSE_ALARM = 0.01
#: The figures every campaign gates: final and maximum horizontal error, and each channel's held-back
#: rig residual (its RMS, and the bias left: a bias far below the noise shows in the mean, not in the
#: RMS). An aided scenario's rows add the aided run's errors and each outage's, gated as well: every
#: figure the baseline holds per unit is.
GATED = SUMMARISED

#: A paired difference within this fraction of the figure is floating point's last digits, not a change:
#: the shipped baseline and a run on another machine differ by up to 7.7e-11 (other kernels), and the
#: signed-rank test had failed a figure multiplied by 1 - 1e-12 (p = 1.8e-12), one sign of noise.
FLOAT_NOISE = 1e-9

Verdict = Literal["holds", "regressed", "missing"]


@dataclass(frozen=True)
class Check:
    """One figure of one scenario × strategy against its baseline."""

    group: str
    figure: str
    test: str  # "paired", "two-sample", "identical" or "" (missing)
    median_ratio: float  # median now / median of the baseline (nan where either is missing)
    p_value: float
    verdict: Verdict


def compare(baseline: dict[str, Any], summary: dict[str, Any], alpha: float = FALSE_ALARM) -> list[Check]:
    """Every figure of every group of ``baseline`` (a ``summary.json``, :func:`check_baseline`) against
    ``summary``: each one is tested, none dropped."""
    check_baseline(baseline, "baseline")
    check_power(baseline, "baseline", alpha)
    prepared = []
    for group, base in baseline["groups"].items():
        now = summary["groups"].get(group)
        for figure in [f for f in base["values"] if f != "unit_seed"]:
            prepared.append(_prepare(group, figure, base, now))
    per_test = alpha / max(1, len(prepared))
    p_values = _p_values([samples for _, samples in prepared])
    return [
        check if p is None else replace(check, p_value=p, verdict="regressed" if p < per_test else "holds")
        for (check, _), p in zip(prepared, p_values, strict=True)
    ]


#: The samples a test compares: the values now and the baseline's (two-sample), or the differences and
#: ``None`` (paired).
_Samples = tuple[str, np.ndarray, np.ndarray | None]


def _prepare(
    group: str, figure: str, base: dict[str, Any], now: dict[str, Any] | None
) -> tuple[Check, _Samples | None]:
    """The check, and the samples its test compares (``None`` where its verdict needs no test)."""
    if now is None or figure not in now["values"]:
        return Check(group, figure, "", float("nan"), float("nan"), "missing"), None
    b = np.asarray(base["values"][figure], dtype=float)
    n = np.asarray(now["values"][figure], dtype=float)
    if not np.isfinite(n).all():  # a unit's figure went NaN or infinite: worse than any number
        return Check(group, figure, "non-finite", float("nan"), 0.0, "regressed"), None
    median_b = np.nanmedian(b)
    ratio = float(np.median(n) / median_b) if median_b > 0 else float("nan")  # n is finite here
    if base["values"]["unit_seed"] == now["values"]["unit_seed"]:
        ok = np.isfinite(b) & np.isfinite(n)
        d = n[ok] - b[ok]
        d[np.abs(d) <= FLOAT_NOISE * np.maximum(np.abs(n[ok]), np.abs(b[ok]))] = 0.0
        if not d.any():
            return Check(group, figure, "identical", ratio, 1.0, "holds"), None
        return Check(group, figure, "paired", ratio, float("nan"), "holds"), ("paired", d, None)
    samples = ("two-sample", n[np.isfinite(n)], b[np.isfinite(b)])
    return Check(group, figure, "two-sample", ratio, float("nan"), "holds"), samples


def _p_values(samples: list[_Samples | None]) -> list[float | None]:
    """Each test's one-sided p-value (``None`` where there is none to make): scipy's test called once for
    all the tests of one kind, sample sizes and ties (its ``axis``), ~20 times faster on a campaign's few
    dozen figures than a call per test, and the same p-values. Ties are in the key because scipy chooses
    its method (exact or asymptotic) once per call, by whether any of its samples has them."""
    batches: dict[tuple[str, int, int, bool], list[int]] = {}
    for i, s in enumerate(samples):
        if s is not None:
            key = (s[0], len(s[1]), 0 if s[2] is None else len(s[2]), _tied(s))
            batches.setdefault(key, []).append(i)
    out: list[float | None] = [None] * len(samples)
    for (test, *_), rows in batches.items():
        now = np.array([samples[i][1] for i in rows])  # type: ignore[index]
        if test == "paired":
            p = stats.wilcoxon(now, alternative="greater", zero_method="zsplit", axis=1).pvalue
        else:
            base = np.array([samples[i][2] for i in rows])  # type: ignore[index]
            p = stats.mannwhitneyu(now, base, alternative="greater", axis=1).pvalue
        for i, value in zip(rows, np.atleast_1d(p).tolist(), strict=True):
            out[i] = float(value)
    return out


def units_needed(tests: int, alpha: float = FALSE_ALARM) -> int:
    """The fewest units whose paired test can fail a figure at ``alpha / tests``: the signed-rank test's
    smallest one-sided p-value over ``n`` units is ``2**-n`` (every difference worse)."""
    return math.floor(math.log2(max(1, tests) / alpha)) + 1


def unjudged(baseline: dict[str, Any], summary: dict[str, Any]) -> list[str]:
    """The groups ``summary`` holds that ``baseline`` does not (a strategy added since): not judged."""
    return [g for g in summary["groups"] if g not in baseline["groups"]]


def _tied(samples: _Samples) -> bool:
    """Whether the test's ranks hold ties as scipy counts them: among the differences' sizes, or a zero
    difference (paired); among both samples' values (two-sample)."""
    _, now, base = samples
    values = np.abs(now) if base is None else np.concatenate([now, base])
    return len(np.unique(values)) < len(values) or (base is None and not now.all())


#: What a summary keeps when it is written as a baseline: no machine's paths, the groups whole.
_BASELINE_KEYS = ("format", "name", "units", "first_seed", "strategies", "scenarios", "series_hz", "groups")


def baseline_of(summary: dict[str, Any]) -> dict[str, Any]:
    """``summary`` without the paths of the machine that ran it (a baseline is shipped and shared)."""
    return {k: summary[k] for k in _BASELINE_KEYS if k in summary}


def check_baseline(doc: dict[str, Any], source: str | Path, spec: CampaignSpec | None = None) -> None:
    """Refuse, before any work, a baseline that would test nothing or less than it says: no groups; a
    group without figures, without each of :data:`GATED`, or with a figure that is not a campaign's; a
    figure's values that are not one finite number per unit (null, NaN, an empty list); ``unit_seed``
    not a list of distinct whole numbers. With ``spec``, a group must be one of its scenario × strategy
    and an aided scenario's group must carry its aided figures.

    Raises
    ------
    SinsInputError
        one line naming ``source`` and the place (``groups.G.values.F[i]``).
    """
    groups = doc.get("groups")
    if not isinstance(groups, dict) or not groups:
        raise SinsInputError(
            f"{source}: groups: a baseline needs at least one scenario/strategy group to test"
        )
    for name, group in groups.items():
        where = f"{source}: groups.{printable(name)}"
        if not isinstance(group, dict) or not isinstance(group.get("values"), dict):
            raise SinsInputError(f"{where}.values: expected a table of each unit's figures")
        values = group["values"]
        seeds = values.get("unit_seed")
        if not isinstance(seeds, list) or not seeds or not all(type(u) is int for u in seeds):
            raise SinsInputError(f"{where}.values.unit_seed: expected a non-empty list of whole numbers")
        if len(set(seeds)) != len(seeds):
            raise SinsInputError(f"{where}.values.unit_seed: a unit_seed appears twice")
        required = set(GATED) | (_aided_figures(spec, name) if spec is not None else set())
        missing = sorted(required - set(values))
        if missing:
            raise SinsInputError(
                f"{where}.values: has no {missing[0]} (a baseline must hold every figure it gates)"
            )
        for figure, figures in values.items():
            if figure != "unit_seed":
                _check_figure(f"{where}.values.{printable(figure)}", figure, figures, len(seeds))
        if spec is not None:
            _check_group(where, name, spec)


def check_power(doc: dict[str, Any], source: str | Path, alpha: float = FALSE_ALARM) -> None:
    """Refuse a baseline (checked by :func:`check_baseline`) of fewer units than any of its figures could
    fail with at ``alpha`` over them all (:func:`units_needed`): such a gate had said "all figures hold"
    of a strategy ten times worse. :func:`compare` and ``sins check`` (before the runs, and before writing
    a baseline) call it."""
    groups = doc["groups"]
    tests = sum(len(g["values"]) - 1 for g in groups.values())
    units = min(len(g["values"]["unit_seed"]) for g in groups.values())
    if units < units_needed(tests, alpha):
        raise SinsInputError(
            f"{source}: {units} units cannot show a regression: each of its {tests} figures is tested at "
            f"{alpha / tests:.2g}, and the least p-value {units} paired units give is "
            f"{2.0**-units:.2g}; a baseline needs {units_needed(tests, alpha)} units or more"
        )


def _check_figure(where: str, figure: str, figures: Any, units: int) -> None:
    if figure not in GATED and not AIDED_COLUMN.fullmatch(figure):
        raise SinsInputError(f"{where}: not a figure a campaign gates")
    if not isinstance(figures, list) or len(figures) != units:
        size = f"{len(figures)} values" if isinstance(figures, list) else type(figures).__name__
        raise SinsInputError(f"{where}: expected {units} numbers, one per unit_seed, got {size}")
    for i, x in enumerate(figures):
        if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x) or x < 0:
            raise SinsInputError(
                f"{where}[{i}]: expected a finite number >= 0 (an error's size), got {short(x)}"
            )


def _check_group(where: str, name: str, spec: CampaignSpec) -> None:
    scenario, _, strategy = name.partition("/")
    if scenario not in {s.name for s in spec.scenarios}:
        raise SinsInputError(f"{where}: the campaign has no scenario {short(scenario)}")
    if strategy not in ("none", *spec.compensation.strategies):
        raise SinsInputError(f"{where}: the campaign runs no strategy {short(strategy)}")


def _aided_figures(spec: CampaignSpec, group: str) -> set[str]:
    """The aided figures every row of ``group``'s scenario has (none for a free-inertial one)."""
    scenario = next((s for s in spec.scenarios if s.name == group.partition("/")[0]), None)
    if scenario is None or scenario.aiding is None:
        return set()
    return {"aided_final_horizontal_m", "aided_max_horizontal_m"}


__all__ = [
    "FALSE_ALARM",
    "FLOAT_NOISE",
    "GATED",
    "Check",
    "Verdict",
    "baseline_of",
    "check_baseline",
    "check_power",
    "compare",
    "units_needed",
    "unjudged",
]
