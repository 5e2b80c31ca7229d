"""A recorded IMU replayed through the integrator against its truth: ``sins integrate`` and the drift of
``sins gap``.

:func:`navigate` integrates increments from the truth's state at their first time and compares the
solution with the truth; :func:`integrate_recording` does so for a file (any format sins reads);
:func:`gap_navigation` sets a real unit's drift beside its simulated twin's.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from sins.nav import strapdown
from sins.nav.metrics import nav_errors, summarize
from sins.nav.vertical import VerticalMode
from sins.recordings import load_recording
from sins.run_results import StrategyRun
from sins.series import CalibrationData, ImuIncrements, ImuRates, NavSeries

if TYPE_CHECKING:
    from sins.gap import GapReport


def navigate(
    imu: ImuIncrements, truth: NavSeries, vertical: VerticalMode = "free", vertical_tau_s: float = 10.0
) -> StrategyRun:
    """Integrate ``imu`` from the truth's state at ``imu.t[0]`` and compare with the truth.

    For ``vertical`` "hold" or "damp" the reference height is the truth's.
    """
    start = truth if truth.t[0] == imu.t[0] else truth.interpolate(np.array([imu.t[0]]))
    h_ref = None
    if vertical != "free":
        same = len(truth.t) == len(imu.t) and np.array_equal(truth.t, imu.t)
        h_ref = truth.h if same else truth.interpolate(imu.t).h
    solution = strapdown.integrate(
        imu, strapdown.InitialState.from_series(start), vertical=vertical, h_ref=h_ref,
        vertical_tau_s=vertical_tau_s,
    )  # fmt: skip
    errors = nav_errors(solution, truth)
    return StrategyRun(solution=solution, errors=errors, summary=summarize(errors))


def integrate_recording(
    imu_path: str | os.PathLike[str],
    truth_path: str | os.PathLike[str] | None,
    vertical: VerticalMode = "free",
    vertical_tau_s: float = 10.0,
    within_truth: bool = False,
    reading: Mapping[str, Any] | None = None,
) -> StrategyRun:
    """Integrate a recorded IMU from its truth's first state; errors against the truth.

    :func:`sins.recordings.load_recording` (any format sins reads, ``reading`` its options; without
    ``truth_path`` the recording's own reference; an IMU running past the truth refused unless
    ``within_truth``), then :func:`navigate`.
    """
    rec = load_recording(imu_path, truth_path, within_truth, reading)
    return navigate(rec.imu, rec.truth, vertical, vertical_tau_s)


def gap_navigation(data: CalibrationData, truth: NavSeries, report: GapReport) -> dict[str, float]:
    """Navigation drift of the real unit and of the simulated one (the model before and after the
    accepted effects), integrated over the recording from the truth, vertical channel held to it.

    The simulated unit's readings are the reference plus the model's predicted error (no noise: the
    drift of what the model explains). Returns final horizontal errors against the truth and the
    horizontal distance between the simulated and the real unit's solutions at the end, m.

    ``truth`` is at the recording's times, as :func:`sins.recordings.gap_data` returns it.
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


__all__ = ["gap_navigation", "integrate_recording", "navigate"]
