"""Corrupting ideal increments chunk by chunk, so that memory stays bounded whatever the duration.

:class:`IncrementStream` is the increment form of :class:`sins.imu.ImuModel`:
:meth:`~sins.imu.ImuModel.corrupt_increments` is one stream fed the whole array at once. Fed the same
increments in chunks, it gives the same readings to the last bit, because everything that crosses a
chunk boundary is carried rather than recomputed:

* each random process (white noise, quantization noise, bias instability, rate random walk) draws from
  its own generator, which a chunk continues where the last left it, and its state (the bias at the last
  sample, the quantization noise's last error of the integrated output) goes on;
* the deterministic errors at an interval's Gauss nodes need the rate reconstructed from the
  neighbouring intervals' means (an effect affine in the inputs needs no nodes: its integral is the
  effect applied to the ideal increments, exactly), and a delayed channel the input ``delay``
  earlier: the stream keeps
  :meth:`IncrementStream.margin` intervals on each side of those it writes, and writes an interval only
  once its later neighbours have come;
* a delayed channel interpolates the running integral of its input, carried as the sum of every
  interval before the window, added in the same order as one long cumulative sum;
* quantization with the remainder carried keeps the running sum and its last rounded value.

The two paths differ only in the bias instability's recursion on irregular sampling, which takes each
chunk's own steps (a stream of regular chunks and the whole array agree).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import NDArray

from sins.core import rowwise
from sins.core.series import ImuIncrements
from sins.imu.effect_set import EffectSet
from sins.imu.effects import (
    BiasInstability,
    Noise,
    Quantization,
    QuantizationNoise,
    RateRandomWalk,
    Saturation,
)
from sins.imu.numerics import cubic_hermite, random_stream, uniform_steps
from sins.imu.vocabulary import SENSORS, Effect, TrueInputs

Array = NDArray[np.float64]

#: Two-point Gauss nodes of each interval, in units of its step from its middle.
_NODES = (-0.5 / math.sqrt(3.0), 0.5 / math.sqrt(3.0))


@dataclass
class _Process:
    """A random bias's generator and its value at the last written sample."""

    effect: BiasInstability | RateRandomWalk
    rng: np.random.Generator
    value: Array | None = None  # None before the first sample


@dataclass
class _Sensor:
    """What one sensor carries from chunk to chunk."""

    name: str
    processes: list[_Process]
    noise: Noise | None
    noise_rng: np.random.Generator | None
    qnoise: QuantizationNoise | None = None
    qnoise_rng: np.random.Generator | None = None
    qnoise_last: Array | None = None  # the integrated output's error at the last written sample
    cum: Array = field(default_factory=lambda: np.zeros(3))  # ideal running integral at the window start
    quant_sum: Array = field(default_factory=lambda: np.zeros(3))  # running sum before rounding
    quant_out: Array = field(default_factory=lambda: np.zeros(3))  # its last rounded value
    affine: list[Effect] = field(default_factory=list)  # deterministic effects integrated exactly
    curved: list[Effect] = field(default_factory=list)  # the others, at the Gauss nodes
    #: The affine effects' ``b``, ``M``, ``K`` summed (:meth:`sins.imu.vocabulary.Effect.affine_terms`).
    terms: tuple[Array, Array, Array] = field(default_factory=lambda: (np.zeros(3), np.zeros((3, 3)),
                                                                       np.zeros((3, 3))))  # fmt: skip
    #: Nothing but affine effects, random biases and white noise: one compiled pass writes the readings.
    plain: bool = False


class _NodeInputs:
    """The true inputs at each buffered interval's Gauss nodes, delayed by ``d``, computed once per
    write for both sensors: the rate reconstructed from the neighbouring intervals' means, and the
    temperature of the moment the channel measured."""

    def __init__(self, t: Array, inc: dict[str, Array], temp: Array | None) -> None:
        self.t, self.temp, self.inc = t, temp, inc
        self.dt = np.diff(t)
        self._means: dict[str, Array] = {}
        self._nodes: list[Array] = []
        self._cache: dict[tuple[int, float], TrueInputs] = {}
        self._uniform: dict[tuple[int, int], bool] = {}

    def uniform(self, lo: int, hi: int) -> bool:
        """Whether the samples ``lo .. hi`` are regular (:func:`~sins.imu.numerics.uniform_steps`), asked
        once for both sensors."""
        if (lo, hi) not in self._uniform:
            self._uniform[lo, hi] = uniform_steps(self.t[lo : hi + 1])
        return self._uniform[lo, hi]

    @property
    def means(self) -> dict[str, Array]:
        """Each sensor's mean rate over each buffered interval (made when first asked)."""
        if not self._means:
            self._means = {sensor: self.inc[sensor] / self.dt[:, None] for sensor in SENSORS}
        return self._means

    @property
    def nodes(self) -> list[Array]:
        """The times of every buffered interval's two Gauss nodes (made when first asked)."""
        if not self._nodes:
            t = self.t
            self._nodes = [0.5 * (t[:-1] + t[1:]) + s * self.dt for s in _NODES]
        return self._nodes

    def __call__(self, j: int, d: float) -> TrueInputs:
        """The inputs at Gauss node ``j`` of every buffered interval, delayed by ``d`` s."""
        if (j, d) not in self._cache:
            t, when, means = self.t, self.nodes[j], self.means
            if d == 0.0:  # each node lies in its own interval
                omega, omega_dot = _reconstruct_own(means["gyro"], self.dt, _NODES[j])
                f, _ = _reconstruct_own(means["accel"], self.dt, _NODES[j])
            else:
                omega, omega_dot = _reconstruct(means["gyro"], t, when - d)
                f, _ = _reconstruct(means["accel"], t, when - d)
            temp = None if self.temp is None else np.interp(when - d, t, self.temp)
            self._cache[j, d] = TrueInputs(omega_ib_b=omega, f_ib_b=f, omega_dot_b=omega_dot, temp=temp)
        return self._cache[j, d]


class IncrementStream:
    """Readings of ``model`` as increments, from ideal increments pushed chunk by chunk.

    Chunks must follow each other (each chunk's ``imu.t[0]`` is the last chunk's final time). Each
    :meth:`push` returns the intervals now complete, :meth:`finish` the rest; together they are
    :meth:`sins.imu.ImuModel.corrupt_increments` of the whole, to the last bit.

    Parameters
    ----------
    model : the IMU's error model
    seed : the run's seed for stochastic effects
    dt_nominal : the sampling step, s: the quantization step of an increment is the rate step times it,
        and the bias instability's recursion uses it on regular samples (one value for every chunk)
    """

    def __init__(self, model: EffectSet, seed: int | None, dt_nominal: float) -> None:
        if not (math.isfinite(dt_nominal) and dt_nominal > 0.0):
            raise ValueError(f"dt_nominal must be a positive number of seconds, got {dt_nominal}")
        self.model = model
        self.seed = seed
        self.dt_nominal = dt_nominal
        self._sensors = {s: self._sensor(s) for s in SENSORS}
        self._margin = self._context()
        # The temperature at the nodes only where an effect reads it: interpolating it at both nodes
        # is a few per cent of a tactical unit's corruption, for nothing.
        self._needs_temp = any(e.needs_temp for e in model.effects)
        self._delayed = any(model.delay_of(s).any() for s in SENSORS)
        self._t: Array | None = None  # buffered sample times (window start .. latest)
        self._inc: dict[str, Array] = {}  # buffered ideal increments per sensor
        self._temp: Array | None = None
        self._written = 0  # intervals of the buffer already written
        self._finished = False

    def _sensor(self, sensor: str) -> _Sensor:
        processes = [
            _Process(e, random_stream(self.seed, e.name))
            for e in self.model.effects_of(sensor)
            if isinstance(e, BiasInstability | RateRandomWalk)
        ]
        noise = self.model.effect_of(sensor, Noise)
        rng = None if noise is None else random_stream(self.seed, noise.name)
        qnoise = self.model.effect_of(sensor, QuantizationNoise)
        qrng = None if qnoise is None else random_stream(self.seed, qnoise.name)
        deterministic = [e for e in self.model.effects_of(sensor) if e.stage == "deterministic"]
        affine = [e for e in deterministic if e.affine]
        curved = [e for e in deterministic if not e.affine]
        terms = [np.zeros(3), np.zeros((3, 3)), np.zeros((3, 3))]
        for e in affine:
            terms = [total + term for total, term in zip(terms, e.affine_terms(), strict=True)]
        q = self.model.effect_of(sensor, Quantization)
        plain = (
            not curved
            and qnoise is None
            and not self.model.delay_of(sensor).any()
            and self.model.effect_of(sensor, Saturation) is None
            and (q is None or not q.step.any())
        )
        return _Sensor(sensor, processes, noise, rng, qnoise, qrng, affine=affine, curved=curved,
                       terms=(terms[0], terms[1], terms[2]), plain=plain)  # fmt: skip

    def margin(self) -> int:
        """Intervals of context kept on each side of those written: the reconstruction's neighbours,
        and the largest delay's reach; none where every sensor is plain (each interval's reading is
        its own increments', its random biases' and its noise's)."""
        return self._margin

    def _context(self) -> int:
        """:meth:`margin`, from the model (fixed for the stream's life)."""
        if all(state.plain for state in self._sensors.values()):
            return 0
        delay = max(float(np.abs(self.model.delay_of(s)).max()) for s in SENSORS)
        return math.ceil(delay / self.dt_nominal) + 3

    def push(self, imu: ImuIncrements, temp: Array | None = None) -> ImuIncrements:
        """Take the next chunk (``temp`` at ``imu.t``, °C, if the model needs it); return the readings
        of the intervals now complete (possibly none)."""
        if self._finished:
            raise ValueError("the stream is finished")
        if len(imu.t) < 2:
            return self._empty()
        if self._t is not None:
            if imu.t[0] != self._t[-1]:
                raise ValueError(f"chunks must follow each other: {imu.t[0]} after {self._t[-1]}")
            if (temp is None) != (self._temp is None):
                raise ValueError("give the temperature with every chunk or with none")
        if self._t is None or len(self._t) == 1:  # nothing buffered but the last time: no copy
            self._t = np.asarray(imu.t, dtype=float)
            self._inc = {"gyro": imu.dtheta_b, "accel": imu.dv_b}
            self._temp = None if temp is None else np.asarray(temp, dtype=float)
        else:
            self._t = np.concatenate([self._t, imu.t[1:]])
            self._inc = {"gyro": np.vstack([self._inc["gyro"], imu.dtheta_b]),
                         "accel": np.vstack([self._inc["accel"], imu.dv_b])}  # fmt: skip
            if temp is not None and self._temp is not None:
                self._temp = np.concatenate([self._temp, np.asarray(temp, dtype=float)[1:]])
        return self._write(len(self._t) - 1 - self.margin())

    def finish(self) -> ImuIncrements:
        """The readings of every interval not yet written."""
        if self._t is None:
            self._finished = True
            return self._empty()
        out = self._write(len(self._t) - 1)
        self._finished = True
        return out

    def _empty(self) -> ImuIncrements:
        t = np.zeros(0) if self._t is None else self._t[self._written : self._written + 1]
        return ImuIncrements(t=t, dtheta_b=np.zeros((0, 3)), dv_b=np.zeros((0, 3)))

    def _write(self, end: int) -> ImuIncrements:
        """Readings of the buffer's intervals ``written .. end``, then the buffer trimmed to the context
        the next ones need."""
        assert self._t is not None
        lo, hi = self._written, max(end, self._written)
        if hi == lo:
            return self._empty()
        nodes = _NodeInputs(self._t, self._inc, self._temp if self._needs_temp else None)
        out = [self._sensor_readings(s, lo, hi, nodes) for s in SENSORS]
        t_out = self._t[lo : hi + 1]
        self._written = hi
        self._trim()
        return ImuIncrements(t=t_out, dtheta_b=out[0], dv_b=out[1])

    def _trim(self) -> None:
        """Drop the intervals no later one needs, adding them to each sensor's running integral in
        order (so it is the same sum as one long cumulative sum's)."""
        assert self._t is not None
        drop = max(0, self._written - self.margin())
        if drop == 0:
            return
        for sensor, inc in self._inc.items():
            state = self._sensors[sensor]
            if self._delayed:  # only a delayed channel reads the running integral
                state.cum = _running_sum(state.cum, inc[:drop])
            self._inc[sensor] = inc[drop:]
        self._t = self._t[drop:]
        if self._temp is not None:
            self._temp = self._temp[drop:]
        self._written -= drop

    # ------------------------------------------------------------------------------------------

    def _sensor_readings(self, sensor: str, lo: int, hi: int, node_inputs: _NodeInputs) -> Array:
        """One sensor's readings of the buffer's intervals ``lo .. hi``, the buffer as context."""
        assert self._t is not None
        model, state = self.model, self._sensors[sensor]
        t, ideal = self._t, self._inc[sensor]
        dt = node_inputs.dt
        rows = slice(lo, hi)
        n_out = hi - lo
        bias = self._bias(state, t[lo : hi + 1], lambda: node_inputs.uniform(lo, hi))  # at their ends
        if state.plain:  # the general path's arithmetic, in one pass and without its temporaries
            z, density = np.zeros((0, 3)), np.zeros(3)
            if state.noise is not None and state.noise_rng is not None:
                z, density = state.noise_rng.standard_normal((n_out, 3)), state.noise.density
            out = np.empty((n_out, 3))
            _plain_kernel(ideal[rows], node_inputs.inc["accel"][rows], dt[rows], *state.terms, bias,
                          density, z, True, out)  # fmt: skip
            return out
        noise_rate = np.zeros((n_out, 3))
        if state.noise is not None and state.noise_rng is not None:
            # White noise as each interval's mean rate: density / sqrt(dt) per interval.
            z = state.noise_rng.standard_normal((n_out, 3))
            noise_rate = rowwise.row_over_col(state.noise.density, np.sqrt(dt[rows])) * z
        if state.qnoise is not None and state.qnoise_rng is not None:
            noise_rate = noise_rate + self._quantization_noise(state, n_out) / dt[rows][:, None]
        sat = model.effect_of(sensor, Saturation)
        delay = model.delay_of(sensor)
        total = np.empty((n_out, 3))
        step = dt[rows]
        half_step = 0.5 * step
        for d in np.unique(delay):
            cols = delay == d
            shifted = self._shifted(ideal, t, float(d), state.cum)[rows] if d else ideal[rows]
            if sat is None:
                # The ideal part stays exact; only the errors come from the reconstruction.
                errors = self._integrated_errors(state, rows, float(d), node_inputs)
                total[:, cols] = (shifted + errors)[:, cols]
                continue
            # Saturation clips the whole reading (input, errors, biases, noise) at the nodes.
            part = np.zeros((n_out, 3))
            for j, when in enumerate(node_inputs.nodes):
                inputs = node_inputs(j, float(d))
                at = when[rows]
                b = np.column_stack([np.interp(at, t[lo : hi + 1], bias[:, i]) for i in range(3)])
                u = inputs.of(sensor)[rows]
                rate = u + model.deterministic_error(sensor, inputs)[rows] + b + noise_rate
                part += rowwise.mul_col(np.clip(rate, -sat.limit, sat.limit), half_step)
            total[:, cols] = part[:, cols]
        if sat is None:
            total = total + rowwise.mul_col(0.5 * (bias[:-1] + bias[1:]) + noise_rate, step)
        q = model.effect_of(sensor, Quantization)
        if q is not None and (q.step > 0).any():
            total = self._quantized(state, total, q.step * self.dt_nominal)
        return total

    def _integrated_errors(self, state: _Sensor, rows: slice, d: float, node_inputs: _NodeInputs) -> Array:
        """The sensor's deterministic errors integrated over the intervals ``rows`` of the buffer, its
        input delayed by ``d`` s.

        The quadratic through the neighbours' means keeps each interval's mean, and the two-point Gauss
        rule is exact for it: an affine effect's integral is therefore the effect applied to the ideal
        increments, ``b Δt + M Δu + K Δv`` (:meth:`sins.imu.vocabulary.Effect.affine_terms`), with no
        reconstruction. Delayed inputs and the other effects take the two Gauss nodes of the
        reconstructed rate.
        """
        model, step = self.model, node_inputs.dt[rows]
        at_nodes = state.curved if d == 0.0 else state.affine + state.curved
        part = np.zeros((len(step), 3))
        if d == 0.0 and state.affine:
            own, dv = node_inputs.inc[state.name][rows], node_inputs.inc["accel"][rows]
            none = np.zeros((0, 3))
            _plain_kernel(own, dv, step, *state.terms, none, np.zeros(3), none, False, part)
        if at_nodes:
            half_step = 0.5 * step
            for j in range(len(_NODES)):
                err = model.deterministic_error(state.name, node_inputs(j, d), at_nodes)[rows]
                part += rowwise.mul_col(err, half_step)
        return part

    def _bias(self, state: _Sensor, t: Array, uniform: Callable[[], bool]) -> Array:
        """The random biases' sum at ``t`` (the written intervals' ends), each process continued."""
        total: Array | None = None
        dt = np.diff(t)
        for p in state.processes:
            values = np.empty((len(t), 3))
            e = p.effect
            if isinstance(e, BiasInstability):
                values[0] = e.sigma * p.rng.standard_normal(3) if p.value is None else p.value
                xi = p.rng.standard_normal((len(dt), 3))
                if uniform():  # one coefficient a channel: no exponential per interval
                    a, phi = np.exp(-self.dt_nominal / e.tau), np.zeros((0, 3))
                else:
                    a, phi = np.zeros(0), np.exp(rowwise.col_over_row(-dt, e.tau))
                _gauss_markov_kernel(phi, np.ascontiguousarray(e.sigma), xi, a, values)
            else:
                start = np.zeros(3) if p.value is None else p.value
                steps = rowwise.outer(np.sqrt(dt), e.density) * p.rng.standard_normal((len(dt), 3))
                values = np.cumsum(np.vstack([start, steps]), axis=0)
            p.value = values[-1].copy()
            total = values if total is None else total + values
        return np.zeros((len(t), 3)) if total is None else total

    @staticmethod
    def _shifted(inc: Array, t: Array, delay: float, cum0: Array) -> Array:
        """Increments of the input delayed by ``delay``: differences of the running integral at
        ``t - delay``, cubic Hermite between samples with the reconstructed rates as slopes; the
        integral starts from ``cum0``, the sum of every interval before the buffer."""
        cum = np.cumsum(np.vstack([cum0, inc]), axis=0)
        rate_at = _reconstruct(inc / np.diff(t)[:, None], t, t)[0]
        shifted = cubic_hermite(t, cum, rate_at, np.clip(t - delay, t[0], t[-1]))
        return np.diff(shifted, axis=0)

    @staticmethod
    def _quantization_noise(state: _Sensor, n: int) -> Array:
        """The next ``n`` increments' share of the quantization noise (n, 3): ``e_k − e_{k−1}``, the
        errors of the integrated output continued from the last chunk's (the first drawn once)."""
        assert state.qnoise is not None and state.qnoise_rng is not None
        if state.qnoise_last is None:
            state.qnoise_last = state.qnoise.angle_errors(state.qnoise_rng, 1)[0]
        e = np.vstack([state.qnoise_last, state.qnoise.angle_errors(state.qnoise_rng, n)])
        state.qnoise_last = e[-1].copy()
        return np.diff(e, axis=0)

    @staticmethod
    def _quantized(state: _Sensor, inc: Array, step: Array) -> Array:
        """Increments quantised with the remainder carried: the differences of the rounded running sum,
        continued from the last chunk's."""
        active = step > 0
        safe = np.where(active, step, 1.0)
        running = np.cumsum(np.vstack([state.quant_sum, inc]), axis=0)[1:]
        rounded = np.round(running / safe) * safe
        out = np.diff(np.vstack([state.quant_out, rounded]), axis=0)
        state.quant_sum, state.quant_out = running[-1].copy(), rounded[-1].copy()
        return np.where(active, out, inc)


@numba.njit(cache=True, nogil=True)
def _gauss_markov_kernel(phi: Array, sigma: Array, xi: Array, a: Array, out: Array) -> None:
    """``out[k] = φ out[k-1] + σ sqrt(1 - φ²) ξ[k-1]`` in place from ``out[0]``, per channel.

    With one coefficient per channel ``a`` (3,) (regular samples) ``φ = a`` throughout and ``phi`` is not
    read; else (``a`` empty) each interval's ``phi`` (n - 1, 3). The arithmetic of the linear filter
    (``scipy.signal.lfilter``) of :meth:`sins.imu.effects.BiasInstability.process`, to the last bit
    (``tests/test_stream.py``).
    """
    if a.shape[0] > 0:
        drive = sigma * np.sqrt(1.0 - a * a)
        a0, a1, a2, d0, d1, d2 = a[0], a[1], a[2], drive[0], drive[1], drive[2]
        v0, v1, v2 = out[0, 0], out[0, 1], out[0, 2]  # the state in registers, not read back
        for k in range(1, out.shape[0]):
            v0 = a0 * v0 + d0 * xi[k - 1, 0]
            v1 = a1 * v1 + d1 * xi[k - 1, 1]
            v2 = a2 * v2 + d2 * xi[k - 1, 2]
            out[k, 0], out[k, 1], out[k, 2] = v0, v1, v2
        return
    for k in range(1, out.shape[0]):
        for i in range(3):
            p = phi[k - 1, i]
            out[k, i] = p * out[k - 1, i] + sigma[i] * np.sqrt(1.0 - p * p) * xi[k - 1, i]


# "contract" fuses multiply-adds, which changes only last bits (as in sins.nav.strapdown's kernel).
@numba.njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract"})
def _plain_kernel(
    own: Array, dv: Array, step: Array, b: Array, m: Array, k: Array, bias: Array, density: Array,
    z: Array, with_input: bool, out: Array,
) -> None:  # fmt: skip
    """Readings of intervals of length ``step`` (n,) from the ideal increments ``own`` and the
    accelerometers' ``dv`` (n, 3): ``Δu + (b Δt + M Δu + K Δv) + (b̄ + σ/√Δt z) Δt``, with ``b̄`` the
    mean of the random bias ``bias`` (n + 1, 3) at the interval's ends and ``σ`` the white noise
    ``density`` driven by ``z`` (n, 3); ``bias`` or ``z`` with no rows: none; not ``with_input``:
    the errors alone, without ``Δu``."""
    random, noisy = bias.shape[0] > 0, z.shape[0] > 0
    for r in range(own.shape[0]):
        dt = step[r]
        per_root_dt = 1.0 / np.sqrt(dt) if noisy else 0.0  # one division a row, not one a channel
        o0, o1, o2, d0, d1, d2 = own[r, 0], own[r, 1], own[r, 2], dv[r, 0], dv[r, 1], dv[r, 2]
        for i in range(3):
            error = b[i] * dt + (m[i, 0] * o0 + m[i, 1] * o1 + m[i, 2] * o2)
            error += k[i, 0] * d0 + k[i, 1] * d1 + k[i, 2] * d2
            rate = 0.5 * (bias[r, i] + bias[r + 1, i]) if random else 0.0
            if noisy:
                rate += density[i] * per_root_dt * z[r, i]
            out[r, i] = (own[r, i] + error if with_input else error) + rate * dt


@numba.njit(cache=True, nogil=True)
def _running_sum(start: Array, rows: Array) -> Array:
    """``start`` plus every row of ``rows`` (m, 3), added in order (a cumulative sum's last row)."""
    out = start.copy()
    for k in range(rows.shape[0]):
        for i in range(3):
            out[i] = out[i] + rows[k, i]
    return out


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
    """:func:`_reconstruct` at local coordinate ``s`` of every interval (by index, no search)."""
    value, rate = np.empty_like(mean), np.empty_like(mean)
    _reconstruct_own_kernel(np.ascontiguousarray(mean), np.ascontiguousarray(dt), s, value, rate)
    return value, rate


@numba.njit(cache=True, nogil=True)
def _reconstruct_own_kernel(mean: Array, dt: Array, s: float, value: Array, rate: Array) -> None:
    """The quadratic through interval ``k``'s neighbours' means (one-sided at the two ends), at ``s``;
    the arithmetic of the array expressions it replaces, to the last bit (``tests/test_stream.py``)."""
    n = mean.shape[0]
    q = s * s - 1.0 / 12.0
    for k in range(n):
        prev, nxt = max(k - 1, 0), min(k + 1, n - 1)
        end = n > 1 and (k == 0 or k == n - 1)
        for i in range(3):
            m, mp, mn = mean[k, i], mean[prev, i], mean[nxt, i]
            slope = mn - mp if end else 0.5 * (mn - mp)
            curve = 0.0 if end else 0.5 * (mn - 2.0 * m + mp)
            value[k, i] = m + slope * s + curve * q
            rate[k, i] = (slope + 2.0 * curve * s) / dt[k]


__all__ = [
    "IncrementStream",
]
