"""The ``sins`` command: a thin layer over :mod:`sins.pipeline`.

Bad input ends in one line on stderr (``sins: error: …``) and exit status 2;
never a traceback.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from sins import __version__
from sins.errors import MissingInputError, SinsInputError
from sins.nav.vertical import VERTICAL_MODES

#: The object ``add_subparsers`` returns, to which each subcommand adds its parser.
_Subparsers = argparse._SubParsersAction

_COLUMNS = (
    ("final N m", "final_north_m", "{:.3f}"),
    ("final E m", "final_east_m", "{:.3f}"),
    ("final D m", "final_down_m", "{:.3f}"),
    ("final hor m", "final_horizontal_m", "{:.3f}"),
    ("max hor m", "max_horizontal_m", "{:.3f}"),
    ("roll °", "final_roll_deg", "{:.4f}"),
    ("pitch °", "final_pitch_deg", "{:.4f}"),
    ("yaw °", "final_yaw_deg", "{:.4f}"),
    ("m/h", "drift_rate_m_per_h", "{:.3f}"),
    ("nmi/h", "drift_rate_nmi_per_h", "{:.4f}"),
)


def _fixed_width(head: list[str], rows: list[list[str]]) -> str:
    """Columns padded to their widest cell: the first left-aligned, the rest right-aligned."""
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]

    def line(cells: list[str]) -> str:
        return "  ".join(
            c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(cells, widths, strict=True))
        )

    return "\n".join(line(r) for r in [head, *rows])


def format_table(summaries: dict[str, dict[str, Any]]) -> str:
    """A fixed-width table: one row per strategy, the headline errors as columns."""
    head = ["strategy"] + [c[0] for c in _COLUMNS]
    rows = [[name] + [fmt.format(s[key]) for _, key, fmt in _COLUMNS] for name, s in summaries.items()]
    return _fixed_width(head, rows)


def _cmd_run(args: argparse.Namespace) -> int:
    from sins import io, pipeline, scenario

    _check_viewer_args(args)
    path = pipeline.resolve_scenario(args.scenario)
    sc = scenario.load(path)
    _check_scenario_size(sc, path, "running")
    try:
        result = pipeline.run_scenario(sc)
    except ValueError as exc:  # a rig session that cannot be fitted, say
        if isinstance(exc, SinsInputError):
            raise
        raise SinsInputError(f"{path}: {exc}") from None
    scenario.check_latitude(sc, result.truth)
    summaries: dict[str, dict[str, Any]] = {name: run.summary.to_dict() for name, run in result.runs.items()}
    for name, summary in summaries.items():
        _check_finite(summary, f"{path}: strategy {name}")
    n = result.samples
    imu_note = f", IMU {sc.imu_model.stem} (seed {sc.imu_seed})" if sc.imu_model else ", ideal IMU"
    report = [
        f"scenario {sc.name}: {sc.description or path}\n"
        f"{n} samples at {sc.rate_hz:g} Hz ({n / sc.rate_hz:g} s){imu_note}, vertical channel {sc.vertical}; "
        "errors are estimate - truth",
        format_table(summaries),
    ]
    residuals = {name: run.residual_rms for name, run in result.runs.items() if run.residual_rms is not None}
    if residuals:
        report.append("\nresidual sensor error on the rig data held back from the fit (RMS per sample)")
        report.append(format_residuals(residuals))
    aided, outages = _aided_json(result, path)
    if aided:
        grade = next(iter(result.aided.values())).filter_grade
        report.append(_aided_report(sc, aided, outages, grade))
    print("\n".join(report))
    for name, run in result.runs.items():
        if run.residual_rms is not None:
            summaries[name]["residual_rms"] = run.residual_rms
    if args.json:
        document: dict[str, Any] = {"scenario": _scenario_json(sc, path, n), "strategies": summaries}
        if aided:
            document |= {"aided": aided, "outages": outages}
        io.write_json(args.json, document)
    _show(args, result, "\n".join(report))
    return 0


#: Memory per sample of what the commands hold whole, bytes (each about 1.2-1.4 times what was measured
#: at 1e6 samples): ``sins simulate``'s truth and increments (430 measured), ``sins run``'s sample times
#: (8; the run itself streams in chunks), a rig session's readings and references (510 measured).
_SIMULATE_BYTES, _RUN_BYTES, _RIG_BYTES = 600, 8, 600
#: ... and an aided run's (``[gnss]``): truth, readings, the filter's solution and records held whole
#: (830 measured: 496 MB against the plain run's 197 MB at 360,000 samples).
_AIDED_BYTES = 1000


def _check_scenario_size(sc: Any, path: Path, what: str, outputs: dict[Path, int] | None = None) -> None:
    """Refuse up front a scenario whose arrays would not fit in memory, or whose CSVs (``{path:
    columns}``) would not fit on their disks; the message gives the size it would need."""
    from sins import scenario
    from sins.io import limits

    n = scenario.sample_count(sc)
    per_sample = _SIMULATE_BYTES if outputs else _RUN_BYTES
    if getattr(sc, "aiding", None) is not None:
        per_sample = max(per_sample, _AIDED_BYTES)
    span = f"{n:.4g} samples ({n / sc.rate_hz:.4g} s at {sc.rate_hz:g} Hz)"
    if outputs:
        limits.check_disk({p: limits.csv_bytes(n + 1, columns) for p, columns in outputs.items()}, path)
    limits.check_memory(n * per_sample, f"{what} {span}", path)
    if sc.compensation is not None:
        _check_rig_size(scenario.load_rig(sc.compensation.rig), sc.compensation.rig)


def _check_rig_size(rig: Any, path: Path, outputs: dict[Path, int] | None = None) -> None:
    """:func:`_check_scenario_size` for a rig session."""
    from sins import scenario
    from sins.io import limits

    rows = scenario.rig_rows(rig)
    if outputs:
        limits.check_disk({p: limits.csv_bytes(rows, columns) for p, columns in outputs.items()}, path)
    limits.check_memory(rows * _RIG_BYTES, f"a rig session of {rows:.4g} rows at {rig.rate_hz:g} Hz", path)


def _check_finite(values: dict[str, Any], where: str) -> None:
    """Refuse a result with a non-finite number rather than print it: the inputs took the computation
    beyond what floating point holds (readings near the physical limits, held for long)."""
    for key, value in values.items():
        if isinstance(value, float) and not math.isfinite(value):
            raise SinsInputError(
                f"{where}: {key} came out {value}; the inputs drive the computation beyond finite numbers "
                "(check the values they hold)"
            )


def _check_viewer_args(args: argparse.Namespace) -> None:
    """Refuse what cannot work before the run, not after it."""
    if not (args.rerun or args.spawn or args.serve):
        return
    from sins import viz

    if args.spawn and not viz.has_display():
        raise SinsInputError(
            f"--spawn: {viz.NO_DISPLAY}; use --rerun OUT.rrd to save a recording, "
            "or --serve for the web viewer"
        )
    if args.rerun:
        viz.check_rrd_path(args.rerun)


def _show(args: argparse.Namespace, result: Any, summary: str) -> None:
    """Hand the run to Rerun as the flags ask: save, spawn the native viewer, serve the web viewer."""
    if not (args.rerun or args.spawn or args.serve):
        return
    from sins import viz

    if args.rerun:
        viz.save(result, args.rerun, summary=summary)
        print(f"wrote {args.rerun} (open it with: rerun {args.rerun})")
    if args.spawn:
        viz.spawn(result, summary=summary)
    if args.serve:
        try:
            address = viz.serve(result, summary=summary, web_port=args.web_port)
        except SinsInputError as exc:
            raise SinsInputError(f"--serve: {exc}") from None
        print(f"serving the Rerun web viewer at {address}  (Ctrl-C stops)", flush=True)
        import time

        while True:  # the servers live as long as this process
            time.sleep(3600)


def _display_unit(channel: str) -> tuple[float, str]:
    """:func:`sins.imu.display_unit`, imported when a table needs it (the CLI starts without numpy)."""
    from sins.imu import display_unit

    return display_unit(channel)


def format_residuals(residuals: dict[str, dict[str, float]]) -> str:
    """Strategy × channel residual RMS (°/h, mg) and the mean ratio to the oracle's (nan without one)."""
    from sins.imu import CHANNELS as _CHANNELS

    head = ["strategy", *(f"{c} {_display_unit(c)[1]}" for c in _CHANNELS), "× oracle"]
    oracle = residuals.get("oracle")
    rows = []
    for name, ch in residuals.items():
        cells = [f"{ch[c] / _display_unit(c)[0]:.3f}" for c in _CHANNELS]
        # Over the channels the oracle leaves any error on (a noiseless channel's floor is 0).
        ratios = [ch[c] / oracle[c] for c in _CHANNELS if oracle and oracle[c] > 0]
        ratio = sum(ratios) / len(ratios) if ratios else float("nan")
        rows.append([name, *cells, f"{ratio:.3f}"])
    return _fixed_width(head, rows)


def _aided_json(
    result: Any, path: Path
) -> tuple[dict[str, dict[str, Any]], dict[str, list[dict[str, float]]]]:
    """The aided runs' summaries (with their fix counts) and their errors per outage, as JSON objects."""
    aided: dict[str, dict[str, Any]] = {}
    outages: dict[str, list[dict[str, float]]] = {}
    for name, run in result.aided.items():
        aided[name] = {**run.summary.to_dict(), "fixes": run.fixes, "rejected_fixes": run.rejected}
        if result.scenario.aiding.sigma_vel_mps is not None:
            aided[name]["rejected_velocity_fixes"] = run.velocity_rejected
        aided[name] |= {"alignment": run.alignment, "alignment_start_s": run.start_s}
        if run.alignment == "static":
            aided[name]["alignment_static_s"] = run.static_s
        if run.heading_sigma_deg is not None:
            aided[name]["alignment_heading_sigma_deg"] = run.heading_sigma_deg
        if run.restarts:
            aided[name]["filter_restarts_s"] = list(run.restarts)
        _check_finite(aided[name], f"{path}: aided strategy {name}")
        outages[name] = [
            {
                "start_s": o.start_s,
                "end_s": o.end_s,
                "final_horizontal_m": o.final_m,
                "max_horizontal_m": o.max_m,
            }
            for o in run.outages
        ]
    return aided, outages


def _aided_report(
    sc: Any, aided: dict[str, dict[str, Any]], outages: dict[str, list[dict[str, float]]], grade: str
) -> str:
    """The aided runs' table and, if any, the errors per outage."""
    a = sc.aiding
    start = _alignment_text(a, next(iter(aided.values())))
    columns: tuple[tuple[str, str, str], ...]
    columns = (("final hor m", "final_horizontal_m", "{:.3f}"), ("max hor m", "max_horizontal_m", "{:.3f}"),
               ("rms hor m", "rms_horizontal_m", "{:.3f}"), ("final D m", "final_down_m", "{:.3f}"),
               ("yaw °", "final_yaw_deg", "{:.4f}"), ("fixes", "fixes", "{:d}"),
               ("rejected", "rejected_fixes", "{:d}"))  # fmt: skip
    if a.sigma_vel_mps is not None:
        columns += (("rejected v", "rejected_velocity_fixes", "{:d}"),)
    head = ["strategy"] + [c[0] for c in columns]
    rows = [[name] + [fmt.format(s[key]) for _, key, fmt in columns] for name, s in aided.items()]
    text = [
        f"\naided by GNSS at {a.rate_hz:g} Hz ({len(a.outages)} outages), filter tuned to the {grade} grade, "
        f"started {start}",
        _fixed_width(head, rows),
    ]
    for name, s in aided.items():
        if s.get("filter_restarts_s"):
            times = ", ".join(f"{t:g}" for t in s["filter_restarts_s"])
            text.append(f"{name}: the filter diverged and started again from the fixes at {times} s")
    windows = [(name, o) for name, items in outages.items() for o in items]
    if windows:
        text.append("\nposition error per outage (horizontal, before the first fix after it)")
        rows = [[name, f"{o['start_s']:g}-{o['end_s']:g} s", f"{o['final_horizontal_m']:.3f}",
                 f"{o['max_horizontal_m']:.3f}"] for name, o in windows]  # fmt: skip
        text.append(_fixed_width(["strategy", "outage", "at end m", "max m"], rows))
    return "\n".join(text)


def _alignment_text(a: Any, run: dict[str, Any]) -> str:
    """How the aided runs started (the alignment that ran), for the report's heading line."""
    if run["alignment"] == "static":
        where = " (heading from elsewhere)" if a.heading_sigma_rad is not None else ""
        return f"aligned over the first {run['alignment_static_s']:g} s{where}"
    if run["alignment"] == "gnss_velocity":
        return (
            f"aligned in motion at {run['alignment_start_s']:g} s, heading from the GNSS velocity "
            f"(1σ {run['alignment_heading_sigma_deg']:.2f}°); errors from then"
        )
    return "from the truth's first state"


def _scenario_json(sc: Any, path: Path, n: int) -> dict[str, Any]:
    return {
        "name": sc.name,
        "file": str(path),
        "rate_hz": sc.rate_hz,
        "samples": n,
        "duration_s": n / sc.rate_hz,
        "vertical": sc.vertical,
    }


def _cmd_integrate(args: argparse.Namespace) -> int:
    from sins import io, pipeline

    run = pipeline.integrate_recording(args.imu, args.truth, args.vertical, args.vertical_tau_s)
    summary = run.summary.to_dict()
    _check_finite(summary, f"{args.imu}: against {args.truth}")
    print(
        f"{args.imu}: {len(run.solution.t) - 1} intervals against {args.truth}; errors are estimate - truth"
    )
    print(format_table({"none": summary}))
    if args.json:
        io.write_json(args.json, {"imu": str(args.imu), "truth": str(args.truth), **summary})
    return 0


def _cmd_simulate(args: argparse.Namespace) -> int:
    from sins import io, pipeline, scenario
    from sins.nav import trajectory

    path = pipeline.resolve_scenario(args.scenario)
    sc = scenario.load(path)
    columns = len(io.RATE_COLUMNS if args.form == "rate" else io.INCREMENT_COLUMNS)
    _check_scenario_size(sc, path, "simulating", {args.imu: columns, args.truth: len(io.TRUTH_COLUMNS)})
    truth, imu = pipeline.simulate(sc)
    scenario.check_latitude(sc, truth)
    note = f"sins {__version__}: ideal IMU of scenario {sc.name} ({path})"
    samples = trajectory.ideal_rates(scenario.build_motion(sc), truth) if args.form == "rate" else imu
    with _progress_bar(f"writing {args.imu}", "row") as bar:
        io.write_imu(args.imu, samples, comment=note, progress=_row_progress(bar))
    with _progress_bar(f"writing {args.truth}", "row") as bar:
        io.write_truth(args.truth, truth, comment=note, progress=_row_progress(bar))
    print(f"wrote {args.imu} ({args.form} form, {len(samples)} rows) and {args.truth} ({len(truth)} rows)")
    return 0


def _cmd_scenarios(args: argparse.Namespace) -> int:
    from sins import pipeline, scenario

    shipped = scenario.presets()
    width = max(map(len, shipped), default=0)
    for name, path in shipped.items():
        sc = scenario.load(path)
        marker = " (default)" if name == pipeline.DEFAULT_SCENARIO else ""
        print(f"{name:<{width}}  {sc.description}{marker}")
    print(f"rig procedures (sins calibrate RIG): {', '.join(scenario.presets('rig'))}")
    print(f"IMU models (--imu): {', '.join(scenario.presets('imu'))}")
    print(f"campaigns (sins campaign NAME): {', '.join(scenario.presets('campaign'))}")
    return 0


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from sins import io, scenario
    from sins.imu import calibration

    rig_path = scenario.resolve_preset(args.rig, "rig")
    rig = scenario.load_rig(rig_path)
    spec = scenario.load_imu(scenario.resolve_preset(args.imu, "imu"))
    _check_rig_size(rig, rig_path, {args.out: len(io.RECORDING_COLUMNS) + 2})
    data = calibration.simulate_rig(rig, spec.model(run_seed=args.seed), seed=args.seed)
    note = (
        f"sins {__version__}: simulated rig {args.rig} with IMU {args.imu}, seed {args.seed}\n"
        f"effects: {', '.join(spec.model(run_seed=args.seed).names) or 'none'}"
    )
    with _progress_bar(f"writing {args.out}", "row") as bar:
        io.write_recording(args.out, data, comment=note, progress=_row_progress(bar))
    print(
        f"wrote {args.out}: {len(data)} rows, {data.t[-1] - data.t[0]:.1f} s at {rig.rate_hz:g} Hz, "
        f"{len(data.phases)} phases"
    )
    return 0


def _cmd_effects(args: argparse.Namespace) -> int:
    from sins import imu
    from sins.imu import spec as imu_spec

    for name, spec in imu_spec.PARAMETERS.items():
        params = ", ".join(f"{p.key} [{p.unit}]" for p in spec.params)
        marker = "  (baseline)" if name in imu.BASELINE else ""
        print(f"{name:<26} {spec.description}{marker}\n{'':<26} {params}")
    return 0


def _cmd_fit(args: argparse.Namespace) -> int:
    from sins import compensation, io
    from sins.compensation.residual import ResidualStrategy

    data = io.read_recording(args.recording)
    io.check_recording_range(args.recording, data)
    if args.strategy == "oracle":
        raise SinsInputError(
            "the oracle knows a simulated unit's true model; it cannot be fitted to a recording"
        )
    if args.no_guard and args.strategy not in ("mlp", "kohonen"):
        raise SinsInputError(f"--no-guard: {args.strategy} has no guard (only mlp and kohonen do)")
    try:
        params = {"guard": False} if args.no_guard else {}
        strategy = compensation.make(args.strategy, **params)
        part = data
        if args.validation:
            part, _ = data.split(args.validation)
        with _progress_bar(f"fitting {args.strategy}", "training") as bar:
            if isinstance(strategy, ResidualStrategy) and bar is not None:
                strategy.progress = _row_progress(bar)
            strategy.fit(part)
    except ValueError as exc:
        raise SinsInputError(f"{args.recording}: {exc}") from None
    compensation.save(strategy, args.out)
    held = f" (the last {args.validation:g} of each phase held back)" if args.validation else ""
    print(f"fitted {args.strategy} on {len(part)} of {len(data)} rows of {args.recording}{held}")
    if isinstance(strategy, ResidualStrategy):
        print(
            f"chosen on {strategy.cv_folds_} folds of {strategy.blocks_} held-back blocks: "
            + "; ".join(f"{s} {_settings(c)}" for s, c in strategy.configs_.items())
        )
        print(strategy.guard_report())
    print(f"wrote {args.out}")
    return 0


@contextmanager
def _progress_bar(description: str, unit: str) -> Iterator[Any]:
    """A tqdm bar on a terminal (stderr), None otherwise: logs and CI get the plain result lines only."""
    if not sys.stderr.isatty():
        yield None
        return
    from tqdm import tqdm

    with tqdm(desc=description, unit=f" {unit}", leave=False, file=sys.stderr) as bar:
        yield bar


def _advance(bar: Any, done: int, total: int | None = None) -> None:
    if total is not None:
        bar.total = total
    bar.update(done - bar.n)


def _row_progress(bar: Any) -> Callable[[int, int], None] | None:
    """A ``progress(done, total)`` callback advancing ``bar``, or None without a bar."""
    if bar is None:
        return None
    return lambda done, total: _advance(bar, done, total)


def _settings(config: dict[str, Any]) -> str:
    return ", ".join(f"{k} {v}" for k, v in config.items())


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from sins import compensation, io

    strategy = compensation.load(args.model)
    data = io.read_recording(args.recording)
    io.check_recording_range(args.recording, data)
    if args.last:
        try:
            _, data = data.split(args.last)
        except ValueError as exc:
            raise SinsInputError(f"{args.recording}: {exc}") from None
    channels = compensation.residual_rms(strategy, data)
    for name, v in channels.items():
        _check_finite(v, f"{args.model} on {args.recording}: {name}")
    scope = f"the last {args.last:g} of each phase" if args.last else "the whole recording"
    print(f"{args.model} ({strategy.name}) on {args.recording}, {scope}: RMS of reading - reference")
    print(f"{'channel':<8} {'before':>12} {'after':>12}  unit")
    for name, v in channels.items():
        size, unit = _display_unit(name)
        print(f"{name:<8} {v['rms_before'] / size:12.4f} {v['rms_after'] / size:12.4f}  {unit}")
    if args.json:
        io.write_json(
            args.json, {"model": str(args.model), "recording": str(args.recording), "channels": channels}
        )
    return 0


def _cmd_gap(args: argparse.Namespace) -> int:
    from sins import gap, io, pipeline

    if args.rerun:
        from sins import viz

        viz.check_rrd_path(args.rerun)
    data, truth, model = _gap_inputs(args)
    with _progress_bar("diagnosing", "candidate") as bar:

        def progress(name: str) -> None:
            assert bar is not None  # passed only when there is a bar
            bar.set_postfix_str(name)
            _advance(bar, bar.n + 1)

        report = gap.diagnose(data, args.holdout, model, progress if bar is not None else None)
    _print_gap_report(args, data, report)
    document = {"recording": str(args.recording), **report.to_dict()}
    if truth is not None and not report.unreferenced:
        nav = pipeline.gap_navigation(data, truth, report)
        print(
            "\nnavigation over the recording (vertical held to the truth), final horizontal error:\n"
            f"  real unit {nav['real_m']:.3f} m; simulated unit {nav['simulated_before_m']:.3f} m with the "
            f"model, {nav['simulated_after_m']:.3f} m with the accepted effects\n"
            f"  simulated against real at the end: {nav['sim_to_real_before_m']:.3f} m before, "
            f"{nav['sim_to_real_after_m']:.3f} m after"
        )
        document["navigation"] = nav
    if args.json:
        io.write_json(args.json, document)
    if args.rerun:
        viz.save_gap(report, args.rerun)
        print(f"wrote {args.rerun}")
    return 0


def _gap_inputs(args: argparse.Namespace) -> tuple[Any, Any, tuple[str, ...]]:
    """``sins gap``'s recording (a file, or a dataset by name), its truth if any, and the model's effects."""
    from sins import imu, io, pipeline, scenario

    if (args.recording is None) == (args.dataset is None):
        raise SinsInputError("gap: give a RECORDING.csv or --dataset NAME (one of them)")
    if not 0.0 < args.holdout < 1.0:
        raise SinsInputError(f"--holdout must be in (0, 1), got {args.holdout}")
    if args.dataset is not None:
        from sins.io import datasets

        if args.truth is not None:
            raise SinsInputError("gap: --truth goes with a RECORDING.csv, not with --dataset")
        data, truth = datasets.load_with_truth(args.dataset)
        args.recording = args.dataset
    else:
        data, truth = pipeline.gap_data(args.recording, args.truth)
        if args.truth is None:
            io.check_recording_range(args.recording, data)
    model: tuple[str, ...] = imu.BASELINE
    if args.model:
        spec = scenario.load_imu(scenario.resolve_preset(args.model, "imu"))
        model = tuple(e.name for e in spec.model().effects)
    return data, truth, model


def _print_gap_report(args: argparse.Namespace, data: Any, report: Any) -> None:
    """The report as ``sins gap`` prints it: the rows, the residuals against the floor, where the gap
    is, the candidates, the diagnosis and what is left unexplained."""
    from sins import gap

    _, held_rows = report.rows
    skipped = (
        f" ({report.unreferenced} without a per-sample reference left out)" if report.unreferenced else ""
    )
    print(f"{args.recording}: {len(data)} rows{skipped}, {held_rows} withheld: {report.withholding}")
    print(f"model: {', '.join(report.model)}")
    head = ["channel", "unit", "before", "after", "noise floor", "before/floor", "after/floor"]
    rows = []
    for ch, v in report.channels.items():
        size, unit = _display_unit(ch)
        rows.append([
            ch, unit, f"{v['rms_before'] / size:.4f}", f"{v['rms_after'] / size:.4f}",
            f"{v['noise_floor'] / size:.4f}", f"{v['rms_before'] / v['noise_floor']:.3f}",
            f"{v['rms_after'] / v['noise_floor']:.3f}",
        ])  # fmt: skip
    print("RMS of reading - model on the withheld rows")
    print(_fixed_width(head, rows))
    if report.where:
        print("\nwhere the gap is (channels above their noise floor, largest first):")
        for w in report.where:
            print(f"  {w['channel']}: {w['excess']:.3f}x the floor; " + ("; ".join(w["concentrates"]) or "-"))
    else:
        print("\nno channel is significantly above its noise floor: the model explains the data")
    threshold = f"{gap.SIGNIFICANT_NATS:.1f} nats"
    print(f"\ncandidate effects (withheld log-likelihood gain less {threshold}, and a random bias's")
    print("allowance; the best above 0 is accepted, then the rest are scored again beside it):")
    for e in report.effects[: args.top]:
        mark = "accepted" if e.accepted else ""
        if e.not_accepted_because:
            mark = f"not accepted: {e.not_accepted_because}"
        if e.indistinguishable:
            mark += f" (this data cannot tell it from {' or '.join(e.indistinguishable)})"
        print(f"  {e.name:<26} {e.score:14.1f}  {mark}")
    for name, why in report.unfitted.items():
        print(f"  {name:<26} {'not fitted':>14}  {why}")
    print(f"\ndiagnosis: {', '.join(report.diagnosis) or 'nothing to add'}")
    print(f"unexplained: {', '.join(report.unexplained) or 'none'}")
    for o in report.outside:
        print(f"  {o.channel}: {o.what()}, which no library effect explains as well")


def _characterise_inputs(args: argparse.Namespace) -> Any:
    """``sins characterise``'s residual: a dataset, a rig recording less its reference, an IMU recording
    less its trajectory's ideal readings, or a static unit's readings as they are."""
    import numpy as np

    from sins import characterise, io, pipeline
    from sins.series import ImuRates

    if (args.recording is None) == (args.dataset is None):
        raise SinsInputError("characterise: give a RECORDING.csv or --dataset NAME (one of them)")
    if args.static and args.truth is not None:
        raise SinsInputError("characterise: --static and --truth exclude each other")
    if args.dataset is not None:
        from sins.io import datasets

        if args.truth is not None or args.static:
            raise SinsInputError(
                "characterise: --truth and --static go with a RECORDING.csv, not with --dataset"
            )
        data, _ = datasets.load_with_truth(args.dataset)
        source = args.dataset
    elif args.truth is not None or any(c.startswith("ref_") for c in io.read_columns(args.recording)):
        data, _ = pipeline.gap_data(args.recording, args.truth)
        source = str(args.recording)
    elif args.static:
        samples, _ = io.read_imu(args.recording)
        if isinstance(samples, ImuRates):
            t, readings = samples.t, np.hstack([samples.omega_ib_b, samples.f_ib_b])
        else:
            dt = np.diff(samples.t)[:, None]
            t = 0.5 * (samples.t[:-1] + samples.t[1:])
            readings = np.hstack([samples.dtheta_b, samples.dv_b]) / dt
        return characterise.residual(t, readings, None, str(args.recording))
    else:
        raise MissingInputError(
            f"{args.recording}: no ref_ columns; a moving unit needs its trajectory, a static one --static",
            needs="truth",
        )
    readings = np.hstack([data.gyro, data.accel])
    reference = np.hstack([data.ref_gyro, data.ref_accel])
    return characterise.residual(data.t, readings, reference, source)


def _cmd_characterise(args: argparse.Namespace) -> int:
    from sins import characterise, io, scenario
    from sins.characterise import check, model_file

    if args.rerun:
        from sins import viz

        viz.check_rrd_path(args.rerun)
    res = _characterise_inputs(args)
    result = characterise.characterise(res)
    print(_format_characterisation(result))
    document = result.to_dict()
    model = None
    if args.out:
        model_file.write_model(args.out, result)
        model = scenario.load_imu(args.out).model()
        print(f"\nwrote {args.out} (noise only; sins run and sins calibrate --imu read it)")
    else:
        model = model_file.imu_model(result)
    closing = check.closing_check(result, model, seed=args.seed)
    print(_format_closing(closing))
    document["closing_check"] = closing.to_dict()
    if args.json:
        io.write_json(args.json, document)
    if args.rerun:
        viz.save_characterisation(result, closing, args.rerun)
        print(f"wrote {args.rerun}")
    return 0


def _format_characterisation(result: Any) -> str:
    """``sins characterise``'s table: each channel's IEEE terms in familiar units, ± 1σ, or what an
    unresolved term would need."""
    from sins.characterise import TERMS
    from sins.characterise.analysis import DISPLAY, display, duration
    from sins.characterise.terms import SYMBOLS

    head = [
        f"{result.source}: {result.rows} rows at {1.0 / result.dt:.6g} Hz in {len(result.segments)} "
        f"segment(s), the longest {duration(result.length_s)}",
        "IEEE Std 952/1293 terms fitted jointly to the overlapping Allan deviation (± 1σ); "
        "B is the Gauss–Markov bias's σ, T its correlation time",
    ]
    rows = []
    for ch, r in result.channels.items():
        for name in TERMS:
            t = r.fit.terms[name]
            unit = DISPLAY[r.sensor][name][1]
            if t.resolved:
                text = f"{display(r.sensor, name, t.value)} ± {display(r.sensor, name, t.sigma)}"
                support = f"τ {t.support_tau_s[0]:.3g}-{t.support_tau_s[-1]:.3g} s" if t.support_tau_s else ""
                if name == "bias_instability" and r.fit.tau_c_range_s:
                    lo, hi = r.fit.tau_c_range_s
                    support = f"T {r.fit.tau_c_s:.3g} s ({lo:.3g}-{hi:.3g}); " + support
                if name == "rate_ramp":
                    support += " (not simulated)"
            else:
                text = f"not resolved (< {display(r.sensor, name, t.upper)})"
                support = ""
                if t.needs_length_s:
                    support = f"needs ≥ {duration(t.needs_length_s)} of recording"
                elif t.needs_rate_hz:
                    support = f"needs sampling at ≥ {t.needs_rate_hz:.3g} Hz"
            rows.append([ch, SYMBOLS[name], text, unit, support])
        if r.fit.excluded_tau_s:
            taus = r.fit.excluded_tau_s
            rows.append(
                [ch, "", "model does not hold", "", f"τ {', '.join(f'{x:.3g}' for x in taus)} s left out"]
            )
    return "\n".join(head) + "\n" + _fixed_width(["channel", "term", "value", "unit", "support"], rows)


def _format_closing(closing: Any) -> str:
    """The closing check in words: where the simulated unit's Allan curves part from the real ones."""
    lines = [
        f"\nclosing check: the model simulated as long as the recording (seed {closing.seed}); curves part "
        f"where their ratio leaves the {100 * closing.confidence:g} % F interval"
    ]
    if not closing.partings:
        lines.append("  the simulated curves lie within the bands at every cluster time")
    lines += [f"  {p.what()}" for p in closing.partings]
    return "\n".join(lines)


def _cmd_campaign(args: argparse.Namespace) -> int:
    from sins import campaign
    from sins.campaign import engine, results

    if args.workers is not None and args.scheduler:
        raise SinsInputError("--workers: the scheduler's cluster has its own workers; give one of the two")
    from sins import scenario

    spec = campaign.load(scenario.resolve_preset(args.campaign, "campaign"))
    if args.rerun:
        from sins import viz

        viz.check_rrd_path(args.rerun)  # before the work, not after
    out = args.out or Path(f"{spec.name}-campaign")
    strategies = dict.fromkeys(["none", *spec.compensation.strategies])
    print(
        f"campaign {spec.name}: {spec.count} units x {len(spec.scenarios)} scenarios x "
        f"{len(strategies)} strategies -> {out}"
    )
    with _progress_bar(f"campaign {spec.name}", "unit") as bar:
        progress = _row_progress(bar) or engine.log_progress()
        done = engine.run(spec, out, args.workers, args.scheduler, args.resume, progress)
    resumed = f" ({done.units_resumed} already done)" if done.units_resumed else ""
    print(f"ran {done.units_run} units in {done.wall_s:.1f} s{resumed}")
    for line in results.table_lines(done.summary):
        print(line)
    written = f"{out / 'results.parquet'} and {out / 'summary.json'}"
    if args.rerun:
        import pyarrow.parquet as pq

        from sins import viz

        viz.save_campaign(pq.read_table(out / "results.parquet").to_pydict(), args.rerun)
        written = f"{out / 'results.parquet'}, {out / 'summary.json'} and {args.rerun}"
    print(f"wrote {written}")
    return 0


def _cmd_check(args: argparse.Namespace) -> int:
    from sins import quality, scenario
    from sins.campaign.spec import is_campaign

    path = Path(args.suite)
    if not path.exists() and scenario.find_preset(args.suite, "campaign") is not None:
        path = scenario.resolve_preset(args.suite, "campaign")
    if is_campaign(path):
        return _check_campaign(args, path)
    suite = quality.load_suite(path)
    if not args.update_baseline and not Path(args.baseline).exists():
        raise SinsInputError(f"{args.baseline}: no such quality baseline; create it with --update-baseline")
    if not args.update_baseline:
        baseline = quality.read_baseline(args.baseline)  # refuse early, before the runs
    measured = quality.measure(suite)
    if args.update_baseline:
        quality.write_baseline(args.baseline, measured, suite)
        count = sum(len(m) for s in measured.values() for m in s.values())
        print(f"wrote {args.baseline}: {count} metrics of {len(measured)} cases")
        return 0
    changes = quality.compare(baseline, measured, suite.tolerances)
    rows = []
    for c in changes:
        rel = "" if c.relative is None else f"{100 * c.relative:+.2f} %"
        fmt = lambda x: "-" if x is None else f"{x:.6g}"  # noqa: E731
        rows.append([f"{c.case}/{c.strategy}", c.metric, fmt(c.baseline), fmt(c.value), rel, c.verdict])
    print(_fixed_width(["case/strategy", "metric", "baseline", "now", "change", "verdict"], rows))
    bad = [c for c in changes if c.verdict in ("regressed", "missing")]
    tol = ", ".join(f"{k} {100 * v:g} %" for k, v in suite.tolerances.items())
    if bad:
        print(f"\n{len(bad)} of {len(changes)} metrics regressed or went missing (tolerances: {tol})")
        for c in bad:
            rel = "" if c.relative is None else f" by {100 * c.relative:+.2f} %"
            print(f"  {c.case}/{c.strategy} {c.metric}: {c.verdict}{rel}")
        return 1
    print(f"\nall {len(changes)} metrics hold (tolerances: {tol})")
    return 0


def _check_campaign(args: argparse.Namespace, path: Path) -> int:
    """``sins check`` on a campaign: its distributions against a baseline summary (sins.campaign.gate)."""
    import tempfile

    from sins import campaign, io
    from sins.campaign import engine, gate, results

    spec = campaign.load(path)
    if not args.update_baseline and not Path(args.baseline).exists():
        raise SinsInputError(f"{args.baseline}: no such campaign baseline; create it with --update-baseline")
    baseline = None if args.update_baseline else results.read_summary(args.baseline)  # refuse early
    with tempfile.TemporaryDirectory() as tmp, _progress_bar(f"campaign {spec.name}", "unit") as bar:
        done = engine.run(spec, Path(tmp) / "out", progress=_row_progress(bar))
    if baseline is None:
        io.write_json(args.baseline, gate.baseline_of(done.summary))
        print(f"wrote {args.baseline}: {len(done.summary['groups'])} groups of {spec.count} units")
        return 0
    checks = gate.compare(baseline, done.summary)
    rows = [
        [c.group, c.figure, c.test or "-", f"{c.median_ratio:.4g}", f"{c.p_value:.3g}", c.verdict]
        for c in checks
    ]
    print(_fixed_width(["scenario/strategy", "figure", "test", "median now/base", "p", "verdict"], rows))
    bad = [c for c in checks if c.verdict != "holds"]
    each = gate.FALSE_ALARM / max(1, len(checks))
    level = f"false-alarm rate {gate.FALSE_ALARM:g} over the {len(checks)} tests, each at {each:.2g}"
    if bad:
        print(f"\n{len(bad)} of {len(checks)} figures regressed or went missing ({level})")
        for c in bad:
            print(f"  {c.group} {c.figure}: {c.verdict} (p = {c.p_value:.3g}, median x{c.median_ratio:.4g})")
        return 1
    print(f"\nall {len(checks)} figures hold ({level})")
    return 0


def _positive(text: str) -> float:
    value = float(text)
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text}")
    return value


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {text}")
    return value


def _fraction(text: str) -> float:
    value = float(text)
    if not 0.0 < value < 1.0:
        raise argparse.ArgumentTypeError(f"must be a fraction in (0, 1), got {text}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The ``sins`` command's argument parser, one subcommand per action."""
    parser = argparse.ArgumentParser(prog="sins", description="Strapdown inertial navigation simulator.")
    parser.add_argument("--version", action="version", version=f"sins {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in _SUBCOMMANDS:
        add(sub)
    return parser


def _add_run(sub: _Subparsers) -> None:
    p = sub.add_parser("run", help="simulate a scenario, integrate it, print the drift summary")
    p.add_argument("scenario", nargs="?", help="scenario file or preset name (default: car_drive)")
    p.add_argument("--json", type=Path, metavar="OUT.json", help="also write the summary as JSON")
    p.add_argument("--rerun", type=Path, metavar="OUT.rrd", help="save the run as a Rerun recording")
    p.add_argument("--spawn", action="store_true", help="show the run in the native Rerun viewer")
    p.add_argument(
        "--serve", action="store_true",
        help="serve the run to the Rerun web viewer (prints the address; Ctrl-C stops)",
    )  # fmt: skip
    p.add_argument("--web-port", type=int, default=9090, help="port of --serve's web viewer (default 9090)")
    p.set_defaults(func=_cmd_run)


def _add_integrate(sub: _Subparsers) -> None:
    p = sub.add_parser("integrate", help="integrate a recorded IMU CSV against its truth CSV")
    p.add_argument("imu", type=Path, metavar="IMU.csv")
    p.add_argument("--truth", type=Path, required=True, metavar="TRUTH.csv")
    p.add_argument("--json", type=Path, metavar="OUT.json")
    p.add_argument(
        "--vertical",
        choices=VERTICAL_MODES,
        default="free",
        help="vertical channel: free inertial, held to, or damped towards the truth height",
    )
    p.add_argument(
        "--vertical-tau-s", type=_positive, default=10.0, help="time constant of 'damp', s (default 10)"
    )
    p.set_defaults(func=_cmd_integrate)


def _add_simulate(sub: _Subparsers) -> None:
    p = sub.add_parser("simulate", help="write a scenario's ideal IMU and truth as CSV")
    p.add_argument("scenario", nargs="?", help="scenario file or preset name (default: car_drive)")
    p.add_argument("--imu", type=Path, required=True, metavar="IMU.csv")
    p.add_argument("--truth", type=Path, required=True, metavar="TRUTH.csv")
    p.add_argument("--form", choices=("increment", "rate"), default="increment")
    p.set_defaults(func=_cmd_simulate)


def _add_calibrate(sub: _Subparsers) -> None:
    p = sub.add_parser("calibrate", help="simulate a calibration rig session and write the recording")
    p.add_argument("rig", metavar="RIG.toml", help="rig file or preset (e.g. 24pos_ratetable)")
    p.add_argument("--imu", required=True, metavar="IMU.toml", help="IMU file or preset (e.g. tactical)")
    p.add_argument("--out", type=Path, required=True, metavar="RECORDING.csv")
    p.add_argument("--seed", type=int, default=0, help="seeds the rig's errors and the IMU's run (default 0)")
    p.set_defaults(func=_cmd_calibrate)


def _add_fit(sub: _Subparsers) -> None:
    p = sub.add_parser("fit", help="fit a compensation strategy on a rig recording")
    p.add_argument("recording", type=Path, metavar="RECORDING.csv")
    p.add_argument(
        "--strategy", required=True,
        help="none, regression, regression_robust, regression_extended, mlp, kohonen "
        "(or the seed paper's mlp_pure, mlp_seed, kohonen_pure)",
    )  # fmt: skip
    p.add_argument(
        "--validation", type=_fraction, metavar="FRACTION",
        help="hold back the last FRACTION of every phase (of the whole recording if it has no phases)",
    )  # fmt: skip
    p.add_argument(
        "--no-guard", action="store_true",
        help="mlp, kohonen: use the learned correction on every channel, even where it does not beat "
        "regression on held-back blocks",
    )  # fmt: skip
    p.add_argument("--out", type=Path, required=True, metavar="MODEL.json")
    p.set_defaults(func=_cmd_fit)


def _add_evaluate(sub: _Subparsers) -> None:
    p = sub.add_parser("evaluate", help="RMS reading error per channel before and after a fitted model")
    p.add_argument("model", type=Path, metavar="MODEL.json")
    p.add_argument("recording", type=Path, metavar="RECORDING.csv")
    p.add_argument(
        "--last", type=_fraction, metavar="FRACTION",
        help="judge only the last FRACTION of every phase (of the whole recording if it has no phases)",
    )  # fmt: skip
    p.add_argument("--json", type=Path, metavar="OUT.json")
    p.set_defaults(func=_cmd_evaluate)


def _add_campaign(sub: _Subparsers) -> None:
    p = sub.add_parser(
        "campaign", help="Monte-Carlo campaign: units x scenarios x strategies, on a dask cluster"
    )
    p.add_argument("campaign", metavar="CAMPAIGN.toml", help="campaign file or preset (e.g. tactical_drives)")
    p.add_argument(
        "--workers",
        type=_count,
        metavar="N",
        help="processes of the local cluster (default: the machine's cores)",
    )
    p.add_argument("--scheduler", metavar="ADDRESS", help="run on an existing dask cluster (tcp://HOST:PORT)")
    p.add_argument("--out", type=Path, metavar="DIR", help="results folder (default: NAME-campaign)")
    p.add_argument("--resume", action="store_true", help="continue the campaign from what --out holds")
    p.add_argument(
        "--rerun", type=Path, metavar="OUT.rrd",
        help="log the spread: percentile bands of horizontal error over time, each unit's final error",
    )  # fmt: skip
    p.set_defaults(func=_cmd_campaign)


def _add_check(sub: _Subparsers) -> None:
    p = sub.add_parser(
        "check", help="the compensation-quality gate: a suite or a campaign against its baseline"
    )
    p.add_argument(
        "suite", metavar="SUITE.toml",
        help="a quality suite, or a campaign file or preset (its distributions gated: sins.campaign.gate)",
    )  # fmt: skip
    p.add_argument("--baseline", type=Path, required=True, metavar="BASELINE.json")
    p.add_argument(
        "--update-baseline", action="store_true", help="write the measured metrics as the baseline"
    )
    p.set_defaults(func=_cmd_check)


def _add_dataset(p: argparse.ArgumentParser) -> None:
    """``--dataset NAME`` (sins.io.datasets.NAMES, written out: importing the readers would slow every
    command's start)."""
    p.add_argument(
        "--dataset", metavar="NAME",
        help="a real dataset from the data root instead of a file: ferraris, psins_vehicle, psins_lasergyro, "
        "broad_05, broad_18",
    )  # fmt: skip


def _add_gap(sub: _Subparsers) -> None:
    p = sub.add_parser("gap", help="sim-to-real gap: where the model fails, which effect explains it")
    p.add_argument("recording", type=Path, nargs="?", metavar="RECORDING.csv")
    _add_dataset(p)
    p.add_argument("--truth", type=Path, metavar="TRUTH.csv", help="the trajectory of an IMU recording")
    p.add_argument("--model", metavar="MODEL.toml", help="the simulation's IMU model (default: the baseline)")
    p.add_argument(
        "--holdout", type=_fraction, default=0.3, metavar="FRACTION",
        help="withhold the last FRACTION of every phase (default 0.3); every verdict is judged on it",
    )  # fmt: skip
    p.add_argument(
        "--json", type=Path, metavar="REPORT.json",
        help="write the report: channels, where, effects, diagnosis, unexplained, outside, allan "
        "(and navigation, with a trajectory)",
    )  # fmt: skip
    p.add_argument(
        "--rerun", type=Path, metavar="OUT.rrd",
        help="log the residuals before and after, their Allan deviations and the excess by input quartile",
    )  # fmt: skip
    p.add_argument("--top", type=int, default=8, help="how many candidates to print (default 8)")
    p.set_defaults(func=_cmd_gap)


def _add_characterise(sub: _Subparsers) -> None:
    p = sub.add_parser(
        "characterise", help="Allan analysis of a recording: IEEE noise terms, an IMU file, the closing check"
    )
    p.add_argument("recording", type=Path, nargs="?", metavar="RECORDING.csv")
    _add_dataset(p)
    p.add_argument("--static", action="store_true", help="the unit stood still: its readings as they are")
    p.add_argument(
        "--truth", type=Path, metavar="TRUTH.csv", help="the trajectory of a moving unit's recording"
    )
    p.add_argument("--out", type=Path, metavar="IMU.toml", help="write the noise model as an IMU file")
    p.add_argument(
        "--json", type=Path, metavar="OUT.json", help="write the curves, terms and check (SI units)"
    )
    p.add_argument("--rerun", type=Path, metavar="OUT.rrd", help="log the real and simulated Allan curves")
    p.add_argument("--seed", type=int, default=0, help="the closing simulation's seed (default 0)")
    p.set_defaults(func=_cmd_characterise)


def _add_effects(sub: _Subparsers) -> None:
    p = sub.add_parser("effects", help="list the IMU error effects, their parameters and units")
    p.set_defaults(func=_cmd_effects)


def _add_scenarios(sub: _Subparsers) -> None:
    p = sub.add_parser("scenarios", help="list the preset scenarios shipped with sins")
    p.set_defaults(func=_cmd_scenarios)


#: Every subcommand, in the order ``sins --help`` lists them.
_SUBCOMMANDS: tuple[Callable[[_Subparsers], None], ...] = (
    _add_run,
    _add_integrate,
    _add_simulate,
    _add_calibrate,
    _add_fit,
    _add_evaluate,
    _add_check,
    _add_campaign,
    _add_gap,
    _add_characterise,
    _add_effects,
    _add_scenarios,
)

#: The flag that gives what a :class:`MissingInputError` says is missing.
_FLAG_FOR = {"truth": "--truth TRUTH.csv"}


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``sins`` command on ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args))
    except MissingInputError as exc:
        flag = _FLAG_FOR.get(exc.needs)
        print(f"sins: error: {exc}" + (f"; give it with {flag}" if flag else ""), file=sys.stderr)
        return 2
    except SinsInputError as exc:
        print(f"sins: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # The reader of our output went away (`sins scenarios | head`): nothing to say, and nothing more
        # to write to it; stdout is pointed at devnull so the interpreter's own flush at exit is quiet.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except OSError as exc:  # a full disk or a permission while writing
        print(f"sins: error: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("sins: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
