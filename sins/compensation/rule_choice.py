"""How a bias rule's mode is chosen on held-back recordings: each training recording judged by its
open-loop attitude with the rule made from the others (``sins.compensation.referenced.choose_rule`` makes
the figures; this module reads them). A mode is kept only where it is no worse than the readings as they
are on every held-back recording and better on their mean; of those kept, the simplest within one
standard error of the best is taken (:func:`chosen_mode`).
"""

from __future__ import annotations

import numpy as np

from sins.compensation.unit_bias import CHOICES, READINGS

#: A held-back mean within this share of the readings' ties with them: a rounding's difference, no gain.
TIE = 1e-9


def chosen_mode(scores: dict[str, list[float]], raw: list[float]) -> str:
    """The mode a rule takes from its open-loop attitude over held-back recordings (``scores``: each
    mode's, deg, one per recording; ``raw``: the readings' as they are); :data:`READINGS` where none is
    kept. Kept: no worse than the readings on any of them, and better on their mean (by more than
    :data:`TIE`): a correction worse than the readings on a recording it was not fitted on may be so on
    the next, and one that only ties with them (a ``bias_only`` prior that gives back the bias it takes)
    adds nothing. Of those, the first in :data:`~sins.compensation.unit_bias.CHOICES`' order (simplest
    first: what it takes from the training recordings and from the recording grows along it) whose mean
    lies within one standard error of the best one's, the error that of their differences recording by
    recording (the one-standard-error rule of cross-validation): three or six held-back recordings cannot
    tell modes closer than that apart, and the simpler one is less of a guess on a unit the recordings
    have not shown."""
    kept = kept_modes(scores, raw)
    if not kept:
        return READINGS
    best = min(kept, key=lambda m: float(np.mean(scores[m])))
    for mode in kept:
        behind, se = behind_by(scores[mode], scores[best])
        # Two modes that differ on one recording alone are behind by exactly their standard error (a/n
        # both): the boundary is within, or rounding's last digit chose (0.9028570299975037 against
        # 0.9028570299975038 on EuRoC's three, the simpler lost).
        if behind <= se * (1.0 + 1e-9):
            return mode
    raise AssertionError("the best mode is within its own standard error")  # pragma: no cover


def kept_modes(scores: dict[str, list[float]], raw: list[float]) -> list[str]:
    """The modes of ``scores`` (in :data:`~sins.compensation.unit_bias.CHOICES`' order) that
    :func:`chosen_mode` keeps: no worse than the readings on any held-back recording, and better on their
    mean by more than :data:`TIE`."""
    bar, given = (1.0 - TIE) * float(np.mean(raw)), [m for m in CHOICES if m in scores]
    return [m for m in given if np.all(np.array(scores[m]) <= raw) and np.mean(scores[m]) < bar]


def behind_by(scores: list[float], best: list[float]) -> tuple[float, float]:
    """How far a mode's held-back figures (deg, one per recording) lie behind the best one's on their
    mean, and that difference's standard error recording by recording (0 for one recording)."""
    gap = np.asarray(scores, dtype=float) - np.asarray(best, dtype=float)
    se = float(gap.std(ddof=1) / np.sqrt(len(gap))) if len(gap) > 1 else 0.0
    return float(gap.mean()), se


__all__ = ["TIE", "behind_by", "chosen_mode", "kept_modes"]
