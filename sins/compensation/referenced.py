"""Compensation of a real unit against its reference trajectory: fitted on intervals, judged open loop.

:func:`fit` fits any strategy on a :class:`~sins.core.series.ReferencedRecording`: the seed model and the
sensors' time offsets on the intervals between reference epochs (:mod:`sins.compensation.interval_fit`),
then, for strategies that learn more than the seed model, on the per-sample references the intervals
give. :func:`open_loop_attitude` judges a strategy the way an orientation benchmark does: the corrected
gyro integrated alone from the reference's first attitude, scored against the reference on the judged
rows. :func:`drive_errors` judges it the way a navigator does: the corrected unit navigating free
inertial from the reference's state, attitude and velocity errors over a window.
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
from sins.compensation.regression import Regression
from sins.compensation.residual import ResidualStrategy
from sins.compensation.several import SeveralFit
from sins.compensation.unit_bias import BiasRule
from sins.compensation.window_net import WindowNet
from sins.core import rotation
from sins.core.series import CalibrationData, ImuIncrements, ImuRates, NavSeries, ReferencedRecording
from sins.errors import SinsInputError, naming
from sins.io.recording import beside_trajectory
from sins.nav import attitude, strapdown
from sins.nav.attitude import AttitudeRmse
from sins.nav.metrics import NavErrors, nav_errors

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
    "BIAS_ONLY",
    "MIN_OPENING_REST_S",
    "DriveErrors",
    "Fitted",
    "FittedSeveral",
    "OpenLoop",
    "between",
    "choose_rule",
    "corrected",
    "drive_errors",
    "fit",
    "fit_several",
    "frame_turn",
    "free_inertial",
    "from_recording",
    "open_loop",
    "open_loop_attitude",
    "opening_rest",
    "replaces_seed_model",
]
