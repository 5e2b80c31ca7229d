"""Where the bias rule finds each recording's opening rest, in the readings as read and as models correct
them, and what each model's rule adds to a rest's reading.

Usage::

    .venv/bin/python tools/opening_rests.py MODEL.json [MODEL.json ...] --recordings REC.npz [REC.npz ...]

A fitted model's bias rule (``unit_bias_``) takes a new recording's gyro bias from its opening rest
(:func:`sins.compensation.unit_bias.opening_rest`, found in the model's corrected readings) plus the
rule's rest offset (the training recordings' bias less their rests' reading). Printed: per recording, the
opening rest's length in seconds as read and as each model corrects it (no rule applied), then per model
its rule's mode and rest offset (°/h). Written to judge whether a network's accelerometer beside least
squares' gyro moves the gyro's bias through where the rests are found or through the rule's own figures
(BROAD's unit B: the rests the same to the window, the offsets not). Nothing here fits.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from sins import io
from sins.compensation import registry
from sins.compensation.unit_bias import opening_rest
from sins.imu import DEG_PER_H


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("models", nargs="+", type=Path)
    parser.add_argument("--recordings", nargs="+", type=Path, required=True)
    args = parser.parse_args()
    models = [registry.load(m) for m in args.models]
    print(f"{'recording':<24} {'as read':>8} " + " ".join(f"{m.stem:>14}" for m in args.models))
    same = 0
    for path in args.recordings:
        imu = io.read(path).beside_reference().imu
        dt = np.diff(imu.t)
        step = float(np.median(dt))
        raw = opening_rest(imu.dtheta_b / dt[:, None], imu.dv_b / dt[:, None], step)
        rests = []
        for model in models:
            c = model.correct_increments(imu)
            rests.append(opening_rest(c.dtheta_b / dt[:, None], c.dv_b / dt[:, None], step))
        same += all(r == raw for r in rests)
        print(f"{path.stem:<24} {raw * step:8.2f} " + " ".join(f"{r * step:14.2f}" for r in rests))
    print(f"the same as read and as every model corrects them: {same} of {len(args.recordings)}")
    for path, model in zip(args.models, models, strict=True):
        rule = getattr(model, "unit_bias_", None)
        if not isinstance(rule, dict):
            print(f"{path.stem}: no bias rule (fitted on one recording)")
            continue
        offset = ", ".join(f"{v / DEG_PER_H:.1f}" for v in rule["rest_offset"])
        print(f"{path.stem}: rule {rule['mode']}, rest offset {offset} °/h")


if __name__ == "__main__":
    main()
