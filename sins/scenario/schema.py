"""The validated forms of scenario, IMU and rig files: frozen dataclasses in SI units.

:mod:`~sins.scenario.validate` and :mod:`~sins.scenario.files` make them from files; nothing here reads
a file or checks a value.
"""

from __future__ import annotations

import math
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

    ``alignment`` says how the filter starts: ``"static"`` a static alignment over the first ``static_s``
    seconds (``heading_sigma_rad`` set: the heading comes from elsewhere, the truth's plus a draw of that
    spread, instead of gyrocompassing); ``"gnss_velocity"`` in motion, heading from the course over
    ground once the speed reaches ``min_speed_mps`` (``sideslip_sigma_rad`` the angle between them);
    ``"truth"`` the truth's first state; ``"auto"`` (no ``[alignment]``) static where the trajectory
    starts with a long enough stop (``static_s``, None: any of 30 s or more) and the gyros can find
    north, in motion otherwise. ``compensate_latency``: the filter is told ``latency_s``.
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
    alignment: str = "auto"
    min_speed_mps: float = 5.0
    sideslip_sigma_rad: float = math.radians(1.0)
    compensate_latency: bool = True


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

    def digest(self) -> str:
        """The unit by its content, 8 hex digits of a SHA-256 over its grade, unit seed, effects (each
        parameter's float64 bytes) and withheld names: not its file's name or comments. Two files that
        name one unit alike but hold others (another bias, the same name) are two units; what a
        simulated recording's ``sensor`` line says (:func:`sins.cli.common.simulated_unit`)."""
        import dataclasses
        import hashlib

        import numpy as np

        h = hashlib.sha256(repr((self.grade, self.unit_seed, sorted(self.withhold))).encode())
        for effect in self.effects:
            h.update(type(effect).__name__.encode())
            for f in dataclasses.fields(effect):
                value = getattr(effect, f.name)
                try:  # numbers and arrays by their exact bytes; a name, a choice by its text
                    said = np.asarray(value, dtype=float).tobytes()
                except (TypeError, ValueError):
                    said = repr(value).encode()
                h.update(f.name.encode() + said)
        return h.hexdigest()[:8]

    def model(self, run_seed: int | None = None) -> imu.ImuModel:
        """The unit's error model for one power-on (``run_seed`` draws its turn-on bias)."""
        from sins import imu
        from sins.imu import spec as imu_spec

        base = imu_spec.draw_unit(self.grade, self.unit_seed, run_seed) if self.grade else imu.ImuModel()
        return base.with_effects(*self.effects).without(*self.withhold)


__all__ = [
    "AidingSpec",
    "CompensationSpec",
    "ImuSpec",
    "Scenario",
    "SegmentsSpec",
    "TruthFileSpec",
    "WaypointsSpec",
]
