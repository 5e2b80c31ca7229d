"""Recordings of one numpy unit, and the .npz form written from them, for the tests of fits on several
recordings and of the .npz reader: numpy and scipy's Rotation only (tests/numpy_referenced.py's sessions)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
from numpy_referenced import HEIGHT_M, LAT_DEG, session, typical_unit
from scipy.integrate import cumulative_trapezoid
from scipy.spatial.transform import Rotation

from sins.compensation import judging, referenced
from sins.core.series import ImuRates, NavSeries


def recordings(
    seed: int, count: int = 3, *, calibrated: bool = False
) -> tuple[list[referenced.ReferencedRecording], object, np.ndarray]:
    """``count`` sessions of one numpy unit whose gyro and accelerometer biases are drawn anew for each
    (the bias between power-ups), everything else shared; ``calibrated``: a gyro read calibrated at
    every power-up (no bias, scale, misalignment or delay; its noise alone)."""
    rng = np.random.default_rng(seed)
    unit = typical_unit(rng)
    if calibrated:
        unit = replace(unit, B=np.zeros((3, 3)), gyro_delay_s=0.0)
    recs, biases = [], []
    for k in range(count):
        gyro_bias = np.zeros(3) if calibrated else np.radians(rng.normal(0.0, 0.1, 3))
        own = replace(unit, B0=gyro_bias, A0=rng.normal(0.0, 0.05, 3))
        s = session(rng, own, duration_s=120.0)
        truth = NavSeries(
            t=s.t_ref, lat=np.full(len(s.t_ref), math.radians(LAT_DEG)), lon=np.zeros(len(s.t_ref)),
            h=np.full(len(s.t_ref), HEIGHT_M), v_n=s.v_n, q_nb=s.q_nb,
        )  # fmt: skip
        rec = judging.from_recording(ImuRates(t=s.t, omega_ib_b=s.gyro, f_ib_b=s.accel), truth, f"numpy {k}")
        recs.append(rec)
        biases.append(own.B0)
    return recs, unit, np.array(biases)


def write_npz(folder: Path, name: str, rec: referenced.ReferencedRecording, positions: bool = False) -> None:
    """A numpy recording written in the .npz form (rates at the step boundaries, the reference there);
    its positions zero, or with ``positions`` its velocity's integral (east, north, up from its start), as
    ``sins evaluate --outage`` needs them."""
    keep = int(np.searchsorted(rec.imu.t, rec.reference.t[-1], side="right"))
    t = rec.imu.t[:keep]
    dt = np.diff(t)[:, None]
    rate = np.vstack([rec.imu.dtheta_b[: keep - 1] / dt, rec.imu.dtheta_b[keep - 2 : keep - 1] / dt[-1:]])
    force = np.vstack([rec.imu.dv_b[: keep - 1] / dt, rec.imu.dv_b[keep - 2 : keep - 1] / dt[-1:]])
    ref = rec.reference.interpolate(t)
    q = Rotation.from_quat(ref.q_nb)
    ned_to_enu = Rotation.from_matrix([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    v_enu = ref.v_n[:, [1, 0, 2]] * [1, 1, -1]
    np.savez(
        folder / f"{name}.npz", t_s=t, gyro_rad_s=rate, accel_m_s2=force,
        q_wxyz=(ned_to_enu * q).as_quat(scalar_first=True), v_m_s=v_enu,
        p_m=_enu_from_start(t, v_enu) if positions else np.zeros((len(t), 3)),
    )  # fmt: skip


def _enu_from_start(t: np.ndarray, v_enu: np.ndarray) -> np.ndarray:
    """Positions from the start, east, north, up, m: the reference's velocity integrated by the trapezoid
    rule (:func:`numpy_referenced.session` moves the unit by its velocity alone, its latitude held)."""
    return np.asarray(cumulative_trapezoid(v_enu, t, axis=0, initial=0.0))
