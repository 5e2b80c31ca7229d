"""A strategy judged on a real recording against its reference trajectory.

:func:`open_loop_attitude` judges it the way an orientation benchmark does: the corrected gyro integrated
alone from the reference's first attitude, scored against the reference on the judged rows.
:func:`drive_errors` judges it the way a navigator does: the corrected unit navigating free inertial from
the reference's state, attitude and velocity errors over a window. :func:`between` and
:func:`from_recording` make the recordings judged; fitting is :mod:`sins.compensation.referenced`'s.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.compensation import Strategy
from sins.core import rotation
from sins.core.series import ImuIncrements, ImuRates, NavSeries, ReferencedRecording
from sins.errors import SinsInputError
from sins.io.recording import beside_trajectory
from sins.nav import attitude, strapdown
from sins.nav.attitude import AttitudeRmse
from sins.nav.metrics import NavErrors, nav_errors

Array = NDArray[np.float64]


def corrected(
    strategy: Strategy | None, rec: ReferencedRecording, *, bias_from_rest: bool = False
) -> ImuIncrements:
    """``rec``'s increments corrected by ``strategy`` (None: as they are); with ``bias_from_rest`` the
    gyro bias is then set again from the opening rest (:func:`opening_rest`): what a user does with a
    calibration from another day.

    Raises
    ------
    SinsInputError
        with ``bias_from_rest``, when the recording does not open with a rest.
    """
    imu = rec.imu if strategy is None else strategy.correct_recording(rec.imu)
    assert isinstance(imu, ImuIncrements)
    if not bias_from_rest:
        return imu
    rest = opening_rest(rec)
    dt = np.diff(imu.t)
    bias = imu.dtheta_b[rest].sum(axis=0) / dt[rest].sum()
    return ImuIncrements(t=imu.t, dtheta_b=imu.dtheta_b - bias * dt[:, None], dv_b=imu.dv_b)


#: The shortest opening rest that :func:`opening_rest` accepts, s.
MIN_OPENING_REST_S = 2.0


def opening_rest(rec: ReferencedRecording) -> slice:
    """The steps of the recording's opening rest: up to the first judged row where the recording marks
    its judged rows (BROAD's movement phases), else while the reference stays within 0.5° of its first
    attitude and 2 cm/s of rest.

    Raises
    ------
    SinsInputError
        when that rest is shorter than :data:`MIN_OPENING_REST_S`.
    """
    t = rec.imu.t
    if rec.judged is not None and rec.judged.any():
        end_t = t[int(np.argmax(rec.judged))]
    else:
        ref = rec.reference
        turn = attitude.attitude_errors(ref.q_nb, np.broadcast_to(ref.q_nb[0], ref.q_nb.shape))[0]
        moving = (turn > np.radians(0.5)) | (np.linalg.norm(ref.v_n, axis=1) > 0.02)
        end_t = ref.t[int(np.argmax(moving))] if moving.any() else ref.t[-1]
    start = int(np.searchsorted(t, rec.reference.t[0]))
    stop = int(np.searchsorted(t, end_t)) - 1
    if stop <= start or t[stop] - t[start] < MIN_OPENING_REST_S:
        raise SinsInputError(
            f"{rec.source or 'recording'}: no opening rest of {MIN_OPENING_REST_S:g} s to take the gyro "
            "bias from"
        )
    return slice(start, stop)


@dataclass(frozen=True)
class OpenLoop:
    """The open-loop attitude's errors at the reference's epochs within the readings: ``t`` (m,) s,
    ``total``, ``heading``, ``inclination`` (m,) rad, ``judged`` (m,) the rows the figures count."""

    t: Array
    total: Array
    heading: Array
    inclination: Array
    judged: NDArray[np.bool_]

    def aoe_deg(self) -> float:
        """The absolute orientation error (Brossard et al. 2020): the RMS of the total attitude error over
        every epoch, judged or not, degrees."""
        return float(np.degrees(np.sqrt(np.mean(self.total**2))))

    def rmse(self) -> AttitudeRmse:
        """BROAD's three RMS figures over the judged rows, degrees."""
        rms = lambda e: float(np.degrees(np.sqrt(np.mean(e[self.judged] ** 2))))  # noqa: E731
        return AttitudeRmse(rms(self.total), rms(self.heading), rms(self.inclination), int(self.judged.sum()))


def open_loop(
    strategy: Strategy | None, rec: ReferencedRecording, *, bias_from_rest: bool = False
) -> OpenLoop:
    """The corrected gyro integrated alone from the reference's first attitude, and its errors against
    the reference. The gyro's increments are turns in inertial space; the navigation frame's own turn
    (Earth's rate: its vertical part only where the reference's heading is not north) is taken out
    (:func:`frame_turn`).

    Raises
    ------
    SinsInputError
        when no judged row has a reference within the readings.
    """
    imu = corrected(strategy, rec, bias_from_rest=bias_from_rest)
    ref = rec.reference
    on_grid = 1e-9 * max(1.0, float(np.abs(ref.t).max()))  # a reference epoch at a reading's time, s
    first = int(np.searchsorted(imu.t, ref.t[0] - on_grid))
    # From the reference's attitude at the first reading within its span (its first epoch's where that is
    # on the readings' grid, slerped between its epochs where not: a FOG-INS at 10 Hz off a MEMS's grid).
    start = (
        ref.q_nb[0]
        if abs(imu.t[first] - ref.t[0]) <= on_grid
        else ref.interpolate(imu.t[first : first + 1]).q_nb[0]
    )
    q = attitude.propagate_increments(imu.dtheta_b[first:], start, frame_turn(rec)[first:])
    # Judged at every reference epoch from there on: the readings' attitude where the epoch is on their
    # grid, slerped between the two readings around it where not (before, such epochs were left out, and
    # a reference wholly off the grid could not be judged).
    inside = (ref.t >= imu.t[first] - on_grid) & (ref.t <= imu.t[-1] + on_grid)
    t_ref, t_q = np.clip(ref.t[inside], imu.t[first], imu.t[-1]), imu.t[first:]
    i = np.clip(np.searchsorted(t_q, t_ref, side="right") - 1, 0, len(t_q) - 2)
    at_ref = rotation.slerp(q[i], q[i + 1], (t_ref - t_q[i]) / (t_q[i + 1] - t_q[i]))
    total, heading, inclination = attitude.attitude_errors(at_ref, ref.q_nb[inside])
    row = np.clip(np.searchsorted(imu.t, t_ref + on_grid, side="right") - 1, 0, len(imu.t) - 1)
    judged = np.ones(len(t_ref), dtype=bool) if rec.judged is None else rec.judged[row]
    if not judged.any():
        raise SinsInputError(
            f"{rec.source or 'recording'}: no judged row has a reference within the readings"
        )
    return OpenLoop(ref.t[inside], total, heading, inclination, np.asarray(judged, dtype=bool))


def open_loop_attitude(
    strategy: Strategy | None, rec: ReferencedRecording, *, bias_from_rest: bool = False
) -> AttitudeRmse:
    """:func:`open_loop`'s figures: BROAD's total, heading and inclination RMSE over the judged rows."""
    return open_loop(strategy, rec, bias_from_rest=bias_from_rest).rmse()


def frame_turn(rec: ReferencedRecording) -> Array:
    """The navigation frame's turn in inertial space over each step, rad (n, 3) in its axes: Earth's rate
    at the reference's mean latitude (its vertical part only where ``heading_known`` is False, none where
    ``latitude_known`` is False; the transport rate of a room or a slow vehicle is left out)."""
    from sins.core import earth

    lat = float(np.mean(rec.reference.lat))
    w_ie = np.array(np.broadcast_arrays(*earth.earth_rate_n(lat)), dtype=float).reshape(3)
    if not rec.heading_known:
        w_ie[:2] = 0.0
    if not rec.latitude_known:
        w_ie[:] = 0.0
    return np.asarray(np.outer(np.diff(rec.imu.t), w_ie))


@dataclass(frozen=True)
class DriveErrors:
    """Free-inertial errors over a window: RMS and final attitude (roll, pitch, yaw, deg) and velocity
    (north, east, down, m/s) errors, the horizontal position error at the end, m, and the RMS of the
    attitude error's rotation angle, deg (the open loop's measure; Euler differences swell near ±90° of
    pitch, where EuRoC's body axes lie)."""

    start_s: float
    end_s: float
    attitude_rms_deg: tuple[float, float, float]
    attitude_final_deg: tuple[float, float, float]
    velocity_rms_mps: tuple[float, float, float]
    velocity_final_mps: tuple[float, float, float]
    horizontal_final_m: float
    attitude_angle_rms_deg: float

    def to_dict(self) -> dict[str, Any]:
        """The figures as a JSON object."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in self.__dict__.items()}


def free_inertial(
    imu: ImuIncrements, rec: ReferencedRecording, start_s: float, end_s: float
) -> tuple[NavSeries, NavSeries, NavErrors]:
    """Readings ``imu`` (``rec``'s, as corrected) navigating free inertial over ``[start_s, end_s]`` from
    the reference's state there (attitude, velocity, position at the reference's point): the solution,
    the reference on its times, and its errors; ``end_s`` is clipped to the reference's last epoch. The
    vertical channel is held to the reference's height (a free vertical channel diverges and says
    nothing of the compensation)."""
    a = int(np.searchsorted(imu.t, start_s))
    b = int(np.searchsorted(imu.t, min(end_s, rec.reference.t[-1]), side="right")) - 1
    if b - a < 10 or imu.t[a] < rec.reference.t[0] or imu.t[b] > rec.reference.t[-1]:
        raise SinsInputError(
            f"{rec.source or 'recording'}: {start_s:g}..{end_s:g} s is not within the reference "
            f"({rec.reference.t[0]:g}..{rec.reference.t[-1]:g} s)"
        )
    seg = imu.steps(a, b)
    truth = rec.reference.interpolate(seg.t)
    solution = strapdown.integrate(
        seg, strapdown.InitialState.from_series(truth, 0), vertical="hold", h_ref=truth.h
    )
    return solution, truth, nav_errors(solution, truth)


def drive_errors(
    strategy: Strategy | None, rec: ReferencedRecording, start_s: float, end_s: float
) -> DriveErrors:
    """The corrected unit navigating free inertial over ``[start_s, end_s]``
    (:func:`free_inertial`), its errors against the reference at its epochs in the window."""
    solution, truth, err = free_inertial(corrected(strategy, rec), rec, start_s, end_s)
    t = solution.t  # the window's steps' times
    inside = (rec.reference.t >= t[0]) & (rec.reference.t <= t[-1])
    rows = np.searchsorted(t, rec.reference.t[inside])
    rows = rows[rows < len(t)]
    att, vel = np.degrees(err.att_rpy_rad[rows]), err.vel_ned_mps[rows]
    angle, _, _ = attitude.attitude_errors(solution.q_nb[rows], truth.q_nb[rows])
    three = lambda x: (float(x[0]), float(x[1]), float(x[2]))  # noqa: E731
    return DriveErrors(
        start_s=float(t[0]), end_s=float(t[-1]),
        attitude_rms_deg=three(np.sqrt(np.mean(att * att, axis=0))), attitude_final_deg=three(att[-1]),
        velocity_rms_mps=three(np.sqrt(np.mean(vel * vel, axis=0))), velocity_final_mps=three(vel[-1]),
        horizontal_final_m=float(err.horizontal_m[-1]),
        attitude_angle_rms_deg=float(np.degrees(np.sqrt(np.mean(angle * angle)))),
    )  # fmt: skip


def between(rec: ReferencedRecording, start_s: float, end_s: float) -> ReferencedRecording:
    """The part of ``rec`` within ``[start_s, end_s]`` (steps and reference epochs)."""
    t = rec.imu.t
    a = int(np.searchsorted(t, start_s))
    b = int(np.searchsorted(t, end_s, side="right")) - 1
    inside = np.flatnonzero((rec.reference.t >= t[a]) & (rec.reference.t <= t[b]))
    return ReferencedRecording(
        imu=rec.imu.steps(a, b),
        reference=rec.reference.at(inside),
        judged=None if rec.judged is None else rec.judged[a : b + 1],
        sensor=rec.sensor,
        reference_name=rec.reference_name,
        source=rec.source,
        heading_known=rec.heading_known,
        latitude_known=rec.latitude_known,
    )


def from_recording(imu: ImuRates | ImuIncrements, truth: NavSeries, source: str) -> ReferencedRecording:
    """A user's readings beside their reference trajectory (a truth CSV, a bag's poses, a EuRoC
    ground truth): rate-form readings integrated between samples by the trapezoid rule.

    Raises
    ------
    SinsInputError
        when the reference does not overlap the readings in time.
    """
    return beside_trajectory(imu, truth, source)


__all__ = [
    "MIN_OPENING_REST_S",
    "DriveErrors",
    "OpenLoop",
    "between",
    "corrected",
    "drive_errors",
    "frame_turn",
    "free_inertial",
    "from_recording",
    "open_loop",
    "open_loop_attitude",
    "opening_rest",
]
