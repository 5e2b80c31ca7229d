"""Sim-to-real gap diagnosis: where simulated and real IMU data part, which unmodelled effect causes it.

The model of a channel's reading error ``e = reading − reference`` is the baseline (the seed model's
bias, scale/misalignment and g-sensitivity rows, fitted by least squares, plus white noise) and any
effects accepted so far. Every library effect not in the model is a candidate
(:mod:`sins.gap.candidates`): regressor columns, a delay, a random bias or an output map, each held
and fitted in the channel's model as :mod:`sins.gap.channel` describes. Each candidate is fitted on the
fit rows and scored on the withheld rows by its log-likelihood gain over the current model, less a
significance threshold (:mod:`sins.gap.scoring`). Candidates are accepted greedily, the one of
greatest gain among those whose score is positive, until none is; guards keep a library effect from
taking credit for a disturbance outside the library or for a rival it cannot be told from
(:mod:`sins.gap.guards`). Where the gap lies is told against each channel's noise floor
(:mod:`sins.gap.floor`), and the findings make a :class:`~sins.gap.report.GapReport`.

:func:`diagnose` runs it in stages: the input checks (:func:`_check`); the session's rows, fit and
withheld, and their reference inputs (:func:`_session`); the model of every channel before any
candidate, and its noise floor (:func:`_starting_models`, :func:`_floors`); the greedy search
(:func:`_search`: :func:`_score_round` tries every candidate left, :func:`_set_aside` gives channels
to a disturbance outside the library, :func:`_accept` takes the best); the channels whose leftover a
disturbance explains (:func:`_leftover_disturbances`); where the gap lies (:func:`_where`); and the
report (:func:`_report`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from threadpoolctl import threadpool_limits

from sins.core.series import STRETCH_LONGEST_S, CalibrationData
from sins.errors import SinsInputError
from sins.gap import lattice
from sins.gap.candidates import CANDIDATES, Candidate, ReferenceInputs, processes, reference_inputs
from sins.gap.channel import ChannelModel
from sins.gap.design import release_free_memory
from sins.gap.floor import (
    FLOOR_DROP,
    SIGNIFICANT_RATIO,
    TINY,
    allan_curves,
    concentrates,
    input_features,
    noise_level,
    quartile_shares,
)
from sins.gap.guards import (
    Choice,
    available,
    exclusive,
    nested_choice,
    outside_library,
    process_or_regressors,
)
from sins.gap.report import EffectScore, GapReport, Outside
from sins.gap.scoring import TIE_NATS, ChannelTrial, Trial, refit_allowance, trial_gain
from sins.imu import BASELINE, CHANNELS, effect_names

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class _Session:
    """What every stage reads: the referenced rows, their split, reference inputs and readings."""

    data: CalibrationData  # the rows with a per-sample reference
    all_rows: int  # before the unreferenced ones were left out
    x: ReferenceInputs
    fit: NDArray[np.bool_]
    withheld: NDArray[np.bool_]
    printed: lattice.Printed  # how the recording's numbers were printed
    withholding: str  # which rows were withheld, and why, in words

    @property
    def n_fit(self) -> int:
        return int(self.fit.sum())

    def readings(self, sensor: str) -> Array:
        """The readings of ``sensor``'s three channels, (n, 3)."""
        return self.data.gyro if sensor == "gyro" else self.data.accel

    def residuals(self, predicted: Array) -> Iterator[Array]:
        """Each channel's residual, reading − reference − ``predicted`` (n, 6), one at a time: six
        of them at once would be as large as the recording's readings."""
        for i, ch in enumerate(CHANNELS):
            sensor, axis = ch.split(".")[0], i % 3
            yield self.readings(sensor)[:, axis] - self.x.of(sensor)[:, axis] - predicted[:, i]


@dataclass
class _Search:
    """The greedy search's state, round to round."""

    models: list[ChannelModel]  # every channel's current model, fitted
    remaining: list[Candidate]  # the candidates still to try
    accepted: list[str] = field(default_factory=list)
    scores: dict[str, EffectScore] = field(default_factory=dict)
    why_not: dict[str, str] = field(default_factory=dict)  # why a candidate scored above 0 was passed over
    outside: list[Outside] = field(default_factory=list)
    outside_channels: set[str] = field(default_factory=set)  # of ``outside``, kept beside it
    unfitted: dict[str, str] = field(default_factory=dict)  # candidates only the withheld rows excite
    #: Each accepted effect's channels, and where a regressor effect's block sits in their columns.
    blocks: dict[str, dict[int, int]] = field(default_factory=dict)


def diagnose(
    data: CalibrationData,
    holdout: float = 0.3,
    model: tuple[str, ...] = BASELINE,
    progress: Callable[[str], None] | None = None,
    candidates: tuple[str, ...] | None = None,
) -> GapReport:
    """Find where the model fails on withheld data, which effects explain it, how far they do.

    Parameters
    ----------
    data : readings beside reference inputs (a rig recording, or an IMU recording with its truth)
    holdout : the fraction withheld: the last part of every phase (of the whole recording without phases)
    model : the effect names of the simulation's model; the baseline's are always in it, and any other
        is fitted from the start and is no candidate
    progress : called with each candidate's name as it is scored
    candidates : the candidates to try (default: every one the model does not hold); a search so
        narrowed tries no disturbance outside the library either (what it is asked is whether these
        effects are there, not what else is)

    Returns
    -------
    GapReport
    """
    _check(data, holdout, model)
    unknown = [n for n in candidates or () if n not in CANDIDATES]
    if unknown:
        raise ValueError(f"candidates: {unknown[0]!r} is not a candidate effect")
    # One BLAS thread: the factors are of a few columns, and OpenBLAS's threads spin on them (2.5
    # times the CPU, 1.7 times the wall time of a 200,000-row diagnosis on two shared cores).
    with threadpool_limits(limits=1, user_api="blas"):
        s = _session(data, holdout)
        models, before = _starting_models(s, model)
        floors = _floors(s, before, models)
        taken = set().union(*(exclusive(n) for n in model))
        tried = [c for c in CANDIDATES.values() if c.name not in taken]
        if candidates is not None:
            tried = [c for c in tried if c.name in candidates]
        state = _search(s, models, tried, progress)
        del models
        outside = _leftover_disturbances(s, state) if candidates is None else []
        return _report(s, model, state, outside, before, floors)


def _check(data: CalibrationData, holdout: float, model: tuple[str, ...]) -> None:
    """Refuse what cannot be diagnosed: non-finite readings or temperatures, a withheld fraction
    outside (0, 1), fewer than 200 referenced rows, an unknown effect in ``model``."""
    where = data.source or "recording"
    for name in ("gyro", "accel"):
        a = getattr(data, name)
        if not np.isfinite(a).all():
            row = int(np.flatnonzero(~np.isfinite(a).all(axis=1))[0])
            raise SinsInputError(f"{where}: NaN or infinite {name} reading at row {row}")
    if data.temp is not None and not np.isfinite(data.temp).all():
        row = int(np.flatnonzero(~np.isfinite(data.temp))[0])
        raise SinsInputError(f"{where}: NaN or infinite temperature at row {row}")
    if not 0.0 < holdout < 1.0:
        raise SinsInputError(f"{where}: the withheld fraction must be in (0, 1), got {holdout}")
    n = int(data.has_reference.sum())
    if n < 200:
        with_ref = " with a per-sample reference" if n < len(data) else ""
        raise SinsInputError(f"{where}: too short to split ({n} rows{with_ref}; at least 200 are needed)")
    unknown = [n for n in model if n not in effect_names()]
    if unknown:
        raise SinsInputError(f"model: unknown effect {unknown[0]!r} (see `sins effects`)")


def _session(data: CalibrationData, holdout: float) -> _Session:
    """The referenced rows (a hand-turned rotation's, without a per-sample reference, say nothing),
    split into fit and withheld rows, with their reference inputs and readings.

    The end of every phase is withheld; a recording without phases, the end of every stretch of like
    input (:meth:`~sins.core.series.CalibrationData.stretches`): its tail alone may hold the only minutes
    of some input (a table's top rate, a mount), which the fit rows would then never see.
    """
    referenced = data.rows_with_reference()
    withheld = referenced.held_back(holdout, like_input=True)
    if referenced.phases:
        withholding = f"the last {holdout:g} of each of its {len(referenced.phases)} phases"
    else:
        withholding = (
            f"the last {holdout:g} of each of {len(referenced.stretches())} stretches of like input "
            "(holds, steady rates, motion cut in blocks of at most "
            f"{STRETCH_LONGEST_S:g} s), as it has no phases"
        )
    return _Session(
        data=referenced,
        all_rows=len(data),
        x=reference_inputs(referenced),
        fit=~withheld,
        withheld=withheld,
        printed=lattice.print_habit(
            referenced.gyro, referenced.accel, referenced.ref_gyro, referenced.ref_accel
        ),
        withholding=withholding,
    )


def _starting_models(s: _Session, model: tuple[str, ...]) -> tuple[list[ChannelModel], Array]:
    """Every channel's model before any candidate, fitted: the baseline and the simulation's other
    effects, whose random bias, if any, is taken as given (not held to the candidates' tests); and
    their predicted errors (n, 6), which the models hold as views (one copy of them, not two)."""
    models = [
        ChannelModel.baseline(
            s.x,
            ch.split(".")[0],
            i % 3,
            s.readings(ch.split(".")[0])[:, i % 3],
            s.fit,
            s.printed,
        )
        for i, ch in enumerate(CHANNELS)
    ]
    for name in model:
        if name in CANDIDATES:
            cand = CANDIDATES[name]
            for i, ch in enumerate(CHANNELS):
                if ch.startswith(cand.sensor):
                    models[i] = models[i].with_candidate(cand, on_trial=False)
    predicted = np.empty((len(s.data), 6))
    for i, m in enumerate(models):
        m = m.fitted()
        assert m.predicted is not None
        predicted[:, i] = m.predicted
        models[i] = dataclasses.replace(m, predicted=predicted[:, i])
    return models, predicted


def _floors(s: _Session, predicted: Array, models: list[ChannelModel]) -> Array:
    """Each channel's noise floor under the ``predicted`` errors (n, 6): the withheld rows' noise
    level (:func:`~sins.gap.floor.noise_level`), which their RMS is set against; on a lattice, the
    larger of the fit rows' and the withheld rows'.

    A unit's noise need not be the same all through a recording (a vehicle's vibration follows its
    speed: 0.0165 and 0.0134 m/s² in the fit and withheld rows of the PSINS drive's accel.x), so the
    withheld RMS is set against the withheld rows' own. Where the noise is rounding's, its level
    depends on where each hold's mean sits in its lattice cell, and a portion may see no reading
    change: there both portions measure it, and the larger is taken.
    """
    out = []
    for r, m in zip(s.residuals(predicted), models, strict=True):
        level = noise_level(r, s.withheld)
        if m.lattice is not None:
            level = max(level, noise_level(r, s.fit))
        out.append(max(level, TINY))
    return np.array(out)


def _search(
    s: _Session,
    models: list[ChannelModel],
    remaining: list[Candidate],
    progress: Callable[[str], None] | None,
) -> _Search:
    """The greedy search: each round, every candidate left is scored; of those whose score is above
    0, the one that explains the withheld rows best is accepted (or the channels it would take are
    set aside for a disturbance outside the library), until none scores above 0."""
    state = _Search(models=list(models), remaining=remaining)
    while state.remaining:
        trials = _score_round(s, state, progress)
        for name, trial in trials.items():
            state.scores[name] = EffectScore(name, trial.names, trial.score, False)
            state.why_not.pop(name, None)
        positive = [n for n in trials if trials[n].score > 0.0]
        if not positive:
            break
        # Significance is each candidate's own test; of those that pass, the one that explains the
        # withheld rows best: a random bias's allowance is no evidence against it.
        best = max(positive, key=lambda n: trials[n].gain)
        choice = process_or_regressors(nested_choice(best, trials), trials)
        if not _set_aside(s, state, choice[0], trials):
            _accept(state, choice, trials)
    return state


def _score_round(s: _Session, state: _Search, progress: Callable[[str], None] | None) -> dict[str, Trial]:
    """Every remaining candidate the data can say something of, tried on its sensor's channels."""
    trials: dict[str, Trial] = {}
    for cand in state.remaining:
        if progress:
            progress(cand.name)
        channels = [i for i, ch in enumerate(CHANNELS) if ch.startswith(cand.sensor)]
        if not available(cand, s.x, s.readings(cand.sensor), s.fit):
            if available(cand, s.x, s.readings(cand.sensor), np.ones_like(s.fit)):
                state.unfitted[cand.name] = "only the withheld rows excite it: the fit rows cannot fit it"
            continue
        trial = _trial(s, state, cand, channels)
        if trial is not None:
            trials[cand.name] = trial
    return trials


def _trial(s: _Session, state: _Search, cand: Candidate, channels: list[int]) -> Trial | None:
    """``cand`` tried on each of ``channels`` it may apply to (None if on none): beside the current
    model of a channel no disturbance outside the library explains, and, for quantization, whose
    readings lie on a lattice."""
    rows = []
    for i in channels:
        if CHANNELS[i] in state.outside_channels:
            continue  # explained by a disturbance outside the library: nothing to add there
        current = state.models[i]
        if cand.name.endswith("quantization") and current.lattice is None:
            continue
        release_free_memory()  # what the last fit freed, before the next one's
        m = current.tried(cand)
        gain, penalty = trial_gain(current, m, s.withheld, s.n_fit)
        rows.append(ChannelTrial(i, gain, penalty, m.fit_rows_loglik()))
    if not rows:
        return None
    tried = [state.models[row.channel] for row in rows]
    allowance = refit_allowance(tried, s.withheld) if cand.kind == "process" else 0.0
    return Trial(tuple(rows), allowance)


def _set_aside(s: _Session, state: _Search, best: str, trials: dict[str, Trial]) -> bool:
    """Whether disturbances outside the library explain some of ``best``'s channels as well as it
    does; if so, those channels are set aside (no candidate is tried there again) and the round is
    scored again without them."""
    process = CANDIDATES[best].kind == "process"
    disturbances = outside_library(trials[best], process, state.models, s.withheld, s.n_fit)
    if not disturbances:
        return False
    state.outside += disturbances
    state.outside_channels |= {o.channel for o in disturbances}
    for name in trials:
        if set(state.scores[name].channels) <= state.outside_channels:
            state.why_not[name] = "a disturbance outside the library explains its channels as well"
    return True


def _accept(state: _Search, choice: Choice, trials: dict[str, Trial]) -> None:
    """Take the chosen candidate into its channels' models; note why its rivals were not taken."""
    best, told_apart, alike = choice
    ties = alike + tuple(
        n
        for n, trial in trials.items()
        if n not in (best, *told_apart, *alike) and abs(trial.gain - trials[best].gain) < TIE_NATS
    )
    state.accepted.append(best)
    state.scores[best] = dataclasses.replace(state.scores[best], accepted=True, indistinguishable=ties)
    for name in told_apart:
        state.why_not[name] = f"the fit rows' likelihood prefers {best}"
    for name in ties:
        state.why_not[name] = f"this data cannot tell it from {best}, which was taken"
    for name in exclusive(best) - {best}:
        what = "random bias" if name.split(".")[1] in processes() else "output map"
        state.why_not.setdefault(name, f"a sensor takes one {what}, and {best} was taken")
    state.blocks[best] = {}
    for i in trials[best].channels:
        state.models[i] = state.models[i].tried(CANDIDATES[best])
        state.blocks[best][i] = len(state.models[i].columns) - 1
    state.remaining = [c for c in state.remaining if c.name not in exclusive(best)]


def _leftover_disturbances(s: _Session, state: _Search) -> list[Outside]:
    """The search's disturbances outside the library, and those of what the library leaves, in the
    channels' order.

    What the library leaves may still be a step or a hum, too small to lift the RMS by 3 % but
    significant by its withheld likelihood: a gap all the same. Each is tried on its own channel
    against no effect (a gain of 0); the channels set aside during the search are not tried again.
    """
    outside = list(state.outside)
    for i, ch in enumerate(CHANNELS):  # each adds to its own channel only: the set before them holds
        if ch not in state.outside_channels:
            alone = Trial((ChannelTrial(i, 0.0, 0.0, np.nan),))
            outside += outside_library(alone, False, state.models, s.withheld, s.n_fit)
    outside.sort(key=lambda o: CHANNELS.index(o.channel))
    return outside


def _where(
    s: _Session, before: Array, after: Array, floors: Array, outside: list[Outside]
) -> tuple[list[dict[str, Any]], list[str], dict[str, Any], dict[str, Any]]:
    """Where the gap lies: the ``where`` entries of the gapped channels, worst first, the channels
    left unexplained, and each channel's input quartiles and Allan deviations. ``before`` and
    ``after`` are the errors (n, 6) predicted before and after the accepted effects.

    A channel has a gap where its withheld RMS before the accepted effects exceeds its floor by
    :data:`~sins.gap.floor.SIGNIFICANT_RATIO`, or a disturbance outside the library explains it;
    it is left unexplained where its RMS after them still does, or such a disturbance explains it.
    """
    withheld = s.withheld
    rms_before, rms_after = _rms(s, before), _rms(s, after)
    disturbed = {CHANNELS.index(o.channel) for o in outside}
    gapped = [i for i in range(6) if rms_before[i] > SIGNIFICANT_RATIO * floors[i] or i in disturbed]
    gapped.sort(key=lambda i: -rms_before[i] / floors[i])
    quartiles, allan = {}, {}
    features = input_features(s.x, withheld)
    for i, (ch, residual, left) in enumerate(
        zip(CHANNELS, s.residuals(before), s.residuals(after), strict=True)
    ):
        quartiles[ch] = quartile_shares(residual, floors[i], features, withheld)
        allan[ch] = allan_curves(residual, left, floors[i], s.x.step_s)
    where: list[dict[str, Any]] = [
        {
            "channel": CHANNELS[i],
            "excess": float(rms_before[i] / floors[i]),
            "concentrates": concentrates(quartiles[CHANNELS[i]], allan[CHANNELS[i]])
            + [o.describe() for o in outside if o.channel == CHANNELS[i]],
        }
        for i in gapped
    ]
    unexplained = [
        ch for i, ch in enumerate(CHANNELS) if rms_after[i] > SIGNIFICANT_RATIO * floors[i] or i in disturbed
    ]
    return where, unexplained, quartiles, allan


def _report(
    s: _Session, model: tuple[str, ...], state: _Search, outside: list[Outside], before: Array, floors: Array
) -> GapReport:
    """The report: per channel the withheld RMS before and after against the floor, where the gap
    lies, the effects (accepted ones first, in the order they were accepted; then the rest, best
    score first), and the residuals and predictions behind them. ``before``: the errors (n, 6)
    predicted before the accepted effects."""
    release_free_memory()
    after = np.empty_like(before)
    for i, m in enumerate(state.models):
        assert m.predicted is not None
        after[:, i] = m.predicted
        state.models[i] = dataclasses.replace(m, predicted=after[:, i])  # its own copy let go
    # An effect that moves the reading by jumps (a clip reached, a delay across a step) lifts the
    # differences of the residual before it as well: where the accepted effects leave the
    # differences smaller, theirs are the white noise's (a heavy clip: 0.02-0.4 of the floor before).
    # Not below FLOOR_DROP of the floor before: what a near-exact model leaves is not noise.
    floors = np.maximum(np.minimum(floors, _floors(s, after, state.models)), FLOOR_DROP * floors)
    withheld = s.withheld
    rms_before, rms_after = _rms(s, before), _rms(s, after)
    channels = {
        ch: {
            "rms_before": float(rms_before[i]),
            "rms_after": float(rms_after[i]),
            "noise_floor": float(floors[i]),
        }
        for i, ch in enumerate(CHANNELS)
    }
    where, unexplained, quartiles, allan = _where(s, before, after, floors, outside)
    release_free_memory()  # what the input quartiles and Allan curves freed, before the residuals
    passed_over = [
        dataclasses.replace(e, not_accepted_because=state.why_not.get(e.name, "") if e.score > 0.0 else "")
        for e in state.scores.values()
        if not e.accepted
    ]
    ordered = [state.scores[n] for n in state.accepted] + sorted(passed_over, key=lambda e: -e.score)
    return GapReport(
        channels=channels,
        where=where,
        effects=ordered,
        diagnosis=state.accepted,
        unexplained=unexplained,
        outside=outside,
        rows=(s.n_fit, int(withheld.sum())),
        withholding=s.withholding,
        unfitted=state.unfitted,
        unreferenced=s.all_rows - len(s.data),
        model=tuple(dict.fromkeys((*BASELINE, *model))),
        residual_before=_withheld_residuals(s, before),
        residual_after=_withheld_residuals(s, after),
        predicted_before=before,
        predicted_after=after,
        t_withheld=s.data.t[withheld],
        allan=allan,
        quartiles=quartiles,
        sizes=_sizes(state),
    )


def _sizes(state: _Search) -> dict[str, dict[str, list[float]]]:
    """Each accepted effect's fitted size per channel, SI: a regressor effect's coefficients (its block
    of each channel's columns), a delay's seconds, a quantizer's step, a random bias's parameters
    (:func:`sins.gap.randombias.sizes`); a clip's: none."""
    out: dict[str, dict[str, list[float]]] = {}
    for name, channels in state.blocks.items():
        kind = CANDIDATES[name].kind
        out[name] = {}
        for i, block in channels.items():
            m = state.models[i]
            if kind == "regressors" and m.coefficients is not None:
                widths = m.widths()
                start = int(sum(widths[:block]))
                out[name][CHANNELS[i]] = [float(v) for v in m.coefficients[start : start + widths[block]]]
            elif kind == "delay" and m.delay_s is not None:
                out[name][CHANNELS[i]] = [float(m.delay_s)]
            elif name.endswith("quantization") and m.lattice is not None:
                out[name][CHANNELS[i]] = [float(m.lattice.step)]
            elif kind == "process" and m.process_size is not None:
                out[name][CHANNELS[i]] = [float(v) for v in m.process_size]
    return {n: v for n, v in out.items() if v}


def _withheld_residuals(s: _Session, predicted: Array) -> Array:
    """Each channel's residual on the withheld rows, under the ``predicted`` errors (n, 6): (m, 6),
    filled a channel at a time (no list of six columns beside their stack)."""
    out = np.empty((int(s.withheld.sum()), 6))
    for i, r in enumerate(s.residuals(predicted)):
        out[:, i] = r[s.withheld]
    return out


def _rms(s: _Session, predicted: Array) -> Array:
    """Each channel's RMS over the withheld rows, under the ``predicted`` errors (n, 6)."""
    return np.array([np.sqrt(np.mean(r[s.withheld] ** 2)) for r in s.residuals(predicted)])


__all__ = [
    "diagnose",
]
