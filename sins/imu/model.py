"""The IMU error model: a library of named effects, composed into a model, applied to either IMU form.

Channels are ``gyro.x`` … ``gyro.z`` and ``accel.x`` … ``accel.z``; an effect is
``SENSOR.EFFECT`` (``gyro.bias``, ``accel.scale_nonlinearity``, …). Parameters
are SI inside (rad/s, m/s², rad/√s, …); :data:`PARAMETERS` maps them to the
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
4. white ``noise``;
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

import zlib
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from sins.nav.earth import G0
from sins.series import ImuIncrements, ImuRates

Array = NDArray[np.float64]

SENSORS = ("gyro", "accel")
CHANNELS = ("gyro.x", "gyro.y", "gyro.z", "accel.x", "accel.y", "accel.z")

DEG = np.pi / 180.0
DEG_PER_H = DEG / 3600.0
PPM = 1e-6
MG = 1e-3 * G0


def display_unit(channel: str) -> tuple[float, str]:
    """The SI size of one display unit of a channel, and its symbol: °/h for gyros, mg for accelerometers."""
    return (DEG_PER_H, "°/h") if channel.startswith("gyro") else (MG, "mg")


UG = 1e-6 * G0


# --------------------------------------------------------------------------- inputs


@dataclass(frozen=True)
class Inputs:
    """True inputs of the IMU at ``n`` times.

    Attributes
    ----------
    omega : (n, 3) angular rate ``omega_ib_b``, rad/s
    f : (n, 3) specific force ``f_ib_b``, m/s²
    omega_dot : (n, 3) angular acceleration, rad/s² (for the size effect)
    temp : (n,) temperature, °C, or None
    """

    omega: Array
    f: Array
    omega_dot: Array
    temp: Array | None = None

    def of(self, sensor: str) -> Array:
        """The input ``sensor`` measures: ``omega`` for "gyro", ``f`` for "accel"."""
        return self.omega if sensor == "gyro" else self.f


# --------------------------------------------------------------------------- effects


def _array(shape: tuple[int, ...] = (3,), fill: float = 0.0, check: str = "") -> Any:
    """A parameter field of ``shape`` (a scalar broadcasts to (3,)); ``check``: "", "positive", "nonneg"."""
    return field(default_factory=lambda: np.full(shape, fill), metadata={"shape": shape, "check": check})


def _as_parameter(x: Any, name: str, shape: tuple[int, ...], check: str) -> Array:
    a = np.asarray(x, dtype=float)
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
    return a


@dataclass(frozen=True)
class Effect:
    """Base of all effects: ``sensor`` is "gyro" or "accel"; ``kind`` names the effect."""

    sensor: str
    kind: ClassVar[str] = ""
    sensors: ClassVar[tuple[str, ...]] = SENSORS
    stage: ClassVar[str] = "deterministic"  # delay | deterministic | stochastic | noise | clip | quantize

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

    def error(self, inputs: Inputs, u: Array) -> Array:
        """Additive error (n, 3) given the inputs and this sensor's (possibly delayed) input ``u``."""
        raise NotImplementedError


@dataclass(frozen=True)
class Bias(Effect):
    """Constant bias ``b`` (rad/s or m/s²); the turn-on part is drawn per run by the grade."""

    value: Array = _array()
    kind: ClassVar[str] = "bias"

    def error(self, inputs: Inputs, u: Array) -> Array:
        """The bias ``b`` at every sample."""
        return np.broadcast_to(self.value, u.shape)


@dataclass(frozen=True)
class ScaleMisalignment(Effect):
    """``M u``: diagonal scale-factor errors, off-diagonal misalignment (the seed's ``B`` and ``A``)."""

    matrix: Array = _array((3, 3))
    kind: ClassVar[str] = "scale_misalignment"

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``M u``."""
        return u @ self.matrix.T


@dataclass(frozen=True)
class GSensitivity(Effect):
    """Gyro drift ``K f`` proportional to specific force (the seed's ``K``), rad/s per m/s²."""

    matrix: Array = _array((3, 3))
    kind: ClassVar[str] = "g_sensitivity"
    sensors: ClassVar[tuple[str, ...]] = ("gyro",)

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``K f`` from the specific force ``f_ib_b``."""
        return inputs.f @ self.matrix.T


@dataclass(frozen=True)
class ScaleNonlinearity(Effect):
    """``k2 u_i²`` on each channel's own axis; ``k2`` in 1/(rad/s) or 1/(m/s²)."""

    k2: Array = _array()
    kind: ClassVar[str] = "scale_nonlinearity"

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``k2 u_i²`` on each axis."""
        return self.k2 * u * u


@dataclass(frozen=True)
class ScaleAsymmetry(Effect):
    """``ka |u_i|``: different scale factors for positive and negative inputs (dimensionless)."""

    ka: Array = _array()
    kind: ClassVar[str] = "scale_asymmetry"

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``ka |u_i|`` on each axis."""
        return self.ka * np.abs(u)


@dataclass(frozen=True)
class G2Sensitivity(Effect):
    """Anisoelastic gyro drift ``Σ_jk G2[i, j, k] f_j f_k``, rad/s per (m/s²)²."""

    tensor: Array = _array((3, 3, 3))
    kind: ClassVar[str] = "g2_sensitivity"
    sensors: ClassVar[tuple[str, ...]] = ("gyro",)

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``Σ_jk G2[i, j, k] f_j f_k`` from the specific force ``f_ib_b``."""
        f = inputs.f
        return np.einsum("ijk,nj,nk->ni", self.tensor, f, f)


@dataclass(frozen=True)
class TemperatureBias(Effect):
    """``c1 (T - T0) + c2 (T - T0)²``; ``c1`` per °C, ``c2`` per °C², in the sensor's SI unit."""

    c1: Array = _array()
    c2: Array = _array()
    t0: float = 20.0
    kind: ClassVar[str] = "temperature_bias"

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``c1 (T - T0) + c2 (T - T0)²``; needs the temperature series."""
        if inputs.temp is None:
            raise ValueError(f"{self.name} needs a temperature series")
        d = (inputs.temp - self.t0)[:, None]
        return self.c1 * d + self.c2 * d * d


@dataclass(frozen=True)
class TemperatureScale(Effect):
    """``s1 (T - T0) u_i``: scale factor drifting with temperature, per °C."""

    s1: Array = _array()
    t0: float = 20.0
    kind: ClassVar[str] = "temperature_scale"

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``s1 (T - T0) u_i``; needs the temperature series."""
        if inputs.temp is None:
            raise ValueError(f"{self.name} needs a temperature series")
        return self.s1 * (inputs.temp - self.t0)[:, None] * u


@dataclass(frozen=True)
class SizeEffect(Effect):
    """Accelerometer ``i`` sits at lever arm ``r_i`` (row ``i``, m) from the reference point:
    ``e_iᵀ (ω̇ × r_i + ω × (ω × r_i))``."""

    lever_arms: Array = _array((3, 3))
    kind: ClassVar[str] = "size_effect"
    sensors: ClassVar[tuple[str, ...]] = ("accel",)

    def error(self, inputs: Inputs, u: Array) -> Array:
        """Accelerometer ``i``'s own axis of ``ω̇ × r_i + ω × (ω × r_i)``."""
        w, wd = inputs.omega, inputs.omega_dot
        out = np.empty_like(w)
        for i in range(3):
            r = self.lever_arms[i]
            out[:, i] = (np.cross(wd, r) + np.cross(w, np.cross(w, r)))[:, i]
        return out


@dataclass(frozen=True)
class TimeOffset(Effect):
    """The channel reports its input ``delay`` seconds late (``u(t - delay)``)."""

    delay: Array = _array()
    kind: ClassVar[str] = "time_offset"
    stage: ClassVar[str] = "delay"


@dataclass(frozen=True)
class Noise(Effect):
    """White noise of density ``density``: rad/√s (angle random walk) or m/s/√s (velocity random walk)."""

    density: Array = _array(check="nonneg")
    kind: ClassVar[str] = "noise"
    stage: ClassVar[str] = "noise"


@dataclass(frozen=True)
class BiasInstability(Effect):
    """First-order Gauss–Markov bias: stationary standard deviation ``sigma``, correlation time ``tau``, s."""

    sigma: Array = _array(check="nonneg")
    tau: Array = _array(fill=100.0, check="positive")
    kind: ClassVar[str] = "bias_instability"
    stage: ClassVar[str] = "stochastic"

    def process(self, t: Array, rng: np.random.Generator) -> Array:
        """The bias at times ``t`` (n, 3), exact discretisation, started from its stationary law."""
        dt = np.diff(t)
        out = np.empty((len(t), 3))
        out[0] = self.sigma * rng.standard_normal(3)
        xi = rng.standard_normal((len(t) - 1, 3))
        phi = np.exp(-dt[:, None] / self.tau)
        drive = self.sigma * np.sqrt(1.0 - phi * phi) * xi
        _ar1(phi, drive, out, _uniform(t))
        return out


@dataclass(frozen=True)
class RateRandomWalk(Effect):
    """A bias that random-walks with density ``density``: rad/s/√s or m/s²/√s."""

    density: Array = _array(check="nonneg")
    kind: ClassVar[str] = "rate_random_walk"
    stage: ClassVar[str] = "stochastic"

    def process(self, t: Array, rng: np.random.Generator) -> Array:
        """The bias at times ``t`` (n, 3): a random walk from 0 at ``t[0]``, exact at each step."""
        steps = self.density * np.sqrt(np.diff(t))[:, None] * rng.standard_normal((len(t) - 1, 3))
        return np.vstack([np.zeros((1, 3)), np.cumsum(steps, axis=0)])


@dataclass(frozen=True)
class Saturation(Effect):
    """Output clipped at ``± limit`` (rad/s or m/s²)."""

    limit: Array = _array(fill=np.inf, check="positive")
    kind: ClassVar[str] = "saturation"
    stage: ClassVar[str] = "clip"


@dataclass(frozen=True)
class Quantization(Effect):
    """Output resolution ``step`` in rate units (rad/s, m/s²); increments use ``step · dt``."""

    step: Array = _array(check="nonneg")
    kind: ClassVar[str] = "quantization"
    stage: ClassVar[str] = "quantize"


EFFECT_TYPES: tuple[type[Effect], ...] = (
    Bias, ScaleMisalignment, GSensitivity, Noise, BiasInstability, RateRandomWalk, ScaleNonlinearity,
    ScaleAsymmetry, G2Sensitivity, TemperatureBias, TemperatureScale, TimeOffset, Quantization, Saturation,
    SizeEffect,
)  # fmt: skip

#: Every effect name of the library.
EFFECT_NAMES: tuple[str, ...] = tuple(f"{s}.{t.kind}" for t in EFFECT_TYPES for s in t.sensors)

#: The seed paper's model plus white noise.
BASELINE = ("gyro.bias", "accel.bias", "gyro.scale_misalignment", "accel.scale_misalignment",
            "gyro.g_sensitivity", "gyro.noise", "accel.noise")  # fmt: skip


def _ar1(phi: Array, drive: Array, out: Array, uniform: bool) -> None:
    """``out[k] = phi[k-1] out[k-1] + drive[k-1]`` (in place), vectorised over channels."""
    from scipy.signal import lfilter

    if len(phi) == 0:
        return
    if uniform:  # one coefficient: a linear filter does it in C
        for i in range(3):
            a = float(np.median(phi[:, i]))
            out[1:, i], _ = lfilter([1.0], [1.0, -a], drive[:, i], zi=[a * out[0, i]])
        return
    for k in range(1, len(out)):
        out[k] = phi[k - 1] * out[k - 1] + drive[k - 1]


def _uniform(t: Array) -> bool:
    """Steps equal to 1 ppm or to the rounding of the time stamps (which grows with |t|)."""
    dt = np.diff(t)
    if len(dt) == 0:
        return True
    return bool(np.ptp(dt) <= 1e-6 * np.median(dt) + 16.0 * np.finfo(float).eps * np.abs(t).max())


def _stream(seed: int | None, name: str) -> np.random.Generator:
    return np.random.default_rng([0 if seed is None else seed, zlib.crc32(name.encode())])


# --------------------------------------------------------------------------- the model


@dataclass(frozen=True)
class ImuModel:
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

    def without(self, *names: str) -> ImuModel:
        """The model with the named effects withheld (unknown names are an error)."""
        _check_names(names)
        return ImuModel(tuple(e for e in self.effects if e.name not in names))

    def only(self, *names: str) -> ImuModel:
        """The model with just the named effects."""
        _check_names(names)
        return ImuModel(tuple(e for e in self.effects if e.name in names))

    def with_effects(self, *effects: Effect) -> ImuModel:
        """The model with ``effects`` added, replacing any of the same name."""
        new = {e.name for e in effects}
        return ImuModel(tuple(e for e in self.effects if e.name not in new) + tuple(effects))

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
        omega_dot = (
            np.gradient(rates.omega_ib_b, t, axis=0) if len(t) > 1 else np.zeros_like(rates.omega_ib_b)
        )
        inputs = Inputs(omega=rates.omega_ib_b, f=rates.f_ib_b, omega_dot=omega_dot, temp=temp)
        dt = np.diff(t)
        out = []
        for sensor in SENSORS:
            delay = self._delay(sensor)
            y = np.empty_like(inputs.of(sensor))
            for d in np.unique(delay):
                shifted = _shift_samples(inputs, t, d) if d else inputs
                y_d = shifted.of(sensor) + self.deterministic_error(sensor, shifted)
                y[:, delay == d] = y_d[:, delay == d]
            y = y + self._stochastic(sensor, t, seed)
            noise = self._get(sensor, Noise)
            if noise is not None and len(t) > 1:
                step = np.median(dt)
                y = y + noise.density / np.sqrt(step) * _stream(seed, noise.name).standard_normal(y.shape)
            y = self._clip_and_round(sensor, y, scale=1.0)
            out.append(y)
        return ImuRates(t=t, omega_ib_b=out[0], f_ib_b=out[1])

    # ----------------------------------------------------------------- increment form

    def corrupt_increments(
        self, imu: ImuIncrements, temp: Array | None = None, seed: int | None = None
    ) -> ImuIncrements:
        """Readings of the modelled IMU as increments: integrals of the corrupted rate.

        Parameters
        ----------
        imu : ideal increments over ``n`` intervals (``imu.t`` has ``n + 1`` times)
        temp : (n+1,) temperature at ``imu.t``, °C (needed by temperature effects)
        seed : the run's seed for stochastic effects
        """
        t = imu.t
        dt = np.diff(t)
        n = len(dt)
        if n == 0:
            return imu
        temp = _check_temp(temp, t)
        means = (imu.dtheta_b / dt[:, None], imu.dv_b / dt[:, None])
        mid = 0.5 * (t[:-1] + t[1:])
        node_s = (-0.5 / np.sqrt(3.0), 0.5 / np.sqrt(3.0))  # two-point Gauss nodes, in units of dt
        nodes = [mid + s * dt for s in node_s]
        cache: dict[tuple[int, float], Inputs] = {}

        def node_inputs(j: int, d: float) -> Inputs:
            """True inputs at Gauss node ``j`` of every interval, delayed by ``d``."""
            if (j, d) not in cache:
                when = nodes[j]
                if d == 0.0:  # each node lies in its own interval
                    omega, omega_dot = _reconstruct_own(means[0], dt, node_s[j])
                    f, _ = _reconstruct_own(means[1], dt, node_s[j])
                else:
                    omega, omega_dot = _reconstruct(means[0], t, when - d)
                    f, _ = _reconstruct(means[1], t, when - d)
                # The channel measured at when - d: its temperature was that of then.
                temp_n = None if temp is None else np.interp(when - d, t, temp)
                cache[j, d] = Inputs(omega=omega, f=f, omega_dot=omega_dot, temp=temp_n)
            return cache[j, d]

        out = []
        for sensor, ideal in (("gyro", imu.dtheta_b), ("accel", imu.dv_b)):
            bias = self._stochastic(sensor, t, seed)
            noise = self._get(sensor, Noise)
            # White noise as each interval's mean rate: density / sqrt(dt) per interval.
            noise_rate = (
                noise.density / np.sqrt(dt)[:, None] * _stream(seed, noise.name).standard_normal((n, 3))
                if noise is not None
                else np.zeros((n, 3))
            )
            sat = self._get(sensor, Saturation)
            deterministic = any(e.stage == "deterministic" for e in self._of(sensor))
            delay = self._delay(sensor)
            total = np.empty_like(ideal)
            for d in np.unique(delay):
                cols = delay == d
                shifted = _shift_increments(ideal, t, d) if d else ideal
                if sat is None:
                    part = np.zeros_like(ideal)
                    if deterministic:
                        for j in range(len(nodes)):
                            part += (
                                0.5 * dt[:, None] * self.deterministic_error(sensor, node_inputs(j, float(d)))
                            )
                    # The ideal part stays exact; only the errors come from the reconstruction.
                    total[:, cols] = (shifted + part)[:, cols]
                    continue
                # Saturation clips the whole reading (input, errors, biases, noise) at the nodes.
                part = np.zeros_like(ideal)
                for j, when in enumerate(nodes):
                    inputs = node_inputs(j, float(d))
                    b = np.column_stack([np.interp(when, t, bias[:, i]) for i in range(3)])
                    rate = inputs.of(sensor) + self.deterministic_error(sensor, inputs) + b + noise_rate
                    part += 0.5 * dt[:, None] * np.clip(rate, -sat.limit, sat.limit)
                total[:, cols] = part[:, cols]
            if sat is None:
                total = total + (0.5 * (bias[:-1] + bias[1:]) + noise_rate) * dt[:, None]
            q = self._get(sensor, Quantization)
            if q is not None and (q.step > 0).any():
                total = _quantize_carry(total, q.step * np.median(dt))
            out.append(total)
        return ImuIncrements(t=t, dtheta_b=out[0], dv_b=out[1])

    # ----------------------------------------------------------------- pieces

    def _of(self, sensor: str) -> list[Effect]:
        return [e for e in self.effects if e.sensor == sensor]

    def _get(self, sensor: str, kind: type[Any]) -> Any:
        return next((e for e in self._of(sensor) if isinstance(e, kind)), None)

    def _delay(self, sensor: str) -> Array:
        off = self._get(sensor, TimeOffset)
        return np.zeros(3) if off is None else off.delay

    def deterministic_error(self, sensor: str, inputs: Inputs) -> Array:
        """The sum of the sensor's deterministic errors (n, 3) at these true inputs (no delay, no noise)."""
        u = inputs.of(sensor)
        err = np.zeros_like(u)
        for e in self._of(sensor):
            if e.stage == "deterministic":
                err = err + e.error(inputs, u)
        return err

    def _stochastic(self, sensor: str, t: Array, seed: int | None) -> Array:
        total = np.zeros((len(t), 3))
        for e in self._of(sensor):
            if isinstance(e, BiasInstability | RateRandomWalk):
                total += e.process(t, _stream(seed, e.name))
        return total

    def _clip_and_round(self, sensor: str, y: Array, scale: float) -> Array:
        sat = self._get(sensor, Saturation)
        if sat is not None:
            y = np.clip(y, -sat.limit, sat.limit)
        q = self._get(sensor, Quantization)
        if q is not None and (q.step > 0).any():
            step = np.where(q.step > 0, q.step * scale, 1.0)
            y = np.where(q.step > 0, np.round(y / step) * step, y)
        return y


def _check_temp(temp: Array | None, t: Array) -> Array | None:
    if temp is None:
        return None
    temp = np.asarray(temp, dtype=float)
    if temp.shape != t.shape:
        raise ValueError(f"temp must have one value per sample time, shape {t.shape}, got {temp.shape}")
    if not np.isfinite(temp).all():
        raise ValueError("temp must be finite")
    return temp


def _check_names(names: tuple[str, ...]) -> None:
    for n in names:
        if n not in EFFECT_NAMES:
            raise ValueError(f"unknown effect {n!r} (see `sins effects`)")


def _reconstruct(mean: Array, t: Array, when: Array) -> tuple[Array, Array]:
    """Rate and its derivative at times ``when`` from interval means (n, 3) over ``t``.

    In interval ``k`` the rate is the quadratic whose means over intervals
    ``k-1, k, k+1`` are the given ones (one-sided at the ends), evaluated at
    ``s = (when - mid_k) / dt_k``.
    """
    n = len(mean)
    k = np.clip(np.searchsorted(t, when, side="right") - 1, 0, n - 1)
    dt = (t[1:] - t[:-1])[k][:, None]
    s = ((when - 0.5 * (t[1:] + t[:-1])[k]) / dt[:, 0])[:, None]
    prev = mean[np.maximum(k - 1, 0)]
    nxt = mean[np.minimum(k + 1, n - 1)]
    cur = mean[k]
    slope = np.where((k == 0)[:, None] | (k == n - 1)[:, None], (nxt - prev), 0.5 * (nxt - prev))
    curve = np.where((k == 0)[:, None] | (k == n - 1)[:, None], 0.0, 0.5 * (nxt - 2.0 * cur + prev))
    value = cur + slope * s + curve * (s * s - 1.0 / 12.0)
    return value, (slope + 2.0 * curve * s) / dt


def _reconstruct_own(mean: Array, dt: Array, s: float) -> tuple[Array, Array]:
    """:func:`_reconstruct` at local coordinate ``s`` of every interval (by slices, no search)."""
    n = len(mean)
    prev = np.vstack([mean[:1], mean[:-1]])
    nxt = np.vstack([mean[1:], mean[-1:]])
    slope = 0.5 * (nxt - prev)
    curve = 0.5 * (nxt - 2.0 * mean + prev)
    if n > 1:  # one-sided at the two ends, as in _reconstruct
        slope[0], slope[-1] = nxt[0] - prev[0], nxt[-1] - prev[-1]
        curve[0] = curve[-1] = 0.0
    value = mean + slope * s + curve * (s * s - 1.0 / 12.0)
    return value, (slope + 2.0 * curve * s) / dt[:, None]


def _shift_samples(inputs: Inputs, t: Array, delay: float) -> Inputs:
    """Inputs delayed by ``delay`` s (cubic Hermite between samples, held at the ends)."""

    def at(y: Array) -> Array:
        dy = np.gradient(y, t, axis=0)
        q = np.clip(t - delay, t[0], t[-1])
        k = np.clip(np.searchsorted(t, q, side="right") - 1, 0, len(t) - 2)
        h = (t[k + 1] - t[k])[:, None]
        s = ((q - t[k]) / h[:, 0])[:, None]
        return (
            (1 + 2 * s) * (1 - s) ** 2 * y[k] + s * (1 - s) ** 2 * h * dy[k]
            + s * s * (3 - 2 * s) * y[k + 1] + s * s * (s - 1) * h * dy[k + 1]
        )  # fmt: skip

    temp = None if inputs.temp is None else np.interp(t - delay, t, inputs.temp)
    return Inputs(omega=at(inputs.omega), f=at(inputs.f), omega_dot=at(inputs.omega_dot), temp=temp)


def _shift_increments(inc: Array, t: Array, delay: float) -> Array:
    """Increments of the input delayed by ``delay``: differences of the cumulative integral at ``t - delay``.

    The cumulative integral is interpolated with cubic Hermite pieces whose
    slopes are the reconstructed rates at the sample times.
    """
    cum = np.vstack([np.zeros((1, 3)), np.cumsum(inc, axis=0)])
    mean = inc / np.diff(t)[:, None]
    rate_at = _reconstruct(mean, t, t)[0]
    q = np.clip(t - delay, t[0], t[-1])
    k = np.clip(np.searchsorted(t, q, side="right") - 1, 0, len(t) - 2)
    h = (t[k + 1] - t[k])[:, None]
    s = ((q - t[k]) / h[:, 0])[:, None]
    shifted = (
        (1 + 2 * s) * (1 - s) ** 2 * cum[k] + s * (1 - s) ** 2 * h * rate_at[k]
        + s * s * (3 - 2 * s) * cum[k + 1] + s * s * (s - 1) * h * rate_at[k + 1]
    )  # fmt: skip
    return np.diff(shifted, axis=0)


def _quantize_carry(inc: Array, step: Array) -> Array:
    """Quantise increments carrying the remainder: the output differences the rounded running sum."""
    active = step > 0
    safe = np.where(active, step, 1.0)
    rounded = np.round(np.cumsum(inc, axis=0) / safe) * safe
    out = np.diff(np.vstack([np.zeros((1, 3)), rounded]), axis=0)
    return np.where(active, out, inc)
