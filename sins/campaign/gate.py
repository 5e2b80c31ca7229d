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
from dataclasses import dataclass
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
    pairs = []
    for group, base in baseline["groups"].items():
        now = summary["groups"].get(group)
        for figure in [f for f in base["values"] if f != "unit_seed"]:
            pairs.append((group, figure, base, now))
    per_test = alpha / max(1, len(pairs))
    return [_check(group, figure, base, now, per_test) for group, figure, base, now in pairs]


def _check(group: str, figure: str, base: dict[str, Any], now: dict[str, Any] | None, level: float) -> Check:
    if now is None or figure not in now["values"]:
        return Check(group, figure, "", float("nan"), float("nan"), "missing")
    b = np.asarray(base["values"][figure], dtype=float)
    n = np.asarray(now["values"][figure], dtype=float)
    if not np.isfinite(n).all():  # a unit's figure went NaN or infinite: worse than any number
        return Check(group, figure, "non-finite", float("nan"), 0.0, "regressed")
    ratio = float(np.nanmedian(n) / np.nanmedian(b)) if np.nanmedian(b) > 0 else float("nan")
    if base["values"]["unit_seed"] == now["values"]["unit_seed"]:
        ok = np.isfinite(b) & np.isfinite(n)
        d = n[ok] - b[ok]
        if not d.any():
            return Check(group, figure, "identical", ratio, 1.0, "holds")
        p = float(stats.wilcoxon(d, alternative="greater", zero_method="zsplit").pvalue)
        test = "paired"
    else:
        p = float(stats.mannwhitneyu(n[np.isfinite(n)], b[np.isfinite(b)], alternative="greater").pvalue)
        test = "two-sample"
    return Check(group, figure, test, ratio, p, "regressed" if p < level else "holds")


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


def _check_figure(where: str, figure: str, figures: Any, units: int) -> None:
    if figure not in GATED and not AIDED_COLUMN.fullmatch(figure):
        raise SinsInputError(f"{where}: not a figure a campaign gates")
    if not isinstance(figures, list) or len(figures) != units:
        size = f"{len(figures)} values" if isinstance(figures, list) else type(figures).__name__
        raise SinsInputError(f"{where}: expected {units} numbers, one per unit_seed, got {size}")
    for i, x in enumerate(figures):
        if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
            raise SinsInputError(f"{where}[{i}]: expected a finite number, got {short(x)}")


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
    "GATED",
    "Check",
    "Verdict",
    "baseline_of",
    "check_baseline",
    "compare",
]
