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

from sins import __version__, io
from sins.compensation.base import Strategy
from sins.errors import SinsInputError

#: Version of the model file format; bump it when the saved state changes meaning.
FORMAT_VERSION = 2
FORMAT_NAME = "sins.compensation"

#: Registered class names: where each class lives (``module:Class``).
CLASSES: dict[str, str] = {
    "none": "sins.compensation.base:NoCompensation",
    "oracle": "sins.compensation.base:Oracle",
    "regression": "sins.compensation.regression:Regression",
    "regression_extended": "sins.compensation.regression:ExtendedRegression",
    "mlp": "sins.compensation.mlp:ResidualMLP",
    "mlp_pure": "sins.compensation.mlp:MLP",
    "kohonen": "sins.compensation.kohonen:LocalLinearMap",
    "kohonen_pure": "sins.compensation.kohonen:Kohonen",
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
