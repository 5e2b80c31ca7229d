"""The EuRoC protocol's commands, unchanged, on a unit whose readings come calibrated: EuRoC's
ADIS16448 with each sequence's own constant gyro bias taken out.

Usage::

    .venv/bin/python tools/calibrated_unit.py [--strategies regression bias_only ...] [--train NAME ...]
        [--judge NAME ...] [--json OUT.json] [--keep DIR]

Some units are read already calibrated: their maker or the dataset's converter takes the bias out at
every power-up (a phone's operating system, a dataset's "calibrated" readings). A model fitted on a few
of their recordings has little left to correct and adds its own errors. Each of EuRoC's eleven sequences is
written in the ``.npz`` form into a temporary data root (folder ``euroc_calibrated``), its gyro less the
mean over the sequence of the gyro less the reference's rate (each step's turn by scipy's ``Rotation``;
numpy and scipy alone, nothing of sins), and the published split is fitted and judged by
``tools/euroc_benchmark.py``'s commands. Prints the open-loop table; what must hold is that no correction
is worse than the raw readings.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parent))

import euroc_benchmark


def own_bias(rec: dict[str, np.ndarray]) -> np.ndarray:
    """A ``.npz`` recording's (its arrays by key) own constant gyro bias, rad/s (3,): the mean over its steps
    of the gyro (the step's mean) less the reference's rate (each step's turn by scipy's ``Rotation``)."""
    w = rec["gyro_rad_s"].astype(float)
    ref = Rotation.from_quat(rec["q_wxyz"].astype(float), scalar_first=True)
    rate = (ref[:-1].inv() * ref[1:]).as_rotvec() / np.diff(rec["t_s"])[:, None]
    return np.asarray(np.mean(0.5 * (w[:-1] + w[1:]) - rate, axis=0), dtype=float)


def calibrated(source: Path, folder: Path) -> np.ndarray:
    """The ``.npz`` recording ``source`` written into ``folder`` under its name with its own constant gyro
    bias taken out (the module docstring); returns that bias, rad/s (3,)."""
    with np.load(source) as z:
        a = {k: np.asarray(z[k]) for k in z.files}
    bias = own_bias(a)
    w = a["gyro_rad_s"].astype(float)
    np.savez(folder / source.name, **{**a, "gyro_rad_s": (w - bias).astype(a["gyro_rad_s"].dtype)})
    return bias


def main(argv: list[str] | None = None) -> int:
    return euroc_benchmark.run_on_euroc_as(
        argv, __doc__.split("\n\n")[0], "euroc_calibrated", calibrated, euroc_benchmark.STRATEGIES
    )


if __name__ == "__main__":
    sys.exit(main())
