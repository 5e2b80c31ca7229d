"""``sins characterise``: the Allan analysis of a recording, an IMU file of its terms, the closing check."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from sins.cli.common import Subparsers, check_outputs, check_plot, fixed_width, save_plot
from sins.cli.options import (
    add_dataset,
    add_plot,
    add_recording_options,
    dataset_inputs,
    read_recording,
    seed,
)
from sins.cli.progress import progress_bar, row_progress
from sins.errors import MissingInputError, SinsInputError

if TYPE_CHECKING:
    from sins.characterise.analysis import ChannelResult, Characterisation, Residual
    from sins.characterise.check import ClosingCheck


def _characterise_inputs(args: argparse.Namespace) -> Residual:
    """``sins characterise``'s residual: a dataset or a recording with a reference (the reference and the
    deterministic errors fitted against it taken away, or the still stretches alone where the reference
    is the noisier), or a static unit's readings as they are (refused if they move)."""
    import numpy as np

    from sins import characterise
    from sins.characterise import reference, still
    from sins.runs import pipeline

    if (args.recording is None) == (args.dataset is None):
        raise SinsInputError("characterise: give a RECORDING or --dataset NAME (one of them)")
    if args.static and args.truth is not None:
        raise SinsInputError("characterise: --static and --truth exclude each other")
    if args.dataset is not None:
        if args.truth is not None or args.static:
            raise SinsInputError("characterise: --truth and --static go with a RECORDING, not with --dataset")
        inputs = read_recording(args, None, args.dataset).reference_inputs()
        return reference.reference_residual(inputs[0], args.dataset)
    rec = read_recording(args, args.recording, None, args.truth)
    if args.static and rec.rig is not None:  # it had been ignored: the ref_ columns taken all the same
        raise SinsInputError(f"{args.recording}: --static, but its ref_ columns are its reference (drop it)")
    if args.truth is not None or rec.rig is not None:
        data, _ = pipeline.gap_data(rec)
        return reference.reference_residual(data, str(args.recording))
    if not args.static and rec.truth is not None:  # a recording with its own reference (.npz, EuRoC, a bag)
        from sins.io.recording import ideal_inputs

        data, _ = ideal_inputs(rec)
        return reference.reference_residual(data, str(args.recording))
    if not args.static:
        raise MissingInputError(
            f"{args.recording}: no ref_ columns; a moving unit needs its trajectory, a static one --static",
            needs="truth",
        )
    t, omega, force = rec.mean_rates()
    readings = np.hstack([omega, force])
    del omega, force
    moved = still.motion(t, readings)
    if moved is not None:
        raise SinsInputError(
            f"{args.recording}: --static, but the unit moves: {moved}; give its trajectory (--truth) or "
            "a recording with ref_ columns"
        )
    return characterise.residual(t, readings, None, str(args.recording))


def _cmd_characterise(args: argparse.Namespace) -> int:
    from sins import characterise, io
    from sins.characterise import check, model_file

    if args.rerun:
        from sins.viz import viewer as viz

        viz.check_rrd_path(args.rerun, "--rerun")
    check_plot(args)
    outputs = {"--out": args.out, "--json": args.json, "--rerun": args.rerun, "--plot": args.plot}
    read = [args.recording, args.truth, *dataset_inputs(args.dataset)]
    check_outputs(outputs, read, kinds={"--out": "toml"})
    with progress_bar("reading", "channels") as bar:
        res = _characterise_inputs(args)
        for line in res.warnings:
            print(f"sins: warning: {line}", file=sys.stderr)
        bar.set_description("characterising")
        result = characterise.characterise(res, progress=row_progress(bar))
    model = model_file.imu_model(result)  # refuses what the readers would refuse, before any output
    with progress_bar("closing check", "channels") as bar:
        closing = check.closing_check(result, model, seed=args.seed, progress=row_progress(bar))
    print(_format_characterisation(result))
    print(_format_closing(closing))
    document = result.to_dict()
    document["closing_check"] = closing.to_dict()
    if args.out:
        model_file.write_model(args.out, result)
        print(f"\nwrote {args.out} (noise only; sins run and sins calibrate --imu read it)")
    if args.json:
        io.write_report(args.json, document)
    if args.rerun:
        viz.save_characterisation(result, closing, args.rerun)
        print(f"wrote {args.rerun}")
    if args.plot:
        from sins.viz import plots

        save_plot(
            args.plot, lambda: plots.characterise_figure(result, closing), f"sins characterise {res.source}"
        )
    return 0


def _format_characterisation(result: Characterisation) -> str:
    """``sins characterise``'s table: each channel's IEEE terms in familiar units, ± 1σ, or what an
    unresolved term would need."""
    from sins.characterise import TERMS
    from sins.characterise.analysis import duration
    from sins.characterise.noise_terms import SYMBOLS

    head = [
        f"{result.source}: {result.rows} rows at {1.0 / result.dt:.6g} Hz in {len(result.segments)} "
        f"segment(s), the longest {duration(result.length_s)}",
        *(f"  {note}" for note in result.notes),
        "IEEE Std 952/1293 terms fitted jointly to the overlapping Allan deviation (± 1σ): B the bias "
        "instability (flicker, IEEE B), GM a Gauss–Markov bias (σ, correlation time T), R the rate ramp "
        "fitted to the rate itself",
    ]
    rows = []
    for ch, r in result.channels.items():
        rows += [[ch, SYMBOLS[name], *_cells(r, name)] for name in TERMS]
        if r.fit.excluded_tau_s:
            taus = r.fit.excluded_tau_s
            rows.append(
                [ch, "", "model does not hold", "", f"τ {', '.join(f'{x:.3g}' for x in taus)} s left out"]
            )
    return "\n".join(head) + "\n" + fixed_width(["channel", "term", "value", "unit", "support"], rows)


#: The support of a resolved term that holds half the Allan variance at no cluster time.
_NOWHERE_LEADING = "under half the variance at every τ; resolved by the joint fit"


def _cells(r: ChannelResult, name: str) -> list[str]:
    """One term's value, unit and support (or what it would need) in the table."""
    from sins.characterise.analysis import DISPLAY, UNBOUNDED, display, duration

    t = r.fit.terms[name]
    unit = DISPLAY[r.sensor][name][1]
    if not t.resolved and t.upper is None:
        return ["not resolved", unit, UNBOUNDED]
    if not t.resolved:
        support = ""
        if t.needs_length_s:
            support = f"needs a stretch of ≥ {duration(t.needs_length_s)}"  # the longest, not the whole
        elif t.needs_rate_hz:
            support = f"needs sampling at ≥ {t.needs_rate_hz:.3g} Hz"
        return [f"not resolved (< {display(r.sensor, name, t.upper)})", unit, support]
    text = f"{display(r.sensor, name, t.value)} ± {display(r.sensor, name, t.sigma)}"
    support = (  # a term may hold half the variance at no τ and still be resolved by the joint fit
        f"τ {t.support_tau_s[0]:.3g}-{t.support_tau_s[-1]:.3g} s" if t.support_tau_s else _NOWHERE_LEADING
    )
    if name == "gauss_markov" and r.fit.tau_c_range_s:
        lo, hi = r.fit.tau_c_range_s
        support = f"T {r.fit.tau_c_s:.3g} s ({lo:.3g}-{hi:.3g}); " + support
    if name == "rate_ramp":
        support = "taken out before the Allan analysis; not simulated"
    return [text, unit, support]


def _format_closing(closing: ClosingCheck) -> str:
    """The closing check in words: where the simulated unit's Allan curves part from the real ones."""
    lines = [
        f"\nclosing check: the model simulated as long as the recording (seed {closing.seed}); curves part "
        f"where their ratio leaves the {100 * closing.confidence:g} % F interval"
    ]
    if not closing.partings:
        lines.append("  the simulated curves lie within the bands at every cluster time")
    lines += [f"  {p.what()}" for p in closing.partings]
    return "\n".join(lines)


def add(sub: Subparsers) -> None:
    """Add ``sins characterise`` to ``sub``."""
    p = sub.add_parser(
        "characterise", help="Allan analysis of a recording: IEEE noise terms, an IMU file, the closing check"
    )
    p.add_argument("recording", type=Path, nargs="?", metavar="RECORDING")
    add_dataset(p)
    p.add_argument("--static", action="store_true", help="the unit stood still: its readings as they are")
    p.add_argument(
        "--truth", type=Path, metavar="TRUTH.csv", help="the trajectory of a moving unit's recording"
    )
    p.add_argument("--out", type=Path, metavar="IMU.toml", help="write the noise model as an IMU file")
    p.add_argument(
        "--json", type=Path, metavar="OUT.json", help="write the curves, terms and check (SI units)"
    )
    p.add_argument("--rerun", type=Path, metavar="OUT.rrd", help="log the real and simulated Allan curves")
    p.add_argument(
        "--seed", type=seed, default=0, metavar="N", help="the closing simulation's seed (default 0)"
    )
    add_plot(p, "the real and simulated Allan curves")
    add_recording_options(p)
    p.set_defaults(func=_cmd_characterise)


__all__ = [
    "add",
]
