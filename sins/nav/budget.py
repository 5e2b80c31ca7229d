"""The analytic growth of the navigation error a constant sensor bias causes: the drift budget's terms.

For a unit at rest, or one that moves slowly enough for its error dynamics to stay those of rest, a
constant error in the level axes excites the Schuler loop (``ω_s = √(g/R)``, 84.4 min at 45°; ``R`` the
mean radius ``√(R_M R_N)``) and one in the vertical axis the free vertical channel's instability
(``τ = √(R / 2g)``, 570 s):

* a level accelerometer bias ``b``: ``δp = b/ω_s² (1 − cos ω_s t)`` (short time ``½ b t²``);
* a level gyro bias ``ε``: the tilt ``ε t`` turns gravity into a level acceleration,
  ``δp = ε R (t − sin(ω_s t)/ω_s)`` (short time ``g ε t³/6``);
* a vertical accelerometer bias ``b`` in the free vertical channel: ``δh = b τ² (cosh(t/τ) − 1)``
  (short time ``½ b t²``); held or damped, it does not grow so.

These are the single-channel solutions: Earth's rate couples the level channels (the Foucault term,
``Ω sin φ``), which changes an hour's curve by under 1 % (``tests/test_strapdown.py`` measures it on the
integrator), and a vehicle that turns rotates body-fixed biases in the navigation frame, so that on a
drive they bound the error rather than predict it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sins.core import earth

Array = NDArray[np.float64]


def mean_radius(lat: float, h: float = 0.0) -> float:
    """``√(R_M R_N) + h``, m: the radius of the Schuler loop and of the vertical channel."""
    r_m, r_n = earth.radii(lat)
    return float(np.sqrt(r_m * r_n)) + h


def schuler_frequency(lat: float, h: float = 0.0) -> float:
    """``ω_s = √(g/R)``, rad/s."""
    return float(np.sqrt(earth.normal_gravity(lat, h) / mean_radius(lat, h)))


def accel_bias_growth(bias: float, t: ArrayLike, lat: float, h: float = 0.0) -> Array:
    """The level position error of a level accelerometer bias ``bias`` (m/s²) after ``t`` s, m."""
    w = schuler_frequency(lat, h)
    return np.asarray(bias / w**2 * (1.0 - np.cos(w * np.asarray(t, dtype=float))))


def gyro_bias_growth(bias: float, t: ArrayLike, lat: float, h: float = 0.0) -> Array:
    """The level position error of a level gyro bias ``bias`` (rad/s) after ``t`` s, m."""
    w = schuler_frequency(lat, h)
    t = np.asarray(t, dtype=float)
    return np.asarray(bias * mean_radius(lat, h) * (t - np.sin(w * t) / w))


def vertical_bias_growth(bias: float, t: ArrayLike, lat: float, h: float = 0.0) -> Array:
    """The free vertical channel's height error of a vertical accelerometer bias ``bias`` (m/s²) after
    ``t`` s, m."""
    tau = float(np.sqrt(mean_radius(lat, h) / (2.0 * earth.normal_gravity(lat, h))))
    return np.asarray(bias * tau**2 * (np.cosh(np.asarray(t, dtype=float) / tau) - 1.0))


def bias_error_ned(gyro_bias_n: ArrayLike, accel_bias_n: ArrayLike, t: ArrayLike, lat: float, h: float = 0.0
                   ) -> Array:  # fmt: skip
    """The north, east and down position error (k, 3), m, a still unit's constant biases cause after
    ``t`` (k,) s of free inertial navigation from a true start: ``gyro_bias_n`` and ``accel_bias_n``
    (3,) are the biases resolved in NED (rad/s, m/s²; what the computed attitude leaves uncompensated).

    An accelerometer bias moves the position along itself (:func:`accel_bias_growth`; down:
    :func:`vertical_bias_growth`, the free channel); a gyro bias about north rolls the computed frame
    right and moves it east, one about east pitches it up and moves it south (:func:`gyro_bias_growth`);
    the vertical gyro bias turns the heading, which moves nothing while the unit stands still.
    """
    gyro, accel = np.asarray(gyro_bias_n, dtype=float), np.asarray(accel_bias_n, dtype=float)
    t = np.asarray(t, dtype=float)
    a, g = accel_bias_growth(1.0, t, lat, h), gyro_bias_growth(1.0, t, lat, h)
    north = accel[0] * a - gyro[1] * g
    east = accel[1] * a + gyro[0] * g
    down = accel[2] * vertical_bias_growth(1.0, t, lat, h)
    return np.column_stack([north, east, down])


__all__ = [
    "accel_bias_growth",
    "bias_error_ned",
    "gyro_bias_growth",
    "mean_radius",
    "schuler_frequency",
    "vertical_bias_growth",
]
