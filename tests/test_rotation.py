"""Property tests of ``sins.core.rotation`` against ``scipy.spatial.transform.Rotation``.

scipy is the independent reference throughout: it shares the conventions of the
package (scalar-last quaternions, Hamilton product, ``from_euler("ZYX", [yaw, pitch,
roll])`` for ``C_nb``) but not its code. Quaternions are compared up to sign, since
``q`` and ``-q`` are the same rotation.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from scipy.spatial.transform import Rotation

from sins.core import rotation

SETTINGS = settings(max_examples=200, deadline=None)

EPS = np.finfo(float).eps
DEG = np.pi / 180.0

# ---------------------------------------------------------------- strategies


def _floats(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


def _vec(n: int, lo: float = -1.0, hi: float = 1.0) -> st.SearchStrategy[np.ndarray]:
    # Tuples of floats mapped to arrays: several times cheaper to draw than hnp.arrays.
    return st.tuples(*[_floats(lo, hi)] * n).map(lambda t: np.array(t, dtype=float))


#: Unit vectors, from a cube sample kept away from the origin.
unit_vectors = _vec(3).filter(lambda v: np.linalg.norm(v) > 0.1).map(lambda v: v / np.linalg.norm(v))

#: Unit quaternions of either sign of the scalar part.
quaternions = _vec(4).filter(lambda q: np.linalg.norm(q) > 0.1).map(lambda q: q / np.linalg.norm(q))

#: Rotation angles: tiny ones (Taylor branches), ordinary ones, and ones just below π.
tiny_angles = _floats(-12.0, -4.0).map(lambda e: 10.0**e)
near_pi_angles = _floats(-9.0, -4.0).map(lambda e: np.pi - 10.0**e)
angles = st.one_of(tiny_angles, _floats(1e-4, np.pi - 1e-4), near_pi_angles)

rotvecs = st.builds(lambda axis, angle: axis * angle, unit_vectors, angles)
tiny_rotvecs = st.builds(lambda axis, angle: axis * angle, unit_vectors, tiny_angles)

vectors = _vec(3, -1e3, 1e3)

#: ZYX Euler angles (roll, pitch, yaw) over the whole range of each angle.
eulers = st.tuples(_floats(-np.pi, np.pi), _floats(-np.pi / 2, np.pi / 2), _floats(-np.pi, np.pi))
#: The same, away from gimbal lock: |pitch| <= 89°.
eulers_regular = st.tuples(_floats(-np.pi, np.pi), _floats(-89 * DEG, 89 * DEG), _floats(-np.pi, np.pi))

#: Leading batch shapes, including the scalar case ().
batch_shapes = hnp.array_shapes(min_dims=0, max_dims=3, min_side=1, max_side=4)


# ------------------------------------------------------------------- helpers


def quat_distance(q: np.ndarray, q_ref: np.ndarray) -> np.ndarray:
    """Distance between quaternions up to sign, over the last axis."""
    q, q_ref = np.asarray(q), np.asarray(q_ref)
    return np.minimum(np.linalg.norm(q - q_ref, axis=-1), np.linalg.norm(q + q_ref, axis=-1))


def angle_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a - b`` wrapped to [-π, π], computed without ``sins``."""
    d = np.asarray(a) - np.asarray(b)
    return np.arctan2(np.sin(d), np.cos(d))


def cross_tol(a: np.ndarray, b: np.ndarray) -> float:
    """Bound on the difference of two cross products computed as differences of two products."""
    # Each component a_i b_j - a_j b_i: three roundings of terms ≤ max|a|·max|b| per side, plus
    # a floor in the subnormal range where relative bounds no longer hold.
    return 8 * EPS * np.abs(a).max() * np.abs(b).max() + 1e-300


def scipy_euler(roll: float, pitch: float, yaw: float) -> Rotation:
    return Rotation.from_euler("ZYX", [yaw, pitch, roll])


# ------------------------------------------------------------ skew and cross


@SETTINGS
@given(vectors, vectors)
def test_skew_is_cross_product_matrix(a: np.ndarray, b: np.ndarray) -> None:
    S = rotation.skew(a)
    # Antisymmetric, with exactly the components of a (no arithmetic involved).
    np.testing.assert_array_equal(S, -S.T)
    np.testing.assert_array_equal([S[2, 1], S[0, 2], S[1, 0]], a)
    # Each component is a difference of two products: a few ulp of max|a|·max|b| apart.
    assert np.all(np.abs(S @ b - np.cross(a, b)) <= cross_tol(a, b))


@SETTINGS
@given(vectors, vectors)
def test_cross_matches_numpy(a: np.ndarray, b: np.ndarray) -> None:
    assert np.all(np.abs(rotation.cross(a, b) - np.cross(a, b)) <= cross_tol(a, b))


@SETTINGS
@given(batch_shapes, batch_shapes)
def test_skew_and_cross_vectorised(shape_a: tuple[int, ...], shape_b: tuple[int, ...]) -> None:
    rng = np.random.default_rng(101)
    a = rng.standard_normal((*shape_a, 3))
    b = rng.standard_normal((*shape_b, 3))
    try:
        expected = np.cross(a, b)
    except ValueError:  # shapes that do not broadcast
        return
    got = rotation.cross(a, b)
    assert got.shape == expected.shape
    # Unit-scale inputs: a few ulp of 1.
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-14)
    S = rotation.skew(a)
    assert S.shape == (*shape_a, 3, 3)
    np.testing.assert_allclose((S @ a[..., None])[..., 0], 0.0, atol=1e-14)  # a × a = 0


# ------------------------------------------------------------- quaternions


def test_hamilton_basis_products() -> None:
    # i⊗j = k, j⊗k = i, k⊗i = j and i⊗i = -1 fix the Hamilton (not JPL) convention.
    i, j, k, one = np.eye(4)
    np.testing.assert_array_equal(rotation.quat_multiply(i, j), k)
    np.testing.assert_array_equal(rotation.quat_multiply(j, k), i)
    np.testing.assert_array_equal(rotation.quat_multiply(k, i), j)
    np.testing.assert_array_equal(rotation.quat_multiply(j, i), -k)
    np.testing.assert_array_equal(rotation.quat_multiply(i, i), -one)


@SETTINGS
@given(quaternions, quaternions)
def test_quat_multiply_matches_scipy(p: np.ndarray, q: np.ndarray) -> None:
    expected = (Rotation.from_quat(p) * Rotation.from_quat(q)).as_quat()
    # Sums of four products of unit-scale numbers, both sides: a few ulp of 1.
    assert quat_distance(rotation.quat_multiply(p, q), expected) < 1e-15 * 4


@SETTINGS
@given(quaternions, quaternions, _floats(0.1, 10.0), _floats(0.1, 10.0))
def test_quat_multiply_is_bilinear(p: np.ndarray, q: np.ndarray, s: float, t: float) -> None:
    # Scaling either factor scales the product (the product is not normalised): a few ulp of s*t.
    np.testing.assert_allclose(
        rotation.quat_multiply(s * p, t * q),
        s * t * rotation.quat_multiply(p, q),
        rtol=0,
        atol=8 * EPS * s * t,
    )


@SETTINGS
@given(quaternions)
def test_quat_conjugate_is_inverse(q: np.ndarray) -> None:
    qc = rotation.quat_conjugate(q)
    # Exact: only signs change.
    np.testing.assert_array_equal(qc, [-q[0], -q[1], -q[2], q[3]])
    # scipy's inverse, up to sign; a few ulp of 1.
    assert quat_distance(qc, Rotation.from_quat(q).inv().as_quat()) < 4e-15
    # q ⊗ q* is the identity: |q|² rounded, a few ulp of 1.
    np.testing.assert_allclose(rotation.quat_multiply(q, qc), [0, 0, 0, 1], atol=4e-15)
    np.testing.assert_allclose(rotation.quat_multiply(qc, q), [0, 0, 0, 1], atol=4e-15)


@SETTINGS
@given(quaternions, _floats(-3.0, 3.0))
def test_quat_normalize(q: np.ndarray, log_scale: float) -> None:
    scaled = q * 10.0**log_scale
    n = rotation.quat_normalize(scaled)
    # Unit norm to a few ulp of 1.
    assert abs(np.linalg.norm(n) - 1.0) < 4 * EPS
    # Non-negative scalar part, same rotation as scipy's (which normalises on input).
    assert n[3] >= 0.0
    assert quat_distance(n, Rotation.from_quat(scaled).as_quat()) < 4 * EPS
    # Canonical: q and -q give the same result (exactly, the arithmetic is sign-symmetric),
    # except for half-turns (w = 0) where both signs have a non-negative scalar part.
    if n[3] != 0.0:
        np.testing.assert_array_equal(rotation.quat_normalize(-scaled), n)


# ----------------------------------------------------------- rotation vectors


@SETTINGS
@given(rotvecs)
def test_quat_from_rotvec_matches_scipy(r: np.ndarray) -> None:
    q = rotation.quat_from_rotvec(r)
    expected = Rotation.from_rotvec(r).as_quat()
    # from_rotvec keeps w = cos(|r|/2) >= 0 for |r| < π, so no sign ambiguity.
    # Vector part relative to its own size (it is ~|r|/2, down to 5e-13): a few ulp,
    # which only holds where the Taylor series replaces sin(x/2)/x at small angles.
    vec_err = np.linalg.norm(q[:3] - expected[:3])
    assert vec_err <= 8 * EPS * np.linalg.norm(expected[:3])
    # Scalar part cos(|r|/2): a few ulp of 1.
    assert abs(q[3] - expected[3]) <= 2 * EPS
    # Result is a unit quaternion to a few ulp.
    assert abs(np.linalg.norm(q) - 1.0) <= 4 * EPS


@SETTINGS
@given(rotvecs)
def test_rotvec_from_quat_matches_scipy(r: np.ndarray) -> None:
    q = Rotation.from_rotvec(r).as_quat()
    got = rotation.rotvec_from_quat(q)
    expected = Rotation.from_quat(q).as_rotvec()
    angle = np.linalg.norm(r)
    # Relative precision even at 1e-12 rad: 2·atan2(s, w)/s and 2/w are both a few ulp
    # accurate; near π the angle is still well conditioned (atan2 with s ≈ 1).
    assert np.linalg.norm(got - expected) <= 16 * EPS * angle
    # The original rotation vector is recovered as well; |r| < π so no sign flip.
    assert np.linalg.norm(got - r) <= 16 * EPS * angle


@SETTINGS
@given(rotvecs, rotvecs)
def test_turn_between_matches_scipy(r0: np.ndarray, r1: np.ndarray) -> None:
    """The turn from q0 to q1 in q0's axes: scipy's (R0⁻¹ R1).as_rotvec(), to the rotation vector's own
    precision (its angle is at most π, so 16 ulp of π)."""
    q0, q1 = Rotation.from_rotvec(r0).as_quat(), Rotation.from_rotvec(r1).as_quat()
    got = rotation.turn_between(q0, q1)
    expected = (Rotation.from_quat(q0).inv() * Rotation.from_quat(q1)).as_rotvec()
    if np.linalg.norm(expected) > np.pi - 1e-6:  # a half turn: either sign of the axis is the same turn
        return
    assert np.linalg.norm(got - expected) <= 64 * EPS * np.pi


@SETTINGS
@given(rotvecs)
def test_rotvec_round_trip(r: np.ndarray) -> None:
    # Relative to |r|, including tiny angles: the Taylor branches of both functions.
    back = rotation.rotvec_from_quat(rotation.quat_from_rotvec(r))
    assert np.linalg.norm(back - r) <= 16 * EPS * np.linalg.norm(r)


@SETTINGS
@given(tiny_rotvecs)
def test_tiny_rotvec_first_order(r: np.ndarray) -> None:
    # For |r| <= 1e-4 the quaternion is [r/2, 1] up to |r|³/48 (sin(x/2) = x/2 - x³/48 + ...)
    # in the vector part and |r|²/8 in the scalar part, plus a few ulp.
    q = rotation.quat_from_rotvec(r)
    a2 = float(r @ r)
    assert np.linalg.norm(q[:3] - 0.5 * r) <= (a2 / 48 + 4 * EPS) * np.sqrt(a2)
    assert abs(q[3] - 1.0) <= a2 / 8 + EPS


def test_zero_rotation() -> None:
    # The identity both ways, exactly, also inside a batch (0/0 must not appear at |r| = 0).
    np.testing.assert_array_equal(rotation.quat_from_rotvec(np.zeros(3)), [0.0, 0.0, 0.0, 1.0])
    np.testing.assert_array_equal(rotation.rotvec_from_quat([0.0, 0.0, 0.0, 1.0]), np.zeros(3))
    np.testing.assert_array_equal(rotation.rotvec_from_quat([0.0, 0.0, 0.0, -2.0]), np.zeros(3))
    batch = np.array([[0.0, 0.0, 0.0], [1e-12, 0.0, 0.0], [0.0, 2.0, 0.0]])
    q = rotation.quat_from_rotvec(batch)
    np.testing.assert_array_equal(q[0], [0.0, 0.0, 0.0, 1.0])
    # Unit-scale angles: a few ulp, relative to |r| as everywhere above.
    np.testing.assert_allclose(rotation.rotvec_from_quat(q), batch, rtol=1e-15, atol=0)


# Hypothesis readily produces w = 0 exactly; the spurious warning is covered by its own test below.
@pytest.mark.filterwarnings("ignore:divide by zero encountered:RuntimeWarning")
@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning")
@SETTINGS
@given(quaternions, _floats(-2.0, 2.0))
def test_rotvec_from_quat_canonical(q: np.ndarray, log_scale: float) -> None:
    # Any scale and either sign give the same rotation vector with angle in [0, π].
    r = rotation.rotvec_from_quat(q)
    r_neg = rotation.rotvec_from_quat(-q * 10.0**log_scale)
    assert np.linalg.norm(r) <= np.pi + 4 * EPS
    # Unit-scale angles: a few ulp of π, unless the angle is π itself, where r and -r coincide.
    if np.linalg.norm(r) < np.pi - 1e-6:
        np.testing.assert_allclose(r_neg, r, rtol=0, atol=1e-14)
    expected = Rotation.from_quat(q).as_rotvec()
    assert np.linalg.norm(r - expected) < 1e-14 or np.linalg.norm(r) > np.pi - 1e-6


@pytest.mark.filterwarnings("ignore:divide by zero encountered:RuntimeWarning")
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_rotvec_from_quat_half_turn(axis: int) -> None:
    q = np.zeros(4)
    q[axis] = 1.0  # w = 0: a rotation by π
    r = rotation.rotvec_from_quat(q)
    # Exact axis, angle π to an ulp (2·atan2(1, 0)); the sign of a half turn is arbitrary.
    np.testing.assert_allclose(np.abs(r), np.pi * np.eye(3)[axis], rtol=0, atol=2 * EPS * np.pi)


def test_rotvec_from_quat_half_turn_no_warning() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rotation.rotvec_from_quat([0.0, 1.0, 0.0, 0.0])


# ----------------------------------------------------------------- matrices


@SETTINGS
@given(quaternions)
def test_dcm_from_quat_matches_scipy(q: np.ndarray) -> None:
    C = rotation.dcm_from_quat(q)
    # Quadratic forms of unit-scale components: a few ulp of 1.
    np.testing.assert_allclose(C, Rotation.from_quat(q).as_matrix(), rtol=0, atol=4e-15)
    # Orthonormal with determinant +1, to a few ulp of 1.
    np.testing.assert_allclose(C @ C.T, np.eye(3), rtol=0, atol=1e-14)
    assert abs(np.linalg.det(C) - 1.0) < 1e-14


@SETTINGS
@given(st.one_of(quaternions, rotvecs.map(lambda r: Rotation.from_rotvec(r).as_quat())))
def test_quat_from_dcm_matches_scipy(q: np.ndarray) -> None:
    # The rotvec strategy adds rotations near π (trace ≈ -1), the x/y/z branches of Shepperd.
    C = Rotation.from_quat(q).as_matrix()
    got = rotation.quat_from_dcm(C)
    assert got[3] >= 0.0
    # Shepperd's method divides by the largest component (>= 1/2): a few ulp of 1.
    assert quat_distance(got, Rotation.from_matrix(C).as_quat()) < 1e-14
    assert quat_distance(got, q) < 1e-14


def test_quat_from_dcm_every_branch() -> None:
    # Half-turns about x, y, z (each branch of Shepperd's method) and the identity.
    for axis in range(3):
        r = np.zeros(3)
        r[axis] = np.pi
        q = rotation.quat_from_dcm(Rotation.from_rotvec(r).as_matrix())
        expected = np.zeros(4)
        expected[axis] = 1.0
        assert quat_distance(q, expected) < 1e-15
    np.testing.assert_allclose(rotation.quat_from_dcm(np.eye(3)), [0, 0, 0, 1], atol=0)


# ------------------------------------------------------------------- Euler


@SETTINGS
@given(st.tuples(_floats(-10.0, 10.0), _floats(-10.0, 10.0), _floats(-10.0, 10.0)))
def test_dcm_from_euler_matches_scipy(angles: tuple[float, float, float]) -> None:
    roll, pitch, yaw = angles  # any angles, also beyond ±π: the formula needs no wrapping
    C = rotation.dcm_from_euler(roll, pitch, yaw)
    # Products of three sines/cosines: a few ulp of 1.
    np.testing.assert_allclose(C, scipy_euler(roll, pitch, yaw).as_matrix(), rtol=0, atol=4e-15)
    # The documented composition Rz(yaw) @ Ry(pitch) @ Rx(roll), built from elementary rotations.
    Rz = Rotation.from_rotvec([0, 0, yaw]).as_matrix()
    Ry = Rotation.from_rotvec([0, pitch, 0]).as_matrix()
    Rx = Rotation.from_rotvec([roll, 0, 0]).as_matrix()
    np.testing.assert_allclose(C, Rz @ Ry @ Rx, rtol=0, atol=4e-15)


@SETTINGS
@given(st.tuples(_floats(-10.0, 10.0), _floats(-10.0, 10.0), _floats(-10.0, 10.0)))
def test_quat_from_euler_matches_scipy(angles: tuple[float, float, float]) -> None:
    roll, pitch, yaw = angles
    q = rotation.quat_from_euler(roll, pitch, yaw)
    assert q[3] >= 0.0
    # Products of three half-angle sines/cosines: a few ulp of 1.
    assert quat_distance(q, scipy_euler(roll, pitch, yaw).as_quat()) < 4e-15
    # Consistent with the matrix form.
    np.testing.assert_allclose(
        rotation.dcm_from_quat(q), rotation.dcm_from_euler(roll, pitch, yaw), atol=1e-14
    )


def _check_euler_against_scipy(got: tuple[np.ndarray, ...], rot: Rotation, pitch: float) -> None:
    yaw_ref, pitch_ref, roll_ref = rot.as_euler("ZYX")
    roll, pitch_got, yaw = got
    # Roll and yaw come from atan2 of entries scaled by cos(pitch) and pitch from arcsin
    # with slope 1/cos(pitch): errors ~eps/cos(pitch) ≤ 57 eps at 89°, on both sides.
    tol = 64 * EPS / np.cos(pitch)
    assert abs(pitch_got - pitch_ref) <= tol
    assert abs(angle_diff(roll, roll_ref)) <= tol
    assert abs(angle_diff(yaw, yaw_ref)) <= tol
    # Documented ranges (closed at -π: an atan2 of a -0.0 entry may give exactly -π).
    assert -np.pi <= roll <= np.pi and -np.pi <= yaw <= np.pi
    assert -np.pi / 2 <= pitch_got <= np.pi / 2


@SETTINGS
@given(eulers_regular)
def test_euler_from_dcm_matches_scipy(angles: tuple[float, float, float]) -> None:
    roll, pitch, yaw = angles
    rot = scipy_euler(roll, pitch, yaw)
    _check_euler_against_scipy(rotation.euler_from_dcm(rot.as_matrix()), rot, pitch)
    # And the input angles themselves come back (same error budget).
    got = rotation.euler_from_dcm(rot.as_matrix())
    assert np.all(np.abs(angle_diff(np.array(got), [roll, pitch, yaw])) <= 64 * EPS / np.cos(pitch))


@SETTINGS
@given(eulers_regular)
def test_euler_from_quat_matches_scipy(angles: tuple[float, float, float]) -> None:
    roll, pitch, yaw = angles
    rot = scipy_euler(roll, pitch, yaw)
    q = rot.as_quat()
    _check_euler_against_scipy(rotation.euler_from_quat(q), rot, pitch)
    _check_euler_against_scipy(rotation.euler_from_quat(-q), rot, pitch)


@pytest.mark.parametrize("pitch", [np.pi / 2, -np.pi / 2])
@pytest.mark.parametrize("roll, yaw", [(0.0, 0.0), (0.3, 1.1), (-2.0, 0.7), (1.0, -2.5), (3.0, 3.0)])
def test_euler_at_gimbal_lock_from_own_dcm(roll: float, pitch: float, yaw: float) -> None:
    # Matrices from dcm_from_euler keep cos(pitch) = 6e-17 as a common factor of the
    # entries that fix roll and yaw, so the split is recovered.
    C = rotation.dcm_from_euler(roll, pitch, yaw)
    C_back = rotation.dcm_from_euler(*rotation.euler_from_dcm(C))
    # arcsin of a value within a few ulp of 1 loses half the digits: sqrt(eps) ≈ 1.5e-8.
    np.testing.assert_allclose(C_back, C, rtol=0, atol=1e-7)


@pytest.mark.parametrize("source", ["scipy_matrix", "quaternion"])
@pytest.mark.parametrize("pitch", [np.pi / 2, -np.pi / 2])
def test_euler_at_gimbal_lock_reproduces_matrix(source: str, pitch: float) -> None:
    # At exactly ±90° only roll ∓ yaw is defined; whatever pair is returned must give the same C_nb.
    worst = 0.0
    for roll, yaw in [(0.3, 1.1), (-2.0, 0.7), (1.0, -2.5), (2.9, -0.4)]:
        rot = scipy_euler(roll, pitch, yaw)
        C = rot.as_matrix()
        if source == "scipy_matrix":
            got = rotation.euler_from_dcm(C)
        else:
            got = rotation.euler_from_quat(rot.as_quat())
        assert abs(abs(got[1]) - np.pi / 2) < 1e-7  # pitch itself: sqrt(eps) as above
        worst = max(worst, np.abs(rotation.dcm_from_euler(*got) - C).max())
    # Same sqrt(eps) budget as above; the bug gives errors of order 0.1 to 1.
    assert worst < 1e-7


# ------------------------------------------------------------------ rotate


@SETTINGS
@given(quaternions, vectors)
def test_rotate_matches_scipy(q: np.ndarray, v: np.ndarray) -> None:
    expected = Rotation.from_quat(q).apply(v)
    # A rotation preserves length; a few ulp relative to |v| (both methods do ~10 flops).
    tol = 32 * EPS * max(np.linalg.norm(v), 1e-300)
    assert np.linalg.norm(rotation.rotate(q, v) - expected) <= tol
    assert np.linalg.norm(rotation.dcm_from_quat(q) @ v - expected) <= tol


# -------------------------------------------------------------- wrap_angle


@SETTINGS
@given(_floats(-1e3, 1e3))
@example(np.pi)
@example(-np.pi)
@example(3 * np.pi)
@example(-3 * np.pi)
@example(np.nextafter(np.pi, np.inf))
@example(np.nextafter(-np.pi, -np.inf))
@example(0.0)
def test_wrap_angle(x: float) -> None:
    y = rotation.wrap_angle(x)
    # Documented range [-π, π]; removing k·2π with k ≈ |x|/2π rounds at the ulp of |x|, so the
    # result may leave the range by that much (3e-13 at |x| = 1e4; nothing for |x| < 30).
    tol = 2 * EPS * abs(x)
    assert -np.pi - tol <= y <= np.pi + tol
    # Same angle: x - y is a multiple of 2π up to the same rounding (ulp of |x| + π).
    k = (x - y) / (2 * np.pi)
    assert abs(k - np.round(k)) * 2 * np.pi <= 4 * EPS * (abs(x) + np.pi)
    # Idempotent: a result inside [-π, π] is a fixed point, exactly.
    if abs(y) <= np.pi:
        assert rotation.wrap_angle(y) == y


@SETTINGS
@given(_floats(-np.pi, np.pi))
def test_wrap_angle_keeps_angles_in_range(x: float) -> None:
    # Angles already in [-π, π] (both ends included) come back unchanged, bit for bit.
    assert rotation.wrap_angle(x) == x


def test_wrap_angle_array() -> None:
    x = np.array([[-7.0, -np.pi, 0.0], [1.0, 3 * np.pi, 7.0], [-20.0, 20.0, 1e3]])
    y = rotation.wrap_angle(x)
    assert y.shape == x.shape
    expected = np.array(
        [
            [-7.0 + 2 * np.pi, -np.pi, 0.0],
            [1.0, np.pi, 7.0 - 2 * np.pi],
            [-20 + 6 * np.pi, 20 - 6 * np.pi, 0.0],
        ]
    )
    expected[2, 2] = 1e3 - 159 * 2 * np.pi
    # ±π are both valid images of 3π, so compare as angles; one rounding of k·2π: a few ulp of |x|.
    np.testing.assert_allclose(angle_diff(y, expected), 0.0, atol=4 * EPS * 1e3)
    assert np.all(np.abs(y) <= np.pi + 4 * EPS * np.abs(x))


# ------------------------------------------------------------ Euler rates


@SETTINGS
@given(eulers, st.tuples(_floats(-2.0, 2.0), _floats(-2.0, 2.0), _floats(-2.0, 2.0)))
def test_euler_rates_to_body_rate_finite_difference(
    angles: tuple[float, float, float], rates: tuple[float, float, float]
) -> None:
    roll, pitch, yaw = angles
    dr, dp, dy = rates
    dt = 1e-5

    def attitude(t: float) -> Rotation:
        return scipy_euler(roll + dr * t, pitch + dp * t, yaw + dy * t)

    # C' = C [omega_b ×]: log(R(0)⁻¹ R(±dt)) = ±dt·omega + dt²/2·omega' + O(dt³); the central
    # difference cancels the dt² term.
    r0_inv = attitude(0.0).inv()
    forward = (r0_inv * attitude(dt)).as_rotvec()
    backward = (r0_inv * attitude(-dt)).as_rotvec()
    omega_fd = (forward - backward) / (2 * dt)
    got = rotation.euler_rates_to_body_rate(roll, pitch, dr, dp, dy)
    # Truncation ~dt²·|rates|³ ≈ 1e-9 for rates ≤ 2 rad/s; rounding of the relative rotation
    # (~1e-16 rad) divided by 2·dt ≈ 1e-11. Also fine at pitch = ±90°.
    np.testing.assert_allclose(got, omega_fd, rtol=0, atol=1e-8)


# -------------------------------------------------------- vectorised shapes


@SETTINGS
@given(batch_shapes)
def test_vectorised_over_leading_axes(shape: tuple[int, ...]) -> None:
    rng = np.random.default_rng(20240611)
    q = rng.standard_normal((*shape, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    p = rng.standard_normal((*shape, 4))
    p /= np.linalg.norm(p, axis=-1, keepdims=True)
    v = rng.standard_normal((*shape, 3))
    r = rng.standard_normal((*shape, 3))
    roll = rng.uniform(-np.pi, np.pi, shape)
    pitch = rng.uniform(-1.5, 1.5, shape)
    yaw = rng.uniform(-np.pi, np.pi, shape)
    rates = rng.standard_normal((3, *shape))

    flat_q = q.reshape(-1, 4)
    rot_q = Rotation.from_quat(flat_q)
    rot_e = Rotation.from_euler("ZYX", np.stack([yaw, pitch, roll], axis=-1).reshape(-1, 3))
    n = flat_q.shape[0]

    def same(got: np.ndarray, expected: np.ndarray, atol: float = 1e-14) -> None:
        # Element-wise the same results as the scalar reference: a few ulp of 1.
        assert got.shape == expected.shape
        np.testing.assert_allclose(got, expected, rtol=0, atol=atol)

    def same_quat(got: np.ndarray, expected_flat: np.ndarray) -> None:
        assert got.shape == (*shape, 4)
        assert np.all(quat_distance(got.reshape(-1, 4), expected_flat) < 1e-14)

    same_quat(rotation.quat_multiply(p, q), (Rotation.from_quat(p.reshape(-1, 4)) * rot_q).as_quat())
    same(rotation.quat_conjugate(q), np.concatenate([-q[..., :3], q[..., 3:]], axis=-1))
    qn = rotation.quat_normalize(3.0 * q)
    same_quat(qn, flat_q)
    assert np.all(qn[..., 3] >= 0.0)
    same_quat(rotation.quat_from_rotvec(r), Rotation.from_rotvec(r.reshape(-1, 3)).as_quat())
    same(rotation.rotvec_from_quat(q).reshape(-1, 3), rot_q.as_rotvec())
    assert rotation.rotvec_from_quat(q).shape == (*shape, 3)
    same(rotation.dcm_from_quat(q), rot_q.as_matrix().reshape((*shape, 3, 3)))
    same_quat(rotation.quat_from_dcm(rot_q.as_matrix().reshape((*shape, 3, 3))), flat_q)
    same(rotation.dcm_from_euler(roll, pitch, yaw), rot_e.as_matrix().reshape((*shape, 3, 3)))
    same_quat(rotation.quat_from_euler(roll, pitch, yaw), rot_e.as_quat())
    for got in (
        rotation.euler_from_dcm(rot_e.as_matrix().reshape((*shape, 3, 3))),
        rotation.euler_from_quat(rot_e.as_quat().reshape((*shape, 4))),
    ):
        assert all(g.shape == shape for g in got)
        # |pitch| ≤ 1.5 rad: eps/cos(1.5) ≈ 14 eps of the angles.
        np.testing.assert_allclose(angle_diff(np.stack(got), np.stack([roll, pitch, yaw])), 0.0, atol=1e-13)
    same(rotation.rotate(q, v).reshape(-1, 3), rot_q.apply(v.reshape(-1, 3)).reshape(n, 3))
    assert rotation.wrap_angle(roll * 3).shape == shape
    body = rotation.euler_rates_to_body_rate(roll, pitch, *rates)
    assert body.shape == (*shape, 3)
    for idx in np.ndindex(*shape):
        same(body[idx], rotation.euler_rates_to_body_rate(roll[idx], pitch[idx], *(x[idx] for x in rates)))


def test_broadcasting_of_scalars_and_batches() -> None:
    # One quaternion applied to many vectors, and scalar Euler angles mixed with arrays.
    rng = np.random.default_rng(7)
    q = rng.standard_normal(4)
    q /= np.linalg.norm(q)
    v = rng.standard_normal((5, 2, 3))
    got = rotation.rotate(q, v)
    assert got.shape == (5, 2, 3)
    # Unit-scale vectors: a few ulp of 1.
    np.testing.assert_allclose(
        got, Rotation.from_quat(q).apply(v.reshape(-1, 3)).reshape(5, 2, 3), atol=1e-14
    )
    yaw = np.linspace(-3, 3, 7)
    C = rotation.dcm_from_euler(0.1, -0.2, yaw)
    assert C.shape == (7, 3, 3)
    np.testing.assert_allclose(
        C, Rotation.from_euler("ZYX", [[y, -0.2, 0.1] for y in yaw]).as_matrix(), atol=4e-15
    )


@pytest.mark.parametrize("distance", [0.0, 1e-14, 1e-12, 1e-10, 1e-9, 1e-8, 2e-8, 1e-7, 1e-6, 1e-3])
def test_euler_angles_round_trip_near_the_lock(distance: float) -> None:
    """``distance`` rad from ±90° pitch, ZYX Euler angles and back: within 1e-7 rad of scipy's rotation
    (the lock's threshold, 1e-8, with the rounding it trades against); the lock had been taken at 1e-12,
    where 1e-12 from it gave 5e-4 rad. The compiled metrics (``sins.nav.metrics``) read the same angles."""
    from sins.nav import metrics

    rng = np.random.default_rng(7)
    yaw, roll = rng.uniform(-3.0, 3.0, (2, 100))
    sign = rng.choice([-1.0, 1.0], 100)
    truth = Rotation.from_euler("ZYX", np.column_stack([yaw, sign * (np.pi / 2 - distance), roll]))
    angles = rotation.euler_from_quat(truth.as_quat())
    back = Rotation.from_quat(rotation.quat_from_euler(*angles))
    assert np.max((back * truth.inv()).magnitude()) < 1e-7
    compiled = metrics._euler_angles(np.ascontiguousarray(truth.as_quat()))
    np.testing.assert_allclose(compiled, np.column_stack(angles), rtol=0, atol=1e-12)
