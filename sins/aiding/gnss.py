"""A GNSS receiver simulated from the truth: position (and velocity) fixes, their errors, outages.

Each fix reports the antenna, ``lever_arm_b`` from the IMU in the body frame, with white noise and an
optional first-order Gauss–Markov error per NED axis (exact discretisation, started from its
stationary law). A latency makes a fix stamped ``t`` report the antenna at ``t - latency_s``; the
fixes carry it (``GnssFixes.latency_s``, unless ``compensate_latency`` is off) and the filter compares
each with its solution at that time of validity. Outages are time windows with no fixes.

:func:`check_fixes` is the gate for fixes from a file or a user: NaN, time that does not increase,
fixes outside the IMU's span and outage windows that end before they start are refused with one
line naming what and where.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from sins.core import earth, rotation
from sins.core.series import NavSeries
from sins.errors import SinsInputError

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Outage:
    """A window ``(start_s, end_s)`` without fixes, s (fixes with ``start_s < t < end_s`` are dropped)."""

    start_s: float
    end_s: float

    def __post_init__(self) -> None:
        """Refuse a window that is not a number or ends before it starts."""
        _check_outage(self, "outage")


@dataclass(frozen=True)
class GnssConfig:
    """A simulated receiver.

    Attributes
    ----------
    rate_hz : fixes per second (1–10 typical)
    sigma_pos_m : (3,) white-noise standard deviation of a fix, NED, m
    markov_sigma_m : (3,) stationary standard deviation of the Gauss–Markov error, NED, m (0: none)
    markov_tau_s : its correlation time, s
    sigma_vel_mps : white-noise standard deviation of velocity fixes, m/s; None: position only
    lever_arm_b : (3,) antenna position from the IMU, body frame, m
    latency_s : a fix stamped ``t`` reports the antenna at ``t - latency_s``, s
    compensate_latency : the filter is told ``latency_s`` and compares each fix with its solution at
        the fix's time of validity; False: it takes the fix as of its stamp (the latency an error)
    outages : windows without fixes
    """

    rate_hz: float = 1.0
    sigma_pos_m: Array = field(default_factory=lambda: np.array([1.5, 1.5, 3.0]))
    markov_sigma_m: Array = field(default_factory=lambda: np.zeros(3))
    markov_tau_s: float = 100.0
    sigma_vel_mps: float | None = None
    lever_arm_b: Array = field(default_factory=lambda: np.zeros(3))
    latency_s: float = 0.0
    compensate_latency: bool = True
    outages: tuple[Outage, ...] = ()

    def __post_init__(self) -> None:
        """Refuse impossible values with one line naming the field."""
        if not (np.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise SinsInputError(f"gnss rate_hz must be a positive number, got {self.rate_hz}")
        for name in ("sigma_pos_m", "markov_sigma_m", "lever_arm_b"):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != (3,) or not np.all(np.isfinite(value)):
                raise SinsInputError(f"gnss {name} must be three finite numbers, got {value.tolist()}")
            if name != "lever_arm_b" and np.any(value < 0):
                raise SinsInputError(f"gnss {name} must not be negative, got {value.tolist()}")
            object.__setattr__(self, name, value)
        if not (np.isfinite(self.markov_tau_s) and self.markov_tau_s > 0):
            raise SinsInputError(f"gnss markov_tau_s must be a positive number, got {self.markov_tau_s}")
        if self.sigma_vel_mps is not None and not (
            np.isfinite(self.sigma_vel_mps) and self.sigma_vel_mps > 0
        ):
            raise SinsInputError(f"gnss sigma_vel_mps must be a positive number, got {self.sigma_vel_mps}")
        if not (np.isfinite(self.latency_s) and self.latency_s >= 0):
            raise SinsInputError(f"gnss latency_s must be a non-negative number, got {self.latency_s}")
        check_outages(self.outages)


@dataclass(frozen=True)
class GnssFixes:
    """Fixes of one receiver.

    Attributes
    ----------
    t : (k,) time stamps, s, increasing
    lat, lon : (k,) antenna position, rad
    h : (k,) antenna height, m
    v_n : (k, 3) antenna velocity, NED, m/s (NaN where the receiver gives none)
    sigma_pos_m : (3,) the position noise the filter is told, NED, m
    sigma_vel_mps : the velocity noise, m/s (None: no velocity fixes)
    lever_arm_b : (3,) antenna position from the IMU, body frame, m
    latency_s : the latency the filter is told: a fix stamped ``t`` holds at ``t - latency_s``, s
    """

    t: Array
    lat: Array
    lon: Array
    h: Array
    v_n: Array
    sigma_pos_m: Array
    sigma_vel_mps: float | None = None
    lever_arm_b: Array = field(default_factory=lambda: np.zeros(3))
    latency_s: float = 0.0

    def __post_init__(self) -> None:
        """Refuse a latency that is not a non-negative number."""
        if not (np.isfinite(self.latency_s) and self.latency_s >= 0):
            raise SinsInputError(f"gnss latency_s must be a non-negative number, got {self.latency_s}")

    @classmethod
    def empty(cls, sigma_pos_m: float = 1.0) -> GnssFixes:
        """No fixes (a run on the IMU alone, or an alignment without a receiver)."""
        none = np.zeros(0)
        return cls(
            t=none, lat=none, lon=none, h=none, v_n=np.zeros((0, 3)), sigma_pos_m=np.full(3, sigma_pos_m)
        )

    def __len__(self) -> int:
        """The number of fixes."""
        return len(self.t)

    def without(self, outages: tuple[Outage, ...] | list[Outage]) -> GnssFixes:
        """These fixes less those inside the outage windows."""
        keep = np.ones(len(self.t), dtype=bool)
        for o in outages:
            keep &= ~((self.t > o.start_s) & (self.t < o.end_s))
        return self.select(keep)

    def select(self, keep: NDArray[np.bool_]) -> GnssFixes:
        """The fixes where ``keep`` (k,) is True."""
        return GnssFixes(
            t=self.t[keep], lat=self.lat[keep], lon=self.lon[keep], h=self.h[keep], v_n=self.v_n[keep],
            sigma_pos_m=self.sigma_pos_m, sigma_vel_mps=self.sigma_vel_mps, lever_arm_b=self.lever_arm_b,
            latency_s=self.latency_s,
        )  # fmt: skip


def gauss_markov(t: Array, sigma: Array, tau_s: float, rng: np.random.Generator) -> Array:
    """A first-order Gauss–Markov process at times ``t``, (k, 3): stationary σ ``sigma``, time constant τ."""
    out = np.empty((len(t), 3))
    if len(t) == 0:
        return out
    out[0] = sigma * rng.standard_normal(3)
    with np.errstate(over="ignore"):  # a vanishing τ: each step forgets the last (φ = 0)
        phi = np.exp(-np.diff(t) / tau_s)
    drive = sigma * np.sqrt(1.0 - phi[:, None] ** 2) * rng.standard_normal((len(t) - 1, 3))
    for k in range(1, len(t)):
        out[k] = phi[k - 1] * out[k - 1] + drive[k - 1]
    return out


def offset_position(lat: Array, lon: Array, h: Array, d_n: Array) -> tuple[Array, Array, Array]:
    """Positions moved by small NED offsets ``d_n`` (k, 3) m (radii at the start point)."""
    r_m, r_n = earth.radii(lat)
    return (
        lat + d_n[:, 0] / (r_m + h),
        lon + d_n[:, 1] / ((r_n + h) * np.cos(lat)),
        h - d_n[:, 2],
    )


def fix_times(t_start: float, t_end: float, rate_hz: float, latency_s: float = 0.0) -> Array:
    """The times a receiver at ``rate_hz`` stamps fixes over ``[t_start, t_end]`` s: every ``1/rate_hz``
    from the start, less those whose measured position (``latency_s`` earlier) would precede it. Outages
    are not taken out (:meth:`GnssFixes.without`)."""
    step = 1.0 / rate_hz
    t = t_start + step * np.arange(int(np.floor((t_end - t_start) / step + 1e-9)) + 1)
    return np.asarray(t[t - latency_s >= t_start - 1e-12], dtype=float)


def simulate(truth: NavSeries, config: GnssConfig, seed: int) -> GnssFixes:
    """Fixes of a receiver riding the truth, at ``config.rate_hz`` from the truth's first time.

    Parameters
    ----------
    truth : the IMU's true states (``q_nb`` places the antenna)
    config : the receiver
    seed : the seed of its errors

    Returns
    -------
    GnssFixes within the truth's span, outages removed
    """
    rng = np.random.default_rng([seed, 22])
    t = fix_times(float(truth.t[0]), float(truth.t[-1]), config.rate_hz, config.latency_s)
    at = truth.interpolate(np.maximum(t - config.latency_s, truth.t[0]))
    C_nb = rotation.dcm_from_quat(at.q_nb)
    arm_n = C_nb @ config.lever_arm_b
    error_n = config.sigma_pos_m * rng.standard_normal((len(t), 3))
    if np.any(config.markov_sigma_m > 0):
        error_n = error_n + gauss_markov(t, config.markov_sigma_m, config.markov_tau_s, rng)
    lat, lon, h = offset_position(at.lat, at.lon, at.h, arm_n + error_n)
    v_n = np.full((len(t), 3), np.nan)
    if config.sigma_vel_mps is not None:
        # The antenna's velocity: the IMU's plus the lever arm turning, ω_nb from the attitude's slope.
        dt = 1e-3
        t0 = np.clip(t - config.latency_s - dt, truth.t[0], truth.t[-1] - 2 * dt)
        q0, q1 = truth.interpolate(t0).q_nb, truth.interpolate(t0 + 2 * dt).q_nb
        omega_nb_b = rotation.turn_between(q0, q1) / (2 * dt)
        arm_rate_n = np.einsum("kij,kj->ki", C_nb, np.cross(omega_nb_b, config.lever_arm_b))
        v_n = at.v_n + arm_rate_n + config.sigma_vel_mps * rng.standard_normal((len(t), 3))
    fixes = GnssFixes(
        t=t, lat=lat, lon=lon, h=h, v_n=v_n, sigma_pos_m=np.hypot(config.sigma_pos_m, config.markov_sigma_m),
        sigma_vel_mps=config.sigma_vel_mps, lever_arm_b=config.lever_arm_b,
        latency_s=config.latency_s if config.compensate_latency else 0.0,
    )  # fmt: skip
    return fixes.without(config.outages)


def _check_outage(o: Outage, label: str) -> None:
    if not (np.isfinite(o.start_s) and np.isfinite(o.end_s)):
        raise SinsInputError(f"{label}: start_s and end_s must be finite, got {o.start_s}, {o.end_s}")
    if o.end_s <= o.start_s:
        raise SinsInputError(f"{label}: ends at {o.end_s} s, not after its start {o.start_s} s")


def check_outages(outages: tuple[Outage, ...] | list[Outage]) -> None:
    """Refuse an outage window that is not finite or ends before it starts (one line, naming which)."""
    for i, o in enumerate(outages):
        _check_outage(o, f"outage {i + 1}")


def check_fixes(fixes: GnssFixes, imu_t: Array, source: str = "gnss") -> None:
    """Refuse fixes a filter cannot use, with one line naming ``source``, the column and the row.

    Parameters
    ----------
    fixes : the fixes
    imu_t : (n+1,) the IMU's sample times, s; every fix must lie in their span
    source : the fixes' origin for the message (a file name, a table)
    """
    columns = {"t": fixes.t, "lat": fixes.lat, "lon": fixes.lon, "h": fixes.h}
    for name, values in columns.items():
        values = np.asarray(values, dtype=float)
        if values.shape != (len(fixes.t),):
            raise SinsInputError(
                f"{source}: column {name} has {values.shape} values, expected {len(fixes.t)}"
            )
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise SinsInputError(
                f"{source}: row {bad[0] + 1}, column {name}: {values[bad[0]]} is not a finite number"
            )
    if fixes.sigma_vel_mps is not None:
        bad_rows = np.flatnonzero(~np.all(np.isfinite(fixes.v_n), axis=1))
        if bad_rows.size:
            raise SinsInputError(f"{source}: row {bad_rows[0] + 1}, column v_n: not a finite number")
    steps = np.diff(fixes.t)
    bad = np.flatnonzero(~(steps > 0))
    if bad.size:
        k = bad[0] + 1
        raise SinsInputError(
            f"{source}: row {k + 1}, column t: {fixes.t[k]} s does not come after the previous "
            f"{fixes.t[k - 1]} s"
        )
    lo, hi = float(imu_t[0]), float(imu_t[-1])
    outside = np.flatnonzero((fixes.t < lo - 1e-9) | (fixes.t > hi + 1e-9))
    if outside.size:
        k = outside[0]
        raise SinsInputError(
            f"{source}: row {k + 1}, column t: {fixes.t[k]} s is outside the IMU's span {lo}..{hi} s"
        )


__all__ = [
    "GnssConfig",
    "GnssFixes",
    "Outage",
    "check_fixes",
    "check_outages",
    "fix_times",
    "gauss_markov",
    "offset_position",
    "simulate",
]
