"""What a recording's axes are, as far as its data show them: beside a reference attitude, whether that
attitude is of the readings' axes (its turns are the gyro's, gravity's reaction in it points up, its
acceleration is the accelerometer's, no axis of the readings dead where it moves), whether its positions
are what its velocities integrate to, and how
its clock sits against the readings' (the shift at which its turns agree best); without one, the
readings' axes against FRD's, from gravity at rest and the lateral force in a land vehicle's turns.
Part of :func:`sins.io.inspection.inspect`."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sins.core import earth, rotation
from sins.core.series import ImuIncrements, ImuRates, NavSeries, ReferencedRecording
from sins.io import axes, local
from sins.io.findings import Clipping, Finding, ReferenceLag, Rest, Windows

Array = NDArray[np.float64]

#: Beside a reference attitude, the specific force it rotates into the world, less the acceleration its
#: velocity gives, points up within this, °: a 1 m/s² accelerometer bias tilts it 6°.
REFERENCE_TILT_DEG = local.LEVEL_WITHIN_DEG
#: Beside a reference attitude, its turns and the gyro's correlate at least this much (EuRoC and
#: BROAD: 0.997 and more; the gyro's noise and a reference's lag take little off).
REFERENCE_TURNS_AGREE = 0.9
#: The intervals the turns are compared over, s (two of the reference's steps at least): short enough
#: that a hand-held unit's turn over one is its integrated rate (over 1 s, BROAD's fast turns of 60-90°
#: about changing axes took the correlation down to 0.78), long beside the noise.
TURN_INTERVAL_S = 0.1
#: A step between readings this many times their median is a gap: the intervals across it hold no turn
#: of the readings' to compare, and are left out (before, one 2 s gap took the correlation to 0.84, and
#: the reference was blamed for the readings' gap).
GAP_STEPS = 5.0
#: The shifts of the reference's clock tried, s, either way (a motion capture's latency is milliseconds
#: to tens of them; a quarter second is a clock set wrongly, which the stamps' own check names).
LAG_SEARCH_S = 0.25
#: A reference whose clock sits this far from the readings', s, or more, is named: at 5 ms a hand-held
#: unit's 2 rad/s turn reads 0.6° off its reference, and every interval a fit or a diagnosis compares
#: is off by the rate's change over it times the lag (EuRoC's sequences: within 2.5 ms; BROAD's two
#: trials: 4.2 and 4.3 ms early, said but not named).
REFERENCE_LAG_S = 0.005
#: Beside a reference attitude, the gyro's turns over :data:`TURN_INTERVAL_S` are the reference's in
#: size within this factor either way, and the specific force's mean in the world (the reference's
#: acceleration taken out) is gravity's size within it: a unit's scale errors are percent, a unit read
#: as another a factor of 57.3 (° and rad) or 9.8 (g and m/s²).
REFERENCE_SCALE = 1.5
#: Normal gravity's size for that comparison, m/s² (any site's within 0.3 %).
_G = 9.806
#: The windows over which the specific force's horizontal part in the world and the reference's
#: acceleration (its velocity's change over the window) are compared, s ...
MOTION_WINDOW_S = 0.5
#: ... where the reference's horizontal acceleration varies by this much at least (RMS about its mean
#: over the windows, m/s²; below it, too little motion to compare) ...
ACCEL_SEEN_MPS2 = 0.1
#: ... and must not correlate below minus this (an accelerometer read negated: -0.99 on EuRoC's V1_02,
#: its world turned upside down to match it). Only against the motion is refused: a gentle motion's
#: correlation is low, not negative (EuRoC's eleven sequences 0.64-1.00, V1_01 the gentlest; BROAD's
#: two trials 0.94 and 1.00; the PSINS drive 0.99).
FORCE_AGAINST = 0.5
#: A channel that reads one value throughout is dead where the reference departs from it over windows
#: of this, s, by more than :data:`DEAD_RATE` (rad/s: 1 °/s, a differentiated motion capture's noise over
#: 1 s a tenth of it) or :data:`DEAD_FORCE` (m/s², gravity's reaction: 3° of tilt) RMS.
DEAD_WINDOW_S = 1.0
DEAD_RATE = np.radians(1.0)
DEAD_FORCE = 0.5
#: A reference's positions move over windows of :data:`POSITION_WINDOW_S` by what its velocities
#: integrate to within :data:`REFERENCE_SCALE` either way, correlating at least this much (EuRoC's,
#: BROAD's and the PSINS drive's: 1.00, their sizes equal to 0.2 %; positions in mm read as m: 1000 ×;
#: velocities of zero beside moving positions: correlation 0).
VELOCITY_AGREES = 0.9
#: The windows positions and velocities are compared over, s.
POSITION_WINDOW_S = 1.0
#: Both move less than this over the windows (RMS, m): a still reference, nothing to compare.
STILL_M = 0.01


def seen_axes(win: Windows | None, rest: Rest | None, f: Array) -> str | None:
    """The readings' axes as far as the data show them, in :mod:`sins.io.axes` letters with ``_`` for an
    axis they do not fix: the vertical from gravity, the lateral from the turns. None: no axis points
    down (within 25°), no gravity is seen, or the unit rested in several orientations."""
    if rest is not None and rest.orientations > 1:
        return None
    up = np.asarray(rest.specific_force) if rest is not None else f.mean(axis=0)
    if not np.linalg.norm(up) > 0:
        return None
    down = -up / np.linalg.norm(up)
    k = int(np.argmax(np.abs(down)))
    if abs(down[k]) < 0.9:
        return None
    letters = ["_", "_", "_"]
    letters[k] = "d" if down[k] > 0 else "u"
    lateral = _lateral(win, down, k) if win is not None else None
    if lateral is not None:
        j, right = lateral
        letters[j] = "r" if right else "l"
        d_vec, r_vec = np.zeros(3), np.zeros(3)
        d_vec[k], r_vec[j] = np.sign(down[k]), 1.0 if right else -1.0
        forward = np.cross(r_vec, d_vec)  # x = y × z in FRD: forward = right × down
        i = 3 - j - k
        letters[i] = "f" if forward[i] > 0 else "b"
    return "".join(letters)


def _lateral(win: Windows, down: Array, k: int) -> tuple[int, bool] | None:
    """The horizontal axis whose specific force follows the yaw rate (``v · r``, driving forward) and
    whether it points right; None without turns enough to tell (the correlation under 0.6, or the other
    axis's over half of it)."""
    yaw = win.mean_w @ down
    if np.std(yaw) <= 5.0 * float(np.median(win.spread_w)) / np.sqrt(win.length):
        return None
    corr = {}
    for j in (a for a in range(3) if a != k):
        x = win.mean_f[:, j]
        corr[j] = float(np.corrcoef(x, yaw)[0, 1]) if np.std(x) > 0 else 0.0
    best = max(corr, key=lambda a: abs(corr[a]))
    other = next(a for a in corr if a != best)
    if abs(corr[best]) < 0.6 or abs(corr[other]) > 0.5 * abs(corr[best]):
        return None
    return best, corr[best] > 0


def frame_findings(frame: str, seen: str | None) -> list[Finding]:
    """The file's axes when the data show they are not FRD: letters to pass as the frame."""
    if seen is None:
        return []
    current = axes.frame_matrix(frame)
    if "_" not in seen:
        if seen == axes.FRD:
            return []
        file_axes = axes.frame_letters(axes.frame_matrix(seen) @ current)
        return [Finding("axes", f"the data show the readings' axes are {seen} (gravity at rest, the lateral "
                        "force in turns), not FRD", option="frame", value=file_axes)]  # fmt: skip
    k = next(i for i, c in enumerate(seen) if c != "_")
    if seen[k] == "d" and k == 2:
        return []
    fits = [a for a in axes.right_handed_frames() if a[k] == seen[k]]
    files = sorted(
        (axes.frame_letters(axes.frame_matrix(a) @ current) for a in fits),
        key=lambda a: (a not in _PREFERRED, _PREFERRED.index(a) if a in _PREFERRED else 0, a),
    )
    listed = ", ".join(f"{a} ({_NAMED[a]})" if a in _NAMED else a for a in files)
    where = "xyz"[k]
    sign, way = ("-", "down") if seen[k] == "d" else ("+", "up")
    what = (f"at rest the specific force (which points up) lies along {sign}{where} as read: {where} points "
            f"{way}, where FRD's z points down; likely axes of the file: {listed}")  # fmt: skip
    if files[0] in _PREFERRED:
        return [Finding("axes", what, option="frame", value=files[0])]
    return [Finding("axes", what, advice="pass --frame with the letters of the file's axes (one of these)")]


def reference_findings(truth: NavSeries, t: Array, w: Array, f: Array) -> list[Finding]:
    """Whether the reference's attitude is that of the readings' axes. Its turns over short intervals
    (:data:`TURN_INTERVAL_S`), in the body, are the gyro's integral over them (less a bias's constant
    part: their correlation about their means near 1). And the specific force rotated by it into the
    world, averaged over the reference's span, less the mean acceleration its velocity gives (the
    velocity's change over the span), is gravity's reaction, pointing up. Elsewhere, the attitude is
    not of these axes: a quaternion of another order (x, y, z, w for w, x, y, z), the other way round
    (the world's in the body), or readings in other axes than the reference's body."""
    inside = np.flatnonzero((t >= truth.t[0]) & (t <= truth.t[-1]))
    if len(inside) < 2 or not t[inside[-1]] > t[inside[0]]:
        return []
    dead = dead_findings(truth, t, w, f, inside)
    if dead:  # nothing of a dead channel's can be judged against the reference
        return dead
    if swapped := _swapped(w[inside], f[inside]):
        return [swapped]
    advice = ("check the reference's quaternion order (w, x, y, z or x, y, z, w), its direction (the "
              "sensor's attitude in the world, not the world's in the sensor) and the readings' "
              "axes")  # fmt: skip
    pairs = _turn_pairs(truth, t, w, inside)
    agreement = None if pairs is None else _correlation(*pairs)
    if agreement is not None and agreement < REFERENCE_TURNS_AGREE:
        what = (f"the reference's turns over {TURN_INTERVAL_S:g} s intervals, in the body, correlate "
                f"{agreement:.2f} with the gyro's (1 where its attitude is of the readings' "
                "axes)")  # fmt: skip
        clipped = _clipped(w[inside])
        if clipped:  # readings held at the sensor's range turn away from the reference's: not its fault
            cut = "the clipped spans cannot be judged against the reference: record with a wider range"
            return [Finding("reference_attitude", f"{what}, and {clipped}", advice=cut)]
        assert pairs is not None
        gyro_turns, ref_turns = pairs
        ref_deg, gyro_deg = np.degrees(_rms_about_mean(ref_turns)), np.degrees(_rms_about_mean(gyro_turns))
        if ref_deg < 0.05 * gyro_deg:  # the gyro turns at least 1 °/s RMS (_turn_pairs)
            still = (f"the reference barely turns ({ref_deg:.3g}° RMS over its {TURN_INTERVAL_S:g} s "
                     f"intervals) while the gyro turns {gyro_deg:.3g}°")  # fmt: skip
            advice = "check that the reference's attitude is the recording's own (a constant is no reference)"
            return [Finding("reference_attitude", still, advice=advice)]
        what += ": the attitude is not of the readings' axes"
        if agreement < -REFERENCE_TURNS_AGREE:  # the turns exactly against the gyro's: a sign
            what += ", or the gyro reads every turn negated"
        return [Finding("reference_attitude", what, advice=advice)]
    inside = inside[:: max(1, len(inside) // 200_000)]  # the mean of a long recording from 200,000 rows
    ts = t[inside]
    ref = truth.interpolate(ts)
    mean_f_n = local.mean_in_world(ts, f[inside], ref.q_nb)
    reaction = mean_f_n - (ref.v_n[-1] - ref.v_n[0]) / float(ts[-1] - ts[0])  # −g: up, in NED
    size = float(np.linalg.norm(reaction))
    if not size > 0:
        return []
    tilt = float(np.degrees(np.arccos(np.clip(-reaction[2] / size, -1.0, 1.0))))
    if tilt <= REFERENCE_TILT_DEG:
        return _scale_findings(pairs, size) + _force_findings(truth, t, f, inside) + _position_findings(truth)
    what = (
        f"the specific force, rotated into the world by the reference's attitude, points {tilt:.0f}° "
        "from up (its mean over the reference's span, the reference's acceleration taken out)"
    )
    if agreement is not None:
        # The turns are the gyro's: the attitude is of the readings' axes, and only the world is turned
        # (a motion capture's frame with y up; NED written for ENU): said so, not blamed on the quaternion.
        what += (f", while its turns agree with the gyro's (correlation {agreement:.2f}): the attitude is of "
                 f"the readings' axes, in a world frame whose up lies along {_up_as_read(reaction / size)} "
                 "as read, not z")  # fmt: skip
        advice = ("write the reference in a world frame with z up (its attitude, velocity and position "
                  "turned by the one rotation that takes its up to z)")  # fmt: skip
        if tilt >= 180.0 - REFERENCE_TILT_DEG:
            what += " (NED written for ENU)"
    else:
        what += ": the attitude is not of the readings' axes"
        if tilt >= 180.0 - REFERENCE_TILT_DEG:  # upside down: the world's z read the wrong way
            what += ", or its world frame's z axis points down where it is read as up (NED written for ENU)"
    return [Finding("reference_attitude", what, advice=advice)]


def dead_findings(truth: NavSeries, t: Array, w: Array, f: Array, inside: NDArray[np.intp]) -> list[Finding]:
    """A channel of the gyro ``w`` or the accelerometer ``f`` (n, 3) that reads one value on every row
    while the reference says it should read otherwise: a dead or unrecorded axis, which every fit would
    take for an axis that never turned or never felt a force. An ideal simulated unit's channel may be
    constant too (a level unit's accelerometer x, a steady turn's rate), but then it reads what the
    reference gives: the turn over :data:`DEAD_WINDOW_S` windows in the body (against the gyro) and
    gravity's reaction in the body (against the accelerometer; the vehicle's acceleration is left out)
    must depart from the constant by :data:`DEAD_RATE` or :data:`DEAD_FORCE` RMS."""
    step = max(1, round(DEAD_WINDOW_S / float(np.median(np.diff(t[inside])))))
    ends = inside[::step]
    if len(ends) < 3:
        return []
    found = []
    ref = truth.interpolate(t[ends])
    expected = {
        "gyro": (w, _reference_turns(truth, t[ends]) / np.diff(t[ends])[:, None], DEAD_RATE),
        "accelerometer": (f, rotation.rotate(rotation.quat_conjugate(ref.q_nb), [0.0, 0.0, -_G]), DEAD_FORCE),
    }
    for sensor, (values, reference, limit) in expected.items():
        for k in np.flatnonzero(np.ptp(values[inside], axis=0) == 0.0):
            value = float(values[inside[0], k]) + 0.0  # no "-0"
            if float(np.sqrt(np.mean((reference[:, k] - value) ** 2))) > limit:
                what = (f"the {sensor}'s {'xyz'[k]} reads {value:g} on every one of its {len(inside)} rows, "
                        "where the reference moves it")  # fmt: skip
                found.append(
                    Finding("dead_channel", what, advice="a dead or unrecorded axis: check the recording")
                )
    return found


def _force_findings(truth: NavSeries, t: Array, f: Array, inside: NDArray[np.intp]) -> list[Finding]:
    """Whether the specific force's horizontal part, rotated into the world by the reference's attitude
    and averaged over windows of :data:`MOTION_WINDOW_S`, follows the reference's acceleration (its
    velocity's change over each window): the accelerometer's sign and axes against the reference's. An
    accelerometer read negated shows gravity's reaction pointing down, which a world frame written with
    z down shows too (and the reader turns it the right way up, :func:`sins.io.local.levelled`); only
    the motion tells them apart. Nothing is said where the reference hardly accelerates
    (:data:`ACCEL_SEEN_MPS2`)."""
    step = max(1, round(MOTION_WINDOW_S / float(np.median(np.diff(t[inside])))))
    edges = inside[::step]
    if len(edges) < 10:
        return []
    rows = np.arange(edges[0], edges[-1])
    world = rotation.rotate(truth.interpolate(t[rows]).q_nb, f[rows])[:, :2]
    force = np.add.reduceat(world, edges[:-1] - edges[0], axis=0) / np.diff(edges)[:, None]
    ref = truth.interpolate(t[edges])
    accel = np.diff(ref.v_n[:, :2], axis=0) / np.diff(t[edges])[:, None]
    x, y = force - force.mean(axis=0), accel - accel.mean(axis=0)
    if float(np.sqrt(np.mean(np.sum(y * y, axis=1)))) < ACCEL_SEEN_MPS2:
        return []
    agreement = float(np.sum(x * y) / np.sqrt(np.sum(x * x) * np.sum(y * y)))
    if agreement >= -FORCE_AGAINST:
        return []
    what = (f"the specific force's horizontal part, turned into the world by the reference's attitude, "
            f"correlates {agreement:.2f} with the reference's acceleration over {MOTION_WINDOW_S:g} s "
            "windows (1 where both see one motion): the accelerometer reads against the motion (its "
            "readings negated?)")  # fmt: skip
    advice = "check the accelerometer's sign and axes, and the frame of the reference's velocity"
    return [Finding("reference_force", what, advice=advice)]


def _position_findings(truth: NavSeries) -> list[Finding]:
    """Whether the reference's positions move over windows of :data:`POSITION_WINDOW_S` by what its
    velocities integrate to (trapezoids): positions in another unit than metres, or velocities of
    another frame or none, are said; a still reference (:data:`STILL_M`) says nothing, nor one that
    holds no positions (one place throughout: written as zeros where only attitude and velocity are
    known)."""
    if not (np.ptp(truth.lat) or np.ptp(truth.lon) or np.ptp(truth.h)):
        return []
    step = max(1, round(POSITION_WINDOW_S / float(np.median(np.diff(truth.t)))))
    at = np.arange(0, len(truth.t), step)
    if len(at) < 4:
        return []
    from scipy.integrate import cumulative_trapezoid

    lat, lon, h, a, b = truth.lat, np.unwrap(truth.lon), truth.h, at[:-1], at[1:]
    moved = earth.ned_offset(lat[b], lon[b], h[b], lat[a], lon[a], h[a])
    flown = np.diff(cumulative_trapezoid(truth.v_n, truth.t, axis=0, initial=0.0)[at], axis=0)
    size_p, size_v = (float(np.sqrt(np.mean(np.sum(a * a, axis=1)))) for a in (moved, flown))
    if max(size_p, size_v) < STILL_M:
        return []
    ratio = size_p / max(size_v, 1e-300)
    agreement = float(np.sum(moved * flown) / max(np.sqrt(np.sum(moved**2) * np.sum(flown**2)), 1e-300))
    if 1.0 / REFERENCE_SCALE <= ratio <= REFERENCE_SCALE and agreement >= VELOCITY_AGREES:
        return []
    what = (f"the reference's positions move {size_p:.3g} m over {POSITION_WINDOW_S:g} s windows (RMS) where "
            f"its velocities integrate to {size_v:.3g} m, correlating {agreement:.2f} with them")  # fmt: skip
    advice = (
        "check the reference's position unit (metres) and its velocity's frame and unit (the world's, m/s)"
    )
    return [Finding("reference_velocity", what, advice=advice)]


#: A gyro axis whose readings sit at their largest or smallest value, in runs of three or more
#: (:func:`stuck`), on this share of rows is clipped: a live axis's noise makes each extreme a single
#: reading.
CLIPPED_SHARE = 0.005


def _clipped(w: Array) -> str:
    """Where the gyro's readings ``w`` (n, 3) are clipped (:func:`stuck` on :data:`CLIPPED_SHARE` of them
    at least), in words ("" where they are not)."""
    for k in range(3):
        for level in (float(w[:, k].max()), float(w[:, k].min())):
            found = stuck(w[:, k], level, STUCK_RTOL)
            if found is not None and found[0] >= CLIPPED_SHARE * len(w):
                return (f"the gyro's {'xyz'[k]} sits at {level:g} rad/s on {found[0]} of its {len(w)} "
                        "readings: clipped at the sensor's range")  # fmt: skip
    return ""


def clipped_channels(imu: ImuRates | ImuIncrements) -> tuple[Clipping, ...]:
    """The channels of ``imu`` whose readings stick at their extreme (:func:`stuck`), each as a
    :class:`~sins.io.findings.Clipping` (rates and specific forces, SI; an increment's at its interval's
    end): what ``sins inspect`` names and ``sins evaluate`` notes. Increments are taken as their
    intervals' mean rates, which differ from the clipped level in their last bits where the intervals
    do: equal within :data:`STUCK_RTOL`."""
    if isinstance(imu, ImuRates):
        t, w, f = imu.t, imu.omega_ib_b, imu.f_ib_b
    else:
        (_, w, f), t = imu.mean_rates(), imu.t[1:]
    values = np.hstack([w, f])
    out = []
    for c in range(6):
        v = values[:, c]
        for level in (float(v.max()), float(v.min())):
            found = stuck(v, level, STUCK_RTOL)
            if found is not None:
                samples, runs, first = found
                name = f"{('gyro', 'accel')[c // 3]}_{'xyz'[c % 3]}"
                out.append(Clipping(name, level, samples, runs, float(t[first])))
    return tuple(out)


#: Readings within this share of a channel's extreme are at it (an increment's rate, its step's rounding).
STUCK_RTOL = 1e-9
#: A clipped level's size is at least this share less than the channel's largest size. A sensor's range
#: is symmetric about zero, ±A; a bias ``b`` taken out after the converter moves the two clips to
#: ``±A - b``, whose sizes differ by ``2|b|``. Allowing ``|b|`` up to 11 % of ``A`` (a consumer MEMS's
#: worst: MPU-6050's ±20 °/s zero-rate output at ±250 °/s is 8 %, its ±80 mg zero-g offset at ±2 g
#: 4 %), ``A - |b| >= (1 - 0.2)(A + |b|)``.
CLIP_ASYMMETRY = 0.2


def stuck(v: Array, level: float, rtol: float = 0.0) -> tuple[int, int, int] | None:
    """``(samples, runs, first row)`` of the runs of three or more readings equal to ``level`` (within
    ``rtol`` of it: clipped readings, what ``sins inspect`` names, and what :func:`_clipped` tells a
    reference check). Readings that take fewer distinct values than half their count are quantized: there
    a still unit's noise sits on its few levels for several readings, so a run counts only more than 10
    steps from the median.

    A clip is at the sensor's range, the channel's largest size either way: a level whose size is less
    than ``1 - CLIP_ASYMMETRY`` of the largest size of ``v`` (the other sign's, which the range's symmetry
    about zero bounds to within the bias, :data:`CLIP_ASYMMETRY`) is not the range but equal readings
    in motion. EuRoC's MH_02 held its gyro y at -1.24826 rad/s for three readings, and reads +1.678
    elsewhere (0.74 of it; the ADIS16448's range is ±17.5 rad/s): that was called the unit saturating."""
    at = np.abs(v - level) <= rtol * abs(level)
    if at.sum() < 3:
        return None
    if abs(level) < (1.0 - CLIP_ASYMMETRY) * float(np.max(np.abs(v))):
        return None
    levels = np.unique(v)
    if len(levels) < len(v) / 2:
        step = float(np.min(np.diff(levels))) if len(levels) > 1 else 0.0
        if abs(level - float(np.median(v))) <= 10.0 * step:
            return None
    edges = np.diff(np.concatenate([[0], at.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    long = (stops - starts) >= 3
    if not long.any():
        return None
    return int((stops - starts)[long].sum()), int(long.sum()), int(starts[long][0])


def _up_as_read(up_ned: Array) -> str:
    """Up (a unit vector in sins's NED) in the axes of the room frame as the file holds it (x east, y north,
    z up: how every reader places a room's frame): an axis where within :data:`REFERENCE_TILT_DEG` of one."""
    up = np.array([up_ned[1], up_ned[0], -up_ned[2]])
    k = int(np.argmax(np.abs(up)))
    if np.degrees(np.arccos(min(1.0, abs(float(up[k]))))) <= REFERENCE_TILT_DEG:
        return f"{'+' if up[k] > 0 else '-'}{'xyz'[k]}"
    return "(x, y, z) = ({:.2f}, {:.2f}, {:.2f})".format(*(np.round(up, 2) + 0.0))  # no "-0.00"


def _scale_findings(pairs: tuple[Array, Array] | None, reaction: float) -> list[Finding]:
    """Readings whose size is not the reference's: the gyro's turns over short intervals against the
    reference's (``pairs``, :func:`_turn_pairs`; RMS about their means), and ``reaction``,
    the specific force's mean size in the world less the reference's acceleration, against gravity's.
    Beyond :data:`REFERENCE_SCALE` either way the readings' unit (or the time's) is not what was read,
    and every figure judged against the reference would measure it."""
    found = []
    if pairs is not None:
        gyro, turns = pairs
        ratio = _rms_about_mean(gyro) / max(_rms_about_mean(turns), 1e-300)
        if not 1.0 / REFERENCE_SCALE <= ratio <= REFERENCE_SCALE:
            what = (f"the gyro's turns over {TURN_INTERVAL_S:g} s intervals are {ratio:.4g} × the "
                    f"reference's{_read_as(ratio, np.degrees(1.0), 'degrees', 'radians')}")  # fmt: skip
            found.append(Finding("reference_gyro_scale", what, advice="check the gyro's unit and the time's"))
    ratio = reaction / _G
    if not 1.0 / REFERENCE_SCALE <= ratio <= REFERENCE_SCALE:
        what = (f"the specific force's mean in the world, the reference's acceleration taken out, is "
                f"{reaction:.4g} m/s², {ratio:.4g} × gravity{_read_as(ratio, _G, 'm/s²', 'g')}")  # fmt: skip
        found.append(Finding("reference_accel_scale", what, advice="check the accelerometer's unit"))
    return found


def _rms_about_mean(x: Array) -> float:
    return float(np.sqrt(np.mean(np.sum((x - x.mean(axis=0)) ** 2, axis=1))))


def _read_as(ratio: float, factor: float, large: str, small: str) -> str:
    """ ": readings in {large} read as {small}" where ``ratio`` is within 10 % of ``factor`` (57.3 for °
    and rad, 9.8 for m/s² and g), the other way round near its inverse; else nothing."""
    if abs(np.log(ratio / factor)) < 0.1:
        return f": readings in {large} read as {small}"
    if abs(np.log(ratio * factor)) < 0.1:
        return f": readings in {small} read as {large}"
    return ""


def _turn_pairs(truth: NavSeries, t: Array, w: Array, inside: NDArray[np.intp]) -> tuple[Array, Array] | None:
    """The gyro's integral over short intervals and the reference's turns over the same (the rotation
    vector of ``q(t_k)⁻¹ q(t_k+1)``, in the body), (m, 3) each; None where the gyro turns too little
    to tell (under 1 °/s RMS about its mean)."""
    ends, gyro = _gyro_turns(truth, t, w, inside)
    if gyro is None:
        return None
    kept = np.isfinite(gyro[:, 0])  # intervals across a gap in the readings left out
    return gyro[kept], _reference_turns(truth, t[ends])[kept]


def reference_lag(truth: NavSeries, t: Array, w: Array) -> ReferenceLag | None:
    """The shift of the reference's clock against the readings' at which its turns over short intervals
    agree best with the gyro's (:func:`_turn_pairs`' correlation), tried every reading's interval
    within :data:`LAG_SEARCH_S` either way and refined between them by a parabola through the best three.
    None where the gyro turns too little to tell, the reference spans too little, the readings are
    further apart than the search reaches, or the best shift is the last one tried (the clock sits
    further off than the search reaches)."""
    if len(t) < 2:
        return None
    dt = float(np.median(np.diff(t)))
    if not dt > 0.0:
        return None
    # The shifts tried stay within the search (floor, not round: 0.25 s / 0.019999 s is 12.5, and 13
    # steps would reach past the reference's ends), and the intervals shifted within the reference.
    # Readings further apart than the search reaches (a time column in ns read as s) place no clock.
    count = int(LAG_SEARCH_S // dt)
    if count < 1:
        return None
    shifts = np.arange(-count, count + 1) * dt
    inside = np.flatnonzero((t >= truth.t[0] + shifts[-1]) & (t <= truth.t[-1] - shifts[-1]))
    if len(inside) < 2 or not t[inside[-1]] > t[inside[0]]:
        return None
    ends, gyro = _gyro_turns(truth, t, w, inside)
    if gyro is None:
        return None
    agreement = np.array([_agreement(truth, t[ends] + shift, gyro) for shift in shifts])
    k = int(np.argmax(agreement))
    if k in (0, len(shifts) - 1):
        return None
    before, best, after = agreement[k - 1 : k + 2]
    curvature = before - 2.0 * best + after
    offset = 0.5 * (before - after) / curvature if curvature < 0.0 else 0.0
    return ReferenceLag(float(shifts[k] + offset * dt), float(best), float(agreement[count]))


def recording_lag(rec: ReferencedRecording) -> ReferenceLag | None:
    """:func:`reference_lag` of readings beside a reference trajectory at its epochs (what fits and
    diagnoses compare): the increments' mean rates at their steps' middles."""
    dt = np.diff(rec.imu.t)
    t_mid = 0.5 * (rec.imu.t[:-1] + rec.imu.t[1:])
    return reference_lag(rec.reference, t_mid, rec.imu.dtheta_b / dt[:, None])


def clock_sits(lag_s: float, readings: str = "the readings'") -> str:
    """Where a reference's clock sits (``lag_s``, :class:`ReferenceLag`'s sign), in the words every report
    uses: "4.3 ms ahead of the readings'"."""
    return f"{1e3 * abs(lag_s):.1f} ms {'behind' if lag_s > 0 else 'ahead of'} {readings}"


def lag_findings(lag: ReferenceLag | None) -> list[Finding]:
    """A reference whose clock sits :data:`REFERENCE_LAG_S` or more from the readings'."""
    if lag is None or abs(lag.lag_s) < REFERENCE_LAG_S:
        return []
    way = "later" if lag.lag_s > 0 else "earlier"
    what = (f"the reference's turns agree best with the gyro's read {abs(lag.lag_s) * 1e3:.1f} ms {way} than "
            f"stamped (correlation {lag.agreement:.4f}; {lag.as_stamped:.4f} as stamped): its clock "
            f"{'lags' if lag.lag_s > 0 else 'leads'} the readings'")  # fmt: skip
    advice = (
        f"sins compares them as stamped: add {-lag.lag_s:+.4f} s to the reference's times, or "
        "find why its clock sits so (a motion capture's latency, a stamp taken on arrival)"
    )
    return [Finding("reference_lag", what, advice=advice)]


def _gyro_turns(
    truth: NavSeries, t: Array, w: Array, inside: NDArray[np.intp]
) -> tuple[NDArray[np.intp], Array | None]:
    """The readings at which the intervals of :data:`TURN_INTERVAL_S` (two of the reference's steps at
    least) end, and the gyro's integral over each, trapezoids; None for the integrals where there are
    fewer than ten intervals or the gyro turns too little to tell (under 1 °/s RMS about its mean)."""
    length_s = max(TURN_INTERVAL_S, 2.0 * float(np.median(np.diff(truth.t))))
    step = max(1, round(length_s / float(np.median(np.diff(t[inside])))))
    ends = inside[::step]
    if len(ends) < 10:
        return ends, None
    within = np.arange(ends[0], ends[-1] + 1)
    dt = np.diff(t[within])
    steps = dt[:, None] * 0.5 * (w[within][1:] + w[within][:-1])  # trapezoids
    summed = np.concatenate([np.zeros((1, 3)), np.cumsum(steps, axis=0)])
    gyro = np.diff(summed[ends - ends[0]], axis=0)
    # An interval across a gap in the readings holds no turn of theirs to compare: NaN, left out.
    gaps = np.concatenate([[0], np.cumsum(dt > GAP_STEPS * float(np.median(dt)))])
    gyro[np.diff(gaps[ends - ends[0]]) > 0] = np.nan
    kept = np.isfinite(gyro[:, 0])
    if kept.sum() < 10:
        return ends, None
    b = gyro[kept] - gyro[kept].mean(axis=0)
    spread = float(np.sqrt(np.mean(np.sum(b * b, axis=1)) / np.mean(np.diff(t[ends])[kept] ** 2)))
    return ends, (gyro if spread >= np.radians(1.0) else None)


def _agreement(truth: NavSeries, t_ends: Array, gyro: Array) -> float:
    """The correlation, about their means, of the reference's turns between the times ``t_ends`` with
    the gyro's ``gyro`` over the same intervals."""
    return _correlation(gyro, _reference_turns(truth, t_ends))


def _reference_turns(truth: NavSeries, t_ends: Array) -> Array:
    """The reference's turns between the times ``t_ends``, in the body, (m - 1, 3)."""
    q = truth.interpolate(t_ends).q_nb
    return np.asarray(rotation.turn_between(q[:-1], q[1:]), dtype=float)


def _swapped(w: Array, f: Array) -> Finding | None:
    """The gyro reading gravity's size on average and the accelerometer next to nothing: its columns and
    the accelerometer's swapped (a rate of 9.8 rad/s held for the recording is no motion)."""
    g_rate, g_force = float(np.linalg.norm(w.mean(axis=0))), float(np.linalg.norm(f.mean(axis=0)))
    if abs(g_rate / earth.G0 - 1.0) > 0.15 or g_force > 0.2 * earth.G0:
        return None
    what = (
        f"the gyro's mean reads {g_rate:.3g} (rad/s), gravity's size; the accelerometer's {g_force:.3g} m/s²"
    )
    advice = "check the columns: the gyro's and the accelerometer's look swapped"
    return Finding("reference_attitude", what, advice=advice)


def _correlation(gyro: Array, turns: Array) -> float:
    """The correlation of two sets of turns about their means (the gyro's NaN rows, across a gap in the
    readings, left out)."""
    kept = np.isfinite(gyro[:, 0])
    gyro, turns = gyro[kept], turns[kept]
    if not len(gyro):
        return 0.0
    a, b = turns - turns.mean(axis=0), gyro - gyro.mean(axis=0)
    scale = float(np.sqrt(np.sum(a * a) * np.sum(b * b)))
    # No turn on either side (a reference that holds still over the readings, or none of them left):
    # nothing agrees, where 0/0 had printed "correlation nan" beside numpy's warning.
    return float(np.sum(a * b)) / scale if scale > 0.0 else 0.0


#: Frames named first, and what they are.
_PREFERRED = ("frd", "flu", "rfu")
_NAMED = {"frd": "sins's own", "flu": "ROS, REP 103", "rfu": "x right, y forward: axes named after ENU"}


__all__ = [
    "ACCEL_SEEN_MPS2",
    "CLIPPED_SHARE",
    "CLIP_ASYMMETRY",
    "DEAD_FORCE",
    "DEAD_RATE",
    "DEAD_WINDOW_S",
    "FORCE_AGAINST",
    "GAP_STEPS",
    "LAG_SEARCH_S",
    "MOTION_WINDOW_S",
    "POSITION_WINDOW_S",
    "REFERENCE_LAG_S",
    "REFERENCE_SCALE",
    "REFERENCE_TILT_DEG",
    "REFERENCE_TURNS_AGREE",
    "STILL_M",
    "STUCK_RTOL",
    "TURN_INTERVAL_S",
    "VELOCITY_AGREES",
    "clipped_channels",
    "clock_sits",
    "dead_findings",
    "frame_findings",
    "lag_findings",
    "recording_lag",
    "reference_findings",
    "reference_lag",
    "seen_axes",
    "stuck",
]
