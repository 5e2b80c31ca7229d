"""Compensation fitted against a reference trajectory on intervals (sins.compensation.interval_fit,
sins.compensation.referenced, ``sins fit/evaluate/correct`` with a reference), judged on data sins did not
make: a
unit of known errors written with numpy whose reference is ten times noisier than the sensor
(tests/numpy_referenced.py), BROAD's motion capture and the PSINS drive (skipped without the data)."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from numpy_referenced import GRAVITY, HEIGHT_M, LAT_DEG, session, typical_unit
from scipy.spatial.transform import Rotation

from sins import compensation
from sins.cli import main
from sins.compensation import coefficients, interval_fit, judging, referenced
from sins.core import earth
from sins.core.series import ImuIncrements, ImuRates, NavSeries
from sins.imu.calibration import SeedModelFit
from sins.io.datasets.root import data_root

DATA = data_root()
BROAD = DATA / "broad_mocap" / "05_undisturbed_slow_rotation_with_breaks_B.mat"
BROAD_18 = DATA / "broad_mocap" / "18_undisturbed_fast_translation_with_breaks_B.mat"
PSINS = DATA / "psins_fog_mems_vehicle" / "transfer_align_fog_mems.mat"
needs_broad = pytest.mark.skipif(
    not (BROAD.exists() and BROAD_18.exists()), reason=f"BROAD trials not in {DATA}"
)
needs_psins = pytest.mark.skipif(not PSINS.exists(), reason=f"the PSINS drive is not in {DATA}")


def _recording(seed: int, **kwargs: float) -> tuple[referenced.ReferencedRecording, object]:
    rng = np.random.default_rng(seed)
    unit = typical_unit(rng)
    s = session(rng, unit, **kwargs)
    lat = np.full(len(s.t_ref), math.radians(LAT_DEG))
    truth = NavSeries(
        t=s.t_ref,
        lat=lat,
        lon=np.zeros(len(s.t_ref)),
        h=np.full(len(s.t_ref), HEIGHT_M),
        v_n=s.v_n,
        q_nb=s.q_nb,
    )
    rec = judging.from_recording(ImuRates(t=s.t, omega_ib_b=s.gyro, f_ib_b=s.accel), truth, "numpy unit")
    return rec, unit


def test_the_generator_agrees_with_the_physics_sins_assumes() -> None:
    """The test's gravity constant is WGS84's normal gravity at its latitude (1e-8 m/s²): otherwise the
    accelerometer's bias would absorb the difference."""
    assert float(earth.normal_gravity(math.radians(LAT_DEG), HEIGHT_M)) == pytest.approx(GRAVITY, abs=1e-8)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_known_unit_is_recovered_within_its_standard_errors_with_a_reference_ten_times_noisier(
    seed: int,
) -> None:
    """Reference noise ten times the sensor's over an interval: every coefficient (biases, scale and
    misalignment, both time offsets) within 4 standard errors of the truth, and the standard errors
    honest: the RMS of the z-scores between 0.4 and 2 (a z-score RMS far below 1 would mean the stated
    errors are inflated, far above that they are too small; 3 × 27 coefficients scatter by ~0.14)."""
    rec, unit = _recording(seed)
    fit = interval_fit.fit_intervals(rec, g_sensitivity=False)
    s = fit.seed
    truth = np.concatenate(
        [unit.B0, unit.B.ravel(), unit.A0, unit.A.ravel(), [unit.gyro_delay_s, unit.accel_delay_s]]
    )
    est = np.concatenate([s.B0, s.B.ravel(), s.A0, s.A.ravel(), [fit.time_offset_s, fit.accel_time_offset_s]])
    se = np.concatenate(
        [s.B0_se, s.B_se.ravel(), s.A0_se, s.A_se.ravel(), [fit.time_offset_se_s, fit.accel_time_offset_se_s]]
    )
    z = (est - truth) / se
    assert np.all(np.abs(z) < 4.0), z.round(2)
    assert 0.4 < float(np.sqrt(np.mean(z * z))) < 2.0, z.round(2)
    # The errors are worth having: scale factors to better than 500 ppm, biases to 30 °/h and 2 mg.
    assert np.all(s.B_se < 5e-4) and np.all(np.degrees(s.B0_se) * 3600 < 30) and np.all(s.A0_se < 2e-2)


def test_fast_turning_within_an_interval_costs_nothing() -> None:
    """Intervals of 5 s over rates of up to 60 °/s (turns of 100° and more that do not commute): the
    composed rotation keeps the scale factors within their standard errors, where summing the rates
    would not."""
    rec, unit = _recording(4)
    fit = interval_fit.fit_intervals(rec, interval_s=5.0, g_sensitivity=False)
    z = (fit.seed.B - unit.B) / fit.seed.B_se
    assert np.all(np.abs(z) < 4.0), z.round(2)


def test_the_intervals_jacobians_are_their_residuals_derivatives() -> None:
    """Each interval's Jacobian, as the fit's least squares reads it (``y ≈ x δ``: the residual left
    falls by ``x δ`` when the parameters move by ``δ``), against central differences of the residual
    itself, at a point off the fit (a few mg, 1e-3 of matrix, 3 ms): the accelerometer's 12 columns of
    bias and matrix and its time offset within 2e-4 of each column's largest entry (measured 3e-7 to
    1.6e-5); the gyro's 21 of bias, matrix and g-sensitivity and its time offset within 3e-2 (measured
    3.4e-3 to 1.1e-2: the Gauss-Newton step's first-order model of the turns, with its residual rotation
    up to 6.4 mrad here). A column summed over the wrong steps or turned by the wrong attitude is off by
    its own size."""
    from sins.compensation.intervals import choose_intervals, expected_dv, lever
    from sins.nav import attitude

    rec, _ = _recording(5)
    fit = interval_fit.fit_intervals(rec, g_sensitivity=False)
    iv, dt = choose_intervals(rec, 1.0), np.diff(rec.imu.t)
    rng = np.random.default_rng(0)
    A0, A = fit.seed.A0 + rng.normal(0.0, 0.03, 3), fit.seed.A + rng.normal(0.0, 1e-3, (3, 3))
    q_int = attitude.propagate_increments(fit.corrected(rec.imu).dtheta_b, np.array([0.0, 0.0, 0.0, 1.0]))
    fixed = (expected_dv(iv, dt), lever(iv, rec.imu, fit.seed, dt))

    def accel(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return interval_fit.accel_problem(
            iv,
            rec.imu,
            dt,
            q_int,
            A0 + theta[:3],
            A + theta[3:12].reshape(3, 3),
            0.003 + theta[12],
            True,
            *fixed,
        )

    x, _ = accel(np.zeros(13))
    steps = np.r_[np.full(3, 1e-4), np.full(9, 1e-6), 1e-5]
    for i, column in enumerate([*range(12), 15]):
        up, down = np.zeros(13), np.zeros(13)
        up[i], down[i] = steps[i], -steps[i]
        numeric = (accel(down)[1] - accel(up)[1]) / (2 * steps[i])
        scale = np.max(np.abs(x[:, :, column]))
        assert np.max(np.abs(numeric - x[:, :, column])) < 2e-4 * scale, (i, column)

    seed = dataclasses.replace(fit.seed, K=np.full((3, 3), 1e-5))

    def gyro(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        moved = dataclasses.replace(
            seed,
            B0=seed.B0 + theta[:3],
            B=seed.B + theta[3:12].reshape(3, 3),
            K=seed.K + theta[12:21].reshape(3, 3),
        )
        return interval_fit.gyro_problem(iv, rec.imu, dt, moved, 0.003 + theta[21], 0.0, True, True)

    x, _ = gyro(np.zeros(22))
    steps = np.r_[np.full(3, 1e-5), np.full(9, 1e-5), np.full(9, 1e-6), 1e-5]
    for i in range(22):
        up, down = np.zeros(22), np.zeros(22)
        up[i], down[i] = steps[i], -steps[i]
        numeric = (gyro(down)[1] - gyro(up)[1]) / (2 * steps[i])
        scale = np.max(np.abs(x[:, :, i]))
        assert np.max(np.abs(numeric - x[:, :, i])) < 3e-2 * scale, i


def test_the_intervals_problems_are_their_plain_sums() -> None:
    """Each interval's sums, against plain code over its own steps: the accelerometer's residual is the
    one :func:`~sins.compensation.intervals.velocity_residual` gives (another code, running sums) turned
    into the reference's world, and the gyro's Jacobian is ``Q_bᵀ Σ_j Q_j f_j`` over the interval's steps
    ``j`` (``Q_j`` the attitude after step ``j``, ``f_j`` its columns: ``-(I + B)⁻¹ e_r u_c``, then the
    time offset's), summed in a loop. Within 1e-9 of each one's largest entry: one step too many, or an
    attitude one step off, moves them by about a step's share (1 % of an interval's 100 steps here)."""
    from sins.compensation import intervals as ivs
    from sins.nav import attitude

    rec, _ = _recording(5)
    fit = interval_fit.fit_intervals(rec, g_sensitivity=False)
    iv, dt = ivs.choose_intervals(rec, 1.0), np.diff(rec.imu.t)
    seed = dataclasses.replace(fit.seed, A0=fit.seed.A0 + 0.02, A=fit.seed.A + 1e-3, K=np.full((3, 3), 1e-5))
    q_int = attitude.propagate_increments(fit.corrected(rec.imu).dtheta_b, np.array([0.0, 0.0, 0.0, 1.0]))
    _, y = interval_fit.accel_problem(
        iv,
        rec.imu,
        dt,
        q_int,
        seed.A0,
        seed.A,
        0.003,
        True,
        ivs.expected_dv(iv, dt),
        ivs.lever(iv, rec.imu, seed, dt),
    )
    a_inv = np.linalg.inv(np.eye(3) + seed.A)
    u = (ivs.shifted(rec.imu.t, rec.imu.dv_b, 0.003) - seed.A0 * dt[:, None]) @ a_inv.T
    body = ivs.velocity_residual(iv, ivs.dcm(q_int), u, dt)
    world = np.einsum("kab,kb->ka", ivs.dcm(iv.q_start), body)
    assert np.max(np.abs(y - world)) < 1e-9 * np.max(np.abs(world))

    x, _ = interval_fit.gyro_problem(iv, rec.imu, dt, seed, 0.003, 0.0, True, True)
    corrected = ivs.correct_increments(rec.imu, seed, 0.003, 0.0)
    q = ivs.dcm(attitude.propagate_increments(corrected.dtheta_b, np.array([0.0, 0.0, 0.0, 1.0])))
    b_inv = np.linalg.inv(np.eye(3) + seed.B)
    blocks = [dt[:, None], corrected.dtheta_b, corrected.dv_b]
    f = np.stack(
        [
            -b_inv[:, r][None, :] * block[:, c : c + 1]
            for block in blocks
            for r in range(3)
            for c in range(block.shape[1])
        ]
        + [ivs.shift_derivative(rec.imu.t, rec.imu.dtheta_b, 0.003) @ b_inv.T],
        axis=2,
    )
    plain = np.empty_like(x)
    for k, (a, b) in enumerate(zip(iv.start, iv.stop, strict=True)):
        total = np.zeros((3, f.shape[2]))
        for j in range(a, b):
            total += q[j + 1] @ f[j]
        plain[k] = q[b].T @ total
    assert np.max(np.abs(x - plain)) < 1e-9 * np.max(np.abs(plain))


def test_the_learners_see_what_the_seed_model_leaves() -> None:
    """The per-sample references reproduce the seed model: regression fitted on them lands on the
    interval fit's coefficients within its standard errors."""
    rec, _ = _recording(5)
    fit = interval_fit.fit_intervals(rec, g_sensitivity=False)
    data = interval_fit.interval_reference(rec, fit)
    again = compensation.make("regression", g_sensitivity=False).fit(data)
    assert np.all(np.abs(again.B_ - fit.seed.B) < 2.0 * fit.seed.B_se)
    assert np.all(np.abs(again.B0_ - fit.seed.B0) < 2.0 * fit.seed.B0_se)


def test_the_coefficients_in_an_engineers_units() -> None:
    zeros, nan = np.zeros((3, 3)), np.full((3, 3), np.nan)
    seed = SeedModelFit(
        B0=np.radians(np.array([1.0, 0.0, 0.0])) / 3600.0,
        B=np.array([[1e-6, 0.0, 0.0], [1e-3, 0.0, 0.0], [0.0, 0.0, 0.0]]),
        K=zeros + np.radians(1.0 / 3600.0) / 9.80665, A0=np.array([9.80665e-6, 0.0, 0.0]), A=zeros,
        B0_se=np.full(3, np.nan), B_se=nan, K_se=nan, A0_se=np.zeros(3), A_se=zeros, residual_rms=np.zeros(6),
    )  # fmt: skip
    table = {(c.sensor, c.term, c.axis): c for c in coefficients.engineering(seed)}
    assert table["gyro", "bias", "x"].value == pytest.approx(1.0) and table["gyro", "bias", "x"].unit == "°/h"
    assert (
        table["gyro", "scale", "x"].value == pytest.approx(1.0) and table["gyro", "scale", "x"].unit == "ppm"
    )
    assert table["gyro", "misalignment", "y←x"].value == pytest.approx(1.0)
    assert table["gyro", "g_sensitivity", "z←y"].value == pytest.approx(1.0)
    assert (
        table["accel", "bias", "x"].value == pytest.approx(1.0) and table["accel", "bias", "x"].unit == "µg"
    )
    assert table["gyro", "bias", "x"].to_dict()["se"] is None


def _write_truth(path: Path, s: Any) -> None:
    """The session's reference as a truth CSV (sins's columns, angles in degrees)."""
    ypr = Rotation.from_quat(s.q_nb).as_euler("ZYX", degrees=True)
    m = len(s.t_ref)
    rows = np.column_stack(
        [
            s.t_ref,
            np.full(m, LAT_DEG),
            np.zeros(m),
            np.full(m, HEIGHT_M),
            s.v_n,
            ypr[:, 2],
            ypr[:, 1],
            ypr[:, 0],
        ]
    )
    np.savetxt(path, rows, delimiter=",", header="t,lat,lon,alt,vn,ve,vd,roll,pitch,yaw", comments="")


def test_fit_evaluate_and_correct_a_users_recording_with_its_truth(tmp_path: Path) -> None:
    """The CLI as a user runs it: a rate CSV and a truth CSV written with numpy; the model file keeps the
    time offsets; evaluate reports the open-loop attitude; correct writes readings that equal the
    strategy's own correction of them."""
    rng = np.random.default_rng(7)
    s = session(rng, typical_unit(rng), duration_s=120.0)
    imu = tmp_path / "imu.csv"
    truth = tmp_path / "truth.csv"
    rows = np.column_stack([s.t, s.gyro, s.accel])
    np.savetxt(imu, rows, delimiter=",", header="t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z", comments="")
    _write_truth(truth, s)
    model, report = tmp_path / "m.json", tmp_path / "e.json"
    assert (
        main(["fit", str(imu), "--truth", str(truth), "--strategy", "regression", "--out", str(model)]) == 0
    )
    saved = json.loads(model.read_text())
    assert saved["variant"] == "regression" and len(saved["state"]["time_offset_s_"]) == 2
    rrd = tmp_path / "open_loop.rrd"
    argv = [
        "evaluate",
        str(model),
        str(imu),
        "--truth",
        str(truth),
        "--json",
        str(report),
        "--rerun",
        str(rrd),
    ]
    assert main(argv) == 0
    doc = json.loads(report.read_text())
    # The Rerun recording holds the very errors the figures are made of.
    logged = _rerun_scalars(rrd, "open_loop/total/regression")
    assert np.degrees(np.sqrt(np.mean(np.radians(logged) ** 2))) == pytest.approx(
        doc["open_loop_attitude"]["total_deg"], rel=1e-9
    )
    # Two minutes of a 0.1 °/s-bias unit turning back and forth: the raw gyro drifts ~2°; the fit's own
    # bias error (its standard error here, ~15 °/h, is the reference's noise) leaves a few tenths.
    assert doc["open_loop_attitude"]["total_deg"] < 0.5 * doc["open_loop_attitude_raw"]["total_deg"]
    out = tmp_path / "corrected.csv"
    assert main(["correct", str(model), str(imu), "--out", str(out)]) == 0
    lines = [line for line in out.read_text().splitlines() if not line.startswith("#")]
    assert lines[0] == "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"
    back = np.loadtxt(lines[1:], delimiter=",")
    strategy = compensation.load(model)
    expected = strategy.correct_rates(ImuRates(t=s.t, omega_ib_b=s.gyro, f_ib_b=s.accel))
    assert np.array_equal(back[:, 0], s.t)
    np.testing.assert_allclose(back[:, 1:4], expected.omega_ib_b, rtol=0, atol=1e-15)
    np.testing.assert_allclose(back[:, 4:7], expected.f_ib_b, rtol=0, atol=1e-15)


def _rerun_scalars(path: Path, entity: str) -> np.ndarray:
    import rerun as rr

    values = []
    for chunk in rr.chunk.RrdReader(path).stream():
        if chunk.entity_path.lstrip("/") == entity and not chunk.is_static:
            batch = chunk.to_record_batch()
            name = next(n for n in batch.schema.names if n.endswith(":scalars"))
            values.append(np.array(batch.column(name).to_pylist(), dtype=float).reshape(-1))
    out = np.concatenate(values)
    return out[np.isfinite(out)]


def test_refusals_in_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rng = np.random.default_rng(8)
    s = session(rng, typical_unit(rng), duration_s=60.0)
    imu = tmp_path / "imu.csv"
    np.savetxt(imu, np.column_stack([s.t, s.gyro, s.accel]), delimiter=",",
               header="t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z", comments="")  # fmt: skip
    late = tmp_path / "late.csv"
    rows = [[1000.0, 45, 0, 0, 0, 0, 0, 0, 0, 0], [1001.0, 45, 0, 0, 0, 0, 0, 0, 0, 0]]
    np.savetxt(late, rows, delimiter=",", header="t,lat,lon,alt,vn,ve,vd,roll,pitch,yaw", comments="")
    cases = [
        (
            ["fit", "--dataset", "nowhere", "--strategy", "regression", "--out", "m.json"],
            "no dataset 'nowhere'",
        ),
        (["fit", str(imu), "--strategy", "regression", "--out", "m.json"], "no reference to fit against"),
        (
            ["fit", str(imu), "--truth", str(late), "--strategy", "regression", "--out", "m.json"],
            "does not overlap",
        ),
        (["fit", str(imu), "--strategy", "nonsense", "--out", "m.json"], "unknown"),
        (  # refused before the fit, not after it
            [
                "fit",
                str(imu),
                "--truth",
                str(late),
                "--strategy",
                "regression",
                "--out",
                str(tmp_path / "no" / "m.json"),
            ],
            "does not exist",
        ),
        (["correct", "m.json", str(imu), "--out", str(tmp_path)], "is a directory"),
    ]
    for argv, text in cases:
        assert main(argv) == 2, argv
        captured = capsys.readouterr()
        assert text in captured.err and captured.err.count("\n") == 1, captured.err
        assert "fitted" not in captured.out, captured.out


@needs_broad
def test_broad_fitted_on_one_trial_and_judged_on_the_other(tmp_path: Path) -> None:
    """BROAD's unit B, both ways: the report carries BROAD's three figures; ``none`` (the raw gyro)
    reproduces an independent scipy integration within 5 % (Earth's vertical rate, which sins takes out,
    is 0.3° of 30°); the fitted model removes most of the raw drift (the bar: a fifth); and the gyro's
    time offset, a property of the unit, agrees between the trials within three standard errors."""
    import scipy.io

    offsets = {}
    for fit_on, judge in (("05", "18"), ("18", "05")):
        model, out = tmp_path / f"m{fit_on}.json", tmp_path / f"e{judge}.json"
        assert main(["fit", "--dataset", f"broad_{fit_on}", "--strategy", "regression", "--out", str(model),
                     "--json", str(tmp_path / f"f{fit_on}.json")]) == 0  # fmt: skip
        assert main(["evaluate", str(model), "--dataset", f"broad_{judge}", "--json", str(out)]) == 0
        doc = json.loads(out.read_text())
        att = doc["open_loop_attitude"]
        assert set(att) >= {"total_deg", "heading_deg", "inclination_deg"}
        raw = doc["open_loop_attitude_raw"]["total_deg"]
        assert att["total_deg"] < 0.2 * raw
        mat = scipy.io.loadmat(BROAD if judge == "05" else BROAD_18, squeeze_me=True)
        assert raw == pytest.approx(_independent_raw(mat), rel=0.05)
        fitted = json.loads((tmp_path / f"f{fit_on}.json").read_text())
        offsets[fit_on] = (fitted["time_offset_ms"]["gyro"], fitted["time_offset_se_ms"]["gyro"])
    (a, sa), (b, sb) = offsets["05"], offsets["18"]
    assert abs(a - b) < 3.0 * math.hypot(sa, sb), offsets


def _independent_raw(mat: dict[str, np.ndarray]) -> float:
    """BROAD's total RMSE of the raw gyro integrated from the first valid optical orientation, with scipy
    (rectangle rule: each sample turns the step before it), over the movement rows."""
    gyr, q, moving = mat["imu_gyr"], mat["opt_quat"], mat["movement"].astype(bool)
    ok = np.isfinite(q).all(axis=1)
    first = int(np.argmax(ok))
    steps = Rotation.from_rotvec(gyr[first + 1 :] / float(mat["sampling_rate"]))
    att = [Rotation.from_quat(q[first][[1, 2, 3, 0]])]
    for r in steps:
        att.append(att[-1] * r)
    est = Rotation.concatenate(att)
    rows = np.arange(first, len(q))
    judged = ok[rows] & moving[rows]
    err = (est[judged] * Rotation.from_quat(q[rows][judged][:, [1, 2, 3, 0]]).inv()).magnitude()
    return float(np.degrees(np.sqrt(np.mean(err * err))))


@needs_psins
def test_psins_drive_fitted_on_70_s_and_judged_on_the_last_30() -> None:
    """The PSINS drive: the gyro biases fitted on the first 70 s against the FOG-INS agree with the file's
    own ``eb0`` (the demo's reference value, not used by the fit) within 0.005 °/s; the corrected MEMS
    navigating free from the FOG-INS state over the last 30 s ends nearer than the raw one by ten times."""
    from sins import io
    from sins.io.datasets.psins_reference import psins_file_biases

    rec = io.read(dataset="psins_vehicle").beside_reference()
    fitted = referenced.fit("regression", judging.between(rec, rec.imu.t[0], 70.0))
    eb0, _ = psins_file_biases()
    assert np.all(np.abs(np.degrees(fitted.intervals.seed.B0 - eb0)) < 0.005)
    raw = judging.drive_errors(None, rec, 70.0, 100.0)
    fixed = judging.drive_errors(fitted.strategy, rec, 70.0, 100.0)
    assert fixed.horizontal_final_m < 0.1 * raw.horizontal_final_m


def test_a_model_is_refused_on_readings_at_another_rate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A model that reads the sensors at fitted time offsets holds them in the fitted rate's terms: on
    readings at half the rate, `sins correct` and `sins evaluate` refuse it in one line naming both rates
    (exit 2), and nothing is written."""
    rng = np.random.default_rng(9)
    s = session(rng, typical_unit(rng), duration_s=60.0)
    header = "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"
    imu, half = tmp_path / "imu.csv", tmp_path / "half.csv"
    rows = np.column_stack([s.t, s.gyro, s.accel])
    np.savetxt(imu, rows, delimiter=",", header=header, comments="")
    np.savetxt(half, rows[::2], delimiter=",", header=header, comments="")
    truth = tmp_path / "truth.csv"
    _write_truth(truth, s)
    model = tmp_path / "m.json"
    assert (
        main(["fit", str(imu), "--truth", str(truth), "--strategy", "regression", "--out", str(model)]) == 0
    )
    capsys.readouterr()
    out = tmp_path / "corrected.csv"
    for argv in (["correct", str(model), str(half), "--out", str(out)],
                 ["evaluate", str(model), str(half), "--truth", str(truth)]):  # fmt: skip
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert "Hz" in err and "fitted on readings at" in err and err.count("\n") == 1, err
        assert "(fit a model on readings at its rate)" in err, err
    assert not out.exists()


@needs_broad
@needs_psins
def test_a_model_is_refused_on_another_unit(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A model fitted on the PSINS drive's MEMS, judged on BROAD's unit B: one line naming both units."""
    model = tmp_path / "m.json"
    assert main(["fit", "--dataset", "psins_vehicle", "--strategy", "bias_only", "--out", str(model)]) == 0
    capsys.readouterr()
    assert main(["evaluate", str(model), "--dataset", "broad_05"]) == 2
    err = capsys.readouterr().err
    assert "fitted on PSINS vehicle MEMS" in err and "BROAD" in err and err.count("\n") == 1, err


@pytest.mark.parametrize("name", ["regression", "regression_rest", "ferraris"])
def test_seed_models_read_the_sensors_at_their_fitted_time_offsets(name: str) -> None:
    """The seed-model strategies invert the model on increments directly (no division by the step); they
    must read each sensor ``time_offset_s_`` later first, as the base class's rate path does: the two
    paths agree to rounding, and differ from the unshifted correction by far more."""
    from sins.compensation.base import Strategy

    rng = np.random.default_rng(11)
    s = session(rng, typical_unit(rng), duration_s=30.0)
    dt = np.diff(s.t)[:, None]
    imu = ImuIncrements(
        t=s.t, dtheta_b=0.5 * (s.gyro[1:] + s.gyro[:-1]) * dt, dv_b=0.5 * (s.accel[1:] + s.accel[:-1]) * dt
    )
    strategy = compensation.make(name)
    strategy.B0_, strategy.B_, strategy.A0_ = (
        rng.normal(0, 1e-3, 3),
        rng.normal(0, 1e-3, (3, 3)),
        rng.normal(0, 1e-2, 3),
    )
    strategy.K_, strategy.A_ = np.zeros((3, 3)), rng.normal(0, 1e-3, (3, 3))
    if name == "regression_rest":
        strategy.rest_rms_, strategy.motion_offset_ = 0.0, np.zeros(3)  # no rest found: the seed model alone
    plain = strategy.correct_increments(imu)
    strategy.time_offset_s_ = np.array([0.004, 0.0025])
    direct = strategy.correct_increments(imu)
    through_rates = Strategy.correct_increments(strategy, imu)
    np.testing.assert_allclose(direct.dtheta_b, through_rates.dtheta_b, rtol=0, atol=1e-15)
    np.testing.assert_allclose(direct.dv_b, through_rates.dv_b, rtol=0, atol=1e-14)
    assert (
        np.abs(direct.dtheta_b - plain.dtheta_b).max()
        > 100 * np.abs(direct.dtheta_b - through_rates.dtheta_b).max()
    )


def _turning(bias_x: float, ref_offset_s: float) -> Any:
    """A unit turning about its own z at 0.3 rad/s for 20 s at 100 Hz (readings exact, plus ``bias_x``
    rad/s about x), its reference at 10 Hz ``ref_offset_s`` past the readings' grid; Earth's rate left
    out (a room's frame of unknown place)."""
    from sins.core.series import ReferencedRecording

    t = np.arange(2001) * 0.01
    rate = np.array([bias_x, 0.0, 0.3])
    imu = ImuIncrements(
        t=t, dtheta_b=np.tile(rate * 0.01, (2000, 1)), dv_b=np.tile([0.0, 0.0, -0.098], (2000, 1))
    )
    t_ref = np.arange(ref_offset_s, 20.0, 0.1)
    q = Rotation.from_rotvec(np.outer(0.3 * t_ref, [0.0, 0.0, 1.0])).as_quat()
    m = len(t_ref)
    reference = NavSeries(t=t_ref, lat=np.full(m, 0.8), lon=np.zeros(m), h=np.zeros(m),
                          v_n=np.zeros((m, 3)), q_nb=q)  # fmt: skip
    return ReferencedRecording(imu=imu, reference=reference, source="numpy turn", heading_known=False,
                               latitude_known=False)  # fmt: skip


def test_the_open_loop_is_judged_at_reference_epochs_off_the_readings_grid() -> None:
    """A reference at 10 Hz 4.5 ms off a 100 Hz MEMS's grid (PSINS's FOG-INS beside its MEMS) had no epoch
    judged ("no judged row has a reference on the readings' times"). Now every epoch is, the readings'
    attitude slerped between the two around it and started from the reference's slerped at the first
    reading: a unit's own readings leave nothing (1e-12 rad: constant-rate turns slerp exactly); a gyro
    bias ``b`` about x, turned round by the turn ``ω`` about z, leaves an angle ``2 b sin(ω τ / 2) / ω``
    after ``τ`` (to first order in ``b``), on grid and off alike."""
    for offset in (0.0, 0.0045):
        own = judging.open_loop(None, _turning(0.0, offset))
        assert len(own.t) == 200 - (offset > 0) and np.max(own.total) < 1e-12, (offset, np.max(own.total))
        biased = judging.open_loop(None, _turning(1e-3, offset))
        start = np.ceil(offset / 0.01 - 1e-9) * 0.01  # the first reading at or after the first epoch
        want = 2e-3 * np.sin(0.3 * (biased.t - start) / 2.0) / 0.3
        np.testing.assert_allclose(biased.total, want, rtol=1e-4, atol=1e-6)  # second order: 2e-7 seen
