"""Tests of ``sins.core.earth`` against independent references.

Nothing here reuses the formulas of the module under test: gravity is compared with
Somigliana's original closed form, with the exact normal gravity field of the
ellipsoid in ellipsoidal-harmonic coordinates and with Bruns' equation for its
vertical gradient; the radii of curvature with derivatives of the ECEF position;
``lla_to_ecef`` with the ellipsoid equation and Bowring's inverse; the Earth and
transport rates with the rotation of a local NED frame built here from geometry.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sins.core import earth

# WGS84 defining and derived constants, written out (NIMA TR8350.2).
A = 6378137.0
F = 1.0 / 298.257223563
B = A * (1.0 - F)
E2 = F * (2.0 - F)
GM = 3.986004418e14
OMEGA = 7.292115e-5
GAMMA_E = 9.7803253359
GAMMA_P = 9.8321849378

EPS = np.finfo(float).eps
DEG = np.pi / 180.0


# ------------------------------------------------------------------- helpers


def somigliana(lat: np.ndarray) -> np.ndarray:
    """Somigliana's closed form in its original shape, (a γe cos² + b γp sin²)/sqrt(a² cos² + b² sin²)."""
    c2, s2 = np.cos(lat) ** 2, np.sin(lat) ** 2
    return (A * GAMMA_E * c2 + B * GAMMA_P * s2) / np.sqrt(A * A * c2 + B * B * s2)


def radii_closed_form(lat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Textbook radii of curvature: R_M = a(1-e²)/W³, R_N = a/W with W = sqrt(1 - e² sin²)."""
    W = np.sqrt(1.0 - E2 * np.sin(lat) ** 2)
    return A * (1.0 - E2) / W**3, A / W


def exact_normal_gravity(lat: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Magnitude of the exact normal gravity of the WGS84 ellipsoid at geodetic (lat, h).

    Closed form in ellipsoidal-harmonic coordinates (u, β), TR8350.2 eqs. 4-5 to 4-13 /
    Heiskanen & Moritz §2-7: no series in h, valid at any height outside the ellipsoid.
    """
    lat, h = np.broadcast_arrays(np.asarray(lat, float), np.asarray(h, float))
    n = A / np.sqrt(1.0 - E2 * np.sin(lat) ** 2)
    p = (n + h) * np.cos(lat)
    z = (n * (1.0 - E2) + h) * np.sin(lat)
    E = np.sqrt(A * A - B * B)  # linear eccentricity
    r2 = p * p + z * z
    u = np.sqrt(0.5 * (r2 - E * E) * (1.0 + np.sqrt(1.0 + 4.0 * E * E * z * z / (r2 - E * E) ** 2)))
    beta = np.arctan2(z * np.sqrt(u * u + E * E), u * p)
    w = np.sqrt((u * u + E * E * np.sin(beta) ** 2) / (u * u + E * E))
    q = 0.5 * ((1.0 + 3.0 * u * u / (E * E)) * np.arctan(E / u) - 3.0 * u / E)
    q0 = 0.5 * ((1.0 + 3.0 * B * B / (E * E)) * np.arctan(E / B) - 3.0 * B / E)
    q_prime = 3.0 * (1.0 + u * u / (E * E)) * (1.0 - u / E * np.arctan(E / u)) - 1.0
    gamma_u = (
        -(
            GM / (u * u + E * E)
            + OMEGA**2 * A * A * E / (u * u + E * E) * q_prime / q0 * (0.5 * np.sin(beta) ** 2 - 1.0 / 6.0)
            - OMEGA**2 * u * np.cos(beta) ** 2
        )
        / w
    )
    gamma_beta = (
        (-(OMEGA**2) * A * A / np.sqrt(u * u + E * E) * q / q0 + OMEGA**2 * np.sqrt(u * u + E * E))
        * np.sin(beta)
        * np.cos(beta)
        / w
    )
    return np.hypot(gamma_u, gamma_beta)


def ecef(lat: float, lon: float, h: float) -> np.ndarray:
    return np.array(earth.lla_to_ecef(lat, lon, h), dtype=float)


def ecef_to_lla_bowring(x: float, y: float, z: float) -> tuple[float, float, float]:
    """Geodetic position from ECEF by Bowring's iteration on the reduced latitude."""
    p = np.hypot(x, y)
    lon = np.arctan2(y, x)
    ep2 = E2 / (1.0 - E2)  # second eccentricity squared
    beta = np.arctan2(z, (1.0 - F) * p)
    for _ in range(5):  # converges cubically: 3 iterations already reach full precision
        lat = np.arctan2(z + ep2 * B * np.sin(beta) ** 3, p - E2 * A * np.cos(beta) ** 3)
        beta = np.arctan2((1.0 - F) * np.sin(lat), np.cos(lat))
    h = p * np.cos(lat) + z * np.sin(lat) - A * np.sqrt(1.0 - E2 * np.sin(lat) ** 2)
    return float(lat), float(lon), float(h)


def c_en(lat: float, lon: float) -> np.ndarray:
    """NED → ECEF rotation: columns are the north, east and down unit vectors in ECEF."""
    sl, cl = np.sin(lat), np.cos(lat)
    so, co = np.sin(lon), np.cos(lon)
    north = [-sl * co, -sl * so, cl]
    east = [-so, co, 0.0]
    down = [-cl * co, -cl * so, -sl]
    return np.column_stack([north, east, down])


def random_positions(seed: int, n: int, max_lat_deg: float = 89.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lat = rng.uniform(-max_lat_deg, max_lat_deg, n) * DEG
    lon = rng.uniform(-180.0, 180.0, n) * DEG
    h = rng.uniform(-500.0, 20e3, n)
    return np.column_stack([lat, lon, h])


# ---------------------------------------------------------------- constants


def test_constants_are_wgs84() -> None:
    assert earth.A == A
    assert earth.F == F
    assert earth.OMEGA_IE == OMEGA
    assert earth.GM == GM
    assert earth.GAMMA_E == GAMMA_E and earth.GAMMA_P == GAMMA_P
    # Derived ones to the rounding of their expressions (a few ulp).
    assert earth.B == pytest.approx(6356752.314245, abs=1e-6)  # TR8350.2 Table 3.3
    assert earth.E2 == pytest.approx(6.69437999014e-3, rel=1e-11)  # TR8350.2 Table 3.3


# ------------------------------------------------------------------ gravity


def test_normal_gravity_at_equator_and_poles() -> None:
    # The defining values themselves; only rounding (a few ulp of 9.8) separates them.
    assert abs(earth.normal_gravity(0.0, 0.0) - 9.7803253359) < 1e-9
    assert abs(earth.normal_gravity(np.pi / 2, 0.0) - 9.8321849378) < 1e-9
    assert abs(earth.normal_gravity(-np.pi / 2, 0.0) - 9.8321849378) < 1e-9


def test_normal_gravity_somigliana_closed_form() -> None:
    lat = np.concatenate([[45 * DEG], np.random.default_rng(1).uniform(-90, 90, 50) * DEG])
    got = earth.normal_gravity(lat, 0.0)
    # Two algebraically equal forms of a few flops each: a few hundred ulp of 9.8 at most.
    np.testing.assert_allclose(got, somigliana(lat), rtol=0, atol=1e-12)
    # Hand-checked value at 45° from the closed form, to the 10 digits of the constants.
    assert abs(got[0] - 9.8061977693) < 1e-9


def test_exact_field_reference_reproduces_somigliana() -> None:
    # Sanity check of the reference itself: on the ellipsoid the exact field gives the defining
    # values; γe, γp are published with 10 digits, so agreement is ~1e-10 (seen: 6e-11).
    lat = np.linspace(-90, 90, 19) * DEG
    np.testing.assert_allclose(exact_normal_gravity(lat, 0.0), somigliana(lat), rtol=0, atol=2e-10)
    np.testing.assert_allclose(
        earth.normal_gravity(lat, 0.0), exact_normal_gravity(lat, 0.0), rtol=0, atol=2e-10
    )


@pytest.mark.parametrize("lat_deg", [0.0, 17.0, 45.0, 60.0, 89.0, -33.0])
def test_free_air_gradient_bruns(lat_deg: float) -> None:
    lat = lat_deg * DEG
    h = 10.0
    gradient = (earth.normal_gravity(lat, 0.0) - earth.normal_gravity(lat, h)) / h
    # Bruns' equation for the normal field: -∂γ/∂h = γ (1/R_M + 1/R_N) + 2ω², with the radii and
    # surface gravity computed here. The textbook series in sins is first order in f, so it may
    # differ by O(f²)·(few) ≈ 3e-5 relative (seen: 1.6e-5 at 45°, 3.3e-5 at the equator); the
    # h-term in the 10 m difference adds only 3h/a ≈ 5e-6.
    r_m, r_n = radii_closed_form(lat)
    bruns = somigliana(lat) * (1.0 / r_m + 1.0 / r_n) + 2.0 * OMEGA**2
    assert gradient == pytest.approx(bruns, rel=1e-4)
    # The same against a central difference of the exact field (no series at all).
    exact = (exact_normal_gravity(lat, -h) - exact_normal_gravity(lat, h)) / (2 * h)
    assert gradient == pytest.approx(exact, rel=1e-4)


def test_free_air_gradient_conventional_value() -> None:
    # The familiar 0.3086 mGal/m near 45° (a rounded mid-latitude figure): to 1 %.
    lat = 45 * DEG
    h = 10.0
    gradient = (earth.normal_gravity(lat, 0.0) - earth.normal_gravity(lat, h)) / h
    assert gradient == pytest.approx(3.086e-6, rel=0.01)


@pytest.mark.parametrize("lat_deg", [0.0, 30.0, 45.0, 60.0, 90.0])
def test_height_dependence_against_exact_field(lat_deg: float) -> None:
    lat = lat_deg * DEG
    # Direct comparison at 10 km. The series neglects O(f²) in its linear term (~3e-5 of the
    # 0.03 m/s² free-air drop ≈ 1e-6) and 4γh³/a³ ≈ 1.5e-7 m/s²; seen: at most 7e-7 m/s².
    # Dropping the h² term (7e-5 m/s²) or the f/m terms of the linear one (1e-4) would fail.
    assert abs(earth.normal_gravity(lat, 10e3) - exact_normal_gravity(lat, 10e3)) < 1.5e-6

    # Second-order term: cubic least-squares fits of both over 0..20 km (h in units of 10 km
    # keeps the fit well conditioned); the h² coefficient of the series is 3γ/a², which the exact
    # field reproduces up to O(f) ≈ 0.3 % (seen: 0.32 % at 45°). Compare to 1 %.
    hs = np.linspace(0.0, 20e3, 41)
    scale = 10e3
    c_exact = np.polynomial.polynomial.polyfit(hs / scale, exact_normal_gravity(lat, hs), 3)
    c_sins = np.polynomial.polynomial.polyfit(hs / scale, earth.normal_gravity(lat, hs), 3)
    assert c_sins[2] == pytest.approx(c_exact[2], rel=0.01)
    # Its size: 3γ/a²·(10 km)² ≈ 7.2e-5 m/s² — a numerical second difference of sins' own values.
    d = 1e3
    second_diff = (
        earth.normal_gravity(lat, 10e3 + d)
        - 2 * earth.normal_gravity(lat, 10e3)
        + earth.normal_gravity(lat, 10e3 - d)
    ) / d**2
    # Exact for a quadratic in h, up to rounding 4·eps·9.8/d² ≈ 1e-20 s⁻²·m⁻¹.
    assert second_diff * scale**2 / 2 == pytest.approx(c_sins[2], rel=1e-6)
    assert c_sins[2] == pytest.approx(3 * somigliana(lat) / A**2 * scale**2, rel=0.01)


def test_normal_gravity_broadcasts() -> None:
    lat = np.linspace(-1.5, 1.5, 7)[:, None]
    h = np.array([0.0, 1e3, 1e4])
    g = earth.normal_gravity(lat, h)
    assert g.shape == (7, 3)
    for i, j in np.ndindex(*g.shape):
        assert g[i, j] == earth.normal_gravity(float(lat[i, 0]), float(h[j]))


# ------------------------------------------------------------------ geometry


@pytest.mark.parametrize("seed", [11, 12])
def test_radii_are_derivatives_of_the_position(seed: int) -> None:
    step = 1e-6  # rad
    for lat, lon, _ in random_positions(seed, 20):
        r_m, r_n = earth.radii(lat)
        d_lat = (ecef(lat + step, lon, 0.0) - ecef(lat - step, lon, 0.0)) / (2 * step)
        d_lon = (ecef(lat, lon + step, 0.0) - ecef(lat, lon - step, 0.0)) / (2 * step)
        # Central differences: truncation R·step²/6 ≈ 1e-6 m; rounding of ~6.4e6 m coordinates
        # (a few 1e-9 m) divided by 2·step ≈ 3e-3 m. 1e-9 relative is 6 mm.
        assert np.linalg.norm(d_lat) == pytest.approx(r_m, rel=1e-9)
        assert np.linalg.norm(d_lon) == pytest.approx(r_n * np.cos(lat), rel=1e-9)
        # And the textbook closed forms, a few ulp apart.
        assert (r_m, r_n) == pytest.approx(radii_closed_form(lat), rel=1e-14)


def test_radii_at_equator_and_pole() -> None:
    r_m, r_n = earth.radii(0.0)
    assert r_n == pytest.approx(A, rel=1e-15)
    assert r_m == pytest.approx(B * B / A, rel=1e-14)  # a(1-e²) = b²/a
    r_m, r_n = earth.radii(np.pi / 2)
    # At the pole both radii are a²/b.
    assert r_m == pytest.approx(A * A / B, rel=1e-14)
    assert r_n == pytest.approx(A * A / B, rel=1e-14)


def test_lla_to_ecef_known_points() -> None:
    # Coordinates of ~6.4e6 m carry rounding of a few 1e-9 m, and cos(π/2) = 6e-17 leaves
    # a·6e-17 ≈ 4e-10 m: 1 µm is generous and still far below any formula error.
    tol = 1e-6
    np.testing.assert_allclose(ecef(0.0, 0.0, 0.0), [A, 0.0, 0.0], rtol=0, atol=tol)
    np.testing.assert_allclose(ecef(0.0, np.pi / 2, 0.0), [0.0, A, 0.0], rtol=0, atol=tol)
    np.testing.assert_allclose(ecef(0.0, np.pi, 100.0), [-(A + 100.0), 0.0, 0.0], rtol=0, atol=tol)
    np.testing.assert_allclose(ecef(np.pi / 2, 0.3, 0.0), [0.0, 0.0, B], rtol=0, atol=tol)
    np.testing.assert_allclose(ecef(-np.pi / 2, 0.3, 0.0), [0.0, 0.0, -B], rtol=0, atol=tol)
    np.testing.assert_allclose(ecef(np.pi / 2, 0.0, 1e3), [0.0, 0.0, B + 1e3], rtol=0, atol=tol)


def test_lla_to_ecef_lies_on_ellipsoid_along_the_normal() -> None:
    for lat, lon, h in random_positions(21, 50):
        p0 = ecef(lat, lon, 0.0)
        # On the ellipsoid x²/a² + y²/a² + z²/b² = 1, to a few ulp of 1.
        assert (p0[0] ** 2 + p0[1] ** 2) / A**2 + p0[2] ** 2 / B**2 == pytest.approx(1.0, abs=1e-15)
        # The outward normal there, the gradient (x/a², y/a², z/b²), has geodetic latitude lat.
        grad = np.array([p0[0] / A**2, p0[1] / A**2, p0[2] / B**2])
        up = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
        np.testing.assert_allclose(grad / np.linalg.norm(grad), up, rtol=0, atol=1e-15)
        # Height is measured along that normal: ~1e-9 m rounding of the coordinates.
        np.testing.assert_allclose(ecef(lat, lon, h) - p0, h * up, rtol=0, atol=1e-8)


def test_lla_round_trip_through_bowring() -> None:
    for lat, lon, h in random_positions(31, 200, max_lat_deg=90.0):
        lat2, lon2, h2 = ecef_to_lla_bowring(*ecef(lat, lon, h))
        # Coordinates rounded at ~1e-9 m map to ~1e-16 rad and ~1e-9 m; 1e-14 rad is 64 nm.
        assert abs(lat2 - lat) < 1e-14
        assert abs(np.angle(np.exp(1j * (lon2 - lon)))) < 1e-14 / max(np.cos(lat), 1e-3)
        assert abs(h2 - h) < 1e-8


def test_ned_frame_helper_matches_geometry() -> None:
    # The NED frame used below: north and east are the directions of d(ECEF)/d(lat) and
    # d(ECEF)/d(lon), down is minus the ellipsoid normal; checked so the later tests rest on it.
    step = 1e-6
    for lat, lon, _ in random_positions(41, 10):
        C = c_en(lat, lon)
        np.testing.assert_allclose(C.T @ C, np.eye(3), atol=1e-15)
        assert np.linalg.det(C) == pytest.approx(1.0, abs=1e-15)
        d_lat = ecef(lat + step, lon, 0.0) - ecef(lat - step, lon, 0.0)
        d_lon = ecef(lat, lon + step, 0.0) - ecef(lat, lon - step, 0.0)
        # Finite-difference directions: rounding ~1e-9 m over a ~13 m chord.
        np.testing.assert_allclose(d_lat / np.linalg.norm(d_lat), C[:, 0], atol=1e-9)
        np.testing.assert_allclose(d_lon / np.linalg.norm(d_lon), C[:, 1], atol=1e-9)


# -------------------------------------------------------------------- rates


def test_earth_rate_n() -> None:
    omega_ie_e = np.array([0.0, 0.0, OMEGA])  # about the ECEF z axis, the Earth's spin axis
    for lat, lon, _ in random_positions(51, 30, max_lat_deg=90.0):
        got = np.array(earth.earth_rate_n(lat), dtype=float)
        # Unit-scale trigonometry times Ω: a few ulp of 7.3e-5.
        assert np.linalg.norm(got) == pytest.approx(7.292115e-5, rel=1e-15)
        np.testing.assert_allclose(got, c_en(lat, lon).T @ omega_ie_e, rtol=0, atol=4 * EPS * OMEGA)


def test_transport_rate_eastward_at_equator() -> None:
    for v, h in [(100.0, 0.0), (250.0, 1e4), (-30.0, 500.0)]:
        got = np.array(earth.transport_rate_n(0.0, h, 0.0, v), dtype=float)
        # At the equator R_N = a: rotation v/(a+h) about north, nothing else (a few ulp).
        np.testing.assert_allclose(got, [v / (A + h), 0.0, 0.0], rtol=1e-15, atol=1e-25)


@pytest.mark.parametrize("seed", [61, 62, 63])
def test_transport_rate_is_rotation_rate_of_ned(seed: int) -> None:
    rng = np.random.default_rng(seed)
    dt = 0.05  # s
    for lat, lon, h in random_positions(seed, 10, max_lat_deg=80.0):
        v_n = rng.uniform(-300.0, 300.0, 3)
        # Move along a straight line in ECEF at the velocity v_n resolved in ECEF and recover the
        # geodetic position with Bowring's method: no sins radius enters the path.
        p0 = ecef(lat, lon, h)
        v_e = c_en(lat, lon) @ v_n

        def frame(t: float, p0: np.ndarray = p0, v_e: np.ndarray = v_e) -> Rotation:
            lat_t, lon_t, _ = ecef_to_lla_bowring(*(p0 + v_e * t))
            return Rotation.from_matrix(c_en(lat_t, lon_t))

        # C_en' = C_en [omega_en_n ×]: the log of C_ne(0) C_en(±dt) is ±dt·omega + O(dt²) with the
        # dt² part symmetric, so the central difference leaves O(dt²).
        r0_inv = frame(0.0).inv()
        omega_fd = ((r0_inv * frame(dt)).as_rotvec() - (r0_inv * frame(-dt)).as_rotvec()) / (2 * dt)
        got = np.array(earth.transport_rate_n(lat, h, v_n[0], v_n[1]), dtype=float)
        # Truncation O(dt²), seen 5e-12 rad/s at dt = 1 s, so ~1.4e-14 here; rounding of the frames
        # (~1e-16 rad) over 2·dt ≈ 1e-15 rad/s. |omega| is up to ~3e-4 rad/s, so 1e-13 is ~1e-9
        # relative: mixing up R_M and R_N (a 0.3-1 % change) fails by six orders of magnitude.
        np.testing.assert_allclose(got, omega_fd, rtol=0, atol=1e-13)


def test_schuler_period() -> None:
    # 2π·sqrt(R/g) with R ≈ 6.38e6 m and g ≈ 9.806 m/s² is about 84.4 min.
    assert earth.schuler_period(45 * DEG) / 60.0 == pytest.approx(84.4, abs=0.2)
    # Longer at altitude (R grows relative to g): a sign check.
    assert earth.schuler_period(45 * DEG, 10e3) > earth.schuler_period(45 * DEG)


@pytest.mark.parametrize("seed", [71, 72])
def test_position_rates_match_ecef_velocity(seed: int) -> None:
    rng = np.random.default_rng(seed)
    dt = 0.02  # s
    for lat, lon, h in random_positions(seed, 20):
        v_n = rng.uniform(-300.0, 300.0, 3)
        d_lat, d_lon, d_h = earth.position_rates(lat, h, *v_n)
        fwd = ecef(lat + d_lat * dt, lon + d_lon * dt, h + d_h * dt)
        bwd = ecef(lat - d_lat * dt, lon - d_lon * dt, h - d_h * dt)
        v_fd = (fwd - bwd) / (2 * dt)
        # Central difference: truncation O(dt²), largest near the poles where d(lon)/dt grows as
        # 1/cos(lat) (seen 1e-5 m/s at dt = 0.3 s, so ~5e-8 here); rounding of the ~6.4e6 m
        # coordinates (a few 1e-9 m) over 2·dt ≈ 1e-7 m/s. Velocities are up to 300 m/s.
        np.testing.assert_allclose(v_fd, c_en(lat, lon) @ v_n, rtol=0, atol=1e-6)
