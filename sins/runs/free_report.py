"""What a navigation without a reference says of itself: where it started, how it was aligned (and how
well that can be, from the rest's noise and a grade's bias levels) and where it ended, as lines to print
and a document to write (``sins integrate --attitude|--align``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from sins.core import earth, rotation
from sins.core.series import ImuIncrements, ImuRates, NavSeries
from sins.errors import MissingInputError, SinsInputError
from sins.io.inspection import PLAUSIBLE_HZ
from sins.nav.vertical import VerticalMode
from sins.runs.replay import FreeStart, still_drift

if TYPE_CHECKING:
    from sins.io.recording import Recording


@dataclass
class FreeReport:
    """A free navigation's account: ``lines`` to print, the figures as a document (:meth:`to_dict`)."""

    lines: list[str] = field(default_factory=list)
    document: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The figures as plain JSON values (``sins integrate --json``)."""
        return dict(self.document)


def start_position(rec: Recording, origin: tuple[float, float, float] | None) -> tuple[float, float, float]:
    """Where a recording without a reference starts: ``origin`` (latitude, longitude rad, height m), else
    its first fix."""
    if origin is not None:
        return origin
    if rec.fixes is not None and len(rec.fixes.t):
        return float(rec.fixes.lat[0]), float(rec.fixes.lon[0]), float(rec.fixes.h[0])
    raise MissingInputError(f"{rec.source}: no start position (origin): the recording has no fix", "origin")


def increments(rec: Recording) -> ImuIncrements:
    """A recording's readings as increments (rate samples integrated between their times)."""
    if isinstance(rec.imu, ImuRates):
        if len(rec.imu) < 2:
            raise SinsInputError(f"{rec.source}: need at least two rate samples")
        return rec.imu.to_increments()
    return rec.imu


def check_solution(sol: NavSeries, where: str, vertical: str) -> None:
    """Refuse a navigation whose position came out non-finite, saying what likely took it there: a free
    vertical channel diverges (e-folding in about 9.5 min near the ground) and over hours leaves floating
    point; stamps in ms read as s make a 100 Hz recording 0.1 Hz and its minutes hours."""
    if np.isfinite([sol.lat[-1], sol.lon[-1], sol.h[-1]]).all():
        return
    span_s = float(sol.t[-1] - sol.t[0])
    why = []
    if vertical == "free":
        hours = f"{span_s / 3600:.3g} h"
        why.append(f"a free vertical channel, which diverges over {hours} (--vertical hold or damp)")
    rate_hz = (len(sol.t) - 1) / span_s if span_s > 0 else math.inf
    if rate_hz < PLAUSIBLE_HZ[0]:  # no IMU's rate (sins inspect's bound): stamps in another unit
        why.append(f"times in another unit (the readings come at {rate_hz:.3g} Hz)")
    raise SinsInputError(
        f"{where}: the position came out non-finite after {span_s:.6g} s; likely causes: "
        + "; ".join([*why, "readings beyond a unit's ranges (sins inspect)"])
    )


def grade_levels(grade: str | None) -> tuple[float, float]:
    """A grade's bias levels, 1σ per axis (its unit-to-unit and turn-on spreads together), rad/s and m/s²."""
    if grade is None:
        return 0.0, 0.0
    from sins.imu import DEG_PER_H, MG, spec

    g = spec.GRADES[grade]
    return (
        math.hypot(g.gyro_bias_dph, g.gyro_turn_on_dph) * DEG_PER_H,
        math.hypot(g.accel_bias_mg, g.accel_turn_on_mg) * MG,
    )


def expected_growth(
    start: FreeStart, sol: NavSeries, vertical: tuple[VerticalMode, float] = ("free", 10.0)
) -> list[tuple[str, Any, Any, str]]:
    """The growth the rest's biases predict (:func:`sins.runs.replay.still_drift`, the vertical channel
    as ``vertical``: its mode and damping time), for the picture (horizontal and height)."""
    if start.rest is None:
        return []
    ned = still_drift(start.rest, sol.t - sol.t[0], *vertical)
    return [("from the rest's biases", sol.t, np.hypot(ned[:, 0], ned[:, 1]), "horizontal"),
            ("from the rest's biases", sol.t, -ned[:, 2], "down")]  # fmt: skip


def free_report(
    source: str,
    start: FreeStart,
    sol: NavSeries,
    align_s: float | None = None,
    grade: str | None = None,
    heading_given: bool = False,
    vertical: tuple[VerticalMode, float] = ("free", 10.0),
) -> FreeReport:
    """What a navigation without a reference says: its start, the alignment on ``align_s`` seconds of rest
    (with ``grade``'s bias levels, its heading given or gyrocompassed) and the solution's offsets, beside
    what the rest's biases predict with the vertical channel as navigated (``vertical``: its mode and
    damping time)."""

    init = start.initial
    offset = earth.ned_offset(sol.lat[-1], sol.lon[-1], sol.h[-1], init.lat, init.lon, init.h)
    roll, pitch, yaw = (math.degrees(float(a)) for a in rotation.euler_from_quat(init.q_nb))
    span = float(sol.t[-1] - sol.t[0])
    where = f"{math.degrees(init.lat):.6f}°, {math.degrees(init.lon):.6f}°, {init.h:g} m"
    lines = [f"{source}: {len(sol.t) - 1} intervals without a reference, from {where} at rest"]
    doc: dict[str, Any] = {
        "imu": source, "truth": None, "start": start.how, "start_s": float(sol.t[0]),
        "origin_deg": [math.degrees(init.lat), math.degrees(init.lon), init.h],
        "attitude_deg": [roll, pitch, yaw], "duration_s": span,
        "final_offset_ned_m": [float(x) for x in offset],
        "final_horizontal_offset_m": float(np.hypot(offset[0], offset[1])),
        "final_velocity_ned_mps": [float(x) for x in sol.v_n[-1]],
    }  # fmt: skip
    if start.rest is not None:
        doc["alignment"] = _alignment(start, align_s, grade, heading_given, lines)
        predicted = still_drift(start.rest, np.array([span]), *vertical)[0]
        doc["predicted_offset_ned_m"] = [float(x) for x in predicted]
        level = float(np.hypot(predicted[0], predicted[1]))
        channel = {"free": "free: the vertical accelerometer bias and the level velocity's Coriolis force",
                   "hold": "held", "damp": "damped"}[vertical[0]]  # fmt: skip
        lines.append(
            f"a unit still all along drifts by its rest's biases alone: {level:.4g} m level, "
            f"{-predicted[2]:+.4g} m up after {span:.4g} s (its rest's mean readings navigated: the level "
            f"gyro bias through the Schuler loop, the vertical channel {channel})"
        )
    else:
        lines.append(f"attitude given: roll {roll:.4f}°, pitch {pitch:.4f}°, yaw {yaw:.4f}°")
    speed = float(np.linalg.norm(sol.v_n[-1]))
    lines.append(
        f"after {span:.6g} s: {offset[0]:+.4g} m north, {offset[1]:+.4g} m east, {offset[2]:+.4g} m down of "
        f"the start ({doc['final_horizontal_offset_m']:.4g} m level); velocity {speed:.4g} m/s; for a unit "
        "that stood still, these are its errors"
    )
    return FreeReport(lines, doc)


def _alignment(
    start: FreeStart, align_s: float | None, grade: str | None, heading_given: bool, lines: list[str]
) -> dict[str, Any]:
    """The alignment and its stated accuracy, said in ``lines``; its JSON object."""
    from sins.imu import DEG_PER_H, MG

    rest = start.rest
    assert rest is not None and start.tilt_sigma is not None
    a = rest.attitude
    noise_tilt, noise_heading = _noise_accuracy(start)
    tilt = math.degrees(start.tilt_sigma)
    per_mg = math.degrees(MG / earth.G0)
    per_dph = math.degrees(DEG_PER_H / (earth.OMEGA_IE * math.cos(rest.lat)))
    levels = f"the {grade} grade's bias levels" if grade else "the noise alone (no --grade)"
    roll, pitch, yaw = math.degrees(a.roll), math.degrees(a.pitch), math.degrees(a.yaw or 0.0)
    lines.append(
        f"aligned on the first {align_s:g} s at rest ({rest.rows} rows), navigating from "
        f"{start.initial_t:.6g} s: roll {roll:.4f}°, pitch {pitch:.4f}° (1σ {tilt:.2g}° from {levels}; a "
        f"level accelerometer bias tilts them by {per_mg:.3g}° per mg)"
    )
    doc: dict[str, Any] = {
        "seconds": align_s, "rows": rest.rows, "roll_deg": roll, "pitch_deg": pitch, "yaw_deg": yaw,
        "tilt_sigma_deg": tilt, "tilt_sigma_noise_deg": math.degrees(noise_tilt), "grade": grade,
        "heading_given": heading_given, "deg_per_mg": per_mg, "heading_deg_per_dph": per_dph,
        "rest": rest.to_dict(),
    }  # fmt: skip
    if start.heading_sigma is None:
        lines.append(f"heading given: {yaw:.4f}°")
        return doc
    heading = math.degrees(start.heading_sigma)
    lines.append(
        f"heading {yaw:.4f}° by gyrocompassing (1σ {heading:.2g}° from {levels}; an east gyro bias turns it "
        f"by {per_dph:.3g}° per °/h)"
    )
    return doc | {"heading_sigma_deg": heading, "heading_sigma_noise_deg": math.degrees(noise_heading)}


def _noise_accuracy(start: FreeStart) -> tuple[float, float]:
    from sins.characterise.bias import alignment_accuracy

    assert start.rest is not None
    return alignment_accuracy(start.rest)


__all__ = [
    "FreeReport",
    "check_solution",
    "expected_growth",
    "free_report",
    "grade_levels",
    "increments",
    "start_position",
]
