"""Free-inertial outages over a referenced recording: how far the readings, as corrected, carry a position
when its aiding drops out for ``length_s``, from every second of the recording.

From each start, every :data:`EVERY_S` from the reference's first epoch while an outage fits within it,
the readings navigate free inertial from the reference's state there for ``length_s``
(:func:`sins.compensation.judging.free_inertial`: attitude, velocity and position at the reference's
point, the vertical held to its height); the error is the horizontal distance from the reference's
position at the outage's end, where a position fix would return. The figures are its RMS, median and 95th
percentile over the outages, beside how far the reference's own positions are from its velocities'
integral over them (PSINS's FOG-INS: 62 mm RMS over 2 s at 14 m/s; BROAD's motion capture and EuRoC's
references: 0.04-0.95 % of their displacement, under 2 cm at 2 s). An accelerometer bias ``b`` held level
leaves ``b T²/2``; a tilt ``δ`` leaves ``g δ T²/2``; a gyro bias ``ω`` tilting the unit leaves ``g ω
T³/6``.

The strapdown's Earth model is at the reference's latitude, nominal where a room's frame does not give it:
its Earth rate then differs from the room's by up to 15 °/h, which on BROAD's unit B moved a 5 s outage's
error by 9 mm of 1.17 m (`tools/broad_free_inertial.py`'s navigation, numpy and scipy alone, leaves the
rate out: `tests/test_outages.py`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.core import earth
from sins.core.series import ImuIncrements, ReferencedRecording
from sins.errors import SinsInputError

Array = NDArray[np.float64]

#: Seconds between the starts of two outages (each second of a recording starts one).
EVERY_S = 1.0
#: The largest share of the reference's own displacement over the outages (its velocities') by which its
#: positions may differ from it (BROAD's and EuRoC's references: under 1 %).
POSITION_MISMATCH = 0.25


@dataclass(frozen=True)
class Outages:
    """Outages of ``length_s``: each one's start (s, the readings' clock) and its horizontal error at the
    end (m)."""

    length_s: float
    start_s: Array
    horizontal_m: Array
    #: The RMS over the outages of the horizontal distance between the reference's own displacement and
    #: its velocities' integral, m: how far the reference itself is from one answer (errors near it are
    #: as much the reference's as the unit's).
    reference_mismatch_m: float = 0.0

    def summary(self) -> dict[str, Any]:
        """The count, the RMS, median and 95th percentile of the horizontal error and the reference's own
        mismatch, m."""
        e = self.horizontal_m
        return {"length_s": self.length_s, "outages": len(e), "rms_m": float(np.sqrt(np.mean(e * e))),
                "median_m": float(np.median(e)), "p95_m": float(np.percentile(e, 95)),
                "reference_mismatch_m": self.reference_mismatch_m}  # fmt: skip


def outages(
    imu: ImuIncrements, rec: ReferencedRecording, length_s: float, every_s: float = EVERY_S
) -> Outages:
    """The outages of ``length_s`` of readings ``imu`` (``rec``'s, as corrected), one every ``every_s``
    (see the module docstring).

    Raises
    ------
    SinsInputError
        naming the recording: a length that is not positive and finite, or longer than the reference;
        a reference whose positions do not follow its velocities.
    """
    from sins.compensation import judging

    where = rec.source or "recording"
    if not (np.isfinite(length_s) and length_s > 0):
        raise SinsInputError(f"{where}: an outage of {length_s:g} s: give a positive number of seconds")
    first = max(float(rec.reference.t[0]), float(imu.t[0]))
    last = min(float(rec.reference.t[-1]), float(imu.t[-1]))
    starts = np.arange(first, last - length_s + 1e-9, every_s)
    if not len(starts):
        raise SinsInputError(
            f"{where}: an outage of {length_s:g} s does not fit within the reference's {last - first:.3g} s"
        )
    mismatch = _check_positions(rec, starts, length_s)
    errors = [judging.free_inertial(imu, rec, s, s + length_s)[2].horizontal_m[-1] for s in starts]
    return Outages(float(length_s), starts, np.asarray(errors, dtype=float), mismatch)


def _check_positions(rec: ReferencedRecording, starts: Array, length_s: float) -> float:
    """How far the reference's positions are from its velocities' integral over the outages (horizontal
    RMS, m); refused above :data:`POSITION_MISMATCH` of the velocities' own displacement and above 1 cm:
    an outage is judged by position, and a file written with none (zeros, say) would give the unit's own
    travel as its error."""
    from scipy.integrate import cumulative_trapezoid

    ref = rec.reference
    moved = earth.local_ned(ref.lat, ref.lon, ref.h, float(ref.lat[0]), float(ref.lon[0]), float(ref.h[0]))
    travelled = cumulative_trapezoid(ref.v_n, ref.t, axis=0, initial=0.0)
    ends = [np.searchsorted(ref.t, [s, s + length_s]).clip(0, len(ref.t) - 1) for s in starts]
    by_position = np.array([moved[b, :2] - moved[a, :2] for a, b in ends])
    by_velocity = np.array([travelled[b, :2] - travelled[a, :2] for a, b in ends])
    rms = lambda x: float(np.sqrt(np.mean(np.sum(x * x, axis=1))))  # noqa: E731
    mismatch, own = rms(by_position - by_velocity), rms(by_velocity)
    if mismatch > max(POSITION_MISMATCH * own, 0.01):
        raise SinsInputError(
            f"{rec.source or 'recording'}: its reference's positions do not follow its velocities over "
            f"outages of {length_s:g} s ({mismatch:.3g} m RMS apart, the velocities moving {own:.3g} m): "
            "an outage is judged by position; give the positions the reference measured"
        )
    return mismatch


__all__ = ["EVERY_S", "POSITION_MISMATCH", "Outages", "outages"]
