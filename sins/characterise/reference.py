"""A recording with a reference: its deterministic errors and its reference taken away before the Allan
analysis, or, where the reference is noisier than the sensor, the sensor's still stretches alone.

**Deterministic errors.** Against a rig's or a trajectory's reference inputs, a unit's bias, scale
factors, misalignments and g-sensitivity (the seed model) make errors that change with the input: a rig
session's holds and rotations turn them into steps and ramps of the residual, which an Allan analysis
reads as slow noise (a tactical unit's rig recording gave a rate random walk of 768–1264 °/h/√h where it
has none). So the seed model is fitted to the residual by least squares first
(:func:`sins.imu.calibration.fit_seed_model`, the fit ``sins.compensation.Regression`` wraps; it sits in
the IMU layer, below both, so this package needs no compensation strategy) and its prediction taken away.
A recording that does not determine it (one orientation) keeps its errors: those are then constant
within each segment, where an Allan deviation does not see them.

**A reference noisier than the sensor.** A reference derived from motion capture (BROAD) is
differentiated: its noise is tens of times the sensor's, and the residual's Allan curve is the
reference's. Where the unit stood still (:func:`sins.characterise.still.still_rows`) its readings need no
reference at all; there the residual's Allan variance at the three shortest cluster times is compared
with the readings' own, and where it exceeds them by :data:`REFERENCE_LIMIT` on any channel the sensor is
characterised on its still stretches, readings as they are, and the report says that the moving parts
are limited by the reference: its noise is never written into a model file as the sensor's.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from sins.characterise.allan import allan
from sins.characterise.analysis import MIN_ROWS, Residual, duration, residual
from sins.characterise.still import still_rows
from sins.core.series import CalibrationData
from sins.errors import SinsInputError
from sins.imu import CHANNELS
from sins.imu.calibration import fit_seed_model

Array = NDArray[np.float64]

#: The residual's Allan variance over the readings' own, at the shortest cluster times where the unit
#: stood still, above which the reference limits the analysis (it adds half the sensor's variance).
REFERENCE_LIMIT = 1.5
#: The cluster sizes compared (1, 2 and 4 samples).
_COMPARED = 3


def seed_model_errors(data: CalibrationData) -> tuple[Array, str]:
    """The seed model's errors (n, 6) fitted to ``data`` against its reference (zero where it has none),
    and a note of what was fitted."""
    predicted = np.zeros((len(data), 6))
    fit = None
    for g_sensitivity in (True, False):
        try:
            fit = fit_seed_model(data, g_sensitivity=g_sensitivity)
            break
        except ValueError:
            continue
    if fit is None:
        return predicted, (
            "the recording does not determine the seed model (bias, scale factors, misalignments): its "
            "errors stay in the residual, constant within each stretch, where an Allan deviation does not "
            "see them"
        )
    ok = data.has_reference
    w, f = data.ref_gyro[ok], data.ref_accel[ok]
    predicted[ok, :3] = fit.B0 + w @ fit.B.T + f @ fit.K.T
    predicted[ok, 3:] = fit.A0 + f @ fit.A.T
    what = "bias, scale factors, misalignments" + (", g-sensitivity" if np.any(fit.K) else "")
    return predicted, f"the seed model ({what}) fitted against the reference by least squares and taken away"


def reference_excess(readings: Array, values: Array, dt: float, still: NDArray[np.bool_]
                     ) -> tuple[Array, tuple[tuple[int, int], ...]] | None:  # fmt: skip
    """Per channel (6,), the residual's Allan variance ``values`` over the readings' own at the three
    shortest cluster times (the largest ratio) where the unit stood still, and those stretches; None
    when it never stood still for :data:`~sins.characterise.analysis.MIN_ROWS` rows."""
    edges = np.diff(np.r_[0, still.astype(np.int8), 0])
    spans = [(int(a), int(b)) for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1),
                                              strict=True) if b - a >= MIN_ROWS]  # fmt: skip
    if not spans:
        return None
    ratio = np.zeros(6)
    for i in range(6):
        own = allan(readings[:, i], dt, spans).avar[:_COMPARED]
        with_reference = allan(np.nan_to_num(values[:, i]), dt, spans).avar[:_COMPARED]
        ratio[i] = float(np.max(with_reference / np.maximum(own, 1e-300)))
    return ratio, tuple(spans)


def _constant(reference: Array) -> bool:
    """Whether every channel of a reference (n, 6) holds one value (to 1e-9 of its size) where finite."""
    finite = reference[np.isfinite(reference).all(axis=1)]
    if len(finite) == 0:
        return False
    return bool(np.all(np.ptp(finite, axis=0) <= 1e-9 * (1.0 + np.abs(finite).max(axis=0))))


def reference_residual(data: CalibrationData, source: str = "") -> Residual:
    """The residual of a recording with a reference (see the module's text).

    Raises
    ------
    SinsInputError
        as :func:`sins.characterise.analysis.residual`; and one line when the reference is noisier than
        the sensor and the unit never stood still long enough to characterise it without one.

    A moving unit that never stood still for :data:`~sins.characterise.analysis.MIN_ROWS` rows is
    analysed against its reference with a warning: its reference's noise could not be checked.
    """
    name = source or data.source or "recording"
    readings = np.hstack([data.gyro, data.accel])
    reference = np.hstack([data.ref_gyro, data.ref_accel])
    deterministic, note = seed_model_errors(data)
    values = readings - reference - deterministic
    dt = float(np.median(np.diff(data.t))) if len(data) > 1 else 1.0
    if _constant(reference):
        res = residual(data.t, readings, reference + deterministic, name)
        return replace(
            res,
            notes=(note, "the reference is constant (a unit at rest): none of its noise is in the residual"),
        )
    still = still_rows(readings, dt) & np.isfinite(values).all(axis=1)
    excess = reference_excess(readings, values, dt, still)
    if excess is None or not np.any(excess[0] > REFERENCE_LIMIT):
        res = residual(data.t, readings, reference + deterministic, name)
        if excess is not None:
            return replace(
                res, notes=(note, "where the unit stood still, the reference adds no noise to the sensor's")
            )
        unchecked = (
            f"{name}: the unit never stood still for {MIN_ROWS} rows, so the reference's noise could not be "
            "checked against the sensor's: the terms below may hold the reference's noise and the motion's"
        )
        return replace(res, notes=(note,), warnings=(*res.warnings, unchecked))
    ratio, spans = excess
    keep = np.zeros(len(data), dtype=bool)
    for a, b in spans:
        keep[a:b] = True
    limited = [f"{ch} {r:.3g}x" for ch, r in zip(CHANNELS, ratio, strict=True) if r > REFERENCE_LIMIT]
    try:
        res = residual(data.t, readings, None, name, keep=keep)
    except SinsInputError as exc:
        raise SinsInputError(f"{exc}; the reference is noisier than the sensor, which can be "
                             "characterised only where it stood still") from None  # fmt: skip
    still_s = sum(b - a for a, b in res.segments) * res.dt
    return replace(res, notes=(
        f"the reference is noisier than the sensor: reading less reference has {', '.join(limited)} the "
        "sensor's own Allan variance at its shortest cluster times where it stood still",
        f"so the sensor is characterised on its {len(res.segments)} still stretches ({duration(still_s)}), "
        "readings as they are; the moving parts are limited by the reference and left out",
    ))  # fmt: skip


__all__ = [
    "REFERENCE_LIMIT",
    "reference_excess",
    "reference_residual",
    "seed_model_errors",
]
