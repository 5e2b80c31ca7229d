"""The IMU error model: a library of named effects, composed into a model, applied to either IMU form.

Channels are ``gyro.x`` … ``gyro.z`` and ``accel.x`` … ``accel.z``; an effect is
``SENSOR.EFFECT`` (``gyro.bias``, ``accel.scale_nonlinearity``, …). Parameters
are SI inside (rad/s, m/s², rad/√s, …); :func:`sins.imu.spec.parameters` maps them to the
familiar units of scenario files (°/h, mg, ppm, °/√h, µg/√Hz, °/h/g).

How a sensor's output is formed from its true input ``u`` (the vector
``omega_ib_b`` for the gyros, ``f_ib_b`` for the accelerometers), always in
this order, whatever the order of effects in a model:

1. ``time_offset``: each channel sees the input at ``t - τ``;
2. deterministic errors, added: ``bias``, ``scale_misalignment`` (``M u``),
   ``g_sensitivity`` (``K f``), ``scale_nonlinearity`` (``k2 u²``),
   ``scale_asymmetry`` (``ka |u|``), ``g2_sensitivity`` (``Σ G2 f f``),
   ``temperature_bias``, ``temperature_scale``, ``size_effect``;
3. stochastic biases, added: ``bias_instability`` (Gauss–Markov),
   ``rate_random_walk``;
4. white ``noise``, and ``quantization_noise`` (white noise of the integrated output: the increment
   of interval ``k`` gains ``e_k − e_{k−1}``, the IEEE quantization term; see
   :class:`QuantizationNoise`);
5. ``saturation``: clipped at ``± limit``;
6. ``quantization``: rounded to the step (increments carry the remainder to
   the next sample, as integrating IMUs do, so the error does not accumulate).

Rate form: the inputs are instantaneous samples; white noise has standard
deviation ``density / sqrt(dt)``. Increment form: the output is the integral
of the corrupted rate over each interval. The rate inside an interval is
reconstructed from the neighbouring increments (a quadratic matching the three
interval means, exact for inputs quadratic in time; linear and one-sided in
the first and last interval) and the error is integrated at the interval's two
Gauss nodes, so linear effects are exact and nonlinear ones are integrated to
O(dt⁴); white noise adds ``density·sqrt(dt)`` per increment. A time offset
delays everything about the measurement, its temperature included.
Stochastic effects draw from a stream keyed by the seed and the effect's name
only, so adding or withholding one effect leaves the others' draws unchanged;
``seed=None`` means seed 0 (runs are reproducible unless a seed is given).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sins.core.series import ImuIncrements, ImuRates, check_increasing
from sins.imu.effect_set import EffectSet, check_temp, shift_samples
from sins.imu.effects import Noise, QuantizationNoise
from sins.imu.numerics import random_stream
from sins.imu.stream import IncrementStream
from sins.imu.vocabulary import SENSORS, TrueInputs

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ImuModel(EffectSet):
    """A set of named effects (at most one of each name) that corrupts ideal readings, in rate or
    increment form."""

    # ----------------------------------------------------------------- rate form

    def corrupt_rates(self, rates: ImuRates, temp: Array | None = None, seed: int | None = None) -> ImuRates:
        """Readings of the modelled IMU at the sample times of ideal ``rates``.

        Parameters
        ----------
        rates : true ``omega_ib_b`` and ``f_ib_b`` at ``n`` times
        temp : (n,) temperature, °C (needed by temperature effects)
        seed : the run's seed for stochastic effects

        Returns
        -------
        ImuRates with the readings
        """
        t = rates.t
        check_increasing(t, "corrupt_rates")
        temp = check_temp(temp, t)  # as corrupt_increments: one of length 1 had been broadcast to all
        omega_dot = (
            np.gradient(rates.omega_ib_b, t, axis=0) if len(t) > 1 else np.zeros_like(rates.omega_ib_b)
        )
        inputs = TrueInputs(
            omega_ib_b=rates.omega_ib_b, f_ib_b=rates.f_ib_b, omega_dot_b=omega_dot, temp=temp
        )
        dt = np.diff(t)
        out = []
        for sensor in SENSORS:
            delay = self.delay_of(sensor)
            y = np.empty_like(inputs.of(sensor))
            for d in np.unique(delay):
                shifted = shift_samples(inputs, t, d) if d else inputs
                y_d = shifted.of(sensor) + self.deterministic_error(sensor, shifted)
                y[:, delay == d] = y_d[:, delay == d]
            y = y + self.stochastic(sensor, t, seed)
            noise = self.effect_of(sensor, Noise)
            if noise is not None and len(t) > 1:
                step = np.median(dt)
                y = y + noise.density / np.sqrt(step) * random_stream(seed, noise.name).standard_normal(
                    y.shape
                )
            qnoise = self.effect_of(sensor, QuantizationNoise)
            if qnoise is not None and len(t) > 1:
                e = qnoise.angle_errors(random_stream(seed, qnoise.name), len(t) + 1)
                y = y + np.diff(e, axis=0) / np.median(dt)
            y = self.clip_and_round(sensor, y, scale=1.0)
            out.append(y)
        return ImuRates(t=t, omega_ib_b=out[0], f_ib_b=out[1])

    # ----------------------------------------------------------------- increment form

    def corrupt_increments(
        self,
        imu: ImuIncrements,
        temp: Array | None = None,
        seed: int | None = None,
        dt_nominal: float | None = None,
    ) -> ImuIncrements:
        """Readings of the modelled IMU as increments: integrals of the corrupted rate.

        One :class:`sins.imu.stream.IncrementStream` fed the whole array; feed one chunk by chunk
        for long runs (the readings are the same to the last bit).

        Parameters
        ----------
        imu : ideal increments over ``n`` intervals (``imu.t`` has ``n + 1`` times)
        temp : (n+1,) temperature at ``imu.t``, °C (needed by temperature effects)
        seed : the run's seed for stochastic effects
        dt_nominal : the sampling step, s (default: the median step)
        """
        t = imu.t
        if len(t) < 2:
            return imu
        check_increasing(t, "corrupt_increments")
        temp = check_temp(temp, t)
        step = float(np.median(np.diff(t))) if dt_nominal is None else dt_nominal
        stream = IncrementStream(self, seed, step)
        head, tail = stream.push(imu, temp), stream.finish()
        return ImuIncrements(
            t=np.concatenate([head.t, tail.t[1:]]) if len(head.t) else tail.t,
            dtheta_b=np.vstack([head.dtheta_b, tail.dtheta_b]),
            dv_b=np.vstack([head.dv_b, tail.dv_b]),
        )


__all__ = [
    "ImuModel",
]
