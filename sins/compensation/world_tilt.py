"""The tilt of a reference's world frame from gravity, estimated from the readings, and the reference
levelled by it.

A motion capture's world frame is set on its floor (a wand, an L-frame) and is as level as that floor
and that setting were. A reference whose vertical is tilted by ``δ`` from gravity's puts ``g δ`` of
gravity in its horizontal axes, 17 mg per degree: a fixed acceleration in the world, which no
coefficient fixed in the body can take while the body turns, so a fit against that reference, or a
diagnosis on it, reads it as the accelerometer's error (a bias that moves as the body turns). EuRoC's
three sequences of its second Vicon room are tilted 0.56°, 0.57° and 0.55° (each beyond 20 standard
errors, and each predicting held-back intervals); levelled, what ``sins fit`` leaves of their velocity
change per interval in motion falls from 61, 83 and 76 to 37, 40 and 58 mm/s RMS (the gyro's residual
is the same to the digit: a turn of the world moves no attitude change). The laser tracker's sequences
(MH_*) are level within their noise.

Estimated on the reference's intervals (:func:`sins.compensation.intervals.choose_intervals`): with the
readings corrected by the seed model and time offsets the intervals give
(:func:`~sins.compensation.interval_fit.fit_intervals`, no g-sensitivity: the gyro's errors turn the
attitude each velocity change is turned by, and a gyro 5 ms late had numpy's level room tilted by
0.04-0.13°), each interval's velocity residual
(:func:`~sins.compensation.interval_fit.accel_problem`, the fit's own) is fitted by least squares on the
accelerometer's bias (3), scale and misalignment (9) and lever arm (3), and the world's tilt about north
and east (2): a tilt ``δ`` leaves ``(δ × g) T`` of the velocity change over an interval of ``T``, in NED
(the seed fit's own lever arm, made without the tilt, had taken part of it). The reference is levelled
(its attitude and velocity turned by ``Exp(−δ)``) where both of the tilt's standard errors are within
:data:`DETERMINED_DEG`, the tilt is beyond :data:`SIGNIFICANT_CHI2` (chi-square of two degrees of
freedom, 95 %), and it predicts intervals it was not fitted on
(:func:`~sins.compensation.interval_fit.predicts_held_back`, the g-sensitivity's rule);
elsewhere it is read as given. The last condition is BROAD's trial 18: a unit that hardly turns, with a
step in its accelerometer, found 0.47° (chi-square 22) that did not predict held-back intervals, and
levelled by it the raw readings' free-inertial velocity against the reference rose from 0.22 to 0.36
m/s. Positions are left as they are: the intervals read them for gravity's size and Earth's rate, which
a tilt of a degree moves by nothing a fit sees (a height change of 17 cm over 10 m).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.compensation import interval_fit, screening
from sins.compensation.intervals import INTERVAL_S, Intervals, choose_intervals, expected_dv, lever
from sins.core import earth, rotation
from sins.core.series import ReferencedRecording
from sins.nav import attitude

Array = NDArray[np.float64]

#: The largest standard error, deg, of either tilt component for the reference to be levelled by it.
DETERMINED_DEG = 0.1
#: The tilt's chi-square (``δᵀ Σ⁻¹ δ``) beyond which it is taken: 95 % of two degrees of freedom.
SIGNIFICANT_CHI2 = 5.991


@dataclass(frozen=True)
class WorldTilt:
    """A reference's world frame against gravity: ``tilt_rad`` (2,) the rotation vector's north and
    east parts that take a level frame to the reference's, ``covariance_rad2`` (2, 2) its covariance,
    ``levelled`` whether the reference was turned by its inverse, ``says`` the verdict in words."""

    tilt_rad: Array
    covariance_rad2: Array
    levelled: bool
    says: str

    @property
    def se_rad(self) -> Array:
        """Each component's standard error, rad."""
        return np.asarray(np.sqrt(np.diag(self.covariance_rad2)), dtype=float)

    def to_dict(self) -> dict[str, Any]:
        """As plain JSON values (``sins gap --json``'s ``statistic.reference_tilt``)."""
        finite = lambda v: [float(x) if np.isfinite(x) else None for x in v]  # noqa: E731
        return {
            "tilt_deg": finite(np.degrees(self.tilt_rad)),
            "standard_error_deg": finite(np.degrees(self.se_rad)),
            "size_deg": float(np.degrees(np.linalg.norm(self.tilt_rad))) if self.determined else None,
            "levelled": self.levelled,
            "says": self.says,
        }

    @property
    def determined(self) -> bool:
        """Whether the recording pins the tilt down within :data:`DETERMINED_DEG` on both axes."""
        se = self.se_rad
        return bool(np.all(np.isfinite(se)) and np.all(se <= np.radians(DETERMINED_DEG)))


def estimate(rec: ReferencedRecording, interval_s: float = INTERVAL_S) -> WorldTilt:
    """The tilt of ``rec``'s reference frame from gravity, and whether to level it (module docstring)."""
    nothing = np.full(2, np.nan), np.full((2, 2), np.nan)
    try:
        seed = interval_fit.fit_intervals(rec, interval_s=interval_s, g_sensitivity=False)
        iv = choose_intervals(rec, interval_s)
    except ValueError as exc:
        return WorldTilt(*nothing, False, f"the world frame's tilt is not estimated: {exc}; read as given")
    dt = np.diff(rec.imu.t)
    gyro = seed.corrected(rec.imu).dtheta_b
    q_int = attitude.propagate_increments(gyro, np.array([0.0, 0.0, 0.0, 1.0]))
    # The accelerometer's own problem at the seed model (bias, matrix and lever arm: the seed fit's
    # lever arm, made without the tilt, had taken part of it, numpy's 0.5° at 0.27-0.37° after it),
    # beside the tilt's two columns: a tilt δ leaves (δ × g) T of each interval's velocity change in NED.
    x, y = interval_fit.accel_problem(
        iv, rec.imu, dt, q_int, seed.seed.A0, seed.seed.A, seed.accel_time_offset_s, False,
        expected_dv(iv, dt), lever(iv, rec.imu, seed.seed, dt),
    )  # fmt: skip
    x = np.asarray(np.concatenate([x, _tilt_columns(iv, dt)], axis=2), dtype=np.float64)
    a, b = x.reshape(-1, x.shape[2]), y.reshape(-1)
    dof = len(b) - a.shape[1]
    gram = a.T @ a
    if dof <= 0 or np.linalg.cond(gram) > 1e12:
        return WorldTilt(*nothing, False, "the world frame's tilt is not determined (the unit turns too "
                         "little to tell it from the accelerometer's bias); read as given")  # fmt: skip
    theta = np.asarray(np.linalg.solve(gram, a.T @ b), dtype=np.float64)
    resid = b - a @ theta
    cov = np.asarray(float(resid @ resid) / dof * np.linalg.inv(gram)[-2:, -2:], dtype=np.float64)
    predicts = interval_fit.predicts_held_back(x, y, np.arange(x.shape[2] - 2))
    return _verdict(theta[-2:], cov, predicts)


def _verdict(tilt: Array, cov: Array, predicts: tuple[bool, float, float]) -> WorldTilt:
    """The tilt's verdict (module docstring): levelled where determined, significant and predicting
    held-back intervals (``predicts``: :func:`~sins.compensation.interval_fit.predicts_held_back`'s
    verdict, gain and its standard error)."""
    deg, se = np.degrees(tilt), np.degrees(np.sqrt(np.diag(cov)))
    size = (f"the world frame tilts {np.degrees(np.linalg.norm(tilt)):.3f}° from gravity (north "
            f"{deg[0]:+.3f}° ± {se[0]:.3f}°, east {deg[1]:+.3f}° ± {se[1]:.3f}°)")  # fmt: skip
    chi2 = float(tilt @ np.linalg.solve(cov, tilt))
    kept, gain, gain_se = predicts
    if not np.all(se <= DETERMINED_DEG):
        why = f"not determined within {DETERMINED_DEG:g}°"
    elif chi2 <= SIGNIFICANT_CHI2:
        why = f"within its noise (chi-square {chi2:.1f})"
    elif not kept:
        why = (
            f"chi-square {chi2:.0f}, but it does not predict held-back intervals (gain "
            f"{gain / gain_se:.1f} standard errors: an error of the accelerometer's own can take its shape "
            "over part of a recording)"
        )
    else:
        levelled = "its attitude and velocity are read levelled (turned by its inverse)"
        return WorldTilt(tilt, cov, True, f"{size}, chi-square {chi2:.0f}: {levelled}")
    return WorldTilt(tilt, cov, False, f"{size}, {why}: read as given")


def _tilt_columns(iv: Intervals, dt: Array) -> Array:
    """Each interval's columns (k, 3, 2) of the tilt about north and east, in NED as
    :func:`~sins.compensation.interval_fit.accel_problem`'s residual: ``(δ × g) T``, ``g`` down."""
    g = np.asarray(earth.normal_gravity(iv.lat, iv.h), dtype=float) * np.ones(len(iv))
    span = iv.seconds(dt)
    out = np.zeros((len(iv), 3, 2))
    out[:, 1, 0] = -g * span  # about north: east's component
    out[:, 0, 1] = g * span  # about east: north's component
    return out


def levelled(
    rec: ReferencedRecording, interval_s: float = INTERVAL_S
) -> tuple[ReferencedRecording, WorldTilt]:
    """``rec`` with its reference levelled where its world frame's tilt is determined, significant and
    predicts held-back intervals (:func:`estimate`, without the reference's spans filled by
    interpolation, which a fit sets aside: :func:`sins.compensation.screening.filled`), and the tilt."""
    spans = screening.filled(rec)
    tilt = estimate(screening.without(rec, list(spans)) if spans else rec, interval_s)
    return level(rec, tilt), tilt


def level(rec: ReferencedRecording, tilt: WorldTilt) -> ReferencedRecording:
    """``rec`` with its reference's attitude and velocity turned by the inverse of ``tilt`` where
    :attr:`WorldTilt.levelled` (as it is elsewhere): a tilt estimated on one part of a recording, applied
    to the whole."""
    if not tilt.levelled:
        return rec
    turn = rotation.quat_from_rotvec(-np.r_[tilt.tilt_rad, 0.0])
    ref = rec.reference
    reference = dataclasses.replace(
        ref, q_nb=rotation.quat_multiply(turn, ref.q_nb), v_n=rotation.rotate(turn, ref.v_n)
    )
    return dataclasses.replace(rec, reference=reference)


__all__ = ["DETERMINED_DEG", "SIGNIFICANT_CHI2", "WorldTilt", "estimate", "level", "levelled"]
