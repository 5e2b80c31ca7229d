"""The strapdown integrator against physics oracles and against itself at other step sizes.

The analytic references (Schuler oscillation, bias error growth, vertical
instability) come from DESIGN.md §5; the Schuler figures at 45° N come from an
independent continuous-time solution.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sins.core import earth
from sins.core.series import ImuRates
from sins.nav import strapdown, trajectory
from sins.nav.metrics import DriftAccumulator, nav_errors, summarize
from sins.nav.motion import Accelerate, Climb, Hold, Rotate, SegmentMotion, Start, Turn

D = np.radians
MG = 1e-3 * earth.G0
DEG_PER_H = D(1.0) / 3600.0


def manoeuvring_hour() -> SegmentMotion:
    """One hour of turns (up to ±8 °/s, some coordinated), accelerations, climbs and attitude changes."""
    rng = np.random.default_rng(1)
    segs: list = [Hold(60), Accelerate(20, 25, 2), Turn(30, D(6), 2)]
    while sum(s.duration for s in segs) < 3400:
        k = rng.integers(5)
        if k == 0:
            segs.append(
                Turn(float(rng.uniform(10, 40)), D(float(rng.uniform(-8, 8))), 2.0, bool(rng.integers(2)))
            )
        elif k == 1:
            segs.append(Accelerate(15, float(rng.uniform(-5, 5)), 2.0))
        elif k == 2:
            segs.append(Climb(float(rng.uniform(20, 60)), D(float(rng.uniform(-5, 5))), 3.0))
        elif k == 3:
            d = [D(float(x)) for x in rng.uniform(-10, 10, 3)]
            segs.append(Rotate(6, d[0], d[1] / 2, d[2], 1.5))
        else:
            segs.append(Hold(float(rng.uniform(10, 60))))
    segs.append(Hold(3600 - sum(s.duration for s in segs)))
    return SegmentMotion.from_segments(Start(D(45), D(7), 300.0, 0.0, 0.0, 0.0, D(30)), segs)


def stationary(lat_deg: float, seconds: float = 3600.0, roll=0.0, pitch=0.0, yaw=0.0) -> SegmentMotion:
    return SegmentMotion.from_segments(
        Start(D(lat_deg), D(10), 100.0, 0.0, roll, pitch, yaw), [Hold(seconds)]
    )


def run(truth, imu, **kw):
    sol = strapdown.integrate(imu, strapdown.InitialState.from_series(truth), **kw)
    return nav_errors(sol, truth)


@pytest.mark.parametrize("lat_deg, attitude", [(45.0, (0.02, -0.01, 0.7)), (-70.0, (0.3, 0.2, -2.5))])
def test_stationary_hour_stays_within_a_millimetre(lat_deg, attitude):
    truth, imu = trajectory.generate(stationary(lat_deg, 3600.0, *attitude), 100.0)
    e = run(truth, imu)
    assert e.horizontal_m.max() < 1e-3  # the bound: 1 mm after 1 h at 100 Hz
    assert np.degrees(np.abs(e.att_rpy_rad).max()) * 3600 < 1e-3  # and attitude within a milli-arcsecond


@pytest.fixture(scope="module")
def manoeuvre():
    return manoeuvring_hour()


def test_manoeuvring_hour_integrates_back_within_10_cm(manoeuvre):
    truth, imu = trajectory.generate(manoeuvre, 100.0)
    rates = np.degrees(np.abs(imu.dtheta_b).max(axis=0)) * 100.0
    assert rates.max() > 5.0  # the trajectory really turns at several °/s
    assert np.abs(np.diff(truth.h)).sum() > 100.0  # and climbs
    s = summarize(run(truth, imu))
    assert s.max_horizontal_m <= 0.1  # the bound (measured: 0.031 m)
    assert max(abs(s.final_roll_deg), abs(s.final_pitch_deg), abs(s.final_yaw_deg)) < 1e-6


def _streamed_rms(motion, rate, vertical):
    """The horizontal RMS error of :func:`run` over the whole motion, generated and integrated chunk by
    chunk as ``sins run`` streams: the same figure to rounding (1e-15 apart, measured at every rate
    here), at a chunk's memory where the 400 Hz hour whole held 1.4 million samples (the file's peak
    RSS 1.2 GB, now 0.7 GB) and in about half the time."""
    first = trajectory.start_state(motion)
    state = strapdown.start(strapdown.InitialState.from_series(first))
    errors = DriftAccumulator(keep_every=0)
    errors.add(nav_errors(first, first))
    h_prev = float(first.h[0])
    for truth, imu in trajectory.generate_chunks(motion, rate):
        solution, state = strapdown.advance(
            state, imu, vertical=vertical, h_ref=np.concatenate([[h_prev], truth.h])
        )
        errors.add(nav_errors(solution, truth))
        h_prev = float(truth.h[-1])
    return errors.summary().rms_horizontal_m


def _sweep(motion, vertical):
    errs = np.array([_streamed_rms(motion, rate, vertical) for rate in (50.0, 100.0, 200.0, 400.0)])
    slope = np.polyfit(np.log([1 / 50, 1 / 100, 1 / 200, 1 / 400]), np.log(errs), 1)[0]
    return errs, slope


def test_step_sweep_converges_at_second_order(manoeuvre):
    # With the vertical channel held to the truth the horizontal mechanisation is
    # isolated: its error must fall at least as fast as dt² (measured slope 2.10).
    errs, slope = _sweep(manoeuvre, "hold")
    assert slope >= 2.0
    assert (errs[:-1] / errs[1:] >= 3.5).all()  # every halving of dt gains close to 4x


def test_step_sweep_free_vertical_channel(manoeuvre):
    # Free inertial: the unstable vertical channel's own O(dt²) error feeds the
    # horizontal one through the radii and Coriolis; the measured slope is 1.97
    # (ratios 3.96, 3.94, 3.85), so the combined order stays second to within 5 %.
    errs, slope = _sweep(manoeuvre, "free")
    assert slope >= 1.9
    assert (errs[:-1] / errs[1:] >= 3.5).all()


def _biased(imu, gyro=None, accel=None):
    dt = np.diff(imu.t)[:, None]
    dth, dv = imu.dtheta_b.copy(), imu.dv_b.copy()
    if gyro is not None:
        dth += np.asarray(gyro) * dt
    if accel is not None:
        dv += np.asarray(accel) * dt
    return dataclasses.replace(imu, dtheta_b=dth, dv_b=dv)


def test_schuler_oracle_north_accelerometer_bias_at_45N():
    truth, imu = trajectory.generate(stationary(45.0), 100.0)
    e = run(truth, _biased(imu, accel=[MG, 0, 0]))
    north = e.pos_ned_m[:, 0]
    i = int(np.argmax(north))
    # The independent continuous-time solution: 12,681 m at 2,529 s; 7,909 m north and 20 m east at 3,600 s.
    assert north[i] == pytest.approx(12681.0, abs=5.0)
    assert e.t[i] == pytest.approx(2529.0, abs=10.0)
    assert north[-1] == pytest.approx(7909.0, abs=5.0)
    assert e.pos_ned_m[-1, 1] == pytest.approx(20.0, abs=5.0)


@pytest.fixture(scope="module")
def equator():
    truth, imu = trajectory.generate(stationary(0.0), 100.0)
    r_m, r_n = earth.radii(0.0)
    return truth, imu, earth.normal_gravity(0.0, 0.0), r_m, r_n


@pytest.mark.parametrize("axis", [0, 1])
def test_accelerometer_bias_follows_schuler_cosine(equator, axis):
    truth, imu, g, r_m, r_n = equator
    radius = (r_m, r_n)[axis]
    w_s = np.sqrt(g / radius)
    accel = np.zeros(3)
    accel[axis] = MG
    e = run(truth, _biased(imu, accel=accel), vertical="hold", h_ref=truth.h)
    ref = MG / w_s**2 * (1 - np.cos(w_s * e.t))
    # At the equator no Foucault term couples the axes; the remaining Earth-rate
    # coupling is second order (measured 5e-5 of the peak).
    assert np.abs(e.pos_ned_m[:, axis] - ref).max() < 1e-3 * ref.max()


@pytest.mark.parametrize("axis", [0, 1])
def test_horizontal_gyro_bias_follows_schuler_ramp(equator, axis):
    truth, imu, g, r_m, r_n = equator
    radius = (r_m, r_n)[axis]
    w_s = np.sqrt(g / radius)
    gyro = np.zeros(3)
    # A y-gyro bias tilts the computed frame nose-up: north error -g ε t³/6;
    # an x-gyro bias rolls it right: east error +g ε t³/6.
    gyro[1 - axis] = DEG_PER_H
    sign = -1.0 if axis == 0 else 1.0
    e = run(truth, _biased(imu, gyro=gyro), vertical="hold", h_ref=truth.h)
    err = sign * e.pos_ned_m[:, axis]
    ref = DEG_PER_H * radius * (e.t - np.sin(w_s * e.t) / w_s)
    # The closed form ignores Earth rate; the coupling through the cos(lat) Earth
    # rate changes the hour-long curve by under 1 % (measured 0.6 %).
    assert np.abs(err - ref).max() < 0.01 * ref.max()
    short = e.t <= 300.0
    cubic = g * DEG_PER_H * e.t[short] ** 3 / 6
    # Short-time law: the next series term is (ω_s t)²/20 = 0.7 % at 300 s.
    assert np.abs(err[short] - cubic).max() < 0.01 * cubic.max()


def test_vertical_channel_diverges_with_time_constant_sqrt_r_over_2g(equator):
    truth, imu, g, r_m, r_n = equator
    tau = np.sqrt(np.sqrt(r_m * r_n) / (2 * g))
    assert tau == pytest.approx(570.0, rel=0.01)
    b = 1e-6 * earth.G0  # 1 µg: the height error stays under 1 km, linear to 1e-4
    e = run(truth, _biased(imu, accel=[0, 0, -b]))  # reads more upward force
    up = -e.pos_ned_m[:, 2]
    # Linearised: δḧ = (2g/R) δh + b, so δh = b τ² (cosh(t/τ) - 1).
    ref = b * tau**2 * (np.cosh(e.t / tau) - 1)
    assert up[-1] == pytest.approx(ref[-1], rel=0.02)  # R differs from the local radius by < 1 %
    assert up[-1] > 10 * b * e.t[-1] ** 2 / 2  # after 1 h, 13x the growth b t²/2 of a neutral channel


def test_vertical_hold_and_damp_bound_the_height_error(equator):
    truth, imu, *_ = equator
    biased = _biased(imu, accel=[0, 0, -MG])
    free = run(truth, biased)
    held = run(truth, biased, vertical="hold", h_ref=truth.h)
    damped = run(truth, biased, vertical="damp", h_ref=truth.h, vertical_tau_s=10.0)
    assert abs(free.pos_ned_m[-1, 2]) > 1e4  # 1 mg vertically for an hour runs away
    assert np.abs(held.pos_ned_m[:, 2]).max() == 0.0
    # Critically damped second-order loop: steady-state error b τ² = 1 mg × 100 s² ≈ 1 m.
    assert abs(damped.pos_ned_m[-1, 2]) == pytest.approx(MG * 100.0, rel=0.01)


def test_chunked_batched_and_decimated_runs_equal_one_run(manoeuvre):
    truth, imu = trajectory.generate(manoeuvre, 100.0)
    n = 20000
    part = dataclasses.replace(imu, t=imu.t[: n + 1], dtheta_b=imu.dtheta_b[:n], dv_b=imu.dv_b[:n])
    init = strapdown.InitialState.from_series(truth)
    whole = strapdown.integrate(part, init)
    state = strapdown.start(init)
    pieces = []
    for k0, k1 in [(0, 7), (7, 9000), (9000, n)]:
        chunk = dataclasses.replace(
            imu, t=imu.t[k0 : k1 + 1], dtheta_b=imu.dtheta_b[k0:k1], dv_b=imu.dv_b[k0:k1]
        )
        out, state = strapdown.advance(state, chunk)
        pieces.append(out)
    np.testing.assert_array_equal(np.concatenate([p.lat for p in pieces]), whole.lat[1:])
    np.testing.assert_array_equal(np.concatenate([p.q_nb for p in pieces]), whole.q_nb[1:])
    noisy = part.dv_b + np.random.default_rng(3).normal(0, 1e-4, part.dv_b.shape)
    batch = strapdown.integrate_batch(
        part.t, np.stack([part.dtheta_b] * 2), np.stack([part.dv_b, noisy]), init
    )
    np.testing.assert_array_equal(batch[0].lon, whole.lon)
    np.testing.assert_array_equal(
        batch[1].v_n, strapdown.integrate(dataclasses.replace(part, dv_b=noisy), init).v_n
    )
    thin = strapdown.integrate(part, init, every=10)
    np.testing.assert_array_equal(thin.h, whole.h[::10])
    np.testing.assert_array_equal(thin.t, whole.t[::10])


def test_bad_arguments_are_refused():
    truth, imu = trajectory.generate(stationary(10.0, 1.0), 100.0)
    init = strapdown.InitialState.from_series(truth)
    with pytest.raises(ValueError, match="vertical must be one of"):
        strapdown.integrate(imu, init, vertical="sideways")
    with pytest.raises(ValueError, match="h_ref"):
        strapdown.integrate(imu, init, vertical="hold", h_ref=np.zeros(3))
    with pytest.raises(ValueError, match="every"):
        strapdown.integrate(imu, init, every=0)
    # Increments of mismatched shapes, or backwards in time: the compiled kernel checks no bounds, and
    # read past the arrays' ends (results that changed from run to run). Mismatched shapes are refused
    # where the increments are made; times that go back, before the kernel runs.
    for changed in ({"dv_b": imu.dv_b[:-1]}, {"dtheta_b": imu.dtheta_b[:, :2]}, {"t": imu.t[:-1]}):
        with pytest.raises(ValueError, match=r"^ImuIncrements\.[a-z_]+: expected shape"):
            dataclasses.replace(imu, **changed)
    with pytest.raises(ValueError, match="t must increase"):
        strapdown.integrate(dataclasses.replace(imu, t=imu.t[::-1].copy()), init)
    # Rates, what most readers give: an AttributeError ('ImuRates' object has no attribute 'dtheta_b').
    rates = ImuRates(t=imu.t[1:], omega_ib_b=imu.dtheta_b, f_ib_b=imu.dv_b)
    with pytest.raises(TypeError, match=r"expected ImuIncrements, got ImuRates \(rates: integrate rates"):
        strapdown.integrate(rates, init)  # type: ignore[arg-type]


def test_a_stretch_of_intervals_integrates_as_the_whole_does_from_its_start():
    """``ImuIncrements.steps(a, b)``: intervals a..b with their b - a + 1 bounding times (a plain slice of
    ``t`` alike is one short); integrated from the whole run's state at ``t[a]`` it ends where the whole
    run is at ``t[b]`` (1e-12 rad, 1 µm: the same arithmetic from a state rounded to its stored form)."""
    turning = SegmentMotion.from_segments(
        Start(D(45), D(10), 100.0, 10.0, 0.0, 0.0, 0.0), [Turn(10.0, D(90), 1.0)]
    )
    truth, imu = trajectory.generate(turning, 100.0)
    whole = strapdown.integrate(imu, strapdown.InitialState.from_series(truth))
    part = imu.steps(300, 700)
    assert len(part) == 400 and part.t[0] == imu.t[300] and part.t[-1] == imu.t[700]
    assert len(imu.steps(300)) == len(imu) - 300 and imu.steps().t.tolist() == imu.t.tolist()
    start = strapdown.InitialState.from_series(whole, 300)
    sol = strapdown.integrate(part, start)
    np.testing.assert_allclose(
        [sol.lat[-1], sol.lon[-1]], [whole.lat[700], whole.lon[700]], rtol=0, atol=1e-12
    )
    assert sol.h[-1] == pytest.approx(whole.h[700], abs=1e-6)


def test_a_damp_loop_shorter_than_two_steps_is_refused_as_a_scenario_refuses_it() -> None:
    """The loop's explicit update is unstable below a step: ``integrate`` gave NaN for a 0.1 s loop at
    10 Hz where a scenario refused it; the library refuses it now, at the scenario's bound."""
    from sins.scenario import validate

    assert strapdown.MIN_TAU_SAMPLES == validate.MIN_TAU_SAMPLES
    still = SegmentMotion.from_segments(Start(0.7, 0.0, 100.0, 0.0, 0.0, 0.0, 0.0), [Hold(5.0)])
    truth, imu = trajectory.generate(still, 10.0)
    start = strapdown.InitialState.from_series(truth)
    with pytest.raises(ValueError, match=r"at least 2 IMU steps \(0.2 s at 10 Hz\)"):
        strapdown.integrate(imu, start, vertical="damp", vertical_tau_s=0.1)
    sol = strapdown.integrate(imu, start, vertical="damp", vertical_tau_s=0.2)
    assert np.abs(sol.h - 100.0).max() < 1e-6


def test_the_library_refuses_what_it_would_integrate_wrongly():
    """Found by a walk through the library: each had run without a word (a step back in a batch's times,
    degrees for an initial latitude, unsorted times beyond a series, waypoints passed backwards), or
    failed inside numpy or the compiled kernel."""
    from sins.core.series import NavSeries
    from sins.nav.motion import WaypointMotion

    truth, imu = trajectory.generate(stationary(10.0, 10.0), 100.0)
    init = strapdown.InitialState.from_series(truth)
    d, v = np.stack([imu.dtheta_b] * 2), np.stack([imu.dv_b] * 2)
    back = imu.t.copy()
    back[5] = back[4] - 1e-3
    with pytest.raises(ValueError, match="integrate_batch: t must increase"):
        strapdown.integrate_batch(back, d, v, init)
    with pytest.raises(ValueError, match=r"t must have shape \(1001,\) for 1000 increments"):
        strapdown.integrate_batch(imu.t[:-1], d, v, init)
    assert strapdown.integrate_batch(imu.t, d[:0], v[:0], init) == []
    with pytest.raises(ValueError, match=r"degrees given for radians"):
        dataclasses.replace(init, lat=45.0)
    with pytest.raises(ValueError, match="not all zero"):
        dataclasses.replace(init, q_nb=np.zeros(4))
    series: NavSeries = truth
    with pytest.raises(ValueError, match="outside"):
        series.interpolate([3.0, 1.0, 17.0, 2.0])  # before: h at 17 s extrapolated
    with pytest.raises(ValueError, match="1-D"):
        series.interpolate(1.5)
    for speeds, said in (([10.0, -5.0, 10.0], "speeds > 0"), ([10.0, 10.0], "m speeds")):
        with pytest.raises(ValueError, match=said):
            WaypointMotion.from_waypoints(0.7, 0.1, 0.0, [[0, 0, 0], [100, 0, 0], [200, 0, 0]], speeds)
    with pytest.raises(ValueError, match="degrees given for radians"):
        WaypointMotion.from_waypoints(45.0, 0.1, 0.0, [[0, 0, 0], [100, 0, 0]], [10.0, 10.0])


def test_chunks_that_do_not_follow_each_other_are_refused():
    """``advance`` had integrated a chunk 1 s after the last one ended, or one back in time, as if it
    followed (the walk's library user); chunks that follow still equal one call, to the bit."""
    truth, imu = trajectory.generate(stationary(10.0, 20.0), 100.0)
    init = strapdown.InitialState.from_series(truth)
    state = strapdown.start(init)
    _, state = strapdown.advance(state, imu.steps(0, 1000))
    for a, b in ((1100, 1500), (500, 900)):
        with pytest.raises(ValueError, match="not where the last ended"):
            strapdown.advance(state, imu.steps(a, b))
    second, state = strapdown.advance(state, imu.steps(1000))
    whole = strapdown.integrate(imu, init)
    assert second.lat[-1] == whole.lat[-1] and second.h[-1] == whole.h[-1]


def test_a_series_holds_unit_quaternions_and_its_own_rows():
    """Twice a unit quaternion had been taken as given (its Euler angles 0.86 rad off); one a printed
    reference rounds (1e-6 off) is taken, and so is one within 1e-3 (``QUAT_NORM_TOL``), beyond which
    it is refused. ``at`` past the end had given an empty series."""
    truth, _ = trajectory.generate(stationary(10.0, 1.0), 10.0)
    for scale, ok in ((1 + 1e-6, True), (1.0005, True), (1.002, False), (2.0, False)):
        q = truth.q_nb.copy()
        q[3] *= scale
        if ok:
            dataclasses.replace(truth, q_nb=q)
        else:
            with pytest.raises(ValueError, match=r"q_nb: row 3 has norm .*, not 1"):
                dataclasses.replace(truth, q_nb=q)
    assert len(truth.at(-1)) == 1
    with pytest.raises(IndexError, match=f"the series has {len(truth)} rows"):
        truth.at(len(truth))
