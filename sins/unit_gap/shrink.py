"""What a diagnosis buys in navigation terms, judged on another recording of the unit.

The model with recording A's accepted effects is fitted on all of A's intervals (the baseline's columns
and the effects', :mod:`sins.unit_gap.intervals`), and so is the baseline alone; each corrects recording
B's readings (read later by the fitted time offsets, the effects' errors taken away at B's own inputs,
the seed model inverted). B's gyro bias is then taken from B's opening rest, as a user does with a
calibration from another day (a MEMS bias moves between recordings: 0.08 rad/s between EuRoC's); without
such a rest it is fitted on B's intervals, and the report says so. Judged on B, open loop
(:func:`sins.compensation.judging.open_loop`: the corrected gyro integrated alone from B's first reference
attitude) and free inertial over windows (:func:`sins.compensation.judging.drive_errors`: attitude and
velocity).
Random biases and output maps predict nothing of another recording; they are named and left out.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.compensation import judging
from sins.compensation.interval_fit import fit_biases
from sins.compensation.intervals import correct_increments, shifted
from sins.core.series import ImuIncrements, ReferencedRecording
from sins.errors import SinsInputError
from sins.imu import vocabulary
from sins.imu.calibration import SeedModelFit
from sins.unit_gap.fitter import SensorFit
from sins.unit_gap.intervals import interval_residuals, step_inputs
from sins.unit_gap.search import baseline_fit, candidates

Array = NDArray[np.float64]

#: The windows of free-inertial navigation the velocity is judged over, s.
WINDOW_S = 10.0


@dataclass(frozen=True)
class UnitModel:
    """A unit's model fitted on one recording: the seed model, each sensor's per-axis time offsets (s),
    and each effect's coefficients per axis (SI, its columns' order)."""

    seed: SeedModelFit
    delays: dict[str, Array]
    effects: dict[str, list[Array]]

    def correct(self, imu: ImuIncrements) -> ImuIncrements:
        """``imu`` read later by the time offsets, its effects' errors taken away, the seed inverted."""
        dtheta, dv = imu.dtheta_b.copy(), imu.dv_b.copy()
        for sensor, out in (("gyro", dtheta), ("accel", dv)):
            for a, tau in enumerate(self.delays.get(sensor, np.zeros(3))):
                if tau:
                    out[:, a] = shifted(imu.t, imu.dtheta_b if sensor == "gyro" else imu.dv_b, float(tau))[
                        :, a
                    ]
        first = correct_increments(ImuIncrements(t=imu.t, dtheta_b=dtheta, dv_b=dv), self.seed)
        steps, dt = step_inputs(first), np.diff(imu.t)
        for name, per_axis in self.effects.items():
            sensor = name.split(".")[0]
            cls = vocabulary.effect_class(name)
            out = dtheta if sensor == "gyro" else dv
            for a, coef in enumerate(per_axis):
                out[:, a] -= (cls.columns(steps, sensor, a) @ coef) * dt
        return correct_increments(ImuIncrements(t=imu.t, dtheta_b=dtheta, dv_b=dv), self.seed)


def fit_model(
    rec: ReferencedRecording, effects: list[str], interval_s: float = 1.0
) -> tuple[UnitModel, list[str]]:
    """The baseline and those of ``effects`` that predict another recording (regressors, time offsets)
    fitted on every interval of ``rec``; and the effects left out."""
    base = baseline_fit(rec, interval_s)
    res = interval_residuals(rec, base.seed, interval_s)
    by_name = {c.name: c for c in candidates(res)}
    kept = [e for e in effects if e in by_name and by_name[e].phis is None]
    left_out = [e for e in effects if e not in kept]
    everything = np.ones(len(res.iv), dtype=bool)
    changes: dict[str, Array] = {}
    delays: dict[str, Array] = {}
    fitted: dict[str, list[Array]] = {}
    for sensor in ("gyro", "accel"):
        blocks = [res.baseline(sensor, base.g_sensitivity)] + [
            by_name[e].columns([0, 1, 2]) for e in kept if e.startswith(sensor)
        ]
        columns = np.concatenate(blocks, axis=2)
        sf = SensorFit.of(res.residual[sensor], everything, ~everything, res.joined, columns)
        coef, _ = sf.solve(columns)
        width = blocks[0].shape[2]
        changes[sensor] = coef[:width]
        at = width
        for e in (e for e in kept if e.startswith(sensor)):
            per_axis = []
            for a in range(3):
                w = by_name[e].per_axis[a].shape[2]
                per_axis.append(coef[at : at + w])
                at += w
            if e.endswith("time_offset"):
                delays[sensor] = np.array([float(p[0]) for p in per_axis])
            else:
                fitted[e] = per_axis
    return UnitModel(_updated(base.seed, changes, base.g_sensitivity), delays, fitted), left_out


def _updated(seed: SeedModelFit, changes: dict[str, Array], g_sensitivity: bool) -> SeedModelFit:
    """The seed model moved by the baseline columns' coefficients (per axis: bias, its scale and
    misalignment row, the gyro's g-sensitivity row where it is fitted)."""
    g = changes["gyro"].reshape(3, 7 if g_sensitivity else 4)
    a = changes["accel"].reshape(3, 4)
    k = seed.K + g[:, 4:7] if g_sensitivity else seed.K
    return dataclasses.replace(
        seed, B0=seed.B0 + g[:, 0], B=seed.B + g[:, 1:4], K=k, A0=seed.A0 + a[:, 0], A=seed.A + a[:, 1:4],
    )  # fmt: skip


def judged(rec: ReferencedRecording, model: UnitModel, interval_s: float = 1.0) -> tuple[dict[str, Any], str]:
    """``rec`` corrected by ``model``, its gyro bias from its opening rest (else from its intervals),
    judged open loop and free inertial (:data:`WINDOW_S` windows); and where the bias came from."""
    imu = model.correct(rec.imu)
    corrected = dataclasses.replace(rec, imu=imu)
    try:
        open_loop = judging.open_loop(None, corrected, bias_from_rest=True)
        rest = judging.opening_rest(corrected)
        bias = imu.dtheta_b[rest].sum(axis=0) / np.diff(imu.t)[rest].sum()
        source = "its opening rest"
    except SinsInputError:
        bias = fit_biases(corrected, interval_s=interval_s).seed.B0
        open_loop = None
        source = "its own intervals (no opening rest to take it from)"
    imu = ImuIncrements(t=imu.t, dtheta_b=imu.dtheta_b - bias * np.diff(imu.t)[:, None], dv_b=imu.dv_b)
    corrected = dataclasses.replace(rec, imu=imu)
    if open_loop is None:
        open_loop = judging.open_loop(None, corrected)
    rmse = open_loop.rmse()
    out: dict[str, Any] = {
        "open_loop_attitude_deg": {"total": rmse.total_deg, "heading": rmse.heading_deg,
                                   "inclination": rmse.inclination_deg},
        "final_attitude_deg": float(np.degrees(open_loop.total[open_loop.judged][-1])),
    }  # fmt: skip
    out.update(_windows(corrected))
    return out, source


def _windows(rec: ReferencedRecording) -> dict[str, Any]:
    """Free-inertial attitude and velocity RMS over consecutive :data:`WINDOW_S` windows, their means."""
    t0, t1 = float(rec.reference.t[0]), float(rec.reference.t[-1])
    att, vel = [], []
    start = t0
    while start + WINDOW_S <= t1:
        drive = judging.drive_errors(None, rec, start, start + WINDOW_S)
        att.append(drive.attitude_angle_rms_deg)  # the rotation angle, as the open loop's (not Euler's)
        vel.append(float(np.sqrt(np.mean(np.square(drive.velocity_rms_mps)))))
        start += WINDOW_S
    if not att:
        return {}
    return {"free_inertial_windows": len(att), "free_inertial_attitude_deg": float(np.mean(att)),
            "free_inertial_velocity_mps": float(np.mean(vel))}  # fmt: skip


def shrink(
    fitted_on: ReferencedRecording,
    judged_on: ReferencedRecording,
    effects: list[str],
    interval_s: float = 1.0,
) -> dict[str, Any]:
    """Recording ``judged_on`` corrected by the model fitted on ``fitted_on`` with and without
    ``effects`` (see the module docstring): the figures of each, what was left out, and the verdict."""
    without, _ = fit_model(fitted_on, [], interval_s)
    with_effects, left_out = fit_model(fitted_on, effects, interval_s)
    before, source = judged(judged_on, without, interval_s)
    after, _ = judged(judged_on, with_effects, interval_s)
    raw, _ = judged(judged_on, _identity(without.seed), interval_s)
    used = [e for e in effects if e not in left_out]
    verdict = said(bool(used), *(d["open_loop_attitude_deg"]["total"] for d in (before, after, raw)))
    return {
        "fitted_on": fitted_on.source, "judged_on": judged_on.source, "effects": used, "left_out": left_out,
        "bias_from": source, "raw": raw, "without_effects": before, "with_effects": after, "verdict": verdict,
    }  # fmt: skip


def said(used: bool, without_deg: float, with_deg: float, raw_deg: float) -> str:
    """The verdict on the open-loop attitude error of a recording corrected by a model fitted on another,
    without and with the accepted effects, beside its raw readings': a shrink over a model worse than the
    readings is said against them (a walk's BROAD pair shrank from 4.38° to 1.57°, the readings 2.59°),
    and a model no better than raw, effects and all, is said so."""
    b, a, r = without_deg, with_deg, raw_deg
    if not used:
        return "no accepted effect predicts another recording: nothing to judge"
    if a < b:
        verdict = f"the accepted effects shrink the open-loop attitude error from {b:.3g}° to {a:.3g}°"
    else:
        verdict = (
            f"the accepted effects do not shrink the open-loop attitude error ({b:.3g}° without, {a:.3g}° "
            "with)"
        )
    if a >= r:
        return (
            verdict + f"; the raw readings give {r:.3g}°: the model, effects and all, is no better than raw"
        )
    if b > r:
        return verdict + f" (the raw readings: {r:.3g}°, so against them from {r:.3g}° to {a:.3g}°)"
    return verdict


def _identity(seed: SeedModelFit) -> UnitModel:
    """No correction at all (the bias is still taken from the rest)."""
    zero = dataclasses.replace(
        seed, B0=np.zeros(3), B=np.zeros((3, 3)), K=np.zeros((3, 3)), A0=np.zeros(3), A=np.zeros((3, 3))
    )
    return UnitModel(zero, {}, {})


def lines(judged: list[dict[str, Any]]) -> list[str]:
    """Each model's shrink on another recording as lines, in degrees (and m/s)."""
    out = ["\nthe shrink on another recording (bias from its opening rest; open loop, the gyro alone):"]
    for j in judged:
        out.append(f"  fitted on {j['fitted_on']}, judged on {j['judged_on']}: {j['verdict']}")
        if "with_effects" in j:
            w, wo, raw = j["with_effects"], j["without_effects"], j["raw"]
            if "free_inertial_velocity_mps" in w:
                att, vel = "free_inertial_attitude_deg", "free_inertial_velocity_mps"
                out.append(
                    f"    free inertial over {w['free_inertial_windows']} windows of 10 s: attitude "
                    f"{raw[att]:.3g}° raw, {wo[att]:.3g}° without, {w[att]:.3g}° with; velocity "
                    f"{raw[vel]:.3g}, {wo[vel]:.3g}, {w[vel]:.3g} m/s"
                    + ("; with the effects worse than raw" if w[att] > raw[att] or w[vel] > raw[vel] else "")
                )
            total = raw["open_loop_attitude_deg"]["total"]
            out.append(f"    raw readings (bias from {j['bias_from']}): {total:.3g}°")
    return out


__all__ = [
    "WINDOW_S",
    "UnitModel",
    "fit_model",
    "judged",
    "lines",
    "said",
    "shrink",
]
