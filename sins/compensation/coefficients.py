"""A seed-model fit in an engineer's terms: each coefficient with its standard error in the units a
datasheet uses (°/h, ppm, mrad, µg, °/h/g), for ``sins fit``'s table and its JSON."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from sins.core.earth import G0
from sins.imu.calibration import SeedModelFit

_AXES = "xyz"
_DPH = math.degrees(1.0) * 3600.0  # rad/s → °/h


@dataclass(frozen=True)
class Coefficient:
    """One coefficient: ``sensor`` (gyro, accel), ``term`` (bias, scale, misalignment, g_sensitivity),
    ``axis`` (``x`` or, off the diagonal, ``x←y``: the x channel's response to the y input), ``value``
    and ``se`` (NaN where not estimated) in ``unit``."""

    sensor: str
    term: str
    axis: str
    value: float
    se: float
    unit: str

    def to_dict(self) -> dict[str, str | float | None]:
        """As JSON: NaN standard errors become None."""
        d: dict[str, str | float | None] = asdict(self)
        if not math.isfinite(self.se):
            d["se"] = None
        return d


def engineering(seed: SeedModelFit, *, g_sensitivity: bool = True) -> list[Coefficient]:
    """The seed model's coefficients (errors as reading − truth) in datasheet units: biases in °/h and
    µg, scale factors (the diagonals) in ppm, misalignments (off the diagonals) in mrad, the gyro's
    g-sensitivity in °/h/g (omitted without ``g_sensitivity``)."""
    out: list[Coefficient] = []
    for sensor, bias, bias_se, matrix, matrix_se, bias_scale, bias_unit in (
        ("gyro", seed.B0, seed.B0_se, seed.B, seed.B_se, _DPH, "°/h"),
        ("accel", seed.A0, seed.A0_se, seed.A, seed.A_se, 1e6 / G0, "µg"),
    ):
        for i in range(3):
            out.append(
                Coefficient(
                    sensor, "bias", _AXES[i], bias[i] * bias_scale, bias_se[i] * bias_scale, bias_unit
                )
            )
        for i in range(3):
            out.append(
                Coefficient(sensor, "scale", _AXES[i], matrix[i, i] * 1e6, matrix_se[i, i] * 1e6, "ppm")
            )
        for i in range(3):
            for j in range(3):
                if i != j:
                    axis = f"{_AXES[i]}←{_AXES[j]}"
                    out.append(
                        Coefficient(
                            sensor, "misalignment", axis, matrix[i, j] * 1e3, matrix_se[i, j] * 1e3, "mrad"
                        )
                    )
    if g_sensitivity:
        for i in range(3):
            for j in range(3):
                value, se = seed.K[i, j] * _DPH * G0, seed.K_se[i, j] * _DPH * G0
                out.append(Coefficient("gyro", "g_sensitivity", f"{_AXES[i]}←{_AXES[j]}", value, se, "°/h/g"))
    return out


def table_rows(coefficients: list[Coefficient]) -> list[list[str]]:
    """Rows for a fixed-width table: sensor, term, axis, value ± se, unit; a coefficient held at zero (an
    infinite standard error: :mod:`sins.compensation.identifiability`) reads ``0 (held)``."""
    rows = []
    for c in coefficients:
        se = f" ± {c.se:.3g}" if math.isfinite(c.se) else ""
        value = "0 (held)" if c.se == math.inf and c.value == 0.0 else f"{c.value:.4g}{se}"
        rows.append([c.sensor, c.term, c.axis, value, c.unit])
    return rows


__all__ = ["Coefficient", "engineering", "table_rows"]
