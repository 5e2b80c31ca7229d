"""The Earth model: WGS84 ellipsoid, Somigliana normal gravity, Earth and transport rates.

Every function takes and returns plain floats or numpy arrays (broadcasting)
and returns components as tuples rather than stacked arrays, so that the same
source compiles unchanged under numba inside the strapdown kernel.
Latitude ``lat`` in radians, height ``h`` in metres above the ellipsoid.

The compiled kernels (``strapdown``, ``trajectory``) inline the leaf function
``radii_and_gravity_from_sin2``, which must stay free of calls to other Python
functions. numba keys a cached kernel on the kernel's own
file only: after editing this module, run ``make clean-cache``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: A float or a numpy array of floats; the functions broadcast like numpy ufuncs.
Floats = Any

#: WGS84 semi-major axis, m.
A = 6378137.0
#: WGS84 flattening.
F = 1.0 / 298.257223563
#: First eccentricity squared.
E2 = F * (2.0 - F)
#: Semi-minor axis, m.
B = A * (1.0 - F)
#: Earth's gravitational constant GM, m³/s².
GM = 3.986004418e14
#: Earth rotation rate, rad/s.
OMEGA_IE = 7.292115e-5
#: The largest latitude sins navigates at, degrees: the latitude/longitude mechanisation is singular at a
#: pole (a scenario's ``[initial] lat_deg``, an origin given to a reader or a command).
MAX_LAT_DEG = 89.9
#: The largest height sins takes for an origin, m (an origin given to a reader or a command, ``sins bias
#: --height``): normal gravity's series in height holds well below it.
MAX_HEIGHT_M = 1e5
#: Normal gravity at the equator and at the poles, m/s² (WGS84).
GAMMA_E = 9.7803253359
GAMMA_P = 9.8321849378
#: Standard gravity, m/s², the unit behind "mg" and "g" in scenario files.
G0 = 9.80665

_SOMIGLIANA_K = (B * GAMMA_P) / (A * GAMMA_E) - 1.0
_M = OMEGA_IE**2 * A**2 * B / GM


def check_latitude(lat: float, what: str) -> None:
    """Refuse a latitude beyond ±π/2 rad (NaN too): 45.0 given for 45° is 45 rad, beyond the pole, which
    a trajectory or an integration then ran on. ``ValueError`` naming ``what`` (``Start.lat``)."""
    if not abs(lat) <= 0.5 * np.pi:
        raise ValueError(f"{what} is {lat!r} rad, beyond ±π/2 (degrees given for radians?)")


def radii(lat: Floats) -> tuple[Floats, Floats]:
    """Meridian and prime-vertical radii of curvature ``(R_M, R_N)`` in metres."""
    r_m, r_n, _ = radii_and_gravity_from_sin2(np.sin(lat) ** 2, 0.0)
    return r_m, r_n


def normal_gravity(lat: Floats, h: Floats) -> Floats:
    """Magnitude of normal gravity (gravitation plus centrifugal), m/s².

    Somigliana's closed formula on the ellipsoid with the standard second-order
    height correction. The vector in NED is ``(0, 0, normal_gravity)``.
    """
    return radii_and_gravity_from_sin2(np.sin(lat) ** 2, h)[2]


def radii_and_gravity_from_sin2(sin2_lat: Floats, h: Floats) -> tuple[Floats, Floats, Floats]:
    """``(R_M, R_N, normal_gravity)`` from ``sin²(lat)`` and height: the one Earth-shape formula.

    A leaf function (numpy only, no calls into this module) so that the compiled
    kernels inline it; :func:`radii` and :func:`normal_gravity` wrap it.
    """
    w = 1.0 - E2 * sin2_lat
    inv_sqrt_w = 1.0 / np.sqrt(w)
    r_n = A * inv_sqrt_w
    gamma0 = GAMMA_E * (1.0 + _SOMIGLIANA_K * sin2_lat) * inv_sqrt_w
    gamma = gamma0 * (1.0 - 2.0 / A * (1.0 + F + _M - 2.0 * F * sin2_lat) * h + 3.0 / (A * A) * h * h)
    return r_n * (1.0 - E2) / w, r_n, gamma


def earth_rate_n(lat: Floats) -> tuple[Floats, Floats, Floats]:
    """Earth rate ``omega_ie_n`` in NED as components ``(north, east, down)``, rad/s."""
    return OMEGA_IE * np.cos(lat), 0.0 * lat, -OMEGA_IE * np.sin(lat)


def transport_rate_n(
    lat: Floats, h: Floats, v_north: Floats, v_east: Floats
) -> tuple[Floats, Floats, Floats]:
    """Transport rate ``omega_en_n`` as components ``(north, east, down)``, rad/s."""
    r_m, r_n = radii(lat)
    rn_h = r_n + h
    return v_east / rn_h, -v_north / (r_m + h), -v_east * np.tan(lat) / rn_h


def position_rates(
    lat: Floats, h: Floats, v_north: Floats, v_east: Floats, v_down: Floats
) -> tuple[Floats, Floats, Floats]:
    """Time derivatives ``(dlat/dt, dlon/dt, dh/dt)`` of geodetic position (rad/s, m/s)."""
    r_m, r_n = radii(lat)
    return v_north / (r_m + h), v_east / ((r_n + h) * np.cos(lat)), -v_down


def lla_to_ecef(lat: Floats, lon: Floats, h: Floats) -> tuple[Floats, Floats, Floats]:
    """ECEF coordinates ``(x, y, z)`` in metres of a geodetic position."""
    _, r_n = radii(lat)
    c = np.cos(lat)
    return (r_n + h) * c * np.cos(lon), (r_n + h) * c * np.sin(lon), (r_n * (1.0 - E2) + h) * np.sin(lat)


def local_ned(lat: Floats, lon: Floats, h: Floats, lat0: float, lon0: float, h0: float) -> Floats:
    """Positions relative to ``(lat0, lon0, h0)`` in that point's north-east-down axes, (n, 3) m.

    Exact (through ECEF), so a path hundreds of kilometres long keeps its shape.
    """
    x, y, z = lla_to_ecef(lat, lon, h)
    x0, y0, z0 = lla_to_ecef(lat0, lon0, h0)
    dx, dy, dz = np.asarray(x) - x0, np.asarray(y) - y0, np.asarray(z) - z0
    s_lat, c_lat, s_lon, c_lon = np.sin(lat0), np.cos(lat0), np.sin(lon0), np.cos(lon0)
    north = -s_lat * c_lon * dx - s_lat * s_lon * dy + c_lat * dz
    east = -s_lon * dx + c_lon * dy
    down = -c_lat * c_lon * dx - c_lat * s_lon * dy - s_lat * dz
    return np.stack([north, east, down], axis=-1)


def ned_offset(lat: Floats, lon: Floats, h: Floats, lat0: Floats, lon0: Floats, h0: Floats) -> Floats:
    """``(lat, lon, h)`` less ``(lat0, lon0, h0)`` in north-east-down metres, (..., 3): the small-angle
    form at the first position's radii and ``cos lat``, for positions metres apart (a filter's
    innovation, an estimate's error, a chord between fixes); :func:`local_ned` for long paths."""
    r_m, r_n = radii(lat)
    return np.stack([(lat - lat0) * (r_m + h), (lon - lon0) * (r_n + h) * np.cos(lat), -(h - h0)], axis=-1)


def schuler_period(lat: Floats, h: Floats = 0.0) -> Floats:
    """Schuler period ``2π sqrt(R/g)`` in seconds, with ``R`` the mean radius ``sqrt(R_M R_N)``."""
    r_m, r_n = radii(lat)
    return 2.0 * np.pi * np.sqrt(np.sqrt(r_m * r_n) / normal_gravity(lat, h))


__all__ = [
    "E2",
    "G0",
    "GAMMA_E",
    "GAMMA_P",
    "GM",
    "MAX_HEIGHT_M",
    "MAX_LAT_DEG",
    "OMEGA_IE",
    "A",
    "B",
    "F",
    "check_latitude",
    "earth_rate_n",
    "lla_to_ecef",
    "local_ned",
    "ned_offset",
    "normal_gravity",
    "position_rates",
    "radii",
    "radii_and_gravity_from_sin2",
    "schuler_period",
    "transport_rate_n",
]
