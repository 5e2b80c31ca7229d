"""Scenario files read and checked: TOML tables → a :class:`~sins.scenario.schema.Scenario` in SI units.

Every unknown key, wrong type or impossible value is refused with one line naming the file and the key
(through :class:`~sins.scenario.toml.TomlKeys`).
"""

from __future__ import annotations

import itertools
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from sins.core.earth import MAX_LAT_DEG
from sins.nav import motion
from sins.nav.vertical import VERTICAL_MODES, VerticalMode
from sins.scenario.presets import preset_or_path
from sins.scenario.schema import (
    AidingSpec,
    CompensationSpec,
    Scenario,
    SegmentsSpec,
    TruthFileSpec,
    WaypointsSpec,
)
from sins.scenario.toml import MAX_SEED, Bound, TomlKeys, read_toml

#: The values of ``[[segment]] type``.
SEGMENT_TYPES = ("hold", "accelerate", "turn", "climb", "attitude")
#: A segment's ramp when ``ramp_s`` is not given (a quarter of a shorter segment), s.
DEFAULT_RAMP_S = 1.0
#: The shortest ramp, s: :data:`sins.nav.motion.MIN_RAMP_S`. The ramp's acceleration ``delta/ramp``
#: (and its jerk, ``delta/ramp²``) grows without bound as the ramp shrinks.
MIN_RAMP_S = motion.MIN_RAMP_S
#: The longest scenario, s (31.7 years): time stamps keep a resolution of 0.12 µs (the spacing of
#: doubles near 1e9), 1/100 of the shortest sample interval (100 kHz).
MAX_DURATION_S = 1e9
#: The fastest vehicle, m/s (Mach 29): beyond it the motion is no longer near the ellipsoid.
MAX_SPEED_MPS = 1e4
#: The slowest waypoint speed, m/s: the longest leg (2.8e6 m) then lasts under 9 years.
MIN_WAYPOINT_SPEED_MPS = 0.01
#: An oscillation's period spans at least this many IMU samples: Simpson's rule then integrates it to
#: a relative error of (2π/10)⁴/2880 = 5e-5 per interval; a shorter period aliases.
MIN_PERIOD_SAMPLES = 10
#: A static alignment averages at least this many IMU samples (0.001 s at 100 Hz, a fraction of one, was
#: taken, and levelled the unit on nothing).
MIN_ALIGN_SAMPLES = 10
#: The damp loop's time constant spans at least this many IMU samples: the integrator's own bound
#: (``sins.nav.strapdown.MIN_TAU_SAMPLES``, not imported: loading a scenario does not load the compiled
#: integrator; a test holds them equal).
MIN_TAU_SAMPLES = 2

#: Static bounds of every numeric scenario field, by its place (``segment.duration_s`` stands for
#: every segment's). The bounds that depend on another field are checked beside them (see the guide).
SCENARIO_BOUNDS: dict[str, Bound] = {
    "imu.rate_hz": Bound(1.0, 100000.0, "Hz"),
    "imu.times_s": Bound(-MAX_DURATION_S, MAX_DURATION_S, "s"),
    "imu.temps_degc": Bound(-100.0, 200.0, "°C", "an IMU's operating range, with margin"),
    "compensation.validation": Bound(0.0, 1.0, "", "a fraction", low_open=True, high_open=True),
    "navigation.vertical_tau_s": Bound(0.0, MAX_DURATION_S, "s", low_open=True),
    "initial.lat_deg": Bound(
        -MAX_LAT_DEG, MAX_LAT_DEG, "°", "the latitude/longitude mechanisation is singular at a pole"
    ),
    "initial.lon_deg": Bound(-180.0, 360.0, "°"),
    "initial.alt_m": Bound(-1000.0, 100000.0, "m"),
    "initial.speed_mps": Bound(0.0, MAX_SPEED_MPS, "m/s"),
    "initial.roll_deg": Bound(-180.0, 180.0, "°"),
    "initial.pitch_deg": Bound(-90.0, 90.0, "°", low_open=True, high_open=True),
    "initial.yaw_deg": Bound(-360.0, 360.0, "°"),
    "segment.duration_s": Bound(0.0, MAX_DURATION_S, "s", low_open=True),
    "segment.ramp_s": Bound(
        MIN_RAMP_S, MAX_DURATION_S / 2, "s", "below it the acceleration delta/ramp is unbounded"
    ),
    "segment.to_speed_mps": Bound(0.0, MAX_SPEED_MPS, "m/s"),
    "segment.delta_speed_mps": Bound(-MAX_SPEED_MPS, MAX_SPEED_MPS, "m/s"),
    "segment.rate_dps": Bound(-360.0, 360.0, "°/s"),
    "segment.angle_deg": Bound(-89.0, 89.0, "°", "a climb's flight-path angle"),
    "segment.roll_deg": Bound(-360.0, 360.0, "°"),
    "segment.pitch_deg": Bound(-360.0, 360.0, "°"),
    "segment.yaw_deg": Bound(-360.0, 360.0, "°"),
    "oscillation.amplitude_deg": Bound(0.0, 89.0, "°"),
    "oscillation.amplitude_m": Bound(0.0, 1000.0, "m"),
    "oscillation.period_s": Bound(0.0, MAX_DURATION_S, "s", low_open=True),
    "oscillation.phase_deg": Bound(-360.0, 360.0, "°"),
    "waypoint.north_m": Bound(-1e6, 1e6, "m", "the radii of the first waypoint are used throughout"),
    "waypoint.east_m": Bound(-1e6, 1e6, "m"),
    "waypoint.up_m": Bound(-1e5, 1e5, "m"),
    "waypoint.speed_mps": Bound(0.0, MAX_SPEED_MPS, "m/s", low_open=True),
    "gnss.rate_hz": Bound(0.1, 10.0, "Hz", "a receiver's fix rates"),
    "gnss.sigma_m": Bound(0.001, 1000.0, "m", "the filter divides by the fixes' variance"),
    "gnss.markov_sigma_m": Bound(0.0, 1000.0, "m"),
    "gnss.markov_tau_s": Bound(0.0, 1e6, "s", low_open=True),
    "gnss.sigma_vel_mps": Bound(0.001, 100.0, "m/s", "the filter divides by the fixes' variance"),
    "gnss.lever_arm_m": Bound(-100.0, 100.0, "m"),
    "gnss.latency_s": Bound(0.0, 10.0, "s"),
    "outage.start_s": Bound(0.0, MAX_DURATION_S, "s", high_open=True),
    "outage.end_s": Bound(0.0, MAX_DURATION_S, "s", low_open=True),
    "alignment.static_s": Bound(0.0, 3600.0, "s", low_open=True),
    "alignment.coarse_s": Bound(0.0, 3600.0, "s", "at most static_s", low_open=True),
    "alignment.heading_sigma_deg": Bound(0.0, 180.0, "°", low_open=True),
    "alignment.min_speed_mps": Bound(0.1, MAX_SPEED_MPS, "m/s", "below it the course over ground is noise"),
    "alignment.sideslip_sigma_deg": Bound(0.0, 30.0, "°", "the filter's small angles"),
}

#: How an aided run starts (``[alignment] method``); ``auto`` picks ``static`` or ``gnss_velocity``.
ALIGNMENT_METHODS = ("auto", "static", "gnss_velocity", "truth")
#: The ``[alignment]`` keys each method reads (``auto`` reads them all).
_ALIGNMENT_KEYS = {
    "static": ("static_s", "coarse_s", "heading_sigma_deg"),
    "gnss_velocity": ("min_speed_mps", "sideslip_sigma_deg"),
    "truth": (),
}

#: The grades the filter may be tuned to (``[gnss] filter_grade``): :data:`sins.imu.spec.GRADES`.
FILTER_GRADES = ("consumer", "industrial", "tactical", "navigation")
_B = SCENARIO_BOUNDS


def load(path: str | os.PathLike[str]) -> Scenario:
    """Read and validate a scenario file.

    Raises
    ------
    SinsInputError
        one line naming the file and the key (or TOML line) at fault.
    """
    path = Path(path)
    return from_dict(read_toml(path, "scenario"), source=path)


#: The keys and tables a scenario may hold at its top, checked before any is read: a misspelt ``[intial]``
#: is named, where it had been the key it then lacks ("initial.lat_deg: missing required key").
TOP_KEYS = ("name", "description", "imu", "compensation", "navigation", "initial", "segment", "waypoint",
            "oscillation", "truth", "gnss", "outage", "alignment")  # fmt: skip


def from_dict(data: dict[str, Any], source: Path | None = None) -> Scenario:
    """Validate a parsed scenario table (what :func:`load` does after parsing).

    Parameters
    ----------
    data : the parsed TOML document
    source : the file it came from: names it in the errors, and relative paths start from its folder

    Raises
    ------
    SinsInputError
        one line naming the file and the key at fault.
    """
    name_of_source = str(source) if source else "<scenario>"
    top = TomlKeys(name_of_source, "", data)
    if odd := [k for k in data if k not in TOP_KEYS]:
        raise top.error(f"unknown key (a scenario's keys: {', '.join(sorted(TOP_KEYS))})", odd[0])
    name = top.string("name", default=source.stem if source else "scenario")
    description = top.string("description", default="")
    base = source.parent if source else Path(".")
    rate_hz, imu_model, imu_seed, temperature = _imu(top.sub("imu"), base)
    compensation = (
        _compensation(top.sub("compensation"), imu_model, base) if top.has("compensation") else None
    )
    vertical, tau = _navigation(top.sub("navigation"), rate_hz)
    trajectory = _trajectory(top, rate_hz, base)
    aiding = _aiding(top, rate_hz)
    top.done()
    return Scenario(
        name=name,
        description=description,
        source=source,
        rate_hz=rate_hz,
        trajectory=trajectory,
        vertical=vertical,
        vertical_tau_s=tau,
        imu_model=imu_model,
        imu_seed=imu_seed,
        compensation=compensation,
        temperature=temperature,
        aiding=aiding,
    )


def _imu(
    imu: TomlKeys, base: Path
) -> tuple[float, Path | None, int, tuple[tuple[float, ...], tuple[float, ...]]]:
    """The ``[imu]`` table: rate (Hz), model file, seed and temperature profile (times s, °C)."""
    rate_hz = imu.bounded("rate_hz", _B["imu.rate_hz"], 100.0)
    imu_model = preset_or_path(imu, "model", "imu", base) if imu.has("model") else None
    imu_seed = imu.integer("seed", 0, high=MAX_SEED)
    temperature: tuple[tuple[float, ...], tuple[float, ...]] = ((0.0,), (20.0,))
    if imu.has("temps_degc"):
        times = imu.bounded_numbers("times_s", _B["imu.times_s"], [0.0])
        temps = imu.bounded_numbers("temps_degc", _B["imu.temps_degc"])
        if len(times) != len(temps) or any(b <= a for a, b in itertools.pairwise(times)):
            raise imu.error("times_s must increase and match temps_degc in length", "times_s")
        temperature = (tuple(times), tuple(temps))
    imu.done()
    return rate_hz, imu_model, imu_seed, temperature


def _compensation(comp: TomlKeys, imu_model: Path | None, base: Path) -> CompensationSpec:
    """The ``[compensation]`` table: the rig, the held-back fraction, the seed and the strategies."""
    if imu_model is None:
        raise comp.error("needs an IMU model to compensate: give [imu] model")
    from sins.compensation import VARIANTS

    names = comp.strings("strategies", ["none", "regression", "mlp", "kohonen"], tuple(VARIANTS))
    compensation = CompensationSpec(
        rig=preset_or_path(comp, "rig", "rig", base),
        validation=comp.bounded("validation", _B["compensation.validation"], 0.3),
        seed=comp.integer("seed", 0, high=MAX_SEED),
        strategies=tuple(dict.fromkeys(["oracle", *names])),  # the oracle is every table's reference
    )
    comp.done()
    return compensation


def _navigation(nav: TomlKeys, rate_hz: float) -> tuple[VerticalMode, float]:
    """The ``[navigation]`` table: the vertical channel's mode and damping time (s)."""
    vertical = nav.choice("vertical", VERTICAL_MODES, "free")
    if vertical != "damp" and nav.has("vertical_tau_s"):  # as sins integrate's --vertical-tau-s: not ignored
        raise nav.error(f'goes with vertical = "damp" (the channel is {vertical})', "vertical_tau_s")
    tau = nav.bounded("vertical_tau_s", _B["navigation.vertical_tau_s"], 10.0)
    if tau < MIN_TAU_SAMPLES / rate_hz:
        raise nav.error(
            f"must be at least {MIN_TAU_SAMPLES} IMU samples ({MIN_TAU_SAMPLES / rate_hz:g} s at "
            f"{rate_hz:g} Hz): a shorter damp loop is unstable, got {tau:g}",
            "vertical_tau_s",
        )
    nav.done()
    return vertical, tau


def _trajectory(top: TomlKeys, rate_hz: float, base: Path) -> SegmentsSpec | WaypointsSpec | TruthFileSpec:
    """Exactly one of ``[[segment]]``, ``[[waypoint]]`` or ``[truth]``."""
    kinds = [k for k in ("segment", "waypoint", "truth") if top.has(k)]
    if len(kinds) != 1:
        found = ", ".join(kinds) or "none"
        raise top.error(
            "give exactly one trajectory: [[segment]] tables, [[waypoint]] tables or a [truth] table "
            f"(found {found})"
        )
    if kinds[0] == "segment":
        return _segments(top, rate_hz)
    if kinds[0] == "waypoint":
        return _waypoints(top)
    truth = top.sub("truth")
    file = truth.string("file")
    truth.done()
    if top.has("initial"):
        raise top.error("not used with a [truth] trajectory (the truth's first row is the start)", "initial")
    return TruthFileSpec(path=(base / file))


def _triple(keys: TomlKeys, key: str, default: list[float]) -> tuple[float, float, float]:
    """Three bounded numbers (north, east, down or x, y, z); a single number stands for all three."""
    bound = _B[f"{keys.where}.{key}"]
    if keys.has(key) and not isinstance(keys.table[key], list):
        value = keys.bounded(key, bound)
        return value, value, value
    values = keys.bounded_numbers(key, bound, default)
    if len(values) != 3:
        raise keys.error(f"expected 3 numbers (or one for all three), got {len(values)}", key)
    return values[0], values[1], values[2]


def _aiding(top: TomlKeys, imu_rate_hz: float) -> AidingSpec | None:
    """The ``[gnss]``, ``[[outage]]`` and ``[alignment]`` tables, or None without ``[gnss]``."""
    if not top.has("gnss"):
        for other in ("outage", "alignment"):
            if top.has(other):
                raise top.error("needs a [gnss] receiver to aid the navigation", other)
        return None
    gnss = top.sub("gnss")
    sigma_vel = gnss.bounded("sigma_vel_mps", _B["gnss.sigma_vel_mps"]) if gnss.has("sigma_vel_mps") else None
    grade = gnss.choice("filter_grade", FILTER_GRADES) if gnss.has("filter_grade") else None
    rate_hz = gnss.bounded("rate_hz", _B["gnss.rate_hz"], 1.0)
    sigma_m = _triple(gnss, "sigma_m", [1.5, 1.5, 3.0])
    markov_sigma_m = _triple(gnss, "markov_sigma_m", [0.0, 0.0, 0.0])
    markov_tau_s = gnss.bounded("markov_tau_s", _B["gnss.markov_tau_s"], 100.0)
    lever_arm_m = _triple(gnss, "lever_arm_m", [0.0, 0.0, 0.0])
    latency_s = gnss.bounded("latency_s", _B["gnss.latency_s"], 0.0)
    seed = gnss.integer("seed", 0, high=MAX_SEED)
    compensate = gnss.boolean("compensate_latency", True)
    gnss.done()
    outages: list[tuple[float, float]] = []
    for out in top.tables("outage"):
        start = out.bounded("start_s", _B["outage.start_s"])
        end = out.bounded("end_s", _B["outage.end_s"])
        if end <= start:
            raise out.error(f"must come after start_s {start:g} s, got {end:g}", "end_s")
        for k, (a, b) in enumerate(outages):  # each outage's figure is the error at its own end
            if start < b and a < end:
                raise out.error(
                    f"{start:g}-{end:g} s overlaps outage[{k + 1}] ({a:g}-{b:g} s): give one outage of "
                    f"{min(a, start):g}-{max(b, end):g} s",
                    "start_s",
                )
        out.done()
        outages.append((start, end))
    align = _alignment(top, imu_rate_hz)
    return AidingSpec(
        rate_hz=rate_hz, sigma_m=sigma_m, markov_sigma_m=markov_sigma_m, markov_tau_s=markov_tau_s,
        sigma_vel_mps=sigma_vel, lever_arm_m=lever_arm_m, latency_s=latency_s, seed=seed, filter_grade=grade,
        outages=tuple(outages), compensate_latency=compensate, **align,
    )  # fmt: skip


def _alignment(top: TomlKeys, imu_rate_hz: float) -> dict[str, Any]:
    """The ``[alignment]`` table as :class:`AidingSpec`'s fields (none: ``auto``, each default)."""
    if not top.has("alignment"):
        return {}
    align = top.sub("alignment")
    # A table with static_s and no method is the static alignment it always was.
    method = align.choice("method", ALIGNMENT_METHODS, "static" if align.has("static_s") else "auto")
    for other, keys in _ALIGNMENT_KEYS.items():
        for key in keys:
            if method not in ("auto", other) and align.has(key):
                raise align.error(f"is not read by method {method!r} (only by {other!r} or 'auto')", key)
    out: dict[str, Any] = {"alignment": method}
    if method == "static" or align.has("static_s"):
        out["static_s"] = align.bounded("static_s", _B["alignment.static_s"], 300.0)
        if out["static_s"] < MIN_ALIGN_SAMPLES / imu_rate_hz:  # a mean of fewer readings levels nothing
            raise align.error(
                f"must be at least {MIN_ALIGN_SAMPLES} IMU samples ({MIN_ALIGN_SAMPLES / imu_rate_hz:g} s at "
                f"{imu_rate_hz:g} Hz), got {out['static_s']:g}",
                "static_s",
            )
    limit = out.get("static_s", 3600.0)
    out["coarse_s"] = align.bounded("coarse_s", _B["alignment.coarse_s"], min(60.0, limit))
    if out["coarse_s"] > limit:
        raise align.error(f"must be at most static_s {limit:g} s, got {out['coarse_s']:g}", "coarse_s")
    if align.has("heading_sigma_deg"):
        out["heading_sigma_rad"] = math.radians(
            align.bounded("heading_sigma_deg", _B["alignment.heading_sigma_deg"])
        )
    out["min_speed_mps"] = align.bounded("min_speed_mps", _B["alignment.min_speed_mps"], 5.0)
    out["sideslip_sigma_rad"] = math.radians(
        align.bounded("sideslip_sigma_deg", _B["alignment.sideslip_sigma_deg"], 1.0)
    )
    align.done()
    return out


def _position(init: TomlKeys) -> tuple[float, float, float]:
    lat = init.bounded("lat_deg", _B["initial.lat_deg"])
    lon = init.bounded("lon_deg", _B["initial.lon_deg"], 0.0)
    h_m = init.bounded("alt_m", _B["initial.alt_m"], 0.0)
    return math.radians(lat), math.radians(lon), h_m


def _segments(top: TomlKeys, rate_hz: float) -> SegmentsSpec:
    start = _start(top.sub("initial"))
    speed = start.speed
    segments: list[motion.Segment] = []
    total = 0.0
    for seg in top.tables("segment"):
        segment, speed = _segment(seg, speed)
        total += segment.duration
        if total > MAX_DURATION_S:
            raise seg.error(
                f"the segments so far last {total:g} s, more than a scenario's {MAX_DURATION_S:g} s",
                "duration_s",
            )
        segments.append(segment)
    if not segments:
        raise top.error("needs at least one [[segment]]", "segment")
    oscillations = tuple(_oscillation(osc, rate_hz) for osc in top.tables("oscillation"))
    return SegmentsSpec(start=start, segments=tuple(segments), oscillations=oscillations)


def _start(init: TomlKeys) -> motion.Start:
    """The ``[initial]`` table: position, speed and attitude at t = 0."""
    lat, lon, h_m = _position(init)
    start = motion.Start(
        lat=lat,
        lon=lon,
        h=h_m,
        speed=init.bounded("speed_mps", _B["initial.speed_mps"], 0.0),
        roll=math.radians(init.bounded("roll_deg", _B["initial.roll_deg"], 0.0)),
        pitch=math.radians(init.bounded("pitch_deg", _B["initial.pitch_deg"], 0.0)),
        yaw=math.radians(init.bounded("yaw_deg", _B["initial.yaw_deg"], 0.0)),
    )
    init.done()
    return start


def _segment(seg: TomlKeys, speed: float) -> tuple[motion.Segment, float]:
    """One ``[[segment]]`` table entered at ``speed`` (m/s): the segment and the speed it leaves at."""
    kind = seg.string("type", choices=SEGMENT_TYPES)
    duration = seg.bounded("duration_s", _B["segment.duration_s"])
    if duration < 2 * MIN_RAMP_S:
        raise seg.error(
            f"must be at least {2 * MIN_RAMP_S:g} s (a ramp in and out of at least {MIN_RAMP_S:g} s "
            f"each), got {duration:g}",
            "duration_s",
        )
    ramp = 0.0
    if kind != "hold":
        default = max(MIN_RAMP_S, min(DEFAULT_RAMP_S, duration / 4))
        ramp = seg.bounded("ramp_s", _B["segment.ramp_s"], default)
        if ramp > duration / 2:
            raise seg.error(f"must be at most half the duration ({duration / 2:g} s), got {ramp:g}", "ramp_s")
    segment: motion.Segment
    if kind == "hold":
        segment = motion.Hold(duration)
    elif kind == "accelerate":
        change = _speed_change(seg, speed)
        speed += change
        segment = motion.Accelerate(duration, change, ramp)
    elif kind == "turn":
        segment = motion.Turn(
            duration, _turn_rate(seg, duration - ramp), ramp, seg.boolean("coordinated", False)
        )
    elif kind == "climb":
        angle = seg.bounded("angle_deg", _B["segment.angle_deg"])
        segment = motion.Climb(duration, math.radians(angle), ramp)
    else:
        d = [
            math.radians(seg.bounded(k, _B[f"segment.{k}"], 0.0))
            for k in ("roll_deg", "pitch_deg", "yaw_deg")
        ]
        segment = motion.Rotate(duration, d[0], d[1], d[2], ramp)
    seg.done()
    return segment, speed


def _speed_change(seg: TomlKeys, speed: float) -> float:
    """An ``accelerate`` segment's change of speed (m/s), from ``to_speed_mps`` or ``delta_speed_mps``."""
    delta = _exactly_one(seg, ("to_speed_mps", "delta_speed_mps"))
    if delta == "to_speed_mps":
        change = seg.bounded("to_speed_mps", _B["segment.to_speed_mps"]) - speed
    else:
        change = seg.bounded("delta_speed_mps", _B["segment.delta_speed_mps"])
    if speed + change < -1e-9:
        raise seg.error(f"the speed would become negative ({speed + change:g} m/s)", delta)
    if speed + change > MAX_SPEED_MPS:
        raise seg.error(f"the speed would become {speed + change:g} m/s, above {MAX_SPEED_MPS:g} m/s", delta)
    return change


def _turn_rate(seg: TomlKeys, plateau_s: float) -> float:
    """A ``turn`` segment's rate (rad/s), from ``rate_dps`` or ``angle_deg`` spread over the plateau."""
    if _exactly_one(seg, ("rate_dps", "angle_deg")) == "rate_dps":
        return math.radians(seg.bounded("rate_dps", _B["segment.rate_dps"]))
    rate = math.radians(seg.number("angle_deg")) / plateau_s
    if abs(rate) > math.radians(360.0):
        raise seg.error(f"turns faster than 360 °/s over {plateau_s:g} s", "angle_deg")
    return rate


def _oscillation(osc: TomlKeys, rate_hz: float) -> motion.Oscillation:
    """One ``[[oscillation]]`` table: a sinusoid on a channel, resolvable at ``rate_hz``."""
    channel = osc.choice("channel", motion.OSCILLATION_CHANNELS)
    if channel == "heave":
        amplitude = osc.bounded("amplitude_m", _B["oscillation.amplitude_m"])
    else:
        amplitude = math.radians(osc.bounded("amplitude_deg", _B["oscillation.amplitude_deg"]))
    period = osc.bounded("period_s", _B["oscillation.period_s"])
    if period < MIN_PERIOD_SAMPLES / rate_hz:
        raise osc.error(
            f"must be at least {MIN_PERIOD_SAMPLES} IMU samples ({MIN_PERIOD_SAMPLES / rate_hz:g} s at "
            f"{rate_hz:g} Hz), or the increments cannot resolve it; got {period:g}",
            "period_s",
        )
    oscillation = motion.Oscillation(
        channel=channel,
        amplitude=amplitude,
        period=period,
        phase=math.radians(osc.bounded("phase_deg", _B["oscillation.phase_deg"], 0.0)),
    )
    osc.done()
    return oscillation


def _exactly_one(seg: TomlKeys, keys: tuple[str, str]) -> str:
    given = [k for k in keys if seg.has(k)]
    if len(given) != 1:
        raise seg.error(f"give exactly one of {' or '.join(keys)}")
    return given[0]


def _waypoints(top: TomlKeys) -> WaypointsSpec:
    init = top.sub("initial")
    lat, lon, h_m = _position(init)
    init.done()
    if top.has("oscillation"):
        raise top.error("oscillations are only for [[segment]] trajectories", "oscillation")
    points, speeds = [], []
    for wp in top.tables("waypoint"):
        north = wp.bounded("north_m", _B["waypoint.north_m"], 0.0)
        east = wp.bounded("east_m", _B["waypoint.east_m"], 0.0)
        points.append((north, east, -wp.bounded("up_m", _B["waypoint.up_m"], 0.0)))
        speed = wp.bounded("speed_mps", _B["waypoint.speed_mps"])
        if speed < MIN_WAYPOINT_SPEED_MPS:
            raise wp.error(
                f"must be at least {MIN_WAYPOINT_SPEED_MPS:g} m/s (a slower leg of the path could last "
                f"decades), got {speed:g}",
                "speed_mps",
            )
        speeds.append(speed)
        wp.done()
    if len(points) < 2:
        raise top.error("needs at least two [[waypoint]] tables", "waypoint")
    p = np.array(points)
    gaps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    if (gaps < 1e-3).any():
        i = int(np.argmax(gaps < 1e-3)) + 2
        raise top.error(f"waypoint {i} is at the same place as waypoint {i - 1}", "waypoint")
    return WaypointsSpec(lat=lat, lon=lon, h=h_m, points_ned=tuple(points), speeds=tuple(speeds))


__all__ = [
    "ALIGNMENT_METHODS",
    "DEFAULT_RAMP_S",
    "FILTER_GRADES",
    "MAX_DURATION_S",
    "MAX_SPEED_MPS",
    "MIN_ALIGN_SAMPLES",
    "MIN_PERIOD_SAMPLES",
    "MIN_RAMP_S",
    "MIN_TAU_SAMPLES",
    "MIN_WAYPOINT_SPEED_MPS",
    "SCENARIO_BOUNDS",
    "SEGMENT_TYPES",
    "TOP_KEYS",
    "from_dict",
    "load",
]
