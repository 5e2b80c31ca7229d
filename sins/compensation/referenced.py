"""Compensation of a real unit fitted against its reference trajectory, on one recording or several.

:func:`fit` fits any strategy on a :class:`~sins.core.series.ReferencedRecording`: the seed model and the
sensors' time offsets on the intervals between reference epochs (:mod:`sins.compensation.interval_fit`),
then, for strategies that learn more than the seed model, on the per-sample references the intervals
give. :func:`fit_several` fits one unit on several recordings, with the rule for each new recording's
bias chosen on held-back ones (:func:`choose_rule`). How a fitted strategy is judged against a
reference is :mod:`sins.compensation.judging`'s.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins import compensation
from sins.compensation import Strategy, identifiability, interval_fit, screening
from sins.compensation.fitted_on import fitted_on, marks_of, readings_of
from sins.compensation.interval_fit import IntervalFit
from sins.compensation.intervals import INTERVAL_S
from sins.compensation.judging import between, corrected
from sins.compensation.regression import Regression
from sins.compensation.residual import ResidualStrategy
from sins.compensation.several import SeveralFit
from sins.compensation.unit_bias import BiasRule
from sins.compensation.window_net import WindowNet
from sins.core.series import CalibrationData, ImuIncrements, ReferencedRecording
from sins.errors import SinsInputError, naming

Array = NDArray[np.float64]

#: Strategies whose whole model is the seed model: they take the interval fit's coefficients as they are.
_SEED_ONLY = ("regression", "regression_robust")
#: The model the PSINS demo's filter estimates: gyro and accelerometer biases alone.
BIAS_ONLY = "bias_only"


@dataclass(frozen=True)
class Fitted:
    """A strategy fitted against a reference, with the interval fit it started from."""

    strategy: Strategy
    intervals: IntervalFit
    review: identifiability.Review | None = None
    #: What of the reference was set aside as gross errors (:mod:`sins.compensation.screening`).
    set_aside: tuple[screening.SetAside, ...] = ()


def fit(
    name: str,
    rec: ReferencedRecording,
    *,
    interval_s: float = INTERVAL_S,
    params: dict[str, Any] | None = None,
    progress: Callable[[int, int], None] | None = None,
    grade: str = identifiability.DEFAULT_GRADE,
    screen: str = screening.DEFAULT,
) -> Fitted:
    """Fit strategy ``name`` on ``rec`` against its reference.

    The seed model, the gyro's and the accelerometer's time offsets and the accelerometer's lever arm
    are fitted on intervals of ``interval_s``; ``regression`` (``regression_robust``: Huber-weighted
    intervals) is that fit; :data:`BIAS_ONLY` the biases alone (the model of the PSINS demo's filter);
    ``regression_rest`` and ``regression_window`` take that seed model and fit what they add
    (``fit_beyond``) on the per-sample references the intervals give
    (:func:`~sins.compensation.interval_fit.interval_reference`); every other strategy is fitted by its
    own ``fit`` on those references. All read the readings at the fitted time offsets. ``none`` learns
    nothing and shifts nothing. ``progress(done, total)`` is handed to the
    learned strategies' training. The coefficients the intervals do not determine are held at zero
    and every other one is checked against what a unit of class ``grade`` can have
    (:mod:`sins.compensation.identifiability`); the verdict is :attr:`Fitted.review`, and the model's
    ``fitted_on_`` records it. ``screen`` says when the reference's gross errors are set aside
    (:data:`sins.compensation.screening.SCREENS`: by default where the fit is refused without;
    :attr:`Fitted.set_aside` says what).

    Raises
    ------
    SinsInputError
        when the recording cannot determine the model, or the model is beyond the class's bounds (one
        line naming the recording).
    """
    where = rec.source or "recording"

    def seed(rs: list[ReferencedRecording]) -> Any:
        if name == BIAS_ONLY:
            return _bias_only(rs[0], interval_s, grade)
        return identifiability.fit_determined(
            lambda holds: interval_fit.fit_intervals(
                rs[0], interval_s=interval_s, robust=name == "regression_robust", holds=holds
            ),
            rs[0], interval_s, grade, where,
        )  # fmt: skip

    try:
        made, [rec], aside = screening.fitted_screened(seed, [rec], interval_s, grade, screen)
        if name == BIAS_ONLY:
            return replace(made, set_aside=aside)
        fitted, review = made
        strategy = compensation.make(name, **(params or {}))
        if name == "none":  # nothing learned: what it was fitted on, as every model says
            strategy.fitted_on_ = {**fitted_on(rec), "checks": review.to_dict()}
            return Fitted(strategy, fitted, review, aside)
        if name in _SEED_ONLY:
            assert isinstance(strategy, Regression)
            strategy.set_fit(fitted.seed)
        elif isinstance(strategy, Regression) and type(strategy).fit_beyond is not Regression.fit_beyond:
            # The seed model from the intervals, what the strategy adds from the per-sample references.
            strategy.set_fit(fitted.seed).fit_beyond(interval_fit.interval_reference(rec, fitted))
        else:
            if progress is not None and hasattr(strategy, "progress"):  # the learners, whose fits take long
                strategy.progress = progress
            rows = interval_fit.interval_reference(rec, fitted)
            if isinstance(strategy, ResidualStrategy):  # on top of the intervals' seed model, as below
                strategy.fit(rows, base=Regression().set_fit(fitted.seed))
            else:
                strategy.fit(rows)
    except ValueError as exc:
        if isinstance(exc, SinsInputError):
            raise
        raise naming(where, exc) from None
    strategy.time_offset_s_ = np.array([fitted.time_offset_s, fitted.accel_time_offset_s])
    strategy.fitted_on_ = {**fitted_on(rec), "checks": review.to_dict()}
    return Fitted(strategy, fitted, review, aside)


@dataclass(frozen=True)
class FittedSeveral:
    """A strategy fitted on several recordings of one unit: the shared seed model with each recording's
    own bias (``several``), what the model does about a new recording's bias (``rule``), and what the
    recordings did not determine (``review``: held at zero, with reasons)."""

    strategy: Strategy
    several: SeveralFit
    rule: BiasRule | None
    review: identifiability.Review | None = None
    #: What of each recording's reference was set aside (:mod:`sins.compensation.screening`).
    set_aside: tuple[screening.SetAside, ...] = ()


def fit_several(
    name: str,
    recs: list[ReferencedRecording],
    *,
    interval_s: float = INTERVAL_S,
    params: dict[str, Any] | None = None,
    progress: Callable[[int, int], None] | None = None,
    rule_mode: str | None = None,
    stage: Callable[[str], None] | None = None,
    grade: str = identifiability.DEFAULT_GRADE,
    screen: str = screening.DEFAULT,
) -> FittedSeveral:
    """Fit strategy ``name`` on several recordings of one unit against their references.

    The seed model is fitted on all of them at once, every coefficient shared but the biases, which are
    each recording's own (:func:`sins.compensation.several.fit_several`); the model's bias is their
    mean. A strategy that learns beyond the seed model learns on the per-sample references of every
    recording, each corrected with its own bias (so that it learns what moves within a recording, not
    between them). What the model does about a new recording's bias is a
    :class:`~sins.compensation.unit_bias.BiasRule` (the model file keeps it as ``unit_bias_``), its mode
    chosen on held-back recordings (:func:`choose_rule`) unless ``rule_mode`` names one. ``none`` learns
    nothing and has no rule. ``progress(done, total)`` is handed to a learner's training, ``stage(text)``
    told of each stage. ``screen``: as :func:`fit`, on every recording.

    Raises
    ------
    SinsInputError
        fewer than two recordings, recordings of different units or rates, one recording twice, or as
        :func:`fit`.
    """
    from sins.compensation.several import check_one_unit

    check_one_unit(recs)
    where = " + ".join(rec.source or "recording" for rec in recs)
    say = stage or (lambda text: None)
    try:
        say(f"the seed model on {len(recs)} recordings")
        (fit_all, review), recs, aside = screening.fitted_screened(
            lambda rs: _several_determined(rs, interval_s, name, grade, where),
            recs,
            interval_s,
            grade,
            screen,
        )
        offsets = np.array([fit_all.time_offset_s, fit_all.accel_time_offset_s])
        if name == BIAS_ONLY:  # the seed model's biases alone, read as they come
            strategy: Strategy = Regression(g_sensitivity=False).set_fit(_biases_only(fit_all.seed))
            strategy.variant = BIAS_ONLY
            offsets = np.zeros(2)
        else:
            strategy = compensation.make(name, **(params or {}))
        if name == "none":  # nothing learned, no rule: what it was fitted on, as every model says
            strategy.fitted_on_ = _several_fitted_on(recs, review)
            return FittedSeveral(strategy, fit_all, None, review, aside)
        if name in _SEED_ONLY:
            assert isinstance(strategy, Regression)
            strategy.set_fit(fit_all.seed)
        elif name != BIAS_ONLY:
            _learn_several(strategy, name, recs, fit_all, progress, say)
        strategy.time_offset_s_ = offsets
        rule = choose_rule(strategy, recs, fit_all, interval_s=interval_s, mode=rule_mode, stage=say)
    except ValueError as exc:
        if isinstance(exc, SinsInputError):
            raise
        raise naming(where, exc) from None
    strategy.unit_bias_ = rule.to_dict()
    strategy.fitted_on_ = _several_fitted_on(recs, review)
    return FittedSeveral(strategy, fit_all, rule, review, aside)


def _several_fitted_on(recs: list[ReferencedRecording], review: identifiability.Review) -> dict[str, Any]:
    """What a model fitted on ``recs`` was fitted on (``fitted_on_``): the unit, each recording and its
    readings' digest, and the fit's checks."""
    return {
        **fitted_on(recs[0]), "recordings": [rec.source for rec in recs],
        "readings": [readings_of(rec) for rec in recs], "marks": [marks_of(rec) for rec in recs],
        "checks": review.to_dict(),
    }  # fmt: skip


def _several_determined(
    recs: list[ReferencedRecording], interval_s: float, name: str, grade: str, where: str
) -> tuple[SeveralFit, identifiability.Review]:
    """The fit on several recordings with the shared coefficients they do not determine for a unit of
    ``grade`` held at zero (:func:`~sins.compensation.identifiability.assess_several`), made again
    holding any that came out less determined than predicted, then judged against the class's bounds
    (:func:`~sins.compensation.identifiability.review`), each recording's own biases by their values
    alone (``sins fit`` says where their standard errors exceed the class's spread)."""
    from sins.compensation import several

    holds = identifiability.assess_several(recs, interval_s, identifiability.class_bounds(grade))
    biases_only = name == BIAS_ONLY
    for _ in range(identifiability.REFITS):
        fit_all = several.fit_several(
            recs, interval_s=interval_s, robust=name == "regression_robust", held=holds.reasons
        )
        values = identifiability.interval_values(fit_all, biases_only)
        more = identifiability.loose(values, holds)
        if not more:
            break
        holds.reasons.update(more)
    review = identifiability.review(values, holds.bounds, where, holds.reasons)
    for r, source in enumerate(fit_all.sources):
        own = identifiability.interval_values(fit_all.for_recording(r), biases_only=True)
        # A recording's own bias is judged by its value alone (finite, within the class's bound): it is
        # not the model's, and the residuals behind its standard error are behind the shared terms' and
        # the mean bias's too, which are judged (sins fit prints it, and says where it is loose).
        identifiability.review(
            {n: (v, None) for n, (v, _) in own.items()}, holds.bounds, f"{where}: {source}"
        )
    return fit_all, review


def replaces_seed_model(strategy: Strategy) -> bool:
    """Whether ``strategy`` corrects with a fit of its own from readings to errors (the seed paper's
    networks, ``regression_extended``), not with the seed model (with or without a learner on top of it):
    fitted on several recordings, the seed model still gives each recording's bias and the bias rule."""
    return strategy.name != "none" and not isinstance(strategy, Regression | ResidualStrategy | WindowNet)


def _learn_several(
    strategy: Strategy, name: str, recs: list[ReferencedRecording], fit_all: SeveralFit,
    progress: Callable[[int, int], None] | None, say: Callable[[str], None],
) -> None:  # fmt: skip
    """A strategy that learns beyond the seed model, on the per-sample references of every recording."""
    from sins.compensation import interval_fit

    if isinstance(strategy, WindowNet):
        # A learner of what moves between recordings: each recording's references with the mean bias.
        pooled = [replace(fit_all.for_recording(r), seed=fit_all.seed) for r in range(len(recs))]
        parts = [interval_fit.interval_reference(rec, f) for rec, f in zip(recs, pooled, strict=True)]
        strategy.progress = progress
        say(f"training {name} (each recording held back in turn, then on all)")
        strategy.set_fit(fit_all.seed)
        strategy.time_offset_s_ = np.array([fit_all.time_offset_s, fit_all.accel_time_offset_s])
        strategy.fit_recordings(parts, recs)
        return
    parts = [_at_mean_bias(interval_fit.interval_reference(rec, fit_all.for_recording(r)), fit_all, r)
             for r, rec in enumerate(recs)]  # fmt: skip
    data = _joined(parts)
    if isinstance(strategy, Regression) and type(strategy).fit_beyond is not Regression.fit_beyond:
        strategy.set_fit(fit_all.seed).fit_beyond(data)
        return
    if progress is not None and hasattr(strategy, "progress"):
        strategy.progress = progress
    if isinstance(strategy, ResidualStrategy):  # its guard judges recordings held back whole
        say(f"training {name} (each recording held back in turn, then on all)")
        # On top of the seed model the intervals fitted (what they do not determine held at zero), as
        # `regression` is: refitted on the per-sample references, least squares took the terms the
        # intervals hold (g-sensitivity) from the differentiated reference's noise.
        strategy.fit(
            data, recordings=np.repeat(np.arange(len(parts)), [len(p) for p in parts]),
            base=Regression().set_fit(fit_all.seed),
        )  # fmt: skip
        return
    say(f"training {name}")
    strategy.fit(data)


def choose_rule(
    strategy: Strategy,
    recs: list[ReferencedRecording],
    fit_all: SeveralFit,
    *,
    interval_s: float = INTERVAL_S,
    mode: str | None = None,
    stage: Callable[[str], None] | None = None,
) -> BiasRule:
    """What ``strategy`` (fitted on ``recs``) does about a new recording's bias: the bias each recording's
    corrected readings still hold (fitted against its reference) gives the rule's prior and spread; the
    mode (or ``mode``) is chosen on the open-loop attitude of held-back recordings (each in turn, the seed
    model and the rule made from the others) by ``rule_choice.chosen_mode``: the simplest within one
    standard error of the best of those no worse than the readings on any, else ``READINGS`` (the gyro as
    read). The mode taken is judged once more from each held-back recording's first motion
    (:func:`_from_first_motion`), which is reported, not used."""
    from sins.compensation import interval_fit, rule_choice, several, unit_bias

    streams = [corrected(strategy, rec) for rec in recs]
    left = np.array([interval_fit.fit_biases(_with_imu(rec, s), interval_s=interval_s).seed.B0
                     for rec, s in zip(recs, streams, strict=True)])  # fmt: skip
    held: dict[str, float] = {}
    each: dict[str, list[float]] = {}
    folds: list[tuple[Regression, BiasRule, ReferencedRecording]] = []  # each held back, with its fold's
    if mode is None and len(recs) >= 3:
        # A fold holds all recordings but one: the mixture choices where that is enough for a mixture.
        mixed = len(recs) - 1 >= unit_bias.MIXTURE_MIN
        judged = [m for m in unit_bias.CHOICES if mixed or not m.endswith(unit_bias.MIXTURE)]
        scores: dict[str, list[float]] = {m: [] for m in judged}
        raw: list[float] = []
        biases_alone = getattr(strategy, "variant", None) == BIAS_ONLY  # its own correction, held back too
        for k, rec in enumerate(recs):
            if stage is not None:
                stage(f"the bias rule: recording {k + 1} of {len(recs)} held back")
            others = [r for i, r in enumerate(recs) if i != k]
            part = several.fit_several(others, interval_s=interval_s)
            seed = Regression(g_sensitivity=False).set_fit(
                _biases_only(part.seed) if biases_alone else part.seed
            )
            seed.time_offset_s_ = (
                np.zeros(2) if biases_alone else np.array([part.time_offset_s, part.accel_time_offset_s])
            )
            own = [seed.correct_increments(r.imu) for r in others]
            rel = part.gyro_bias - part.gyro_bias.mean(axis=0)
            base = unit_bias.rule_from(rel, own, model_bias=seed.B0_, accel_biases=part.accel_bias)
            stream = seed.correct_increments(rec.imu)
            folds.append((seed, base, rec))
            raw.append(unit_bias.open_loop_deg(rec.imu, rec))
            for m in judged:
                scores[m].append(
                    unit_bias.open_loop_deg(unit_bias.corrected(unit_bias.with_mode(base, m), stream), rec)
                )
        held = {m: float(np.mean(v)) for m, v in scores.items()}
        mode = rule_choice.chosen_mode(scores, raw)
        held["raw"] = float(np.mean(raw))  # the readings as they are
        each = {**scores, "raw": raw}
    rule = unit_bias.rule_from(left, streams, mode=mode or "pooled", model_bias=fit_all.seed.B0,
                               accel_biases=fit_all.accel_bias, held_back_deg=held,
                               held_back_each_deg=each)  # fmt: skip
    if folds and rule.mode != unit_bias.READINGS:
        rule = replace(rule, moving_held_back_deg=_from_first_motion(folds, rule.choice, each))
    return rule


def _from_first_motion(
    folds: list[tuple[Regression, BiasRule, ReferencedRecording]], choice: str, whole: dict[str, list[float]]
) -> dict[str, list[float]]:
    """The open-loop attitude (deg) of each held-back recording from its first motion (its opening rest cut
    away) under ``choice`` with its fold's seed model and rule (``rule``), and of its readings as read there
    (``raw``): what a new recording that opens moving gets, which one held back whole with its rest does not
    show. One that opens moving keeps its figures held back whole (``whole``: the same open loops)."""
    from sins.compensation import unit_bias

    out: dict[str, list[float]] = {"rule": list(whole[choice]), "raw": list(whole["raw"])}
    for k, (seed, base, rec) in enumerate(folds):
        rest = unit_bias.rest_of(rec.imu)[0]
        if rest:
            moving = between(rec, float(rec.imu.t[rest]), float(rec.imu.t[-1]))
            rule, stream = unit_bias.with_mode(base, choice), seed.correct_increments(moving.imu)
            out["rule"][k] = unit_bias.open_loop_deg(unit_bias.corrected(rule, stream), moving)
            out["raw"][k] = unit_bias.open_loop_deg(moving.imu, moving)
    return out


def _biases_only(seed: Any) -> Any:
    """``seed`` with every coefficient but the biases zero."""
    zeros = np.zeros((3, 3))
    return replace(seed, B=zeros, K=zeros, A=zeros)


def _at_mean_bias(part: CalibrationData, fit_all: SeveralFit, r: int) -> CalibrationData:
    """Recording ``r``'s per-sample references with its readings at the recordings' mean biases: each
    reading less its own bias's difference from the mean (``gyro = ω + B0 + B ω + K n``,
    ``accel = n + A0 + A n``). What differs between recordings is the bias rule's, at correction time
    and from the recording alone; a learner shown it would learn to tell the training recordings apart
    by their motion and take each one's bias with it, which a new recording's motion does not carry (a
    numpy MEMS unit's biases drawn anew: ``mlp`` worse than the raw readings on a judged recording)."""
    return replace(
        part,
        gyro=part.gyro - (fit_all.gyro_bias[r] - fit_all.gyro_bias.mean(axis=0)),
        accel=part.accel - (fit_all.accel_bias[r] - fit_all.accel_bias.mean(axis=0)),
    )


def _joined(parts: list[CalibrationData]) -> CalibrationData:
    """Per-sample references of several recordings one after another: each recording's times moved on
    past the last one's, a second apart, so time keeps increasing and no block spans two of them."""
    out_t, shift = [], 0.0
    for p in parts:
        out_t.append(p.t - p.t[0] + shift)
        shift = out_t[-1][-1] + 1.0
    cat = lambda name: np.vstack([getattr(p, name) for p in parts])  # noqa: E731
    return CalibrationData(
        t=np.concatenate(out_t), gyro=cat("gyro"), accel=cat("accel"), ref_gyro=cat("ref_gyro"),
        ref_accel=cat("ref_accel"), source=" + ".join(p.source for p in parts),
    )  # fmt: skip


def _with_imu(rec: ReferencedRecording, imu: ImuIncrements) -> ReferencedRecording:
    return replace(rec, imu=imu)


def _bias_only(rec: ReferencedRecording, interval_s: float, grade: str) -> Fitted:
    """The gyro's and accelerometer's biases alone, on intervals (no scale, misalignment, offsets)."""
    fitted, review = identifiability.fit_determined(
        lambda holds: interval_fit.fit_biases(rec, interval_s=interval_s, holds=holds),
        rec, interval_s, grade, rec.source or "recording", biases_only=True,
    )  # fmt: skip
    strategy = Regression(g_sensitivity=False).set_fit(fitted.seed)
    strategy.variant = BIAS_ONLY  # reported and saved by its name, not as the class it is fitted with
    strategy.fitted_on_ = {**fitted_on(rec), "checks": review.to_dict()}
    return Fitted(strategy, fitted, review)


__all__ = [
    "BIAS_ONLY",
    "Fitted",
    "FittedSeveral",
    "choose_rule",
    "fit",
    "fit_several",
    "replaces_seed_model",
]
