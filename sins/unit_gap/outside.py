"""Disturbances outside the library on the interval residuals: a single bias step and an oscillation.

As on samples (:mod:`sins.gap.guards`), a library effect must explain a channel better than a one-off
bias step or a hum would, or the channel goes to ``outside`` and ``unexplained``. On intervals both are
columns like any effect's (:meth:`~sins.unit_gap.intervals.IntervalResiduals.columns`): a step at an
interval boundary is the channel's bias column from that interval on; an oscillation is a cosine and a
sine of the step's time, of a period between 2.5 intervals (shorter ones average out within an interval)
and half the recording, chosen on the fit intervals. Where the best candidate is a random bias, a
disturbance is also tried beside it (:func:`beside_wander`): a wander and a step can both be there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sins.gap.report import Outside
from sins.gap.scoring import SIGNIFICANT_NATS, TIE_NATS
from sins.imu import CHANNELS
from sins.unit_gap.fitter import SensorFit
from sins.unit_gap.intervals import IntervalResiduals

Array = NDArray[np.float64]

#: Periods tried for an oscillation, per octave.
_PER_OCTAVE = 12
#: A step is placed this many intervals from either end at least, so that both sides are fitted.
_EDGE = 3


@dataclass(frozen=True)
class Tried:
    """A disturbance tried on one channel: what it is, its columns (k, 3, q), its withheld gain on the
    channel's own component, and there the fit intervals' log-likelihood less BIC's penalty for its
    parameters (a step's size and time, a hum's two amplitudes and period)."""

    outside: Outside
    columns: Array
    gain: float
    #: (n, q) the disturbance per step of the readings, one column a coefficient (``columns`` are these
    #: moved into the intervals' residuals).
    per_step: Array
    fit_score: float = 0.0


def _parameters(what: Outside) -> int:
    """A disturbance's parameters: a step's size and time, a hum's two amplitudes and period."""
    return 2 if what.kind == "bias step" else 3


def _reduction(sf: SensorFit, basis: Array, left_w: Array, column: Array) -> float:
    """How much adding ``column`` (k, 3, q) to a model whose whitened fit columns span ``basis`` and
    which leaves ``left_w`` (its whitened fit residual, flat) lowers the fit rows' sum of squares."""
    c = sf.whiten(column)[sf.fit].reshape(-1, column.shape[2])
    c = c - basis @ (basis.T @ c)
    coef = np.linalg.lstsq(c, left_w, rcond=1e-9)[0]
    return float(np.sum((c @ coef) ** 2))


def _basis(sf: SensorFit, current: Array) -> Array:
    """An orthonormal basis of the current whitened columns on the fit intervals."""
    if current.shape[2] == 0:
        return np.zeros((int(sf.fit.sum()) * 3, 0))
    q, r = np.linalg.qr(sf.whiten(current)[sf.fit].reshape(-1, current.shape[2]))
    keep = np.abs(np.diag(r)) > 1e-9 * np.abs(np.diag(r)).max(initial=0.0)
    return np.asarray(q[:, keep])


def try_disturbances(
    sf: SensorFit, res: IntervalResiduals, sensor: str, axis: int, current: Array, left: Array
) -> list[Tried]:
    """The best bias step and the best oscillation of channel ``sensor``.``axis`` beside the
    ``current`` columns (k, 3, p), which leave ``left`` (k, 3)."""
    basis = _basis(sf, current)
    left_w = sf.whiten(left)[sf.fit].reshape(-1)
    channel = CHANNELS.index(f"{sensor}.{'xyz'[axis]}")
    out = []
    bias = res.columns(sensor, np.ones((len(res.dt), 1)), axis)
    k = len(res.iv)
    boundaries = range(_EDGE, k - _EDGE)
    if len(boundaries):
        best = max(boundaries, key=lambda k0: _reduction(sf, basis, left_w, _masked(bias, k0)))
        step = _masked(bias, best)
        what = Outside(CHANNELS[channel], "bias step", 0.0, 0.0, t_s=float(res.t[res.iv.start[best]]))
        from_step = (np.arange(len(res.dt)) >= res.iv.start[best]).astype(float)[:, None]
        out.append(_tried(sf, current, step, what, axis, from_step))
    span = float(res.t[-1] - res.t[0])
    shortest = 2.5 * float(np.median(res.span))
    if span / 2.0 > shortest:
        periods = shortest * 2.0 ** (
            np.arange(int(_PER_OCTAVE * np.log2(span / 2.0 / shortest)) + 1) / _PER_OCTAVE
        )
        waves = {float(p): _wave(res, sensor, axis, float(p)) for p in periods}
        best_p = max(waves, key=lambda p: _reduction(sf, basis, left_w, waves[p]))
        what = Outside(CHANNELS[channel], "periodic", 0.0, 0.0, period_s=best_p)
        out.append(_tried(sf, current, waves[best_p], what, axis, _phases(res, best_p)))
    return out


def _masked(bias: Array, k0: int) -> Array:
    out = bias.copy()
    out[:k0] = 0.0
    return out


def _phases(res: IntervalResiduals, period_s: float) -> Array:
    """(n, 2) an oscillation's cosine and sine at the middle of every step."""
    phase = 2.0 * np.pi * 0.5 * (res.t[:-1] + res.t[1:]) / period_s
    return np.column_stack([np.cos(phase), np.sin(phase)])


def _wave(res: IntervalResiduals, sensor: str, axis: int, period_s: float) -> Array:
    return res.columns(sensor, _phases(res, period_s), axis)


def _tried(sf: SensorFit, current: Array, columns: Array, what: Outside, axis: int, per_step: Array) -> Tried:
    """The disturbance's columns fitted beside the current ones: its size and its withheld gain on
    its own component."""
    _, before = sf.solve(current)
    coef, after = sf.solve(np.concatenate([current, columns], axis=2))
    own = coef[current.shape[2] :]
    size = float(own[0]) if what.kind == "bias step" else float(np.hypot(*own[:2]))
    gain = float(sf.gains(before, after)[axis])
    score = gain - SIGNIFICANT_NATS
    fit_score = float(sf.fit_loglik(after)[axis]) - sf.bic_penalty(_parameters(what))
    outside = Outside(what.channel, what.kind, size, score, what.t_s, what.period_s)
    return Tried(outside, columns, gain, per_step, fit_score)


def explains_as_well(
    tried: list[Tried], effect_gain: float, effect_fit: float | None = None
) -> Outside | None:
    """The disturbance that explains its channel as well as an effect gaining ``effect_gain`` there
    (withheld gain above :data:`~sins.gap.scoring.SIGNIFICANT_NATS` and within
    :data:`~sins.gap.scoring.TIE_NATS` of the effect's), the better if both do; else None.

    Against a random bias (``effect_fit``: its fit intervals' log-likelihood less BIC's penalty on the
    channel), the fit intervals decide instead, as on samples (:func:`sins.gap.guards.outside_library`):
    its noise follows a step that falls inside a withheld block, where the fit intervals cannot place
    the step (any boundary within the block fits them alike); on the fit intervals it pays for trailing
    the step."""
    if effect_fit is None:
        found = [t for t in tried if t.gain > SIGNIFICANT_NATS and t.gain > effect_gain - TIE_NATS]
    else:
        found = [t for t in tried if t.gain > SIGNIFICANT_NATS and t.fit_score > effect_fit - TIE_NATS]
    return max(found, key=lambda t: t.gain).outside if found else None


def beside_wander(
    sf: SensorFit, current: Array, tried: list[Tried], axis: int, phis: Array, wander_fit: float
) -> Outside | None:
    """The disturbance that a random bias (its wander among ``phis``, fitted beside the ``current``
    columns: ``wander_fit``, its fit intervals' log-likelihood less BIC's penalty on component ``axis``)
    needs beside it, the better if both do; else None.

    A bias that wanders takes a step or a hum into its path when its noise is estimated with them in
    the residual: its driving noise grows to follow them, and the disturbance, tried beside the wander
    so estimated, gains nothing (a 0.3 °/s gyro step on EuRoC's V2_01 went to ``gyro.bias_instability``). So
    the noise is estimated again with the disturbance's columns fitted, and the pair is judged on the fit
    intervals against the wander alone: above :data:`~sins.gap.scoring.SIGNIFICANT_NATS` after BIC's
    penalty for every parameter (φ, and a step's size and time or a hum's two amplitudes and period).
    The disturbance must also predict the withheld intervals, as every candidate must (its withheld gain
    above the same): the wander of a real gyro bias takes the shape of some slow hum on the fit intervals
    alone (EuRoC's MH_01: gyro z, 0.016 °/s over 90 s, 7.5 nats there and 5.3 withheld). A recording
    whose bias wanders and holds nothing else keeps its wander."""
    found = []
    for t in tried:
        columns = np.concatenate([current, t.columns], axis=2)
        both = SensorFit.of(sf.y, sf.fit, sf.withheld, sf.joined, columns, phis)
        _, after = both.solve(columns)
        score = float(both.fit_loglik(after)[axis]) - both.bic_penalty(1 + _parameters(t.outside))
        if t.gain > SIGNIFICANT_NATS and score > wander_fit + SIGNIFICANT_NATS:
            found.append((score, t.outside))
    return max(found, key=lambda f: f[0])[1] if found else None


__all__ = [
    "Tried",
    "beside_wander",
    "explains_as_well",
    "try_disturbances",
]
