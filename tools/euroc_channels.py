"""What each model leaves of every channel on the judged recordings: the learners beside least squares.

Usage::

    .venv/bin/python tools/euroc_channels.py MODELS/regression.json MODELS/mlp.json MODELS/kohonen.json
        [--folder euroc] [--judge X Y ...] [--root DATA_ROOT]

``sins evaluate`` judges a model on a recording by the gyro's open-loop attitude, which the bias rule's
estimate of the recording's gyro bias dominates, and says nothing of the accelerometer. This tool judges
every channel as the gap diagnosis does, on the reference's intervals of about 1 s
(:func:`sins.unit_gap.intervals.interval_residuals`): the rotation the corrected gyro composes to against
the reference's, and the velocity change the corrected accelerometer makes against the reference's, each
in the body's axes. Each model corrects the whole recording as ``sins evaluate`` does (its bias rule
included), then the residuals are taken with nothing further corrected. Printed per judged recording and
channel: the RMS over the intervals, and the same less the recording's own mean (what is left once one
constant bias is taken out: the model's part, not the bias rule's); then, per channel, each model's mean
over the recordings against the first model's (``MODELS/regression.json`` first: what the learners add
beyond least squares). The models are ``tools/euroc_benchmark.py --models DIR``'s, fitted on the six
training sequences; nothing here fits.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from pathlib import Path

import numpy as np

from sins import compensation, io
from sins.compensation import judging
from sins.core.series import ReferencedRecording
from sins.imu.calibration import SeedModelFit
from sins.unit_gap.intervals import interval_residuals

JUDGE = ["MH_02_easy", "MH_04_difficult", "V1_01_easy", "V1_03_difficult", "V2_02_medium"]
CHANNELS = [f"{s}.{a}" for s in ("gyro", "accel") for a in "xyz"]
#: Printed units: the gyro's residual turn over an interval in millidegrees, the accelerometer's velocity
#: change in mm/s (over 1 s: a mean force error in mm/s²).
SCALE = np.array([1e3 * 180.0 / np.pi] * 3 + [1e3] * 3)


def _nothing() -> SeedModelFit:
    """A seed model that corrects nothing: the residuals of readings corrected beforehand."""
    z3, z33 = np.zeros(3), np.zeros((3, 3))
    return SeedModelFit(z3, z33, z33, z3, z33, z3, z33, z33, z3, z33, np.zeros(6))


def residuals(model: compensation.Strategy | None, rec: ReferencedRecording) -> np.ndarray:
    """Per interval (k, 6): gyro rad, accelerometer m/s, of ``rec`` corrected by ``model`` (None: raw)."""
    imu = judging.corrected(model, rec)
    res = interval_residuals(dataclasses.replace(rec, imu=imu), _nothing(), 1.0)
    return np.hstack([res.residual["gyro"], res.residual["accel"]])


def main_(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("models", nargs="+", type=Path)
    p.add_argument("--folder", default="euroc")
    p.add_argument("--judge", nargs="+", default=JUDGE)
    p.add_argument("--root", type=Path, help="the data root (default: SINS_DATA or ../shared/data)")
    args = p.parse_args(argv)
    if args.root is not None:
        os.environ["SINS_DATA"] = str(args.root)
    # The raw readings first, then each model under its file's name (its path where that is ambiguous).
    stems = [m.stem for m in args.models]
    names = [m.stem if stems.count(m.stem) == 1 and m.stem != "raw" else str(m) for m in args.models]
    rows = [("raw", None), *((n, compensation.load(m)) for n, m in zip(names, args.models, strict=True))]
    labels = [label for label, _ in rows]
    rms: dict[str, list[np.ndarray]] = {n: [] for n in labels}
    demeaned: dict[str, list[np.ndarray]] = {n: [] for n in labels}
    print("RMS over the intervals (less the recording's own mean in brackets); gyro mdeg, accel mm/s")
    for name in args.judge:
        rec = io.read(dataset=f"{args.folder}/{name}").beside_reference()
        print(f"{name}:")
        for label, model in rows:
            r = residuals(model, rec) * SCALE
            rms[label].append(np.sqrt(np.mean(r * r, axis=0)))
            demeaned[label].append(np.std(r, axis=0))
            both = zip(CHANNELS, rms[label][-1], demeaned[label][-1], strict=True)
            cells = "  ".join(f"{c} {a:7.1f} ({b:5.1f})" for c, a, b in both)
            print(f"  {label:<16} {cells}", flush=True)
    first = labels[1]
    print(f"\nmean over the {len(args.judge)} recordings, less each one's mean; ratio to {first}")
    base = np.mean(demeaned[first], axis=0)
    for label in labels:
        mean = np.mean(demeaned[label], axis=0)
        cells = "  ".join(f"{c} {m:6.1f} ×{m / b:5.3f}" for c, m, b in zip(CHANNELS, mean, base, strict=True))
        print(f"  {label:<16} {cells}")
    return 0


if __name__ == "__main__":
    sys.exit(main_())
