"""What the networks' accelerometer is worth in navigation terms on BROAD's hand-held unit B: the horizontal
position error of short free-inertial windows on the parts no model was fitted on.

Usage::

    .venv/bin/python tools/broad_free_inertial.py [--strategies regression kohonen_pure mlp_seed]
        [--windows 2 5] [--every 1] [--train 05_1 18_1 18_3] [--judge 05_2 05_3 18_2] [--at-imu]
        [--json OUT.json] [--keep DIR]

The two BROAD trials of unit B are cut into three parts each as ``tools/another_unit.py`` cuts them, the
models fitted on its training parts (``--train``, default ``05_1 18_1 18_3``) as ``sins fit`` fits
several recordings (``sins.compensation.fitting.fit_several``, the networks' guard on: on this unit it
writes their accelerometer beside least squares' gyro and bias rule) and each judged part (``--judge``,
default ``05_2 05_3 18_2``) corrected by each model as ``sins evaluate`` corrects it
(``correct_recording``) and by none. From every
``--every`` seconds of a judged part, a window of each ``--windows`` length is navigated free-inertial
from the reference's attitude and velocity at its start: the attitude composed step by step from the
corrected gyro's increments (scipy's ``Rotation``), each velocity increment turned into the reference's
world frame at the step's mean attitude, gravity (9.81 m/s²) taken out along its vertical, the position
integrated by the trapezoid rule; Earth's rate is left out (the frame's latitude is not known: 15 °/h is
a twentieth of a degree in 5 s). The error is the horizontal distance from the reference's position (its
velocity integrated by the trapezoid rule: the parts hold none) at the window's end, where an outage of
that length would leave a position fix's aiding; its vertical holds the gravity model's error and is
not judged. Nothing of ``sins.nav`` is used: numpy and scipy judge sins's corrections.

``--at-imu``: the reference moved from the motion capture's point to the IMU by the lever arm least
squares' fit on the training parts estimates (``sins fit``'s ``lever_arm_mm``, body frame; the velocity
``v + C (ω × r)``, ``ω`` the reference attitude's own rate), so that what a model may have learned of the
arm (``ω̇ × r + ω × (ω × r)``, which the seed model cannot express) is not counted as its gain.

``--keep DIR``: the parts written to a new folder, the judged ones with positions (their velocity's
integral), so that sins's own commands give the same figures: ``sins fit DIR/05_1.npz DIR/18_1.npz
DIR/18_3.npz --strategy kohonen_pure --out m.json``, then ``sins evaluate m.json DIR/05_2.npz
DIR/05_3.npz DIR/18_2.npz --outage 2 --outage 5`` (``sins.compensation.outages``: sins's navigation,
with Earth's rate at a nominal latitude, from every second of the part rather than from its second).

Prints per judged part the RMS over its windows for each model (mm), and each strategy's mean paired
difference from least squares (``regression``) per part, with the mean over the three parts and its
standard error. About 1 min on 2 cores.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import cumulative_trapezoid
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parent))

from another_unit import with_positions, write_parts

from sins import io
from sins.compensation import fitting
from sins.core.series import ImuIncrements

TRAIN = ["05_1", "18_1", "18_3"]
JUDGE = ["05_2", "05_3", "18_2"]
#: Gravity's size for the free-inertial windows, m/s² (only the horizontal error is judged).
G_M_S2 = 9.81


def window_errors(
    imu: ImuIncrements, part: dict[str, np.ndarray], length_s: float, every_s: float
) -> np.ndarray:
    """The horizontal position error, m, at the end of each free-inertial window of ``length_s`` started
    every ``every_s`` in ``imu`` (a judged part's readings as corrected, on the part's own times from
    zero) against the part's reference (``part``: its ``.npz`` arrays)."""
    t_s = part["t_s"]
    if len(imu.t) != len(t_s) or not np.allclose(imu.t + t_s[0], t_s, rtol=0.0, atol=1e-9):
        raise ValueError("the readings are not on the part's own times")
    p_ref = cumulative_trapezoid(part["v_m_s"], t_s, axis=0, initial=0.0)
    attitude = Rotation.from_quat(part["q_wxyz"], scalar_first=True)  # body to world
    dt = np.diff(t_s)
    steps = round(length_s / float(np.median(dt)))
    starts = np.searchsorted(t_s, np.arange(t_s[0] + 1.0, t_s[-1] - length_s, every_s))
    starts = starts[starts + steps < len(t_s)]
    turn = attitude[starts]  # the windows start on the part's own samples
    v = part["v_m_s"][starts].copy()
    p = p_ref[starts].copy()
    for k in range(steps):
        at = starts + k
        after = turn * Rotation.from_rotvec(imu.dtheta_b[at])
        dv = 0.5 * (turn.apply(imu.dv_b[at]) + after.apply(imu.dv_b[at]))
        dv[:, 2] -= G_M_S2 * dt[at]
        p += (v + 0.5 * dv) * dt[at, None]
        v += dv
        turn = after
    error = p - p_ref[starts + steps]
    return np.asarray(np.hypot(error[:, 0], error[:, 1]))


def at_imu(part: dict[str, np.ndarray], arm_b_m: np.ndarray) -> dict[str, np.ndarray]:
    """``part`` with its reference's velocity moved to a point ``arm_b_m`` (m, body frame) from its own:
    ``v + C (ω × r)``, ``ω`` the body rate of the reference's attitude (each step's, averaged at the
    samples). Its integral is the moved position less its start's (``C r`` at the start), which the
    windows, judging differences, do not see."""
    t_s = part["t_s"]
    attitude = Rotation.from_quat(part["q_wxyz"], scalar_first=True)
    step_rate = (attitude[:-1].inv() * attitude[1:]).as_rotvec() / np.diff(t_s)[:, None]
    rate = np.vstack([step_rate[:1], 0.5 * (step_rate[1:] + step_rate[:-1]), step_rate[-1:]])
    return {**part, "v_m_s": part["v_m_s"] + attitude.apply(np.cross(rate, arm_b_m))}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--strategies", nargs="+", default=["regression", "kohonen_pure", "mlp_seed"])
    p.add_argument("--windows", nargs="+", type=float, default=[2.0, 5.0], help="window lengths, s")
    p.add_argument("--every", type=float, default=1.0, help="a window starts every this many seconds")
    p.add_argument("--train", nargs="+", default=TRAIN, help="the parts the models are fitted on")
    p.add_argument("--judge", nargs="+", default=JUDGE, help="the parts they are judged on")
    p.add_argument("--at-imu", action="store_true", help="the reference moved to the IMU by the fitted arm")
    p.add_argument("--json", type=Path, help="write every window's error here")
    p.add_argument(
        "--keep", type=Path, metavar="DIR",
        help="write the parts to DIR (a new folder) for sins's own commands, the judged ones with positions",
    )  # fmt: skip
    args = p.parse_args(argv)
    if args.keep is not None:
        if args.keep.exists():  # a new folder: nothing of the user's is written over
            p.error(f"--keep {args.keep}: exists; give a new folder")
        args.keep.mkdir(parents=True)
    strategies = ["regression", *[s for s in args.strategies if s != "regression"]]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for trial in ("05", "18"):
            write_parts(io.read(dataset=f"broad_{trial}").beside_reference(), trial, 3, folder)
        recs = {n: io.read(str(folder / f"{n}.npz")).beside_reference() for n in args.train + args.judge}
        parts = {n: dict(np.load(folder / f"{n}.npz")) for n in args.judge}
        if args.keep is not None:
            for n in args.train:
                shutil.copy(folder / f"{n}.npz", args.keep / f"{n}.npz")
            for n in args.judge:  # `sins evaluate --outage` judges by position: the velocity's integral
                np.savez(args.keep / f"{n}.npz", **with_positions(folder / f"{n}.npz"))
    models: dict[str, Any] = {"none": None}
    for s in strategies:
        outcome = fitting.fit_several(s, [recs[n] for n in args.train], args.train)
        guard = outcome.document.get("network_guard")
        said = f" (its guard: accelerometer {guard['accelerometer']}, gyro {guard['gyro']})" if guard else ""
        print(f"fitted {s} on {', '.join(args.train)}{said}", flush=True)
        models[s] = outcome.strategy
        if s == "regression" and args.at_imu:  # the arm least squares' fit found, as `sins fit` says it
            arm_b_m = 1e-3 * np.asarray(outcome.document["lever_arm_mm"])
            arm = ", ".join(f"{1e3 * x:.2f}" for x in arm_b_m)
            print(f"the reference moved to the IMU by {arm} mm (body x y z)")
            parts = {n: at_imu(part, arm_b_m) for n, part in parts.items()}
    # Each judged part corrected once by each model, for every window length.
    corrected = {
        n: {m: recs[n].imu if s is None else s.correct_recording(recs[n].imu) for m, s in models.items()}
        for n in args.judge
    }
    errors: dict[str, dict[str, dict[str, list[float]]]] = {}
    for length in args.windows:
        key = f"{length:g} s"
        errors[key] = {}
        print(f"\n{key} windows, horizontal position error at the end, RMS over the windows, mm")
        print("| part | windows | " + " | ".join(models) + " |")
        print("|---" * (len(models) + 2) + "|")
        for n in args.judge:
            errors[key][n] = {
                m: window_errors(imu, parts[n], length, args.every).tolist()
                for m, imu in corrected[n].items()
            }
            rms = [1e3 * np.sqrt(np.mean(np.square(errors[key][n][m]))) for m in models]
            print(f"| {n} | {len(errors[key][n]['none'])} | " + " | ".join(f"{r:.1f}" for r in rms) + " |")
        for s in strategies[1:]:
            per = np.array(
                [np.mean(np.subtract(errors[key][n][s], errors[key][n]["regression"])) for n in args.judge]
            )
            se = per.std(ddof=1) / np.sqrt(len(per))
            cells = ", ".join(f"{1e3 * x:+.1f}" for x in per)
            print(f"{s} less regression, mean over each part's windows: {cells} mm; "
                  f"{1e3 * per.mean():+.1f} ± {1e3 * se:.1f} mm over the parts")  # fmt: skip
    if args.json:
        io.write_report(args.json, {"windows_every_s": args.every, "errors_m": errors})  # atomic
    return 0


if __name__ == "__main__":
    sys.exit(main())
