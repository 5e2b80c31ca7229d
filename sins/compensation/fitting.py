"""A strategy fitted on what a recording holds, and what the fit says of itself.

Three kinds of fit, one per kind of recording: a rig session's rows (:func:`fit_rig`: the strategy's own
fit, its seed model's coefficients checked against the unit's class), a recording beside its reference
trajectory (:func:`fit_referenced`: the seed model on intervals, then the strategy) and several recordings
of one unit (:func:`fit_several`: a shared model, each recording's bias, the rule for a new one's). Each
returns a :class:`FitOutcome`: the fitted strategy, the lines a command prints and the document it writes
(``--json``). The library owns both, so a notebook gets what ``sins fit`` prints.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from sins.compensation import coefficients, interval_fit, seed_terms
from sins.core.text import fixed_width
from sins.errors import SinsInputError, naming
from sins.io import frame_check

if TYPE_CHECKING:
    from sins.compensation.base import Strategy
    from sins.compensation.unit_bias import BiasRule
    from sins.core.series import CalibrationData, ReferencedRecording
    from sins.io.findings import ReferenceLag

#: A fit's progress: rows (or epochs) done of a total.
Progress = Callable[[int, int], None]


@dataclass
class FitOutcome:
    """A fitted strategy, the lines that say what was fitted, and its document.

    Attributes
    ----------
    strategy : the fitted strategy, ready for :func:`sins.compensation.save`
    lines : what the fit found, a line each (coefficients as tables)
    document : the figures as plain JSON values (:meth:`to_dict`)
    """

    strategy: Strategy
    lines: list[str] = field(default_factory=list)
    document: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The fit's figures as plain JSON values (``sins fit --json``)."""
        return dict(self.document)


def coefficient_lines(table: list[Any], title: str) -> list[str]:
    """A coefficient table (:func:`coefficients.engineering`) under its title."""
    return [title, fixed_width(["sensor", "term", "axis", "value", "unit"], coefficients.table_rows(table))]


def progress_unit(name: str) -> str:
    """What a rig fit of strategy ``name`` counts as it goes: a network's epochs, or its trainings."""
    from sins import compensation
    from sins.compensation.mlp import MLP

    try:
        strategy = compensation.make(name)
    except ValueError:  # bias_only, an unknown name: the fit refuses it in one line (a traceback, here)
        return "trainings"
    return "epochs" if isinstance(strategy, MLP) else "trainings"


def fit_rig(
    name: str,
    data: CalibrationData,
    *,
    where: str,
    sensor: str,
    validation: float | None = None,
    guard: bool = True,
    grade: str = "consumer",
    progress: Progress | None = None,
) -> FitOutcome:
    """Strategy ``name`` fitted on a rig recording's rows (the last ``validation`` of every phase held
    back), its seed model's coefficients reviewed against a ``grade`` unit's before the model is written.
    ``where`` names the recording in messages, ``sensor`` the unit in the model file."""
    from sins import compensation
    from sins.compensation import fitted_on
    from sins.compensation.mlp import MLP
    from sins.compensation.regression import Regression
    from sins.compensation.residual import ResidualStrategy

    if name == "bias_only":
        raise SinsInputError(
            f"{where}: bias_only is fitted against a trajectory's reference, and this is a rig recording "
            "(the other strategies fit one)"
        )
    lines: list[str] = []
    angles = any(p.angle_rad is not None for p in data.phases)
    try:
        strategy = compensation.make(name, **({} if guard else {"guard": False}))
        if angles and isinstance(strategy, Regression) and strategy.g_sensitivity:
            # Turns known by their angles alone cannot tell the gyro's g-sensitivity: it is left out.
            strategy = compensation.make(name, g_sensitivity=False)
            lines.append(
                f"{where}: its turns give only their angles, which cannot tell the g-sensitivity: left out"
            )
        part = data.split(validation)[0] if validation else data
        if isinstance(strategy, ResidualStrategy | MLP):  # the strategies whose fits take long
            strategy.progress = progress
        strategy.fit(part)
    except ValueError as exc:
        raise naming(where, exc) from None
    held = f" (the last {validation:g} of each phase held back)" if validation else ""
    lines.append(f"fitted {strategy.label} on {len(part)} of {len(data)} rows of {where}{held}")
    document: dict[str, Any] = {"strategy": strategy.label, "rows": len(part)}
    said, found = _guard_report(strategy, "", "squared error")
    lines += said
    document |= found
    checks = _rig_seed_review(strategy, part, where, grade, lines, document)
    lines += _unjudged_network(name, strategy.label, rig=True)
    strategy.fitted_on_ = {
        "sensor": sensor, "rate_hz": None, "reference": "rig", "checks": checks,
        "readings": [fitted_on.readings_of(data)], "marks": [fitted_on.marks_of(data)],
        "held_back": validation or 0.0,
    }  # fmt: skip
    return FitOutcome(strategy, lines, document)


def _guard_report(
    strategy: Any, how: str, unit: str, by_recording: bool = False
) -> tuple[list[str], dict[str, Any]]:
    """A learned strategy's guard, in lines and as its document (``guard``, ``learned_on``; or
    ``mlp_window``'s ``window_guard``, its gain in ``unit``), and nothing for the others. ``how``: on what
    the learner was chosen, with ``{folds}`` and ``{blocks}`` (default: folds of held-back blocks);
    ``by_recording``: the folds are recordings, the guard's standard errors over them."""
    from sins.compensation.residual import ResidualStrategy
    from sins.compensation.window_net import WindowNet

    if isinstance(strategy, ResidualStrategy) and getattr(strategy, "guard_", None):
        how = how or "chosen on {folds} folds of {blocks} held-back blocks"
        used = [ch for ch, u in zip(strategy.guard_, strategy.used_, strict=True) if u]
        document = {"guard": {ch: bool(g["earns_its_place"]) for ch, g in strategy.guard_.items()},
                    "learned_on": used}  # fmt: skip
        return _learner_lines(
            strategy, how.format(folds=strategy.cv_folds_, blocks=strategy.blocks_), by_recording
        ), document
    if isinstance(strategy, WindowNet) and hasattr(strategy, "held_back_gain_"):
        return _window_lines(strategy, unit)
    return [], {}


def _learner_lines(strategy: Any, how: str, by_recording: bool = False) -> list[str]:
    """What a learned strategy chose (``how``: on what it was chosen), then its guard per channel: the
    physics terms each took, the learner's held-back gain over them, what the model uses there (the
    learner where the guard kept it, or everywhere with the guard off), and the same in words."""
    from sins.compensation.base import recordings_threshold

    chosen = "; ".join(f"{s} {_settings(c)}" for s, c in strategy.configs_.items())
    lines, learned = [f"{how}: {chosen}"], []
    for k, (ch, g) in enumerate(strategy.guard_.items()):
        base = "regression" + "".join(f" + {t}" for t in strategy.terms_.get(ch, {}).get("groups", []))
        used = bool(strategy.used_[k])
        learned += [ch] if used else []
        forced = " (guard off)" if used and not g["earns_its_place"] else ""
        gain, se = 100 * g["gain_fraction"], 100 * g["gain_se_fraction"]
        lines.append(f"{ch:<8} {base:<26} learner's held-back gain {gain:+7.2f} % ± {se:.2f} %  -> "
                     f"{'learned' if used else base}{forced}")  # fmt: skip
    over = (
        f" over the held-back recordings (Student's t over {strategy.cv_folds_}: "
        f"{recordings_threshold(strategy.guard_z, strategy.cv_folds_):.3g})"
        if by_recording
        else ""
    )
    rule = (
        "the guard is off: the learner corrects every channel, whatever its held-back gain"
        if not strategy.guard
        else f"the guard keeps the learner where its held-back gain exceeds {strategy.guard_z:g} standard "
        f"errors{over}, least squares (and its terms) elsewhere"
    )
    said = (
        f"the learner corrects {', '.join(learned)}" if learned else "the learner adds nothing: least squares"
    )
    return [*lines, f"{said} ({rule})"]


def _window_lines(strategy: Any, unit: str) -> tuple[list[str], dict[str, Any]]:
    """``mlp_window``'s guard: the networks' held-back gain over least squares (``unit``: degrees of
    open-loop attitude on held-back recordings, or the squared error of held-back parts), and the gyro
    axes they correct (none where the guard refused them), in a line and as its document."""
    gain, se = strategy.held_back_gain_, strategy.held_back_gain_se_
    axes = strategy.window_axes
    shown = (f"{gain[0]:+.3g}° ± {se[0]:.2g}° of open-loop attitude" if unit == "deg"
             else ", ".join(f"{a} {g:+.3g} ± {s:.2g}" for a, g, s in zip("xyz", gain, se, strict=True)) +
             " of squared error")  # fmt: skip
    used = (f"the networks correct gyro {', '.join(axes)}" + ("" if strategy.guard else " (guard off)")
            if axes else "the networks are not used: least squares")  # fmt: skip
    line = f"the window networks' held-back gain over least squares: {shown} -> {used}"
    return [line], {"window_guard": {"held_back_gain": gain.tolist(), "standard_error": se.tolist(),
                                     "unit": unit, "gyro_axes_corrected": axes}}  # fmt: skip


def _rig_seed_review(
    strategy: Strategy,
    part: CalibrationData,
    where: str,
    grade: str,
    lines: list[str],
    document: dict[str, Any],
) -> dict[str, Any]:
    """The seed model's coefficients with their standard errors (the strategy's own for regression, the
    stage the learners start from for the others), reviewed against a ``grade`` unit's."""
    from sins.compensation import identifiability
    from sins.compensation.ferraris import Ferraris
    from sins.imu import calibration

    try:
        seed = calibration.fit_seed_model(part)
        with_k = True
    except ValueError:
        try:  # a session whose turns give only their angles (Ferraris) cannot tell K
            seed, with_k = calibration.fit_seed_model(part, g_sensitivity=False), False
        except ValueError:
            seed = None
    caption = "least squares of the seed model on the rows (± 1σ)"
    if isinstance(strategy, Ferraris):  # its own fit, g-sensitivity and all, where least squares has none
        f = strategy
        seed = calibration.SeedModelFit(
            f.B0_, f.B_, f.K_, f.A0_, f.A_, f.B0_se_, f.B_se_, f.K_se_, f.A0_se_, f.A_se_, np.full(6, np.nan)
        )
        with_k, caption = True, "the Ferraris procedure's coefficients (± 1σ)"
    if strategy.name == "none" or seed is None:
        return {"grade": grade, "held": {}}
    table = coefficients.engineering(seed, g_sensitivity=with_k)
    lines += coefficient_lines(table, caption)
    document["coefficients"] = [c.to_dict() for c in table]
    bounds = identifiability.class_bounds(grade)
    return identifiability.review(identifiability.seed_values(seed), bounds, where).to_dict()


def fit_referenced(
    name: str,
    rec: ReferencedRecording,
    *,
    where: str,
    validation: float | None = None,
    interval_s: float = 1.0,
    guard: bool = True,
    grade: str = "consumer",
    progress: Progress | None = None,
    screen: str = "refused",
) -> FitOutcome:
    """Strategy ``name`` fitted on a recording beside its reference trajectory: the seed model on
    intervals of ``interval_s``, then the strategy (the last ``validation`` of the span held back);
    ``screen``: when the reference's gross errors are set aside (:mod:`sins.compensation.screening`)."""
    from sins.compensation import judging, referenced, world_tilt

    part = rec
    if validation:
        span = rec.imu.t[-1] - rec.imu.t[0]
        part = judging.between(rec, rec.imu.t[0], rec.imu.t[-1] - validation * span)
    # The reference levelled where tilted from gravity, estimated on what the fit reads.
    part, tilt = world_tilt.levelled(part, interval_s)
    rec = world_tilt.level(rec, tilt)
    clock = frame_check.recording_lag(rec)
    with _clock_named([(where, clock)]):
        fitted = referenced.fit(
            name,
            part,
            interval_s=interval_s,
            params={} if guard else {"guard": False},
            progress=progress,
            grade=grade,
            screen=screen,
        )
    fit = fitted.intervals
    back = f", the last {validation:g} of its span held back" if validation else ""
    lines = [
        f"fitted {fitted.strategy.label} on {where} ({rec.sensor or 'unit'} against {rec.reference_name}"
        f"{back}): {fit.intervals} intervals of {fit.interval_s:g} s",
        f"reference: {fit.quality.summary()}",
        f"reference: {tilt.says}",
    ]
    fitted.strategy.fitted_on_["reference_tilt"] = tilt.to_dict()
    if clock is not None:
        lines.append(f"reference: {clock_words(clock.lag_s)}")
    lines += _screen_lines([where], fitted.set_aside, [fitted.intervals.residuals])
    table = coefficients.engineering(fit.seed, g_sensitivity=fit.g_sensitivity)
    if name == referenced.BIAS_ONLY:  # the other terms are not fitted: zeros, not estimates
        table = [c for c in table if c.term == "bias"]
    lines += coefficient_lines(table, "the seed model on the intervals (± 1σ; held: not determined, zero)")
    held = _held_lines(fitted.review, grade, "the recording does", lines)
    if fit.g_sensitivity_test is not None:
        kept, gain, se = fit.g_sensitivity_test
        verdict = "kept" if kept else "left out (zero)"
        lines.append(
            f"g-sensitivity {verdict}: it predicts held-back intervals by {gain:.3g} ± {se:.3g} rad²"
        )
    document: dict[str, Any] = {
        "strategy": fitted.strategy.label,
        "intervals": fit.intervals,
        "interval_s": fit.interval_s,
        "coefficients": [c.to_dict() for c in table],
        "reference_quality": fit.quality.__dict__,
        "g_sensitivity": fit.g_sensitivity,
        "grade": grade,
        "held": held,
        "reference_clock_ms": None if clock is None else 1e3 * clock.lag_s,
        "reference_tilt": tilt.to_dict(),
        "set_aside": [a.to_dict() for a in fitted.set_aside if a.found()],
    }
    if name != referenced.BIAS_ONLY:
        document |= _offsets(fit, lines)
    said, found = _guard_report(fitted.strategy, "", "squared error")  # the learners' guard, as elsewhere
    said += _unjudged_network(name, fitted.strategy.label)
    return FitOutcome(fitted.strategy, lines + said, document | found)


def _unjudged_network(name: str, label: str, *, rig: bool = False) -> list[str]:
    """Said where a network the guard judges (:func:`sins.compensation.network_guard.guards`) is fitted on
    one recording: the guard holds recordings back whole, and one recording has none to spare (a rig
    recording cannot be fitted with others: a fit on several takes recordings beside a trajectory)."""
    from sins.compensation import network_guard

    if not network_guard.guards(name):
        return []
    where = "beside their reference trajectories (a rig recording is fitted alone)" if rig else "of the unit"
    return [
        f"{label} is written unjudged: its guard judges it against least squares with each recording held "
        f"back whole, on {network_guard.MIN_RECORDINGS} recordings or more {where}"
    ]


def _screen_lines(names: list[str], aside: Sequence[Any], residuals: list[Any]) -> list[str]:
    """What the screen set aside of each recording; or, where it set nothing aside, the intervals far
    off the fit that it would (:mod:`sins.compensation.screening`)."""
    from sins.compensation import screening

    lines = [a.line(n) for n, a in zip(names, aside, strict=True) if a.found()]
    if any(a.spans_s for a in aside):  # screened: the intervals it left are the fit's
        return lines
    suspect = [screening.suspect_line(n, *r) for n, r in zip(names, residuals, strict=True) if r is not None]
    return lines + [line for line in suspect if line]


def _held_lines(review: Any, grade: str, what: str, lines: list[str]) -> dict[str, Any]:
    """The coefficients a review held at zero, said in ``lines``; returned for the document."""
    held = review.held if review is not None else {}
    if held:
        lines.append(f"held at zero, as {what} not determine them for a {grade} unit:")
        lines += [f"  {line}" for line in review.lines()]
    return dict(held)


def _offsets(fit: Any, lines: list[str]) -> dict[str, Any]:
    """The time offsets and the lever arm an interval fit found."""
    arm = np.asarray(fit.lever_arm_m) * 1e3

    def offset(tau: float, se: float) -> str:
        return f"{tau * 1e3:.3f} ± {se * 1e3:.3f} ms" if np.isfinite(se) else "0 (held)"

    def finite(se: float) -> float | None:
        return se * 1e3 if np.isfinite(se) else None

    gyro = offset(fit.time_offset_s, fit.time_offset_se_s)
    accel = offset(fit.accel_time_offset_s, fit.accel_time_offset_se_s)
    lines.append(
        f"time offsets (the readings lag the reference): gyro {gyro}, accelerometer {accel}; accelerometer "
        f"{arm[0]:.1f}, {arm[1]:.1f}, {arm[2]:.1f} mm from the reference's point"
    )
    return {
        "time_offset_ms": {"gyro": fit.time_offset_s * 1e3, "accel": fit.accel_time_offset_s * 1e3},
        "time_offset_se_ms": {
            "gyro": finite(fit.time_offset_se_s),
            "accel": finite(fit.accel_time_offset_se_s),
        },
        "lever_arm_mm": arm.tolist(),
    }


def fit_several(
    name: str,
    recs: Sequence[ReferencedRecording],
    names: Sequence[str],
    *,
    interval_s: float = 1.0,
    guard: bool = True,
    rule_mode: str | None = None,
    grade: str = "consumer",
    progress: Progress | None = None,
    stage: Callable[[str], Any] | None = None,
    screen: str = "refused",
) -> FitOutcome:
    """Strategy ``name`` fitted on several recordings of one unit (``names`` name them): one shared model,
    each recording's own bias, and the rule a new recording's bias is taken by (``rule_mode``, or the one
    that does best on held-back recordings). A network that replaces the seed model is written only where
    it beats least squares on held-back recordings (:mod:`sins.compensation.network_guard`; ``guard``)."""
    from sins.compensation import network_guard, referenced, world_tilt

    # Each reference's world frame levelled where it is tilted from gravity, once for every fit below.
    tilts = [world_tilt.levelled(r, interval_s) for r in recs]
    recs = [r for r, _ in tilts]

    def fit(strategy_name: str, on: list[ReferencedRecording], **more: Any) -> referenced.FittedSeveral:
        network = network_guard.guards(strategy_name)  # no guard of its own to lift
        return referenced.fit_several(
            strategy_name, on, interval_s=interval_s, params={} if guard or network else {"guard": False},
            rule_mode=rule_mode, grade=grade, screen=screen, **more,
        )  # fmt: skip

    clocks = [frame_check.recording_lag(r) for r in recs]
    verdict = None
    with _clock_named(list(zip(names, clocks, strict=True))):
        if guard and network_guard.guards(name):
            verdict = network_guard.judged(
                name, list(recs), list(names), lambda n, on: fit(n, on).strategy, stage, interval_s
            )
        network = verdict is None or verdict.kept or verdict.accel_alone
        fitted = fit(name if network else network_guard.BASELINE, list(recs), progress=progress, stage=stage)
        if verdict is not None and verdict.kept and not verdict.accel_kept:
            # Least squares' accelerometer in place of the network's, its bias rule chosen with the
            # network's: the model each of the guard's folds judged.
            fitted.strategy.accel_seed_ = np.vstack([fitted.several.seed.A0, fitted.several.seed.A])
        if verdict is not None and verdict.accel_alone:
            # The network's accelerometer beside least squares' gyro and least squares' rule, as the
            # guard's folds judged it (network_guard.with_seed_gyro).
            least = fit(network_guard.BASELINE, list(recs), stage=stage)
            strategy = network_guard.with_seed_gyro(fitted.strategy, least.strategy)
            fitted = dataclasses.replace(fitted, strategy=strategy, rule=least.rule)
    lines = [f"{n}: reference: {t.says}" for n, (_, t) in zip(names, tilts, strict=True)]
    lags = [None if c is None else c.lag_s for c in clocks]
    document = _several_document(fitted, list(names), lags, grade, lines)
    document["seed_terms"] = _own_seed_terms(list(recs), list(names), interval_s, grade)
    lines += seed_terms.lines(document["seed_terms"])
    document["reference_tilt"] = {n: t.to_dict() for n, (_, t) in zip(names, tilts, strict=True)}
    fitted.strategy.fitted_on_["reference_tilt"] = document["reference_tilt"]
    aside = [(n, a) for n, a in zip(names, fitted.set_aside, strict=True) if a.found()]
    lines += _screen_lines(list(names), fitted.set_aside, list(fitted.several.residuals))
    document["set_aside"] = [{**a.to_dict(), "recording": n} for n, a in aside]
    strategy = fitted.strategy
    how = "its learner chosen with each of the {folds} recordings held back whole ({blocks} blocks)"
    said, found = _guard_report(strategy, how, "deg", by_recording=True)
    lines += said
    document |= found
    if verdict is not None:  # kept in the model file too, as the learners' guards are
        lines += verdict.lines()
        strategy.fitted_on_["network_guard"] = document["network_guard"] = verdict.to_dict()
    elif not guard and network_guard.guards(name):
        lines.append(f"the guard is off: {name} is written without being judged held back")
    held = _held_lines(fitted.review, grade, "the recordings do", lines)
    document |= {"grade": grade, "held": held}
    return FitOutcome(fitted.strategy, lines, document)


def _own_seed_terms(
    recs: list[ReferencedRecording], names: list[str], interval_s: float, grade: str
) -> dict[str, Any]:
    """Each recording's own seed model, fitted on it alone, compared with the others' by ``grade``'s
    spreads (:func:`sins.compensation.seed_terms.differing`): the shared fit takes them as one, and says
    where they are not. A recording whose intervals alone cannot be fitted is not compared."""
    own = {}
    for name, rec in zip(names, recs, strict=True):
        try:
            fit = interval_fit.fit_intervals(
                rec, interval_s=interval_s, time_offset=False, g_sensitivity=False
            )
        except ValueError:
            continue
        own[name] = seed_terms.of_fit(fit.seed)
    return seed_terms.differing(own, grade)


#: Said under the shared seed model of a strategy that corrects with a fit of its own.
_REPLACED = (
    "{label} corrects with its own fit from readings to errors, on every recording at their mean bias, not "
    "with this seed model, which gives each recording's bias and chooses the bias rule"
)


def _several_document(
    fitted: Any, names: list[str], clocks: list[float | None], grade: str, lines: list[str]
) -> dict[str, Any]:
    """What a fit on several recordings found, said in ``lines`` and returned as its document;
    ``clocks`` each recording's reference clock against its readings, s (None where not seen)."""
    fit = fitted.several
    lines.append(
        f"fitted {fitted.strategy.label} on {len(names)} recordings of one unit: "
        f"{sum(fit.intervals)} intervals of {fit.interval_s:g} s"
    )
    table = coefficients.engineering(fit.seed, g_sensitivity=fit.g_sensitivity)
    from sins.compensation.referenced import BIAS_ONLY, replaces_seed_model

    if fitted.strategy.label == BIAS_ONLY:  # its model keeps the biases alone: the rest is not applied
        table = [c for c in table if c.term == "bias"]
    lines += coefficient_lines(table, "the shared seed model (± 1σ; the bias is the recordings' mean)")
    lines += [_REPLACED.format(label=fitted.strategy.label)] if replaces_seed_model(fitted.strategy) else []
    per_hour = np.degrees(1.0) * 3600.0
    rows, biases = [], []
    for rec_name, b, se, a, n, lag in zip(
        names, fit.gyro_bias, fit.gyro_bias_se, fit.accel_bias, fit.intervals, clocks, strict=True
    ):
        rows.append(
            [
                rec_name,
                str(n),
                *(f"{x * per_hour:.1f} ± {e * per_hour:.1f}" for x, e in zip(b, se, strict=True)),
                "-" if lag is None else f"{1e3 * lag:+.1f}",
            ]
        )
        biases.append({
            "recording": rec_name, "intervals": n, "gyro_bias_deg_h": (b * per_hour).tolist(),
            "gyro_bias_se_deg_h": (se * per_hour).tolist(), "accel_bias_m_s2": a.tolist(),
            "reference_clock_ms": None if lag is None else 1e3 * lag,
        })  # fmt: skip
    spread = fit.bias_spread() * per_hour
    lines += [
        "each recording's own gyro bias, °/h (± 1σ), and its reference's clock against its readings "
        "(ms; + behind)",
        fixed_width(["recording", "intervals", "x", "y", "z", "clock ms"], rows),
        f"spread of the bias between recordings: {spread[0]:.1f}, {spread[1]:.1f}, {spread[2]:.1f} °/h",
    ]
    lines += [
        f"{rec_name}: " + clock_words(lag, "the reference's clock")
        for rec_name, lag in zip(names, clocks, strict=True)
        if lag is not None and abs(lag) >= frame_check.REFERENCE_LAG_S
    ]
    lines += _noisy_recording_lines(fit, names, grade)
    document: dict[str, Any] = {
        "strategy": fitted.strategy.label, "recordings": names, "intervals": list(fit.intervals),
        "interval_s": fit.interval_s, "coefficients": [c.to_dict() for c in table],
        "recording_biases": biases, **_offsets(fit, lines),  # shared by the recordings, as one fit's
    }  # fmt: skip
    if fitted.rule is not None:
        rule = fitted.rule
        held = "; ".join(
            f"{'the raw readings' if m == 'raw' else m} {v:.2f}°" for m, v in rule.held_back_deg.items()
        )
        judged = (
            f" (open-loop attitude on held-back recordings, mean: {held})" if held
            else " (as named)" if len(names) >= 3
            else f" (not chosen on held-back recordings: that takes three or more, here {len(names)})"
        )  # fmt: skip
        lines += _rule_lines(rule, names, judged)
        document["bias_rule"] = rule.to_dict()
    return document


def _noisy_recording_lines(fit: Any, names: list[str], grade: str) -> list[str]:
    """A line for each recording whose own biases the fit determines only beyond the class's spread: a
    fit refuses that of a model's coefficient, but a recording's own bias is not the model's (the
    residuals behind its standard error are in the shared terms' too, which are judged), so it is said,
    not refused. An aliased unit's recording (EuRoC decimated to 100 Hz by taking every second reading)
    had a fit refused on it, whose model, written, corrects a fourth recording from 116.7° to 5.6°."""
    from sins.compensation import identifiability

    bounds = identifiability.class_bounds(grade)
    out = []
    for r, name in enumerate(names):
        own = identifiability.interval_values(fit.for_recording(r), biases_only=True)
        loose = identifiability.beyond_spread(own, bounds)
        if loose:
            out.append(
                f"{name}: its own bias is determined only beyond a {grade} unit's spread "
                f"({'; '.join(loose)}): the fit's residuals, pooled over the recordings, are large "
                "against what its intervals tell of its bias (readings aliased or noisy, a noisy reference, "
                "or a reference's clock off)"
            )
    return out


def _rule_lines(rule: BiasRule, names: list[str], judged: str) -> list[str]:
    """What ``sins fit`` says of a new recording's bias (:func:`_mode_line`), and of one that opens moving:
    the rule on the held-back recordings from their first motion, beside their raw readings there."""
    from sins.compensation.unit_bias import FROM_REST, MIN_REST_S

    line, moving = _mode_line(rule, names, judged), rule.moving_held_back_deg
    if not moving:
        return [line]
    pairs = list(zip(names, moving["rule"], moving["raw"], strict=False))
    worse = [f"{name} {v:.2f}° against {raw:.2f}°" for name, v, raw in pairs if v > raw]
    # The advice holds for a rule that reads a rest; pooled and online read none.
    advice = f": a recording that opens with a rest of {MIN_REST_S:g} s or more has its bias read there"
    said = (
        f"; worse than raw on {', '.join(worse)}{advice if rule.mode in FROM_REST else ''}" if worse
        else ", worse than raw on none"
    )  # fmt: skip
    return [
        line,
        f"a recording that opens moving: held back from their first motion (opening rests cut away), "
        f"{rule.choice} leaves {np.mean(moving['rule']):.2f}° against the raw readings' "
        f"{np.mean(moving['raw']):.2f}°{said}",
    ]


def _mode_line(rule: BiasRule, names: list[str], judged: str) -> str:
    """The rule's mode, or, where the model leaves the gyro as read, the held-back recordings the best
    rule left worse than their raw readings."""
    from sins.compensation.rule_choice import behind_by, kept_modes
    from sins.compensation.unit_bias import CHOICES, READINGS

    each, means, choice = rule.held_back_each_deg, rule.held_back_deg, rule.choice
    if rule.mode != READINGS:
        kept = kept_modes(each, each.get("raw", [])) if choice in each else []
        best = min(kept, key=means.__getitem__, default=choice)
        if best == choice:
            return f"a new recording's bias: {choice}{judged}"
        behind, se = behind_by(each[choice], each[best])
        return (
            f"a new recording's bias: {choice}{judged}; {best} is ahead by {behind:.2f}°, no more than "
            f"its standard error over these recordings ({se:.2f}°), so the simpler {choice} is taken"
        )
    best = min((m for m in CHOICES if m in means), key=means.__getitem__)
    worse = ", ".join(
        f"{name} {v:.2f}° against {raw:.2f}°"
        for name, v, raw in zip(names, each.get(best, []), each.get("raw", []), strict=False)
        if v > raw
    )
    return (
        "a new recording's gyro: left as read, as every rule for its bias left a held-back recording worse "
        f"than its raw readings (the best, {best}: {worse}){judged}"
    )


@contextmanager
def _clock_named(clocks: list[tuple[str, ReferenceLag | None]]) -> Iterator[None]:
    """A fit's refusal (the data do not determine a term) with each recording named whose reference's
    clock sits :data:`~sins.io.frame_check.REFERENCE_LAG_S` or more off its readings': such a reference
    makes every interval's residual large, which spoils the standard errors of every recording fitted
    beside it, and the refusal alone would send the user looking at the excitation."""
    try:
        yield
    except SinsInputError as exc:
        its = "its readings'"
        off = [
            f"{name}'s reference clock sits {frame_check.clock_sits(c.lag_s, its)} (add {-c.lag_s:+.4f} s "
            "to its times)"
            for name, c in clocks
            if c is not None and abs(c.lag_s) >= frame_check.REFERENCE_LAG_S
        ]
        if not off:
            raise
        raise SinsInputError(f"{exc}; but first: {'; '.join(off)}, which alone can spoil a fit") from None


def clock_words(lag_s: float, subject: str = "its clock") -> str:
    """Where a reference's clock sits against the readings' (:func:`sins.io.frame_check.reference_lag`),
    in words; from :data:`~sins.io.frame_check.REFERENCE_LAG_S` on, what that does to a fit."""
    words = f"{subject} sits {frame_check.clock_sits(lag_s)} (its turns against the gyro's)"
    if abs(lag_s) >= frame_check.REFERENCE_LAG_S:
        words += (
            "; the intervals are compared as stamped, and every one is off by the rate's change over it "
            f"times that: add {-lag_s:+.4f} s to the reference's times to align them"
        )
    return words


def _settings(config: dict[str, Any]) -> str:
    """A learner's chosen configuration as ``key value, key value``."""
    return ", ".join(f"{k} {v}" for k, v in config.items())


__all__ = [
    "FitOutcome",
    "Progress",
    "clock_words",
    "coefficient_lines",
    "fit_referenced",
    "fit_rig",
    "fit_several",
    "progress_unit",
]
