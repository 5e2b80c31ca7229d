"""Campaign files (TOML): which units, which rig and strategies, which scenarios.

A campaign draws ``count`` units of one IMU file (a grade's units differ by ``unit_seed``), fits
every strategy on each unit's rig session and drives each unit through every scenario::

    name = "tactical_drives"
    [units]
    imu = "tactical"          # IMU file or preset; each unit replaces its unit_seed
    count = 40
    first_seed = 1            # unit k (0, 1, ...) has unit_seed first_seed + k
    [compensation]
    rig = "24pos_ratetable"   # rig file or preset
    validation = 0.3          # the last fraction of each rig phase held back to judge the fit
    strategies = ["none", "regression", "mlp"]
    [[scenario]]
    file = "car_drive"        # scenario file or preset: its motion, rate, vertical channel, cabin
    [keep]
    series_hz = 0.2           # each row's thinned horizontal error series (0: none)

Each unit has two power-ons, as a real one would: the rig session (:func:`rig_seed`) and the
navigation runs (:func:`nav_seed`). A row's seeds are written beside it, so ``sins run`` on a
scenario with ``[imu] model`` (that IMU file with the row's ``unit_seed``), ``[imu] seed`` =
``nav_seed`` and ``[compensation] seed`` = ``rig_seed`` reproduces it to the last digit.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sins import scenario
from sins.errors import SinsInputError
from sins.io.documents import printable
from sins.scenario import CompensationSpec, ImuSpec, Scenario
from sins.scenario.budget import check_rig_size, check_scenario_size
from sins.scenario.toml import Bound, TomlKeys, read_toml

#: The most units a campaign may draw (a million unit-runs is a cluster's week, not a typo's).
MAX_UNITS = 1_000_000
#: The most scenarios one campaign drives each unit through.
MAX_SCENARIOS = 100
_SERIES_HZ = Bound(0.0, 10.0, "Hz", "the thinned error series kept per row")
#: The slowest series kept, Hz, but for 0 (none): below it a sample's spacing overflows the counts
#: that thin a run (``1e-300`` failed in a worker with an ``IndexError``).
MIN_SERIES_HZ = 1e-6
_VALIDATION = Bound(0.0, 0.9, "", "a fraction of each rig phase", low_open=True)
#: Every strategy a campaign runs unless it says otherwise.
DEFAULT_STRATEGIES = ("none", "regression")


def rig_seed(unit_seed: int) -> int:
    """The power-on seed of a unit's rig session: ``2 · unit_seed``."""
    return 2 * unit_seed


def nav_seed(unit_seed: int) -> int:
    """The power-on seed of a unit's navigation runs: ``2 · unit_seed + 1`` (never the rig's)."""
    return 2 * unit_seed + 1


@dataclass(frozen=True)
class CampaignSpec:
    """A campaign file, validated; paths resolved."""

    name: str
    source: Path
    imu: ImuSpec
    count: int
    first_seed: int
    compensation: CompensationSpec
    scenarios: tuple[Scenario, ...]
    series_hz: float

    def unit_seed(self, unit: int) -> int:
        """The ``unit_seed`` of unit ``unit`` (0-based)."""
        return self.first_seed + unit

    def unit_imu(self, unit: int) -> ImuSpec:
        """Unit ``unit``'s IMU: the campaign's file with the unit's ``unit_seed``."""
        return dataclasses.replace(self.imu, unit_seed=self.unit_seed(unit))

    def unit_compensation(self, unit: int) -> CompensationSpec:
        """The compensation table with the unit's rig power-on seed."""
        return dataclasses.replace(self.compensation, seed=rig_seed(self.unit_seed(unit)))


def load(path: str | os.PathLike[str]) -> CampaignSpec:
    """Read and validate a campaign file; every file it uses is read, and every scenario checked as
    ``sins run`` checks it before any work, now, before any cluster starts (:func:`check`).

    Raises
    ------
    SinsInputError
        one line naming the campaign file and the key: an unknown key, zero units, an unknown strategy,
        a scenario, IMU or rig file that does not exist or does not validate (its own message within),
        a scenario its units could not drive.
    """
    from sins.compensation import VARIANTS

    path = Path(path)
    top = TomlKeys(str(path), "", read_toml(path, "campaign"))
    base = path.parent
    name = _name(top, path)
    units = top.sub("units")
    imu = _read(units, "imu", scenario.load_imu, scenario.preset_or_path(units, "imu", "imu", base))
    count = units.integer("count", 0, low=1, high=MAX_UNITS)
    if not units.has("count"):
        raise units.error("is required: how many units to draw", "count")
    first_seed = units.integer("first_seed", 0, high=2**62 - MAX_UNITS)
    units.done()
    comp = top.sub("compensation")
    strategies = comp.strings("strategies", list(DEFAULT_STRATEGIES), tuple(VARIANTS))
    rig = scenario.preset_or_path(comp, "rig", "rig", base)
    procedure = _read(comp, "rig", scenario.load_rig, rig)  # a bad rig file now, not in every task
    compensation = CompensationSpec(
        rig=rig,
        validation=comp.bounded("validation", _VALIDATION, 0.3),
        seed=0,  # each unit's own (rig_seed)
        strategies=tuple(dict.fromkeys(["oracle", *strategies])),
    )
    comp.done()
    scenarios = _scenarios(top, base)
    series_hz = _series_hz(top)
    top.done()
    spec = CampaignSpec(name, path, imu, count, first_seed, compensation, scenarios, series_hz)
    check_rig_size(procedure, rig)
    for i, sc in enumerate(scenarios, start=1):
        _read(TomlKeys(str(path), f"scenario[{i}]", {}), "file", lambda s: check(s, imu.grade), sc)
    return spec


def check(sc: Scenario, grade: str | None) -> None:
    """What ``sins run`` refuses of a scenario before any work, for a unit of ``grade``: its memory
    (aided runs hold their arrays whole), a motion shorter than a sample, an alignment the trajectory
    cannot give (:func:`sins.runs.pipeline.check_runnable`)."""
    from sins.runs import pipeline

    assert sc.source is not None
    check_scenario_size(sc, sc.source, "a unit driving")
    pipeline.check_runnable(sc, grade)


def _read(table: TomlKeys, key: str, reader: Callable[[Any], Any], value: Any) -> Any:
    """``reader(value)``, its one-line refusal prefixed with the campaign file and ``key``."""
    try:
        return reader(value)
    except SinsInputError as exc:
        raise table.error(f"{exc}", key) from None


def _name(top: TomlKeys, path: Path) -> str:
    """The campaign's name (default: the file's stem), which names its default results folder."""
    name = top.string("name", default=path.stem)
    if not name or not name.isprintable() or any(c in name for c in "/\\") or name in (".", ".."):
        raise top.error(
            f"{printable(name)!r} cannot name a folder ({printable(name) or 'empty'}-campaign, the default "
            "results folder): no slashes, no control characters", "name"
        )  # fmt: skip
    return name


def _scenarios(top: TomlKeys, base: Path) -> tuple[Scenario, ...]:
    scenarios = tuple(_scenario(table, base) for table in top.tables("scenario"))
    if not scenarios:
        raise top.error("needs at least one [[scenario]] table", "scenario")
    if len(scenarios) > MAX_SCENARIOS:
        raise top.error(f"has {len(scenarios)} scenarios, more than {MAX_SCENARIOS}", "scenario")
    names = [s.name for s in scenarios]
    if len(set(names)) != len(names):
        raise top.error(
            f"two scenarios share a name ({', '.join(names)}): rows would be ambiguous", "scenario"
        )
    return scenarios


def _series_hz(top: TomlKeys) -> float:
    """``[keep] series_hz``: 0 (no series) or from :data:`MIN_SERIES_HZ` up."""
    if not top.has("keep"):
        return 0.2
    keep = top.sub("keep")
    series_hz = keep.bounded("series_hz", _SERIES_HZ, 0.2)
    if 0.0 < series_hz < MIN_SERIES_HZ:
        days = 1 / MIN_SERIES_HZ / 86400
        raise keep.error(
            f"must be 0 (no series) or at least {MIN_SERIES_HZ:g} Hz (a sample in {days:.3g} days), "
            f"got {series_hz:g}", "series_hz"
        )  # fmt: skip
    keep.done()
    return series_hz


def is_campaign(path: str | os.PathLike[str]) -> bool:
    """Whether the TOML file at ``path`` is a campaign (it has a ``[units]`` table); False if unreadable."""
    try:
        return "units" in read_toml(Path(path), "campaign")
    except SinsInputError:
        return False


def _scenario(table: TomlKeys, base: Path) -> Scenario:
    """One ``[[scenario]]``: the file's motion, rate, vertical channel and cabin temperature."""
    path = scenario.preset_or_path(table, "file", "", base)
    table.done()
    try:
        sc = scenario.load(path)
    except SinsInputError as exc:
        raise table.error(f"{exc}", "file") from None
    # The campaign's unit and compensation replace the file's own: the pipeline is handed each fitted
    # unit directly (pipeline.run_scenario's ``unit``).
    return dataclasses.replace(sc, imu_model=None, compensation=None)


def describe(spec: CampaignSpec) -> dict[str, Any]:
    """What the campaign runs, for the results' metadata."""
    return {
        "name": spec.name,
        "source": str(spec.source),
        "imu": str(spec.imu.source),
        "units": spec.count,
        "first_seed": spec.first_seed,
        "rig": str(spec.compensation.rig),
        "validation": spec.compensation.validation,
        "strategies": list(spec.compensation.strategies),
        "scenarios": [s.name for s in spec.scenarios],
        "series_hz": spec.series_hz,
    }


__all__ = [
    "DEFAULT_STRATEGIES",
    "MAX_SCENARIOS",
    "MAX_UNITS",
    "MIN_SERIES_HZ",
    "CampaignSpec",
    "check",
    "describe",
    "is_campaign",
    "load",
    "nav_seed",
    "rig_seed",
]
