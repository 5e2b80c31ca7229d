"""The compensation interface: what every strategy does, and how one is judged on recorded data.

Every strategy follows one interface (scikit-learn style):

* ``fit(data)`` on a :class:`~sins.core.series.CalibrationData` returns the
  strategy; what it learned sits in attributes ending in ``_``, and a refit starts
  from none of them;
* ``correct(gyro, accel, temp=None)`` maps readings (rate form, SI) to
  estimates of the true inputs; ``correct_rates`` and ``correct_increments``
  apply it to whole IMU streams (increments through their mean rate over each
  interval, which is exact for the linear strategies);
* ``predict_error(gyro, accel, temp)`` is ``readings - correct(readings)``, the
  error each channel is believed to carry.

A strategy fitted against a real unit's reference may also carry ``time_offset_s_``: how late the gyro
and the accelerometer read (s, (2,); a filter's delay). ``correct_rates`` and ``correct_increments``,
which see whole streams, read each sensor that much later before correcting; ``correct``, sample by
sample, cannot and does not.

The strategies themselves live in the modules beside this one; :mod:`sins.compensation.registry` makes
them by name and keeps their model files.
"""

from __future__ import annotations

import functools
import inspect
import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from sins.core import rowwise
from sins.core.series import CalibrationData, ImuIncrements, ImuRates
from sins.errors import SinsInputError
from sins.imu import CHANNELS, ImuModel, calibration
from sins.io.documents import printable

Array = NDArray[np.float64]


def _fresh_fit(fit: Callable[..., Any]) -> Callable[..., Any]:
    """``fit`` that starts from nothing learned, as scikit-learn's estimators do: every attribute ending in
    ``_`` is dropped first, so that a refit keeps none of an earlier fit's (a model fitted against a
    trajectory, then on a rig, had kept its time offsets, bias rule and provenance: 800 °/h of gyro
    correction a fresh fit did not make). Only the outermost call drops them (a fit may call another),
    and data of another type is refused by name, not by an attribute missing deep inside."""

    @functools.wraps(fit)
    def fresh(self: Strategy, data: Any, *args: Any, **kwargs: Any) -> Any:
        if self.__dict__.get("_fitting"):
            return fit(self, data, *args, **kwargs)
        if not isinstance(data, CalibrationData):
            raise TypeError(
                f"{type(self).__name__}.fit takes CalibrationData (a rig's rows, or a recording's per-sample "
                f"references: Recording.reference_inputs()[0]), not {type(data).__name__}"
            )
        self.check_params()  # a max_epochs of -3 is refused here, not by an empty loop's missing loss
        for name in [n for n in vars(self) if n.endswith("_") and not n.startswith("_")]:
            delattr(self, name)
        self.__dict__["_fitting"] = True
        try:
            return fit(self, data, *args, **kwargs)
        finally:
            del self.__dict__["_fitting"]

    return fresh


def _shaped_correct(correct: Callable[..., Any]) -> Callable[..., Any]:
    """``correct`` that refuses readings of another shape in one line, whatever the strategy (some had
    answered (n, 2) readings with numpy's broadcasting error, or a single reading with an axis error)."""

    @functools.wraps(correct)
    def shaped(self: Strategy, gyro: Array, accel: Array, temp: Array | None = None) -> Any:
        g, a = np.shape(gyro), np.shape(accel)
        if len(g) != 2 or g[1] != 3 or a != g:
            raise ValueError(f"gyro and accel must both be (n, 3), got {g} and {a}")
        if temp is not None and np.shape(temp) != (g[0],):
            raise ValueError(f"temp must be ({g[0]},), got {np.shape(temp)}")
        omega_ib_b, f_ib_b = correct(self, gyro, accel, temp)
        seed = vars(self).get("accel_seed_")
        if seed is not None:
            # The seed model's accelerometer (Strategy.accel_seed_), inverted as least squares inverts it.
            zeros = np.zeros((3, 3))
            a0, a_m = np.asarray(seed[0], dtype=float), np.asarray(seed[1:], dtype=float)
            f_ib_b = calibration.invert_seed_model(zeros[0], zeros, zeros, a0, a_m, gyro, accel)[1]
        whole = vars(self).get("gyro_seed_")
        if whole is not None:  # the seed model's gyro (Strategy.gyro_seed_): least squares' own correction
            omega_ib_b = calibration.invert_seed_model(*seed_arrays(whole), gyro, accel)[0]
        return omega_ib_b, f_ib_b

    return shaped


def seed_arrays(rows: Array) -> tuple[Array, Array, Array, Array, Array]:
    """The seed model's ``B0, B, K, A0, A`` from its rows ``[B0; B; K; A0; A]`` (11, 3), as
    :attr:`Strategy.gyro_seed_` holds them."""
    m = np.asarray(rows, dtype=float)
    return m[0], m[1:4], m[4:7], m[7], m[8:11]


class NotFittedError(ValueError, AttributeError):
    """A strategy used before :meth:`Strategy.fit` (scikit-learn's ``NotFittedError``: an AttributeError
    too, so ``getattr(strategy, "fitted_on_", None)`` keeps its default)."""


class Strategy(ABC):
    """A compensation strategy (see the module docstring)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "fit" in cls.__dict__:
            cls.fit = _fresh_fit(cls.__dict__["fit"])  # type: ignore[method-assign]
        if "correct" in cls.__dict__:
            cls.correct = _shaped_correct(cls.__dict__["correct"])  # type: ignore[method-assign]

    def __getattr__(self, name: str) -> Any:
        # Called only where the attribute is missing: a learned one (ending in "_") before fit said so,
        # not an AttributeError deep inside a correction ("'Regression' object has no attribute 'B0_'").
        if name.endswith("_") and not name.startswith("__"):
            learned = sorted(k for k in vars(self) if k.endswith("_") and not k.startswith("_"))
            if learned:  # fitted: a name it never learns (coef_) had been "not fitted: call fit() first"
                said = ", ".join(learned)
                raise AttributeError(f"{type(self).__name__} learned no {name} (it learned: {said})")
            raise NotFittedError(f"{type(self).__name__} is not fitted: call fit() first (it sets {name})")
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    name: ClassVar[str] = ""
    #: Each numeric constructor parameter's range (every element's, for a list): what
    #: :meth:`check_params` holds it to. A subclass extends its parent's.
    param_ranges: ClassVar[dict[str, ParamRange]] = {}
    #: The fitted attributes a model file of it may hold (:meth:`check_state` refuses any other, so that a
    #: misspelt ``unit_bias_`` is not loaded and then ignored). A subclass extends its parent's.
    state_keys: ClassVar[tuple[str, ...]] = ("fitted_on_", "time_offset_s_", "unit_bias_")
    #: The variant it was made as (``regression_robust`` is a ``regression``; :func:`make` sets it).
    variant: str = ""
    #: How late the gyro and the accelerometer read, s (see the module docstring); set by a fit against a
    #: real unit's reference, absent otherwise.
    time_offset_s_: Array
    #: What the strategy was fitted on, where a real unit's recording says: ``sensor``, ``rate_hz``,
    #: ``reference``; absent otherwise.
    fitted_on_: dict[str, Any]
    #: What the strategy does about a new recording's gyro bias, where it was fitted on several
    #: recordings of one unit (:class:`sins.compensation.unit_bias.BiasRule` as a dict; applied by
    #: :meth:`correct_recording`); absent otherwise.
    unit_bias_: dict[str, Any]
    #: The seed model's accelerometer, ``[A0; A]`` (4, 3: the bias, m/s², then the matrix of
    #: ``accel = n + A0 + A n``), that corrects the accelerometer in place of the strategy's own
    #: correction: set on a network whose gyro earned its place held back and whose accelerometer did
    #: not (:mod:`sins.compensation.network_guard`; the networks' :attr:`state_keys` hold it); absent
    #: otherwise.
    accel_seed_: Array
    #: The whole seed model, ``[B0; B; K; A0; A]`` (11, 3; :func:`seed_arrays`), whose gyro correction
    #: replaces the strategy's own: set on a network whose accelerometer earned its place held back and
    #: whose gyro did not, beside least squares' bias rule (:mod:`sins.compensation.network_guard`; the
    #: networks' :attr:`state_keys` hold it); absent otherwise.
    gyro_seed_: Array
    #: Called as ``progress(done, total)`` while a long fit trains (the learners set it up in their
    #: constructors; absent on the others).
    progress: Callable[[int, int], None] | None

    @abstractmethod
    def fit(self, data: CalibrationData) -> Strategy:
        """Learn from calibration data; returns ``self``."""

    @abstractmethod
    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """Estimated true angular rate and specific force (n, 3) from readings (n, 3)."""

    @property
    def label(self) -> str:
        """What to call it in reports: the variant it was made or loaded as, else the one its parameters
        make it (:meth:`kind`: a clone ``type(s)(**s.params())`` of ``mlp_seed`` had said ``mlp_pure``)."""
        return self.variant or self.kind()

    def kind(self) -> str:
        """The registered variant its parameters make it, where one of them changes what it is
        (``Regression(robust=True)`` is ``regression_robust``); here its class's name."""
        return self.name

    def beyond_box(self, gyro: Array, accel: Array, temp: Array | None = None) -> NDArray[np.bool_]:
        """The readings (n, 3 each) at which a learned part of the model reads beyond the inputs it was
        trained on; none for a model without one (the learners' own: ``ResidualStrategy.beyond_box``)."""
        return np.zeros(len(gyro), dtype=bool)

    def predict_error(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """The error believed to be in each reading: ``readings - correct(readings)``."""
        omega_ib_b, f_ib_b = self.correct(gyro, accel, temp)
        return gyro - omega_ib_b, accel - f_ib_b

    def correct_rates(self, rates: ImuRates, temp: Array | None = None) -> ImuRates:
        """Correct rate-form samples ``omega_ib_b`` and ``f_ib_b`` (``temp`` at ``rates.t``), each
        sensor read ``time_offset_s_`` later first where the strategy has one."""
        rates = self.aligned_rates(rates)
        omega_ib_b, f_ib_b = self.correct(rates.omega_ib_b, rates.f_ib_b, temp)
        return ImuRates(t=rates.t, omega_ib_b=omega_ib_b, f_ib_b=f_ib_b)

    def correct_increments(self, imu: ImuIncrements, temp: Array | None = None) -> ImuIncrements:
        """Correct increments through their mean rate over each interval (``temp`` at ``imu.t``), each
        sensor read ``time_offset_s_`` later first where the strategy has one."""
        imu = self.aligned_increments(imu)
        dt = np.diff(imu.t)
        if temp is not None and np.shape(temp) != np.shape(imu.t):  # in the caller's terms
            raise ValueError(f"temp must be {np.shape(imu.t)} (at imu.t), got {np.shape(temp)}")
        mid_temp = None if temp is None else 0.5 * (np.asarray(temp)[:-1] + np.asarray(temp)[1:])
        omega_ib_b, f_ib_b = self.correct(imu.dtheta_b / dt[:, None], imu.dv_b / dt[:, None], mid_temp)
        return ImuIncrements(
            t=imu.t, dtheta_b=rowwise.mul_col(omega_ib_b, dt), dv_b=rowwise.mul_col(f_ib_b, dt)
        )

    def correct_recording(
        self, readings: ImuRates | ImuIncrements, temp: Array | None = None
    ) -> ImuRates | ImuIncrements:
        """A whole recording, in time order and in its own form: :meth:`correct_rates` or
        :meth:`correct_increments`, then, where the strategy was fitted on several recordings of one unit,
        its rule for the recording's own gyro bias (``unit_bias_``: estimated from the readings before
        each one; under the rule ``readings``, the gyro kept as read:
        :func:`sins.compensation.unit_bias.applied`). A stream corrected a chunk at a time
        (``correct_increments`` alone) has no rule."""
        out = (
            self.correct_rates(readings, temp)
            if isinstance(readings, ImuRates)
            else self.correct_increments(readings, temp)
        )
        rule = getattr(self, "unit_bias_", None)
        if not isinstance(rule, dict):
            return out
        from sins.compensation import unit_bias

        return unit_bias.applied(unit_bias.BiasRule.from_dict(rule), readings, out)

    def leaves_gyro_as_read(self) -> bool:
        """Whether :meth:`correct_recording` keeps the gyro as read: the model's fit on several recordings
        found every bias rule worse than the raw readings on a held-back one (the rule ``readings``)."""
        from sins.compensation.unit_bias import READINGS

        rule = getattr(self, "unit_bias_", None)
        return isinstance(rule, dict) and rule.get("mode") == READINGS

    def aligned_rates(self, rates: ImuRates) -> ImuRates:
        """``rates`` with each sensor read ``time_offset_s_`` later (linear interpolation; the ends
        held, so a stream corrected a chunk at a time holds each chunk's last reading over the offset),
        or as they are without a time offset."""
        offsets = getattr(self, "time_offset_s_", None)
        if offsets is None or not np.any(offsets):
            return rates
        later = lambda x, tau: np.stack(  # noqa: E731
            [np.interp(rates.t + tau, rates.t, x[:, i]) for i in range(3)], axis=1
        )
        return ImuRates(
            t=rates.t, omega_ib_b=later(rates.omega_ib_b, offsets[0]), f_ib_b=later(rates.f_ib_b, offsets[1])
        )

    def aligned_increments(self, imu: ImuIncrements) -> ImuIncrements:
        """``imu`` with each sensor read ``time_offset_s_`` later
        (:func:`sins.compensation.intervals.shift_increments`), or as it is without a time offset."""
        offsets = getattr(self, "time_offset_s_", None)
        if offsets is None or not np.any(offsets):
            return imu
        from sins.compensation.intervals import shift_increments

        return ImuIncrements(
            t=imu.t,
            dtheta_b=shift_increments(imu, float(offsets[0]), accel=False).dtheta_b,
            dv_b=shift_increments(imu, float(offsets[1]), gyro=False).dv_b,
        )

    def get_state(self) -> dict[str, Any]:
        """What :func:`save` writes: the fitted attributes, as plain lists and numbers."""
        return {k: _plain(v) for k, v in vars(self).items() if k.endswith("_")}

    def check_state(self, state: dict[str, Any]) -> None:
        """Refuse a saved state this strategy (as constructed) cannot hold, before any array, network or
        map of it is made: ``ValueError`` naming the key and what it must be.
        :func:`~sins.compensation.load` calls it before :meth:`set_state`. Here: every key a fitted
        attribute of this strategy (:attr:`state_keys`); strategies add their own shapes and sizes."""
        odd = [k for k in state if k not in self.state_keys]
        if odd:
            key, its = printable(odd[0])[:80], ", ".join(sorted(self.state_keys))
            raise ValueError(f"state.{key} is not a fitted attribute of {self.name} (its: {its})")
        if "fitted_on_" in state:
            _check_fitted_on(state["fitted_on_"])
        if "accel_seed_" in state:
            seed = state_array(state, "accel_seed_", (4, 3))
            if abs(np.linalg.det(np.eye(3) + seed[1:])) < 1e-6:  # solved for the force: invertible
                raise ValueError("state.accel_seed_: I + A is singular (its rows 2-4 are A)")
        if "gyro_seed_" in state:
            _, b_m, _, _, a_m = seed_arrays(state_array(state, "gyro_seed_", (11, 3)))
            if min(abs(np.linalg.det(np.eye(3) + m)) for m in (b_m, a_m)) < 1e-6:
                raise ValueError("state.gyro_seed_: I + B or I + A is singular (rows 2-4 are B, 9-11 A)")
        if "unit_bias_" in state:
            from sins.compensation import unit_bias

            if not isinstance(state["unit_bias_"], dict):
                raise ValueError("state.unit_bias_ is not an object")
            unit_bias.BiasRule.from_dict(state["unit_bias_"])

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore what :meth:`get_state` gave (lists become float arrays)."""
        for k, v in state.items():
            setattr(self, k, np.asarray(v, dtype=float) if isinstance(v, list) else v)

    def params(self) -> dict[str, Any]:
        """The constructor's parameters as it holds them (scikit-learn's rule: each ``__init__`` argument
        is kept under its own name), in JSON's terms (tuples as lists): what a model file saves beside
        the state, and what the class is made again from."""
        return {name: _json_param(getattr(self, name)) for name in self.init_parameters()}

    def check_params(self) -> None:
        """Refuse a constructor argument of another kind than its default (``guard="false"``, which is
        true; ``huber_k="2"``) or outside its :attr:`param_ranges` (``max_epochs=-3``, ``seed=1.5``):
        ``ValueError`` naming it and what it must be. The constructors keep what they are given
        (scikit-learn's rule); :func:`~sins.compensation.make`, :meth:`fit`, :func:`~sins.compensation.save`
        and a model file's loader call this."""
        names = self.init_parameters()
        check_param_kinds(self.label, {name: getattr(self, name) for name in names}, names)
        for name, allowed in self.param_ranges.items():
            value = getattr(self, name)
            items = value if isinstance(value, list | tuple) else [value]
            if not items:  # an empty grid had passed here and failed in fit ("no fold could be fitted")
                raise ValueError(f"{self.label}: {name} is {value!r}, expected one or more of {allowed}")
            if not all(allowed.holds(v) for v in items):
                raise ValueError(f"{self.label}: {name} is {value!r}, expected {allowed}")

    @classmethod
    def init_parameters(cls) -> dict[str, inspect.Parameter]:
        """The constructor's named parameters, in order (what :meth:`params` reports, and a model file's
        ``params`` may hold)."""
        return {
            name: p for name, p in inspect.signature(cls.__init__).parameters.items()
            if name != "self" and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
        }  # fmt: skip


def state_array(
    state: dict[str, Any], key: str, shape: tuple[int | None, ...], where: str = "state"
) -> Array:
    """``state[key]`` as :func:`checked_array` makes it (``where.key`` in its message), or ValueError
    when it is missing."""
    if key not in state:
        raise ValueError(f"{where}.{key} is missing")
    return checked_array(state[key], shape, f"{where}.{key}")


def checked_array(value: Any, shape: tuple[int | None, ...], where: str) -> Array:
    """``value`` as a float array of ``shape`` (``None``: any size on that axis), every value finite;
    else ``ValueError`` naming ``where``. Made of a file's own numbers, so no larger than the file: a
    ``true`` or a ``"0.1"`` in it is refused, not read as 1 or 0.1 (numpy would convert both)."""
    odd = _not_a_number(value)
    if odd is not None:
        raise ValueError(f"{where} holds {odd!r}, not a number")
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{where} is not an array of numbers") from None
    if array.ndim != len(shape) or any(
        n is not None and n != m for n, m in zip(shape, array.shape, strict=True)
    ):
        wanted = (
            "("
            + ", ".join("n" if n is None else str(n) for n in shape)
            + ("," if len(shape) == 1 else "")
            + ")"
        )
        raise ValueError(f"{where} has shape {array.shape}, expected {wanted}")
    if not np.isfinite(array).all():
        raise ValueError(f"{where} holds a number that is not finite")
    return array


def _not_a_number(value: Any) -> Any:
    """The first boolean or string in ``value`` (nested lists walked), else None."""
    stack = [value]
    while stack:
        item = stack.pop()
        if isinstance(item, list | tuple):
            stack.extend(item)
        elif isinstance(item, bool | str | bytes):
            return item
    return None


#: The most a recording's rate may be, Hz, in a model file's ``fitted_on_`` (the readers' own bound).
_MAX_RATE_HZ = 1e6


def _check_fitted_on(fitted: Any) -> None:
    """Refuse a ``fitted_on_`` that would make :func:`~sins.compensation.fitted_on.check_fitted_on` pass
    what it exists to refuse: not an object, a rate that is not a positive finite number (a rig's is
    null), axes that are not three letters of a right-handed frame, a unit's name that is not text."""
    if not isinstance(fitted, dict):
        raise ValueError("state.fitted_on_ is not an object")
    if "rate_hz" not in fitted:  # every fit writes it; without it a model met every rate unchecked
        raise ValueError("state.fitted_on_.rate_hz is missing: the rate fitted at, or null for a rig")
    rate = fitted.get("rate_hz")
    if rate is not None and (
        isinstance(rate, bool) or not isinstance(rate, int | float) or not 0.0 < rate <= _MAX_RATE_HZ
    ):
        raise ValueError(f"state.fitted_on_.rate_hz is {rate!r}: a rate in Hz (0 to 1e6), or null for a rig")
    frame = fitted.get("frame")
    if frame is not None and not _is_frame(frame):
        raise ValueError(f"state.fitted_on_.frame is {frame!r}: the letters of a frame, such as frd")
    marks = fitted.get("marks")
    if marks is not None and not (
        isinstance(marks, list)
        and all(isinstance(m, list) and all(isinstance(x, str) for x in m) for m in marks)
    ):
        raise ValueError("state.fitted_on_.marks is not a list of each recording's marks (text)")
    sensor = fitted.get("sensor")
    if sensor is not None and not isinstance(sensor, str):
        raise ValueError(f"state.fitted_on_.sensor is {sensor!r}: a unit's name")


def _is_frame(frame: Any) -> bool:
    """Whether ``frame`` is the letters of a right-handed frame (:func:`sins.io.axes.frame_matrix`)."""
    from sins.io.axes import frame_matrix

    try:
        return isinstance(frame, str) and frame_matrix(frame) is not None
    except SinsInputError:
        return False


@dataclass(frozen=True)
class ParamRange:
    """The values a numeric constructor parameter may take: finite, from ``low`` to ``high`` (None: no
    bound), ``low`` itself excluded where ``above``; only whole numbers where ``whole`` (a count, a seed);
    None too where ``none``. Held by :meth:`Strategy.check_params`; its ``str`` is what the refusal says."""

    low: float | None = None
    high: float | None = None
    whole: bool = False
    above: bool = False
    none: bool = False

    def holds(self, value: Any) -> bool:
        """Whether ``value`` lies in the range (a boolean is not a number; 2.0 is not a whole one)."""
        if value is None:
            return self.none
        if isinstance(value, bool | np.bool_) or not isinstance(
            value, int | float | np.integer | np.floating
        ):
            return False
        if self.whole and not isinstance(value, int | np.integer):
            return False
        if not math.isfinite(value):
            return False
        low_ok = self.low is None or (value > self.low if self.above else value >= self.low)
        return bool(low_ok and (self.high is None or value <= self.high))

    def __str__(self) -> str:
        what = "a whole number" if self.whole else "a number"
        low, high = _said(self.low), _said(self.high)
        if self.low is not None and self.high is not None:
            said = f"{what} above {low}, at most {high}" if self.above else f"{what} from {low} to {high}"
        elif self.low is not None:
            said = f"{what} above {low}" if self.above else f"{what}, {low} or more"
        else:
            said = what if self.high is None else f"{what}, at most {high}"
        return said + (" (or None)" if self.none else "")


def _said(bound: float | None) -> str:
    """A range's bound as a user writes it: whole bounds in full (4294967295, not 4.29497e+09)."""
    if bound is None:
        return ""
    return str(int(bound)) if float(bound).is_integer() else f"{bound:g}"


#: A seed of the generators the learners use (numpy's, MiniSom's and torch's all take 0 to 2³² − 1).
SEED_RANGE = ParamRange(0, 2**32 - 1, whole=True)
#: A guard's threshold in standard errors.
GUARD_Z_RANGE = ParamRange(0, 100)


def recordings_threshold(z: float, n: int) -> float:
    """The standard errors a gain must exceed where they are estimated from ``n`` held-back recordings
    (``n - 1`` degrees of freedom): Student's t quantile at the normal's one-sided level of ``z`` (for 2,
    97.7 %: three recordings 4.53, five 2.87, six 2.65, ten 2.32), so that a null gain over a few
    recordings passes as rarely as one ``z`` standard errors of a known spread would (over three, 2
    passed one in eleven; a numpy unit's written networks lost judged in four of six fits). Infinite
    below two."""
    from scipy.stats import norm, t

    return float(t.ppf(norm.cdf(z), n - 1)) if n >= 2 else math.inf


def sum_standard_error(draws: NDArray[np.floating] | list[float]) -> Any:
    """The standard error of the sum of independent draws along the first axis: ``√n`` times their
    sample standard deviation; infinite with fewer than two (no spread to judge by). What every guard
    judges a held-back gain's sum against (``gain > z · this``): the residual learners'
    (:mod:`~sins.compensation.residual`), the physics terms' forward selection
    (:mod:`~sins.compensation.terms`) and ``mlp_window``'s; the draws are the held-back blocks, or the
    recordings where each recording is a fold (the sampling unit a new recording is)."""
    x = np.asarray(draws, dtype=float)
    if len(x) < 2:
        return np.full(x.shape[1:], np.inf) if x.ndim > 1 else np.inf
    return np.sqrt(len(x) * x.var(axis=0, ddof=1))


def param_kind(default: Any) -> str:
    """What a parameter whose default is ``default`` must be, in words ("" where any value may do)."""
    if isinstance(default, bool):
        return "true or false"
    if isinstance(default, int | float):
        return "a number"
    if isinstance(default, str):
        return "text"
    if isinstance(default, tuple | list):
        return "a list"
    return ""


def is_param_kind(value: Any, default: Any) -> bool:
    """Whether ``value`` (from JSON) is of the kind of ``default`` (:func:`param_kind`)."""
    if isinstance(default, bool):
        return isinstance(value, bool)
    if isinstance(default, int | float):
        return isinstance(value, int | float) and not isinstance(value, bool)
    if isinstance(default, str):
        return isinstance(value, str)
    return isinstance(value, list)


def wrong_kind(
    values: dict[str, Any], signature: dict[str, inspect.Parameter]
) -> tuple[str, Any, str] | None:
    """The first of ``values`` of another kind than its parameter's default in ``signature`` (numpy's
    scalars and tuples taken as JSON takes them), as ``(name, value, the kind wanted)``; None if none is."""
    for name, value in values.items():
        default = signature[name].default
        wanted = param_kind(default)
        if wanted and not is_param_kind(_json_param(value), default):
            return name, value, wanted
    return None


def check_param_kinds(label: str, values: dict[str, Any], signature: dict[str, inspect.Parameter]) -> None:
    """Refuse :func:`wrong_kind`'s first value: ``ValueError`` naming ``label`` and it."""
    if found := wrong_kind(values, signature):
        name, value, wanted = found
        raise ValueError(f"{label}: {name} is {value!r}, expected {wanted}")


def _json_param(value: Any) -> Any:
    """A constructor parameter in JSON's terms: tuples (nested too) as lists, numpy's scalars (a sweep's
    ``np.int64``, ``np.bool_``) as Python's, which JSON writes."""
    if isinstance(value, tuple | list):
        return [_json_param(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _plain(value: Any) -> Any:
    return value.tolist() if isinstance(value, np.ndarray) else value


class NoCompensation(Strategy):
    """Readings taken as they are."""

    name = "none"

    def fit(self, data: CalibrationData) -> NoCompensation:
        """Nothing to learn; returns self."""
        return self

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """The readings unchanged."""
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
    param_ranges: ClassVar[dict[str, ParamRange]] = {"iterations": ParamRange(1, 100, whole=True)}

    def __init__(self, model: ImuModel | None = None, iterations: int = 6) -> None:
        self.model = model
        self.iterations = iterations

    def fit(self, data: CalibrationData) -> Oracle:
        """Nothing to learn, but the model must be given; returns self."""
        if self.model is None:
            raise ValueError("the oracle needs the simulated unit's model: Oracle(model)")
        return self

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """Invert the unit's deterministic errors by fixed-point iteration (angular acceleration 0)."""
        from sins.imu import TrueInputs

        if self.model is None:
            raise ValueError("the oracle needs the simulated unit's model: Oracle(model)")
        omega_ib_b, f_ib_b = gyro.copy(), accel.copy()
        zero = np.zeros_like(omega_ib_b)
        for _ in range(self.iterations):
            inputs = TrueInputs(omega_ib_b=omega_ib_b, f_ib_b=f_ib_b, omega_dot_b=zero, temp=temp)
            omega_ib_b = gyro - self.model.deterministic_error("gyro", inputs)
            f_ib_b = accel - self.model.deterministic_error("accel", inputs)
        return omega_ib_b, f_ib_b

    def get_state(self) -> dict[str, Any]:
        """Always raises ``ValueError``: an oracle holds a simulated unit, not a model to save."""
        raise ValueError("the oracle knows a simulated unit; it cannot be saved as a model file")


# --------------------------------------------------------------------------- judging on recorded data


def residual_rms(strategy: Strategy, data: CalibrationData) -> dict[str, dict[str, float]]:
    """Per channel, the RMS of reading − reference before and after correction (SI units), its mean
    (``mean_before``, ``mean_after``: the bias left, which the RMS buries under the noise), and
    ``beyond_noise``: the RMS after correction less the white noise's share, ``√max(rms² − σ², 0)``, with
    ``σ`` the residual's sample-to-sample spread (``std(Δr)/√2``, which a bias or a slow error does not
    raise): what the model leaves that is not noise.

    Rows without a finite reference are left out.
    """
    ok = data.has_reference
    if not ok.any():
        raise SinsInputError(f"{data.source or 'recording'}: no rows with a reference to judge against")
    temp = None if data.temp is None else data.temp[ok]
    omega_ib_b, f_ib_b = strategy.correct(data.gyro[ok], data.accel[ok], temp)
    before = np.hstack([data.gyro[ok] - data.ref_gyro[ok], data.accel[ok] - data.ref_accel[ok]])
    after = np.hstack([omega_ib_b - data.ref_gyro[ok], f_ib_b - data.ref_accel[ok]])
    rms = lambda x: np.sqrt(np.mean(x * x, axis=0))  # noqa: E731
    b, a = rms(before), rms(after)
    mb, ma = before.mean(axis=0), after.mean(axis=0)
    noise = np.std(np.diff(after, axis=0), axis=0) / np.sqrt(2.0) if len(after) > 2 else np.zeros(6)
    beyond = np.sqrt(np.maximum(a * a - noise * noise, 0.0))
    return {
        ch: {
            "rms_before": float(b[i]),
            "rms_after": float(a[i]),
            "mean_before": float(mb[i]),
            "mean_after": float(ma[i]),
            "beyond_noise": float(beyond[i]),
        }
        for i, ch in enumerate(CHANNELS)
    }


__all__ = [
    "GUARD_Z_RANGE",
    "SEED_RANGE",
    "NoCompensation",
    "NotFittedError",
    "Oracle",
    "ParamRange",
    "Strategy",
    "check_param_kinds",
    "checked_array",
    "is_param_kind",
    "param_kind",
    "recordings_threshold",
    "residual_rms",
    "seed_arrays",
    "state_array",
    "sum_standard_error",
    "wrong_kind",
]
