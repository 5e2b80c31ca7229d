"""The numpy-only rig procedures of ``tests/numpy_rigs.py`` against analytic facts, and their files
against sins's reader: the independent data the cross-rig checks rest on must be right itself."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy_rigs as nr
import pytest

from sins import io

PROCEDURES = {
    "tumble_and_table": lambda: nr.tumble_and_table(rate_hz=50.0, holds=6, hold_s=3.0),
    "faces_and_axis_table": lambda: nr.faces_and_axis_table(rate_hz=100.0, hold_s=3.0),
    "continuous_tumble": lambda: nr.continuous_tumble(rate_hz=50.0, duration_s=120.0),
}


@pytest.mark.parametrize("name", list(PROCEDURES))
def test_specific_force_is_gravity_and_the_rate_holds_earths(name: str):
    s = PROCEDURES[name]()
    # No lever arm and no linear motion: |f| = G everywhere, to rounding.
    np.testing.assert_allclose(np.linalg.norm(s.ref_accel, axis=1), nr.G, rtol=1e-12)
    # The vertical component of the body rate is Earth's (-Ω sin φ along down) plus the table's; at rest
    # (no turn) the rate is Earth's, whose angle with the force is fixed by the latitude:
    # f·ω = -G (C_bn e_down)·ω = -G ω_ie,down = G Ω sin φ.
    up = -s.ref_accel / nr.G
    still = np.linalg.norm(s.ref_gyro, axis=1) < 2 * nr.EARTH_RATE
    if name != "continuous_tumble":
        assert still.sum() > 0
        np.testing.assert_allclose(np.linalg.norm(s.ref_gyro[still], axis=1), nr.EARTH_RATE, rtol=1e-9)
        dot = (s.ref_accel[still] * s.ref_gyro[still]).sum(axis=1)
        np.testing.assert_allclose(dot, nr.G * nr.EARTH_RATE * np.sin(nr.LAT), rtol=1e-9)
    # A table turns about the vertical: its rate is all along "up", so the horizontal part of the
    # body rate is Earth's alone (Ω cos φ) wherever the unit is not tumbling.
    if name == "faces_and_axis_table":
        vertical = (s.ref_gyro * up).sum(axis=1)
        horizontal = np.linalg.norm(s.ref_gyro - vertical[:, None] * up, axis=1)
        np.testing.assert_allclose(horizontal, nr.EARTH_RATE * np.cos(nr.LAT), rtol=1e-9)
        assert np.degrees(np.abs(vertical).max()) == pytest.approx(300.0, abs=0.01)


def test_the_force_turns_as_the_rate_says():
    """The direction of gravity in body axes, u = -f/G, turns as du/dt = -ω_nb × u, and ω_nb differs
    from the recorded ω_ib by Earth's rate only. Central differences at 400 Hz (truncation 4e-5 rad/s
    at these rates of up to 3.5 rad/s) leave |du/dt + ω_ib × u| at Earth's part, Ω cos φ = 5.2e-5
    rad/s, or below: a frame, sign or order mistake in the attitude would leave rad/s."""
    s = nr.continuous_tumble(rate_hz=400.0, duration_s=30.0)
    u = -s.ref_accel / nr.G
    dudt = (u[2:] - u[:-2]) * (s.rate_hz / 2.0)
    mismatch = np.linalg.norm(dudt + np.cross(s.ref_gyro[1:-1], u[1:-1]), axis=1)
    assert np.abs(s.ref_gyro).max() > 2.5
    assert mismatch.max() < nr.EARTH_RATE * np.cos(nr.LAT) + 1e-4, mismatch.max()


def test_unit_errors_against_their_formulas():
    w = np.array([[0.5, -1.0, 2.0]])
    f = np.array([[1.0, -2.0, -9.0]])
    temp = np.array([30.0])
    unit = nr.Unit(gyro_k2=np.array([1e-3, 0, 0]), gyro_ka=np.array([0, 2e-3, 0]),
                   accel_ts=np.array([0, 0, 1e-4]), gyro_tc2=np.array([0, 0, 1e-6]))  # fmt: skip
    g = np.zeros((3, 3, 3))
    g[1, 0, 2] = 3e-6
    e_g, e_a = nr.Unit(gyro_g2=g).errors(w, f, temp)
    np.testing.assert_allclose(e_g, [[0.0, 3e-6 * 1.0 * -9.0, 0.0]])
    e_g, e_a = unit.errors(w, f, temp)
    np.testing.assert_allclose(e_g, [[1e-3 * 0.25, 2e-3 * 1.0, 1e-6 * 100.0]])
    np.testing.assert_allclose(e_a, [[0.0, 0.0, 1e-4 * 10.0 * -9.0]])


def test_white_noise_per_sample_follows_its_density():
    rng = np.random.default_rng(0)
    unit = nr.baseline_unit(rng)
    zero = np.zeros((100_000, 3))
    temp = np.full(100_000, 20.0)
    gyro, accel = unit.read(zero, zero, temp, 100.0, rng)
    e_g, e_a = unit.errors(zero, zero, temp)
    np.testing.assert_allclose((gyro - e_g).std(axis=0), np.radians(0.01), rtol=0.01)  # 0.01 °/s
    np.testing.assert_allclose((accel - e_a).std(axis=0), 1e-3 * nr.G, rtol=0.01)  # 1 mg


def test_its_files_read_back_in_sins(tmp_path: Path):
    s = nr.faces_and_axis_table(rate_hz=100.0, hold_s=2.0)
    rng = np.random.default_rng(1)
    gyro, accel = nr.baseline_unit(rng).read(s.ref_gyro, s.ref_accel, s.temp, s.rate_hz, rng)
    path = tmp_path / "other_tool.csv"
    nr.write_csv(path, s, gyro, accel)
    data = io.read(path).rig
    assert data.phases == () and data.temp is not None
    for got, want in ((data.t, s.t), (data.gyro, gyro), (data.accel, accel), (data.ref_gyro, s.ref_gyro),
                      (data.ref_accel, s.ref_accel), (data.temp, s.temp)):  # fmt: skip
        # Ten significant digits: 5e-10 relative, and Earth-rate-sized rates print to 1e-14 rad/s.
        np.testing.assert_allclose(got, want, rtol=6e-10, atol=1e-14)
