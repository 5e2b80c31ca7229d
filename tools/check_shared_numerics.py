"""How close sins's shared numerics are to their alternatives: the figures behind keeping or replacing each.

Usage::

    OMP_NUM_THREADS=1 .venv/bin/python tools/check_shared_numerics.py

* the overlapping Allan deviation (:mod:`sins.core.allan`, the rate's mean taken out) against the gap floor's
  before issue 34 (the running sum of the rate as it comes), on zero-mean residuals and on a 9.8 m/s²
  reading;
* :meth:`sins.core.series.NavSeries.interpolate`'s slerp against ``scipy.spatial.transform.Slerp``;
* :func:`sins.imu.numerics.cubic_hermite` against ``scipy.interpolate.CubicHermiteSpline``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicHermiteSpline
from scipy.spatial.transform import Rotation, Slerp

from sins.core.allan import allan_deviation
from sins.core.series import NavSeries
from sins.imu.numerics import cubic_hermite

Array = NDArray[np.float64]


def _adev_as_it_comes(rate: Array, clusters: NDArray[np.int64]) -> Array:
    """The gap floor's Allan deviation before issue 34: no mean taken out."""
    theta = np.concatenate([[0.0], np.cumsum(rate)])
    out = np.empty(len(clusters))
    for j, m in enumerate(clusters):
        d = theta[2 * m :] - 2.0 * theta[m:-m] + theta[: -2 * m]
        out[j] = np.sqrt(np.mean(d * d) / (2.0 * m * m))
    return out


def allan() -> None:
    rng = np.random.default_rng(0)
    clusters = 2 ** np.arange(14)
    for mean, n in ((0.0, 200_000), (9.8, 200_000), (9.8, 2_000_000)):
        x = mean + 0.01 * rng.standard_normal(n) + np.cumsum(1e-5 * rng.standard_normal(n))
        a, b = _adev_as_it_comes(x, clusters), allan_deviation(x, clusters)
        print(
            f"allan, mean {mean:g}, {n} samples: largest relative difference {np.max(np.abs(a - b) / b):.1e}"
        )


def slerp() -> None:
    rng = np.random.default_rng(1)
    n = 20_001
    t = np.arange(n) * 0.01
    q = Rotation.from_rotvec(np.cumsum(rng.normal(0, 0.02, (n, 3)), axis=0)).as_quat()
    zero = np.zeros(n)
    series = NavSeries(t=t, lat=zero, lon=zero, h=zero, v_n=np.zeros((n, 3)), q_nb=q)
    when = np.sort(rng.uniform(t[0], t[-1], 100_000))
    a = series.interpolate(when).q_nb
    b = Slerp(t, Rotation.from_quat(q))(when).as_quat()
    b = b * np.sign(np.sum(a * b, axis=1))[:, None]
    angle = (Rotation.from_quat(a).inv() * Rotation.from_quat(b)).magnitude()
    same = np.mean(np.all(a == b, axis=1))
    print(f"slerp: largest component difference {np.abs(a - b).max():.1e}, angle {angle.max():.1e} rad, "
          f"{same:.0%} of rows bit-equal")  # fmt: skip


def hermite() -> None:
    rng = np.random.default_rng(2)
    n = 100_001
    t = np.arange(n) * 0.01
    y = np.cumsum(rng.normal(size=(n, 3)), axis=0) * 1e-2 + 9.8
    dy = np.gradient(y, t, axis=0)
    when = np.clip(t - 0.0013, t[0], t[-1])
    a, b = cubic_hermite(t, y, dy, when), CubicHermiteSpline(t, y, dy)(when)
    worst = np.abs(a - b).max()
    share = worst / np.abs(y).max()
    print(f"cubic Hermite: largest difference {worst:.1e} ({share:.1e} of the largest value), "
          f"{np.mean(a == b):.0%} bit-equal")  # fmt: skip


if __name__ == "__main__":
    allan()
    slerp()
    hermite()
