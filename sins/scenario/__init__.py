"""Scenario files (TOML) → frozen dataclasses → a motion; and the IMU and rig files they name.

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

One module per job, each importing only those above it in this list:
:mod:`~sins.scenario.toml` (typed TOML tables, one-line errors), :mod:`~sins.scenario.presets` (the
shipped presets by name), :mod:`~sins.scenario.schema` (the dataclasses),
:mod:`~sins.scenario.validate` (scenario files), :mod:`~sins.scenario.build` (the motion) and
:mod:`~sins.scenario.files` (IMU and rig files). Every name is importable from ``sins.scenario``.
"""

from sins.nav.vertical import VERTICAL_MODES
from sins.scenario.build import (
    MAX_LAT_DEG,
    build_motion,
    check_latitude,
    idle_outages,
    sample_count,
    unsampled_end,
)
from sins.scenario.files import RIG_BOUNDS, load_imu, load_rig, rig_rows
from sins.scenario.presets import PresetKind, find_preset, preset_dir, preset_or_path, presets, resolve_preset
from sins.scenario.schema import (
    AidingSpec,
    CompensationSpec,
    ImuSpec,
    Scenario,
    SegmentsSpec,
    TruthFileSpec,
    WaypointsSpec,
)
from sins.scenario.toml import Bound, TomlKeys, read_toml
from sins.scenario.validate import (
    DEFAULT_RAMP_S,
    MAX_DURATION_S,
    MIN_RAMP_S,
    SCENARIO_BOUNDS,
    SEGMENT_TYPES,
    from_dict,
    load,
)

__all__ = [
    "DEFAULT_RAMP_S",
    "MAX_DURATION_S",
    "MAX_LAT_DEG",
    "MIN_RAMP_S",
    "RIG_BOUNDS",
    "SCENARIO_BOUNDS",
    "SEGMENT_TYPES",
    "VERTICAL_MODES",
    "AidingSpec",
    "Bound",
    "CompensationSpec",
    "ImuSpec",
    "PresetKind",
    "Scenario",
    "SegmentsSpec",
    "TomlKeys",
    "TruthFileSpec",
    "WaypointsSpec",
    "build_motion",
    "check_latitude",
    "find_preset",
    "from_dict",
    "idle_outages",
    "load",
    "load_imu",
    "load_rig",
    "preset_dir",
    "preset_or_path",
    "presets",
    "read_toml",
    "resolve_preset",
    "rig_rows",
    "sample_count",
    "unsampled_end",
]
