"""A recording characterised: each channel's Allan curve and the noise terms fitted to it.

The input is what is left of a reading once its reference is taken away (:func:`residual`): a static
unit's readings as they are (a constant input does not change an Allan deviation), or a moving unit's
readings less the reference inputs of its trajectory or rig and less the deterministic errors fitted
against them (:mod:`sins.characterise.reference`). Rows without a reference (the turns of a hand-made
Ferraris session) split the recording into segments, and so do gaps in time; the Allan deviation pools
the cluster differences inside each segment (:mod:`sins.characterise.allan`).

Each channel (:func:`characterise_channel`): the rate's ramp is fitted to the rate itself
(:mod:`sins.characterise.trend`) and judged against the noise of the curve the rate leaves without it
(:meth:`~sins.characterise.allan.AllanCurve.detrended`): the curve with the ramp would let a rate random
walk take the ramp's rise and hide it. Resolved, the ramp stays out of the curve analysed; not resolved,
the rate is analysed as it is. The noise terms are then decided on that curve
(:mod:`sins.characterise.selection`). Taking a fitted line out of noise also takes its own apparent
trend, which reads a rate random walk beside a resolved ramp a little low (by how much:
``docs/guide/characterise.md``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.characterise import trend
from sins.characterise.allan import MIN_CLUSTERS, AllanCurve, allan
from sins.characterise.noise_terms import TERMS, NoiseFit, R, Term
from sins.characterise.selection import Weights, fit_terms, weigh
from sins.characterise.trend import Ramp
from sins.errors import SinsInputError
from sins.imu import CHANNELS, DEG, DEG_PER_H, UG

Array = NDArray[np.float64]

#: A recording needs this many rows in its longest segment: five octaves of cluster sizes (each point
#: averaging :data:`~sins.characterise.allan.MIN_CLUSTERS` clusters), enough to tell two terms apart.
MIN_ROWS = 16 * MIN_CLUSTERS
#: A channel needs this many cluster times with a non-zero Allan variance.
MIN_POINTS = 3
#: A sampling step this long or longer is not an IMU's: a time column in milliseconds reads so.
SLOW_STEP_S = 1.0
#: A step longer than this many sampling steps is a gap between segments.
GAP_STEPS = 1.5
#: Steps within a segment may differ from the median step by this fraction (time-stamp rounding).
STEP_TOLERANCE = 0.01
_ARCSEC = DEG / 3600.0

#: The display unit of each term, per sensor: (SI size of one unit, symbol).
DISPLAY: dict[str, dict[str, tuple[float, str]]] = {
    "gyro": {
        "quantization": (_ARCSEC, "arcsec"),
        "white": (DEG / 60.0, "°/√h"),
        "flicker": (DEG_PER_H, "°/h"),
        "gauss_markov": (DEG_PER_H, "°/h"),
        "rate_random_walk": (DEG_PER_H / 60.0, "°/h/√h"),
        "rate_ramp": (DEG_PER_H / 3600.0, "°/h²"),
    },
    "accel": {
        "quantization": (UG, "µg·s"),
        "white": (UG, "µg/√Hz"),
        "flicker": (UG, "µg"),
        "gauss_markov": (UG, "µg"),
        "rate_random_walk": (UG, "µg/√s"),
        "rate_ramp": (UG, "µg/s"),
    },
}
#: The SI unit of each term, per sensor (the JSON's).
SI_UNITS: dict[str, dict[str, str]] = {
    "gyro": {"quantization": "rad", "white": "rad/√s", "flicker": "rad/s", "gauss_markov": "rad/s",
             "rate_random_walk": "rad/s/√s", "rate_ramp": "rad/s²"},
    "accel": {"quantization": "m/s", "white": "m/s/√s", "flicker": "m/s²", "gauss_markov": "m/s²",
              "rate_random_walk": "m/s²/√s", "rate_ramp": "m/s³"},
}  # fmt: skip
#: The display unit of an Allan deviation, per sensor.
ADEV_DISPLAY = {"gyro": (DEG_PER_H, "°/h"), "accel": (UG, "µg")}


@dataclass(frozen=True)
class Residual:
    """A recording's readings less their reference, in uniformly sampled segments.

    Attributes
    ----------
    values : (n, 6) residual of ``gyro.x`` … ``accel.z``, rad/s and m/s² (NaN outside the segments)
    dt : the sampling step, s
    segments : ``(start, stop)`` row ranges, each uniformly sampled and referenced
    source : where it came from (a path or a dataset name)
    input_mean : (6,) the readings' mean over the segments (the constant input a static unit sees, which
        the closing simulation feeds its model: quantization needs an input that crosses its levels)
    notes : what was done to the readings before the analysis, in words (one line each)
    warnings : what looks wrong with them, in words (one line each)
    """

    values: Array
    dt: float
    segments: tuple[tuple[int, int], ...]
    source: str = ""
    input_mean: Array | None = None
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    @property
    def length_s(self) -> float:
        """The longest segment's duration, s."""
        return max(b - a for a, b in self.segments) * self.dt

    @property
    def rows(self) -> int:
        """The rows inside the segments."""
        return sum(b - a for a, b in self.segments)


def residual(t: Array, readings: Array, reference: Array | None = None, source: str = "",
             keep: NDArray[np.bool_] | None = None) -> Residual:  # fmt: skip
    """The residual of readings (n, 6) at times ``t`` (n,) against a reference (n, 6), or None (static).

    Rows where the residual is not finite (or outside ``keep``, when given), and steps longer than
    :data:`GAP_STEPS` sampling steps, end a segment; every step inside a segment must match the sampling
    step to :data:`STEP_TOLERANCE`. A sampling step of :data:`SLOW_STEP_S` or more is kept with a warning
    (no IMU samples so slowly: a time column in milliseconds reads so).

    Raises
    ------
    SinsInputError
        one line naming ``source``: fewer than :data:`MIN_ROWS` rows in the longest segment, steps that
        are not increasing, uneven sampling (with the row), or a channel that is constant in every
        segment.
    """
    t = np.asarray(t, dtype=float)
    raw = np.asarray(readings, dtype=float)
    values = raw if reference is None else raw - np.asarray(reference, dtype=float)
    name = source or "recording"
    if values.ndim != 2 or values.shape[1] != 6 or len(t) != len(values):
        raise SinsInputError(
            f"{name}: expected (n, 6) readings beside n times, got {values.shape} and {t.shape}"
        )
    if len(t) < MIN_ROWS:
        raise SinsInputError(
            f"{name}: {len(t)} rows; an Allan analysis needs at least {MIN_ROWS} {_WHY_ROWS}"
        )
    steps = np.diff(t)
    if not np.all(steps > 0.0):
        row = int(np.argmax(~(steps > 0.0))) + 1
        raise SinsInputError(f"{name}: row {row + 1}: time t={t[row]:g} s does not increase")
    dt = float(np.median(steps))
    good = np.isfinite(values).all(axis=1) & (True if keep is None else np.asarray(keep, dtype=bool))
    segments = _segments(name, good, steps, dt)
    _check_constant(name, values, segments)
    total = sum(raw[a:b].sum(axis=0) for a, b in segments)
    mean = np.asarray(total, dtype=float) / sum(b - a for a, b in segments)
    warnings: tuple[str, ...] = ()
    if dt >= SLOW_STEP_S:
        warnings = (
            f"{name}: sampled every {dt:g} s ({1.0 / dt:.3g} Hz), slower than any IMU: sins reads time in "
            "seconds (a time column in milliseconds reads so); the terms below assume seconds",
        )
    return Residual(values, dt, segments, source, mean, (), warnings)


_WHY_ROWS = f"in one stretch (five octaves of cluster sizes, each averaging {MIN_CLUSTERS} clusters)"


def _segments(name: str, good: NDArray[np.bool_], steps: Array, dt: float) -> tuple[tuple[int, int], ...]:
    """The uniformly sampled runs of ``good`` rows; refuses uneven sampling inside one."""
    breaks = steps > GAP_STEPS * dt
    rows = np.flatnonzero(good)
    segments = []
    if len(rows):
        joined = (np.diff(rows) == 1) & ~breaks[rows[:-1]]
        starts = rows[np.r_[True, ~joined]]
        stops = rows[np.r_[~joined, True]] + 1
        segments = [(int(a), int(b)) for a, b in zip(starts, stops, strict=True) if b - a >= 2]
    longest = max((b - a for a, b in segments), default=0)
    if longest < MIN_ROWS:
        raise SinsInputError(
            f"{name}: the longest stretch of referenced rows without a gap has {longest}; an Allan analysis "
            f"needs at least {MIN_ROWS} {_WHY_ROWS}"
        )
    for a, b in segments:
        inner = steps[a : b - 1]
        off = np.abs(inner - dt) > STEP_TOLERANCE * dt
        if off.any():
            row = a + int(np.argmax(off)) + 1
            raise SinsInputError(
                f"{name}: row {row + 1}: step {inner[int(np.argmax(off))]:g} s against the sampling step "
                f"{dt:g} s; an Allan analysis needs uniform sampling"
            )
    return tuple(segments)


def _check_constant(name: str, values: Array, segments: tuple[tuple[int, int], ...]) -> None:
    """Refuse a channel that never changes inside a segment: its Allan variance is zero everywhere."""
    for i, ch in enumerate(CHANNELS):
        if all(float(np.ptp(values[a:b, i])) == 0.0 for a, b in segments):
            raise SinsInputError(
                f"{name}: {ch} is constant in every stretch (its Allan variance is 0 at every cluster "
                "time): nothing to characterise (a channel that is not recorded, or readings rounded "
                "coarser than their noise)"
            )


@dataclass(frozen=True)
class ChannelResult:
    """One channel's Allan curve and the terms fitted to it.

    Attributes
    ----------
    channel : ``gyro.x`` … ``accel.z``
    curve : the Allan curve analysed (of the rate less its ramp, where the ramp was resolved)
    fit : the terms
    weights : the full model that weighted the fit (for :func:`refit_channel`)
    ramp : the rate's ramp
    ramp_weights : the full model of the curve without the ramp, which the ramp was judged against
    """

    channel: str
    curve: AllanCurve
    fit: NoiseFit
    weights: Weights | None = None
    ramp: Ramp | None = None
    ramp_weights: Weights | None = None

    @property
    def sensor(self) -> str:
        """``gyro`` or ``accel``."""
        return self.channel.split(".")[0]


@dataclass(frozen=True)
class Characterisation:
    """A recording's noise, channel by channel (see :func:`characterise`).

    Attributes
    ----------
    source : the recording
    dt : sampling step, s
    rows : rows analysed
    segments : the segments' row ranges
    channels : channel → :class:`ChannelResult`
    input_mean : (6,) the readings' mean (see :class:`Residual`), or None
    notes, warnings : the residual's (see :class:`Residual`)
    """

    source: str
    dt: float
    rows: int
    segments: tuple[tuple[int, int], ...]
    channels: dict[str, ChannelResult] = field(default_factory=dict)
    input_mean: Array | None = None
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    @property
    def length_s(self) -> float:
        """The longest segment's duration, s."""
        return max(b - a for a, b in self.segments) * self.dt

    def to_dict(self) -> dict[str, Any]:
        """The JSON document: SI units throughout, each term with its uncertainty and support."""
        out: dict[str, Any] = {
            "source": self.source,
            "dt_s": self.dt,
            "rate_hz": 1.0 / self.dt,
            "rows": self.rows,
            "segments": [list(s) for s in self.segments],
            "longest_segment_s": self.length_s,
            "confidence": next(iter(self.channels.values())).curve.confidence if self.channels else None,
            "notes": list(self.notes),
            "warnings": list(self.warnings),
            "channels": {ch: _channel_dict(r) for ch, r in self.channels.items()},
        }
        return out


def _channel_dict(r: ChannelResult) -> dict[str, Any]:
    low, high = r.curve.interval()
    terms: dict[str, Any] = {}
    for name in TERMS:
        t = r.fit.terms[name]
        entry: dict[str, Any] = {
            "symbol": t.symbol,
            "unit": SI_UNITS[r.sensor][name],
            "resolved": t.resolved,
            "value": t.value,
            "sigma": t.sigma,
            "upper": t.upper,
            "support_tau_s": list(t.support_tau_s),
            "needs_length_s": t.needs_length_s,
            "needs_rate_hz": t.needs_rate_hz,
        }
        if name == "gauss_markov":
            entry["tau_c_s"] = r.fit.tau_c_s
            entry["tau_c_range_s"] = list(r.fit.tau_c_range_s) if r.fit.tau_c_range_s else None
        if name == "rate_ramp":
            entry["removed_before_allan"] = r.fit.ramp_removed
            entry["simulated"] = False
            entry["sigma_judged"] = r.ramp.sigma_slow if r.ramp is not None else None
        terms[name] = entry
    return {
        "tau_s": r.curve.tau_s.tolist(),
        "adev": r.curve.adev.tolist(),
        "adev_low": low.tolist(),
        "adev_high": high.tolist(),
        "edf": r.curve.edf.tolist(),
        "model_adev": np.sqrt(r.fit.avar(r.curve.tau_s, r.curve.clusters)).tolist(),
        "excluded_tau_s": list(r.fit.excluded_tau_s),
        "tolerance": r.fit.tolerance,
        "terms": terms,
        "chi2": r.fit.chi2,
        "dof": r.fit.dof,
    }


def characterise_channel(rate: Array, dt: float, segments: tuple[tuple[int, int], ...] | None = None,
                         channel: str = "gyro.x") -> ChannelResult:  # fmt: skip
    """One channel: its ramp judged against the noise of the curve without it, the curve analysed (less
    the ramp where it is resolved), and the noise terms decided on it (see the module's text).

    Raises
    ------
    SinsInputError
        when fewer than :data:`MIN_POINTS` cluster times have a non-zero Allan variance.
    """
    spans = segments if segments is not None else ((0, len(rate)),)
    raw = allan(rate, dt, spans)
    if int(np.count_nonzero(raw.avar > 0.0)) < MIN_POINTS:
        raise SinsInputError(
            f"{channel}: {int(np.count_nonzero(raw.avar > 0.0))} of {len(raw.avar)} cluster times have a "
            f"non-zero Allan variance; a fit needs {MIN_POINTS} (readings rounded coarser than their noise?)"
        )
    r = trend.slope(rate, dt, spans)
    without = raw.detrended(r)
    ramp_weights = weigh(without)
    ramp = trend.fit_ramp(rate, dt, spans, ramp_weights.slow_models(), ramp_weights.tau_c_s, r)
    if ramp.resolved:
        return _result(channel, without, ramp_weights, ramp, ramp_weights, spans, dt)
    return _result(channel, raw, weigh(raw), ramp, ramp_weights, spans, dt)


def refit_channel(rate: Array, dt: float, segments: tuple[tuple[int, int], ...] | None,
                  previous: ChannelResult) -> ChannelResult:  # fmt: skip
    """One more refit of a channel from its result: the weights of both curves (with and without the
    ramp) one pass on from the result's, the ramp judged again, the terms decided again. A result at its
    fixed point comes back with the same resolved terms (the test of :func:`characterise_channel`'s
    convergence)."""
    if previous.weights is None or previous.ramp_weights is None:
        raise ValueError("the previous result keeps no weights to refit from")
    spans = segments if segments is not None else ((0, len(rate)),)
    raw = allan(rate, dt, spans)
    r = trend.slope(rate, dt, spans)
    without = raw.detrended(r)
    ramp_weights = weigh(without, previous.ramp_weights, passes=1)
    ramp = trend.fit_ramp(rate, dt, spans, ramp_weights.slow_models(), ramp_weights.tau_c_s, r)
    curve = without if ramp.resolved else raw
    weights = weigh(curve, previous.weights, passes=1)
    return _result(previous.channel, curve, weights, ramp, ramp_weights, spans, dt)


def _result(channel: str, curve: AllanCurve, weights: Weights, ramp: Ramp, ramp_weights: Weights,
            spans: tuple[tuple[int, int], ...], dt: float) -> ChannelResult:  # fmt: skip
    removed = ramp.resolved
    length = max(b - a for a, b in spans) * dt
    noise = fit_terms(curve, length, weights)
    if removed:
        term = Term("rate_ramp", True, ramp.value, ramp.sigma, None, ())
    else:
        need = trend.needs_length(ramp.upper, dt, noise.coefficients, noise.tau_c_s, length)
        term = Term("rate_ramp", False, None, None, ramp.upper, (), need or 4.0 * length)
    coefficients = noise.coefficients.copy()
    covariance = noise.covariance.copy()
    if removed:
        coefficients[R] = ramp.value**2
        covariance[R, R] = (2.0 * abs(ramp.value) * ramp.sigma) ** 2
    fit = replace(noise, terms={**noise.terms, "rate_ramp": term}, coefficients=coefficients,
                  covariance=covariance, ramp_removed=removed)  # fmt: skip
    return ChannelResult(channel, curve.with_edf(weights.edf), fit, weights, ramp, ramp_weights)


def characterise(
    res: Residual, channels: tuple[str, ...] = CHANNELS, progress: Callable[[int, int], None] | None = None
) -> Characterisation:
    """Every channel's Allan curve with its confidence intervals and the IEEE noise terms fitted to it;
    ``progress(channels_done, channels)`` after each channel.

    Raises
    ------
    SinsInputError
        one line naming the source and channel: a channel whose Allan curve has too few non-zero points.
    """
    out = {}
    for ch in channels:
        i = CHANNELS.index(ch)
        try:
            out[ch] = characterise_channel(res.values[:, i], res.dt, res.segments, ch)
        except SinsInputError as exc:
            raise SinsInputError(f"{res.source or 'recording'}: {exc}") from None
        if progress is not None:
            progress(len(out), len(channels))
    return Characterisation(res.source, res.dt, res.rows, res.segments, out, res.input_mean, res.notes,
                            res.warnings)  # fmt: skip


#: What an unresolved term without a bound is said to be: its fit beside the resolved terms fails (a
#: Gauss–Markov bias whose correlation time nothing in the curve holds), so the data give it no bound.
UNBOUNDED = "no bound: no fit holds it beside the resolved terms"


def display(sensor: str, name: str, value: float | None) -> str:
    """A term's value in its display unit, four significant digits ('-' for None)."""
    if value is None or not math.isfinite(value):
        return "-"
    size, _ = DISPLAY[sensor][name]
    return f"{value / size:.4g}"


def duration(seconds: float) -> str:
    """A duration in the unit that reads best: s, min, h or days."""
    if seconds < 120.0:
        return f"{seconds:.3g} s"
    if seconds < 7200.0:
        return f"{seconds / 60.0:.3g} min"
    if seconds < 3.0 * 86400.0:
        return f"{seconds / 3600.0:.3g} h"
    return f"{seconds / 86400.0:.3g} days"


__all__ = [
    "ADEV_DISPLAY",
    "DISPLAY",
    "GAP_STEPS",
    "MIN_POINTS",
    "MIN_ROWS",
    "SI_UNITS",
    "SLOW_STEP_S",
    "STEP_TOLERANCE",
    "UNBOUNDED",
    "ChannelResult",
    "Characterisation",
    "Residual",
    "characterise",
    "characterise_channel",
    "display",
    "duration",
    "refit_channel",
    "residual",
]
