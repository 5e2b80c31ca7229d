"""Reference epochs that contradict the readings grossly, set aside before a fit against a trajectory.

A reference is a measurement too, and its making can leave errors no sensor model explains: a motion
capture's markers lost and the attitude slerped across the gap, a position glitch differentiated into a
velocity that spikes for one step (EuRoC's laser-tracker positions, differentiated, spike by up to
12 m/s), a marker swap. An interval whose end lies on such an epoch sits tens of the residuals' own
spread off the fit. Least squares, whose standard errors come from those residuals, is pulled by it and
then holds or refuses coefficients the rest of the reference determines: three EuRoC recordings with
their velocity differentiated from their positions had ``regression`` refused ("accel bias x was held
at zero and then moved ...: the fit is unstable").

The screen (:func:`screened`): a robust fit (Huber's weights, the same coefficients held), and every
interval whose residual lies beyond :data:`SCREEN_Z` robust standard deviations (per recording, sensor
and axis: the residuals' median absolute deviation / 0.6745) has its span's reference epochs, ends
included, set aside (:func:`set_aside`). An interval formed across the hole then has ends the reference
got right: an interval's residual reads its two ends' states and the readings between, nothing else.
Passes repeat until none is found, at most :data:`MAX_PASSES`.

An error of the unit that the seed model lacks (a scale nonlinearity in the fastest turns) makes the
largest residuals too, and those are a learner's to learn; so by default a fit is screened only where
it is refused on every interval (:func:`fitted_screened`, :data:`SCREENS`), and a fit made on every
interval names the intervals the screen would take (:func:`suspect_line`).

One gross error is told by the reference alone, and set aside before every fit (but ``never``): a span
a converter filled by interpolation (:func:`filled`, :mod:`sins.io.filled`: one constant rate for
0.25 s or longer while the gyro's readings do not). Three 1 s gaps slerped into each of three EuRoC
recordings cost 1-4° of judged attitude, and an error of the unit cannot look like this.

What judges a model (:func:`sins.compensation.judging.open_loop`, ``sins evaluate``) is not screened:
it judges against the reference as it is.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from sins.compensation import identifiability, interval_fit, several
from sins.compensation.intervals import INTERVAL_S, choose_intervals
from sins.core.series import ReferencedRecording
from sins.io.filled import FILLED_MIN_S, FILLED_Z, filled_spans, spans_said

Array = NDArray[np.float64]

#: An interval this many robust standard deviations off the fit, or more, is a gross error of the
#: reference, set aside. Normal residuals would allow 7 (the 60,000 values of 10,000 intervals pass it
#: by chance once in 6.5 million fits), but real ones have tails: the clean references sins holds reach
#: 16 (BROAD's unit B, its trials cut in three and fitted together, in trial 18's fast turns; each trial
#: whole 11.0 and 10.5, EuRoC's eleven sequences 9.6, the PSINS drive 3.4), and none of them is touched.
#: Gross errors made of them (a velocity differentiated from positions, a slerped gap) reach 31-600.
SCREEN_Z = 20.0
#: Passes of fit and screen at most (a pass sets aside what the last one's intervals showed; the
#: intervals walked again across the holes may end on a gross epoch the last ones skipped).
MAX_PASSES = 3
#: When a fit against a trajectory sets its reference's gross errors aside (:func:`fitted_screened`):
#: only where the fit is refused without (the default: an error of the unit that the seed model lacks,
#: a scale nonlinearity in the fastest turns, makes the largest residuals too, and a screen of every fit
#: would take from a learner what it is there to learn), before every fit, or never.
SCREENS = ("refused", "always", "never")
DEFAULT = "refused"
#: The smallest residual spread screened against, gyro rad and accelerometer m/s an interval: an exact
#: reference's residuals are rounding, whose spread would make any interval a gross error (a
#: navigation-grade gyro's noise over 1 s is 3e-7 rad, an accelerometer's 2e-4 m/s).
FLOOR = (1e-9, 1e-8)

_Made = TypeVar("_Made")
#: What an interval far off the fit may be, for the lines a fit prints.
_WHY = (
    "the reference contradicts the readings there (a glitch, a gap filled by interpolation), or the unit "
    "errs there as its seed model does not (a scale nonlinearity in the fastest turns: a learner's to learn)"
)


def suspect_line(name: str, gyro_resid: Array, accel_resid: Array) -> str | None:
    """A line for a fit made on every interval whose residuals hold some beyond :data:`SCREEN_Z`; None
    where none is."""
    bad, z = gross(gyro_resid, accel_resid)
    if not bad.any():
        return None
    return (
        f"{name}: {int(bad.sum())} interval(s) up to {float(z.max()):.0f} robust σ off the fit, beyond "
        f"{SCREEN_Z:g}: {_WHY}; sins fit --screen always sets them aside"
    )


#: Residuals of a robust fit: each recording's gyro (k, 3) rad and accelerometer (k, 3) m/s per interval.
Residuals = Callable[[list[ReferencedRecording]], list[tuple[Array, Array]]]


@dataclass(frozen=True)
class SetAside:
    """What of one recording's reference was set aside: the spans of time, s (the recording's clock),
    and the largest residual among them, in robust standard deviations."""

    source: str
    spans_s: tuple[tuple[float, float], ...]
    largest_z: float
    #: The spans found filled by interpolation (:func:`filled`), s.
    filled_s: tuple[tuple[float, float], ...] = ()

    def found(self) -> bool:
        """Whether anything of the reference was set aside."""
        return bool(self.spans_s or self.filled_s)

    def seconds(self) -> float:
        """The reference's time set aside, s."""
        return float(sum(b - a for a, b in (*self.spans_s, *self.filled_s)))

    def line(self, name: str) -> str:
        """What a fit says of it, one line."""
        said = []
        if self.filled_s:
            said.append(
                f"{spans_said(self.filled_s)} of its reference set aside as filled by interpolation: it "
                f"turns at one rate for {FILLED_MIN_S:g} s or longer where the gyro's readings turn away "
                f"from one rate {FILLED_Z:g}× more than their noise would (a gap a converter slerped)"
            )
        if self.spans_s:
            seconds = sum(b - a for a, b in self.spans_s)
            said.append(
                f"{len(self.spans_s)} span(s) of its reference set aside ({seconds:.1f} s in all; "
                f"intervals up to {self.largest_z:.0f} robust σ off the fit, beyond {SCREEN_Z:g}): {_WHY}"
            )
        return f"{name}: " + "; and ".join(said)

    def to_dict(self) -> dict[str, Any]:
        """As plain JSON values (a fit's ``--json``: ``set_aside``)."""
        return {
            "source": self.source,
            "spans_s": [list(s) for s in self.spans_s],
            "largest_z": self.largest_z,
            "filled_spans_s": [list(s) for s in self.filled_s],
        }


def filled(rec: ReferencedRecording) -> tuple[tuple[float, float], ...]:
    """The spans of ``rec``'s reference filled by interpolation (:func:`sins.io.filled.filled_spans`,
    against each increment's mean rate at its middle): the times of their inner epochs."""
    mid, w, _ = rec.imu.mean_rates()
    return filled_spans(rec.reference.t, rec.reference.q_nb, mid, w)


def gross(gyro_resid: Array, accel_resid: Array) -> tuple[NDArray[np.bool_], Array]:
    """Which intervals are gross errors (beyond :data:`SCREEN_Z` on any axis of either sensor), and each
    interval's largest robust z."""
    z = np.zeros(len(gyro_resid))
    for resid, floor in zip((gyro_resid, accel_resid), FLOOR, strict=True):
        centre = np.median(resid, axis=0)
        spread = np.maximum(np.median(np.abs(resid - centre), axis=0) / 0.6745, floor)
        z = np.maximum(z, (np.abs(resid - centre) / spread).max(axis=1))
    return z > SCREEN_Z, z


def without(rec: ReferencedRecording, spans_s: list[tuple[float, float]]) -> ReferencedRecording:
    """``rec`` with its reference's epochs within any of ``spans_s`` (ends included) left out."""
    t = rec.reference.t
    out = np.zeros(len(t), dtype=bool)
    for a, b in spans_s:
        out |= (t >= a) & (t <= b)
    return replace(rec, reference=rec.reference.at(np.flatnonzero(~out)))


def set_aside(
    recs: list[ReferencedRecording], residuals: Residuals, interval_s: float = INTERVAL_S
) -> tuple[list[ReferencedRecording], list[SetAside]]:
    """``recs`` with the reference epochs of their gross intervals set aside (see the module docstring),
    and what was set aside of each. ``residuals(recs)`` is the robust fit's; where it cannot be made
    (``ValueError``: the recordings do not determine the model), nothing is set aside and the fit proper
    says why."""
    out = list(recs)
    spans: list[list[tuple[float, float]]] = [[] for _ in recs]
    largest = np.zeros(len(recs))
    for _ in range(MAX_PASSES):
        try:
            found = residuals(out)
        except ValueError:
            break
        if not any(gross(g, a)[0].any() for g, a in found):
            break
        for r, (g, a) in enumerate(found):
            bad, z = gross(g, a)
            if not bad.any():
                continue
            iv = choose_intervals(out[r], interval_s)
            t = out[r].imu.t
            new = [(float(t[iv.start[k]]), float(t[iv.stop[k]])) for k in np.flatnonzero(bad)]
            spans[r] += new
            largest[r] = max(largest[r], float(z[bad].max()))
            out[r] = without(out[r], new)
    aside = [
        SetAside(rec.source, tuple(sorted(s)), float(z))
        for rec, s, z in zip(recs, spans, largest, strict=True)
    ]
    return out, aside


def screened(
    recs: list[ReferencedRecording],
    interval_s: float = INTERVAL_S,
    grade: str = identifiability.DEFAULT_GRADE,
) -> tuple[list[ReferencedRecording], tuple[SetAside, ...]]:
    """``recs`` with their references' gross errors set aside (:func:`set_aside`), found by a robust fit
    of the seed model (Huber's weights; on several recordings one fit, each its own biases) that holds
    what the recordings do not determine for a unit of ``grade``."""
    bounds = identifiability.class_bounds(grade)

    def residuals(rs: list[ReferencedRecording]) -> list[tuple[Array, Array]]:
        if len(rs) == 1:
            holds = identifiability.assess(rs[0], interval_s, bounds)
            one = interval_fit.fit_intervals(
                rs[0], interval_s=interval_s, g_sensitivity=False, robust=True, holds=holds
            )
            assert one.residuals is not None
            return [one.residuals]
        held = identifiability.assess_several(rs, interval_s, bounds).reasons
        return list(several.fit_several(rs, interval_s=interval_s, robust=True, held=held).residuals)

    out, aside = set_aside(recs, residuals, interval_s)
    return out, tuple(aside)


def fitted_screened(
    make: Callable[[list[ReferencedRecording]], _Made],
    recs: list[ReferencedRecording],
    interval_s: float = INTERVAL_S,
    grade: str = identifiability.DEFAULT_GRADE,
    screen: str = DEFAULT,
) -> tuple[_Made, list[ReferencedRecording], tuple[SetAside, ...]]:
    """``make(recs)`` (a fit), with the references' gross errors set aside as ``screen`` says
    (:data:`SCREENS`): ``refused``, where ``make`` refuses the recordings as they are (``ValueError``)
    and :func:`screened` sets something aside, ``make`` again on what is left (else the refusal stands);
    ``always``, :func:`screened` first; ``never``, ``make(recs)`` alone. Unless ``never``, the spans
    :func:`filled` finds are set aside before all. Returns the fit, the recordings it was made on and what
    was set aside of each."""
    if screen not in SCREENS:
        raise ValueError(f"screen {screen!r} (known: {', '.join(SCREENS)})")
    nothing = tuple(SetAside(rec.source, (), 0.0) for rec in recs)
    if screen == "never":
        return make(recs), recs, nothing
    fills = [filled(rec) for rec in recs]
    recs = [without(rec, list(f)) if f else rec for rec, f in zip(recs, fills, strict=True)]

    def with_filled(aside: tuple[SetAside, ...]) -> tuple[SetAside, ...]:
        return tuple(replace(a, filled_s=f) for a, f in zip(aside, fills, strict=True))

    if screen == "always":
        recs, aside = screened(recs, interval_s, grade)
        return make(recs), recs, with_filled(aside)
    try:
        return make(recs), recs, with_filled(nothing)
    except ValueError:
        trimmed, aside = screened(recs, interval_s, grade)
        if not any(a.spans_s for a in aside):
            raise
    return make(trimmed), trimmed, with_filled(aside)


__all__ = [
    "DEFAULT",
    "FLOOR",
    "MAX_PASSES",
    "SCREENS",
    "SCREEN_Z",
    "SetAside",
    "filled",
    "fitted_screened",
    "gross",
    "screened",
    "set_aside",
    "suspect_line",
    "without",
]
