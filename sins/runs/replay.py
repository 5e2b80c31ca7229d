"""A recorded IMU replayed through the integrator against its truth (``sins integrate``); or, without a
truth, from a given start or a still unit's own coarse alignment.

:func:`navigate` integrates increments from the truth's state at their first time and compares the
solution with the truth; :func:`integrate_recording` does so for a recording (:func:`sins.io.read`);
(The gap diagnosis's drift check is :func:`sins.gap.navigation.gap_navigation`.) Without a truth,
:func:`free_start` starts a unit at rest at a given position, in a given attitude or in the one its
opening rest implies (levelling and gyrocompassing, :mod:`sins.aiding.alignment`, its accuracy from the
noise the rest shows and the bias levels given, :func:`sins.characterise.bias.alignment_accuracy`), and
:func:`navigate_free` integrates from there; :func:`still_drift` is the error the biases measured at the
rest would cause (:func:`sins.nav.budget.bias_error_ned`), what a still recording's solution should show.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from sins.core import earth, rotation
from sins.core.series import ImuIncrements, NavSeries
from sins.errors import MissingInputError, SinsInputError
from sins.nav import strapdown
from sins.nav.metrics import nav_errors, summarize
from sins.nav.vertical import VerticalMode
from sins.runs.readings import run_inputs
from sins.runs.results import StrategyRun

if TYPE_CHECKING:
    from sins.characterise.bias import BiasEstimate
    from sins.io.recording import Recording


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
    rec: Recording,
    vertical: VerticalMode = "free",
    vertical_tau_s: float = 10.0,
    within_truth: bool = False,
) -> StrategyRun:
    """Integrate a recording (:func:`sins.io.read`, with its own reference or a truth file beside it) from
    its truth's first state; errors against the truth.

    :func:`sins.runs.readings.run_inputs` (an IMU running past the truth refused unless ``within_truth``),
    then :func:`navigate`.
    """
    inputs = run_inputs(rec, within_truth)
    return navigate(inputs.imu, inputs.truth, vertical, vertical_tau_s)


@dataclass(frozen=True)
class FreeStart:
    """Where a navigation without a reference starts.

    Attributes
    ----------
    initial : the state at ``imu.t[index]`` (at rest: zero velocity)
    index : the IMU time it starts at (0 from a given attitude; after the aligning rest)
    how : ``"given"`` (position and attitude given) or ``"aligned"`` (attitude from the opening rest)
    rest : the aligning rest's biases in the attitude started from (None when given)
    tilt_sigma, heading_sigma : the alignment's stated 1σ, rad: the noise's part and the bias levels'
        (:func:`sins.characterise.bias.alignment_accuracy`); heading None where it was given
    levels : the gyro and accelerometer bias levels (1σ, rad/s and m/s²) that accuracy assumes (0: the
        noise's part alone)
    initial_t : ``imu.t[index]``, s
    """

    initial: strapdown.InitialState
    index: int
    how: str
    rest: BiasEstimate | None = None
    tilt_sigma: float | None = None
    heading_sigma: float | None = None
    levels: tuple[float, float] = (0.0, 0.0)
    initial_t: float = 0.0


def free_start(
    imu: ImuIncrements,
    origin: tuple[float, float, float],
    *,
    attitude: tuple[float, float, float] | None = None,
    align_s: float | None = None,
    heading: float | None = None,
    levels: tuple[float, float] = (0.0, 0.0),
    source: str = "",
) -> FreeStart:
    """A unit at rest at ``origin`` (lat, lon rad, h m): in ``attitude`` (roll, pitch, yaw rad) from its
    first time, or aligned on its first ``align_s`` seconds (roll and pitch from the accelerometers, the
    heading gyrocompassed, or ``heading`` rad where given) from their end.

    Raises
    ------
    SinsInputError
        neither or both of ``attitude`` and ``align_s``; a recording shorter than the alignment, or
        moving in it; a heading the gyros do not resolve and that is not given.
    """
    from sins.characterise import bias  # the noise fits: only a start without a reference needs them
    from sins.characterise.still import motion

    lat, lon, h = origin
    if (attitude is None) == (align_s is None):
        raise SinsInputError(f"{source}: start from a given attitude or from an alignment (one of them)")
    if attitude is not None:
        q = rotation.quat_from_euler(*attitude)
        initial = strapdown.InitialState(lat=lat, lon=lon, h=h, v_n=np.zeros(3), q_nb=q)
        return FreeStart(initial, 0, "given", initial_t=float(imu.t[0]))
    assert align_s is not None
    k = int(np.searchsorted(imu.t, imu.t[0] + align_s - 1e-9))
    if k >= len(imu.t) - 1:
        raise SinsInputError(
            f"{source}: an alignment of {align_s:g} s: the recording spans {imu.t[-1] - imu.t[0]:.6g} s, "
            "leaving nothing to navigate after the alignment"
        )
    dt = np.diff(imu.t[: k + 1])[:, None]
    t, readings = 0.5 * (imu.t[:k] + imu.t[1 : k + 1]), np.hstack([imu.dtheta_b[:k], imu.dv_b[:k]]) / dt
    moved = motion(t, readings)
    if moved is not None:
        raise SinsInputError(f"{source}: an alignment of {align_s:g} s: the unit moves in it: {moved}")
    rest = bias.estimate_bias(t, readings, lat, h, source=source, location="the start given")
    a = rest.attitude
    if heading is not None:
        rest = bias.in_attitude(rest, (a.roll, a.pitch, heading), "levelled, heading given")
    elif a.yaw is None:
        raise MissingInputError(
            f"{source}: the alignment does not resolve the heading: {a.heading_note}", needs="heading"
        )
    tilt, yaw_sigma = bias.alignment_accuracy(rest, *levels)
    att = rest.attitude
    q = rotation.quat_from_euler(att.roll, att.pitch, att.yaw or 0.0)
    initial = strapdown.InitialState(lat=lat, lon=lon, h=h, v_n=np.zeros(3), q_nb=q)
    heading_sigma = None if heading is not None else yaw_sigma
    return FreeStart(initial, k, "aligned", rest, tilt, heading_sigma, levels, float(imu.t[k]))


def navigate_free(
    imu: ImuIncrements, start: FreeStart, vertical: VerticalMode = "free", vertical_tau_s: float = 10.0
) -> NavSeries:
    """Integrate ``imu`` from ``start`` (from its ``index``); held or damped, the vertical channel goes
    to the start's height."""
    k = start.index
    part = imu if k == 0 else imu.steps(k)
    h_ref = None if vertical == "free" else np.full(len(part.t), start.initial.h)
    return strapdown.integrate(
        part, start.initial, vertical=vertical, h_ref=h_ref, vertical_tau_s=vertical_tau_s
    )


#: The longest step, s, :func:`still_drift` integrates a still unit's readings over (the Schuler loop's
#: 84 minutes and the vertical channel's 9.5 minutes are slow beside it).
STILL_STEP_S = 1.0


def still_drift(
    rest: BiasEstimate, t: NDArray[np.float64], vertical: VerticalMode = "free", vertical_tau_s: float = 10.0
) -> NDArray[np.float64]:
    """The north, east, down offset (k, 3), m, after ``t`` (k,) s (increasing, from the navigation's start)
    of a unit that stays as still as during ``rest``: its mean rest readings (Earth's rate and gravity in
    the attitude taken there, and its biases) integrated from that attitude, the vertical channel as
    navigated (held or damped to the start's height). What the biases measured predict, with what couples
    them: the growth of each bias alone (:func:`sins.nav.budget.bias_error_ned`) leaves out the Coriolis
    and centripetal forces of the level velocity error on the vertical channel, which made a tactical
    unit's height after 28 minutes twice that growth. Aligned on the rest, the level accelerometer biases
    and the east gyro bias are zero by construction: the tilt and heading took them."""
    t = np.asarray(t, dtype=float)
    grid = np.union1d(np.r_[0.0, t], np.arange(0.0, float(t[-1]), STILL_STEP_S))
    dt = np.diff(grid)[:, None]
    still = ImuIncrements(
        t=grid, dtheta_b=rest.vector("gyro", "mean") * dt, dv_b=rest.vector("accel", "mean") * dt
    )
    a = rest.attitude
    h = rest.h if math.isfinite(rest.h) else 0.0
    q = rotation.quat_from_euler(a.roll, a.pitch, a.yaw or 0.0)
    initial = strapdown.InitialState(lat=rest.lat, lon=0.0, h=h, v_n=np.zeros(3), q_nb=q)
    sol = navigate_free(still, FreeStart(initial, 0, "aligned", rest), vertical, vertical_tau_s)
    at = np.searchsorted(grid, t)
    return earth.ned_offset(sol.lat[at], sol.lon[at], sol.h[at], rest.lat, 0.0, h)


__all__ = [
    "STILL_STEP_S",
    "FreeStart",
    "free_start",
    "integrate_recording",
    "navigate",
    "navigate_free",
    "still_drift",
]
