"""IMU and rig files read and checked: an :class:`~sins.scenario.schema.ImuSpec`, a rig procedure.

Scenario files name them (``[imu] model``, ``[compensation] rig``), and so do ``sins calibrate`` and
``sins gap --model``. The IMU model and the calibration rig are imported when a file is read: ``sins run``
of a scenario without an IMU needs neither.
"""

from __future__ import annotations

import itertools
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.core.earth import MAX_LAT_DEG
from sins.errors import SinsInputError
from sins.scenario.schema import ImuSpec
from sins.scenario.toml import MAX_SEED, Bound, TomlKeys, read_toml
from sins.scenario.validate import MAX_DURATION_S

#: A dwell spans at least this many samples: a phase needs two rows to be split into fit and held-back
#: parts (a dwell shorter than half a sample would have no rows at all).
MIN_DWELL_SAMPLES = 2

#: Static bounds of every numeric rig-file field, by its place. A dwell is also at least
#: :data:`MIN_DWELL_SAMPLES` samples; ``positions.count`` is one of the counts the rig knows.
RIG_BOUNDS: dict[str, Bound] = {
    "rig.lat_deg": Bound(-MAX_LAT_DEG, MAX_LAT_DEG, "°", "the local level frame is singular at a pole"),
    "rig.lon_deg": Bound(-180.0, 360.0, "°"),
    "rig.alt_m": Bound(-1000.0, 10000.0, "m"),
    "rig.rate_hz": Bound(1.0, 100000.0, "Hz"),
    "rig.orientation_error_deg": Bound(0.0, 10.0, "°", "1σ of each position"),
    "rig.rate_error_ppm": Bound(0.0, 1e5, "ppm", "1σ of the table's rate scale"),
    "positions.dwell_s": Bound(0.0, 1e6, "s", low_open=True),
    "rate_table.rates_dps": Bound(1e-3, 1e4, "°/s", "magnitudes: both signs are run"),
    "rate_table.dwell_s": Bound(0.0, 1e6, "s", low_open=True),
    "rate_table.accel_dps2": Bound(1.0, 1e6, "°/s²", "a slower table would ramp for hours"),
    "temperature.times_s": Bound(-MAX_DURATION_S, MAX_DURATION_S, "s"),
    "temperature.temps_degc": Bound(-100.0, 200.0, "°C", "an IMU's operating range, with margin"),
}

if TYPE_CHECKING:
    from sins.imu import calibration


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
    unit_seed = top.integer("unit_seed", 0, high=MAX_SEED)
    withhold = tuple(top.strings("withhold", [], imu.effect_names()))
    effects: list[imu.Effect] = []
    for table in top.tables("effect"):
        name = table.string("name", choices=imu.effect_names())
        if any(e.name == name for e in effects):  # one effect, one table: the model would refuse it later
            raise table.error(
                f"{name} is given by an earlier [[effect]] table too (one table an effect)", "name"
            )
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
    kwargs: dict[str, Any] = {
        key: rig.bounded(key, RIG_BOUNDS[f"rig.{key}"], default)
        for key, default in (("lat_deg", 45.0), ("lon_deg", 0.0), ("alt_m", 0.0), ("rate_hz", 100.0),
                             ("orientation_error_deg", 0.0), ("rate_error_ppm", 0.0))
    }  # fmt: skip
    rig.done()
    kwargs["h_m"] = kwargs.pop("alt_m")  # the file's key; the package's name of a height (glossary)
    rate_hz = kwargs["rate_hz"]
    positions = top.sub("positions")
    count = positions.number("count", 0)
    if count not in calibration.POSITION_COUNTS:
        raise positions.error(
            f"must be one of {', '.join(map(str, calibration.POSITION_COUNTS))}, got {count:g}", "count"
        )
    kwargs["positions"] = int(count)
    kwargs["position_dwell_s"] = _dwell(positions, "positions", 20.0, rate_hz)
    positions.done()
    if top.has("rate_table"):
        table = top.sub("rate_table")
        rates = table.bounded_numbers("rates_dps", RIG_BOUNDS["rate_table.rates_dps"])
        kwargs["rate_table"] = calibration.RateTable(
            rates_dps=tuple(rates),
            axes=tuple(table.strings("axes", ["x", "y", "z"], ("x", "y", "z"))),
            orientations=tuple(table.strings("orientations", ["up", "down"], ("up", "down"))),
            dwell_s=_dwell(table, "rate_table", 10.0, rate_hz),
            accel_dps2=table.bounded("accel_dps2", RIG_BOUNDS["rate_table.accel_dps2"], 100.0),
        )
        table.done()
    else:
        kwargs["rate_table"] = None
    if top.has("temperature"):
        temp = top.sub("temperature")
        times = temp.bounded_numbers("times_s", RIG_BOUNDS["temperature.times_s"])
        temps = temp.bounded_numbers("temps_degc", RIG_BOUNDS["temperature.temps_degc"])
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


def _dwell(keys: TomlKeys, table: str, default: float, rate_hz: float) -> float:
    """A dwell within its bound and at least :data:`MIN_DWELL_SAMPLES` samples at ``rate_hz``."""
    dwell = keys.bounded("dwell_s", RIG_BOUNDS[f"{table}.dwell_s"], default)
    if dwell * rate_hz < MIN_DWELL_SAMPLES:
        raise keys.error(
            f"must be at least {MIN_DWELL_SAMPLES} samples ({MIN_DWELL_SAMPLES / rate_hz:g} s at "
            f"{rate_hz:g} Hz) "
            f"so that the phase has rows to fit and to hold back, got {dwell:g}",
            "dwell_s",
        )
    return dwell


def rig_rows(rig: calibration.RigProcedure) -> int:
    """The rows a session of ``rig`` has (what :func:`~sins.imu.calibration.simulate_rig` makes), without
    simulating it: each position's dwell, then per mounted axis and orientation a table run that ramps
    at ``accel_dps2`` to each rate of both signs, dwells, and ramps back to rest."""
    rows = rig.positions * round(rig.position_dwell_s * rig.rate_hz)
    rt = rig.rate_table
    if rt is not None:
        rates = [s * r for r in rt.rates_dps for s in (1.0, -1.0)]
        steps = [abs(b - a) for a, b in itertools.pairwise([0.0, *rates, 0.0])]
        duration = sum(steps) / rt.accel_dps2 + rt.dwell_s * len(rates)
        rows += len(rt.axes) * len(rt.orientations) * round(duration * rig.rate_hz)
    return rows


__all__ = [
    "MIN_DWELL_SAMPLES",
    "RIG_BOUNDS",
    "load_imu",
    "load_rig",
    "rig_rows",
]
