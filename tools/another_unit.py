"""The EuRoC protocol's commands, unchanged, on another unit: BROAD's hand-held MEMS IMU (unit B).

Usage::

    .venv/bin/python tools/another_unit.py [--parts 3] [--strategies regression mlp_window ...]
        [--gaps N] [--screen refused|always|never] [--calibrated] [--backward | --mocap120]
        [--json OUT.json] [--keep DIR]

sins holds two BROAD trials of unit B (``broad_05``: slow rotations, ``broad_18``: fast translations, each
with rests). Each is cut into ``--parts`` consecutive recordings and written in the ``.npz`` form of
``shared/data/euroc`` into a temporary data root (folder ``broad_b``; the reference slerped across the
motion capture's short gaps, its world frame the optical one, z up). The models are fitted on the parts
``--train`` lists (default ``05_1 18_1 18_3``) and judged on the others (default ``05_2 05_3 18_2``) by
``tools/euroc_benchmark.py``'s commands (``sins fit --dataset broad_b/...``, ``sins evaluate``). Prints the
open-loop table; what must hold is that no correction is worse than the raw readings.

``--gaps N``: each training part's reference with ``N`` gaps of 1 s filled as converters fill a motion
capture's lost markers (the attitude slerped by scipy, the velocity a straight line; placed with a fixed
seed), the judged parts as they are; ``--screen`` is handed to ``sins fit``
(:mod:`sins.compensation.screening`).

``--backward``: each part's reference written as the published preprocessing for learned gyro correction
writes a motion capture's (Brossard et al. 2020, its TUM-VI branch): positions (here the reference's
velocity integrated by the trapezoid rule) and the velocity a backward difference of them, its first row
zero: half a step late, which ``sins`` reads on the positions' clock
(:func:`sins.io.local.on_positions_clock`). ``--mocap120``: the same, and the capture at 120 Hz, as that
preprocessing reads a 120 Hz motion capture onto the IMU's stamps: the attitude slerped to 120 Hz and back,
the positions linearly, the readings within the capture's span (``tools/gap_real_cases.py``'s
``as_mocap120``).

``--calibrated``: each part with its own constant gyro bias taken out (``tools/calibrated_unit.py``'s
``calibrated``, numpy and scipy alone): the unit as it would read calibrated at every power-up.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parent))

import euroc_benchmark
import spoiled_references
from calibrated_unit import calibrated

from sins import io
from sins.core.series import ReferencedRecording

#: NED to ENU (and back): east and north swapped, down turned up.
_NED_TO_ENU = Rotation.from_matrix([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def write_parts(rec: ReferencedRecording, stem: str, parts: int, folder: Path) -> list[str]:
    """``rec`` cut into ``parts`` recordings of equal length within its reference's span, each written as
    ``folder/{stem}_{k}.npz``; returns the names."""
    t_all = rec.imu.t
    first = int(np.searchsorted(t_all, rec.reference.t[0]))
    last = int(np.searchsorted(t_all, rec.reference.t[-1], side="right")) - 1
    cuts = np.linspace(first, last, parts + 1).round().astype(int)
    names = []
    for k in range(parts):
        a, b = int(cuts[k]), int(cuts[k + 1])
        t = t_all[a : b + 1]
        dt = np.diff(t)[:, None]
        steps = slice(a, b)
        rate = rec.imu.dtheta_b[steps] / dt
        force = rec.imu.dv_b[steps] / dt
        # Readings at the step boundaries: each step's mean rate, the last repeated.
        rate, force = np.vstack([rate, rate[-1:]]), np.vstack([force, force[-1:]])
        ref = rec.reference.interpolate(t)
        q = _NED_TO_ENU * Rotation.from_quat(ref.q_nb)
        v = ref.v_n[:, [1, 0, 2]] * [1.0, 1.0, -1.0]
        name = f"{stem}_{k + 1}"
        np.savez(
            folder / f"{name}.npz", t_s=t, gyro_rad_s=rate, accel_m_s2=force,
            q_wxyz=q.as_quat(scalar_first=True), v_m_s=v, p_m=np.zeros_like(v),
        )  # fmt: skip
        names.append(name)
    return names


def with_positions(path: Path) -> dict[str, np.ndarray]:
    """The part at ``path`` with its positions: its reference's velocity integrated by the trapezoid rule
    (the parts are written with none)."""
    from scipy.integrate import cumulative_trapezoid

    a = dict(np.load(path))
    a["p_m"] = cumulative_trapezoid(a["v_m_s"], a["t_s"], axis=0, initial=0.0)
    return a


def backward(path: Path) -> None:
    """The part at ``path`` written again with positions and a backward-difference velocity
    (``--backward``)."""
    a = with_positions(path)
    v = np.zeros_like(a["p_m"])
    v[1:] = np.diff(a["p_m"], axis=0) / np.diff(a["t_s"])[:, None]
    np.savez(path, **{**a, "v_m_s": v})


def mocap120(path: Path) -> None:
    """The part at ``path`` written again as a 120 Hz motion capture's reference arrives from the
    published preprocessing (``--mocap120``)."""
    import gap_real_cases

    np.savez(path, **gap_real_cases.as_mocap120(with_positions(path)))


def with_gaps(path: Path, gaps: int, rng: np.random.Generator) -> None:
    """The ``.npz`` recording at ``path`` written again with ``gaps`` 1 s gaps of its reference filled
    (the attitude slerped, the velocity a straight line between the gap's ends)."""
    a = dict(np.load(path))
    t, q, v = a["t_s"], a["q_wxyz"].copy(), a["v_m_s"].copy()
    steps = round(1.0 / float(np.median(np.diff(t))))
    for _ in range(gaps):
        i = int(rng.integers(len(t) // 10, len(t) - len(t) // 10 - steps))
        spoiled_references.fill_gap(t, q, [v], i, i + steps)
    np.savez(path, **{**a, "q_wxyz": q, "v_m_s": v})


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--parts", type=int, default=3)
    p.add_argument("--train", nargs="+", default=["05_1", "18_1", "18_3"])
    p.add_argument("--judge", nargs="+", default=["05_2", "05_3", "18_2"])
    p.add_argument("--strategies", nargs="+", default=euroc_benchmark.STRATEGIES)
    p.add_argument("--gaps", type=int, default=0, help="1 s gaps filled in each training part's reference")
    p.add_argument("--screen", choices=("refused", "always", "never"), help="handed to sins fit")
    p.add_argument("--calibrated", action="store_true", help="each part's own gyro bias taken out")
    form = p.add_mutually_exclusive_group()
    form.add_argument("--backward", action="store_true", help="velocities a backward difference of positions")
    form.add_argument("--mocap120", action="store_true", help="as a 120 Hz motion capture's preprocessing")
    p.add_argument("--json", type=Path)
    p.add_argument("--keep", type=Path, help="write the .npz recordings here (a data root) and keep them")
    args = p.parse_args(argv)

    def write(folder: Path) -> None:
        rng = np.random.default_rng(0)
        for trial in ("05", "18"):
            rec = io.read(dataset=f"broad_{trial}").beside_reference()
            for name in write_parts(rec, trial, args.parts, folder):
                if args.gaps and name in args.train:
                    with_gaps(folder / f"{name}.npz", args.gaps, rng)
                if args.calibrated:
                    calibrated(folder / f"{name}.npz", folder)  # written again under its name
                if args.backward:
                    backward(folder / f"{name}.npz")
                if args.mocap120:
                    mocap120(folder / f"{name}.npz")

    return euroc_benchmark.run_on_unit(
        write, "broad_b", args.train, args.judge, args.strategies, json_out=args.json, keep=args.keep,
        screen=args.screen,
    )  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())
