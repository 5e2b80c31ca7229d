"""A real unit's gap: its recordings diagnosed against their own references, on the statistic each
reference calls for (per-sample residuals, or integrated rotation and velocity change over its
intervals), the verdicts across the recordings, and what they buy in navigation on another recording.

:mod:`~sins.unit_gap.inputs` reads what ``sins gap`` reads; :mod:`~sins.unit_gap.statistic` chooses the
statistic; :mod:`~sins.unit_gap.intervals`, :mod:`~sins.unit_gap.fitter`, :mod:`~sins.unit_gap.outside`
and :mod:`~sins.unit_gap.search` are the diagnosis on intervals, :mod:`~sins.unit_gap.delays` the delays
tried per sample beside it, :mod:`~sins.unit_gap.report` its report;
:mod:`~sins.unit_gap.across` the verdicts across recordings, :mod:`~sins.unit_gap.shrink` the shrink on
another recording, and :mod:`~sins.unit_gap.run` the whole, as ``sins gap`` runs it.
"""

from sins.unit_gap.run import Diagnosed, diagnose_one, shrinks, verdicts

__all__ = [
    "Diagnosed",
    "diagnose_one",
    "shrinks",
    "verdicts",
]
