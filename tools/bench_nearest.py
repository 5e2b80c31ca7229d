"""A map's nearest two nodes, two ways: every node's distance from each row (compiled,
``sins.compensation.kohonen._two_nearest``, what a correction uses up to ``_SCANNED_NODES`` nodes) and
scipy's k-d tree (``cKDTree.query(k=2)``, beyond). Prints each one's time on random codebooks of several
sizes and inputs, their ratio, and whether the winners and distances agree to the last bit.

Usage::

    .venv/bin/python tools/bench_nearest.py [--rows 100000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from scipy.spatial import cKDTree

from sins.compensation import kohonen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rows", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(1)
    print(f"{args.rows} rows, median of {args.repeat}; scanned nodes up to {kohonen._SCANNED_NODES}")
    for inputs in (2, 3, 5):
        for nodes in (25, 64, 144, 256, 400, 625):
            codebook = rng.normal(size=(nodes, inputs))
            x = 1.2 * rng.normal(size=(args.rows, inputs))
            tree = cKDTree(codebook)
            kohonen._two_nearest(x[:2], codebook)  # compiled before timing
            scan, search = [], []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                near, dist = kohonen._two_nearest(x, codebook)
                t1 = time.perf_counter()
                d, n = tree.query(x, k=2)
                search.append(time.perf_counter() - t1)
                scan.append(t1 - t0)
            same = np.array_equal(near[:, 0], n[:, 0]) and np.array_equal(dist, d)
            a, b = statistics.median(scan), statistics.median(search)
            agree = "the same to the last bit" if same else "DIFFERENT"
            print(f"{inputs} inputs, {nodes:3d} nodes: scan {a * 1e3:6.1f} ms, tree {b * 1e3:6.1f} ms, "
                  f"tree/scan {b / a:4.2f}, {agree}")  # fmt: skip


if __name__ == "__main__":
    main()
