"""``tests/independent_rig.py`` against analytic facts, and its files against sins's reader.

The generator is numpy alone; the checks here use their own rotation code (rotation matrices, not the
generator's quaternions) so that a shared mistake cannot pass unseen.
"""

from __future__ import annotations

import dataclasses

import independent_rig as ir
import numpy as np
import pytest

from sins import io

G, OMEGA, LAT = 9.80665, 7.292115e-5, np.radians(45.0)
W_IE_N = OMEGA * np.array([np.cos(LAT), 0.0, -np.sin(LAT)])


@pytest.fixture(scope="module")
def sessions() -> dict[str, ir.Session]:
    return {"tumble_and_table": ir.tumble_and_table(), "faces_and_axis_table": ir.faces_and_axis_table(),
            "continuous_tumble": ir.continuous_tumble()}  # fmt: skip


# ----------------------------------------------------------------------------------------------- helpers


def _skew(v: np.ndarray) -> np.ndarray:
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    return out - np.swapaxes(out, -1, -2)


def _rodrigues(rv: np.ndarray) -> np.ndarray:
    """exp([rv×]) = I + sin θ K + (1 - cos θ) K², K the unit axis's cross matrix."""
    theta = np.linalg.norm(rv, axis=-1)[..., None, None]
    K = _skew(rv / np.where(theta[..., 0] > 0, theta[..., 0], 1.0))
    return np.eye(3) + np.sin(theta) * K + (1 - np.cos(theta)) * K @ K


def _running_products(M: np.ndarray) -> np.ndarray:
    """``M[0] @ M[1] @ … @ M[k]`` for every k (prefix scan; the earlier factor stays on the left)."""
    out, d = M.copy(), 1
    while d < len(out):
        out[d:] = out[:-d] @ out[d:]
        d *= 2
    return out


def _body_turns(ref_gyro: np.ndarray, rate_hz: float) -> np.ndarray:
    """``B_k``: the body's turn relative to inertial space from sample 0 to k, from ``omega_ib_b`` alone.

    Second order with halved steps: the rate is linear between samples; each half step turns by the
    trapezoid of its ends (3ω_k + ω_k+1)h/8, then (ω_k + 3ω_k+1)h/8, composed in body axes.
    """
    h = 1.0 / rate_hz
    a, b = ref_gyro[:-1], ref_gyro[1:]
    steps = _rodrigues((3 * a + b) * h / 8) @ _rodrigues((a + 3 * b) * h / 8)
    return _running_products(np.concatenate([np.eye(3)[None], steps]))


def _step_bounds(ref_gyro: np.ndarray, rate_hz: float) -> np.ndarray:
    """A bound on each sample step's attitude error from the samples alone (n - 1,), rad.

    The trapezoid of a linearly interpolated rate errs by ≤ h³|ω̈|/12 where ω is smooth, ≤ h²Δs/8
    at a kink (slope change Δs, a table ramp's ends) and ≤ h|Δω|/2 at a jump (a tumble turn's start
    and end, instants the samples cannot place). The second differences dd_k, dd_k+1 at a step's ends
    sum to ~2h²|ω̈|, Δs·h or 2|Δω| in those cases, so h (|dd_k| + |dd_k+1|)/4 covers all three. Two half
    steps leave h³|ω × ω̇|/48 of the rate's non-commutativity (coning) unaccounted.
    """
    h = 1.0 / rate_hz
    dd = np.zeros(len(ref_gyro))
    dd[1:-1] = np.linalg.norm(ref_gyro[2:] - 2 * ref_gyro[1:-1] + ref_gyro[:-2], axis=1)
    d = ref_gyro[1:] - ref_gyro[:-1]
    coning = np.linalg.norm(np.cross(ref_gyro[:-1], d), axis=1) * h**2 / 48
    return h * (dd[:-1] + dd[1:]) / 4 + coning


def _triad(f: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``C_nb`` (n, 3, 3) of a unit at rest, from its force and rate: f is up, and ω_b = Ω(cos φ N_b -
    sin φ D_b) gives north: N_b = (ω_b/Ω + sin φ D_b)/cos φ. Rows of C_nb: N_b, E_b, D_b."""
    down = -f / np.linalg.norm(f, axis=1, keepdims=True)
    north = (w / OMEGA + np.sin(LAT) * down) / np.cos(LAT)
    north -= (north * down).sum(axis=1, keepdims=True) * down
    north /= np.linalg.norm(north, axis=1, keepdims=True)
    return np.stack([north, np.cross(down, north), down], axis=1)


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), (a * b).sum(axis=1))


def _rotation_angle(R: np.ndarray) -> np.ndarray:
    """The angle of each rotation matrix, precise near zero (from the skew part: sin θ)."""
    skew = (R - np.swapaxes(R, -1, -2)) / 2
    s = np.linalg.norm(np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=1), axis=1)
    c = (np.trace(R, axis1=1, axis2=2) - 1) / 2
    return np.arctan2(s, c)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of True."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(int), 0]))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))
