"""Cross-rig validation of the compensation strategies: fitted on one rig procedure, judged on others.

Usage::

    .venv/bin/python tools/bench_crossrig.py [--units 20] [--regimes seed gyro.scale_nonlinearity ...]
        [--strategies regression mlp kohonen ...] [--workers 2] [--drive-minutes 60] [--save OUT.json]
    .venv/bin/python tools/bench_crossrig.py --load OUT.json        # print a saved run's tables

Every unit is written by ``tests/numpy_rigs.py`` (numpy alone, not ``sins``): the
issue's baseline unit (0.05 °/s gyro bias, 2e-3 scale and misalignment, 0.02 °/s/g
g-sensitivity, 0.01 °/s and 1 mg white noise per sample at 100 Hz) plus, per regime,
one effect the seed model lacks on one channel drawn at random, sized so that its
RMS over the fitting session is 2.5-4x that channel's noise.

* Fitted on the independent "tumble and table" procedure (20 random orientations held
  6 s, a table about the vertical to 250 °/s in seven mounts, 10 -> 40 °C, 100 Hz;
  47,000 rows).
* Judged, per channel in units of the true white noise of the judged session, on:
  ``same`` (a second session of that procedure with fresh noise), ``sins_rig``
  (sins's 26-position tilted rig and rate table to 200 °/s, 25 -> 35 °C, 100 Hz),
  ``faces_200hz`` (six faces and a table about three mounts to 300 °/s, a 20 -> 35 °C
  soak, 200 Hz) and ``tumble_50hz`` (continuous tumbling to 200 °/s, 15-30 °C, 50 Hz);
  and by the final horizontal error of the ``car_drive`` preset (1 h, vertical channel
  damped, 15 -> 35 °C) driven with the unit's errors and fresh noise.

Prints per regime and strategy the mean over units of: the affected channel's
residual (× noise) on each judged procedure, the worst channel's, and the drift with
its ratio to regression's mean drift.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import numpy_rigs as ind

from sins import compensation, imu, scenario
from sins.core.series import CalibrationData, ImuIncrements
from sins.imu import calibration
from sins.nav import strapdown
from sins.nav.metrics import nav_errors, summarize
from sins.runs import pipeline

REGIMES = (
    "seed",
    "gyro.scale_nonlinearity",
    "accel.scale_nonlinearity",
    "gyro.scale_asymmetry",
    "accel.scale_asymmetry",
    "gyro.g2_sensitivity",
    "gyro.temperature_bias",
    "accel.temperature_bias",
    "gyro.temperature_scale",
    "accel.temperature_scale",
)
STRATEGIES = ("none", "regression", "regression_extended", "mlp", "kohonen", "mlp_pure", "kohonen_pure")
JUDGES = ("same", "sins_rig", "faces_200hz", "tumble_50hz")


def _effect_field(regime: str, axis: int, rng: np.random.Generator) -> tuple[str, Any]:
    """The Unit field of a regime's effect, with unit size on channel ``axis``."""
    sensor, kind = regime.split(".")
    if kind == "g2_sensitivity":
        g2 = np.zeros((3, 3, 3))
        m = rng.standard_normal((3, 3))
        g2[axis] = 0.5 * (m + m.T)
        return "gyro_g2", g2
    vec = np.zeros(3)
    vec[axis] = rng.choice([-1.0, 1.0])
    field = {"scale_nonlinearity": "k2", "scale_asymmetry": "ka", "temperature_bias": "tc1",
             "temperature_scale": "ts"}[kind]  # fmt: skip
    return f"{sensor}_{field}", vec


def draw_unit(regime: str, seed: int, fit: ind.Session) -> tuple[ind.Unit, int]:
    """The unit of ``regime`` number ``seed`` and its affected channel (0-5, or -1 for the seed model)."""
    rng = np.random.default_rng([seed, 2026])
    unit = ind.baseline_unit(rng)
    if regime == "seed":
        return unit, -1
    axis = int(rng.integers(3))
    name, value = _effect_field(regime, axis, rng)
    extra = {name: value}
    if name.endswith("tc1"):  # a temperature bias with some curvature: c2 = c1 / 15 °C
        extra[name.replace("tc1", "tc2")] = value / 15.0
    shape = ind.Unit(**extra)  # the effect alone, unit size
    errors = shape.errors(fit.ref_gyro, fit.ref_accel, fit.temp)
    channel = axis + (3 if regime.startswith("accel") else 0)
    effect = np.hstack(errors)[:, channel]
    density = unit.gyro_noise if channel < 3 else unit.accel_noise
    sigma = density * np.sqrt(fit.rate_hz)
    size = rng.uniform(2.5, 4.0) * sigma / float(np.sqrt(np.mean(effect**2)))
    scaled = {k: v * size for k, v in extra.items()}
    return dataclasses.replace(unit, **scaled), channel


def _recording(session: ind.Session, unit: ind.Unit, seed: int) -> CalibrationData:
    rng = np.random.default_rng([seed, 5])
    gyro, accel = unit.read(session.ref_gyro, session.ref_accel, session.temp, session.rate_hz, rng)
    return CalibrationData(
        t=session.t,
        gyro=gyro,
        accel=accel,
        ref_gyro=session.ref_gyro,
        ref_accel=session.ref_accel,
        temp=session.temp,
        source=session.name,
    )


def _sins_rig_session() -> ind.Session:
    """sins's own 26-position tilted rig and rate table, reference only (the unit is applied after)."""
    rig = calibration.RigProcedure(
        positions=26, position_dwell_s=8.0,
        rate_table=calibration.RateTable(rates_dps=(20.0, 100.0, 200.0), dwell_s=4.0),
        temperature=calibration.TemperatureProfile((0.0, 800.0), (25.0, 35.0)),
    )  # fmt: skip
    data = calibration.simulate_rig(rig, imu.ImuModel(), seed=0)
    assert data.temp is not None
    return ind.Session(t=data.t, ref_gyro=data.ref_gyro, ref_accel=data.ref_accel, temp=data.temp,
                       rate_hz=rig.rate_hz, name="sins_rig")  # fmt: skip


def _sessions() -> dict[str, ind.Session]:
    return {
        "fit": ind.tumble_and_table(rate_hz=100.0, seed=1, holds=20, hold_s=6.0),
        "same": ind.tumble_and_table(rate_hz=100.0, seed=1, holds=20, hold_s=6.0),
        "sins_rig": _sins_rig_session(),
        "faces_200hz": ind.faces_and_axis_table(rate_hz=200.0, seed=2, temp_profile="soak"),
        "tumble_50hz": ind.continuous_tumble(rate_hz=50.0, seed=3),
    }


_DRIVE: dict[str, Any] = {}


def _drive(minutes: float) -> dict[str, Any]:
    if not _DRIVE:
        sc = scenario.load(pipeline.resolve_scenario("car_drive"))
        truth, ideal = pipeline.simulate(sc)
        keep = ideal.t <= ideal.t[0] + 60.0 * minutes
        n = int(keep.sum())
        ideal = ImuIncrements(t=ideal.t[:n], dtheta_b=ideal.dtheta_b[: n - 1], dv_b=ideal.dv_b[: n - 1])
        truth = truth.interpolate(ideal.t)
        temp = np.interp(ideal.t, [ideal.t[0], ideal.t[-1]], [15.0, 35.0])
        _DRIVE.update(truth=truth, ideal=ideal, temp=temp)
    return _DRIVE


def _drive_errors(
    unit: ind.Unit, seed: int, fitted: dict[str, compensation.Strategy], minutes: float
) -> dict:
    d = _drive(minutes)
    ideal, truth, temp = d["ideal"], d["truth"], d["temp"]
    dt = np.diff(ideal.t)[:, None]
    mid = 0.5 * (temp[1:] + temp[:-1])
    rng = np.random.default_rng([seed, 77])
    gyro, accel = unit.read(ideal.dtheta_b / dt, ideal.dv_b / dt, mid, 1.0 / float(np.median(dt)), rng)
    corrupted = ImuIncrements(t=ideal.t, dtheta_b=gyro * dt, dv_b=accel * dt)
    start = strapdown.InitialState.from_series(truth.at(0))
    out = {}
    for name, strategy in fitted.items():
        corrected = strategy.correct_increments(corrupted, temp)
        sol = strapdown.integrate(corrected, start, vertical="damp", h_ref=truth.h)
        out[name] = summarize(nav_errors(sol, truth)).final_horizontal_m
    return out


def run_unit(task: tuple[str, int, tuple[str, ...], float]) -> dict[str, Any]:
    regime, seed, strategies, minutes = task
    import torch

    torch.set_num_threads(1)
    sessions = _sessions()
    unit, channel = draw_unit(regime, seed, sessions["fit"])
    fit_data = _recording(sessions["fit"], unit, seed)
    fitted, fit_s, guard = {}, {}, {}
    for name in strategies:
        started = time.perf_counter()
        fitted[name] = compensation.make(name).fit(fit_data)
        fit_s[name] = time.perf_counter() - started
        if hasattr(fitted[name], "used_"):
            guard[name] = [bool(u) for u in fitted[name].used_]
    residual: dict[str, dict[str, list[float]]] = {}
    for judge in JUDGES:
        session = sessions[judge]
        data = _recording(session, unit, 1000 + seed if judge == "same" else 2000 + seed)
        sigma = np.concatenate([unit.gyro_noise * np.ones(3), unit.accel_noise * np.ones(3)])
        sigma = sigma * np.sqrt(session.rate_hz)
        residual[judge] = {}
        for name, strategy in fitted.items():
            rms = compensation.residual_rms(strategy, data)
            residual[judge][name] = [v["rms_after"] / s for v, s in zip(rms.values(), sigma, strict=True)]
    drift = _drive_errors(unit, 3000 + seed, fitted, minutes) if minutes > 0 else {}
    return {"regime": regime, "seed": seed, "channel": channel, "residual": residual, "drift": drift,
            "fit_s": fit_s, "guard": guard, "fit_rows": len(fit_data)}  # fmt: skip


def _having(rows: list[dict[str, Any]], strategy: str) -> list[dict[str, Any]]:
    """The units a strategy was run on (a run may leave the slow pure variants out)."""
    return [c for c in rows if strategy in c["residual"]["same"]]


def _affected(c: dict[str, Any], judge: str, strategy: str) -> float:
    """The affected channel's residual × noise (the worst channel for a seed-model unit)."""
    r = c["residual"][judge][strategy]
    return float(r[c["channel"]] if c["channel"] >= 0 else max(r))


def _drift_ratio(rows: list[dict[str, Any]], strategy: str) -> float:
    """Mean 1-h drift over regression's mean on the same units."""
    rows = [c for c in _having(rows, strategy) if c["drift"]]
    if not rows:
        return float("nan")
    return float(
        np.mean([c["drift"][strategy] for c in rows]) / np.mean([c["drift"]["regression"] for c in rows])
    )


def _strategies(cases: list[dict[str, Any]]) -> list[str]:
    seen = {s for c in cases for s in c["residual"]["same"]}
    return [s for s in STRATEGIES if s in seen]


def summarise(cases: list[dict[str, Any]]) -> None:
    regimes = [r for r in REGIMES if any(c["regime"] == r for c in cases)]
    for regime in regimes:
        rows = [c for c in cases if c["regime"] == regime]
        print(f"\n{regime}: {len(rows)} units (affected channel: residual x noise per judged procedure; "
              "worst channel over all; 1-h drift; units, where a strategy ran on fewer)")  # fmt: skip
        head = " ".join(f"{j:>11}" for j in JUDGES)
        print(f"{'strategy':<20} {head} {'worst':>7} {'drift km':>9} {'/ regr.':>7} {'fit s':>6}")
        for s in _strategies(rows):
            mine = _having(rows, s)
            cells = [f"{np.mean([_affected(c, j, s) for c in mine]):11.3f}" for j in JUDGES]
            worst = max(max(c["residual"][j][s]) for c in mine for j in JUDGES)
            drift = np.mean([c["drift"][s] for c in mine]) if mine[0]["drift"] else np.nan
            fit_s = np.median([c["fit_s"][s] for c in mine])
            fewer = f" ({len(mine)} units)" if len(mine) != len(rows) else ""
            print(
                f"{s:<20} {' '.join(cells)} {worst:7.3f} {drift / 1e3:9.2f} {_drift_ratio(rows, s):7.3f} "
                f"{fit_s:6.1f}{fewer}"
            )


def markdown(cases: list[dict[str, Any]], strategies: tuple[str, ...] = STRATEGIES[1:]) -> None:
    """The README's two tables: per regime and strategy, the affected channel's residual × noise (mean over
    units) on the worst judged procedure, with the procedure's initial; and the mean 1-h drift over
    regression's on the same units. A strategy run on fewer units than the regime's count says how many."""
    regimes = [r for r in REGIMES if any(c["regime"] == r for c in cases)]
    head = "| regime | units | " + " | ".join(strategies) + " |"
    rule = "|---|---|" + "---|" * len(strategies)
    print("Residual × noise on the affected channel (seed: worst channel), worst judged procedure "
          "(s same, r sins rig, f faces, t tumble):\n")  # fmt: skip
    print(head + "\n" + rule)

    def fewer(rows: list[dict[str, Any]], s: str) -> str:
        n = len(_having(rows, s))
        return f" ({n})" if n != len(rows) else ""

    for regime in regimes:
        rows = [c for c in cases if c["regime"] == regime]
        cells = []
        for s in strategies:
            means = {j: float(np.mean([_affected(c, j, s) for c in _having(rows, s)])) for j in JUDGES}
            worst = max(means, key=means.__getitem__)
            cells.append(f"{means[worst]:.2f} {worst[0]}{fewer(rows, s)}")
        print(f"| {regime} | {len(rows)} | " + " | ".join(cells) + " |")
    print(
        "\n1-hour drive, mean final horizontal error over regression's on the same units "
        "(regression's in km):\n"
    )
    print(head + "\n" + rule)
    for regime in regimes:
        rows = [c for c in cases if c["regime"] == regime and c["drift"]]
        if not rows:
            continue
        ref = float(np.mean([c["drift"]["regression"] for c in rows]))
        cells = [
            f"{_drift_ratio(rows, s):.2f}{fewer(rows, s)}" if s != "regression" else f"1 ({ref / 1e3:.1f})"
            for s in strategies
        ]
        print(f"| {regime} | {len(rows)} | " + " | ".join(cells) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=20)
    parser.add_argument("--first-unit", type=int, default=0)
    parser.add_argument("--regimes", nargs="+", default=list(REGIMES), choices=REGIMES)
    parser.add_argument("--strategies", nargs="+", default=list(STRATEGIES))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--drive-minutes", type=float, default=60.0)
    parser.add_argument("--save", type=Path)
    parser.add_argument("--load", type=Path, nargs="+")
    parser.add_argument("--markdown", action="store_true", help="with --load: the README's tables")
    args = parser.parse_args()
    if args.load:
        cases = [c for path in args.load for c in json.loads(path.read_text())["cases"]]
        if args.markdown:
            markdown(cases, tuple(s for s in _strategies(cases) if s != "none"))
        else:
            summarise(cases)
        return
    # Unit by unit across the regimes, so that a run stopped early has every regime at a like count.
    tasks = [(r, s, tuple(args.strategies), args.drive_minutes)
             for s in range(args.first_unit, args.first_unit + args.units) for r in args.regimes]  # fmt: skip
    started = time.perf_counter()
    cases = []
    with ProcessPoolExecutor(args.workers) as pool:
        for i, case in enumerate(pool.map(run_unit, tasks), 1):
            cases.append(case)
            ch = case["channel"]
            aff = {s: case["residual"]["same"][s][ch] if ch >= 0 else max(case["residual"]["same"][s])
                   for s in args.strategies}  # fmt: skip
            elapsed = time.perf_counter() - started
            print(f"[{i}/{len(tasks)} {elapsed:.0f} s] {case['regime']} unit {case['seed']} "
                  + " ".join(f"{s}={v:.2f}" for s, v in aff.items()), flush=True)  # fmt: skip
            if args.save:
                tmp = args.save.with_suffix(".tmp")
                tmp.write_text(json.dumps({"format": "bench_crossrig", "cases": cases}))
                tmp.replace(args.save)
    summarise(cases)
    print(f"\n{len(tasks)} units in {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()
