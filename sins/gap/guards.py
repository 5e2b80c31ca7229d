"""The guards that keep a library effect from taking credit for what it is not, and the rules of choice.

Candidates are accepted greedily, the one of greatest withheld gain among those whose score is
positive (:mod:`sins.gap.scoring`), until none is. Three guards keep a library effect from taking
credit for what it is not:

- a random bias tracks a single jump or a hum as well as a real instability, so a process candidate
  must drive its bias alike in all four quarters of the fit rows and leave no burst in its
  innovations (:func:`sins.gap.randombias.falsified`, applied as the channel model is fitted);
- where a disturbance outside the library (a single bias step, an oscillation) explains a channel
  as well as the best candidate does, that channel is reported in ``outside`` and ``unexplained``
  instead (:func:`outside_library`);
- candidates whose withheld gains lie within :data:`sins.gap.scoring.TIE_NATS` of the accepted one's
  are reported as indistinguishable on this data; between the two random biases, the fit rows'
  likelihood-ratio test decides (:func:`nested_choice`), and between a random bias and a regressor
  effect, the fit rows' likelihood less BIC's penalty (:func:`process_or_regressors`).

A sensor's model holds one random bias and one output map at most (:func:`exclusive`), and a candidate
is tried only where the data can say something of it (:func:`available`).
"""

from __future__ import annotations

import dataclasses
from functools import partial

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from sins.gap import disturbance
from sins.gap.candidates import CANDIDATES, Candidate, ReferenceInputs, outputs, processes
from sins.gap.channel import ChannelModel
from sins.gap.design import release_free_memory
from sins.gap.report import Outside
from sins.gap.scoring import SIGNIFICANT_NATS, TIE_NATS, ChannelTrial, Trial, trial_gain
from sins.imu import CHANNELS

Array = NDArray[np.float64]

#: A choice between rival candidates: the one chosen, those told apart from it, those that could not be.
Choice = tuple[str, tuple[str, ...], tuple[str, ...]]


def exclusive(name: str) -> set[str]:
    """The effects a model holding ``name`` takes no more: itself, and for a random bias or an output
    map the sensor's others of that kind. One random bias per sensor: the other is an alternative to
    it, not an addition. Likewise one output map (quantizing a clipped reading is not modelled)."""
    sensor, kind = name.split(".")
    for group in (processes(), outputs()):
        if kind in group:
            return {f"{sensor}.{k}" for k in group}
    return {name}


def nested_choice(best: str, trials: dict[str, Trial]) -> Choice:
    """Between a sensor's two random biases, the one the fit rows' likelihood-ratio test prefers.

    A rate random walk is a bias instability with ``τ → ∞``. Their one-step predictions of the
    withheld rows hardly differ (both lean on the last few hundred rows, far shorter than ``τ``);
    the fit rows' likelihood can tell them apart, but only with frequencies well below
    ``1 / (2π τ)``, which a session of a few ``τ`` hardly has. The instability is chosen where twice
    its log-likelihood gain exceeds χ² (p = 0.001, one degree per channel: the demeaned residual
    already favours a bias that reverts to zero by about a unit per channel); otherwise the walk,
    the simpler, and the two are reported as indistinguishable.

    Returns the choice, the candidates told apart from it and those that could not be.
    """
    sensor, kind = best.split(".")
    if kind not in processes():
        return best, (), ()
    bi, rw = trials.get(f"{sensor}.bias_instability"), trials.get(f"{sensor}.rate_random_walk")
    if bi is None or rw is None or not (bi.score > 0.0 and rw.score > 0.0) or bi.names != rw.names:
        return best, (), ()
    gain = sum(row.fit_loglik for row in bi.rows) - sum(row.fit_loglik for row in rw.rows)
    if 2.0 * gain > float(chi2.isf(0.001, len(bi.rows))):
        return f"{sensor}.bias_instability", (f"{sensor}.rate_random_walk",), ()
    return f"{sensor}.rate_random_walk", (), (f"{sensor}.bias_instability",)


def process_or_regressors(choice: Choice, trials: dict[str, Trial]) -> Choice:
    """Between a random bias and a regressor effect that both gain on the withheld rows, the one the
    fit rows' likelihood less BIC's penalty prefers.

    A random bias's filter follows any level that holds for a while: a static position's offset from
    g² sensitivity or a slow temperature drift as much as a wandering bias. With the withheld rows at
    the end of each phase, it has caught the level before they begin, and predicts them about as well
    as regressors that explain the level from the inputs, with fewer parameters. On the fit rows it
    pays for following: its innovations after every change of level, which the regressors predict.
    The regressor is taken where it is ahead there by more than :data:`sins.gap.scoring.TIE_NATS`;
    within that, the two are listed as indistinguishable.

    Takes and returns what :func:`nested_choice` returns: the choice, the candidates told apart from
    it and those that could not be.
    """
    best, told_apart, alike = choice
    if best.split(".")[1] not in processes():
        return choice

    def fit_score(name: str) -> float:
        return float(sum(row.fit_loglik - row.penalty for row in trials[name].rows))

    rivals = [
        n
        for n, trial in trials.items()
        if CANDIDATES[n].kind in ("regressors", "delay")
        and trial.score > 0.0
        and trial.names == trials[best].names
    ]
    if not rivals:
        return choice
    rival = max(rivals, key=fit_score)
    margin = fit_score(rival) - fit_score(best)
    if margin > TIE_NATS:
        return (
            rival,
            tuple(n for n in trials if n.split(".")[1] in processes() and n.startswith(rival.split(".")[0])),
            (),
        )
    if margin > -TIE_NATS:
        return best, told_apart, (*alike, rival)
    return choice


def outside_library(
    trial: Trial, process: bool, models: list[ChannelModel], withheld: NDArray[np.bool_], n_fit: int
) -> list[Outside]:
    """The channels of ``trial`` where a disturbance outside the library does as well as its effect.

    Two such disturbances are tried on each channel, fitted on the fit rows beside the model's
    regressors: a single bias step (:func:`sins.gap.disturbance.best_step`; its size and time are two
    parameters) and an oscillation (:func:`sins.gap.disturbance.best_oscillation`; frequency and two
    amplitudes, three). A library effect that explains a channel no better than a one-off step or a
    hum cannot claim it; the disturbance is reported instead. As well: a withheld gain above
    :data:`sins.gap.scoring.SIGNIFICANT_NATS`, and within :data:`sins.gap.scoring.TIE_NATS` of the
    effect's; or, where the effect is a random bias (``process``), a fit-row log-likelihood less
    BIC's penalty within :data:`sins.gap.scoring.TIE_NATS` of its own. The random bias's filter
    predicts each withheld row from the readings before it, so it follows a step that falls inside a
    withheld block, where the fit rows cannot place it; on the fit rows it pays for trailing the
    step, as it does for trailing regressors' levels (:func:`process_or_regressors`).

    ``models`` are the current (fitted) models of every channel, ``trial`` the effect's rows on them.
    """
    out = []
    for row in trial.rows:
        if row.gain <= 0.0 and trial.score > 0.0:
            continue  # the effect gains nothing here: no gain to take from it
        release_free_memory()  # what the last channel's transforms and fits freed
        found = _disturbance(models[row.channel], row, process, withheld, n_fit)
        if found is not None:
            out.append(found)
    return out


def _disturbance(
    model: ChannelModel, row: ChannelTrial, process: bool, withheld: NDArray[np.bool_], n_fit: int
) -> Outside | None:
    """The better of a bias step and an oscillation on one channel, where it does as well as the
    effect tried there (``row``; see :func:`outside_library`), else None."""
    t, residual, design = model.x.t, model.residual, model.design()
    factor = design.factor(model.fit, gram_rows=model.fit)  # one pass serves the step and the hum
    t_step, size = disturbance.best_step(residual, design, model.fit, t, factor)
    period, amplitude = disturbance.best_oscillation(residual, design, model.fit, t, factor)
    channel = CHANNELS[row.channel]
    tries = [
        (Outside(channel, "bias step", size, 0.0, t_s=t_step), partial(_step, t_step), 2, 1),
        (Outside(channel, "periodic", amplitude, 0.0, period_s=period), partial(_wave, period), 3, 2),
    ]
    found = []
    for candidate, column, k, width in tries:
        m = model.with_columns(column).fitted()
        outside_gain, penalty_k = trial_gain(model, m, withheld, n_fit, k - width)
        if process:
            as_well = m.fit_rows_loglik() - penalty_k > row.fit_loglik - row.penalty - TIE_NATS
        else:  # gains compared, as for ties: no better than the disturbance is not what happened
            as_well = outside_gain > row.gain - TIE_NATS
        if outside_gain > SIGNIFICANT_NATS and as_well:
            found.append(dataclasses.replace(candidate, score=outside_gain - SIGNIFICANT_NATS))
    return max(found, key=lambda o: o.score) if found else None


def _step(t_step: float, x: ReferenceInputs) -> Array:
    """A bias step's column of a chunk of rows: 1 after ``t_step``."""
    return (x.t > t_step)[:, None].astype(float)


def _wave(period_s: float, x: ReferenceInputs) -> Array:
    """An oscillation's columns of a chunk of rows: its cosine and sine."""
    return np.column_stack([np.cos(2 * np.pi * x.t / period_s), np.sin(2 * np.pi * x.t / period_s)])


def available(cand: Candidate, x: ReferenceInputs, readings: Array, fit: NDArray[np.bool_]) -> bool:
    """Whether the data can say anything about a candidate.

    Temperature effects need a varying temperature; saturation needs readings piled up at an
    extreme (ten or more equal to it) while the reference goes beyond it. (Quantization needs
    readings on a lattice: each channel's model holds its own, and only those channels try it.)
    """
    if "temperature" in cand.name:
        return x.temp is not None and float(np.ptp(x.temp)) > 0.5
    if not cand.name.endswith("saturation"):
        return True
    for j in range(readings.shape[1]):  # a channel's fit rows at a time: no (n, 3) copies
        r, ref = readings[fit, j], x.of(cand.sensor)[fit, j]
        top, bottom, margin = r.max(), r.min(), 1e-3 * np.abs(r).max()
        if np.sum(r == top) >= 10 and np.sum(ref > top + margin) >= 10:
            return True
        if np.sum(r == bottom) >= 10 and np.sum(ref < bottom - margin) >= 10:
            return True
    return False


__all__ = [
    "Choice",
    "available",
    "exclusive",
    "nested_choice",
    "outside_library",
    "process_or_regressors",
]
