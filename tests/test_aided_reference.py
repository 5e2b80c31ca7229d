"""sins's GNSS/INS filter against an independent one: the same recorded IMU and fixes, the same start.

Issue 22 asks for pyins's filter as the reference: ``tests/test_aided_pyins.py`` runs it (PyPI's
``python-ins``, in the ``test`` extra). This module holds a second reference that the tests own,
``tests/numpy_ins_filter.py``: a loosely coupled filter written with numpy alone, sharing no code with
sins and different from it wherever a choice is free (ECEF instead of NED, a direction-cosine matrix
instead of a quaternion, covariance steps of 0.1 s instead of 1 s, fixes and their noise in ECEF,
Joseph-form updates), and fast enough to run on several units. Its mechanisation alone, on the ideal
IMU of the drive below, stays within 1.6 mm of the truth over 600 s (sins's own integrator: 1.6 mm).

The stream: the shipped ``car_drive_aided_10min`` drive (10 min at 100 Hz, turns, stops, two 60 s GNSS
outages at 150-210 s and 420-480 s), 1 Hz fixes with its receiver (1.5, 1.5, 3 m; antenna 1 m ahead of
and 1.2 m above the IMU), and two kinds of tactical unit: ``modelled`` (constant biases drawn from the
filter's ``P0`` plus the grade's white noise: what both filters model; three seeds) and the preset's own
unit (the full tactical draw: scale factors, misalignments, g-sensitivity and bias instability, which
neither filter models). Both filters start from the truth's first state with the same ``P0``
(``FilterConfig.for_grade("tactical")``) and the same IMU model.

What "the same size" is held to, per run:

* aided phase (the fixes' span from 60 s on, outages left out): horizontal RMS within 5 % of each other
  (the seed-to-seed spread of this RMS is about 8 %, so "the same size" here is finer than the run's luck);
* each outage's end (the sample before the fix that closes it): the two horizontal error vectors within
  0.05 of the filters' own predicted horizontal σ there. On the same data, two correct filters on the same
  error model (the φ-angle one, here in two frames) differ only by their discretisations, which move the
  covariances by well under 1 % (0.2 % measured); a dropped term, a wrong sign or a lever arm ignored
  moves the error by a σ or more (the last is tried below). (pyins, on the modified φ-angle model, parts
  from sins by 0.08σ at the first outage's end: ``test_aided_pyins.py``.)
* biases (modelled unit): each filter's final estimates within 3σ (its own σ) of the true ones, and the
  two filters' estimates within 0.05σ of each other.

Measured (seeds 1-3, modelled unit; sins / reference): aided RMS 0.917 / 0.917, 0.807 / 0.808 and
0.906 / 0.906 m; outage ends 2.64 / 2.51 and 6.61 / 6.62 m, 26.63 / 26.63 and 5.59 / 5.61 m, 61.86 / 61.92
and 11.13 / 11.14 m, against a predicted σ of 24.2 and 9.4 m (the covariances agree to 0.19 %); the
largest distance between the two end vectors is 0.007σ; every bias estimate within 1.6σ of the truth,
the two filters' within 0.01σ of each other. The preset's unit: 0.813 / 0.813 m, 25.91 / 25.85 m and
7.08 / 7.08 m. A reference told the antenna sits on the IMU fails both the RMS and the outage checks.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy_ins_filter as ref
import pytest

from sins import imu, scenario
from sins.aiding import ekf, gnss
from sins.core.series import ImuIncrements, NavSeries
from sins.nav import strapdown
from sins.runs import pipeline

CONFIG = ekf.FilterConfig.for_grade("tactical")
TUNING = ref.Tuning(
    arw=CONFIG.arw_rad_rt_s, vrw=CONFIG.vrw_mps_rt_s, gyro_bias_sigma=CONFIG.gyro_bias_sigma,
    accel_bias_sigma=CONFIG.accel_bias_sigma, gyro_bias_walk=CONFIG.gyro_bias_walk,
    accel_bias_walk=CONFIG.accel_bias_walk, position_sigma_m=CONFIG.position_sigma_m,
    velocity_sigma_mps=CONFIG.velocity_sigma_mps, tilt_sigma_rad=CONFIG.tilt_sigma_rad,
    heading_sigma_rad=CONFIG.heading_sigma_rad,
)  # fmt: skip
SEEDS = (1, 2, 3)
RMS_TOLERANCE = 0.05  # relative; the seed-to-seed spread of the aided RMS is ~8 %
END_TOLERANCE = 0.05  # of the predicted horizontal σ at the outage's end
BIAS_AGREEMENT = 0.05  # of the filters' σ


@dataclass(frozen=True)
class Drive:
    """The truth, the ideal IMU, the receiver, and the scenario they come from."""

    sc: scenario.Scenario
    truth: NavSeries
    ideal: ImuIncrements
    receiver: gnss.GnssConfig


@dataclass(frozen=True)
class Figures:
    """One filter's errors on one run."""

    aided_rms_m: float
    end_ne_m: np.ndarray  # (outages, 2) the horizontal error at each outage's end
    end_sigma_m: np.ndarray  # (outages,) its predicted horizontal σ, before the fix that ends the outage
    bias: np.ndarray  # (6,) final gyro (rad/s) and accelerometer (m/s²) bias estimates
    bias_sigma: np.ndarray  # (6,) their σ
    rejected: int


def make_drive() -> Drive:
    """The shipped drive, its truth and ideal IMU, and its receiver (white noise only)."""
    sc = scenario.load(pipeline.resolve_scenario("car_drive_aided_10min"))
    assert sc.aiding is not None
    a = sc.aiding
    truth, ideal = pipeline.simulate(sc)
    receiver = gnss.GnssConfig(
        rate_hz=a.rate_hz, sigma_pos_m=np.array(a.sigma_m), lever_arm_b=np.array(a.lever_arm_m),
        outages=tuple(gnss.Outage(s, e) for s, e in a.outages),
    )  # fmt: skip
    assert len(receiver.outages) == 2 and np.any(receiver.lever_arm_b != 0.0)
    return Drive(sc, truth, ideal, receiver)


@pytest.fixture(scope="module")
def drive() -> Drive:
    return make_drive()


def ned_errors(drive: Drive, lat: np.ndarray, lon: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Position errors against the truth in its local NED axes (through ECEF), (n, 3) m."""
    t = drive.truth
    d_e = ref.ecef_from_geodetic(lat, lon, h) - ref.ecef_from_geodetic(t.lat, t.lon, t.h)
    return ref.ned_from_ecef(d_e, t.lat, t.lon)


def aided_samples(drive: Drive) -> np.ndarray:
    """The samples from 60 s on (the drive's first stop over) outside the outages."""
    t = drive.truth.t
    keep = t >= 60.0
    for o in drive.receiver.outages:
        keep &= ~((t > o.start_s) & (t < o.end_s))
    return keep


def outage_ends(drive: Drive) -> list[int]:
    """The sample before the fix that closes each outage."""
    return [int(np.searchsorted(drive.truth.t, o.end_s)) - 1 for o in drive.receiver.outages]


def position_figures(drive: Drive, err: np.ndarray) -> tuple[float, np.ndarray]:
    """Aided-phase horizontal RMS and the outage ends' horizontal errors."""
    horizontal = np.hypot(err[:, 0], err[:, 1])
    return float(np.sqrt(np.mean(horizontal[aided_samples(drive)] ** 2))), err[outage_ends(drive), :2]


def sins_figures(drive: Drive, readings: ImuIncrements, fixes: gnss.GnssFixes) -> Figures:
    """sins's filter from the truth's first state, its initial covariance stated."""
    start = strapdown.InitialState.from_series(drive.truth)
    result = ekf.run(readings, fixes, CONFIG, start, P0=CONFIG.initial_covariance())
    rms, ends = position_figures(drive, ned_errors(drive, result.nav.lat, result.nav.lon, result.nav.h))
    sigma = []
    for o in drive.receiver.outages:
        row = int(np.flatnonzero(np.isclose(result.t_cov, o.end_s) & ~result.after_update)[0])
        sigma.append(np.hypot(*result.sigma()[row, :2]))
    return Figures(
        rms, ends, np.array(sigma), np.concatenate([result.gyro_bias[-1], result.accel_bias[-1]]),
        result.sigma()[-1, 9:15], result.rejected,
    )  # fmt: skip


def truth_start(truth: NavSeries) -> dict[str, np.ndarray]:
    """The truth's first state as the reference takes it (its attitude as a matrix)."""
    return {"lat": truth.lat[0], "lon": truth.lon[0], "h": truth.h[0], "v_ned": truth.v_n[0],
            "C_nb": ref.dcm_from_quaternion(truth.q_nb[0])}  # fmt: skip


def reference_figures(drive: Drive, readings: ImuIncrements, fixes: gnss.GnssFixes, arm_b=None) -> Figures:
    """The numpy reference on the same arrays and start (``arm_b`` replaces the lever arm it is told)."""
    t = drive.truth
    arm = fixes.lever_arm_b if arm_b is None else arm_b
    given = {"t": fixes.t, "lat": fixes.lat, "lon": fixes.lon, "h": fixes.h, "sigma_ned": fixes.sigma_pos_m,
             "arm_b": arm}  # fmt: skip
    result = ref.run(readings.t, readings.dtheta_b, readings.dv_b, given, truth_start(t), TUNING)
    rms, ends = position_figures(drive, ned_errors(drive, *result.geodetic()))
    sigma = []
    for o, k in zip(drive.receiver.outages, outage_ends(drive), strict=True):
        j = int(np.flatnonzero(np.isclose(result.fix_t, o.end_s))[0])  # its P before that fix's update
        C_en = ref.ned_to_ecef(float(t.lat[k]), float(t.lon[k]))
        P_ned = C_en.T @ result.P_before[j][:3, :3] @ C_en
        sigma.append(np.sqrt(P_ned[0, 0] + P_ned[1, 1]))
    return Figures(
        rms, ends, np.array(sigma), np.concatenate([result.gyro_bias[-1], result.accel_bias[-1]]),
        np.sqrt(np.diag(result.P[-1]))[9:15], result.rejected,
    )  # fmt: skip


def modelled_unit(seed: int) -> tuple[imu.ImuModel, np.ndarray]:
    """Constant biases drawn from the filter's P0 and the grade's white noise; the true biases (6,)."""
    rng = np.random.default_rng([seed, 22])
    b_g = rng.standard_normal(3) * CONFIG.gyro_bias_sigma
    b_a = rng.standard_normal(3) * CONFIG.accel_bias_sigma
    unit = imu.ImuModel((
        imu.Bias("gyro", b_g), imu.Bias("accel", b_a),
        imu.Noise("gyro", np.full(3, CONFIG.arw_rad_rt_s)),
        imu.Noise("accel", np.full(3, CONFIG.vrw_mps_rt_s)),
    ))  # fmt: skip
    return unit, np.concatenate([b_g, b_a])


@pytest.fixture(scope="module")
def modelled(drive: Drive) -> list[tuple[np.ndarray, Figures, Figures]]:
    """Per seed: the true biases, sins's figures and the reference's."""
    out = []
    for seed in SEEDS:
        unit, true_bias = modelled_unit(seed)
        readings = unit.corrupt_increments(drive.ideal, seed=seed)
        fixes = gnss.simulate(drive.truth, drive.receiver, seed=seed)
        out.append(
            (true_bias, sins_figures(drive, readings, fixes), reference_figures(drive, readings, fixes))
        )
    return out


@pytest.fixture(scope="module")
def preset_unit(drive: Drive) -> tuple[Figures, Figures]:
    """The preset's own unit and receiver seeds (the stream ``sins run car_drive_aided_10min`` aids)."""
    sc = drive.sc
    assert sc.imu_model is not None and sc.aiding is not None
    unit = scenario.load_imu(sc.imu_model).model(run_seed=sc.imu_seed)
    readings = unit.corrupt_increments(drive.ideal, seed=sc.imu_seed, dt_nominal=1.0 / sc.rate_hz)
    fixes = gnss.simulate(drive.truth, drive.receiver, seed=sc.aiding.seed)
    return sins_figures(drive, readings, fixes), reference_figures(drive, readings, fixes)


def differences(ours: Figures, theirs: Figures) -> tuple[float, float, float]:
    """Relative gap of the aided RMS, of the predicted σ at the outage ends, and the largest distance
    between the outage ends' horizontal errors in units of that σ."""
    rms = abs(ours.aided_rms_m / theirs.aided_rms_m - 1.0)
    sigma = float(np.max(np.abs(ours.end_sigma_m / theirs.end_sigma_m - 1.0)))
    gap = float(np.max(np.linalg.norm(ours.end_ne_m - theirs.end_ne_m, axis=1) / ours.end_sigma_m))
    return rms, sigma, gap


def assert_same_size(ours: Figures, theirs: Figures) -> None:
    assert ours.rejected == 0 and theirs.rejected == 0
    rms, sigma, gap = differences(ours, theirs)
    assert rms < RMS_TOLERANCE, (ours.aided_rms_m, theirs.aided_rms_m)
    # The predicted σ themselves agree (the two covariances), to the discretisations' 1 %.
    assert sigma < 0.01, (ours.end_sigma_m, theirs.end_sigma_m)
    assert gap < END_TOLERANCE, (ours.end_ne_m, theirs.end_ne_m)


def test_modelled_unit_errors_are_the_same_size_in_both_filters(modelled):
    for _, ours, theirs in modelled:
        assert_same_size(ours, theirs)
        # The outages are where the filters are tested: their predicted σ is metres, several times the
        # fixes' 2.1 m horizontal noise, so 0.05σ is not lost in it.
        assert np.all(ours.end_sigma_m > 4.0)


def test_preset_unit_errors_are_the_same_size_in_both_filters(preset_unit):
    # Neither filter models this unit's scale factors, misalignments and g-sensitivity: both are wrong
    # in the same way, and still agree with each other.
    assert_same_size(*preset_unit)


def test_both_filters_estimate_the_true_biases(modelled):
    for true_bias, ours, theirs in modelled:
        for fig in (ours, theirs):
            z = (fig.bias - true_bias) / fig.bias_sigma
            assert np.all(np.abs(z) < 3.0), z
        assert np.all(np.abs(ours.bias - theirs.bias) < BIAS_AGREEMENT * ours.bias_sigma)
        # ... and they were learnt: the horizontal accelerometers' σ falls below a tenth of its start.
        assert np.all(ours.bias_sigma[3:5] < 0.1 * CONFIG.accel_bias_sigma)


def test_the_comparison_sees_a_lever_arm_left_out(drive, modelled):
    # The reference told the antenna sits on the IMU (it is 1.6 m away): the check above must fail.
    unit, _ = modelled_unit(SEEDS[0])
    readings = unit.corrupt_increments(drive.ideal, seed=SEEDS[0])
    fixes = gnss.simulate(drive.truth, drive.receiver, seed=SEEDS[0])
    wrong = reference_figures(drive, readings, fixes, arm_b=np.zeros(3))
    rms, _, gap = differences(modelled[0][1], wrong)
    assert rms > RMS_TOLERANCE and gap > END_TOLERANCE, (rms, gap)


def test_the_reference_is_independent_and_its_mechanisation_follows_the_truth(drive):
    source = Path(ref.__file__).read_text()
    imported = [n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.Import | ast.ImportFrom)]
    modules = {a.name for n in imported if isinstance(n, ast.Import) for a in n.names}
    modules |= {n.module or "" for n in imported if isinstance(n, ast.ImportFrom)}
    assert modules == {"__future__", "math", "dataclasses", "numpy"}, modules
    # Free inertial on the ideal IMU (no fixes): 600 s of this drive stay within 1.6 mm of the truth (sins's
    # integrator: 1.6 mm). A wrong or missing term shows as metres: Coriolis at 14 m/s is 2e-3 m/s²,
    # hundreds of metres in 600 s; J2 gravitation instead of normal gravity, 5e-5 m/s², gave 9 m.
    # 1 cm leaves the integration's second-order error a margin of 6.
    none = {"t": np.zeros(0), "lat": np.zeros(0), "lon": np.zeros(0), "h": np.zeros(0),
            "sigma_ned": np.ones(3), "arm_b": np.zeros(3)}  # fmt: skip
    ideal = drive.ideal
    result = ref.run(ideal.t, ideal.dtheta_b, ideal.dv_b, none, truth_start(drive.truth), TUNING)
    err = ned_errors(drive, *result.geodetic())
    assert np.max(np.linalg.norm(err, axis=1)) < 0.01, np.abs(err).max(axis=0)
