"""Runs of a scenario: from its file to each strategy's drift, the one streaming engine.

These are the library calls behind ``sins run`` and campaigns; each returns plain results
(:mod:`sins.runs.results`) that the command line prints and writes.

One engine runs every scenario (:func:`run_units`; :func:`run_scenario` is that of one unit): the
trajectory is generated chunk by chunk on a second thread, and each unit's stream (its corruption, or
the ideal IMU as it is) is corrected by each strategy and integrated chunk by chunk; only the errors'
statistics and thinned series are kept. A scenario with ``[gnss]`` keeps the generated truth and ideal
IMU whole, and after the stream each unit's readings go through the GNSS/INS filter
(:func:`aided_runs`), started as :mod:`sins.aiding.policy` says.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

import numpy as np
from numpy.typing import NDArray

# The names imported ``as`` themselves lived here before they moved to the modules named (the aided run's
# outage error, readings as files hold them, the presets, what runs give back, a unit's fit and the
# replay of a recorded IMU): they stay importable from here.
from sins import scenario
from sins.aiding.outages import OutageError as OutageError
from sins.aiding.outages import outage_errors
from sins.core.series import ImuIncrements, NavSeries
from sins.errors import SinsInputError
from sins.nav import strapdown, trajectory
from sins.nav.metrics import (
    BlockMeans,
    DriftAccumulator,
    TruthFrame,
    errors_against,
    kept_indices,
    nav_errors,
    summarize,
    thinned_indices,
)
from sins.runs.readings import RunInputs as RunInputs
from sins.runs.readings import SimulatedReadings as SimulatedReadings
from sins.runs.readings import cabin_temperature as _cabin
from sins.runs.readings import gap_data as gap_data
from sins.runs.readings import input_errors
from sins.runs.readings import run_inputs as run_inputs
from sins.runs.readings import simulate as simulate
from sins.runs.readings import simulate_readings as simulate_readings
from sins.runs.readings import with_unit as with_unit
from sins.runs.replay import integrate_recording as integrate_recording
from sins.runs.replay import navigate as navigate
from sins.runs.results import AidedRun, ScenarioRun, StrategyRun
from sins.runs.unit_fit import FittedUnit as FittedUnit
from sins.runs.unit_fit import fit_unit
from sins.scenario import PresetKind, Scenario, resolve_preset
from sins.scenario import preset_dir as preset_dir
from sins.scenario import presets as presets

if TYPE_CHECKING:
    from sins.aiding.gnss import GnssConfig
    from sins.compensation import Strategy
    from sins.imu import ImuModel
    from sins.nav.motion import Motion
    from sins.scenario import AidingSpec

_T = TypeVar("_T")

#: A progress callback: ``progress(done, total)``.
Progress = Callable[[int, int], None]

#: The most samples a run's thinned series keep (an hour at 10 Hz): a longer run keeps them sparser.
MAX_KEPT = 36_000

#: The scenario ``sins run`` uses without an argument.
DEFAULT_SCENARIO = "car_drive"


def resolve_scenario(name_or_path: str | os.PathLike[str] | None, kind: PresetKind = "") -> Path:
    """A file path from a path, a preset name of ``kind``, or ``None`` (the default scenario).

    :func:`sins.scenario.resolve_preset` with :data:`DEFAULT_SCENARIO` for ``None``.
    """
    return resolve_preset(DEFAULT_SCENARIO if name_or_path is None else name_or_path, kind)


def run_scenario(
    sc: Scenario, keep_hz: float = 10.0, unit: FittedUnit | None = None, progress: Progress | None = None
) -> ScenarioRun:
    """Simulate a scenario and integrate its IMU stream once per compensation strategy: :func:`run_units`
    of one unit, with the navigation power-on ``sc.imu_seed``.

    The unit is ``unit`` (from :func:`fit_unit`: a campaign fits a unit once and drives it through every
    scenario), else the scenario's ``[imu] model`` with its ``[compensation]`` strategies fitted first
    (silently: :func:`fit_unit` takes its own ``progress``), else the ideal IMU, whose one run is
    ``"none"``. ``progress(done, work)`` is called as chunks are integrated and as aided filters end
    (:func:`run_units`).

    The rig session and the navigation run are two power-ons of the same unit (seeds ``[compensation]
    seed`` and ``[imu] seed``): strategies fitted on the rig meet the navigation run's own turn-on bias.
    ``oracle`` knows the navigation run's true deterministic model; it is every table's reference.

    Raises
    ------
    SinsInputError
        a scenario the trajectory or the unit cannot follow (naming the scenario), or a refused alignment.
    """
    if unit is None and sc.imu_model is not None:
        unit = fit_unit(scenario.load_imu(sc.imu_model), sc.compensation)
    return run_units(sc, [unit], [sc.imu_seed], keep_hz, progress=progress)[0]


def run_units(
    sc: Scenario,
    units: Sequence[FittedUnit | None],
    nav_seeds: Sequence[int],
    keep_hz: float = 10.0,
    sensor_errors: bool = True,
    progress: Progress | None = None,
) -> list[ScenarioRun]:
    """Drive several units through one scenario, sharing its trajectory: the one streaming engine.

    The truth and ideal IMU are generated once, chunk by chunk, and each unit corrupts (power-on
    ``nav_seeds[i]``; ``None`` is the ideal IMU, whose stream gives the ideal increments as they are),
    corrects and integrates every chunk in turn, exactly as it would alone: each result equals
    :func:`run_scenario` of that unit with ``sc.imu_seed = nav_seeds[i]`` to the last bit, and the
    readings equal the whole array's corruption (:class:`sins.imu.stream.IncrementStream`), and so do the
    integrated solutions (:func:`sins.nav.strapdown.advance` continues exactly). Memory is bounded by the
    chunk and the thinned series, whatever the duration; a scenario with ``[gnss]`` also keeps its truth
    and ideal IMU whole for the aided runs (:func:`aided_runs`), which follow the stream.
    ``sensor_errors=False`` leaves out the runs' ``sensor_error`` and the ``sensor_t`` (a plot's, which a
    campaign does not keep; the ideal IMU has none).
    ``progress(done, work)`` is called as the chunks are integrated (``done`` samples of ``work``) and
    as each aided run's filter ends (each counts as the samples again: ``work`` is the samples times one
    plus the aided runs), so that a bar ends only when the runs do.

    Raises
    ------
    SinsInputError
        as :func:`run_scenario`.
    """
    if len(units) != len(nav_seeds):
        raise ValueError(f"{len(units)} units but {len(nav_seeds)} navigation seeds")
    if not 0.0 < keep_hz < math.inf:  # 0 divided by zero, -1 kept every sample, NaN blamed the scenario
        raise ValueError(f"keep_hz {keep_hz!r}: expected a positive rate of kept samples, Hz")
    with input_errors(sc.source or sc.name):
        motion = scenario.build_motion(sc)
        keep_every = _keep_every(sc, motion, keep_hz)
        total = int(scenario.sample_count(sc, motion))
        first = trajectory.start_state(motion)
        chunks = _prefetched(_shared(sc, trajectory.generate_chunks(motion, sc.rate_hz)))
        pending = _Pending()  # one for all the units: they take the same rows, mostly at the same time
        driven = [
            _DrivenUnit(sc, unit, seed, first, keep_every, pending, sensor_errors)
            for unit, seed in zip(units, nav_seeds, strict=True)
        ]
        whole = _Simulated(first, total) if sc.aiding is not None else None  # for the aided runs
        # An aided run filters the whole recording after the stream: each counts as its samples again, so
        # that the bar does not stand at its end while the filters run (20 s for an aided hour).
        aided = sum(len(d.strategies) for d in driven) if whole is not None else 0
        work = total * (1 + aided)
        for truth, frame, ideal6, ideal, cabin in chunks:
            pending.add(frame, ideal6)
            if whole is not None:
                whole.add(truth, ideal)
            for d in driven:
                d.push(ideal, cabin)
            done = min(d.step.samples for d in driven)
            pending.release(done)
            if progress is not None:
                progress(done, work)
        for d in driven:
            d.finish()
        simulated = None if whole is None else whole.arrays()
        filtered = itertools.count(1)

        def one_filtered() -> None:
            if progress is not None:
                progress(total * (1 + next(filtered)), work)

        return [d.result(seed, simulated, one_filtered) for d, seed in zip(driven, nav_seeds, strict=True)]


def _shared(
    sc: Scenario, chunks: Iterator[tuple[NavSeries, ImuIncrements]]
) -> Iterator[tuple[NavSeries, TruthFrame, NDArray[np.float64], ImuIncrements, NDArray[np.float64]]]:
    """What every unit needs of each generated chunk, made once (on the prefetching thread): the truth
    as it is and as a frame (:class:`sins.nav.metrics.TruthFrame`), the ideal increments as (n, 6) and
    as they are, and the cabin temperature at their times."""
    for truth, ideal in chunks:
        yield truth, TruthFrame.of(truth), np.hstack([ideal.dtheta_b, ideal.dv_b]), ideal, _cabin(sc, ideal.t)


class _Simulated:
    """The generated truth and ideal IMU kept whole for the aided runs, written chunk by chunk into arrays
    made once (no chunk is held, no array copied when the stream ends): :func:`sins.nav.trajectory.generate`'s
    arrays, to the bit."""

    def __init__(self, first: NavSeries, intervals: int) -> None:
        n = intervals + 1
        self.t, self.lat, self.lon, self.h = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        self.v_n, self.q_nb = np.empty((n, 3)), np.empty((n, 4))
        self.dtheta_b, self.dv_b = np.empty((intervals, 3)), np.empty((intervals, 3))
        self.rows = 0
        self._put(first)

    def _put(self, truth: NavSeries) -> None:
        rows = slice(self.rows, self.rows + len(truth.t))
        self.t[rows], self.lat[rows], self.lon[rows], self.h[rows] = truth.t, truth.lat, truth.lon, truth.h
        self.v_n[rows], self.q_nb[rows] = truth.v_n, truth.q_nb
        self.rows = rows.stop

    def add(self, truth: NavSeries, ideal: ImuIncrements) -> None:
        """A generated chunk: the truth at ``ideal.t[1:]`` and the increments over its intervals."""
        self.dtheta_b[self.rows - 1 : self.rows - 1 + len(ideal)] = ideal.dtheta_b
        self.dv_b[self.rows - 1 : self.rows - 1 + len(ideal)] = ideal.dv_b
        self._put(truth)

    def arrays(self) -> tuple[NavSeries, ImuIncrements]:
        """The truth at every sample time and the ideal increments between them."""
        if self.rows != len(self.t):  # the sample count and the generated chunks disagree: a bug
            raise RuntimeError(f"{self.rows} of {len(self.t)} samples generated")
        truth = NavSeries(t=self.t, lat=self.lat, lon=self.lon, h=self.h, v_n=self.v_n, q_nb=self.q_nb)
        return truth, ImuIncrements(t=self.t, dtheta_b=self.dtheta_b, dv_b=self.dv_b)


class _IdealStream:
    """The ideal IMU as a unit's stream: each chunk's readings are its ideal increments, as they are."""

    def push(self, ideal: ImuIncrements, cabin: NDArray[np.float64]) -> ImuIncrements:
        """The chunk's readings: the ideal increments."""
        return ideal

    def finish(self) -> ImuIncrements:
        """Nothing held back."""
        return ImuIncrements(t=np.zeros(0), dtheta_b=np.zeros((0, 3)), dv_b=np.zeros((0, 3)))


class _DrivenUnit:
    """One unit's navigation power-on through a scenario (``unit`` None: the ideal IMU, the one strategy
    ``"none"`` taking its readings as they are): its stream, its strategies' runs."""

    def __init__(
        self,
        sc: Scenario,
        unit: FittedUnit | None,
        nav_seed: int,
        first: NavSeries,
        keep_every: int,
        pending: _Pending,
        sensor_errors: bool = True,
    ) -> None:
        from sins.imu.stream import IncrementStream

        self.sc, self.unit, self.keep_every = sc, unit, keep_every
        self.nav_model: ImuModel | None = None
        self.strategies: dict[str, Strategy | None] = {"none": None}
        self.stream: IncrementStream | _IdealStream = _IdealStream()
        if unit is not None:
            self.nav_model = nav_model = unit.spec.model(run_seed=nav_seed)
            self.strategies = dict(unit.for_run(nav_model))
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
            sensor_errors and unit is not None,
        )

    def push(self, ideal: ImuIncrements, cabin: NDArray[np.float64]) -> None:
        """A generated chunk (its truth already added to the units' pending rows): corrupt it, and
        correct and integrate what the stream writes."""
        self.step(self.stream.push(ideal, cabin))

    def finish(self) -> None:
        """The stream's last intervals."""
        self.step(self.stream.finish())

    def result(
        self,
        nav_seed: int,
        simulated: tuple[NavSeries, ImuIncrements] | None,
        filtered: Callable[[], None] | None = None,
    ) -> ScenarioRun:
        """The unit's runs, as :func:`run_scenario` gives them; ``simulated`` the scenario's whole truth
        and ideal IMU for its aided runs (None: the scenario has none), ``filtered()`` called as each
        aided run ends."""
        samples, keep_every = self.step.samples, self.keep_every
        last_truth = self.step.last_truth
        if samples % keep_every and last_truth is not None:
            self.truth_kept.append(last_truth)
        residuals = self.unit.residuals if self.unit is not None else {}
        out = {
            name: run.result(residuals.get(name), samples, keep_every, self.step.sensor_errors)
            for name, run in self.runs.items()
        }
        sensor_t = self.step.mid_t.means()[:, 0] if self.step.sensor_errors else None
        sc = dataclasses.replace(self.sc, imu_seed=nav_seed)
        aided = {}
        if simulated is not None:
            grade = self.unit.spec.grade if self.unit is not None else None
            aided = aided_runs(
                sc, self.strategies, *simulated, self.nav_model, grade, keep_every, filtered=filtered
            )
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
    truth: NavSeries,
    ideal: ImuIncrements,
    nav_model: ImuModel | None = None,
    grade: str | None = None,
    keep_every: int = 1,
    filtered: Callable[[], None] | None = None,
) -> dict[str, AidedRun]:
    """Each strategy's corrected stream navigated by the GNSS/INS filter (``[gnss]`` in the scenario).

    Whole arrays, not streamed: the unit reads ``ideal`` (its corruption of the whole array, equal to the
    streamed run's to the last bit), the receiver rides ``truth``, and the filter starts as
    ``[alignment]`` says (:func:`sins.aiding.policy.plan_alignment`: still, in motion from the GNSS
    velocity, or the truth's first state where the scenario says ``method = "truth"``). The filter is
    tuned to ``[gnss] filter_grade``, else to the IMU model's grade, else to the navigation grade.

    Parameters
    ----------
    sc : the scenario (``sc.aiding`` set)
    strategies : name -> the strategy that corrects the readings (None: take them as they are)
    truth, ideal : the scenario's truth and ideal IMU (:func:`simulate`'s)
    nav_model : the unit's error model for this run (None: the ideal IMU)
    grade : the IMU file's grade, if any
    keep_every : the display series keep every ``keep_every``-th sample (and the last)
    filtered : called as each strategy's filter ends (a progress bar's step)
    """
    from sins.aiding import ekf, gnss, policy  # the filter's imports (filterpy) only for aided runs

    a = sc.aiding
    assert a is not None
    temp = _cabin(sc, ideal.t)
    readings = ideal
    if nav_model is not None:
        readings = nav_model.corrupt_increments(ideal, temp, seed=sc.imu_seed, dt_nominal=1.0 / sc.rate_hz)
    fixes = gnss.simulate(truth, _receiver(a), seed=a.seed)
    filter_grade = a.filter_grade or grade or "navigation"
    config = ekf.FilterConfig.for_grade(filter_grade)
    plan = policy.plan_alignment(a, truth, config, str(sc.source or sc.name))
    true_bias = _true_bias(nav_model)
    keep = None
    out = {}
    for name, strategy in strategies.items():
        corrected = readings if strategy is None else strategy.correct_increments(readings, temp)
        result, k, heading_sigma = policy.run_aligned(plan, corrected, fixes, config, truth)
        ran = truth if k == 0 else truth.at(np.arange(k, len(truth.t)))
        errors = nav_errors(result.nav, ran)
        windows = outage_errors(a.outages, ran.t, errors.horizontal_m)
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
        if filtered is not None:
            filtered()
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
    where = str(sc.source or sc.name)
    motion = scenario.build_motion(sc)
    if scenario.sample_count(sc, motion) < 1:
        raise SinsInputError(
            f"{where}: the motion lasts {motion.t_end - motion.t_start:g} s, shorter than one sample"
        )
    a = sc.aiding
    if a is None:
        return
    # Here, not above: the filter's module imports filterpy and with it scipy.stats (~0.5 s), which a
    # campaign without [gnss] never needs.
    from sins.aiding import alignment, ekf, gnss, policy

    truth, ideal = simulate(sc)
    config = ekf.FilterConfig.for_grade(a.filter_grade or grade or "navigation")
    plan = policy.plan_alignment(a, truth, config, where)
    if plan.method == "gnss_velocity":
        fixes = gnss.simulate(truth, _receiver(a), seed=a.seed)
        motion_config = alignment.MotionConfig(
            min_speed_mps=a.min_speed_mps, sideslip_sigma_rad=a.sideslip_sigma_rad
        )
        try:
            alignment.in_motion_start(ideal, fixes, config, motion_config)
        except SinsInputError as exc:
            raise SinsInputError(f"{where}: {exc}") from None


def _true_bias(nav_model: ImuModel | None) -> NDArray[np.float64] | None:
    """The unit's constant gyro and accelerometer biases (6,), to set beside the filter's estimates: the
    constant parts ``b`` of its affine effects (:meth:`sins.imu.Effect.affine_terms`)."""
    if nav_model is None:
        return None
    return np.concatenate([_constant_bias(nav_model, sensor) for sensor in ("gyro", "accel")])


def _constant_bias(model: ImuModel, sensor: str) -> NDArray[np.float64]:
    out = np.zeros(3)
    for e in model.effects_of(sensor):
        if e.affine:
            out = out + e.affine_terms()[0]
    return out


def _keep_every(sc: Scenario, motion: Motion, keep_hz: float) -> int:
    """Every how many samples the thinned series keep one: about ``keep_hz``, and no more than
    :data:`MAX_KEPT` over the run (a 6-hour run keeps a sample every 0.6 s, not 2 million)."""
    samples = (motion.t_end - motion.t_start) * sc.rate_hz
    return max(1, round(sc.rate_hz / keep_hz), math.ceil(samples / MAX_KEPT))


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
    """Correct and integrate each chunk of a unit's readings with every strategy, in turn: the engine's
    one step."""

    sc: Scenario
    strategies: dict[str, Strategy | None]  # None: the readings as they are (the ideal IMU's)
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
            corrected = corrupted if strategy is None else strategy.correct_increments(corrupted, temp)
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


def _prefetched(items: Iterator[_T]) -> Iterator[_T]:
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


__all__ = [
    "DEFAULT_SCENARIO",
    "MAX_KEPT",
    "Progress",
    "aided_runs",
    "check_runnable",
    "resolve_scenario",
    "run_scenario",
    "run_units",
]
