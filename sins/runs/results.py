"""What a run gives back: one integrated stream's errors, one aided run's, and a scenario's runs.

Plain frozen dataclasses of arrays, made by :mod:`sins.runs.pipeline` (scenarios), :mod:`sins.runs.replay`
(recorded IMUs) and read by the command line, :mod:`sins.viz.plots`, :mod:`sins.viz.viewer` and campaigns.
Summaries cover every sample; the series are thinned for display (:data:`sins.runs.pipeline.MAX_KEPT`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.aiding.outages import OutageError
from sins.core.series import NavSeries
from sins.nav.metrics import DriftSummary, NavErrors
from sins.scenario import Scenario


@dataclass(frozen=True)
class StrategyRun:
    """One integrated IMU stream and its errors against the truth.

    ``residual_rms`` (compensated scenarios): per channel, the RMS of the
    corrected reading's error on the rig data held back from the fit, SI units.
    ``sensor_error`` (scenarios with an IMU model): the error of the stream
    this run integrated (corrected reading − ideal), (m, 6) in rad/s and m/s²
    in the order of :data:`sins.imu.CHANNELS`, as block means at the
    scenario's ``sensor_t``.
    """

    solution: NavSeries
    errors: NavErrors
    summary: DriftSummary
    residual_rms: dict[str, float] | None = None
    sensor_error: NDArray[np.float64] | None = None


@dataclass(frozen=True)
class AidedRun:
    """One strategy's stream integrated by the GNSS/INS filter (:mod:`sins.aiding.ekf`).

    The summary covers every sample; for display, ``errors`` are thinned as the scenario's plain
    runs', and the filter's records (``t_cov``: each propagation step's end and each update) to at
    most :data:`~sins.runs.pipeline.MAX_KEPT`: ``sigma`` (m, 15) the 1σ of the filter's states (position
    NED m, velocity m/s, attitude rad, gyro bias rad/s, accelerometer bias m/s²), ``bias`` (m, 6) the
    estimated gyro and accelerometer biases. ``true_bias`` (6,) is the unit's constant bias (None for
    the ideal IMU); ``fix_t`` the fixes' times; ``restarts`` when the filter started again from a fix
    after a run of refused ones (:class:`sins.aiding.ekf.FilterConfig` ``reinit_after``). An in-motion
    alignment starts the filter at ``start_s``: the summary and ``errors`` cover the run from there.
    """

    summary: DriftSummary
    fixes: int
    rejected: int
    outages: tuple[OutageError, ...]
    filter_grade: str = "navigation"
    errors: NavErrors | None = None
    t_cov: NDArray[np.float64] | None = None
    sigma: NDArray[np.float64] | None = None
    bias: NDArray[np.float64] | None = None
    true_bias: NDArray[np.float64] | None = None
    fix_t: NDArray[np.float64] | None = None
    restarts: tuple[float, ...] = ()  # times the filter started again after a run of refused fixes, s
    alignment: str = "truth"  # how the filter started: "static", "gnss_velocity" or "truth"
    start_s: float = 0.0  # when it started (an in-motion alignment's fix), s
    static_s: float = 0.0  # a static alignment's still window, s
    heading_sigma_deg: float | None = None  # the in-motion alignment's heading 1σ told to the filter, °
    velocity_rejected: int = 0  # GNSS velocities the gate refused (with velocity fixes)


@dataclass(frozen=True)
class ScenarioRun:
    """A scenario's truth and one run per compensation strategy.

    Summaries use every sample; ``truth`` and each run's ``solution`` and
    ``errors`` are thinned to about ``keep_hz`` (every ``round(rate/keep_hz)``-th
    sample, plus the last), and to at most :data:`~sins.runs.pipeline.MAX_KEPT` samples for longer
    runs, so that memory stays bounded whatever the duration, and the
    runs' ``sensor_error`` are means over blocks of as many intervals, centred
    at ``sensor_t``: a mean keeps the systematic error a plot can show and
    averages down the noise it cannot.
    """

    scenario: Scenario
    samples: int
    truth: NavSeries
    runs: dict[str, StrategyRun]
    sensor_t: NDArray[np.float64] | None = None
    aided: dict[str, AidedRun] = field(default_factory=dict)

    def to_dict(self, source: str | None = None) -> dict[str, Any]:
        """The run as ``sins run --json`` writes it: ``scenario`` (its name, file ``source`` or the
        scenario's own, rate, samples, duration, vertical channel), ``strategies`` (each run's summary,
        :meth:`sins.nav.metrics.DriftSummary.to_dict`, with its ``residual_rms`` where it has one) and, for
        an aided scenario, ``aided`` and ``outages`` (:meth:`aided_dicts`)."""
        sc, n = self.scenario, self.samples
        strategies: dict[str, dict[str, Any]] = {}
        for name, run in self.runs.items():
            strategies[name] = run.summary.to_dict()
            if run.residual_rms is not None:
                strategies[name]["residual_rms"] = run.residual_rms
        file = source if source is not None else str(sc.source or "")
        scenario = {"name": sc.name, "file": file, "rate_hz": sc.rate_hz, "samples": n,
                    "duration_s": n / sc.rate_hz, "vertical": sc.vertical}  # fmt: skip
        document: dict[str, Any] = {"scenario": scenario, "strategies": strategies}
        aided, outages = self.aided_dicts()
        if aided:
            document |= {"aided": aided, "outages": outages}
        return document

    def aided_dicts(self) -> tuple[dict[str, dict[str, Any]], dict[str, list[dict[str, float]]]]:
        """The aided runs' summaries (with their fix counts and how they started) and their errors per
        outage, as JSON objects; both empty for a scenario without aiding."""
        aided: dict[str, dict[str, Any]] = {}
        outages: dict[str, list[dict[str, float]]] = {}
        aiding = self.scenario.aiding
        if aiding is None:
            return aided, outages
        for name, run in self.aided.items():
            aided[name] = {**run.summary.to_dict(), "fixes": run.fixes, "rejected_fixes": run.rejected}
            if aiding.sigma_vel_mps is not None:
                aided[name]["rejected_velocity_fixes"] = run.velocity_rejected
            aided[name] |= {"alignment": run.alignment, "alignment_start_s": run.start_s}
            if run.alignment == "static":
                aided[name]["alignment_static_s"] = run.static_s
            if run.heading_sigma_deg is not None:
                aided[name]["alignment_heading_sigma_deg"] = run.heading_sigma_deg
            if run.restarts:
                aided[name]["filter_restarts_s"] = list(run.restarts)
            outages[name] = [
                {"start_s": o.start_s, "end_s": o.end_s, "final_horizontal_m": o.final_m,
                 "max_horizontal_m": o.max_m}
                for o in run.outages
            ]  # fmt: skip
        return aided, outages


__all__ = ["AidedRun", "ScenarioRun", "StrategyRun"]
