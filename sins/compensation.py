"""Compensation strategies: fitted on calibration data, they remove the IMU's errors before integration.

Every strategy follows one interface (scikit-learn style):

* ``fit(data)`` on a :class:`~sins.series.CalibrationData` returns the
  strategy; what it learned sits in attributes ending in ``_``;
* ``correct(gyro, accel, temp=None)`` maps readings (rate form, SI) to
  estimates of the true inputs; ``correct_rates`` and ``correct_increments``
  apply it to whole IMU streams (increments through their mean rate over each
  interval, which is exact for the linear strategies);
* ``predict_error(gyro, accel, temp)`` is ``readings - correct(readings)``, the
  error each channel is believed to carry.

Strategies are made by name with :func:`make` (variants in :data:`VARIANTS`) and saved to a
versioned JSON file with :func:`save` / :func:`load`; a file from another
format version is refused with a clear message.
"""

from __future__ import annotations

import os
from abc import ABC, abstractmethod
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from sins import __version__, calibration, io
from sins.errors import SinsInputError
from sins.imu import CHANNELS, ImuModel
from sins.series import CalibrationData, ImuIncrements, ImuRates

Array = NDArray[np.float64]

#: Version of the model file format; bump it when the saved state changes meaning.
FORMAT_VERSION = 2
FORMAT_NAME = "sins.compensation"


class Strategy(ABC):
    """A compensation strategy (see the module docstring)."""

    name: ClassVar[str] = ""

    @abstractmethod
    def fit(self, data: CalibrationData) -> Strategy:
        """Learn from calibration data; returns ``self``."""

    @abstractmethod
    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """Estimated true angular rate and specific force (n, 3) from readings (n, 3)."""

    def predict_error(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """The error believed to be in each reading: ``readings - correct(readings)``."""
        w, f = self.correct(gyro, accel, temp)
        return gyro - w, accel - f

    def correct_rates(self, rates: ImuRates, temp: Array | None = None) -> ImuRates:
        w, f = self.correct(rates.omega_ib_b, rates.f_ib_b, temp)
        return ImuRates(t=rates.t, omega_ib_b=w, f_ib_b=f)

    def correct_increments(self, imu: ImuIncrements, temp: Array | None = None) -> ImuIncrements:
        """Correct increments through their mean rate over each interval (``temp`` at ``imu.t``)."""
        dt = np.diff(imu.t)[:, None]
        mid_temp = None if temp is None else 0.5 * (np.asarray(temp)[:-1] + np.asarray(temp)[1:])
        w, f = self.correct(imu.dtheta_b / dt, imu.dv_b / dt, mid_temp)
        return ImuIncrements(t=imu.t, dtheta_b=w * dt, dv_b=f * dt)

    def get_state(self) -> dict[str, Any]:
        """What :func:`save` writes: the fitted attributes, as plain lists and numbers."""
        return {k: _plain(v) for k, v in vars(self).items() if k.endswith("_")}

    def set_state(self, state: dict[str, Any]) -> None:
        for k, v in state.items():
            setattr(self, k, np.asarray(v, dtype=float) if isinstance(v, list) else v)

    def params(self) -> dict[str, Any]:
        """Constructor parameters (saved beside the state)."""
        return {}


def _plain(value: Any) -> Any:
    return value.tolist() if isinstance(value, np.ndarray) else value


class NoCompensation(Strategy):
    """Readings taken as they are."""

    name = "none"

    def fit(self, data: CalibrationData) -> NoCompensation:
        return self

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        return gyro, accel


class Oracle(Strategy):
    """Knows the simulated unit's true deterministic error model and inverts it.

    The limit any strategy can reach: what is left is the unit's noise and
    stochastic biases. The inversion solves ``reading = x + e(x)`` by
    fixed-point iteration ``x ← reading - e(x)``, which converges because the
    errors are small against the inputs (each pass gains the error's relative
    size, below 1e-2 for every grade).
    """

    name = "oracle"

    def __init__(self, model: ImuModel | None = None, iterations: int = 6) -> None:
        self.model = model
        self.iterations = iterations

    def fit(self, data: CalibrationData) -> Oracle:
        if self.model is None:
            raise ValueError("the oracle needs the simulated unit's model: Oracle(model)")
        return self

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        from sins.imu import Inputs

        if self.model is None:
            raise ValueError("the oracle needs the simulated unit's model: Oracle(model)")
        w, f = gyro.copy(), accel.copy()
        zero = np.zeros_like(w)
        for _ in range(self.iterations):
            inputs = Inputs(omega=w, f=f, omega_dot=zero, temp=temp)
            w = gyro - self.model.deterministic_error("gyro", inputs)
            f = accel - self.model.deterministic_error("accel", inputs)
        return w, f

    def get_state(self) -> dict[str, Any]:
        raise ValueError("the oracle knows a simulated unit; it cannot be saved as a model file")


class Regression(Strategy):
    """Least squares on the seed paper's 33 coefficients: ``Δω = B0 + Bω + Kn``, ``Δn = A0 + An``.

    ``robust=True`` re-weights residuals with Huber's function (threshold
    ``huber_k`` robust standard deviations, iterated) so that outliers in the
    calibration data do not pull the fit. Corrections invert the linear model
    exactly.
    """

    name = "regression"

    def __init__(self, robust: bool = False, huber_k: float = 1.345, g_sensitivity: bool = True) -> None:
        self.robust = robust
        self.huber_k = huber_k
        self.g_sensitivity = g_sensitivity

    def params(self) -> dict[str, Any]:
        return {"robust": self.robust, "huber_k": self.huber_k, "g_sensitivity": self.g_sensitivity}

    def fit(self, data: CalibrationData) -> Regression:
        weights = _huber_weights(data, self.huber_k, self.g_sensitivity) if self.robust else None
        fit = calibration.fit_seed_model(data, g_sensitivity=self.g_sensitivity, weights=weights)
        self.B0_, self.B_, self.K_, self.A0_, self.A_ = fit.B0, fit.B, fit.K, fit.A0, fit.A
        return self

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        return calibration.invert_seed_model(self.B0_, self.B_, self.K_, self.A0_, self.A_, gyro, accel)


def _huber_weights(data: CalibrationData, k: float, g_sensitivity: bool, passes: int = 5) -> Array:
    """Row weights of iteratively re-weighted least squares with Huber's function.

    Residuals (reading − reference − fitted error) are standardised per channel
    by their median absolute deviation; a row's weight is ``min(1, k/|z|)`` of
    its worst channel, so one corrupted reading discounts the whole sample.
    """
    weights = np.ones(len(data))
    ok = np.isfinite(data.ref_gyro).all(axis=1) & np.isfinite(data.ref_accel).all(axis=1)
    w_ref, n_ref = data.ref_gyro[ok], data.ref_accel[ok]
    for _ in range(passes):
        fit = calibration.fit_seed_model(data, g_sensitivity=g_sensitivity, weights=weights)
        err_g = fit.B0 + w_ref @ fit.B.T + n_ref @ fit.K.T
        err_a = fit.A0 + n_ref @ fit.A.T
        resid = np.hstack([data.gyro[ok] - w_ref - err_g, data.accel[ok] - n_ref - err_a])
        mad = np.median(np.abs(resid - np.median(resid, axis=0)), axis=0) / 0.6745
        z = np.abs(resid) / np.where(mad > 0, mad, 1.0)
        weights = np.ones(len(data))
        weights[ok] = np.minimum(1.0, k / np.maximum(z, 1e-12)).min(axis=1)
    return weights


class ExtendedRegression(Strategy):
    """Least squares with extra regressors a user switches on: squares of the inputs, temperature.

    Each channel's error is linear in ``[1, ω, n]`` plus, with ``squares``,
    ``[ω², n²]`` (element-wise: scale nonlinearity, and the diagonal of g²
    sensitivity) and, with ``temperature`` and temperature in the data,
    ``[T − T0, (T − T0)², (T − T0)·u]`` (temperature bias and scale). Fitted on
    the reference inputs like the seed model; corrections invert it by
    fixed-point iteration ``x ← reading − e(x)``.
    """

    name = "regression_extended"

    def __init__(
        self, squares: bool = True, temperature: bool = True, t0: float = 20.0, iterations: int = 6
    ) -> None:
        self.squares = squares
        self.temperature = temperature
        self.t0 = t0
        self.iterations = iterations

    def params(self) -> dict[str, Any]:
        return {
            "squares": self.squares,
            "temperature": self.temperature,
            "t0": self.t0,
            "iterations": self.iterations,
        }

    def _design(self, w: Array, f: Array, temp: Array | None) -> list[Array]:
        """Per channel, its regressors (n, p): the shared columns and its own temperature-scale term."""
        cols = [np.ones((len(w), 1)), w, f]
        if self.squares:
            cols += [w * w, f * f]
        shared = np.hstack(cols)
        if not self.uses_temp_:
            return [shared] * 6
        if temp is None:
            raise ValueError("this regression was fitted with temperature: give the temperature series")
        d = (np.asarray(temp, dtype=float) - self.t0)[:, None]
        u = np.hstack([w, f])
        return [np.hstack([shared, d, d * d, d * u[:, [i]]]) for i in range(6)]

    def fit(self, data: CalibrationData) -> ExtendedRegression:
        ok = np.isfinite(data.ref_gyro).all(axis=1) & np.isfinite(data.ref_accel).all(axis=1)
        self.uses_temp_ = bool(self.temperature and data.temp is not None)
        temp = None if data.temp is None else data.temp[ok]
        designs = self._design(data.ref_gyro[ok], data.ref_accel[ok], temp)
        errors = np.hstack([data.gyro - data.ref_gyro, data.accel - data.ref_accel])[ok]
        coef = []
        for i, x in enumerate(designs):
            scale = np.sqrt(np.mean(x * x, axis=0))
            scale = np.where(scale > 0, scale, 1.0)
            c, *_ = np.linalg.lstsq(x / scale, errors[:, i], rcond=None)
            coef.append(c / scale)
        self.coef_ = np.array(coef)
        return self

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        w, f = gyro.copy(), accel.copy()
        for _ in range(self.iterations):
            err = np.column_stack([x @ c for x, c in zip(self._design(w, f, temp), self.coef_, strict=True)])
            w, f = gyro - err[:, :3], accel - err[:, 3:]
        return w, f


def strategy_class(name: str) -> type[Strategy]:
    """The class registered under ``name``; the learned ones import torch or minisom only when asked for."""
    if name in ("mlp", "mlp_pure"):
        from sins.mlp import MLP, ResidualMLP

        return ResidualMLP if name == "mlp" else MLP
    if name in ("kohonen", "kohonen_pure"):
        from sins.kohonen import Kohonen, LocalLinearMap

        return LocalLinearMap if name == "kohonen" else Kohonen
    classes: dict[str, type[Strategy]] = {
        "none": NoCompensation, "oracle": Oracle, "regression": Regression,
        "regression_extended": ExtendedRegression,
    }  # fmt: skip
    if name not in classes:
        raise ValueError(f"unknown strategy {name!r} (known: {', '.join(VARIANTS)})")
    return classes[name]


#: Strategy variants by name: (registered class name, constructor parameters).
VARIANTS: dict[str, tuple[str, dict[str, Any]]] = {
    "none": ("none", {}),
    "oracle": ("oracle", {}),
    "regression": ("regression", {}),
    "regression_robust": ("regression", {"robust": True}),
    "regression_extended": ("regression_extended", {}),
    "mlp": ("mlp", {}),
    "mlp_pure": ("mlp_pure", {}),
    "mlp_seed": ("mlp_pure", {"mode": "seed", "hidden": (16,), "alpha": 0.05, "max_epochs": 30}),
    "kohonen": ("kohonen", {}),
    "kohonen_pure": ("kohonen_pure", {}),
}

#: Names a model file may carry (the registered classes that can be fitted).
SAVED_STRATEGIES = ("none", "regression", "regression_extended", "mlp", "mlp_pure", "kohonen", "kohonen_pure")


def make(name: str, **params: Any) -> Strategy:
    """A strategy by variant name (see :data:`VARIANTS`), with parameters overriding the variant's."""
    if name not in VARIANTS:
        raise ValueError(f"unknown strategy {name!r} (known: {', '.join(VARIANTS)})")
    cls_name, defaults = VARIANTS[name]
    return strategy_class(cls_name)(**{**defaults, **params})


# --------------------------------------------------------------------------- model files


def save(strategy: Strategy, path: str | os.PathLike[str]) -> None:
    """Write a fitted strategy to a versioned JSON file (atomically)."""
    doc = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "sins": __version__,
        "strategy": strategy.name,
        "params": strategy.params(),
        "state": strategy.get_state(),
    }
    io.write_json(path, doc)


def load(path: str | os.PathLike[str]) -> Strategy:
    """Read a strategy written by :func:`save`; refuse other formats and versions in one line."""
    path = Path(path)
    doc = io.read_json_document(path, "model file", FORMAT_NAME)
    if doc.get("version") != FORMAT_VERSION:
        raise SinsInputError(
            f"{path}: model file format version {doc.get('version')!r} (written by sins {doc.get('sins')}); "
            f"this sins reads version {FORMAT_VERSION}: fit the model again"
        )
    name = doc.get("strategy")
    if name not in SAVED_STRATEGIES:
        raise SinsInputError(f"{path}: unknown strategy {name!r} (known: {', '.join(SAVED_STRATEGIES)})")
    try:
        strategy = strategy_class(name)(**doc.get("params", {}))
        strategy.set_state(doc.get("state", {}))
    except (TypeError, ValueError, KeyError) as exc:
        raise SinsInputError(f"{path}: malformed {name} model ({exc})") from None
    return strategy


# --------------------------------------------------------------------------- judging on recorded data


def residual_rms(strategy: Strategy, data: CalibrationData) -> dict[str, dict[str, float]]:
    """Per channel, the RMS of reading − reference before and after correction (SI units).

    Rows without a finite reference are left out.
    """
    ok = np.isfinite(data.ref_gyro).all(axis=1) & np.isfinite(data.ref_accel).all(axis=1)
    if not ok.any():
        raise SinsInputError(f"{data.source or 'recording'}: no rows with a reference to judge against")
    temp = None if data.temp is None else data.temp[ok]
    w, f = strategy.correct(data.gyro[ok], data.accel[ok], temp)
    before = np.hstack([data.gyro[ok] - data.ref_gyro[ok], data.accel[ok] - data.ref_accel[ok]])
    after = np.hstack([w - data.ref_gyro[ok], f - data.ref_accel[ok]])
    rms = lambda x: np.sqrt(np.mean(x * x, axis=0))  # noqa: E731
    b, a = rms(before), rms(after)
    return {ch: {"rms_before": float(b[i]), "rms_after": float(a[i])} for i, ch in enumerate(CHANNELS)}
