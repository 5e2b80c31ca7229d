"""The filter's statistics over Monte-Carlo runs: NEES, NIS, bias convergence and an outage's growth.

Each run draws its initial errors and its IMU biases from the filter's own ``P0`` and its noise from the
filter's model (a tactical unit's white noise; constant biases), so a consistent filter's normalised
errors are χ²-distributed. Bounds: the two-sided 95 % interval of the mean of ``N`` χ² draws; about
5 % of the times fall outside by chance, and the tests allow 15 % (a binomial 4σ margin over the
~150 times).

The outage's reference is independent of the filter's propagation: position error after ``T`` s of
straight level cruise from the state and covariance at the outage's start, by the short-time
polynomial (Schuler and Earth-rate terms, under 1 % over 60 s, left out)::

    δr_N(T) = δr_N + δv_N T + ½ (g φ_E - (C δb_a)_N) T² + ⅙ g (C δb_g)_E T³
    δr_E(T) = δr_E + δv_E T - ½ (g φ_N + (C δb_a)_E) T² - ⅙ g (C δb_g)_N T³

plus the white noises' ``q_v T³/3`` and ``g² q_a T⁵/20`` per axis.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from sins import imu
from sins.aiding import ekf, gnss
from sins.core import earth, rotation
from sins.core.series import ImuIncrements, NavSeries
from sins.nav import strapdown, trajectory
from sins.nav.motion import Accelerate, Hold, SegmentMotion, Start, Turn

D = np.radians
RUNS = 50
CONFIG = ekf.FilterConfig.for_grade(
    "tactical", gyro_bias_walk=0.0, accel_bias_walk=0.0, position_sigma_m=3.0, velocity_sigma_mps=0.1,
    tilt_sigma_rad=D(0.05), heading_sigma_rad=D(0.5),
)  # fmt: skip
RECEIVER = gnss.GnssConfig(lever_arm_b=np.array([1.0, 0.3, -1.2]))


def driving(cruise_s: float) -> SegmentMotion:
    """Accelerations and turns both ways (biases and heading become observable), then a straight cruise."""
    return SegmentMotion.from_segments(
        Start(lat=D(45.0), lon=D(7.6), h=250.0, yaw=D(30.0)),
        [Accelerate(10, 10.0, 2.0), Turn(20, D(4.5), 2.0), Hold(20), Turn(20, D(-4.5), 2.0),
         Accelerate(10, -5.0, 2.0), Turn(20, D(4.5), 2.0), Hold(cruise_s)],
    )  # fmt: skip


def one_run(truth: NavSeries, ideal: ImuIncrements, run: int, receiver: gnss.GnssConfig) -> tuple:
    """A run from errors drawn from ``P0``: the result and the true biases."""
    P0 = CONFIG.initial_covariance()
    e0 = np.random.default_rng([run, 5]).standard_normal(15) * np.sqrt(np.diag(P0))
    gyro_bias, accel_bias = -e0[9:12], -e0[12:15]  # the filter starts at zero bias: δb = -b
    unit = imu.ImuModel((
        imu.Bias("gyro", gyro_bias), imu.Bias("accel", accel_bias),
        imu.Noise("gyro", np.full(3, CONFIG.arw_rad_rt_s)),
        imu.Noise("accel", np.full(3, CONFIG.vrw_mps_rt_s)),
    ))  # fmt: skip
    readings = unit.corrupt_increments(ideal, seed=run)
    fixes = gnss.simulate(truth, receiver, seed=run)
    # The filter alone: it starts from the truth moved by an error drawn from its P0, not from an
    # alignment (whose errors are not P0's draws), so that NEES tests the filter's covariance only.
    start = strapdown.InitialState.from_series(truth)
    r_m, r_n = earth.radii(start.lat)
    start = strapdown.InitialState(
        lat=start.lat + e0[0] / (r_m + start.h),
        lon=start.lon + e0[1] / ((r_n + start.h) * np.cos(start.lat)),
        h=start.h - e0[2], v_n=start.v_n + e0[3:6],
        q_nb=rotation.quat_multiply(rotation.quat_from_rotvec(-e0[6:9]), start.q_nb),
    )  # fmt: skip
    return ekf.run(readings, fixes, CONFIG, start, P0=P0), gyro_bias, accel_bias


def state_errors(result: ekf.AidedResult, truth: NavSeries, gyro_bias, accel_bias, rows) -> np.ndarray:
    """The 15 errors (estimate minus truth) at the covariance records ``rows``."""
    nav = ekf.nav_error_state(result.nav, truth)[np.searchsorted(truth.t, result.t_cov[rows])]
    return np.hstack([nav, result.gyro_bias[rows] - gyro_bias, result.accel_bias[rows] - accel_bias])


@pytest.fixture(scope="module")
def monte_carlo() -> dict[str, np.ndarray]:
    truth, ideal = trajectory.generate(driving(50.0), 100.0)
    nees, nis, final, sigma, rejected = [], [], [], [], 0
    for run in range(RUNS):
        result, b_g, b_a = one_run(truth, ideal, run, RECEIVER)
        rows = np.flatnonzero(result.after_update)
        e = state_errors(result, truth, b_g, b_a, rows)
        nees.append(np.einsum("ki,kij,kj->k", e, np.linalg.inv(result.P[rows]), e))
        nis.append(result.nis)
        final.append(e[-1])
        sigma.append(result.sigma()[-1])
        rejected += result.rejected
    # The 99.99 % gate refuses 1 in 10⁴ good fixes: under 1 expected of ~7500, Poisson.
    assert rejected <= 4
    return {"nees": np.array(nees), "nis": np.array(nis), "final": np.array(final), "sigma": np.array(sigma)}


def _inside(mean: np.ndarray, dof: int) -> float:
    low, high = chi2.ppf([0.025, 0.975], RUNS * dof) / RUNS
    return float(np.mean((mean > low) & (mean < high)))


def test_nees_and_nis_stay_within_their_chi2_bounds(monte_carlo):
    nees, nis = monte_carlo["nees"], monte_carlo["nis"]
    assert nees.shape[1] > 140 and nis.shape[1] > 140
    assert _inside(nees.mean(axis=0), 15) >= 0.85
    assert _inside(nis.mean(axis=0), 3) >= 0.85
    # Over the whole run: the mean NEES of N runs has a spread sqrt(2·15/N) (runs are independent).
    assert abs(nees.mean() - 15.0) < 3.0 * np.sqrt(30.0 / RUNS)
    assert abs(nis.mean() - 3.0) < 3.0 * np.sqrt(6.0 / RUNS)


def test_biases_converge_to_the_true_ones_within_3_sigma(monte_carlo):
    final, sigma = monte_carlo["final"], monte_carlo["sigma"]
    z = final[:, 9:15] / sigma[:, 9:15]
    assert np.mean(np.abs(z) < 3.0) >= 0.97  # 99.7 % expected of 300 values
    # ... and they are learnt: over the 150 s drive the horizontal gyro biases' σ falls to about 0.15 of
    # its start, the accelerometers' to 0.2 (horizontal) and 0.03 (vertical). The vertical gyro's
    # stays: its heading drift of 5e-4 °/s shows only slowly through the turns.
    shrink = sigma[0] / np.sqrt(np.diag(CONFIG.initial_covariance()))
    assert np.all(shrink[[9, 10, 12, 13, 14]] < 0.25) and shrink[11] > 0.9, shrink[9:]


@pytest.fixture(scope="module")
def outage() -> dict[str, np.ndarray]:
    """60 s outages from 200 s in straight cruise: errors at the end and the predictions."""
    start_s, length_s = 200.0, 60.0
    truth, ideal = trajectory.generate(driving(170.0), 100.0)
    receiver = gnss.GnssConfig(
        lever_arm_b=RECEIVER.lever_arm_b, outages=(gnss.Outage(start_s, start_s + length_s),)
    )
    g = earth.normal_gravity(truth.lat[0], truth.h[0])
    error, analytic, filtered = [], [], []
    for run in range(RUNS):
        result, _, _ = one_run(truth, ideal, 1000 + run, receiver)
        at_start = int(np.flatnonzero(result.t_cov <= start_s)[-1])
        at_end = int(np.flatnonzero(result.t_cov <= start_s + length_s - 1e-9)[-1] + 1)  # before the next fix
        assert abs(result.t_cov[at_end] - (start_s + length_s)) < 1e-6 and not result.after_update[at_end]
        k = int(np.searchsorted(truth.t, start_s + length_s)) - 1  # the sample before the fix corrects it
        error.append(ekf.nav_error_state(result.nav.at(k), truth.at(k))[0, :2])
        C = rotation.dcm_from_quat(truth.q_nb[int(np.searchsorted(truth.t, start_s))])
        T = length_s
        M = np.zeros((2, 15))
        M[0, [0, 3]] = 1.0, T
        M[1, [1, 4]] = 1.0, T
        M[0, 7], M[1, 6] = 0.5 * g * T**2, -0.5 * g * T**2
        M[0, 12:15], M[1, 12:15] = -0.5 * T**2 * C[0], -0.5 * T**2 * C[1]
        M[0, 9:12], M[1, 9:12] = g * T**3 / 6.0 * C[1], -g * T**3 / 6.0 * C[0]
        noise = CONFIG.vrw_mps_rt_s**2 * T**3 / 3.0 + g**2 * CONFIG.arw_rad_rt_s**2 * T**5 / 20.0
        analytic.append(np.diag(M @ result.P[at_start] @ M.T) + noise)
        filtered.append(np.diag(result.P[at_end])[:2])
    return {"error": np.array(error), "analytic": np.array(analytic), "filtered": np.array(filtered)}


def test_outage_error_grows_as_the_covariance_at_its_start_predicts(outage):
    error, analytic, filtered = outage["error"], outage["analytic"], outage["filtered"]
    # The filter's own propagation and the independent polynomial agree on the variance at the end.
    assert np.allclose(filtered, analytic, rtol=0.05), np.c_[filtered[:3], analytic[:3]]
    # Realised errors: the mean of (error / predicted σ)² over runs is 1 within its spread over runs.
    ratio = (error**2 / analytic).sum(axis=1) / 2.0
    spread = ratio.std(ddof=1) / np.sqrt(RUNS)
    assert abs(ratio.mean() - 1.0) < 2.0 * spread, (ratio.mean(), spread)
    # The horizontal error is metres, not centimetres or kilometres: the test has teeth.
    assert 1.0 < np.sqrt(np.mean(np.sum(error**2, axis=1))) < 100.0


def test_velocity_fixes_keep_the_filter_consistent():
    """Position and velocity fixes at 2 Hz (the velocity's lever-arm term included): 30 runs, NEES
    within its χ² band at most times and on average (spread sqrt(2·15/30))."""
    truth, ideal = trajectory.generate(driving(50.0), 100.0)
    receiver = gnss.GnssConfig(lever_arm_b=RECEIVER.lever_arm_b, sigma_vel_mps=0.05, rate_hz=2.0)
    runs, nees, rejected = 30, [], 0
    for run in range(runs):
        result, b_g, b_a = one_run(truth, ideal, 2000 + run, receiver)
        rows = np.flatnonzero(result.after_update)
        e = state_errors(result, truth, b_g, b_a, rows)
        nees.append(np.einsum("ki,kij,kj->k", e, np.linalg.inv(result.P[rows]), e))
        rejected += result.rejected
    assert rejected <= 4  # of ~9000 fixes at the 99.99 % gate
    mean = np.array(nees).mean(axis=0)
    low, high = chi2.ppf([0.025, 0.975], runs * 15) / runs
    assert np.mean((mean > low) & (mean < high)) >= 0.85
    assert abs(mean.mean() - 15.0) < 3.0 * np.sqrt(30.0 / runs)
