"""The EuRoC protocol's commands, unchanged, on a unit sins did not make, whose recordings are each a new
power-up: a numpy MEMS unit.

Usage::

    .venv/bin/python tools/numpy_unit.py [--grade mems|good] [--strategies regression mlp ...]
        [--json OUT.json] [--keep DIR] [--seed 11]

Six recordings of one unit (``tests/numpy_referenced.py``: numpy and scipy's ``Rotation`` only; 120 s at
100 Hz, turned up to 80° about every axis, a reference at every reading), its scale factors,
misalignments and noise shared, its gyro and accelerometer biases drawn anew for each recording (``mems``:
0.1 °/s and 0.05 m/s², the unit's other errors 0.3 %; ``good``: 2e-5 rad/s and 2 mg, 1e-4), written in
the ``.npz`` form of ``shared/data/euroc`` into a temporary data root (folder ``numpy_unit``). The models
are fitted on ``r0 r1 r2`` and judged on ``r3 r4 r5`` by ``tools/euroc_benchmark.py``'s commands. What
must hold: no correction worse than the raw readings on any judged recording.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "tests"))

import euroc_benchmark  # noqa: E402
from numpy_referenced import HEIGHT_M, LAT_DEG, session, typical_unit  # noqa: E402
from numpy_units import write_npz  # noqa: E402

from sins.compensation import judging  # noqa: E402
from sins.core.series import ImuRates, NavSeries  # noqa: E402


def write_unit(folder: Path, grade: str, seed: int, count: int = 6) -> None:
    """``count`` recordings of one numpy unit of ``grade`` written as ``folder/r{k}.npz``."""
    rng = np.random.default_rng(seed)
    unit = typical_unit(rng)
    gyro_sd, accel_sd = np.radians(0.1), 0.05
    if grade == "good":
        unit = replace(
            unit, B=rng.normal(0.0, 1e-4, (3, 3)), A=rng.normal(0.0, 1e-4, (3, 3)), gyro_delay_s=0.0,
            accel_delay_s=0.0, gyro_sigma=np.radians(0.005), accel_sigma=0.002,
        )  # fmt: skip
        gyro_sd, accel_sd = 2e-5, 0.002
    for k in range(count):
        own = replace(unit, B0=rng.normal(0.0, gyro_sd, 3), A0=rng.normal(0.0, accel_sd, 3))
        s = session(rng, own, duration_s=120.0, rate_hz=100.0, ref_hz=100.0, ref_noise_ratio=1.0)
        truth = NavSeries(
            t=s.t_ref, lat=np.full(len(s.t_ref), math.radians(LAT_DEG)), lon=np.zeros(len(s.t_ref)),
            h=np.full(len(s.t_ref), HEIGHT_M), v_n=s.v_n, q_nb=s.q_nb,
        )  # fmt: skip
        rec = judging.from_recording(ImuRates(t=s.t, omega_ib_b=s.gyro, f_ib_b=s.accel), truth, f"r{k}")
        write_npz(folder, f"r{k}", rec)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--grade", choices=("mems", "good"), default="mems")
    p.add_argument("--seed", type=int, default=11)
    p.add_argument("--strategies", nargs="+", default=euroc_benchmark.STRATEGIES)
    p.add_argument("--json", type=Path)
    p.add_argument("--keep", type=Path, help="write the .npz recordings here (a data root) and keep them")
    args = p.parse_args(argv)
    return euroc_benchmark.run_on_unit(
        lambda folder: write_unit(folder, args.grade, args.seed),
        "numpy_unit",
        ["r0", "r1", "r2"],
        ["r3", "r4", "r5"],
        args.strategies,
        json_out=args.json,
        keep=args.keep,
    )


if __name__ == "__main__":
    sys.exit(main())
