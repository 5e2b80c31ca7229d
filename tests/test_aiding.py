"""The GNSS simulator, the filter's error model and its plumbing, against independent references.

References: the antenna position through ECEF (``earth.local_ned``, not the simulator's own offset);
the sample statistics of the noise and of a Gauss–Markov process; the filter's linear error model
against two runs of the nonlinear strapdown integrator that differ by a small initial error.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from conftest import refusal

from sins.aiding import ekf, gnss
from sins.core import earth, rotation
from sins.core.series import ImuIncrements, NavSeries
from sins.nav import strapdown, trajectory
from sins.nav.motion import Accelerate, Hold, SegmentMotion, Start, Turn

D = np.radians


def drive(seconds_after: float = 20.0) -> SegmentMotion:
    """A short drive: accelerate, turn both ways, slow down, then cruise."""
    return SegmentMotion.from_segments(
        Start(lat=D(45.0), lon=D(7.6), h=250.0, yaw=D(30.0)),
        [Accelerate(10, 12.0, 2.0), Turn(15, D(5.0), 2.0), Hold(5), Turn(15, D(-6.0), 2.0),
         Accelerate(8, -4.0, 2.0), Hold(seconds_after)],
    )  # fmt: skip


def _relative(fixes: gnss.GnssFixes, at: NavSeries) -> np.ndarray:
    """Each fix relative to the state at its row, in that state's NED axes (exact, through ECEF)."""
    return np.array([earth.local_ned(fixes.lat[k], fixes.lon[k], fixes.h[k], at.lat[k], at.lon[k], at.h[k])
                     for k in range(len(fixes))])  # fmt: skip


@pytest.fixture(scope="module")
def driven() -> tuple[NavSeries, ImuIncrements]:
    return trajectory.generate(drive(), 100.0)


def test_fixes_place_the_antenna_at_its_lever_arm(driven):
    truth, _ = driven
    arm = np.array([1.2, -0.4, -1.5])
    config = gnss.GnssConfig(rate_hz=5.0, sigma_pos_m=np.zeros(3), lever_arm_b=arm, sigma_vel_mps=1e-9)
    fixes = gnss.simulate(truth, config, seed=1)
    assert np.allclose(np.diff(fixes.t), 0.2) and fixes.t[0] == truth.t[0]
    at = truth.interpolate(fixes.t)
    # ECEF reference: the fix relative to the IMU in the IMU's local NED axes is C_nb l_b.
    rel = _relative(fixes, at)
    assert np.max(np.abs(rel - rotation.dcm_from_quat(at.q_nb) @ arm)) < 1e-3
    # Velocity: the finite difference of the fixes' positions (central, 0.2 s apart) in NED.
    ned = earth.local_ned(fixes.lat, fixes.lon, fixes.h, fixes.lat[0], fixes.lon[0], fixes.h[0])
    slope = (ned[2:] - ned[:-2]) / 0.4
    assert np.max(np.abs(slope - fixes.v_n[1:-1])) < 0.02  # the drive's jerk over ±0.2 s


def test_fix_noise_and_gauss_markov_have_their_stated_statistics(driven):
    truth, _ = driven
    sigma = np.array([1.0, 2.0, 3.0])
    fixes = gnss.simulate(truth, gnss.GnssConfig(rate_hz=10.0, sigma_pos_m=sigma), seed=2)
    at = truth.interpolate(fixes.t)
    err = _relative(fixes, at)
    n = len(err)
    # The sample standard deviation of n Gaussian draws has a relative spread 1/sqrt(2n): 4 of those.
    assert np.all(np.abs(err.std(axis=0) / sigma - 1.0) < 4.0 / np.sqrt(2 * n)), err.std(axis=0)
    assert np.all(np.abs(err.mean(axis=0)) < 4.0 * sigma / np.sqrt(n))
    # A long Gauss–Markov path: stationary σ and the lag-τ correlation e^-1.
    t = np.arange(200_000) * 0.5
    x = gnss.gauss_markov(t, np.array([2.0, 2.0, 2.0]), 10.0, np.random.default_rng(3))
    assert np.allclose(x.std(axis=0), 2.0, rtol=0.05)
    lag = 20  # 10 s
    corr = np.mean(x[:-lag] * x[lag:], axis=0) / x.var(axis=0)
    assert np.allclose(corr, np.exp(-1.0), atol=0.03)


def test_outages_and_latency(driven):
    truth, _ = driven
    config = gnss.GnssConfig(sigma_pos_m=np.zeros(3), latency_s=0.3,
                             outages=(gnss.Outage(10.0, 20.0), gnss.Outage(40.0, 45.5)))  # fmt: skip
    fixes = gnss.simulate(truth, config, seed=4)
    assert not np.any((fixes.t > 10.0) & (fixes.t < 20.0)) and not np.any((fixes.t > 40.0) & (fixes.t < 45.5))
    assert 10.0 in fixes.t and 20.0 in fixes.t and 45.0 not in fixes.t and 46.0 in fixes.t
    late = truth.interpolate(fixes.t - 0.3)
    rel = _relative(fixes, late)
    assert np.max(np.abs(rel)) < 1e-6 and fixes.t[0] >= 0.3


def _fixes(**change) -> gnss.GnssFixes:
    base = gnss.GnssFixes(
        t=np.array([1.0, 2.0, 3.0]), lat=np.full(3, 0.7), lon=np.full(3, 0.1), h=np.full(3, 100.0),
        v_n=np.full((3, 3), np.nan), sigma_pos_m=np.ones(3),
    )  # fmt: skip
    return dataclasses.replace(base, **change)


def test_bad_gnss_input_is_refused_in_one_line():
    imu_t = np.linspace(0.0, 10.0, 1001)
    refusal(lambda: gnss.check_fixes(_fixes(lat=np.array([0.7, np.nan, 0.7])), imu_t, "fixes.csv"),
            "fixes.csv", "row 2", "column lat")  # fmt: skip
    refusal(
        lambda: gnss.check_fixes(_fixes(t=np.array([1.0, 2.0, 2.0])), imu_t), "row 3", "column t", "2.0 s"
    )
    refusal(
        lambda: gnss.check_fixes(_fixes(t=np.array([1.0, 3.0, 2.0])), imu_t), "row 3", "does not come after"
    )
    refusal(
        lambda: gnss.check_fixes(_fixes(t=np.array([1.0, 2.0, 12.0])), imu_t), "row 3", "outside", "0.0..10.0"
    )
    refusal(lambda: gnss.Outage(30.0, 20.0), "outage", "ends at 20.0 s, not after its start 30.0 s")
    refusal(lambda: gnss.Outage(float("nan"), 2.0), "outage", "finite")
    # A window built around the check (a subclass, a copy) is still caught by position in a list.
    late = object.__new__(gnss.Outage)
    object.__setattr__(late, "start_s", 5.0)
    object.__setattr__(late, "end_s", 5.0)
    refusal(lambda: gnss.check_outages([gnss.Outage(1.0, 2.0), late]), "outage 2", "ends at 5.0 s")
    refusal(lambda: gnss.GnssConfig(rate_hz=0.0), "rate_hz")
    refusal(lambda: gnss.GnssConfig(sigma_pos_m=np.array([1.0, -1.0, 1.0])), "sigma_pos_m")
    refusal(lambda: ekf.FilterConfig.for_grade("tactical", propagation_dt_s=0.0), "propagation_dt_s")
    # The filter gates its fixes through the same check.
    imu = ImuIncrements(t=imu_t, dtheta_b=np.zeros((1000, 3)), dv_b=np.zeros((1000, 3)))
    start = strapdown.InitialState(0.7, 0.1, 100.0, np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]))
    config = ekf.FilterConfig.for_grade("tactical")
    refusal(
        lambda: ekf.run(imu, _fixes(h=np.array([1.0, np.inf, 1.0])), config, start),
        "gnss",
        "row 2",
        "column h",
    )


def _perturbed(initial: strapdown.InitialState, dx: np.ndarray) -> strapdown.InitialState:
    """``initial`` moved by the error state ``dx[:9]`` (estimate = truth + error)."""
    r_m, r_n = earth.radii(initial.lat)
    return strapdown.InitialState(
        lat=initial.lat + dx[0] / (r_m + initial.h),
        lon=initial.lon + dx[1] / ((r_n + initial.h) * np.cos(initial.lat)),
        h=initial.h - dx[2],
        v_n=initial.v_n + dx[3:6],
        q_nb=rotation.quat_multiply(rotation.quat_from_rotvec(-dx[6:9]), initial.q_nb),
    )


def test_error_model_matches_the_nonlinear_integrator(driven):
    """Φ from :func:`ekf.error_dynamics` (1 s steps along the truth) carries a small initial error and
    bias error to within 3 % of what two strapdown runs, one from the truth and one from the perturbed
    state on bias-corrupted readings, disagree by after 60 s."""
    truth, imu = driven
    dx0 = np.array([3.0, -2.0, 1.0, 0.1, -0.2, 0.05, 2e-4, -3e-4, 1e-3, 2e-6, -3e-6, 1e-6, 5e-3, -4e-3, 6e-3])
    dt = np.diff(imu.t)[:, None]
    # δb = estimated minus true bias; the reading carries the true bias, the integrator assumes none.
    biased = ImuIncrements(imu.t, imu.dtheta_b - dx0[9:12] * dt, imu.dv_b - dx0[12:15] * dt)
    start = strapdown.InitialState.from_series(truth)
    k_end = 6000
    ref = strapdown.integrate(
        ImuIncrements(imu.t[: k_end + 1], imu.dtheta_b[:k_end], imu.dv_b[:k_end]), start
    )
    sol = strapdown.integrate(
        ImuIncrements(biased.t[: k_end + 1], biased.dtheta_b[:k_end], biased.dv_b[:k_end]),
        _perturbed(start, dx0),
    )
    actual = ekf.nav_error_state(sol.at(-1), ref.at(-1))[0]
    phi_total = np.eye(15)
    C_all = rotation.dcm_from_quat(ref.q_nb[1:])
    f_all = np.einsum("kij,kj->ki", C_all, imu.dv_b[:k_end] / dt[:k_end])
    for k in range(0, k_end, 100):
        rows = slice(k, k + 100)
        F = ekf.error_dynamics(float(ref.lat[rows].mean()), float(ref.h[rows].mean()),
                               ref.v_n[rows].mean(axis=0),
                               f_all[rows].mean(axis=0), C_all[rows].mean(axis=0))  # fmt: skip
        phi, _ = ekf.discretize(F, np.zeros((15, 15)), 1.0)
        phi_total = phi @ phi_total
    predicted = (phi_total @ dx0)[:9]
    scale = np.array([np.linalg.norm(actual[s]) for s in (slice(0, 3), slice(3, 6), slice(6, 9))]).repeat(3)
    assert np.all(np.abs(predicted - actual) < 0.03 * scale), np.c_[predicted, actual]


def test_moving_a_state_to_itself_leaves_the_integration_unchanged(driven):
    truth, imu = driven
    whole = strapdown.integrate(imu, strapdown.InitialState.from_series(truth))
    state = strapdown.start(strapdown.InitialState.from_series(truth))
    pieces = []
    for k in range(0, len(imu), 777):
        j = min(len(imu), k + 777)
        out, state = strapdown.advance(
            state, ImuIncrements(imu.t[k : j + 1], imu.dtheta_b[k:j], imu.dv_b[k:j])
        )
        state = strapdown.moved(state, strapdown.current(state))
        pieces.append(out)
    lat = np.concatenate([p.lat for p in pieces])
    q = np.concatenate([p.q_nb for p in pieces])
    assert np.max(np.abs(lat - whole.lat[1:])) < 1e-14 and np.max(np.abs(q - whole.q_nb[1:])) < 1e-12


def test_a_wild_fix_is_gated_and_counted(driven):
    truth, imu = driven
    config = ekf.FilterConfig.for_grade("tactical", position_sigma_m=1.0, velocity_sigma_mps=0.1,
                                        tilt_sigma_rad=D(0.05), heading_sigma_rad=D(0.2))  # fmt: skip
    fixes = gnss.simulate(truth, gnss.GnssConfig(sigma_pos_m=np.full(3, 1.0)), seed=5)
    lat = fixes.lat.copy()
    lat[30] += 100.0 / earth.A  # 100 m north
    result = ekf.run(
        imu, dataclasses.replace(fixes, lat=lat), config, strapdown.InitialState.from_series(truth)
    )
    assert result.rejected == 1 and not result.accepted[30] and result.nis[30] > 1000
    assert np.all(result.accepted[np.arange(len(fixes)) != 30])
    assert np.max(np.abs(ekf.nav_error_state(result.nav, truth)[:, :2])) < 3.0
    assert np.all(result.nav.q_nb[:, 3] >= 0.0)  # corrected rows keep the integrator's sign convention


def test_a_diverged_filter_starts_again_from_the_fixes_instead_of_refusing_them_all():
    """A gyro bias of 5000 °/h and an accelerometer bias of 5 mg (the filter, tuned to a tactical unit,
    expects a few °/h and 1 mg) carried through a 40 s outage: every fix after it disagrees beyond the
    gate (1000 °/h the filter still follows). Without restarts the filter refuses them all and ends
    hundreds of metres off; with them four are refused, it starts again from the fifth, accepts the
    rest and ends within a few metres. A clean run never restarts."""
    truth, ideal = trajectory.generate(drive(seconds_after=60.0), 100.0)
    dt = np.diff(ideal.t)[:, None]
    biased = dataclasses.replace(
        ideal,
        dtheta_b=ideal.dtheta_b + np.array([0.0, 0.0, D(5000.0) / 3600.0]) * dt,
        dv_b=ideal.dv_b + np.array([5e-3 * earth.G0, 0.0, 0.0]) * dt,
    )
    receiver = gnss.GnssConfig(sigma_pos_m=np.full(3, 1.0), outages=(gnss.Outage(20.0, 60.0),))
    fixes = gnss.simulate(truth, receiver, seed=4)
    start = strapdown.InitialState.from_series(truth)
    config = ekf.FilterConfig.for_grade("tactical", position_sigma_m=1.0, velocity_sigma_mps=0.1,
                                        tilt_sigma_rad=D(0.05), heading_sigma_rad=D(0.2))  # fmt: skip
    never = ekf.run(biased, fixes, dataclasses.replace(config, reinit_after=None), start)
    again = ekf.run(biased, fixes, config, start)
    after = fixes.t > 60.0
    assert never.rejected >= int(after.sum()) - 1 and len(never.reinit_t) == 0
    horizontal = lambda r: float(np.hypot(*ekf.nav_error_state(r.nav, truth)[-1, :2]))  # noqa: E731
    assert horizontal(never) > 100.0
    assert len(again.reinit_t) >= 1 and again.reinit_t[0] > 60.0
    assert again.rejected <= 5 * len(again.reinit_t)
    assert horizontal(again) < 5.0
    clean = ekf.run(ideal, fixes, config, start)
    assert len(clean.reinit_t) == 0 and clean.rejected == 0


def test_outage_windows_hold_the_samples_between_their_fixes():
    """Samples at 100 Hz with the rounding a long sum or a file leaves (±5e-12 s): a window holds the
    samples strictly between the fixes on its edges (the sample at an edge takes that fix), found here
    by integer arithmetic on the sample index; one that outlasts the run holds every sample to its end;
    one that starts after the last sample, or holds none, gives no row."""
    from sins.aiding.outages import outage_errors, window_rows

    k = np.arange(301)
    t = k / 100.0 + np.random.default_rng(11).uniform(-5e-12, 5e-12, k.size)  # 0 .. 3 s
    horizontal = np.sqrt(k + 1.0)  # any error that grows: the last sample is the largest
    assert np.array_equal(window_rows(t, 1.0, 1.5), np.arange(101, 150))
    assert np.array_equal(window_rows(t, 2.0, 10.0), np.arange(201, 301))
    assert window_rows(t, 1.0, 1.01).size == 0  # two fixes one sample apart: nothing between them
    windows = outage_errors([(1.0, 1.5), (2.0, 10.0), (1.0, 1.01), (3.0, 4.0)], t, horizontal)
    assert [(w.start_s, w.end_s) for w in windows] == [(1.0, 1.5), (2.0, 10.0)]
    assert windows[0].final_m == windows[0].max_m == np.sqrt(150.0)  # sample 149, before the fix at 1.5 s
    assert windows[1].final_m == np.sqrt(301.0)  # the run's last sample, 3 s
