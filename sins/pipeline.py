"""Runs: a scenario from file to drift summary, and a recorded IMU file against its truth.

These are the library calls behind the CLI; each returns plain results that
the CLI prints and writes.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

import numpy as np
from numpy.typing import NDArray

from sins import io, scenario
from sins.errors import MissingInputError, SinsInputError
from sins.nav import strapdown, trajectory
from sins.nav.metrics import (
    BlockMeans,
    DriftAccumulator,
    DriftSummary,
    NavErrors,
    TruthFrame,
    errors_against,
    kept_indices,
    nav_errors,
    summarize,
    thinned_indices,
)
from sins.nav.vertical import VerticalMode
from sins.scenario import PresetKind, Scenario, resolve_preset

# Re-exported: the presets lived here before they moved down to sins.scenario.
from sins.scenario import preset_dir as preset_dir
from sins.scenario import presets as presets
from sins.series import CalibrationData, ImuIncrements, ImuRates, NavSeries

if TYPE_CHECKING:
    from sins.aiding.ekf import AidedResult, FilterConfig
    from sins.aiding.gnss import GnssConfig, GnssFixes
    from sins.compensation import Strategy
    from sins.gap import GapReport
    from sins.imu import ImuModel
    from sins.nav.motion import Motion
    from sins.scenario import AidingSpec

T = TypeVar("T")

#: The most samples a run's thinned series keep (an hour at 10 Hz): a longer run keeps them sparser.
MAX_KEPT = 36_000

#: The scenario ``sins run`` uses without an argument.
DEFAULT_SCENARIO = "car_drive"


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
class OutageError:
    """The horizontal position error of an aided run over one outage window, m.

    ``final_m`` is at the last IMU sample before the window's end (or the run's end), before any fix
    corrects it; ``max_m`` the largest within the window.
    """

    start_s: float
    end_s: float
    final_m: float
    max_m: float


@dataclass(frozen=True)
class AidedRun:
    """One strategy's stream integrated by the GNSS/INS filter (:mod:`sins.aiding.ekf`).

    The summary covers every sample; for display, ``errors`` are thinned as the scenario's plain
    runs', and the filter's records (``t_cov``: each propagation step's end and each update) to at
    most :data:`MAX_KEPT`: ``sigma`` (m, 15) the 1σ of the filter's states (position NED m, velocity
    m/s, attitude rad, gyro bias rad/s, accelerometer bias m/s²), ``bias`` (m, 6) the estimated gyro
    and accelerometer biases. ``true_bias`` (6,) is the unit's constant bias (None for the ideal IMU);
    ``fix_t`` the fixes' times; ``restarts`` when the filter started again from a fix after a run of
    refused ones (:class:`sins.aiding.ekf.FilterConfig` ``reinit_after``). An in-motion alignment
    starts the filter at ``start_s``: the summary and ``errors`` cover the run from there.
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
    sample, plus the last), and to at most :data:`MAX_KEPT` samples for longer
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


def resolve_scenario(name_or_path: str | os.PathLike[str] | None, kind: PresetKind = "") -> Path:
    """A file path from a path, a preset name of ``kind``, or ``None`` (the default scenario).

    :func:`sins.scenario.resolve_preset` with :data:`DEFAULT_SCENARIO` for ``None``.
    """
    return resolve_preset(DEFAULT_SCENARIO if name_or_path is None else name_or_path, kind)


def simulate(sc: Scenario) -> tuple[NavSeries, ImuIncrements]:
    """Truth and exact ideal IMU of a scenario."""
    try:
        return trajectory.generate(scenario.build_motion(sc), sc.rate_hz)
    except ValueError as exc:
        if isinstance(exc, SinsInputError):
            raise
        raise SinsInputError(f"{sc.source or sc.name}: {exc}") from None


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


def run_scenario(sc: Scenario, keep_hz: float = 10.0, unit: FittedUnit | None = None) -> ScenarioRun:
    """Simulate a scenario and integrate its IMU stream.

    Without an IMU model the one run is ``"none"``: the ideal IMU, streamed
    chunk by chunk, so memory stays bounded whatever the duration. With one
    (``[imu] model``), see :func:`_run_with_imu`. ``unit`` (from :func:`fit_unit`) replaces the
    scenario's IMU file and compensation: a campaign fits a unit once and drives it through
    every scenario; the navigation run's power-on is still ``sc.imu_seed``.
    """
    if sc.imu_model is not None or unit is not None:
        return _run_with_imu(sc, keep_hz, unit)
    try:
        motion = scenario.build_motion(sc)
        first = trajectory.start_state(motion)
        chunks = _prefetched(trajectory.generate_chunks(motion, sc.rate_hz))
        keep_every = _keep_every(sc, motion, keep_hz)
        state = strapdown.start(strapdown.InitialState.from_series(first))
        acc = DriftAccumulator(keep_every)
        acc.add(nav_errors(first, first))
        truth_kept, solution_kept = [first], [first]
        samples = 0
        h_prev = float(first.h[0])
        for truth_c, imu_c in chunks:
            h_ref = np.concatenate([[h_prev], truth_c.h]) if sc.vertical != "free" else None
            solution_c, state = strapdown.advance(
                state, imu_c, vertical=sc.vertical, h_ref=h_ref, vertical_tau_s=sc.vertical_tau_s
            )
            acc.add(nav_errors(solution_c, truth_c))
            keep = kept_indices(samples + 1, len(truth_c.t), keep_every)
            truth_kept.append(truth_c.at(keep))
            solution_kept.append(solution_c.at(keep))
            samples += len(truth_c.t)
            h_prev = float(truth_c.h[-1])
    except ValueError as exc:
        if isinstance(exc, SinsInputError):
            raise
        raise SinsInputError(f"{sc.source or sc.name}: {exc}") from None
    if samples % keep_every:
        truth_kept.append(truth_c.at(-1))
        solution_kept.append(solution_c.at(-1))
    run = StrategyRun(solution=_join(solution_kept), errors=acc.kept(), summary=acc.summary())
    aided = aided_runs(sc, {"none": None}, keep_every=keep_every) if sc.aiding is not None else {}
    return ScenarioRun(scenario=sc, samples=samples, truth=_join(truth_kept), runs={"none": run}, aided=aided)


def _run_with_imu(sc: Scenario, keep_hz: float, unit: FittedUnit | None = None) -> ScenarioRun:
    """The scenario with a corrupted IMU, once per compensation strategy on the same stream.

    The rig session and the navigation run are two power-ons of the same unit
    (seeds ``[compensation] seed`` and ``[imu] seed``): strategies fitted on the
    rig meet the navigation run's own turn-on bias. ``oracle`` knows the
    navigation run's true deterministic model; it is every table's reference.

    Streamed: the ideal IMU is generated, corrupted (:class:`sins.imu.stream.IncrementStream`,
    the unit's state carried between chunks), corrected by each strategy and integrated chunk by
    chunk, and only the errors' statistics and thinned series are kept, so memory stays bounded
    whatever the duration. The readings equal the whole array's corruption to the last bit, and so
    do the integrated solutions (:func:`sins.nav.strapdown.advance` continues exactly).
    """
    if unit is None:
        assert sc.imu_model is not None
        unit = fit_unit(scenario.load_imu(sc.imu_model), sc.compensation)
    return run_units(sc, [unit], [sc.imu_seed], keep_hz)[0]


def run_units(
    sc: Scenario,
    units: Sequence[FittedUnit],
    nav_seeds: Sequence[int],
    keep_hz: float = 10.0,
    sensor_errors: bool = True,
) -> list[ScenarioRun]:
    """Drive several fitted units through one scenario, sharing its trajectory.

    The truth and ideal IMU are generated once, chunk by chunk, and each unit corrupts (power-on
    ``nav_seeds[i]``), corrects and integrates every chunk in turn, exactly as it would alone:
    each result equals :func:`run_scenario` of that unit with ``sc.imu_seed = nav_seeds[i]`` to the
    last bit. Memory is bounded by the chunk and the thinned series, whatever the duration.
    ``sensor_errors=False`` leaves out the runs' ``sensor_error`` and the ``sensor_t`` (a plot's, which
    a campaign does not keep: ~10 ns of a unit-sample's ~300).
    """
    if len(units) != len(nav_seeds):
        raise ValueError(f"{len(units)} units but {len(nav_seeds)} navigation seeds")
    try:
        motion = scenario.build_motion(sc)
        keep_every = _keep_every(sc, motion, keep_hz)
        first = trajectory.start_state(motion)
        chunks = _prefetched(_shared(sc, trajectory.generate_chunks(motion, sc.rate_hz)))
        pending = _Pending()  # one for all the units: they take the same rows, mostly at the same time
        driven = [
            _DrivenUnit(sc, unit, seed, first, keep_every, pending, sensor_errors)
            for unit, seed in zip(units, nav_seeds, strict=True)
        ]
        for frame, ideal6, ideal_c, cabin in chunks:
            pending.add(frame, ideal6)
            for d in driven:
                d.push(ideal_c, cabin)
            pending.release(min(d.step.samples for d in driven))
        for d in driven:
            d.finish()
    except ValueError as exc:
        if isinstance(exc, SinsInputError):
            raise
        raise SinsInputError(f"{sc.source or sc.name}: {exc}") from None
    return [d.result(seed) for d, seed in zip(driven, nav_seeds, strict=True)]


def _shared(
    sc: Scenario, chunks: Iterator[tuple[NavSeries, ImuIncrements]]
) -> Iterator[tuple[TruthFrame, NDArray[np.float64], ImuIncrements, NDArray[np.float64]]]:
    """What every unit needs of each generated chunk, made once (on the prefetching thread): the
    truth's frame (:class:`sins.nav.metrics.TruthFrame`), the ideal increments as (n, 6) and as they
    are, and the cabin temperature at their times."""
    for truth, ideal in chunks:
        yield TruthFrame.of(truth), np.hstack([ideal.dtheta_b, ideal.dv_b]), ideal, _cabin(sc, ideal.t)


class _DrivenUnit:
    """One unit's navigation power-on through a scenario: its stream, its strategies' runs."""

    def __init__(
        self,
        sc: Scenario,
        unit: FittedUnit,
        nav_seed: int,
        first: NavSeries,
        keep_every: int,
        pending: _Pending,
        sensor_errors: bool = True,
    ) -> None:
        from sins.imu.stream import IncrementStream

        self.sc, self.unit, self.keep_every = sc, unit, keep_every
        self.nav_model = nav_model = unit.spec.model(run_seed=nav_seed)
        self.strategies = unit.for_run(nav_model)
        self.stream = IncrementStream(nav_model, nav_seed, 1.0 / sc.rate_hz)
        self.runs = {name: _StreamedRun(first, keep_every) for name in self.strategies}
        self.truth_kept = [first]
        self.step = _ChunkStep(
            sc,
            self.strategies,
            self.runs,
            pending,
            self.truth_kept,
            keep_every,
            float(first.h[0]),
            sensor_errors,
        )

    def push(self, ideal: ImuIncrements, cabin: NDArray[np.float64]) -> None:
        """A generated chunk (its truth already added to the units' pending rows): corrupt it, and
        correct and integrate what the stream writes."""
        self.step(self.stream.push(ideal, cabin))

    def finish(self) -> None:
        """The stream's last intervals."""
        self.step(self.stream.finish())

    def result(self, nav_seed: int) -> ScenarioRun:
        """The unit's runs, as :func:`run_scenario` gives them."""
        samples, keep_every = self.step.samples, self.keep_every
        last_truth = self.step.last_truth
        if samples % keep_every and last_truth is not None:
            self.truth_kept.append(last_truth)
        residuals = self.unit.residuals
        out = {
            name: run.result(residuals.get(name), samples, keep_every, self.step.sensor_errors)
            for name, run in self.runs.items()
        }
        sensor_t = self.step.mid_t.means()[:, 0] if self.step.sensor_errors else None
        sc = dataclasses.replace(self.sc, imu_seed=nav_seed)
        aided = {}
        if sc.aiding is not None:
            strategies: dict[str, Strategy | None] = dict(self.strategies)
            aided = aided_runs(sc, strategies, self.nav_model, self.unit.spec.grade, keep_every=keep_every)
        return ScenarioRun(
            scenario=sc,
            samples=samples,
            truth=_join(self.truth_kept),
            runs=out,
            sensor_t=sensor_t,
            aided=aided,
        )


def aided_runs(
    sc: Scenario,
    strategies: dict[str, Strategy | None],
    nav_model: ImuModel | None = None,
    grade: str | None = None,
    keep_every: int = 1,
) -> dict[str, AidedRun]:
    """Each strategy's corrected stream navigated by the GNSS/INS filter (``[gnss]`` in the scenario).

    Whole arrays, not streamed: the truth and the readings are made again (the same, to the last
    bit, as the streamed run's), the receiver rides the truth, and the filter starts from an alignment
    (``[alignment]``, :func:`_alignment_plan`: still, in motion from the GNSS velocity, or the truth's
    first state where the scenario says ``method = "truth"``). The filter is tuned to
    ``[gnss] filter_grade``, else to the IMU model's grade, else to the navigation grade.

    Parameters
    ----------
    sc : the scenario (``sc.aiding`` set)
    strategies : name -> the strategy that corrects the readings (None: take them as they are)
    nav_model : the unit's error model for this run (None: the ideal IMU)
    grade : the IMU file's grade, if any
    keep_every : the display series keep every ``keep_every``-th sample (and the last)
    """
    from sins.aiding import ekf, gnss

    a = sc.aiding
    assert a is not None
    truth, ideal = simulate(sc)
    temp = _cabin(sc, ideal.t)
    readings = ideal
    if nav_model is not None:
        readings = nav_model.corrupt_increments(ideal, temp, seed=sc.imu_seed, dt_nominal=1.0 / sc.rate_hz)
    fixes = gnss.simulate(truth, _receiver(a), seed=a.seed)
    filter_grade = a.filter_grade or grade or "navigation"
    config = ekf.FilterConfig.for_grade(filter_grade)
    plan = _alignment_plan(sc, truth, config)
    true_bias = _true_bias(nav_model)
    keep = None
    out = {}
    for name, strategy in strategies.items():
        corrected = readings if strategy is None else strategy.correct_increments(readings, temp)
        result, k, heading_sigma = _aligned_run(plan, corrected, fixes, config, truth)
        ran = truth if k == 0 else truth.at(np.arange(k, len(truth.t)))
        errors = nav_errors(result.nav, ran)
        windows = _outage_errors(a.outages, ran.t, errors.horizontal_m)
        if keep is None:
            keep = thinned_indices(len(ran.t), keep_every)
            records = thinned_indices(len(result.t_cov), math.ceil(len(result.t_cov) / MAX_KEPT))
        out[name] = AidedRun(
            summarize(errors), len(fixes), result.rejected, tuple(windows), filter_grade,
            errors=errors.at(keep), t_cov=result.t_cov[records], sigma=result.sigma()[records],
            bias=np.hstack([result.gyro_bias, result.accel_bias])[records], true_bias=true_bias,
            fix_t=np.asarray(fixes.t, dtype=float), restarts=tuple(float(x) for x in result.reinit_t),
            alignment=plan.method, start_s=float(ran.t[0]), static_s=plan.static_s,
            heading_sigma_deg=None if heading_sigma is None else math.degrees(heading_sigma),
            velocity_rejected=result.velocity_rejected,
        )  # fmt: skip
    return out


def _receiver(a: AidingSpec) -> GnssConfig:
    """The simulated receiver a scenario's ``[gnss]`` and ``[[outage]]`` describe."""
    from sins.aiding import gnss

    return gnss.GnssConfig(
        rate_hz=a.rate_hz, sigma_pos_m=np.array(a.sigma_m), markov_sigma_m=np.array(a.markov_sigma_m),
        markov_tau_s=a.markov_tau_s, sigma_vel_mps=a.sigma_vel_mps, lever_arm_b=np.array(a.lever_arm_m),
        latency_s=a.latency_s, compensate_latency=a.compensate_latency,
        outages=tuple(gnss.Outage(s, e) for s, e in a.outages),
    )  # fmt: skip


def check_runnable(sc: Scenario, grade: str | None = None) -> None:
    """Refuse now what driving ``sc`` would refuse later, without driving it: a motion shorter than
    one sample and, with ``[gnss]``, an alignment the trajectory cannot give (a still window longer than
    the run, or while the vehicle moves; a speed the GNSS never shows). A campaign checks each scenario
    so before its cluster starts and its units are fitted. ``grade``: the IMU file's, which tunes the
    filter as in :func:`aided_runs`.

    Raises
    ------
    SinsInputError
        naming the scenario and the key, as :func:`run_scenario` would.
    """
    from sins.aiding import alignment, ekf, gnss

    where = sc.source or sc.name
    motion = scenario.build_motion(sc)
    if scenario.sample_count(sc, motion) < 1:
        raise SinsInputError(
            f"{where}: the motion lasts {motion.t_end - motion.t_start:g} s, shorter than one sample"
        )
    a = sc.aiding
    if a is None:
        return
    truth, ideal = simulate(sc)
    config = ekf.FilterConfig.for_grade(a.filter_grade or grade or "navigation")
    plan = _alignment_plan(sc, truth, config)
    if plan.method == "gnss_velocity":
        fixes = gnss.simulate(truth, _receiver(a), seed=a.seed)
        motion_config = alignment.MotionConfig(
            min_speed_mps=a.min_speed_mps, sideslip_sigma_rad=a.sideslip_sigma_rad
        )
        try:
            alignment.in_motion_start(ideal, fixes, config, motion_config)
        except SinsInputError as exc:
            raise SinsInputError(f"{where}: {exc}") from None


#: The shortest stop at the start an automatic alignment aligns still on, s.
AUTO_MIN_STOP_S = 30.0
#: The longest still window an automatic alignment uses (the fine alignment gains little after), s.
AUTO_MAX_STATIC_S = 300.0


@dataclass(frozen=True)
class _AlignmentPlan:
    """How every strategy's aided run starts (``[alignment]`` resolved against the trajectory)."""

    method: str  # "static", "gnss_velocity" or "truth"
    static_s: float = 0.0
    coarse_s: float = 0.0
    heading: tuple[float, float] | None = None  # a static alignment's heading from elsewhere, rad
    min_speed_mps: float = 5.0
    sideslip_sigma_rad: float = 0.0
    where: str = ""  # the scenario, for the in-motion alignment's refusal


def _alignment_plan(sc: Scenario, truth: NavSeries, config: FilterConfig) -> _AlignmentPlan:
    """``[alignment]`` resolved: ``auto`` aligns still on a stop at the start of ``static_s`` (default any
    of :data:`AUTO_MIN_STOP_S` or more, up to :data:`AUTO_MAX_STATIC_S` used) where gyrocompassing
    finds north within :data:`sins.aiding.alignment.GYROCOMPASS_MAX_SIGMA_RAD` (or the heading comes
    from elsewhere), and in motion from the GNSS velocity otherwise."""
    from sins.aiding import alignment

    a = sc.aiding
    assert a is not None
    method, static_s = a.alignment, a.static_s
    if method == "auto":
        stop = _initial_stop_s(truth)
        static_s = static_s if static_s is not None else min(stop, AUTO_MAX_STATIC_S)
        coarse = min(a.coarse_s, static_s)
        north = a.heading_sigma_rad is not None or (
            coarse > 0
            and np.sqrt(alignment.coarse_covariance(config, float(truth.lat[0]), coarse, 1.0)[8, 8])
            <= alignment.GYROCOMPASS_MAX_SIGMA_RAD
        )
        enough = stop >= max(static_s, AUTO_MIN_STOP_S) - 1e-9
        method = "static" if enough and north else "gnss_velocity"
    if method == "static":
        assert static_s is not None
        plan = _AlignmentPlan("static", static_s, min(a.coarse_s, static_s))
        return dataclasses.replace(plan, heading=_alignment_heading(sc, truth, static_s))
    return _AlignmentPlan(
        method, min_speed_mps=a.min_speed_mps, sideslip_sigma_rad=a.sideslip_sigma_rad,
        where=str(sc.source or sc.name),
    )  # fmt: skip


def _initial_stop_s(truth: NavSeries) -> float:
    """How long the vehicle stands still (no speed, no turn) from the first sample, s."""
    yaw = np.unwrap(truth.euler()[2])
    moving = (np.linalg.norm(truth.v_n, axis=1) > 1e-6) | (np.abs(yaw - yaw[0]) > 1e-9)
    if not moving.any():
        return float(truth.t[-1] - truth.t[0])
    return float(truth.t[max(int(np.argmax(moving)) - 1, 0)] - truth.t[0])


def _aligned_run(
    plan: _AlignmentPlan, imu: ImuIncrements, fixes: GnssFixes, config: FilterConfig, truth: NavSeries
) -> tuple[AidedResult, int, float | None]:
    """One strategy's aided run as ``plan`` starts it: the result, the sample it starts at, and the
    in-motion alignment's heading σ (rad; None for the others)."""
    from sins.aiding import alignment, ekf

    if plan.method == "static":
        setup = alignment.AlignmentConfig(static_s=plan.static_s, coarse_s=plan.coarse_s)
        return alignment.aligned_run(imu, fixes, config, setup, heading=plan.heading), 0, None
    if plan.method == "gnss_velocity":
        motion = alignment.MotionConfig(
            min_speed_mps=plan.min_speed_mps, sideslip_sigma_rad=plan.sideslip_sigma_rad
        )
        try:
            start, result = alignment.in_motion_run(imu, fixes, config, motion)
        except SinsInputError as exc:
            raise SinsInputError(f"{plan.where}: {exc}") from None
        return result, start.index, start.heading_sigma_rad
    return ekf.run(imu, fixes, config, strapdown.InitialState.from_series(truth)), 0, None


def _alignment_heading(sc: Scenario, truth: NavSeries, static_s: float) -> tuple[float, float] | None:
    """The heading given to a static alignment (``[alignment] heading_sigma_deg``: the truth's, off by a
    draw of that σ), or None to gyrocompass; refuses a vehicle that moves within ``static_s``."""
    a = sc.aiding
    assert a is not None
    where = sc.source or sc.name
    still = truth.t <= truth.t[0] + static_s + 1e-9
    if truth.t[-1] < truth.t[0] + static_s - 1e-9:
        raise SinsInputError(
            f"{where}: alignment.static_s: {static_s:g} s is longer than the run's "
            f"{truth.t[-1] - truth.t[0]:g} s"
        )
    speed = float(np.max(np.linalg.norm(truth.v_n[still], axis=1)))
    turn = np.abs(np.diff(np.unwrap(truth.euler()[2][still])))
    if speed > 1e-6 or float(np.sum(turn)) > 1e-9:
        raise SinsInputError(
            f"{where}: alignment.static_s: the vehicle moves within the first {static_s:g} s "
            f"(speed up to {speed:.3g} m/s); an alignment needs it still"
        )
    if a.heading_sigma_rad is None:
        return None
    draw = np.random.default_rng([a.seed, 3]).standard_normal()
    return float(truth.euler()[2][0] + a.heading_sigma_rad * draw), a.heading_sigma_rad


def _true_bias(nav_model: ImuModel | None) -> NDArray[np.float64] | None:
    """The unit's constant gyro and accelerometer biases (6,), to set beside the filter's estimates."""
    if nav_model is None:
        return None
    from sins.imu import Bias

    gyro, accel = nav_model.effect_of("gyro", Bias), nav_model.effect_of("accel", Bias)
    return np.concatenate([np.zeros(3) if b is None else b.value for b in (gyro, accel)])


def _outage_errors(
    outages: Sequence[tuple[float, float]], t: NDArray[np.float64], horizontal: NDArray[np.float64]
) -> list[OutageError]:
    """Each outage's horizontal error at its end (the sample before the fix that ends it) and its max."""
    windows = []
    for start, end in outages:
        if start >= t[-1]:
            continue
        # Samples within 1 µs of an edge (a fix's, up to rounding) are the fix's, not the window's.
        inside = np.flatnonzero((t > start + 1e-6) & (t < min(end, t[-1]) + 1e-9))
        if end < t[-1]:  # the sample before the fix at the window's end
            inside = inside[t[inside] < end - 1e-6]
        if inside.size == 0:
            continue
        windows.append(
            OutageError(start, end, float(horizontal[inside[-1]]), float(horizontal[inside].max()))
        )
    return windows


def _keep_every(sc: Scenario, motion: Motion, keep_hz: float) -> int:
    """Every how many samples the thinned series keep one: about ``keep_hz``, and no more than
    :data:`MAX_KEPT` over the run (a 6-hour run keeps a sample every 0.6 s, not 2 million)."""
    samples = (motion.t_end - motion.t_start) * sc.rate_hz
    return max(1, round(sc.rate_hz / keep_hz), math.ceil(samples / MAX_KEPT))


def _cabin(sc: Scenario, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """The cabin temperature at ``t``, °C (default a constant 20)."""
    return np.asarray(np.interp(t, *sc.temperature), dtype=float)


@dataclass(frozen=True)
class FittedUnit:
    """One unit's strategies, fitted on its rig session, ready to drive any number of scenarios.

    ``strategies`` holds every strategy but the oracle, whose model is each navigation run's own
    (:meth:`for_run`); ``residuals`` the RMS of each one's corrected readings on the held-back rig
    rows, per channel, SI units (the oracle's knowing the rig session's unit), and ``biases`` their
    mean (the bias each strategy leaves).
    """

    spec: scenario.ImuSpec
    compensation: scenario.CompensationSpec | None
    strategies: dict[str, Strategy]
    residuals: dict[str, dict[str, float]]
    biases: dict[str, dict[str, float]] = field(default_factory=dict)

    def for_run(self, nav_model: ImuModel) -> dict[str, Strategy]:
        """The strategies in the scenario's order, the oracle knowing ``nav_model``."""
        from sins import compensation

        names = ["none", *(self.compensation.strategies if self.compensation else ())]
        out: dict[str, Strategy] = {}
        for name in names:
            out[name] = compensation.Oracle(nav_model) if name == "oracle" else self.strategies[name]
        return out


def fit_unit(spec: scenario.ImuSpec, comp: scenario.CompensationSpec | None) -> FittedUnit:
    """Simulate the unit's rig session (power-on ``comp.seed``) and fit every strategy of ``comp``.

    Without ``comp``, only ``"none"``.
    """
    from sins import compensation
    from sins.imu import calibration

    strategies: dict[str, Strategy] = {"none": compensation.make("none")}
    residuals: dict[str, dict[str, float]] = {}
    biases: dict[str, dict[str, float]] = {}
    if comp is None:
        return FittedUnit(spec, comp, strategies, residuals, biases)
    rig = scenario.load_rig(comp.rig)
    rig_model = spec.model(run_seed=comp.seed)
    data = calibration.simulate_rig(rig, rig_model, seed=comp.seed)
    fit, held = data.split(comp.validation)
    for name in comp.strategies:
        if name == "oracle":
            # On the rig it knows the rig session's unit; in navigation, the navigation run's.
            judged: Strategy = compensation.Oracle(rig_model)
        else:
            judged = strategies[name] = compensation.make(name).fit(fit)
        channels = compensation.residual_rms(judged, held)
        residuals[name] = {ch: v["rms_after"] for ch, v in channels.items()}
        biases[name] = {ch: v["mean_after"] for ch, v in channels.items()}
    return FittedUnit(spec, comp, strategies, residuals, biases)


class _Pending:
    """Truth states and ideal increments generated but not yet integrated by every unit: a unit's
    corruption writes an interval only once the intervals after it have come. The units driven
    together take the same rows (all of them, as soon as their streams' margins agree), so the rows
    of a take are joined once for all of them."""

    def __init__(self) -> None:
        self._chunks: list[tuple[int, TruthFrame, NDArray[np.float64]]] = []  # (first row, frame, ideal)
        self._end = 0  # rows added
        self._last: tuple[tuple[int, int], tuple[TruthFrame, NDArray[np.float64]]] | None = None

    def add(self, frame: TruthFrame, ideal: NDArray[np.float64]) -> None:
        """A generated chunk: the truth's frame at ``t[1:]`` and the ideal increments (n, 6)."""
        self._chunks.append((self._end, frame, ideal))
        self._end += len(frame)

    def take(self, start: int, n: int) -> tuple[TruthFrame, NDArray[np.float64]]:
        """Rows ``start .. start + n``: the intervals' truth (at their ends) and ideal increments (n, 6)."""
        if self._last is not None and self._last[0] == (start, n):
            return self._last[1]
        frames, ideal = [], []
        for first, frame, inc in self._chunks:
            lo, hi = max(start - first, 0), min(start + n - first, len(frame))
            if lo < hi:
                frames.append(frame.rows(lo, hi))
                ideal.append(inc[lo:hi])
        if sum(len(f) for f in frames) != n:
            raise RuntimeError(f"rows {start}..{start + n} are not all pending")  # a bug, not bad input
        taken = TruthFrame.join(frames), ideal[0] if len(ideal) == 1 else np.vstack(ideal)
        self._last = (start, n), taken
        return taken

    def release(self, before: int) -> None:
        """Drop the chunks every unit has taken: those that end at or before row ``before``."""
        while self._chunks and self._chunks[0][0] + len(self._chunks[0][1]) <= before:
            self._chunks.pop(0)


class _StreamedRun:
    """One strategy's integration state and what it keeps of its errors."""

    def __init__(self, first: NavSeries, keep_every: int) -> None:
        self.state = strapdown.start(strapdown.InitialState.from_series(first))
        self.errors = DriftAccumulator(keep_every)
        self.errors.add(nav_errors(first, first))
        self.kept = [first]
        self.last: NavSeries = first
        self.sensor = BlockMeans(keep_every)

    def result(
        self, residual: dict[str, float] | None, samples: int, keep_every: int, sensor_errors: bool = True
    ) -> StrategyRun:
        """The run's thinned solution and errors, its summary over every sample."""
        kept = self.kept + ([self.last] if samples % keep_every else [])
        sensor = self.sensor.means() if sensor_errors else None
        return StrategyRun(_join(kept), self.errors.kept(), self.errors.summary(), residual, sensor)


@dataclass
class _ChunkStep:
    """Correct and integrate each chunk of corrupted readings with every strategy, in turn."""

    sc: Scenario
    strategies: dict[str, Strategy]
    runs: dict[str, _StreamedRun]
    pending: _Pending
    truth_kept: list[NavSeries]
    keep_every: int
    h_prev: float  # the truth's height at the last integrated sample (the vertical aiding's start)
    sensor_errors: bool = True  # the block means of each stream's sensor errors, and their times
    samples: int = 0
    mid_t: BlockMeans = field(init=False)  # the block means' times: the intervals' mid-times
    last_truth: NavSeries | None = None  # the truth at the last integrated sample

    def __post_init__(self) -> None:
        self.mid_t = BlockMeans(self.keep_every)

    def __call__(self, corrupted: ImuIncrements) -> None:
        n = len(corrupted)
        if n == 0:
            return
        sc = self.sc
        frame, ideal = self.pending.take(self.samples, n)
        self.last_truth = frame.truth(slice(-1, None))
        temp = _cabin(sc, corrupted.t)
        dt = np.diff(corrupted.t)
        keep = kept_indices(self.samples + 1, n, self.keep_every)
        h_ref = np.concatenate([[self.h_prev], frame.h]) if sc.vertical != "free" else None
        for name, strategy in self.strategies.items():
            run = self.runs[name]
            corrected = strategy.correct_increments(corrupted, temp)
            solution, run.state = strapdown.advance(
                run.state, corrected, vertical=sc.vertical, h_ref=h_ref, vertical_tau_s=sc.vertical_tau_s
            )
            run.errors.add(*errors_against(solution, frame))
            run.kept.append(solution.at(keep))
            run.last = solution.at(np.array([-1]))  # a copy: a view would hold the chunk's solution
            if self.sensor_errors:
                run.sensor.add_difference((corrected.dtheta_b, corrected.dv_b), ideal, dt)
        if self.sensor_errors:
            self.mid_t.add(0.5 * (corrupted.t[:-1] + corrupted.t[1:])[:, None])
        self.truth_kept.append(frame.truth(keep))
        self.samples += n
        self.h_prev = float(frame.h[-1])


def _prefetched(items: Iterator[T]) -> Iterator[T]:
    """Yield from ``items``, producing the next one in a worker thread meanwhile.

    The compiled kernels release the GIL, so generating chunk k+1 overlaps
    integrating chunk k on a second core.
    """
    with ThreadPoolExecutor(max_workers=1) as pool:
        future = pool.submit(next, items, None)
        while (item := future.result()) is not None:
            future = pool.submit(next, items, None)
            yield item


def _join(parts: list[NavSeries]) -> NavSeries:
    return NavSeries(
        t=np.concatenate([p.t for p in parts]),
        lat=np.concatenate([p.lat for p in parts]),
        lon=np.concatenate([p.lon for p in parts]),
        h=np.concatenate([p.h for p in parts]),
        v_n=np.concatenate([p.v_n for p in parts]),
        q_nb=np.concatenate([p.q_nb for p in parts]),
    )


def integrate_recording(
    imu_path: str | os.PathLike[str],
    truth_path: str | os.PathLike[str],
    vertical: VerticalMode = "free",
    vertical_tau_s: float = 10.0,
) -> StrategyRun:
    """Integrate a recorded IMU file from its truth's first state; errors against the truth.

    Increment form: the first row's interval starts at the truth's first time.
    Rate form: the samples are integrated to increments between rows, and the
    run starts at the first row's time, which must lie within the truth.
    """
    truth = io.read_truth(truth_path)
    samples, table = io.read_imu(imu_path)
    imu: ImuIncrements
    if isinstance(samples, ImuRates):
        if samples.t[0] < truth.t[0] or samples.t[0] > truth.t[-1]:
            raise SinsInputError(
                f"{imu_path}: first sample at {samples.t[0]:g} s is outside the truth's "
                f"{truth.t[0]:g}..{truth.t[-1]:g} s"
            )
        if len(samples) < 2:
            raise SinsInputError(f"{imu_path}: need at least two rate samples")
        imu = samples.to_increments()
    else:
        imu = io.increments_from_table(table, float(truth.t[0]))
    if imu.t[-1] > truth.t[-1] + 1e-9:
        inside = int(np.searchsorted(imu.t, truth.t[-1] + 1e-9, side="right"))
        if inside < 2:
            raise SinsInputError(f"{imu_path}: no IMU interval ends within the truth's time span")
        imu = ImuIncrements(
            t=imu.t[:inside], dtheta_b=imu.dtheta_b[: inside - 1], dv_b=imu.dv_b[: inside - 1]
        )
    return navigate(imu, truth, vertical, vertical_tau_s)


def gap_data(
    recording: str | os.PathLike[str], truth: str | os.PathLike[str] | None = None
) -> tuple[CalibrationData, NavSeries | None]:
    """Readings beside reference inputs for :func:`sins.gap.diagnose`, and the truth at their times.

    Without ``truth``: a rig recording with ``ref_`` columns (the truth returned is None). With it:
    an IMU recording in rate form whose reference inputs come from the truth trajectory through the
    exact ideal-IMU path (splines through the truth, then the strapdown equations backwards).
    """
    from sins.nav import motion

    if truth is None:
        if not any(c.startswith("ref_") for c in io.read_columns(recording)):
            raise MissingInputError(
                f"{recording}: no ref_ columns (a rig recording has them); an IMU recording needs its "
                "trajectory (a truth file)",
                needs="truth",
            )
        return io.read_recording(recording), None
    samples, table = io.read_imu(recording)
    if not isinstance(samples, ImuRates):
        raise SinsInputError(f"{recording}: the gap diagnosis needs the rate form (wx..wz, fx..fz columns)")
    path = io.read_truth(truth)
    if len(path.t) < 4:
        raise SinsInputError(f"{truth}: a truth trajectory needs at least 4 rows")
    inside = (samples.t >= path.t[0]) & (samples.t <= path.t[-1])
    if inside.sum() < len(samples.t):
        raise SinsInputError(
            f"{recording}: rows from t={samples.t[~inside][0]:g} s lie outside the truth's "
            f"{path.t[0]:g}..{path.t[-1]:g} s in {truth}"
        )
    at_samples = path.interpolate(samples.t)
    ideal = trajectory.ideal_rates(motion.RecordedMotion.from_series(path), at_samples)
    temp = table.data[:, table.columns.index("temp")] if "temp" in table.columns else None
    data = CalibrationData(
        t=samples.t, gyro=samples.omega_ib_b, accel=samples.f_ib_b, ref_gyro=ideal.omega_ib_b,
        ref_accel=ideal.f_ib_b, temp=temp, source=str(recording),
    )  # fmt: skip
    return data, at_samples


def gap_navigation(data: CalibrationData, truth: NavSeries, report: GapReport) -> dict[str, float]:
    """Navigation drift of the real unit and of the simulated one (the model before and after the
    accepted effects), integrated over the recording from the truth, vertical channel held to it.

    The simulated unit's readings are the reference plus the model's predicted error (no noise: the
    drift of what the model explains). Returns final horizontal errors against the truth and the
    horizontal distance between the simulated and the real unit's solutions at the end, m.

    ``truth`` is at the recording's times, as :func:`gap_data` returns it.
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


@dataclass(frozen=True)
class RecordingOutages:
    """A real recording's IMU aided by its reference position as fixes, with outages opened in them.

    ``outages`` are each window's horizontal error at its end and its maximum (:class:`OutageError`),
    ``predicted_m`` the filter's horizontal 1σ at each window's end, ``free_m`` the error of the raw
    readings (no bias correction) integrated over each window from the aided state at its start: what
    the filter's estimate of the biases is worth. ``gyro_bias`` and
    ``accel_bias`` are the final estimates (rad/s, m/s²); ``rms_m`` the horizontal RMS over the run.
    """

    outages: tuple[OutageError, ...]
    predicted_m: tuple[float, ...]
    free_m: tuple[float, ...]
    gyro_bias: NDArray[np.float64]
    accel_bias: NDArray[np.float64]
    rms_m: float
    fixes: int
    rejected: int


def psins_vehicle_outages(
    outages: tuple[tuple[float, float], ...] = ((30.0, 45.0), (60.0, 80.0), (85.0, 95.0)),
    *,
    rate_hz: float = 1.0,
    sigma_m: float = 0.5,
    grade: str = "consumer",
    root: str | os.PathLike[str] | None = None,
) -> RecordingOutages:
    """The PSINS vehicle recording's MEMS aided by the FOG-INS position as fixes, through outages.

    The MEMS increments are integrated from the FOG-INS state (moved to the MEMS's place) at their
    first time inside the reference; fixes are the FOG-INS position at ``rate_hz`` (its place, so the
    lever arm is the reader's estimate of it, in MEMS axes) with ``sigma_m`` told to the filter; the
    filter is tuned to ``grade`` (the file's MEMS has ≈ 0.06 °/s gyro and 5 mg accelerometer biases:
    consumer grade). Errors are against the FOG-INS solution moved to the MEMS's place.
    """
    from sins.aiding import ekf, gnss
    from sins.io.datasets.psins_vehicle import psins_alignment, read_psins_vehicle
    from sins.nav import rotation

    data, fog = read_psins_vehicle(root)
    assert fog is not None
    arm = psins_alignment(root).lever_arm_m  # the MEMS from the FOG-INS, MEMS axes
    dt = 0.01  # the MEMS's increments: row k covers the 10 ms before t + 5 ms
    t_end = data.t + 0.5 * dt
    lat, lon, h = gnss.offset_position(fog.lat, fog.lon, fog.h, rotation.dcm_from_quat(fog.q_nb) @ arm)
    truth = NavSeries(t=fog.t, lat=lat, lon=lon, h=h, v_n=fog.v_n, q_nb=fog.q_nb)
    t = np.r_[t_end[0] - dt, t_end]
    rows = np.flatnonzero((t >= truth.t[0]) & (t <= truth.t[-1]))
    k0, k1 = int(rows[0]), int(rows[-1])
    imu = ImuIncrements(t=t[k0 : k1 + 1], dtheta_b=data.gyro[k0:k1] * dt, dv_b=data.accel[k0:k1] * dt)
    start = strapdown.InitialState.from_series(truth.interpolate(imu.t[:1]))
    fix_t = np.arange(np.ceil(imu.t[0] * rate_hz), imu.t[-1] * rate_hz) / rate_hz
    at = fog.interpolate(fix_t)
    fixes = gnss.GnssFixes(
        t=fix_t, lat=at.lat, lon=at.lon, h=at.h, v_n=np.full((len(fix_t), 3), np.nan),
        sigma_pos_m=np.full(3, sigma_m), lever_arm_b=-arm,
    ).without([gnss.Outage(a, b) for a, b in outages])  # fmt: skip
    config = ekf.FilterConfig.for_grade(
        grade, position_sigma_m=sigma_m, velocity_sigma_mps=0.1, tilt_sigma_rad=np.radians(0.5),
        heading_sigma_rad=np.radians(1.0),
    )  # fmt: skip
    result = ekf.run(imu, fixes, config, start)
    reference = truth.interpolate(imu.t)
    horizontal = nav_errors(result.nav, reference).horizontal_m
    windows, predicted, free = [], [], []
    for a, b in outages:
        inside = np.flatnonzero((imu.t > a + 1e-6) & (imu.t < b - 1e-6))  # the fixes' samples are not in it
        windows.append(OutageError(a, b, float(horizontal[inside[-1]]), float(horizontal[inside].max())))
        row = int(np.flatnonzero((result.t_cov <= b + 1e-9) & ~result.after_update)[-1])
        predicted.append(float(np.hypot(*result.sigma()[row, :2])))
        # The raw readings from the aided state at the window's start (after its last fix).
        k = int(inside[0]) - 1
        steps = slice(k, int(inside[-1]))
        seg = ImuIncrements(
            t=imu.t[k : int(inside[-1]) + 1], dtheta_b=imu.dtheta_b[steps], dv_b=imu.dv_b[steps]
        )
        alone = strapdown.integrate(seg, strapdown.InitialState.from_series(result.nav, k))
        free.append(float(nav_errors(alone.at(-1), reference.at(int(inside[-1]))).horizontal_m[0]))
    return RecordingOutages(
        outages=tuple(windows), predicted_m=tuple(predicted), free_m=tuple(free),
        gyro_bias=result.gyro_bias[-1], accel_bias=result.accel_bias[-1],
        rms_m=float(np.sqrt(np.mean(horizontal**2))), fixes=len(fixes), rejected=result.rejected,
    )  # fmt: skip
