"""A set of named effects and what is asked of it: the effects on a sensor, their deterministic error
at given inputs, the random biases, the output maps. :class:`sins.imu.model.ImuModel` is such a set that
also corrupts readings; the increment stream (:mod:`sins.imu.stream`) works on the set alone."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Self

import numpy as np
from numpy.typing import NDArray

from sins.imu.effects import Quantization, Saturation, TimeOffset
from sins.imu.numerics import cubic_hermite, hermite_slopes, random_stream
from sins.imu.vocabulary import Effect, TrueInputs, check_names

Array = NDArray[np.float64]


@dataclass(frozen=True)
class EffectSet:
    """A set of named effects; at most one of each name."""

    effects: tuple[Effect, ...] = ()

    def __post_init__(self) -> None:
        names = [e.name for e in self.effects]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"effect given twice: {', '.join(sorted(dup))}")

    @property
    def names(self) -> tuple[str, ...]:
        """The effects' names, in model order."""
        return tuple(e.name for e in self.effects)

    def get(self, name: str) -> Effect | None:
        """The effect named ``name``, or None if the model lacks it."""
        return next((e for e in self.effects if e.name == name), None)

    def without(self, *names: str) -> Self:
        """The model with the named effects withheld (unknown names are an error)."""
        check_names(names)
        return type(self)(tuple(e for e in self.effects if e.name not in names))

    def only(self, *names: str) -> Self:
        """The model with just the named effects."""
        check_names(names)
        return type(self)(tuple(e for e in self.effects if e.name in names))

    def with_effects(self, *effects: Effect) -> Self:
        """The model with ``effects`` added, replacing any of the same name."""
        new = {e.name for e in effects}
        return type(self)(tuple(e for e in self.effects if e.name not in new) + tuple(effects))

    def effects_of(self, sensor: str) -> list[Effect]:
        """The effects on ``sensor`` (gyro or accel), in model order."""
        return [e for e in self.effects if e.sensor == sensor]

    def effect_of(self, sensor: str, kind: type[Any]) -> Any:
        """The effect of type ``kind`` on ``sensor``, or None."""
        return next((e for e in self.effects_of(sensor) if isinstance(e, kind)), None)

    def delay_of(self, sensor: str) -> Array:
        """The sensor's delay per axis, s (zeros without a time offset)."""
        off = self.effect_of(sensor, TimeOffset)
        return np.zeros(3) if off is None else off.delay

    def deterministic_error(
        self, sensor: str, inputs: TrueInputs, effects: Sequence[Effect] | None = None
    ) -> Array:
        """The sum of the sensor's deterministic errors (n, 3) at these true inputs (no delay, no noise);
        ``effects``: only those of them (default: all)."""
        u = inputs.of(sensor)
        err = np.zeros_like(u)
        for e in self.effects_of(sensor) if effects is None else effects:
            if e.stage == "deterministic":
                np.add(err, e.error(inputs, u), out=err)  # in place: the same sums, no new array each
        return err

    def stochastic(self, sensor: str, t: Array, seed: int | None) -> Array:
        """The sum of the sensor's random biases (n, 3) at times ``t``, drawn from the run's ``seed``."""
        total = np.zeros((len(t), 3))
        for e in self.effects_of(sensor):
            if e.stage == "stochastic":
                total += e.process(t, random_stream(seed, e.name))
        return total

    def clip_and_round(self, sensor: str, y: Array, scale: float) -> Array:
        """Readings ``y`` clipped at the saturation limit and rounded to the quantization step times
        ``scale`` (1 for rates, the step for increments)."""
        sat = self.effect_of(sensor, Saturation)
        if sat is not None:
            y = np.clip(y, -sat.limit, sat.limit)
        q = self.effect_of(sensor, Quantization)
        if q is not None and (q.step > 0).any():
            step = np.where(q.step > 0, q.step * scale, 1.0)
            y = np.where(q.step > 0, np.round(y / step) * step, y)
        return y


def check_temp(temp: Array | None, t: Array) -> Array | None:
    """``temp`` as floats, checked to have one finite value per time of ``t`` (None stays None)."""
    if temp is None:
        return None
    temp = np.asarray(temp, dtype=float)
    if temp.shape != t.shape:
        raise ValueError(f"temp must have one value per sample time, shape {t.shape}, got {temp.shape}")
    if not np.isfinite(temp).all():
        raise ValueError("temp must be finite")
    return temp


def shift_samples(inputs: TrueInputs, t: Array, delay: float) -> TrueInputs:
    """Inputs delayed by ``delay`` s (cubic Hermite between samples, held at the ends)."""

    def at(y: Array) -> Array:
        out, into = hermite_slopes(t, y, np.gradient(y, t, axis=0))
        return cubic_hermite(t, y, out, np.clip(t - delay, t[0], t[-1]), into)

    temp = None if inputs.temp is None else np.interp(t - delay, t, inputs.temp)
    return TrueInputs(
        omega_ib_b=at(inputs.omega_ib_b),
        f_ib_b=at(inputs.f_ib_b),
        omega_dot_b=at(inputs.omega_dot_b),
        temp=temp,
    )


__all__ = [
    "EffectSet",
    "check_temp",
    "shift_samples",
]
