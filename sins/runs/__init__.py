"""Runs: a scenario from its file to each strategy's drift (:mod:`~sins.runs.pipeline`, the one streaming
engine), what runs give back (:mod:`~sins.runs.results`), a unit's strategies fitted once
(:mod:`~sins.runs.unit_fit`), the readings a run reads or simulates (:mod:`~sins.runs.readings`) and a
recorded IMU replayed against its truth (:mod:`~sins.runs.replay`)."""

from __future__ import annotations

from sins import _lazy

#: The modules of this package, each imported the first time it is used (``sins.runs.free_report``).
SUBMODULES = ("free_report", "pipeline", "readings", "replay", "results", "unit_fit")

__getattr__, __dir__ = _lazy(globals(), {}, SUBMODULES)

__all__ = ["SUBMODULES"]
