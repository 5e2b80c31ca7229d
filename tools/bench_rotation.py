"""sins's hand-written rotations against scipy's ``Rotation`` and ``Slerp``, at the sizes sins uses.

Each pair computes the same numbers (``tests/test_rotation.py`` holds them equal); this prints the median
of ``--repeats`` timings of each and their ratio, so that the choice in ``sins.core.rotation`` (scipy where
it is within 10 % of the hand-written function, the hand-written one where it is not) is made on figures.

    .venv/bin/python tools/bench_rotation.py [--repeats 15]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from sins.core import rotation
from sins.core.series import NavSeries


def _median_s(f: Callable[[], Any], repeats: int) -> float:
    f()  # warm
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _hand_slerp(nav: NavSeries, t: np.ndarray) -> np.ndarray:
    return nav.interpolate(t).q_nb


def _scipy_slerp(nav: NavSeries, t: np.ndarray) -> np.ndarray:
    q = Slerp(nav.t, Rotation.from_quat(nav.q_nb))(t).as_quat()
    return np.asarray(q)


def cases(n: int, rng: np.random.Generator) -> dict[str, tuple[Callable[[], Any], Callable[[], Any]]]:
    """``{name: (hand-written, scipy)}`` on ``n`` rotations."""
    q = Rotation.random(n, rng=rng).as_quat()
    p = Rotation.random(n, rng=rng).as_quat()
    v = rng.normal(size=(n, 3))
    r = 0.1 * rng.normal(size=(n, 3))
    t = np.arange(n, dtype=float)
    nav = NavSeries(t=t, lat=np.zeros(n), lon=np.zeros(n), h=np.zeros(n), v_n=np.zeros((n, 3)), q_nb=q)
    t_new = np.sort(rng.uniform(0.0, n - 1.0, n))
    return {
        "quat_multiply": (
            lambda: rotation.quat_multiply(p, q),
            lambda: (Rotation.from_quat(p) * Rotation.from_quat(q)).as_quat(canonical=False),
        ),
        "quat_from_rotvec": (lambda: rotation.quat_from_rotvec(r), lambda: Rotation.from_rotvec(r).as_quat()),
        "rotvec_from_quat": (lambda: rotation.rotvec_from_quat(q), lambda: Rotation.from_quat(q).as_rotvec()),
        "dcm_from_quat": (lambda: rotation.dcm_from_quat(q), lambda: Rotation.from_quat(q).as_matrix()),
        "euler_from_quat": (
            lambda: rotation.euler_from_quat(q),
            lambda: Rotation.from_quat(q).as_euler("ZYX"),
        ),
        "rotate": (lambda: rotation.rotate(q, v), lambda: Rotation.from_quat(q).apply(v)),
        "NavSeries.interpolate (slerp)": (lambda: _hand_slerp(nav, t_new), lambda: _scipy_slerp(nav, t_new)),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 1_000, 100_000])
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    print(f"{'function':32s} {'n':>8s} {'sins ms':>10s} {'scipy ms':>10s} {'scipy/sins':>10s}")
    for n in args.sizes:
        for name, (hand, sp) in cases(n, rng).items():
            if name.startswith("NavSeries") and n < 2:
                continue
            a, b = _median_s(hand, args.repeats), _median_s(sp, args.repeats)
            print(f"{name:32s} {n:8d} {a * 1e3:10.4f} {b * 1e3:10.4f} {b / a:10.2f}")


if __name__ == "__main__":
    main()
