"""Spans of a reference attitude filled by interpolation, told by the reference and the gyro alone.

A converter that loses a motion capture's markers fills the gap: the attitude slerped, the position a
straight line (LGC-Net's TUM-VI preprocessing, for one). A slerp turns at one constant rate; a measured
attitude never holds its rate, to 1 % of its own typical change from one epoch to the next, for
:data:`FILLED_MIN_S` (the references sins holds: 14 ms at most). And a unit that truly turns at one rate
(at rest, on a rate table) reads one rate, to its noise. So where the reference turns at one rate that
long while the gyro's readings turn away from one rate by more than :data:`FILLED_Z` times what their
noise alone would, the span was filled, not measured. :mod:`sins.compensation.screening` sets such
spans aside before a fit; :func:`sins.io.inspection.inspect` names them. A gap in the position alone
(a laser tracker's, the attitude measured throughout) is not told this way.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: A reference that turns at one constant rate this long, s, or longer, while the readings do not, was
#: filled by interpolation. Measured references hold a rate for 14 ms at most (BROAD, upsampled from its
#: capture; EuRoC's 0-10 ms); a converter's slerp across a lost marker for the gap.
FILLED_MIN_S = 0.25
#: One rate: each epoch's change of rate from the last within this fraction of the recording's median
#: change where its rate changes (a slerp's is rounding, 1e-12 of it and less; float32 quaternions'
#: 1e-3). A reference upsampled from a slower capture holds its rate exactly between the capture's
#: samples: those epochs are not counted in the median.
FILLED_STEP = 1e-2
#: ... while the gyro's readings over the span turn away from one rate by more than this many times
#: what their noise alone would (:func:`_departure`): a unit at rest or on a rate table, whose reference
#: holds one rate truly, reads about 1 (rate samples) to 2 (increments: the trapezoid that makes them
#: halves the noise's step-to-step spread it is measured by); slerped 1 s gaps in EuRoC's flights 24-350.
FILLED_Z = 10.0
#: A reference turning slower than this, rad/s, holds one attitude: a simulation's exact rest, whose
#: unit's bias may wander over minutes (a slerp between two measured attitudes turns by their noise at
#: least, 1e-4 rad over the gap).
_AT_REST = 1e-9


def filled_spans(t_ref: Array, q_nb: Array, t: Array, w: Array) -> tuple[tuple[float, float], ...]:
    """The spans of a reference attitude filled by interpolation (see the module docstring).

    Parameters
    ----------
    t_ref, q_nb : the reference's epochs (m,) s and attitudes (m, 4), scalar-last
    t, w : the gyro's readings (n, 3) rad/s at times (n,) s (an increment's mean rate at its middle)

    Returns
    -------
    tuple
        ``(first, last)`` s of each span's inner epochs: those the interpolation made, its ends left out.
    """
    from scipy.spatial.transform import Rotation  # here: reading a recording need not import scipy.spatial

    if len(t_ref) < 4 or len(w) < 3:
        return ()
    q = Rotation.from_quat(q_nb)
    rate = (q[:-1].inv() * q[1:]).as_rotvec() / np.diff(t_ref)[:, None]  # body axes, each step
    change = np.linalg.norm(np.diff(rate, axis=0), axis=1)  # at each inner epoch
    scale = float(np.quantile(change, 0.99))
    moving = change[change > 1e-9 * scale]
    if not scale > 0.0 or len(moving) == 0:  # an exact reference at rest or at one rate throughout
        return ()
    typical = float(np.median(moving))
    step = np.diff(w, axis=0)
    noise = np.median(np.abs(step - np.median(step, axis=0)), axis=0) / 0.6745 / np.sqrt(2.0)
    edges = np.diff(np.concatenate([[0], (change <= FILLED_STEP * typical).astype(np.int8), [0]]))
    spans = []
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        # inner epochs a+1 .. b changed rate by nothing: epochs a .. b+1 lie on one arc
        if t_ref[b + 1] - t_ref[a] < FILLED_MIN_S or not np.abs(rate[a]).max() > _AT_REST:
            continue  # too short, or an exact reference's rest (a slerp between measured ends turns)
        inside = (t >= t_ref[a]) & (t <= t_ref[b + 1])
        if inside.sum() >= 3 and _departure(w[inside], t[inside], noise) > FILLED_Z:
            spans.append((float(t_ref[a + 1]), float(t_ref[b])))
    return tuple(spans)


def spans_said(spans: tuple[tuple[float, float], ...]) -> str:
    """``spans`` (s) as the reports say them: how many, their seconds in all, the first three."""
    where = ", ".join(f"{a:.2f}-{b:.2f} s" for a, b in spans[:3]) + (", ..." if len(spans) > 3 else "")
    return f"{len(spans)} span(s) ({sum(b - a for a, b in spans):.1f} s in all: {where})"


def _departure(w: Array, t: Array, noise: Array) -> float:
    """How far the gyro's readings ``w`` (k, 3) at ``t`` (k,) turn away from one rate over their span, in
    units of what their ``noise`` (3,) alone would turn: the RMS of the angle their departure from their
    mean rate integrates to, against white noise's (a Brownian bridge's, ``σ √(dt T / 6)``, ``σ`` from
    the readings' step-to-step differences), the largest axis. Integrated, a rate's swings add up while
    noise averages out: a 1 s slerp across a flight's gap reads 24 and more, a unit at one rate 1-2."""
    dt = float(np.median(np.diff(t)))
    angle = np.cumsum((w - w.mean(axis=0)) * dt, axis=0)
    rms = np.sqrt(np.mean(angle**2, axis=0))
    expected = np.maximum(noise, np.finfo(float).tiny) * np.sqrt(dt * len(t) * dt / 6.0)
    return float((rms / expected).max())


__all__ = ["FILLED_MIN_S", "FILLED_STEP", "FILLED_Z", "filled_spans", "spans_said"]
