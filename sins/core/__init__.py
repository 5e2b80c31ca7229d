"""The base layer: rotations, the Earth, Allan variances, compiled row-wise arithmetic and the data model
(:mod:`sins.core.series`) every other package exchanges. Imports nothing else from sins but its errors."""

__all__: list[str] = []
