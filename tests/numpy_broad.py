"""BROAD's attitude error metric and the Madgwick filter its example code scores, written without ``sins``.

These are the independent references of ``tests/test_broad_metric.py`` and ``tools/broad_reference.py``:
numpy (and numba for the filter's per-sample loop, which is 100× faster than Python's), in BROAD's own
conventions (quaternions scalar-first ``[w, x, y, z]``, orientation of the IMU in the earth frame), so
that nothing is shared with :mod:`sins.nav.attitude` but the definitions.

* The error metric of Laidig et al., "BROAD — A Benchmark for Robust Inertial Orientation Estimation",
  Data 6(7), 2021, as its example code (github dlaidig/broad, ``example_code/broad_utils.py``) states it:
  the error quaternion ``e = q_est ⊗ q_ref⁻¹`` (in the earth frame), ``total = 2 acos|e_w|``,
  ``heading = 2 atan|e_z / e_w|``, ``inclination = 2 acos √(e_w² + e_z²)``, RMS over the movement rows
  ignoring NaN (rows without an optical reference).
* Madgwick's MARG filter from his 2010 report ("An efficient orientation filter for inertial and
  inertial/magnetic sensor arrays", x-io / University of Bristol): gyro rate of the quaternion less
  ``β`` times the normalised gradient of the accelerometer and magnetometer objective (report eqs.
  25–34, 43–46), one explicit Euler step per sample, renormalised. Earth frame: x along the horizontal
  magnetic field, z up (north-west-up). ``mag_ref_scale`` scales the magnetic reference ``b``: 1 is the
  report; 0.5 is the C code BROAD ran (``example_code/madgwick_mahony_c_code/MadgwickAHRS.cpp``, from
  x-io's 2012 release), which stores ``√(h_x² + h_y²)`` and ``h_z`` in the variables its equations use as
  ``2 b_x`` and ``2 b_z``, so its field reference is half the measured field's unit length and the
  magnetometer weighs less in the gradient than the report's. BROAD also runs it in float32.
"""

from __future__ import annotations

import numba
import numpy as np
from scipy.spatial.transform import Rotation

#: BROAD's Madgwick gain, its TAGP ("trial-agnostic good parameter": the β of its 0.01–0.30 grid with
#: the least mean total RMSE over the 39 trials; ``example_code/out/results_madgwick_average_rmse.json``).
MADGWICK_BETA = 0.12
#: The published figures at that gain (same file, ``trials → <stem> → tagp_parameters``), degrees.
MADGWICK_PUBLISHED_DEG = {
    "05_undisturbed_slow_rotation_with_breaks_B": {
        "total_deg": 1.7858627911654175,
        "heading_deg": 1.632848954589384,
        "inclination_deg": 0.7232921656490349,
    },
    "18_undisturbed_fast_translation_with_breaks_B": {
        "total_deg": 4.461444080112256,
        "heading_deg": 2.868569328563213,
        "inclination_deg": 3.4174490945804177,
    },
}
#: The magnetic reference's scale in the C code BROAD ran (see the module's docstring).
BROAD_C_MAG_REF_SCALE = 0.5
#: Madgwick's earth frame is north-west-up; BROAD turns it 90° about z into ENU (``q_ENU = q_z ⊗ q``).
NWU_TO_ENU_WXYZ = np.array([np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)])


def hamilton(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """``p ⊗ q`` row by row, scalar-first, as the left-multiplication matrix ``L(p)`` applied to ``q``."""
    p, q = np.broadcast_arrays(np.atleast_2d(p), np.atleast_2d(q))
    w, x, y, z = p[:, 0], p[:, 1], p[:, 2], p[:, 3]
    left = np.stack(
        [
            np.stack([w, -x, -y, -z], axis=-1),
            np.stack([x, w, -z, y], axis=-1),
            np.stack([y, z, w, -x], axis=-1),
            np.stack([z, -y, x, w], axis=-1),
        ],
        axis=-2,
    )
    return np.einsum("nij,nj->ni", left, q)


def broad_errors(q_est_wxyz: np.ndarray, q_ref_wxyz: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Total, heading and inclination error per row, rad, by BROAD's definition (scalar-first)."""
    est = q_est_wxyz / np.linalg.norm(q_est_wxyz, axis=1, keepdims=True)
    ref = q_ref_wxyz / np.linalg.norm(q_ref_wxyz, axis=1, keepdims=True)
    e = hamilton(est, ref * np.array([1.0, -1.0, -1.0, -1.0]))
    e = e / np.linalg.norm(e, axis=1, keepdims=True)
    total = 2.0 * np.arccos(np.clip(np.abs(e[:, 0]), 0.0, 1.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        heading = 2.0 * np.arctan(np.abs(e[:, 3] / e[:, 0]))
    inclination = 2.0 * np.arccos(np.clip(np.sqrt(e[:, 0] ** 2 + e[:, 3] ** 2), 0.0, 1.0))
    return total, heading, inclination


def broad_rmse_deg(q_est_wxyz: np.ndarray, q_ref_wxyz: np.ndarray, movement: np.ndarray) -> dict[str, float]:
    """BROAD's three RMS errors over the ``movement`` rows, degrees (NaN rows ignored, as its nanmean)."""
    errors = broad_errors(q_est_wxyz, q_ref_wxyz)
    rms = [float(np.degrees(np.sqrt(np.nanmean(e[np.asarray(movement, bool)] ** 2)))) for e in errors]
    return dict(zip(("total_deg", "heading_deg", "inclination_deg"), rms, strict=True))


def quat_from_acc_mag(acc: np.ndarray, mag: np.ndarray) -> np.ndarray:
    """BROAD's starting state for Madgwick, scalar-first: the rotation whose matrix has the columns
    ``x̂, ŷ, ẑ`` with ``z`` along the accelerometer, ``x = (z × −m) × z`` (the horizontal part of the
    field, negated) and ``y = z × x`` (``quatFromAccMag`` of ``broad_utils.py``)."""
    z = np.asarray(acc, float)
    x = np.cross(np.cross(z, -np.asarray(mag, float)), z)
    y = np.cross(z, x)
    matrix = np.column_stack([v / np.linalg.norm(v) for v in (x, y, z)])
    return Rotation.from_matrix(matrix).as_quat(scalar_first=True)


@numba.njit(cache=True)
def _madgwick_marg(
    gyr: np.ndarray,
    acc: np.ndarray,
    mag: np.ndarray,
    q_start: np.ndarray,
    beta: float,
    dt: float,
    mag_ref_scale: float,
    out: np.ndarray,
) -> None:
    q0, q1, q2, q3 = q_start[0], q_start[1], q_start[2], q_start[3]
    for i in range(gyr.shape[0]):
        gx, gy, gz = gyr[i, 0], gyr[i, 1], gyr[i, 2]
        # q̇ = ½ q ⊗ [0, ω] (report eq. 11).
        d0 = 0.5 * (-q1 * gx - q2 * gy - q3 * gz)
        d1 = 0.5 * (q0 * gx + q2 * gz - q3 * gy)
        d2 = 0.5 * (q0 * gy - q1 * gz + q3 * gx)
        d3 = 0.5 * (q0 * gz + q1 * gy - q2 * gx)
        na = np.sqrt(acc[i, 0] ** 2 + acc[i, 1] ** 2 + acc[i, 2] ** 2)
        nm = np.sqrt(mag[i, 0] ** 2 + mag[i, 1] ** 2 + mag[i, 2] ** 2)
        ax, ay, az = acc[i, 0] / na, acc[i, 1] / na, acc[i, 2] / na
        mx, my, mz = mag[i, 0] / nm, mag[i, 1] / nm, mag[i, 2] / nm
        # h = q ⊗ m ⊗ q*: the field in the earth frame (eq. 45); b keeps its horizontal size (eq. 46).
        r00 = q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3
        r01 = 2.0 * (q1 * q2 - q0 * q3)
        r02 = 2.0 * (q1 * q3 + q0 * q2)
        r10 = 2.0 * (q1 * q2 + q0 * q3)
        r11 = q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3
        r12 = 2.0 * (q2 * q3 - q0 * q1)
        r20 = 2.0 * (q1 * q3 - q0 * q2)
        r21 = 2.0 * (q2 * q3 + q0 * q1)
        r22 = q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3
        hx = r00 * mx + r01 * my + r02 * mz
        hy = r10 * mx + r11 * my + r12 * mz
        hz = r20 * mx + r21 * my + r22 * mz
        bx = mag_ref_scale * np.sqrt(hx * hx + hy * hy)
        bz = mag_ref_scale * hz
        # Objective (eqs. 25 and 29): gravity [0, 0, 1] and b seen in the sensor frame, less the readings.
        f0 = 2.0 * (q1 * q3 - q0 * q2) - ax
        f1 = 2.0 * (q0 * q1 + q2 * q3) - ay
        f2 = 2.0 * (0.5 - q1 * q1 - q2 * q2) - az
        f3 = 2.0 * bx * (0.5 - q2 * q2 - q3 * q3) + 2.0 * bz * (q1 * q3 - q0 * q2) - mx
        f4 = 2.0 * bx * (q1 * q2 - q0 * q3) + 2.0 * bz * (q0 * q1 + q2 * q3) - my
        f5 = 2.0 * bx * (q0 * q2 + q1 * q3) + 2.0 * bz * (0.5 - q1 * q1 - q2 * q2) - mz
        # Gradient Jᵀ f (eqs. 26, 30, 34), the Jacobian's columns written out.
        s0 = -2.0 * q2 * f0 + 2.0 * q1 * f1 - 2.0 * bz * q2 * f3 + (-2.0 * bx * q3 + 2.0 * bz * q1) * f4
        s0 += 2.0 * bx * q2 * f5
        s1 = 2.0 * q3 * f0 + 2.0 * q0 * f1 - 4.0 * q1 * f2 + 2.0 * bz * q3 * f3
        s1 += (2.0 * bx * q2 + 2.0 * bz * q0) * f4 + (2.0 * bx * q3 - 4.0 * bz * q1) * f5
        s2 = -2.0 * q0 * f0 + 2.0 * q3 * f1 - 4.0 * q2 * f2 + (-4.0 * bx * q2 - 2.0 * bz * q0) * f3
        s2 += (2.0 * bx * q1 + 2.0 * bz * q3) * f4 + (2.0 * bx * q0 - 4.0 * bz * q2) * f5
        s3 = 2.0 * q1 * f0 + 2.0 * q2 * f1 + (-4.0 * bx * q3 + 2.0 * bz * q1) * f3
        s3 += (-2.0 * bx * q0 + 2.0 * bz * q2) * f4 + 2.0 * bx * q1 * f5
        ns = np.sqrt(s0 * s0 + s1 * s1 + s2 * s2 + s3 * s3)
        if ns > 0.0:
            d0 -= beta * s0 / ns
            d1 -= beta * s1 / ns
            d2 -= beta * s2 / ns
            d3 -= beta * s3 / ns
        q0, q1, q2, q3 = q0 + d0 * dt, q1 + d1 * dt, q2 + d2 * dt, q3 + d3 * dt
        nq = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
        q0, q1, q2, q3 = q0 / nq, q1 / nq, q2 / nq, q3 / nq
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = q0, q1, q2, q3


def madgwick_marg(
    gyr: np.ndarray,
    acc: np.ndarray,
    mag: np.ndarray,
    q_start_wxyz: np.ndarray,
    beta: float,
    rate_hz: float,
    mag_ref_scale: float = 1.0,
) -> np.ndarray:
    """Madgwick's MARG filter over every row, scalar-first NWU orientations after each row's update.

    Row 0 is already updated from ``q_start_wxyz`` (as BROAD's ``updateBatch``). ``gyr`` rad/s, ``acc``
    and ``mag`` in any unit (normalised), none of them all-zero.
    """
    gyr, acc, mag = (np.ascontiguousarray(a, dtype=float) for a in (gyr, acc, mag))
    out = np.empty((len(gyr), 4))
    q_start = np.asarray(q_start_wxyz, float)
    _madgwick_marg(gyr, acc, mag, q_start / np.linalg.norm(q_start), beta, 1.0 / rate_hz, mag_ref_scale, out)
    return out


def broad_madgwick_enu(
    mat: dict[str, np.ndarray], mag_ref_scale: float = BROAD_C_MAG_REF_SCALE
) -> np.ndarray:
    """BROAD's Madgwick run on one trial (its ``process_data.py``'s ``runMadgwick`` at the TAGP):
    started from the first sample's accelerometer and magnetometer, then turned into ENU; scalar-first."""
    q = madgwick_marg(
        mat["imu_gyr"],
        mat["imu_acc"],
        mat["imu_mag"],
        quat_from_acc_mag(mat["imu_acc"][0], mat["imu_mag"][0]),
        MADGWICK_BETA,
        float(mat["sampling_rate"]),
        mag_ref_scale,
    )
    return hamilton(NWU_TO_ENU_WXYZ, q)
