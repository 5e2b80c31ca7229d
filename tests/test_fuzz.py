"""Fuzzed input files: every reader and every command that takes a file, on mutated copies of small files.

Each target starts from small valid files (a few seconds of a scenario at 20 Hz, a 10 Hz rig session,
a model fitted on it, a one-case quality suite, synthetic copies of the real datasets) and mutates
them: byte flips, truncation, deleted and duplicated lines, ``nan``/``inf``/``1e400``/``-0``/huge/tiny
numbers and text in a CSV field, numeric TOML fields pushed to extremes (``1e-300``, ``1e300``,
negative, zero), keys removed, retyped or unknown. The property, for every example:

* the command ends with exit status 0 and a sound result (no ``nan`` or ``inf`` in what it prints
  or in the JSON it writes), or with exit status 2 and exactly one line on stderr that names one of
  its input files (or, for a size refusal, its output) — never another exception (a traceback);
* never a hang: each example runs under a watchdog (:func:`watchdog`) that stops it when it has used
  :data:`HANG_CPU_S` seconds of CPU (the inputs are tiny: an example that long spins) or made no
  progress (its process and children gained almost no CPU time over ``conftest.STALL_S`` seconds: it is
  blocked). Never wall time alone: a slow, loaded machine is not a hang;
* never a file left behind: after a refusal the output it was asked for does not exist, and no
  temporary file is left in the output folder;
* never an input changed: every input's bytes (a folder's every file) are hashed before and after
  (:func:`snapshot`), and a difference is an :class:`InputChanged` failure.

The dataset readers are called directly (their files live under a data root, not on the command line):
a result or one :class:`~sins.errors.SinsInputError` line naming the file.

``@settings(derandomize=True)`` makes CI reproducible; ``tools/fuzz_long.py`` runs the same targets
with many more examples and fresh randomness. Run with ``--hypothesis-show-statistics`` to see how
many examples each target ran.
"""

from __future__ import annotations

import contextlib
import copy
import io as _io
import json
import lzma
import math
import os
import re
import shutil
import signal
import tempfile
import threading
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import scipy.io
from conftest import STALL_CPU_S, STALL_S, Progress
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from test_dataset_psins_vehicle import synthetic_recording

from sins.cli import main
from sins.errors import SinsInputError

#: CPU time one example may use, s (this process and its children). The inputs run in well under a
#: second each (a few seconds of motion at 20 Hz, a 40 s rig session at 10 Hz); one that spins this long
#: is stuck. CPU time, not wall time: a loaded machine slows an example, it does not add CPU to it.
HANG_CPU_S = 120.0

#: Examples run per target in this process (for the reports of ``tools/fuzz_long.py``).
EXAMPLES: Counter[str] = Counter()

#: Where :func:`workdir` copies the files of an example that fails (``tools/fuzz_long.py --keep``).
KEEP_FAILURES: list[Path] = []

#: The last command run (written beside the kept files as ``argv.json``).
LAST_ARGV: list[list[str]] = [[]]


def ci(examples: int) -> Callable[[Any], Any]:
    """The CI profile: ``examples`` per target, reproducible, no deadline (the watchdog finds hangs)."""
    return settings(
        max_examples=examples,
        deadline=None,
        derandomize=True,
        database=None,
        phases=[Phase.explicit, Phase.generate, Phase.shrink],  # no "explain": a minute per failure
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )


# --------------------------------------------------------------------------- running a command


class Hang(BaseException):
    """An example spun past :data:`HANG_CPU_S` of CPU or stopped progressing (a BaseException, so no
    ``except Exception`` swallows it)."""


@contextlib.contextmanager
def watchdog(
    cpu_s: float = HANG_CPU_S, stall_s: float = STALL_S, stall_cpu_s: float = STALL_CPU_S
) -> Iterator[None]:
    """Raise :class:`Hang` in this (main) thread when the block has used ``cpu_s`` of CPU time (this
    process and its children) or its process tree has stalled for ``stall_s`` (``conftest.Progress``).

    A thread samples the CPU time every half second and, to stop the block, sends SIGUSR1 to the main
    thread: a signal interrupts a blocking read (of a FIFO, say), whose handler raises :class:`Hang`."""
    why: list[str] = []

    def stop(signum: int, frame: Any) -> None:
        raise Hang(why[0] if why else "stopped")

    main_thread = threading.main_thread().ident
    assert main_thread is not None and threading.current_thread().ident == main_thread
    previous = signal.signal(signal.SIGUSR1, stop)
    done = threading.Event()
    watch = Progress(os.getpid(), stall_s=stall_s, stall_cpu_s=stall_cpu_s)

    def guard() -> None:
        while not done.wait(0.5):
            if watch.cpu_s() > cpu_s:
                why.append(f"used more than {cpu_s:g} s of CPU")
            elif watch.stalled():
                why.append(f"made no progress in {stall_s:g} s")
            else:
                continue
            signal.pthread_kill(main_thread, signal.SIGUSR1)
            return

    thread = threading.Thread(target=guard, name="fuzz-watchdog", daemon=True)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()
        signal.signal(signal.SIGUSR1, previous)


def run_cli(argv: list[str], hang_cpu_s: float = HANG_CPU_S) -> tuple[int, str, str]:
    """``sins.cli.main(argv)`` in this process: exit status, stdout, stderr. Any exception escapes."""
    out, err = _io.StringIO(), _io.StringIO()
    LAST_ARGV[0] = argv
    with watchdog(hang_cpu_s), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, out.getvalue(), err.getvalue()


class InputChanged(AssertionError):
    """A command changed one of its inputs (its bytes, or what kind of file it is)."""


def snapshot(paths: list[Path]) -> dict[str, str]:
    """What each of ``paths`` is, never opening a special file: a regular file's SHA-256, a folder's
    every regular file's (by name), a FIFO's or device's kind, a symbolic link's target and what that
    is, "absent"."""
    out: dict[str, str] = {}
    for path in paths:
        out[str(path)] = _what(Path(path))
    return out


def _what(path: Path) -> str:
    import hashlib
    import stat

    try:
        st = os.lstat(path)
    except OSError:
        return "absent"
    if stat.S_ISLNK(st.st_mode):
        return f"link to {os.readlink(path)}: " + _what(Path(os.path.realpath(path)))
    if stat.S_ISREG(st.st_mode):
        return hashlib.sha256(path.read_bytes()).hexdigest()
    if stat.S_ISDIR(st.st_mode):
        files = sorted(p for p in path.rglob("*") if p.is_file() and not p.is_symlink())
        inner = [f"{p.relative_to(path)}={hashlib.sha256(p.read_bytes()).hexdigest()}" for p in files]
        return "folder " + hashlib.sha256("\n".join(inner).encode()).hexdigest()
    return f"special {stat.S_IFMT(st.st_mode):o}"


def check_unchanged(before: dict[str, str], argv: list[str]) -> None:
    """Raise :class:`InputChanged` when an input is not what :func:`snapshot` found before ``argv``."""
    after = snapshot([Path(p) for p in before])
    changed = [p for p in before if before[p] != after[p]]
    if changed:
        raise InputChanged(
            f"{argv[0]} changed its input(s) {changed}: {before[changed[0]]} -> {after[changed[0]]}"
        )


NON_FINITE = re.compile(r"(?<![\w./-])[-+]?(nan|inf|infinity)(?!\w)", re.IGNORECASE)


def _finite_json(value: Any, where: str) -> None:
    if isinstance(value, float):
        assert math.isfinite(value), f"{where}: {value!r} in the JSON output"
    elif isinstance(value, dict):
        for k, v in value.items():
            _finite_json(v, f"{where}.{k}")
    elif isinstance(value, list):
        for i, v in enumerate(value):
            _finite_json(v, f"{where}[{i}]")


def check_cli(
    argv: list[str],
    inputs: list[Path],
    outputs: list[Path],
    folder: Path,
    ok: tuple[int, ...] = (0,),
    hang_cpu_s: float = HANG_CPU_S,
) -> tuple[int, str, str]:
    """Run ``argv`` and assert the fuzzing property (see the module docstring).

    ``inputs`` are the files the command reads (a refusal names one of them), ``outputs`` those it
    is asked to write (none exist before), ``folder`` where they go (no temporary file may stay, at any
    depth). ``ok`` are the exit statuses of a sound result (``sins check`` also ends 1 on a
    regression); ``hang_cpu_s`` the CPU bound (a campaign starts a cluster).
    """
    for path in outputs:
        assert not path.exists()
    before = snapshot(inputs)
    rc, out, err = run_cli(argv, hang_cpu_s)
    check_unchanged(before, argv)
    leftovers = [p.name for p in folder.rglob("*.tmp")]
    assert not leftovers, f"temporary files left behind: {leftovers}"
    if rc in ok:
        assert not NON_FINITE.search(out), f"non-finite number in the output of {argv}:\n{out}"
        for path in outputs:
            if path.suffix == ".json" and path.exists():
                _finite_json(json.loads(path.read_text(encoding="utf-8")), path.name)
        return rc, out, err
    assert rc == 2, f"exit status {rc} for {argv}; stderr: {err!r}"
    assert_one_line(err, inputs + outputs)
    for path in outputs:
        assert not path.exists(), f"{path} left behind after a refusal: {err!r}"
    return rc, out, err


def assert_one_line(err: str, files: list[Path]) -> None:
    """Exactly one line, ``sins: error: ...``, naming one of ``files``."""
    assert err.endswith("\n") and err.count("\n") == 1, f"not one line: {err!r}"
    assert err.startswith("sins: error: "), err
    assert "Traceback" not in err
    assert any(str(p) in err for p in files), f"names none of {[p.name for p in files]}: {err!r}"


# --------------------------------------------------------------------------- mutations

#: What a mutated CSV field or TOML value becomes: non-finite, overflowing, signed zero, denormal,
#: extreme, not a number at all.
TOKENS = (
    "nan", "NaN", "-nan", "inf", "-inf", "Infinity", "1e400", "-1e400", "-0", "-0.0", "0", "1e300",
    "-1e300", "1e-300", "-1e-300", "5e-324", "1.7976931348623157e308", "1e18", "-1e18", "abc", "",
    " ", "1_0", "0x10", "1e", "--1", "9" * 40, "1,2", "\t3",
)  # fmt: skip

#: Values a TOML number is pushed to (and a few of other types).
EXTREMES: tuple[Any, ...] = (
    0, 0.0, -0.0, -1, -1.0, 1e-300, -1e-300, 5e-324, 1e-9, 0.5, 1e300, -1e300, 1.7976931348623157e308,
    math.inf, -math.inf, math.nan, 2**63 - 1, -(2**63), 1.5, "text", True, [1.0, 2.0], {"a": 1},
)  # fmt: skip


def mutate_lines(text: str, data: st.DataObject, header_lines: int = 1) -> bytes:
    """One to three mutations of a text file: a byte flipped, truncation, a line deleted or duplicated,
    a comma-separated field replaced by a :data:`TOKENS` value."""
    raw = text.encode("utf-8")
    for _ in range(data.draw(st.integers(1, 3), label="mutations")):
        kind = data.draw(st.sampled_from(["flip", "truncate", "delete", "duplicate", "field", "field"]))
        lines = raw.split(b"\n")
        if kind == "flip" and raw:
            i = data.draw(st.integers(0, len(raw) - 1), label="byte")
            raw = raw[:i] + bytes([data.draw(st.integers(0, 255), label="value")]) + raw[i + 1 :]
        elif kind == "truncate":
            raw = raw[: data.draw(st.integers(0, len(raw)), label="length")]
        elif kind in ("delete", "duplicate") and lines:
            i = data.draw(st.integers(0, len(lines) - 1), label="line")
            if kind == "delete":
                del lines[i]
            else:
                lines.insert(i, lines[i])
            raw = b"\n".join(lines)
        elif kind == "field" and len(lines) > header_lines:
            i = data.draw(st.integers(0, len(lines) - 1), label="line")
            cells = lines[i].split(b",")
            j = data.draw(st.integers(0, len(cells) - 1), label="column")
            cells[j] = data.draw(st.sampled_from(TOKENS), label="token").encode()
            lines[i] = b",".join(cells)
            raw = b"\n".join(lines)
    return raw


def mutate_bytes(raw: bytes, data: st.DataObject) -> bytes:
    """One to three byte flips or truncations of a binary file."""
    for _ in range(data.draw(st.integers(1, 3), label="mutations")):
        if data.draw(st.booleans(), label="truncate") or not raw:
            raw = raw[: data.draw(st.integers(0, len(raw)), label="length")]
        else:
            i = data.draw(st.integers(0, len(raw) - 1), label="byte")
            raw = raw[:i] + bytes([data.draw(st.integers(0, 255), label="value")]) + raw[i + 1 :]
    return raw


def toml_value(v: Any) -> str:
    """A TOML literal: numbers (``inf``, ``nan``), strings, booleans, arrays, inline tables."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else repr(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + "}"
    return repr(v)


def _is_tables(v: Any) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)


def to_toml(doc: dict[str, Any]) -> str:
    """A TOML document: top-level keys, then ``[table]`` and ``[[array of tables]]`` sections."""
    out = [f"{k} = {toml_value(v)}" for k, v in doc.items() if not isinstance(v, dict) and not _is_tables(v)]
    for k, v in doc.items():
        if isinstance(v, dict):
            out += [f"[{k}]"] + [f"{kk} = {toml_value(vv)}" for kk, vv in v.items()]
        elif _is_tables(v):
            for item in v:
                out += [f"[[{k}]]"] + [f"{kk} = {toml_value(vv)}" for kk, vv in item.items()]
    return "\n".join(out) + "\n"


def numeric_paths(doc: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Paths (keys and indices) to every number in a parsed TOML document, arrays included."""
    out: list[tuple[Any, ...]] = []
    items = doc.items() if isinstance(doc, dict) else enumerate(doc) if isinstance(doc, list) else []
    for k, v in items:
        if isinstance(v, int | float) and not isinstance(v, bool):
            out.append((*prefix, k))
        elif isinstance(v, dict | list):
            out.extend(numeric_paths(v, (*prefix, k)))
    return out


def _parent(doc: Any, path: tuple[Any, ...]) -> Any:
    for k in path[:-1]:
        doc = doc[k]
    return doc


def mutate_doc(doc: dict[str, Any], data: st.DataObject) -> dict[str, Any]:
    """One or two edits of a TOML document: a number pushed to an :data:`EXTREMES` value (most
    often), a key removed, or an unknown key added."""
    doc = json.loads(json.dumps(doc))
    for _ in range(data.draw(st.integers(1, 2), label="edits")):
        paths = numeric_paths(doc)
        kind = data.draw(st.sampled_from(["value", "value", "value", "value", "drop", "add"]), label="edit")
        if kind == "value" and paths:
            path = data.draw(st.sampled_from(paths), label="path")
            _parent(doc, path)[path[-1]] = copy.deepcopy(
                data.draw(st.sampled_from(EXTREMES), label="extreme")
            )
        elif kind == "drop" and paths:
            path = data.draw(st.sampled_from(paths), label="path")
            parent = _parent(doc, path)
            if isinstance(parent, dict):
                del parent[path[-1]]
        elif kind == "add":
            tables = [v for v in doc.values() if isinstance(v, dict)]
            target = data.draw(st.sampled_from([doc, *tables]), label="table")
            target["fuzz_key"] = copy.deepcopy(data.draw(st.sampled_from(EXTREMES), label="extreme"))
    return doc


# --------------------------------------------------------------------------- the small valid files

SCENARIO: dict[str, Any] = {
    "name": "fuzz",
    "imu": {"rate_hz": 20, "seed": 3, "times_s": [0.0, 4.0], "temps_degc": [20.0, 25.0]},
    "navigation": {"vertical": "damp", "vertical_tau_s": 10.0},
    "initial": {"lat_deg": 45.0, "lon_deg": 7.0, "alt_m": 100.0, "speed_mps": 5.0, "roll_deg": 1.0,
                "pitch_deg": 2.0, "yaw_deg": 30.0},
    "segment": [
        {"type": "hold", "duration_s": 0.5},
        {"type": "accelerate", "duration_s": 1.0, "delta_speed_mps": 1.0, "ramp_s": 0.25},
        {"type": "accelerate", "duration_s": 1.0, "to_speed_mps": 4.0},
        {"type": "turn", "duration_s": 1.0, "rate_dps": 10.0, "ramp_s": 0.25, "coordinated": True},
        {"type": "turn", "duration_s": 1.0, "angle_deg": 5.0, "ramp_s": 0.25},
        {"type": "climb", "duration_s": 1.0, "angle_deg": 5.0, "ramp_s": 0.25},
        {"type": "attitude", "duration_s": 1.0, "roll_deg": 5.0, "pitch_deg": 2.0, "yaw_deg": 3.0,
         "ramp_s": 0.25},
    ],
    "oscillation": [
        {"channel": "roll", "amplitude_deg": 2.0, "period_s": 1.5, "phase_deg": 10.0},
        {"channel": "heave", "amplitude_m": 0.1, "period_s": 2.0},
    ],
}  # fmt: skip

WAYPOINTS: dict[str, Any] = {
    "name": "fuzz_wp",
    "imu": {"rate_hz": 20},
    "initial": {"lat_deg": 52.0, "lon_deg": 4.0, "alt_m": 2.0},
    "waypoint": [
        {"north_m": 0.0, "east_m": 0.0, "speed_mps": 5.0},
        {"north_m": 10.0, "east_m": 3.0, "speed_mps": 8.0},
        {"north_m": 20.0, "east_m": 10.0, "up_m": 1.0, "speed_mps": 6.0},
    ],
}

TRUTH_SCENARIO: dict[str, Any] = {
    "name": "fuzz_truth",
    "imu": {"rate_hz": 20},
    "truth": {"file": "truth.csv"},
}

IMU_MODEL: dict[str, Any] = {
    "grade": "tactical",
    "unit_seed": 2,
    "effect": [
        {"name": "gyro.bias_instability", "sigma_dph": 1.0, "tau_s": 50.0},
        {"name": "gyro.scale_nonlinearity", "k2_ppm_per_dps": [30.0, 30.0, 30.0]},
        {"name": "accel.temperature_bias", "c1_mg_per_degc": 0.01, "c2_mg_per_degc2": 0.001,
         "t0_degc": 20.0},
        {"name": "gyro.time_offset", "delay_ms": 1.0},
        {"name": "accel.quantization", "step_mg": 0.5},
        {"name": "gyro.saturation", "limit_dps": 300.0},
        {"name": "accel.size_effect", "lever_arms_mm": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]},
        {"name": "accel.rate_random_walk", "rrw_ug_per_rt_s": 5.0},
    ],
}  # fmt: skip

RIG: dict[str, Any] = {
    "rig": {"lat_deg": 45.0, "lon_deg": 7.0, "alt_m": 200.0, "rate_hz": 10, "orientation_error_deg": 0.1,
            "rate_error_ppm": 10.0},
    "positions": {"count": 6, "dwell_s": 4.0},
    "rate_table": {"rates_dps": [30.0], "axes": ["x", "y", "z"], "orientations": ["up"], "dwell_s": 4.0,
                   "accel_dps2": 100.0},
    "temperature": {"times_s": [0.0, 20.0], "temps_degc": [20.0, 30.0]},
}  # fmt: skip

#: A scenario with an IMU model and compensation fitted on a rig session: the files it names are fuzzed.
MODEL_SCENARIO: dict[str, Any] = {
    "name": "fuzz_model",
    "imu": {"rate_hz": 20, "model": "imu.toml", "seed": 1},
    "compensation": {"rig": "rig.toml", "validation": 0.3, "seed": 2, "strategies": ["regression"]},
    "initial": {"lat_deg": 45.0, "speed_mps": 5.0},
    "segment": [{"type": "turn", "duration_s": 3.0, "rate_dps": 10.0}],
}

SUITE = '[[case]]\nname = "tiny"\nscenario = "case.toml"\n[tolerance]\nhorizontal = 0.1\nresidual = 0.05\n'


@dataclass(frozen=True)
class Base:
    """The small valid files every target starts from, as text (bytes for the binary ones)."""

    folder: Path
    truth_csv: str
    increment_csv: str
    rate_csv: str
    recording_csv: str
    model_json: str
    baseline_json: str


def _ok(argv: list[str]) -> None:
    rc, _, err = run_cli(argv)
    assert rc == 0, err


def make_base(folder: Path) -> Base:
    """Write and simulate the small valid files in ``folder``."""
    (folder / "scenario.toml").write_text(to_toml(SCENARIO), encoding="utf-8")
    _ok(["simulate", str(folder / "scenario.toml"), "--imu", str(folder / "inc.csv"), "--truth",
         str(folder / "truth.csv")])  # fmt: skip
    _ok(["simulate", str(folder / "scenario.toml"), "--imu", str(folder / "rate.csv"), "--truth",
         str(folder / "truth_r.csv"), "--form", "rate"])  # fmt: skip
    (folder / "imu.toml").write_text(to_toml(IMU_MODEL), encoding="utf-8")
    (folder / "rig.toml").write_text(to_toml(RIG), encoding="utf-8")
    _ok(["calibrate", str(folder / "rig.toml"), "--imu", str(folder / "imu.toml"), "--out",
         str(folder / "rec.csv"), "--seed", "5"])  # fmt: skip
    _ok(["fit", str(folder / "rec.csv"), "--strategy", "regression", "--out", str(folder / "model.json")])
    (folder / "case.toml").write_text(to_toml(MODEL_SCENARIO), encoding="utf-8")
    (folder / "quality.toml").write_text(SUITE, encoding="utf-8")
    _ok(["check", str(folder / "quality.toml"), "--baseline", str(folder / "baseline.json"),
         "--update-baseline"])  # fmt: skip
    text = lambda name: (folder / name).read_text(encoding="utf-8")  # noqa: E731
    return Base(folder, text("truth.csv"), text("inc.csv"), text("rate.csv"), text("rec.csv"),
                text("model.json"), text("baseline.json"))  # fmt: skip


@pytest.fixture(scope="module")
def base(tmp_path_factory: pytest.TempPathFactory) -> Base:
    return make_base(tmp_path_factory.mktemp("fuzz_base"))


@contextlib.contextmanager
def workdir(b: Base) -> Iterator[Path]:
    """A fresh folder per example (hypothesis runs many examples in one test call)."""
    with tempfile.TemporaryDirectory(dir=b.folder) as name:
        try:
            yield Path(name)
        except (Exception, Hang):
            if KEEP_FAILURES:
                kept = KEEP_FAILURES[0] / Path(name).name
                shutil.copytree(name, kept, symlinks=True)  # links kept as links (a dangling one too)
                (kept / "argv.json").write_text(json.dumps([a.replace(name, "{dir}") for a in LAST_ARGV[0]]))
            raise


def _write(path: Path, content: str | bytes) -> Path:
    if isinstance(content, str):
        path.write_text(content, encoding="utf-8")
    else:
        path.write_bytes(content)
    return path


# --------------------------------------------------------------------------- the targets


def target_scenario_values(b: Base, data: st.DataObject) -> None:
    """A scenario (segments, waypoints or a truth file) with numbers pushed to extremes; run or simulate."""
    doc = data.draw(st.sampled_from([SCENARIO, WAYPOINTS, TRUTH_SCENARIO]), label="scenario")
    with workdir(b) as d:
        _write(d / "truth.csv", b.truth_csv)
        path = _write(d / "s.toml", to_toml(mutate_doc(doc, data)))
        _scenario_command(d, path, [d / "truth.csv"], data)


def target_scenario_bytes(b: Base, data: st.DataObject) -> None:
    """A scenario file's text mutated (bytes, lines, fields), or its truth file's; run or simulate."""
    doc = data.draw(st.sampled_from([SCENARIO, WAYPOINTS, TRUTH_SCENARIO]), label="scenario")
    with workdir(b) as d:
        truth = b.truth_csv.encode()
        text = to_toml(doc).encode()
        if doc is TRUTH_SCENARIO and data.draw(st.booleans(), label="mutate truth"):
            truth = mutate_lines(b.truth_csv, data, header_lines=2)
        else:
            text = mutate_lines(to_toml(doc), data, header_lines=0)
        _write(d / "truth.csv", truth)
        path = _write(d / "s.toml", text)
        _scenario_command(d, path, [d / "truth.csv"], data)


def _scenario_command(d: Path, path: Path, others: list[Path], data: st.DataObject) -> None:
    out = d / "out"
    out.mkdir()
    if data.draw(st.booleans(), label="run"):
        check_cli(
            ["run", str(path), "--json", str(out / "run.json")], [path, *others], [out / "run.json"], out
        )
    else:
        imu, truth = out / "imu.csv", out / "truth.csv"
        form = data.draw(st.sampled_from(["increment", "rate"]), label="form")
        rc, _, _ = check_cli(["simulate", str(path), "--imu", str(imu), "--truth", str(truth), "--form",
                                form], [path, *others], [imu, truth], out)  # fmt: skip
        if rc == 0:  # what simulate wrote reads back and integrates
            check_cli(["integrate", str(imu), "--truth", str(truth)], [imu, truth], [], out)


def target_imu_and_rig_values(b: Base, data: st.DataObject) -> None:
    """IMU model and rig files with numbers pushed to extremes: ``sins calibrate RIG --imu IMU``."""
    which = data.draw(st.sampled_from(["imu", "rig", "both"]), label="which")
    with workdir(b) as d:
        imu = _write(d / "imu.toml", to_toml(mutate_doc(IMU_MODEL, data) if which != "rig" else IMU_MODEL))
        rig = _write(d / "rig.toml", to_toml(mutate_doc(RIG, data) if which != "imu" else RIG))
        out = d / "out"
        out.mkdir()
        seed = str(data.draw(st.sampled_from([0, 1, 2**31])))
        check_cli(["calibrate", str(rig), "--imu", str(imu), "--out", str(out / "rec.csv"), "--seed", seed],
                  [imu, rig], [out / "rec.csv"], out)  # fmt: skip


def target_imu_and_rig_bytes(b: Base, data: st.DataObject) -> None:
    """IMU model and rig files with their text mutated: ``sins calibrate RIG --imu IMU``."""
    which = data.draw(st.sampled_from(["imu", "rig"]), label="which")
    with workdir(b) as d:
        imu_text, rig_text = to_toml(IMU_MODEL), to_toml(RIG)
        imu = _write(d / "imu.toml", mutate_lines(imu_text, data, 0) if which == "imu" else imu_text)
        rig = _write(d / "rig.toml", mutate_lines(rig_text, data, 0) if which == "rig" else rig_text)
        out = d / "out"
        out.mkdir()
        check_cli(["calibrate", str(rig), "--imu", str(imu), "--out", str(out / "rec.csv")], [imu, rig],
                  [out / "rec.csv"], out)  # fmt: skip


def target_scenario_model_files(b: Base, data: st.DataObject) -> None:
    """A scenario's ``[imu] model`` and ``[compensation] rig`` files mutated: ``sins run``."""
    which = data.draw(st.sampled_from(["imu", "rig", "scenario"]), label="which")
    with workdir(b) as d:
        imu = _write(d / "imu.toml", to_toml(mutate_doc(IMU_MODEL, data) if which == "imu" else IMU_MODEL))
        rig = _write(d / "rig.toml", to_toml(mutate_doc(RIG, data) if which == "rig" else RIG))
        doc = mutate_doc(MODEL_SCENARIO, data) if which == "scenario" else MODEL_SCENARIO
        path = _write(d / "s.toml", to_toml(doc))
        out = d / "out"
        out.mkdir()
        check_cli(
            ["run", str(path), "--json", str(out / "run.json")], [path, imu, rig], [out / "run.json"], out
        )


def target_imu_csv(b: Base, data: st.DataObject) -> None:
    """IMU (increment or rate form) and truth CSVs mutated: ``sins integrate IMU --truth TRUTH``."""
    form = data.draw(st.sampled_from(["increment", "rate"]), label="form")
    imu_text = b.increment_csv if form == "increment" else b.rate_csv
    which = data.draw(st.sampled_from(["imu", "truth", "both"]), label="which")
    with workdir(b) as d:
        imu = _write(d / "imu.csv", mutate_lines(imu_text, data, 2) if which != "truth" else imu_text)
        truth = _write(d / "truth.csv", mutate_lines(b.truth_csv, data, 2) if which != "imu" else b.truth_csv)
        out = d / "out"
        out.mkdir()
        vertical = data.draw(st.sampled_from(["free", "hold", "damp"]), label="vertical")
        check_cli(["integrate", str(imu), "--truth", str(truth), "--vertical", vertical, "--json",
                   str(out / "nav.json")], [imu, truth], [out / "nav.json"], out)  # fmt: skip


def target_recording_csv(b: Base, data: st.DataObject) -> None:
    """A rig recording mutated: ``sins fit``, ``sins evaluate`` (with a good model) and ``sins gap``."""
    command = data.draw(st.sampled_from(["fit", "evaluate", "gap"]), label="command")
    with workdir(b) as d:
        rec = _write(d / "rec.csv", mutate_lines(b.recording_csv, data, 3))
        model = _write(d / "model.json", b.model_json)
        out = d / "out"
        out.mkdir()
        if command == "fit":
            strategy = data.draw(
                st.sampled_from(["none", "regression", "regression_extended"]), label="strategy"
            )
            validation = data.draw(st.sampled_from([[], ["--validation", "0.3"]]), label="validation")
            check_cli(["fit", str(rec), "--strategy", strategy, *validation, "--out", str(out / "m.json")],
                      [rec], [out / "m.json"], out)  # fmt: skip
        elif command == "evaluate":
            check_cli(["evaluate", str(model), str(rec), "--last", "0.3", "--json", str(out / "e.json")],
                      [rec, model], [out / "e.json"], out)  # fmt: skip
        else:
            check_cli(["gap", str(rec)], [rec], [], out)


def target_model_json(b: Base, data: st.DataObject) -> None:
    """A model file mutated (its text, or a value in its JSON): ``sins evaluate MODEL REC``."""
    with workdir(b) as d:
        if data.draw(st.booleans(), label="as text"):
            content: str | bytes = mutate_lines(b.model_json, data, 0)
        else:
            content = json.dumps(_mutate_json(json.loads(b.model_json), data))
        model = _write(d / "model.json", content)
        rec = _write(d / "rec.csv", b.recording_csv)
        out = d / "out"
        out.mkdir()
        check_cli(["evaluate", str(model), str(rec), "--json", str(out / "e.json")], [model, rec],
                  [out / "e.json"], out)  # fmt: skip


_JSON_VALUES: tuple[Any, ...] = (
    None, True, 0, -1, 1e300, -1e300, 1e-300, math.nan, math.inf, "x", [], [1.0], [[1.0, 2.0]], {}, 2,
    "regression", "none", "sins.compensation",
)  # fmt: skip


def _json_paths(doc: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out: list[tuple[Any, ...]] = [prefix] if prefix else []
    items = doc.items() if isinstance(doc, dict) else enumerate(doc) if isinstance(doc, list) else []
    for k, v in items:
        if isinstance(v, dict | list):
            out.extend(_json_paths(v, (*prefix, k)))
        else:
            out.append((*prefix, k))
    return out


def _mutate_json(doc: Any, data: st.DataObject) -> Any:
    """One or two values of a JSON document (any depth) replaced by :data:`_JSON_VALUES`, or deleted."""
    for _ in range(data.draw(st.integers(1, 2), label="edits")):
        path = data.draw(st.sampled_from(_json_paths(doc)), label="path")
        parent = _parent(doc, path)
        if data.draw(st.integers(0, 4), label="delete") == 0 and isinstance(parent, dict):
            del parent[path[-1]]
        else:
            parent[path[-1]] = copy.deepcopy(data.draw(st.sampled_from(_JSON_VALUES), label="value"))
    return doc


def target_quality(b: Base, data: st.DataObject) -> None:
    """A quality suite (its text or numbers) and baseline (its JSON) mutated: ``sins check``."""
    which = data.draw(st.sampled_from(["suite", "baseline", "case"]), label="which")
    with workdir(b) as d:
        for name in ("imu.toml", "rig.toml"):
            _write(d / name, (b.folder / name).read_text(encoding="utf-8"))
        suite = _write(d / "quality.toml", mutate_lines(SUITE, data, 0) if which == "suite" else SUITE)
        case = _write(d / "case.toml", to_toml(mutate_doc(MODEL_SCENARIO, data) if which == "case" else
                                               MODEL_SCENARIO))  # fmt: skip
        baseline_doc = json.loads(b.baseline_json)
        baseline = _write(d / "baseline.json", json.dumps(_mutate_json(baseline_doc, data)) if which ==
                          "baseline" else b.baseline_json)  # fmt: skip
        check_cli(["check", str(suite), "--baseline", str(baseline)], [suite, case, baseline], [], d,
                  ok=(0, 1))  # fmt: skip


# --------------------------------------------------------------------------- dataset readers


def _assert_read(read: Callable[[], Any], files: list[Path]) -> None:
    """A sound result (finite readings, increasing time) or one SinsInputError line naming a file."""
    try:
        with watchdog():
            result = read()
    except SinsInputError as exc:
        message = str(exc)
        assert "\n" not in message, message
        assert any(str(p) in message for p in files), f"names none of {files}: {message!r}"
        return
    data = result[0] if isinstance(result, tuple) else result
    assert len(data.t) > 0 and np.isfinite(data.t).all() and (np.diff(data.t) > 0).all()
    for name in ("gyro", "accel"):
        assert np.isfinite(getattr(data, name)).all(), name
    for name in ("ref_gyro", "ref_accel"):
        assert not np.isinf(getattr(data, name)).any(), name


def _ferraris_files(folder: Path) -> tuple[str, str]:
    rows = "\n".join(f"{k},0.5,-0.25,0.125,0.1,-0.2,9.8" for k in range(100))
    sections = {name: {"start": 10 * k, "end": 10 * k + 5} for k, name in enumerate(
        ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a", "x_rot", "y_rot", "z_rot"))}  # fmt: skip
    return f"n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n{rows}\n", json.dumps(sections, indent=1)


_LASER_HEADER = (
    "% PSINS-format SIMU text file\n% attitude and velocity\n0 0 -90 0 0 0\n% position, t0, interval, g\n"
    "34.2 108.9 380 10 10 9.780327\n% scales\n0.1 0.1 0.1 125 125 125\n"
)


def _laser_text() -> str:
    rows = "".join(f"{-1 + (k % 3 == 0)} {k % 2} 1 0 {-(k % 5 == 0)} 80\n" for k in range(60))
    return _LASER_HEADER + rows


def _broad_mat(n: int = 600) -> dict[str, Any]:
    """A short BROAD-like trial: a turning unit with optical orientation and position, some NaN rows."""
    from scipy.spatial.transform import Rotation

    from sins.io.datasets.broad import BROAD_GRAVITY, BROAD_RATE_HZ

    t = np.arange(n) / BROAD_RATE_HZ
    angles = np.stack([0.8 * np.sin(4.4 * t), 0.5 * np.sin(6.9 * t + 0.3), 0.6 * np.sin(3.1 * t + 1.0)], 1)
    att = Rotation.from_euler("ZYX", angles)
    h = 1e-6
    rate = (Rotation.from_euler("ZYX", angles - h).inv() * att).as_rotvec() / h  # backward difference
    pos = np.stack([0.2 * np.sin(5.0 * t), 0.1 * np.sin(8.2 * t), 1.5 + 0.05 * np.sin(12.6 * t)], 1)
    acc = -np.stack([0.2 * 25.0 * np.sin(5.0 * t), 0.1 * 8.2**2 * np.sin(8.2 * t),
                     0.05 * 12.6**2 * np.sin(12.6 * t)], 1)  # fmt: skip
    f = att.inv().apply(acc + np.array([0.0, 0.0, BROAD_GRAVITY]))
    quat = att.as_quat()[:, [3, 0, 1, 2]]
    quat[:20] = np.nan
    return {"imu_gyr": rate, "imu_acc": f, "imu_mag": np.zeros((n, 3)), "opt_quat": quat, "opt_pos": pos,
            "movement": np.ones(n, dtype=np.uint8), "sampling_rate": BROAD_RATE_HZ,
            "info": "synthetic"}  # fmt: skip


def _mutate_array(a: np.ndarray, data: st.DataObject) -> np.ndarray:
    a = np.array(a, dtype=float)
    kind = data.draw(st.sampled_from(["value", "truncate", "drop column"]), label="array edit")
    if kind == "value" and a.size:
        i = data.draw(st.integers(0, a.size - 1), label="index")
        a.flat[i] = data.draw(st.sampled_from([np.nan, np.inf, -np.inf, 1e300, -1e300, 0.0, -0.0, 1e-300]))
    elif kind == "truncate" and a.ndim:
        a = a[: data.draw(st.integers(0, len(a)), label="rows")]
    elif kind == "drop column" and a.ndim == 2 and a.shape[1]:
        a = a[:, 1:]
    return a


def target_datasets(b: Base, data: st.DataObject) -> None:
    """The dataset readers on mutated synthetic files (text, xz, MAT: bytes and values)."""
    from sins import io
    from sins.io import datasets
    from sins.io.datasets.broad import BROAD_FOLDER, BROAD_TRIALS
    from sins.io.datasets.psins_lasergyro import PSINS_LASERGYRO_FILE, PSINS_LASERGYRO_FOLDER
    from sins.io.datasets.psins_vehicle import PSINS_VEHICLE_FILE, PSINS_VEHICLE_FOLDER

    name = data.draw(st.sampled_from(["ferraris", "psins_lasergyro", "psins_vehicle", "broad_05"]))
    with workdir(b) as root:
        if name == "ferraris":
            folder = root / datasets.FERRARIS_FOLDER
            folder.mkdir()
            csv_text, sections = _ferraris_files(folder)
            which = data.draw(st.sampled_from(["csv", "json"]), label="which")
            csv = _write(folder / "example_ferraris_session.csv",
                         mutate_lines(csv_text, data, 1) if which == "csv" else csv_text)  # fmt: skip
            js = _write(folder / "example_ferraris_session_list.json",
                        mutate_lines(sections, data, 0) if which == "json" else sections)  # fmt: skip
            files = [csv, js]
        elif name == "psins_lasergyro":
            folder = root / PSINS_LASERGYRO_FOLDER
            folder.mkdir()
            raw = lzma.compress(mutate_lines(_laser_text(), data, 0))
            if data.draw(st.integers(0, 3), label="damage the xz") == 0:
                raw = mutate_bytes(raw, data)
            files = [_write(folder / PSINS_LASERGYRO_FILE, raw)]
        else:
            folder = root / (PSINS_VEHICLE_FOLDER if name == "psins_vehicle" else BROAD_FOLDER)
            folder.mkdir()
            content = synthetic_recording() if name == "psins_vehicle" else _broad_mat()
            path = folder / (PSINS_VEHICLE_FILE if name == "psins_vehicle" else f"{BROAD_TRIALS[0]}.mat")
            if data.draw(st.booleans(), label="values"):
                key = data.draw(
                    st.sampled_from(sorted(k for k, v in content.items() if isinstance(v, np.ndarray)))
                )
                content[key] = _mutate_array(content[key], data)
                scipy.io.savemat(path, content)
            else:
                scipy.io.savemat(path, content)
                path.write_bytes(mutate_bytes(path.read_bytes(), data))
            files = [path]
        _assert_read(lambda: io.read(dataset=name, root=root).reference_inputs(), [*files, root])


# --------------------------------------------------------------------------- registry and CI tests

#: Every target by name, with its CI example count (1-10 s each on one core).
TARGETS: dict[str, tuple[Callable[[Base, st.DataObject], None], int]] = {
    "scenario_values": (target_scenario_values, 200),
    "scenario_bytes": (target_scenario_bytes, 200),
    "imu_and_rig_values": (target_imu_and_rig_values, 100),
    "imu_and_rig_bytes": (target_imu_and_rig_bytes, 80),
    "scenario_model_files": (target_scenario_model_files, 60),
    "imu_csv": (target_imu_csv, 300),
    "recording_csv": (target_recording_csv, 60),
    "model_json": (target_model_json, 200),
    "quality": (target_quality, 40),
    "datasets": (target_datasets, 150),
}


def run_target(name: str, b: Base, data: st.DataObject) -> None:
    """One example of target ``name`` (counted in :data:`EXAMPLES`)."""
    EXAMPLES[name] += 1
    TARGETS[name][0](b, data)


@ci(TARGETS["scenario_values"][1])
@given(data=st.data())
def test_scenario_values(base: Base, data: st.DataObject) -> None:
    run_target("scenario_values", base, data)


@ci(TARGETS["scenario_bytes"][1])
@given(data=st.data())
def test_scenario_bytes(base: Base, data: st.DataObject) -> None:
    run_target("scenario_bytes", base, data)


@ci(TARGETS["imu_and_rig_values"][1])
@given(data=st.data())
def test_imu_and_rig_values(base: Base, data: st.DataObject) -> None:
    run_target("imu_and_rig_values", base, data)


@ci(TARGETS["imu_and_rig_bytes"][1])
@given(data=st.data())
def test_imu_and_rig_bytes(base: Base, data: st.DataObject) -> None:
    run_target("imu_and_rig_bytes", base, data)


@ci(TARGETS["scenario_model_files"][1])
@given(data=st.data())
def test_scenario_model_files(base: Base, data: st.DataObject) -> None:
    run_target("scenario_model_files", base, data)


@ci(TARGETS["imu_csv"][1])
@given(data=st.data())
def test_imu_csv(base: Base, data: st.DataObject) -> None:
    run_target("imu_csv", base, data)


@ci(TARGETS["recording_csv"][1])
@given(data=st.data())
def test_recording_csv(base: Base, data: st.DataObject) -> None:
    run_target("recording_csv", base, data)


@ci(TARGETS["model_json"][1])
@given(data=st.data())
def test_model_json(base: Base, data: st.DataObject) -> None:
    run_target("model_json", base, data)


@ci(TARGETS["quality"][1])
@given(data=st.data())
def test_quality(base: Base, data: st.DataObject) -> None:
    run_target("quality", base, data)


@ci(TARGETS["datasets"][1])
@given(data=st.data())
def test_datasets(base: Base, data: st.DataObject) -> None:
    run_target("datasets", base, data)


def test_the_base_files_are_sound(base: Base) -> None:
    """The mutations start from files every command takes (else the targets would test nothing)."""
    with workdir(base) as d:
        for doc in (SCENARIO, WAYPOINTS, TRUTH_SCENARIO, MODEL_SCENARIO):
            (d / "truth.csv").write_text(base.truth_csv, encoding="utf-8")
            for name in ("imu.toml", "rig.toml"):
                (d / name).write_text((base.folder / name).read_text(encoding="utf-8"), encoding="utf-8")
            path = _write(d / "s.toml", to_toml(doc))
            rc, out, err = run_cli(["run", str(path)])
            assert rc == 0, err
    assert "final" in out
    for line in base.recording_csv.splitlines()[:3]:
        assert line.startswith("#")
    assert os.path.getsize(base.folder / "baseline.json") > 0


def test_the_watchdog_stops_a_spin_and_a_block_but_not_a_slow_example(tmp_path: Path) -> None:
    """Hangs by CPU time and progress, never wall time: a loop spinning past its CPU budget is stopped;
    a FIFO's reader (blocked: no CPU at all) is stopped once it has stalled; an example that works a
    fifth of the time (what a machine at load 5 gives a process) runs to its end."""
    import time

    with pytest.raises(Hang, match="CPU"), watchdog(cpu_s=1.0):
        while True:
            pass
    fifo = tmp_path / "f"
    os.mkfifo(fifo)
    with pytest.raises(Hang, match="no progress"), watchdog(stall_s=2.0, stall_cpu_s=0.05):
        fifo.read_bytes()  # blocks in open() until a writer comes: none will
    worked = 0
    with watchdog(cpu_s=60.0, stall_s=1.0, stall_cpu_s=0.05):
        start = time.process_time()
        while time.process_time() - start < 0.6:  # 0.6 s of CPU over about 3 s
            tick = time.process_time()
            while time.process_time() - tick < 0.01:
                worked += 1
            time.sleep(0.04)
    assert worked > 0
