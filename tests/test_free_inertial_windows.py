"""``tools/broad_free_inertial.py``'s free-inertial windows against closed forms, on parts written with
numpy alone: readings that are the reference's own leave nothing; an accelerometer bias ``b`` along the
body's x leaves its double integral, ``b T²/2`` held level and still, and on a unit rolled 30° and
turning about its own z at ``ω`` the double integral of ``b`` turned with it (which a turn composed on
the wrong side, about the world's z, would not give); and an IMU off the reference's point is judged at
its own point once the reference is moved there (``at_imu``)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sins.core.series import ImuIncrements

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
from broad_free_inertial import G_M_S2, at_imu, window_errors

DT_S = 0.005
ROLL = Rotation.from_euler("x", 30.0, degrees=True)


def _part(
    seconds: float, omega_rad_s: float, bias_m_s2: float
) -> tuple[ImuIncrements, dict[str, np.ndarray]]:
    """A unit at rest in the world (z up), rolled 30° and turning about its own z at ``omega_rad_s``
    (none: held level), its accelerometer reading ``bias_m_s2`` more along its x: its increments, each
    the exact integral over its step, and its part's reference."""
    t = 100.0 + DT_S * np.arange(round(seconds / DT_S) + 1)
    turn = Rotation.from_euler("z", omega_rad_s * (t - t[0])[:, None])
    body_to_world = (ROLL if omega_rad_s else Rotation.identity()) * turn
    up_in_rolled = (ROLL if omega_rad_s else Rotation.identity()).inv().apply([0.0, 0.0, G_M_S2])
    a, b = omega_rad_s * (t[:-1] - t[0]), omega_rad_s * (t[1:] - t[0])
    # ∫ Rz(-ω s) u ds over each step: the rolled frame's gravity turned back by the body's own turn.
    if omega_rad_s:
        c = (np.sin(b) - np.sin(a)) / omega_rad_s
        s = (np.cos(a) - np.cos(b)) / omega_rad_s
    else:
        c, s = np.full(len(a), DT_S), np.zeros(len(a))
    x, y, z = up_in_rolled
    dv_b = np.column_stack([c * x + s * y + bias_m_s2 * DT_S, -s * x + c * y, np.full(len(a), z * DT_S)])
    dtheta_b = np.tile([0.0, 0.0, omega_rad_s * DT_S], (len(a), 1))
    part = {
        "t_s": t,
        "q_wxyz": body_to_world.as_quat(scalar_first=True),
        "v_m_s": np.zeros((len(t), 3)),
    }
    return ImuIncrements(t=t - t[0], dtheta_b=dtheta_b, dv_b=dv_b), part


def test_readings_that_are_the_references_own_leave_no_error() -> None:
    """Held level, every 2 s window ends where it began, to 1e-12 m. Rolled and turning at 0.5 rad/s, to
    0.02 mm: each step's velocity increment is turned at the mean of its two ends' attitudes, a second-
    order rule whose error is about ω²dt²/12 of gravity (5e-6 m/s², 0.01 mm after 2 s)."""
    for omega, bound in ((0.0, 1e-12), (0.5, 2e-5)):
        imu, part = _part(12.0, omega, 0.0)
        errors = window_errors(imu, part, 2.0, 1.0)
        assert len(errors) == 9 and errors.max() < bound, (omega, errors.max())


@pytest.mark.parametrize("omega", [0.0, 0.5])
def test_an_accelerometer_bias_leaves_its_double_integral(omega: float) -> None:
    """A bias of 0.01 m/s² along the body's x. Held level: 0.5 b T² = 20 mm at the end of every 2 s window
    (the trapezoid rule is exact for a constant acceleration: to 1e-12). Rolled 30° and turning about its
    own z at 0.5 rad/s from the angle θ0 at a window's start: the world sees (b cos θ, b cos 30° sin θ)
    horizontally, whose double integral over T is b/ω² (cos θ0 − cos(θ0+ωT) − ωT sin θ0, cos 30° (ωT
    cos θ0 − sin(θ0+ωT) + sin θ0)), to 0.5 % (the steps' second-order terms)."""
    bias, length = 0.01, 2.0
    imu, part = _part(12.0, omega, bias)
    errors = window_errors(imu, part, length, 1.0)
    if omega == 0.0:
        np.testing.assert_allclose(errors, 0.5 * bias * length**2, rtol=1e-12)
        return
    theta0 = omega * np.arange(1.0, 12.0 - length, 1.0)
    wt = omega * length
    ex = np.cos(theta0) - np.cos(theta0 + wt) - wt * np.sin(theta0)
    ey = np.cos(np.radians(30.0)) * (wt * np.cos(theta0) - np.sin(theta0 + wt) + np.sin(theta0))
    np.testing.assert_allclose(errors, bias / omega**2 * np.hypot(ex, ey), rtol=5e-3)


def test_an_imu_off_the_references_point_is_judged_at_its_own_point() -> None:
    """A level unit turning about z at 1 rad/s about the reference's point, which stays still, its IMU
    0.1 m out along the body's x: the IMU reads the centripetal ω²r inwards beside gravity. Against the
    reference's own point each 2 s window starts still where the IMU runs at ω r, and ends the double
    integral of that centripetal force from rest away, r √((1 − cos ωT)² + (ωT − sin ωT)²) = 178.7 mm;
    against the reference moved to the IMU by ``at_imu`` (the velocity C (ω × r)), it ends within 0.1 mm
    (the steps' second-order terms)."""
    omega, arm_m = 1.0, 0.1
    t = 100.0 + DT_S * np.arange(round(12.0 / DT_S) + 1)
    steps = len(t) - 1
    dv_b = np.tile([-(omega**2) * arm_m * DT_S, 0.0, G_M_S2 * DT_S], (steps, 1))
    imu = ImuIncrements(t=t - t[0], dtheta_b=np.tile([0.0, 0.0, omega * DT_S], (steps, 1)), dv_b=dv_b)
    turn = Rotation.from_euler("z", omega * (t - t[0])[:, None])
    part = {"t_s": t, "q_wxyz": turn.as_quat(scalar_first=True), "v_m_s": np.zeros((len(t), 3))}
    at_point = window_errors(imu, part, 2.0, 1.0)
    wt = omega * 2.0
    np.testing.assert_allclose(at_point, arm_m * np.hypot(1.0 - np.cos(wt), wt - np.sin(wt)), rtol=1e-4)
    moved = window_errors(imu, at_imu(part, np.array([arm_m, 0.0, 0.0])), 2.0, 1.0)
    assert moved.max() < 1e-4, moved.max()
