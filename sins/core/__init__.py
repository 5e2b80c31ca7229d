"""The base layer: rotations, the Earth, Allan variances, compiled row-wise arithmetic, the data model
(:mod:`sins.core.series`) every other package exchanges, and the renames a command defers to its end
(:mod:`sins.core.deferred`). Imports nothing else from sins but its errors."""

from __future__ import annotations

from sins import _lazy

#: The modules of this package, each imported the first time it is used (``sins.core.allan``).
SUBMODULES = ("allan", "deferred", "earth", "rotation", "rowwise", "series", "text")

__getattr__, __dir__ = _lazy(globals(), {}, SUBMODULES)

__all__ = ["SUBMODULES"]
