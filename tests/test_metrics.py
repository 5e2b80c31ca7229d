"""Error metrics: definitions checked against scipy and against a whole-series computation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sins.core import earth, rotation
from sins.core.series import NavSeries
from sins.nav.metrics import DriftAccumulator, NavErrors, euler_errors, nav_errors, summarize


def test_euler_errors_match_the_rotation_module_and_scipy():
    rng = np.random.default_rng(11)
    q1 = Rotation.random(2000, random_state=rng).as_quat()
    q2 = Rotation.random(2000, random_state=rng).as_quat()
    q1[0] = rotation.quat_from_euler(0.3, np.pi / 2, 1.1)  # gimbal lock takes its own branch
    expected = rotation.wrap_angle(np.column_stack(rotation.euler_from_quat(q1)) - np.column_stack(
        rotation.euler_from_quat(q2)))  # fmt: skip
    np.testing.assert_allclose(euler_errors(q1, q2), expected, rtol=0, atol=1e-12)  # same formulas, rounding
    ypr1 = Rotation.from_quat(q1[1:]).as_euler("ZYX")
    ypr2 = Rotation.from_quat(q2[1:]).as_euler("ZYX")
    ref = rotation.wrap_angle((ypr1 - ypr2)[:, ::-1])
    np.testing.assert_allclose(euler_errors(q1[1:], q2[1:]), ref, rtol=0, atol=1e-9)  # scipy's own rounding


def _series(t, lat, lon, h, v, q):
    return NavSeries(t=t, lat=lat, lon=lon, h=h, v_n=v, q_nb=q)


def test_position_errors_in_metres_north_east_down():
    n = 5
    t = np.arange(n, dtype=float)
    lat0, lon0, h0 = np.radians(40.0), np.radians(-3.0), 650.0
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    truth = _series(t, np.full(n, lat0), np.full(n, lon0), np.full(n, h0), np.zeros((n, 3)), q)
    r_m, r_n = earth.radii(lat0)
    est = _series(
        t, lat0 + 10.0 / (r_m + h0) * t, lon0 - 4.0 / ((r_n + h0) * np.cos(lat0)) * t, h0 + 2.0 * t,
        np.zeros((n, 3)), q,
    )  # fmt: skip
    e = nav_errors(est, truth)
    np.testing.assert_allclose(e.pos_ned_m, np.column_stack([10 * t, -4 * t, -2 * t]), atol=1e-9)
    s = summarize(e)
    assert s.final_horizontal_m == pytest.approx(np.hypot(40, 16))
    assert s.drift_rate_m_per_h == pytest.approx(np.hypot(40, 16) / (4 / 3600))
    assert s.drift_rate_nmi_per_h == pytest.approx(s.drift_rate_m_per_h / 1852)


def test_accumulator_in_chunks_equals_one_pass():
    rng = np.random.default_rng(2)
    n = 1003
    e = NavErrors(
        t=np.arange(n) * 0.1, pos_ned_m=rng.normal(size=(n, 3)), vel_ned_mps=rng.normal(size=(n, 3)),
        att_rpy_rad=rng.normal(size=(n, 3)),
    )  # fmt: skip
    acc = DriftAccumulator(keep_every=7)
    for a, b in [(0, 1), (1, 500), (500, 501), (501, n)]:
        acc.add(NavErrors(e.t[a:b], e.pos_ned_m[a:b], e.vel_ned_mps[a:b], e.att_rpy_rad[a:b]))
    whole, chunked = summarize(e), acc.summary()
    for key, value in whole.to_dict().items():
        assert getattr(chunked, key) == pytest.approx(value, rel=1e-12), key
    kept = acc.kept()
    np.testing.assert_array_equal(kept.t, np.append(e.t[::7], e.t[-1]))  # every 7th, then the last
    np.testing.assert_array_equal(kept.pos_ned_m[-1], e.pos_ned_m[-1])


def test_a_diverged_chunk_leaves_the_largest_error_not_a_number() -> None:
    # A NaN in the errors (a solution that diverged) had the largest horizontal error read 0.0 (Python's
    # max(0.0, nan)) where every other figure read NaN; in a chunked run it kept the value from before.
    n = 20
    pos = np.ones((n, 3))
    pos[5, 0] = np.nan
    e = NavErrors(
        t=np.arange(n) * 0.1, pos_ned_m=pos, vel_ned_mps=np.zeros((n, 3)), att_rpy_rad=np.zeros((n, 3))
    )
    assert np.isnan(summarize(e).max_horizontal_m)
    acc = DriftAccumulator()
    acc.add(NavErrors(e.t[:10], e.pos_ned_m[:10], e.vel_ned_mps[:10], e.att_rpy_rad[:10]))
    acc.add(NavErrors(e.t[10:], e.pos_ned_m[10:], e.vel_ned_mps[10:], e.att_rpy_rad[10:]))
    assert np.isnan(acc.summary().max_horizontal_m)


def _random_pair(n: int, seed: int) -> tuple[NavSeries, NavSeries]:
    """A truth wandering over the globe (both hemispheres, the antimeridian) and an estimate off it by
    metres, the longitude error sometimes across ±π."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.01
    lat = rng.uniform(-1.4, 1.4, n)
    lon = rng.uniform(-np.pi, np.pi, n)
    h = rng.uniform(-100.0, 9000.0, n)
    q = Rotation.random(n, random_state=rng).as_quat()
    truth = _series(t, lat, lon, h, rng.normal(0, 30, (n, 3)), q)
    d_lon = rng.normal(0, 1e-5, n)
    d_lon[::50] += 2 * np.pi * rng.choice([-1.0, 1.0], len(d_lon[::50]))  # wrapped back by the error
    q_est = Rotation.from_rotvec(rng.normal(0, 0.05, (n, 3))) * Rotation.from_quat(q)
    est = _series(
        t, lat + rng.normal(0, 1e-5, n), lon + d_lon, h + rng.normal(0, 5, n),
        truth.v_n + rng.normal(0, 0.1, (n, 3)), q_est.as_quat(),
    )  # fmt: skip
    est.q_nb[0] = rotation.quat_from_euler(0.3, np.pi / 2, 1.1)  # gimbal lock takes its own branch
    return est, truth


def test_the_compiled_errors_equal_the_numpy_expressions_to_the_last_bit():
    # The errors of one pass of compiled code against the module docstring's numpy expressions (as
    # nav_errors computed them before): the same operations in the same order, so equal, not close.
    # Attitude: against the compiled euler_errors (held to the rotation module above), bit for bit.
    from sins.nav.metrics import TruthFrame, errors_against

    est, truth = _random_pair(3000, 5)
    errors, horizontal = errors_against(est, TruthFrame.of(truth))
    r_m, r_n = earth.radii(truth.lat)
    north = (est.lat - truth.lat) * (r_m + truth.h)
    east = rotation.wrap_angle(est.lon - truth.lon) * (r_n + truth.h) * np.cos(truth.lat)
    np.testing.assert_array_equal(errors.pos_ned_m, np.column_stack([north, east, -(est.h - truth.h)]))
    np.testing.assert_array_equal(errors.vel_ned_mps, est.v_n - truth.v_n)
    np.testing.assert_array_equal(errors.att_rpy_rad, euler_errors(est.q_nb, truth.q_nb))
    np.testing.assert_array_equal(horizontal, np.sqrt(north * north + east * east))
    np.testing.assert_array_equal(errors.t, est.t)
    assert np.abs(errors.pos_ned_m[:, 1]).max() < 1e3  # the ±2π longitude jumps were wrapped


def test_a_truth_frame_slices_and_joins_as_its_truth():
    from sins.nav.metrics import TruthFrame

    est, truth = _random_pair(400, 6)
    frame = TruthFrame.of(truth)
    joined = TruthFrame.join([frame.rows(0, 150), frame.rows(150, 151), frame.rows(151, 400)])
    np.testing.assert_array_equal(joined.data, frame.data)
    back = frame.truth(np.array([3, 7, 399]))
    for name in ("t", "lat", "lon", "h", "v_n", "q_nb"):
        np.testing.assert_array_equal(getattr(back, name), getattr(truth, name)[[3, 7, 399]])
    np.testing.assert_array_equal(frame.h, truth.h)
    # Errors against rows of the frame are the rows of the errors against the whole.
    from sins.nav.metrics import errors_against

    whole, _ = errors_against(est, frame)
    part, _ = errors_against(est.at(slice(150, 400)), frame.rows(150, 400))
    np.testing.assert_array_equal(part.att_rpy_rad, whole.att_rpy_rad[150:])
    with pytest.raises(ValueError, match="400 states, the truth frame 250"):
        errors_against(est, frame.rows(150, 400))


def test_max_abs_columns_is_numpys_nan_included():
    from sins.nav.metrics import _max_abs_columns

    x = np.random.default_rng(7).normal(size=(500, 3))
    np.testing.assert_array_equal(_max_abs_columns(x), np.abs(x).max(axis=0))
    x[10, 1] = np.nan  # numpy's max propagates a NaN: a diverged run must not look bounded
    x[400, 2] = np.nan
    x[499, 2] = 99.0
    np.testing.assert_array_equal(_max_abs_columns(x), np.abs(x).max(axis=0))
    x[0, 0] = np.nan
    np.testing.assert_array_equal(_max_abs_columns(x), np.abs(x).max(axis=0))


def test_accumulator_with_the_horizontal_given_equals_without():
    from sins.nav.metrics import TruthFrame, errors_against

    est, truth = _random_pair(1000, 8)
    errors, horizontal = errors_against(est, TruthFrame.of(truth))
    a, b = DriftAccumulator(keep_every=9), DriftAccumulator(keep_every=9)
    a.add(errors)
    b.add(errors, horizontal)
    assert a.summary() == b.summary()


def test_a_container_of_mismatched_shapes_is_refused_where_it_is_made() -> None:
    # A NavSeries whose latitude was shorter than its times failed in nav_errors in numpy's words
    # ("could not broadcast"), and one whose q_nb had 3 columns was taken; ImuRates and CalibrationData
    # alike. Each is refused where it is made, naming the container, the field and both shapes.
    from sins.core.series import CalibrationData, ImuRates

    n, z = 5, np.zeros(5)
    with pytest.raises(ValueError, match=r"^NavSeries\.lat: expected shape \(5,\) for 5 rows, got \(4,\)"):
        NavSeries(t=np.arange(n), lat=z[:4], lon=z, h=z, v_n=np.zeros((n, 3)), q_nb=np.zeros((n, 4)))
    with pytest.raises(ValueError, match=r"^NavSeries\.q_nb: expected shape \(5, 4\)"):
        NavSeries(t=np.arange(n), lat=z, lon=z, h=z, v_n=np.zeros((n, 3)), q_nb=np.zeros((n, 3)))
    with pytest.raises(ValueError, match=r"^ImuRates\.omega_ib_b: expected shape \(5, 3\)"):
        ImuRates(t=np.arange(n), omega_ib_b=np.zeros((n, 2)), f_ib_b=np.zeros((n, 3)))
    with pytest.raises(ValueError, match=r"^CalibrationData\.temp: expected shape \(5,\)"):
        three = np.zeros((n, 3))
        CalibrationData(np.arange(n), three, three, three, three, temp=z[:3])
