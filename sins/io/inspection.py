"""A recording's sanity check: rate, jitter, gaps, clipping, and the unit and frame mistakes its data show.

:func:`inspect` reads nothing but the readings (and the stamps' other clocks where a recording has
them). At rest the specific force is gravity, about 9.806 m/s² pointing up, and the angular rate is
Earth's, 7.292e-5 rad/s: a size off by a unit's factor names the unit (g read as m/s², deg/s read as
rad/s), a size of gravity × the sample interval names increments read as rates, and gravity along +z
names a z axis pointing up (FLU, or axes named after ENU) where FRD's points down. In motion, a land
vehicle's lateral specific force follows its yaw rate (``v · r``, the vehicle driving forward), which
names the axis pointing right. Beside a reference attitude, the readings' axes are its body's
whatever they are called, and the reference judges them instead (:mod:`sins.io.frame_check`); the
shift of its clock at which its turns agree best with the gyro's says how it sits against the
readings' (named from 5 ms, :data:`~sins.io.frame_check.REFERENCE_LAG_S`). The time
stamps give the rate, its jitter and the gaps; runs of equal readings at a channel's extreme give
clipping. Each finding names the reader option (and its value) that mends it, or says what to do where
no option does; a clean recording gives none.

Rest is found from the data: among the one-second windows whose readings vary least (within 3× the
quietest 5 %), the largest group whose means agree (within 6 standard errors), two seconds at least;
beside a reference, none where it turns or travels (a steady turn reads as a still unit with a large
bias, a straight cruise as a still unit).
Where a fifth of the quiet windows hold gravity 20° or more away from it (a rig session, a hand-held
unit), the axes are not judged.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

from sins.core import rotation
from sins.core.earth import OMEGA_IE, ned_offset
from sins.core.series import NavSeries
from sins.errors import SinsInputError
from sins.io import filled, frame_check
from sins.io import units as unitdefs
from sins.io.findings import Clipping, Finding, Gap, Inspection, Rest, Windows
from sins.io.recording import Recording

Array = NDArray[np.float64]

#: Normal gravity halfway between the equator's 9.780 and the poles' 9.832 m/s².
GRAVITY = 9.806
#: Gravity's size at rest counts as right within this fraction (latitude ±0.27 %, a consumer unit's
#: 13 mg bias 1.3 %).
GRAVITY_TOL = 0.015
#: Beyond this fraction of gravity at rest no accelerometer bias or scale error explains the size: the
#: readings' unit or form is wrong (``sins bias`` and ``sins integrate --align`` refuse such a rest).
GRAVITY_OFF = 0.15
#: A unit's factor is named when the size at rest is within this fraction of what it gives.
UNIT_TOL = 0.05
#: The fastest rate any IMU measures (4000 °/s), rad/s.
MAX_GYRO_RADPS = 70.0
#: Plausible IMU sampling rates, Hz, for naming a time unit.
PLAUSIBLE_HZ = (10.0, 10_000.0)
#: A stated rate and the stamps' may differ by this fraction.
RATE_TOL = 0.005
#: Jitter of the sample interval (RMS, fraction of it) worth a word.
JITTER_TOL = 0.05
FULL_SCALES = {"gyro": (125, 250, 300, 500, 1000, 2000, 4000), "accel": (2, 4, 5, 8, 10, 16, 30, 50, 200)}

#: Rate units and the increment units that go with them (for "increments read as rates").
_INCREMENT_UNIT = {"rad/s": "rad", "mrad/s": "mrad", "deg/s": "deg", "m/s^2": "m/s", "cm/s^2": "cm/s",
                   "ft/s^2": "ft/s", "g": "g*s", "mg": "mg*s", "ug": "ug*s"}  # fmt: skip


def inspect(rec: Recording, rate_hz: float | None = None) -> Inspection:
    """Check a recording (see the module docstring).

    Parameters
    ----------
    rec : the recording as read (:func:`sins.io.read`): its ``units``, ``frame`` and
        ``column_map`` say how it was read, so that a finding names what to pass instead
    rate_hz : the unit's stated sampling rate, Hz (overrides the recording's own ``stated_rate_hz``)

    Returns
    -------
    Inspection
        figures and findings; no findings for a clean recording.

    Raises
    ------
    SinsInputError
        fewer than two readings.
    """
    if len(rec.imu) < 2:
        raise SinsInputError(f"{rec.source}: {len(rec.imu)} reading(s); inspecting needs two or more")
    t, w, f = rec.mean_rates()
    stamps = rec.imu.t if rec.form == "increment" else t
    med, jitter, gaps = _stamps(stamps)
    stated = rate_hz if rate_hz is not None else rec.stated_rate_hz
    findings: list[Finding] = []
    findings += _time_findings(rec, med, jitter, gaps, stated, rate_hz is not None)
    windows = _windows(w, f, med)
    moving = _moving(rec, t, windows) if windows is not None and rec.truth is not None else None
    rest = _rest(windows, med, moving) if windows is not None else None
    findings += _rest_findings(rec, rest, med)
    frame = frame_check.seen_axes(windows, rest, f)
    # Beside a reference attitude, the readings' axes are its body's, whatever they are called: the
    # reference judges them, not FRD's convention. A file sins corrected keeps the axes of the recording
    # it corrected, which its model was fitted on: a EuRoC sequence's (x up) had been flagged, and the
    # --frame advised would have turned readings the model had already corrected.
    lag = None
    if rec.truth is None:
        findings += [] if rec.corrected_by else frame_check.frame_findings(rec.frame, frame)
    else:
        attitude = frame_check.reference_findings(rec.truth, t, w, f)
        # Only a reference of the readings' axes has turns to time against the gyro's.
        lag = None if attitude else frame_check.reference_lag(rec.truth, t, w)
        findings += attitude + frame_check.lag_findings(lag)
        if not attitude:
            findings += _filled_findings(rec.truth, t, w)
    findings = _one_per_unit(findings + _range_findings(rec, w))
    clipping = _clipping(rec)
    findings += [_clip_finding(c) for c in clipping]
    if rec.kind == "dataset":  # no reader option applies: the dataset's reader fixes units and axes
        findings = [_as_read(f) for f in findings]
    return Inspection(
        source=rec.source, form=rec.form, rows=len(rec.imu), span_s=float(stamps[-1] - stamps[0]),
        rate_hz=1.0 / med, jitter=jitter, stated_rate_hz=stated, gaps=gaps, rest=rest, clipping=clipping,
        axes=frame, findings=tuple(findings), reference_lag=lag,
    )  # fmt: skip


def _filled_findings(truth: NavSeries, t: Array, w: Array) -> list[Finding]:
    """The reference's spans filled by interpolation (:mod:`sins.io.filled`), as one finding."""
    spans = filled.filled_spans(truth.t, truth.q_nb, t, w)
    if not spans:
        return []
    what = (
        f"the reference turns at one constant rate for {filled.FILLED_MIN_S:g} s or longer where the "
        f"gyro's readings turn away from one rate {filled.FILLED_Z:g}x more than their noise would, over "
        f"{filled.spans_said(spans)}: filled by interpolation (a gap slerped), not measured"
    )
    advice = (
        "sins fit sets these spans aside (unless --screen never); sins evaluate judges the reference as it is"
    )
    return [Finding("reference_filled", what, advice=advice)]


#: The reference's scale checks and the checks of the readings alone that name the same unit's mistake.
_SAME_UNIT = {
    "reference_gyro_scale": {"gyro_range", "dtheta_range", "gyro_unit", "dtheta_unit", "time_unit"},
    "reference_accel_scale": {"accel_unit", "dv_unit", "gravity_size", "gravity_unknown", "time_unit"},
}


def _one_per_unit(findings: list[Finding]) -> list[Finding]:
    """``findings`` less a reference's scale check where the readings alone name that unit's mistake
    (theirs says which option to pass)."""
    codes = {f.code for f in findings}
    return [f for f in findings if not (_SAME_UNIT.get(f.code, set()) & codes)]


def _as_read(finding: Finding) -> Finding:
    """A finding on a dataset: what the data show, without a reader option to pass (a dataset's reader
    gives its readings in the units and axes its SOURCE.md states; fits and judgements on it are in
    those)."""
    if finding.option is None and "--" not in finding.advice:
        return finding
    return dataclasses.replace(
        finding, option=None, value=None,
        advice="a dataset is read as its reader gives it (its SOURCE.md): no reader option applies",
    )  # fmt: skip


# --------------------------------------------------------------------------- time


def gaps_note(t: Array, across: str = "each integrated across as one interval") -> str:
    """The stretches without readings in the stamps ``t`` (s, increasing), as :func:`inspect` finds them,
    in a sentence: how many, the longest, and what ``across`` them is done ("" for none: ``sins
    integrate`` says it, which crossed a 5 s gap without a word; ``sins bias``, which averaged across one
    as silently)."""
    found = _stamps(t)[2]
    if not found:
        return ""
    g = max(found, key=lambda g: g.length_s)
    return (f"{len(found)} gap(s) in the readings (the longest {g.length_s:.3g} s at {g.start_s:.6g} s), "
            f"{across} (sins inspect lists them)")  # fmt: skip


def _stamps(t: Array) -> tuple[float, float, tuple[Gap, ...]]:
    """The stamps' median step, its RMS jitter (a fraction of it, over the steady steps) and the gaps."""
    dt = np.diff(t)
    med = float(np.median(dt)) if len(dt) else float("nan")
    steady = dt[(dt > 0.5 * med) & (dt < 1.5 * med)]
    jitter = float(np.std(steady) / med) if steady.size > 1 else 0.0
    return med, jitter, _gaps(t, dt, med, jitter)


def _gaps(t: Array, dt: Array, med: float, jitter: float) -> tuple[Gap, ...]:
    """Intervals longer than 1.5 steps (more where the stamps jitter): one or more samples missing."""
    limit = med * max(1.5, 1.0 + 5.0 * jitter)
    return tuple(
        Gap(start_s=float(t[i]), length_s=float(dt[i]), missing=max(1, round(dt[i] / med) - 1))
        for i in np.flatnonzero(dt > limit)
    )


def _time_findings(
    rec: Recording, med: float, jitter: float, gaps: tuple[Gap, ...], stated: float | None, given: bool
) -> list[Finding]:
    out = []
    rate = 1.0 / med
    if not rec.time_from_rate and not PLAUSIBLE_HZ[0] / 10 <= rate <= PLAUSIBLE_HZ[1] * 10:
        out.append(_time_unit(rec, med))
    if stated is not None and abs(rate / stated - 1.0) > RATE_TOL:
        by = "the given rate" if given else rec.stated_by
        out.append(Finding(
            "rate_mismatch",
            f"the stamps give {rate:.6g} Hz, {100 * (rate / stated - 1):+.1f} % against the stated "
            f"{stated:.6g} Hz ({by})",
            advice="sins integrates over the stamps: if they are right, the stated rate is not; if the "
            "unit's clock is right and the stamps' is not, every integrated angle and velocity is off "
            "by as much",
        ))  # fmt: skip
    out += _clock_findings(rec)
    if gaps:
        longest = max(gaps, key=lambda g: g.length_s)
        out.append(Finding(
            "gaps",
            f"{len(gaps)} gap(s) in the stamps, {sum(g.missing for g in gaps)} samples missing; the longest "
            f"{longest.length_s:.3g} s at t = {longest.start_s:.6g} s",
            advice="sins integrates across a gap as one interval, as if the readings changed linearly "
            "over it: trim the recording there, or read it in parts",
        ))  # fmt: skip
    if jitter > JITTER_TOL:
        out.append(Finding(
            "jitter",
            f"the sample interval jitters by {100 * jitter:.1f} % (RMS) of its {med:.6g} s",
            advice="stamps taken on arrival rather than at sampling; sins integrates over them as they are",
        ))  # fmt: skip
    return out


def _time_unit(rec: Recording, med: float) -> Finding:
    """The samples come implausibly slowly or fast: the time unit that gives a plausible rate."""
    unit = rec.units.get("t", "s")
    raw = med / unitdefs.UNITS["t"][unit]
    fits = [
        u for u, k in unitdefs.UNITS["t"].items() if PLAUSIBLE_HZ[0] <= 1.0 / (raw * k) <= PLAUSIBLE_HZ[1]
    ]
    what = f"the samples come at {1.0 / med:.3g} Hz (one every {med:.3g} s), no IMU's rate"
    if not fits or rec.kind not in ("sins csv", "csv columns"):
        return Finding("time_unit", what, advice="check the time column's unit")
    best = fits[0]
    rate = 1.0 / (raw * unitdefs.UNITS["t"][best])
    return Finding(
        "time_unit", f"{what}: the times are likely in {best} ({rate:.3g} Hz)",
        option="units", value=_units_with(rec, t=best),
    )  # fmt: skip


def _clock_findings(rec: Recording) -> list[Finding]:
    """A bag's stamps against its recorder's clock over the same readings (a sensor clock's drift)."""
    if rec.receive_t is None or len(rec.receive_t) < 2:
        return []
    stamped = float(rec.imu.t[-1] - rec.imu.t[0])
    received = float(rec.receive_t[-1] - rec.receive_t[0])
    if received < 10.0 or abs(stamped / received - 1.0) <= RATE_TOL:
        return []
    return [Finding(
        "clock_mismatch",
        f"the header stamps span {stamped:.6g} s, the recorder's clock {received:.6g} s over the same "
        f"readings ({100 * (stamped / received - 1):+.1f} %)",
        advice="the sensor's clock or the recorder's runs off; sins integrates over the header stamps",
    )]  # fmt: skip


def _units_with(rec: Recording, **changes: str) -> str:
    """The units text to pass: what was given (units other than SI) with ``changes``."""
    given = {k: v for k, v in rec.units.items() if v != unitdefs.SI.get(k)}
    given.update(changes)
    return unitdefs.spec_text({k: v for k, v in given.items() if v != unitdefs.SI.get(k)} or changes)


# --------------------------------------------------------------------------- rest


def _windows(w: Array, f: Array, med: float) -> Windows | None:
    """One-second windows (at least 8 samples, and 8 windows), or None for a recording too short."""
    length = max(8, round(1.0 / med)) if np.isfinite(med) and med > 0 else 8
    count = len(w) // length
    if count < 8:
        return None
    cut = count * length
    ww, ff = w[:cut].reshape(count, length, 3), f[:cut].reshape(count, length, 3)
    return Windows(
        length=length, mean_w=ww.mean(axis=1), mean_f=ff.mean(axis=1),
        spread_w=np.linalg.norm(ww.std(axis=1), axis=1), spread_f=np.linalg.norm(ff.std(axis=1), axis=1),
    )  # fmt: skip


def _rest(win: Windows, med: float, moving: NDArray[np.bool_] | None = None) -> Rest | None:
    """The windows at rest (see the module docstring) and their means, or None (less than two seconds).
    ``moving``: windows a reference shows turning or travelling, never at rest (a steady turn reads as a
    still unit with a large bias, a straight cruise as a still unit)."""
    candidate = np.ones(len(win.mean_w), dtype=bool) if moving is None else ~moving
    if candidate.sum() < 2:
        return None
    quiet = candidate.copy()
    for spread in (win.spread_w, win.spread_f):
        floor = float(np.percentile(spread[candidate], 5))
        quiet &= spread <= 3.0 * floor + 1e-12 * float(np.median(spread) + 1e-300)
    if quiet.sum() < 2:
        return None
    root = np.sqrt(win.length)
    tol = (6.0 * float(np.median(win.spread_w[quiet])) / root + 1e-15,
           6.0 * float(np.median(win.spread_f[quiet])) / root + 1e-15)  # fmt: skip
    ref = _largest_cluster(win, np.flatnonzero(quiet), tol)
    rest = quiet & (np.linalg.norm(win.mean_w - win.mean_w[ref], axis=1) <= tol[0])
    rest &= np.linalg.norm(win.mean_f - win.mean_f[ref], axis=1) <= tol[1]
    seconds = float(rest.sum() * win.length * med)
    if seconds < 2.0 or rest.sum() < 2:
        return None
    mean_w, mean_f = win.mean_w[rest].mean(axis=0), win.mean_f[rest].mean(axis=0)
    size_w = float(np.linalg.norm(mean_w))
    noise = float(np.median(win.spread_w[rest]))
    stderr = noise / np.sqrt(rest.sum() * win.length)
    scatter = float(np.linalg.norm(win.mean_w[rest].std(axis=0)))
    agreeing = scatter <= max(0.2 * size_w, 3.0 * noise / root)
    # Quiet windows whose gravity points 20° or more away from the rest's: other orientations at rest.
    # (A force of zero, a dead accelerometer's, points nowhere: taken as not turned.)
    up = win.mean_f[quiet] / np.maximum(np.linalg.norm(win.mean_f[quiet], axis=1), 1e-300)[:, None]
    turned = up @ (mean_f / max(float(np.linalg.norm(mean_f)), 1e-300)) < np.cos(np.radians(20.0))
    turned &= np.linalg.norm(win.mean_f[quiet], axis=1) > 0.0
    return Rest(
        seconds=seconds,
        specific_force=(float(mean_f[0]), float(mean_f[1]), float(mean_f[2])),
        rate=(float(mean_w[0]), float(mean_w[1]), float(mean_w[2])),
        gravity_ratio=float(np.linalg.norm(mean_f)) / GRAVITY,
        earth_rate_ratio=size_w / OMEGA_IE,
        rate_resolved=bool(size_w > 0 and stderr < 0.1 * size_w and agreeing and rest.sum() >= 3),
        orientations=bool(turned.mean() > 0.2) + 1,
    )


#: A window a reference shows turning faster than this, °/s, is not at rest, whatever its readings say.
REST_TURN_DPS = 0.5
#: ... or travelling faster than this on average over it, m/s: a vehicle creeping. (The chord between the
#: window's two positions, not a velocity: one differenced from a motion capture's positions at 120 Hz
#: scatters by about 85 mm/s for each millimetre of their noise, the chord over a second by 1.4 mm/s.)
REST_SPEED_MPS = 0.1


def _moving(rec: Recording, t: Array, win: Windows) -> NDArray[np.bool_]:
    """The windows whose reference turns faster than :data:`REST_TURN_DPS` between their first and last
    readings, or travels faster than :data:`REST_SPEED_MPS` between them: judged over the part within the
    reference's span where that is half the window or more (a reference that starts a few stamps after
    the readings still judges their first window), not judged elsewhere."""
    truth = rec.truth
    assert truth is not None
    first = np.arange(len(win.mean_w)) * win.length
    last = first + win.length - 1
    t0, t1 = np.maximum(t[first], truth.t[0]), np.minimum(t[last], truth.t[-1])
    out = np.zeros(len(first), dtype=bool)
    inside = (t1 > t0) & (t1 - t0 >= 0.5 * (t[last] - t[first]))
    if inside.any():
        start, end = truth.interpolate(t0[inside]), truth.interpolate(t1[inside])
        turn = rotation.turn_between(start.q_nb, end.q_nb)
        rate = np.linalg.norm(turn, axis=1) / (t1[inside] - t0[inside])
        chord = ned_offset(end.lat, end.lon, end.h, start.lat, start.lon, start.h)
        speed = np.linalg.norm(chord, axis=1) / (t1[inside] - t0[inside])
        out[inside] = (rate > np.radians(REST_TURN_DPS)) | (speed > REST_SPEED_MPS)
    return out


def _largest_cluster(win: Windows, quiet: NDArray[np.intp], tol: tuple[float, float]) -> int:
    """The quiet window whose means the most other quiet windows agree with (a still unit's one
    orientation; a rig's or a drive's longest), among at most 400 of them spread over the recording."""
    candidates = quiet if len(quiet) <= 400 else quiet[np.linspace(0, len(quiet) - 1, 400).astype(int)]
    best, most = int(candidates[0]), -1
    for start in range(0, len(candidates), 20):  # blocks of 20: (20, quiet) distances at a time
        block = candidates[start : start + 20]
        near = np.ones((len(block), len(quiet)), dtype=bool)
        for means, limit in ((win.mean_w, tol[0]), (win.mean_f, tol[1])):
            near &= np.linalg.norm(means[block][:, None, :] - means[quiet][None, :, :], axis=2) <= limit
        counts = near.sum(axis=1)
        if counts.max() > most:
            best, most = int(block[int(np.argmax(counts))]), int(counts.max())
    return best


def _rest_findings(rec: Recording, rest: Rest | None, med: float) -> list[Finding]:
    if rest is None:
        return []
    out = _gravity_findings(rec, rest, med)
    if not any(f.code in ("increments_as_rates", "rates_as_increments") for f in out):
        out += _earth_rate_findings(rec, rest)
    return out


def _unit_for(rec: Recording, key: str, ratio: float) -> str | None:
    """The unit of ``key`` under which a size ``ratio`` × the expected one would be right, if any
    other than the one read with."""
    if not ratio > 0.0:  # a channel that reads zero (a dead or unrecorded accelerometer): no unit fits
        return None
    current = rec.units.get(key, unitdefs.SI[key])
    wanted = unitdefs.UNITS[key][current] / ratio
    for unit, k in unitdefs.UNITS[key].items():
        if abs(wanted / k - 1.0) < UNIT_TOL and unit != current:
            return unit
    return None


def _gravity_findings(rec: Recording, rest: Rest, med: float) -> list[Finding]:
    """Gravity's size at rest against normal gravity: a unit, a form, a rate or a scale error."""
    rho = rest.gravity_ratio
    size = rho * GRAVITY
    if abs(rho - 1.0) <= GRAVITY_TOL:
        return []
    key = "accel" if rec.form == "rate" else "dv"
    seen = f"at rest |f| = {size:.4g} m/s², {rho:.4g} × gravity"
    if rec.form == "rate" and abs(rho / med - 1.0) < UNIT_TOL:
        return [_form_finding(rec, "increments_as_rates", f"{seen}, gravity × the {med:.3g} s interval: "
                              "the columns hold increments (dθ, dv), read as rates")]  # fmt: skip
    if rec.form == "increment" and abs(rho * med - 1.0) < UNIT_TOL:
        return [_form_finding(rec, "rates_as_increments", f"{seen}, gravity / the {med:.3g} s interval: "
                              "the columns hold rates (ω, f), read as increments")]  # fmt: skip
    unit = _unit_for(rec, key, rho)
    if unit is not None:
        return [Finding(f"{key}_unit", f"{seen}: the {key} readings are in {unit}",
                        option="units", value=_units_with(rec, **{key: unit}))]  # fmt: skip
    if abs(rho - 1.0) < GRAVITY_OFF:
        off = 100 * (rho - 1.0)
        if rec.form == "increment":
            what = (f"{seen} (dv over the stamped intervals): the intervals are {off:+.1f} % off their "
                    f"stamps (the unit samples at {1.0 / (med * rho):.5g} Hz, not {1.0 / med:.5g} Hz), "
                    f"or the accelerometers' scale is {off:+.1f} % off")  # fmt: skip
            if rec.time_from_rate and rec.stated_rate_hz:
                return [Finding("interval", what, option="rate", value=f"{rec.stated_rate_hz / rho:.6g}")]
            return [
                Finding("interval", what, advice="check the stamps against the unit's own sampling clock")
            ]
        return [Finding("gravity_size", f"{seen}: a scale error of {off:+.1f} % or a bias of "
                        f"{size - GRAVITY:+.3g} m/s² on the vertical axis",
                        advice="calibrate the unit or check its range setting")]  # fmt: skip
    return [Finding("gravity_unknown", f"{seen}, which no unit sins knows explains",
                    advice="check the accelerometer columns and their units")]  # fmt: skip


def _form_finding(rec: Recording, code: str, what: str) -> Finding:
    """Name the columns as the other form (keeping the file columns and their units)."""
    to_increment = code == "increments_as_rates"
    pairs = (("gyro", "dtheta"), ("accel", "dv")) if to_increment else (("dtheta", "gyro"), ("dv", "accel"))
    mapping = rec.column_map
    if not mapping:
        return Finding(code, what, advice="the recording's format says they are rates: check the source")
    columns = ",".join(
        f"{new}_{a}={mapping.get(f'{old}_{a}', f'{old}_{a}')}" for old, new in pairs for a in "xyz"
    )
    if "t" in mapping and mapping["t"] != "t":
        columns = f"t={mapping['t']}," + columns
    units = {k: v for k, v in rec.units.items() if v != unitdefs.SI.get(k) and k in ("t", "temp")}
    for old, new in pairs:
        given = rec.units.get(old, unitdefs.SI[old])
        if given != unitdefs.SI[old]:
            back = {v: k for k, v in _INCREMENT_UNIT.items()}
            units[new] = (_INCREMENT_UNIT if to_increment else back).get(given, unitdefs.SI[new])
    value = columns if not units else f"{columns} (and units {unitdefs.spec_text(units)})"
    return Finding(code, what, option="columns", value=value)


def _earth_rate_findings(rec: Recording, rest: Rest) -> list[Finding]:
    """Earth's rate at rest: a size off by a unit's factor names the unit (when the mean is resolved)."""
    ratio = rest.earth_rate_ratio
    if not rest.rate_resolved or 0.5 <= ratio <= 2.0:
        return []
    key = "gyro" if rec.form == "rate" else "dtheta"
    unit = _unit_for(rec, key, ratio)
    if unit is None:
        return []
    size = ratio * OMEGA_IE
    bias_dph = np.degrees(size) * 3600.0
    return [Finding(
        f"{key}_unit",
        f"at rest |ω| = {size:.4g} rad/s, {ratio:.4g} × Earth's rate: the {key} readings are in {unit} "
        f"(or the unit's bias is {bias_dph:.3g} °/h)",
        option="units", value=_units_with(rec, **{key: unit}),
    )]  # fmt: skip


def _range_findings(rec: Recording, w: Array) -> list[Finding]:
    """Rates beyond any gyro's range: degrees read as radians."""
    top = float(np.abs(w).max()) if w.size else 0.0
    if top <= MAX_GYRO_RADPS:
        return []
    key = "gyro" if rec.form == "rate" else "dtheta"
    current = rec.units.get(key, unitdefs.SI[key])
    degree = "deg/s" if key == "gyro" else "deg"
    what = f"the gyros reach {top:.4g} rad/s ({np.degrees(top):.4g} °/s), beyond any IMU's range"
    if current == unitdefs.SI[key]:
        return [Finding(f"{key}_range", f"{what}: degrees read as radians", option="units",
                        value=_units_with(rec, **{key: degree}))]  # fmt: skip
    return [Finding(f"{key}_range", what, advice="check the gyro columns and their units")]


# --------------------------------------------------------------------------- clipping


def _clipping(rec: Recording) -> tuple[Clipping, ...]:
    """Channels whose readings stick at their extreme (:func:`sins.io.frame_check.clipped_channels`), an
    increment recording's as its steps' mean rates."""
    return frame_check.clipped_channels(rec.imu)


def _clip_finding(c: Clipping) -> Finding:
    gyro = c.channel.startswith("gyro")
    unit, scale = ("°/s", np.degrees(1.0)) if gyro else ("g", 1.0 / 9.80665)
    shown = c.level * scale
    scales = FULL_SCALES["gyro" if gyro else "accel"]
    near = next((s for s in scales if abs(abs(shown) / s - 1.0) < 0.02), None)
    full = f", a ±{near:g} {unit} full scale" if near is not None else ""
    return Finding(
        "clipping",
        f"{c.channel} sticks at {c.level:+.6g} (SI; {shown:+.4g} {unit}{full}) on {c.samples} readings in "
        f"{c.runs} run(s), the first at t = {c.first_s:.6g} s",
        advice="the unit saturated: its readings there are not the motion; use a wider range or leave "
        "those stretches out",
    )


__all__ = [
    "FULL_SCALES",
    "GRAVITY",
    "GRAVITY_OFF",
    "GRAVITY_TOL",
    "JITTER_TOL",
    "MAX_GYRO_RADPS",
    "PLAUSIBLE_HZ",
    "RATE_TOL",
    "REST_SPEED_MPS",
    "REST_TURN_DPS",
    "UNIT_TOL",
    "Clipping",
    "Finding",
    "Gap",
    "Inspection",
    "Rest",
    "gaps_note",
    "inspect",
]
