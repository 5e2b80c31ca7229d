"""Compensation strategies: fitted on calibration data, they remove the IMU's errors before integration.

:mod:`~sins.compensation.base` holds the interface, :mod:`~sins.compensation.registry` makes strategies by
name and keeps their model files; the strategies are :mod:`~sins.compensation.regression` (least squares),
:mod:`~sins.compensation.mlp` and :mod:`~sins.compensation.kohonen` (learned, on
:mod:`~sins.compensation.residual`'s physics-first base).
"""

from sins.compensation.base import (
    NoCompensation,
    NotFittedError,
    Oracle,
    ParamRange,
    Strategy,
    residual_rms,
)
from sins.compensation.registry import (
    CLASSES,
    DESCRIPTIONS,
    FORMAT_NAME,
    FORMAT_VERSION,
    SAVED_STRATEGIES,
    VARIANTS,
    load,
    make,
    save,
    strategy_class,
    strategy_names,
)
from sins.compensation.regression import ExtendedRegression, Regression

__all__ = [
    "CLASSES",
    "DESCRIPTIONS",
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "SAVED_STRATEGIES",
    "VARIANTS",
    "ExtendedRegression",
    "NoCompensation",
    "NotFittedError",
    "Oracle",
    "ParamRange",
    "Regression",
    "Strategy",
    "load",
    "make",
    "residual_rms",
    "save",
    "strategy_class",
    "strategy_names",
]
