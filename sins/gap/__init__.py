"""The sim-to-real gap: which unmodelled error effect parts a recording from its simulation.

:mod:`~sins.gap.diagnosis` runs the greedy search over the effect library: its candidates
(:mod:`~sins.gap.candidates`), each channel's model (:mod:`~sins.gap.channel`), their scores
(:mod:`~sins.gap.scoring`), the guards and rules of choice (:mod:`~sins.gap.guards`), the noise floor
and where the gap lies (:mod:`~sins.gap.floor`) and the report (:mod:`~sins.gap.report`); the
columns are built a chunk of rows at a time (:mod:`~sins.gap.design`), so a long recording's are never
held whole.
:mod:`~sins.gap.lattice`, :mod:`~sins.gap.randombias` and :mod:`~sins.gap.disturbance` are its
specialists for quantization lattices, random biases and out-of-library disturbances.
"""

from sins.gap.candidates import CANDIDATES, Candidate, baseline_columns, regressors_of
from sins.gap.diagnosis import diagnose
from sins.gap.floor import SIGNIFICANT_RATIO, allan_deviation, noise_floor
from sins.gap.report import EffectScore, GapReport, Outside
from sins.gap.scoring import SIGNIFICANT_NATS, TIE_NATS

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
