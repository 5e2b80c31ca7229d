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
    """A ``sins run --json`` document with the scenario's file named by its name alone (checkouts differ)
    and without the version of the sins that wrote it (its first key, ``"sins"``: a release's, not a
    result)."""
    out = json.loads(json.dumps(document))
    out.pop("sins", None)
    out["scenario"]["file"] = Path(out["scenario"]["file"]).name
    return out


#: How far a recorded number may move on another machine's arithmetic: relative, and absolute near zero.
#: Rounding in the last bits of a sum over a run (1e-16 relative a step, 60,000 steps, a filter's
#: gains amplifying it by at most a few hundred) stays below 1e-9; a change of code moves results by
#: 1e-6 and more.
RELATIVE, ABSOLUTE = 1e-9, 1e-12


def differences(got: Any, want: Any, where: str = "") -> list[str]:
    """Where ``got`` differs from ``want``: numbers beyond :data:`RELATIVE` (or :data:`ABSOLUTE`), other
    values or shapes at all; one line each, naming the field."""
    if isinstance(want, dict) and isinstance(got, dict):
        odd = [f"{where}: keys {sorted(set(got) ^ set(want))} differ"] if set(got) != set(want) else []
        return odd + [d for k in want if k in got for d in differences(got[k], want[k], f"{where}.{k}")]
    if isinstance(want, list) and isinstance(got, list):
        if len(got) != len(want):
            return [f"{where}: {len(got)} items, recorded {len(want)}"]
        return [
            d
            for i, (g, w) in enumerate(zip(got, want, strict=True))
            for d in differences(g, w, f"{where}[{i}]")
        ]
    numbers = (int, float)
    if isinstance(want, numbers) and isinstance(got, numbers) and not isinstance(want, bool):
        if abs(got - want) <= max(RELATIVE * abs(want), ABSOLUTE):
            return []
        return [f"{where}: {got!r}, recorded {want!r}"]
    return [] if got == want else [f"{where}: {got!r}, recorded {want!r}"]


def write(folder: Path, documents: dict[str, dict[str, Any]]) -> None:
    """Record ``{preset: document}`` and :func:`platform` in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, document in documents.items():
        (folder / f"{name}.json").write_text(json.dumps(normalised(document), indent=2) + "\n")
    (folder / "platform.json").write_text(json.dumps(platform(), indent=2) + "\n")
