"""A unit's recordings diagnosed: each on the statistic its reference calls for, then the verdicts across
them and the shrink of each one's model judged on another (what ``sins gap`` does).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.compensation import seed_terms
from sins.compensation.interval_fit import IntervalFit
from sins.compensation.intervals import INTERVAL_S
from sins.core.series import CalibrationData, NavSeries
from sins.errors import SinsInputError
from sins.gap import GapReport, diagnose
from sins.imu import BASELINE, CHANNELS
from sins.io.filled import spans_said
from sins.unit_gap import across, clock, delays, plausible, shrink, statistic, through_attitude
from sins.unit_gap.inputs import GapInput
from sins.unit_gap.report import interval_report
from sins.unit_gap.search import BLOCK_S, baseline_fit, diagnose_intervals

#: The shortest recording diagnosed against a trajectory, s: two blocks, each of whose last part is held
#: back (1-2 s of a unit at rest had been given per-sample verdicts and lever arms of 14 m, where 5-20 s
#: were refused for too few intervals).
MIN_SPAN_S = 2.0 * BLOCK_S


@dataclass
class Diagnosed:
    """One recording diagnosed: its name, the report, how many rows it has, and its per-sample form
    where it was diagnosed on samples (for the navigation beside a trajectory)."""

    name: str
    report: GapReport
    rows: int
    samples: tuple[CalibrationData, NavSeries | None] | None = None
    extra: dict[str, Any] = field(default_factory=dict)


def diagnose_one(
    inp: GapInput,
    holdout: float = 0.3,
    model: tuple[str, ...] = BASELINE,
    asked: str = "auto",
    interval_s: float | None = None,
    progress: Callable[[str], None] | None = None,
) -> Diagnosed:
    """``inp`` diagnosed on the statistic ``asked`` for ("auto": :func:`sins.unit_gap.statistic.choose`).

    Raises
    ------
    SinsInputError
        one line naming the recording: intervals asked of a per-sample reference, a recording whose
        intervals cannot be fitted, a model beyond the baseline on intervals, and as the diagnosis does.
    """
    if inp.referenced is not None:  # whichever statistic: a 1 s recording had been given a diagnosis
        span = float(inp.referenced.imu.t[-1] - inp.referenced.imu.t[0])
        if span < MIN_SPAN_S:
            raise SinsInputError(
                f"{inp.name}: {span:.3g} s of readings; a diagnosis against a trajectory needs at least "
                f"{MIN_SPAN_S:g} s (two of the {BLOCK_S:g} s blocks whose last part it holds back)"
            )
    if asked == "samples" and interval_s is not None:  # it had changed the reference's line alone
        raise SinsInputError(f"{inp.name}: an interval length goes with the interval statistic, not samples")
    interval_s = INTERVAL_S if interval_s is None else interval_s
    if asked == "intervals" and inp.referenced is None:
        raise SinsInputError(
            f"{inp.name}: --statistic intervals needs a reference trajectory; this one is per-sample inputs"
        )
    baseline, unfitted = _baseline(inp, interval_s) if inp.referenced is not None else (None, "")
    found = _diagnosed(inp, baseline, unfitted, holdout, model, asked, interval_s, progress)
    if baseline is None:
        return found
    # Each recording's seed model beside its verdicts: what the verdicts across recordings compare.
    seed = {**found.report.statistic, "seed_model": seed_terms.of_fit(baseline.seed)}
    return dataclasses.replace(found, report=_with_statistic(found.report, seed))


def _diagnosed(
    inp: GapInput,
    baseline: IntervalFit | None,
    unfitted: str,
    holdout: float,
    model: tuple[str, ...],
    asked: str,
    interval_s: float,
    progress: Callable[[str], None] | None,
) -> Diagnosed:
    """``inp`` diagnosed on the statistic ``asked`` for, its baseline on intervals given (or None and
    why not: ``unfitted``)."""
    data = _samples(inp, asked)
    trajectory = inp.referenced.reference if inp.referenced is not None else None
    chosen = statistic.choose(
        asked, data[0] if data else None, trajectory, baseline.quality if baseline else None
    )
    if chosen.kind == "samples":
        found = _on_samples(inp, data, holdout, model, progress, chosen)
        baseline_model = tuple(model) == tuple(BASELINE)  # the intervals take no other
        if asked == "auto" and baseline is not None and baseline_model and _every_channel_left(found, chosen):
            return _intervals_instead(inp, found, baseline, holdout, interval_s, progress, chosen)
        return found
    if tuple(model) != tuple(BASELINE):
        raise SinsInputError(f"{inp.name}: --model goes with the per-sample statistic (--statistic samples)")
    if baseline is None:
        # The reference calls for intervals (or they were asked for), and they cannot be fitted.
        where = unfitted if inp.name in unfitted else f"{inp.name}: {unfitted}"
        raise SinsInputError(f"{where}; --statistic samples diagnoses it per sample without them")
    per_sample = data if asked == "auto" else None  # the delays are tried per sample where auto chose
    return _on_intervals(inp, baseline, holdout, interval_s, progress, chosen, per_sample)


def _on_samples(
    inp: GapInput,
    data: tuple[CalibrationData, NavSeries | None] | None,
    holdout: float,
    model: tuple[str, ...],
    progress: Callable[[str], None] | None,
    chosen: statistic.Statistic,
) -> Diagnosed:
    """``inp`` diagnosed per sample (:func:`sins.gap.diagnose`)."""
    if data is None:
        data = inp.samples()
    report = diagnose(data[0], holdout, model, progress)
    report = _with_reference(_with_statistic(report, chosen.to_dict()), inp)
    readings = np.hstack([data[0].gyro, data[0].accel])
    return Diagnosed(inp.name, _with_plausibility(report, readings), len(data[0]), data)


def _on_intervals(
    inp: GapInput,
    baseline: IntervalFit,
    holdout: float,
    interval_s: float,
    progress: Callable[[str], None] | None,
    chosen: statistic.Statistic,
    data: tuple[CalibrationData, NavSeries | None] | None,
) -> Diagnosed:
    """``inp`` diagnosed on its reference's intervals, the accelerometer with the gyro as corrected
    (:mod:`sins.unit_gap.through_attitude`), and the delays per sample beside them where ``data``, the
    per-sample form, is given (:mod:`sins.unit_gap.delays`)."""
    assert inp.referenced is not None
    try:
        d = diagnose_intervals(inp.referenced, holdout, interval_s, progress, baseline)
    except ValueError as exc:
        raise SinsInputError(f"{inp.name}: {exc}") from None
    d, attitude_note = through_attitude.accel_rediagnosed(inp.referenced, d, holdout, interval_s, progress)
    report = interval_report(d, holdout, chosen.to_dict())
    if attitude_note:
        report = _with_statistic(report, {**report.statistic, "accel_with_gyro_corrected": attitude_note})
    if data is not None:
        report = delays.with_delays(report, data[0], inp.referenced.reference, holdout)
    report = _with_reference(report, inp)
    _, omega, force = inp.referenced.imu.mean_rates()
    readings = np.hstack([omega, force])
    return Diagnosed(inp.name, _with_plausibility(report, readings), len(inp.referenced.imu.t) - 1)


def _every_channel_left(found: Diagnosed, chosen: statistic.Statistic) -> bool:
    """Whether samples were chosen on the sensor's noise measured in motion (no rest to measure it on)
    and the per-sample diagnosis then left every channel unexplained: in motion the local cubic takes
    what it cannot follow for the sensor's noise (a drone's vibration: EuRoC's V1_02 read from where it
    moves had the reading less its reference at 0.32-0.49 of that noise, which no residual is), and the
    per-sample residual holds what no library effect explains per sample."""
    in_motion = chosen.figures.get("sensor_noise_from") == statistic.IN_MOTION
    return in_motion and set(found.report.unexplained) >= set(CHANNELS)


def _intervals_instead(
    inp: GapInput,
    found: Diagnosed,
    baseline: IntervalFit,
    holdout: float,
    interval_s: float,
    progress: Callable[[str], None] | None,
    chosen: statistic.Statistic,
) -> Diagnosed:
    """The diagnosis on intervals where it leaves fewer channels unexplained than ``found``'s per sample
    (:func:`_every_channel_left`), the report saying why; ``found`` otherwise, or where the intervals
    cannot be fitted."""
    why = (
        f"{chosen.why}; but per sample every channel was left unexplained, and the sensor's noise was "
        "measured in motion (no rest), where a drone's vibration passes for noise: the intervals, over "
        "which it averages out, leave fewer"
    )
    instead = statistic.Statistic("intervals", why, chosen.figures)
    try:
        on_intervals = _on_intervals(inp, baseline, holdout, interval_s, progress, instead, found.samples)
    except SinsInputError:
        return found
    if len(on_intervals.report.unexplained) < len(found.report.unexplained):
        return on_intervals
    return found


def _with_plausibility(report: GapReport, readings: NDArray[np.float64]) -> GapReport:
    """The report with its accepted effects whose size no unit has (:mod:`sins.unit_gap.plausible`),
    judged against the recording's largest readings (``readings`` (n, 6), in the channels' order)."""
    largest = dict(zip(CHANNELS, np.abs(readings).max(axis=0).tolist(), strict=True))
    return dataclasses.replace(report, implausible=plausible.implausible(report.sizes, largest))


def _baseline(inp: GapInput, interval_s: float) -> tuple[IntervalFit | None, str]:
    """The interval fit of the baseline, or None and why where the recording's intervals cannot be
    fitted (too few, too little turning)."""
    assert inp.referenced is not None
    try:
        return baseline_fit(inp.referenced, interval_s), ""
    except ValueError as exc:
        return None, str(exc)


def _samples(inp: GapInput, asked: str) -> tuple[CalibrationData, NavSeries | None] | None:
    """The per-sample form where the choice needs it (``auto``) or it is asked for; None where it
    cannot be made from a trajectory (the choice then takes the intervals)."""
    if inp.referenced is None or asked == "samples":
        return inp.samples()
    if asked == "intervals":
        return None
    try:
        return inp.samples()
    except (SinsInputError, ValueError):
        return None


def _with_statistic(report: GapReport, chosen: dict[str, Any]) -> GapReport:
    return dataclasses.replace(report, statistic=chosen)


def _with_reference(report: GapReport, inp: GapInput) -> GapReport:
    """The report with where the reference's clock sits (:mod:`sins.unit_gap.clock`), beside a
    reference trajectory whose turns show it, its spans filled by interpolation, where it has some, and
    its world frame's tilt (:mod:`sins.unit_gap.inputs`)."""
    if inp.referenced is None:
        return report
    if inp.filled_s:
        report = _with_statistic(report, {**report.statistic, "reference_filled": _filled(report, inp)})
    if inp.tilt is not None:
        report = _with_statistic(report, {**report.statistic, "reference_tilt": inp.tilt.to_dict()})
    found = clock.reference_clock(inp.referenced, report.sizes)
    if found is None:
        return report
    if "shared_delay" in found:
        why = "the delay both sensors share, taken for the reference's clock (statistic.reference_clock)"
        report = _clock_not_named(report, found["shared_delay"]["of_the_clock"], why)
    return _with_statistic(report, {**report.statistic, "reference_clock": found})


def _clock_not_named(report: GapReport, names: list[str], why: str) -> GapReport:
    """The report without ``names`` (time offsets taken for the reference's clock,
    :func:`sins.unit_gap.clock.shared_delay`) in its diagnosis, each scored as not accepted and why; their
    sizes stay, as the model the shrink fits keeps them (:func:`modelled`)."""
    effects = [
        dataclasses.replace(e, accepted=False, not_accepted_because=why) if e.name in names else e
        for e in report.effects
    ]
    diagnosis = [n for n in report.diagnosis if n not in names]
    return dataclasses.replace(report, diagnosis=diagnosis, effects=effects)


def modelled(report: GapReport) -> list[str]:
    """The effects the model of ``report``'s recording holds: its diagnosis and the time offsets it took
    for the reference's clock (which a model fitted against that reference needs all the same)."""
    return [*report.diagnosis, *clock.of_the_clock(report.statistic)]  # never in both (_clock_not_named)


def _filled(report: GapReport, inp: GapInput) -> dict[str, Any]:
    """The reference's spans filled by interpolation, and what the diagnosis did with them."""
    intervals = report.statistic.get("kind") == "intervals"
    kept = "set aside from its intervals" if intervals else "kept in its per-sample residuals"
    says = f"{spans_said(inp.filled_s)} filled by interpolation, {kept}"
    return {"spans_s": [list(s) for s in inp.filled_s], "says": says}


def shrinks(
    inputs: list[GapInput], results: list[Diagnosed], interval_s: float | None = None
) -> list[dict[str, Any]]:
    """Each recording's accepted effects fitted on it and judged on the next (the last on the first):
    :func:`sins.unit_gap.shrink.shrink`, where both have a reference trajectory."""
    out = []
    n = len(inputs)
    for i in range(n):
        a, b = inputs[i], inputs[(i + 1) % n]
        if a.referenced is None or b.referenced is None:
            out.append({"fitted_on": a.name, "judged_on": b.name,
                        "verdict": "needs a reference trajectory on both recordings"})  # fmt: skip
            continue
        try:
            figures = shrink.shrink(
                a.referenced, b.referenced, modelled(results[i].report),
                INTERVAL_S if interval_s is None else interval_s,
            )  # fmt: skip
        except (SinsInputError, ValueError) as exc:
            figures = {"verdict": f"not judged: {exc}"}
        out.append({**figures, "fitted_on": a.name, "judged_on": b.name})
    return out


def verdicts(results: list[Diagnosed]) -> dict[str, Any]:
    """The verdicts across the recordings (:func:`sins.unit_gap.across.verdicts`)."""
    return across.verdicts([(r.name, r.report) for r in results])


__all__ = [
    "MIN_SPAN_S",
    "Diagnosed",
    "diagnose_one",
    "modelled",
    "shrinks",
    "verdicts",
]
