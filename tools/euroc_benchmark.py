"""The published open-loop gyro benchmark on EuRoC, run with sins's own commands.

Usage::

    .venv/bin/python tools/euroc_benchmark.py [--strategies regression mlp ...] [--root DATA_ROOT]
        [--folder euroc] [--train A B ...] [--judge X Y ...] [--json OUT.json] [--models DIR]
        [--outage SECONDS]

The protocol of Brossard et al. 2020 (``shared/data/euroc/SOURCE.md``): every strategy fitted with
``sins fit --dataset euroc/A --dataset euroc/B ... --strategy S --out M`` on the six training sequences,
then judged with ``sins evaluate M --dataset euroc/X --dataset euroc/Y ... --json OUT`` on the five
others by its absolute orientation error (AOE: the corrected gyro integrated alone from the reference's
first attitude, RMS of the angle over every sample, no Earth rate). Nothing of a judged sequence is read
by a fit. Prints one row per judged sequence (raw, every strategy once, Brossard 2020 as SOURCE.md cites
it) and the mean, each fit's wall time, and checks the raw row against SOURCE.md's independent scipy
integration (within 1 %). ``--outage SECONDS``: also ``sins evaluate --outage SECONDS``, and a second
table of the RMS horizontal error at the outages' ends, m.

``--folder``, ``--train`` and ``--judge`` run the same commands on another unit's ``.npz`` recordings
(``--folder myunit --train a b c --judge d e f``); the published columns are then left out.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from sins.cli import main
from sins.compensation.network_guard import BASELINE
from sins.io.datasets import data_root

TRAIN = ["MH_01_easy", "MH_03_medium", "MH_05_difficult", "V1_02_medium", "V2_01_easy", "V2_03_difficult"]
JUDGE = ["MH_02_easy", "MH_04_difficult", "V1_01_easy", "V1_03_difficult", "V2_02_medium"]
#: SOURCE.md: the raw gyro's AOE by an independent scipy integration, and Brossard et al. 2020's network
#: as cited there (deg).
RAW_SOURCE = {"MH_02_easy": 123.1, "MH_04_difficult": 130.3, "V1_01_easy": 114.1, "V1_03_difficult": 120.1,
              "V2_02_medium": 116.9}  # fmt: skip
BROSSARD = {"MH_02_easy": 1.39, "MH_04_difficult": 1.40, "V1_01_easy": 1.13, "V1_03_difficult": 2.70,
            "V2_02_medium": 3.85}  # fmt: skip
STRATEGIES = ["regression", "bias_only", "regression_robust", "regression_rest", "regression_window",
              "mlp", "kohonen", "mlp_window", "mlp_pure", "mlp_seed", "kohonen_pure"]  # fmt: skip


def _run(argv: list[str], quiet: bool = True) -> int:
    """``sins ARGV`` in this process; its output kept quiet."""
    sink = io.StringIO()
    with contextlib.redirect_stdout(sink) if quiet else contextlib.nullcontext():
        code = main(argv)
    if code:
        print(sink.getvalue(), file=sys.stderr)
    return code


def _evaluate(
    model: Path, folder: str, names: list[str], out: Path, outage: float | None = None
) -> dict[str, dict[str, Any]]:
    """Every judged recording's document by its name: one ``sins evaluate`` of them all (several
    ``--dataset``: each judged as alone, the documents under ``recordings``), with ``--outage`` where
    given."""
    datasets = [f"{folder}/{n}" for n in names]
    outages = ["--outage", str(outage)] if outage else []
    code = _run(
        [
            "evaluate",
            str(model),
            *(a for d in datasets for a in ("--dataset", d)),
            "--json",
            str(out),
            *outages,
        ]
    )
    if code:
        raise SystemExit(f"sins evaluate {model} on {', '.join(datasets)} failed ({code})")
    doc = json.loads(out.read_text())
    judged = doc["recordings"] if len(names) > 1 else [doc]
    return {name: judged[i] for i, name in enumerate(names)}


def main_(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--strategies", nargs="+", default=STRATEGIES)
    p.add_argument("--root", type=Path, help="the data root (default: SINS_DATA or ../shared/data)")
    p.add_argument("--folder", default="euroc")
    p.add_argument("--train", nargs="+", default=TRAIN)
    p.add_argument("--judge", nargs="+", default=JUDGE)
    p.add_argument("--json", type=Path, help="write every figure here")
    p.add_argument("--models", type=Path, help="keep the fitted models in this folder")
    p.add_argument(
        "--screen", choices=("refused", "always", "never"), help="sins fit --screen (default its own)"
    )
    p.add_argument("--outage", type=float, metavar="SECONDS", help="also sins evaluate --outage SECONDS")
    args = p.parse_args(argv)
    if args.root is not None:
        os.environ["SINS_DATA"] = str(args.root)
    work = Path(tempfile.mkdtemp(prefix="sins-euroc-"))
    try:
        return _benchmark(args, work)
    finally:  # the fits' documents and judged reports (and the models, without --models)
        shutil.rmtree(work, ignore_errors=True)


def _benchmark(args: argparse.Namespace, work: Path) -> int:
    """Every strategy fitted and judged (see the module docstring), ``work`` the scratch folder."""
    published = args.folder == "euroc" and args.judge == JUDGE and args.train == TRAIN
    models = args.models or work
    models.mkdir(parents=True, exist_ok=True)
    results: dict[str, Any] = {"train": args.train, "judge": args.judge, "fits": {}, "aoe_deg": {}}
    strategies = list(dict.fromkeys(args.strategies))  # each once: a column and its mean
    for strategy in strategies:
        model = models / f"{strategy}.json"
        fit_json = work / f"{strategy}.fit.json"
        argv_fit = ["fit", *(a for n in args.train for a in ("--dataset", f"{args.folder}/{n}")),
                    "--strategy", strategy, "--out", str(model), "--json", str(fit_json),
                    *(["--screen", args.screen] if args.screen else [])]  # fmt: skip
        start = time.perf_counter()
        if _run(argv_fit):  # refused (its one line printed above): its column left out, the others go on
            results["fits"][strategy] = {"refused": True}
            continue
        seconds = time.perf_counter() - start
        doc = json.loads(fit_json.read_text())
        guard = doc.get("network_guard")  # the seed paper's networks: least squares written where they lose
        results["fits"][strategy] = {"seconds": seconds, "bias_rule": doc.get("bias_rule", {}),
                                     "network_guard": guard}  # fmt: skip
        rule = doc.get("bias_rule", {})
        mode = rule.get("mode", "-") + (" (mixture)" if rule.get("mixture") else "")
        wrote = "" if guard is None else f"; its guard wrote {guard['written']}"
        print(f"fitted {strategy} in {seconds:.1f} s (bias rule: {mode}{wrote})", file=sys.stderr)
        for name, judged in _evaluate(
            model, args.folder, args.judge, work / f"{strategy}.judged.json", args.outage
        ).items():
            results["aoe_deg"].setdefault(name, {})["none"] = judged["open_loop_attitude_raw"]["aoe_deg"]
            results["aoe_deg"][name][strategy] = judged["open_loop_attitude"]["aoe_deg"]
            if args.outage:  # the RMS horizontal error at the outages' ends, m
                outage = judged["free_inertial_outages"][0]
                results.setdefault("outage_m", {}).setdefault(name, {})["none"] = outage["raw"]["rms_m"]
                results["outage_m"][name][strategy] = outage["corrected"]["rms_m"]
    fitted = [s for s in strategies if s != "none" and not results["fits"][s].get("refused")]
    if not fitted:
        raise SystemExit("every sins fit was refused")
    refused = [s for s in strategies if results["fits"].get(s, {}).get("refused")]
    _table(results, fitted, published)  # the raw column is "none"
    if args.outage:
        print(f"\n{args.outage:g} s free-inertial outages from every second, RMS horizontal error, m")
        _table(results, fitted, False, key="outage_m", digits=4)
    if refused:
        print("refused by sins fit (see above): " + ", ".join(refused))
    # Their columns are least squares' correction: the networks' held-back guard wrote its model.
    guards = {s: results["fits"][s].get("network_guard") or {} for s in fitted}
    guarded = [s for s, g in guards.items() if g.get("written") == BASELINE]
    if guarded:
        said = ", ".join(guarded)
        print(f"written as least squares' model by the networks' guard (sins fit says why): {said}")
    if args.json:
        args.json.write_text(json.dumps(results, indent=2))
    return 0


def run_on_unit(
    write: Callable[[Path], None], folder: str, train: list[str], judge: list[str], strategies: list[str],
    *, json_out: Path | None = None, keep: Path | None = None, screen: str | None = None,
    outage: float | None = None,
) -> int:  # fmt: skip
    """The benchmark on recordings of another unit: ``write`` puts them into ``ROOT/folder`` of a data root,
    ``keep`` or a temporary one, removed after (the recordings written for the run, not the user's)."""
    root = keep or Path(tempfile.mkdtemp(prefix=f"sins-{folder}-"))
    try:
        (root / folder).mkdir(parents=True, exist_ok=True)
        write(root / folder)
        bench = ["--root", str(root), "--folder", folder, "--train", *train, "--judge", *judge,
                 "--strategies", *strategies, *(["--json", str(json_out)] if json_out else []),
                 *(["--screen", screen] if screen else []),
                 *(["--outage", str(outage)] if outage else [])]  # fmt: skip
        return main_(bench)
    finally:
        if keep is None:
            shutil.rmtree(root, ignore_errors=True)


def run_on_euroc_as(
    argv: list[str] | None, description: str, folder: str, rewrite: Callable[[Path, Path], object],
    strategies: list[str],
) -> int:  # fmt: skip
    """The benchmark on EuRoC's sequences each written anew by ``rewrite(source, folder)`` (the ``.npz``
    ``source`` into ``folder`` under its name): a command line of ``--strategies`` (default
    ``strategies``), ``--train``, ``--judge`` (the published split), ``--json`` and ``--keep``, for the
    tools that make another unit of EuRoC's (read calibrated, aliased)."""
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--strategies", nargs="+", default=strategies)
    p.add_argument("--train", nargs="+", default=TRAIN, help="the sequences fitted on")
    p.add_argument("--judge", nargs="+", default=JUDGE, help="the sequences judged")
    p.add_argument("--json", type=Path)
    p.add_argument("--keep", type=Path, help="write the .npz recordings here (a data root) and keep them")
    args = p.parse_args(argv)
    shared = data_root()  # the library's rule: SINS_DATA, else ../shared/data

    def write(out: Path) -> None:
        for name in [*args.train, *args.judge]:
            rewrite(shared / "euroc" / f"{name}.npz", out)

    return run_on_unit(
        write, folder, args.train, args.judge, args.strategies, json_out=args.json, keep=args.keep
    )


def _table(
    results: dict[str, Any], strategies: list[str], published: bool, key: str = "aoe_deg", digits: int = 2
) -> None:
    """One row per judged sequence of ``results[key]`` and the mean (with the fit times under the AOE)."""
    cols = ["none", *strategies]
    head = ["sequence", *cols] + (["Brossard 2020", "raw (SOURCE.md)"] if published else [])
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    sums = dict.fromkeys(cols, 0.0)
    names = list(results[key])
    for name in names:
        row = results[key][name]
        for c in cols:
            sums[c] += row[c]
        cells = [f"{row[c]:.{digits}f}" for c in cols]
        if published:
            raw = row["none"]
            off = 100 * (raw / RAW_SOURCE[name] - 1)
            cells += [f"{BROSSARD[name]:.2f}", f"{RAW_SOURCE[name]:.1f} ({off:+.2f} %)"]
        print(f"| {name} | " + " | ".join(cells) + " |")
    mean = [f"**{sums[c] / len(names):.{digits}f}**" for c in cols]
    if published:
        mean += [f"**{sum(BROSSARD.values()) / len(BROSSARD):.2f}**", ""]
    print("| mean | " + " | ".join(mean) + " |")
    if key == "aoe_deg":
        print(
            "\nfit wall time: " + ", ".join(f"{s} {results['fits'][s]['seconds']:.0f} s" for s in strategies)
        )


if __name__ == "__main__":
    sys.exit(main_())
