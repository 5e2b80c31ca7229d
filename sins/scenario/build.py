"""A validated scenario turned into the continuous motion it describes (with the geodesy that places it),
its sample count, and the check that its path stays off the poles."""

from __future__ import annotations

import math

import numpy as np

from sins import io
from sins.core import earth
from sins.core.earth import MAX_LAT_DEG
from sins.core.series import NavSeries
from sins.errors import SinsInputError
from sins.nav import motion, trajectory
from sins.scenario.schema import Scenario, SegmentsSpec, TruthFileSpec, WaypointsSpec
from sins.scenario.validate import MAX_DURATION_S


def _check_level(p: np.ndarray, where: object) -> None:
    """Refuse waypoints whose path has no level direction somewhere: a leg straight up or down, or a
    waypoint whose neighbours lie level-wise on one spot (the path turns back on itself there). The
    attitude follows the level velocity, which such a path makes zero (before: NaN attitudes, numpy's
    warnings, and a refusal that blamed the inputs' size)."""
    legs = np.linalg.norm(np.diff(p, axis=0)[:, :2], axis=1)
    through = np.linalg.norm((p[2:] - p[:-2])[:, :2], axis=1)
    for i in np.flatnonzero(legs == 0.0):
        raise SinsInputError(f"{where}: waypoint[{i + 2}]: straight up or down from waypoint[{i + 1}]: "
                             "the path has no level direction there (the attitude follows it)")  # fmt: skip
    for i in np.flatnonzero(through == 0.0):
        raise SinsInputError(f"{where}: waypoint[{i + 2}]: the path turns back on itself there (waypoints "
                             f"{i + 1} and {i + 3} level at one place): no level direction")  # fmt: skip


#: A truth file's velocities, integrated from its first position, may leave a row this far from its
#: recorded position, m, ...
TRUTH_DRIFT_M = 10.0
#: ... or this share of the path recorded up to it: a solution's velocities and positions agree to
#: centimetres over minutes (a velocity bias of 1 cm/s: 36 m an hour, against tens of km travelled),
#: while a velocity in another frame (east, north, up) or unit (km/h) misses by the path's own length.
TRUTH_DRIFT_SHARE = 0.05


def _check_truth(truth: NavSeries, path: object) -> None:
    """Refuse a truth file whose velocities do not integrate (trapezoids on the ellipsoid) to its
    positions: the motion is made from its velocities and attitudes, its first position the start
    (:class:`~sins.nav.motion.RecordedMotion`), so the file's other positions would be set aside
    without a word."""
    from scipy.integrate import cumulative_trapezoid

    lat, lon, h = truth.lat, np.unwrap(truth.lon), truth.h
    r_m, r_n = earth.radii(lat)
    north, east = r_m + h, (r_n + h) * np.cos(lat)  # metres a radian of latitude, of longitude

    def integral(rate: np.ndarray) -> np.ndarray:
        return np.asarray(cumulative_trapezoid(rate, truth.t, initial=0.0))

    off = np.sqrt(
        ((integral(truth.v_n[:, 0] / north) - (lat - lat[0])) * north) ** 2
        + ((integral(truth.v_n[:, 1] / east) - (lon - lon[0])) * east) ** 2
        + (integral(-truth.v_n[:, 2]) - (h - h[0])) ** 2
    )
    steps = np.linalg.norm(earth.ned_offset(lat[1:], lon[1:], h[1:], lat[:-1], lon[:-1], h[:-1]), axis=-1)
    travelled = np.concatenate([[0.0], np.cumsum(steps)])
    bad = np.flatnonzero(off > np.maximum(TRUTH_DRIFT_M, TRUTH_DRIFT_SHARE * travelled))
    if bad.size:
        k = int(bad[0])
        raise SinsInputError(
            f"{path}: its velocities do not integrate to its positions: at t = {truth.t[k]:g} s they lead "
            f"{off[k]:.3g} m from the recorded position, {travelled[k]:.3g} m along the recorded path "
            "(a velocity in another frame than north, east, down, or in another unit?); the motion is "
            "made from the velocities"
        )


def build_motion(scenario: Scenario) -> motion.Motion:
    """The continuous motion a scenario describes.

    Segments compile to a :class:`~sins.nav.motion.SegmentMotion`; waypoints to a
    :class:`~sins.nav.motion.WaypointMotion` starting at the first waypoint; a truth file (read here,
    not when the scenario is loaded) to a :class:`~sins.nav.motion.RecordedMotion`.

    Raises
    ------
    SinsInputError
        the truth file is missing, cannot be read, has fewer than 4 rows, spans more than
        :data:`~sins.scenario.validate.MAX_DURATION_S`, or its velocities do not integrate to its
        positions (:data:`TRUTH_DRIFT_M`, :data:`TRUTH_DRIFT_SHARE`).
    """
    spec = scenario.trajectory
    if isinstance(spec, SegmentsSpec):
        return motion.SegmentMotion.from_segments(spec.start, spec.segments, spec.oscillations)
    if isinstance(spec, WaypointsSpec):
        p = np.array(spec.points_ned)
        # The path starts at the first waypoint; place it relative to [initial].
        r_m, r_n = earth.radii(spec.lat)
        lat0 = spec.lat + p[0, 0] / (r_m + spec.h)
        lon0 = spec.lon + p[0, 1] / ((r_n + spec.h) * math.cos(spec.lat))
        _check_level(p, scenario.source or scenario.name)
        return motion.WaypointMotion.from_waypoints(lat0, lon0, spec.h - p[0, 2], p, np.array(spec.speeds))
    if not spec.path.is_file():
        raise SinsInputError(f"{scenario.source or scenario.name}: truth.file: no such file: {spec.path}")
    truth = io.read_truth(spec.path)
    if len(truth.t) < 4:
        raise SinsInputError(f"{spec.path}: a truth trajectory needs at least 4 rows to define a motion")
    span = float(truth.t[-1] - truth.t[0])
    if not span <= MAX_DURATION_S:
        raise SinsInputError(
            f"{spec.path}: the truth spans {span:g} s (column 't'), more than a scenario's "
            f"{MAX_DURATION_S:g} s"
        )
    _check_truth(truth, spec.path)
    return motion.RecordedMotion.from_series(truth)


def unsampled_end(scenario: Scenario) -> str:
    """What of a segment or waypoint motion's end falls after its last sample, in words ("" where
    nothing does, and for a truth file, which the samples cover as it was recorded): a run has
    ``floor(duration · rate)`` intervals, so at 1 Hz a 2.5 s motion runs 2 s and never ends its turn."""
    if isinstance(scenario.trajectory, TruthFileSpec):
        return ""
    m = build_motion(scenario)
    span = m.t_end - m.t_start
    covered = trajectory.interval_count(span, scenario.rate_hz) / scenario.rate_hz
    if span - covered <= 1e-9 * max(1.0, span):
        return ""
    return (f"the motion lasts {span:g} s; at {scenario.rate_hz:g} Hz its samples end at {covered:g} s, and "
            f"its last {span - covered:.6g} s, shorter than an interval, are not run")  # fmt: skip


def idle_outages(scenario: Scenario) -> list[str]:
    """The ``[[outage]]`` windows that drop no fix of the scenario's receiver (or start after its motion
    ends), each in words (none without ``[gnss]``): the receiver's fixes
    (:func:`sins.aiding.gnss.fix_times`, as it simulates them) that an outage drops are those strictly
    inside it, so 300–301 s at 1 Hz drops none. Its figures are then the drift between two fixes, not an
    outage's."""
    a = scenario.aiding
    if a is None or not a.outages:
        return []
    from sins.aiding.gnss import fix_times

    m = build_motion(scenario)
    fix_t = fix_times(m.t_start, m.t_end, a.rate_hz, a.latency_s)
    notes = []
    for start, end in a.outages:
        if start >= m.t_end:  # counted among the outages, and no table nor word said it did nothing
            notes.append(
                f"the outage {start:g}-{end:g} s starts after the motion ends ({m.t_end:g} s): it drops none"
            )
        elif not np.any((fix_t > start) & (fix_t < end)):
            notes.append(
                f"the outage {start:g}-{end:g} s drops no fix of the {a.rate_hz:g} Hz receiver (an outage "
                "drops the fixes strictly inside it): its figures are the drift between two fixes"
            )
    return notes


def sample_count(scenario: Scenario, motion_: motion.Motion | None = None) -> float:
    """How many IMU samples the scenario's run has (a float: it may be far beyond any array's size).

    ``motion_`` is the scenario's motion when already built (a truth file is read to build it).
    """
    m = build_motion(scenario) if motion_ is None else motion_
    return float(trajectory.interval_count(m.t_end - m.t_start, scenario.rate_hz))


def check_latitude(scenario: Scenario, truth: NavSeries) -> None:
    """Refuse a trajectory that passes beyond ±:data:`MAX_LAT_DEG` (over a pole).

    The latitude/longitude mechanisation divides by ``cos(lat)``; across a pole the latitude simply
    runs on past 90° (a truth file no reader takes back).

    Raises
    ------
    SinsInputError
        naming the scenario, the latitude reached and when.
    """
    beyond = np.abs(truth.lat) > math.radians(MAX_LAT_DEG)
    if beyond.any():
        k = int(np.argmax(beyond))
        raise SinsInputError(
            f"{scenario.source or scenario.name}: the trajectory reaches latitude "
            f"{math.degrees(float(truth.lat[k])):.4g}° at t = {float(truth.t[k]):g} s; the "
            f"latitude/longitude mechanisation cannot pass a pole (keep within ±{MAX_LAT_DEG:g}°)"
        )


__all__ = [
    "MAX_LAT_DEG",
    "TRUTH_DRIFT_M",
    "TRUTH_DRIFT_SHARE",
    "build_motion",
    "check_latitude",
    "idle_outages",
    "sample_count",
    "unsampled_end",
]
