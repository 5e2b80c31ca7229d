"""A recording characterised: each channel's Allan curve and the noise terms fitted to it.

The input is what is left of a reading once its reference is taken away (:func:`residual`): a static
unit's readings as they are (a constant input does not change an Allan deviation), or a moving unit's
readings less the reference inputs of its trajectory or rig. Rows without a reference (the turns of a
hand-made Ferraris session) split the recording into segments, and so do gaps in time; the Allan
deviation pools the cluster differences inside each segment (:mod:`sins.characterise.allan`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.characterise.allan import MIN_CLUSTERS, AllanCurve, allan
from sins.characterise.terms import TERMS, NoiseFit, fit_terms, spectral
from sins.errors import SinsInputError
from sins.imu.model import CHANNELS, DEG, DEG_PER_H, UG

Array = NDArray[np.float64]

#: A recording needs this many rows in its longest segment: two octaves of cluster sizes.
MIN_ROWS = 2 * MIN_CLUSTERS
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
        "bias_instability": (DEG_PER_H, "°/h"),
        "rate_random_walk": (DEG_PER_H / 60.0, "°/h/√h"),
        "rate_ramp": (DEG_PER_H / 3600.0, "°/h²"),
    },
    "accel": {
        "quantization": (UG, "µg·s"),
        "white": (UG, "µg/√Hz"),
        "bias_instability": (UG, "µg"),
        "rate_random_walk": (UG, "µg/√s"),
        "rate_ramp": (UG, "µg/s"),
    },
}
#: The SI unit of each term, per sensor (the JSON's).
SI_UNITS: dict[str, dict[str, str]] = {
    "gyro": {"quantization": "rad", "white": "rad/√s", "bias_instability": "rad/s",
             "rate_random_walk": "rad/s/√s", "rate_ramp": "rad/s²"},
    "accel": {"quantization": "m/s", "white": "m/s/√s", "bias_instability": "m/s²",
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
    """

    values: Array
    dt: float
    segments: tuple[tuple[int, int], ...]
    source: str = ""
    input_mean: Array | None = None

    @property
    def length_s(self) -> float:
        """The longest segment's duration, s."""
        return max(b - a for a, b in self.segments) * self.dt

    @property
    def rows(self) -> int:
        """The rows inside the segments."""
        return sum(b - a for a, b in self.segments)


def residual(t: Array, readings: Array, reference: Array | None = None, source: str = "") -> Residual:
    """The residual of readings (n, 6) at times ``t`` (n,) against a reference (n, 6), or None (static).

    Rows where the residual is not finite, and steps longer than :data:`GAP_STEPS` sampling steps, end
    a segment; every step inside a segment must match the sampling step to :data:`STEP_TOLERANCE`.

    Raises
    ------
    SinsInputError
        one line naming ``source``: fewer than :data:`MIN_ROWS` referenced rows in a row, steps that are
        not increasing, or uneven sampling (with the row).
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
        raise SinsInputError(f"{name}: {len(t)} rows; an Allan analysis needs at least {MIN_ROWS}")
    steps = np.diff(t)
    if not np.all(steps > 0.0):
        row = int(np.argmax(~(steps > 0.0))) + 1
        raise SinsInputError(f"{name}: row {row + 1}: time t={t[row]:g} s does not increase")
    dt = float(np.median(steps))
    good = np.isfinite(values).all(axis=1)
    breaks = steps > GAP_STEPS * dt
    rows = np.flatnonzero(good)
    segments = []
    if len(rows):
        joined = (np.diff(rows) == 1) & ~breaks[rows[:-1]]
        starts = rows[np.r_[True, ~joined]]
        stops = rows[np.r_[~joined, True]] + 1
        segments = [(int(a), int(b)) for a, b in zip(starts, stops, strict=True) if b - a >= 2]
    if not segments or max(b - a for a, b in segments) < MIN_ROWS:
        raise SinsInputError(
            f"{name}: no stretch of {MIN_ROWS} referenced rows without a gap; an Allan analysis needs one"
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
    total = sum(raw[a:b].sum(axis=0) for a, b in segments)
    mean = np.asarray(total, dtype=float) / sum(b - a for a, b in segments)
    return Residual(values, dt, tuple(segments), source, mean)


@dataclass(frozen=True)
class ChannelResult:
    """One channel's Allan curve and the noise terms fitted to it."""

    channel: str
    curve: AllanCurve
    fit: NoiseFit

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
    """

    source: str
    dt: float
    rows: int
    segments: tuple[tuple[int, int], ...]
    channels: dict[str, ChannelResult] = field(default_factory=dict)
    input_mean: Array | None = None

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
            "channels": {},
        }
        for ch, r in self.channels.items():
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
                if name == "bias_instability":
                    entry["tau_c_s"] = r.fit.tau_c_s
                    entry["tau_c_range_s"] = list(r.fit.tau_c_range_s) if r.fit.tau_c_range_s else None
                    entry["b_ieee"] = r.fit.b_ieee
                    entry["b_ieee_sigma"] = r.fit.b_ieee_sigma
                if name == "rate_ramp":
                    entry["simulated"] = False
                terms[name] = entry
            out["channels"][ch] = {
                "tau_s": r.curve.tau_s.tolist(),
                "adev": r.curve.adev.tolist(),
                "adev_low": low.tolist(),
                "adev_high": high.tolist(),
                "edf": r.curve.edf.tolist(),
                "model_adev": np.sqrt(r.fit.resolved_avar(r.curve.tau_s)).tolist(),
                "excluded_tau_s": list(r.fit.excluded_tau_s),
                "tolerance": r.fit.tolerance,
                "terms": terms,
                "chi2": r.fit.chi2,
                "dof": r.fit.dof,
            }
        return out


def characterise_channel(rate: Array, dt: float, segments: tuple[tuple[int, int], ...] | None = None,
                         channel: str = "gyro.x") -> ChannelResult:  # fmt: skip
    """One channel: the Allan curve and the terms fitted to it, then twice over the curve's EDF and its
    points' correlation from the fitted noise (:func:`~sins.characterise.terms.spectral`) and the terms
    fitted again with them (the estimates' variances from the previous fit's model)."""
    spans = segments if segments is not None else ((0, len(rate)),)
    curve = allan(rate, dt, spans)
    length = max(b - a for a, b in spans) * dt
    fit = fit_terms(curve, length)
    for _ in range(2):
        edf, corr = spectral(curve, fit.coefficients, fit.tau_c_s)
        curve = curve.with_edf(edf)
        fit = fit_terms(curve, length, corr, fit.avar(curve.tau_s))
    return ChannelResult(channel, curve, fit)


def characterise(
    res: Residual, channels: tuple[str, ...] = CHANNELS, progress: Callable[[int, int], None] | None = None
) -> Characterisation:
    """Every channel's Allan curve with its confidence intervals and the IEEE noise terms fitted to it;
    ``progress(channels_done, channels)`` after each channel."""
    out = {}
    for ch in channels:
        i = CHANNELS.index(ch)
        out[ch] = characterise_channel(res.values[:, i], res.dt, res.segments, ch)
        if progress is not None:
            progress(len(out), len(channels))
    return Characterisation(res.source, res.dt, res.rows, res.segments, out, res.input_mean)


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
