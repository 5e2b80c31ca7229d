"""An aided run's position error over its GNSS outage windows: the samples a window holds, and its error.

One rule for simulated scenarios and real recordings alike: a window ``(start, end)`` holds the IMU
samples after the fix that opens it and before the fix that closes it, so its last sample's error is
the drift no fix has corrected yet. A window that runs past the run's last sample holds every sample
from its start to the end.

The fixes sit on the windows' edges up to rounding, and so do the samples that take them; a sample
within :data:`EDGE_S` of an edge is the fix's, not the window's. 1 µs is far above the rounding of
times up to days (an ulp of 1e5 s is 1.5e-11 s; times read from text or summed from steps carry a few
ulp) and far below any IMU's step (10 ms at 100 Hz, 1 ms at 1 kHz), so it neither lets an edge's
sample into the window nor drops one that lies in it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

#: How close to a window's edge a sample is the edge's fix's, not the window's, s.
EDGE_S = 1e-6


@dataclass(frozen=True)
class OutageError:
    """The horizontal position error of an aided run over one outage window, m.

    ``final_m`` is at the last IMU sample before the window's end (or the run's end), before any fix
    corrects it; ``max_m`` the largest within the window.
    """

    start_s: float
    end_s: float
    final_m: float
    max_m: float


def window_rows(t: NDArray[np.float64], start_s: float, end_s: float) -> NDArray[np.intp]:
    """The rows of the sample times ``t`` (s, increasing) inside the window ``(start_s, end_s)``.

    Those after the fix at ``start_s`` and before the fix at ``end_s`` (both more than :data:`EDGE_S`
    away); a window ending at or after ``t[-1]`` holds every sample after its start. Empty when none is.
    """
    after = t > start_s + EDGE_S
    if end_s < t[-1]:
        return np.flatnonzero(after & (t < end_s - EDGE_S))
    return np.flatnonzero(after)


def outage_errors(
    outages: Sequence[tuple[float, float]], t: NDArray[np.float64], horizontal_m: NDArray[np.float64]
) -> list[OutageError]:
    """Each window's horizontal error at its last sample (:func:`window_rows`) and its largest, m.

    ``t`` (n,) the run's sample times, s; ``horizontal_m`` (n,) its horizontal error there. Windows
    that start at or after the run's last sample, or hold no sample, are left out.
    """
    windows = []
    for start, end in outages:
        if start >= t[-1]:
            continue
        inside = window_rows(t, start, end)
        if inside.size:
            error = horizontal_m[inside]
            windows.append(OutageError(start, end, float(error[-1]), float(error.max())))
    return windows


__all__ = [
    "EDGE_S",
    "OutageError",
    "outage_errors",
    "window_rows",
]
