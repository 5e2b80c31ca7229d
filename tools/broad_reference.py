"""BROAD's reference figures: what orientation filters and the bare gyro reach, by BROAD's metric.

Usage::

    .venv/bin/python tools/broad_reference.py [--trials 05 18] [--root DATA_ROOT] [--json OUT.json]

Per trial (``broad_mocap/NN_*.mat`` under the data root, ``SINS_DATA`` or ``../shared/data``), the total,
heading and inclination RMSE over the ``movement`` rows, by :func:`sins.nav.attitude.attitude_rmse`
(BROAD's definition), of:

* Madgwick's MARG filter as BROAD's example code runs it (β = 0.12, its TAGP; started from the first
  sample's accelerometer and magnetometer; turned from north-west-up into ENU), the figure BROAD
  published beside the one reproduced here with ``tests/numpy_broad.py`` (BROAD's C code's magnetic
  reference scale), and the same filter as Madgwick's report writes it (the magnetic reference at full
  scale, as the ``ahrs`` package implements it);
* VQF (the ``vqf`` package, default parameters): the offline (acausal) and the online (causal) filter,
  9D (gyro, accelerometer, magnetometer; ENU) and 6D (no magnetometer, so its heading is arbitrary: the
  constant heading offset over the judged rows is removed before scoring, the heading *drift* stays;
  the 6D figures as output are in the JSON);
* the gyro alone, open loop (:func:`sins.nav.attitude.propagate`) from the first row with an optical
  orientation: raw; less the mean of the trial's opening rest (the rows before the ``movement``
  flag's first 1); less the mean of the other trials' opening rests.

Earth's rate is not removed from the gyro (nor by BROAD); taking it out (latitude 52.5°, ENU taken as
true north) moves the rest-bias figures by ≤ 0.03°.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np
import scipy.io
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import numpy_broad as nb  # the independent Madgwick (tests/numpy_broad.py)
from vqf import VQF, offlineVQF

from sins.errors import SinsInputError
from sins.io.datasets.broad import BROAD_FOLDER
from sins.io.datasets.root import data_root
from sins.io.formats import write_json
from sins.nav.attitude import AttitudeRmse, attitude_rmse, propagate

FORMAT = "sins-broad-reference"
Array = NDArray[np.float64]
ROWS = (
    ("madgwick_published", "Madgwick β=0.12, published (BROAD's C++)"),
    ("madgwick_reproduced", "Madgwick β=0.12, reproduced (numpy, C code's mag scale)"),
    ("madgwick_report", "Madgwick β=0.12, report's mag scale (as ahrs)"),
    ("vqf_9d_offline", "VQF 9D offline"),
    ("vqf_9d_online", "VQF 9D online"),
    ("vqf_6d_offline", "VQF 6D offline, heading offset removed"),
    ("vqf_6d_online", "VQF 6D online, heading offset removed"),
    ("gyro_raw", "gyro only, raw"),
    ("gyro_rest_bias", "gyro only, bias from the opening rest"),
    ("gyro_other_bias", "gyro only, bias from the other trial's rest"),
)


def _trial_file(number: str, root: str | None) -> Path:
    """``<root>/broad_mocap/NN_*.mat`` for trial ``number``, or a one-line error."""
    folder = data_root(root) / BROAD_FOLDER
    if not folder.is_dir():
        raise SinsInputError(f"{folder}: no such data folder; set SINS_DATA or pass --root")
    if not number.isdigit():
        raise SinsInputError(f"--trials: {number!r} is not a trial number (05, 18, ...)")
    found = sorted(folder.glob(f"{int(number):02d}_*.mat"))
    if len(found) != 1:
        raise SinsInputError(f"{folder}: {len(found)} files match trial {int(number):02d}_*.mat; expected 1")
    return found[0]


def _load(path: Path) -> dict[str, Any]:
    mat = scipy.io.loadmat(path, squeeze_me=True)
    for name in ("imu_gyr", "imu_acc", "imu_mag", "opt_quat", "movement", "sampling_rate"):
        if name not in mat:
            raise SinsInputError(f"{path}: no variable {name!r}")
    for name in ("imu_gyr", "imu_acc", "imu_mag"):
        mat[name] = np.ascontiguousarray(mat[name], dtype=float)
    mat["movement"] = np.asarray(mat["movement"]).astype(bool)
    mat["opening_rest"] = int(np.argmax(mat["movement"]))  # rows before the first movement row
    return mat


def _scalar_last(q_wxyz: Array) -> Array:
    return np.ascontiguousarray(np.asarray(q_wxyz)[:, [1, 2, 3, 0]])


def heading_offset_removed(q_est: Array, q_ref: Array, judged: NDArray[np.bool_]) -> tuple[Array, float]:
    """``q_est`` (scalar-last) turned about the vertical by the circular mean of its signed heading error
    over the judged rows with a reference, and that offset, rad."""
    ok = judged & np.isfinite(q_ref).all(axis=1)
    e = (Rotation.from_quat(q_est[ok]) * Rotation.from_quat(q_ref[ok]).inv()).as_quat()
    signed = 2.0 * np.arctan2(e[:, 2] * np.sign(e[:, 3]), np.abs(e[:, 3]))
    offset = float(np.arctan2(np.sin(signed).mean(), np.cos(signed).mean()))
    return (Rotation.from_rotvec([0.0, 0.0, -offset]) * Rotation.from_quat(q_est)).as_quat(), offset


def gyro_only(mat: dict[str, Any], bias_radps: Array) -> AttitudeRmse:
    """Open-loop attitude from ``imu_gyr − bias``, started at the first row with an optical orientation."""
    ref = _scalar_last(mat["opt_quat"])
    start = int(np.argmax(np.isfinite(ref).all(axis=1)))
    t = np.arange(start, len(ref)) / float(mat["sampling_rate"])
    q = propagate(t, mat["imu_gyr"][start:] - bias_radps, ref[start])
    return attitude_rmse(q, ref[start:], mat["movement"][start:])


def _figures(r: AttitudeRmse) -> dict[str, Any]:
    return r.to_dict()


def trial_figures(stem: str, mat: dict[str, Any], other_bias: Array) -> dict[str, Any]:
    """Every row of the table for one trial."""
    ref = _scalar_last(mat["opt_quat"])
    judged = mat["movement"]
    rate = float(mat["sampling_rate"])
    gyr, acc, mag = mat["imu_gyr"], mat["imu_acc"], mat["imu_mag"]
    out: dict[str, Any] = {}
    published = nb.MADGWICK_PUBLISHED_DEG.get(stem)
    out["madgwick_published"] = None if published is None else dict(published)
    for key, scale in (("madgwick_reproduced", nb.BROAD_C_MAG_REF_SCALE), ("madgwick_report", 1.0)):
        out[key] = _figures(attitude_rmse(_scalar_last(nb.broad_madgwick_enu(mat, scale)), ref, judged))
    offsets = {}
    for mode, result in (
        ("offline", offlineVQF(gyr, acc, mag, 1.0 / rate, None)),
        ("online", VQF(1.0 / rate).updateBatch(gyr, acc, mag)),
    ):
        out[f"vqf_9d_{mode}"] = _figures(attitude_rmse(_scalar_last(result["quat9D"]), ref, judged))
        q6 = _scalar_last(result["quat6D"])
        aligned, offset = heading_offset_removed(q6, ref, judged)
        out[f"vqf_6d_{mode}"] = _figures(attitude_rmse(aligned, ref, judged))
        out[f"vqf_6d_{mode}_as_output"] = _figures(attitude_rmse(q6, ref, judged))
        offsets[mode] = float(np.degrees(offset))
    rest_bias = gyr[: mat["opening_rest"]].mean(axis=0)
    out["gyro_raw"] = _figures(gyro_only(mat, np.zeros(3)))
    out["gyro_rest_bias"] = _figures(gyro_only(mat, rest_bias))
    out["gyro_other_bias"] = _figures(gyro_only(mat, other_bias))
    return {
        "stem": stem,
        "judged_rows": int(judged.sum()),
        "start_row": int(np.argmax(np.isfinite(ref).all(axis=1))),
        "opening_rest_rows": [0, mat["opening_rest"]],
        "rest_bias_dps": np.degrees(rest_bias).tolist(),
        "other_bias_dps": np.degrees(other_bias).tolist(),
        "vqf_6d_heading_offset_deg": offsets,
        "figures": out,
    }


def _print(number: str, trial: dict[str, Any]) -> None:
    start, rest = trial["start_row"], trial["opening_rest_rows"][1]
    print(
        f"\nbroad_{number} ({trial['stem']}): {trial['judged_rows']} movement rows judged; gyro-only "
        f"runs start at row {start}; opening rest rows 0:{rest}, bias "
        f"[{', '.join(f'{b:.4f}' for b in trial['rest_bias_dps'])}] °/s"
    )
    print(f"  {'':62s} {'total °':>8s} {'heading °':>10s} {'incl. °':>8s}")
    for key, label in ROWS:
        f = trial["figures"][key]
        if f is None:
            print(f"  {label:62s} {'—':>8s}")
            continue
        print(f"  {label:62s} {f['total_deg']:8.3f} {f['heading_deg']:10.3f} {f['inclination_deg']:8.3f}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", nargs="+", default=["05", "18"], metavar="NN")
    parser.add_argument("--root", help="the data root (default: SINS_DATA or ../shared/data)")
    parser.add_argument("--json", metavar="OUT", help="write the figures as JSON")
    args = parser.parse_args()
    try:
        paths = {n: _trial_file(n, args.root) for n in args.trials}
        mats = {n: _load(p) for n, p in paths.items()}
        if len(mats) < 2:
            raise SinsInputError("--trials: name at least two trials (the other-trial bias needs one)")
        biases = {n: m["imu_gyr"][: m["opening_rest"]].mean(axis=0) for n, m in mats.items()}
        trials = {}
        for n, m in mats.items():
            other = np.mean([b for k, b in biases.items() if k != n], axis=0)
            trials[n] = trial_figures(paths[n].stem, m, other)
            _print(n, trials[n])
        if args.json:
            write_json(args.json, {"format": FORMAT, "version": 1, "trials": trials})
            print(f"\nwritten: {args.json}")
    except SinsInputError as exc:
        print(f"broad_reference: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
