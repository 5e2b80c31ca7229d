"""``sins run --json`` of the short presets as recorded, and the machine they were recorded on.

Used by ``tests/test_scenario.py`` (the runs equal these to the last bit) and ``tools/check_run_outputs.py
golden`` (which records them again). The figures are the last bits of floating-point sums, so they hold
only where the arithmetic is the same: numpy's, numba's and scipy's versions, the SIMD paths numpy takes
on this CPU, and OpenBLAS's kernel (``OPENBLAS_CORETYPE``: ``make test`` pins none, and the aided
preset's attitude errors move in their last bits between OpenBLAS's Haswell and SkylakeX kernels).
:func:`platform` is that fingerprint. Recorded unpinned, after the run engine's refactoring had been
checked equal to the code before it with the kernels pinned (commit 87c81cd's records).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numba
import numpy as np
import scipy

#: The folder of the recorded documents and their ``platform.json``.
FOLDER = Path(__file__).resolve().parent / "run_outputs"

#: The presets recorded: the short ones (seconds each), the ideal IMU's and an aided one's paths.
SHORT_PRESETS = ("car_drive_5min", "survey_waypoints", "car_drive_aided_10min")


def platform() -> dict[str, Any]:
    """What the recorded bits depend on, here and now."""
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    return {
        "numpy": np.__version__,
        "numba": numba.__version__,
        "scipy": scipy.__version__,
        "numpy_simd": sorted(f for f in __cpu_dispatch__ if __cpu_features__.get(f)),
        "OPENBLAS_CORETYPE": os.environ.get("OPENBLAS_CORETYPE", ""),
    }


def normalised(document: dict[str, Any]) -> dict[str, Any]:
    """A ``sins run --json`` document with the scenario's file named by its name alone (checkouts differ)."""
    out = json.loads(json.dumps(document))
    out["scenario"]["file"] = Path(out["scenario"]["file"]).name
    return out


def write(folder: Path, documents: dict[str, dict[str, Any]]) -> None:
    """Record ``{preset: document}`` and :func:`platform` in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, document in documents.items():
        (folder / f"{name}.json").write_text(json.dumps(normalised(document), indent=2) + "\n")
    (folder / "platform.json").write_text(json.dumps(platform(), indent=2) + "\n")
