"""Benchmark of the compensation strategies' cost: fitting on about 100,000 samples, correcting an hour; fit
time against the rows; fitting and judging on real recordings.

Usage::

    .venv/bin/python tools/bench_compensation.py [--repeat 3] [--threads N] [--strategies ...]
    .venv/bin/python tools/bench_compensation.py --scaling [--rows 50000 150000 500000] [--strategies mlp]
    .venv/bin/python tools/bench_compensation.py --real [--strategies mlp kohonen ...]
    .venv/bin/python tools/bench_compensation.py --jobs 1 2 [--repeat 3] [--strategies mlp kohonen]

The fitting session is another tool's procedure (``tests/numpy_rigs.py``, numpy alone):
46 random orientations and a table to 250 °/s in seven mounts, 10 -> 40 °C, 100 Hz,
about 100,000 rows, of the issue's baseline unit with a gyro scale nonlinearity
(so that the learners have something to learn). Prints per strategy the median fit
time and the median time to correct one hour of 100 Hz readings (360,000 rows, rate
form, with temperature), over ``--repeat`` runs.

``--scaling``: the procedure with 15 orientations (50,200 rows), run as many times over as makes about
``--rows`` rows (other orientations each time, the chamber cycling 10 -> 40 °C each run, one unit), so
that every size is made alike; per size the median fit time (wall, and this process's CPU time, which a
busy machine inflates far less) and the exponent of a least-squares line through log time against log
rows (1: time linear in the rows).

``--jobs``: the learned residual strategies' fit on the fitting session with each number of
cross-validation threads (``n_jobs``), alternated, ``--repeat`` times: median wall and CPU time per
setting (what the default is chosen by), and whether the fitted models are the same.

``--real``: each strategy fitted by :func:`sins.compensation.referenced.fit` (intervals of 1 s) on BROAD
trial 05 and
judged on trial 18 (open-loop attitude), and on the PSINS drive's first 70 s, judged on its last 30 s
(free-inertial drive); the data root is ``../shared/data`` (``SINS_DATA`` overrides it).
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import numpy_rigs

from sins import compensation, io
from sins.core.series import CalibrationData

STRATEGIES = ("regression", "regression_robust", "regression_extended", "mlp", "kohonen", "mlp_pure",
              "kohonen_pure")  # fmt: skip
REAL = ("regression_extended", "mlp", "kohonen", "mlp_pure", "mlp_seed", "kohonen_pure")
#: Orientations of one run of the procedure in ``--scaling`` (50,200 rows).
_SCALING_HOLDS = 15


def session(holds: int = 46, runs: int = 1) -> tuple[CalibrationData, Any]:
    """The fitting session, ``runs`` runs of the procedure with ``holds`` orientations each, and the
    readings' temperatures (for correcting)."""
    rng = np.random.default_rng(0)
    unit = dataclasses.replace(numpy_rigs.baseline_unit(rng), gyro_k2=np.array([0.0, 2e-5, 0.0]))
    parts = [
        numpy_rigs.tumble_and_table(rate_hz=100.0, seed=k, holds=holds, hold_s=12.0) for k in range(runs)
    ]
    t = np.concatenate([p.t + k * (p.t[-1] + 0.01) for k, p in enumerate(parts)])
    w, f, temp = (
        np.concatenate([getattr(p, name) for p in parts]) for name in ("ref_gyro", "ref_accel", "temp")
    )
    gyro, accel = unit.read(w, f, temp, 100.0, rng)
    return CalibrationData(t, gyro, accel, w, f, temp), temp


def timed(call: Callable[[], Any]) -> tuple[float, float, Any]:
    """Wall and process CPU seconds of ``call()``, and what it returned."""
    wall, cpu = time.perf_counter(), time.process_time()
    out = call()
    return time.perf_counter() - wall, time.process_time() - cpu, out


def cost(strategies: list[str], repeat: int) -> None:
    """Median fit time on the 46-orientation session and time to correct an hour."""
    import torch

    data, temp = session()
    hour = 360_000
    index = np.arange(hour) % len(data)
    print(f"{len(data)} fitting rows; correcting {hour} rows; torch threads {torch.get_num_threads()}")
    for name in strategies:
        fit_s, correct_s = [], []
        for _ in range(repeat):
            strategy = compensation.make(name)
            fit_s.append(timed(lambda st=strategy: st.fit(data))[0])
            correct_s.append(
                timed(lambda st=strategy: st.correct(data.gyro[index], data.accel[index], temp[index]))[0]
            )
        print(
            f"{name:<20} fit median {statistics.median(fit_s):7.2f} s (min {min(fit_s):.2f}, max "
            f"{max(fit_s):.2f})   correct 1 h median {statistics.median(correct_s):6.3f} s"
        )


def jobs(strategies: list[str], settings: list[int], repeat: int) -> None:
    """Median fit time, wall and CPU, of each strategy with each number of cross-validation threads."""
    import json

    data, _ = session()
    print(f"{len(data)} fitting rows; n_jobs {settings}, alternated, {repeat} times")
    for name in strategies:
        runs: dict[int, list[tuple[float, float, str]]] = {n: [] for n in settings}
        for _ in range(repeat):
            for n in settings:
                strategy = compensation.make(name, n_jobs=n)
                wall, cpu, fitted = timed(lambda st=strategy: st.fit(data))
                state = {k: v for k, v in fitted.get_state().items() if k != "fit_seconds_"}
                runs[n].append((wall, cpu, json.dumps(state, sort_keys=True, default=str)))
        same = len({r[2] for rs in runs.values() for r in rs}) == 1
        for n, rs in runs.items():
            wall, cpu = statistics.median(r[0] for r in rs), statistics.median(r[1] for r in rs)
            print(f"{name:<12} n_jobs {n}: fit median {wall:6.2f} s wall, {cpu:6.2f} s CPU")
        print(f"{name:<12} the models of every setting the same: {same}")


def scaling(strategies: list[str], rows: list[int], repeat: int) -> None:
    """Fit time against the rows, and the log-log exponent."""
    one = len(session(_SCALING_HOLDS)[0])
    sizes = [max(1, round(n / one)) for n in rows]
    sessions = [session(_SCALING_HOLDS, k)[0] for k in sizes]
    print("rows: " + ", ".join(f"{len(d)} ({k} runs)" for d, k in zip(sessions, sizes, strict=True)))
    for name in strategies:
        walls, cpus = [], []
        for data in sessions:
            runs = [timed(lambda d=data, n=name: compensation.make(n).fit(d)) for _ in range(repeat)]
            wall, cpu = statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs)
            walls.append(wall)
            cpus.append(cpu)
            fitted = runs[-1][2]
            chosen = getattr(fitted, "configs_", "")
            print(f"{name:<12} {len(data):>8} rows  fit {wall:7.1f} s wall  {cpu:7.1f} s CPU  {chosen}")
        n = np.log([len(d) for d in sessions])
        print(
            f"{name:<12} exponent of fit time in the rows: wall {np.polyfit(n, np.log(walls), 1)[0]:.2f}, "
            f"CPU {np.polyfit(n, np.log(cpus), 1)[0]:.2f}"
        )


def real(strategies: list[str]) -> None:
    """Fit and judge on BROAD (05 -> 18) and on the PSINS drive (first 70 s -> last 30 s)."""
    from sins.compensation import judging, referenced
    from sins.errors import SinsInputError

    try:
        fit_on, judge_on = (
            io.read(dataset="broad_05").beside_reference(),
            io.read(dataset="broad_18").beside_reference(),
        )
        drive = io.read(dataset="psins_vehicle").beside_reference()
    except (SinsInputError, OSError) as exc:
        sys.exit(f"bench_compensation: the real recordings are not there ({exc})")
    print(f"BROAD 05: {len(fit_on.imu.t) - 1} steps; PSINS drive: {len(drive.imu.t) - 1} steps")
    start = drive.imu.t[0]
    first = judging.between(drive, start, start + 70.0)
    for name in strategies:
        wall_f, cpu_f, fitted = timed(lambda n=name: referenced.fit(n, fit_on, interval_s=1.0))
        wall_e, cpu_e, score = timed(lambda f=fitted: judging.open_loop_attitude(f.strategy, judge_on))
        wall_p, cpu_p, on_drive = timed(lambda n=name: referenced.fit(n, first, interval_s=1.0))
        errors = judging.drive_errors(on_drive.strategy, drive, start + 70.0, start + 100.0)
        print(
            f"{name:<20} BROAD fit {wall_f:6.1f} s ({cpu_f:5.1f} s CPU) + evaluate {wall_e:4.1f} s "
            f"({cpu_e:4.1f} s CPU): {score.total_deg:.2f}° on 18   PSINS fit {wall_p:6.1f} s ({cpu_p:5.1f} "
            f"s CPU): {errors.horizontal_final_m:.2f} m after 30 s"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--threads", type=int, default=0, help="torch threads (0: torch's default)")
    parser.add_argument("--strategies", nargs="+")
    parser.add_argument("--scaling", action="store_true", help="fit time against the rows")
    parser.add_argument("--rows", nargs="+", type=int, default=[50_000, 150_000, 500_000])
    parser.add_argument("--real", action="store_true", help="fit and judge on BROAD and the PSINS drive")
    parser.add_argument("--jobs", nargs="+", type=int, help="compare these numbers of fitting threads")
    args = parser.parse_args()
    import torch

    if args.threads:
        torch.set_num_threads(args.threads)
    if args.scaling:
        scaling(args.strategies or ["mlp", "kohonen"], args.rows, args.repeat)
    elif args.real:
        real(args.strategies or list(REAL))
    elif args.jobs:
        jobs(args.strategies or ["mlp", "kohonen"], args.jobs, args.repeat)
    else:
        cost(args.strategies or list(STRATEGIES), args.repeat)


if __name__ == "__main__":
    main()
