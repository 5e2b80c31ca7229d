"""Sim-to-real gap diagnosis: where simulated and real IMU data part, which unmodelled effect causes it.

The model of a channel's reading error ``e = reading − reference`` is the
baseline (the seed model's bias, scale/misalignment and g-sensitivity rows,
fitted by least squares, plus white noise) and any effects accepted so far.
Every library effect not in the model is a candidate, of one of three kinds:

- *regressors* (scale nonlinearity and asymmetry, g² sensitivity, temperature
  bias and scale, time offset, size effect): columns added to the channel's
  least-squares fit;
- *processes* (bias instability, rate random walk): a first-order Gauss–Markov
  or random-walk bias under the white noise, fitted on the fit rows' residual
  and predicted one step ahead by the steady-state Kalman filter;
- *output maps* (quantization, saturation): the prediction rounded to the
  readings' lattice or clipped at the readings' pile-up.

Each candidate is fitted on the fit rows and scored on the withheld rows: the
Gaussian log-likelihood gain of its withheld residual over the current
model's, minus ``k/2 · ln(n_fit)`` for its ``k`` parameters (BIC's penalty).
Candidates are accepted greedily while the best score is positive. A random
bias tracks a single jump or any one-off misfit as well as a real instability,
so a process candidate must also drive its bias alike in both halves of the
fit rows (see :func:`_homogeneous`).

The noise floor of a channel is the white-noise level the model expects,
measured without the model: the spread of first differences of the fit rows'
residual, which slowly varying unmodelled errors do not reach.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from sins.errors import SinsInputError
from sins.imu import BASELINE, CHANNELS, EFFECT_NAMES
from sins.series import CalibrationData

Array = NDArray[np.float64]

#: A channel's withheld residual counts as above its floor beyond this ratio (3 % plus sampling error).
SIGNIFICANT_RATIO = 1.03
#: Below any real sensor's noise (2e-5 °/h, 1e-11 g): the floor of noiseless (simulated) readings, SI units.
_TINY = 1e-10
#: Random-walk and Gauss–Markov correlation times tried for the process candidates, s.
_TAUS_S = np.geomspace(2.0, 5000.0, 12)
#: Drives ``q / r`` tried for the process candidates.
_DRIVE_RATIOS = np.geomspace(1e-9, 1e-1, 17)
#: Input quartiles reported where the excess concentrates.
_FEATURES = ("|ω|", "|f|", "temperature", "rate of change", "time")


@dataclass(frozen=True)
class Candidate:
    """One library effect as the diagnosis sees it: its name, its channels and its kind."""

    name: str
    sensor: str
    kind: str  # "regressors" | "process" | "output"
    columns: Callable[[_Inputs, int], Array] | None = None  # (n, k) extra regressors of axis i


@dataclass
class _Inputs:
    """The reference inputs of every row, and what the regressors are built from."""

    t: Array
    omega: Array
    f: Array
    omega_dot: Array
    u_dot: dict[str, Array]
    temp: Array | None
    step_s: float

    def of(self, sensor: str) -> Array:
        return self.omega if sensor == "gyro" else self.f


def _size_columns(x: _Inputs, i: int) -> Array:
    w, wd = x.omega, x.omega_dot
    cols = []
    for j in range(3):
        r = np.zeros(3)
        r[j] = 1.0
        cols.append((np.cross(wd, r) + np.cross(w, np.cross(w, r)))[:, i])
    return np.stack(cols, axis=1)


def _g2_columns(x: _Inputs, i: int) -> Array:
    f = x.f / 9.80665  # in g: keeps the columns near the others' size
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
        Candidate(f"{sensor}.time_offset", sensor, "regressors", lambda x, i: x.u_dot[sensor][:, i : i + 1]),
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


#: Every candidate the diagnosis knows, by effect name (all of DESIGN.md §4 beyond the baseline).
CANDIDATES: dict[str, Candidate] = {c.name: c for s in ("gyro", "accel") for c in _candidates(s)}
assert set(CANDIDATES) == set(EFFECT_NAMES) - set(BASELINE) - {"gyro.bias", "accel.bias"}


@dataclass(frozen=True)
class EffectScore:
    """A candidate's score in the round it was accepted or last scored: log-likelihood gain less penalty."""

    name: str
    channels: tuple[str, ...]
    score: float
    accepted: bool

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "channels": list(self.channels),
            "score": self.score if np.isfinite(self.score) else None,  # None: ruled out (_homogeneous)
            "accepted": self.accepted,
        }


@dataclass(frozen=True)
class GapReport:
    """What :func:`diagnose` found; ``to_dict`` gives the stable JSON keys."""

    channels: dict[str, dict[str, float]]
    where: list[dict[str, Any]]
    effects: list[EffectScore]
    diagnosis: list[str]
    unexplained: list[str]
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
        return {
            "channels": self.channels,
            "where": self.where,
            "effects": [e.to_dict() for e in self.effects],
            "diagnosis": self.diagnosis,
            "unexplained": self.unexplained,
        }


# --------------------------------------------------------------------------- the channel models


class _ChannelModel:
    """One channel's current model: regressor columns, an optional process, an optional output map."""

    def __init__(
        self, x: _Inputs, sensor: str, axis: int, error: Array, reading: Array, fit: NDArray[np.bool_]
    ) -> None:
        self.x, self.sensor, self.axis = x, sensor, axis
        self.error, self.reading, self.fit = error, reading, fit
        u = x.of(sensor)
        base = [np.ones(len(x.t)), u[:, 0], u[:, 1], u[:, 2]]
        if sensor == "gyro":
            base += [x.f[:, 0], x.f[:, 1], x.f[:, 2]]
        self.columns: list[Array] = [np.stack(base, axis=1)]
        self.process: str | None = None  # "bias_instability" | "rate_random_walk"
        self.process_on_trial = True  # a candidate's process must pass _homogeneous; the model's need not
        self.output: str | None = None  # "quantization" | "saturation"

    def with_candidate(self, cand: Candidate, on_trial: bool = True) -> _ChannelModel:
        m = copy.copy(self)
        m.columns = list(self.columns)
        if cand.kind == "regressors":
            assert cand.columns is not None
            m.columns.append(cand.columns(self.x, self.axis))
        elif cand.kind == "process":
            m.process, m.process_on_trial = cand.name.split(".")[1], on_trial
        else:
            m.output = cand.name.split(".")[1]
        return m

    @property
    def n_params(self) -> int:
        k = sum(c.shape[1] for c in self.columns)
        if self.process is not None:
            k += 2 if self.process == "bias_instability" else 1
        return k + (self.output is not None)

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
        coef, *_ = np.linalg.lstsq(a[rows] / scale, self.error[rows], rcond=rcond)
        pred = (a / scale) @ coef
        if self.process is not None:
            y = self.error - pred
            phi, q, r = _fit_process(self.process, y, self.fit, self.x.step_s)
            if self.process_on_trial and not _homogeneous(y, self.fit, self.x.t, phi, q, r):
                return np.full_like(pred, np.nan)  # not this process: see _homogeneous
            pred = pred + y - _innovations(y, phi, _steady_gain(phi, q, r)[0])
        if self.output is not None:
            pred = _output_map(self.output, pred, self.reading - self.error, self.reading, self.fit)
        return pred


def _steady_gain(phi: float, q: float, r: float) -> tuple[float, float]:
    """Steady-state Kalman gain and innovation variance of ``b' = φ b + w (q)``, ``y = b + v (r)``."""
    # Riccati: P = φ² P r / (P + r) + q  (P the predicted variance).
    a, b, c = 1.0, r * (1.0 - phi * phi) - q, -q * r
    p = (-b + np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
    return p / (p + r), p + r


def _innovations(y: Array, phi: float, gain: float) -> Array:
    """One-step-ahead innovations of the steady-state filter: ``x̂' = φ(1−K) x̂ + φ K y``.

    The filter starts from the mean of the first 100 samples, not from 0: a start from 0 would
    be a jump the process did not make.
    """
    # Transposed direct form: the state is the next prediction, so zi is the first one.
    pred, _ = lfilter([0.0, phi * gain], [1.0, -phi * (1.0 - gain)], y, zi=[float(np.mean(y[:100]))])
    return np.asarray(y - pred)


def _fit_process(kind: str, y: Array, fit: NDArray[np.bool_], step_s: float) -> tuple[float, float, float]:
    """(φ, q, r) maximising the innovations' likelihood on the fit rows, over a grid of τ and q/r.

    ``r``, the white noise's variance, is the noise floor's square; the grid chooses the bias's
    correlation (``φ = exp(−step/τ)``, 1 for a random walk) and drive ``q``.

    The filter runs over every row in time order (so withheld blocks are predicted from what came
    before them, as a filter in the field would), but only the fit rows' innovations choose.
    """
    r = max(noise_floor(y[fit]) ** 2, _TINY**2)  # the white part, from first differences
    best = (-np.inf, 1.0, 0.0, r)
    phis = [1.0] if kind == "rate_random_walk" else list(np.exp(-step_s / _TAUS_S))
    for phi in phis:
        for ratio in _DRIVE_RATIOS:
            ll = _log_likelihood(_innovations(y, phi, _steady_gain(phi, ratio * r, r)[0])[fit])
            if ll > best[0]:
                best = (ll, phi, ratio * r, r)
    return best[1], best[2], best[3]


def _log_likelihood(innovations: Array) -> float:
    """Gaussian log-likelihood of innovations with their own variance, up to a constant."""
    return -0.5 * len(innovations) * float(np.log(np.mean(innovations * innovations)))


def _homogeneous(y: Array, fit: NDArray[np.bool_], t: Array, phi: float, q: float, r: float) -> bool:
    """Whether one drive ``q`` serves all four quarters of the fit rows (a likelihood-ratio test).

    A random bias tracks a single jump or any other one-off misfit as well as a real instability;
    only a real one drives the bias alike all along. With each quarter's own ``q`` (``φ`` and ``r``
    kept), twice the log-likelihood gain over the common ``q`` is χ² with 3 degrees of freedom for a
    real process; beyond 16.3 (p = 0.001) it is not this process.
    """
    if q <= 0.0:
        return False
    edges = np.quantile(t[fit], [0.25, 0.5, 0.75])
    quarter = np.searchsorted(edges, t, side="right")
    trials = [_innovations(y, phi, _steady_gain(phi, ratio * r, r)[0]) for ratio in _DRIVE_RATIOS]
    common = trials[int(np.argmin(np.abs(_DRIVE_RATIOS * r - q)))]  # q is on the grid
    gain = 0.0
    for k in range(4):
        rows = fit & (quarter == k)
        gain += max(_log_likelihood(nu[rows]) for nu in trials) - _log_likelihood(common[rows])
    return 2.0 * gain <= 16.3


def _output_map(kind: str, pred: Array, reference: Array, reading: Array, fit: NDArray[np.bool_]) -> Array:
    """The prediction of the error after the readings' lattice or clipping, learnt from the fit rows."""
    y = reference + pred  # predicted reading
    if kind == "quantization":
        steps = np.diff(np.unique(reading[fit]))
        steps = steps[steps > 1e-15 * np.abs(reading).max()]
        if len(steps) == 0:
            return pred
        q = float(np.median(steps))
        return np.round(y / q) * q - reference
    top, bottom = float(reading[fit].max()), float(reading[fit].min())
    return np.clip(y, bottom, top) - reference


# --------------------------------------------------------------------------- the diagnosis


def _inputs(data: CalibrationData) -> _Inputs:
    t = data.t
    grad = (lambda a: np.gradient(a, t, axis=0)) if len(t) > 2 else np.zeros_like
    return _Inputs(
        t=t,
        omega=data.ref_gyro,
        f=data.ref_accel,
        omega_dot=grad(data.ref_gyro),
        u_dot={"gyro": -grad(data.ref_gyro), "accel": -grad(data.ref_accel)},
        temp=data.temp,
        step_s=float(np.median(np.diff(t))),
    )


def noise_floor(residual: Array) -> float:
    """White-noise level of a residual series from its first differences: ``std(Δr) / √2``.

    Differencing removes what varies slowly (unmodelled scale, temperature or bias effects) and
    keeps white noise of any distribution, quantised readings' included, at twice its variance.
    """
    return float(np.std(np.diff(residual)) / np.sqrt(2.0))


def _score(before: Array, after: Array, withheld: NDArray[np.bool_], k_extra: int, n_fit: int) -> float:
    """Withheld log-likelihood gain (Gaussian, own variance) less ``k/2 ln n_fit``."""
    if np.isnan(after).any():
        return -np.inf
    s0 = float(np.mean(before[withheld] ** 2)) + _TINY**2
    s1 = float(np.mean(after[withheld] ** 2)) + _TINY**2
    n = int(withheld.sum())
    return 0.5 * n * np.log(s0 / s1) - 0.5 * k_extra * np.log(n_fit)


def _available(cand: Candidate, x: _Inputs, readings: Array, fit: NDArray[np.bool_]) -> bool:
    """Whether the data can say anything about a candidate.

    Temperature effects need a varying temperature; saturation needs readings piled up at an
    extreme (ten or more equal to it) while the reference goes beyond it; quantization needs
    readings on a lattice (fewer distinct values than half the rows).
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
    if cand.name.endswith("quantization"):
        return any(len(np.unique(r[:, j])) < 0.5 * len(r) for j in range(r.shape[1]))
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
        raise SinsInputError(f"{where}: --holdout must be in (0, 1), got {holdout}")
    n = int((np.isfinite(data.ref_gyro).all(axis=1) & np.isfinite(data.ref_accel).all(axis=1)).sum())
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
    fit_part, _ = data.split(holdout)
    fit = np.zeros(len(data), dtype=bool)
    fit[np.searchsorted(data.t, fit_part.t)] = True
    withheld = ~fit
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
    floors = np.array([max(noise_floor(residual[fit, i]), _TINY) for i in range(6)])

    accepted: list[str] = []
    scores: dict[str, EffectScore] = {}
    remaining = [c for c in CANDIDATES.values() if c.name not in model]
    while remaining:
        round_scores: dict[str, tuple[float, list[tuple[int, _ChannelModel, Array]]]] = {}
        for cand in remaining:
            if progress:
                progress(cand.name)
            chans = [i for i, ch in enumerate(CHANNELS) if ch.startswith(cand.sensor)]
            if not _available(cand, x, readings[:, chans], fit):
                continue
            total, trial = 0.0, []
            for i in chans:
                m = models[i].with_candidate(cand)
                r = m.error - m.predict()
                total += _score(residual[:, i], r, withheld, m.n_params - models[i].n_params, n_fit)
                trial.append((i, m, r))
            round_scores[cand.name] = (total, trial)
        for name, (total, _) in round_scores.items():
            names = tuple(ch for ch in CHANNELS if ch.startswith(CANDIDATES[name].sensor))
            scores[name] = EffectScore(name, names, float(total), False)
        if not round_scores:
            break
        positive = [n for n in round_scores if round_scores[n][0] > 0.0]
        if not positive:
            break
        best = max(positive, key=lambda n: round_scores[n][0])
        accepted.append(best)
        scores[best] = EffectScore(best, scores[best].channels, scores[best].score, True)
        for i, m, r in round_scores[best][1]:
            models[i], residual[:, i] = m, r
        remaining = [c for c in remaining if c.name != best]

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
    gapped = [i for i in range(6) if rms_before[i] > SIGNIFICANT_RATIO * floors[i]]
    gapped.sort(key=lambda i: -rms_before[i] / floors[i])
    where: list[dict[str, Any]] = [
        {
            "channel": CHANNELS[i],
            "excess": float(rms_before[i] / floors[i]),
            "concentrates": _concentrates(before[:, i], floors[i], x, withheld),
        }
        for i in gapped
    ]
    unexplained = [ch for i, ch in enumerate(CHANNELS) if rms_after[i] > SIGNIFICANT_RATIO * floors[i]]
    # Accepted effects first, in the order they were accepted; then the rest, best score first.
    ordered = [scores[n] for n in accepted] + sorted(
        (e for e in scores.values() if not e.accepted), key=lambda e: -e.score
    )
    return GapReport(
        channels=channels,
        where=where,
        effects=ordered,
        diagnosis=accepted,
        unexplained=unexplained,
        rows=(n_fit, int(withheld.sum())),
        unreferenced=all_rows - len(data),
        model=tuple(dict.fromkeys((*BASELINE, *model))),
        residual_before=before[withheld],
        residual_after=residual[withheld],
        predicted_before=errors - before,
        predicted_after=errors - residual,
        t_withheld=data.t[withheld],
    )


def _concentrates(residual: Array, floor: float, x: _Inputs, withheld: NDArray[np.bool_]) -> list[str]:
    """Where a channel's excess power sits: input quartiles holding most of it, and the time scales."""
    excess = residual[withheld] ** 2 - floor**2
    total = float(np.sum(np.maximum(excess, 0.0)))
    out: list[str] = []
    if total <= 0.0:
        return out
    features = {
        "|ω|": np.linalg.norm(x.omega, axis=1),
        "|f|": np.linalg.norm(x.f, axis=1),
        "temperature": x.temp,
        "rate of change": np.linalg.norm(x.omega_dot, axis=1),
        "time": x.t,
    }
    for name in _FEATURES:
        v = features[name]
        # A constant input (a static unit's rate of change: 1e-19 from uneven time stamps) says nothing.
        if v is None or float(np.ptp(v)) <= 1e-9 * max(1.0, float(np.abs(v).max())):
            continue
        v = v[withheld]
        edges = np.quantile(v, [0.25, 0.5, 0.75])
        bins = np.searchsorted(edges, v, side="right")
        # A bin may sit below the floor: shares are of the bins above it.
        per_bin = np.maximum([np.sum(excess[bins == b]) for b in range(4)], 0.0)
        share = per_bin / max(float(np.sum(per_bin)), 1e-300)
        top = int(np.argmax(share))
        if share[top] > 0.5:
            label = ("lowest", "second", "third", "highest")[top]
            out.append(f"{name}: {label} quartile holds {100 * share[top]:.0f} % of the excess")
    # Frequency: block means of the residual against white noise's 1/√m.
    r = residual[withheld]
    for m in (10, 100, 1000, 10000):
        if len(r) < 4 * m:
            break
        blocks = r[: len(r) // m * m].reshape(-1, m).mean(axis=1)
        ratio = float(np.std(blocks) / (floor / np.sqrt(m)))
        if ratio > 2.0:
            out.append(f"slow: averages over {m * x.step_s:g} s spread {ratio:.1f}× white noise's")
            break
    return out
