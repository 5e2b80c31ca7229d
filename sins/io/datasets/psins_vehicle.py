"""The PSINS FOG/MEMS vehicle recording (``psins_fog_mems_vehicle/``; BSD 2-clause, PSINS toolbox,
Gongmin Yan, NWPU; github.com/WangShanpeng/PSINS ``data/transfer_align_fog_mems.mat``)
    100 s of a MEMS IMU (100 Hz increments) beside the navigation solution of a
    fibre-optic-gyro INS (10 Hz attitude, velocity, position) on a vehicle driving
    north at 12–16 m/s while the mount rolls through ±32°.
    :func:`read_psins_vehicle` returns the MEMS readings beside a reference derived
    from the FOG-INS solution as :class:`~sins.core.series.CalibrationData`, and the
    FOG-INS solution as a :class:`~sins.core.series.NavSeries`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

# scipy's io, signal and interpolate modules are imported in the functions that use them: ~0.6 s at
# import, which every command paid for any recording (tools/bench_startup.py).
import numpy as np
from numpy.typing import NDArray

from sins.core import earth, rotation
from sins.core.series import CalibrationData, NavSeries
from sins.errors import SinsInputError
from sins.io.datasets.matfile import check_mat_v5
from sins.io.datasets.root import check_magnitude, dataset_file
from sins.io.formats import MAX_FORCE_MPS2, MAX_RATE_RADPS, MAX_TIME_S, MAX_TRUTH_SPEED_MPS, TRUTH_ALT_M

Array = NDArray[np.float64]

PSINS_VEHICLE_FOLDER = "psins_fog_mems_vehicle"
PSINS_VEHICLE_FILE = "transfer_align_fog_mems.mat"
#: PSINS axes to the package's. PSINS bodies are X-right, Y-forward, Z-up and its navigation frame is
#: East-North-Up; swapping the first two axes and negating the third turns RFU into FRD and ENU into
#: NED alike (a proper rotation, det +1); the data agree (``docs/guide/datasets.md``).
_PSINS_TO_SINS = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: ``mimu`` columns: dθ x, y, z (rad), dv x, y, z (m/s), t (s) — the PSINS IMU-file layout.
_MIMU_COLUMNS = 7
#: ``fogavp`` columns: pitch, roll, yaw (rad), vE, vN, vU (m/s), lat, lon (rad), h (m), t (s) — PSINS avp.
_AVP_COLUMNS = 10
#: Fewest rows of either table: the alignment fits 15 parameters on 10 Hz means and the gap
#: diagnosis needs 200 rows; 100 FOG-INS intervals (10 s) is the least that pins the fits down.
_MIN_INTERVALS = 100
#: Time offsets searched, s: ± one FOG-INS interval (the correlation of |ω| on this file has one peak
#: in it, falling off smoothly on both sides: ``docs/guide/datasets.md``).
_MAX_OFFSET_S = 0.1
#: Step of the offset grid before the parabolic refinement, s: near its top the correlation falls by
#: ≈ 2e-5 over 2 ms, smooth enough for a parabola through three 1 ms steps.
_OFFSET_STEP_S = 0.001


@dataclass(frozen=True)
class PsinsAlignment:
    """How :func:`read_psins_vehicle` puts the FOG-INS reference on the MEMS, as estimated from the data.

    Attributes
    ----------
    offset_s : FOG-INS clock minus MEMS clock at the same instant, s (``t_fog = t_mems + offset_s``)
    c_mems_fog : (3, 3) rotation of FOG-body (FRD) vectors into MEMS-body (FRD) axes
    lever_arm_m : (3,) the MEMS's position relative to the FOG-INS's, MEMS axes (FRD), m
    correlation : correlation of |ω| (MEMS against reference, 10 Hz interval means) at ``offset_s``
    """

    offset_s: float
    c_mems_fog: Array
    lever_arm_m: Array
    correlation: float

    @property
    def rotvec_deg(self) -> Array:
        """The mounting rotation MEMS ← FOG as a rotation vector, degrees."""
        from scipy.spatial.transform import Rotation

        return np.degrees(Rotation.from_matrix(self.c_mems_fog).as_rotvec())


def read_psins_vehicle(
    root: str | os.PathLike[str] | None = None, *, rate: Literal["mems", "fog"] = "mems"
) -> tuple[CalibrationData, NavSeries | None]:
    """The MEMS readings of ``transfer_align_fog_mems.mat`` against the FOG-INS solution.

    Readings (``gyro``, ``accel``): the MEMS increments ``mimu`` divided by
    their 10 ms interval (rate form), in the MEMS's own axes turned from PSINS's
    right-forward-up into forward-right-down. Each row integrates the 10 ms
    before its stamp (PSINS's increment convention), so ``t`` is the stamp minus
    5 ms, the interval's middle. Temperature is not recorded (``temp`` None).

    Reference (``ref_gyro``, ``ref_accel``): the file holds no FOG *readings*,
    only the FOG-INS navigation solution ``fogavp`` at 10 Hz, so the reference
    is derived from it: ``ω_ib_b = ω_nb_b + C_bn (ω_ie_n + ω_en_n)`` with
    ``ω_nb_b`` the rate of a rotation spline through the attitudes, and
    ``f_ib_b = C_bn (dv_n/dt + (2ω_ie_n + ω_en_n) × v_n − g_n)`` with a cubic
    spline through the velocities, WGS84 normal gravity, Earth and transport
    rates (both splines keep each 0.1 s interval's mean exact). It is then read
    on the MEMS clock, turned into the MEMS axes and moved to the MEMS's place
    (``f += ω̇ × r + ω × (ω × r)``), with three things estimated from the data
    (:class:`PsinsAlignment`, :func:`psins_alignment`):

    * time offset: the FOG-INS clock against the MEMS's, at the peak of the
      correlation of |ω| over 10 Hz interval means (parabolic refinement of a
      1 ms grid over ± one FOG-INS interval);
    * mounting rotation MEMS ← FOG: a Wahba/Kabsch fit of the mean-removed
      10 Hz rate vectors;
    * lever arm: a least-squares fit of the accelerometer error to
      ``ω̇ × r + ω × (ω × r)`` beside a bias and a 3×3 scale/misalignment.

    The reference knows the motion only below 5 Hz (the FOG-INS's Nyquist
    frequency): at 100 Hz a gap diagnosis counts the vibration the MEMS sees and
    the reference cannot against the MEMS, and ``rate="fog"`` gives the 10 Hz
    interval means instead, where that content averages out (the better input
    for a diagnosis). The estimates found on this file and how well the MEMS
    and the reference agree are in ``docs/guide/datasets.md``.

    Navigation solution: ``fogavp`` in NED, radians and metres, with the
    attitude of the MEMS body (``C_n,mems = C_n,fog c_mems_fog^T``) and times on
    the MEMS clock (``t_fog − offset_s``); position and velocity are the
    FOG-INS's, at its place (the lever arm away from the MEMS).

    Parameters
    ----------
    root : the data root, or None for :func:`data_root`
    rate : "mems" (every MEMS sample, 100 Hz) or "fog" (means over the FOG-INS's 0.1 s intervals)

    Returns
    -------
    tuple[CalibrationData, NavSeries | None]
        ``t`` (n,) s, ``gyro`` (n, 3) rad/s, ``accel`` (n, 3) m/s², ``ref_gyro``
        (n, 3) rad/s, ``ref_accel`` (n, 3) m/s², no NaN, no phases, ``source`` the
        MAT path; rows whose reference would need extrapolation (the first
        ≈ 0.1 s) are left out. Then the FOG-INS solution at 10 Hz (never None
        for this file).

    Raises
    ------
    SinsInputError
        one line: a missing folder or file (saying how to point at the data), a
        file that is not a MAT file or is damaged, a missing or malformed variable.
    """
    if rate not in ("mems", "fog"):
        raise SinsInputError(f"rate {rate!r}: expected 'mems' or 'fog'")
    path = _path(root)
    mems, nav = _load(path)
    ref = _Reference(nav)
    align = _estimate_alignment(mems, ref, path)
    if rate == "mems":
        tau = mems.t + align.offset_s
        keep = (tau >= nav.t[0]) & (tau <= nav.t[-1])
        t, gyro, accel = mems.t[keep], mems.omega[keep], mems.f[keep]
        omega_fog, f_fog = ref.at(tau[keep])
    else:
        t, gyro, accel, omega_fog, f_fog = _interval_means(mems, ref, align.offset_s)
    ref_gyro, ref_accel = _on_mems(t, omega_fog, f_fog, align.c_mems_fog, align.lever_arm_m)
    data = CalibrationData(
        t=t,
        gyro=gyro,
        accel=accel,
        ref_gyro=ref_gyro,
        ref_accel=ref_accel,
        temp=None,
        phases=(),
        source=str(path),
    )
    q_fog_mems = rotation.quat_conjugate(rotation.quat_from_dcm(align.c_mems_fog))
    nav_mems = NavSeries(
        t=nav.t - align.offset_s,
        lat=nav.lat,
        lon=nav.lon,
        h=nav.h,
        v_n=nav.v_n,
        q_nb=rotation.quat_normalize(rotation.quat_multiply(nav.q_nb, q_fog_mems)),
    )
    return data, nav_mems


def psins_alignment(root: str | os.PathLike[str] | None = None) -> PsinsAlignment:
    """The time offset, mounting rotation and lever arm :func:`read_psins_vehicle` estimates and applies.

    Parameters
    ----------
    root : the data root, or None for :func:`data_root`

    Raises
    ------
    SinsInputError
        as :func:`read_psins_vehicle`.
    """
    path = _path(root)
    mems, nav = _load(path)
    return _estimate_alignment(mems, _Reference(nav), path)


# --------------------------------------------------------------------------- reading


@dataclass(frozen=True)
class _Mems:
    """MEMS readings in rate form, FRD, at the middle of each increment's interval."""

    t: Array
    omega: Array
    f: Array
    t_end: Array  # the stamps: row k integrates (t_end[k] − dt[k], t_end[k]]
    dt: Array


def _path(root: str | os.PathLike[str] | None) -> Path:
    return dataset_file(PSINS_VEHICLE_FOLDER, PSINS_VEHICLE_FILE, root)


def _load(path: Path) -> tuple[_Mems, NavSeries]:
    """The two tables, checked, in the package's axes and units (the FOG-INS on its own clock)."""
    import scipy.io
    from scipy.spatial.transform import Rotation

    try:
        raw = path.read_bytes()
        head = raw[:128]
    except OSError as exc:
        raise SinsInputError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if not head.startswith(b"MATLAB 5.0 MAT-file"):
        raise SinsInputError(f"{path}: not a MATLAB 5 MAT file (no 'MATLAB 5.0 MAT-file' header)")
    check_mat_v5(path, raw)  # scipy's reader crashes on some damage instead of raising
    try:
        content: dict[str, Any] = scipy.io.loadmat(path, squeeze_me=True)
    except Exception as exc:  # a damaged file raises MatReadError, OSError, ValueError, IndexError, …
        message = " ".join(str(exc).split()) or "no detail"
        raise SinsInputError(f"{path}: damaged MAT file: {type(exc).__name__}: {message}") from None
    mimu = _table(path, content, "mimu", _MIMU_COLUMNS)
    avp = _table(path, content, "fogavp", _AVP_COLUMNS)
    t_end = mimu[:, 6]
    step = np.diff(t_end)
    # The first row's interval lies before the first stamp: it gets the usual step.
    dt = np.r_[np.median(step), step]
    mems = _Mems(
        t=t_end - 0.5 * dt,
        omega=(mimu[:, 0:3] @ _PSINS_TO_SINS.T) / dt[:, None],
        f=(mimu[:, 3:6] @ _PSINS_TO_SINS.T) / dt[:, None],
        t_end=t_end,
        dt=dt,
    )
    # PSINS a2mat: C_nb (ENU ← RFU) = Rz(yaw) Rx(pitch) Ry(roll), scipy's intrinsic "ZXY" (checked
    # against a2mat's closed form to 3e-16); yaw positive counter-clockwise from north. Checked in
    # NED: the heading (−1.1 … +2.9°) follows the course over ground atan2(vE, vN) (−5.6 … −2.1°),
    # ≈ 4.8° apart (mounting or crab), correlation 0.99, both dipping by ≈ 2.5° at 45–50 s; the
    # opposite yaw sign gives correlation −0.99. Position agrees with velocity: dlat/dt (R_M + h) matches vN
    # to 0.03 m/s, so lat/lon are radians and vE, vN are in that order.
    c_enu = Rotation.from_euler("ZXY", np.stack([avp[:, 2], avp[:, 0], avp[:, 1]], axis=1)).as_matrix()
    c_ned = _PSINS_TO_SINS @ c_enu @ _PSINS_TO_SINS.T
    nav = NavSeries(
        t=avp[:, 9].copy(),
        lat=avp[:, 6].copy(),
        lon=avp[:, 7].copy(),
        h=avp[:, 8].copy(),
        v_n=avp[:, 3:6] @ _PSINS_TO_SINS.T,
        q_nb=rotation.quat_from_dcm(c_ned),
    )
    check_magnitude(path, "'mimu' rates (column / interval)", mems.omega, MAX_RATE_RADPS, "rad/s")
    check_magnitude(path, "'mimu' specific force (column / interval)", mems.f, MAX_FORCE_MPS2, "m/s²")
    check_magnitude(path, "'mimu' time", t_end, MAX_TIME_S, "s")
    check_magnitude(path, "'fogavp' time", nav.t, MAX_TIME_S, "s")
    check_magnitude(path, "'fogavp' attitude", avp[:, 0:3], 1e3, "rad")
    check_magnitude(path, "'fogavp' velocity", avp[:, 3:6], MAX_TRUTH_SPEED_MPS, "m/s")
    check_magnitude(path, "'fogavp' latitude", nav.lat, math.pi / 2, "rad")
    check_magnitude(path, "'fogavp' longitude", nav.lon, 1e3, "rad")
    check_magnitude(path, "'fogavp' height", nav.h, max(abs(a) for a in TRUTH_ALT_M), "m")
    overlap = min(mems.t_end[-1], nav.t[-1]) - max(mems.t_end[0], nav.t[0])
    if overlap < _MIN_INTERVALS * float(np.median(np.diff(nav.t))):
        raise SinsInputError(
            f"{path}: 'mimu' ({mems.t_end[0]:.6g}..{mems.t_end[-1]:.6g} s) and 'fogavp' "
            f"({nav.t[0]:.6g}..{nav.t[-1]:.6g} s) share fewer than {_MIN_INTERVALS} FOG-INS intervals"
        )
    return mems, nav


def _table(path: Path, content: dict[str, Any], name: str, columns: int) -> Array:
    """Variable ``name``: a finite (n, columns) array with increasing times in its last column."""
    if name not in content:
        raise SinsInputError(f"{path}: no variable {name!r}")
    value = content[name]
    if not (isinstance(value, np.ndarray) and value.ndim == 2 and value.shape[1] == columns):
        found = value.shape if isinstance(value, np.ndarray) else type(value).__name__
        raise SinsInputError(f"{path}: variable {name!r}: expected an (n, {columns}) array, found {found}")
    if not np.issubdtype(value.dtype, np.number) or value.shape[0] <= _MIN_INTERVALS:
        raise SinsInputError(
            f"{path}: variable {name!r}: expected more than {_MIN_INTERVALS} numeric rows, "
            f"found {value.shape[0]} of {value.dtype}"
        )
    table = np.asarray(value, dtype=float)
    bad = ~np.isfinite(table)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise SinsInputError(f"{path}: variable {name!r}: row {r + 1}, column {c + 1} is {table[r, c]}")
    step = np.diff(table[:, -1])
    if np.any(step <= 0.0):
        r = int(np.argmax(step <= 0.0)) + 1
        raise SinsInputError(
            f"{path}: variable {name!r}: row {r + 1}: time {table[r, -1]:.6g} s is not after the "
            "previous row's"
        )
    return table


# --------------------------------------------------------------------------- the reference


class _Reference:
    """The FOG-INS body's ``omega_ib_b`` and ``f_ib_b`` (FRD) in its span, on its clock."""

    def __init__(self, nav: NavSeries) -> None:
        from scipy.interpolate import CubicSpline
        from scipy.spatial.transform import Rotation, RotationSpline

        self.nav = nav
        self.attitude = RotationSpline(nav.t, Rotation.from_quat(nav.q_nb))
        self.velocity = CubicSpline(nav.t, nav.v_n, axis=0)

    def at(self, t: Array) -> tuple[Array, Array]:
        """Instantaneous ``omega_ib_b`` and ``f_ib_b`` at times ``t``."""
        # RotationSpline's first derivative is the body-frame rate: it matches the rotation vector of
        # C_nb(t)^T C_nb(t + 10 ms) / 10 ms to 2e-4 rad/s, and the navigation-frame one only to 5e-2.
        c_bn = self.attitude(t).inv()
        v = self.velocity(t)
        omega = self.attitude(t, 1) + c_bn.apply(self._omega_in(t, v))
        return omega, c_bn.apply(self._f_n(t, v, self.velocity(t, 1)))

    def interval_means(self) -> tuple[Array, Array, Array]:
        """Midpoints of the FOG-INS intervals, and the mean ``omega_ib_b`` and ``f_ib_b`` over each."""
        nav = self.nav
        dt = np.diff(nav.t)
        mid = 0.5 * (nav.t[1:] + nav.t[:-1])
        q = nav.q_nb
        # The attitude increment C_b(k) b(k+1) over the interval, as a rotation vector.
        step = rotation.turn_between(q[:-1], q[1:])
        v = 0.5 * (nav.v_n[1:] + nav.v_n[:-1])
        a = np.diff(nav.v_n, axis=0) / dt[:, None]
        c_bn = self.attitude(mid).inv()
        omega = step / dt[:, None] + c_bn.apply(self._omega_in(mid, v))
        return mid, omega, c_bn.apply(self._f_n(mid, v, a))

    def _earth(self, t: Array, v: Array) -> tuple[Array, Array, Array]:
        """``omega_ie_n``, ``omega_en_n`` (n, 3) and normal gravity (n,) at times ``t``."""
        lat = np.interp(t, self.nav.t, self.nav.lat)
        h = np.interp(t, self.nav.t, self.nav.h)
        ie = np.stack(np.broadcast_arrays(*earth.earth_rate_n(lat)), axis=1)
        en = np.stack(earth.transport_rate_n(lat, h, v[:, 0], v[:, 1]), axis=1)
        return ie, en, np.asarray(earth.normal_gravity(lat, h), dtype=float)

    def _omega_in(self, t: Array, v: Array) -> Array:
        ie, en, _ = self._earth(t, v)
        return np.asarray(ie + en, dtype=float)

    def _f_n(self, t: Array, v: Array, a: Array) -> Array:
        ie, en, g = self._earth(t, v)
        f = a + np.cross(2.0 * ie + en, v)
        f[:, 2] -= g
        return np.asarray(f, dtype=float)


def _on_mems(
    t: Array, omega_fog: Array, f_fog: Array, c_mems_fog: Array, lever_arm: Array
) -> tuple[Array, Array]:
    """The reference turned into the MEMS axes and moved to the MEMS's place."""
    omega = omega_fog @ c_mems_fog.T
    return omega, f_fog @ c_mems_fog.T + _lever_columns(t, omega) @ lever_arm


def _lever_columns(t: Array, omega: Array) -> Array:
    """(n, 3, 3): column j is ``ω̇ × e_j + ω × (ω × e_j)``, the specific force a unit offset along j adds."""
    omega_dot = np.gradient(omega, t, axis=0)
    out = np.empty((len(t), 3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = 1.0
        out[:, :, j] = np.cross(omega_dot, e) + np.cross(omega, np.cross(omega, e))
    return out


def _mems_means(mems: _Mems, x: Array, start: Array, stop: Array) -> Array:
    """Means of the MEMS rate ``x`` (constant over each row's interval) over ``(start, stop]``, MEMS clock."""
    edges = np.r_[mems.t_end[0] - mems.dt[0], mems.t_end]
    integral = np.vstack([np.zeros((1, 3)), np.cumsum(x * mems.dt[:, None], axis=0)])
    at = [np.stack([np.interp(s, edges, integral[:, j]) for j in range(3)], axis=1) for s in (start, stop)]
    return np.asarray((at[1] - at[0]) / (stop - start)[:, None], dtype=float)


def _interval_means(
    mems: _Mems, ref: _Reference, offset_s: float
) -> tuple[Array, Array, Array, Array, Array]:
    """Times (MEMS clock), MEMS gyro and accel, reference rate and specific force (FOG axes): 0.1 s means."""
    start, stop = ref.nav.t[:-1] - offset_s, ref.nav.t[1:] - offset_s
    inside = (start >= mems.t_end[0] - mems.dt[0]) & (stop <= mems.t_end[-1])
    mid, omega, f = ref.interval_means()
    start, stop = start[inside], stop[inside]
    return (
        mid[inside] - offset_s,
        _mems_means(mems, mems.omega, start, stop),
        _mems_means(mems, mems.f, start, stop),
        omega[inside],
        f[inside],
    )


def _correlation(a: Array, b: Array) -> float:
    a, b = a - a.mean(), b - b.mean()
    return float(a @ b) / math.sqrt(float(a @ a) * float(b @ b))


def _estimate_alignment(mems: _Mems, ref: _Reference, path: Path) -> PsinsAlignment:
    """Time offset, mounting rotation and lever arm, in that order, each fitted on 0.1 s means.

    On means over the FOG-INS's intervals both sides carry the same motion; at 100 Hz the MEMS's
    vibration above 5 Hz, which the reference lacks, would flatten the correlation peak and bias it
    (the figures are in ``docs/guide/datasets.md``).
    """
    from scipy.spatial.transform import Rotation

    t_fog = ref.nav.t
    _, omega_ref, f_ref = ref.interval_means()
    # The intervals the MEMS covers at every offset tried.
    inside = (t_fog[:-1] - _MAX_OFFSET_S >= mems.t_end[0] - mems.dt[0]) & (
        t_fog[1:] + _MAX_OFFSET_S <= mems.t_end[-1]
    )
    if inside.sum() < _MIN_INTERVALS:
        raise SinsInputError(
            f"{path}: fewer than {_MIN_INTERVALS} FOG-INS intervals lie within the MEMS recording"
        )
    start, stop = t_fog[:-1][inside], t_fog[1:][inside]
    omega_ref, f_ref = omega_ref[inside], f_ref[inside]

    # The fits need rotation about two axes at least (Wahba's problem is singular otherwise); 1e-3 rad/s
    # RMS is 20 times the 10 Hz disagreement of this file's two units (its spreads: 3.4, 0.9, 0.4 °/s).
    spread = np.linalg.svd(omega_ref - omega_ref.mean(axis=0), compute_uv=False) / math.sqrt(len(omega_ref))
    if spread[1] < 1e-3:
        raise SinsInputError(
            f"{path}: 'fogavp' turns about fewer than two axes (rate spreads "
            f"{', '.join(f'{s:.2g}' for s in spread)} rad/s): too little to align the units by"
        )
    # Time offset: |ω| does not depend on the mounting rotation.
    magnitude = np.linalg.norm(omega_ref, axis=1)
    offsets = np.arange(-_MAX_OFFSET_S, _MAX_OFFSET_S + 0.5 * _OFFSET_STEP_S, _OFFSET_STEP_S)
    scores = np.array(
        [
            _correlation(
                np.linalg.norm(_mems_means(mems, mems.omega, start - d, stop - d), axis=1), magnitude
            )
            for d in offsets
        ]
    )
    i = int(np.argmax(scores))
    offset = float(offsets[i])
    if 0 < i < len(offsets) - 1:
        y0, y1, y2 = (float(s) for s in scores[i - 1 : i + 2])
        if y0 - 2.0 * y1 + y2 < 0.0:
            offset += _OFFSET_STEP_S * 0.5 * (y0 - y2) / (y0 - 2.0 * y1 + y2)
    omega_mems = _mems_means(mems, mems.omega, start - offset, stop - offset)
    f_mems = _mems_means(mems, mems.f, start - offset, stop - offset)

    # Mounting rotation: Wahba's problem on the rate vectors, each side's mean (the MEMS's bias) removed.
    fit, _ = Rotation.align_vectors(omega_mems - omega_mems.mean(axis=0), omega_ref - omega_ref.mean(axis=0))
    c = fit.as_matrix()

    # Lever arm: accelerometer error = bias + 3×3 scale/misalignment + lever-arm terms, least squares.
    omega = omega_ref @ c.T
    f = f_ref @ c.T
    lever = _lever_columns(0.5 * (start + stop) - offset, omega)
    n = len(f)
    design = np.zeros((3, n, 15))
    for axis in range(3):
        design[axis, :, axis] = 1.0
        design[axis, :, 3 + 3 * axis : 6 + 3 * axis] = f
        design[axis, :, 12:15] = lever[:, axis, :]
    solution, *_ = np.linalg.lstsq(design.reshape(3 * n, 15), (f_mems - f).T.reshape(3 * n), rcond=None)
    return PsinsAlignment(
        offset_s=offset,
        c_mems_fog=c,
        lever_arm_m=np.asarray(solution[12:15], dtype=float),
        correlation=_correlation(np.linalg.norm(omega_mems, axis=1), magnitude),
    )


__all__ = [
    "PSINS_VEHICLE_FILE",
    "PSINS_VEHICLE_FOLDER",
    "PsinsAlignment",
    "psins_alignment",
    "read_psins_vehicle",
]
