"""Error metrics: definitions checked against scipy and against a whole-series computation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sins.nav import earth, rotation
from sins.nav.metrics import DriftAccumulator, NavErrors, euler_errors, nav_errors, summarize
from sins.series import NavSeries


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
