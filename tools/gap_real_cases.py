"""The gap diagnosis on real recordings with one effect added to a real unit's readings (issue 42).

Usage::

    .venv/bin/python tools/gap_real_cases.py [--bases euroc/MH_01_easy broad_05 broad_05:mocap120:moving ...]
        [--jobs 2] [--effects NAME ...] [--scale X] [--save CASES.json] [--root DIR]
    .venv/bin/python tools/gap_real_cases.py --load CASES.json

Each base is a real recording in the ``.npz`` form of ``shared/data/euroc`` (its SOURCE.md): a EuRoC
sequence as it is, or a BROAD trial written in that form here (its longest stretch with every reading and
the optical reference finite: ``opt_quat`` the attitude of the IMU in the optical ENU frame, ``opt_pos`` the
position, the velocity a quadratic Savitzky-Golay derivative of it over 0.1 s; ``broad_NN:mocap120`` with its
reference as the published preprocessing writes a 120 Hz motion capture's, ``:moving`` from where it starts
moving, as a recording without an opening rest arrives: :func:`base_arrays`). To each, with numpy alone
(not ``sins.imu``), one effect is added to the readings, at a MEMS unit's size:

* ``gyro.time_offset``, ``accel.time_offset``: the sensor's readings 5 ms late (a band-limited delay:
  the spectrum turned by ``e^{-2πifτ}``, the ends mirrored first, so that the noise keeps its spectrum);
* ``gyro.scale_nonlinearity``: ``k2 ω_i²``, ``k2`` a 0.5 % scale error at the recording's RMS rate;
  ``accel.scale_nonlinearity``: ``k2 f_i²``, 2000 ppm/g;
* ``gyro.scale_asymmetry``: ``ka |ω_i|``, ``ka`` 5000 ppm; ``accel.scale_asymmetry``: ``ka |f_i|``, 2000 ppm;
* ``gyro.g2_sensitivity``: ``Σ G2 f_j f_k``, every element 0.05 °/s/g² with random signs;
* outside the library: a 0.3 °/s sinusoid of period 37 s on gyro x, a 0.3 °/s bias step on gyro y half
  way, a 10 mg sinusoid of period 37 s on accel y, a 10 mg step on accel x half way.

The input of each effect is the unit's own reading (what a real unit's effect sees is its true input; the
reading differs from it by the unit's errors, a few per cent of the effect at most). Each modified copy is
written into a temporary data root (never the project's or the shared data) and diagnosed as a user does,
``sins gap --dataset FOLDER/NAME --json OUT`` in a process of its own, as is the base unmodified. A library
case passes where the added effect is in the diagnosis and the base's diagnosis lacks it; a disturbance
passes where ``outside`` names its channel. Prints one row per case and the totals, by base; beside them
the library cases passed where an effect the report lists as indistinguishable from one it accepts
(``indistinguishable_from``) counts as named, in the case and in the base alike.
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import scipy.io
from scipy.signal import savgol_filter
from scipy.spatial.transform import Rotation, Slerp

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("SINS_DATA", ROOT.parent / "shared" / "data"))
G = 9.80665
DEG = np.pi / 180.0
MG = 1e-3 * G

LIBRARY = (
    "gyro.time_offset", "accel.time_offset", "gyro.scale_nonlinearity", "accel.scale_nonlinearity",
    "gyro.scale_asymmetry", "accel.scale_asymmetry", "gyro.g2_sensitivity",
)  # fmt: skip
OUTSIDE = {
    "gyro.x sinusoid": "gyro.x",
    "gyro.y step": "gyro.y",
    "accel.y sinusoid": "accel.y",
    "accel.x step": "accel.x",
}
#: The bases developed on, and those kept for judging (never looked at while the diagnosis was built).
DEVELOP = ("euroc/MH_01_easy", "euroc/V1_02_medium", "broad_05")
JUDGE = ("euroc/MH_03_medium", "euroc/V2_01_easy", "broad_18")
BROAD_RATE_HZ = 285.714
#: A case is observable where the oracle's withheld gain reaches this (SIGNIFICANT_NATS + TIE_NATS).
OBSERVABLE_NATS = 9.0


@functools.cache
def _broad_mat(trial: str) -> dict[str, Any]:
    """A BROAD trial's ``.mat`` file as scipy reads it (read once: the ``:moving`` form reads it twice)."""
    return dict(scipy.io.loadmat(str(next((SHARED / "broad_mocap").glob(f"{trial}_*.mat"))), squeeze_me=True))


def broad_npz(trial: str) -> dict[str, np.ndarray]:
    """A BROAD trial in the ``.npz`` form (see the module docstring)."""
    m = _broad_mat(trial)
    cols = [np.asarray(m[k], dtype=float) for k in ("imu_gyr", "imu_acc", "opt_quat", "opt_pos")]
    ok = np.isfinite(np.hstack(cols)).all(axis=1)
    edges = np.diff(np.r_[0, ok.astype(int), 0])
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    k = int(np.argmax(stops - starts))
    rows = slice(starts[k], stops[k])
    pos = cols[3][rows]
    v = savgol_filter(pos, 29, 2, deriv=1, delta=1.0 / BROAD_RATE_HZ, axis=0)
    q = cols[2][rows] / np.linalg.norm(cols[2][rows], axis=1, keepdims=True)
    return {
        "t_s": np.arange(starts[k], stops[k]) / BROAD_RATE_HZ,
        "gyro_rad_s": cols[0][rows], "accel_m_s2": cols[1][rows], "q_wxyz": q, "v_m_s": v,
        "p_m": pos - pos[0],
    }  # fmt: skip


def base_arrays(base: str) -> dict[str, np.ndarray]:
    """The base recording's arrays: a EuRoC ``.npz`` as it is, a BROAD trial converted (``broad_NN``; with
    ``:mocap120``, its reference as :func:`as_mocap120` writes it; with ``:moving``, from one second after
    its ``movement`` flag first rises, so that it opens moving)."""
    if base.startswith("broad_"):
        trial, *forms = base.removeprefix("broad_").split(":")
        if set(forms) - {"mocap120", "moving"}:
            raise SystemExit(f"{base}: unknown form (known: broad_NN[:mocap120][:moving])")
        a = broad_npz(trial)
        if "moving" in forms:
            moving = np.asarray(_broad_mat(trial)["movement"]).astype(bool)
            start = np.flatnonzero(moving)[0] / BROAD_RATE_HZ + 1.0
            keep = a["t_s"] >= start
            a = {k: v[keep] for k, v in a.items()}
            a["p_m"] = a["p_m"] - a["p_m"][0]
        return as_mocap120(a) if "mocap120" in forms else a
    if ":" in base:
        raise SystemExit(f"{base}: forms are for BROAD's trials (broad_NN[:mocap120][:moving])")
    with np.load(SHARED / f"{base}.npz") as z:
        return {k: np.asarray(z[k]) for k in z.files}


def as_mocap120(a: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``a`` with its reference as the published preprocessing of a 120 Hz motion capture writes one
    (Brossard et al.'s TUM-VI branch, ``mbrossar/denoise-imu-gyro``): the attitude slerped to 120 Hz and
    back to the readings' stamps, the positions linearly, the velocity a backward difference of the
    positions (its first row zero), the positions from the first; the readings within the capture's span."""
    t = a["t_s"]
    t_capture = np.arange(t[0], t[-1], 1.0 / 120.0)
    attitude = Rotation.from_quat(a["q_wxyz"][:, [1, 2, 3, 0]])
    captured = Slerp(t, attitude)(t_capture)
    inside = (t >= t_capture[0]) & (t <= t_capture[-1])
    t_in = t[inside]
    q = Slerp(t_capture, captured)(t_in).as_quat()[:, [3, 0, 1, 2]]
    p_capture = np.column_stack([np.interp(t_capture, t, a["p_m"][:, i]) for i in range(3)])
    p = np.column_stack([np.interp(t_in, t_capture, p_capture[:, i]) for i in range(3)])
    v = np.zeros_like(p)
    v[1:] = np.diff(p, axis=0) / np.diff(t_in)[:, None]
    return {
        "t_s": t_in, "gyro_rad_s": a["gyro_rad_s"][inside], "accel_m_s2": a["accel_m_s2"][inside],
        "q_wxyz": q, "v_m_s": v, "p_m": p - p[0],
    }  # fmt: skip


def delayed(x: np.ndarray, tau_s: float, dt: float) -> np.ndarray:
    """``x`` (n, 3) read ``tau_s`` late: band-limited, the ends mirrored against the wrap-around."""
    n = len(x)
    padded = np.concatenate([x[::-1], x, x[::-1]])
    f = np.fft.rfftfreq(len(padded), dt)
    shifted = np.fft.irfft(
        np.fft.rfft(padded, axis=0) * np.exp(-2j * np.pi * f * tau_s)[:, None], len(padded), axis=0
    )
    return np.asarray(shifted[n : 2 * n])


def added(case: str, a: dict[str, np.ndarray], seed: int = 0, scale: float = 1.0) -> dict[str, np.ndarray]:
    """The base's arrays with ``case`` added to the readings (see the module docstring), its size
    ``scale`` times the docstring's."""
    out = {k: v.astype(float) for k, v in a.items()}
    t, w, f = out["t_s"], out["gyro_rad_s"], out["accel_m_s2"]
    dt = float(np.median(np.diff(t)))
    rng = np.random.default_rng(seed)
    half = t >= t[0] + 0.5 * (t[-1] - t[0])
    wave = np.sin(2 * np.pi * (t - t[0]) / 37.0)
    if case == "gyro.time_offset":
        out["gyro_rad_s"] = delayed(w, scale * 5e-3, dt)
    elif case == "accel.time_offset":
        out["accel_m_s2"] = delayed(f, scale * 5e-3, dt)
    elif case == "gyro.scale_nonlinearity":
        k2 = scale * 0.005 / np.sqrt(np.mean(w**2, axis=0))
        out["gyro_rad_s"] = w + k2 * w * w
    elif case == "accel.scale_nonlinearity":
        out["accel_m_s2"] = f + scale * 2000e-6 / G * f * f
    elif case == "gyro.scale_asymmetry":
        out["gyro_rad_s"] = w + scale * 5000e-6 * np.abs(w)
    elif case == "accel.scale_asymmetry":
        out["accel_m_s2"] = f + scale * 2000e-6 * np.abs(f)
    elif case == "gyro.g2_sensitivity":
        g2 = scale * 0.05 * DEG / G**2 * rng.choice([-1.0, 1.0], (3, 3, 3))
        out["gyro_rad_s"] = w + np.einsum("ijk,nj,nk->ni", g2, f, f)
    elif case == "gyro.x sinusoid":
        out["gyro_rad_s"] = w + np.outer(scale * 0.3 * DEG * wave, [1.0, 0.0, 0.0])
    elif case == "gyro.y step":
        out["gyro_rad_s"] = w + np.outer(scale * 0.3 * DEG * half, [0.0, 1.0, 0.0])
    elif case == "accel.y sinusoid":
        out["accel_m_s2"] = f + np.outer(scale * 10 * MG * wave, [0.0, 1.0, 0.0])
    elif case == "accel.x step":
        out["accel_m_s2"] = f + np.outer(scale * 10 * MG * half, [1.0, 0.0, 0.0])
    elif case != "clean":
        raise ValueError(f"unknown case {case!r}")
    return out


def oracle_nats(root: Path, clean: str, name: str, case: str) -> float:
    """What a model that knew the added effect would gain on the withheld intervals, in nats: the
    effect's own contribution to the interval residuals (the modified recording's less the clean one's,
    both at the clean recording's baseline fit), less what the baseline's columns absorb, whitened by the
    clean recording's noise (the diagnosis's own interval geometry, :mod:`sins.unit_gap`: an oracle of
    observability, not an independent check). Below ``gap.SIGNIFICANT_NATS`` + ``gap.TIE_NATS`` (9) no
    diagnosis could name it with evidence to spare."""
    from sins import io
    from sins.unit_gap.fitter import SensorFit
    from sins.unit_gap.intervals import interval_residuals
    from sins.unit_gap.search import baseline_fit, withheld_intervals

    base_rec = io.read(dataset=f"cases/{clean}", root=root).beside_reference()
    rec = io.read(dataset=f"cases/{name}", root=root).beside_reference()
    fitted = baseline_fit(base_rec, 1.0)
    a, b = interval_residuals(base_rec, fitted.seed, 1.0), interval_residuals(rec, fitted.seed, 1.0)
    held = withheld_intervals(a.t_mid, 0.3)
    sensors = ("gyro", "accel") if case in OUTSIDE else (case.split(".")[0],)
    total = 0.0
    for sensor in sensors:
        columns = a.baseline(sensor, fitted.g_sensitivity)
        sf = SensorFit.of(a.residual[sensor], ~held, held, a.joined, columns)
        delta = b.residual[sensor] - a.residual[sensor]
        everything = np.ones(len(held), dtype=bool)
        w = SensorFit(delta, everything, held, a.joined, sf.phi, sf.theta, sf.sigma)
        _, left = w.solve(columns)
        total += 0.5 * float(np.sum(w.whiten(left)[held] ** 2))
    return total


def diagnose(root: Path, name: str, timeout_s: float) -> dict[str, Any]:
    """``sins gap --dataset cases/NAME --json`` in its own process, with ``root`` as the data root."""
    out = root / f"{name.replace('/', '_')}.json"
    env = {**os.environ, "SINS_DATA": str(root), "OMP_NUM_THREADS": "1"}
    started = time.perf_counter()
    done = subprocess.run(
        [str(ROOT / ".venv" / "bin" / "sins"), "gap", "--dataset", f"cases/{name}", "--json", str(out)],
        env=env, capture_output=True, text=True, timeout=timeout_s, check=False,
    )  # fmt: skip
    wall = time.perf_counter() - started
    if done.returncode != 0:
        return {
            "error": done.stderr.strip().splitlines()[-1] if done.stderr.strip() else "failed",
            "wall_s": wall,
        }
    report = json.loads(out.read_text())
    return {
        "diagnosis": report["diagnosis"], "unexplained": report["unexplained"],
        "outside": [(o["channel"], o["kind"]) for o in report["outside"]],
        "statistic": report.get("statistic", {}).get("kind"), "wall_s": wall,
        "sizes": report.get("sizes", {}),
        "tied": sorted({t for e in report["effects"] if e.get("accepted")
                        for t in e.get("indistinguishable_from", [])}),
    }  # fmt: skip


def run_base(
    base: str, cases: list[str], root: Path, jobs: int, timeout_s: float, scale: float = 1.0
) -> list[dict[str, Any]]:
    """Every case of one base, written and diagnosed; the clean base first; each effect ``scale`` times
    its size."""
    arrays = base_arrays(base)
    folder = root / "cases"
    folder.mkdir(parents=True, exist_ok=True)
    tag = base.replace("/", "_").replace(":", "_")
    names = []
    for case in ["clean", *cases]:
        name = f"{tag}__{case.replace(' ', '_')}"
        np.savez(folder / f"{name}.npz", **added(case, arrays, scale=scale))  # type: ignore[arg-type]
        names.append((case, name))
    with ThreadPoolExecutor(jobs) as pool:
        results = list(pool.map(lambda cn: diagnose(root, cn[1], timeout_s), names))
    rows = []
    clean = results[0]
    for (case, name), result in zip(names, results, strict=True):
        oracle = oracle_nats(root, names[0][1], name, case) if case != "clean" else float("nan")
        rows.append({
            "base": base, "case": case, **result, "oracle": oracle, "passed": judged(case, result, clean),
            "passed_or_tied": judged(case, result, clean, tied=True),
        })  # fmt: skip
    return rows


def judged(case: str, result: dict[str, Any], clean: dict[str, Any], tied: bool = False) -> bool | None:
    """A library case: its effect diagnosed, and not in the base's diagnosis; a disturbance: its channel
    named in ``outside``; the base itself: None. With ``tied``, an effect the report lists as
    indistinguishable from one it accepts counts as named (in the case and in the base alike)."""
    if case == "clean" or "error" in result:
        return None if case == "clean" else False
    if case in OUTSIDE:
        return any(ch == OUTSIDE[case] for ch, _ in result["outside"])

    def named(r: dict[str, Any]) -> list[str]:
        return [*r.get("diagnosis", []), *(r.get("tied", []) if tied else [])]

    return case in named(result) and case not in named(clean)


def summary(rows: list[dict[str, Any]]) -> None:
    """The table and the totals."""
    print(f"{'base':<20} {'case':<25} {'stat':<9} {'oracle':>7} {'pass':<4} {'s':>4}  diagnosis | outside")
    for r in rows:
        mark = {True: "yes", False: "NO", None: "-"}[r["passed"]]
        what = r.get("error") or (", ".join(r["diagnosis"]) or "nothing")
        outside = ", ".join(f"{c} {k}" for c, k in r.get("outside", []))
        oracle = f"{r.get('oracle', float('nan')):7.0f}"
        stat = r.get("statistic") or "-"
        head = f"{r['base']:<20} {r['case']:<25} {stat:<9} {oracle} {mark:<4} {r['wall_s']:4.0f}"
        print(f"{head}  {what} | {outside}")
    for label, bases in (("developed on", DEVELOP), ("kept for judging", JUDGE), ("all", None)):
        chosen = [r for r in rows if bases is None or r["base"] in bases]
        lib = [r for r in chosen if r["case"] in LIBRARY]
        seen = [r for r in lib if r.get("oracle", 0.0) >= OBSERVABLE_NATS]
        out = [r for r in chosen if r["case"] in OUTSIDE]
        if lib or out:
            print(
                f"{label}: library effects named beyond the base's diagnosis {_passes(lib)} of {len(lib)} "
                f"({_passes(seen)} of the {len(seen)} observable; named or listed as indistinguishable from "
                f"one named {_passes(lib, 'passed_or_tied')} and {_passes(seen, 'passed_or_tied')}); "
                f"outside disturbances flagged on their channel {_passes(out)} of {len(out)}"
            )


def _passes(rows: list[dict[str, Any]], key: str = "passed") -> int:
    return sum(bool(r.get(key)) for r in rows)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bases", nargs="+", default=[*DEVELOP, *JUDGE])
    p.add_argument(
        "--effects", nargs="+", default=[*LIBRARY, *OUTSIDE], help="cases (effect names or disturbances)"
    )
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--scale", type=float, default=1.0, help="every effect this many times its size")
    p.add_argument("--timeout-s", type=float, default=600.0)
    p.add_argument("--root", type=Path, help="the temporary data root (default: a new temporary folder)")
    p.add_argument("--save", type=Path)
    p.add_argument("--load", type=Path)
    args = p.parse_args()
    if args.load:
        summary(json.loads(args.load.read_text()))
        return 0
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="sins-gap-cases-") as tmp:
        root = args.root or Path(tmp)
        for base in args.bases:
            rows += run_base(base, args.effects, root, args.jobs, args.timeout_s, args.scale)
            print(f"done {base}", file=sys.stderr)
    if args.save:
        args.save.write_text(json.dumps(rows, indent=1))
    summary(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
