"""EuRoC's commands on references spoiled the way converters spoil a motion capture's poses.

Usage::

    .venv/bin/python tools/spoiled_references.py [--spoil velocity|gaps] [--screen refused|always|never]
        [--strategies regression ...] [--keep DIR]

Three of EuRoC's training sequences (MH_01_easy, MH_03_medium, V1_02_medium) are written again in the
``.npz`` form with their reference spoiled by numpy alone (``velocity``: ``v_m_s`` the positions'
differences over 5 ms, the first row zero, as a converter of TUM-VI's poses writes it; ``gaps``: that,
and three 1 s gaps in each filled as converters fill them, the attitude slerped by scipy and the position
a straight line, drawn with a fixed seed), beside three judged sequences as they are (V1_01_easy,
MH_02_easy, V2_02_medium), in one folder of a temporary data root (``spoiled``). The models are fitted
on the three and judged on the others by ``tools/euroc_benchmark.py``'s commands; ``--screen`` is handed
to ``sins fit`` (:mod:`sins.compensation.screening`). Prints the open-loop table, what ``sins fit`` says
of the references on stderr.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

sys.path.insert(0, str(Path(__file__).resolve().parent))

import euroc_benchmark

from sins.io import datasets

TRAIN = ["MH_01_easy", "MH_03_medium", "V1_02_medium"]
JUDGE = ["V1_01_easy", "MH_02_easy", "V2_02_medium"]
#: Each gap's length, steps of 5 ms (1 s), and how many in each recording.
GAP_STEPS, GAPS = 200, 3


def fill_gap(t: np.ndarray, q_wxyz: np.ndarray, lines: list[np.ndarray], a: int, b: int) -> None:
    """Rows ``a`` to ``b`` filled in place as converters fill a motion capture's gap: the attitude
    ``q_wxyz`` slerped by scipy between the two ends, each array of ``lines`` (n, 3) a straight line."""
    ends = Rotation.from_quat(q_wxyz[[a, b]], scalar_first=True)
    q_wxyz[a : b + 1] = Slerp(t[[a, b]], ends)(t[a : b + 1]).as_quat(scalar_first=True)
    for x in lines:
        for c in range(x.shape[1]):
            x[a : b + 1, c] = np.interp(t[a : b + 1], t[[a, b]], x[[a, b], c])


def spoiled(arrays: dict[str, np.ndarray], spoil: str, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """The recording's arrays with its reference spoiled (see the module docstring)."""
    t = arrays["t_s"]
    q = np.asarray(arrays["q_wxyz"], dtype=float)
    p = np.asarray(arrays["p_m"], dtype=float).copy()
    if spoil == "gaps":
        for _ in range(GAPS):
            a = int(rng.integers(2000, len(t) - 2000))
            fill_gap(t, q, [p], a, a + GAP_STEPS)
    v = np.zeros_like(p)
    v[1:] = np.diff(p, axis=0) / 0.005
    return {**arrays, "q_wxyz": q, "v_m_s": v, "p_m": p}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--spoil", choices=("velocity", "gaps"), default="velocity")
    p.add_argument("--screen", choices=("refused", "always", "never"))
    p.add_argument("--strategies", nargs="+", default=["regression"])
    p.add_argument("--keep", type=Path, help="write the .npz recordings here (a data root) and keep them")
    args = p.parse_args(argv)
    source = datasets.data_root() / "euroc"

    def write(folder: Path) -> None:
        rng = np.random.default_rng(5)
        for name in TRAIN + JUDGE:
            with np.load(source / f"{name}.npz") as archive:
                arrays = {k: np.asarray(v) for k, v in archive.items()}
            np.savez(
                folder / f"{name}.npz", **(spoiled(arrays, args.spoil, rng) if name in TRAIN else arrays)
            )

    return euroc_benchmark.run_on_unit(
        write, "spoiled", TRAIN, JUDGE, args.strategies, keep=args.keep, screen=args.screen
    )


if __name__ == "__main__":
    sys.exit(main())
