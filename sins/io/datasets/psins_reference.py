"""The PSINS FOG/MEMS vehicle recording as a :class:`~sins.core.series.ReferencedRecording`: the MEMS's own
increments beside the FOG-INS navigation solution at its 10 Hz epochs, on the MEMS's clock and in its
axes (the time offset and mounting rotation :func:`~sins.io.datasets.psins_vehicle.psins_alignment`
estimates), nothing differentiated.
"""

from __future__ import annotations

import os

# scipy's io, signal and interpolate modules are imported in the functions that use them: ~0.6 s at
# import, which every command paid for any recording (tools/bench_startup.py).
import numpy as np
from numpy.typing import NDArray

from sins.core import earth, rotation
from sins.core.series import ImuIncrements, NavSeries, ReferencedRecording
from sins.errors import SinsInputError
from sins.io.datasets.psins_vehicle import _PSINS_TO_SINS, _load, _path, psins_alignment, read_psins_vehicle

Array = NDArray[np.float64]


def _read_psins_vehicle_reference(root: str | os.PathLike[str] | None = None) -> ReferencedRecording:
    """The MEMS's 100 Hz increments (FRD) beside the FOG-INS solution of the MEMS's body.

    ``imu.t`` are the MEMS's stamps (each row integrates the 10 ms before its stamp; the first row's
    interval starts one step before the first stamp); the reference is
    :func:`~sins.io.datasets.psins_vehicle.read_psins_vehicle`'s solution of the MEMS body (attitude),
    on the MEMS clock, within the increments' span, with the FOG-INS's position and velocity moved to
    the MEMS's place by the lever arm :func:`~sins.io.datasets.psins_vehicle.psins_alignment` estimates
    (0.19 m: at the vehicle's roll rates its velocity differs by up to 0.06 m/s). Every step is judged.

    Raises
    ------
    SinsInputError
        as :func:`~sins.io.datasets.psins_vehicle.read_psins_vehicle`.
    """
    path = _path(root)
    mems, _ = _load(path)
    _, nav = read_psins_vehicle(root)
    assert nav is not None  # the file always has its FOG-INS solution
    t = np.r_[mems.t_end[0] - mems.dt[0], mems.t_end]
    inside = (nav.t >= t[0]) & (nav.t <= t[-1])
    return ReferencedRecording(
        imu=ImuIncrements(t=t, dtheta_b=mems.omega * mems.dt[:, None], dv_b=mems.f * mems.dt[:, None]),
        reference=_at_mems(nav, psins_alignment(root).lever_arm_m).at(np.flatnonzero(inside)),
        judged=None,
        sensor="PSINS vehicle MEMS (transfer_align_fog_mems.mat)",
        reference_name="FOG-INS navigation solution (10 Hz)",
        source=str(path),
    )


def _at_mems(nav: NavSeries, arm: Array) -> NavSeries:
    """The FOG-INS's solution moved to the MEMS at ``arm`` (MEMS axes, m): position by ``C_nb r``,
    velocity by ``C_nb (ω_nb × r)`` with ``ω_nb`` the rate of a rotation spline through the attitudes."""
    from scipy.spatial.transform import Rotation, RotationSpline

    c_nb = rotation.dcm_from_quat(nav.q_nb)
    omega = RotationSpline(nav.t, Rotation.from_quat(nav.q_nb))(nav.t, 1)  # body rate, rad/s, body axes
    offset = c_nb @ arm
    r_m, r_n = earth.radii(nav.lat)
    return NavSeries(
        t=nav.t,
        lat=nav.lat + offset[:, 0] / (r_m + nav.h),
        lon=nav.lon + offset[:, 1] / ((r_n + nav.h) * np.cos(nav.lat)),
        h=nav.h - offset[:, 2],
        v_n=nav.v_n + np.einsum("kab,kb->ka", c_nb, np.cross(omega, arm)),
        q_nb=nav.q_nb,
    )


def psins_file_biases(root: str | os.PathLike[str] | None = None) -> tuple[Array, Array]:
    """The file's undocumented ``eb0`` (gyro, rad/s) and ``db0`` (accelerometer, m/s²), in FRD: the
    biases the PSINS demo's plots compare its filter's estimates with.

    Raises
    ------
    SinsInputError
        when the file lacks either variable or it is not three numbers.
    """
    import scipy.io

    path = _path(root)
    content = scipy.io.loadmat(path, squeeze_me=True, variable_names=["eb0", "db0"])
    out = []
    for name in ("eb0", "db0"):
        value = np.asarray(content.get(name, np.empty(0)), dtype=float).reshape(-1)
        if value.shape != (3,) or not np.isfinite(value).all():
            raise SinsInputError(f"{path}: variable {name!r}: expected three finite numbers")
        out.append(_PSINS_TO_SINS @ value)
    return out[0], out[1]


__all__ = [
    "psins_file_biases",
]
