"""The effect vocabulary's registry: what an effect declares, and the one list of the library's effects.

An effect is a class (:class:`Effect`) that declares, beside its error, everything the rest of sins
derives from it: its file parameters with their units and ranges (:class:`Param`, read by
:mod:`sins.imu.spec`), its regression columns (:meth:`Effect.columns`), the kind of candidate the gap
diagnosis makes of it (:attr:`Effect.candidate`, read by :mod:`sins.gap.candidates`), the physics term
group the learned strategies may take it in (:attr:`Effect.term`, read by
:mod:`sins.compensation.terms`) and its typical size (:meth:`Effect.typical`).
:func:`register` adds a class to the vocabulary; the library's effects (:mod:`sins.imu.effects`) are
registered as they are defined, and a user's effect is registered the same way, with no edit of sins:
it is then simulated, read from IMU files, listed by ``sins effects``, offered by the gap diagnosis
and by the term groups.

Channels are ``gyro.x`` … ``accel.z``; an effect is named ``SENSOR.KIND`` (``gyro.bias``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar, Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

from sins.core.earth import G0

Array = NDArray[np.float64]

SENSORS = ("gyro", "accel")
CHANNELS = ("gyro.x", "gyro.y", "gyro.z", "accel.x", "accel.y", "accel.z")

DEG = np.pi / 180.0
DEG_PER_H = DEG / 3600.0
PPM = 1e-6
MG = 1e-3 * G0
UG = 1e-6 * G0


def display_unit(channel: str) -> tuple[float, str]:
    """The SI size of one display unit of a channel, and its symbol: °/h for gyros, mg for accelerometers."""
    return (DEG_PER_H, "°/h") if channel.startswith("gyro") else (MG, "mg")


@dataclass(frozen=True)
class TrueInputs:
    """True inputs of the IMU at ``n`` times.

    Attributes
    ----------
    omega_ib_b : (n, 3) angular rate, rad/s
    f_ib_b : (n, 3) specific force, m/s²
    omega_dot_b : (n, 3) angular acceleration ``d(omega_ib_b)/dt``, rad/s² (for the size effect)
    temp : (n,) temperature, °C, or None
    """

    omega_ib_b: Array
    f_ib_b: Array
    omega_dot_b: Array
    temp: Array | None = None

    def of(self, sensor: str) -> Array:
        """The input ``sensor`` measures: ``omega_ib_b`` for "gyro", ``f_ib_b`` for "accel"."""
        return self.omega_ib_b if sensor == "gyro" else self.f_ib_b


class RegressorInputs(Protocol):
    """What an effect's regression columns are built from (:meth:`Effect.columns`): the inputs of ``n``
    rows in the caller's scales. ``temp_offset`` is the temperature from the caller's origin (None
    without a temperature); ``omega_dot_b`` the angular acceleration (asked only by the size effect)."""

    @property
    def omega_ib_b(self) -> Array:
        """(n, 3) angular rate."""

    @property
    def f_ib_b(self) -> Array:
        """(n, 3) specific force."""

    @property
    def temp_offset(self) -> Array | None:
        """(n,) temperature from the caller's origin, or None."""

    @property
    def omega_dot_b(self) -> Array:
        """(n, 3) angular acceleration."""

    def of(self, sensor: str) -> Array:
        """``omega_ib_b`` for "gyro", ``f_ib_b`` for "accel"."""


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


def vector_param(key: str, field: str, factor: float, unit: str, low: float = -1e6, high: float = 1e6,
                 low_open: bool = False) -> Param:  # fmt: skip
    """A :class:`Param` of three values, one per axis (a scalar in a file stands for all three)."""
    return Param(key, field, factor, (3,), unit, low, high, low_open)


@dataclass(frozen=True)
class Term:
    """The physics term group an effect's columns join in the learned strategies
    (:mod:`sins.compensation.terms`): the group's name, as strategy files store it, and its
    rank, the place of its columns in a channel's design (files store the coefficients in that
    order, so a group's rank never changes)."""

    group: str
    rank: int


def parameter_field(shape: tuple[int, ...] = (3,), fill: float = 0.0, check: str = "") -> Any:
    """A dataclass field of an effect parameter of ``shape`` (a scalar broadcasts to (3,)), checked when the
    effect is made; ``check``: "", "positive", "nonneg"."""
    return field(default_factory=lambda: np.full(shape, fill), metadata={"shape": shape, "check": check})


def _as_parameter(x: Any, name: str, shape: tuple[int, ...], check: str) -> Array:
    # A copy, read-only: the caller's array had stayed the frozen effect's own, so a value changed after
    # the check (b[0] = nan) changed the model.
    a = np.array(x, dtype=float)
    if shape == (3,) and a.shape == ():
        a = np.full(3, float(a))
    if a.shape != shape or np.isnan(a).any() or (check != "positive" and not np.isfinite(a).all()):
        raise ValueError(
            f"{name}: expected a finite {'x'.join(map(str, shape))} array, got {np.asarray(x).tolist()!r}"
        )
    if check == "positive" and (a <= 0).any():
        raise ValueError(f"{name}: must be positive")
    if check == "nonneg" and (a < 0).any():
        raise ValueError(f"{name}: must be non-negative")
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class Effect:
    """Base of all effects: ``sensor`` is "gyro" or "accel"; ``kind`` names the effect.

    A subclass declares, as class attributes: ``kind``; the ``sensors`` it may sit on; its ``stage``
    (delay | deterministic | stochastic | noise | clip | quantize, the order a reading is formed in,
    :mod:`sins.imu.model`); ``params`` and ``description`` per sensor (its file parameters and one
    line for ``sins effects``); ``candidate``, the gap diagnosis's kind of candidate ("regressors",
    "delay", "process", "output", or None: not diagnosed); ``term``, its physics term group (or
    None); ``needs_temp``, whether its error needs the temperature. A deterministic effect defines
    :meth:`error`, a "regressors" candidate or a term :meth:`columns`.
    """

    sensor: str
    kind: ClassVar[str] = ""
    sensors: ClassVar[tuple[str, ...]] = SENSORS
    stage: ClassVar[str] = "deterministic"
    params: ClassVar[dict[str, tuple[Param, ...]]] = {}
    description: ClassVar[dict[str, str]] = {}
    candidate: ClassVar[str | None] = None
    term: ClassVar[Term | None] = None
    needs_temp: ClassVar[bool] = False
    #: Whether the error is affine in the true inputs, ``b + M u + K f`` (:meth:`affine_terms`): its
    #: integral over an interval is then ``b Δt + M Δu + K Δv`` of the interval's ideal increments,
    #: exactly, and the increment form needs no rate reconstructed at Gauss nodes for it.
    affine: ClassVar[bool] = False

    def __post_init__(self) -> None:
        if self.sensor not in self.sensors:
            raise ValueError(
                f"{self.kind}: sensor must be one of {', '.join(self.sensors)}, got {self.sensor!r}"
            )
        for f in fields(self):
            if "shape" in f.metadata:
                value = _as_parameter(getattr(self, f.name), f"{self.name}.{f.name}", f.metadata["shape"],
                                      f.metadata["check"])  # fmt: skip
                object.__setattr__(self, f.name, value)

    @property
    def name(self) -> str:
        """The effect's name, ``SENSOR.EFFECT`` (``gyro.bias``)."""
        return f"{self.sensor}.{self.kind}"

    def error(self, inputs: TrueInputs, u: Array) -> Array:
        """Additive error (n, 3) given the inputs and this sensor's (possibly delayed) input ``u``."""
        raise NotImplementedError

    def affine_terms(self) -> tuple[Array, Array, Array]:
        """An affine effect's ``b`` (3,), ``M`` (3, 3) on the sensor's own input and ``K`` (3, 3) on the
        specific force, its error being ``b + M u + K f``."""
        raise NotImplementedError(f"{self.name} is not affine in the inputs")

    def process(self, t: Array, rng: np.random.Generator) -> Array:
        """A stochastic effect's random bias at times ``t`` (n, 3), drawn from ``rng``."""
        raise NotImplementedError(f"{self.name} is not a random bias")

    @classmethod
    def columns(cls, x: RegressorInputs, sensor: str, axis: int) -> Array:
        """The regressors (n, k) of channel ``sensor``.``axis`` whose coefficients are this effect's
        (up to the scales of ``x``): what the gap diagnosis and the physics terms fit."""
        raise NotImplementedError(f"{cls.kind} has no regression columns")

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """The effect on ``sensor`` at a size typical of a tactical unit times ``scale`` (None: no
        typical size), drawing what it needs from ``rng`` (:func:`sins.imu.spec.typical_effect`)."""
        return None


_REGISTRY: dict[str, type[Effect]] = {}
_E = TypeVar("_E", bound=type[Effect])


def register(cls: _E) -> _E:
    """Add the effect class ``cls`` to the vocabulary (a class decorator; returns ``cls``).

    Raises ``ValueError`` if its kind is taken by another class or it lacks a sensor's parameters.
    """
    if not cls.kind or (cls.kind in _REGISTRY and _REGISTRY[cls.kind] is not cls):
        raise ValueError(f"effect kind {cls.kind!r} is empty or already registered")
    missing = [s for s in cls.sensors if s not in cls.params or s not in cls.description]
    if missing:
        raise ValueError(f"{cls.kind}: no parameters or description for {', '.join(missing)}")
    _REGISTRY[cls.kind] = cls
    return cls


def unregister(kind: str) -> None:
    """Take the effect ``kind`` out of the vocabulary (a test's own effect, once it is done)."""
    _REGISTRY.pop(kind, None)


def effect_types() -> tuple[type[Effect], ...]:
    """Every registered effect class, in the order registered."""
    return tuple(_REGISTRY.values())


def effect_names() -> tuple[str, ...]:
    """Every effect name of the vocabulary, ``SENSOR.KIND``, in the order registered."""
    return tuple(f"{s}.{t.kind}" for t in _REGISTRY.values() for s in t.sensors)


def effect_class(name: str) -> type[Effect]:
    """The class of the effect named ``name`` (``gyro.bias``); ``ValueError`` for an unknown name."""
    sensor, _, kind = name.partition(".")
    cls = _REGISTRY.get(kind)
    if cls is None or sensor not in cls.sensors:
        raise ValueError(f"unknown effect {name!r} (see `sins effects`)")
    return cls


def check_names(names: tuple[str, ...] | list[str]) -> None:
    """``ValueError`` naming the first of ``names`` that is not an effect of the vocabulary."""
    for n in names:
        effect_class(n)


def effects_where(test: Callable[[type[Effect]], bool]) -> list[tuple[str, type[Effect]]]:
    """``(name, class)`` of every registered effect whose class passes ``test``, in registry order."""
    return [(f"{s}.{t.kind}", t) for t in _REGISTRY.values() if test(t) for s in t.sensors]


__all__ = [
    "CHANNELS",
    "DEG",
    "DEG_PER_H",
    "MG",
    "PPM",
    "SENSORS",
    "UG",
    "Effect",
    "Param",
    "RegressorInputs",
    "Term",
    "TrueInputs",
    "check_names",
    "display_unit",
    "effect_class",
    "effect_names",
    "effect_types",
    "effects_where",
    "parameter_field",
    "register",
    "unregister",
    "vector_param",
]
