"""What a model file records of the readings it was fitted on, and the check that a recording is one the
model may correct: the same unit, axes and rate (a model's time offsets and rests are in samples' terms).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sins.compensation import Strategy
from sins.core.series import CalibrationData, ReferencedRecording
from sins.errors import SinsInputError
from sins.io.recording import Recording


def fitted_on(rec: ReferencedRecording) -> dict[str, Any]:
    """What a model file records of the recording it was fitted on: the unit, its rate, the reference,
    the file's axes the readings were read on (where said), and the readings' digest
    (:func:`readings_of`)."""
    said = {"frame": rec.frame} if rec.frame else {}
    return {"sensor": rec.sensor, "rate_hz": rec.rate_hz, "reference": rec.reference_name, **said,
            "readings": [readings_of(rec)], "marks": [marks_of(rec)]}  # fmt: skip


def readings_of(rec: ReferencedRecording | CalibrationData) -> str:
    """The digest of the readings a fit takes (:func:`sins.io.provenance.readings_digest`): a recording's
    increments, a rig's rates and forces."""
    from sins.io.provenance import readings_digest

    if isinstance(rec, CalibrationData):
        return readings_digest(rec.t, rec.gyro, rec.accel)
    return readings_digest(rec.imu.t, rec.imu.dtheta_b, rec.imu.dv_b)


def marks_of(rec: ReferencedRecording | CalibrationData) -> list[str]:
    """The marks of the readings a fit takes (:func:`sins.io.provenance.readings_marks`), by which a part
    cut from them is known: a rig's rates and forces, a recording's increments."""
    from sins.io.provenance import readings_marks

    if isinstance(rec, CalibrationData):
        return readings_marks(rec.gyro, rec.accel)
    return readings_marks(rec.imu.dtheta_b, rec.imu.dv_b)


def check_fitted_on(
    strategy: Strategy,
    rec: ReferencedRecording | CalibrationData | Recording,
    where: str,
    sensor: str | None = None,
) -> None:
    """Refuse a model fitted on another unit (both named: ``sensor``, else the recording's own), on
    readings read on other axes (``--frame``: its matrices are in the axes it was fitted on; both
    said) or, when it reads the sensors at time offsets or tracks rests (both set in samples' terms), at
    another rate (more than 5 % apart).

    Raises
    ------
    SinsInputError
        naming both units, both axes or both rates.
    """
    fitted = getattr(strategy, "fitted_on_", None)
    if not isinstance(fitted, dict):
        return
    sensor = getattr(rec, "sensor", "") if sensor is None else sensor
    if fitted.get("sensor") and sensor and fitted["sensor"] != sensor:
        folder = " (a data root's FOLDER/NAME takes its folder for its unit)" if f"{sensor}/" in where else ""
        said = f"the model was fitted on {fitted['sensor']}; this recording is {sensor}{folder}"
        raise SinsInputError(f"{where}: {said}")
    frame = getattr(rec, "frame", "")
    if fitted.get("frame") and frame and fitted["frame"] != frame:
        raise SinsInputError(
            f"{where}: the model was fitted on readings taken on the file's axes as {fitted['frame']}; this "
            f"recording is read as {frame} (read it with --frame {fitted['frame']}, or fit again)"
        )
    rate = fitted.get("rate_hz")
    t = rec.imu.t if isinstance(rec, ReferencedRecording | Recording) else rec.t
    here = float(1.0 / np.median(np.diff(t)))
    if isinstance(rate, int | float) and not isinstance(rate, bool) and abs(here - rate) > 0.05 * rate:
        raise SinsInputError(
            f"{where}: the model was fitted on readings at {rate:.6g} Hz, its time offsets in those terms; "
            f"this recording is at {here:.6g} Hz (fit a model on readings at its rate)"
        )


__all__ = ["check_fitted_on", "fitted_on", "marks_of", "readings_of"]
