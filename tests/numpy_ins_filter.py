"""An independent loosely coupled GNSS/INS filter in the Earth-fixed frame, numpy only.

The reference against which ``tests/test_aided_reference.py`` judges :mod:`sins.aiding.ekf`. It shares no
code with sins (it imports nothing from it) and differs from it by construction wherever a choice is free:

* **Frame.** Mechanisation and error states in ECEF (``e``), not local-level NED: no radii of curvature, no
  transport rate (it is implicit in ECEF), positions as Cartesian vectors; latitude and height only to
  read fixes in and results out.
* **Gravity.** WGS84 normal gravity (Somigliana, second order in height: the standard model, which is
  also the simulated world's) along the ellipsoid's normal, carried through each 0.1 s step by a central
  field's gradient. (The J2 gravitation field alone, tried first, differs from it by 5e-5 m/s² at 45°:
  2.8 m north and 9.4 m down after 600 s of free inertial navigation on the ideal IMU, against 1.6 mm
  with normal gravity.)
* **Attitude.** A direction-cosine matrix ``C_eb`` advanced by Rodrigues' formula on the coned rotation
  vector and by the Earth's turn about ``z``; not a quaternion.
* **Covariance.** Propagated every ``COV_STEPS`` IMU intervals (0.1 s at 100 Hz, sins: 1 s), with a
  trapezoidal discrete noise ``½ (Φ Qc Φᵀ + Qc) T``; Joseph-form updates.
* **Fixes.** Converted to ECEF; the noise, given per NED axis, rotated into ``e``.

Error state, estimate minus truth (15): ``δr_e``, ``δv_e``, attitude ``ψ`` (``Ĉ_eb = (I - [ψ×]) C_eb``),
``δb_g``, ``δb_a``. Its dynamics, derived from the ECEF mechanisation to first order::

    δṙ = δv
    δv̇ = [f_e×] ψ - 2 [ω_ie×] δv + Γ δr - Ĉ_eb δb_a + Ĉ_eb w_a
    ψ̇  = -[ω_ie×] ψ + Ĉ_eb δb_g - Ĉ_eb w_g
    δḃ_g, δḃ_a: random walks

with ``Γ = (g/|r|) (3 r̂ r̂ᵀ - I)`` the gradient of a central field (the Schuler and vertical terms).
Position fixes of an antenna at ``l_b``: ``δz = δr + [(Ĉ_eb l_b)×] ψ``.

Sources: the equations are textbook (Groves, *Principles of GNSS, Inertial, and Multisensor Integrated
Navigation Systems*, 2nd ed., ch. 2.4, 5.2, 14.2); the code is written here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# WGS84 (NIMA TR8350.2).
A_M = 6378137.0
FLATTENING = 1.0 / 298.257223563
E2 = FLATTENING * (2.0 - FLATTENING)
MU = 3.986004418e14  # m³/s²
GAMMA_EQUATOR, GAMMA_POLE = 9.7803253359, 9.8321849378  # normal gravity on the ellipsoid, m/s²
OMEGA = 7.292115e-5  # rad/s
#: χ² with 3 degrees of freedom at 99.99 %: fixes whose NIS is above it are refused.
GATE_NIS = 21.107576
#: IMU intervals per covariance step.
COV_STEPS = 10

POS, VEL, ATT, BG, BA = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12), slice(12, 15)


def skew(v: np.ndarray) -> np.ndarray:
    """``[v×]``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rodrigues(phi: np.ndarray) -> np.ndarray:
    """The rotation matrix ``exp([φ×])``."""
    angle = math.sqrt(float(phi @ phi))
    K = skew(phi)
    if angle < 1e-8:
        return np.eye(3) + K + 0.5 * K @ K
    return np.eye(3) + math.sin(angle) / angle * K + (1.0 - math.cos(angle)) / angle**2 * K @ K


def rodrigues_batch(phi: np.ndarray) -> np.ndarray:
    """``exp([φ×])`` for each row of ``phi`` (m, 3), (m, 3, 3)."""
    angle2 = np.einsum("ki,ki->k", phi, phi)
    angle = np.sqrt(angle2)
    small = angle < 1e-4
    safe = np.where(small, 1.0, angle)
    # Series below 1e-4 rad, where the next terms are under 1e-17.
    a = np.where(small, 1.0 - angle2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - angle2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    K = np.zeros((len(phi), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -phi[:, 2], phi[:, 1], -phi[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = phi[:, 2], -phi[:, 1], phi[:, 0]
    return np.eye(3) + a[:, None, None] * K + b[:, None, None] * (K @ K)


def dcm_from_quaternion(q_xyzw: np.ndarray) -> np.ndarray:
    """Body-to-navigation matrices from quaternions stored scalar-last, (..., 3, 3)."""
    x, y, z, w = np.moveaxis(np.asarray(q_xyzw, dtype=float), -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
    ], axis=-2)  # fmt: skip


def ecef_from_geodetic(lat: np.ndarray, lon: np.ndarray, h: np.ndarray) -> np.ndarray:
    """ECEF positions, (..., 3) m, from geodetic latitude and longitude (rad) and ellipsoidal height (m)."""
    n = A_M / np.sqrt(1.0 - E2 * np.sin(lat) ** 2)
    return np.stack([
        (n + h) * np.cos(lat) * np.cos(lon), (n + h) * np.cos(lat) * np.sin(lon),
        (n * (1.0 - E2) + h) * np.sin(lat),
    ], axis=-1)  # fmt: skip


def geodetic_from_ecef(r_e: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Latitude, longitude (rad) and height (m) of ECEF positions (fixed-point iteration, to 1e-12 rad)."""
    x, y, z = np.moveaxis(np.asarray(r_e, dtype=float), -1, 0)
    p = np.hypot(x, y)
    lat = np.arctan2(z, p * (1.0 - E2))
    for _ in range(6):  # converges by a factor ~e² per pass
        n = A_M / np.sqrt(1.0 - E2 * np.sin(lat) ** 2)
        h = p / np.cos(lat) - n
        lat = np.arctan2(z, p * (1.0 - E2 * n / (n + h)))
    n = A_M / np.sqrt(1.0 - E2 * np.sin(lat) ** 2)
    return lat, np.arctan2(y, x), p / np.cos(lat) - n


def ned_from_ecef(d_e: np.ndarray, lat: np.ndarray, lon: np.ndarray) -> np.ndarray:
    """ECEF vectors ``d_e`` (k, 3) in the local north, east, down axes at ``lat``, ``lon`` (k,), (k, 3)."""
    sl, cl, so, co = np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon)
    x, y, z = d_e[:, 0], d_e[:, 1], d_e[:, 2]
    return np.stack(
        [-sl * co * x - sl * so * y + cl * z, -so * x + co * y, -cl * co * x - cl * so * y - sl * z], axis=1
    )


def ned_to_ecef(lat: float, lon: float) -> np.ndarray:
    """``C_en``: its columns are the north, east and down directions in ECEF."""
    sl, cl, so, co = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    return np.array([[-sl * co, -so, -cl * co], [-sl * so, co, -cl * so], [cl, 0.0, -sl]])


def normal_gravity(lat: float, h: float) -> float:
    """WGS84 normal gravity (gravitation and centrifugal), m/s²: Somigliana on the ellipsoid, second order
    in height above it (NIMA TR8350.2, eqs. 4-1 and 4-3)."""
    s2 = math.sin(lat) ** 2
    b = A_M * (1.0 - FLATTENING)
    k = b * GAMMA_POLE / (A_M * GAMMA_EQUATOR) - 1.0
    m = OMEGA**2 * A_M**2 * b / MU
    gamma0 = GAMMA_EQUATOR * (1.0 + k * s2) / math.sqrt(1.0 - E2 * s2)
    return gamma0 * (
        1.0 - 2.0 / A_M * (1.0 + FLATTENING + m - 2.0 * FLATTENING * s2) * h + 3.0 * h * h / A_M**2
    )


def gravity_ecef(r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normal gravity at ECEF position ``r`` (along the ellipsoid's normal, down) and its gradient ``Γ``.

    ``Γ = (g/|r|) (3 r̂ r̂ᵀ - I)`` is a central field's: enough to carry gravity over the ~1 m a vehicle
    moves in one covariance step (the ellipsoid's share of the gradient changes g there by < 1e-9 m/s²).
    """
    lat, lon, h = geodetic_from_ecef(r)
    g = normal_gravity(float(lat), float(h))
    rn = float(np.linalg.norm(r))
    u = r / rn
    return ned_to_ecef(float(lat), float(lon))[:, 2] * g, g / rn * (3.0 * np.outer(u, u) - np.eye(3))


@dataclass(frozen=True)
class Tuning:
    """The filter's model of the IMU (densities per √s, biases' σ) and its start's 1σ (NED, as given)."""

    arw: float
    vrw: float
    gyro_bias_sigma: float
    accel_bias_sigma: float
    gyro_bias_walk: float
    accel_bias_walk: float
    position_sigma_m: float
    velocity_sigma_mps: float
    tilt_sigma_rad: float
    heading_sigma_rad: float


@dataclass
class Result:
    """The run: the solution at every IMU time, the covariance and biases after every fix's update."""

    t: np.ndarray
    r_e: np.ndarray
    v_e: np.ndarray
    C_eb: np.ndarray
    fix_t: np.ndarray
    P: np.ndarray
    gyro_bias: np.ndarray
    accel_bias: np.ndarray
    rejected: int
    P_before: np.ndarray

    def geodetic(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Latitude, longitude, height of the solution at every IMU time."""
        return geodetic_from_ecef(self.r_e)


def initial_covariance(tuning: Tuning, C_en: np.ndarray) -> np.ndarray:
    """``P0`` in the ECEF error state from 1σ values given per NED axis (attitude ``ψ = C_en φ_n``)."""
    P = np.zeros((15, 15))
    P[POS, POS] = C_en @ np.diag(np.full(3, tuning.position_sigma_m**2)) @ C_en.T
    P[VEL, VEL] = C_en @ np.diag(np.full(3, tuning.velocity_sigma_mps**2)) @ C_en.T
    att = [tuning.tilt_sigma_rad**2, tuning.tilt_sigma_rad**2, tuning.heading_sigma_rad**2]
    P[ATT, ATT] = C_en @ np.diag(att) @ C_en.T
    P[BG, BG] = np.eye(3) * tuning.gyro_bias_sigma**2
    P[BA, BA] = np.eye(3) * tuning.accel_bias_sigma**2
    return P


def dynamics(r: np.ndarray, f_e: np.ndarray, C_eb: np.ndarray) -> np.ndarray:
    """The error state's ``F`` (15, 15) (module docstring)."""
    w = np.array([0.0, 0.0, OMEGA])
    F = np.zeros((15, 15))
    F[POS, VEL] = np.eye(3)
    F[VEL, POS] = gravity_ecef(r)[1]
    F[VEL, VEL] = -2.0 * skew(w)
    F[VEL, ATT] = skew(f_e)
    F[VEL, BA] = -C_eb
    F[ATT, ATT] = -skew(w)
    F[ATT, BG] = C_eb
    return F


class Filter:
    """The running filter: the ECEF state, the estimated biases and the error state's covariance."""

    def __init__(
        self, r: np.ndarray, v: np.ndarray, C_eb: np.ndarray, P0: np.ndarray, tuning: Tuning, n: int
    ) -> None:
        self.r, self.v, self.C = r.copy(), v.copy(), C_eb.copy()
        # The solution at the n + 1 IMU times (the corrected one where a fix updates it).
        self.out_r, self.out_v, self.out_C = (
            np.empty((n + 1, 3)),
            np.empty((n + 1, 3)),
            np.empty((n + 1, 3, 3)),
        )
        self.out_r[0], self.out_v[0], self.out_C[0] = r, v, C_eb
        self.k = 1
        self.b_g, self.b_a = np.zeros(3), np.zeros(3)
        self.P = P0.copy()
        self.Qc = np.diag(np.concatenate([
            np.zeros(3), np.full(3, tuning.vrw**2), np.full(3, tuning.arw**2),
            np.full(3, tuning.gyro_bias_walk**2), np.full(3, tuning.accel_bias_walk**2),
        ]))  # fmt: skip
        self.prev_dth, self.prev_dv = np.zeros(3), np.zeros(3)
        self.sum_dv_e, self.span = np.zeros(3), 0.0

    def steps(self, dth: np.ndarray, dv: np.ndarray, dt: float) -> None:
        """IMU intervals of one step ``dt``: readings corrected by the bias estimates, coning and sculling
        (two-sample, vectorised over the block), then the ECEF update sample by sample."""
        dth = dth - self.b_g * dt
        dv = dv - self.b_a * dt
        prev_dth = np.vstack([self.prev_dth, dth[:-1]])
        prev_dv = np.vstack([self.prev_dv, dv[:-1]])
        self.prev_dth, self.prev_dv = dth[-1], dv[-1]
        alpha = dth + np.cross(prev_dth, dth) / 12.0
        dv_b = dv + 0.5 * np.cross(dth, dv) + (np.cross(prev_dth, dv) + np.cross(prev_dv, dth)) / 12.0
        turns = rodrigues_batch(alpha)
        turn = OMEGA * dt
        c, s = math.cos(turn), math.sin(turn)
        earth_turn = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        r_block = self.r.copy()
        g_block, gradient = gravity_ecef(r_block)
        for k in range(len(dth)):
            # The body-frame increment into ECEF over an interval in which ECEF turns by ω dt about z.
            dv_e = self.C @ dv_b[k]
            dv_e[0], dv_e[1] = dv_e[0] + 0.5 * turn * dv_e[1], dv_e[1] - 0.5 * turn * dv_e[0]
            g_dt = (g_block + gradient @ (self.r + 0.5 * dt * self.v - r_block)) * dt
            v_mid = self.v + 0.5 * (dv_e + g_dt)  # Coriolis at mid-interval: gravity's share included
            coriolis_dt = np.array([-2.0 * OMEGA * v_mid[1], 2.0 * OMEGA * v_mid[0], 0.0]) * dt
            v_new = self.v + dv_e + g_dt - coriolis_dt
            self.r = self.r + 0.5 * (self.v + v_new) * dt
            self.v = v_new
            self.C = earth_turn @ self.C @ turns[k]
            self.sum_dv_e += dv_e
            self.out_r[self.k], self.out_v[self.k], self.out_C[self.k] = self.r, self.v, self.C
            self.k += 1
        self.span += dt * len(dth)

    def propagate(self) -> None:
        """The covariance over the intervals stepped since the last call, from their mean specific force."""
        if self.span <= 0.0:
            return
        T = self.span
        F = dynamics(self.r, self.sum_dv_e / T, self.C)
        Phi = np.eye(15) + F * T + 0.5 * (F @ F) * T * T
        Qc = self.Qc.copy()
        Qc[VEL, VEL] = self.C @ Qc[VEL, VEL] @ self.C.T  # white noise of the body axes, seen in e
        Qc[ATT, ATT] = self.C @ Qc[ATT, ATT] @ self.C.T
        self.P = Phi @ self.P @ Phi.T + 0.5 * (Phi @ Qc @ Phi.T + Qc) * T
        self.P = 0.5 * (self.P + self.P.T)
        self.sum_dv_e, self.span = np.zeros(3), 0.0

    def fix(self, r_fix: np.ndarray, R: np.ndarray, arm_b: np.ndarray, late_s: float) -> bool:
        """Update with an antenna fix taken ``late_s`` before now; False if the gate refuses it."""
        arm_e = self.C @ arm_b
        z = self.r + arm_e - self.v * late_s - r_fix
        H = np.zeros((3, 15))
        H[:, POS] = np.eye(3)
        H[:, ATT] = skew(arm_e)
        S = H @ self.P @ H.T + R
        if float(z @ np.linalg.solve(S, z)) > GATE_NIS:
            return False
        K = np.linalg.solve(S, H @ self.P).T
        dx = K @ z
        IKH = np.eye(15) - K @ H
        self.P = IKH @ self.P @ IKH.T + K @ R @ K.T
        self.r = self.r - dx[POS]
        self.v = self.v - dx[VEL]
        self.C = rodrigues(dx[ATT]) @ self.C  # Ĉ = (I - [ψ×]) C, so C ≈ exp([ψ×]) Ĉ
        self.b_g = self.b_g - dx[BG]
        self.b_a = self.b_a - dx[BA]
        return True


def run(
    t: np.ndarray,
    dtheta_b: np.ndarray,
    dv_b: np.ndarray,
    fixes: dict[str, np.ndarray],
    start: dict[str, np.ndarray],
    tuning: Tuning,
) -> Result:
    """Integrate increments ``(t[k], t[k+1]]`` (a uniform step) aided by antenna fixes, closed loop.

    Parameters
    ----------
    t : (n+1,) s; dtheta_b, dv_b : (n, 3) the IMU's angle and velocity increments, rad and m/s
    fixes : ``t``, ``lat``, ``lon`` (rad), ``h`` (m) per fix; ``sigma_ned`` (3,) m; ``arm_b`` (3,) m
    start : ``lat``, ``lon``, ``h``, ``v_ned`` (3,), ``C_nb`` (3, 3): the state at ``t[0]``
    tuning : the IMU model and the start's 1σ
    """
    n, dt = len(dtheta_b), float(np.mean(np.diff(t)))
    C_en = ned_to_ecef(float(start["lat"]), float(start["lon"]))
    r0 = ecef_from_geodetic(float(start["lat"]), float(start["lon"]), float(start["h"]))
    nav = Filter(r0, C_en @ start["v_ned"], C_en @ start["C_nb"], initial_covariance(tuning, C_en), tuning, n)
    fix_at = np.clip(np.round((fixes["t"] - t[0]) / dt).astype(int), 0, n)  # the nearest sample
    r_fix = ecef_from_geodetic(fixes["lat"], fixes["lon"], fixes["h"])
    arm_b = np.asarray(fixes["arm_b"], dtype=float)
    rec: dict[str, list[np.ndarray]] = {"P": [], "P_before": [], "b_g": [], "b_a": []}
    rejected, k = 0, 0
    for j in range(len(fix_at) + 1):
        stop = int(fix_at[j]) if j < len(fix_at) else n
        while k < stop:
            k_end = min(stop, k + COV_STEPS)
            nav.steps(dtheta_b[k:k_end], dv_b[k:k_end], dt)
            nav.propagate()
            k = k_end
        if j == len(fix_at):
            break
        rec["P_before"].append(nav.P.copy())
        C = ned_to_ecef(float(fixes["lat"][j]), float(fixes["lon"][j]))
        R = C @ np.diag(np.asarray(fixes["sigma_ned"], dtype=float) ** 2) @ C.T
        rejected += not nav.fix(r_fix[j], R, arm_b, float(t[k] - fixes["t"][j]))
        nav.out_r[k], nav.out_v[k], nav.out_C[k] = nav.r, nav.v, nav.C
        rec["P"].append(nav.P.copy())
        rec["b_g"].append(nav.b_g.copy())
        rec["b_a"].append(nav.b_a.copy())
    return Result(
        t=t, r_e=nav.out_r, v_e=nav.out_v, C_eb=nav.out_C, fix_t=np.asarray(fixes["t"], dtype=float),
        P=np.array(rec["P"]), gyro_bias=np.array(rec["b_g"]), accel_bias=np.array(rec["b_a"]),
        rejected=rejected, P_before=np.array(rec["P_before"]),
    )  # fmt: skip
