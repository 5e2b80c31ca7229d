"""A user's runs in and out, run as a user runs them (the CLI in a temporary folder): a scenario unit's
corrupted readings, ``sins run --imu/--seed``, the solution written by ``sins integrate --out``, a truth
shorter than the IMU, and ``sins gap`` on either IMU form."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from sins import io
from sins.cli import main
from sins.core import earth
from sins.errors import SinsInputError

# 20 s still, then 10 s speeding up: a tactical unit, its power-on seed 3.
SCENARIO = """\
name = "drive"
[imu]
rate_hz = 100
model = "tactical"
seed = 3
[initial]
lat_deg = 45.0
lon_deg = 7.0
alt_m = 200.0
[[segment]]
type = "hold"
duration_s = 20
[[segment]]
type = "accelerate"
duration_s = 10
to_speed_mps = 10
"""

# A unit with known constant errors and white noise only (test_the_readings_carry_the_units_errors).
IMU_FILE = """\
[[effect]]
name = "gyro.bias"
bias_dph = [10.0, -20.0, 30.0]
[[effect]]
name = "accel.bias"
bias_mg = [1.0, -2.0, 0.5]
[[effect]]
name = "gyro.noise"
arw_deg_per_rt_h = [0.1, 0.1, 0.1]
[[effect]]
name = "accel.noise"
vrw_ug_per_rt_hz = [100.0, 100.0, 100.0]
"""


def _one_line_error(capsys: pytest.CaptureFixture[str], *fragments: str) -> str:
    captured = capsys.readouterr()
    assert captured.err.startswith("sins: error: ") and captured.err.count("\n") == 1, captured.err
    assert "Traceback" not in captured.out + captured.err
    for fragment in fragments:
        assert fragment in captured.err, (fragment, captured.err)
    return captured.err


@pytest.fixture
def folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A user's working folder, holding the scenario."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "drive.toml").write_text(SCENARIO, encoding="utf-8")
    return tmp_path


def _summary(path: str) -> dict[str, float]:
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    return doc["strategies"]["none"] if "strategies" in doc else doc


# --------------------------------------------------------------------------- simulate


def test_simulate_says_how_to_integrate_a_damped_vertical_as_run_does(folder: Path, capsys) -> None:
    """``sins integrate``'s vertical channel is free unless told; a scenario that damps its own had its
    simulated readings integrated to metres of height error where ``sins run`` gave centimetres (a
    walkthrough's car_drive_5min: 64.5 m against 0.121 m). ``sins simulate`` now says the flags, and
    with them ``integrate`` gives ``run``'s figures."""
    (folder / "damped.toml").write_text(SCENARIO + '[navigation]\nvertical = "damp"\nvertical_tau_s = 5\n')
    assert main(["simulate", "damped.toml", "--imu", "d.csv", "--truth", "dt.csv"]) == 0
    note = capsys.readouterr().err
    assert "sins: note: the scenario's vertical channel is damp" in note
    flags = note.split("--truth dt.csv ")[1].split(" integrates")[0].split()
    assert flags == ["--vertical", "damp", "--vertical-tau-s", "5"]
    assert main(["integrate", "d.csv", "--truth", "dt.csv", *flags, "--json", "di.json"]) == 0
    assert main(["run", "damped.toml", "--json", "dr.json"]) == 0
    integrated, ran = _summary("di.json"), _summary("dr.json")
    assert integrated["final_down_m"] == pytest.approx(ran["final_down_m"], rel=1e-9, abs=1e-12)


def test_simulate_writes_the_units_readings_that_run_integrates(folder: Path, capsys) -> None:
    """The readings ``sins simulate`` writes for a scenario with ``[imu] model`` are those ``sins run``
    integrates as ``none``: integrated back they give its summary to rounding (the whole-array
    corruption equals the streamed one, and 17 digits round-trip a double; the streamed run sums its
    statistics chunk by chunk, measured 1.5e-11 apart at most)."""
    assert main(["simulate", "drive.toml", "--imu", "imu.csv", "--truth", "truth.csv"]) == 0
    assert "IMU tactical (power-on seed 3)" in capsys.readouterr().out
    assert main(["integrate", "imu.csv", "--truth", "truth.csv", "--json", "i.json"]) == 0
    assert main(["run", "drive.toml", "--json", "r.json"]) == 0
    integrated, ran = _summary("i.json"), _summary("r.json")
    common = set(integrated) & set(ran)
    assert len(common) >= 10
    for key in common:  # the streamed run sums its error statistics chunk by chunk: 1e-15 apart
        assert integrated[key] == pytest.approx(ran[key], rel=1e-9, abs=1e-12), key
    # The tactical unit drifts: metres in 30 s, where the ideal IMU leaves well under a millimetre.
    assert _summary("r.json")["final_horizontal_m"] > 0.1
    table = io.read_table("imu.csv")
    assert table.columns[-1] == "temp" and np.all(table.column("temp") == 20.0)  # the cabin's default

    # --ideal: the exact ideal readings, the same as the scenario without its unit.
    assert main(["simulate", "drive.toml", "--imu", "ideal.csv", "--truth", "t2.csv", "--ideal"]) == 0
    (folder / "plain.toml").write_text(SCENARIO.replace('model = "tactical"\nseed = 3\n', ""))
    assert main(["simulate", "plain.toml", "--imu", "plain.csv", "--truth", "t3.csv"]) == 0
    ideal, plain = io.read_table("ideal.csv"), io.read_table("plain.csv")
    assert ideal.columns == plain.columns == io.INCREMENT_COLUMNS
    assert np.array_equal(ideal.data, plain.data)
    assert not np.array_equal(ideal.data, table.data[:, :7])
    capsys.readouterr()
    assert (
        main(["simulate", "drive.toml", "--imu", "x.csv", "--truth", "y.csv", "--ideal", "--seed", "1"]) == 2
    )
    _one_line_error(capsys, "--ideal")
    assert not (folder / "x.csv").exists()


def test_the_readings_carry_the_units_errors(folder: Path, capsys) -> None:
    """Still for 60 s with a unit of known biases and white noise (an IMU file written here): the mean
    reading error is the file's bias within 4 standard errors of a mean of white noise (density /
    √duration), in both IMU forms. The ideal readings come from ``--ideal``."""
    (folder / "unit.toml").write_text(IMU_FILE, encoding="utf-8")
    (folder / "still.toml").write_text(
        '[imu]\nrate_hz = 100\nmodel = "unit.toml"\n[initial]\nlat_deg = 45\n'
        '[[segment]]\ntype = "hold"\nduration_s = 60\n',
        encoding="utf-8",
    )
    bias = np.r_[np.radians([10.0, -20.0, 30.0]) / 3600, 9.80665e-3 * np.array([1.0, -2.0, 0.5])]
    density = np.r_[np.full(3, np.radians(0.1) / 60), np.full(3, 100e-6 * 9.80665)]  # per √s
    for form in ("increment", "rate"):
        args = ["simulate", "still.toml", "--truth", "t.csv", "--form", form]
        assert main([*args, "--imu", "unit.csv"]) == 0 and main([*args, "--imu", "ideal.csv", "--ideal"]) == 0
        read, ideal = io.read_table("unit.csv"), io.read_table("ideal.csv")
        error = read.data[:, 1:7] - ideal.data[:, 1:7]
        if form == "increment":
            error = error / np.diff(np.r_[0.0, read.column("t")])[:, None]
        standard_error = density / math.sqrt(60.0)
        assert np.all(np.abs(error.mean(axis=0) - bias) < 4 * standard_error), form
        # ... and the noise is the density's: sample σ within 5 % (6,000 samples: 1 % standard error).
        np.testing.assert_allclose(error.std(axis=0), density * 10.0, rtol=0.05)
    capsys.readouterr()


# --------------------------------------------------------------------------- run --imu --seed


def test_run_imu_and_seed_override_the_scenarios_unit(folder: Path, capsys) -> None:
    """``--imu GRADE --seed N`` is the scenario with ``[imu] model = GRADE`` and ``seed = N``, to the
    last digit; another power-on drifts otherwise; a seed for the ideal IMU and an unknown grade are
    refused in one line."""
    edited = SCENARIO.replace('model = "tactical"\nseed = 3', 'model = "consumer"\nseed = 8')
    (folder / "consumer.toml").write_text(edited, encoding="utf-8")
    assert main(["run", "consumer.toml", "--json", "file.json"]) == 0
    assert main(["run", "drive.toml", "--imu", "consumer", "--seed", "8", "--json", "flags.json"]) == 0
    assert "IMU consumer (seed 8)" in capsys.readouterr().out
    assert _summary("flags.json") == _summary("file.json")
    assert main(["run", "drive.toml", "--imu", "consumer", "--seed", "9", "--json", "other.json"]) == 0
    assert _summary("other.json")["final_north_m"] != _summary("file.json")["final_north_m"]
    capsys.readouterr()
    (folder / "plain.toml").write_text(SCENARIO.replace('model = "tactical"\nseed = 3\n', ""))
    assert main(["run", "plain.toml", "--seed", "2"]) == 2
    _one_line_error(capsys, "plain.toml", "--seed needs an IMU model")
    assert main(["run", "drive.toml", "--imu", "military"]) == 2
    _one_line_error(capsys, "military", "tactical")


# --------------------------------------------------------------------------- integrate --out


def test_integrate_writes_the_solution(folder: Path, capsys) -> None:
    """One row per IMU time in the truth file's columns and units, as CSV and as Parquet (the same
    numbers: 17 digits round-trip a double); its last row is the summary's final state: the final
    errors recomputed from the written solution and truth with numpy agree with the summary's."""
    assert main(["simulate", "drive.toml", "--imu", "imu.csv", "--truth", "truth.csv"]) == 0
    args = ["integrate", "imu.csv", "--truth", "truth.csv", "--json", "s.json"]
    assert main([*args, "--out", "sol.csv"]) == 0 and main([*args, "--out", "sol.parquet"]) == 0
    assert "wrote sol.parquet (3001 rows)" in capsys.readouterr().out
    csv = io.read_table("sol.csv", required=io.TRUTH_COLUMNS)
    assert csv.columns == io.TRUTH_COLUMNS and len(csv.data) == 3001
    table = pq.read_table("sol.parquet")
    assert table.column_names == list(io.TRUTH_COLUMNS)
    assert table.schema.field("lat_deg").metadata == {b"unit": b"deg"}
    for name in io.TRUTH_COLUMNS:
        assert np.array_equal(table.column(name).to_numpy(), csv.column(name)), name
    truth = io.read_table("truth.csv", required=io.TRUTH_COLUMNS)
    assert np.array_equal(csv.column("t"), truth.column("t"))  # one row per IMU time
    summary = _summary("s.json")
    lat, h = np.radians(truth.column("lat_deg")[-1]), truth.column("h_m")[-1]
    r_m, r_n = earth.radii(lat)
    north = np.radians(csv.column("lat_deg")[-1] - truth.column("lat_deg")[-1]) * (r_m + h)
    east = np.radians(csv.column("lon_deg")[-1] - truth.column("lon_deg")[-1]) * (r_n + h) * np.cos(lat)
    # A 30 s drift of metres; metres per degree differ between the radii at the two heights by 1e-7.
    assert north == pytest.approx(summary["final_north_m"], rel=1e-6, abs=1e-9)
    assert east == pytest.approx(summary["final_east_m"], rel=1e-6, abs=1e-9)
    assert csv.column("yaw_deg")[-1] - truth.column("yaw_deg")[-1] == pytest.approx(
        summary["final_yaw_deg"], abs=1e-9
    )
    assert main([*args, "--out", "sol.txt"]) == 2
    _one_line_error(capsys, "sol.txt", ".csv or .parquet")
    # Readings with a hole: integrated across it as one interval, and said so (it was silent before).
    assert "gap(s)" not in capsys.readouterr().err
    lines = Path("imu.csv").read_text(encoding="utf-8").splitlines()
    first = next(k for k, line in enumerate(lines) if line[:1].isdigit())
    Path("holed.csv").write_text(
        "\n".join(lines[: first + 1000] + lines[first + 1050 :]) + "\n", encoding="utf-8"
    )
    assert main(["integrate", "holed.csv", "--truth", "truth.csv"]) == 0
    err = capsys.readouterr().err
    assert "sins: note: holed.csv: 1 gap(s) in the readings (the longest 0.51 s at 10 s)" in err, err


def test_a_truth_shorter_than_the_imu_is_refused_or_cut_when_asked(folder: Path, capsys) -> None:
    """A truth that ends before the IMU is never cut silently: refused in one line naming both files
    and how many intervals lie inside; with ``--within-truth`` integrated to its end, with a note."""
    assert main(["simulate", "drive.toml", "--imu", "imu.csv", "--truth", "truth.csv"]) == 0
    lines = (folder / "truth.csv").read_text(encoding="utf-8").splitlines()
    head = next(i for i, line in enumerate(lines) if not line.startswith("#")) + 1  # comments, header
    (folder / "short.csv").write_text("\n".join(lines[: head + 1000]) + "\n", encoding="utf-8")  # 1000 rows
    capsys.readouterr()
    assert main(["integrate", "imu.csv", "--truth", "short.csv", "--out", "sol.csv"]) == 2
    _one_line_error(capsys, "imu.csv", "short.csv", "999 of 3000 intervals", "--within-truth")
    assert not (folder / "sol.csv").exists()
    assert main(["integrate", "imu.csv", "--truth", "short.csv", "--within-truth", "--out", "sol.csv"]) == 0
    captured = capsys.readouterr()
    assert "the first 999 of 3000 intervals" in captured.err
    assert "999 intervals against short.csv" in captured.out
    assert len(io.read_truth("sol.csv").t) == 1000


def test_within_truth_cuts_the_readings_before_a_truth_file_begins_too() -> None:
    """``--within-truth`` integrates "only the IMU intervals inside the truth's span": rate-form readings
    that begin before a truth file had been refused all the same ("first sample at 0 s is outside the
    truth's 5..10 s"), the tail alone cut. Now the intervals before it are left out, and said."""
    from sins.core.series import ImuRates, NavSeries
    from sins.runs.readings import run_inputs

    t = np.arange(1001) / 100.0
    rates = ImuRates(t=t, omega_ib_b=np.zeros((1001, 3)), f_ib_b=np.tile([0.0, 0.0, -9.81], (1001, 1)))
    late = t[500:]
    truth = NavSeries(t=late, lat=np.full(501, 0.8), lon=np.zeros(501), h=np.zeros(501),
                      v_n=np.zeros((501, 3)), q_nb=np.tile([0.0, 0.0, 0.0, 1.0], (501, 1)))  # fmt: skip
    rec = io.Recording(rates, "imu.csv", "sins csv", truth, truth_from="late.csv")
    with pytest.raises(SinsInputError, match=r"first sample at 0 s is outside the truth's 5\.\.10 s"):
        run_inputs(rec)
    inputs = run_inputs(rec, within_truth=True)
    assert inputs.before_truth == 500 and inputs.imu.t[0] == 5.0 and len(inputs.imu) == 500


# --------------------------------------------------------------------------- gap on either form


# Turns both ways at up to 40 °/s and a speed change: rates that make a gyro's scale nonlinearity show.
TURNS = """\
name = "turns"
[imu]
rate_hz = 100
[initial]
lat_deg = 45.0
speed_mps = 10.0
[[segment]]
type = "hold"
duration_s = 10
[[segment]]
type = "turn"
duration_s = 20
rate_dps = 40
ramp_s = 3
[[segment]]
type = "accelerate"
duration_s = 10
to_speed_mps = 15
[[segment]]
type = "turn"
duration_s = 20
rate_dps = -40
ramp_s = 3
[[segment]]
type = "turn"
duration_s = 20
rate_dps = 25
ramp_s = 3
[[segment]]
type = "hold"
duration_s = 10
"""


def test_gap_gives_the_same_answer_on_either_imu_form(folder: Path, capsys) -> None:
    """One unit's errors planted with numpy on the ideal readings of both forms (``sins simulate
    --ideal``): bias, scale and misalignment, a gyro scale nonlinearity of 2e-3 /(rad/s) on z, and the
    same white-noise draws (a rate sample's σ is an increment's σ / dt). ``sins gap --truth`` on the
    increment form compares interval means (the reading's and the reference's, Simpson through the
    truth's splines) where the rate form compares instantaneous samples, so the answers agree to what
    that changes: the nonlinear term by the input's variance within an interval (k2·(dt·ω̇)²/12 <
    1e-9 rad/s here) and the one row the increment form lacks. Measured: the same diagnosis, the
    channels' RMS and floors within 0.23 %; allowed 2 %, far below the 32 % the planted effect adds on
    gyro.z (1.32x its floor before, 1.00x after)."""
    (folder / "turns.toml").write_text(TURNS, encoding="utf-8")
    rng = np.random.default_rng(11)
    bias = np.r_[np.radians(np.array([5.0, -3.0, 4.0]) / 3600), 9.80665e-3 * np.array([1.0, -0.5, 0.8])]
    matrix = 300e-6 * rng.standard_normal((2, 3, 3))
    k2 = np.array([0.0, 0.0, 2e-3])
    sigma = np.r_[np.full(3, np.radians(0.1) / 60 * 10), np.full(3, 100e-6 * 9.80665 * 10)]  # at 100 Hz
    noise = rng.standard_normal((9001, 6)) * sigma
    reports = {}
    for form in ("rate", "increment"):
        args = ["simulate", "turns.toml", "--imu", f"{form}.csv", "--truth", "truth.csv", "--form", form]
        assert main([*args, "--ideal"]) == 0
        table = io.read_table(f"{form}.csv")
        t = table.column("t")
        dt = np.diff(np.r_[0.0, t])[:, None] if form == "increment" else 1.0
        u = table.data[:, 1:7] / dt  # the true input: a sample, or an interval's mean
        error = bias + np.hstack([u[:, :3] @ matrix[0].T, u[:, 3:] @ matrix[1].T])
        error[:, :3] += k2 * u[:, :3] ** 2
        error += noise[: len(t)]
        table.data[:, 1:7] += error * dt
        io.write_table(f"{form}.csv", list(table.columns), table.data, "errors planted with numpy")
        assert main(["gap", f"{form}.csv", "--truth", "truth.csv", "--json", f"{form}.json"]) == 0
        reports[form] = json.loads((folder / f"{form}.json").read_text(encoding="utf-8"))
    capsys.readouterr()
    rate, inc = reports["rate"], reports["increment"]
    assert rate["diagnosis"] == inc["diagnosis"] == ["gyro.scale_nonlinearity"]
    assert rate["unexplained"] == inc["unexplained"]
    for channel, values in rate["channels"].items():
        for key in ("rms_before", "rms_after", "noise_floor"):
            assert inc["channels"][channel][key] == pytest.approx(values[key], rel=0.02), (channel, key)
    z = rate["channels"]["gyro.z"]
    assert z["rms_before"] > 1.2 * z["noise_floor"] and z["rms_after"] < 1.05 * z["noise_floor"]


# --------------------------------------------------------------------------- effects --grades


def test_effects_lists_every_grades_values(capsys) -> None:
    """``sins effects --grades``: a column per grade and a row per value of the grade definitions in
    code, each printed as defined (the values are short decimals, so %g prints them exactly)."""
    import dataclasses

    from sins.imu.spec import GRADES

    assert main(["effects", "--grades"]) == 0
    lines = capsys.readouterr().out.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("value"))
    assert lines[head].split()[-len(GRADES) :] == list(GRADES)
    rows = [line.split() for line in lines[head + 1 :]]
    fields = [
        f.name
        for f in dataclasses.fields(next(iter(GRADES.values())))
        if f.name not in ("name", "description")
    ]
    assert len(rows) == len(fields)
    for row, name in zip(rows, fields, strict=True):
        values = [float(v) for v in row[-len(GRADES) :]]
        assert values == [getattr(g, name) for g in GRADES.values()], name
    for grade in GRADES.values():
        assert any(grade.description in line for line in lines[:head])
