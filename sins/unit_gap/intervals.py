"""The residuals of integrated rotation and velocity change over a reference's intervals, and the columns
every candidate effect adds to them: the gap's statistic where the reference is noisier than the sensor.

A reference trajectory (a motion capture, a better INS) gives attitude and velocity; differentiated into
per-sample rates and forces, its noise grows with the sample rate and soon exceeds the sensor's many
times (BROAD's motion capture: 0.4-1.6 °/s against a MEMS gyro's 0.1 °/s), and what the per-sample
diagnosis then measures is the reference. Integrated, the sensor's noise grows only with the square root
of the time, while the reference's stays that of two epochs. So, as the compensation's interval fit
(:mod:`sins.compensation.interval_fit`) does, each interval between two reference epochs compares the
rotation the seed-corrected gyro composes to with the reference's, and the velocity change the corrected
accelerometer makes (turned by the gyro's attitude, gravity and the Coriolis terms taken away) with the
reference's:

* gyro: ``y_k = log(R_meas^T R_ref)``, a rotation vector in the interval's end axes;
* accelerometer: the velocity change the reference says less the corrected readings', m/s, turned into
  the body's axes at the interval's start (so that each component is, as near as the turn within the
  interval allows, one accelerometer's).

Both are linear, to first order, in a change of what the readings are corrected by: an error ``c u_j``
on axis ``r`` of step ``j`` (``u`` any function of the step's inputs: an effect's regression columns,
:meth:`sins.imu.Effect.columns`) moves the gyro's residual by ``R_b^T Σ_j R_{j+1} (−(I + B)⁻¹ e_r) u_j dt_j
c`` (``R`` the attitude the corrected increments integrate to), and the accelerometer's likewise through
the attitude in the middle of each step. :class:`IntervalResiduals` holds the residuals at the seed
model's fit (the linearisation point) and builds any candidate's columns from the readings' own steps
(:class:`StepInputs`: the sensor is far less noisy than the differentiated reference, so errors in
the variables are the sensor's noise, not the reference's).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.compensation.intervals import (
    Intervals,
    choose_intervals,
    correct_increments,
    dcm,
    shift_derivative,
    summing,
    velocity_residual,
)
from sins.core import rotation
from sins.core.series import ImuIncrements, ReferencedRecording
from sins.imu.calibration import SeedModelFit
from sins.nav import attitude

Array = NDArray[np.float64]


@dataclass(frozen=True)
class StepInputs:
    """The inputs of each step of the readings, as an effect's regression columns read them
    (:class:`sins.imu.vocabulary.RegressorInputs`): the seed-corrected readings' mean rate and force
    over the step, and the rate's change (central differences between the steps' middles)."""

    omega_ib_b: Array
    f_ib_b: Array
    omega_dot_b: Array
    temp_offset: Array | None = None

    def of(self, sensor: str) -> Array:
        """The input ``sensor`` measures."""
        return self.omega_ib_b if sensor == "gyro" else self.f_ib_b


@dataclass(frozen=True, eq=False)
class IntervalResiduals:
    """The intervals' residuals at a seed model's fit, and how any per-step error moves them.

    Attributes
    ----------
    iv : the intervals (:func:`sins.compensation.intervals.choose_intervals`)
    t : (n + 1,) the readings' step boundaries, s
    steps : each step's inputs
    residual : per sensor, (k, 3): the gyro's rotation vector (rad, end axes), the accelerometer's
        velocity change (m/s, start axes)
    maps : per sensor, (n, 3, 3): column ``r`` of step ``j`` is how a unit change of axis ``r``'s
        corrected increment in that step moves the interval's sum, before :attr:`left`
    left : per sensor, (k, 3, 3): the interval's sum into the residual's axes
    rate_change : per sensor, (n, 3): d/dτ of each step's raw increment read ``τ`` later, at 0
    """

    iv: Intervals
    t: Array
    steps: StepInputs
    residual: dict[str, Array]
    maps: dict[str, Array]
    left: dict[str, Array]
    rate_change: dict[str, Array]

    @property
    def dt(self) -> Array:
        """(n,) the steps' lengths, s."""
        return np.diff(self.t)

    @property
    def span(self) -> Array:
        """(k,) each interval's length, s."""
        return np.asarray(self.t[self.iv.stop] - self.t[self.iv.start])

    @property
    def t_mid(self) -> Array:
        """(k,) each interval's middle, s."""
        return np.asarray(0.5 * (self.t[self.iv.stop] + self.t[self.iv.start]))

    @property
    def joined(self) -> NDArray[np.bool_]:
        """(k,) whether interval ``k`` starts where the one before ended (they share an epoch, and
        so its noise)."""
        out = np.zeros(len(self.iv), dtype=bool)
        out[1:] = self.iv.start[1:] == self.iv.stop[:-1]
        return out

    def columns(self, sensor: str, per_step: Array, axis: int) -> Array:
        """(k, 3, p): how errors ``per_step`` (n, p) of axis ``axis`` of ``sensor``, one coefficient a
        column, in the sensor's units (rad/s, m/s²), move each interval's residual."""
        u = np.asarray(per_step, dtype=float).reshape(len(self.dt), -1)
        steps = self.maps[sensor][:, :, axis][:, :, None] * (u * self.dt[:, None])[:, None, :]
        part = np.asarray(self._summing @ steps.reshape(len(u), -1)).reshape(len(self.iv), 3, -1)
        return np.asarray(np.einsum("kab,kbp->kap", self.left[sensor], part))

    @cached_property
    def _summing(self) -> Any:
        """The intervals' indicator over the steps (:func:`sins.compensation.intervals.summing`), made
        once: a diagnosis asks for some 900 sets of columns (a hum's periods on every channel)."""
        return summing(self.iv.start, self.iv.stop, len(self.dt))

    def baseline(self, sensor: str, g_sensitivity: bool = True) -> Array:
        """(k, 3, p) the baseline's columns (the seed model's): each axis's bias and scale and
        misalignment row, and the gyro's g-sensitivity row (with ``g_sensitivity``)."""
        inputs = [np.ones((len(self.dt), 1)), self.steps.of(sensor)]
        if sensor == "gyro" and g_sensitivity:
            inputs.append(self.steps.f_ib_b)
        per_step = np.hstack(inputs)
        return np.concatenate([self.columns(sensor, per_step, r) for r in range(3)], axis=2)

    def delay_steps(self, sensor: str, axis: int) -> Array:
        """(n, 1) what reading axis ``axis`` of ``sensor`` a second later changes each step's reading
        by, per second of delay, in the sensor's units: minus its rate of change (the time offset's
        column, moved into the residuals by :meth:`columns`: the readings lag the reference by its
        coefficient)."""
        return np.asarray(-(self.rate_change[sensor][:, axis] / self.dt)[:, None], dtype=float)


def step_inputs(corrected: ImuIncrements) -> StepInputs:
    """Each step's inputs from corrected increments: mean rate and force, and the rate's change
    (central differences between the steps' middles)."""
    dt = np.diff(corrected.t)
    rate = corrected.dtheta_b / dt[:, None]
    mid = 0.5 * (corrected.t[:-1] + corrected.t[1:])
    omega_dot = np.gradient(rate, mid, axis=0) if len(mid) > 2 else np.zeros_like(rate)
    return StepInputs(omega_ib_b=rate, f_ib_b=corrected.dv_b / dt[:, None], omega_dot_b=omega_dot)


def interval_residuals(rec: ReferencedRecording, seed: SeedModelFit, interval_s: float) -> IntervalResiduals:
    """The intervals of about ``interval_s`` of ``rec`` (:func:`sins.compensation.intervals.choose_intervals`)
    and their residuals with the readings corrected by ``seed`` (no time offsets, no lever arm: both
    are candidates).

    Raises
    ------
    ValueError
        as :func:`~sins.compensation.intervals.choose_intervals`.
    """
    iv = choose_intervals(rec, interval_s)
    imu = rec.imu
    dt = np.diff(imu.t)
    corrected = correct_increments(imu, seed)
    q = attitude.propagate_increments(corrected.dtheta_b, np.array([0.0, 0.0, 0.0, 1.0]))
    rot = dcm(q)
    b_inv = np.asarray(np.linalg.inv(np.eye(3) + seed.B), dtype=float)
    a_inv = np.asarray(np.linalg.inv(np.eye(3) + seed.A), dtype=float)
    r_a, r_b = rot[iv.start], rot[iv.stop]
    r_meas = np.einsum("kji,kjl->kil", r_a, r_b)
    gyro = rotation.rotvec_from_quat(
        rotation.quat_from_dcm(np.einsum("kji,kjl->kil", r_meas, iv.body_turn()))
    )
    middle = 0.5 * (rot[:-1] + rot[1:])
    accel = velocity_residual(iv, rot, corrected.dv_b, dt)
    steps = step_inputs(corrected)
    return IntervalResiduals(
        iv=iv,
        t=imu.t,
        steps=steps,
        residual={"gyro": np.asarray(gyro), "accel": np.asarray(accel)},
        maps={
            "gyro": -np.einsum("jab,bc->jac", rot[1:], b_inv),
            "accel": -np.einsum("jab,bc->jac", middle, a_inv),
        },
        left={"gyro": np.transpose(r_b, (0, 2, 1)), "accel": np.transpose(r_a, (0, 2, 1))},
        rate_change={
            "gyro": shift_derivative(imu.t, imu.dtheta_b, 0.0),
            "accel": shift_derivative(imu.t, imu.dv_b, 0.0),
        },
    )


__all__ = [
    "IntervalResiduals",
    "StepInputs",
    "interval_residuals",
    "step_inputs",
]
