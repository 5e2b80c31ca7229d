"""Compensation strategies: interface laws, regression against the oracle, robustness, model files, CLI."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import refusal

from sins import compensation, imu, io
from sins.cli import main
from sins.core.series import CalibrationData, ImuRates
from sins.imu import calibration
from sins.imu import spec as imu_spec
from sins.nav import trajectory
from sins.nav.motion import Hold, SegmentMotion, Start, Turn

FAST = calibration.RigProcedure(position_dwell_s=8.0, rate_table=calibration.RateTable(dwell_s=4.0))


def _unit(grade: str, seed: int, *, noise: bool = True) -> imu.ImuModel:
    model = imu_spec.draw_unit(grade, seed, 100 + seed).only(*imu.BASELINE)
    return model if noise else model.without("gyro.noise", "accel.noise")


def _mean_rms(channels: dict[str, dict[str, float]], key: str) -> np.ndarray:
    values = np.array([v[key] for v in channels.values()])
    return np.array([values[:3].mean(), values[3:].mean()])  # gyro, accel


def test_interface_laws():
    data = calibration.simulate_rig(FAST, _unit("tactical", 1), seed=1)
    for name in ("none", "regression", "regression_robust"):
        strategy = compensation.make(name)
        assert strategy.fit(data) is strategy  # fit returns the strategy
        learned = [k for k in vars(strategy) if k.endswith("_")]
        assert (len(learned) > 0) == (name != "none")  # what it learned ends in "_"
        w, f = strategy.correct(data.gyro, data.accel)
        eg, ea = strategy.predict_error(data.gyro, data.accel)
        np.testing.assert_array_equal(eg, data.gyro - w)
        np.testing.assert_array_equal(ea, data.accel - f)
    with pytest.raises(ValueError, match="unknown strategy"):
        compensation.make("mlp_v0")
    with pytest.raises(ValueError, match="needs the simulated unit"):
        compensation.Oracle().fit(data)


def test_regression_comes_within_5_percent_of_the_oracle_on_linear_errors():
    """The issue's target, in residual sensor error on validation data, averaged over ten units."""
    ratios = []
    for seed in range(10):
        model = _unit("tactical", seed)
        fit, val = calibration.simulate_rig(FAST, model, seed=seed).split(0.3)
        oracle = _mean_rms(compensation.residual_rms(compensation.Oracle(model).fit(fit), val), "rms_after")
        regression = _mean_rms(
            compensation.residual_rms(compensation.make("regression").fit(fit), val), "rms_after"
        )
        ratios.append(regression / oracle)
    ratio = np.mean(ratios, axis=0)
    assert (ratio >= 1.0 - 1e-3).all()  # nobody beats the truth (beyond the noise of the validation RMS)
    assert (ratio <= 1.05).all()  # measured: 1.0003 gyro, 1.0001 accel


def test_robust_regression_resists_outliers_in_the_calibration_data():
    model = _unit("tactical", 5)
    data = calibration.simulate_rig(FAST, model, seed=5)
    rng = np.random.default_rng(0)
    bad = rng.choice(len(data), len(data) // 20, replace=False)  # 5 % of the rows
    gyro, accel = data.gyro.copy(), data.accel.copy()
    gyro[bad] += rng.normal(0.0, 0.05, (len(bad), 3))  # ~10,000 °/h glitches
    accel[bad] += rng.normal(0.0, 2.0, (len(bad), 3))  # ~200 mg glitches
    dirty_fit, _ = dataclasses.replace(data, gyro=gyro, accel=accel).split(0.3)
    _, clean_val = data.split(0.3)
    oracle = _mean_rms(
        compensation.residual_rms(compensation.Oracle(model).fit(dirty_fit), clean_val), "rms_after"
    )
    plain = _mean_rms(
        compensation.residual_rms(compensation.make("regression").fit(dirty_fit), clean_val), "rms_after"
    )
    robust = _mean_rms(
        compensation.residual_rms(compensation.make("regression_robust").fit(dirty_fit), clean_val),
        "rms_after",
    )
    assert (plain > 1.05 * oracle).all()  # the outliers pull least squares (measured +11 % gyro, +15 % accel)
    assert (robust < 1.01 * oracle).all()  # Huber weights put it back at the floor (measured +0.01 %)


def test_linear_strategy_corrects_increments_exactly():
    model = _unit("consumer", 3, noise=False)
    data = calibration.simulate_rig(FAST, model, seed=3)
    strategy = compensation.make("regression").fit(data)
    motion = SegmentMotion.from_segments(Start(0.7, 0.1, 50.0, 10.0), [Hold(5), Turn(10, 0.2, 2.0), Hold(5)])
    _, ideal = trajectory.generate(motion, 100.0)
    corrupted = model.corrupt_increments(ideal, seed=1)
    corrected = strategy.correct_increments(corrupted)
    # Consumer-grade (percent-level) linear errors, noiseless: removed to rounding.
    np.testing.assert_allclose(corrected.dtheta_b, ideal.dtheta_b, rtol=0, atol=1e-13)
    np.testing.assert_allclose(corrected.dv_b, ideal.dv_b, rtol=0, atol=1e-12)
    assert np.abs(corrupted.dtheta_b - ideal.dtheta_b).max() > 1e-6  # there was something to remove


def test_regression_corrects_increments_as_the_rate_form_does():
    # The seed model is affine: inverted on the increments (biases times the step) it gives the rate
    # form's correction of the mean rate times the step, but for rounding.
    model = _unit("consumer", 4, noise=False)
    strategy = compensation.make("regression").fit(calibration.simulate_rig(FAST, model, seed=4))
    motion = SegmentMotion.from_segments(Start(0.7, 0.1, 50.0, 10.0), [Hold(2), Turn(5, 0.4, 1.0), Hold(2)])
    _, ideal = trajectory.generate(motion, 100.0)
    corrupted = model.corrupt_increments(ideal, seed=2)
    direct = strategy.correct_increments(corrupted)
    via_rates = compensation.Strategy.correct_increments(strategy, corrupted)
    np.testing.assert_allclose(direct.dtheta_b, via_rates.dtheta_b, rtol=0, atol=1e-15)
    np.testing.assert_allclose(direct.dv_b, via_rates.dv_b, rtol=0, atol=1e-14)
    assert not np.array_equal(direct.dtheta_b, corrupted.dtheta_b)


def test_model_files_round_trip_and_refuse_other_versions(tmp_path: Path):
    data = calibration.simulate_rig(FAST, _unit("industrial", 2), seed=2)
    strategy = compensation.make("regression_robust").fit(data)
    path = tmp_path / "model.json"
    compensation.save(strategy, path)
    again = compensation.load(path)
    assert isinstance(again, compensation.Regression) and again.robust
    np.testing.assert_array_equal(
        again.correct(data.gyro, data.accel)[0], strategy.correct(data.gyro, data.accel)[0]
    )
    doc = json.loads(path.read_text())
    for change, fragment in (
        ({"version": 99}, "version 99"),
        ({"format": "something.else"}, "not a sins model file"),
        ({"strategy": "wizard"}, "unknown strategy 'wizard'"),
        (
            {"state": {"B0_": [1, 2]}, "params": {"robust": True, "colour": "red"}},
            "malformed regression model",
        ),
    ):
        bad = tmp_path / "bad.json"
        bad.write_text(json.dumps({**doc, **change}))
        refusal(lambda bad=bad: compensation.load(bad), str(bad), fragment)
    (tmp_path / "junk.json").write_text("{not json")
    refusal(lambda: compensation.load(tmp_path / "junk.json"), "junk.json", "not a sins model file")
    refusal(lambda: compensation.load(tmp_path / "missing.json"), "missing.json", "no such model file")
    with pytest.raises(ValueError, match="cannot be saved"):
        compensation.save(compensation.Oracle(_unit("tactical", 1)), tmp_path / "oracle.json")


def test_fit_and_evaluate_on_a_recording(tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    rec, model_path, out = tmp_path / "rec.csv", tmp_path / "model.json", tmp_path / "eval.json"
    io.write_recording(rec, calibration.simulate_rig(FAST, _unit("consumer", 4), seed=4))
    assert (
        main(["fit", str(rec), "--strategy", "regression", "--validation", "0.3", "--out", str(model_path)])
        == 0
    )
    assert main(["evaluate", str(model_path), str(rec), "--last", "0.3", "--json", str(out)]) == 0
    channels = json.loads(out.read_text())["channels"]
    assert list(channels) == list(imu.CHANNELS)
    for name, v in channels.items():
        assert v["rms_after"] < v["rms_before"], name  # consumer-grade errors dwarf the noise
    noise = _unit("consumer", 4)
    floor = (
        np.concatenate([noise.get("gyro.noise").density, noise.get("accel.noise").density]) * 10.0
    )  # 100 Hz
    after = np.array([v["rms_after"] for v in channels.values()])
    # What is left is the white noise, divided by (1 + scale factor): consumer units have percent-level ones.
    np.testing.assert_allclose(after, floor, rtol=0.05)
    # The last 0.3 of each phase is what the fit held back: a held-back judgement. The whole recording
    # holds rows the model was fitted on, and is said to; its last half, 0.2 of 0.5 in the fit, is 40 %
    # fitted on, and its last 0.9 67 %, said from half on (both had been said to be the model's own
    # readings, a share of 1.0).
    assert json.loads(out.read_text())["fitted_on_this_recording"] is False
    capsys.readouterr()
    assert main(["evaluate", str(model_path), str(rec), "--json", str(out)]) == 0
    assert json.loads(out.read_text())["fitted_on_this_recording"] is True
    assert "the model was fitted on these readings" in capsys.readouterr().out
    assert main(["evaluate", str(model_path), str(rec), "--last", "0.5", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["share_in_fit"] == pytest.approx(0.4) and doc["fitted_on_this_recording"] is False
    assert "model's fit" not in capsys.readouterr().out
    assert main(["evaluate", str(model_path), str(rec), "--last", "0.9", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["share_in_fit"] == pytest.approx(0.6 / 0.9)
    assert "about 67% of these readings were in the model's fit" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv_tail, fragment",
    [
        (["--strategy", "mlp_v0"], "unknown strategy"),
        (["--strategy", "oracle"], "cannot be fitted"),
    ],
)
def test_fit_refusals(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv_tail: list[str], fragment: str
):
    rec = tmp_path / "rec.csv"
    io.write_recording(rec, calibration.simulate_rig(FAST, _unit("tactical", 1), seed=1))
    assert main(["fit", str(rec), *argv_tail, "--out", str(tmp_path / "m.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and fragment in err and not (tmp_path / "m.json").exists()


def test_evaluate_refuses_a_recording_without_references(tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    data = calibration.simulate_rig(FAST, _unit("tactical", 1), seed=1)
    model_path = tmp_path / "m.json"
    compensation.save(compensation.make("regression").fit(data), model_path)
    plain = tmp_path / "plain.csv"
    io.write_imu(plain, ImuRates(t=data.t, omega_ib_b=data.gyro, f_ib_b=data.accel))
    assert main(["evaluate", str(model_path), str(plain)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no reference to judge against" in err and "--truth" in err


def test_a_poorly_determined_fit_shows_in_its_standard_errors():
    data = calibration.simulate_rig(FAST, _unit("consumer", 2), seed=2)
    head, _ = data.split(0.3, by_phase=False)  # the last 30 % in time holds every z-axis table run
    fit = calibration.fit_seed_model(head)
    whole = calibration.fit_seed_model(data)
    # Without z-axis table runs the z-rate column is seen only through the Earth's 15 °/h:
    # its scale factor's standard error is hundreds of times what the whole session gives.
    assert fit.B_se[2, 2] > 100 * whole.B_se[2, 2]
    assert fit.B_se[0, 0] < 2 * whole.B_se[0, 0]  # the x axis, which did turn, is unaffected


# --------------------------------------------------------------------------- learned strategies

NONLINEAR_RIG = calibration.RigProcedure(
    position_dwell_s=10.0,
    rate_table=calibration.RateTable(rates_dps=(10, 30, 60, 100, 150, 200), dwell_s=5.0),
)


@pytest.fixture(scope="module")
def nonlinear_runs() -> list[dict[str, np.ndarray]]:
    """Three tactical units with scale nonlinearity and g² sensitivity added; validation RMS per strategy."""
    runs = []
    for seed in range(3):
        rng = np.random.default_rng(seed)
        model = _unit("tactical", seed).with_effects(
            imu.ScaleNonlinearity("gyro", rng.normal(0.0, 3e-3, 3)),  # 3e-3 per rad/s: 1 % at 200 °/s
            imu.ScaleNonlinearity("accel", rng.normal(0.0, 5e-4, 3)),
            imu.G2Sensitivity("gyro", rng.normal(0.0, 2e-6, (3, 3, 3))),
        )
        fit, val = calibration.simulate_rig(NONLINEAR_RIG, model, seed=seed).split(0.3)
        names = ("none", "regression", "mlp", "kohonen", "kohonen_pure")
        strategies = {name: compensation.make(name) for name in names}
        strategies["oracle"] = compensation.Oracle(model)
        runs.append(
            {name: _after(compensation.residual_rms(s.fit(fit), val)) for name, s in strategies.items()}
        )
    return runs


def _after(channels: dict[str, dict[str, float]]) -> np.ndarray:
    return np.array([v["rms_after"] for v in channels.values()])


def _systematic(run: dict[str, np.ndarray], name: str) -> np.ndarray:
    """Residual beyond the oracle's (the unit's noise floor): sqrt(rms² − floor²)."""
    return np.sqrt(np.maximum(run[name] ** 2 - run["oracle"] ** 2, 0.0))


def test_mlp_leaves_at_most_half_the_residual_of_linear_regression(nonlinear_runs):
    total = np.mean([r["mlp"] / r["regression"] for r in nonlinear_runs], axis=0)
    # Gyros, where the nonlinear errors dominate: measured 0.06-0.30 of regression's residual.
    assert (total[:3] <= 0.5).all()
    # The accelerometers' errors here are mostly linear and regression already sits near the noise
    # floor, so halving the *total* is out of reach (measured 0.18-0.97); what regression leaves
    # beyond the floor, the network does halve.
    systematic = np.mean(
        [_systematic(r, "mlp") / _systematic(r, "regression") for r in nonlinear_runs], axis=0
    )
    assert (systematic <= 0.5).all()


def test_the_papers_map_improves_on_none_fivefold_beyond_the_noise_floor(nonlinear_runs):
    # kohonen_pure: node means over the readings. In total RMS the accelerometers cannot improve 5x:
    # their errors are only 1.3-3x their noise. The systematic part (beyond the oracle's floor) improves
    # 7-12x on the gyros, more on the accelerometers.
    ratios = [
        _systematic(r, "none") / np.maximum(_systematic(r, "kohonen_pure"), 1e-15) for r in nonlinear_runs
    ]
    ratio = np.mean(ratios, axis=0)
    assert (ratio >= 5.0).all()
    assert (np.mean([r["none"] / r["kohonen_pure"] for r in nonlinear_runs], axis=0)[:3] >= 3.0).all()


def test_the_local_linear_map_is_never_worse_than_regression_and_halves_it_on_the_gyros(nonlinear_runs):
    for run in nonlinear_runs:
        # The guard's promise on the rig it was fitted on (held-back rows): no channel worse than
        # regression beyond its own estimation noise.
        assert (run["kohonen"] <= 1.01 * run["regression"]).all()
    systematic = np.mean(
        [_systematic(r, "kohonen") / _systematic(r, "regression") for r in nonlinear_runs], axis=0
    )
    # Measured: 0.05-0.3 on the gyros. The accelerometers' systematic error is 0.2-1 of regression's: on this
    # faces-down rig the force is only ever ±1 g along an axis, six points a map folds between.
    assert (systematic[:3] <= 0.5).all()


@pytest.mark.parametrize("name", ["mlp_seed"])  # the others: tests/test_learned.py
def test_learned_strategies_save_load_and_correct_alike(tmp_path: Path, name: str):
    data = calibration.simulate_rig(FAST, _unit("consumer", 6), seed=6)
    small = data.rows(slice(0, len(data), 20))  # 2,600 rows: enough to learn something, fast
    small = calibration.CalibrationData(small.t, small.gyro, small.accel, small.ref_gyro, small.ref_accel)
    params = {"max_epochs": 3} if name == "mlp_seed" else {}
    strategy = compensation.make(name, **params).fit(small)
    path = tmp_path / f"{name}.json"
    compensation.save(strategy, path)
    again = compensation.load(path)
    w1, f1 = strategy.correct(data.gyro, data.accel)
    w2, f2 = again.correct(data.gyro, data.accel)
    np.testing.assert_array_equal(w2, w1)
    np.testing.assert_array_equal(f2, f1)
    before = _after(compensation.residual_rms(compensation.make("none"), data))
    after = _after(compensation.residual_rms(strategy, data))
    assert (after < before).mean() >= 0.5  # it learned something on most channels


def test_seed_mode_stops_at_its_residual():
    data = calibration.simulate_rig(FAST, _unit("consumer", 7), seed=7)
    small = data.rows(slice(0, len(data), 40))
    small = calibration.CalibrationData(small.t, small.gyro, small.accel, small.ref_gyro, small.ref_accel)
    loose = compensation.make("mlp_seed", residual=1.0, max_epochs=50).fit(small)
    assert loose.epochs_ == 1 and loose.final_error_ < 1.0  # ε below 1 after the first pass: stop
    tight = compensation.make("mlp_seed", residual=1e-12, max_epochs=3).fit(small)
    assert tight.epochs_ == 3 and tight.final_error_ > 1e-12  # never reached: stopped by max_epochs


# --------------------------------------------------------------------------- strategies in scenarios

LINEAR_IMU = """\
[[effect]]
name = "gyro.bias"
bias_dph = [4.0, -3.0, 5.0]
[[effect]]
name = "accel.bias"
bias_mg = [0.8, -1.1, 0.6]
[[effect]]
name = "gyro.scale_misalignment"
matrix_ppm = [[300, 120, -80], [-150, -250, 60], [90, -40, 400]]
[[effect]]
name = "accel.scale_misalignment"
matrix_ppm = [[250, -90, 70], [110, -300, -50], [-60, 80, 200]]
[[effect]]
name = "gyro.g_sensitivity"
matrix_dph_per_g = [[1.0, -0.5, 0.3], [0.4, -1.2, 0.2], [-0.3, 0.6, 0.8]]
[[effect]]
name = "gyro.noise"
arw_deg_per_rt_h = 0.05
[[effect]]
name = "accel.noise"
vrw_ug_per_rt_hz = 50
"""

DRIVE = """\
[imu]
rate_hz = 100
model = "{imu}"
seed = {seed}
[compensation]
rig = "24pos_ratetable"
validation = 0.3
seed = {rig_seed}
strategies = ["regression"]
[navigation]
vertical = "damp"
[initial]
lat_deg = 45.0
lon_deg = 7.0
alt_m = 200.0
[[segment]]
type = "accelerate"
duration_s = 20
to_speed_mps = 15
[[segment]]
type = "turn"
duration_s = 30
angle_deg = 90
[[segment]]
type = "hold"
duration_s = 250
[[segment]]
type = "turn"
duration_s = 30
angle_deg = -120
[[segment]]
type = "hold"
duration_s = 270
"""


def test_regression_drifts_like_the_oracle_over_an_hour_on_the_seed_model_alone():
    """The issue's drift target on a unit with only the seed's linear errors (no noise: DESIGN §4).

    Regression recovers the 33 coefficients so exactly that the hour's drift is the integrator's
    own, like the oracle's; the uncompensated unit drifts kilometres, so a coefficient off by one
    part in 10⁶ (0.2 °/h of bias) would show. With white noise added the rig's finite length
    limits it instead: see the next test and tools/bench_rig_length.py.
    """
    from sins.nav import strapdown
    from sins.nav.metrics import nav_errors, summarize

    seg = [Turn(30, np.radians(3.0), 3.0), Hold(3570)]
    drive = SegmentMotion.from_segments(Start(np.radians(45.0), 0.1, 200.0), seg)
    truth, ideal = trajectory.generate(drive, 50.0)
    start = strapdown.InitialState.from_series(truth)
    ratios = []
    for seed in range(3):
        model = _unit("tactical", seed, noise=False)
        corrupted = model.corrupt_increments(ideal)
        fit, _ = calibration.simulate_rig(FAST, model, seed=seed).split(0.3)
        drift = {}
        for name, strategy in (
            ("none", compensation.make("none")),
            ("oracle", compensation.Oracle(model)),
            ("regression", compensation.make("regression").fit(fit)),
        ):
            corrected = strategy.correct_increments(corrupted)
            sol = strapdown.integrate(corrected, start, vertical="hold", h_ref=truth.h)
            drift[name] = summarize(nav_errors(sol, truth)).final_horizontal_m
        assert drift["none"] > 1000.0  # measured 497-1481 km
        assert drift["oracle"] < 0.01  # the integrator's own error over the hour (measured 0.035 mm)
        ratios.append(drift["regression"] / drift["oracle"])
    assert abs(np.mean(ratios) - 1.0) < 0.05  # measured 1.00004, 1.00010, 0.99983


def test_regression_drift_is_bounded_by_its_calibration_on_linear_errors(tmp_path: Path):
    """Ten-minute drives of a unit with the seed model's errors plus white noise (the baseline).

    Here the 5 % drift target is out of reach of a 17-minute rig session, and it should not be
    expected: the fitted gyro biases carry a standard error of about 0.1 °/h (30 °/h of noise per
    sample over ~1e5 samples), which alone drifts g·ε·t³/6 ≈ 170 m in ten minutes against the
    ~600 m the unit's own noise drives. Measured ratios to the oracle: 1.76, 1.37, 0.96. The
    excess shrinks as 1/T with the rig's length T (tools/bench_rig_length.py, one-hour drives,
    20 units: 4.1× at 17 min, 2.0× at 65 min, 1.3× at 4.3 h, 0.96× at 17 h). What must hold: residual sensor
    error within 5 % of the oracle's, and a drift far below the uncompensated one and within a
    factor 2 of the oracle's.
    """
    from sins import scenario
    from sins.runs import pipeline

    (tmp_path / "imu.toml").write_text(LINEAR_IMU)
    ratios = []
    for seed in range(3):
        path = tmp_path / f"drive{seed}.toml"
        path.write_text(DRIVE.format(imu=tmp_path / "imu.toml", seed=seed, rig_seed=10 + seed))
        runs = pipeline.run_scenario(scenario.load(path)).runs
        oracle = runs["oracle"].summary.final_horizontal_m
        assert runs["none"].summary.final_horizontal_m > 5 * oracle
        ratios.append(runs["regression"].summary.final_horizontal_m / oracle)
        residual = np.array(list(runs["regression"].residual_rms.values()))
        assert (residual <= 1.05 * np.array(list(runs["oracle"].residual_rms.values()))).all()
    assert 0.5 < np.mean(ratios) < 2.0


def test_run_json_has_every_strategy_with_residuals(tmp_path: Path, capsys: pytest.CaptureFixture[str]):
    (tmp_path / "imu.toml").write_text(LINEAR_IMU)
    path = tmp_path / "drive.toml"
    path.write_text(DRIVE.format(imu=tmp_path / "imu.toml", seed=0, rig_seed=1))
    out = tmp_path / "run.json"
    assert main(["run", str(path), "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "residual sensor error" in printed and "× oracle" in printed
    strategies = json.loads(out.read_text())["strategies"]
    assert list(strategies) == ["none", "oracle", "regression"]
    for name in ("oracle", "regression"):
        assert list(strategies[name]["residual_rms"]) == list(imu.CHANNELS)
        assert strategies[name]["final_horizontal_m"] > 0
    assert "residual_rms" not in strategies["none"]  # "none" is the raw stream, not fitted on the rig


def test_extended_regression_captures_squares_and_temperature(tmp_path: Path):
    rig = calibration.RigProcedure(
        position_dwell_s=8.0,
        rate_table=calibration.RateTable(rates_dps=(10, 30, 60, 100, 150, 200), dwell_s=4.0),
        temperature=calibration.TemperatureProfile((0.0, 800.0), (0.0, 40.0)),  # a chamber ramp
    )
    rng = np.random.default_rng(0)
    model = _unit("tactical", 0).with_effects(
        imu.ScaleNonlinearity("gyro", rng.normal(0.0, 3e-3, 3)),
        imu.ScaleNonlinearity("accel", rng.normal(0.0, 5e-4, 3)),
        imu.TemperatureBias("gyro", c1=[1e-6, -1e-6, 2e-6]),  # ~0.2 °/h per °C
        imu.TemperatureScale("accel", s1=[1e-5, -2e-5, 1e-5]),  # 10-20 ppm per °C
    )
    fit, val = calibration.simulate_rig(rig, model, seed=0).split(0.3)
    oracle = _after(compensation.residual_rms(compensation.Oracle(model), val))
    plain = _after(compensation.residual_rms(compensation.make("regression").fit(fit), val))
    extended = compensation.make("regression_extended").fit(fit)
    after = _after(compensation.residual_rms(extended, val))
    assert (plain[:3] > 3.0 * oracle[:3]).all()  # the linear model cannot represent k2·ω² (measured 3.4-17x)
    np.testing.assert_allclose(after, oracle, rtol=0.01)  # with squares and temperature it can (1.000x)
    path = tmp_path / "extended.json"
    compensation.save(extended, path)
    again = compensation.load(path)
    np.testing.assert_array_equal(
        again.correct(val.gyro, val.accel, val.temp)[0], extended.correct(val.gyro, val.accel, val.temp)[0]
    )
    with pytest.raises(ValueError, match="temperature"):
        extended.correct(val.gyro, val.accel)


def test_extended_regression_refuses_what_the_rig_cannot_tell(tmp_path: Path):
    """A table turning about the vertical only: the reference's f_z is −g on every row but for a wobble in
    its 11th digit (a reference printed to that many), so its square is the bias column again to 1e-11.
    Least squares with numpy's default cut gave the pair cancelling coefficients of ~1e16, which the
    model-file reader then refused (sins would write a file it cannot read); the minimum-norm solution
    that followed kept them small, but shared the bias with the force's columns, so that a single held
    pose corrected other forces by tens of m/s² (a library walk's). Such rows determine no seed model:
    refused as ``regression`` refuses them, and no file is written."""
    rng = np.random.default_rng(3)
    n = 4000
    t = np.arange(n) / 100.0
    w = np.zeros((n, 3))
    w[:, 2] = np.radians(40.0) * np.sin(2 * np.pi * 0.05 * t)
    f = np.zeros((n, 3))
    f[:, 2] = -9.80665 * (1.0 + 1e-11 * np.sin(2 * np.pi * 0.3 * t))
    f[:, 0] = 1e-10 * np.cos(t)
    gyro = w + 1e-4 + rng.normal(0, 1e-4, (n, 3))
    accel = f + 1e-2 + rng.normal(0, 1e-3, (n, 3))
    data = CalibrationData(t=t, gyro=gyro, accel=accel, ref_gyro=w, ref_accel=f)
    for name in ("regression", "regression_extended"):
        with pytest.raises(ValueError, match="not determined by this recording"):
            compensation.make(name).fit(data)
