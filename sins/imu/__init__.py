"""The IMU: the effect vocabulary (:mod:`~sins.imu.vocabulary`, the library's effects in
:mod:`~sins.imu.effects`), models that compose them and corrupt readings (:mod:`~sins.imu.model`, chunk
by chunk in :mod:`~sins.imu.stream`), specifications in engineers' units and grades
(:mod:`~sins.imu.spec`), and calibration rigs with the seed model's fit (:mod:`~sins.imu.calibration`).

The model's public names are importable from here (``from sins.imu import ImuModel``).
"""

from sins.imu.effects import (
    BASELINE,
    Bias,
    BiasInstability,
    G2Sensitivity,
    GSensitivity,
    MotionBias,
    Noise,
    Quantization,
    QuantizationNoise,
    RateRandomWalk,
    Saturation,
    ScaleAsymmetry,
    ScaleMisalignment,
    ScaleNonlinearity,
    SizeEffect,
    TemperatureBias,
    TemperatureScale,
    TimeOffset,
)
from sins.imu.model import ImuModel
from sins.imu.vocabulary import (
    CHANNELS,
    DEG,
    DEG_PER_H,
    MG,
    PPM,
    SENSORS,
    UG,
    Effect,
    TrueInputs,
    display_unit,
    effect_class,
    effect_names,
    effect_types,
    register,
)

__all__ = [
    "BASELINE",
    "CHANNELS",
    "DEG",
    "DEG_PER_H",
    "MG",
    "PPM",
    "SENSORS",
    "UG",
    "Bias",
    "BiasInstability",
    "Effect",
    "G2Sensitivity",
    "GSensitivity",
    "ImuModel",
    "MotionBias",
    "Noise",
    "Quantization",
    "QuantizationNoise",
    "RateRandomWalk",
    "Saturation",
    "ScaleAsymmetry",
    "ScaleMisalignment",
    "ScaleNonlinearity",
    "SizeEffect",
    "TemperatureBias",
    "TemperatureScale",
    "TimeOffset",
    "TrueInputs",
    "display_unit",
    "effect_class",
    "effect_names",
    "effect_types",
    "register",
]
