"""The sim-to-real gap: which unmodelled error effect parts a recording from its simulation.

:mod:`~sins.gap.diagnosis` runs the greedy search over the effect library; :mod:`~sins.gap.lattice`,
:mod:`~sins.gap.randombias` and :mod:`~sins.gap.disturbance` are its specialists for quantization
lattices, random biases and out-of-library disturbances.
"""

from sins.gap.diagnosis import (
    CANDIDATES,
    SIGNIFICANT_NATS,
    SIGNIFICANT_RATIO,
    TIE_NATS,
    Candidate,
    EffectScore,
    GapReport,
    Outside,
    allan_deviation,
    baseline_columns,
    diagnose,
    noise_floor,
    regressors_of,
)

__all__ = [
    "CANDIDATES",
    "SIGNIFICANT_NATS",
    "SIGNIFICANT_RATIO",
    "TIE_NATS",
    "Candidate",
    "EffectScore",
    "GapReport",
    "Outside",
    "allan_deviation",
    "baseline_columns",
    "diagnose",
    "noise_floor",
    "regressors_of",
]
