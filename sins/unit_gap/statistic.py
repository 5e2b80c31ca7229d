"""Which statistic a recording's reference calls for: per-sample residuals or integrated ones.

The per-sample diagnosis (:func:`sins.gap.diagnose`) sets each reading against its reference input. Where
that reference is a trajectory, its inputs come by differentiation (splines through attitude and
position), whose noise may exceed the sensor's many times; the residual is then the reference's, and so
is every verdict on it. The interval statistic (:mod:`sins.unit_gap.search`) compares integrated
rotation and velocity change instead, where the reference's noise is that of two epochs.

:func:`choose` measures both noises per sample: the sensor's own from its readings alone (what a local
polynomial through a few neighbouring readings leaves, so that the motion, smooth over that span, does
not count; :func:`sensor_noise`), and the residual's (reading less its reference input, its noise level
from first differences: :func:`sins.gap.floor.noise_level`). Where the residual's exceeds the sensor's by
:data:`REFERENCE_RATIO` on any channel (the reference's own noise at least as large as the sensor's), the
reference sets the per-sample residual and the intervals are used. The interval fit's own figures (the
reference's noise over an interval at rest against the sensor's:
:class:`~sins.compensation.interval_fit.ReferenceQuality`) are reported beside them.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_coeffs, savgol_filter

from sins.compensation.interval_fit import ReferenceQuality
from sins.core.series import CalibrationData, NavSeries
from sins.gap.floor import TINY, noise_floor, noise_level

Array = NDArray[np.float64]

#: The residual's noise against the sensor's beyond which the reference's noise is not negligible: 1.2,
#: where the reference's own noise is two thirds of the sensor's (``√(1.2² − 1)``). An exact reference
#: (a simulation's trajectory) measures 1.0 (0.98-1.03 in the tests); EuRoC's interpolated ground
#: truth 1.3-1.4, BROAD's motion capture 6.6-11.4, both on their rests' noise.
REFERENCE_RATIO = 1.2
#: The local polynomial the sensor's noise is measured about: this many readings, this degree (a cubic
#: over 11 readings follows a rate that turns over 50 ms at 200 Hz).
_WINDOW, _DEGREE = 11, 3
STATISTICS = ("auto", "samples", "intervals")
#: Where the sensor's noise was measured without 200 rows at rest (``sensor_noise_from``): in motion,
#: where what the cubic cannot follow passes for noise.
IN_MOTION = "a cubic through 11 readings"


@dataclass(frozen=True)
class Statistic:
    """The statistic chosen (``kind``: "samples" or "intervals"), why in words, and the figures."""

    kind: str
    why: str
    figures: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON form."""
        return {"kind": self.kind, "why": self.why, **self.figures}


def sensor_noise(readings: Array) -> Array:
    """Each channel's white noise (n, k) → (k,), from what a cubic through 11 neighbouring readings
    leaves, divided by the part of white noise it leaves (``√(1 − c₀)``, ``c₀`` its centre weight)."""
    if len(readings) < 4 * _WINDOW:
        return np.full(readings.shape[1], np.nan)
    smooth = savgol_filter(readings, _WINDOW, _DEGREE, axis=0, mode="interp")
    centre = float(savgol_coeffs(_WINDOW, _DEGREE)[_WINDOW // 2])
    left = (readings - smooth)[_WINDOW:-_WINDOW]
    return np.asarray(np.std(left, axis=0) / np.sqrt(1.0 - centre))


#: A reference epoch is at rest where, over the second after it, the reference turns by less than this
#: and moves at less than :data:`_STILL_MPS` (the interval fit's test of a still interval).
_STILL_DEG, _STILL_MPS, _STILL_S = 0.5, 0.02, 1.0
#: The fewest rows at rest that measure the sensor's noise; with fewer, :func:`sensor_noise` of all rows.
_FEWEST_AT_REST = 200


def rest_rows(t: Array, reference: NavSeries) -> NDArray[np.bool_]:
    """The rows at ``t`` within a second after a reference epoch at rest (turned by less than 0.5°
    and moved at less than 2 cm/s over that second)."""
    ahead = np.clip(np.searchsorted(reference.t, reference.t + _STILL_S), 0, len(reference.t) - 1)
    q0, q1 = reference.q_nb, reference.q_nb[ahead]
    turn = 2.0 * np.arccos(np.clip(np.abs(np.sum(q0 * q1, axis=1)), 0.0, 1.0))
    speed = np.maximum(np.linalg.norm(reference.v_n, axis=1), np.linalg.norm(reference.v_n[ahead], axis=1))
    still = (turn < np.radians(_STILL_DEG)) & (speed < _STILL_MPS) & (reference.t[ahead] > reference.t)
    epoch = np.clip(np.searchsorted(reference.t, t, side="right") - 1, 0, len(reference.t) - 1)
    inside = (t >= reference.t[0]) & (t <= reference.t[epoch] + _STILL_S)
    return np.asarray(still[epoch] & inside, dtype=bool)


def _channels(data: CalibrationData) -> Iterator[tuple[str, Array, Array]]:
    """Each channel's name, readings and per-sample residual (reading less its reference input)."""
    for sensor, readings, reference_input in (
        ("gyro", data.gyro, data.ref_gyro), ("accel", data.accel, data.ref_accel)
    ):  # fmt: skip
        for a in range(3):
            yield f"{sensor}.{'xyz'[a]}", readings[:, a], readings[:, a] - reference_input[:, a]


def per_sample_ratios(data: CalibrationData, reference: NavSeries | None) -> tuple[dict[str, float], str]:
    """Per channel, the per-sample residual's noise (reading less its reference input, over every row
    with a reference) over the sensor's own: its readings' at rest (where the ``reference`` trajectory
    stands still for a second), else :func:`sensor_noise` of all rows; and which of the two it was."""
    data = data.rows_with_reference()
    rest = rest_rows(data.t, reference) if reference is not None else np.zeros(len(data.t), dtype=bool)
    at_rest = int(rest.sum()) >= _FEWEST_AT_REST
    cubic = None if at_rest else np.concatenate([sensor_noise(data.gyro), sensor_noise(data.accel)])
    out = {}
    for i, (ch, readings, residual) in enumerate(_channels(data)):
        own = noise_floor(readings, rest) if cubic is None else cubic[i]
        out[ch] = float(noise_level(residual) / max(float(own), TINY))
    where = f"its readings at rest ({int(rest.sum())} rows)" if at_rest else IN_MOTION
    return out, where


def rest_ratios(data: CalibrationData, reference: NavSeries) -> dict[str, float]:
    """Per channel, the per-sample residual's noise over the sensor's own on the rows at rest alone
    (:func:`rest_rows`; empty where fewer than 200 are): what the reference's differentiation adds where
    nothing moves, which a delay of the sensor moves little (a unit at rest has no rate to delay; the
    rests' edges hold some: EuRoC's gyro 5 ms late, 0.28-0.44 → 1.26-1.33 on the gyro's mean)."""
    data = data.rows_with_reference()
    rest = rest_rows(data.t, reference)
    if int(rest.sum()) < _FEWEST_AT_REST:
        return {}
    return {
        ch: float(noise_level(residual, rest) / max(float(noise_floor(readings, rest)), TINY))
        for ch, readings, residual in _channels(data)
    }


def quality_figures(quality: ReferenceQuality | None) -> dict[str, Any]:
    """The interval fit's figures on the reference (its noise over an interval at rest against the
    sensor's), for the report."""
    if quality is None:
        return {}
    out: dict[str, Any] = {"interval_quality": quality.summary()}
    if quality.still_deg is not None and quality.sensor_still_deg:
        out["interval_reference_over_sensor"] = {
            "gyro": quality.still_deg / quality.sensor_still_deg,
            "accel": (quality.still_mps or 0.0) / max(quality.sensor_still_mps or 0.0, TINY),
        }
    return out


def choose(
    asked: str,
    data: CalibrationData | None,
    trajectory: NavSeries | None,
    quality: ReferenceQuality | None,
) -> Statistic:
    """The statistic ``asked`` for ("auto": as the reference calls for; see the module docstring), with
    its reason. ``data``: the per-sample form (None if not made); ``trajectory``: the reference as a
    trajectory (None where it is per-sample inputs: then only samples can be used)."""
    figures = quality_figures(quality)
    if trajectory is None:
        return Statistic(
            "samples", "the reference is per-sample inputs (a rig's, or a dataset's): nothing to integrate",
            figures,
        )  # fmt: skip
    ratios, where = per_sample_ratios(data, trajectory) if data is not None else ({}, "")
    if ratios:
        figures["per_sample_residual_over_sensor"] = ratios
        figures["sensor_noise_from"] = where
    worst = max(ratios, key=lambda c: ratios[c]) if ratios else None
    measured = (
        f"per sample, the reading less its reference varies {ratios[worst]:.2g}x the sensor's own noise "
        f"({where}) on {worst}"
        if worst is not None
        else "the per-sample noises were not measured"
    )
    if asked in ("samples", "intervals"):
        return Statistic(asked, f"asked for; {measured}", figures)
    if worst is not None and ratios[worst] > REFERENCE_RATIO:
        why = (
            f"{measured}: the differentiated reference sets the per-sample residual, so rotation and "
            "velocity change are compared over the reference's intervals"
        )
        return Statistic("intervals", why, figures)
    why = f"{measured}, within {REFERENCE_RATIO:.2g}x: the sensor, not the reference, sets the residual"
    return Statistic("samples", why, figures)


__all__ = [
    "IN_MOTION",
    "REFERENCE_RATIO",
    "STATISTICS",
    "Statistic",
    "choose",
    "per_sample_ratios",
    "quality_figures",
    "rest_ratios",
    "rest_rows",
    "sensor_noise",
]
