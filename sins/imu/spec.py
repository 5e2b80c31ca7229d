"""IMU specifications: effects in familiar units, and grade presets that draw individual units.

Files name an effect and give its parameters in the units engineers use
(°/h, mg, ppm, °/√h, µg/√Hz, °/h/g, …); each effect class declares its own
(:attr:`sins.imu.Effect.params`), and :func:`parameters` gathers them: the table that
converts them to the SI fields of the effect classes (``SI = value × factor``).
A grade (consumer MEMS, industrial, tactical, navigation) gives the spread of each coefficient;
:func:`draw_unit` draws one unit's deterministic coefficients from its ``unit_seed`` and its turn-on bias
from a ``run_seed``, so the same unit can be powered on many times.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sins import imu
from sins.core.earth import G0
from sins.imu.vocabulary import Param

DEG = imu.DEG
DEG_PER_H = imu.DEG_PER_H


@dataclass(frozen=True)
class EffectSpec:
    """An effect's class, one-line description and file parameters (as its class declares them)."""

    cls: type[imu.Effect]
    description: str
    params: tuple[Param, ...]


def parameters() -> dict[str, EffectSpec]:
    """Effect name → its spec, for every effect of the vocabulary (:func:`sins.imu.effect_names`, in
    that order): read from the effect classes when called, so an effect registered later is in it."""
    return {
        f"{s}.{cls.kind}": EffectSpec(cls, cls.description[s], cls.params[s])
        for cls in imu.effect_types()
        for s in cls.sensors
    }


def effect_from_params(name: str, params: dict[str, Any]) -> imu.Effect:
    """Build an effect from file parameters (familiar units); missing parameters are zero.

    Raises ``ValueError`` naming the effect and parameter for an unknown key, a wrong shape, a
    non-finite value or one outside the parameter's range (:class:`sins.imu.vocabulary.Param`), and
    naming the effect where none of its parameters is given (it would change nothing: a table cut short).
    """
    cls = imu.effect_class(name)
    sensor = name.split(".")[0]
    known = {p.key: p for p in cls.params[sensor]}
    if known and not params:
        listed = ", ".join(known)
        raise ValueError(f"{name}: no parameter given, so it would change nothing (parameters: {listed})")
    for key in params:
        if key not in known:
            raise ValueError(f"{name}: unknown parameter {key!r} (parameters: {', '.join(known)})")
    kwargs: dict[str, Any] = {}
    for key, value in params.items():
        p = known[key]
        if not _numbers(value):  # TOML's strings and booleans: float() would read "1e3" and true
            raise ValueError(f"{name}.{key}: expected a number or a list of numbers, got {repr(value)[:60]}")
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
    return cls(sensor, **kwargs)


def _numbers(value: Any) -> bool:
    """Whether ``value`` is a number (not a boolean) or a list, nested, of them."""
    if isinstance(value, list | tuple):
        return all(_numbers(v) for v in value)
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool)


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
    if isinstance(grade, str) and grade not in GRADES:
        raise ValueError(f"unknown grade {grade!r} (known: {', '.join(GRADES)})")
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


def typical_effect(name: str, rng: np.random.Generator, scale: float = 1.0) -> imu.Effect:
    """One effect beyond the baseline at a size typical of a tactical unit, times ``scale``
    (:meth:`sins.imu.Effect.typical` of its class).

    The sizes are those a 20-minute 24-position + rate-table session at 100 Hz resolves from a
    tactical unit's noise: what the sim-to-real benchmark injects and withholds. Every effect with a
    typical size draws from ``rng`` in the vocabulary's order and the one named is returned, so its
    draw does not depend on which effect is asked for.
    """
    drawn = {}
    for cls in imu.effect_types():
        for sensor in cls.sensors:
            effect = cls.typical(sensor, rng, scale)
            if effect is not None:
                drawn[effect.name] = effect
    if name not in drawn:
        sensor, _, kind = name.partition(".")
        raise ValueError(f"no typical size for {name!r} (sensor {sensor}, effect {kind})")
    return drawn[name]


__all__ = [
    "DEG",
    "DEG_PER_H",
    "GRADES",
    "EffectSpec",
    "Grade",
    "draw_unit",
    "effect_from_params",
    "parameters",
    "typical_effect",
]
