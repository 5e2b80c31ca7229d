"""Which rows of a recording a still unit's biases are taken over (:mod:`sins.characterise.bias`): the
first ``--seconds``, a rest long enough for the noise fit, the rests of a referenced recording, and
whether a reference's rate is Earth's.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from sins.characterise.analysis import MIN_ROWS
from sins.characterise.still import WINDOW_S
from sins.core import earth
from sins.errors import SinsInputError

Array = NDArray[np.float64]

#: Consecutive still stretches of a referenced recording less than :data:`REST_GAP_S` apart whose
#: reference specific force turns by less than this, rad, are one rest (a Ferraris hold cut in two by a
#: window the still test flagged); a turn between holds is tens of degrees.
REST_ANGLE = math.radians(1.0)
#: See :data:`REST_ANGLE`, s: a window flagged inside a rest loses it and one window either side (0.75 s
#: of 0.25-s windows; Ferraris's z_p hold, 0.77 s); BROAD's breaks, in one attitude, lie 30 s apart.
REST_GAP_S = 4 * WINDOW_S
#: A reference's rate is Earth's where its size lies within this fraction of Ω (PSINS's static INS: to
#: 1e-12; a trajectory's residual motion at rest: EuRoC 56-175 °/h, BROAD 8-51 °/h, against 15.04).
EARTH_RATE_TOL = 0.01


def earth_rate_rows(reference: Array) -> NDArray[np.bool_]:
    """The rows (n,) of a reference (n, 6) whose rate is Earth's, to :data:`EARTH_RATE_TOL` (a static
    rig's: PSINS's ring-laser INS; not Ferraris's, which leaves it out, nor a trajectory's)."""
    size = np.linalg.norm(np.asarray(reference, dtype=float)[:, :3], axis=1)
    return np.asarray(np.abs(size - earth.OMEGA_IE) <= EARTH_RATE_TOL * earth.OMEGA_IE, dtype=bool)


def rest_groups(
    t: Array, reference: Array, segments: tuple[tuple[int, int], ...]
) -> list[list[tuple[int, int]]]:
    """The still ``segments`` of a per-row ``reference`` (n, 6) gathered into rests: consecutive ones less
    than :data:`REST_GAP_S` apart whose reference specific force turns by less than :data:`REST_ANGLE`."""
    groups: list[list[tuple[int, int]]] = []
    for a, b in segments:
        if groups and t[a] - t[groups[-1][-1][1] - 1] <= REST_GAP_S:
            last = np.concatenate([reference[i:j, 3:] for i, j in groups[-1]]).mean(axis=0)
            here = reference[a:b, 3:].mean(axis=0)
            cos = float(last @ here) / float(np.linalg.norm(last) * np.linalg.norm(here))
            if cos >= math.cos(REST_ANGLE):
                groups[-1].append((a, b))
                continue
        groups.append([(a, b)])
    return groups


def check_rest_rows(t: Array, readings: Array, reference: Array | None, keep: NDArray[np.bool_] | None,
                source: str) -> None:  # fmt: skip
    """Refuse, in the words of a rest, rows whose longest run at rest (kept, finite, with a reference
    where there is one) is shorter than the noise fit needs (:data:`~sins.characterise.analysis.MIN_ROWS`
    in one stretch): a vehicle that never stands still had been told of "referenced rows without a gap".
    """
    good = np.isfinite(np.asarray(readings, dtype=float)).all(axis=1)
    if reference is not None:
        good &= np.isfinite(np.asarray(reference, dtype=float)).all(axis=1)
    if keep is not None:
        good &= np.asarray(keep, dtype=bool)
    edges = np.diff(np.r_[0, good.astype(np.int8), 0])
    longest = int(np.max(np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1), initial=0))
    if longest >= MIN_ROWS or len(t) < 2:
        return  # enough (or too few rows to say a rate: residual says so)
    dt = float(np.median(np.diff(np.asarray(t, dtype=float))))
    raise SinsInputError(
        f"{source or 'recording'}: no rest long enough for the biases: the longest stretch at rest has "
        f"{longest} rows ({longest * dt:.3g} s at {1.0 / dt:.4g} Hz); the noise fit needs {MIN_ROWS} in "
        f"one stretch ({MIN_ROWS * dt:.3g} s)"
    )


def first_rows(t: Array, seconds: float, source: str) -> NDArray[np.bool_]:
    """The rows (n,) of the first ``seconds``: ``seconds × rate`` of them (a row stands for the step after
    it: ``t < t0 + seconds``, half a step's margin against rounding; ``t ≤ t0 + 1`` had kept 201 rows of
    1 s at 200 Hz).

    Raises
    ------
    SinsInputError
        ``seconds`` not positive, or fewer rows than the noise fit needs.
    """
    if not 0.0 < seconds < math.inf:
        raise SinsInputError(f"{source}: the first {seconds:g} s: expected a positive number of seconds")
    dt = float(np.median(np.diff(t)))
    within: NDArray[np.bool_] = np.asarray(t < t[0] + seconds - 0.5 * dt, dtype=bool)
    if (kept := int(within.sum())) < MIN_ROWS:
        raise SinsInputError(
            f"{source}: the first {seconds:g} s keep {kept} rows at {1.0 / dt:.4g} Hz; the noise "
            f"fit needs at least {MIN_ROWS} ({MIN_ROWS * dt:.3g} s)"
        )
    return within


__all__ = ["EARTH_RATE_TOL", "REST_ANGLE", "REST_GAP_S", "check_rest_rows", "earth_rate_rows", "first_rows",
           "rest_groups"]  # fmt: skip
