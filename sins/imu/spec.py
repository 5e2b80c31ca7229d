"""IMU specifications: effects in familiar units, and grade presets that draw individual units.

Files name an effect and give its parameters in the units engineers use
(°/h, mg, ppm, °/√h, µg/√Hz, °/h/g, …); :data:`PARAMETERS` is the one table
that converts them to the SI fields of :mod:`sins.imu`'s effect classes
(``SI = value × factor``). A grade (consumer MEMS, industrial, tactical,
navigation) gives the spread of each coefficient; :func:`draw_unit` draws one
unit's deterministic coefficients from its ``unit_seed`` and its turn-on bias
from a ``run_seed``, so the same unit can be powered on many times.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sins import imu
from sins.nav.earth import G0

DEG = imu.DEG
DEG_PER_H = imu.DEG_PER_H


@dataclass(frozen=True)
class Param:
    """One file parameter: its key, the effect field it sets, ``SI = value × factor``, and the range
    ``[low, high]`` (``(low, high]`` if ``low_open``) every element must lie in, in the file's unit.

    The ranges are generous, far beyond any real unit, and keep every error the model adds finite
    for any motion a scenario may describe (they are listed in ``docs/guide/scenarios.md``).
    """

    key: str
    field: str
    factor: float
    shape: tuple[int, ...]
    unit: str
    low: float = -1e6
    high: float = 1e6
    low_open: bool = False


@dataclass(frozen=True)
class EffectSpec:
    """An effect's class, one-line description and file parameters."""

    cls: type[imu.Effect]
    description: str
    params: tuple[Param, ...]


def _v(key: str, field: str, factor: float, unit: str, low: float = -1e6, high: float = 1e6,
       low_open: bool = False) -> Param:  # fmt: skip
    return Param(key, field, factor, (3,), unit, low, high, low_open)


#: A temperature parameter's range, °C: an IMU's operating range with margin (as scenario and rig files).
_T_LOW, _T_HIGH = -100.0, 200.0


_SPECS: dict[str, EffectSpec] = {
    "gyro.bias": EffectSpec(imu.Bias, "constant drift", (_v("bias_dph", "value", DEG_PER_H, "°/h"),)),
    "accel.bias": EffectSpec(imu.Bias, "constant offset", (_v("bias_mg", "value", imu.MG, "mg", -1e5, 1e5),)),
    "gyro.scale_misalignment": EffectSpec(
        imu.ScaleMisalignment,
        "scale-factor errors (diagonal) and axis misalignment: M·ω",
        (Param("matrix_ppm", "matrix", imu.PPM, (3, 3), "ppm"),),
    ),
    "accel.scale_misalignment": EffectSpec(
        imu.ScaleMisalignment,
        "scale-factor errors (diagonal) and axis misalignment: M·f",
        (Param("matrix_ppm", "matrix", imu.PPM, (3, 3), "ppm"),),
    ),
    "gyro.g_sensitivity": EffectSpec(
        imu.GSensitivity,
        "drift proportional to specific force: K·f",
        (Param("matrix_dph_per_g", "matrix", DEG_PER_H / G0, (3, 3), "°/h/g"),),
    ),
    "gyro.noise": EffectSpec(
        imu.Noise,
        "white noise (angle random walk)",
        (_v("arw_deg_per_rt_h", "density", DEG / 60.0, "°/√h", 0.0, 1e4),),
    ),
    "accel.noise": EffectSpec(
        imu.Noise,
        "white noise (velocity random walk)",
        (_v("vrw_ug_per_rt_hz", "density", imu.UG, "µg/√Hz", 0.0, 1e7),),
    ),
    "gyro.bias_instability": EffectSpec(
        imu.BiasInstability,
        "Gauss–Markov bias: σ, correlation time τ",
        (_v("sigma_dph", "sigma", DEG_PER_H, "°/h", 0.0), _v("tau_s", "tau", 1.0, "s", 1e-6, 1e9)),
    ),
    "accel.bias_instability": EffectSpec(
        imu.BiasInstability,
        "Gauss–Markov bias: σ, correlation time τ",
        (_v("sigma_ug", "sigma", imu.UG, "µg", 0.0, 1e8), _v("tau_s", "tau", 1.0, "s", 1e-6, 1e9)),
    ),
    "gyro.rate_random_walk": EffectSpec(
        imu.RateRandomWalk,
        "random-walk bias",
        (_v("rrw_dph_per_rt_h", "density", DEG_PER_H / 60.0, "°/h/√h", 0.0),),
    ),
    "accel.rate_random_walk": EffectSpec(
        imu.RateRandomWalk, "random-walk bias", (_v("rrw_ug_per_rt_s", "density", imu.UG, "µg/√s", 0.0, 1e8),)
    ),
    "gyro.scale_nonlinearity": EffectSpec(
        imu.ScaleNonlinearity,
        "k2·ω²: scale error growing with the rate",
        (_v("k2_ppm_per_dps", "k2", imu.PPM / DEG, "ppm/(°/s)"),),
    ),
    "accel.scale_nonlinearity": EffectSpec(
        imu.ScaleNonlinearity,
        "k2·f²: scale error growing with the force",
        (_v("k2_ppm_per_g", "k2", imu.PPM / G0, "ppm/g"),),
    ),
    "gyro.scale_asymmetry": EffectSpec(
        imu.ScaleAsymmetry, "ka·|ω|: sign-dependent scale factor", (_v("ka_ppm", "ka", imu.PPM, "ppm"),)
    ),
    "accel.scale_asymmetry": EffectSpec(
        imu.ScaleAsymmetry, "ka·|f|: sign-dependent scale factor", (_v("ka_ppm", "ka", imu.PPM, "ppm"),)
    ),
    "gyro.g2_sensitivity": EffectSpec(
        imu.G2Sensitivity,
        "anisoelastic drift Σ G2·f·f",
        (Param("tensor_dph_per_g2", "tensor", DEG_PER_H / G0**2, (3, 3, 3), "°/h/g²"),),
    ),
    "gyro.temperature_bias": EffectSpec(
        imu.TemperatureBias,
        "c1·(T−T0) + c2·(T−T0)²",
        (
            _v("c1_dph_per_degc", "c1", DEG_PER_H, "°/h/°C", -1e4, 1e4),
            _v("c2_dph_per_degc2", "c2", DEG_PER_H, "°/h/°C²", -1e3, 1e3),
            Param("t0_degc", "t0", 1.0, (), "°C", _T_LOW, _T_HIGH),
        ),
    ),
    "accel.temperature_bias": EffectSpec(
        imu.TemperatureBias,
        "c1·(T−T0) + c2·(T−T0)²",
        (
            _v("c1_mg_per_degc", "c1", imu.MG, "mg/°C", -1e3, 1e3),
            _v("c2_mg_per_degc2", "c2", imu.MG, "mg/°C²", -1e2, 1e2),
            Param("t0_degc", "t0", 1.0, (), "°C", _T_LOW, _T_HIGH),
        ),
    ),
    "gyro.temperature_scale": EffectSpec(
        imu.TemperatureScale,
        "s1·(T−T0)·ω",
        (
            _v("s1_ppm_per_degc", "s1", imu.PPM, "ppm/°C", -1e5, 1e5),
            Param("t0_degc", "t0", 1.0, (), "°C", _T_LOW, _T_HIGH),
        ),
    ),
    "accel.temperature_scale": EffectSpec(
        imu.TemperatureScale,
        "s1·(T−T0)·f",
        (
            _v("s1_ppm_per_degc", "s1", imu.PPM, "ppm/°C", -1e5, 1e5),
            Param("t0_degc", "t0", 1.0, (), "°C", _T_LOW, _T_HIGH),
        ),
    ),
    "gyro.time_offset": EffectSpec(
        imu.TimeOffset, "reports the input τ late", (_v("delay_ms", "delay", 1e-3, "ms", -1e3, 1e3),)
    ),
    "accel.time_offset": EffectSpec(
        imu.TimeOffset, "reports the input τ late", (_v("delay_ms", "delay", 1e-3, "ms", -1e3, 1e3),)
    ),
    "gyro.quantization": EffectSpec(
        imu.Quantization, "output resolution", (_v("step_dps", "step", DEG, "°/s", 0.0, 1e3),)
    ),
    "accel.quantization": EffectSpec(
        imu.Quantization, "output resolution", (_v("step_mg", "step", imu.MG, "mg", 0.0, 1e5),)
    ),
    "gyro.quantization_noise": EffectSpec(
        imu.QuantizationNoise,
        "white noise of the integrated angle (IEEE quantization term Q)",
        (_v("q_arcsec", "q", DEG / 3600.0, "arcsec", 0.0, 1e5),),
    ),
    "accel.quantization_noise": EffectSpec(
        imu.QuantizationNoise,
        "white noise of the integrated velocity (IEEE quantization term Q)",
        (_v("q_ug_s", "q", imu.UG, "µg·s", 0.0, 1e7),),
    ),
    "gyro.saturation": EffectSpec(
        imu.Saturation, "output clipped at ± limit", (_v("limit_dps", "limit", DEG, "°/s", 1e-3, 1e6),)
    ),
    "accel.saturation": EffectSpec(
        imu.Saturation, "output clipped at ± limit", (_v("limit_g", "limit", G0, "g", 1e-6, 1e5),)
    ),
    "accel.size_effect": EffectSpec(
        imu.SizeEffect,
        "lever arm r_i of each accelerometer: ω̇×r + ω×(ω×r)",
        (Param("lever_arms_mm", "lever_arms", 1e-3, (3, 3), "mm (row i: accelerometer i)", -1e4, 1e4),),
    ),
}

#: Effect name → its spec; the same names as :data:`sins.imu.EFFECT_NAMES`.
PARAMETERS = _SPECS
assert set(PARAMETERS) == set(imu.EFFECT_NAMES)


def effect_from_params(name: str, params: dict[str, Any]) -> imu.Effect:
    """Build an effect from file parameters (familiar units); missing parameters are zero.

    Raises ``ValueError`` naming the effect and parameter for an unknown key, a wrong shape, a
    non-finite value or one outside the parameter's range (:class:`Param`).
    """
    if name not in PARAMETERS:
        raise ValueError(f"unknown effect {name!r} (see `sins effects`)")
    spec = PARAMETERS[name]
    known = {p.key: p for p in spec.params}
    for key in params:
        if key not in known:
            raise ValueError(f"{name}: unknown parameter {key!r} (parameters: {', '.join(known)})")
    kwargs: dict[str, Any] = {}
    for key, value in params.items():
        p = known[key]
        a = np.asarray(value, dtype=float)
        if p.shape == (3,) and a.shape == ():
            a = np.full(3, float(a))
        if a.shape != p.shape:
            raise ValueError(f"{name}.{key}: expected shape {p.shape}, got {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError(f"{name}.{key}: values must be finite")
        outside = (a < p.low) | (a > p.high) | ((a == p.low) & p.low_open)
        if outside.any():
            value = float(a.flat[int(np.argmax(outside))])
            low = "(" if p.low_open else "["
            raise ValueError(
                f"{name}.{key}: values must be in {low}{p.low:g}, {p.high:g}] {p.unit}, got {value:g}"
            )
        kwargs[p.field] = float(a) * p.factor if p.shape == () else a * p.factor
    return spec.cls(name.split(".")[0], **kwargs)


# --------------------------------------------------------------------------- grades


@dataclass(frozen=True)
class Grade:
    """Spreads (1σ, unit to unit) and fixed noise levels of an IMU grade, in familiar units.

    A unit's bias is its own draw plus a turn-on draw per run; scale factors
    and misalignments are drawn per unit; noise and bias instability are the
    grade's values.
    """

    name: str
    description: str
    gyro_bias_dph: float
    gyro_turn_on_dph: float
    accel_bias_mg: float
    accel_turn_on_mg: float
    gyro_scale_ppm: float
    gyro_misalignment_ppm: float
    accel_scale_ppm: float
    accel_misalignment_ppm: float
    g_sensitivity_dph_per_g: float
    arw_deg_per_rt_h: float
    vrw_ug_per_rt_hz: float
    gyro_instability_dph: float
    accel_instability_ug: float
    instability_tau_s: float


#: Typical magnitudes per grade; industrial sits between consumer MEMS and tactical.
_GRADE_LIST = (
    Grade(
        name="consumer",
        description="consumer MEMS (phones, wearables)",
        gyro_bias_dph=200.0, gyro_turn_on_dph=50.0, accel_bias_mg=10.0,
        accel_turn_on_mg=3.0, gyro_scale_ppm=20000.0, gyro_misalignment_ppm=10000.0,
        accel_scale_ppm=10000.0, accel_misalignment_ppm=5000.0, g_sensitivity_dph_per_g=100.0,
        arw_deg_per_rt_h=1.0, vrw_ug_per_rt_hz=1000.0, gyro_instability_dph=30.0,
        accel_instability_ug=100.0, instability_tau_s=100.0,
    ),
    Grade(
        name="industrial",
        description="industrial MEMS",
        gyro_bias_dph=30.0, gyro_turn_on_dph=10.0, accel_bias_mg=3.0,
        accel_turn_on_mg=1.0, gyro_scale_ppm=2000.0, gyro_misalignment_ppm=1000.0,
        accel_scale_ppm=1500.0, accel_misalignment_ppm=800.0, g_sensitivity_dph_per_g=10.0,
        arw_deg_per_rt_h=0.3, vrw_ug_per_rt_hz=300.0, gyro_instability_dph=5.0,
        accel_instability_ug=50.0, instability_tau_s=200.0,
    ),
    Grade(
        name="tactical",
        description="tactical grade (FOG / high-end MEMS)",
        gyro_bias_dph=5.0, gyro_turn_on_dph=1.0, accel_bias_mg=1.0,
        accel_turn_on_mg=0.2, gyro_scale_ppm=300.0, gyro_misalignment_ppm=200.0,
        accel_scale_ppm=300.0, accel_misalignment_ppm=150.0, g_sensitivity_dph_per_g=1.0,
        arw_deg_per_rt_h=0.1, vrw_ug_per_rt_hz=100.0, gyro_instability_dph=0.5,
        accel_instability_ug=20.0, instability_tau_s=300.0,
    ),
    Grade(
        name="navigation",
        description="navigation grade (RLG / FOG)",
        gyro_bias_dph=0.01, gyro_turn_on_dph=0.003, accel_bias_mg=0.05,
        accel_turn_on_mg=0.01, gyro_scale_ppm=50.0, gyro_misalignment_ppm=20.0,
        accel_scale_ppm=50.0, accel_misalignment_ppm=20.0, g_sensitivity_dph_per_g=0.01,
        arw_deg_per_rt_h=0.002, vrw_ug_per_rt_hz=20.0, gyro_instability_dph=0.003,
        accel_instability_ug=5.0, instability_tau_s=600.0,
    ),
)  # fmt: skip
GRADES: dict[str, Grade] = {g.name: g for g in _GRADE_LIST}


def draw_unit(grade: str | Grade, unit_seed: int, run_seed: int | None = None) -> imu.ImuModel:
    """One unit of a grade: the seed model's coefficients, white noise and bias instability.

    Parameters
    ----------
    grade : a name in :data:`GRADES` or a :class:`Grade`
    unit_seed : draws the unit's deterministic coefficients (the same seed, the same unit)
    run_seed : draws this power-on's turn-on bias; None keeps only the unit's bias

    Returns
    -------
    ImuModel with the baseline effects (``imu.BASELINE``) plus ``*.bias_instability``
    """
    g = GRADES[grade] if isinstance(grade, str) else grade
    unit = np.random.default_rng([unit_seed, 1])
    turn_on = np.random.default_rng([run_seed, 2]) if run_seed is not None else None

    def bias(sigma: float, sigma_turn_on: float, factor: float) -> np.ndarray:
        b = unit.normal(0.0, sigma, 3)
        if turn_on is not None:
            b = b + turn_on.normal(0.0, sigma_turn_on, 3)
        return b * factor

    def matrix(scale: float, misalignment: float) -> np.ndarray:
        m = unit.normal(0.0, misalignment, (3, 3))
        m[np.diag_indices(3)] = unit.normal(0.0, scale, 3)
        return m * imu.PPM

    return imu.ImuModel(
        (
            imu.Bias("gyro", bias(g.gyro_bias_dph, g.gyro_turn_on_dph, DEG_PER_H)),
            imu.Bias("accel", bias(g.accel_bias_mg, g.accel_turn_on_mg, imu.MG)),
            imu.ScaleMisalignment("gyro", matrix(g.gyro_scale_ppm, g.gyro_misalignment_ppm)),
            imu.ScaleMisalignment("accel", matrix(g.accel_scale_ppm, g.accel_misalignment_ppm)),
            imu.GSensitivity("gyro", unit.normal(0.0, g.g_sensitivity_dph_per_g, (3, 3)) * DEG_PER_H / G0),
            imu.Noise("gyro", np.full(3, g.arw_deg_per_rt_h * DEG / 60.0)),
            imu.Noise("accel", np.full(3, g.vrw_ug_per_rt_hz * imu.UG)),
            imu.BiasInstability(
                "gyro", np.full(3, g.gyro_instability_dph * DEG_PER_H), np.full(3, g.instability_tau_s)
            ),
            imu.BiasInstability(
                "accel", np.full(3, g.accel_instability_ug * imu.UG), np.full(3, g.instability_tau_s)
            ),
        )
    )


def _signs(rng: np.random.Generator, shape: tuple[int, ...] = (3,)) -> Any:
    """Magnitudes between 0.5 and 1 of the typical one, random signs: every axis has the effect."""
    return rng.uniform(0.5, 1.0, shape) * rng.choice([-1.0, 1.0], shape)


def typical_effect(name: str, rng: np.random.Generator, scale: float = 1.0) -> imu.Effect:
    """One effect beyond the baseline at a size typical of a tactical unit, times ``scale``.

    The sizes are those a 20-minute 24-position + rate-table session at 100 Hz resolves from a
    tactical unit's noise: what the sim-to-real benchmark injects and withholds.
    """
    s = scale
    dps, dph, mg = np.radians(1.0), imu.DEG_PER_H, imu.MG
    sensor, kind = name.split(".")
    table: dict[str, imu.Effect] = {
        "gyro.scale_nonlinearity": imu.ScaleNonlinearity("gyro", s * 1e-6 / dps * _signs(rng)),
        "accel.scale_nonlinearity": imu.ScaleNonlinearity("accel", s * 100e-6 / G0 * _signs(rng)),
        "gyro.scale_asymmetry": imu.ScaleAsymmetry("gyro", s * 300e-6 * _signs(rng)),
        "accel.scale_asymmetry": imu.ScaleAsymmetry("accel", s * 300e-6 * _signs(rng)),
        "gyro.g2_sensitivity": imu.G2Sensitivity("gyro", s * 3.0 * dph / G0**2 * _signs(rng, (3, 3, 3))),
        "gyro.temperature_bias": imu.TemperatureBias("gyro", c1=s * 0.5 * dph * _signs(rng)),
        "accel.temperature_bias": imu.TemperatureBias("accel", c1=s * 0.02 * mg * _signs(rng)),
        "gyro.temperature_scale": imu.TemperatureScale("gyro", s1=s * 10e-6 * _signs(rng)),
        "accel.temperature_scale": imu.TemperatureScale("accel", s1=s * 10e-6 * _signs(rng)),
        "gyro.time_offset": imu.TimeOffset("gyro", delay=np.full(3, s * 1e-3)),
        "accel.time_offset": imu.TimeOffset("accel", delay=np.full(3, s * 1e-3)),
        "gyro.quantization": imu.Quantization("gyro", step=np.full(3, s * 0.05 * dps)),
        "accel.quantization": imu.Quantization("accel", step=np.full(3, s * 2.0 * mg)),
        "gyro.saturation": imu.Saturation("gyro", limit=np.full(3, 150.0 * dps / s)),
        "accel.saturation": imu.Saturation("accel", limit=np.full(3, 0.95 * G0 / s)),
        "accel.size_effect": imu.SizeEffect("accel", s * 2e-3 * _signs(rng, (3, 3))),
        "gyro.bias_instability": imu.BiasInstability(
            "gyro", sigma=np.full(3, s * 5.0 * dph), tau=np.full(3, 100.0)
        ),
        "accel.bias_instability": imu.BiasInstability(
            "accel", sigma=np.full(3, s * 0.1 * mg), tau=np.full(3, 100.0)
        ),
        "gyro.rate_random_walk": imu.RateRandomWalk("gyro", density=np.full(3, s * 20.0 * dph / 60.0)),
        "accel.rate_random_walk": imu.RateRandomWalk("accel", density=np.full(3, s * 50e-6 * G0)),
    }
    if name not in table:
        raise ValueError(f"no typical size for {name!r} (sensor {sensor}, effect {kind})")
    return table[name]


__all__ = [
    "DEG",
    "DEG_PER_H",
    "GRADES",
    "PARAMETERS",
    "EffectSpec",
    "Grade",
    "Param",
    "draw_unit",
    "effect_from_params",
    "typical_effect",
]
