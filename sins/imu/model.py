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

import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

import numba
import numpy as np
from numpy.typing import NDArray

from sins import rowwise
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

    #: Whether the error is affine in the true inputs, ``b + M u + K f`` (:meth:`affine_terms`): its
    #: integral over an interval is then ``b Δt + M Δu + K Δv`` of the interval's ideal increments,
    #: exactly, and the increment form needs no rate reconstructed at Gauss nodes for it.
    affine: ClassVar[bool] = False

    def error(self, inputs: Inputs, u: Array) -> Array:
        """Additive error (n, 3) given the inputs and this sensor's (possibly delayed) input ``u``."""
        raise NotImplementedError

    def affine_terms(self) -> tuple[Array, Array, Array]:
        """An affine effect's ``b`` (3,), ``M`` (3, 3) on the sensor's own input and ``K`` (3, 3) on the
        specific force, its error being ``b + M u + K f``."""
        raise NotImplementedError(f"{self.name} is not affine in the inputs")


@dataclass(frozen=True)
class Bias(Effect):
    """Constant bias ``b`` (rad/s or m/s²); the turn-on part is drawn per run by the grade."""

    value: Array = _array()
    kind: ClassVar[str] = "bias"
    affine: ClassVar[bool] = True

    def error(self, inputs: Inputs, u: Array) -> Array:
        """The bias ``b`` at every sample."""
        return rowwise.add_row(np.zeros(u.shape), self.value)

    def affine_terms(self) -> tuple[Array, Array, Array]:
        """``b``, no matrices."""
        return self.value, np.zeros((3, 3)), np.zeros((3, 3))


@dataclass(frozen=True)
class ScaleMisalignment(Effect):
    """``M u``: diagonal scale-factor errors, off-diagonal misalignment (the seed's ``B`` and ``A``)."""

    matrix: Array = _array((3, 3))
    kind: ClassVar[str] = "scale_misalignment"
    affine: ClassVar[bool] = True

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``M u``."""
        return apply_matrix(self.matrix, u)

    def affine_terms(self) -> tuple[Array, Array, Array]:
        """``M`` on the sensor's own input."""
        return np.zeros(3), self.matrix, np.zeros((3, 3))


@dataclass(frozen=True)
class GSensitivity(Effect):
    """Gyro drift ``K f`` proportional to specific force (the seed's ``K``), rad/s per m/s²."""

    matrix: Array = _array((3, 3))
    kind: ClassVar[str] = "g_sensitivity"
    sensors: ClassVar[tuple[str, ...]] = ("gyro",)
    affine: ClassVar[bool] = True

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``K f`` from the specific force ``f_ib_b``."""
        return apply_matrix(self.matrix, inputs.f_ib_b)

    def affine_terms(self) -> tuple[Array, Array, Array]:
        """``K`` on the specific force."""
        return np.zeros(3), np.zeros((3, 3)), self.matrix


@dataclass(frozen=True)
class ScaleNonlinearity(Effect):
    """``k2 u_i²`` on each channel's own axis; ``k2`` in 1/(rad/s) or 1/(m/s²)."""

    k2: Array = _array()
    kind: ClassVar[str] = "scale_nonlinearity"

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``k2 u_i²`` on each axis."""
        return rowwise.mul_row(u, self.k2) * u


@dataclass(frozen=True)
class ScaleAsymmetry(Effect):
    """``ka |u_i|``: different scale factors for positive and negative inputs (dimensionless)."""

    ka: Array = _array()
    kind: ClassVar[str] = "scale_asymmetry"

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``ka |u_i|`` on each axis."""
        return rowwise.mul_row(np.abs(u), self.ka)


@dataclass(frozen=True)
class G2Sensitivity(Effect):
    """Anisoelastic gyro drift ``Σ_jk G2[i, j, k] f_j f_k``, rad/s per (m/s²)²."""

    tensor: Array = _array((3, 3, 3))
    kind: ClassVar[str] = "g2_sensitivity"
    sensors: ClassVar[tuple[str, ...]] = ("gyro",)

    def error(self, inputs: Inputs, u: Array) -> Array:
        """``Σ_jk G2[i, j, k] f_j f_k`` from the specific force ``f_ib_b``."""
        f = inputs.f_ib_b
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
        d = inputs.temp - self.t0
        return rowwise.outer(d, self.c1) + rowwise.mul_col(rowwise.outer(d, self.c2), d)


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
        return rowwise.outer(inputs.temp - self.t0, self.s1) * u


@dataclass(frozen=True)
class SizeEffect(Effect):
    """Accelerometer ``i`` sits at lever arm ``r_i`` (row ``i``, m) from the reference point:
    ``e_iᵀ (ω̇ × r_i + ω × (ω × r_i))``."""

    lever_arms: Array = _array((3, 3))
    kind: ClassVar[str] = "size_effect"
    sensors: ClassVar[tuple[str, ...]] = ("accel",)

    def error(self, inputs: Inputs, u: Array) -> Array:
        """Accelerometer ``i``'s own axis of ``ω̇ × r_i + ω × (ω × r_i)``."""
        w, wd = inputs.omega_ib_b, inputs.omega_dot_b
        out = np.empty_like(w)
        for i in range(3):
            out[:, i] = lever_arm_acceleration(w, wd, self.lever_arms[i])[:, i]
        return out


def lever_arm_acceleration(omega: Array, omega_dot: Array, r: Array) -> Array:
    """The specific force at lever arm ``r`` (3,) m from the reference point, less the reference
    point's: ``ω̇ × r + ω × (ω × r)`` (n, 3), m/s², body axes.

    The size effect's error (:class:`SizeEffect`), and per unit lever arm its regressors in the gap
    diagnosis (:mod:`sins.gap.candidates`).

    Parameters
    ----------
    omega : (n, 3) angular rate ``omega_ib_b``, rad/s
    omega_dot : (n, 3) angular acceleration, rad/s²
    r : (3,) lever arm, m
    """
    return np.cross(omega_dot, r) + np.cross(omega, np.cross(omega, r))


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
class QuantizationNoise(Effect):
    """White noise of the integrated output: the IEEE Std 952 / 1293 quantization term ``Q``.

    ``q`` (rad for a gyro, m/s for an accelerometer) is the standard deviation of an error ``e_k`` in
    the angle (velocity) the unit has integrated up to its ``k``-th output, independent from output
    to output; the increment of interval ``k`` gains ``e_k − e_{k−1}`` (its mean rate that over the
    step ``dt``). Its Allan variance is ``3 q²/τ²`` at every cluster time ``τ = m·dt``, exactly (a
    cluster's mean is ``(e_end − e_start)/τ`` and three independent ``e`` enter each difference), and
    its two-sided spectrum per sample is ``4 sin²(π f dt) q²/dt²``: the term as the standards define
    it and as :mod:`sins.characterise.terms` fits it.

    Why an effect of its own, not :class:`Quantization`: the term describes a quantizer whose error is
    independent from sample to sample. A rounding quantizer's is only when the input moves by more
    than about half a step between samples (its own noise, or a ring-laser gyro's mechanical dither,
    randomises the remainder). On a nearly constant input (a unit at rest under Earth rate and
    gravity) rounding with the remainder carried makes a deterministic sawtooth instead, whose Allan
    curve has lobes where the term has a ``τ⁻¹`` slope; :class:`Quantization` models that output as it
    is (rounded to the unit's step) and stays as it was.

    Why white angle noise rather than a dithered quantizer: the term gives one number, ``Q``; a
    dithered quantizer needs a step and a dither law, and its output lies on a lattice. A real unit's
    ``Q`` is often not its count's ``step/√12`` (readout timing and bursts add to it: the PSINS
    ring-laser unit's accelerometers show ``Q`` ≈ 133 µg·s on a count of 125 µg·s, 3.7 times
    ``125/√12``), so a lattice of ``√12 Q`` would be no more the unit's than none. The error is
    Gaussian: the term fixes only its variance, and the Allan variance and spectrum above hold for any
    law of that variance (a uniform rounding error included). With :class:`Quantization` in the same
    model the running sum is rounded after this noise is added: a quantizer dithered by it.

    In rate form the sample ``k`` gains ``(e_k − e_{k−1}) / dt`` (``dt`` the median step): the
    reading taken as the interval's mean rate, as a sampled output's is.
    """

    q: Array = _array(check="nonneg")
    kind: ClassVar[str] = "quantization_noise"
    stage: ClassVar[str] = "noise"

    def angle_errors(self, rng: np.random.Generator, n: int) -> Array:
        """``n`` independent errors of the integrated output (n, 3), rad or m/s."""
        return self.q * rng.standard_normal((n, 3))


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
        uniform = uniform_steps(t)
        if uniform and len(phi):  # one coefficient a channel, the median step's
            phi = np.median(phi, axis=0)
        drive = self.sigma * np.sqrt(1.0 - phi * phi) * xi
        _ar1(np.atleast_2d(phi), drive, out, uniform)
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
    SizeEffect, QuantizationNoise,
)  # fmt: skip

#: Every effect name of the library.
EFFECT_NAMES: tuple[str, ...] = tuple(f"{s}.{t.kind}" for t in EFFECT_TYPES for s in t.sensors)

#: The seed paper's model plus white noise.
BASELINE = ("gyro.bias", "accel.bias", "gyro.scale_misalignment", "accel.scale_misalignment",
            "gyro.g_sensitivity", "gyro.noise", "accel.noise")  # fmt: skip


def _ar1(phi: Array, drive: Array, out: Array, uniform: bool) -> None:
    """``out[k] = phi[k-1] out[k-1] + drive[k-1]`` (in place), vectorised over channels; ``uniform``:
    ``phi`` is one row (1, 3), every interval's."""
    from scipy.signal import lfilter

    if len(phi) == 0:
        return
    if uniform:  # one coefficient: a linear filter does it in C
        for i in range(3):
            a = float(phi[0, i])
            out[1:, i], _ = lfilter([1.0], [1.0, -a], drive[:, i], zi=[a * out[0, i]])
        return
    for k in range(1, len(out)):
        out[k] = phi[k - 1] * out[k - 1] + drive[k - 1]


def uniform_steps(t: Array) -> bool:
    """Whether ``t`` is sampled regularly: its steps equal to 1 ppm of their median or to the
    rounding of the time stamps (which grows with ``|t|``)."""
    t = np.ascontiguousarray(t, dtype=float)
    if len(t) < 2:
        return True
    low, high, largest = _step_range(t)
    spread = high - low
    rounding = 16.0 * np.finfo(float).eps * largest
    # The median lies between the smallest and largest step: most calls are settled without it.
    if spread <= 1e-6 * low + rounding:
        return True
    if spread > 1e-6 * high + rounding:
        return False
    return bool(spread <= 1e-6 * np.median(np.diff(t)) + rounding)


@numba.njit(cache=True, nogil=True)
def _step_range(t: Array) -> tuple[float, float, float]:
    """The smallest and largest step of ``t`` (at least two samples) and its largest ``|t|``, in one
    pass (each chunk of a stream asks)."""
    low = high = t[1] - t[0]
    largest = max(abs(t[0]), abs(t[1]))
    for k in range(2, t.shape[0]):
        step = t[k] - t[k - 1]
        low, high, largest = min(low, step), max(high, step), max(largest, abs(t[k]))
    return low, high, largest


def apply_matrix(matrix: NDArray[Any], rows: NDArray[Any]) -> Array:
    """``matrix`` (3, 3) applied to every row of ``rows`` (n, 3): ``rows @ matrix.T``.

    Through a C-ordered copy of the transpose: numpy's ``matmul`` takes a loop five times slower for
    a transposed (Fortran-ordered) 3×3 on thousands of rows, with the same arithmetic (the same
    bits from 2 rows up, ``tests/test_rowwise.py``); a single row goes the way ``@`` sends it.
    """
    if rows.ndim == 2 and rows.shape[0] > 1:
        return np.asarray(rows @ np.ascontiguousarray(matrix.T), dtype=np.float64)
    return np.asarray(rows @ matrix.T, dtype=np.float64)


def random_stream(seed: int | None, name: str) -> np.random.Generator:
    """The generator of one effect's random draws in a run: its own stream of the run's seed, so that
    adding or removing another effect leaves its draws alone."""
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
        inputs = Inputs(omega_ib_b=rates.omega_ib_b, f_ib_b=rates.f_ib_b, omega_dot_b=omega_dot, temp=temp)
        dt = np.diff(t)
        out = []
        for sensor in SENSORS:
            delay = self.delay_of(sensor)
            y = np.empty_like(inputs.of(sensor))
            for d in np.unique(delay):
                shifted = _shift_samples(inputs, t, d) if d else inputs
                y_d = shifted.of(sensor) + self.deterministic_error(sensor, shifted)
                y[:, delay == d] = y_d[:, delay == d]
            y = y + self._stochastic(sensor, t, seed)
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
            y = self._clip_and_round(sensor, y, scale=1.0)
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
        from sins.imu.stream import IncrementStream  # the stream builds on this module

        t = imu.t
        if len(t) < 2:
            return imu
        temp = _check_temp(temp, t)
        step = float(np.median(np.diff(t))) if dt_nominal is None else dt_nominal
        stream = IncrementStream(self, seed, step)
        head, tail = stream.push(imu, temp), stream.finish()
        return ImuIncrements(
            t=np.concatenate([head.t, tail.t[1:]]) if len(head.t) else tail.t,
            dtheta_b=np.vstack([head.dtheta_b, tail.dtheta_b]),
            dv_b=np.vstack([head.dv_b, tail.dv_b]),
        )

    # ----------------------------------------------------------------- pieces

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
        self, sensor: str, inputs: Inputs, effects: Sequence[Effect] | None = None
    ) -> Array:
        """The sum of the sensor's deterministic errors (n, 3) at these true inputs (no delay, no noise);
        ``effects``: only those of them (default: all)."""
        u = inputs.of(sensor)
        err = np.zeros_like(u)
        for e in self.effects_of(sensor) if effects is None else effects:
            if e.stage == "deterministic":
                np.add(err, e.error(inputs, u), out=err)  # in place: the same sums, no new array each
        return err

    def _stochastic(self, sensor: str, t: Array, seed: int | None) -> Array:
        total = np.zeros((len(t), 3))
        for e in self.effects_of(sensor):
            if isinstance(e, BiasInstability | RateRandomWalk):
                total += e.process(t, random_stream(seed, e.name))
        return total

    def _clip_and_round(self, sensor: str, y: Array, scale: float) -> Array:
        sat = self.effect_of(sensor, Saturation)
        if sat is not None:
            y = np.clip(y, -sat.limit, sat.limit)
        q = self.effect_of(sensor, Quantization)
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


#: A one-sided slope replaces the central one at a row where the central stencil's second difference
#: stands out from both one-sided stencils' by more than 1 / this: a kink (a rig's rate switched to a
#: ramp, a turn started), not curvature.
KINK_RATIO = 0.1


def hermite_slopes(t: Array, y: Array, central: Array) -> tuple[Array, Array]:
    """The slopes a cubic Hermite curve through samples ``y`` (n, k) leaves and enters each row with:
    the central ones, except at a kink.

    A rig's commanded rate is piecewise linear, and the force turns as a rotation starts: where the
    slope changes at a row, the central slope there is the mean of the two sides, and the curve bends
    across the intervals on both (a lag of τ then errs by τ times half the change of slope). Where
    the central stencil's second difference stands out from both one-sided stencils' (each below
    :data:`KINK_RATIO` of it), each side takes its own one-sided slope, exact on a straight side.
    Elsewhere, smooth curvature and inflections included, both are the central slope.
    """
    right, left = central.copy(), central.copy()
    n = len(t)
    if n > 4:
        h = np.diff(t)[:, None]
        secant = np.diff(y, axis=0) / h
        bend = np.abs(np.diff(secant, axis=0))  # the stencil centred on rows 1 .. n-2
        # Rows 2 .. n-3 have a centred stencil and both one-sided ones.
        centre, back, ahead = bend[1:-1], bend[:-2], bend[2:]
        kink = (ahead < KINK_RATIO * centre) & (back < KINK_RATIO * centre)
        rows = slice(2, n - 2)
        forward = secant[2:-1] + (secant[2:-1] - secant[3:]) * h[2:-1] / (h[2:-1] + h[3:])
        backward = secant[1:-2] + (secant[1:-2] - secant[:-3]) * h[1:-2] / (h[1:-2] + h[:-3])
        right[rows] = np.where(kink, forward, central[rows])
        left[rows] = np.where(kink, backward, central[rows])
    return right, left


def cubic_hermite(t: Array, y: Array, dy: Array, when: Array, dy_in: Array | None = None) -> Array:
    """Samples ``y`` (n, k) at times ``t``, with slopes ``dy``, interpolated at ``when`` (within
    ``t``'s span) by cubic Hermite pieces; ``dy_in``, if given, are the slopes each interval
    enters its end row with (``dy`` those it leaves its start row with; see :func:`hermite_slopes`).

    Written out in the Hermite basis. The gap diagnosis delays its reference with a scipy ``PPoly``
    (:meth:`sins.gap.candidates.ReferenceInputs.lag`), the same curve in power form: the two agree to
    the last few bits only, so each keeps its own.
    """
    dy_in = dy if dy_in is None else dy_in
    k = np.clip(np.searchsorted(t, when, side="right") - 1, 0, len(t) - 2)
    h = (t[k + 1] - t[k])[:, None]
    s = ((when - t[k]) / h[:, 0])[:, None]
    return (
        (1 + 2 * s) * (1 - s) ** 2 * y[k] + s * (1 - s) ** 2 * h * dy[k]
        + s * s * (3 - 2 * s) * y[k + 1] + s * s * (s - 1) * h * dy_in[k + 1]
    )  # fmt: skip


def _shift_samples(inputs: Inputs, t: Array, delay: float) -> Inputs:
    """Inputs delayed by ``delay`` s (cubic Hermite between samples, held at the ends)."""

    def at(y: Array) -> Array:
        out, into = hermite_slopes(t, y, np.gradient(y, t, axis=0))
        return cubic_hermite(t, y, out, np.clip(t - delay, t[0], t[-1]), into)

    temp = None if inputs.temp is None else np.interp(t - delay, t, inputs.temp)
    return Inputs(
        omega_ib_b=at(inputs.omega_ib_b),
        f_ib_b=at(inputs.f_ib_b),
        omega_dot_b=at(inputs.omega_dot_b),
        temp=temp,
    )


__all__ = [
    "BASELINE",
    "CHANNELS",
    "DEG",
    "DEG_PER_H",
    "EFFECT_NAMES",
    "EFFECT_TYPES",
    "KINK_RATIO",
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
    "Inputs",
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
    "apply_matrix",
    "cubic_hermite",
    "display_unit",
    "hermite_slopes",
    "lever_arm_acceleration",
    "random_stream",
    "uniform_steps",
]
