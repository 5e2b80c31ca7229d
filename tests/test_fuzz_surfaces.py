"""Fuzzed inputs of the newer surfaces (issue 35): campaign files and the files they name, aided
scenarios, model files of every strategy, ``sins characterise``'s inputs, the campaign gate's baseline
and ``sins gap`` with a truth.

The property is :mod:`test_fuzz`'s, for every example: exit 0 with a sound result, or exit 2 and one
line naming an input or an output; never a traceback or a hang; no temporary file left at any depth.
The mutations are :mod:`test_fuzz`'s (values pushed to extremes, keys dropped or added, bytes, lines
and fields), and for model files any value replaced by another kind, size or shape of array. A campaign
that passes its checks runs on a local cluster of one worker (each such example takes seconds), so the
CI profile runs few of those; ``tools/fuzz_long.py`` runs them all at length.
"""

from __future__ import annotations

import copy
import json
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_fuzz import (
    TOKENS,
    _json_paths,
    _mutate_json,
    _ok,
    _parent,
    _write,
    check_cli,
    ci,
    mutate_doc,
    mutate_lines,
    run_cli,
    to_toml,
    workdir,
)

#: A campaign example's CPU bound, s (this process and its cluster's): a local cluster starts and one
#: unit is fitted and driven (~10 s of CPU).
CAMPAIGN_HANG_S = 240.0

IMU: dict[str, Any] = {"grade": "tactical", "unit_seed": 2}
RIG: dict[str, Any] = {
    "rig": {"lat_deg": 45.0, "rate_hz": 10},
    "positions": {"count": 6, "dwell_s": 4.0},
    "rate_table": {"rates_dps": [30.0], "axes": ["z"], "orientations": ["up"], "dwell_s": 4.0},
}
DRIVE: dict[str, Any] = {
    "name": "drive",
    "imu": {"rate_hz": 20},
    "initial": {"lat_deg": 45.0, "yaw_deg": 10.0},
    "segment": [{"type": "accelerate", "duration_s": 5.0, "to_speed_mps": 5.0},
                {"type": "turn", "duration_s": 5.0, "angle_deg": 45.0}],
}  # fmt: skip
AIDED: dict[str, Any] = {
    "name": "aided",
    "imu": {"rate_hz": 20},
    "gnss": {"rate_hz": 1, "seed": 3, "sigma_m": [1.5, 1.5, 3.0]},
    "outage": [{"start_s": 20.0, "end_s": 30.0}],
    "alignment": {"method": "gnss_velocity", "min_speed_mps": 3.0},
    "initial": {"lat_deg": 45.0, "yaw_deg": 10.0},
    "segment": [{"type": "accelerate", "duration_s": 10.0, "to_speed_mps": 8.0},
                {"type": "turn", "duration_s": 30.0, "angle_deg": 60.0}],
}  # fmt: skip
CAMPAIGN: dict[str, Any] = {
    "name": "fz",
    "units": {"imu": "imu.toml", "count": 1, "first_seed": 3},
    "compensation": {"rig": "rig.toml", "validation": 0.3, "strategies": ["none", "regression"]},
    "scenario": [{"file": "drive.toml"}, {"file": "aided.toml"}],
    "keep": {"series_hz": 1.0},
}
#: Small fits of every strategy a model file may hold (the guard off: the learners correct).
FITS: dict[str, dict[str, Any]] = {
    "none": {},
    "regression": {},
    "regression_extended": {"squares": False},
    "mlp": {"hidden_sizes": ((4,),), "decays": (1e-4,), "folds": 2, "guard": False},
    "mlp_pure": {"hidden": (8, 8), "max_epochs": 5},
    "kohonen": {"sizes": (3,), "sigmas": (0.7,), "folds": 2, "guard": False},
    "kohonen_pure": {"rows": 4, "cols": 4, "iterations": 500},
}
NAMED = {"imu.toml": IMU, "rig.toml": RIG, "drive.toml": DRIVE, "aided.toml": AIDED}


@dataclass(frozen=True)
class Surfaces:
    """The small valid files the targets start from: the campaign's, its baseline, a model file of each
    strategy and the rig recording they were fitted on, a static recording, a drive's IMU and truth."""

    folder: Path
    campaign_baseline: str
    models: dict[str, str]
    recording: str
    static: str
    imu: str
    truth: str


def make_surfaces(folder: Path) -> Surfaces:
    """Write, fit, run and simulate the base files in ``folder`` (a campaign's cluster included)."""
    from sins import compensation, io

    for name, doc in NAMED.items():
        _write(folder / name, to_toml(doc))
    _write(folder / "campaign.toml", to_toml(CAMPAIGN))
    # The campaign's one unit, its figures standing for the units a gate needs (gate.check_power: one
    # unit's gate could never fail), each under a seed of its own: the surface is the file's form.
    from sins import campaign
    from sins.campaign import engine, gate

    done = engine.run(campaign.load(folder / "campaign.toml"), folder / "run", workers=1)
    doc = gate.baseline_of(done.summary)
    units = gate.units_needed(sum(len(g["values"]) - 1 for g in doc["groups"].values()))
    for group in doc["groups"].values():
        group["values"] = {k: [v[0] + i if k == "unit_seed" else v[0] for i in range(units)]
                           for k, v in group["values"].items()}  # fmt: skip
    io.write_json(folder / "baseline.json", doc)
    rec = folder / "rec.csv"
    _ok(
        [
            "calibrate",
            str(folder / "rig.toml"),
            "--imu",
            str(folder / "imu.toml"),
            "--out",
            str(rec),
            "--seed",
            "5",
        ]
    )
    data = io.read(rec).rig
    models = {}
    for name, params in FITS.items():
        compensation.save(compensation.make(name, **params).fit(data), folder / f"m_{name}.json")
        models[name] = (folder / f"m_{name}.json").read_text(encoding="utf-8")
    rng = np.random.default_rng(1)
    n = 2400  # two minutes at 20 Hz
    readings = np.column_stack([np.arange(n) / 20.0, rng.normal(0.0, 1e-3, (n, 3)),
                                np.array([0.0, 0.0, -9.80665]) + rng.normal(0.0, 2e-3, (n, 3))])  # fmt: skip
    header = "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"
    np.savetxt(folder / "static.csv", readings, delimiter=",", header=header, comments="", fmt="%.17g")
    _ok(["simulate", str(folder / "drive.toml"), "--imu", str(folder / "imu.csv"), "--truth",
         str(folder / "truth.csv"), "--form", "rate"])  # fmt: skip
    text = lambda name: (folder / name).read_text(encoding="utf-8")  # noqa: E731
    return Surfaces(folder, text("baseline.json"), models, text("rec.csv"), text("static.csv"),
                    text("imu.csv"), text("truth.csv"))  # fmt: skip


@pytest.fixture(scope="module")
def surfaces(tmp_path_factory: pytest.TempPathFactory) -> Surfaces:
    return make_surfaces(tmp_path_factory.mktemp("fuzz_surfaces"))


def _named_files(d: Path, mutated: str = "", doc: dict[str, Any] | None = None) -> list[Path]:
    """The campaign's named files written in ``d``, ``mutated`` replaced by ``doc``."""
    return [_write(d / name, to_toml(doc if name == mutated and doc is not None else value))
            for name, value in NAMED.items()]  # fmt: skip


def _campaign(d: Path, argv_tail: list[str], inputs: list[Path], ok: tuple[int, ...] = (0,)) -> None:
    check_cli(["campaign", str(d / "c.toml"), "--out", str(d / "out"), "--workers", "1", *argv_tail],
              inputs, [], d, ok=ok, hang_cpu_s=CAMPAIGN_HANG_S)  # fmt: skip


# --------------------------------------------------------------------------- the targets


def target_campaign_values(b: Surfaces, data: st.DataObject) -> None:
    """A campaign file with numbers pushed to extremes, keys dropped or added: ``sins campaign``."""
    with workdir(b) as d:
        named = _named_files(d)
        path = _write(d / "c.toml", to_toml(mutate_doc(CAMPAIGN, data)))
        _campaign(d, [], [path, *named])


def target_campaign_bytes(b: Surfaces, data: st.DataObject) -> None:
    """A campaign file's text mutated (bytes, lines, fields): ``sins campaign``."""
    with workdir(b) as d:
        named = _named_files(d)
        path = _write(d / "c.toml", mutate_lines(to_toml(CAMPAIGN), data, 0))
        _campaign(d, [], [path, *named])


def target_campaign_files(b: Surfaces, data: st.DataObject) -> None:
    """One of the files a campaign names (its IMU, rig, drive or aided scenario) mutated."""
    which = data.draw(st.sampled_from(sorted(NAMED)), label="file")
    with workdir(b) as d:
        named = _named_files(d, which, mutate_doc(NAMED[which], data))
        path = _write(d / "c.toml", to_toml(CAMPAIGN))
        _campaign(d, [], [path, *named])


def target_aided_scenarios(b: Surfaces, data: st.DataObject) -> None:
    """An aided scenario (receiver, outage, alignment) with values pushed to extremes: ``sins run``."""
    with workdir(b) as d:
        path = _write(d / "a.toml", to_toml(mutate_doc(AIDED, data)))
        out = d / "out"
        out.mkdir()
        check_cli(["run", str(path), "--json", str(out / "run.json")], [path], [out / "run.json"], out)


#: What a value anywhere in a model file becomes: other kinds, huge and tiny numbers, other shapes, and
#: arrays of up to 48,000 numbers (~0.24 MB of JSON: three edits keep a file under the 1 MB the memory
#: bound is stated for). Rows are separate lists: a shared one, edited in place, multiplied a file to 31 MB.
_MODEL_VALUES = st.one_of(
    st.sampled_from([None, True, "x", 0, -1, 2**40, 10**18, 1e12, -1e12, 1e-300, 1e300, [], {}, [[]]]),
    st.integers(-5, 300),
    st.lists(st.floats(-1e3, 1e3), max_size=40),
    st.lists(st.lists(st.floats(-1e3, 1e3), min_size=1, max_size=8), max_size=40),
    st.builds(
        lambda rows, cols: [[0.5] * cols for _ in range(rows)], st.integers(1, 800), st.integers(1, 60)
    ),
)


def _mutate_model(doc: Any, data: st.DataObject) -> Any:
    for _ in range(data.draw(st.integers(1, 3), label="edits")):
        path = data.draw(st.sampled_from(_json_paths(doc)), label="path")
        _parent(doc, path)[path[-1]] = copy.deepcopy(data.draw(_MODEL_VALUES, label="value"))
    return doc


def target_model_files(b: Surfaces, data: st.DataObject) -> None:
    """A model file of any strategy, its text or any value in it mutated: ``sins evaluate``."""
    name = data.draw(st.sampled_from(sorted(FITS)), label="strategy")
    with workdir(b) as d:
        how = data.draw(st.sampled_from(["text", "values", "shapes"]), label="how")
        doc = json.loads(b.models[name])
        if how == "text":
            content: str | bytes = mutate_lines(b.models[name], data, 0)
        else:
            content = json.dumps(_mutate_json(doc, data) if how == "values" else _mutate_model(doc, data))
        model = _write(d / "model.json", content)
        assert model.stat().st_size < 1_000_000  # the files the memory bound is stated for
        rec = _write(d / "rec.csv", b.recording)
        out = d / "out"
        out.mkdir()
        check_cli(["evaluate", str(model), str(rec), "--json", str(out / "e.json")], [model, rec],
                  [out / "e.json"], out)  # fmt: skip


def target_characterise(b: Surfaces, data: st.DataObject) -> None:
    """``sins characterise``'s inputs mutated: a static recording, or a moving one's readings or truth."""
    static = data.draw(st.booleans(), label="static")
    with workdir(b) as d:
        out = d / "out"
        out.mkdir()
        outputs = [out / "m.toml", out / "c.json"]
        tail = ["--out", str(outputs[0]), "--json", str(outputs[1])]
        if static:
            rec = _write(d / "s.csv", mutate_lines(b.static, data, 1))
            check_cli(["characterise", str(rec), "--static", *tail], [rec], outputs, out)
            return
        which = data.draw(st.sampled_from(["imu", "truth"]), label="which")
        imu = _write(d / "i.csv", mutate_lines(b.imu, data, 1) if which == "imu" else b.imu)
        truth = _write(d / "t.csv", mutate_lines(b.truth, data, 1) if which == "truth" else b.truth)
        check_cli(["characterise", str(imu), "--truth", str(truth), *tail], [imu, truth], outputs, out)


def target_campaign_gate(b: Surfaces, data: st.DataObject) -> None:
    """A campaign baseline mutated (values, keys, kinds) or its text: ``sins check CAMPAIGN``."""
    with workdir(b) as d:
        named = _named_files(d)
        path = _write(d / "c.toml", to_toml(CAMPAIGN))
        if data.draw(st.booleans(), label="as text"):
            content = mutate_lines(b.campaign_baseline, data, 0)
        else:
            content = json.dumps(_mutate_json(json.loads(b.campaign_baseline), data))
        baseline = _write(d / "b.json", content)
        check_cli(["check", str(path), "--baseline", str(baseline)], [path, baseline, *named], [], d,
                  ok=(0, 1), hang_cpu_s=CAMPAIGN_HANG_S)  # fmt: skip


def target_gap_truth(b: Surfaces, data: st.DataObject) -> None:
    """``sins gap IMU --truth TRUTH``: the readings or the truth mutated, or a field a token."""
    which = data.draw(st.sampled_from(["imu", "truth"]), label="which")
    with workdir(b) as d:
        imu = _write(d / "i.csv", mutate_lines(b.imu, data, 1) if which == "imu" else b.imu)
        truth = _write(d / "t.csv", mutate_lines(b.truth, data, 1) if which == "truth" else b.truth)
        check_cli(["gap", str(imu), "--truth", str(truth)], [imu, truth], [], d)


#: Every target by name with its CI example count (the campaign targets start a cluster when the
#: mutated campaign is sound: a few seconds each).
TARGETS: dict[str, tuple[Callable[[Surfaces, st.DataObject], None], int]] = {
    "campaign_values": (target_campaign_values, 10),
    "campaign_bytes": (target_campaign_bytes, 10),
    "campaign_files": (target_campaign_files, 4),
    "aided_scenarios": (target_aided_scenarios, 40),
    "model_files": (target_model_files, 80),
    "characterise": (target_characterise, 15),
    "campaign_gate": (target_campaign_gate, 4),
    "gap_truth": (target_gap_truth, 15),
}
EXAMPLES: dict[str, int] = dict.fromkeys(TARGETS, 0)


def run_target(name: str, b: Surfaces, data: st.DataObject) -> None:
    """One example of target ``name`` (counted in :data:`EXAMPLES`)."""
    EXAMPLES[name] += 1
    TARGETS[name][0](b, data)


@pytest.mark.parametrize("name", sorted(TARGETS))
def test_surface(surfaces: Surfaces, name: str) -> None:
    @ci(TARGETS[name][1])
    @given(data=st.data())
    def body(data: st.DataObject) -> None:
        run_target(name, surfaces, data)

    body()


def test_the_base_files_are_sound(surfaces: Surfaces) -> None:
    """The mutations start from inputs every command takes (else the targets would test nothing)."""
    doc = json.loads(surfaces.campaign_baseline)
    assert {"drive/regression", "aided/regression"} <= set(doc["groups"])
    assert "outage1_end_m" in doc["groups"]["aided/regression"]["values"]
    assert len(surfaces.models) == len(FITS) and TOKENS


def test_an_aligning_fix_at_the_runs_end_is_one_line(tmp_path: Path) -> None:
    """Found by the long fuzz run: an outage until the speed is reached only at the last fix. The
    filter was handed one sample: numpy's "Mean of empty slice" warnings, then "cannot convert float
    NaN to integer"."""
    doc = copy.deepcopy(AIDED)
    doc["outage"] = [{"start_s": 0.0, "end_s": 30.0}]
    doc["segment"][0]["to_speed_mps"] = 1.5
    path = _write(tmp_path / "a.toml", to_toml(doc))
    with warnings.catch_warnings(record=True) as caught:  # printed on a user's terminal
        warnings.simplefilter("always")
        rc, _, err = run_cli(["run", str(path)])
    assert rc == 2 and err.count("\n") == 1 and "first reaches 3 m/s at the run's end" in err, err
    assert [str(w.message) for w in caught] == []


def test_a_reference_beyond_every_range_is_one_line_without_numpy_warnings(tmp_path: Path) -> None:
    """Found by the long fuzz run: a rig recording's ``ref_gyro_x`` of -1e300 made numpy warn of an
    overflow (two lines) before the reader's one-line refusal."""
    for name in ("imu.toml", "rig.toml"):
        _write(tmp_path / name, to_toml(NAMED[name]))
    rec = tmp_path / "rec.csv"
    _ok(["calibrate", str(tmp_path / "rig.toml"), "--imu", str(tmp_path / "imu.toml"), "--out", str(rec)])
    lines = rec.read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    column = lines[header].split(",").index("ref_gyro_x")
    cells = lines[header + 50].split(",")
    cells[column] = "-1e300"
    lines[header + 50] = ",".join(cells)
    rec.write_text("\n".join(lines) + "\n")
    with warnings.catch_warnings(record=True) as caught:  # printed on a user's terminal
        warnings.simplefilter("always")
        rc, _, err = run_cli(["fit", str(rec), "--strategy", "none", "--out", str(tmp_path / "m.json")])
    assert rc == 2 and err.count("\n") == 1 and "ref_gyro_x" in err, err
    assert [str(w.message) for w in caught] == []
