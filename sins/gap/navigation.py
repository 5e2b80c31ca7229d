"""The gap diagnosis's drift check: a real unit and its simulated twin navigated over the recording.

The simulated unit's readings are the reference plus the model's predicted error before and after the
accepted effects; their drift beside the real unit's says, in metres, how much of the gap the effects close.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from sins.core.series import CalibrationData, ImuRates, NavSeries
from sins.nav import strapdown
from sins.nav.metrics import nav_errors, summarize

if TYPE_CHECKING:
    from sins.gap.report import GapReport


def gap_navigation(data: CalibrationData, truth: NavSeries, report: GapReport) -> dict[str, float]:
    """Navigation drift of the real unit and of the simulated one (the model before and after the
    accepted effects), integrated over the recording from the truth, vertical channel held to it.

    The simulated unit's readings are the reference plus the model's predicted error (no noise: the
    drift of what the model explains). Returns final horizontal errors against the truth and the
    horizontal distance between the simulated and the real unit's solutions at the end, m.

    ``truth`` is at the recording's times, as :func:`sins.runs.readings.gap_data` returns it.
    """
    start = strapdown.InitialState.from_series(truth.at(0))

    def solve(gyro: NDArray[np.float64], accel: NDArray[np.float64]) -> NavSeries:
        increments = ImuRates(t=data.t, omega_ib_b=gyro, f_ib_b=accel).to_increments()
        return strapdown.integrate(increments, start, vertical="hold", h_ref=truth.h)

    real = solve(data.gyro, data.accel)
    out = {"real_m": summarize(nav_errors(real, truth)).final_horizontal_m}
    for label, predicted in (("before", report.predicted_before), ("after", report.predicted_after)):
        sim = solve(data.ref_gyro + predicted[:, :3], data.ref_accel + predicted[:, 3:])
        out[f"simulated_{label}_m"] = summarize(nav_errors(sim, truth)).final_horizontal_m
        out[f"sim_to_real_{label}_m"] = summarize(nav_errors(sim, real)).final_horizontal_m
    return out


__all__ = [
    "gap_navigation",
]
