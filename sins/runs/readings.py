"""Readings as files hold them: a scenario's truth and its unit's readings, a recorded IMU file beside
its truth, and a recording's reference inputs for the sim-to-real diagnosis.

The library calls behind ``sins simulate``, ``sins integrate``'s reading of its files and ``sins gap`` /
``sins characterise --truth``; :mod:`sins.runs.pipeline` runs what they read (and re-exports these names).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sins import io, scenario
from sins.core.series import CalibrationData, ImuIncrements, ImuRates, NavSeries
from sins.errors import MissingInputError, SinsInputError
from sins.nav import trajectory
from sins.scenario import Scenario, resolve_preset
from sins.scenario.toml import MAX_SEED


@contextmanager
def input_errors(where: object) -> Iterator[None]:
    """Raise a ``ValueError`` from within (one not already a :class:`~sins.errors.SinsInputError`) as a
    ``SinsInputError`` naming ``where``: the numerical layers refuse bad values with ``ValueError``,
    without knowing the scenario or file they came from."""
    try:
        yield
    except ValueError as exc:
        if isinstance(exc, SinsInputError):
            raise
        raise SinsInputError(f"{where}: {exc}") from None


def simulate(sc: Scenario) -> tuple[NavSeries, ImuIncrements]:
    """Truth and exact ideal IMU of a scenario.

    Raises
    ------
    SinsInputError
        a trajectory that cannot be generated, naming the scenario.
    """
    with input_errors(sc.source or sc.name):
        return trajectory.generate(scenario.build_motion(sc), sc.rate_hz)


def with_unit(sc: Scenario, imu: str | os.PathLike[str] | None = None, seed: int | None = None) -> Scenario:
    """The scenario with another IMU (``imu``: a grade or IMU preset such as ``tactical``, or an IMU
    file) and/or another navigation power-on (``seed``, the ``[imu] seed``); ``None`` keeps the
    scenario's.

    Raises
    ------
    SinsInputError
        ``imu`` is neither a preset nor a file; or a ``seed`` is given for a scenario without an IMU
        model (the ideal IMU has nothing to draw).
    """
    model = sc.imu_model if imu is None else resolve_preset(imu, "imu")
    if seed is not None and model is None:
        raise SinsInputError(
            f"{sc.source or sc.name}: --seed needs an IMU model: the scenario runs the ideal IMU, "
            "which draws nothing"
        )
    if seed is not None and not 0 <= seed <= MAX_SEED:
        raise SinsInputError(f"--seed: must be in [0, {MAX_SEED}], got {seed}")
    return dataclasses.replace(sc, imu_model=model, imu_seed=sc.imu_seed if seed is None else seed)


@dataclass(frozen=True)
class SimulatedReadings:
    """A scenario's truth and the readings of its unit (:func:`simulate_readings`).

    ``readings`` are in increment form (``truth.t`` is their interval edges) or rate form (at the
    truth's times); ``temp`` the cabin temperature at the rows' times, °C (None for the ideal IMU);
    ``model`` the IMU file the unit came from (None: ideal) and ``seed`` its power-on.
    """

    truth: NavSeries
    readings: ImuIncrements | ImuRates
    temp: NDArray[np.float64] | None
    model: Path | None
    seed: int


def simulate_readings(sc: Scenario, form: str = "increment", ideal: bool = False) -> SimulatedReadings:
    """The truth and what the scenario's unit (``[imu] model``, power-on ``[imu] seed``) reads along it.

    Increment form: the readings ``sins run`` integrates as its ``none`` strategy, to the last bit
    (the whole-array corruption equals the streamed one). Rate form: the same unit and power-on
    sampled instantaneously at the truth's times (:meth:`sins.imu.ImuModel.corrupt_rates`); its noise
    draws are its own. ``ideal`` (or a scenario without a model): the exact ideal IMU.
    """
    if form not in ("increment", "rate"):
        raise ValueError(f"form must be 'increment' or 'rate', got {form!r}")
    truth, increments = simulate(sc)
    readings: ImuIncrements | ImuRates = increments
    if form == "rate":
        readings = trajectory.ideal_rates(scenario.build_motion(sc), truth)
    if ideal or sc.imu_model is None:
        return SimulatedReadings(truth, readings, None, None, sc.imu_seed)
    model = scenario.load_imu(sc.imu_model).model(run_seed=sc.imu_seed)
    temp = cabin_temperature(sc, truth.t)
    with input_errors(sc.imu_model):
        if isinstance(readings, ImuRates):
            readings = model.corrupt_rates(readings, temp, seed=sc.imu_seed)
        else:
            readings = model.corrupt_increments(readings, temp, seed=sc.imu_seed, dt_nominal=1.0 / sc.rate_hz)
    row_temp = temp if form == "rate" else temp[1:]  # increment rows are stamped at their interval's end
    return SimulatedReadings(truth, readings, row_temp, sc.imu_model, sc.imu_seed)


def cabin_temperature(sc: Scenario, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """The cabin temperature at ``t``, °C (default a constant 20)."""
    return np.asarray(np.interp(t, *sc.temperature), dtype=float)


@dataclass(frozen=True)
class RunInputs:
    """A recording's readings as increments beside the truth they are integrated against
    (:func:`run_inputs`).

    ``intervals`` is how many the recording holds; ``imu`` may hold fewer (``within_truth``: those
    inside the truth's span); ``before_truth`` how many of them were left out at the start because they
    begin before the recording's own reference does.
    """

    imu: ImuIncrements
    truth: NavSeries
    intervals: int
    before_truth: int = 0


#: Readings past the recording's own reference's last pose that are cut without ``within_truth``: at
#: most this long, s, or this fraction of the recording (the last pose commonly comes a few readings
#: before the last reading); longer is refused.
OWN_TAIL_S, OWN_TAIL_FRACTION = 1.0, 0.01


def run_inputs(rec: io.Recording, within_truth: bool = False) -> RunInputs:
    """A recording (:func:`sins.io.read`, either form) as increments, beside its truth (a truth file given
    to the reader, or the recording's own reference: a bag's poses, a EuRoC ground truth, a dataset's).

    Increment form: the first row's interval starts where the reader was told (a truth file's first
    time). Rate form: the samples are integrated to increments between rows, and the run starts at the
    first row's time, which must lie within the truth. Against the recording's own reference (a motion
    capture that starts seconds after the IMU), the readings before its first time are left out
    (``before_truth`` says how many intervals); against a truth file that is refused, as a mistake,
    unless ``within_truth``.

    Raises
    ------
    SinsInputError
        a rate-form recording starting outside the truth; readings running past the truth's end,
        unless ``within_truth`` (then the intervals inside it are kept, and ``intervals`` says how
        many the recording held): nothing is cut without being asked for, except against the
        recording's own reference, whose last pose commonly comes a few samples before the last
        reading: a tail of up to :data:`OWN_TAIL_S` or :data:`OWN_TAIL_FRACTION` of the span is cut
        (the caller says so: ``intervals`` against ``len(imu)``), a longer one refused as a truth
        file's is.
    MissingInputError
        a recording without a reference trajectory.
    """
    if not rec.has_trajectory:
        raise io.recording.missing_reference(rec)
    where = rec.name
    # Every reader gives a reference as the recording's truth (a dataset's beside its readings: its
    # referenced form's increments, or a FOLDER/NAME's file as read), whatever it keeps for the fits.
    assert rec.truth is not None
    samples: ImuIncrements | ImuRates = rec.imu
    truth = rec.truth
    truth_name = rec.truth_from or "its own reference"
    own = not rec.truth_from
    imu: ImuIncrements
    before = 0
    # Before a truth file begins: a mistake unless only what lies within it was asked for (it had cut the
    # tail alone, and refused a recording that starts before the truth it was given with).
    if (own or within_truth) and samples.t[0] < truth.t[0]:
        before = int(np.searchsorted(samples.t, truth.t[0]))  # the first edge at or after the reference
        if before >= len(samples.t) - 1:
            raise SinsInputError(f"{where}: no reading lies within its own reference's time span")
        samples = _from(samples, before)
    if isinstance(samples, ImuRates):
        if samples.t[0] < truth.t[0] or samples.t[0] > truth.t[-1]:
            raise SinsInputError(
                f"{where}: first sample at {samples.t[0]:g} s is outside the truth's "
                f"{truth.t[0]:g}..{truth.t[-1]:g} s"
            )
        if len(samples) < 2:
            raise SinsInputError(f"{where}: need at least two rate samples")
        imu = samples.to_increments()
    else:
        imu = samples
        if not imu.t[0] >= truth.t[0]:
            raise SinsInputError(
                f"{where}: the first interval starts at {imu.t[0]:g} s, before the truth's first "
                f"time {truth.t[0]:g} s"
            )
    intervals = len(imu)
    if imu.t[-1] > truth.t[-1] + 1e-9:
        inside = int(np.searchsorted(imu.t, truth.t[-1] + 1e-9, side="right"))
        tail = imu.t[-1] - truth.t[-1]
        short = own and tail <= max(OWN_TAIL_S, OWN_TAIL_FRACTION * (imu.t[-1] - imu.t[0]))
        if not within_truth and not short:
            raise SinsInputError(
                f"{where}: the IMU runs to {imu.t[-1]:g} s but the truth ({truth_name}) ends at "
                f"{truth.t[-1]:g} s ({inside - 1} of {intervals} intervals inside it); give the whole "
                "truth, or --within-truth to integrate only those intervals"
            )
        if inside < 2:
            raise SinsInputError(f"{where}: no IMU interval ends within the truth's time span")
        imu = ImuIncrements(
            t=imu.t[:inside], dtheta_b=imu.dtheta_b[: inside - 1], dv_b=imu.dv_b[: inside - 1]
        )
    return RunInputs(imu, truth, intervals + before, before)


def _from(samples: ImuIncrements | ImuRates, k: int) -> ImuIncrements | ImuRates:
    """The readings from row ``k`` (increments: from the interval starting at edge ``k``)."""
    if isinstance(samples, ImuRates):
        return ImuRates(t=samples.t[k:], omega_ib_b=samples.omega_ib_b[k:], f_ib_b=samples.f_ib_b[k:])
    return samples.steps(k)


def gap_data(rec: io.Recording) -> tuple[CalibrationData, NavSeries | None]:
    """Readings beside reference inputs for :func:`sins.gap.diagnose`, and the truth at their times.

    A rig recording (``ref_`` columns): its own (the truth returned is None). A recording read beside a
    truth trajectory (:func:`sins.io.read` with ``truth``), in either form: its reference inputs come
    from the truth through the exact ideal-IMU path (splines through the truth, then the strapdown
    equations backwards). Rate form: the readings at their times beside the ideal rates there.
    Increment form (the first row's interval starts at the truth's first time): each interval's mean
    rate (increment / its length) at its mid-time beside the ideal rate's mean over the same interval
    (Simpson's rule on the splines), so that every error linear in the input (bias, scale,
    misalignment, g-sensitivity) compares exactly; one quadratic in it (``k2·u²``) differs from its
    value at the mean input by ``k2`` times the input's variance over the interval (``(dt·u̇)²/12`` for a
    steady change), and white noise keeps its density.

    Raises
    ------
    MissingInputError
        neither ``ref_`` columns nor a truth.
    SinsInputError
        a truth of fewer than 4 rows; rows outside the truth's span.
    """
    if rec.rig is not None:
        return rec.rig, None
    if rec.truth is None:
        raise MissingInputError(
            f"{rec.source}: no ref_ columns (a rig recording has them); an IMU recording needs its "
            "trajectory (a truth file)",
            needs="truth",
        )
    path, truth_name = rec.truth, rec.truth_from or f"{rec.source}'s own reference"
    if len(path.t) < 4:
        raise SinsInputError(f"{truth_name}: a truth trajectory needs at least 4 rows")
    samples = rec.imu
    row_t = samples.t if isinstance(samples, ImuRates) else samples.t[1:]
    inside = (row_t >= path.t[0]) & (row_t <= path.t[-1])
    if inside.sum() < len(row_t):
        raise SinsInputError(
            f"{rec.source}: rows from t={row_t[~inside][0]:g} s lie outside the truth's "
            f"{path.t[0]:g}..{path.t[-1]:g} s in {truth_name}"
        )
    temp = rec.temp
    if isinstance(samples, ImuRates):
        at_samples = path.interpolate(samples.t)
        reference = _ideal_rates_at(path, at_samples)
        readings = samples
    else:
        readings, reference, at_samples = _interval_means(samples, path)
        if temp is not None:
            temp = np.interp(readings.t, samples.t[1:], temp)
    data = CalibrationData(
        t=readings.t, gyro=readings.omega_ib_b, accel=readings.f_ib_b, ref_gyro=reference.omega_ib_b,
        ref_accel=reference.f_ib_b, temp=temp, source=rec.source,
    )  # fmt: skip
    return data, at_samples


def _ideal_rates_at(path: NavSeries, at: NavSeries) -> ImuRates:
    """The exact ideal IMU at ``at``'s times of the motion through the recorded truth ``path``."""
    from sins.nav import motion

    return trajectory.ideal_rates(motion.RecordedMotion.from_series(path), at)


def _interval_means(increments: ImuIncrements, path: NavSeries) -> tuple[ImuRates, ImuRates, NavSeries]:
    """Increments as mean rates at their intervals' mid-times; the ideal rate's mean over each interval
    (Simpson's rule through the truth ``path``'s splines); the truth at the mid-times."""
    t = increments.t
    dt = np.diff(t)[:, None]
    mid = 0.5 * (t[:-1] + t[1:])
    at_mid = path.interpolate(mid)
    edges, centres = _ideal_rates_at(path, path.interpolate(t)), _ideal_rates_at(path, at_mid)

    def simpson(x_edges: NDArray[np.float64], x_mid: NDArray[np.float64]) -> NDArray[np.float64]:
        return (x_edges[:-1] + 4.0 * x_mid + x_edges[1:]) / 6.0

    readings = ImuRates(t=mid, omega_ib_b=increments.dtheta_b / dt, f_ib_b=increments.dv_b / dt)
    reference = ImuRates(
        t=mid,
        omega_ib_b=simpson(edges.omega_ib_b, centres.omega_ib_b),
        f_ib_b=simpson(edges.f_ib_b, centres.f_ib_b),
    )
    return readings, reference, at_mid


__all__ = [
    "OWN_TAIL_FRACTION",
    "OWN_TAIL_S",
    "RunInputs",
    "SimulatedReadings",
    "cabin_temperature",
    "gap_data",
    "input_errors",
    "run_inputs",
    "simulate",
    "simulate_readings",
    "with_unit",
]
