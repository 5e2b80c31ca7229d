"""Time-series containers that cross module boundaries: navigation states and IMU samples.

Frozen dataclasses of plain arrays. A :class:`NavSeries` is both a truth
trajectory and an integrated solution; IMU data come in the two forms of the
package docstring, :class:`ImuIncrements` and :class:`ImuRates`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sins import rotation

Array = NDArray[np.float64]


@dataclass(frozen=True)
class NavSeries:
    """Navigation states at ``n`` times.

    Attributes
    ----------
    t : (n,) s
    lat, lon : (n,) rad
    h : (n,) m, height above the WGS84 ellipsoid
    v_n : (n, 3) m/s, NED velocity relative to Earth
    q_nb : (n, 4) attitude quaternion, scalar-last
    """

    t: Array
    lat: Array
    lon: Array
    h: Array
    v_n: Array
    q_nb: Array

    def __len__(self) -> int:
        return len(self.t)

    def euler(self) -> tuple[Array, Array, Array]:
        """``(roll, pitch, yaw)`` in radians, each (n,)."""
        return rotation.euler_from_quat(self.q_nb)

    def at(self, index: int | slice | NDArray[np.integer]) -> NavSeries:
        """The states at ``index`` (an int keeps a length-1 series)."""
        if isinstance(index, int | np.integer):
            index = slice(index, index + 1 if index != -1 else None)
        return NavSeries(
            t=self.t[index],
            lat=self.lat[index],
            lon=self.lon[index],
            h=self.h[index],
            v_n=self.v_n[index],
            q_nb=self.q_nb[index],
        )

    def interpolate(self, t: Array) -> NavSeries:
        """States at times ``t`` (within the span): linear in position and velocity, slerp in attitude."""
        t = np.asarray(t, dtype=float)
        if t.size and (t[0] < self.t[0] - 1e-9 or t[-1] > self.t[-1] + 1e-9):
            raise ValueError(
                f"cannot interpolate at {t[0]:.6g}..{t[-1]:.6g} s outside {self.t[0]:.6g}..{self.t[-1]:.6g} s"
            )
        i = np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, len(self.t) - 2)
        w = (t - self.t[i]) / (self.t[i + 1] - self.t[i])
        lerp = lambda a: a[i] + (a[i + 1] - a[i]) * (w if a.ndim == 1 else w[:, None])  # noqa: E731
        dq = rotation.quat_multiply(rotation.quat_conjugate(self.q_nb[i]), self.q_nb[i + 1])
        step = rotation.quat_from_rotvec(rotation.rotvec_from_quat(dq) * w[:, None])
        return NavSeries(
            t=t,
            lat=lerp(self.lat),
            lon=lerp(self.lon),
            h=lerp(self.h),
            v_n=lerp(self.v_n),
            q_nb=rotation.quat_multiply(self.q_nb[i], step),
        )


@dataclass(frozen=True)
class ImuIncrements:
    """IMU output in increment form.

    Attributes
    ----------
    t : (n+1,) s; ``t[0]`` starts the first interval, row ``k`` of the
        increments covers ``(t[k], t[k+1]]``
    dtheta_b : (n, 3) rad, integral of ``omega_ib_b`` over each interval
    dv_b : (n, 3) m/s, integral of ``f_ib_b`` over each interval
    """

    t: Array
    dtheta_b: Array
    dv_b: Array

    def __len__(self) -> int:
        return len(self.dtheta_b)


@dataclass(frozen=True)
class ImuRates:
    """IMU output in rate form: instantaneous samples.

    Attributes
    ----------
    t : (n,) s
    omega_ib_b : (n, 3) rad/s
    f_ib_b : (n, 3) m/s²
    """

    t: Array
    omega_ib_b: Array
    f_ib_b: Array

    def __len__(self) -> int:
        return len(self.t)

    def to_increments(self) -> ImuIncrements:
        """Integrate to increments over the intervals between samples.

        Four-point cubic quadrature ``dt/24 (-x[k-1] + 13 x[k] + 13 x[k+1] - x[k+2])``
        on uniform interior intervals (fourth order), the trapezoid rule at the
        two ends and wherever the step varies by more than 1 ppm.
        """
        if len(self.t) < 2:
            raise ValueError("rate-form IMU data need at least two samples to form an interval")
        dt = np.diff(self.t)
        out = []
        for x in (self.omega_ib_b, self.f_ib_b):
            inc = 0.5 * (x[:-1] + x[1:]) * dt[:, None]
            if len(x) >= 4:
                # Uniform to the rounding of the time stamps, which grows with |t|
                # (time-of-day or GPS-second stamps), plus one part per million.
                tol = 1e-6 * dt[1:-1] + 8.0 * np.finfo(float).eps * np.abs(self.t[2:-1])
                uniform = np.abs(dt[1:-1] - dt[:-2]) + np.abs(dt[2:] - dt[1:-1]) < tol
                cubic = (dt[1:-1] / 24.0)[:, None] * (-x[:-3] + 13.0 * x[1:-2] + 13.0 * x[2:-1] - x[3:])
                inc[1:-1] = np.where(uniform[:, None], cubic, inc[1:-1])
            out.append(inc)
        return ImuIncrements(t=self.t, dtheta_b=out[0], dv_b=out[1])
