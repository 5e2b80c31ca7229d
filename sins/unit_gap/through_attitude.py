"""The accelerometer judged with the gyro as its diagnosis corrects it.

The accelerometer's residual over an interval is the velocity change its readings make, turned by the
attitude the gyro integrates within the interval (:mod:`sins.unit_gap.intervals`). An error of the gyro
turns that attitude, and gravity turned with it shows on the accelerometer's channels: EuRoC's MH_01
with 0.3 °/s of hum on gyro x (``tools/gap_real_cases.py``) had accel y flagged with the same 37.8 s
period, BROAD's trial 05 (as a 120 Hz capture's reference, from where it moves) with a bias step on gyro
y had accel x flagged stepping at the same second, a gyro scale nonlinearity brought ``accel.size_effect``
with it on MH_01, and numpy's unit with its gyro 5 ms late had accelerometer effects named on six of ten
motions (a disturbance on the gyro is fitted on the gyro, so the accelerometer keeps what the gyro's
error did to it).

So where the gyro's diagnosis fitted anything beyond its baseline (accepted effects with columns, and
disturbances outside the library), its readings are corrected by that fit, per step, and the
accelerometer is searched again on them (:func:`accel_rediagnosed`; each sensor's search is its own, so
the gyro's is not repeated): that is the report's accelerometer, the gyro's stays the first's. A
random bias is not taken out: it has no columns (its path is the intervals' noise model's). The report
says what the accelerometer's verdicts were before.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.core.series import ReferencedRecording
from sins.imu import CHANNELS
from sins.unit_gap.search import IntervalDiagnosis, diagnose_intervals, step_columns

Array = NDArray[np.float64]


def gyro_error(d: IntervalDiagnosis) -> tuple[Array, list[str]] | None:
    """The gyro's error per step of the readings that its diagnosis fitted beyond the baseline, rad/s
    (n, 3), and what it is in words (the effects' names, the disturbances' channels and kinds); None
    where it fitted nothing that has columns. The coefficients are one least squares of all of them
    beside the baseline on the fit intervals, as the report's sizes are."""
    st, res = d.states["gyro"], d.residuals
    axes = [a for a in range(3) if a not in st.aside]
    parts: list[tuple[int, Array, Array]] = []  # (axis, per step (n, q), its columns (k, 3, q))
    names = []
    for cand in st.accepted:
        if cand.phis is not None:  # a random bias: its path is the noise model's
            continue
        names.append(cand.name)
        parts += [(a, step_columns(res, cand.name, a), cand.per_axis[a]) for a in axes]
    for t in [*st.disturbances, *d.leftover.get("gyro", [])]:
        parts.append(("xyz".index(t.outside.channel[-1]), t.per_step, t.columns))
    names += [f"{o.channel} {o.kind}" for o in d.outside if o.channel.startswith("gyro")]
    if not parts:
        return None
    coef, _ = st.fit.solve(np.concatenate([st.baseline, *(c for _, _, c in parts)], axis=2))
    error = np.zeros((len(res.dt), 3))
    at = st.baseline.shape[2]
    for axis, u, c in parts:
        width = c.shape[2]
        error[:, axis] += u @ coef[at : at + width]
        at += width
    return error, names


def accel_rediagnosed(
    rec: ReferencedRecording,
    d: IntervalDiagnosis,
    holdout: float,
    interval_s: float,
    progress: Callable[[str], None] | None = None,
) -> tuple[IntervalDiagnosis, dict[str, Any]]:
    """``d`` with its accelerometer's half diagnosed again on ``rec`` with the gyro corrected by
    :func:`gyro_error` (see the module docstring), and what that changed in words; ``d`` and an empty
    note where the gyro's diagnosis fitted nothing with columns."""
    found = gyro_error(d)
    if found is None:
        return d, {}
    error, names = found
    dt = np.diff(rec.imu.t)[:, None]
    imu = dataclasses.replace(rec.imu, dtheta_b=rec.imu.dtheta_b - error * dt)
    try:
        again = diagnose_intervals(
            dataclasses.replace(rec, imu=imu), holdout, interval_s, progress, sensors=("accel",)
        )
    except ValueError as exc:  # the first diagnosis stands, and the report says why
        return d, {"gyro_taken_out": names, "says": f"the accelerometer not diagnosed again: {exc}"}
    if len(again.residuals.iv) != len(d.residuals.iv) or bool(np.any(again.withheld != d.withheld)):
        return d, {
            "gyro_taken_out": names,
            "says": "the accelerometer not diagnosed again: its intervals differ once the gyro is corrected",
        }
    merged = _merged(d, again)
    before, after = _accel_verdicts(d), _accel_verdicts(merged)
    said = ", ".join(names)
    says = (
        f"the accelerometer diagnosed with the gyro corrected by what its diagnosis fitted ({said}): the "
        "velocity change is turned by the gyro's attitude"
    )
    read = "; ".join(before) or "nothing"
    says += f"; before, it read {read}" if before != after else "; the same verdicts"
    return merged, {"gyro_taken_out": names, "accel_before": before, "says": says}


def _accel_verdicts(d: IntervalDiagnosis) -> list[str]:
    """The accelerometer's accepted effects and disturbances, in words."""
    effects = [n for n in d.diagnosis if n.startswith("accel")]
    return effects + [f"{o.channel} {o.kind}" for o in d.outside if o.channel.startswith("accel")]


def _merged(d: IntervalDiagnosis, again: IntervalDiagnosis) -> IntervalDiagnosis:
    """``d``'s gyro half beside ``again``'s accelerometer half."""

    def gyro(name: str) -> bool:
        return name.startswith("gyro")

    accepted = [e for e in d.effects if e.accepted and gyro(e.name)]
    accepted += [e for e in again.effects if e.accepted and not gyro(e.name)]
    rest = [e for e in d.effects if not e.accepted and gyro(e.name)]
    rest += [e for e in again.effects if not e.accepted and not gyro(e.name)]
    outside = [o for o in d.outside if gyro(o.channel)] + [o for o in again.outside if not gyro(o.channel)]
    return dataclasses.replace(
        d,
        states={"gyro": d.states["gyro"], "accel": again.states["accel"]},
        before={"gyro": d.before["gyro"], "accel": again.before["accel"]},
        after={"gyro": d.after["gyro"], "accel": again.after["accel"]},
        left={"gyro": d.left["gyro"], "accel": again.left["accel"]},
        effects=accepted + sorted(rest, key=lambda e: -e.score),
        diagnosis=[n for n in d.diagnosis if gyro(n)] + [n for n in again.diagnosis if not gyro(n)],
        outside=sorted(outside, key=lambda o: CHANNELS.index(o.channel)),
        sizes={
            **{k: v for k, v in d.sizes.items() if gyro(k)},
            **{k: v for k, v in again.sizes.items() if not gyro(k)},
        },
        leftover={**again.leftover, "gyro": d.leftover.get("gyro", [])},
    )


__all__ = ["accel_rediagnosed", "gyro_error"]
