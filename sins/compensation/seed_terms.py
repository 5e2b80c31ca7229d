"""The seed model's scale and misalignment terms compared across recordings of one unit.

A model of a unit, and a simulation of it, holds one value of each scale factor and misalignment; a
recording whose reference says otherwise parts from both wherever it turns. Each recording's own seed
model is fitted on its reference's intervals alone (:func:`sins.compensation.interval_fit.fit_intervals`;
``sins gap`` keeps it as ``statistic.seed_model``, ``sins fit`` on several recordings fits it beside the
shared one), with standard errors; its gyro matrix ``B`` and accelerometer matrix ``A`` (``reading −
truth = … + M x``: the diagonal the scale errors, ``M[i, j]`` off it axis ``i``'s reading of axis ``j``'s
input, ``i←j``) are compared. A term *differs between the recordings* where both

* its values are not one value within their standard errors: the chi-square of their weighted mean above
  scipy's 99.9 % quantile on ``n − 1`` degrees of freedom, and
* its values span more than the unit-to-unit spread of that term in the unit's class
  (:func:`sins.compensation.identifiability.class_bounds`; a consumer unit's, the loosest, unless a fit's
  ``--grade`` says otherwise: the gyro's misalignment 10 mrad and scale 2 %, the accelerometer's 5 mrad
  and 1 %): a difference between one unit's recordings as large as between two units is not the unit's.

A recording is named *apart* where, without it, the others do not differ by the same test: the term is
that recording's (its reference's, its mounting's), not a unit whose term wanders. A value beyond the
class's bound (five spreads) is said so: no unit of the class has it, and the term's columns more likely
take up the reference's error or an effect the model lacks (EuRoC's accelerometer misalignments on a
drone, where the specific force stays near gravity's direction: 0.1 rad ± 0.02 on V1_01). EuRoC's V1_01
reads 22.9 mrad of its x rate on its gyro y against 0.08 and 3.8 on V1_02 and V1_03, the largest thing
between it and the best published figure (``tools/euroc_bias_ceiling.py``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from sins.compensation.identifiability import DEFAULT_GRADE, class_bounds
from sins.imu.calibration import SeedModelFit

Array = NDArray[np.float64]

#: The chi-square quantile above which a term's values are not one value within their standard errors.
CONFIDENCE = 0.999
#: Where each sensor's matrix is in a seed model fit.
_MATRICES = {"gyro": ("B", "B_se"), "accel": ("A", "A_se")}


def of_fit(seed: SeedModelFit) -> dict[str, dict[str, list[list[float]]]]:
    """A recording's seed-model matrices and their standard errors, SI, as ``statistic.seed_model``
    keeps them."""
    return {
        sensor: {"matrix": getattr(seed, m).tolist(), "se": getattr(seed, se).tolist()}
        for sensor, (m, se) in _MATRICES.items()
    }


class Term(NamedTuple):
    """One term of a sensor's seed-model matrix, ``M[i, j]``: its ``name`` (``gyro scale y`` on the
    diagonal, ``gyro misalignment y←x`` off it), the key of its class's spread and bound
    (:func:`~sins.compensation.identifiability.class_bounds`: ``gyro.scale``, ``gyro.misalignment``) and
    how it is shown (``scale`` × the dimensionless value, in ``unit``: ppm, mrad)."""

    name: str
    kind: str
    scale: float
    unit: str


def term(sensor: str, i: int, j: int) -> Term:
    """The term ``M[i, j]`` of ``sensor``'s matrix (:class:`Term`)."""
    axes = "xyz"
    if i == j:
        return Term(f"{sensor} scale {axes[i]}", f"{sensor}.scale", 1e6, "ppm")
    return Term(f"{sensor} misalignment {axes[i]}←{axes[j]}", f"{sensor}.misalignment", 1e3, "mrad")


def _differs(values: Array, se: Array, spread: float) -> tuple[bool, float]:
    """Whether ``values`` (± ``se``) differ by the module's test, and their chi-square."""
    weights = 1.0 / se**2
    mean = float(np.sum(weights * values) / np.sum(weights))
    stat = float(np.sum(((values - mean) / se) ** 2))
    wide = float(values.max() - values.min()) > spread
    return bool(wide and stat > chi2.ppf(CONFIDENCE, len(values) - 1)), stat


def differing(seed_models: Mapping[str, dict[str, Any]], grade: str = DEFAULT_GRADE) -> dict[str, Any]:
    """The recordings ``compared`` (the names of ``seed_models``, each as :func:`of_fit` gives it), the
    ``grade`` whose spreads and bounds judge them, and the terms that ``differ`` between them (see the
    module docstring): each with its values and standard errors per recording (mrad for a misalignment,
    ppm for a scale), its chi-square and degrees of freedom, the recording apart or None, and the
    recordings where its value is beyond the class's bound (``beyond_bound``: no unit of the class has
    it). A term not fitted on a recording (a standard error of zero, or not finite) is left out there."""
    bounds = class_bounds(grade)
    kept = list(seed_models.items())
    out: list[dict[str, Any]] = []
    for sensor in _MATRICES:
        for i in range(3):
            for j in range(3):
                each = {
                    n: (float(m[sensor]["matrix"][i][j]), float(m[sensor]["se"][i][j]))
                    for n, m in kept
                    if float(m[sensor]["se"][i][j]) > 0.0
                }
                if len(each) < 2:
                    continue
                t = term(sensor, i, j)
                limit = bounds.spread[t.kind]
                values, se = (np.array(v) for v in zip(*each.values(), strict=True))
                found, stat = _differs(values, se, limit)
                if not found:
                    continue
                out.append({
                    "term": t.name,
                    "unit": t.unit,
                    "values": {n: [v * t.scale, s * t.scale] for n, (v, s) in each.items()},
                    "chi_square": stat,
                    "dof": len(each) - 1,
                    "apart": _apart(each, limit),
                    "beyond_bound": [n for n, (v, _) in each.items() if abs(v) > bounds.bound[t.kind]],
                })  # fmt: skip
    return {"compared": [n for n, _ in kept], "differ": out, "grade": grade}


def _apart(each: dict[str, tuple[float, float]], spread: float) -> str | None:
    """The one recording without which the others do not differ (of three or more), else None."""
    if len(each) < 3:
        return None
    alone = []
    for name in each:
        rest = [v for n, v in each.items() if n != name]
        values, se = (np.array(v) for v in zip(*rest, strict=True))
        if not _differs(values, se, spread)[0]:
            alone.append(name)
    return alone[0] if len(alone) == 1 else None


def lines(found: dict[str, Any]) -> list[str]:
    """What :func:`differing` found, a line per term under a heading, or one line where nothing differs;
    none where fewer than two recordings have a seed model."""
    if len(found["compared"]) < 2:
        return []
    if not found["differ"]:
        return [
            f"each recording's own seed model (fitted on it alone): its scale and misalignment agree between "
            f"the {len(found['compared'])} recordings (within their standard errors or a {found['grade']} "
            "unit's spread)"
        ]
    out = [
        "each recording's own seed model (fitted on it alone): terms that differ between the recordings by "
        f"more than their standard errors and a {found['grade']} unit's spread (a model of the unit, and a "
        "simulation of it, hold one value):"
    ]
    for d in found["differ"]:
        each = ", ".join(f"{n} {v:.3g} ± {s:.2g}" for n, (v, s) in d["values"].items())
        apart = f"; {d['apart']} apart from the others" if d["apart"] else ""
        stat = f"chi-square {d['chi_square']:.3g} on {d['dof']}"
        out.append(f"  {d['term']} ({d['unit']}): {each}; {stat}{apart}")
        if d["beyond_bound"]:
            out.append(
                f"    beyond what a {found['grade']} unit has on {', '.join(d['beyond_bound'])}: more likely "
                "its columns absorb the reference's error or an effect the model lacks than the unit's term"
            )
    return out


__all__ = [
    "CONFIDENCE",
    "Term",
    "differing",
    "lines",
    "of_fit",
    "term",
]
