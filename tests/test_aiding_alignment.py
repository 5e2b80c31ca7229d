"""Static alignment at 45° N: coarse levelling and gyrocompassing at their physical limits, then the
filter's fine alignment with zero-velocity updates.

References, independent of the code under test: the tilt a bias leaves is the angle between the true
and the biased specific force, ``|b_a⊥| / g`` (geometry, any attitude); the heading a gyrocompass
settles at is the direction of the measured horizontal Earth rate,
``ψ_err = -atan2(ε_E - Ω sin φ · b_aE/g, Ω cos φ + ε_N)`` (``ε`` and ``b_a`` resolved in n), whose
first order is the textbook ``ε_E / (Ω cos φ)``: a tactical unit's 5 °/h makes it tens of degrees.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from conftest import refusal
from scipy import stats

from sins import imu
from sins.aiding import alignment, ekf, gnss, policy
from sins.core import earth, rotation
from sins.core.series import NavSeries
from sins.imu import spec
from sins.nav import trajectory
from sins.nav.motion import Accelerate, Hold, SegmentMotion, Start

D = np.radians
LAT = D(45.0)


def still(seconds: float) -> SegmentMotion:
    return SegmentMotion.from_segments(
        Start(lat=LAT, lon=D(7.6), h=250.0, roll=D(2.0), pitch=D(-3.0), yaw=D(30.0)), [Hold(seconds)]
    )


def _attitude_only(truth: NavSeries, q_nb: np.ndarray) -> NavSeries:
    return NavSeries(t=truth.t[:1], lat=truth.lat[:1], lon=truth.lon[:1], h=truth.h[:1], v_n=truth.v_n[:1],
                     q_nb=q_nb[None])  # fmt: skip


@pytest.mark.parametrize("unit_seed", [0, 1, 2, 3])
def test_coarse_alignment_of_a_tactical_unit_settles_at_its_bias_limits(unit_seed):
    truth, ideal = trajectory.generate(still(60.0), 100.0)
    unit = spec.draw_unit("tactical", unit_seed, run_seed=unit_seed)
    b_g, b_a = unit.get("gyro.bias").value, unit.get("accel.bias").value
    readings = imu.ImuModel((imu.Bias("gyro", b_g), imu.Bias("accel", b_a))).corrupt_increments(ideal)
    q_nb = alignment.coarse_attitude(readings, 60.0)
    C_true, C_est = rotation.dcm_from_quat(truth.q_nb[0]), rotation.dcm_from_quat(q_nb)
    # Tilt: the angle between the estimated and the true down axis is |b_a⊥| / g.
    f_b = C_true.T @ np.array([0.0, 0.0, -earth.normal_gravity(LAT, 250.0)])
    b_perp = b_a - f_b * (f_b @ b_a) / (f_b @ f_b)
    tilt = np.arccos(np.clip((C_est.T @ [0, 0, 1]) @ (C_true.T @ [0, 0, 1]), -1.0, 1.0))
    assert tilt == pytest.approx(np.linalg.norm(b_perp) / np.linalg.norm(f_b), rel=0.02)
    # Heading: the gyrocompass limit.
    eps_n, b_n = C_true @ b_g, C_true @ b_a
    g = np.linalg.norm(f_b)
    expected = -np.arctan2(eps_n[1] - earth.OMEGA_IE * np.sin(LAT) * b_n[1] / g,
                           earth.OMEGA_IE * np.cos(LAT) + eps_n[0])  # fmt: skip
    yaw_error = rotation.wrap_angle(
        rotation.euler_from_quat(q_nb)[2] - rotation.euler_from_quat(truth.q_nb[0])[2]
    )
    assert abs(yaw_error - expected) < D(0.2), (np.degrees(yaw_error), np.degrees(expected))
    assert abs(np.degrees(expected)) > 5.0  # a tactical gyro's bias: degrees, far from 0.1°


@pytest.fixture(scope="module")
def still_five_minutes() -> tuple[NavSeries, object]:
    return trajectory.generate(still(300.0), 100.0)


@pytest.mark.parametrize("run", [1, 2, 3, 4])
def test_fine_alignment_of_a_navigation_grade_unit_in_five_minutes(still_five_minutes, run):
    """Roll and pitch within 0.01°; heading within 3σ of the filter's, whose σ is under 0.1° (the
    physical limit: the grade's 0.01 °/h gyro bias gives 0.05°, its ARW 0.04° over 300 s)."""
    truth, ideal = still_five_minutes
    config = ekf.FilterConfig.for_grade("navigation", gyro_bias_walk=0.0, accel_bias_walk=0.0)
    rng = np.random.default_rng([run, 7])
    b_g = config.gyro_bias_sigma * rng.standard_normal(3)
    b_a = config.accel_bias_sigma * rng.standard_normal(3)
    unit = imu.ImuModel((
        imu.Bias("gyro", b_g), imu.Bias("accel", b_a),
        imu.Noise("gyro", np.full(3, config.arw_rad_rt_s)),
        imu.Noise("accel", np.full(3, config.vrw_mps_rt_s)),
    ))  # fmt: skip
    readings = unit.corrupt_increments(ideal, seed=run)
    none = gnss.GnssFixes.empty()
    result = alignment.aligned_run(readings, none, config, alignment.AlignmentConfig(300.0, 60.0),
                                   position=(truth.lat[0], truth.lon[0], truth.h[0]))  # fmt: skip
    roll, pitch, yaw = (np.degrees(a[-1]) for a in result.nav.euler())
    true_roll, true_pitch, true_yaw = (np.degrees(a[-1]) for a in truth.euler())
    assert abs(roll - true_roll) < 0.01 and abs(pitch - true_pitch) < 0.01
    sigma_heading = np.degrees(result.sigma()[-1, 8])
    assert sigma_heading < 0.1
    assert abs((yaw - true_yaw + 180.0) % 360.0 - 180.0) < 3.0 * sigma_heading
    # The tilt sits at the limit of the biases the filter has not learnt (residual = true - estimated).
    phi = ekf.nav_error_state(result.nav.at(-1), truth.at(-1))[0, 6:9]
    limit = alignment.static_limits(rotation.dcm_from_quat(truth.q_nb[-1]), LAT, b_g - result.gyro_bias[-1],
                                    b_a - result.accel_bias[-1])  # fmt: skip
    assert np.all(np.abs(phi[:2] - limit[:2]) < D(0.001))
    assert len(result.zupt_t) == 3000  # 10 Hz over the 300 s


def test_alignment_refuses_a_short_recording_or_no_position():
    _, ideal = trajectory.generate(still(10.0), 100.0)
    config = ekf.FilterConfig.for_grade("tactical")
    none = gnss.GnssFixes.empty()
    refusal(lambda: alignment.aligned_run(ideal, none, config, alignment.AlignmentConfig(60.0, 30.0)),
            "needs 60.0 s of still readings")  # fmt: skip
    refusal(
        lambda: alignment.aligned_run(ideal, none, config, alignment.AlignmentConfig(5.0, 5.0)),
        "start position",
    )
    refusal(lambda: alignment.AlignmentConfig(60.0, 90.0), "coarse_s")


@dataclass(frozen=True)
class _Table:
    """An ``[alignment]`` table without a scenario: what :mod:`sins.aiding.policy` reads."""

    alignment: str = "auto"
    static_s: float | None = None
    coarse_s: float = 60.0
    heading_sigma_rad: float | None = None
    min_speed_mps: float = 5.0
    sideslip_sigma_rad: float = D(1.0)
    seed: int = 0


def test_the_alignment_policy_aligns_still_only_where_the_gyros_find_north():
    """``auto`` on a drive that stands 40 s before it moves: a navigation-grade gyro (0.01 °/h) finds
    north to well under 2° and aligns still over the whole stop; a tactical one (5 °/h, against the
    Earth rate's 10.6 °/h horizontal part at 45°) cannot, and aligns in motion unless the heading comes
    from elsewhere; a drive that moves from its start aligns in motion; a still window longer than the
    stop is refused, naming the scenario."""
    start = Start(lat=LAT, lon=D(7.6), h=250.0, yaw=D(30.0))
    stop_then_go = SegmentMotion.from_segments(start, [Hold(40.0), Accelerate(10, 12.0, 2.0)])
    truth, _ = trajectory.generate(stop_then_go, 50.0)
    moving, _ = trajectory.generate(SegmentMotion.from_segments(start, [Accelerate(10, 12.0, 2.0)]), 50.0)
    navigation, tactical = ekf.FilterConfig.for_grade("navigation"), ekf.FilterConfig.for_grade("tactical")
    # The stop ends within a sample of 40 s (the smooth ramp reaches 0.07 µm/s at 40.02 s, 1.2 at 40.04).
    assert 40.0 <= policy.initial_stop_s(truth) <= 40.02 + 1e-9
    plan = policy.plan_alignment(_Table(), truth, navigation)
    assert plan.method == "static" and plan.heading is None
    assert plan.static_s == plan.coarse_s == policy.initial_stop_s(truth)
    assert policy.plan_alignment(_Table(), truth, tactical).method == "gnss_velocity"
    told = policy.plan_alignment(_Table(heading_sigma_rad=D(1.0)), truth, tactical)
    assert told.method == "static" and told.heading is not None and told.heading[1] == D(1.0)
    assert policy.plan_alignment(_Table(), moving, navigation).method == "gnss_velocity"
    late = _Table(alignment="static", static_s=50.0)
    refusal(
        lambda: policy.plan_alignment(late, truth, navigation, "drive.toml"), "drive.toml", "vehicle moves"
    )
    # The heading from elsewhere is the truth's off by a draw of the told σ: over 200 seeds the mean
    # square of the normalised errors lies within χ²₂₀₀/200's 99 % band (0.77-1.26).
    z = [
        (policy.static_heading(_Table(heading_sigma_rad=D(1.0), seed=s), truth, 40.0) or (0.0,))[0] - D(30.0)
        for s in range(200)
    ]
    low, high = stats.chi2.ppf([0.005, 0.995], 200) / 200
    assert low < np.mean((np.array(z) / D(1.0)) ** 2) < high
