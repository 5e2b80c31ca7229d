"""Least-squares compensation: the seed paper's linear error model, and an extended one with temperature."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from sins.compensation.base import Array, ParamRange, Strategy, state_array
from sins.core.series import CalibrationData, ImuIncrements
from sins.imu import calibration


class Regression(Strategy):
    """Least squares on the seed paper's 33 coefficients: ``Δω = B0 + Bω + Kn``, ``Δn = A0 + An``.

    ``robust=True`` re-weights residuals with Huber's function (threshold
    ``huber_k`` robust standard deviations, iterated) so that outliers in the
    calibration data do not pull the fit. Corrections invert the linear model
    exactly.
    """

    name = "regression"
    state_keys = (*Strategy.state_keys, "B0_", "B_", "K_", "A0_", "A_")
    #: ``huber_k`` in robust standard deviations: below about 0.1 every row is down-weighted alike.
    param_ranges: ClassVar[dict[str, ParamRange]] = {"huber_k": ParamRange(0, 100, above=True)}

    def __init__(self, robust: bool = False, huber_k: float = 1.345, g_sensitivity: bool = True) -> None:
        self.robust = robust
        self.huber_k = huber_k
        self.g_sensitivity = g_sensitivity

    def kind(self) -> str:
        """``regression_robust`` where Huber-weighted (a subclass keeps its own name)."""
        return "regression_robust" if self.robust is True and self.name == "regression" else self.name

    def fit(self, data: CalibrationData) -> Regression:
        """Fit the seed model by least squares (Huber-weighted if ``robust``), then :meth:`fit_beyond`;
        returns self."""
        weights = _huber_weights(data, self.huber_k, self.g_sensitivity) if self.robust else None
        self.set_fit(calibration.fit_seed_model(data, g_sensitivity=self.g_sensitivity, weights=weights))
        return self.fit_beyond(data)

    def fit_beyond(self, data: CalibrationData) -> Regression:
        """Fit what a subclass adds to the seed model already set (:meth:`set_fit`) on ``data``; returns
        self. ``Regression`` adds nothing; :meth:`fit` is the seed model's fit, then this."""
        return self

    def set_fit(self, fit: calibration.SeedModelFit) -> Regression:
        """Take the coefficients of a seed-model fit made elsewhere (on a real unit's intervals,
        :mod:`sins.compensation.interval_fit`) as this strategy's; returns self."""
        self.B0_, self.B_, self.K_, self.A0_, self.A_ = fit.B0, fit.B, fit.K, fit.A0, fit.A
        return self

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """Invert the fitted seed model exactly (``temp`` unused)."""
        return calibration.invert_seed_model(self.B0_, self.B_, self.K_, self.A0_, self.A_, gyro, accel)

    def check_state(self, state: dict[str, Any]) -> None:
        """The seed model's five coefficient arrays: ``B0_``, ``A0_`` (3,), ``B_``, ``K_``, ``A_`` (3, 3)."""
        super().check_state(state)
        for key in ("B0_", "A0_"):
            state_array(state, key, (3,))
        for key in ("B_", "K_", "A_"):
            state_array(state, key, (3, 3))

    def correct_increments(self, imu: ImuIncrements, temp: Array | None = None) -> ImuIncrements:
        """Invert the seed model on the increments themselves (each sensor read ``time_offset_s_`` later
        first, where the strategy has one): it is affine, so the mean rate's correction times the step is
        the increment's, with no division by the step and product back."""
        imu = self.aligned_increments(imu)  # a time offset fitted against a reference, read first
        dtheta_b, dv_b = calibration.invert_seed_model(
            self.B0_, self.B_, self.K_, self.A0_, self.A_, imu.dtheta_b, imu.dv_b, dt=np.diff(imu.t)
        )
        return ImuIncrements(t=imu.t, dtheta_b=dtheta_b, dv_b=dv_b)


def _huber_weights(data: CalibrationData, k: float, g_sensitivity: bool, passes: int = 5) -> Array:
    """Row weights of iteratively re-weighted least squares with Huber's function.

    Residuals (reading − reference − fitted error) are standardised per channel
    by their median absolute deviation; a row's weight is ``min(1, k/|z|)`` of
    its worst channel, so one corrupted reading discounts the whole sample.
    """
    weights = np.ones(len(data))
    ok = data.has_reference
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


#: The most fixed-point passes an extended regression's inversion makes (6 by default; each pass gains
#: the error's relative size, below 1e-2 for every grade).
MAX_ITERATIONS = 100


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
    state_keys = (*Strategy.state_keys, "uses_temp_", "coef_")
    #: ``t0``, °C: the temperature the thermal terms are taken about.
    param_ranges: ClassVar[dict[str, ParamRange]] = {
        "t0": ParamRange(-273.15, 1000),
        "iterations": ParamRange(1, MAX_ITERATIONS, whole=True),
    }

    def __init__(
        self, squares: bool = True, temperature: bool = True, t0: float = 20.0, iterations: int = 6
    ) -> None:
        self.squares = squares
        self.temperature = temperature
        self.t0 = t0
        self.iterations = iterations

    def check_state(self, state: dict[str, Any]) -> None:
        """``uses_temp_`` a boolean; ``coef_`` (6, p) with the columns of the fitted regressors; at most
        :data:`MAX_ITERATIONS` passes of the inversion."""
        super().check_state(state)
        uses_temp = state.get("uses_temp_", False)
        if not isinstance(uses_temp, bool):
            raise ValueError("state.uses_temp_ must be true or false")
        columns = 7 + 6 * bool(self.squares) + 3 * uses_temp
        state_array(state, "coef_", (6, columns))

    def _shared(self, omega_ib_b: Array, f_ib_b: Array) -> Array:
        """The columns every channel's regressors share (n, k): ``[1, ω, f]`` and, with ``squares``,
        ``[ω², f²]``."""
        cols = [np.ones((len(omega_ib_b), 1)), omega_ib_b, f_ib_b]
        if self.squares:
            cols += [omega_ib_b * omega_ib_b, f_ib_b * f_ib_b]
        return np.hstack(cols)

    def _temp_offset(self, temp: Array | None) -> Array | None:
        """``T − T0`` (n, 1) where the fit used temperature, else None."""
        if not self.uses_temp_:
            return None
        if temp is None:
            raise ValueError("this regression was fitted with temperature: give the temperature series")
        return (np.asarray(temp, dtype=float) - self.t0)[:, None]

    def _design(self, omega_ib_b: Array, f_ib_b: Array, temp: Array | None) -> list[Array]:
        """Per channel, its regressors (n, p): the shared columns and its own temperature-scale term."""
        shared = self._shared(omega_ib_b, f_ib_b)
        d = self._temp_offset(temp)
        if d is None:
            return [shared] * 6
        u = np.hstack([omega_ib_b, f_ib_b])
        return [np.hstack([shared, d, d * d, d * u[:, [i]]]) for i in range(6)]

    def fit(self, data: CalibrationData) -> ExtendedRegression:
        """Fit each channel's coefficients by least squares on the reference inputs; returns self.
        ``ValueError`` where the rows do not determine the seed model (one orientation, no turns), as
        ``regression`` refuses them: its minimum-norm solution there spread the bias over the force's
        columns, and corrected other forces by tens of m/s²."""
        data.check_readings()
        calibration.fit_seed_model(data)  # its refusal, where the rows do not determine it
        ok = data.has_reference
        self.uses_temp_ = bool(self.temperature and data.temp is not None)
        temp = None if data.temp is None else data.temp[ok]
        designs = self._design(data.ref_gyro[ok], data.ref_accel[ok], temp)
        errors = np.hstack([data.gyro - data.ref_gyro, data.accel - data.ref_accel])[ok]
        coef = []
        for i, x in enumerate(designs):
            scale = np.sqrt(np.mean(x * x, axis=0))
            # What the rig does not show takes no coefficient: a column whose RMS is below 1e-9 of the
            # largest (an input that is rounding on this rig, scaled up to unit RMS, took coefficients of
            # 1e15-1e16 that the model-file reader then refuses), and a combination of columns the rig
            # does not tell apart (the minimum-norm solution, singular values below 1e-9 of the largest
            # dropped). The same rule as the term groups' (sins.compensation.terms).
            shown = scale > 1e-9 * scale.max()
            c = np.zeros(x.shape[1])
            c[shown] = np.linalg.lstsq(x[:, shown] / scale[shown], errors[:, i], rcond=1e-9)[0] / scale[shown]
            coef.append(c)
        self.coef_ = np.array(coef)
        return self

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """Invert the fitted model by fixed-point iteration (needs ``temp`` if fitted with it)."""
        omega_ib_b, f_ib_b = gyro.copy(), accel.copy()
        d = self._temp_offset(temp)
        for _ in range(self.iterations):
            err = self._errors(omega_ib_b, f_ib_b, d)
            omega_ib_b, f_ib_b = gyro - err[:, :3], accel - err[:, 3:]
        return omega_ib_b, f_ib_b

    def _errors(self, omega_ib_b: Array, f_ib_b: Array, d: Array | None) -> Array:
        """The fitted errors (n, 6) at inputs ``omega_ib_b``, ``f_ib_b`` and temperature offset ``d`` (n, 1).

        The same sums as ``x @ c`` over :meth:`_design`'s columns, but the columns all channels share go
        through one matrix product instead of six: an hour's correction is 360,000 rows × 6 passes.
        """
        shared = self._shared(omega_ib_b, f_ib_b)
        k = shared.shape[1]
        err = shared @ np.ascontiguousarray(self.coef_[:, :k].T)
        if d is not None:
            u = np.hstack([omega_ib_b, f_ib_b])
            err += d * self.coef_[:, k] + d * d * self.coef_[:, k + 1] + d * u * self.coef_[:, k + 2]
        return err


__all__ = [
    "MAX_ITERATIONS",
    "ExtendedRegression",
    "Regression",
]
