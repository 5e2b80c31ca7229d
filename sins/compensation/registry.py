"""Strategies by name, and their model files.

:func:`make` builds a strategy from its variant name (:data:`VARIANTS`); :func:`save` and :func:`load`
keep a fitted one in a versioned JSON file, and a file of another format version or an unknown strategy
is refused in one line. The registry names each class by its module, so the interface never imports the
strategies back, and torch or minisom load only when a learned strategy is asked for.
"""

from __future__ import annotations

import importlib
import os
from pathlib import Path
from typing import Any

import numpy as np

from sins import __version__, io
from sins.compensation.base import NoCompensation, NotFittedError, Strategy, check_param_kinds, wrong_kind
from sins.errors import SinsInputError
from sins.io.documents import printable, short

#: Version of the model file format; bump it when the saved state changes meaning.
FORMAT_VERSION = 3
FORMAT_NAME = "sins.compensation"

#: Registered class names: where each class lives (``module:Class``).
CLASSES: dict[str, str] = {
    "none": "sins.compensation.base:NoCompensation",
    "oracle": "sins.compensation.base:Oracle",
    "regression": "sins.compensation.regression:Regression",
    "regression_extended": "sins.compensation.regression:ExtendedRegression",
    "regression_rest": "sins.compensation.rest:RestAware",
    "regression_window": "sins.compensation.window:WindowRegression",
    "mlp_window": "sins.compensation.window_net:WindowNet",
    "mlp": "sins.compensation.mlp:ResidualMLP",
    "mlp_pure": "sins.compensation.mlp:MLP",
    "kohonen": "sins.compensation.kohonen:LocalLinearMap",
    "kohonen_pure": "sins.compensation.kohonen_pure:Kohonen",
    "ferraris": "sins.compensation.ferraris:Ferraris",
}


def strategy_class(name: str) -> type[Strategy]:
    """The class registered under ``name``, imported when first asked for."""
    if name not in CLASSES:
        raise ValueError(f"unknown strategy {name!r} (known: {', '.join(VARIANTS)})")
    module, cls = CLASSES[name].split(":")
    found: type[Strategy] = getattr(importlib.import_module(module), cls)
    return found


#: Strategy variants by name: (registered class name, constructor parameters).
VARIANTS: dict[str, tuple[str, dict[str, Any]]] = {
    "none": ("none", {}),
    "oracle": ("oracle", {}),
    "regression": ("regression", {}),
    "regression_robust": ("regression", {"robust": True}),
    "regression_extended": ("regression_extended", {}),
    "regression_rest": ("regression_rest", {}),
    "regression_window": ("regression_window", {}),
    "mlp_window": ("mlp_window", {}),
    "mlp": ("mlp", {}),
    "mlp_pure": ("mlp_pure", {}),
    "mlp_seed": ("mlp_pure", {"mode": "seed", "hidden": (16,), "alpha": 0.05, "max_epochs": 30}),
    "kohonen": ("kohonen", {}),
    "kohonen_pure": ("kohonen_pure", {}),
    "ferraris": ("ferraris", {}),
}

#: Variants fitted only against a reference trajectory (:mod:`sins.compensation.referenced`), which a model
#: file may
#: name beside :data:`VARIANTS`: the biases alone, a ``regression`` whose other terms stay zero.
REFERENCE_VARIANTS = ("bias_only",)

#: What each strategy a user can fit is, one line each, in the order ``sins strategies`` lists them: every
#: variant but the oracle (a simulation's own unit), and ``bias_only``, fitted against a trajectory only
#: (the biases of the seed model, what a filter that estimates biases alone keeps).
DESCRIPTIONS: dict[str, str] = {
    "none": "the readings as they are",
    "regression": "least squares of the seed model: biases, scale factors, misalignments, g-sensitivity",
    "regression_robust": "regression with Huber-weighted rows or intervals",
    "regression_extended": "regression with the terms the data choose (scale nonlinearity, asymmetry, ...)",
    "regression_rest": "regression, then the gyro bias taken again at every rest",
    "regression_window": "regression, then a ridge gyro correction from a window of past readings",
    "mlp": "regression, then a feed-forward network of what it leaves (guarded on held-back data)",
    "mlp_window": "regression, then a network of the gyro's error from a window of past readings (guarded "
    "on held-back recordings)",
    "mlp_pure": "the seed paper's network from readings to errors",
    "mlp_seed": "the seed paper's network, trained as the paper does",
    "kohonen": "regression, then a self-organising local linear map of what it leaves (guarded)",
    "kohonen_pure": "the seed paper's self-organising map",
    "ferraris": "the Ferraris calibration of six holds and three turns",
    "bias_only": "against a trajectory: the gyro's and accelerometer's biases alone",
}


def strategy_names(taking: str | None = None) -> list[str]:
    """The strategies a user can fit (:data:`DESCRIPTIONS`), in order; with ``taking``, those whose
    constructor takes that parameter (``"guard"``: the learners with a guard)."""
    names = list(DESCRIPTIONS)
    if taking is None:
        return names
    return [n for n in names if n in VARIANTS and taking in strategy_class(VARIANTS[n][0]).init_parameters()]


#: Names a model file may carry (the registered classes that can be fitted).
SAVED_STRATEGIES = (
    "none",
    "regression",
    "regression_extended",
    "regression_rest",
    "regression_window",
    "mlp_window",
    "ferraris",
    "mlp",
    "mlp_pure",
    "kohonen",
    "kohonen_pure",
)


def make(name: str, **params: Any) -> Strategy:
    """A strategy by variant name (see :data:`VARIANTS`), with parameters overriding the variant's."""
    if name in REFERENCE_VARIANTS:
        raise ValueError(
            f"{name} is fitted against a reference trajectory only: sins fit RECORDING --strategy {name}, "
            f"or sins.compensation.referenced.fit({name!r}, recording)"
        )
    if name not in VARIANTS:
        raise ValueError(f"unknown strategy {name!r} (known: {', '.join(VARIANTS)})")
    cls_name, defaults = VARIANTS[name]
    cls = strategy_class(cls_name)
    signature = cls.init_parameters()
    unknown = [k for k in params if k not in signature]
    if unknown:
        raise ValueError(f"{unknown[0]} is not a parameter of {name} (known: {', '.join(signature)})")
    check_param_kinds(name, params, signature)  # before the constructor bounds them
    strategy = cls(**{**defaults, **params})
    strategy.variant = name
    strategy.check_params()  # and their ranges
    return strategy


# --------------------------------------------------------------------------- model files


def save(strategy: Strategy, path: str | os.PathLike[str]) -> None:
    """Write a fitted strategy to a versioned JSON file (atomically). A parameter of another kind than
    its default is refused (:meth:`Strategy.check_params`), and a strategy not fitted
    (:class:`NotFittedError`): the file could not be loaded."""
    strategy.check_params()
    state = strategy.get_state()
    if not state and strategy.name != NoCompensation.name:  # a file load would refuse ("B0_ is missing")
        raise NotFittedError(f"{type(strategy).__name__} is not fitted: call fit() before saving it")
    doc = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "sins": __version__,
        "strategy": strategy.name,
        "variant": strategy.label,
        "params": strategy.params(),
        "state": state,
    }
    io.write_json(path, doc)


def _variant(variant: Any, name: str) -> str:
    """A model file's ``variant``, one of strategy ``name``'s (:data:`VARIANTS`, or ``bias_only`` of
    ``regression``); else ``ValueError``. A ``regression_rest`` file relabelled ``regression`` had loaded
    as least squares that called itself ``regression_rest``, its rest rule dropped without a word."""
    of = {v: cls for v, (cls, _) in VARIANTS.items()} | {v: "regression" for v in REFERENCE_VARIANTS}
    if not isinstance(variant, str) or of.get(variant) != name:
        theirs = [v for v, cls in of.items() if cls == name]
        raise ValueError(f"variant {short(variant)} is not a variant of {name} (its: {', '.join(theirs)})")
    return variant


def load(path: str | os.PathLike[str]) -> Strategy:
    """Read a strategy written by :func:`save`; refuse other formats and versions in one line.

    The parameters and state are checked (objects; every number finite and at most
    :data:`MAX_MODEL_VALUE` in magnitude), the variant against the strategy (one of its own), the
    parameters against the strategy's bounds (:meth:`Strategy.check_params`: a network's layers and
    widths, a map's nodes), the state's shapes and sizes against
    the parameters before any array, network or map is made (:meth:`Strategy.check_state`: a file of
    70 kB cannot ask for a 6 GB network), and the model corrects a few probe readings; so a damaged file
    is refused here, in one line naming the file, rather than failing or printing NaN later.
    """
    path = Path(path)
    doc = io.read_json_document(path, "model file", FORMAT_NAME)
    version = doc.get("version")
    if isinstance(version, bool) or version != FORMAT_VERSION:
        if isinstance(version, bool) or not isinstance(version, int):  # none, text, a switch
            said = "no" if "version" not in doc else f"{short(version)} for its"
            wanted = f"the number {FORMAT_VERSION} in this sins's"
            raise SinsInputError(f'{path}: malformed model file ({said} "version": {wanted})')
        writer = short(doc.get("sins"))
        raise SinsInputError(
            f"{path}: model file format version {short(version)} (written by sins {writer}); "
            f"this sins reads version {FORMAT_VERSION}: fit the model again"
        )
    name = doc.get("strategy")
    if name not in SAVED_STRATEGIES:
        raise SinsInputError(f"{path}: unknown strategy {short(name)} (known: {', '.join(SAVED_STRATEGIES)})")
    if "state" not in doc:
        raise SinsInputError(f'{path}: malformed {name} model (no "state": what the fit learned)')
    params, state = doc.get("params", {}), doc["state"]
    for key, value in (("params", params), ("state", state)):
        if not isinstance(value, dict):
            raise SinsInputError(f'{path}: malformed {name} model ("{key}" is not an object)')
        _check_values(path, name, value, key)
    _check_params(path, name, params)
    try:
        variant = _variant(doc.get("variant", name), name)  # what the file says it is, first
        strategy = strategy_class(name)(**params)
        strategy.check_params()  # their kinds and ranges, a network's size, a map's
        # The state's shapes and sizes against the strategy's, before any array, network or map is made.
        strategy.check_state(state)
        strategy.set_state(state)
        strategy.variant = variant
        # A probe: what the checks above do not see fails here, not in the middle of a run.
        gyro, accel = _PROBE
        gyro_c, accel_c = strategy.correct(gyro, accel, np.full(len(gyro), 20.0))
        corrected = np.hstack([np.asarray(gyro_c, dtype=float), np.asarray(accel_c, dtype=float)])
    except _MALFORMED as exc:
        why = printable(" ".join(str(exc).split()))[:300]
        raise SinsInputError(f"{path}: malformed {name} model ({type(exc).__name__}: {why})") from None
    if corrected.shape != (len(gyro), 6) or not np.isfinite(corrected).all():
        raise SinsInputError(
            f"{path}: malformed {name} model (its correction of a probe reading is not finite, or of shape "
            f"{corrected.shape})"
        )
    return strategy


#: What building a strategy from a damaged file may raise (torch's shape errors are RuntimeErrors;
#: numpy's singular matrices ValueErrors; a number too large for a float an OverflowError).
_MALFORMED = (TypeError, ValueError, KeyError, AttributeError, IndexError, RuntimeError, OverflowError,
              ZeroDivisionError, FloatingPointError)  # fmt: skip

#: Readings a model file is tried on when loaded: at rest, turning at 1 rad/s and at 100 °/s under
#: 2 g, in rad/s and m/s² (a fitted model corrects each to finite values).
_PROBE = (
    np.array([[0.0, 0.0, 0.0], [1.0, -0.5, 0.2], [-1.745, 1.745, 1.745]]),
    np.array([[0.0, 0.0, -9.8], [1.0, 2.0, -9.0], [19.6, -19.6, 5.0]]),
)

#: The largest magnitude a number in a model file may have: fitted coefficients, weights, prototypes
#: and scales are all far smaller; larger ones overflow when a reading is corrected.
MAX_MODEL_VALUE = 1e12


def _check_params(path: Path, name: str, params: dict[str, Any]) -> None:
    """Refuse a parameter the strategy's constructor does not take, or of another kind than its default
    (a ``"big"`` for a number, a ``1`` for a switch, a number for a list of layers): the constructors
    bound their values, not their types, and a string would pass some of them silently."""
    signature = strategy_class(name).init_parameters()
    known = list(signature)
    for key in params:
        if key not in known:
            shown = printable(str(key))[:60]
            raise SinsInputError(
                f"{path}: malformed {name} model (params.{shown} is not a parameter of {name}; "
                f"known: {', '.join(known)})"
            )
    if found := wrong_kind(params, signature):
        key, value, wanted = found
        raise SinsInputError(
            f"{path}: malformed {name} model (params.{key} is {short(value)}: expected {wanted})"
        )


def _check_values(path: Path, name: str, value: Any, where: str) -> None:
    """Refuse a non-finite or overflowing number anywhere in a model file's ``params`` or ``state``."""
    if isinstance(value, dict):
        for k, v in value.items():
            _check_values(path, name, v, f"{where}.{k}")
    elif isinstance(value, list):
        for i, v in enumerate(value):
            _check_values(path, name, v, f"{where}[{i}]")
    elif isinstance(value, int | float) and not isinstance(value, bool) and not abs(value) <= MAX_MODEL_VALUE:
        raise SinsInputError(
            f"{path}: malformed {name} model ({where} is {short(value)}; numbers must be finite and at most "
            f"{MAX_MODEL_VALUE:g} in magnitude)"
        )


__all__ = [
    "CLASSES",
    "DESCRIPTIONS",
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "MAX_MODEL_VALUE",
    "REFERENCE_VARIANTS",
    "SAVED_STRATEGIES",
    "VARIANTS",
    "load",
    "make",
    "save",
    "strategy_class",
    "strategy_names",
]
