"""The exact ideal IMU and the truth, against references that share none of their numerics.

* An Earth-centred mechanisation (position, velocity and attitude in ECEF, no
  transport rate, no NED Coriolis form) solved by scipy's DOP853 from the
  continuous ideal IMU must reproduce the generated truth.
* The Simpson increments must agree with 5-point Gauss–Legendre integrals of
  the continuous rates.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.integrate import quad_vec, solve_ivp
from scipy.spatial.transform import Rotation

from sins import io
from sins.core import earth, rotation
from sins.nav import strapdown, trajectory
from sins.nav.metrics import nav_errors
from sins.nav.motion import (
    Accelerate,
    Climb,
    Hold,
    Oscillation,
    RecordedMotion,
    Rotate,
    SegmentMotion,
    Start,
    Turn,
    WaypointMotion,
)

D = np.radians


@pytest.fixture(scope="module")
def motion() -> SegmentMotion:
    """Ten minutes of fast manoeuvres at 60° N, with a seaway on top."""
    segs = [
        Hold(20), Accelerate(15, 30.0, 3), Turn(25, D(9), 3, True), Climb(60, D(8), 6), Turn(30, D(-6), 4),
        Rotate(8, D(15), D(-5), D(20), 2), Accelerate(20, -12.0, 4), Turn(40, D(4), 5), Climb(50, D(-6), 5),
        Rotate(10, D(-15), D(5), D(-20), 2), Hold(20),
    ]  # fmt: skip
    segs.append(Hold(600 - sum(s.duration for s in segs)))
    osc = [Oscillation("roll", D(3), 7.0), Oscillation("heave", 0.5, 5.0, 1.0)]
    return SegmentMotion.from_segments(Start(D(60), D(25), 400.0, 5.0, 0.0, 0.0, D(-40)), segs, osc)


def _c_en(lat, lon):
    """Columns: north, east, down of the local-level frame, in ECEF."""
    sl, cl, so, co = np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon)
    return np.array([[-sl * co, -so, -cl * co], [-sl * so, co, -cl * so], [cl, 0.0, -sl]])


def _geodetic(r):
    """ECEF → (lat, lon, h) by fixed-point iteration on the latitude (independent of sins)."""
    x, y, z = r
    p = np.hypot(x, y)
    lat = np.arctan2(z, p * (1 - earth.E2))
    for _ in range(8):
        n = earth.A / np.sqrt(1 - earth.E2 * np.sin(lat) ** 2)
        h = p / np.cos(lat) - n
        lat = np.arctan2(z, p * (1 - earth.E2 * n / (n + h)))
    n = earth.A / np.sqrt(1 - earth.E2 * np.sin(lat) ** 2)
    return lat, np.arctan2(y, x), p / np.cos(lat) - n


def test_truth_agrees_with_an_ecef_mechanisation_solved_by_scipy(motion):
    truth, _ = trajectory.generate(motion, 100.0)
    w_ie = np.array([0.0, 0.0, earth.OMEGA_IE])

    def rhs(t, y):
        r, v, q = y[:3], y[3:6], y[6:]
        lat, lon, h = _geodetic(r)
        kin = motion.kinematics(np.array([t]))
        omega_ib_b, f_b = trajectory.specific_force_and_rate(kin, np.array([lat]), np.array([h]))
        c_eb = Rotation.from_quat(q).as_matrix()
        gamma_e = _c_en(lat, lon) @ np.array([0.0, 0.0, earth.normal_gravity(lat, h)])
        dv = c_eb @ f_b[0] - 2 * np.cross(w_ie, v) + gamma_e
        omega_eb_b = omega_ib_b[0] - c_eb.T @ w_ie
        x, yq, z, w = q
        dq = 0.5 * np.array([
            w * omega_eb_b[0] + yq * omega_eb_b[2] - z * omega_eb_b[1],
            w * omega_eb_b[1] + z * omega_eb_b[0] - x * omega_eb_b[2],
            w * omega_eb_b[2] + x * omega_eb_b[1] - yq * omega_eb_b[0],
            -x * omega_eb_b[0] - yq * omega_eb_b[1] - z * omega_eb_b[2],
        ])  # fmt: skip
        return np.concatenate([v, dv, dq])

    c_en0 = _c_en(truth.lat[0], truth.lon[0])
    y0 = np.concatenate([
        np.array(earth.lla_to_ecef(truth.lat[0], truth.lon[0], truth.h[0])),
        c_en0 @ truth.v_n[0],
        Rotation.from_matrix(c_en0 @ rotation.dcm_from_quat(truth.q_nb[0])).as_quat(),
    ])  # fmt: skip
    check = np.arange(0, len(truth.t), 2000)
    # Restart the solver at every breakpoint: an adaptive step across a jump in
    # the third derivative loses accuracy (seen: a 5e-11 rad tilt at a ramp).
    y = y0
    states = {}
    edges = np.unique(np.concatenate([[truth.t[0], truth.t[-1]], motion.breakpoints()]))
    for a, b in itertools.pairwise(edges):
        inside = check[(truth.t[check] > a) & (truth.t[check] <= b)]
        sol = solve_ivp(rhs, (a, b), y, method="DOP853", dense_output=True, rtol=1e-12, atol=1e-10)
        assert sol.success
        states.update((i, sol.sol(truth.t[i])) for i in inside)
        y = sol.y[:, -1]
    states[0] = y0
    for i in check:
        r, v, q = states[i][:3], states[i][3:6], states[i][6:]
        c_en = _c_en(truth.lat[i], truth.lon[i])
        # Both are exact solutions of the same motion: they differ by the ODE
        # tolerance (rtol 1e-12 of 6.4e6 m coordinates) and the Simpson quadrature:
        # measured 1.1e-5 m, 1.0e-7 m/s, 1.6e-11 in C_nb.
        assert np.linalg.norm(r - np.array(earth.lla_to_ecef(truth.lat[i], truth.lon[i], truth.h[i]))) < 1e-4
        assert np.abs(c_en.T @ v - truth.v_n[i]).max() < 1e-6
        c_nb = c_en.T @ Rotation.from_quat(q).as_matrix()
        assert np.abs(c_nb - rotation.dcm_from_quat(truth.q_nb[i])).max() < 1e-10  # measured 1.6e-11


def test_simpson_increments_match_gauss_legendre(motion):
    truth, imu = trajectory.generate(motion, 100.0)
    x, w = np.polynomial.legendre.leggauss(5)
    rows = np.random.default_rng(5).choice(len(imu), 400, replace=False)
    a, b = imu.t[rows], imu.t[rows + 1]
    t = (0.5 * (a + b))[:, None] + (0.5 * (b - a))[:, None] * x
    # Position at the nodes by linear interpolation: the Earth terms change by
    # < 1e-14 over the 5 mm that the interpolation is off by.
    lat = np.interp(t.ravel(), truth.t, truth.lat)
    h = np.interp(t.ravel(), truth.t, truth.h)
    omega, f = trajectory.specific_force_and_rate(motion.kinematics(t.ravel()), lat, h)
    weights = (0.5 * (b - a))[:, None, None] * w[None, :, None]
    ref_dtheta = (omega.reshape(len(rows), 5, 3) * weights).sum(axis=1)
    ref_dv = (f.reshape(len(rows), 5, 3) * weights).sum(axis=1)
    # The samples hit breakpoints where Gauss–Legendre loses accuracy; Simpson
    # splits there, so compare with a bound well above both methods' error.
    assert np.abs(imu.dtheta_b[rows] - ref_dtheta).max() < 1e-12
    assert np.abs(imu.dv_b[rows] - ref_dv).max() < 1e-10


@pytest.mark.parametrize("rate_hz, hold_s", [(4.0, 1.0), (3.0, 1.1)], ids=["on samples", "between samples"])
def test_increments_are_exact_below_100_hz(rate_hz, hold_s):
    """Sample intervals wider than the 10 ms piece, the ramps' ends on the samples (4 Hz) and between
    them (3 Hz): every increment is scipy's adaptive quadrature of the continuous rate and force.

    A turn in place at the equator ramped from rest to 90 °/s in 0.5 s (a quintic smoothstep): its
    rate's fourth derivative reaches 360 A / T⁴ = 9,048 rad/s⁵, so Simpson on 10 ms pieces is off by at
    most ``h w⁴ max|f⁗| / 2880`` = 7.9e-9 rad an interval at 4 Hz (5.9e-9 at 3 Hz's narrower pieces).
    Simpson on whole intervals was off by 0.09° (1.5e-3 rad) at 4 Hz mid-ramp, and by 0.1° a turn at 3 Hz.
    """
    start = Start(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    motion = SegmentMotion.from_segments(start, [Hold(hold_s), Turn(2.0, D(90), 0.5), Hold(1.5)])
    truth, imu = trajectory.generate(motion, rate_hz)
    breaks = motion.breakpoints()

    def rate_and_force(t):
        kin = motion.kinematics(np.array([t]))
        omega, f = trajectory.specific_force_and_rate(kin, np.zeros(1), np.zeros(1))
        return np.concatenate([omega[0], f[0]])

    worst = np.zeros(2)
    for k in range(len(imu)):
        a, b = imu.t[k], imu.t[k + 1]
        inside = [p for p in breaks if a + 1e-9 < p < b - 1e-9]
        ref, _ = quad_vec(rate_and_force, a, b, epsabs=1e-13, epsrel=0, points=inside or None)
        err = np.abs(np.concatenate([imu.dtheta_b[k], imu.dv_b[k]]) - ref)
        worst = np.maximum(worst, [err[:3].max(), err[3:].max()])
    assert worst[0] < 8e-9 and worst[1] < 1e-12, worst
    # Chunks of a few intervals (the pieces bound a chunk's memory) join to the whole, bit for bit.
    parts = list(trajectory.generate_chunks(motion, rate_hz, chunk=100))
    assert len(parts) > 1
    np.testing.assert_array_equal(np.concatenate([p[1].dtheta_b for p in parts]), imu.dtheta_b)
    np.testing.assert_array_equal(np.concatenate([p[0].q_nb for p in parts]), truth.q_nb[1:])


def test_ideal_rates_are_the_derivative_of_the_increments(motion):
    truth, imu = trajectory.generate(motion, 400.0)
    rates = trajectory.ideal_rates(motion, truth)
    inc = rates.to_increments()
    # The 4-point rule is fourth order: error ~ dt⁴ ω'''' ≈ 1e-10 × O(1e-2) here.
    assert np.abs(inc.dtheta_b[1:-1] - imu.dtheta_b[1:-1]).max() < 1e-9
    assert np.abs(inc.dv_b[1:-1] - imu.dv_b[1:-1]).max() < 1e-8


def test_chunks_join_to_the_whole(motion):
    truth, imu = trajectory.generate(motion, 100.0)
    parts = list(trajectory.generate_chunks(motion, 100.0, chunk=777))
    np.testing.assert_allclose(np.concatenate([p[1].dv_b for p in parts]), imu.dv_b, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.concatenate([p[0].lat for p in parts]), truth.lat[1:], rtol=0, atol=1e-15)


def test_waypoints_are_passed_at_their_speeds():
    points = np.array([[0, 0, 0], [800, 300, 0], [1500, 1400, -20], [900, 2500, -30], [-200, 2000, 0]], float)
    speeds = np.array([8.0, 14.0, 20.0, 12.0, 6.0])
    lat0, lon0, h0 = D(52.0), D(4.0), 10.0
    motion = WaypointMotion.from_waypoints(lat0, lon0, h0, points, speeds)
    knots = motion.knots
    kin = motion.kinematics(knots)
    np.testing.assert_allclose(np.linalg.norm(kin.v_n, axis=1), speeds, rtol=1e-12)
    truth, imu = trajectory.generate(motion, 100.0)
    passed = truth.interpolate(knots[knots <= truth.t[-1]])
    k = len(passed.t)
    # The waypoints in geodetic terms: offsets scaled by the radii at the first one.
    r_m, r_n = earth.radii(lat0)
    lat = lat0 + points[:k, 0] / (r_m + h0)
    lon = lon0 + points[:k, 1] / ((r_n + h0) * np.cos(lat0))
    # The integrated truth meets them to the quadrature error plus the linear
    # interpolation between 10 ms samples (v² dt²/8R: nanometres).
    assert np.abs((passed.lat - lat) * r_m).max() < 1e-4
    assert np.abs((passed.lon - lon) * r_n * np.cos(lat0)).max() < 1e-4
    assert np.abs(passed.h - (h0 - points[:k, 2])).max() < 1e-3  # a v_D dt²/8 interpolation term
    e = nav_errors(strapdown.integrate(imu, strapdown.InitialState.from_series(truth)), truth)
    assert e.horizontal_m.max() < 0.01  # its ideal IMU integrates back like any other motion


def test_recorded_truth_motion_reproduces_the_record(motion, tmp_path):
    truth, _ = trajectory.generate(motion, 50.0)
    path = tmp_path / "truth.csv"
    io.write_truth(path, truth)
    record = io.read_truth(path)
    recorded = RecordedMotion(
        t=record.t, lat0=float(record.lat[0]), lon0=float(record.lon[0]), h0=float(record.h[0]),
        v_n=record.v_n, q_nb=record.q_nb,
    )  # fmt: skip
    again, imu = trajectory.generate(recorded, 100.0)
    e = nav_errors(again, truth)
    # Cubic splines through 50 Hz samples: next to a jump of the third derivative
    # (ramp joints) the error is O(h³ × jump) = (0.02 s)³ × 2 rad/s³ ≈ 2e-5 rad
    # (measured 1.8e-5 rad); the integrated velocity error stays sub-centimetre.
    assert e.horizontal_m.max() < 0.01
    assert np.abs(e.att_rpy_rad).max() < 5e-5
    e2 = nav_errors(strapdown.integrate(imu, strapdown.InitialState.from_series(again)), again)
    assert e2.horizontal_m.max() < 0.01


def test_the_increment_convention() -> None:
    """The package's convention (sins's docstring, "IMU samples"): row ``k`` of an increment series is the
    integral over ``(t[k], t[k+1]]``. A rate ramp ``ω = t`` integrates to ``(t[k+1]² − t[k]²) / 2`` there,
    whatever the steps; the rate form's conversion (cubic where the steps are uniform) is exact for it."""
    from sins.core.series import ImuRates

    t = np.cumsum(np.r_[0.0, np.full(50, 0.01)]) + 3.0
    ramp = np.column_stack([t, 2 * t, -t])
    inc = ImuRates(t=t, omega_ib_b=ramp, f_ib_b=ramp).to_increments()
    expected = 0.5 * (t[1:] ** 2 - t[:-1] ** 2)
    np.testing.assert_allclose(inc.dtheta_b[:, 0], expected, rtol=1e-12)
    np.testing.assert_allclose(inc.dv_b[:, 2], -expected, rtol=1e-12)
    assert len(inc.t) == len(inc.dtheta_b) + 1 and inc.t[0] == t[0]
