"""One unit of a campaign: its rig session, its fitted strategies, its scenarios, its rows.

Pure sins, no distributed engine: a unit's rows depend on the campaign and the unit's index alone,
so any worker, in any order, on any machine, computes the same rows.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sins import pipeline
from sins.campaign.spec import CampaignSpec, nav_seed, rig_seed
from sins.imu import CHANNELS

#: The figures of a row, in the order of its columns (a :class:`sins.nav.metrics.DriftSummary`'s,
#: then the held-back rig residual per channel).
SUMMARY_FIELDS = (
    "final_horizontal_m",
    "max_horizontal_m",
    "rms_horizontal_m",
    "final_down_m",
    "final_roll_deg",
    "final_pitch_deg",
    "final_yaw_deg",
    "drift_rate_m_per_h",
)
RESIDUAL_FIELDS = tuple(f"residual_{ch.replace('.', '_')}" for ch in CHANNELS)


def run_unit(spec: CampaignSpec, unit: int) -> list[dict[str, Any]]:
    """Every row of unit ``unit`` (0-based): one per scenario × strategy, in the campaign's order.

    The unit's rig session is simulated and every strategy fitted once; each scenario is then driven
    with the navigation power-on (:func:`~sins.campaign.spec.nav_seed`), corrected by each strategy
    and integrated by :func:`sins.pipeline.run_scenario`, the very path ``sins run`` takes.
    """
    seed = spec.unit_seed(unit)
    fitted = pipeline.fit_unit(spec.unit_imu(unit), spec.unit_compensation(unit))
    rows = []
    for index, base in enumerate(spec.scenarios):
        sc = spec.unit_scenario(index, unit)
        keep_hz = spec.series_hz if spec.series_hz > 0 else 1.0 / max(base.rate_hz, 1.0)
        result = pipeline.run_scenario(sc, keep_hz=keep_hz, unit=fitted)
        for strategy, run in result.runs.items():
            summary = run.summary.to_dict()
            residual = run.residual_rms or {}
            row: dict[str, Any] = {
                "unit": unit,
                "unit_seed": seed,
                "rig_seed": rig_seed(seed),
                "nav_seed": nav_seed(seed),
                "scenario": base.name,
                "strategy": strategy,
                **{k: float(summary[k]) for k in SUMMARY_FIELDS},
                **{
                    f: float(residual.get(ch, np.nan))
                    for f, ch in zip(RESIDUAL_FIELDS, CHANNELS, strict=True)
                },
            }
            if spec.series_hz > 0:
                row["series_t_s"] = run.errors.t.astype(np.float32).tolist()
                row["series_horizontal_m"] = run.errors.horizontal_m.astype(np.float32).tolist()
            rows.append(row)
    return rows
