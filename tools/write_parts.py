"""A recording cut into consecutive parts, each written as an ``.npz`` recording with positions, for sins's
own commands: several recordings of one unit to fit on and to judge, with outages judged by position.

Usage::

    .venv/bin/python tools/write_parts.py --dataset psins_vehicle --parts 6 --out DIR

The parts are cut as ``tools/another_unit.py`` cuts BROAD's trials (equal lengths within the reference's
span, the reference interpolated at the readings, in the ``.npz`` form of ``shared/data/euroc``), and each
reference's positions are its velocity integrated by the trapezoid rule (``another_unit.with_positions``):
``sins evaluate --outage`` judges by position and refuses a reference whose positions do not follow its
velocities. ``DIR`` must be a new folder. Then, for instance (PSINS's vehicle MEMS, 16.7 s parts)::

    sins fit DIR/v_1.npz DIR/v_3.npz DIR/v_5.npz --interval-s 0.5 --strategy mlp_seed --out m.json
    sins evaluate m.json DIR/v_2.npz DIR/v_4.npz DIR/v_6.npz --outage 2 --outage 5
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from another_unit import with_positions, write_parts

from sins import io


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--dataset", required=True, help="a dataset sins reads with its reference (psins_vehicle)")
    p.add_argument("--parts", type=int, default=6, help="how many parts (default 6)")
    p.add_argument("--stem", default="v", help="the parts are named STEM_1.npz, STEM_2.npz, …")
    p.add_argument("--out", type=Path, required=True, metavar="DIR", help="a new folder for the parts")
    args = p.parse_args(argv)
    if args.parts < 1:
        p.error(f"--parts {args.parts}: give 1 or more")
    if args.out.exists():  # nothing of the user's is written over
        p.error(f"--out {args.out}: exists; give a new folder")
    rec = io.read(dataset=args.dataset).beside_reference()
    args.out.mkdir(parents=True)
    with tempfile.TemporaryDirectory() as tmp:
        names = write_parts(rec, args.stem, args.parts, Path(tmp))
        for name in names:
            np.savez(args.out / f"{name}.npz", **with_positions(Path(tmp) / f"{name}.npz"))
    span = (rec.reference.t[-1] - rec.reference.t[0]) / args.parts
    print(f"wrote {len(names)} parts of {span:.1f} s to {args.out}: {', '.join(n + '.npz' for n in names)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
