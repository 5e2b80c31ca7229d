"""The base layer: rotations, the Earth, Allan variances, compiled row-wise arithmetic and the data model
(:mod:`sins.core.series`) every other package exchanges. Imports nothing else from sins but its errors."""

from __future__ import annotations

from sins import _lazy

#: The modules of this package, each imported the first time it is used (``sins.core.allan``).
SUBMODULES = ("allan", "earth", "rotation", "rowwise", "series", "text")

__getattr__, __dir__ = _lazy(globals(), {}, SUBMODULES)

__all__ = ["SUBMODULES"]
