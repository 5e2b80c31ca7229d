"""Loosely coupled GNSS/INS: a 15-state error-state Kalman filter on filterpy, closed loop.

The states are errors, estimate minus truth: position ``δr`` (NED, m), velocity ``δv_n`` (m/s),
attitude ``φ`` (rad; the estimated ``C_nb`` is ``(I - [φ×]) C_nb``), gyro bias ``δb_g`` (rad/s)
and accelerometer bias ``δb_a`` (m/s²), the estimated biases minus the true ones. Their dynamics
(the ψ-angle model of Titterton & Weston, ch. 12, with the Earth-rate and transport-rate terms a
vehicle sees)::

    δṙ = δv                                 + (0, 0, ·) ,  δv̇_D gains (2g/R) δr_D
    δv̇ = [f_n×] φ - (2 ω_ie + ω_en) × δv - C_nb δb_a
    φ̇  = -(ω_ie + ω_en) × φ + δω_in(δr, δv) + C_nb δb_g
    δḃ_g, δḃ_a: random walks

The strapdown integrator (:mod:`sins.nav.strapdown`) carries the whole state between measurements,
on readings corrected by the estimated biases; the covariance is propagated every
``propagation_dt_s`` (1 s by default, not at the IMU rate) with the transition
``Φ = I + F T + (F T)²/2`` and the discrete noise ``Q = Qc T + (F Qc + Qc Fᵀ) T²/2 + F Qc Fᵀ T³/3``
built from the mean specific force, attitude and state over that stretch. After each update the
estimated errors are fed back into the integrator and the biases, and the filter's state is reset to
zero (closed loop).

Measurements: a GNSS antenna position (lever arm ``l_b``: ``δr_a = δr + [(C_nb l_b)×] φ``), its
velocity when the receiver gives one, and zero-velocity updates over windows known to be still.
Each is gated on its normalised innovation squared (NIS); rejected fixes are counted (positions and
velocities apart). A fix with a known latency (``GnssFixes.latency_s``) is compared with the solution
kept at its time of validity, less the feedback applied since: the difference is today's error.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from filterpy.kalman import KalmanFilter
from numpy.typing import NDArray
from scipy.stats import chi2

from sins.aiding.gnss import GnssFixes, check_fixes
from sins.core import earth, rotation
from sins.core.series import ImuIncrements, NavSeries
from sins.errors import SinsInputError
from sins.imu import spec
from sins.nav import strapdown

Array = NDArray[np.float64]

#: Slices of the error state.
POS, VEL, ATT, BG, BA = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12), slice(12, 15)
#: Number of states.
N_STATES = 15
#: NIS above this refuses a 3-component measurement (χ²₃ at 99.99 %).
GATE_NIS = float(chi2.ppf(0.9999, 3))


@dataclass(frozen=True)
class FilterConfig:
    """The filter's model of the IMU and its starting uncertainty.

    Attributes
    ----------
    arw_rad_rt_s : gyro white noise (angle random walk), rad/√s
    vrw_mps_rt_s : accelerometer white noise (velocity random walk), m/s/√s
    gyro_bias_sigma : initial 1σ of the gyro biases, rad/s
    accel_bias_sigma : initial 1σ of the accelerometer biases, m/s²
    gyro_bias_walk : random-walk density of the gyro biases, rad/s/√s
    accel_bias_walk : random-walk density of the accelerometer biases, m/s²/√s
    position_sigma_m, velocity_sigma_mps : initial 1σ per axis
    tilt_sigma_rad, heading_sigma_rad : initial 1σ of roll/pitch (``φ_N``, ``φ_E``) and heading (``φ_D``)
    propagation_dt_s : the longest step of the covariance propagation, s
    gate_nis : NIS above which a 3-component measurement is refused (None: no gate)
    zupt_sigma_mps : 1σ of a zero-velocity update, m/s
    zupt_rate_hz : zero-velocity updates per second inside a still window
    reinit_after : when this many position fixes in a row fail the gate, the filter starts again from
        the last of them (its position taken, the covariance reset to the initial one widened by the
        disagreement; the earlier ones count as refused): a divergence, not bad luck (at the gate's
        99.99 %, five failures in a row of a consistent filter have a chance of 1e-20). None: never.
    """

    arw_rad_rt_s: float
    vrw_mps_rt_s: float
    gyro_bias_sigma: float
    accel_bias_sigma: float
    gyro_bias_walk: float = 0.0
    accel_bias_walk: float = 0.0
    position_sigma_m: float = 5.0
    velocity_sigma_mps: float = 0.5
    tilt_sigma_rad: float = float(np.radians(1.0))
    heading_sigma_rad: float = float(np.radians(5.0))
    propagation_dt_s: float = 1.0
    gate_nis: float | None = GATE_NIS
    zupt_sigma_mps: float = 0.01
    zupt_rate_hz: float = 10.0
    reinit_after: int | None = 5

    def __post_init__(self) -> None:
        """Refuse negative densities and sigmas, and steps that are not positive."""
        for name in ("arw_rad_rt_s", "vrw_mps_rt_s", "gyro_bias_sigma", "accel_bias_sigma", "gyro_bias_walk",
                     "accel_bias_walk"):  # fmt: skip
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise SinsInputError(f"filter {name} must be a non-negative number, got {value}")
        for name in ("position_sigma_m", "velocity_sigma_mps", "tilt_sigma_rad", "heading_sigma_rad",
                     "propagation_dt_s", "zupt_sigma_mps", "zupt_rate_hz"):  # fmt: skip
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise SinsInputError(f"filter {name} must be a positive number, got {value}")

    @classmethod
    def for_grade(cls, grade: str | spec.Grade, **overrides: float) -> FilterConfig:
        """The filter tuned to a grade's noise and biases (bias instability as an equivalent random walk)."""
        g = spec.GRADES[grade] if isinstance(grade, str) else grade
        dph = np.radians(1.0) / 3600.0
        tau = g.instability_tau_s
        values: dict[str, float] = {
            "arw_rad_rt_s": np.radians(g.arw_deg_per_rt_h) / 60.0,
            "vrw_mps_rt_s": g.vrw_ug_per_rt_hz * 1e-6 * earth.G0,
            "gyro_bias_sigma": float(np.hypot(g.gyro_bias_dph, g.gyro_turn_on_dph)) * dph,
            "accel_bias_sigma": float(np.hypot(g.accel_bias_mg, g.accel_turn_on_mg)) * 1e-3 * earth.G0,
            "gyro_bias_walk": g.gyro_instability_dph * dph * np.sqrt(2.0 / tau),
            "accel_bias_walk": g.accel_instability_ug * 1e-6 * earth.G0 * np.sqrt(2.0 / tau),
        }
        values.update(overrides)
        floats: dict[str, Any] = {k: float(v) for k, v in values.items()}  # the float fields, by name
        return cls(**floats)

    def initial_covariance(self) -> Array:
        """``P0``: the diagonal of the initial 1σ values, squared."""
        sigma = np.concatenate([
            np.full(3, self.position_sigma_m), np.full(3, self.velocity_sigma_mps),
            [self.tilt_sigma_rad, self.tilt_sigma_rad, self.heading_sigma_rad],
            np.full(3, self.gyro_bias_sigma), np.full(3, self.accel_bias_sigma),
        ])  # fmt: skip
        return np.diag(sigma**2)

    def noise_density(self) -> Array:
        """``Qc``: the continuous process noise, (15, 15)."""
        q = np.concatenate([
            np.zeros(3), np.full(3, self.vrw_mps_rt_s**2), np.full(3, self.arw_rad_rt_s**2),
            np.full(3, self.gyro_bias_walk**2), np.full(3, self.accel_bias_walk**2),
        ])  # fmt: skip
        return np.diag(q)


def error_dynamics(lat: float, h: float, v_n: Array, f_n: Array, C_nb: Array) -> Array:
    """The error state's dynamics matrix ``F`` (15, 15) at one state (module docstring's equations).

    Parameters
    ----------
    lat, h : position, rad and m
    v_n : (3,) velocity, m/s
    f_n : (3,) specific force in n, m/s²
    C_nb : (3, 3) attitude
    """
    r_m, r_n, g = earth.radii_and_gravity_from_sin2(np.sin(lat) ** 2, h)
    rm_h, rn_h = r_m + h, r_n + h
    s, c = np.sin(lat), np.cos(lat)
    w_ie = earth.OMEGA_IE * np.array([c, 0.0, -s])
    w_en = np.array([v_n[1] / rn_h, -v_n[0] / rm_h, -v_n[1] * s / (c * rn_h)])
    F = np.zeros((N_STATES, N_STATES))
    F[POS, VEL] = np.eye(3)
    F[5, 2] = 2.0 * g / np.sqrt(rm_h * rn_h)
    F[VEL, VEL] = -rotation.skew(2.0 * w_ie + w_en)
    F[VEL, ATT] = rotation.skew(f_n)
    F[VEL, BA] = -C_nb
    F[ATT, ATT] = -rotation.skew(w_ie + w_en)
    F[6, 4] = 1.0 / rn_h
    F[7, 3] = -1.0 / rm_h
    F[8, 4] = -s / (c * rn_h)
    F[6, 0] = -earth.OMEGA_IE * s / rm_h
    F[8, 0] = -earth.OMEGA_IE * c / rm_h
    F[ATT, BG] = C_nb
    return F


def discretize(F: Array, Qc: Array, dt: float) -> tuple[Array, Array]:
    """Transition ``Φ`` and discrete noise ``Q`` over ``dt`` (second order in ``F dt``, third in ``Q``)."""
    Fdt = F * dt
    phi = np.eye(len(F)) + Fdt + 0.5 * Fdt @ Fdt
    FQ = F @ Qc
    Q = Qc * dt + (FQ + FQ.T) * (0.5 * dt * dt) + (F @ Qc @ F.T) * (dt**3 / 3.0)
    return phi, Q


def nav_error_state(nav: NavSeries, truth: NavSeries) -> Array:
    """Position, velocity and attitude errors (estimate minus truth) in the filter's terms, (n, 9).

    Position in NED metres at the truth's radii; attitude ``φ`` with ``C_est = (I - [φ×]) C_true``.
    """
    d_r = -earth.ned_offset(truth.lat, truth.lon, truth.h, nav.lat, nav.lon, nav.h)
    dq = rotation.quat_multiply(nav.q_nb, rotation.quat_conjugate(truth.q_nb))
    phi = -rotation.rotvec_from_quat(dq)
    return np.hstack([d_r, nav.v_n - truth.v_n, phi])


@dataclass(frozen=True)
class AidedResult:
    """An aided run.

    Attributes
    ----------
    nav : the corrected solution at every IMU sample time
    t_cov : (m,) times of the covariance records: each propagation step's end and each update, s
    P : (m, 15, 15) the covariance there
    gyro_bias : (m, 3) the estimated gyro biases there, rad/s
    accel_bias : (m, 3) the estimated accelerometer biases there, m/s²
    after_update : (m,) True where the record follows a measurement update
    fix_t : (k,) the GNSS fixes' times
    nis : (k,) each fix's position NIS (before its update)
    accepted : (k,) whether the gate let the fix's position in (its velocity, if any, is gated after
        it, on its own NIS, and is used only with an accepted position)
    zupt_t : (j,) times of the zero-velocity updates
    reinit_t : times of the fixes the filter started again from, after a run of refused ones
    velocity_tried : (k,) whether the fix's velocity met the gate (a receiver's velocity, with an
        accepted position); empty without velocity fixes
    velocity_accepted : (k,) whether the gate let it in
    """

    nav: NavSeries
    t_cov: Array
    P: Array
    gyro_bias: Array
    accel_bias: Array
    after_update: NDArray[np.bool_]
    fix_t: Array
    nis: Array
    accepted: NDArray[np.bool_]
    zupt_t: Array = field(default_factory=lambda: np.zeros(0))
    reinit_t: Array = field(default_factory=lambda: np.zeros(0))
    velocity_tried: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))
    velocity_accepted: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))

    @property
    def rejected(self) -> int:
        """The number of GNSS fixes the gate refused (their positions)."""
        return int(np.count_nonzero(~self.accepted))

    @property
    def velocity_rejected(self) -> int:
        """The number of GNSS velocities the gate refused (of those it met: an accepted fix's)."""
        return int(np.count_nonzero(self.velocity_tried & ~self.velocity_accepted))

    def sigma(self) -> Array:
        """The 1σ of every state at the records, (m, 15)."""
        return np.sqrt(np.einsum("kii->ki", self.P))


# Kinds of the measurement events.
_FIX, _ZUPT = 0, 1


def _events(
    t: Array, fixes: GnssFixes, zupt: Sequence[tuple[float, float]], rate_hz: float
) -> list[tuple[int, int, int]]:
    """``(imu index, kind, row)`` of every measurement, in time order (a fix goes to its nearest sample)."""
    n = len(t) - 1
    out = []
    idx = np.clip(np.searchsorted(t, fixes.t), 1, n)
    nearer = np.abs(t[idx - 1] - fixes.t) < np.abs(t[idx] - fixes.t)
    idx = np.where(nearer, idx - 1, idx)
    out += [(int(k), _FIX, j) for j, k in enumerate(idx)]
    for j, (start, end) in enumerate(zupt):
        if not end > start:
            raise SinsInputError(
                f"zero-velocity window {j + 1}: ends at {end} s, not after its start {start} s"
            )
        times = np.arange(start + 1.0 / rate_hz, end + 1e-9, 1.0 / rate_hz)
        ks = np.unique(np.clip(np.searchsorted(t, times), 1, n))
        out += [(int(k), _ZUPT, j) for k in ks if t[0] < t[k] <= end + 1e-9]
    out.sort()
    return out


def run(
    imu: ImuIncrements,
    fixes: GnssFixes,
    config: FilterConfig,
    initial: strapdown.InitialState,
    *,
    zupt: Sequence[tuple[float, float]] = (),
    P0: Array | None = None,
) -> AidedResult:
    """Integrate an IMU aided by GNSS fixes (and zero-velocity windows), closed loop.

    Parameters
    ----------
    imu : the readings (biased, noisy: what the unit gives)
    fixes : the receiver's fixes within the IMU's span (:func:`sins.aiding.gnss.check_fixes` gates them)
    config : the filter's IMU model and starting uncertainty
    initial : the state the filter starts from at ``imu.t[0]`` (an alignment's, or the truth's)
    zupt : windows ``(start, end)`` in s where the vehicle is known to stand still
    P0 : (15, 15) initial covariance; default ``config.initial_covariance()``

    Returns
    -------
    AidedResult
    """
    t = np.asarray(imu.t, dtype=float)
    check_fixes(fixes, t)
    n = len(imu.dtheta_b)
    step = max(1, round(config.propagation_dt_s / float(np.median(np.diff(t)))))
    loop = _ClosedLoop(imu, fixes, config, initial, P0)
    k = 0
    for idx, kind, row in [*_events(t, fixes, zupt, config.zupt_rate_hz), (n, -1, -1)]:
        while k < idx:
            k_end = min(idx, k + step)
            loop.propagate(k, k_end)
            k = k_end
        if kind < 0:
            break
        if kind == _ZUPT:
            loop.zero_velocity(idx)
        else:
            loop.fix(idx, row)
        loop.feed_back()
        loop.keep_update(idx)
    return loop.result()


class _ClosedLoop:
    """The running filter of :func:`run`: the integrator's state, the estimated biases, the filterpy
    filter, and what is recorded of them."""

    def __init__(
        self,
        imu: ImuIncrements,
        fixes: GnssFixes,
        config: FilterConfig,
        initial: strapdown.InitialState,
        P0: Array | None,
    ) -> None:
        self.imu, self.fixes = imu, fixes
        self.t = t = np.asarray(imu.t, dtype=float)
        self.dt_all = np.diff(t)
        n = len(imu.dtheta_b)
        self.kf = kf = KalmanFilter(dim_x=N_STATES, dim_z=3)
        kf.P = np.array(config.initial_covariance() if P0 is None else P0, dtype=float)
        self.Qc = config.noise_density()
        self.R_pos = np.diag(np.asarray(fixes.sigma_pos_m, dtype=float) ** 2)
        self.R_vel = None if fixes.sigma_vel_mps is None else np.eye(3) * fixes.sigma_vel_mps**2
        self.R_zupt = np.eye(3) * config.zupt_sigma_mps**2
        self.arm_b = np.asarray(fixes.lever_arm_b, dtype=float)
        self.gate = np.inf if config.gate_nis is None else config.gate_nis
        self.state = strapdown.start(initial)
        self.b_g, self.b_a = np.zeros(3), np.zeros(3)
        self.lat, self.lon, self.h = np.empty(n + 1), np.empty(n + 1), np.empty(n + 1)
        self.v, self.q = np.empty((n + 1, 3)), np.empty((n + 1, 4))
        self.lat[0], self.lon[0], self.h[0] = initial.lat, initial.lon, initial.h
        self.v[0], self.q[0] = initial.v_n, self.state[6:10]
        self.rec_t: list[float] = [t[0]]
        self.rec_P: list[Array] = [kf.P.copy()]
        self.rec_bg: list[Array] = [self.b_g.copy()]
        self.rec_ba: list[Array] = [self.b_a.copy()]
        self.rec_upd: list[bool] = [False]
        self.nis = np.full(len(fixes.t), np.nan)
        self.accepted = np.zeros(len(fixes.t), dtype=bool)
        self.zupt_t: list[float] = []
        self.vel_tried = np.zeros(len(fixes.t), dtype=bool)
        self.vel_accepted = np.zeros(len(fixes.t), dtype=bool)
        self.config = config
        self.refused_in_a_row = 0
        self.reinit_t: list[float] = []
        self.k_now = 0  # the sample the integrator's state is at
        # With a latency: the feedback (sample, δr, δv) applied, to bring an older solution's error up to now.
        self.fed_k: list[int] = []
        self.fed_dx: list[Array] = []

    def record(self, time: float, updated: bool) -> None:
        """Keep the covariance and biases at ``time``."""
        self.rec_t.append(time)
        self.rec_P.append(self.kf.P.copy())
        self.rec_bg.append(self.b_g.copy())
        self.rec_ba.append(self.b_a.copy())
        self.rec_upd.append(updated)

    def propagate(self, k: int, k_end: int) -> None:
        """Integrate intervals ``k:k_end`` on bias-corrected readings; propagate the covariance over them."""
        imu, t = self.imu, self.t
        dts = self.dt_all[k:k_end, None]
        dv_b = imu.dv_b[k:k_end] - self.b_a * dts
        seg = ImuIncrements(t=t[k : k_end + 1], dtheta_b=imu.dtheta_b[k:k_end] - self.b_g * dts, dv_b=dv_b)
        states, self.state = strapdown.advance(self.state, seg)
        self.lat[k + 1 : k_end + 1], self.lon[k + 1 : k_end + 1] = states.lat, states.lon
        self.h[k + 1 : k_end + 1] = states.h
        self.v[k + 1 : k_end + 1], self.q[k + 1 : k_end + 1] = states.v_n, states.q_nb
        C_all = rotation.dcm_from_quat(states.q_nb)
        span = float(t[k_end] - t[k])
        f_n = np.einsum("kij,kj->i", C_all, dv_b) / span
        F = error_dynamics(
            float(states.lat.mean()), float(states.h.mean()), states.v_n.mean(axis=0), f_n, C_all.mean(axis=0)
        )
        phi, Q = discretize(F, self.Qc, span)
        self.kf.predict(F=phi, Q=Q)
        self.k_now = k_end
        self.record(float(t[k_end]), False)

    def gated_update(self, z: Array, H: Array, R: Array) -> tuple[float, bool]:
        """Update with ``z`` unless its NIS is above the gate; the NIS and whether it was used."""
        kf = self.kf
        S = H @ kf.P @ H.T + R
        value = float(z @ np.linalg.solve(S, z))
        if value > self.gate:
            return value, False
        kf.x = np.zeros((N_STATES, 1))
        kf.update(z[:, None], R=R, H=H)
        return value, True

    def feed_back(self) -> None:
        """Move the estimated errors into the integrator and the biases; the filter's state back to 0."""
        dx = np.asarray(self.kf.x, dtype=float).ravel()
        nav = strapdown.current(self.state)
        r_m, r_n = earth.radii(nav.lat)
        corrected = strapdown.InitialState(
            lat=nav.lat - dx[0] / (r_m + nav.h),
            lon=nav.lon - dx[1] / ((r_n + nav.h) * np.cos(nav.lat)),
            h=nav.h + dx[2],
            v_n=nav.v_n - dx[VEL],
            q_nb=rotation.quat_multiply(rotation.quat_from_rotvec(dx[ATT]), nav.q_nb),
        )
        self.state = strapdown.moved(self.state, corrected)
        if self.fixes.latency_s > 0:
            self.fed_k.append(self.k_now)
            self.fed_dx.append(dx[:6].copy())
        self.b_g = self.b_g - dx[BG]
        self.b_a = self.b_a - dx[BA]
        self.kf.x = np.zeros((N_STATES, 1))

    def zero_velocity(self, idx: int) -> None:
        """A zero-velocity update at sample ``idx``."""
        nav = strapdown.current(self.state)
        H = np.zeros((3, N_STATES))
        H[:, VEL] = np.eye(3)
        self.gated_update(nav.v_n.copy(), H, self.R_zupt)
        self.zupt_t.append(float(self.t[idx]))

    def fix(self, idx: int, row: int) -> None:
        """GNSS fix ``row`` at sample ``idx``: its antenna position, then its velocity if it has one."""
        t = self.t
        lat, lon, h, v_n, q_nb, fed = self.solution_at(idx, float(self.fixes.t[row] - self.fixes.latency_s))
        C_nb = rotation.dcm_from_quat(q_nb)
        arm_n = C_nb @ self.arm_b
        fixes = self.fixes
        z = earth.ned_offset(lat, lon, h, fixes.lat[row], fixes.lon[row], fixes.h[row]) + arm_n - fed[POS]
        if self.fixes.latency_s == 0:  # the fix moved to the sample's time with the INS velocity
            z = z - v_n * (t[idx] - self.fixes.t[row])
        H = np.zeros((3, N_STATES))
        H[:, POS] = np.eye(3)
        H[:, ATT] = rotation.skew(arm_n)
        self.nis[row], self.accepted[row] = self.gated_update(z, H, self.R_pos)
        self.refused_in_a_row = 0 if self.accepted[row] else self.refused_in_a_row + 1
        if self.config.reinit_after is not None and self.refused_in_a_row >= self.config.reinit_after:
            self.start_again(z, H, float(t[idx]))
            self.accepted[row] = True
        if self.accepted[row] and self.R_vel is not None:
            self.feed_back()
            self.velocity_fix(idx, row)

    def velocity_fix(self, idx: int, row: int) -> None:
        """Fix ``row``'s antenna velocity at sample ``idx`` (after its position)."""
        _, _, _, v_n, q_nb, fed = self.solution_at(idx, float(self.fixes.t[row] - self.fixes.latency_s))
        assert self.R_vel is not None
        C_nb = rotation.dcm_from_quat(q_nb)
        last = max(idx, 1) - 1  # the interval ending at the fix's sample (the first at the start)
        omega_b = self.imu.dtheta_b[last] / self.dt_all[last] - self.b_g
        arm_rate_n = C_nb @ np.cross(omega_b, self.arm_b)
        H = np.zeros((3, N_STATES))
        H[:, VEL] = np.eye(3)
        H[:, ATT] = rotation.skew(arm_rate_n)
        self.vel_tried[row] = True
        _, self.vel_accepted[row] = self.gated_update(
            v_n + arm_rate_n - fed[VEL] - self.fixes.v_n[row], H, self.R_vel
        )

    def solution_at(self, idx: int, t_valid: float) -> tuple[float, float, float, Array, Array, Array]:
        """The solution at a fix's time of validity ``t_valid`` (at most sample ``idx``, now) and the
        feedback applied since (6,: δr, δv; the solution's error then, less it, is its error now).

        Without latency, or with the time at or after now: the current state, no feedback.
        """
        nav = strapdown.current(self.state)
        now = (float(nav.lat), float(nav.lon), float(nav.h), np.asarray(nav.v_n), np.asarray(nav.q_nb))
        if self.fixes.latency_s == 0 or t_valid >= self.t[idx]:
            return (*now, np.zeros(6))
        t = self.t
        j = int(np.clip(np.searchsorted(t[: idx + 1], t_valid), 1, idx))
        w = float(np.clip((t_valid - t[j - 1]) / (t[j] - t[j - 1]), 0.0, 1.0))

        def between(a: Array) -> Array:
            return np.asarray((1.0 - w) * a[j - 1] + w * a[j])

        # Feedback after t_valid counts whole, but the history keeps an update's sample corrected (before
        # now's): at sample j, the interpolation already holds w of it.
        fed = np.zeros(6)
        for k, dx in zip(reversed(self.fed_k), reversed(self.fed_dx), strict=True):
            if t[k] <= t_valid:
                break
            fed += dx * (1.0 - w if k == j < idx else 1.0)
        q = self.q[j] if w >= 0.5 else self.q[j - 1]
        return (
            float(between(self.lat)),
            float(between(self.lon)),
            float(between(self.h)),
            between(self.v),
            q,
            fed,
        )

    def start_again(self, z: Array, H: Array, time: float) -> None:
        """Start the filter again from this fix: the covariance back to its initial value, the position
        and velocity blocks widened by the disagreement ``z``, and the fix taken without the gate."""
        P = self.config.initial_covariance()
        P[POS, POS] += np.diag(z * z)
        P[VEL, VEL] += np.diag((z / max(self.config.propagation_dt_s, 1.0)) ** 2)
        self.kf.P = P
        self.kf.x = np.zeros((N_STATES, 1))
        self.kf.update(z[:, None], R=self.R_pos, H=H)
        self.refused_in_a_row = 0
        self.reinit_t.append(time)

    def keep_update(self, idx: int) -> None:
        """The corrected state at sample ``idx`` replaces the integrated one; the record after it."""
        nav = strapdown.current(self.state)
        sign = -1.0 if nav.q_nb[3] < 0.0 else 1.0  # scalar part >= 0, as the integrator writes them
        self.lat[idx], self.lon[idx], self.h[idx] = nav.lat, nav.lon, nav.h
        self.v[idx], self.q[idx] = nav.v_n, sign * nav.q_nb
        self.record(float(self.t[idx]), True)

    def result(self) -> AidedResult:
        """The run as :func:`run` returns it."""
        fixes = self.fixes
        return AidedResult(
            nav=NavSeries(t=self.t, lat=self.lat, lon=self.lon, h=self.h, v_n=self.v, q_nb=self.q),
            t_cov=np.array(self.rec_t), P=np.array(self.rec_P), gyro_bias=np.array(self.rec_bg),
            accel_bias=np.array(self.rec_ba), after_update=np.array(self.rec_upd),
            fix_t=np.asarray(fixes.t, dtype=float), nis=self.nis, accepted=self.accepted,
            zupt_t=np.array(self.zupt_t), reinit_t=np.array(self.reinit_t),
            velocity_tried=self.vel_tried, velocity_accepted=self.vel_accepted,
        )  # fmt: skip


__all__ = [
    "ATT",
    "BA",
    "BG",
    "GATE_NIS",
    "N_STATES",
    "POS",
    "VEL",
    "AidedResult",
    "FilterConfig",
    "discretize",
    "error_dynamics",
    "nav_error_state",
    "run",
]
