"""Record what runs give, and check later that a refactoring left it equal to the last bit.

Usage::

    .venv/bin/python tools/check_run_outputs.py record DIR [--only NAME ...]
    .venv/bin/python tools/check_run_outputs.py compare DIR [--only NAME ...]
    .venv/bin/python tools/check_run_outputs.py golden


For every preset ``sins scenarios`` lists, and a few variants (another unit or power-on on a preset, the
aided drive with the ideal IMU), it keeps ``sins run --json`` and a SHA-256 of every array and figure
of the :class:`sins.runs.pipeline.ScenarioRun` (thinned truth and solutions, errors, sensor errors, the aided
runs' errors, filter records and outage windows); and ``sins integrate --json`` of a simulated
recording in each form. ``compare`` runs them again and names every file or field that differs. The
machine's BLAS and torch kernels are part of the figures: record and compare on one machine, with the
same environment (``make test``'s kernel variables, say). ``golden`` records the short presets the suite
compares with (``tests/recorded_runs.py``), where a change of figures is meant.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import hashlib
import io
import json
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from sins import scenario
from sins.cli import main as sins_main
from sins.runs import pipeline

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import recorded_runs


def _digests(value: Any, prefix: str = "") -> Iterator[tuple[str, str]]:
    """``(field path, sha256)`` of every array and number under ``value`` (dataclasses, dicts, tuples)."""
    if isinstance(value, np.ndarray):
        data = np.ascontiguousarray(value)
        head = f"{data.dtype.str}{data.shape}".encode()
        yield prefix, hashlib.sha256(head + data.tobytes()).hexdigest()
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            if f.name != "scenario":  # the input, not an output
                yield from _digests(getattr(value, f.name), f"{prefix}.{f.name}")
    elif isinstance(value, dict):
        for key, item in value.items():
            yield from _digests(item, f"{prefix}[{key}]")
    elif isinstance(value, tuple | list):
        for i, item in enumerate(value):
            yield from _digests(item, f"{prefix}[{i}]")
    elif value is None or isinstance(value, bool | int | float | str):
        yield prefix, repr(value)
    else:
        raise TypeError(f"{prefix}: cannot digest a {type(value).__name__}")


def _quiet(argv: list[str]) -> None:
    """``sins ARGV`` with its report swallowed; a failure is raised."""
    with contextlib.redirect_stdout(io.StringIO()):
        status = sins_main(argv)
    if status != 0:
        raise RuntimeError(f"sins {' '.join(argv)} exited with {status}")


def _variants() -> dict[str, Callable[[], scenario.Scenario]]:
    """Runs beyond the presets: paths the presets do not take."""

    def load(name: str) -> scenario.Scenario:
        return scenario.load(pipeline.resolve_scenario(name))

    return {
        "static+tactical": lambda: pipeline.with_unit(load("static"), "tactical", 3),
        "car_drive_5min+consumer": lambda: pipeline.with_unit(load("car_drive_5min"), "consumer", 7),
        "car_drive_aided_10min+ideal": lambda: dataclasses.replace(
            load("car_drive_aided_10min"), imu_model=None, compensation=None
        ),
    }


def _record_runs(names: list[str], out: Path) -> None:
    variants = _variants()
    for name in names:
        start = time.perf_counter()
        if name in variants:
            result = pipeline.run_scenario(variants[name]())
        else:
            _quiet(["run", name, "--json", str(out / f"{name}.json")])
            result = pipeline.run_scenario(scenario.load(pipeline.resolve_scenario(name)))
        digests = dict(_digests(result))
        (out / f"{name}.digest.json").write_text(json.dumps(digests, indent=1, sort_keys=True))
        print(f"{name}: {len(digests)} fields, {time.perf_counter() - start:.1f} s", flush=True)


def _record_integrate(out: Path) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        for form in ("increment", "rate"):
            imu, truth = Path(tmp, f"imu_{form}.csv"), Path(tmp, "truth.csv")
            _quiet(["simulate", "car_drive_5min", "--model", "tactical", "--seed", "4", "--form", form,
                    "--imu", str(imu), "--truth", str(truth)])  # fmt: skip
            report = out / f"integrate_{form}.json"
            _quiet(["integrate", str(imu), "--truth", str(truth), "--json", str(report)])
    print("integrate: increment and rate forms", flush=True)


def _flat(value: Any, prefix: str = "") -> dict[str, Any]:
    """A JSON document as ``{field path: value}``; a path names only its file (the checkouts differ)."""
    if isinstance(value, dict):
        return {k: v for key, item in value.items() for k, v in _flat(item, f"{prefix}.{key}").items()}
    if isinstance(value, list):
        return {k: v for i, item in enumerate(value) for k, v in _flat(item, f"{prefix}[{i}]").items()}
    if isinstance(value, str) and "/" in value:
        return {prefix: Path(value).name}
    return {prefix: value}


def _differences(before: Path, after: Path) -> list[str]:
    """The files of ``before`` that ``after`` lacks, and the fields that differ (floats exactly)."""
    found = []
    for old in sorted(before.glob("*.json")):
        new = after / old.name
        if not new.is_file():
            found.append(f"{old.name}: missing")
            continue
        a, b = _flat(json.loads(old.read_text())), _flat(json.loads(new.read_text()))
        # repr: exact for floats, and NaN equals NaN
        # "sins", a report's first key, is the version that wrote it: a release's, not a result.
        keys = (a.keys() | b.keys()) - {".sins"}
        fields = sorted(k for k in keys if repr(a.get(k, "-")) != repr(b.get(k, "-")))
        if fields:
            found.append(f"{old.name}: {len(fields)} fields differ: {', '.join(fields[:8])}")
    return found


def _golden() -> None:
    """The suite's recorded short presets, and the arithmetic they were recorded on."""
    with tempfile.TemporaryDirectory() as tmp:
        documents = {}
        for name in recorded_runs.SHORT_PRESETS:
            _quiet(["run", name, "--json", str(Path(tmp, f"{name}.json"))])
            documents[name] = json.loads(Path(tmp, f"{name}.json").read_text())
    recorded_runs.write(recorded_runs.FOLDER, documents)
    print(f"recorded {', '.join(documents)} in {recorded_runs.FOLDER}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("record", "compare", "golden"))
    parser.add_argument("folder", type=Path, nargs="?", help="where the records are (record, compare)")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="these runs alone (and no integrate)")
    args = parser.parse_args()
    if args.action == "golden":
        _golden()
        return 0
    if args.folder is None:
        parser.error(f"{args.action} needs a folder")
    names = args.only or [*pipeline.presets(), *_variants()]
    if args.action == "record":
        args.folder.mkdir(parents=True, exist_ok=True)
        _record_runs(names, args.folder)
        if not args.only:
            _record_integrate(args.folder)
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        now = Path(tmp)
        _record_runs(names, now)
        if not args.only:
            _record_integrate(now)
        before = Path(tmp, "before")
        before.mkdir()
        for path in now.glob("*.json"):  # compare only what was run again
            if (args.folder / path.name).is_file():
                (before / path.name).write_bytes((args.folder / path.name).read_bytes())
        found = _differences(before, now)
        checked = len(list(before.glob("*.json")))
    print("\n".join(found) if found else f"all {checked} files equal to the last bit")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
