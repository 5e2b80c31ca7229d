"""Pictures: the Rerun viewer bridge (:mod:`~sins.viz.viewer`, the only module that imports rerun) and
headless figures (:mod:`~sins.viz.plots`, the only one that imports matplotlib). Importing this package
imports neither."""

from __future__ import annotations

from sins import _lazy

#: The modules of this package, each imported the first time it is used (``sins.viz.plots``).
SUBMODULES = ("plots", "viewer")

__getattr__, __dir__ = _lazy(globals(), {}, SUBMODULES)

__all__ = ["SUBMODULES"]
