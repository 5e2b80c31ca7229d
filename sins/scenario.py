"""Scenario files (TOML) → frozen dataclasses → a motion.

A scenario names how the vehicle moves (segments, waypoints or a recorded
truth file), the IMU sample rate and how the vertical channel is treated.
Units at this edge carry suffixes (``lat_deg``, ``rate_dps``, ``duration_s``);
everything is converted to SI on reading. Any unknown key, wrong type or
impossible value is refused with one line naming the file and the key.

Example (see ``scenarios/`` for the presets)::

    name = "car"
    [imu]
    rate_hz = 100
    [initial]
    lat_deg = 45.0
    lon_deg = 7.6
    alt_m = 250.0
    yaw_deg = 30.0
    [[segment]]
    type = "accelerate"
    duration_s = 10
    to_speed_mps = 15
    [[segment]]
    type = "turn"
    duration_s = 20
    rate_dps = 4.5
"""

from __future__ import annotations

import itertools
import math
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from sins import io
from sins.errors import SinsInputError
from sins.nav import earth, motion

if TYPE_CHECKING:  # the IMU and rig readers import these when called: `sins run` needs neither
    from sins import imu
    from sins.imu import calibration

_MISSING: Any = object()

SEGMENT_TYPES = ("hold", "accelerate", "turn", "climb", "attitude")
VERTICAL_MODES = ("free", "hold", "damp")
DEFAULT_RAMP_S = 1.0


@dataclass(frozen=True)
class SegmentsSpec:
    """Trajectory from motion segments (SI units)."""

    start: motion.Start
    segments: tuple[motion.Segment, ...]
    oscillations: tuple[motion.Oscillation, ...] = ()


@dataclass(frozen=True)
class WaypointsSpec:
    """Trajectory through waypoints: start position (rad, m), offsets (m, NED) and speeds (m/s)."""

    lat: float
    lon: float
    h: float
    points_ned: tuple[tuple[float, float, float], ...]
    speeds: tuple[float, ...]


@dataclass(frozen=True)
class TruthFileSpec:
    """Trajectory through a recorded truth CSV."""

    path: Path


@dataclass(frozen=True)
class Scenario:
    """A validated scenario."""

    name: str
    description: str
    source: Path | None
    rate_hz: float
    trajectory: SegmentsSpec | WaypointsSpec | TruthFileSpec
    vertical: str = "free"
    vertical_tau_s: float = 10.0
    imu_model: Path | None = None
    imu_seed: int = 0
    compensation: CompensationSpec | None = None
    temperature: tuple[tuple[float, ...], tuple[float, ...]] = ((0.0,), (20.0,))  # (times_s, temps_degc)


@dataclass(frozen=True)
class CompensationSpec:
    """How a scenario's strategies are fitted: the rig session, its held-back fraction, the strategies."""

    rig: Path
    validation: float
    seed: int
    strategies: tuple[str, ...]


class TomlKeys:
    """Typed access to one TOML table that remembers which keys were used."""

    def __init__(self, source: str, where: str, table: Any) -> None:
        self.source = source
        self.where = where
        if not isinstance(table, dict):
            raise self.error(f"expected a table, got {_kind(table)}")
        self.table = table
        self.used: set[str] = set()

    def error(self, message: str, key: str | None = None) -> SinsInputError:
        """The one-line error to raise for ``key`` (or the table), naming the file and key."""
        place = f"{self.where}.{key}" if key and self.where else (key or self.where)
        return SinsInputError(f"{self.source}: {place}: {message}" if place else f"{self.source}: {message}")

    def has(self, key: str) -> bool:
        """Whether the table has ``key`` (without marking it used)."""
        return key in self.table

    def _default(self, key: str, default: Any) -> Any:
        """The default for an absent key, or the error for an absent required one."""
        if default is _MISSING:
            raise self.error("missing required key", key)
        return default

    def get(self, key: str) -> Any:
        """The raw value of ``key``, marked as used."""
        self.used.add(key)
        return self.table[key]

    def number(
        self,
        key: str,
        default: Any = _MISSING,
        *,
        low: float | None = None,
        high: float | None = None,
        low_open: bool = False,
        high_open: bool = False,
    ) -> float:
        """A finite number within ``low`` and ``high`` (open where ``*_open``); ``default`` if absent."""
        if key not in self.table:
            return float(self._default(key, default))
        value = self.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(f"expected a number, got {_kind(value)} {value!r}", key)
        try:
            value = float(value)
        except OverflowError:
            raise self.error("number too large", key) from None
        if not math.isfinite(value):
            raise self.error(f"must be finite, got {value!r}", key)
        if low is not None and (value < low or (low_open and value == low)):
            raise self.error(f"must be {'>' if low_open else '>='} {low:g}, got {value:g}", key)
        if high is not None and (value > high or (high_open and value == high)):
            raise self.error(f"must be {'<' if high_open else '<='} {high:g}, got {value:g}", key)
        return value

    def string(self, key: str, default: Any = _MISSING, choices: tuple[str, ...] = ()) -> str:
        """A string, one of ``choices`` when given; ``default`` if absent."""
        if key not in self.table:
            return str(self._default(key, default))
        value = self.get(key)
        if not isinstance(value, str):
            raise self.error(f"expected a string, got {_kind(value)} {value!r}", key)
        if choices and value not in choices:
            raise self.error(f"must be one of {', '.join(choices)}; got {value!r}", key)
        return value

    def numbers(self, key: str, default: Any = _MISSING) -> list[float]:
        """A non-empty array of finite numbers."""
        if key not in self.table:
            return list(self._default(key, default))
        value = self.get(key)
        if not isinstance(value, list) or not value:
            raise self.error(f"expected a non-empty array of numbers, got {_kind(value)}", key)
        out = []
        for i, item in enumerate(value):
            if isinstance(item, bool) or not isinstance(item, int | float) or not math.isfinite(float(item)):
                raise self.error(f"item {i + 1}: expected a finite number, got {item!r}", key)
            out.append(float(item))
        return out

    def strings(self, key: str, default: Any = _MISSING, choices: tuple[str, ...] = ()) -> list[str]:
        """An array of strings, each among ``choices`` when given."""
        if key not in self.table:
            return list(self._default(key, default))
        value = self.get(key)
        if not isinstance(value, list):
            raise self.error(f"expected an array of strings, got {_kind(value)}", key)
        for i, item in enumerate(value):
            if not isinstance(item, str) or (choices and item not in choices):
                allowed = f" (one of {', '.join(choices)})" if choices else ""
                raise self.error(f"item {i + 1}: expected a string{allowed}, got {item!r}", key)
        return list(value)

    def boolean(self, key: str, default: bool) -> bool:
        """A boolean; ``default`` if absent."""
        if key not in self.table:
            return default
        value = self.get(key)
        if not isinstance(value, bool):
            raise self.error(f"expected true or false, got {_kind(value)} {value!r}", key)
        return value

    def tables(self, key: str) -> list[TomlKeys]:
        """The array of tables ``[[key]]``, each as a :class:`TomlKeys`; empty if absent."""
        if key not in self.table:
            return []
        value = self.get(key)
        if not isinstance(value, list):
            raise self.error(f"expected an array of tables ([[{key}]]), got {_kind(value)}", key)
        return [TomlKeys(self.source, f"{key}[{i + 1}]", item) for i, item in enumerate(value)]

    def sub(self, key: str) -> TomlKeys:
        """The sub-table ``key`` as a :class:`TomlKeys` (empty if absent)."""
        value = self.get(key) if key in self.table else {}
        return TomlKeys(self.source, key, value)

    def done(self, allowed: tuple[str, ...] = ()) -> None:
        """Refuse keys that were never read (unknown or not valid in this context)."""
        for key in self.table:
            if key not in self.used and key not in allowed:
                known = ", ".join(sorted(self.used | set(allowed))) or "none"
                raise self.error(f"unknown key (keys used here: {known})", key)


def _kind(value: Any) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "an array",
            dict: "a table"}.get(type(value), type(value).__name__)  # fmt: skip


def load(path: str | os.PathLike[str]) -> Scenario:
    """Read and validate a scenario file.

    Raises
    ------
    SinsInputError
        one line naming the file and the key (or TOML line) at fault.
    """
    path = Path(path)
    return from_dict(read_toml(path, "scenario"), source=path)


def read_toml(path: Path, what: str) -> dict[str, Any]:
    """A TOML file parsed; one-line errors name the file and ``what`` kind of file it is."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise SinsInputError(f"{path}: no such {what} file") from None
    except tomllib.TOMLDecodeError as exc:
        raise SinsInputError(f"{path}: invalid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise SinsInputError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except IsADirectoryError:
        raise SinsInputError(f"{path}: is a directory, expected a {what} file") from None
    except OSError as exc:
        raise SinsInputError(f"{path}: cannot read: {exc}") from None


def from_dict(data: dict[str, Any], source: Path | None = None) -> Scenario:
    """Validate a parsed scenario table (what :func:`load` does after parsing)."""
    name_of_source = str(source) if source else "<scenario>"
    top = TomlKeys(name_of_source, "", data)
    name = top.string("name", default=source.stem if source else "scenario")
    description = top.string("description", default="")
    imu = top.sub("imu")
    rate_hz = imu.number("rate_hz", 100.0, low=1.0, high=100000.0)
    base = source.parent if source else Path(".")
    imu_model = _preset_or_path(imu, "model", "imu", base) if imu.has("model") else None
    imu_seed = int(imu.number("seed", 0, low=0))
    temperature: tuple[tuple[float, ...], tuple[float, ...]] = ((0.0,), (20.0,))
    if imu.has("temps_degc"):
        times, temps = imu.numbers("times_s", [0.0]), imu.numbers("temps_degc")
        if len(times) != len(temps) or any(b <= a for a, b in itertools.pairwise(times)):
            raise imu.error("times_s must increase and match temps_degc in length", "times_s")
        temperature = (tuple(times), tuple(temps))
    imu.done()
    compensation = None
    if top.has("compensation"):
        comp = top.sub("compensation")
        if imu_model is None:
            raise comp.error("needs an IMU model to compensate: give [imu] model")
        from sins.compensation import VARIANTS

        names = comp.strings("strategies", ["none", "regression", "mlp", "kohonen"], tuple(VARIANTS))
        compensation = CompensationSpec(
            rig=_preset_or_path(comp, "rig", "rig", base),
            validation=comp.number("validation", 0.3, low=0.0, high=1.0, low_open=True, high_open=True),
            seed=int(comp.number("seed", 0, low=0)),
            strategies=tuple(dict.fromkeys(["oracle", *names])),  # the oracle is every table's reference
        )
        comp.done()
    nav = top.sub("navigation")
    vertical = nav.string("vertical", "free", VERTICAL_MODES)
    tau = nav.number("vertical_tau_s", 10.0, low=0.0, low_open=True)
    nav.done()

    kinds = [k for k in ("segment", "waypoint", "truth") if top.has(k)]
    if len(kinds) != 1:
        found = ", ".join(kinds) or "none"
        raise top.error(
            "give exactly one trajectory: [[segment]] tables, [[waypoint]] tables or a [truth] table "
            f"(found {found})"
        )
    trajectory: SegmentsSpec | WaypointsSpec | TruthFileSpec
    if kinds[0] == "segment":
        trajectory = _segments(top)
    elif kinds[0] == "waypoint":
        trajectory = _waypoints(top)
    else:
        truth = top.sub("truth")
        file = truth.string("file")
        truth.done()
        base = source.parent if source else Path(".")
        trajectory = TruthFileSpec(path=(base / file))
        if top.has("initial"):
            raise top.error(
                "not used with a [truth] trajectory (the truth's first row is the start)", "initial"
            )
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
    )


def _preset_or_path(keys: TomlKeys, key: str, kind: str, base: Path) -> Path:
    """A file named by ``key``: a path relative to the scenario, or a preset name of ``kind``."""
    value = keys.string(key)
    path = base / value
    if path.suffix == ".toml" or path.exists():
        return path
    preset = Path(__file__).parent / "scenarios" / kind / f"{value}.toml"
    if preset.exists():
        return preset
    raise keys.error(f"no such file or {kind} preset: {value!r}", key)


def _position(init: TomlKeys) -> tuple[float, float, float]:
    lat = init.number("lat_deg", low=-89.9, high=89.9)
    lon = init.number("lon_deg", 0.0, low=-180.0, high=360.0)
    alt = init.number("alt_m", 0.0, low=-1000.0, high=100000.0)
    return math.radians(lat), math.radians(lon), alt


def _segments(top: TomlKeys) -> SegmentsSpec:
    init = top.sub("initial")
    lat, lon, alt = _position(init)
    start = motion.Start(
        lat=lat,
        lon=lon,
        h=alt,
        speed=init.number("speed_mps", 0.0, low=0.0),
        roll=math.radians(init.number("roll_deg", 0.0, low=-180.0, high=180.0)),
        pitch=math.radians(
            init.number("pitch_deg", 0.0, low=-90.0, high=90.0, low_open=True, high_open=True)
        ),
        yaw=math.radians(init.number("yaw_deg", 0.0, low=-360.0, high=360.0)),
    )
    init.done()
    speed = start.speed
    segments: list[motion.Segment] = []
    for seg in top.tables("segment"):
        kind = seg.string("type", choices=SEGMENT_TYPES)
        duration = seg.number("duration_s", low=0.0, low_open=True)
        ramp = 0.0
        if kind != "hold":
            ramp = seg.number("ramp_s", min(DEFAULT_RAMP_S, duration / 4), low=0.0, low_open=True)
            if ramp > duration / 2:
                raise seg.error(
                    f"must be at most half the duration ({duration / 2:g} s), got {ramp:g}", "ramp_s"
                )
        plateau = duration - ramp
        if kind == "hold":
            segments.append(motion.Hold(duration))
        elif kind == "accelerate":
            delta = _exactly_one(seg, ("to_speed_mps", "delta_speed_mps"))
            if delta == "to_speed_mps":
                change = seg.number("to_speed_mps", low=0.0) - speed
            else:
                change = seg.number("delta_speed_mps")
            if speed + change < -1e-9:
                raise seg.error(f"the speed would become negative ({speed + change:g} m/s)", delta)
            speed += change
            segments.append(motion.Accelerate(duration, change, ramp))
        elif kind == "turn":
            which = _exactly_one(seg, ("rate_dps", "angle_deg"))
            if which == "rate_dps":
                rate = math.radians(seg.number("rate_dps", low=-360.0, high=360.0))
            else:
                rate = math.radians(seg.number("angle_deg")) / plateau
                if abs(rate) > math.radians(360.0):
                    raise seg.error(f"turns faster than 360 °/s over {plateau:g} s", "angle_deg")
            segments.append(motion.Turn(duration, rate, ramp, seg.boolean("coordinated", False)))
        elif kind == "climb":
            angle = seg.number("angle_deg", low=-89.0, high=89.0)
            segments.append(motion.Climb(duration, math.radians(angle), ramp))
        else:
            d = [
                math.radians(seg.number(k, 0.0, low=-360.0, high=360.0))
                for k in ("roll_deg", "pitch_deg", "yaw_deg")
            ]
            segments.append(motion.Rotate(duration, d[0], d[1], d[2], ramp))
        seg.done()
    if not segments:
        raise top.error("needs at least one [[segment]]", "segment")
    oscillations = []
    for osc in top.tables("oscillation"):
        channel = osc.string("channel", choices=("roll", "pitch", "yaw", "heave"))
        if channel == "heave":
            amplitude = osc.number("amplitude_m", low=0.0)
        else:
            amplitude = math.radians(osc.number("amplitude_deg", low=0.0, high=89.0))
        oscillations.append(
            motion.Oscillation(
                channel=channel,
                amplitude=amplitude,
                period=osc.number("period_s", low=0.0, low_open=True),
                phase=math.radians(osc.number("phase_deg", 0.0)),
            )
        )
        osc.done()
    return SegmentsSpec(start=start, segments=tuple(segments), oscillations=tuple(oscillations))


def _exactly_one(seg: TomlKeys, keys: tuple[str, str]) -> str:
    given = [k for k in keys if seg.has(k)]
    if len(given) != 1:
        raise seg.error(f"give exactly one of {' or '.join(keys)}")
    return given[0]


def _waypoints(top: TomlKeys) -> WaypointsSpec:
    init = top.sub("initial")
    lat, lon, alt = _position(init)
    init.done()
    if top.has("oscillation"):
        raise top.error("oscillations are only for [[segment]] trajectories", "oscillation")
    points, speeds = [], []
    for wp in top.tables("waypoint"):
        points.append((wp.number("north_m", 0.0), wp.number("east_m", 0.0), -wp.number("up_m", 0.0)))
        speeds.append(wp.number("speed_mps", low=0.0, low_open=True))
        wp.done()
    if len(points) < 2:
        raise top.error("needs at least two [[waypoint]] tables", "waypoint")
    p = np.array(points)
    gaps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    if (gaps < 1e-3).any():
        i = int(np.argmax(gaps < 1e-3)) + 2
        raise top.error(f"waypoint {i} is at the same place as waypoint {i - 1}", "waypoint")
    return WaypointsSpec(lat=lat, lon=lon, h=alt, points_ned=tuple(points), speeds=tuple(speeds))


def build_motion(scenario: Scenario) -> motion.Motion:
    """The continuous motion a scenario describes."""
    spec = scenario.trajectory
    if isinstance(spec, SegmentsSpec):
        return motion.SegmentMotion.from_segments(spec.start, spec.segments, spec.oscillations)
    if isinstance(spec, WaypointsSpec):
        p = np.array(spec.points_ned)
        # The path starts at the first waypoint; place it relative to [initial].
        r_m, r_n = earth.radii(spec.lat)
        lat0 = spec.lat + p[0, 0] / (r_m + spec.h)
        lon0 = spec.lon + p[0, 1] / ((r_n + spec.h) * math.cos(spec.lat))
        return motion.WaypointMotion.from_waypoints(lat0, lon0, spec.h - p[0, 2], p, np.array(spec.speeds))
    truth = io.read_truth(spec.path)
    if len(truth.t) < 4:
        raise SinsInputError(f"{spec.path}: a truth trajectory needs at least 4 rows to define a motion")
    return motion.RecordedMotion.from_series(truth)


# --------------------------------------------------------------------------- IMU and rig files


@dataclass(frozen=True)
class ImuSpec:
    """An IMU file: an optional grade's unit draw, explicit effects, withheld effect names."""

    grade: str | None
    unit_seed: int
    effects: tuple[imu.Effect, ...]
    withhold: tuple[str, ...]
    source: Path | None = None

    def model(self, run_seed: int | None = None) -> imu.ImuModel:
        """The unit's error model for one power-on (``run_seed`` draws its turn-on bias)."""
        from sins import imu
        from sins.imu import spec as imu_spec

        base = imu_spec.draw_unit(self.grade, self.unit_seed, run_seed) if self.grade else imu.ImuModel()
        return base.with_effects(*self.effects).without(*self.withhold)


def load_imu(path: str | os.PathLike[str]) -> ImuSpec:
    """Read an IMU file::

    grade = "tactical"          # optional: consumer | industrial | tactical | navigation
    unit_seed = 1               # which unit of the grade
    withhold = ["gyro.noise"]   # optional: effects switched off
    [[effect]]                  # explicit effects, in familiar units (`sins effects`)
    name = "gyro.scale_nonlinearity"
    k2_ppm_per_dps = [50, 50, 50]
    """
    from sins import imu
    from sins.imu import spec as imu_spec

    path = Path(path)
    top = TomlKeys(str(path), "", read_toml(path, "IMU"))
    grade = top.string("grade", None, tuple(imu_spec.GRADES)) if top.has("grade") else None
    unit_seed = int(top.number("unit_seed", 0, low=0))
    withhold = tuple(top.strings("withhold", [], imu.EFFECT_NAMES))
    effects = []
    for table in top.tables("effect"):
        name = table.string("name", choices=imu.EFFECT_NAMES)
        params = {k: table.get(k) for k in table.table if k != "name"}
        try:
            effects.append(imu_spec.effect_from_params(name, params))
        except (ValueError, TypeError) as exc:
            raise table.error(str(exc)) from None
    top.done()
    if grade is None and not effects:
        raise top.error("give a grade, [[effect]] tables, or both")
    return ImuSpec(grade=grade, unit_seed=unit_seed, effects=tuple(effects), withhold=withhold, source=path)


def load_rig(path: str | os.PathLike[str]) -> calibration.RigProcedure:
    """Read a rig file (``[rig]``, ``[positions]``, ``[rate_table]``, ``[temperature]``; see scenarios/)."""
    from sins.imu import calibration

    path = Path(path)
    top = TomlKeys(str(path), "", read_toml(path, "rig"))
    rig = top.sub("rig")
    kwargs: dict[str, Any] = dict(
        lat_deg=rig.number("lat_deg", 45.0, low=-89.9, high=89.9),
        lon_deg=rig.number("lon_deg", 0.0, low=-180.0, high=360.0),
        alt_m=rig.number("alt_m", 0.0, low=-1000.0, high=10000.0),
        rate_hz=rig.number("rate_hz", 100.0, low=1.0, high=100000.0),
        orientation_error_deg=rig.number("orientation_error_deg", 0.0, low=0.0, high=10.0),
        rate_error_ppm=rig.number("rate_error_ppm", 0.0, low=0.0, high=1e5),
    )
    rig.done()
    positions = top.sub("positions")
    count = positions.number("count", 0)
    if count not in calibration.POSITION_COUNTS:
        raise positions.error(
            f"must be one of {', '.join(map(str, calibration.POSITION_COUNTS))}, got {count:g}", "count"
        )
    kwargs["positions"] = int(count)
    kwargs["position_dwell_s"] = positions.number("dwell_s", 20.0, low=0.0, low_open=True)
    positions.done()
    if top.has("rate_table"):
        table = top.sub("rate_table")
        rates = table.numbers("rates_dps")
        if any(r <= 0 for r in rates):
            raise table.error("rates are magnitudes (both signs are run): give positive values", "rates_dps")
        kwargs["rate_table"] = calibration.RateTable(
            rates_dps=tuple(rates),
            axes=tuple(table.strings("axes", ["x", "y", "z"], ("x", "y", "z"))),
            orientations=tuple(table.strings("orientations", ["up", "down"], ("up", "down"))),
            dwell_s=table.number("dwell_s", 10.0, low=0.0, low_open=True),
            accel_dps2=table.number("accel_dps2", 100.0, low=0.0, low_open=True),
        )
        table.done()
    else:
        kwargs["rate_table"] = None
    if top.has("temperature"):
        temp = top.sub("temperature")
        times, temps = temp.numbers("times_s"), temp.numbers("temps_degc")
        if len(times) != len(temps):
            raise temp.error(f"times_s has {len(times)} values, temps_degc {len(temps)}")
        if any(b <= a for a, b in itertools.pairwise(times)):
            raise temp.error("must increase", "times_s")
        kwargs["temperature"] = calibration.TemperatureProfile(tuple(times), tuple(temps))
        temp.done()
    top.done()
    try:
        return calibration.RigProcedure(**kwargs)
    except ValueError as exc:
        raise SinsInputError(f"{path}: {exc}") from None
