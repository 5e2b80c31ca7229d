"""Open-loop attitude from angular rates, and its error against a reference orientation.

:func:`propagate` integrates body rates from a starting attitude with no aiding: what a gyro alone
tells of the orientation. :func:`attitude_errors` measures an estimate against a reference the way the
BROAD benchmark does (Laidig et al., Data 6(7), 2021): the error quaternion ``q_est ⊗ q_ref*`` is
expressed in the navigation frame, its whole angle is the *total* error, its part about the vertical
the *heading* error and the rest the *inclination* error. The vertical is the navigation frame's z
axis, so the figures are the same in NED and in ENU.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numba
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@numba.njit(cache=True, nogil=True)
def _propagate(dtheta: Array, q0: Array, frame: Array, out: Array) -> None:
    """``out[k] = exp(-frame[k-1]) ⊗ out[k-1] ⊗ exp(dtheta[k-1])``: each step's rotation vector applied in
    body axes, and the navigation frame's own turn (``frame``, rotation vectors in its axes) taken out."""
    x, y, z, w = q0[0], q0[1], q0[2], q0[3]
    out[0, 0], out[0, 1], out[0, 2], out[0, 3] = x, y, z, w
    for k in range(1, out.shape[0]):
        fx, fy, fz = -frame[k - 1, 0], -frame[k - 1, 1], -frame[k - 1, 2]
        fa = np.sqrt(fx * fx + fy * fy + fz * fz)
        if fa > 0.0:
            fs = np.sin(0.5 * fa) / fa
            ex, ey, ez, ew = fs * fx, fs * fy, fs * fz, np.cos(0.5 * fa)
            # q ← e ⊗ q
            x, y, z, w = (
                ew * x + ex * w + ey * z - ez * y,
                ew * y - ex * z + ey * w + ez * x,
                ew * z + ex * y - ey * x + ez * w,
                ew * w - ex * x - ey * y - ez * z,
            )
        rx, ry, rz = dtheta[k - 1, 0], dtheta[k - 1, 1], dtheta[k - 1, 2]
        angle = np.sqrt(rx * rx + ry * ry + rz * rz)
        # sin(a/2)/a by its series where a is small: full precision at rest.
        if angle < 1e-4:
            s = 0.5 - angle * angle / 48.0
        else:
            s = np.sin(0.5 * angle) / angle
        c = np.cos(0.5 * angle)
        dx, dy, dz = s * rx, s * ry, s * rz
        # q ← q ⊗ dq (the body turns by the step's rotation, expressed in its own axes).
        nx = w * dx + x * c + y * dz - z * dy
        ny = w * dy - x * dz + y * c + z * dx
        nz = w * dz + x * dy - y * dx + z * c
        nw = w * c - x * dx - y * dy - z * dz
        norm = np.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
        x, y, z, w = nx / norm, ny / norm, nz / norm, nw / norm
        out[k, 0], out[k, 1], out[k, 2], out[k, 3] = x, y, z, w


def propagate(t: Array, omega_nb_b: Array, q0_nb: Array) -> Array:
    """The attitude ``q_nb`` at every time from body rates and a starting attitude, open loop.

    Parameters
    ----------
    t : (n,) s, increasing
    omega_nb_b : (n, 3) rad/s, the body's rate relative to the navigation frame, sampled at ``t``
        (rate form: instantaneous values; each step uses the mean of its two end samples)
    q0_nb : (4,) the attitude at ``t[0]``, scalar-last

    Returns
    -------
    (n, 4) unit quaternions ``q_nb``, scalar-last; row 0 is ``q0_nb`` normalised.
    """
    t = np.asarray(t, dtype=float)
    omega = np.asarray(omega_nb_b, dtype=float)
    if omega.shape != (len(t), 3):
        raise ValueError(f"omega_nb_b has shape {omega.shape}; expected ({len(t)}, 3)")
    dtheta = 0.5 * (omega[:-1] + omega[1:]) * np.diff(t)[:, None]
    return propagate_increments(dtheta, q0_nb)


def propagate_increments(dtheta_b: Array, q0_nb: Array, frame_turn_n: Array | None = None) -> Array:
    """The attitude ``q_nb`` after each of ``n`` steps of body rotation, open loop.

    Each step is the rotation by its rotation vector in body axes, ``q ← q ⊗ exp(dθ)``: exact for a
    rate of fixed direction over the step (the coning within a step is the increments' business).
    With ``frame_turn_n``, the increments are the body's turn in inertial space (a gyro's) and the
    navigation frame turns too (Earth's rate, ``ω_in`` times the step): ``q ← exp(−φ) ⊗ q ⊗ exp(dθ)``.

    Parameters
    ----------
    dtheta_b : (n, 3) rad, each step's rotation of the body (relative to the navigation frame, or to
        inertial space with ``frame_turn_n``)
    q0_nb : (4,) the attitude before the first step, scalar-last
    frame_turn_n : (n, 3) or (3,) rad, the navigation frame's turn over each step in its own axes, or None

    Returns
    -------
    (n + 1, 4) unit quaternions ``q_nb``, scalar-last; row 0 is ``q0_nb`` normalised.
    """
    dtheta = np.ascontiguousarray(dtheta_b, dtype=float).reshape(-1, 3)
    frame = np.zeros((len(dtheta), 3)) if frame_turn_n is None else np.asarray(frame_turn_n, dtype=float)
    frame = np.ascontiguousarray(np.broadcast_to(frame, (len(dtheta), 3)))
    q0 = np.asarray(q0_nb, dtype=float)
    out = np.empty((len(dtheta) + 1, 4))
    _propagate(dtheta, q0 / np.linalg.norm(q0), frame, out)
    return out


def attitude_errors(q_est_nb: Array, q_ref_nb: Array) -> tuple[Array, Array, Array]:
    """Total, heading and inclination error of each estimate against its reference, rad.

    The error quaternion ``e = q_est ⊗ q_ref*`` rotates the reference's axes into the estimate's,
    expressed in the navigation frame. ``total = 2 acos |e_w|``; ``heading = 2 atan |e_z / e_w|``,
    its rotation about the vertical; ``inclination = 2 acos √(e_w² + e_z²)``, the tilt left once
    the heading part is taken out. Rows with a non-finite reference give NaN.

    Parameters
    ----------
    q_est_nb, q_ref_nb : (n, 4) scalar-last quaternions (normalised here)

    Returns
    -------
    total, heading, inclination : (n,) rad, each in [0, π]
    """
    q_est = np.asarray(q_est_nb, dtype=float)
    q_ref = np.asarray(q_ref_nb, dtype=float)
    q_est = q_est / np.linalg.norm(q_est, axis=1, keepdims=True)
    q_ref = q_ref / np.linalg.norm(q_ref, axis=1, keepdims=True)
    # e = q_est ⊗ conj(q_ref), scalar-last.
    ax, ay, az, aw = q_est[:, 0], q_est[:, 1], q_est[:, 2], q_est[:, 3]
    bx, by, bz, bw = -q_ref[:, 0], -q_ref[:, 1], -q_ref[:, 2], q_ref[:, 3]
    ew = aw * bw - ax * bx - ay * by - az * bz
    ez = aw * bz + ax * by - ay * bx + az * bw
    norm = np.sqrt(
        ew * ew
        + ez * ez
        + (aw * bx + ax * bw + ay * bz - az * by) ** 2
        + (aw * by - ax * bz + ay * bw + az * bx) ** 2
    )
    ew, ez = ew / norm, ez / norm
    total = 2.0 * np.arccos(np.clip(np.abs(ew), 0.0, 1.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        heading = 2.0 * np.arctan(np.abs(ez / ew))
    inclination = 2.0 * np.arccos(np.clip(np.sqrt(ew * ew + ez * ez), 0.0, 1.0))
    return total, heading, inclination


@dataclass(frozen=True)
class AttitudeRmse:
    """RMS attitude errors over the judged rows, degrees (BROAD's figures), and how many rows."""

    total_deg: float
    heading_deg: float
    inclination_deg: float
    rows: int

    def to_dict(self) -> dict[str, float | int]:
        """The figures as a JSON object."""
        return asdict(self)


def attitude_rmse(q_est_nb: Array, q_ref_nb: Array, judged: NDArray[np.bool_] | None = None) -> AttitudeRmse:
    """:func:`attitude_errors` as RMS over the rows where ``judged`` holds and both are finite.

    Raises
    ------
    ValueError
        when no row is judged.
    """
    total, heading, inclination = attitude_errors(q_est_nb, q_ref_nb)
    ok = np.isfinite(total) & np.isfinite(heading) & np.isfinite(inclination)
    if judged is not None:
        ok &= np.asarray(judged, dtype=bool)
    if not ok.any():
        raise ValueError("no rows to judge the attitude on (no finite reference where judged)")
    rms = lambda e: float(np.degrees(np.sqrt(np.mean(e[ok] ** 2))))  # noqa: E731
    return AttitudeRmse(rms(total), rms(heading), rms(inclination), int(ok.sum()))


__all__ = [
    "AttitudeRmse",
    "attitude_errors",
    "attitude_rmse",
    "propagate",
    "propagate_increments",
]
