"""The online estimate of a recording's gyro bias: what a vehicle that stays within reach knows.

A gyro bias tilts the attitude the gyro integrates, the tilt turns gravity into a horizontal specific
force, and the velocity that force integrates to grows as ``g b t²/2`` (4.4 m/s after 30 s for 1e-3
rad/s), while the true velocity of a vehicle that stays within reach stays within a few m/s. Every
:data:`UPDATE_S` the bias's change from a prior is estimated again by least squares on the velocity so
far, in a frame levelled by the first readings of specific force (its heading arbitrary: only the
horizontal components are used): the true velocity as noise, the initial tilt and velocity and the
accelerometer's bias as nuisances, the change regularised towards zero by the prior's spread. Readings
are corrected by the last estimate made before them (causal). Which prior, and when this estimate is
used, is :mod:`sins.compensation.unit_bias`'s.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from sins.core import rotation
from sins.core.series import ImuIncrements

Array = NDArray[np.float64]

#: How often the online estimate is made again, s.
UPDATE_S = 2.0
#: Normal gravity's size for the velocity model, m/s² (the latitude is not known; only the horizontal
#: components are used, where its size scales the tilt's effect by less than 0.3 %).
_G = 9.81
#: The rows of specific force the online rule levels its frame by.
_LEVELLING_ROWS = 20


def estimate(
    imu: ImuIncrements,
    track: Array,
    prior: Array,
    sigma: Array,
    sigma_v_mps: float,
    sigma_accel_mps2: float,
    components: Array | None = None,
    across: float = 1.0,
) -> Array:
    """The bias (n, 3) rad/s of each step of ``imu`` (corrected increments): ``track`` before the first
    update, then ``prior`` plus the estimate every :data:`UPDATE_S` from the readings before it, its
    change from ``prior`` held to ``sigma`` (3,), the true velocity taken as noise of ``sigma_v_mps`` and
    the accelerometer's bias held to ``sigma_accel_mps2`` (module docstring). With ``components`` (k, 3),
    the bias's prior is their mixture instead, each of width ``sigma``, equally likely beforehand: each
    one's estimate is made as above and they are weighed by their evidence so far
    (:func:`_mixture`). ``across`` ≥ 1 widens the bias change's prior across gravity alone (the body's
    up at the start, as levelling finds it): ``sigma`` along it, ``across`` times wider in every direction
    orthogonal to it in ``sigma``'s units (:func:`_bias_precision`)."""
    dt = np.diff(imu.t)
    step = max(1, round(UPDATE_S / float(np.median(dt))))
    at = np.arange(step, len(imu.t), step)
    if not len(at):
        return track
    first = slice(0, _LEVELLING_ROWS)  # all that levelling reads of the specific force
    c0 = attitude_dcm(levelled(imu.dv_b[first] / dt[first, None])[None, :])[0]
    v, s, i_s = _velocity_terms(imu.dtheta_b - prior * dt[:, None], imu.dv_b, dt, c0, at)
    t = (imu.t - imu.t[0])[at]
    zero, one = np.zeros(len(at)), np.ones(len(at))
    # Unknowns: the true velocity at the start (2), the initial tilt (2), the bias change (3), the
    # accelerometer's bias (3); two rows (east, north) per update time. A bias change δ tilts the frame
    # by S δ (S = ∫ C dt), which moves the velocity by g ∫ S δ; an accelerometer bias by -∫ C b_a = -S b_a.
    rows_e = np.column_stack([-one, zero, zero, -_G * t, _G * i_s[:, 1], s[:, 0]])
    rows_n = np.column_stack([zero, -one, _G * t, zero, -_G * i_s[:, 0], s[:, 1]])
    design = np.stack([rows_e, rows_n], axis=1) / sigma_v_mps  # (m, 2, 10)
    target = v[:, :2] / sigma_v_mps
    prior_rows = np.diag(
        np.r_[1 / 2.0, 1 / 2.0, 1 / 0.2, 1 / 0.2, 1 / sigma, np.full(3, 1 / sigma_accel_mps2)]
    )
    # Running sums of the normal equations: the estimate at each update from the rows before it.
    lam0 = prior_rows.T @ prior_rows  # the unknowns' prior precision
    if across != 1.0:
        lam0[4:7, 4:7] = _bias_precision(np.asarray(sigma, dtype=float), c0[2], across)
    grams = lam0 + np.cumsum(np.einsum("mra,mrb->mab", design, design), axis=0)
    rhss = np.cumsum(np.einsum("mra,mr->ma", design, target), axis=0)
    if components is None:
        change = np.linalg.solve(grams, rhss[:, :, None])[:, 4:7, 0]
    else:
        squares = np.cumsum(np.einsum("mr,mr->m", target, target))
        change = _mixture(grams, rhss, squares, lam0, components - prior)
    out = track.copy()
    ends = np.r_[at[1:], len(out)]
    out[at[0] :] = np.repeat(prior + change, ends - at, axis=0)
    return out


def _bias_precision(sigma: Array, up_b: Array, across: float) -> Array:
    """The bias change's prior precision (3, 3) for covariance ``D (k² I − (k² − 1) ũũᵀ) D``, ``D =
    diag(sigma)``, ``ũ = D up_b / |D up_b|``, ``k = across``: the variance along ``up_b`` (the body's up)
    that ``sigma`` gives it, ``k²`` times more across it. Along gravity the bias turns only the heading,
    which the velocity barely sees, so a wider prior there lets it wander; across it the velocity pins
    it down."""
    d_inv = np.diag(1.0 / sigma)
    u = sigma * up_b
    u = u / np.linalg.norm(u)
    inner = np.eye(3) / across**2 + (1.0 - 1.0 / across**2) * np.outer(u, u)
    return np.asarray(d_inv @ inner @ d_inv, dtype=float)


def _mixture(grams: Array, rhss: Array, squares: Array, lam0: Array, centres: Array) -> Array:
    """The bias change (m, 3) at each update under a prior that is a mixture of Gaussians: the unknowns'
    prior precision ``lam0`` (10, 10) about means that differ in the bias change alone (``centres``,
    (k, 3)). Each component's posterior mean solves the same normal equations (``grams`` (m, 10, 10),
    ``rhss`` (m, 10): the rows so far) from its own prior mean; its evidence is the Gaussian marginal
    likelihood of the rows so far (``squares``: their targets' sum of squares), up to a factor all
    components share (one precision, so one determinant). The estimate is the posterior mixture's mean:
    each component's weighted by its evidence."""
    mu = np.zeros((len(centres), lam0.shape[0]))
    mu[:, 4:7] = centres
    eta = (mu @ lam0)[None, :, :] + rhss[:, None, :]  # (m, k, 10): Λ₀μ + Hᵀy
    # One factorisation per update for every component (its right-hand sides side by side): memory of
    # (m, 10, k), where broadcasting the matrices to each component would make (m, k, 10, 10).
    post = np.linalg.solve(grams, eta.transpose(0, 2, 1)).transpose(0, 2, 1)
    # -2 log evidence = yᵀy + μᵀΛ₀μ − ηᵀ G⁻¹ η (the common log-determinants left out)
    prior_term = np.einsum("ka,ab,kb->k", mu, lam0, mu)
    q = squares[:, None] + prior_term[None, :] - np.einsum("mka,mka->mk", eta, post)
    w = np.exp(-0.5 * (q - q.min(axis=1, keepdims=True)))
    w /= w.sum(axis=1, keepdims=True)
    return np.asarray(np.einsum("mk,mka->ma", w, post[:, :, 4:7]), dtype=float)


@numba.njit(cache=True, nogil=True)
def _velocity_terms(
    dtheta: Array, dv: Array, dt: Array, c0: Array, at: NDArray[np.int64]
) -> tuple[Array, Array, Array]:  # pragma: no cover  (compiled)
    """One pass over the steps: the attitude ``C`` (body to the levelled frame) the increments ``dtheta``
    integrate to from ``c0``, the velocity the specific force's increments ``dv`` make in it less
    gravity's, ``S = ∫ C dt`` and ``∫ S dt``; returned at the step boundaries ``at``: velocity (m, 3),
    ``S`` and ``∫ S dt`` (m, 3, 3). Scalar arithmetic throughout (no array is made within the loop)."""
    m = len(at)
    v_at = np.zeros((m, 3))
    s_at = np.zeros((m, 3, 3))
    is_at = np.zeros((m, 3, 3))
    c = c0.copy()
    turned = np.empty((3, 3))
    v = np.zeros(3)
    s = np.zeros((3, 3))
    i_s = np.zeros((3, 3))
    j = 0
    for k in range(len(dt) + 1):
        while j < m and at[j] == k:
            v_at[j, :] = v
            s_at[j, :, :] = s
            is_at[j, :, :] = i_s
            j += 1
        if k == len(dt):
            break
        h = dt[k]
        px, py, pz = dtheta[k, 0], dtheta[k, 1], dtheta[k, 2]
        ax, ay, az = dv[k, 0], dv[k, 1], dv[k, 2]
        # The step's velocity increment turned by half the step's own turn (first order), into the frame.
        mx = ax + 0.5 * (py * az - pz * ay)
        my = ay + 0.5 * (pz * ax - px * az)
        mz = az + 0.5 * (px * ay - py * ax)
        for r in range(3):
            v[r] += c[r, 0] * mx + c[r, 1] * my + c[r, 2] * mz
            for q in range(3):
                i_s[r, q] += s[r, q] * h + 0.5 * c[r, q] * h * h
                s[r, q] += c[r, q] * h
        v[2] -= _G * h
        # C ← C Exp(φ), Rodrigues: Exp(φ) = I + a [φ]× + b [φ]×², a = sin θ/θ, b = (1 − cos θ)/θ².
        th2 = px * px + py * py + pz * pz
        if th2 > 1e-24:
            th = np.sqrt(th2)
            a, b = np.sin(th) / th, (1.0 - np.cos(th)) / th2
        else:
            a, b = 1.0, 0.5
        e00, e11, e22 = (
            1.0 - b * (py * py + pz * pz),
            1.0 - b * (px * px + pz * pz),
            1.0 - b * (px * px + py * py),
        )
        e01, e10 = -a * pz + b * px * py, a * pz + b * px * py
        e02, e20 = a * py + b * px * pz, -a * py + b * px * pz
        e12, e21 = -a * px + b * py * pz, a * px + b * py * pz
        for r in range(3):
            c0r, c1r, c2r = c[r, 0], c[r, 1], c[r, 2]
            turned[r, 0] = c0r * e00 + c1r * e10 + c2r * e20
            turned[r, 1] = c0r * e01 + c1r * e11 + c2r * e21
            turned[r, 2] = c0r * e02 + c1r * e12 + c2r * e22
        c[:, :] = turned
    return v_at, s_at, is_at


def levelled(force: Array) -> Array:
    """A scalar-last quaternion of the body in a frame with z up, levelled by the mean of the first
    :data:`_LEVELLING_ROWS` readings of specific force (0.1 s at 200 Hz; its heading arbitrary)."""
    up = force[: max(1, min(len(force), _LEVELLING_ROWS))].mean(axis=0)
    z = up / np.linalg.norm(up)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.asarray(rotation.quat_from_dcm(np.array([x, y, z])), dtype=float)


def attitude_dcm(q: Array) -> Array:
    """Direction cosine matrices of scalar-last quaternions (body to frame)."""
    return np.asarray(rotation.dcm_from_quat(q), dtype=float)


__all__ = ["UPDATE_S", "attitude_dcm", "estimate", "levelled"]
