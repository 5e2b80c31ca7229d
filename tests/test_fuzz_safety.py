"""Fuzzed paths and recordings (issue 41): outputs aliasing inputs, special files, degenerate and still
recordings fitted, bags, EuRoC folders and ``.npz`` recordings mutated.

The property is :mod:`test_fuzz`'s (exit 0 with a sound result, or exit 2 and one line naming an input or
an output; never a traceback or a hang; no temporary file left at any depth), and for every example:

* **no input changed**: every input is hashed before and after (:func:`test_fuzz.snapshot`; a FIFO or a
  device by its kind, never opened), and an output that is an input, by any path, is refused (exit 2);
* **special files stay what they were**: a FIFO, a character device or a symbolic link given as an
  output is one after (a device is written in place: as root, the examples use a device node of their
  own, so that a regression replaces that node and not the machine's ``/dev/null``);
* **no fitted model beyond its class**: a fit that ends 0 writes only coefficients with a finite standard
  error within the class's spread and a value within its bound (:mod:`sins.compensation.identifiability`),
  read back from its ``--json``; held ones are zero (:class:`BeyondBounds` otherwise).

``tools/fuzz_long.py`` runs these targets at length beside the others; the suite runs a few examples of
each (``@settings(derandomize=True)``).
"""

from __future__ import annotations

import json
import os
import shutil
import stat
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_fuzz import (
    IMU_MODEL,
    RIG,
    TOKENS,
    _write,
    assert_one_line,
    check_unchanged,
    ci,
    mutate_bytes,
    mutate_lines,
    run_cli,
    snapshot,
    to_toml,
    workdir,
)

from sins.compensation import identifiability
from sins.core.earth import G0
from sins.imu import DEG_PER_H
from sins.io.paths import writes_in_place

#: A drive of 30 s that turns about every axis, climbs, rolls and pitches (what a fit can determine).
DRIVE: dict[str, Any] = {
    "name": "drive",
    "imu": {"rate_hz": 20, "seed": 3},
    "initial": {"lat_deg": 45.0, "alt_m": 100.0, "speed_mps": 5.0, "yaw_deg": 30.0},
    "segment": [
        {"type": "accelerate", "duration_s": 4.0, "to_speed_mps": 8.0},
        {"type": "turn", "duration_s": 5.0, "rate_dps": 20.0, "ramp_s": 0.5},
        {"type": "attitude", "duration_s": 5.0, "roll_deg": 20.0, "pitch_deg": 10.0, "yaw_deg": 40.0,
         "ramp_s": 0.5},
        {"type": "climb", "duration_s": 5.0, "angle_deg": 8.0, "ramp_s": 0.5},
        {"type": "attitude", "duration_s": 5.0, "roll_deg": -15.0, "pitch_deg": -5.0, "yaw_deg": -30.0,
         "ramp_s": 0.5},
        {"type": "hold", "duration_s": 6.0},
    ],
}  # fmt: skip
GRADES = ("consumer", "industrial", "tactical", "navigation")


@dataclass(frozen=True)
class SafetyBase:
    """The small valid files the targets start from (in ``folder``: every file a command reads)."""

    folder: Path


def make_base(folder: Path) -> SafetyBase:
    """Write, simulate and fit the base files in ``folder``."""
    from test_readers import _euroc
    from test_safety import _still_bag

    _write(folder / "s.toml", to_toml(DRIVE))
    _write(folder / "imu.toml", to_toml(IMU_MODEL))
    _write(folder / "rig.toml", to_toml(RIG))
    for argv in (
        ["simulate", str(folder / "s.toml"), "--model", "tactical", "--imu", str(folder / "drive.csv"),
         "--truth", str(folder / "truth.csv")],
        ["calibrate", str(folder / "rig.toml"), "--imu", str(folder / "imu.toml"), "--out",
         str(folder / "rig.csv")],
        ["fit", str(folder / "rig.csv"), "--strategy", "regression", "--out", str(folder / "m.json")],
    ):  # fmt: skip
        rc, _, err = run_cli(argv)
        assert rc == 0, err
    rng = np.random.default_rng(1)
    rows = 1200
    gravity = np.array([0.0, 0.0, -9.80665])
    readings = np.column_stack([np.arange(rows) / 20.0, rng.normal(0.0, 1e-3, (rows, 3)),
                                gravity + rng.normal(0.0, 2e-3, (rows, 3))])  # fmt: skip
    header = "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"
    np.savetxt(folder / "static.csv", readings, delimiter=",", header=header, comments="", fmt="%.17g")
    _still_bag(folder / "still.bag", seconds=25.0)
    _euroc(folder / "euroc")
    _npz_arrays(folder / "rec.npz")
    return SafetyBase(folder)


@pytest.fixture(scope="module")
def base(tmp_path_factory: pytest.TempPathFactory) -> SafetyBase:
    return make_base(tmp_path_factory.mktemp("fuzz_safety"))


def _npz_arrays(path: Path, n: int = 6000, seed: int = 3) -> dict[str, np.ndarray]:
    """A 30 s ``.npz`` recording turning about every axis, its reference exact (the shared EuRoC form)."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    t = 1.4e9 + np.arange(n) / 200.0
    rates = np.column_stack([0.4 * np.sin(0.7 * (t - t[0])), 0.3 * np.cos(0.5 * (t - t[0])), np.full(n, 0.2)])
    q = Rotation.identity()
    qs = []
    for k in range(n):  # the attitude the rates integrate to (body axes), step by step
        qs.append(q.as_quat(scalar_first=True))
        q = q * Rotation.from_rotvec(rates[k] / 200.0)
    q_wxyz = np.array(qs)
    g_body = Rotation.from_quat(q_wxyz, scalar_first=True).inv().apply([0.0, 0.0, 9.81])
    arrays = {
        "t_s": t,
        "gyro_rad_s": (rates + rng.normal(0, 1e-3, (n, 3)) + 2e-3).astype(np.float32),
        "accel_m_s2": (g_body + rng.normal(0, 1e-2, (n, 3))).astype(np.float32),
        "q_wxyz": q_wxyz.astype(np.float32),
        "v_m_s": np.zeros((n, 3), np.float32),
        "p_m": np.zeros((n, 3), np.float32),
    }
    np.savez(path, **arrays)
    return arrays


#: Fits written and checked (their coefficients kept and held), for the reports of tools/fuzz_long.py.
FITS: Counter[str] = Counter()


class BeyondBounds(AssertionError):
    """A fit ended 0 and wrote a coefficient beyond its class's bounds (or not determined)."""


def check_fit_document(path: Path, grade: str) -> None:
    """A ``sins fit --json`` document: every coefficient kept within ``grade``'s bounds, every held one
    zero (see the module docstring)."""
    doc = json.loads(path.read_text())
    bounds = identifiability.class_bounds(grade)
    FITS["models"] += 1
    FITS["held"] += len(doc.get("held", {}))
    units = {"°/h": DEG_PER_H, "µg": 1e-6 * G0, "ppm": 1e-6, "mrad": 1e-3, "°/h/g": DEG_PER_H / G0}
    for c in doc.get("coefficients", []):
        name = f"{c['sensor']}.{c['term']}.{c['axis']}"
        value = c["value"] * units[c["unit"]]
        if name in doc.get("held", {}):
            if value != 0.0:
                raise BeyondBounds(f"{name} held but {c['value']} {c['unit']}")
            continue
        if c["se"] is None:
            continue  # not part of the model (a g-sensitivity left out): zero, checked by review
        se = c["se"] * units[c["unit"]]
        if not (abs(value) <= bounds.largest(name) and se <= bounds.limit(name)):
            raise BeyondBounds(f"{name} = {c['value']} ± {c['se']} {c['unit']} for a {grade} unit")
        FITS["kept"] += 1


def _run(argv: list[str], inputs: list[Path], folder: Path, aliased: bool = False) -> tuple[int, str, str]:
    """Run ``argv``: the fuzz property (see the module docstring); ``aliased``: an output is an input,
    which must be refused."""
    before = snapshot(inputs)
    rc, out, err = run_cli(argv)
    check_unchanged(before, argv)
    leftovers = [str(p) for p in folder.rglob("*.tmp")]
    assert not leftovers, f"temporary files left behind: {leftovers}"
    if aliased:
        assert rc == 2, f"an output aliasing an input was written: {argv}: {out[-300:]}"
    if rc != 0:
        assert rc == 2, f"exit status {rc} for {argv}; stderr: {err!r}"
        assert_one_line(err, [Path(a) for a in argv if "/" in a or "." in a] + inputs)
    return rc, out, err


# --------------------------------------------------------------------------- outputs


def _device(folder: Path, name: str) -> Path:
    from test_safety import device

    return device(folder, name)


#: Each command: its argv (``{n}`` the input file n, copied into the example's folder; ``OUT1``,
#: ``OUT2`` the outputs) and its inputs.
COMMANDS: dict[str, tuple[str, tuple[str, ...]]] = {
    "fit_rig": ("fit {rig.csv} --strategy none --out OUT1 --json OUT2", ("rig.csv",)),
    "fit_truth": ("fit {drive.csv} --truth {truth.csv} --strategy bias_only --out OUT1 --json OUT2",
                  ("drive.csv", "truth.csv")),
    "evaluate": ("evaluate {m.json} {rig.csv} --json OUT1", ("m.json", "rig.csv")),
    "correct": ("correct {m.json} {rig.csv} --out OUT1", ("m.json", "rig.csv")),
    "integrate": ("integrate {drive.csv} --truth {truth.csv} --out OUT1 --json OUT2",
                  ("drive.csv", "truth.csv")),
    "inspect": ("inspect {drive.csv} --json OUT1", ("drive.csv",)),
    "characterise": ("characterise {static.csv} --static --out OUT1 --json OUT2", ("static.csv",)),
    "simulate": ("simulate {s.toml} --imu OUT1 --truth OUT2", ("s.toml",)),
    "calibrate": ("calibrate {rig.toml} --imu {imu.toml} --out OUT1", ("rig.toml", "imu.toml")),
    "run": ("run {s.toml} --json OUT1", ("s.toml",)),
}  # fmt: skip
#: What an output may be: a fresh name, or an input by some path, or a special file.
ALIASES = ("input", "hard link", "symbolic link", "dotted", "other output")
SPECIALS = ("null device", "full device", "FIFO", "folder", "link to a fresh name", "missing folder",
            "link to a missing folder")  # fmt: skip


def _output(
    d: Path, kind: str, inputs: list[Path], slot: int, first: Path | None, data: st.DataObject
) -> Path:
    """An output path of ``kind`` in ``d``."""
    source = inputs[data.draw(st.integers(0, len(inputs) - 1), label="input")] if inputs else None
    fresh = d / "out" / f"o{slot}.json"
    if kind == "fresh" or source is None:
        return fresh
    if kind == "input":
        return source
    if kind == "hard link":
        os.link(source, d / f"hard{slot}")
        return d / f"hard{slot}"
    if kind == "symbolic link":
        (d / f"sym{slot}").symlink_to(source)
        return d / f"sym{slot}"
    if kind == "dotted":
        return d / "out" / ".." / source.name
    if kind == "other output":
        return first if first is not None else fresh
    if kind in ("null device", "full device"):
        return _device(d, "null" if kind == "null device" else "full")
    if kind == "FIFO":
        os.mkfifo(d / f"fifo{slot}")
        return d / f"fifo{slot}"
    if kind == "folder":
        (d / f"dir{slot}").mkdir()
        return d / f"dir{slot}"
    if kind == "link to a fresh name":
        (d / f"link{slot}").symlink_to(d / "out" / f"target{slot}")
        return d / f"link{slot}"
    if kind == "link to a missing folder":
        (d / f"gone{slot}").symlink_to(d / "nowhere" / "x")
        return d / f"gone{slot}"
    return d / "nowhere" / f"o{slot}.json"


def target_output_paths(b: SafetyBase, data: st.DataObject) -> None:
    """A command's outputs drawn among fresh names, its inputs by any path, each other and special
    files: an alias is refused, no input changes, special files stay special."""
    name = data.draw(st.sampled_from(sorted(COMMANDS)), label="command")
    template, names = COMMANDS[name]
    with workdir(b) as d:
        (d / "out").mkdir()
        inputs = [Path(shutil.copy(b.folder / n, d / n)) for n in names]
        argv = template.split()
        for n, path in zip(names, inputs, strict=True):
            argv = [a.replace("{" + n + "}", str(path)) for a in argv]
        kinds, first, aliased = [], None, False
        for slot in (1, 2):
            if f"OUT{slot}" not in argv:
                continue
            kind = data.draw(st.sampled_from(["fresh", "fresh", *ALIASES, *SPECIALS]), label=f"out{slot}")
            if kind == "other output" and first is None:
                kind = "fresh"
            path = _output(d, kind, inputs, slot, first, data)
            if kind == "other output" and first is not None and writes_in_place(first):
                kind = "null device"  # the same device twice: written in place twice, as asked
            first = path if first is None else first
            aliased = aliased or kind in ALIASES
            kinds.append((kind, path))
            argv[argv.index(f"OUT{slot}")] = str(path)
        specials = {str(p): _kind(p) for k, p in kinds if k in ("FIFO", "null device", "full device")}
        links = [p for k, p in kinds if "link" in k and k != "hard link"]
        _run(argv, inputs, d, aliased)
        for path, kind in specials.items():
            assert _kind(Path(path)) == kind, f"{path} was {kind}, is {_kind(Path(path))}"
        for link in links:
            assert link.is_symlink(), f"{link} is no longer a link"


def _kind(path: Path) -> int:
    return stat.S_IFMT(os.lstat(path).st_mode)


# --------------------------------------------------------------------------- inputs that are not files


#: Commands and the input slot to replace: argv (``{IN}`` the replaced input, ``{n}`` the others).
READS: tuple[tuple[str, str, tuple[str, ...]], ...] = (
    ("inspect {IN}", "drive.csv", ()),
    ("integrate {IN} --truth {truth.csv}", "drive.csv", ("truth.csv",)),
    ("integrate {drive.csv} --truth {IN}", "truth.csv", ("drive.csv",)),
    ("fit {drive.csv} --truth {IN} --strategy bias_only --out out/m.json", "truth.csv", ("drive.csv",)),
    ("fit {IN} --strategy none --out out/m.json", "rig.csv", ()),
    ("evaluate {IN} {rig.csv}", "m.json", ("rig.csv",)),
    ("evaluate {m.json} {IN}", "rig.csv", ("m.json",)),
    ("correct {m.json} {IN} --out out/c.csv", "rig.csv", ("m.json",)),
    ("run {IN}", "s.toml", ()),
    ("calibrate {rig.toml} --imu {IN} --out out/r.csv", "imu.toml", ("rig.toml",)),
    ("characterise {IN} --static", "static.csv", ()),
    ("inspect {IN}", "rec.npz", ()),
)
REPLACEMENTS = ("FIFO", "zero device", "null device", "folder", "link to a FIFO", "empty file", "garbage")


def target_special_inputs(b: SafetyBase, data: st.DataObject) -> None:
    """One input of a command replaced by a FIFO, a device, a folder, a link to a FIFO, an empty file or
    bytes of garbage: one line, no hang (a FIFO blocked its reader for ever, /dev/zero never ended)."""
    template, replaced, others = data.draw(st.sampled_from(READS), label="command")
    kind = data.draw(st.sampled_from(REPLACEMENTS), label="replacement")
    with workdir(b) as d:
        (d / "out").mkdir()
        inputs = [Path(shutil.copy(b.folder / n, d / n)) for n in others]
        target = d / replaced
        if kind in ("FIFO", "link to a FIFO"):
            os.mkfifo(d / "pipe")
            if kind == "FIFO":
                os.rename(d / "pipe", target)
            else:
                target.symlink_to(d / "pipe")
        elif kind == "zero device":
            target = Path("/dev/zero")
        elif kind == "null device":
            target = _device(d, "null")
        elif kind == "folder":
            target.mkdir()
        elif kind == "empty file":
            target.write_bytes(b"")
        else:
            target.write_bytes(bytes(data.draw(st.binary(min_size=1, max_size=400), label="garbage")))
        argv = [a.replace("{IN}", str(target)) for a in template.split()]
        for n, path in zip(others, inputs, strict=True):
            argv = [a.replace("{" + n + "}", str(path)) for a in argv]
        argv = [str(d / a) if a.startswith("out/") else a for a in argv]
        rc, _, _ = _run(argv, [*inputs, target], d)
        if kind not in ("empty file", "garbage"):
            assert rc == 2, f"{kind} as {replaced} was read: {argv}"


# --------------------------------------------------------------------------- fits of degenerate recordings


def _segments(data: st.DataObject) -> list[dict[str, Any]]:
    """One to four segments: holds (a still recording when alone), turns about the vertical, climbs,
    attitude changes, accelerations."""
    kinds = data.draw(
        st.lists(st.sampled_from(["hold", "hold", "turn", "climb", "attitude", "accelerate"]), min_size=1,
                 max_size=4), label="segments")  # fmt: skip
    total = data.draw(st.sampled_from([22.0, 30.0, 45.0]), label="seconds")
    out = []
    for kind in kinds:
        seg: dict[str, Any] = {"type": kind, "duration_s": total / len(kinds)}
        if kind == "turn":
            seg["rate_dps"] = data.draw(st.sampled_from([-30.0, 5.0, 45.0]), label="rate")
        elif kind == "climb":
            seg["angle_deg"] = data.draw(st.sampled_from([-5.0, 3.0, 10.0]), label="climb")
        elif kind == "attitude":
            angles = ("roll_deg", "pitch_deg", "yaw_deg")
            seg |= {k: data.draw(st.sampled_from([-20.0, 0.0, 15.0]), label=k) for k in angles}
        elif kind == "accelerate":
            seg["delta_speed_mps"] = data.draw(st.sampled_from([-2.0, 3.0]), label="speed")
        out.append(seg)
    return out


def target_degenerate_fits(b: SafetyBase, data: st.DataObject) -> None:
    """Recordings that determine some coefficients, few or none (still, yaw alone, short, one climb) of
    units of any grade (or ideal), fitted against their truth: refused in one line, or every coefficient
    written within its class's bounds, the undetermined held at zero."""
    rate = data.draw(st.sampled_from([20, 50]), label="rate")
    lat = data.draw(st.sampled_from([0.0, 45.0, 80.0]), label="lat")
    doc = {"name": "degenerate", "imu": {"rate_hz": rate, "seed": 1},
           "initial": {"lat_deg": lat, "speed_mps": 0.0}, "segment": _segments(data)}  # fmt: skip
    model = data.draw(st.sampled_from([*GRADES, None]), label="unit")
    grade = data.draw(st.sampled_from([*GRADES, None]), label="grade")
    strategy = data.draw(st.sampled_from(["regression", "regression", "bias_only", "regression_robust"]))
    with workdir(b) as d:
        scenario = _write(d / "s.toml", to_toml(doc))
        imu, truth = d / "imu.csv", d / "truth.csv"
        argv = ["simulate", str(scenario), "--imu", str(imu), "--truth", str(truth)]
        rc, _, err = run_cli([*argv, *(["--model", model] if model else [])])
        if rc != 0:
            assert_one_line(err, [scenario])
            return
        out = d / "out"
        out.mkdir()
        fit = ["fit", str(imu), "--truth", str(truth), "--strategy", strategy, "--out", str(out / "m.json"),
               "--json", str(out / "f.json"), *(["--grade", grade] if grade else [])]  # fmt: skip
        rc, _, _ = _run(fit, [imu, truth], out)
        if rc == 0:
            check_fit_document(out / "f.json", grade or identifiability.DEFAULT_GRADE)


def target_rig_fits(b: SafetyBase, data: st.DataObject) -> None:
    """Rig sessions that turn about some axes and hold some positions (none, six, twelve) of units of any
    grade, fitted: refused in one line, or the seed model within its class's bounds."""
    rig = json.loads(json.dumps(RIG))
    rig["positions"]["count"] = data.draw(st.sampled_from([0, 6, 12]), label="positions")
    rig["rate_table"]["axes"] = data.draw(st.lists(st.sampled_from(["x", "y", "z"]), min_size=1, max_size=3,
                                                   unique=True), label="axes")  # fmt: skip
    model = data.draw(st.sampled_from(GRADES), label="unit")
    with workdir(b) as d:
        rig_toml = _write(d / "rig.toml", to_toml(rig))
        rec = d / "rig.csv"
        rc, _, err = run_cli(["calibrate", str(rig_toml), "--imu", model, "--out", str(rec)])
        if rc != 0:
            assert_one_line(err, [rig_toml])
            return
        out = d / "out"
        out.mkdir()
        strategy = data.draw(st.sampled_from(["regression", "regression_robust"]), label="strategy")
        rc, _, _ = _run(["fit", str(rec), "--strategy", strategy, "--out", str(out / "m.json"), "--json",
                         str(out / "f.json")], [rec], out)  # fmt: skip
        if rc == 0:
            check_fit_document(out / "f.json", identifiability.DEFAULT_GRADE)


# --------------------------------------------------------------------------- bags, EuRoC, npz


def target_bags(b: SafetyBase, data: st.DataObject) -> None:
    """A still bag with its own poses, written with a mutation (a zero quaternion, a NaN reading, two pose
    topics, poses ending early) or its bytes damaged: inspected, integrated, fitted."""
    from test_safety import _still_bag

    how = data.draw(st.sampled_from(["zero quaternion", "nan", "two poses", "poses end", "bytes", "as is"]))
    with workdir(b) as d:
        bag = d / "b.bag"
        seconds = data.draw(st.sampled_from([5.0, 25.0]), label="seconds")
        if how == "bytes":
            bag.write_bytes(mutate_bytes((b.folder / "still.bag").read_bytes(), data))
        else:
            _still_bag(
                bag, seconds=seconds,
                zero_quaternion_at=data.draw(st.integers(0, 20)) if how == "zero quaternion" else None,
                nan_reading_at=data.draw(st.integers(0, 400)) if how == "nan" else None,
                pose_topics=("/a", "/b") if how == "two poses" else ("/pose",),
                poses_end_s=data.draw(st.floats(0.0, seconds)) if how == "poses end" else None,
            )  # fmt: skip
        out = d / "out"
        out.mkdir()
        command = data.draw(st.sampled_from(["inspect", "integrate", "fit", "characterise"]), label="command")
        argv = {
            "inspect": ["inspect", str(bag)],
            "integrate": ["integrate", str(bag), "--json", str(out / "n.json")],
            "fit": ["fit", str(bag), "--origin", "45,0,0", "--strategy", "regression", "--out",
                    str(out / "m.json"), "--json", str(out / "f.json")],
            "characterise": ["characterise", str(bag), "--static"],
        }[command]  # fmt: skip
        rc, _, _ = _run(argv, [bag], out)
        if rc == 0 and command == "fit":
            check_fit_document(out / "f.json", identifiability.DEFAULT_GRADE)


def target_euroc(b: SafetyBase, data: st.DataObject) -> None:
    """A EuRoC folder with its IMU file, reference or ``sensor.yaml`` mutated (lines, fields, stamps
    beyond 64 bits) or replaced by a FIFO: inspected, integrated."""
    with workdir(b) as d:
        root = Path(shutil.copytree(b.folder / "euroc", d / "euroc"))
        mav = root / "mav0"
        which = data.draw(st.sampled_from(["imu0/data.csv", "state_groundtruth_estimate0/data.csv",
                                           "imu0/sensor.yaml"]), label="file")  # fmt: skip
        path = mav / which
        if data.draw(st.integers(0, 9), label="fifo") == 0:
            path.unlink()
            os.mkfifo(path)
        elif data.draw(st.booleans(), label="stamp"):
            lines = path.read_text().splitlines()
            k = data.draw(st.integers(1, len(lines) - 1), label="line")
            cells = lines[k].split(",")
            cells[0] = data.draw(st.sampled_from(["99999999999999999999", "-5", "1e19", "9223372036854775808",
                                                  "0", "x"]), label="stamp")  # fmt: skip
            lines[k] = ",".join(cells)
            path.write_text("\n".join(lines) + "\n")
        else:
            path.write_bytes(mutate_lines(path.read_text(), data, 1))
        argv = data.draw(st.sampled_from([["inspect", str(root)], ["integrate", str(root)]]), label="command")
        _run(argv, [root], d)


def target_npz(b: SafetyBase, data: st.DataObject) -> None:
    """An ``.npz`` recording with a key missing, lengths that disagree, non-finite or huge values, time
    that does not increase, another shape or a zero quaternion: inspected, integrated, fitted alone or
    with another recording of the unit (a fit on several)."""
    arrays = dict(np.load(b.folder / "rec.npz"))
    key = data.draw(st.sampled_from(sorted(arrays)), label="key")
    how = data.draw(st.sampled_from(["drop", "shorter", "value", "time back", "shape", "zero quaternion",
                                     "as is"]), label="how")  # fmt: skip
    a = np.array(arrays[key], dtype=float)
    if how == "drop":
        del arrays[key]
    elif how == "shorter":
        arrays[key] = a[: data.draw(st.integers(0, len(a) - 1), label="rows")]
    elif how == "value":
        a.flat[data.draw(st.integers(0, a.size - 1), label="at")] = data.draw(
            st.sampled_from([np.nan, np.inf, -np.inf, 1e300, -1e30, 0.0]), label="value")  # fmt: skip
        arrays[key] = a
    elif how == "time back":
        t = np.array(arrays["t_s"], dtype=float)
        k = data.draw(st.integers(1, len(t) - 1), label="row")
        t[k] = t[k - 1] - data.draw(st.sampled_from([0.0, 1e-3, 10.0]), label="back")
        arrays["t_s"] = t
    elif how == "shape":
        arrays[key] = a.reshape(len(a), -1)[:, :1] if a.ndim > 1 else np.column_stack([a, a])
    elif how == "zero quaternion":
        q = np.array(arrays["q_wxyz"], dtype=float)
        q[data.draw(st.integers(0, len(q) - 1), label="row")] = 0.0
        arrays["q_wxyz"] = q
    with workdir(b) as d:
        path = d / "rec.npz"
        np.savez(path, **arrays)
        out = d / "out"
        out.mkdir()
        command = data.draw(st.sampled_from(["inspect", "integrate", "fit", "fit two"]), label="command")
        other = Path(shutil.copy(b.folder / "rec.npz", d / "other.npz"))
        fit = ["--strategy", "regression", "--out", str(out / "m.json"), "--json", str(out / "f.json")]
        argv = {"inspect": ["inspect", str(path)], "integrate": ["integrate", str(path)],
                "fit": ["fit", str(path), *fit],
                "fit two": ["fit", str(path), str(other), *fit]}[command]  # fmt: skip
        rc, _, _ = _run(argv, [path, other], out)
        if rc == 0 and command.startswith("fit"):
            check_fit_document(out / "f.json", identifiability.DEFAULT_GRADE)


#: Every target by name with its CI example count.
TARGETS: dict[str, tuple[Callable[[SafetyBase, st.DataObject], None], int]] = {
    "output_paths": (target_output_paths, 40),
    "special_inputs": (target_special_inputs, 30),
    "degenerate_fits": (target_degenerate_fits, 12),
    "rig_fits": (target_rig_fits, 6),
    "bags": (target_bags, 12),
    "euroc": (target_euroc, 15),
    "npz": (target_npz, 15),
}
EXAMPLES: dict[str, int] = dict.fromkeys(TARGETS, 0)


def run_target(name: str, b: SafetyBase, data: st.DataObject) -> None:
    """One example of target ``name`` (counted in :data:`EXAMPLES`)."""
    EXAMPLES[name] += 1
    TARGETS[name][0](b, data)


@pytest.mark.parametrize("name", sorted(TARGETS))
def test_target(base: SafetyBase, name: str) -> None:
    @ci(TARGETS[name][1])
    @given(data=st.data())
    def body(data: st.DataObject) -> None:
        run_target(name, base, data)

    body()


def test_the_base_files_are_sound(base: SafetyBase, tmp_path: Path) -> None:
    """The mutations start from inputs every command takes, and the drive determines most coefficients
    (else the fits would test only refusals)."""
    out = tmp_path / "f.json"
    rc, _, err = run_cli(["fit", str(base.folder / "drive.csv"), "--truth", str(base.folder / "truth.csv"),
                          "--strategy", "regression", "--out", str(tmp_path / "m.json"),
                          "--json", str(out)])  # fmt: skip
    assert rc == 0, err
    check_fit_document(out, identifiability.DEFAULT_GRADE)
    for argv in (["inspect", str(base.folder / "still.bag")], ["inspect", str(base.folder / "euroc")],
                 ["integrate", str(base.folder / "rec.npz")]):  # fmt: skip
        rc, _, err = run_cli(argv)
        assert rc == 0, err
    assert TOKENS
