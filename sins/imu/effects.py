"""The library's effects: each defined once, with its error, its file parameters and units, its
regression columns, its gap candidate, its physics term group and its typical size
(:mod:`sins.imu.vocabulary` says what an effect declares). Registered in the order ``sins effects``
lists them.

How a sensor's output is formed from its true input, whatever the order of effects in a model, is in
:mod:`sins.imu.model`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from sins.core import rowwise
from sins.core.earth import G0
from sins.imu.numerics import apply_matrix, ar1, uniform_steps
from sins.imu.vocabulary import (
    DEG,
    DEG_PER_H,
    MG,
    PPM,
    UG,
    Effect,
    Param,
    RegressorInputs,
    Term,
    TrueInputs,
    register,
)
from sins.imu.vocabulary import parameter_field as _array
from sins.imu.vocabulary import vector_param as _v

Array = NDArray[np.float64]

#: A temperature parameter's range, °C: an IMU's operating range with margin (as scenario and rig files).
_T_LOW, _T_HIGH = -100.0, 200.0
_DPS = float(np.radians(1.0))  # one degree per second, rad/s (as the typical sizes were stated)


def _signs(rng: np.random.Generator, shape: tuple[int, ...] = (3,)) -> Array:
    """Magnitudes between 0.5 and 1 of the typical one, random signs: every axis has the effect."""
    return np.asarray(rng.uniform(0.5, 1.0, shape) * rng.choice([-1.0, 1.0], shape))


def _own(x: RegressorInputs, sensor: str, axis: int) -> Array:
    """Channel ``sensor``.``axis``'s own input (n, 1)."""
    return x.of(sensor)[:, axis : axis + 1]


def _temp(x: RegressorInputs) -> Array:
    if x.temp_offset is None:
        raise ValueError("these terms need the temperature: give the temperature series")
    return x.temp_offset[:, None]


@dataclass(frozen=True)
class Bias(Effect):
    """Constant bias ``b`` (rad/s or m/s²); the turn-on part is drawn per run by the grade."""

    value: Array = _array()
    kind: ClassVar[str] = "bias"
    affine: ClassVar[bool] = True
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (_v("bias_dph", "value", DEG_PER_H, "°/h"),),
        "accel": (_v("bias_mg", "value", MG, "mg", -1e5, 1e5),),
    }
    description: ClassVar[dict[str, str]] = {"gyro": "constant drift", "accel": "constant offset"}

    def error(self, inputs: TrueInputs, u: Array) -> Array:
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
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        s: (Param("matrix_ppm", "matrix", PPM, (3, 3), "ppm"),) for s in ("gyro", "accel")
    }
    description: ClassVar[dict[str, str]] = {
        "gyro": "scale-factor errors (diagonal) and axis misalignment: M·ω",
        "accel": "scale-factor errors (diagonal) and axis misalignment: M·f",
    }

    def error(self, inputs: TrueInputs, u: Array) -> Array:
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
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (Param("matrix_dph_per_g", "matrix", DEG_PER_H / G0, (3, 3), "°/h/g"),)
    }
    description: ClassVar[dict[str, str]] = {"gyro": "drift proportional to specific force: K·f"}

    def error(self, inputs: TrueInputs, u: Array) -> Array:
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
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (_v("k2_ppm_per_dps", "k2", PPM / DEG, "ppm/(°/s)"),),
        "accel": (_v("k2_ppm_per_g", "k2", PPM / G0, "ppm/g"),),
    }
    description: ClassVar[dict[str, str]] = {
        "gyro": "k2·ω²: scale error growing with the rate",
        "accel": "k2·f²: scale error growing with the force",
    }
    candidate: ClassVar[str | None] = "regressors"
    term: ClassVar[Term | None] = Term("squares", 1)

    @classmethod
    def columns(cls, x: RegressorInputs, sensor: str, axis: int) -> Array:
        """``u_i²``."""
        u = _own(x, sensor, axis)
        return u * u

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """1 ppm/(°/s) (gyro), 100 ppm/g (accel)."""
        if sensor == "gyro":
            return cls(sensor, scale * 1e-6 / _DPS * _signs(rng))
        return cls(sensor, scale * 100e-6 / G0 * _signs(rng))

    def error(self, inputs: TrueInputs, u: Array) -> Array:
        """``k2 u_i²`` on each axis."""
        return rowwise.mul_row(u, self.k2) * u


@dataclass(frozen=True)
class ScaleAsymmetry(Effect):
    """``ka |u_i|``: different scale factors for positive and negative inputs (dimensionless)."""

    ka: Array = _array()
    kind: ClassVar[str] = "scale_asymmetry"
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        s: (_v("ka_ppm", "ka", PPM, "ppm"),) for s in ("gyro", "accel")
    }
    description: ClassVar[dict[str, str]] = {
        "gyro": "ka·|ω|: sign-dependent scale factor",
        "accel": "ka·|f|: sign-dependent scale factor",
    }
    candidate: ClassVar[str | None] = "regressors"
    term: ClassVar[Term | None] = Term("asymmetry", 2)

    @classmethod
    def columns(cls, x: RegressorInputs, sensor: str, axis: int) -> Array:
        """``|u_i|``."""
        return np.abs(_own(x, sensor, axis))

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """300 ppm."""
        return cls(sensor, scale * 300e-6 * _signs(rng))

    def error(self, inputs: TrueInputs, u: Array) -> Array:
        """``ka |u_i|`` on each axis."""
        return rowwise.mul_row(np.abs(u), self.ka)


@dataclass(frozen=True)
class G2Sensitivity(Effect):
    """Anisoelastic gyro drift ``Σ_jk G2[i, j, k] f_j f_k``, rad/s per (m/s²)²."""

    tensor: Array = _array((3, 3, 3))
    kind: ClassVar[str] = "g2_sensitivity"
    sensors: ClassVar[tuple[str, ...]] = ("gyro",)
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (Param("tensor_dph_per_g2", "tensor", DEG_PER_H / G0**2, (3, 3, 3), "°/h/g²"),)
    }
    description: ClassVar[dict[str, str]] = {"gyro": "anisoelastic drift Σ G2·f·f"}
    candidate: ClassVar[str | None] = "regressors"
    term: ClassVar[Term | None] = Term("g2", 3)

    @classmethod
    def columns(cls, x: RegressorInputs, sensor: str, axis: int) -> Array:
        """The six products ``f_j f_k``: the squares, then ``f_x f_y``, ``f_x f_z``, ``f_y f_z`` (a
        symmetric tensor's six independent coefficients per axis)."""
        f = x.f_ib_b
        return np.hstack([f * f, f[:, [0, 0, 1]] * f[:, [1, 2, 2]]])

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """3 °/h/g²."""
        return cls(sensor, scale * 3.0 * DEG_PER_H / G0**2 * _signs(rng, (3, 3, 3)))

    def error(self, inputs: TrueInputs, u: Array) -> Array:
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
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (
            _v("c1_dph_per_degc", "c1", DEG_PER_H, "°/h/°C", -1e4, 1e4),
            _v("c2_dph_per_degc2", "c2", DEG_PER_H, "°/h/°C²", -1e3, 1e3),
            Param("t0_degc", "t0", 1.0, (), "°C", _T_LOW, _T_HIGH),
        ),
        "accel": (
            _v("c1_mg_per_degc", "c1", MG, "mg/°C", -1e3, 1e3),
            _v("c2_mg_per_degc2", "c2", MG, "mg/°C²", -1e2, 1e2),
            Param("t0_degc", "t0", 1.0, (), "°C", _T_LOW, _T_HIGH),
        ),
    }
    description: ClassVar[dict[str, str]] = {s: "c1·(T−T0) + c2·(T−T0)²" for s in ("gyro", "accel")}
    candidate: ClassVar[str | None] = "regressors"
    term: ClassVar[Term | None] = Term("temperature", 0)
    needs_temp: ClassVar[bool] = True

    @classmethod
    def columns(cls, x: RegressorInputs, sensor: str, axis: int) -> Array:
        """``T`` and ``T²``, from the caller's origin."""
        t = _temp(x)
        return np.hstack([t, t * t])

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """0.5 °/h/°C (gyro), 0.02 mg/°C (accel)."""
        if sensor == "gyro":
            return cls(sensor, c1=scale * 0.5 * DEG_PER_H * _signs(rng))
        return cls(sensor, c1=scale * 0.02 * MG * _signs(rng))

    def error(self, inputs: TrueInputs, u: Array) -> Array:
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
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        s: (
            _v("s1_ppm_per_degc", "s1", PPM, "ppm/°C", -1e5, 1e5),
            Param("t0_degc", "t0", 1.0, (), "°C", _T_LOW, _T_HIGH),
        )
        for s in ("gyro", "accel")
    }
    description: ClassVar[dict[str, str]] = {"gyro": "s1·(T−T0)·ω", "accel": "s1·(T−T0)·f"}
    candidate: ClassVar[str | None] = "regressors"
    term: ClassVar[Term | None] = Term("temperature", 0)
    needs_temp: ClassVar[bool] = True

    @classmethod
    def columns(cls, x: RegressorInputs, sensor: str, axis: int) -> Array:
        """``T u_i``, from the caller's origin."""
        return _temp(x) * _own(x, sensor, axis)

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """10 ppm/°C."""
        return cls(sensor, s1=scale * 10e-6 * _signs(rng))

    def error(self, inputs: TrueInputs, u: Array) -> Array:
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
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "accel": (
            Param("lever_arms_mm", "lever_arms", 1e-3, (3, 3), "mm (row i: accelerometer i)", -1e4, 1e4),
        )
    }
    description: ClassVar[dict[str, str]] = {"accel": "lever arm r_i of each accelerometer: ω̇×r + ω×(ω×r)"}
    candidate: ClassVar[str | None] = "regressors"

    @classmethod
    def columns(cls, x: RegressorInputs, sensor: str, axis: int) -> Array:
        """Accelerometer ``axis``'s reading of a unit lever arm along each body axis: the effect's
        three coefficients of that row are its lever arm's components."""
        omega_dot = x.omega_dot_b
        return np.stack(
            [lever_arm_acceleration(x.omega_ib_b, omega_dot, r)[:, axis] for r in np.eye(3)], axis=1
        )

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """2 mm."""
        return cls(sensor, scale * 2e-3 * _signs(rng, (3, 3)))

    def error(self, inputs: TrueInputs, u: Array) -> Array:
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
class MotionBias(Effect):
    """A bias that differs while the unit turns from its bias at rest, by ``b`` in full motion:
    ``b · m``, ``m = |ω|² / (|ω|² + ω₀²)`` (0 at rest, ½ at ``ω₀``, 1 well above it), ``ω₀``
    :data:`HALF_RATE_DPS`.

    A MEMS gyro's bias in motion need not be its bias at rest (vibration rectified in the sensing
    element, the rotation's own cross-coupling): BROAD's unit B differs by some 80-160 °/h between its
    rests and its rotations, in the compensation fit and in the gap's intervals alike. ``ω₀`` is fixed,
    so that the effect is one coefficient per axis, a regression column like any other; a unit whose
    bias turns over at another rate fits it in part.
    """

    value: Array = _array()
    kind: ClassVar[str] = "motion_bias"
    #: The rate at which half the bias in motion is reached, °/s: ten times a MEMS gyro's noise at
    #: rest (0.1-0.2 °/s per sample), a fifth of a slow hand-turned rotation.
    HALF_RATE_DPS: ClassVar[float] = 5.0
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (_v("bias_dph", "value", DEG_PER_H, "°/h"),),
        "accel": (_v("bias_mg", "value", MG, "mg", -1e5, 1e5),),
    }
    description: ClassVar[dict[str, str]] = {
        s: "bias in motion beyond that at rest: b·|ω|²/(|ω|²+ω₀²), ω₀ = 5 °/s" for s in ("gyro", "accel")
    }
    candidate: ClassVar[str | None] = "regressors"

    @classmethod
    def motion(cls, omega: Array) -> Array:
        """``m`` (n,) of the angular rate ``omega`` (n, 3), rad/s."""
        w2 = np.einsum("ij,ij->i", omega, omega)
        w0 = cls.HALF_RATE_DPS * _DPS
        return np.asarray(w2 / (w2 + w0 * w0))

    @classmethod
    def columns(cls, x: RegressorInputs, sensor: str, axis: int) -> Array:
        """``m`` of the rate, the same on every axis."""
        return cls.motion(x.omega_ib_b)[:, None]

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """20 °/h (gyro), 0.1 mg (accel)."""
        size = 20.0 * DEG_PER_H if sensor == "gyro" else 0.1 * MG
        return cls(sensor, scale * size * _signs(rng))

    def error(self, inputs: TrueInputs, u: Array) -> Array:
        """``b · m`` on each axis."""
        return rowwise.outer(self.motion(inputs.omega_ib_b), self.value)


@dataclass(frozen=True)
class TimeOffset(Effect):
    """The channel reports its input ``delay`` seconds late (``u(t - delay)``)."""

    delay: Array = _array()
    kind: ClassVar[str] = "time_offset"
    stage: ClassVar[str] = "delay"
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        s: (_v("delay_ms", "delay", 1e-3, "ms", -1e3, 1e3),) for s in ("gyro", "accel")
    }
    description: ClassVar[dict[str, str]] = {s: "reports the input τ late" for s in ("gyro", "accel")}
    candidate: ClassVar[str | None] = "delay"

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """1 ms."""
        return cls(sensor, delay=np.full(3, scale * 1e-3))


@dataclass(frozen=True)
class Noise(Effect):
    """White noise of density ``density``: rad/√s (angle random walk) or m/s/√s (velocity random walk)."""

    density: Array = _array(check="nonneg")
    kind: ClassVar[str] = "noise"
    stage: ClassVar[str] = "noise"
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (_v("arw_deg_per_rt_h", "density", DEG / 60.0, "°/√h", 0.0, 1e4),),
        "accel": (_v("vrw_ug_per_rt_hz", "density", UG, "µg/√Hz", 0.0, 1e7),),
    }
    description: ClassVar[dict[str, str]] = {
        "gyro": "white noise (angle random walk)",
        "accel": "white noise (velocity random walk)",
    }


@dataclass(frozen=True)
class QuantizationNoise(Effect):
    """White noise of the integrated output: the IEEE Std 952 / 1293 quantization term ``Q``.

    ``q`` (rad for a gyro, m/s for an accelerometer) is the standard deviation of an error ``e_k`` in
    the angle (velocity) the unit has integrated up to its ``k``-th output, independent from output
    to output; the increment of interval ``k`` gains ``e_k − e_{k−1}`` (its mean rate that over the
    step ``dt``). Its Allan variance is ``3 q²/τ²`` at every cluster time ``τ = m·dt``, exactly (a
    cluster's mean is ``(e_end − e_start)/τ`` and three independent ``e`` enter each difference), and
    its two-sided spectrum per sample is ``4 sin²(π f dt) q²/dt²``: the term as the standards define
    it and as :mod:`sins.characterise.noise_terms` fits it.

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
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (_v("q_arcsec", "q", DEG / 3600.0, "arcsec", 0.0, 1e5),),
        "accel": (_v("q_ug_s", "q", UG, "µg·s", 0.0, 1e7),),
    }
    description: ClassVar[dict[str, str]] = {
        "gyro": "white noise of the integrated angle (IEEE quantization term Q)",
        "accel": "white noise of the integrated velocity (IEEE quantization term Q)",
    }
    #: Not diagnosed: white noise beside the baseline's, which the channel model takes as it comes
    #: (``sins characterise`` measures it from the Allan curve); a model that holds it is diagnosed as
    #: without.
    candidate: ClassVar[str | None] = None

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
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (_v("sigma_dph", "sigma", DEG_PER_H, "°/h", 0.0), _v("tau_s", "tau", 1.0, "s", 1e-6, 1e9)),
        "accel": (_v("sigma_ug", "sigma", UG, "µg", 0.0, 1e8), _v("tau_s", "tau", 1.0, "s", 1e-6, 1e9)),
    }
    description: ClassVar[dict[str, str]] = {
        s: "Gauss–Markov bias: σ, correlation time τ" for s in ("gyro", "accel")
    }
    candidate: ClassVar[str | None] = "process"

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """5 °/h (gyro), 0.1 mg (accel), 100 s."""
        sigma = scale * 5.0 * DEG_PER_H if sensor == "gyro" else scale * 0.1 * MG
        return cls(sensor, sigma=np.full(3, sigma), tau=np.full(3, 100.0))

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
        ar1(np.atleast_2d(phi), drive, out, uniform)
        return out


@dataclass(frozen=True)
class RateRandomWalk(Effect):
    """A bias that random-walks with density ``density``: rad/s/√s or m/s²/√s."""

    density: Array = _array(check="nonneg")
    kind: ClassVar[str] = "rate_random_walk"
    stage: ClassVar[str] = "stochastic"
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (_v("rrw_dph_per_rt_h", "density", DEG_PER_H / 60.0, "°/h/√h", 0.0),),
        "accel": (_v("rrw_ug_per_rt_s", "density", UG, "µg/√s", 0.0, 1e8),),
    }
    description: ClassVar[dict[str, str]] = {s: "random-walk bias" for s in ("gyro", "accel")}
    candidate: ClassVar[str | None] = "process"

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """20 °/h/√h (gyro), 50 µg/√s (accel)."""
        density = scale * 20.0 * DEG_PER_H / 60.0 if sensor == "gyro" else scale * 50e-6 * G0
        return cls(sensor, density=np.full(3, density))

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
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (_v("limit_dps", "limit", DEG, "°/s", 1e-3, 1e6),),
        "accel": (_v("limit_g", "limit", G0, "g", 1e-6, 1e5),),
    }
    description: ClassVar[dict[str, str]] = {s: "output clipped at ± limit" for s in ("gyro", "accel")}
    candidate: ClassVar[str | None] = "output"

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """150 °/s (gyro), 0.95 g (accel), divided by ``scale``."""
        limit = 150.0 * _DPS / scale if sensor == "gyro" else 0.95 * G0 / scale
        return cls(sensor, limit=np.full(3, limit))


@dataclass(frozen=True)
class Quantization(Effect):
    """Output resolution ``step`` in rate units (rad/s, m/s²); increments use ``step · dt``."""

    step: Array = _array(check="nonneg")
    kind: ClassVar[str] = "quantization"
    stage: ClassVar[str] = "quantize"
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (_v("step_dps", "step", DEG, "°/s", 0.0, 1e3),),
        "accel": (_v("step_mg", "step", MG, "mg", 0.0, 1e5),),
    }
    description: ClassVar[dict[str, str]] = {s: "output resolution" for s in ("gyro", "accel")}
    candidate: ClassVar[str | None] = "output"

    @classmethod
    def typical(cls, sensor: str, rng: np.random.Generator, scale: float) -> Effect | None:
        """0.05 °/s (gyro), 2 mg (accel)."""
        step = scale * 0.05 * _DPS if sensor == "gyro" else scale * 2.0 * MG
        return cls(sensor, step=np.full(3, step))


for _cls in (Bias, ScaleMisalignment, GSensitivity, Noise, BiasInstability, RateRandomWalk, ScaleNonlinearity,
             ScaleAsymmetry, G2Sensitivity, TemperatureBias, TemperatureScale, TimeOffset, Quantization,
             QuantizationNoise, Saturation, SizeEffect, MotionBias):  # fmt: skip
    register(_cls)

#: The seed paper's model plus white noise.
BASELINE = ("gyro.bias", "accel.bias", "gyro.scale_misalignment", "accel.scale_misalignment",
            "gyro.g_sensitivity", "gyro.noise", "accel.noise")  # fmt: skip


__all__ = [
    "BASELINE",
    "Bias",
    "BiasInstability",
    "G2Sensitivity",
    "GSensitivity",
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
    "lever_arm_acceleration",
]
