"""Rotation maths on plain arrays: quaternions, direction cosine matrices, Euler angles.

Pure functions, vectorised over leading axes: a quaternion argument has shape
``(..., 4)`` (scalar-last ``[x, y, z, w]``), a vector ``(..., 3)``, a matrix
``(..., 3, 3)``. Conventions are those of the package docstring; tests check
every function against ``scipy.spatial.transform.Rotation``. Hand-written rather than scipy's:
``tools/bench_rotation.py`` finds scipy's 1.4-26 times slower for products, rotation vectors, Euler angles
and slerp at 1,000-100,000 rotations; its ``from_rotvec`` and ``as_matrix`` are faster, but using them moves
the aided hour-long drive's final yaw by 1.6e-9 relative, beyond the 1e-9 every preset's figures are held
to (``docs/speed.md``, "Rotations").
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


def skew(v: ArrayLike) -> Array:
    """Cross-product matrix ``[v×]`` so that ``skew(a) @ b == cross(a, b)``.

    Parameters
    ----------
    v : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    v = np.asarray(v, dtype=float)
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1] = -v[..., 2]
    out[..., 0, 2] = v[..., 1]
    out[..., 1, 0] = v[..., 2]
    out[..., 1, 2] = -v[..., 0]
    out[..., 2, 0] = -v[..., 1]
    out[..., 2, 1] = v[..., 0]
    return out


def cross(a: ArrayLike, b: ArrayLike) -> Array:
    """Cross product over the last axis, shape (..., 3); several times faster than ``np.cross``."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    ax, ay, az = a[..., 0], a[..., 1], a[..., 2]
    bx, by, bz = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx], axis=-1)


def quat_multiply(p: ArrayLike, q: ArrayLike) -> Array:
    """Hamilton product ``p ⊗ q`` of scalar-last quaternions, shape (..., 4)."""
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    px, py, pz, pw = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    qx, qy, qz, qw = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack(
        [
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
            pw * qw - px * qx - py * qy - pz * qz,
        ],
        axis=-1,
    )


def quat_conjugate(q: ArrayLike) -> Array:
    """Conjugate (the inverse of a unit quaternion), shape (..., 4)."""
    q = np.asarray(q, dtype=float)
    return np.concatenate([-q[..., :3], q[..., 3:]], axis=-1)


def quat_normalize(q: ArrayLike) -> Array:
    """Scale to unit norm with a non-negative scalar part, shape (..., 4)."""
    a = np.asarray(q, dtype=float)
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    return np.where(a[..., 3:] < 0.0, -a, a)


def quat_from_rotvec(rotvec: ArrayLike) -> Array:
    """Quaternion of the rotation by ``|r|`` radians about ``r/|r|``.

    Parameters
    ----------
    rotvec : array_like, shape (..., 3), radians

    Returns
    -------
    ndarray, shape (..., 4)
    """
    r = np.asarray(rotvec, dtype=float)
    angle = np.linalg.norm(r, axis=-1, keepdims=True)
    half = 0.5 * angle
    # sin(x/2)/x by its Taylor series where x is small, to keep full precision.
    small = angle < 1e-4
    a2 = angle * angle
    k = np.where(small, 0.5 - a2 / 48.0 + a2 * a2 / 3840.0, np.sin(half) / np.where(small, 1.0, angle))
    return np.concatenate([k * r, np.cos(half)], axis=-1)


def rotvec_from_quat(q: ArrayLike) -> Array:
    """Rotation vector (radians, angle in [0, π]) of a unit quaternion, shape (..., 3)."""
    q = quat_normalize(q)
    v = q[..., :3]
    s = np.linalg.norm(v, axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(s, q[..., 3:])
    small = s < 1e-8
    w = q[..., 3:]
    k = np.where(small, 2.0 / np.where(small, w, 1.0), angle / np.where(small, 1.0, s))
    return k * v


def turn_between(q0: ArrayLike, q1: ArrayLike) -> Array:
    """Rotation vector of ``q0⁻¹ ⊗ q1``: the turn from attitude ``q0`` to ``q1``, in ``q0``'s body axes
    (radians), shape (..., 3)."""
    return rotvec_from_quat(quat_multiply(quat_conjugate(q0), q1))


def slerp(q0: ArrayLike, q1: ArrayLike, w: ArrayLike) -> Array:
    """The attitude a fraction ``w`` (...,) of the way from ``q0`` to ``q1`` along the shortest turn:
    ``q0 ⊗ exp(w · log(q0⁻¹ ⊗ q1))``, shape (..., 4)."""
    w = np.asarray(w, dtype=float)
    return quat_multiply(q0, quat_from_rotvec(turn_between(q0, q1) * w[..., None]))


def dcm_from_quat(q: ArrayLike) -> Array:
    """Direction cosine matrix of a unit quaternion: ``q_nb`` → ``C_nb``, shape (..., 3, 3)."""
    q = np.asarray(q, dtype=float)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    out = np.empty((*q.shape[:-1], 3, 3))
    out[..., 0, 0] = 1.0 - 2.0 * (yy + zz)
    out[..., 0, 1] = 2.0 * (xy - wz)
    out[..., 0, 2] = 2.0 * (xz + wy)
    out[..., 1, 0] = 2.0 * (xy + wz)
    out[..., 1, 1] = 1.0 - 2.0 * (xx + zz)
    out[..., 1, 2] = 2.0 * (yz - wx)
    out[..., 2, 0] = 2.0 * (xz - wy)
    out[..., 2, 1] = 2.0 * (yz + wx)
    out[..., 2, 2] = 1.0 - 2.0 * (xx + yy)
    return out


def quat_from_dcm(C: ArrayLike) -> Array:
    """Unit quaternion (non-negative scalar part) of a rotation matrix, shape (..., 4).

    Uses the numerically best of the four branches (Shepperd's method) per element.
    """
    C = np.asarray(C, dtype=float)
    tr = C[..., 0, 0] + C[..., 1, 1] + C[..., 2, 2]
    cand = np.stack([C[..., 0, 0], C[..., 1, 1], C[..., 2, 2], tr], axis=-1)
    best = np.argmax(cand, axis=-1)
    q = np.empty((*C.shape[:-2], 4))
    # Each branch divides by the largest of 4w², 4x², 4y², 4z², never near zero.
    for i in range(4):
        sel = best == i
        if not np.any(sel):
            continue
        c = C[sel]
        if i == 3:
            w = 0.5 * np.sqrt(1.0 + c[:, 0, 0] + c[:, 1, 1] + c[:, 2, 2])
            f = 0.25 / w
            q[sel] = np.stack(
                [
                    (c[:, 2, 1] - c[:, 1, 2]) * f,
                    (c[:, 0, 2] - c[:, 2, 0]) * f,
                    (c[:, 1, 0] - c[:, 0, 1]) * f,
                    w,
                ],
                axis=-1,
            )
        else:
            j, k = (i + 1) % 3, (i + 2) % 3
            qi = 0.5 * np.sqrt(1.0 + c[:, i, i] - c[:, j, j] - c[:, k, k])
            f = 0.25 / qi
            row = np.empty((c.shape[0], 4))
            row[:, i] = qi
            row[:, j] = (c[:, j, i] + c[:, i, j]) * f
            row[:, k] = (c[:, k, i] + c[:, i, k]) * f
            row[:, 3] = (c[:, k, j] - c[:, j, k]) * f
            q[sel] = row
    return quat_normalize(q)


def dcm_from_euler(roll: ArrayLike, pitch: ArrayLike, yaw: ArrayLike) -> Array:
    """``C_nb`` from ZYX Euler angles in radians, shape (..., 3, 3)."""
    roll, pitch, yaw = np.broadcast_arrays(
        np.asarray(roll, float), np.asarray(pitch, float), np.asarray(yaw, float)
    )
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    out = np.empty((*roll.shape, 3, 3))
    out[..., 0, 0] = cp * cy
    out[..., 0, 1] = sr * sp * cy - cr * sy
    out[..., 0, 2] = cr * sp * cy + sr * sy
    out[..., 1, 0] = cp * sy
    out[..., 1, 1] = sr * sp * sy + cr * cy
    out[..., 1, 2] = cr * sp * sy - sr * cy
    out[..., 2, 0] = -sp
    out[..., 2, 1] = sr * cp
    out[..., 2, 2] = cr * cp
    return out


def euler_from_dcm(C: ArrayLike) -> tuple[Array, Array, Array]:
    """ZYX Euler angles ``(roll, pitch, yaw)`` in radians from ``C_nb``.

    Roll and yaw are in [-π, π], pitch in [-π/2, π/2]. At pitch = ±90° only
    yaw ∓ roll is defined; this returns roll = 0 and the matching yaw.
    """
    C = np.asarray(C, dtype=float)
    return _euler(
        C[..., 0, 0], C[..., 1, 0], C[..., 2, 0], C[..., 2, 1], C[..., 2, 2], C[..., 0, 1], C[..., 1, 1]
    )


#: How near ±90° pitch, as ``cos(pitch)``, ZYX Euler angles are taken as locked (roll 0, yaw the rest).
GIMBAL_LOCK = 1e-8


def _euler(
    c00: Array, c10: Array, c20: Array, c21: Array, c22: Array, c01: Array, c11: Array
) -> tuple[Array, Array, Array]:
    # atan2 keeps full precision near ±90°, where arcsin loses half the digits. The norms are of a
    # rotation matrix's elements (at most 1): a square root of the squares is within an ulp of hypot's
    # overflow-safe one and four times cheaper (the campaign kernel computes it at every sample).
    pitch = np.arctan2(-c20, np.sqrt(c00 * c00 + c10 * c10))
    # Within 1e-8 of ±90° roll and yaw are one angle: (c21, c22) and (c00, c10) are cos(pitch) long and
    # their rounding (1e-16) turned 1e-12 from the lock into 5e-4 rad of round-trip error; taken as
    # locked there, the error is at most the 1e-8 left out, either side of it.
    locked = c21 * c21 + c22 * c22 < GIMBAL_LOCK**2
    roll = np.where(locked, 0.0, np.arctan2(c21, c22))
    yaw = np.where(locked, np.arctan2(-c01, c11), np.arctan2(c10, c00))
    return roll, pitch, yaw


def quat_from_euler(roll: ArrayLike, pitch: ArrayLike, yaw: ArrayLike) -> Array:
    """``q_nb`` from ZYX Euler angles in radians, shape (..., 4)."""
    roll, pitch, yaw = np.broadcast_arrays(
        np.asarray(roll, float), np.asarray(pitch, float), np.asarray(yaw, float)
    )
    cr, sr = np.cos(0.5 * roll), np.sin(0.5 * roll)
    cp, sp = np.cos(0.5 * pitch), np.sin(0.5 * pitch)
    cy, sy = np.cos(0.5 * yaw), np.sin(0.5 * yaw)
    q = np.stack(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ],
        axis=-1,
    )
    return np.where(q[..., 3:] < 0.0, -q, q)


def euler_from_quat(q: ArrayLike) -> tuple[Array, Array, Array]:
    """ZYX Euler angles ``(roll, pitch, yaw)`` in radians from a unit ``q_nb``.

    The same angles as :func:`euler_from_dcm` of :func:`dcm_from_quat`, from the
    seven matrix elements they need.
    """
    q = np.asarray(q, dtype=float)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return _euler(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y + w * z),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
        2.0 * (x * y - w * z),
        1.0 - 2.0 * (x * x + z * z),
    )


def rotate(q: ArrayLike, v: ArrayLike) -> Array:
    """Rotate vectors by quaternions: ``C(q) @ v``, broadcasting, shape (..., 3)."""
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    u = q[..., :3]
    w = q[..., 3:]
    t = 2.0 * cross(u, v)
    return v + w * t + cross(u, t)


def wrap_angle(angle: ArrayLike) -> Array:
    """Wrap angles in radians to [-π, π]."""
    a = np.asarray(angle, dtype=float)
    # Rounding is several times faster than a float modulo on long series.
    return a - (2.0 * np.pi) * np.round(a / (2.0 * np.pi))


def euler_rates_to_body_rate(
    roll: ArrayLike,
    pitch: ArrayLike,
    roll_rate: ArrayLike,
    pitch_rate: ArrayLike,
    yaw_rate: ArrayLike,
) -> Array:
    """Body angular rate ``omega_nb_b`` (rad/s) from ZYX Euler angles and their rates.

    Singular at pitch = ±90° only in the inverse direction; this direction is
    defined everywhere. Returns shape (..., 3).
    """
    roll, pitch, dr, dp, dy = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (roll, pitch, roll_rate, pitch_rate, yaw_rate))
    )
    sr, cr = np.sin(roll), np.cos(roll)
    sp, cp = np.sin(pitch), np.cos(pitch)
    return np.stack([dr - dy * sp, dp * cr + dy * sr * cp, -dp * sr + dy * cr * cp], axis=-1)


__all__ = [
    "GIMBAL_LOCK",
    "cross",
    "dcm_from_euler",
    "dcm_from_quat",
    "euler_from_dcm",
    "euler_from_quat",
    "euler_rates_to_body_rate",
    "quat_conjugate",
    "quat_from_dcm",
    "quat_from_euler",
    "quat_from_rotvec",
    "quat_multiply",
    "quat_normalize",
    "rotate",
    "rotvec_from_quat",
    "skew",
    "slerp",
    "turn_between",
    "wrap_angle",
]
