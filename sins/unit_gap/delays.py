"""The sensors' delays tried per sample beside a diagnosis on intervals.

A delay's signature is the reading's own rate of change times the delay: per sample, on every reading;
over an interval, only through the change of the reading between the interval's two ends. EuRoC's
accelerometer read 5 ms late (``tools/gap_real_cases.py``) shows 0-3 nats on its intervals, nothing a
diagnosis could name, while per sample it is sized at 4.0-5.2 ms on all four EuRoC bases; the diagnosis
on intervals, which EuRoC's reference calls for (:mod:`sins.unit_gap.statistic`), missed every such case.

Why delays alone: what a reference's noise and its smoothing do per sample follows the motion's size
(the per-sample diagnosis of a clean EuRoC sequence names the accelerometer's scale nonlinearity or size
effect, which its intervals do not), but a zero-phase smoothing shifts nothing in time: per sample the
four clean EuRoC bases name no delay. A reference much noisier than that is another matter: BROAD's
motion capture has delays named per sample on its clean trials (1.8-5.1 ms: its clock, its filters).
The two are told apart by the reference's attitude per sample at rest (the mean over the gyro's
channels of :func:`~sins.unit_gap.statistic.rest_ratios`), which a delay of either sensor hardly moves,
where the per-sample residual over all rows is the delay's own as much as the reference's (EuRoC's V1_02
with the accelerometer 5 ms late: 2.3 → 4.4 times the sensor's noise on accel z). EuRoC's clean bases
read 0.28-0.44 there, 1.26-1.33 with the gyro 5 ms late; BROAD's trials 2.99 and 6.10 as ``sins gap
--dataset`` reads them, 16.3 and 34.2 as ``tools/gap_real_cases.py`` writes them (its reference's velocity
a Savitzky-Golay derivative of the positions). A recording without a rest is judged in motion instead,
against the noise a cubic through 11 readings leaves (:func:`reference_ratios`).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from sins.core.series import CalibrationData, NavSeries
from sins.errors import SinsInputError
from sins.gap import GapReport, diagnose
from sins.unit_gap.clock import BOTH_SIGNS, one_clock
from sins.unit_gap.statistic import IN_MOTION, per_sample_ratios, rest_ratios

#: The reference's attitude per sample at rest, its residual's noise over the gyro's own averaged over the
#: gyro's channels, within which the delays are tried per sample: the reference's own noise there at
#: most √(2² − 1) = 1.7 times the gyro's. Between the largest of EuRoC's cases (1.33) and the smallest of
#: BROAD's (2.99), about as far from each (×1.5).
DELAY_RATIO = 2.0
#: The effects tried per sample.
DELAYS = ("gyro.time_offset", "accel.time_offset")


def with_delays(
    report: GapReport, data: CalibrationData | None, reference: NavSeries, holdout: float
) -> GapReport:
    """``report`` (a diagnosis on intervals) with the delays that the per-sample residuals of ``data``
    (its reference inputs from the trajectory ``reference``) show and it lacks, where the reference
    allows (:data:`DELAY_RATIO`); ``statistic.delays_per_sample`` says what was tried and found, or why
    not. ``report`` as it is where there is no per-sample form."""
    if data is None:
        return report
    at_rest, where = reference_ratios(data, reference)
    untried: dict[str, Any] = {"tried": False, "rest_ratios": at_rest, "ratios_measured": where}
    gyro = {ch: r for ch, r in at_rest.items() if ch.startswith("gyro")}
    if not gyro:
        said = "delays not tried per sample: the reference's noise not measured per sample"
        return _noted(report, {**untried, "says": said})
    mean = sum(gyro.values()) / len(gyro)
    if mean > DELAY_RATIO:
        said = (
            f"delays not tried per sample: {where} the reference's rate varies {mean:.2g}x the gyro's own "
            f"noise (the mean over its axes), beyond {DELAY_RATIO:g}x (a reference that noisy per sample "
            "has lags of its own: its clock, its filters)"
        )
        return _noted(report, {**untried, "says": said})
    try:
        found = diagnose(data, holdout, candidates=DELAYS)
    except (SinsInputError, ValueError) as exc:  # what the intervals diagnosed stands
        return _noted(report, {**untried, "says": f"delays not tried per sample: {exc}"})
    # A sensor with a channel that a disturbance outside the library explains is not given a delay
    # here, as the search tries no candidate there: the per-sample search does not fit the disturbance,
    # and EuRoC's V1_02 with a 0.3 °/s hum on gyro x had a gyro delay of 0.1 ms named beside it.
    disturbed = {o.channel.split(".")[0] for o in report.outside}
    sizes_ms = {n: {ch: 1e3 * v[0] for ch, v in found.sizes[n].items()} for n in found.diagnosis}
    added = [
        n for n in found.diagnosis
        if n not in report.diagnosis and n.split(".")[0] not in disturbed and one_clock(sizes_ms[n])
    ]  # fmt: skip
    note: dict[str, Any] = {
        "tried": True,
        "rest_ratios": at_rest,
        "ratios_measured": where,
        "accepted": list(found.diagnosis),
        "added": added,
        "beside_a_disturbance": [n for n in found.diagnosis if n not in (*report.diagnosis, *added)],
        "scores": {e.name: e.score for e in found.effects},
        "sizes_ms": sizes_ms,
        "says": _said(found, report, added, sizes_ms),
    }
    taken = {e.name: e for e in found.effects if e.name in added}
    return dataclasses.replace(
        _noted(report, note),
        diagnosis=[*report.diagnosis, *added],
        effects=[e for e in report.effects if e.name not in taken] + list(taken.values()),
        sizes={**report.sizes, **{n: found.sizes[n] for n in added}},
    )


def reference_ratios(data: CalibrationData, reference: NavSeries) -> tuple[dict[str, float], str]:
    """Per channel, the reference's noise per sample against the sensor's: on the rows at rest
    (:func:`~sins.unit_gap.statistic.rest_ratios`), or, without a rest of 200 rows, over every row
    against the noise a cubic through 11 readings leaves (:func:`~sins.unit_gap.statistic.per_sample_ratios`),
    which motion the cubic cannot follow inflates: EuRoC's V1_02 read from where it moves reads 0.32-0.49
    there (its drone's vibration), BROAD's trials so read 8.1 and 19 (their capture system); and where
    it was measured, in words."""
    at_rest = rest_ratios(data, reference)
    if at_rest:
        return at_rest, "at rest"
    return per_sample_ratios(data, reference)[0], f"in motion (no rest; against {IN_MOTION})"


def _said(
    found: GapReport, report: GapReport, added: list[str], sizes_ms: dict[str, dict[str, float]]
) -> str:
    """One line: the delays tried per sample, and what each came to beside ``report``'s diagnosis."""
    head = f"delays tried per sample ({', '.join(DELAYS)}; a delay shows on every reading there)"
    if not found.diagnosis:
        return f"{head}: none found"
    parts = []
    for name in found.diagnosis:
        sized = ", ".join(f"{ch} {ms:.2f}" for ch, ms in sizes_ms[name].items())
        why = ""
        if name in report.diagnosis:
            why = "; named on the intervals too"
        elif not one_clock(sizes_ms[name]):
            why = f"; not named: {BOTH_SIGNS}"
        elif name not in added:
            why = "; not named: a disturbance outside the library is on that sensor"
        parts.append(f"{name} ({sized} ms{why})")
    return f"{head}: {'; '.join(parts)}"


def _noted(report: GapReport, note: dict[str, Any]) -> GapReport:
    return dataclasses.replace(report, statistic={**report.statistic, "delays_per_sample": note})


__all__ = ["DELAYS", "DELAY_RATIO", "reference_ratios", "with_delays"]
