"""Runs: a scenario from its file to each strategy's drift (:mod:`~sins.runs.pipeline`, the one streaming
engine), what runs give back (:mod:`~sins.runs.results`), a unit's strategies fitted once
(:mod:`~sins.runs.unit_fit`), the readings a run reads or simulates (:mod:`~sins.runs.readings`) and a
recorded IMU replayed against its truth (:mod:`~sins.runs.replay`)."""

__all__: list[str] = []
