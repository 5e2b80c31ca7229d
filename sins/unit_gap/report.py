"""The interval diagnosis as a :class:`~sins.gap.report.GapReport`: the same keys as on samples, so that
``sins gap --json`` reads alike whichever statistic was used; ``statistic`` says which, and why.

The channels' figures are the intervals' residuals as mean rates (rad/s, m/s²: the residual over the
interval's length): their withheld RMS before and after the accepted effects, and the noise floor, the
noise level of what the accepted effects leave (:func:`sins.gap.floor.noise_level`, which the epochs that
neighbouring intervals share do not lift).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.gap.report import GapReport
from sins.imu import BASELINE, CHANNELS, DEG_PER_H, MG
from sins.unit_gap.search import (
    BLOCK_S,
    IntervalDiagnosis,
    channel_figures,
    not_on_intervals,
    significant_ratio,
)

Array = NDArray[np.float64]


def reference_limits(d: IntervalDiagnosis, figures: dict[str, dict[str, float]]) -> str:
    """What the reference limits, in words: its noise over an interval against the sensor's (the
    baseline's interval fit), and the mean rate and force error an interval resolves (the floor)."""
    span = float(np.median(d.residuals.span))
    gyro = [figures[c]["noise_floor"] / DEG_PER_H for c in CHANNELS[:3]]
    accel = [figures[c]["noise_floor"] / MG for c in CHANNELS[3:]]
    return (
        f"{d.baseline.quality.summary()}; one interval of {span:.3g} s resolves a mean rate error of "
        f"{min(gyro):.3g}-{max(gyro):.3g} °/h and a force error of {min(accel):.3g}-{max(accel):.3g} mg "
        "(the noise floor): an effect smaller over an interval is seen only over many"
    )


def interval_report(d: IntervalDiagnosis, holdout: float, statistic: dict[str, Any]) -> GapReport:
    """The report of an interval diagnosis (see the module docstring)."""
    figures, unexplained = channel_figures(d)
    span = float(np.median(d.residuals.span))
    where: list[dict[str, Any]] = []
    for ch, v in figures.items():
        disturbances = [o.describe() for o in d.outside if o.channel == ch]
        if v["rms_before"] > significant_ratio(int(d.withheld.sum())) * v["noise_floor"] or disturbances:
            where.append({
                "channel": ch,
                "excess": v["rms_before"] / v["noise_floor"],
                "concentrates": [f"over the reference's intervals of {span:.3g} s", *disturbances],
            })  # fmt: skip
    where.sort(key=lambda w: -float(w["excess"]))
    k = len(d.residuals.iv)
    withholding = (
        f"the last {holdout:g} of the reference's intervals of {span:.3g} s in every {BLOCK_S:g} s "
        f"({int(d.withheld.sum())} of {k})"
    )
    return GapReport(
        channels=figures,
        where=where,
        effects=d.effects,
        diagnosis=d.diagnosis,
        unexplained=unexplained,
        outside=d.outside,
        rows=(int(d.fit.sum()), int(d.withheld.sum())),
        withholding=withholding,
        unfitted=not_on_intervals(),
        model=BASELINE,
        residual_before=_as_rates(d, d.before),
        residual_after=_as_rates(d, d.after),
        t_withheld=d.residuals.t_mid[d.withheld],
        sizes=d.sizes,
        statistic={**statistic, "reference_limits": reference_limits(d, figures), "interval_s": span},
    )


def _as_rates(d: IntervalDiagnosis, left: dict[str, Array]) -> Array:
    """The withheld intervals' residuals (m, 6) as mean rates, in :data:`~sins.imu.CHANNELS`' order."""
    span = d.residuals.span[d.withheld][:, None]
    return np.hstack([left["gyro"][d.withheld], left["accel"][d.withheld]]) / span


__all__ = [
    "interval_report",
    "reference_limits",
]
