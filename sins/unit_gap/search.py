"""The gap diagnosis on a reference's intervals: the greedy search of :mod:`sins.gap.diagnosis`, scored
on the residuals of integrated rotation and velocity change (:mod:`sins.unit_gap.intervals`).

The baseline is the seed model (bias, scale and misalignment, the gyro's g-sensitivity) fitted on the
intervals by :func:`sins.compensation.interval_fit.fit_intervals` (its linearisation point; no time
offsets and no lever arm: both are library effects, ``time_offset`` and ``size_effect``). Every library
effect whose class declares regression columns, and the time offsets, are candidates: each adds its
columns (built from the readings' own steps) to its sensor's least squares. The intervals are
withheld in blocks as samples are (the last ``holdout`` of every block of :data:`BLOCK_S`), each
candidate is fitted on the others and scored by its withheld gain less
:data:`~sins.gap.scoring.SIGNIFICANT_NATS` (:class:`~sins.unit_gap.fitter.SensorFit`: the noise that
shared epochs give the intervals whitened), and the one of greatest gain among those above it is
accepted, until none is. A bias step or an oscillation that explains a channel as well as the best
candidate, or that a random bias, the best, needs beside it, takes the channel
(:mod:`sins.unit_gap.outside`); candidates within
:data:`~sins.gap.scoring.TIE_NATS` of the accepted one are listed as indistinguishable.

Random biases and output maps (quantization, saturation) are effects of single readings: the intervals
say nothing of them, and the report names them as not fitted, with the reason.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from sins.compensation import interval_fit
from sins.compensation.interval_fit import IntervalFit
from sins.core.series import ReferencedRecording
from sins.gap.floor import SIGNIFICANT_RATIO, TINY, noise_level
from sins.gap.report import EffectScore, Outside
from sins.gap.scoring import SIGNIFICANT_NATS, TIE_NATS
from sins.imu import CHANNELS, Effect, vocabulary
from sins.unit_gap.clock import BOTH_SIGNS, one_clock
from sins.unit_gap.fitter import (
    INSTABILITY,
    NO_WANDER,
    RANDOM_WALK,
    SensorFit,
    chains,
    cross_gains,
    refit_allowance,
)
from sins.unit_gap.intervals import IntervalResiduals, interval_residuals
from sins.unit_gap.outside import Tried, beside_wander, explains_as_well, try_disturbances

Array = NDArray[np.float64]
Rows = NDArray[np.bool_]

#: Intervals are withheld at the end of blocks of this length, s: short beside a recording's kinds of
#: motion (a rest, a turn, a drive), so that every kind is both fitted and judged.
BLOCK_S = 10.0


@dataclass(frozen=True)
class Candidate:
    """A library effect on intervals: its columns for each of its sensor's axes, (k, 3, p) each; a
    random bias has none, and the wander ``phis`` its noise may take instead (see
    :mod:`sins.unit_gap.fitter`)."""

    name: str
    sensor: str
    per_axis: tuple[Array, Array, Array]
    phis: Array | None = None
    delay: bool = False  # a time offset: one column per axis, its coefficient the axis's delay

    def columns(self, axes: list[int]) -> Array:
        """Its columns on ``axes``, side by side."""
        return np.concatenate([self.per_axis[a] for a in axes], axis=2)


@dataclass
class SensorState:
    """A sensor's model as the search builds it: its fit, the accepted candidates and what they leave."""

    fit: SensorFit
    baseline: Array
    accepted: list[Candidate] = field(default_factory=list)
    aside: set[int] = field(default_factory=set)  # axes a disturbance outside the library explains
    phis: Array = field(default_factory=lambda: NO_WANDER)  # the wander its noise may take
    #: The disturbances set aside for their channels: their columns (k, 3, q), every component, and per
    #: step of the readings.
    disturbances: list[Tried] = field(default_factory=list)

    def columns(self, extra: Candidate | None = None) -> Array:
        """The baseline's and the accepted candidates' columns (and ``extra``'s), on the axes not set
        aside for a candidate, then the set-aside disturbances' own: an interval's residual is in the
        interval's turning axes, so a step on one axis shows on the others as the body turns (a 0.3 °/s
        gyro x step on EuRoC's MH_02 had y and z take a g² sensitivity 3× their own, and leave them
        unexplained)."""
        axes = [a for a in range(3) if a not in self.aside]
        blocks = [self.baseline] + [c.columns(axes) for c in self.accepted]
        if extra is not None:
            blocks.append(extra.columns(axes))
        return np.concatenate(blocks + [t.columns for t in self.disturbances], axis=2)


@dataclass(frozen=True)
class Trial:
    """A candidate fitted beside its sensor's model: the withheld gain of each component, and what a
    random bias may gain by chance beyond :data:`~sins.gap.scoring.SIGNIFICANT_NATS`
    (:func:`~sins.unit_gap.fitter.refit_allowance`)."""

    candidate: Candidate
    gains: Array
    allowance: float = 0.0
    fit_scores: Array | None = None  # a random bias's: per component, fit log-likelihood less BIC's penalty
    both_signs: bool = False  # a delay whose axes are late by delays of both signs: no one clock's

    def gain(self, aside: set[int]) -> float:
        """The gain over the components not set aside."""
        return float(sum(g for a, g in enumerate(self.gains) if a not in aside))

    def score(self, aside: set[int]) -> float:
        """The gain beyond what it needs: accepted above 0."""
        return self.gain(aside) - SIGNIFICANT_NATS - self.allowance


@dataclass(frozen=True)
class IntervalDiagnosis:
    """What the search on intervals found, for :mod:`sins.unit_gap.report`."""

    residuals: IntervalResiduals
    baseline: IntervalFit
    states: dict[str, SensorState]
    before: dict[str, Array]  # what the baseline leaves, (k, 3)
    after: dict[str, Array]  # what the accepted effects leave: a random bias's one-step predictions too
    left: dict[str, Array]  # what the accepted regressors leave (a random bias's path in it): the floor's
    effects: list[EffectScore]
    diagnosis: list[str]
    outside: list[Outside]
    sizes: dict[str, dict[str, list[float]]]  # accepted effect -> channel -> its coefficients, SI
    fit: Rows
    withheld: Rows
    #: Per sensor, the disturbances found on the channels the library leaves (:func:`_leftover`).
    leftover: dict[str, list[Tried]] = field(default_factory=dict)


def withheld_intervals(t_mid: Array, holdout: float, block_s: float = BLOCK_S) -> Rows:
    """The intervals withheld: the last ``holdout`` of each block of ``block_s`` (at least one each
    way in a block of two or more)."""
    block = np.floor((t_mid - t_mid[0]) / block_s).astype(int)
    out = np.zeros(len(t_mid), dtype=bool)
    for b in np.unique(block):
        rows = np.flatnonzero(block == b)
        held = min(max(int(np.floor(holdout * len(rows) + 0.5)), 1), len(rows) - 1) if len(rows) > 1 else 0
        out[rows[len(rows) - held :]] = True
    return out


def baseline_fit(rec: ReferencedRecording, interval_s: float) -> IntervalFit:
    """The seed model fitted on the intervals (:func:`sins.compensation.interval_fit.fit_intervals`,
    no time offsets), the gyro's g-sensitivity kept only where it predicts intervals it was not fitted
    on (the compensation fit's own rule: a recording whose rests all face one way cannot tell it from
    the bias, and a K fitted on its noise corrects another recording wrongly; ``g_sensitivity`` says
    which).

    Raises
    ------
    ValueError
        as :func:`~sins.compensation.interval_fit.fit_intervals`, without the g-sensitivity too.
    """
    try:
        return interval_fit.fit_intervals(rec, interval_s=interval_s, time_offset=False, g_sensitivity="auto")
    except ValueError:
        return interval_fit.fit_intervals(rec, interval_s=interval_s, time_offset=False, g_sensitivity=False)


def candidates(res: IntervalResiduals) -> list[Candidate]:
    """Every library effect the intervals can judge: regression columns (those that need a temperature
    only with one), the time offsets, and the random biases as a wander of the intervals' noise."""
    none = np.zeros((len(res.iv), 3, 0))
    out = [
        Candidate(f"{sensor}.{kind}", sensor, (none, none, none), phis)
        for sensor in ("gyro", "accel")
        for kind, phis in (("bias_instability", INSTABILITY), ("rate_random_walk", RANDOM_WALK))
    ]
    for name, cls in _with_columns():
        if cls.needs_temp and res.steps.temp_offset is None:
            continue
        sensor = name.split(".")[0]
        per_axis = tuple(res.columns(sensor, _effect_steps(res, cls, sensor, a), a) for a in range(3))
        out.append(Candidate(name, sensor, per_axis, delay=cls.candidate == "delay"))  # type: ignore[arg-type]
    return out


def _with_columns() -> list[tuple[str, type[Effect]]]:
    """The library's effects with columns on intervals: regressors and delays."""
    return vocabulary.effects_where(lambda t: t.candidate in ("regressors", "delay"))


def step_columns(res: IntervalResiduals, name: str, axis: int) -> Array:
    """(n, p): the error per step of the readings, one column a coefficient, that library effect
    ``name`` makes on axis ``axis`` (its candidate's columns are these moved into the residuals): a
    regressor's own columns, a delay's ``-τ`` times the reading's rate of change. Made again where
    needed rather than kept: a long recording's steps times every candidate's columns."""
    return _effect_steps(res, dict(_with_columns())[name], name.split(".")[0], axis)


def _effect_steps(res: IntervalResiduals, cls: type[Effect], sensor: str, axis: int) -> Array:
    """:func:`step_columns` of effect class ``cls`` on ``sensor``, the class at hand (:func:`candidates`
    looks each up once, not once an axis)."""
    if cls.candidate == "delay":
        return res.delay_steps(sensor, axis)
    return np.asarray(cls.columns(res.steps, sensor, axis), dtype=float)


def not_on_intervals() -> dict[str, str]:
    """The library's candidates the intervals say nothing of, with the reason."""
    return {
        name: "an effect of single readings: judged on samples, not on intervals (--statistic samples)"
        for name, _ in vocabulary.effects_where(lambda t: t.candidate == "output")
    }


def diagnose_intervals(
    rec: ReferencedRecording,
    holdout: float = 0.3,
    interval_s: float = 1.0,
    progress: Callable[[str], None] | None = None,
    baseline: IntervalFit | None = None,
    sensors: tuple[str, ...] = ("gyro", "accel"),
) -> IntervalDiagnosis:
    """The gap diagnosis of ``rec`` on its reference's intervals (see the module docstring);
    ``baseline``: :func:`baseline_fit`'s, if the caller has it; ``sensors``: those searched (each
    sensor's search is its own; the others keep their baseline).

    Raises
    ------
    ValueError
        where the intervals cannot be formed or fitted (too few, too little turning).
    """
    baseline = baseline or baseline_fit(rec, interval_s)
    res = interval_residuals(rec, baseline.seed, interval_s)
    withheld = withheld_intervals(res.t_mid, holdout)
    fit = ~withheld
    states = {}
    for sensor in ("gyro", "accel"):
        base = res.baseline(sensor, baseline.g_sensitivity)
        states[sensor] = SensorState(
            SensorFit.of(res.residual[sensor], fit, withheld, res.joined, base), base
        )
    before = {s: st.fit.solve(st.columns())[1] for s, st in states.items()}
    remaining = [c for c in candidates(res) if c.sensor in sensors]
    scores: dict[str, EffectScore] = {}
    accepted: list[str] = []
    outside: list[Outside] = []
    while remaining:
        trials = _round(states, remaining, progress)
        for t in trials:
            aside = states[t.candidate.sensor].aside
            scores[t.candidate.name] = EffectScore(
                t.candidate.name, _names(t.candidate.sensor, aside), t.score(aside), False
            )
        for t in trials:
            if t.both_signs and scores[t.candidate.name].score > 0.0:
                scores[t.candidate.name] = dataclasses.replace(
                    scores[t.candidate.name], not_accepted_because=BOTH_SIGNS
                )
        positive = [t for t in trials if t.score(states[t.candidate.sensor].aside) > 0.0 and not t.both_signs]
        if not positive:
            break
        best = max(positive, key=lambda t: t.gain(states[t.candidate.sensor].aside))
        found = _set_aside(states[best.candidate.sensor], res, best)
        if found:
            outside += found
            continue
        _accept(states, best, trials, scores, accepted)
        taken = best.candidate
        bias = taken.phis is not None  # a sensor takes one random bias
        remaining = [
            c
            for c in remaining
            if c.name != taken.name and not (bias and c.phis is not None and c.sensor == taken.sensor)
        ]
    leftover = _leftover({s: states[s] for s in sensors}, res)
    outside += [t.outside for found in leftover.values() for t in found]
    left = {s: st.fit.solve(st.columns())[1] for s, st in states.items()}
    after = {s: _predicted_away(st, left[s]) for s, st in states.items()}
    ordered = [scores[n] for n in accepted] + sorted(
        (e for n, e in scores.items() if n not in accepted), key=lambda e: -e.score
    )
    return IntervalDiagnosis(
        res, baseline, states, before, after, left, ordered, accepted,
        sorted(outside, key=lambda o: CHANNELS.index(o.channel)), _sizes(states, float(np.median(res.span))),
        fit, withheld, leftover,
    )  # fmt: skip


def _predicted_away(st: SensorState, left: Array) -> Array:
    """What a sensor's accepted effects leave of the intervals (k, 3): the regressors' residual ``left``
    less, where a random bias was accepted, its one-step prediction from the intervals before (the
    noise's innovations, in its units), as on samples (:mod:`sins.gap.channel`): what the bias was
    accepted for. Without one, ``left`` itself."""
    if not any(c.phis is not None for c in st.accepted):
        return left
    return st.fit.raw_innovations(left)


def _names(sensor: str, aside: set[int]) -> tuple[str, ...]:
    return tuple(f"{sensor}.{'xyz'[a]}" for a in range(3) if a not in aside)


def _round(
    states: dict[str, SensorState], remaining: list[Candidate], progress: Callable[[str], None] | None
) -> list[Trial]:
    """Every remaining candidate fitted beside its sensor's model."""
    trials = []
    for cand in remaining:
        if progress:
            progress(cand.name)
        st = states[cand.sensor]
        if len(st.aside) == 3:
            continue
        _, before = st.fit.solve(st.columns())
        if cand.phis is not None:  # a random bias: the same columns, the noise with its wander
            fit = st.fit
            wandering = SensorFit.of(fit.y, fit.fit, fit.withheld, fit.joined, st.columns(), cand.phis)
            _, after = wandering.solve(st.columns())
            allowance = refit_allowance(fit, st.columns(), SIGNIFICANT_NATS)
            scores = wandering.fit_loglik(after) - fit.bic_penalty(1)  # its one more parameter, φ
            trials.append(Trial(cand, cross_gains(fit, before, wandering, after), allowance, scores))
            continue
        coef, after = st.fit.solve(st.columns(cand))
        trials.append(Trial(cand, st.fit.gains(before, after), both_signs=_both_signs(st, cand, coef)))
    return trials


def _both_signs(st: SensorState, cand: Candidate, coef: Array) -> bool:
    """Whether ``cand``, a delay fitted beside ``st``'s model (``coef``, the columns of
    :meth:`SensorState.columns` with it), makes its sensor's axes late by delays no one clock gives
    (:func:`sins.unit_gap.clock.one_clock`; with 5 ms added to EuRoC's eleven sequences and BROAD's two
    trials, every delay accepted had one sign, 1.8-13 ms)."""
    if not cand.delay:
        return False
    axes = [a for a in range(3) if a not in st.aside]
    at = st.baseline.shape[2] + sum(c.columns(axes).shape[2] for c in st.accepted)
    return not one_clock({f"{cand.sensor}.{'xyz'[a]}": float(coef[at + i]) for i, a in enumerate(axes)})


def _set_aside(st: SensorState, res: IntervalResiduals, best: Trial) -> list[Outside]:
    """The channels of ``best``'s sensor where a disturbance outside the library explains as much as
    ``best`` does; they are set aside (no candidate is fitted there again)."""
    current = st.columns()
    _, left = st.fit.solve(current)
    found = []
    for axis in range(3):
        if axis in st.aside or best.gains[axis] <= 0.0:
            continue
        tried = try_disturbances(st.fit, res, best.candidate.sensor, axis, current, left)
        fit_score = None if best.fit_scores is None else float(best.fit_scores[axis])
        disturbance = explains_as_well(tried, float(best.gains[axis]), fit_score)
        if disturbance is None and fit_score is not None and best.candidate.phis is not None:
            disturbance = beside_wander(st.fit, current, tried, axis, best.candidate.phis, fit_score)
        if disturbance is not None:
            found.append(disturbance)
            st.aside.add(axis)
            st.disturbances.append(next(t for t in tried if t.outside is disturbance))
    if found:  # the noise is the model's, as when an effect is accepted (_accept)
        st.fit = SensorFit.of(st.fit.y, st.fit.fit, st.fit.withheld, st.fit.joined, st.columns(), st.phis)
    return found


def _accept(
    states: dict[str, SensorState], best: Trial, trials: list[Trial], scores: dict[str, EffectScore],
    accepted: list[str],
) -> None:  # fmt: skip
    """Take ``best`` into its sensor's model; note those this data cannot tell from it."""
    name = best.candidate.name
    aside = states[best.candidate.sensor].aside
    ties = tuple(
        t.candidate.name
        for t in trials
        if t.candidate.name != name
        and t.candidate.sensor == best.candidate.sensor
        and abs(t.gain(aside) - best.gain(aside)) < TIE_NATS
    )
    scores[name] = dataclasses.replace(scores[name], accepted=True, indistinguishable=ties)
    for tie in ties:
        scores[tie] = dataclasses.replace(
            scores[tie], not_accepted_because=f"this data cannot tell it from {name}, which was taken"
        )
    st = states[best.candidate.sensor]
    st.accepted.append(best.candidate)
    if best.candidate.phis is not None:
        st.phis = best.candidate.phis
    # The noise is the model's: what the accepted effect explained is no longer the noise's to whiten.
    st.fit = SensorFit.of(st.fit.y, st.fit.fit, st.fit.withheld, st.fit.joined, st.columns(), st.phis)
    accepted.append(name)


def _leftover(states: dict[str, SensorState], res: IntervalResiduals) -> dict[str, list[Tried]]:
    """Per sensor, a step or an oscillation significant on a channel the library leaves: a gap all the
    same."""
    out: dict[str, list[Tried]] = {}
    for sensor, st in states.items():
        current = st.columns()
        _, left = st.fit.solve(current)
        for axis in range(3):
            if axis in st.aside:
                continue
            tried: list[Tried] = try_disturbances(st.fit, res, sensor, axis, current, left)
            found = explains_as_well(tried, 0.0)
            if found is not None:
                out.setdefault(sensor, []).append(next(t for t in tried if t.outside is found))
    return out


def _sizes(states: dict[str, SensorState], span: float) -> dict[str, dict[str, list[float]]]:
    """Each accepted effect's fitted coefficients per channel, SI (the columns' own, in the order the
    effect's class gives them; a random bias's correlation time, s, its intervals ``span`` s long)."""
    out: dict[str, dict[str, list[float]]] = {}
    for sensor, st in states.items():
        coef, _ = st.fit.solve(st.columns())
        at = st.baseline.shape[2]
        axes = [a for a in range(3) if a not in st.aside]
        for cand in st.accepted:
            out[cand.name] = {}
            if cand.phis is not None:  # a random bias: its parameters, from the intervals' noise model
                walk = cand.name.endswith("rate_random_walk")  # fitted at φ = 0.995: read as a walk
                out[cand.name] = {f"{sensor}.{'xyz'[a]}": _process_size(st.fit, a, span, walk) for a in axes}
                continue
            for a in axes:
                width = cand.per_axis[a].shape[2]
                out[cand.name][f"{sensor}.{'xyz'[a]}"] = [float(v) for v in coef[at : at + width]]
                at += width
    return out


def _process_size(fit: SensorFit, axis: int, span: float, walk: bool = False) -> list[float]:
    """A random bias's parameters from the intervals' noise model on component ``axis``: ``(1 − φB) y =
    (1 + θB) a``, ``a`` of spread σ, read as the bias over an interval of ``span`` s (``y = T b + n``, ``n``
    white) that moves as ``b' = φ b + w``. Matching the two sides' autocovariances, ``T² var(w) = σ²
    (1 + θ² + θ (1 + φ²) / φ)``: a Gauss–Markov bias's stationary σ = √(var(w) / (1 − φ²)) and correlation
    time τ = −T / ln φ; a walk's (φ = 1; the bias averaged over each interval) density σ (1 + θ) / T^1.5
    (the library's parameters, :func:`sins.gap.randombias.sizes`' on samples). ``walk``: the candidate is
    a walk, fitted at φ just below 1 (:data:`~sins.unit_gap.fitter.RANDOM_WALK`) to keep its model
    stationary: its density (read as a Gauss-Markov σ and τ, its τ of 200 s had been shown as a density of
    2.5e9 °/h/√h)."""
    phi, theta, sigma = float(fit.phi[axis]), float(fit.theta[axis]), float(fit.sigma[axis])
    if phi >= 1.0 or walk:
        return [max(sigma * (1.0 + theta), 0.0) / span**1.5]
    if not phi > 0.0:
        return [0.0, float("inf")]
    drive = max(sigma**2 * (1.0 + theta**2 + theta * (1.0 + phi**2) / phi), 0.0) / span**2
    return [float(np.sqrt(drive / (1.0 - phi**2))), float(-span / np.log(phi))]


def interval_noise_level(residual: Array, joined: Rows) -> float:
    """:func:`~sins.gap.floor.noise_level` of an interval residual (k,) over every chain of joined
    intervals, fit and withheld alike: the withheld blocks alone hold one triple of neighbours each,
    too few to measure a lag-one correlation."""
    d0, d1, n0, n1 = 0.0, 0.0, 0, 0
    for a, b in chains(joined):
        d = np.diff(residual[a:b])
        d0, n0 = d0 + float(np.sum(d * d)), n0 + len(d)
        d1, n1 = d1 + float(np.sum(d[1:] * d[:-1])), n1 + max(len(d) - 1, 0)
    if n1 == 0 or d0 / n0 + d1 / n1 <= 0.0:
        return noise_level(residual)
    return float(np.sqrt(d0 / n0 + d1 / n1))


def significant_ratio(withheld: int) -> float:
    """The RMS over ``withheld`` intervals against the floor beyond which a channel is above it:
    :data:`~sins.gap.floor.SIGNIFICANT_RATIO`, or two standard errors of an RMS of that many values
    (``1 + 2/√(2m)``) where that is larger: 1.21 for a 150 s recording's 45 withheld intervals, whose
    RMS a clean recording's (``tests/numpy_unit_gap.py``) spread from 0.94 to 1.19 of its floor."""
    return max(SIGNIFICANT_RATIO, 1.0 + 2.0 / np.sqrt(2.0 * max(withheld, 1)))


def channel_figures(d: IntervalDiagnosis) -> tuple[dict[str, dict[str, float]], list[str]]:
    """Per channel, the withheld RMS before and after the accepted effects and the noise floor, as
    mean rates over the intervals (rad/s, m/s²); and the channels left unexplained (above the floor by
    :func:`significant_ratio`, or taken by a disturbance outside the library, or where a delay of both
    signs predicts the withheld intervals: :data:`BOTH_SIGNS`)."""
    span = float(np.median(d.residuals.span))
    ratio = significant_ratio(int(d.withheld.sum()))
    figures, unexplained = {}, []
    disturbed = {o.channel for o in d.outside} | {
        ch for e in d.effects if e.score > 0.0 and e.not_accepted_because == BOTH_SIGNS for ch in e.channels
    }
    for sensor in ("gyro", "accel"):
        for a in range(3):
            ch = f"{sensor}.{'xyz'[a]}"
            before, after = d.before[sensor][:, a], d.after[sensor][:, a]
            floor = max(interval_noise_level(d.left[sensor][:, a], d.residuals.joined), TINY) / span
            rms_after = float(np.sqrt(np.mean(after[d.withheld] ** 2))) / span
            figures[ch] = {
                "rms_before": float(np.sqrt(np.mean(before[d.withheld] ** 2))) / span,
                "rms_after": rms_after,
                "noise_floor": floor,
            }
            if rms_after > ratio * floor or ch in disturbed:
                unexplained.append(ch)
    return figures, unexplained


__all__ = [
    "BLOCK_S",
    "Candidate",
    "IntervalDiagnosis",
    "SensorState",
    "Trial",
    "baseline_fit",
    "candidates",
    "channel_figures",
    "diagnose_intervals",
    "interval_noise_level",
    "not_on_intervals",
    "significant_ratio",
    "step_columns",
    "withheld_intervals",
]
