"""The campaign gate: does a strategy do worse than its baseline campaign, beyond chance?

A single seed moving says nothing; a distribution moving does. For every scenario × strategy of the
baseline and every gated figure (:data:`GATED`), the units' values now are tested against the
baseline's, one-sided (worse = larger):

* **paired**, when both campaigns drew the same units (same ``unit_seed`` list): the Wilcoxon
  signed-rank test on the differences. Identical values (an unchanged strategy, run again) hold.
* **two-sample**, when the units differ (a reseeded campaign): the Mann–Whitney U test.

A figure regresses when its p-value is below ``alpha / tests`` (Bonferroni over every test of the
comparison), so the chance that a campaign of an unchanged strategy fails the gate at all is at most
``alpha`` (:data:`FALSE_ALARM`). A group of the baseline missing now fails as "missing".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from scipy import stats

from sins.campaign.results import SUMMARISED

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
    """Every gated figure of every group of ``baseline`` (a ``summary.json``) against ``summary``."""
    pairs = []
    for group, base in baseline["groups"].items():
        now = summary["groups"].get(group)
        for figure in [f for f in base["values"] if f != "unit_seed"]:
            b = np.asarray(base["values"].get(figure, []), dtype=float)
            if np.isfinite(b).any():
                pairs.append((group, figure, base, now))
    per_test = alpha / max(1, len(pairs))
    return [_check(group, figure, base, now, per_test) for group, figure, base, now in pairs]


def _check(group: str, figure: str, base: dict[str, Any], now: dict[str, Any] | None, level: float) -> Check:
    if now is None or figure not in now["values"]:
        return Check(group, figure, "", float("nan"), float("nan"), "missing")
    b = np.asarray(base["values"][figure], dtype=float)
    n = np.asarray(now["values"][figure], dtype=float)
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
