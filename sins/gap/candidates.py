"""The gap diagnosis's candidates: every library effect beyond the baseline, and what they are built from.

The model of a channel's reading error ``e = reading − reference`` starts as the baseline (the seed
model's bias, scale/misalignment and g-sensitivity rows, :func:`baseline_columns`, plus white noise).
Every library effect not in the model is a candidate (:data:`CANDIDATES`), of one of four kinds
(how the channel model holds and fits each: :mod:`sins.gap.channel`):

- *regressors* (scale nonlinearity and asymmetry, g² sensitivity, temperature bias and scale, size
  effect): columns added to the channel's least-squares fit, built from the reference inputs of every
  row (:class:`ReferenceInputs`; :func:`regressors_of` gives them);
- *delay* (time offset): the reading is the reference at ``t − τ`` (:meth:`ReferenceInputs.lag`);
- *processes* (bias instability, rate random walk): a random bias under the white noise; a sensor's
  model holds one at most (:data:`PROCESSES`);
- *output maps* (quantization, saturation): a map of the reading; one at most (:data:`OUTPUTS`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PPoly

from sins.imu import BASELINE, EFFECT_NAMES
from sins.imu.model import hermite_slopes, lever_arm_acceleration
from sins.nav.earth import G0
from sins.series import CalibrationData

Array = NDArray[np.float64]

#: The random-bias candidates' kinds: a sensor's model has at most one.
PROCESSES = ("bias_instability", "rate_random_walk")
#: The output-map candidates' kinds: a sensor's model has at most one.
OUTPUTS = ("quantization", "saturation")


@dataclass(frozen=True)
class Candidate:
    """One library effect as the diagnosis sees it: its name, its channels and its kind."""

    name: str
    sensor: str
    kind: str  # "regressors" | "delay" | "process" | "output"
    columns: Callable[[ReferenceInputs, int], Array] | None = None  # (n, k) extra regressors of axis i


@dataclass(frozen=True, eq=False)
class ReferenceInputs:
    """The reference inputs of every row, and what the regressors and the delay are built from.

    Attributes
    ----------
    t : (n,) s
    omega_ib_b, f_ib_b : (n, 3) the reference angular rate (rad/s) and specific force (m/s²)
    omega_dot_b : (n, 3) the reference's angular acceleration, rad/s² (central differences)
    u_rate : per sensor, (n, 3) the rate of change of its reference (central differences)
    temp : (n,) °C, or None
    step_s : the median sampling step, s
    splines : per sensor and axis, the cubic Hermite curve of its reference through the rows (for
        :meth:`lag`; see :func:`kinked_hermite`)
    """

    t: Array
    omega_ib_b: Array
    f_ib_b: Array
    omega_dot_b: Array
    u_rate: dict[str, Array]
    temp: Array | None
    step_s: float
    splines: dict[tuple[str, int], PPoly]

    def of(self, sensor: str) -> Array:
        """The reference ``sensor`` measures: ``omega`` for "gyro", ``f`` for "accel"."""
        return self.omega_ib_b if sensor == "gyro" else self.f_ib_b

    def lag(self, sensor: str, axis: int, delay_s: float) -> Array:
        """``u(t − τ) − u(t)`` of the reference ``u`` of one axis: cubic Hermite between the rows
        (:func:`kinked_hermite`), held at the ends.

        The curve is a scipy ``PPoly`` (:attr:`splines`), not :func:`sins.imu.model.cubic_hermite`,
        which delays the simulated inputs: the two agree to the last few bits only where both take
        the central slopes.
        """
        u = self.of(sensor)[:, axis]
        when = np.clip(self.t - delay_s, self.t[0], self.t[-1])
        return np.asarray(self.splines[sensor, axis](when)) - u


def reference_inputs(data: CalibrationData) -> ReferenceInputs:
    """The reference inputs of every row of ``data``, their rates of change and their splines."""
    t = data.t
    grad = (lambda a: np.gradient(a, t, axis=0)) if len(t) > 2 else np.zeros_like
    u_rate = {"gyro": grad(data.ref_gyro), "accel": grad(data.ref_accel)}
    reference = {"gyro": data.ref_gyro, "accel": data.ref_accel}
    return ReferenceInputs(
        t=t,
        omega_ib_b=data.ref_gyro,
        f_ib_b=data.ref_accel,
        omega_dot_b=grad(data.ref_gyro),
        u_rate=u_rate,
        temp=data.temp,
        step_s=float(np.median(np.diff(t))),
        splines={
            (sensor, axis): kinked_hermite(t, reference[sensor][:, axis], u_rate[sensor][:, axis])
            for sensor in ("gyro", "accel")
            for axis in range(3)
        },
    )


def kinked_hermite(t: Array, u: Array, central: Array) -> PPoly:
    """The cubic Hermite curve through ``(t, u)`` with the slopes of
    :func:`sins.imu.model.hermite_slopes` (central, but one-sided on each side of a kink), as a
    scipy ``PPoly``: the curve the simulator delays its rate samples along, so that a delay is
    diagnosed on the curve it was made on. Where no row is a kink it is scipy's
    ``CubicHermiteSpline`` with the central slopes, to the last bit (the same coefficients)."""
    n = len(t)
    right, left = hermite_slopes(t, u[:, None], central[:, None])
    right, left = right[:, 0], left[:, 0]
    dx = np.diff(t)
    slope = np.diff(u) / dx
    # As scipy's CubicHermiteSpline builds its coefficients, with a slope of each side.
    tt = (right[:-1] + left[1:] - 2 * slope) / dx
    c = np.empty((4, n - 1))
    c[0] = tt / dx
    c[1] = (slope - right[:-1]) / dx - tt
    c[2] = right[:-1]
    c[3] = u[:-1]
    return PPoly(c, t)


def baseline_columns(sensor: str, omega: Array, f: Array) -> Array:
    """The baseline's regressors of one channel: bias and scale/misalignment, and the gyro's g-sensitivity."""
    u = omega if sensor == "gyro" else f
    base = [np.ones(len(u)), u[:, 0], u[:, 1], u[:, 2]]
    if sensor == "gyro":
        base += [f[:, 0], f[:, 1], f[:, 2]]
    return np.stack(base, axis=1)


def _size_columns(x: ReferenceInputs, i: int) -> Array:
    """Accelerometer ``i``'s reading of a unit lever arm along each body axis: the size effect's
    three coefficients are its lever arm's components (:class:`sins.imu.SizeEffect`)."""
    return np.stack([lever_arm_acceleration(x.omega_ib_b, x.omega_dot_b, r)[:, i] for r in np.eye(3)], axis=1)


def _g2_columns(x: ReferenceInputs, i: int) -> Array:
    f = x.f_ib_b / G0  # in g: keeps the columns near the others' size
    return np.stack([f[:, j] * f[:, k] for j in range(3) for k in range(j, 3)], axis=1)


def _temp(x: ReferenceInputs) -> Array:
    assert x.temp is not None
    return x.temp - float(np.mean(x.temp))


def _candidates(sensor: str) -> list[Candidate]:
    def own(fn: Callable[[Array], Array]) -> Callable[[ReferenceInputs, int], Array]:
        return lambda x, i: fn(x.of(sensor)[:, i])[:, None]

    out = [
        Candidate(f"{sensor}.scale_nonlinearity", sensor, "regressors", own(np.square)),
        Candidate(f"{sensor}.scale_asymmetry", sensor, "regressors", own(np.abs)),
        Candidate(
            f"{sensor}.temperature_bias",
            sensor,
            "regressors",
            lambda x, i: np.stack([_temp(x), _temp(x) ** 2], axis=1),
        ),
        Candidate(
            f"{sensor}.temperature_scale",
            sensor,
            "regressors",
            lambda x, i: (_temp(x) * x.of(sensor)[:, i])[:, None],
        ),
        Candidate(f"{sensor}.time_offset", sensor, "delay"),
        Candidate(f"{sensor}.bias_instability", sensor, "process"),
        Candidate(f"{sensor}.rate_random_walk", sensor, "process"),
        Candidate(f"{sensor}.quantization", sensor, "output"),
        Candidate(f"{sensor}.saturation", sensor, "output"),
    ]
    if sensor == "gyro":
        out.append(Candidate("gyro.g2_sensitivity", "gyro", "regressors", _g2_columns))
    else:
        out.append(Candidate("accel.size_effect", "accel", "regressors", _size_columns))
    return out


#: Library effects the diagnosis does not test: the IEEE quantization term's white noise of the integrated
#: output is noise beside the baseline's white noise, which the channel model takes as it comes
#: (``sins characterise`` measures it from the Allan curve); a model that holds it is diagnosed as without.
NOT_CANDIDATES = ("gyro.quantization_noise", "accel.quantization_noise")
#: Every candidate the diagnosis knows, by effect name (every library effect beyond the baseline).
CANDIDATES: dict[str, Candidate] = {c.name: c for s in ("gyro", "accel") for c in _candidates(s)}
assert set(CANDIDATES) == set(EFFECT_NAMES) - set(BASELINE) - {"gyro.bias", "accel.bias"} - set(
    NOT_CANDIDATES
)


def regressors_of(name: str, data: CalibrationData) -> list[Array]:
    """The columns the regressor candidate ``name`` adds to each of its sensor's three channels.

    What the diagnosis fits beside the baseline's columns; exposed for oracles that ask what a
    candidate could absorb (``tools/bench_gap.py``).
    """
    cand = CANDIDATES.get(name)
    if cand is None or cand.columns is None:
        raise ValueError(f"{name!r} is not a regressor candidate")
    if "temperature" in name and data.temp is None:
        where = data.source or "the recording"
        raise ValueError(f"{name!r} needs a temperature column, and {where} has none")
    x = reference_inputs(data)
    return [cand.columns(x, i) for i in range(3)]


__all__ = [
    "CANDIDATES",
    "NOT_CANDIDATES",
    "OUTPUTS",
    "PROCESSES",
    "Candidate",
    "ReferenceInputs",
    "baseline_columns",
    "kinked_hermite",
    "reference_inputs",
    "regressors_of",
]
