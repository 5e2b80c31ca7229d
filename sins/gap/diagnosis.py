"""Sim-to-real gap diagnosis: where simulated and real IMU data part, which unmodelled effect causes it.

The model of a channel's reading error ``e = reading − reference`` is the
baseline (the seed model's bias, scale/misalignment and g-sensitivity rows,
fitted by least squares, plus white noise) and any effects accepted so far.
Every library effect not in the model is a candidate, of one of three kinds:

- *regressors* (scale nonlinearity and asymmetry, g² sensitivity, temperature
  bias and scale, size effect): columns added to the channel's least-squares
  fit;
- *delay* (time offset): the reading is the reference at ``t − τ``, cubic
  Hermite between rows; ``τ`` is found by a 1-D search beside the regressors;
- *processes* (bias instability, rate random walk): a first-order Gauss–Markov
  or random-walk bias under the white noise, fitted by the likelihood of the fit
  rows' innovations, the regressors refitted beside it by generalised least
  squares, and predicted one step ahead by the steady-state Kalman filter;
- *output maps* (quantization, saturation): a quantizer on the readings'
  lattice (each reading rounded, or increments rounded with the remainder
  carried, after white noise whose level it fits; :mod:`sins.gap.lattice`), or the
  prediction clipped at the readings' pile-up.

Each candidate is fitted on the fit rows and scored on the withheld rows: the
Gaussian log-likelihood gain of its withheld residual over the current
model's. On readings that lie on a lattice, each is scored instead by the
probability of the reading at its recorded resolution: a quantizer's
probability of its lattice index, a continuous model's of the same lattice bin.
Its parameters need no penalty beyond what their errors cost the withheld
rows; its score is the gain less a significance threshold,
:data:`SIGNIFICANT_NATS` (``ln(20 / 0.05)``: a likelihood ratio fitted on other
rows passes it by chance with probability ``0.05 / 20`` at most, Markov's
bound). A random bias, whose filter also follows the withheld rows, may
correct the current coefficients' errors there; what that can gain by chance
is added to its threshold (:func:`_refit_allowance`). Candidates are accepted
greedily, the one of greatest gain among those whose score is positive, until
none is. Three guards keep a library effect from taking credit for what it is
not:

- a random bias tracks a single jump or a hum as well as a real instability,
  so a process candidate must drive its bias alike in all four quarters of the
  fit rows and leave no burst in its innovations (:func:`sins.gap.randombias.falsified`);
- where a disturbance outside the library (a single bias step, an oscillation)
  explains a channel as well as the best candidate does, that channel is
  reported in ``outside`` and ``unexplained`` instead (:func:`_outside`);
- candidates whose withheld gains lie within :data:`TIE_NATS` of the accepted
  one's are reported as indistinguishable on this data; between the two random
  biases, the fit rows' likelihood-ratio test decides (:func:`_nested_choice`).

The noise floor of a channel is the white-noise level the model expects,
measured without the model: the spread of first differences of the residual,
which slowly varying unmodelled errors do not reach (and which holds rounding's
spread as well), within the fit rows and within the withheld rows, the larger
of the two. Rounding's spread depends on where each hold's mean sits in its
lattice cell: where readings leave their level a few times an hour, one portion
may see more of it than the other, or none. Where the gap lies is told by
input quartiles and by the residual's Allan deviation against that white noise
(:func:`allan_deviation`).
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicHermiteSpline
from scipy.optimize import minimize_scalar
from scipy.stats import chi2

from sins.errors import SinsInputError
from sins.gap import disturbance, lattice, randombias
from sins.imu import BASELINE, CHANNELS, EFFECT_NAMES, display_unit
from sins.nav.earth import G0
from sins.series import CalibrationData

Array = NDArray[np.float64]

#: A channel's withheld residual counts as above its floor beyond this ratio (3 % plus sampling error).
SIGNIFICANT_RATIO = 1.03
#: The withheld log-likelihood gain a candidate needs, in nats: ln(20 / 0.05), a chance of 0.05 / 20
#: that one of some twenty candidates passes where the current model holds (see :func:`_trial_gain`).
SIGNIFICANT_NATS = float(np.log(20 / 0.05))
#: Below any real sensor's noise (2e-5 °/h, 1e-11 g): the floor of noiseless (simulated) readings, SI units.
_TINY = 1e-10
#: Candidates whose withheld log-likelihood gains differ by less than this are
#: indistinguishable on the data: a likelihood ratio below e³ ≈ 20, short of "strong" evidence.
TIE_NATS = 3.0
#: The white noise before rounding, in quantization steps, tried for the quantization candidate.
_NOISE_PER_STEP = (0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.45, 0.7, 1.0)
#: The two quantizers (see :mod:`sins.gap.lattice`).
_QUANTIZERS = {"rounded": lattice.rounded, "carried": lattice.carried}
#: Their readings' log-probabilities alone, for choosing one (the carried kind's filter gives all at once).
_QUANTIZER_LOGLIK: dict[str, Callable[[Array, Array, float], Array]] = {
    "rounded": lattice.rounded_loglik,
    "carried": lambda m, mu, s: lattice.carried(m, mu, s)[0],
}
#: The random-bias candidates: a sensor's model has at most one.
_PROCESSES = ("bias_instability", "rate_random_walk")
#: The output-map candidates: a sensor's model has at most one.
_OUTPUTS = ("quantization", "saturation")
#: Input quartiles reported where the excess concentrates.
_FEATURES = ("|ω|", "|f|", "temperature", "rate of change", "time")


@dataclass(frozen=True)
class Candidate:
    """One library effect as the diagnosis sees it: its name, its channels and its kind."""

    name: str
    sensor: str
    kind: str  # "regressors" | "delay" | "process" | "output"
    columns: Callable[[_Inputs, int], Array] | None = None  # (n, k) extra regressors of axis i


@dataclass
class _Inputs:
    """The reference inputs of every row, and what the regressors are built from."""

    t: Array
    omega: Array
    f: Array
    omega_dot: Array
    u_rate: dict[str, Array]  # the reference's rate of change, central differences
    temp: Array | None
    step_s: float
    _splines: dict[tuple[str, int], CubicHermiteSpline] = field(default_factory=dict)

    def of(self, sensor: str) -> Array:
        return self.omega if sensor == "gyro" else self.f

    def lag(self, sensor: str, axis: int, delay_s: float) -> Array:
        """``u(t − τ) − u(t)`` of the reference ``u`` of one axis: cubic Hermite between the rows, with
        slopes from central differences, held at the ends (the spline built once per axis)."""
        u = self.of(sensor)[:, axis]
        key = (sensor, axis)
        if key not in self._splines:
            self._splines[key] = CubicHermiteSpline(self.t, u, self.u_rate[sensor][:, axis])
        return np.asarray(self._splines[key](np.clip(self.t - delay_s, self.t[0], self.t[-1]))) - u


def baseline_columns(sensor: str, omega: Array, f: Array) -> Array:
    """The baseline's regressors of one channel: bias and scale/misalignment, and the gyro's g-sensitivity."""
    u = omega if sensor == "gyro" else f
    base = [np.ones(len(u)), u[:, 0], u[:, 1], u[:, 2]]
    if sensor == "gyro":
        base += [f[:, 0], f[:, 1], f[:, 2]]
    return np.stack(base, axis=1)


def _size_columns(x: _Inputs, i: int) -> Array:
    w, wd = x.omega, x.omega_dot
    cols = []
    for j in range(3):
        r = np.zeros(3)
        r[j] = 1.0
        cols.append((np.cross(wd, r) + np.cross(w, np.cross(w, r)))[:, i])
    return np.stack(cols, axis=1)


def _g2_columns(x: _Inputs, i: int) -> Array:
    f = x.f / G0  # in g: keeps the columns near the others' size
    return np.stack([f[:, j] * f[:, k] for j in range(3) for k in range(j, 3)], axis=1)


def _temp(x: _Inputs) -> Array:
    assert x.temp is not None
    return x.temp - float(np.mean(x.temp))


def _candidates(sensor: str) -> list[Candidate]:
    def own(fn: Callable[[Array], Array]) -> Callable[[_Inputs, int], Array]:
        return lambda x, i: fn(x.of(sensor)[:, i])[:, None]

    out = [
        Candidate(f"{sensor}.scale_nonlinearity", sensor, "regressors", own(np.square)),
        Candidate(f"{sensor}.scale_asymmetry", sensor, "regressors", own(np.abs)),
        Candidate(
            f"{sensor}.temperature_bias",
            sensor,
            "regressors",
            lambda x, i: np.stack([_temp(x), _temp(x) ** 2], axis=1),
        ),
        Candidate(
            f"{sensor}.temperature_scale",
            sensor,
            "regressors",
            lambda x, i: (_temp(x) * x.of(sensor)[:, i])[:, None],
        ),
        Candidate(f"{sensor}.time_offset", sensor, "delay"),
        Candidate(f"{sensor}.bias_instability", sensor, "process"),
        Candidate(f"{sensor}.rate_random_walk", sensor, "process"),
        Candidate(f"{sensor}.quantization", sensor, "output"),
        Candidate(f"{sensor}.saturation", sensor, "output"),
    ]
    if sensor == "gyro":
        out.append(Candidate("gyro.g2_sensitivity", "gyro", "regressors", _g2_columns))
    else:
        out.append(Candidate("accel.size_effect", "accel", "regressors", _size_columns))
    return out


#: Every candidate the diagnosis knows, by effect name (every library effect beyond the baseline).
CANDIDATES: dict[str, Candidate] = {c.name: c for s in ("gyro", "accel") for c in _candidates(s)}
assert set(CANDIDATES) == set(EFFECT_NAMES) - set(BASELINE) - {"gyro.bias", "accel.bias"}


@dataclass(frozen=True)
class EffectScore:
    """A candidate's score in the round it was accepted or last scored: its withheld log-likelihood
    gain less what it needs to be significant (:data:`SIGNIFICANT_NATS`, and a random bias's
    allowance)."""

    name: str
    channels: tuple[str, ...]
    score: float
    accepted: bool
    #: Candidates this one could not be told from (gains within :data:`TIE_NATS`); set on accepted ones.
    indistinguishable: tuple[str, ...] = ()
    #: Why a candidate that scored above 0 was not accepted all the same ("" otherwise).
    not_accepted_because: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON form; ``score`` is None for a candidate ruled out (falsified)."""
        return {
            "name": self.name,
            "channels": list(self.channels),
            "score": self.score if np.isfinite(self.score) else None,  # None: ruled out (falsified)
            "accepted": self.accepted,
            "indistinguishable_from": list(self.indistinguishable),
            "not_accepted_because": self.not_accepted_because or None,
        }


@dataclass(frozen=True)
class Outside:
    """A disturbance outside the library that explains a channel's gap as well as any library effect."""

    channel: str
    kind: str  # "bias step" | "periodic"
    size: float  # the step's size or the oscillation's amplitude, SI units of the channel
    score: float  # withheld log-likelihood gain less SIGNIFICANT_NATS, as for the candidates
    t_s: float | None = None  # when the step happens
    period_s: float | None = None  # the oscillation's period

    def to_dict(self) -> dict[str, Any]:
        """JSON form, without the fields that do not apply."""
        return {k: v for k, v in dataclasses.asdict(self).items() if v is not None}

    def what(self) -> str:
        """The disturbance in words, in the channel's display unit."""
        size, unit = display_unit(self.channel)
        if self.kind == "periodic":
            return f"an oscillation of {self.size / size:.3g} {unit} every {self.period_s:.3g} s"
        return f"a bias step of {self.size / size:+.3g} {unit} at {self.t_s:.1f} s"

    def describe(self) -> str:
        """As a ``where`` entry: the view it belongs to, then :meth:`what`."""
        return f"{'frequency' if self.kind == 'periodic' else 'time'}: {self.what()}"


@dataclass(frozen=True)
class GapReport:
    """What :func:`diagnose` found; ``to_dict`` gives the stable JSON keys."""

    channels: dict[str, dict[str, float]]
    where: list[dict[str, Any]]
    effects: list[EffectScore]
    diagnosis: list[str]
    unexplained: list[str]
    #: Channels whose gap a disturbance outside the library (a bias step, an oscillation) explains.
    outside: list[Outside] = field(default_factory=list)
    #: Per channel: ``tau_s`` and the Allan deviation of the residual ``before`` and ``after`` the
    #: accepted effects, and of the white noise the model expects (``model``), SI units.
    allan: dict[str, dict[str, list[float]]] = field(default_factory=dict)
    #: Per channel and input: the share of the withheld excess in each quartile of that input.
    quartiles: dict[str, dict[str, list[float]]] = field(default_factory=dict)
    rows: tuple[int, int] = (0, 0)  # fit, withheld
    unreferenced: int = 0  # rows left out for want of a per-sample reference
    model: tuple[str, ...] = BASELINE
    residual_before: Array = field(default_factory=lambda: np.zeros((0, 6)))
    residual_after: Array = field(default_factory=lambda: np.zeros((0, 6)))
    t_withheld: Array = field(default_factory=lambda: np.zeros(0))
    #: The models' predicted errors of every referenced row, (n, 6) SI: before and after the accepted effects.
    predicted_before: Array = field(default_factory=lambda: np.zeros((0, 6)))
    predicted_after: Array = field(default_factory=lambda: np.zeros((0, 6)))

    def to_dict(self) -> dict[str, Any]:
        """The stable JSON form: the findings and Allan deviations, not the series."""
        return {
            "channels": self.channels,
            "where": self.where,
            "effects": [e.to_dict() for e in self.effects],
            "diagnosis": self.diagnosis,
            "unexplained": self.unexplained,
            "outside": [o.to_dict() for o in self.outside],
            "allan": self.allan,
        }


# --------------------------------------------------------------------------- the channel models


class _ChannelModel:
    """One channel's current model: regressor columns, an optional process, an optional output map."""

    def __init__(
        self, x: _Inputs, sensor: str, axis: int, error: Array, reading: Array, fit: NDArray[np.bool_]
    ) -> None:
        self.x, self.sensor, self.axis = x, sensor, axis
        self.error, self.reading, self.fit = error, reading, fit
        self.lattice = lattice.find(reading[fit])
        self.columns: list[Array] = [baseline_columns(sensor, x.omega, x.f)]
        self.delayed = False  # whether the reading is the reference at t − τ
        self.delay_s: float | None = None  # τ, once fitted
        self.process: str | None = None  # "bias_instability" | "rate_random_walk"
        self.process_on_trial = True  # a candidate's process must pass falsified(); the model's need not
        self.output: str | None = None  # "quantization" | "saturation"
        self.quantizer: tuple[str, float] | None = None  # its kind and noise per step, once fitted
        self.loglik_rows: Array | None = None  # a quantizer's ln P of every row's reading, once predicted
        self.fit_loglik = np.nan  # the process's innovations' log-likelihood on the fit rows, once predicted

    def with_candidate(self, cand: Candidate, on_trial: bool = True) -> _ChannelModel:
        m = copy.copy(self)
        m.columns = list(self.columns)
        if cand.kind == "regressors":
            assert cand.columns is not None
            m.columns.append(cand.columns(self.x, self.axis))
        elif cand.kind == "delay":
            m.delayed, m.delay_s = True, None
        elif cand.kind == "process":
            m.process, m.process_on_trial = cand.name.split(".")[1], on_trial
        else:
            m.output, m.quantizer, m.loglik_rows = cand.name.split(".")[1], None, None
        return m

    def with_columns(self, columns: Array) -> _ChannelModel:
        m = copy.copy(self)
        m.columns = [*self.columns, columns]
        return m

    @property
    def n_params(self) -> int:
        k = sum(c.shape[1] for c in self.columns)
        if self.process is not None:
            k += 2 if self.process == "bias_instability" else 1
        return k + (self.output is not None) + self.delayed

    def predict(self) -> Array:
        """The predicted error of every row, all parameters fitted on the fit rows."""
        a = np.hstack(self.columns)
        rows, rcond = self.fit, None
        scale = np.maximum(np.abs(a[rows]).max(axis=0), 1e-300)
        if self.output == "saturation":
            # Clipped readings say nothing of the unclipped model; what the other rows hardly
            # excite (an axis that is only ever clipped when it sees gravity) is left at zero.
            seen = self.reading[self.fit]
            rows, rcond = self.fit & (self.reading < seen.max()) & (self.reading > seen.min()), 1e-3
        lag = np.zeros_like(self.error)  # what a delay adds to the error: the reference at t − τ less at t
        if self.delayed:
            if self.delay_s is None:
                self.delay_s = _fit_delay(self.x, self.sensor, self.axis, self.error, a / scale, rows)
            lag = self.x.lag(self.sensor, self.axis, self.delay_s)
        error = self.error - lag
        coef, *_ = np.linalg.lstsq(a[rows] / scale, error[rows], rcond=rcond)
        pred = (a / scale) @ coef
        if self.process is not None:
            y = error - pred
            process = self._fit_process(y)
            # A random bias misleads least squares: a walk's level in each static position passes for
            # scale factors. Generalised least squares instead: the innovations filter is linear, so
            # the regressors that whiten best are those fitted to the filtered error and columns.
            phi, gain = process.phi, process.gain
            whitened = np.column_stack([randombias.innovations(c, phi, gain) for c in (a / scale).T])
            target = randombias.innovations(error, phi, gain)
            coef, *_ = np.linalg.lstsq(whitened[rows], target[rows], rcond=rcond)
            pred = (a / scale) @ coef
            y = error - pred
            process = self._fit_process(y)
            if self.process_on_trial and randombias.falsified(process, self.fit, self.x.t):
                return np.full_like(pred, np.nan)  # not this process: see randombias.falsified
            self.fit_loglik = process.fit_loglik  # for _nested_choice
            pred = pred + y - process.innovations
        pred = pred + lag
        if self.output == "quantization":
            pred = self._quantized(pred, a / scale)
        elif self.output == "saturation":
            reference = self.reading - self.error
            top, bottom = float(self.reading[self.fit].max()), float(self.reading[self.fit].min())
            pred = np.clip(reference + pred, bottom, top) - reference
        return pred

    def fit_rows_loglik(self, residual: Array) -> float:
        """The fit rows' Gaussian log-likelihood (own variance): of the process's innovations where
        the model has a random bias, of ``residual``, the model's, otherwise. Once predicted."""
        return self.fit_loglik if self.process is not None else randombias.log_likelihood(residual[self.fit])

    def _fit_process(self, y: Array) -> randombias.RandomBiasFit:
        """The random bias under the residual ``y``, its white part from first differences within the
        fit rows (as the floor's), not straddling the withheld blocks: a walk's increments over a
        block would inflate it."""
        r = max(noise_floor(y, self.fit) ** 2, _TINY**2)
        walk = self.process == "rate_random_walk"
        return randombias.fit(y, self.fit, self.x.step_s, r, walk)

    def _quantized(self, pred: Array, columns: Array) -> Array:
        """The expected reading of the quantizer the fit rows' likelihood prefers; sets ``loglik_rows``.

        Rounded or carried, and the white noise before the rounding (per step, over
        :data:`_NOISE_PER_STEP`): chosen once; the models built on this one keep them. For the
        rounded kind the regressors and the noise are then refitted by the readings' own likelihood
        (:func:`lattice.fit_rounded`): least squares on rounded readings misplaces the mean.
        """
        assert self.lattice is not None
        reference = self.reading - self.error
        m = self.lattice.index(self.reading)
        mu = self.lattice.units(reference + pred)
        if self.quantizer is None:
            choices = [(k, s) for k in _QUANTIZERS for s in _NOISE_PER_STEP]
            if abs(self.lattice.offset) > 1e-9 * self.lattice.step:
                choices = [c for c in choices if c[0] == "rounded"]  # differences of a lattice have no offset
            self.quantizer = max(
                choices, key=lambda c: float(_QUANTIZER_LOGLIK[c[0]](m, mu, c[1])[self.fit].sum())
            )
        kind, s = self.quantizer
        if kind == "rounded":
            delta, s = lattice.fit_rounded(m[self.fit], mu[self.fit], columns[self.fit], s)
            mu, self.quantizer = mu + columns @ delta, ("rounded", s)
        self.loglik_rows, expected, _ = _QUANTIZERS[kind](m, mu, s)
        return expected * self.lattice.step + self.lattice.offset - reference


def _fit_delay(
    x: _Inputs, sensor: str, axis: int, error: Array, columns: Array, rows: NDArray[np.bool_]
) -> float:
    """The delay τ whose lag, with the regressors fitted beside it, leaves the least on the fit rows.

    To first order the lag is ``−τ u̇``, a column whose coefficient is ``τ``; the search refines it
    within two rows either side, where the rest matters: a step in the reference (a rig turning
    faster than a row) is smoothed differently from its slope.
    """
    a = columns[rows]
    slope = -x.u_rate[sensor][rows, axis : axis + 1]
    coef, *_ = np.linalg.lstsq(np.hstack([a, slope]), error[rows], rcond=None)
    first = float(coef[-1])

    def left(tau: float) -> float:
        target = (error - x.lag(sensor, axis, tau))[rows]
        c, *_ = np.linalg.lstsq(a, target, rcond=None)
        return float(np.sum((target - a @ c) ** 2))

    span = 2.0 * x.step_s
    found = minimize_scalar(
        left, bounds=(first - span, first + span), method="bounded", options={"xatol": 1e-3 * x.step_s}
    )
    return float(found.x) if found.fun < left(first) else first


# --------------------------------------------------------------------------- the diagnosis


def _inputs(data: CalibrationData) -> _Inputs:
    t = data.t
    grad = (lambda a: np.gradient(a, t, axis=0)) if len(t) > 2 else np.zeros_like
    return _Inputs(
        t=t,
        omega=data.ref_gyro,
        f=data.ref_accel,
        omega_dot=grad(data.ref_gyro),
        u_rate={"gyro": grad(data.ref_gyro), "accel": grad(data.ref_accel)},
        temp=data.temp,
        step_s=float(np.median(np.diff(t))),
    )


def regressors_of(name: str, data: CalibrationData) -> list[Array]:
    """The columns the regressor candidate ``name`` adds to each of its sensor's three channels.

    What the diagnosis fits beside the baseline's columns; exposed for oracles that ask what a
    candidate could absorb (``tools/bench_gap.py``).
    """
    cand = CANDIDATES.get(name)
    if cand is None or cand.columns is None:
        raise ValueError(f"{name!r} is not a regressor candidate")
    if "temperature" in name and data.temp is None:
        where = data.source or "the recording"
        raise ValueError(f"{name!r} needs a temperature column, and {where} has none")
    x = _inputs(data)
    return [cand.columns(x, i) for i in range(3)]


def noise_floor(residual: Array, rows: NDArray[np.bool_] | None = None) -> float:
    """White-noise level of a residual series from its first differences: ``std(Δr) / √2``.

    Differencing removes what varies slowly (unmodelled scale, temperature or bias effects) and
    keeps white noise of any distribution, quantised readings' included, at twice its variance.
    With ``rows``, only differences between consecutive rows both in it count (0 where none do).
    """
    d = np.diff(residual)
    if rows is not None:
        d = d[rows[1:] & rows[:-1]]
    return float(np.std(d) / np.sqrt(2.0)) if len(d) else 0.0


def _gain(before: Array, after: Array, withheld: NDArray[np.bool_]) -> float:
    """Withheld log-likelihood gain (Gaussian, own variance)."""
    if np.isnan(after).any():
        return -np.inf
    s0 = float(np.mean(before[withheld] ** 2)) + _TINY**2
    s1 = float(np.mean(after[withheld] ** 2)) + _TINY**2
    return 0.5 * int(withheld.sum()) * float(np.log(s0 / s1))


def _trial_gain(
    current: _ChannelModel, trial: _ChannelModel, before: Array, after: Array,
    withheld: NDArray[np.bool_], n_fit: int, extra: int = 0,
) -> tuple[float, float]:  # fmt: skip
    """A trial model's withheld log-likelihood gain over the current one (whose residual is
    ``before``), and BIC's penalty for its extra parameters, for comparisons on the fit rows.

    Readings off a lattice: :func:`_gain`. On a lattice, each withheld reading's probability at the
    readings' resolution: a quantizer's own, a continuous model's of the reading's lattice bin (its
    residual Gaussian with its own variance).
    ``extra`` counts parameters the trial has beyond its columns (a step's time, a hum's frequency).

    The gain needs no penalty for the trial's parameters: they were fitted on other rows, and each
    one's error costs the withheld likelihood what it is worth. Where the current model holds, the
    withheld likelihood ratio of a model fitted on the fit rows has expectation 1 at most, so it
    exceeds ``e^T`` with probability ``e^-T`` at most (Markov): :data:`SIGNIFICANT_NATS` is ``T``.
    (Approximately: each model's variance here is its own withheld mean square.)
    """
    k = trial.n_params - current.n_params + extra
    penalty = 0.5 * k * float(np.log(n_fit))
    if trial.lattice is None or np.isnan(after).any():
        return _gain(before, after, withheld), penalty

    def loglik(model: _ChannelModel, residual: Array) -> float:
        if model.loglik_rows is not None:
            return float(model.loglik_rows[withheld].sum())
        assert trial.lattice is not None
        sigma = float(np.sqrt(np.mean(residual[withheld] ** 2))) + _TINY
        return float(lattice.binned(residual[withheld], trial.lattice.step, sigma).sum())

    return loglik(trial, after) - loglik(current, before), penalty


def _refit_allowance(models: list[_ChannelModel], withheld: NDArray[np.bool_]) -> float:
    """What a random bias may gain on the withheld rows where the current models hold, beyond
    :data:`SIGNIFICANT_NATS`: the part of their error that comes from coefficients fitted on the
    fit rows alone, at probability ``1 − e^-T``.

    A random bias's filter follows the withheld readings as they come, so it also corrects the
    current regressors' coefficient errors there: on a drive whose withheld rows are its last
    straight, a misfit that the fit rows' turns could not pin down. With white noise of variance
    ``σ²`` and columns ``A``, the coefficients' error is ``N(0, σ² (A_fᵀA_f)⁻¹)`` and the withheld
    log-likelihood it costs is ``½ Σ λ_j χ²₁``, ``λ`` the eigenvalues of ``(A_fᵀA_f)⁻¹ A_wᵀA_w``:
    at most ``½ λ_max χ²`` with as many degrees as there are nonzero ``λ``. On a rig whose holds
    are all split alike, ``λ ≈ n_withheld / n_fit`` for every column.

    The random bias's gain over the fitted current model is its gain over the true one (beyond
    ``T`` with probability ``e^-T`` at most, :func:`_trial_gain`) plus this loss (beyond the
    allowance with probability ``e^-T``): beyond both with probability ``2 e^-T`` at most.
    """
    lam_max, degrees = 0.0, 0
    for m in models:
        a = np.hstack(m.columns)
        a_fit = a[m.fit]
        scale = np.maximum(np.abs(a_fit).max(axis=0), 1e-300)
        _, s, vt = np.linalg.svd(a_fit / scale, full_matrices=False)
        keep = s > s[0] * max(a_fit.shape) * np.finfo(float).eps  # lstsq's cut-off
        lam = np.linalg.svd((a[withheld] / scale) @ vt[keep].T / s[keep], compute_uv=False) ** 2
        lam_max = max(lam_max, float(lam.max(initial=0.0)))
        degrees += int(np.sum(lam > 1e-9 * lam.max(initial=0.0)))
    if degrees == 0:
        return 0.0
    return 0.5 * lam_max * float(chi2.isf(np.exp(-SIGNIFICANT_NATS), degrees))


def _available(cand: Candidate, x: _Inputs, readings: Array, fit: NDArray[np.bool_]) -> bool:
    """Whether the data can say anything about a candidate.

    Temperature effects need a varying temperature; saturation needs readings piled up at an
    extreme (ten or more equal to it) while the reference goes beyond it. (Quantization needs
    readings on a lattice: each channel's model holds its own, and only those channels try it.)
    """
    if "temperature" in cand.name:
        return x.temp is not None and float(np.ptp(x.temp)) > 0.5
    r = readings[fit]
    if cand.name.endswith("saturation"):
        ref = x.of(cand.sensor)[fit]
        for j in range(r.shape[1]):
            top, bottom, margin = r[:, j].max(), r[:, j].min(), 1e-3 * np.abs(r[:, j]).max()
            if np.sum(r[:, j] == top) >= 10 and np.sum(ref[:, j] > top + margin) >= 10:
                return True
            if np.sum(r[:, j] == bottom) >= 10 and np.sum(ref[:, j] < bottom - margin) >= 10:
                return True
        return False
    return True


def _check(data: CalibrationData, holdout: float) -> None:
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


def diagnose(
    data: CalibrationData,
    holdout: float = 0.3,
    model: tuple[str, ...] = BASELINE,
    progress: Callable[[str], None] | None = None,
) -> GapReport:
    """Find where the model fails on withheld data, which effects explain it, how far they do.

    Parameters
    ----------
    data : readings beside reference inputs (a rig recording, or an IMU recording with its truth)
    holdout : the fraction withheld: the last part of every phase (of the whole recording without phases)
    model : the effect names of the simulation's model; the baseline's are always in it, and any other
        is fitted from the start and is no candidate
    progress : called with each candidate's name as it is scored
    """
    _check(data, holdout)
    all_rows = len(data)
    data = data.referenced()  # rows without a per-sample reference (a hand-turned rotation) say nothing
    unknown = [n for n in model if n not in EFFECT_NAMES]
    if unknown:
        raise SinsInputError(f"model: unknown effect {unknown[0]!r} (see `sins effects`)")
    withheld = data.held_back(holdout)
    fit = ~withheld
    x = _inputs(data)
    n_fit = int(fit.sum())
    readings = np.hstack([data.gyro, data.accel])
    errors = readings - np.hstack([data.ref_gyro, data.ref_accel])
    models = [
        _ChannelModel(x, ch.split(".")[0], i % 3, errors[:, i], readings[:, i], fit)
        for i, ch in enumerate(CHANNELS)
    ]
    for name in model:
        if name in CANDIDATES:
            cand = CANDIDATES[name]
            for i, ch in enumerate(CHANNELS):
                if ch.startswith(cand.sensor):
                    models[i] = models[i].with_candidate(cand, on_trial=False)
    residual = np.stack([m.error - m.predict() for m in models], axis=1)
    before = residual.copy()
    # Both portions measure the same white noise; where it is rounding's, its level depends on
    # where each hold's mean sits in its lattice cell, and a portion may see no reading change.
    floors = np.array([max(noise_floor(r, fit), noise_floor(r, withheld), _TINY) for r in residual.T])

    accepted: list[str] = []
    scores: dict[str, EffectScore] = {}
    why_not: dict[str, str] = {}  # why a candidate whose latest score is above 0 was passed over
    outside: list[Outside] = []
    outside_channels: set[str] = set()  # of ``outside``, kept beside it
    taken = set().union(*(_exclusive(n) for n in model))
    remaining = [c for c in CANDIDATES.values() if c.name not in taken]
    while remaining:
        round_scores: dict[str, _Trial] = {}
        for cand in remaining:
            if progress:
                progress(cand.name)
            chans = [i for i, ch in enumerate(CHANNELS) if ch.startswith(cand.sensor)]
            if not _available(cand, x, readings[:, chans], fit):
                continue
            trial = _Trial()
            for i in chans:
                if CHANNELS[i] in outside_channels:
                    continue  # explained by a disturbance outside the library: nothing to add there
                if cand.name.endswith("quantization") and models[i].lattice is None:
                    continue
                m, r = _tried(models[i], cand)
                gain, penalty = _trial_gain(models[i], m, residual[:, i], r, withheld, n_fit)
                trial.add(i, gain, penalty, m.fit_rows_loglik(r))
            if trial.channels:
                if cand.kind == "process":
                    trial.allowance = _refit_allowance([models[i] for i in trial.channels], withheld)
                round_scores[cand.name] = trial
        for name, trial in round_scores.items():
            scores[name] = EffectScore(name, trial.names, trial.score, False)
            why_not.pop(name, None)
        positive = [n for n in round_scores if round_scores[n].score > 0.0]
        if not positive:
            break
        # Significance is each candidate's own test; of those that pass, the one that explains the
        # withheld rows best: a random bias's allowance is no evidence against it.
        best = max(positive, key=lambda n: round_scores[n].gain)
        best, told_apart, alike = _process_or_regressors(*_nested_choice(best, round_scores), round_scores)
        process = CANDIDATES[best].kind == "process"
        disturbances = _outside(round_scores[best], process, models, residual, x.t, fit, withheld, n_fit)
        if disturbances:  # the best candidate's gain there is a step's or a hum's: score again without
            outside += disturbances
            outside_channels |= {o.channel for o in disturbances}
            for name in round_scores:
                if set(scores[name].channels) <= outside_channels:
                    why_not[name] = "a disturbance outside the library explains its channels as well"
            continue
        ties = alike + tuple(
            n
            for n, trial in round_scores.items()
            if n not in (best, *told_apart, *alike) and abs(trial.gain - round_scores[best].gain) < TIE_NATS
        )
        accepted.append(best)
        scores[best] = dataclasses.replace(scores[best], accepted=True, indistinguishable=ties)
        for name in told_apart:
            why_not[name] = f"the fit rows' likelihood prefers {best}"
        for name in ties:
            why_not[name] = f"this data cannot tell it from {best}, which was taken"
        for name in _exclusive(best) - {best}:
            what = "random bias" if name.split(".")[1] in _PROCESSES else "output map"
            why_not.setdefault(name, f"a sensor takes one {what}, and {best} was taken")
        for i in round_scores[best].channels:
            models[i], residual[:, i] = _tried(models[i], CANDIDATES[best])
        remaining = [c for c in remaining if c.name not in _exclusive(best)]

    rms_before = np.sqrt(np.mean(before[withheld] ** 2, axis=0))
    rms_after = np.sqrt(np.mean(residual[withheld] ** 2, axis=0))
    channels = {
        ch: {
            "rms_before": float(rms_before[i]),
            "rms_after": float(rms_after[i]),
            "noise_floor": float(floors[i]),
        }
        for i, ch in enumerate(CHANNELS)
    }
    # What the library leaves may still be a step or a hum, too small to lift the RMS by 3 % but
    # significant by its withheld likelihood: a gap all the same.
    for i, ch in enumerate(CHANNELS):  # each adds to its own channel only: the set before them holds
        if ch not in outside_channels:
            alone = _Trial([_ChannelTrial(i, 0.0, 0.0, np.nan)])
            outside += _outside(alone, False, models, residual, x.t, fit, withheld, n_fit)
    outside.sort(key=lambda o: CHANNELS.index(o.channel))
    disturbed = {CHANNELS.index(o.channel) for o in outside}
    gapped = [i for i in range(6) if rms_before[i] > SIGNIFICANT_RATIO * floors[i] or i in disturbed]
    gapped.sort(key=lambda i: -rms_before[i] / floors[i])
    quartiles = {ch: _quartile_shares(before[:, i], floors[i], x, withheld) for i, ch in enumerate(CHANNELS)}
    allan = {ch: _allan(before[:, i], residual[:, i], floors[i], x.step_s) for i, ch in enumerate(CHANNELS)}
    where: list[dict[str, Any]] = [
        {
            "channel": CHANNELS[i],
            "excess": float(rms_before[i] / floors[i]),
            "concentrates": _concentrates(quartiles[CHANNELS[i]], allan[CHANNELS[i]])
            + [o.describe() for o in outside if o.channel == CHANNELS[i]],
        }
        for i in gapped
    ]
    unexplained = [
        ch for i, ch in enumerate(CHANNELS) if rms_after[i] > SIGNIFICANT_RATIO * floors[i] or i in disturbed
    ]
    # Accepted effects first, in the order they were accepted; then the rest, best score first.
    passed_over = [
        dataclasses.replace(e, not_accepted_because=why_not.get(e.name, "") if e.score > 0.0 else "")
        for e in scores.values()
        if not e.accepted
    ]
    ordered = [scores[n] for n in accepted] + sorted(passed_over, key=lambda e: -e.score)
    return GapReport(
        channels=channels,
        where=where,
        effects=ordered,
        diagnosis=accepted,
        unexplained=unexplained,
        outside=outside,
        rows=(n_fit, int(withheld.sum())),
        unreferenced=all_rows - len(data),
        model=tuple(dict.fromkeys((*BASELINE, *model))),
        residual_before=before[withheld],
        residual_after=residual[withheld],
        predicted_before=errors - before,
        predicted_after=errors - residual,
        t_withheld=data.t[withheld],
        allan=allan,
        quartiles=quartiles,
    )


def _exclusive(name: str) -> set[str]:
    """The effects a model holding ``name`` takes no more: itself, and for a random bias or an output
    map the sensor's others of that kind. One random bias per sensor: the other is an alternative to
    it, not an addition. Likewise one output map (quantizing a clipped reading is not modelled)."""
    sensor, kind = name.split(".")
    for group in (_PROCESSES, _OUTPUTS):
        if kind in group:
            return {f"{sensor}.{k}" for k in group}
    return {name}


def _nested_choice(best: str, trials: dict[str, _Trial]) -> tuple[str, tuple[str, ...], tuple[str, ...]]:
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
    if kind not in _PROCESSES:
        return best, (), ()
    bi, rw = trials.get(f"{sensor}.bias_instability"), trials.get(f"{sensor}.rate_random_walk")
    if bi is None or rw is None or not (bi.score > 0.0 and rw.score > 0.0) or bi.names != rw.names:
        return best, (), ()
    gain = sum(row.fit_loglik for row in bi.rows) - sum(row.fit_loglik for row in rw.rows)
    if 2.0 * gain > float(chi2.isf(0.001, len(bi.rows))):
        return f"{sensor}.bias_instability", (f"{sensor}.rate_random_walk",), ()
    return f"{sensor}.rate_random_walk", (), (f"{sensor}.bias_instability",)


def _process_or_regressors(
    best: str, told_apart: tuple[str, ...], alike: tuple[str, ...], trials: dict[str, _Trial]
) -> tuple[str, tuple[str, ...], tuple[str, ...]]:
    """Between a random bias and a regressor effect that both gain on the withheld rows, the one the
    fit rows' likelihood less BIC's penalty prefers.

    A random bias's filter follows any level that holds for a while: a static position's offset from
    g² sensitivity or a slow temperature drift as much as a wandering bias. With the withheld rows at
    the end of each phase, it has caught the level before they begin, and predicts them about as well
    as regressors that explain the level from the inputs, with fewer parameters. On the fit rows it
    pays for following: its innovations after every change of level, which the regressors predict.
    The regressor is taken where it is ahead there by more than :data:`TIE_NATS`; within that, the
    two are listed as indistinguishable.

    Takes and returns what :func:`_nested_choice` does: the choice, the candidates told apart from
    it and those that could not be.
    """
    if best.split(".")[1] not in _PROCESSES:
        return best, told_apart, alike

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
        return best, told_apart, alike
    rival = max(rivals, key=fit_score)
    margin = fit_score(rival) - fit_score(best)
    if margin > TIE_NATS:
        return (
            rival,
            tuple(n for n in trials if n.split(".")[1] in _PROCESSES and n.startswith(rival.split(".")[0])),
            (),
        )
    if margin > -TIE_NATS:
        return best, told_apart, (*alike, rival)
    return best, told_apart, alike


class _ChannelTrial(NamedTuple):
    """A candidate tried on one channel."""

    channel: int
    gain: float  # the withheld log-likelihood gain
    penalty: float  # BIC's, for comparisons on the fit rows
    fit_loglik: float  # the fit rows' log-likelihood: the process's innovations' for a random bias


@dataclass
class _Trial:
    """A candidate tried on a sensor's channels.

    The trial models and residuals are not kept: one per candidate and channel would hold
    hundreds of MB on a long recording. :func:`_tried` rebuilds the accepted one's.
    """

    rows: list[_ChannelTrial] = field(default_factory=list)
    #: Beyond :data:`SIGNIFICANT_NATS`, what the candidate may gain where the current model holds
    #: (a random bias: :func:`_refit_allowance`).
    allowance: float = 0.0

    def add(self, i: int, gain: float, penalty: float, fit_loglik: float) -> None:
        self.rows.append(_ChannelTrial(i, gain, penalty, fit_loglik))

    @property
    def channels(self) -> list[int]:
        return [row.channel for row in self.rows]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(CHANNELS[i] for i in self.channels)

    @property
    def gain(self) -> float:
        """The withheld log-likelihood gain."""
        return float(sum(row.gain for row in self.rows))

    @property
    def score(self) -> float:
        """The gain beyond what it needs to be significant: accepted above 0."""
        return self.gain - SIGNIFICANT_NATS - self.allowance


def _tried(model: _ChannelModel, cand: Candidate) -> tuple[_ChannelModel, Array]:
    """A channel's model with a candidate added, fitted, and the residual it leaves on every row."""
    m = model.with_candidate(cand)
    return m, m.error - m.predict()


def _outside(
    trial: _Trial,
    process: bool,
    models: list[_ChannelModel],
    residual: Array,
    t: Array,
    fit: NDArray[np.bool_],
    withheld: NDArray[np.bool_],
    n_fit: int,
) -> list[Outside]:
    """The channels of ``trial`` where a disturbance outside the library does as well as its effect.

    Two such disturbances are tried on each channel, fitted on the fit rows beside the model's
    regressors: a single bias step (:func:`sins.gap.disturbance.best_step`; its size and time are two
    parameters) and an oscillation (:func:`sins.gap.disturbance.best_oscillation`; frequency and two
    amplitudes, three). A library effect that explains a channel no better than a one-off step or a
    hum cannot claim it; the disturbance is reported instead. As well: a withheld gain above
    :data:`SIGNIFICANT_NATS`, and within :data:`TIE_NATS` of the effect's; or, where the effect is
    a random bias (``process``), a fit-row log-likelihood less BIC's penalty within
    :data:`TIE_NATS` of its own. The random bias's filter predicts each withheld row from the
    readings before it, so it follows a step that falls inside a withheld block, where the fit rows
    cannot place it; on the fit rows it pays for trailing the step, as it does for trailing
    regressors' levels (:func:`_process_or_regressors`).
    """
    out = []
    for i, gain, penalty, fit_loglik in trial.rows:
        if gain <= 0.0 and trial.score > 0.0:
            continue  # the effect gains nothing here: no gain to take from it
        columns = np.hstack(models[i].columns)
        t_step, size = disturbance.best_step(residual[:, i], columns, fit, t)
        period, amplitude = disturbance.best_oscillation(residual[:, i], columns, fit, t)
        wave = np.column_stack([np.cos(2 * np.pi * t / period), np.sin(2 * np.pi * t / period)])
        step_column = (t > t_step)[:, None].astype(float)
        tries = [
            (Outside(CHANNELS[i], "bias step", size, 0.0, t_s=t_step), step_column, 2),
            (Outside(CHANNELS[i], "periodic", amplitude, 0.0, period_s=period), wave, 3),
        ]
        found = []
        for candidate, column, k in tries:
            m = models[i].with_columns(column)
            after = m.error - m.predict()
            outside_gain, penalty_k = _trial_gain(
                models[i], m, residual[:, i], after, withheld, n_fit, k - column.shape[1]
            )
            if process:
                as_well = m.fit_rows_loglik(after) - penalty_k > fit_loglik - penalty - TIE_NATS
            else:  # gains compared, as for ties: no better than the disturbance is not what happened
                as_well = outside_gain > gain - TIE_NATS
            if outside_gain > SIGNIFICANT_NATS and as_well:
                found.append(dataclasses.replace(candidate, score=outside_gain - SIGNIFICANT_NATS))
        if found:
            out.append(max(found, key=lambda o: o.score))
    return out


def allan_deviation(rate: Array, clusters: NDArray[np.integer[Any]]) -> Array:
    """Overlapping Allan deviation of a uniformly sampled rate series, for each cluster size (rows).

    With ``θ`` the running sum of the rate, ``σ²(m) = ⟨(θₖ₊₂ₘ − 2θₖ₊ₘ + θₖ)²⟩ / (2 m²)`` over every
    ``k``: white noise of standard deviation ``σ`` gives ``σ / √m``. The cluster time is ``m`` times
    the sampling step; the deviation is in the rate's units.
    """
    theta = np.concatenate([[0.0], np.cumsum(rate)])
    out = np.empty(len(clusters))
    for j, m in enumerate(clusters):
        d = theta[2 * m :] - 2.0 * theta[m:-m] + theta[: -2 * m]
        out[j] = np.sqrt(np.mean(d * d) / (2.0 * m * m))
    return out


def _allan(before: Array, after: Array, floor: float, step_s: float) -> dict[str, list[float]]:
    """The Allan deviations of a channel's residual, every row in time order, at octave clusters.

    Octaves up to an eighth of the rows, so that every point averages at least eight clusters.
    """
    clusters = 2 ** np.arange(int(np.log2(max(len(before) // 8, 1))) + 1)
    return {
        "tau_s": list(clusters * step_s),
        "before": list(allan_deviation(before, clusters)),
        "after": list(allan_deviation(after, clusters)),
        "model": list(floor / np.sqrt(clusters)),
    }


def _quartile_shares(
    residual: Array, floor: float, x: _Inputs, withheld: NDArray[np.bool_]
) -> dict[str, list[float]]:
    """For each input, the share of a channel's withheld excess power in each of its quartiles.

    Inputs that do not vary (a static unit's rate of change: 1e-19 from uneven time stamps) and a
    channel with no excess give nothing.
    """
    excess = residual[withheld] ** 2 - floor**2
    if float(np.sum(np.maximum(excess, 0.0))) <= 0.0:
        return {}
    features = {
        "|ω|": np.linalg.norm(x.omega, axis=1),
        "|f|": np.linalg.norm(x.f, axis=1),
        "temperature": x.temp,
        "rate of change": np.linalg.norm(x.omega_dot, axis=1),
        "time": x.t,
    }
    out = {}
    for name in _FEATURES:
        v = features[name]
        if v is None or float(np.ptp(v)) <= 1e-9 * max(1.0, float(np.abs(v).max())):
            continue
        v = v[withheld]
        bins = np.searchsorted(np.quantile(v, [0.25, 0.5, 0.75]), v, side="right")
        # A bin may sit below the floor: shares are of the bins above it.
        per_bin = np.maximum([np.sum(excess[bins == b]) for b in range(4)], 0.0)
        out[name] = list(per_bin / max(float(np.sum(per_bin)), 1e-300))
    return out


def _concentrates(shares: dict[str, list[float]], allan: dict[str, list[float]]) -> list[str]:
    """Where a channel's excess sits: an input quartile holding most of it, and the time scale at
    which the residual's Allan deviation stands furthest above the white noise the model expects."""
    out: list[str] = []
    for name, share in shares.items():
        top = int(np.argmax(share))
        if share[top] > 0.5:
            label = ("lowest", "second", "third", "highest")[top]
            out.append(f"{name}: {label} quartile holds {100 * share[top]:.0f} % of the excess")
    ratio = np.array(allan["before"]) / np.maximum(np.array(allan["model"]), 1e-300)
    if len(ratio) and ratio.max() > 1.5:  # 2.25× the variance: beyond the scatter of eight clusters
        k = int(np.argmax(ratio))
        tau = f"τ = {allan['tau_s'][k]:.3g} s"
        out.append(f"frequency: Allan deviation at {tau} is {ratio[k]:.1f}× the model's white noise")
    return out
