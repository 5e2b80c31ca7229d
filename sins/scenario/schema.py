"""The validated forms of scenario, IMU and rig files: frozen dataclasses in SI units.

:mod:`~sins.scenario.validate` and :mod:`~sins.scenario.files` make them from files; nothing here reads
a file or checks a value.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from sins.nav import motion
from sins.nav.vertical import VerticalMode

if TYPE_CHECKING:  # ImuSpec.model imports these when called: `sins run` without an IMU needs neither
    from sins import imu


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
    vertical: VerticalMode = "free"
    vertical_tau_s: float = 10.0
    imu_model: Path | None = None
    imu_seed: int = 0
    compensation: CompensationSpec | None = None
    temperature: tuple[tuple[float, ...], tuple[float, ...]] = ((0.0,), (20.0,))  # (times_s, temps_degc)
    aiding: AidingSpec | None = None


@dataclass(frozen=True)
class AidingSpec:
    """A scenario's GNSS receiver, outages and alignment (``[gnss]``, ``[[outage]]``, ``[alignment]``), SI.

    ``static_s`` None: the filter starts from the truth's first state; otherwise from a static alignment
    over the first ``static_s`` seconds (``heading_sigma_rad`` set: the heading comes from elsewhere,
    the truth's plus a draw of that spread, instead of gyrocompassing).
    """

    rate_hz: float
    sigma_m: tuple[float, float, float]
    markov_sigma_m: tuple[float, float, float]
    markov_tau_s: float
    sigma_vel_mps: float | None
    lever_arm_m: tuple[float, float, float]
    latency_s: float
    seed: int
    filter_grade: str | None
    outages: tuple[tuple[float, float], ...]
    static_s: float | None = None
    coarse_s: float = 60.0
    heading_sigma_rad: float | None = None


@dataclass(frozen=True)
class CompensationSpec:
    """How a scenario's strategies are fitted: the rig session, its held-back fraction, the strategies."""

    rig: Path
    validation: float
    seed: int
    strategies: tuple[str, ...]


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
