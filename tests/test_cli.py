"""The ``sins`` command: run, simulate + integrate round trips, bad input as one line and exit status 2."""

from __future__ import annotations

import argparse
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import run_process

from sins import io
from sins.cli import main
from sins.runs import pipeline

SUMMARY_KEYS = (
    "final_north_m",
    "final_east_m",
    "final_down_m",
    "final_horizontal_m",
    "max_horizontal_m",
    "final_roll_deg",
    "final_pitch_deg",
    "final_yaw_deg",
)

SHORT = """\
name = "short"
description = "three seconds"
[imu]
rate_hz = 100
[initial]
lat_deg = 45.0
lon_deg = 7.0
alt_m = 200.0
speed_mps = 5.0
[[segment]]
type = "accelerate"
duration_s = 2
delta_speed_mps = 2
[[segment]]
type = "turn"
duration_s = 1
rate_dps = 3
"""

# About a minute of manoeuvres: speed change, coordinated turn, climb, attitude change, all at once
# ramped, so that every IMU channel is exercised.
MANOEUVRES = """\
name = "manoeuvres"
[imu]
rate_hz = 100
[initial]
lat_deg = 45.0
lon_deg = 7.0
alt_m = 200.0
speed_mps = 5.0
yaw_deg = 30.0
[[segment]]
type = "accelerate"
duration_s = 10
to_speed_mps = 20
ramp_s = 2
[[segment]]
type = "turn"
duration_s = 20
angle_deg = 90
ramp_s = 3
coordinated = true
[[segment]]
type = "climb"
duration_s = 15
angle_deg = 5
ramp_s = 3
[[segment]]
type = "attitude"
duration_s = 10
roll_deg = 10
pitch_deg = -3
ramp_s = 2
[[segment]]
type = "hold"
duration_s = 5
"""


def _assert_one_line_error(rc: int, out: str, err: str) -> None:
    assert rc == 2, (rc, out, err)
    assert err.startswith("sins: error: "), err
    assert err.endswith("\n") and err.count("\n") == 1, err
    assert "Traceback" not in out + err


# --------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def short_files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A short scenario and its simulated increment IMU and truth."""
    d = tmp_path_factory.mktemp("short")
    scenario = d / "short.toml"
    scenario.write_text(SHORT, encoding="utf-8")
    imu, truth = d / "imu.csv", d / "truth.csv"
    assert main(["simulate", str(scenario), "--imu", str(imu), "--truth", str(truth)]) == 0
    return {"dir": d, "scenario": scenario, "imu": imu, "truth": truth}


def test_a_truth_file_says_it_is_the_truth(short_files: dict[str, Path]) -> None:
    # The truth file's header had said "ideal IMU of scenario ..." and "sensor: ideal IMU (simulated)",
    # the readings' words: a truth file is no sensor's.
    head = [x for x in short_files["truth"].read_text().splitlines() if x.startswith("#")]
    assert "truth of scenario short" in head[0] and head[0].endswith("beside imu.csv's")
    assert not any(x.startswith("# sensor:") for x in head)
    imu_head = [x for x in short_files["imu"].read_text().splitlines() if x.startswith("#")]
    assert "# sensor: ideal IMU (simulated)" in imu_head


@pytest.fixture(scope="module")
def round_trips(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, float]]:
    """Simulate the one-minute scenario in both IMU forms and integrate each back against the truth."""
    d = tmp_path_factory.mktemp("manoeuvres")
    scenario = d / "manoeuvres.toml"
    scenario.write_text(MANOEUVRES, encoding="utf-8")
    results = {}
    for form in ("increment", "rate"):
        imu, truth, out = d / f"imu_{form}.csv", d / f"truth_{form}.csv", d / f"{form}.json"
        assert (
            main(["simulate", str(scenario), "--imu", str(imu), "--truth", str(truth), "--form", form]) == 0
        )
        assert main(["integrate", str(imu), "--truth", str(truth), "--json", str(out)]) == 0
        results[form] = json.loads(out.read_text(encoding="utf-8"))
        results[form]["truth_rows"] = len(io.read_truth(truth).t)
    return results


# --------------------------------------------------------------------------- run


def test_run_prints_table_and_writes_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT, encoding="utf-8")
    out = tmp_path / "summary.json"
    assert main(["run", str(scenario), "--json", str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.err == ""
    lines = captured.out.splitlines()
    header = next(line for line in lines if line.startswith("strategy"))
    assert "final hor m" in header
    assert any(line.startswith("none ") for line in lines)
    assert "300 samples at 100 Hz (3 s)" in captured.out
    doc = json.loads(out.read_text(encoding="utf-8"))
    assert doc["scenario"]["name"] == "short"
    assert doc["scenario"]["samples"] == 300
    assert set(doc["strategies"]) == {"none"}
    none = doc["strategies"]["none"]
    for key in SUMMARY_KEYS:
        assert isinstance(none[key], float) and math.isfinite(none[key]), key
    # An ideal IMU over 3 s drifts by far less than a millimetre (the 60 s round trip below measures 0.1 mm).
    assert none["max_horizontal_m"] < 1e-3


def test_run_preset_static(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    out = tmp_path / "static.json"
    assert main(["run", "static", "--json", str(out)]) == 0
    captured = capsys.readouterr()
    assert "scenario static" in captured.out and "360000 samples at 100 Hz" in captured.out
    doc = json.loads(out.read_text(encoding="utf-8"))
    assert doc["scenario"]["duration_s"] == 3600.0
    none = doc["strategies"]["none"]
    # Level and at rest with an ideal IMU the only error is the integrator's rounding, which the free
    # vertical channel amplifies over the hour: measured 2e-6 m horizontal, 6e-5 m down. 1 mm is >10x that.
    assert none["final_horizontal_m"] < 1e-3 and abs(none["final_down_m"]) < 1e-3


def test_scenarios_lists_every_preset(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["scenarios"]) == 0
    out = capsys.readouterr().out
    lines = [line for line in out.splitlines() if line.strip()]
    names = [line.split()[0] for line in lines[:-3]]  # the last three list rig, IMU and campaign presets
    root = Path(__file__).resolve().parents[1] / "scenarios"
    shipped = sorted(p.stem for p in root.glob("*.toml"))
    assert sorted(names) == shipped == sorted(pipeline.presets())
    assert sum("(default)" in line for line in out.splitlines()) == 1
    assert lines[-3].startswith("rig procedures") and lines[-2].startswith("IMU models")
    assert lines[-1].startswith("campaigns")
    for kind, line in (("rig", lines[-3]), ("imu", lines[-2]), ("campaign", lines[-1])):
        listed = sorted(x.strip() for x in line.split(":", 1)[1].split(","))
        assert (
            listed == sorted(p.stem for p in (root / kind).glob("*.toml")) == sorted(pipeline.presets(kind))
        )


# --------------------------------------------------------------------------- simulate + integrate


def test_round_trip_increment_form(round_trips: dict[str, dict[str, float]]) -> None:
    r = round_trips["increment"]
    assert r["truth_rows"] == 6001 and r["duration_s"] == 60.0
    # The ideal increments are exact to ~1e-10 (Simpson, see sins.nav.trajectory) and the files carry 17
    # digits, so what is left is the strapdown algorithm's own error at 100 Hz: measured 1e-4 m
    # horizontally after 60 s of manoeuvres. 1 cm is 100 times that, and far below the metres a
    # wrong sign or a missing Earth/transport-rate term would give over a minute.
    assert r["final_horizontal_m"] < 1e-2 and r["max_horizontal_m"] < 1e-2
    assert abs(r["final_down_m"]) < 1e-2  # measured 2.5e-4 m
    for axis in ("roll", "pitch", "yaw"):
        assert abs(r[f"final_{axis}_deg"]) < 1e-6  # measured < 3e-8 deg


def test_round_trip_rate_form(round_trips: dict[str, dict[str, float]]) -> None:
    r, ref = round_trips["rate"], round_trips["increment"]
    assert r["truth_rows"] == 6001 and r["duration_s"] == 60.0
    assert r["final_horizontal_m"] < 1e-2 and r["max_horizontal_m"] < 1e-2  # as for the increment form
    # The 4th-order quadrature errs by ~h⁴·f'''' per interval inside and the two trapezoid end
    # intervals by h³/12·f'' ≈ 1e-7 m/s; measured against the increment form: 5e-7 m in position and
    # 5e-7 deg in attitude. Allow 20 times that.
    for key in ("final_north_m", "final_east_m", "final_down_m"):
        assert abs(r[key] - ref[key]) < 1e-5, key
    for axis in ("roll", "pitch", "yaw"):
        assert abs(r[f"final_{axis}_deg"]) < 1e-5  # measured < 4e-9 deg final, 5e-7 deg max
        assert r[f"max_{axis}_deg"] < 1e-5


def test_simulate_writes_readable_files(
    short_files: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    samples, table = io.read(short_files["imu"]).imu, io.read_table(short_files["imu"])
    truth = io.read_truth(short_files["truth"])
    assert len(truth.t) == 301 and len(samples) == 300
    assert np.array_equal(table.column("t"), truth.t[1:])  # row k ends at the truth's (k+1)-th time
    assert short_files["imu"].read_text(encoding="utf-8").startswith("# sins ")


def test_simulate_reports_the_rows_it_wrote(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT, encoding="utf-8")
    imu, truth = tmp_path / "imu.csv", tmp_path / "truth.csv"
    assert main(["simulate", str(scenario), "--imu", str(imu), "--truth", str(truth), "--form", "rate"]) == 0
    reported = [int(n) for n in re.findall(r"(\d+) rows", capsys.readouterr().out)]
    assert reported == [len(io.read(imu).imu), len(io.read_truth(truth).t)]


# --------------------------------------------------------------------------- bad input


def _edit_csv(src: Path, dst: Path, edit) -> Path:
    lines = src.read_text(encoding="utf-8").splitlines()
    dst.write_text("\n".join(edit(lines)) + "\n", encoding="utf-8")
    return dst


def _set_cell(lines: list[str], row: int, col: int, value: str) -> list[str]:
    """Data row ``row`` (0-based, after one comment line and the header)."""
    cells = lines[2 + row].split(",")
    cells[col] = value
    lines[2 + row] = ",".join(cells)
    return lines


def _bad_cases(f: dict[str, Path], tmp: Path) -> dict[str, tuple[list[str], str]]:
    """argv and a fragment the message must contain, per bad input."""
    imu, truth = f["imu"], f["truth"]
    malformed = tmp / "malformed.toml"
    malformed.write_text('name = "x"\n[[segment]\ntype = "hold"\n', encoding="utf-8")
    unknown = tmp / "unknown.toml"
    unknown.write_text(SHORT.replace("[imu]\n", "[imu]\nfilter = 3\n"), encoding="utf-8")
    truth_file = tmp / "truth_missing.toml"
    truth_file.write_text('[truth]\nfile = "gone.csv"\n', encoding="utf-8")
    no_yaw = _edit_csv(
        truth,
        tmp / "no_yaw.csv",
        lambda ls: [ln if ln.startswith("#") else ln.rsplit(",", 1)[0] for ln in ls],
    )
    nan = _edit_csv(imu, tmp / "nan.csv", lambda ls: _set_cell(ls, 10, 5, "nan"))
    back = _edit_csv(imu, tmp / "back.csv", lambda ls: _set_cell(ls, 20, 0, "0.05"))
    mixed = _edit_csv(
        imu,
        tmp / "mixed.csv",
        lambda ls: [line if line.startswith("#") else line.replace("dtheta", "gyro") for line in ls],
    )  # the header's names (rows are numbers)
    return {
        "malformed-toml": (["run", str(malformed)], "invalid TOML"),
        "unknown-key": (["run", str(unknown)], "imu.filter"),
        "truth-file-missing": (["run", str(truth_file)], "gone.csv"),
        "missing-column": (["integrate", str(imu), "--truth", str(no_yaw)], "'yaw_deg'"),
        "nan": (["integrate", str(nan), "--truth", str(truth)], f"{nan}:13: column 'dv_y'"),
        "non-increasing-time": (["integrate", str(back), "--truth", str(truth)], f"{back}:23: column 't'"),
        "mixed-forms": (["integrate", str(mixed), "--truth", str(truth)], "mixes rate columns"),
        # A damp loop shorter than two steps: before, NaN, and a message that blamed the data.
        "damp-loop-too-short": (
            ["integrate", str(imu), "--truth", str(truth), "--vertical", "damp", "--vertical-tau-s", "0.001"],
            "--vertical-tau-s 0.001: with the vertical channel damped, at least 2 IMU steps",
        ),
        "nonexistent-imu": (["integrate", str(tmp / "nope.csv"), "--truth", str(truth)], "nope.csv"),
        "nonexistent-truth": (["integrate", str(imu), "--truth", str(tmp / "nope.csv")], "nope.csv"),
        "nonexistent-scenario": (["run", str(tmp / "nope.toml")], "nope.toml"),
        "unknown-preset": (["run", "no_such_preset"], "no_such_preset"),
        "json-nonexistent-dir": (
            ["run", str(f["scenario"]), "--json", str(tmp / "nodir" / "x.json")],
            "nodir",
        ),
        "integrate-json-nonexistent-dir": (
            ["integrate", str(imu), "--truth", str(truth), "--json", str(tmp / "nodir" / "x.json")],
            "does not exist",
        ),
        "simulate-nonexistent-dir": (
            [
                "simulate",
                str(f["scenario"]),
                "--imu",
                str(tmp / "nodir" / "i.csv"),
                "--truth",
                str(tmp / "t.csv"),
            ],
            "does not exist",
        ),
        "imu-starts-at-truth-start": (
            ["integrate", str(_shifted(imu, tmp)), "--truth", str(truth)],
            "not before",
        ),
    }


def _shifted(imu: Path, tmp: Path) -> Path:
    """Increment rows whose first interval would end at the truth's first time (t = 0)."""

    def edit(lines: list[str]) -> list[str]:
        top = next(i for i, line in enumerate(lines) if not line.startswith("#")) + 1  # comments, header
        body = [line.split(",") for line in lines[top:]]
        return lines[:top] + [",".join([repr(float(c[0]) - 0.01), *c[1:]]) for c in body]

    return _edit_csv(imu, tmp / "shifted.csv", edit)


BAD_IDS = [
    "malformed-toml",
    "unknown-key",
    "truth-file-missing",
    "missing-column",
    "nan",
    "non-increasing-time",
    "mixed-forms",
    "nonexistent-imu",
    "nonexistent-truth",
    "nonexistent-scenario",
    "unknown-preset",
    "json-nonexistent-dir",
    "integrate-json-nonexistent-dir",
    "simulate-nonexistent-dir",
    "imu-starts-at-truth-start",
]


@pytest.mark.parametrize("case", BAD_IDS)
def test_bad_input_in_process(
    case: str, short_files: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv, fragment = _bad_cases(short_files, tmp_path)[case]
    rc = main(argv)
    captured = capsys.readouterr()
    _assert_one_line_error(rc, captured.out, captured.err)
    assert fragment in captured.err
    assert not (tmp_path / "nodir").exists()


@pytest.mark.parametrize("case", ["nan", "malformed-toml", "mixed-forms"])
def test_bad_input_subprocess(case: str, short_files: dict[str, Path], tmp_path: Path) -> None:
    argv, fragment = _bad_cases(short_files, tmp_path)[case]
    proc = run_process([sys.executable, "-m", "sins.cli", *argv], capture_output=True, text=True, check=False)
    _assert_one_line_error(proc.returncode, proc.stdout, proc.stderr)
    assert fragment in proc.stderr


def test_usage_errors_are_argparse_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["fit", "rig.csv", "--out", "m.json"])  # --strategy is required
    assert info.value.code == 2
    assert "Traceback" not in capsys.readouterr().err
    # A recording or --dataset FOLDER/NAME, one of them: sins's own one-line refusal, exit 2 too.
    rc = main(["integrate"])
    _assert_one_line_error(rc, "", capsys.readouterr().err)
    # Words argparse leaves over that no positional can take, and unknown options, are still refused,
    # by the command's own usage.
    for argv in (["inspect", "a.csv", "--json", "x.json", "b.csv"], ["run", "static", "--seed", "1", "extra"],
                 ["fit", "a.npz", "--strategy", "regression", "--out", "m.json", "--bogus"]):  # fmt: skip
        with pytest.raises(SystemExit) as info:
            main(argv)
        err = capsys.readouterr().err
        assert info.value.code == 2 and f"sins {argv[0]}: error: unrecognized arguments: " in err, err
    # An output file named as a folder (argparse's Path drops the slash: model.json was written).
    for argv in (["fit", "a.npz", "--strategy", "regression", "--out", "m.json/"],
                 ["evaluate", "m.json", "a.npz", "--json=e.json/"],
                 ["simulate", "static", "--imu", "i.csv/", "--truth", "t.csv"],
                 ["check", "quality", "--update-baseline", "--baseline", "b.json/"]):  # fmt: skip
        with pytest.raises(SystemExit) as info:
            main(argv)
        err = capsys.readouterr().err
        assert info.value.code == 2 and "/: ends in /, a folder's name; " in err, err


def test_a_recording_after_an_option_is_the_commands_recording() -> None:
    """argparse gives an optional positional the words before the first option and took a recording
    after one for unrecognised (``sins correct M.json --out c.csv r.npz`` was refused): now it is the
    command's, converted by the positional's own type, after those before it."""
    from sins.cli import parse

    args = parse(["correct", "m.json", "--out", "c.csv", "r.npz"])
    assert (str(args.model), str(args.recording), str(args.out)) == ("m.json", "r.npz", "c.csv")
    args = parse(["fit", "a.npz", "--strategy", "regression", "b.npz", "--out", "m.json", "c.npz"])
    assert [str(r) for r in args.recording] == ["a.npz", "b.npz", "c.npz"] and str(args.out) == "m.json"
    args = parse(["inspect", "--json", "x.json", "r.csv"])
    assert str(args.recording) == "r.csv"


def test_json_onto_a_directory(
    short_files: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "out.json").mkdir()
    rc = main(["integrate", str(short_files["imu"]), "--truth", str(short_files["truth"]),
               "--json", str(tmp_path / "out.json")])  # fmt: skip
    _assert_one_line_error(rc, "", capsys.readouterr().err)


def test_scenario_not_utf8(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "latin1.toml"
    path.write_bytes('name = "Zürich"\n'.encode("latin-1"))
    rc = main(["run", str(path)])
    _assert_one_line_error(rc, "", capsys.readouterr().err)


# --------------------------------------------------------------------------- calibrate, effects

RIG = """\
[rig]
lat_deg = 48.0
rate_hz = 50
[positions]
count = 6
dwell_s = 2
[rate_table]
rates_dps = [20, 60]
axes = ["x", "z"]
orientations = ["up"]
dwell_s = 1
accel_dps2 = 120
"""

IMU = """\
grade = "industrial"
unit_seed = 4
withhold = ["gyro.bias_instability"]
[[effect]]
name = "gyro.scale_nonlinearity"
k2_ppm_per_dps = [30, 30, 30]
"""


def test_effects_lists_every_effect_with_units(capsys: pytest.CaptureFixture[str]) -> None:
    from sins import imu

    assert main(["effects"]) == 0
    out = capsys.readouterr().out
    for name in imu.effect_names():
        assert name in out
    for unit in ("°/h", "mg", "ppm", "°/√h", "µg/√Hz", "°/h/g"):
        assert unit in out


def test_calibrate_writes_a_seeded_recording(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from sins import io

    (tmp_path / "rig.toml").write_text(RIG)
    (tmp_path / "imu.toml").write_text(IMU)
    outs = []
    for name, seed in (("a.csv", "7"), ("b.csv", "7"), ("c.csv", "8")):
        rc = main(["calibrate", str(tmp_path / "rig.toml"), "--imu", str(tmp_path / "imu.toml"),
                   "--out", str(tmp_path / name), "--seed", seed])  # fmt: skip
        assert rc == 0
        outs.append(io.read(tmp_path / name).rig)
    a, b, c = outs
    # Six positions; two table runs of four rates, each rate a ramp and a dwell, then a ramp to rest.
    assert sum(p.kind == "static" for p in a.phases) == 6
    assert sum(p.kind == "rotation" for p in a.phases) == 2 * (4 * 2 + 1)
    assert any(p.name == "table z up +60 °/s" for p in a.phases)
    np.testing.assert_array_equal(a.gyro, b.gyro)  # same seed, same recording
    assert not np.array_equal(a.gyro, c.gyro)  # another run of the same unit
    header = (tmp_path / "a.csv").read_text().splitlines()[1]
    assert "gyro.scale_nonlinearity" in header and "gyro.bias_instability" not in header
    # The preset names work too.
    assert main(["calibrate", "24pos_ratetable", "--imu", "tactical", "--out", str(tmp_path / "p.csv")]) == 0


@pytest.mark.parametrize(
    "imu_text, fragment",
    [
        ('grade = "military"\n', "grade"),
        ('[[effect]]\nname = "gyro.wobble"\n', "name"),
        ('[[effect]]\nname = "gyro.bias"\nbias_dps = 1\n', "unknown parameter 'bias_dps'"),
        ('[[effect]]\nname = "gyro.scale_misalignment"\nmatrix_ppm = [1, 2]\n', "shape"),
        ("unit_seed = 1\n", "give a grade"),
        (
            '[[effect]]\nname = "gyro.bias"\nbias_dph = 1\n[[effect]]\nname = "gyro.bias"\nbias_dph = 2\n',
            "effect[2].name: gyro.bias is given",
        ),
        # Strings and booleans were read by float(): "1e3" a bias of 1000 mg, true one of 1 mg.
        ('[[effect]]\nname = "accel.bias"\nbias_mg = ["1", "0", "0"]\n', "bias_mg: expected a number or"),
        ('[[effect]]\nname = "accel.bias"\nbias_mg = true\n', "bias_mg: expected a number or a list"),
        # A table cut short: before, a bias of zero, changing nothing without a word.
        ('grade = "tactical"\n[[effect]]\nname = "gyro.bias"\n', "effect[1]: gyro.bias: no parameter given"),
    ],
)
def test_bad_imu_files_give_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], imu_text: str, fragment: str
) -> None:
    (tmp_path / "rig.toml").write_text(RIG)
    (tmp_path / "imu.toml").write_text(imu_text)
    rc = main(["calibrate", str(tmp_path / "rig.toml"), "--imu", str(tmp_path / "imu.toml"),
               "--out", str(tmp_path / "x.csv")])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and err.startswith("sins: error: ")
    assert fragment in err and "imu.toml" in err
    assert not (tmp_path / "x.csv").exists()


def test_bad_rig_file_gives_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "rig.toml").write_text(RIG.replace("count = 6", "count = 7"))
    (tmp_path / "imu.toml").write_text(IMU)
    rc = main(["calibrate", str(tmp_path / "rig.toml"), "--imu", str(tmp_path / "imu.toml"),
               "--out", str(tmp_path / "x.csv")])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 2 and "positions.count" in err and err.count("\n") == 1


def test_a_reader_that_goes_away_ends_the_command_quietly() -> None:
    """`sins scenarios | head -1`: the pipe's reader closes before sins writes; sins stops without a
    message (it had printed "sins: error: : Broken pipe") and with the status a shell gives SIGPIPE."""
    sins = Path(sys.executable).parent / "sins"
    proc = subprocess.Popen([str(sins), "scenarios"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # before the interpreter has even started: every write meets a closed pipe
    err = proc.stderr.read().decode()
    assert proc.wait(60) == 141 and err == ""


def test_the_dataset_option_names_every_dataset_the_library_reads() -> None:
    """``--dataset``'s help is written out (the CLI does not import the readers to start); it must
    name exactly the datasets ``sins.io.datasets`` can load."""
    from sins.cli import build_parser
    from sins.io import datasets

    for command in ("gap", "characterise", "fit", "evaluate", "correct"):
        sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
        option = next(a for a in sub.choices[command]._actions if "--dataset" in a.option_strings)
        assert option.help is not None
        named = option.help.split(": ", 1)[1].split(" (")[0].split(", ")
        assert sorted(named) == sorted(datasets.NAMES), (command, named)


def test_the_run_table_says_where_the_guard_kept_regression() -> None:
    """A learned strategy whose guard kept regression everywhere prints regression's row; the report
    says so rather than leave it to look like a learner that learnt nothing (issue 33)."""
    from types import SimpleNamespace

    from sins.cli.run import guard_notes

    kept = SimpleNamespace(
        guard_={"gyro.x": {"earns_its_place": False}, "accel.x": {"earns_its_place": False}}
    )
    mixed = SimpleNamespace(
        guard_={"gyro.x": {"earns_its_place": True}, "accel.x": {"earns_its_place": False}}
    )
    notes = guard_notes({"regression": object(), "mlp": kept, "kohonen": mixed})
    assert len(notes) == 2
    assert notes[0].startswith("mlp: the guard kept regression") and "every channel" in notes[0]
    assert notes[1] == "kohonen: learned on gyro.x; the guard kept regression on the others"


def test_a_list_of_numbers_that_starts_negative_is_a_value() -> None:
    # argparse takes "-33.9" for a value but "-33.9,151.2,10" for an option: every southern origin and
    # negative roll was refused ("expected one argument") unless written with "=". Now both spellings
    # parse alike, and a word that is an option after one is still an option.
    from sins.cli import parse

    spaced = parse(["integrate", "r.csv", "--origin", "-33.9,151.2,10", "--attitude", "-2,1,30"])
    joined = parse(["integrate", "r.csv", "--origin=-33.9,151.2,10", "--attitude=-2,1,30"])
    assert vars(spaced) == vars(joined)
    assert spaced.origin is not None and spaced.attitude is not None
    assert parse(["bias", "r.csv", "--lat", "-45", "--attitude", "-1,-0.5,-.5"]).lat == -45.0
    with pytest.raises(SystemExit):
        parse(["integrate", "r.csv", "--origin", "--json", "x.json"])


def test_an_origin_at_a_pole_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    # The latitude/longitude mechanisation is singular at a pole: --origin 90,0,0 was taken, and 20 s of a
    # still EuRoC unit's readings were said to have moved it 169 km east (89.95° N: 690 m). Scenarios stop
    # at ±89.9°; the origin now does too, before anything is read.
    assert main(["integrate", "r.npz", "--origin=90,0,0", "--attitude", "0,0,0"]) == 2
    assert "--origin '90,0,0': latitude ±89.9°" in capsys.readouterr().err
    assert main(["integrate", "r.npz", "--origin=-89.95,0,0", "--attitude", "0,0,0"]) == 2
    assert "latitude ±89.9°" in capsys.readouterr().err


def test_an_origin_without_an_attitude_asks_for_one(
    short_files: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    # A walk's `sins integrate r.csv --origin 45,0,0` read "origin: does not apply to r.csv, a CSV file",
    # where --origin does apply to it: what was missing is the start's attitude.
    assert main(["integrate", str(short_files["imu"]), "--origin", "45,0,0"]) == 2
    err = capsys.readouterr().err
    assert "--origin starts" in err and "give --attitude R,P,Y or --align SECONDS with it" in err
    # Beside --truth it had asked for --attitude, which --truth then refused: a loop.
    imu, truth = str(short_files["imu"]), str(short_files["truth"])
    assert main(["integrate", imu, "--truth", truth, "--origin", "45,0,0"]) == 2
    assert "--truth gives its start" in capsys.readouterr().err


def test_a_truth_that_begins_late_is_named(
    short_files: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A truth file cut of its first rows had the IMU file blamed ("imu.csv:4: column 't': first
    # increment ends at 0.01 s, not after the start time 0.5 s"): the truth is what begins too late.
    lines = short_files["truth"].read_text().splitlines()
    head = sum(1 for x in lines if x.startswith("#")) + 1  # the comments and the column names
    late = tmp_path / "late.csv"
    late.write_text("\n".join(lines[:head] + lines[head + 50 :]) + "\n")
    t0 = float(lines[head + 50].split(",")[0])
    assert main(["integrate", str(short_files["imu"]), "--truth", str(late)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"sins: error: {late}: begins at {t0:g} s, not before ") and err.count("\n") == 1


def test_a_readers_option_that_does_not_apply_is_said_as_the_flag(
    short_files: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    # The reader names its own arguments ("topic: does not apply", "rate_hz does not apply to a
    # dataset"); the command line says its flags. And an option is taken by its whole name only: inspect
    # has no --truth, which argparse's prefixes had read as --truth-topic.
    imu = str(short_files["imu"])
    assert main(["inspect", imu, "--topic", "/imu"]) == 2
    assert capsys.readouterr().err == f"sins: error: --topic: does not apply to {imu}, a CSV file\n"
    assert main(["inspect", "--dataset", "ferraris", "--rate", "100"]) == 2
    assert "ferraris: --rate does not apply to a dataset" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["inspect", imu, "--truth", str(short_files["truth"])])
    assert "unrecognized arguments: --truth" in capsys.readouterr().err


def test_an_option_no_one_reads_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # A walk found three options taken and ignored (exit 0, no word): --web-port without --serve,
    # --vertical-tau-s without --vertical damp; and --web-port 99999999 refused only after the whole
    # run, in rerun's words ("out of range integral type conversion attempted").
    assert main(["run", "static", "--web-port", "9091"]) == 2
    assert capsys.readouterr().err == "sins: error: --web-port goes with --serve\n"
    with pytest.raises(SystemExit):
        main(["run", "static", "--serve", "--web-port", "99999999"])
    assert "must be a port, 1 to 65535" in capsys.readouterr().err
    imu, truth, short = tmp_path / "imu.csv", tmp_path / "truth.csv", tmp_path / "short.toml"
    short.write_text('[initial]\nlat_deg = 45.0\n[[segment]]\ntype = "hold"\nduration_s = 20\n')
    assert main(["simulate", str(short), "--imu", str(imu), "--truth", str(truth), "--ideal"]) == 0
    capsys.readouterr()
    assert main(["integrate", str(imu), "--truth", str(truth), "--vertical-tau-s", "1e-9"]) == 2
    assert "--vertical-tau-s goes with --vertical damp (the channel is free)" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["bias", "x.csv", "--seconds", "0"], "sins bias: error: argument --seconds: must be a positive"),
        (["integrate", "x.csv", "--vertical", "up"], "sins integrate: error: argument --vertical: invalid"),
        (["fit", "x.csv", "--strategy", "regression"], "sins fit: error: the following arguments are"),
        ([], "sins: error: the following arguments are required: COMMAND (sins --help)"),
    ],
)
def test_an_option_of_the_wrong_form_is_one_line_naming_the_help(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """argparse's refusals had printed the command's usage first (eleven lines for ``sins bias
    --seconds 0``, where ``--lat 95`` took one line): one line now, pointing at ``--help``."""
    with pytest.raises(SystemExit) as ended:
        main(argv)
    err = capsys.readouterr().err
    assert ended.value.code == 2 and err.count("\n") == 1 and said in err and "--help)" in err, err
