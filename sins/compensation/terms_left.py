"""The gyro scale and misalignment a fitted model leaves of a recording, against its reference.

A model fitted on some recordings corrects another with their scale factors and misalignments. Where
the judged recording's own differ (its mounting, its reference, a unit whose terms moved), the open-loop
attitude keeps an error that no estimate of the bias takes away, and the figures say nothing of why.
``sins evaluate`` therefore fits the seed model once more on the model's corrected readings against the
recording's reference (:func:`sins.compensation.interval_fit.fit_intervals`: its intervals, no time
offset, no g-sensitivity; the bias is taken up by the fit's own) and names each gyro term left where

* it is larger than a consumer unit's unit-to-unit spread of that term
  (:func:`sins.compensation.identifiability.class_bounds`: 10 mrad of misalignment, 2 % of scale): a
  difference from the model as large as between two units, which no model of the unit would hold, and
* it is determined: more than :data:`Z_DETERMINED` standard errors (99.9 %, two-sided), the test of
  :mod:`sins.compensation.seed_terms` for one value.

EuRoC's V1_01, judged by least squares fitted on the published split's six training sequences, is left
24.1 ± 2.6 mrad of its x rate on its gyro y (on the 0.2 s intervals of ``tools/euroc_bias_ceiling.py``,
19.5, where a matrix of its own takes its 2.38° to 1.27°); no other judged sequence is left a term
beyond a unit's spread.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.stats import norm

from sins.compensation import interval_fit, seed_terms
from sins.compensation.identifiability import DEFAULT_GRADE, class_bounds

if TYPE_CHECKING:
    from sins.core.series import ImuIncrements, ReferencedRecording

#: A term left is determined beyond this many standard errors (99.9 %, two-sided).
Z_DETERMINED = float(norm.ppf(1.0 - 0.001 / 2.0))


def gyro_terms_left(corrected_imu: ImuIncrements, rec: ReferencedRecording) -> dict[str, Any]:
    """The gyro terms a model leaves of ``rec`` (see the module docstring), ``corrected_imu`` its
    readings as the model corrects them (before any bias rule; the readings as they are where the model
    leaves the gyro as read): ``terms``, each with its ``name`` (``gyro misalignment y←x``, ``gyro scale
    z``), ``value`` and ``se`` (mrad or ppm, ``unit``); ``intervals`` the fit's. Where the recording's
    intervals cannot be fitted, ``not_judged`` says why and ``terms`` is empty."""
    corrected = dataclasses.replace(rec, imu=corrected_imu)
    try:
        fit = interval_fit.fit_intervals(corrected, time_offset=False, g_sensitivity=False)
    except ValueError as exc:
        return {"terms": [], "not_judged": str(exc)}
    spread = class_bounds(DEFAULT_GRADE).spread
    terms = []
    for i in range(3):
        for j in range(3):
            value, se, t = float(fit.seed.B[i, j]), float(fit.seed.B_se[i, j]), seed_terms.term("gyro", i, j)
            if abs(value) > spread[t.kind] and np.isfinite(se) and abs(value) > Z_DETERMINED * se:
                terms.append({"name": t.name, "value": value * t.scale, "se": se * t.scale, "unit": t.unit})
    return {"terms": terms, "intervals": fit.intervals}


def said(left: dict[str, Any]) -> str:
    """The terms left, in one line ("" where none)."""
    if not left["terms"]:
        return ""
    each = ", ".join(f"{t['name']} {t['value']:.3g} ± {t['se']:.2g} {t['unit']}" for t in left["terms"])
    return (
        f"against its reference, the model leaves this recording's {each}: beyond a {DEFAULT_GRADE} unit's "
        "spread, a term of the recording's own (its mounting, its reference) that no model fitted on "
        "other recordings holds, and that no bias estimate takes away"
    )


__all__ = [
    "Z_DETERMINED",
    "gyro_terms_left",
    "said",
]
