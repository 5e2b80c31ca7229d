"""What a run will hold: a scenario's or a rig session's memory and disk, refused up front when too big.

The per-sample figures are what the commands hold whole, with a margin over what was measured
(``docs/speed.md``); the run itself streams in chunks.
"""

from __future__ import annotations

from pathlib import Path

from sins.imu.calibration import RigProcedure
from sins.io import limits
from sins.scenario.build import sample_count
from sins.scenario.files import load_rig, rig_rows
from sins.scenario.schema import Scenario

#: Bytes a sample: ``sins simulate``'s truth and increments, ``sins run``'s sample times and what it keeps
#: of each (16 measured: a 100 kHz turn's peak grew 234 MB from 150 s to 300 s; it had been taken as the
#: times' 8 alone, half of it), a rig session's readings and references.
SIMULATE_BYTES, RUN_BYTES, RIG_BYTES = 600, 20, 600
#: ... and an aided run's (``[gnss]``): truth, readings, the filter's solution and records held whole.
AIDED_BYTES = 1000


def check_scenario_size(sc: Scenario, path: Path, what: str, outputs: dict[Path, int] | None = None) -> None:
    """Refuse up front a scenario whose arrays would not fit in memory, or whose CSVs (``{path:
    columns}``) would not fit on their disks; the message gives the size it would need.

    Raises
    ------
    SinsInputError
        naming ``path`` and the size needed.
    """
    n = sample_count(sc)
    per_sample = SIMULATE_BYTES if outputs else RUN_BYTES
    if sc.aiding is not None:
        per_sample = max(per_sample, AIDED_BYTES)
    span = f"{n:.4g} samples ({n / sc.rate_hz:.4g} s at {sc.rate_hz:g} Hz)"
    if outputs:
        limits.check_disk({p: limits.csv_bytes(n + 1, columns) for p, columns in outputs.items()}, path)
    limits.check_memory(n * per_sample, f"{what} {span}", path)
    if sc.compensation is not None:
        check_rig_size(load_rig(sc.compensation.rig), sc.compensation.rig)


def check_rig_size(rig: RigProcedure, path: Path, outputs: dict[Path, int] | None = None) -> None:
    """:func:`check_scenario_size` for a rig session."""
    rows = rig_rows(rig)
    if outputs:
        limits.check_disk({p: limits.csv_bytes(rows, columns) for p, columns in outputs.items()}, path)
    limits.check_memory(rows * RIG_BYTES, f"a rig session of {rows:.4g} rows at {rig.rate_hz:g} Hz", path)


__all__ = [
    "AIDED_BYTES",
    "RIG_BYTES",
    "RUN_BYTES",
    "SIMULATE_BYTES",
    "check_rig_size",
    "check_scenario_size",
]
