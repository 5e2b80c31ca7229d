"""Navigation errors against a truth, and their summary.

Errors are estimate − truth. Position errors are in metres along the truth's
local north, east and down: ``δN = δlat (R_M + h)``, ``δE = δlon (R_N + h) cos lat``,
``δD = -δh``; linearised, which is within 0.01 % for errors below 100 km.
Attitude errors are the differences of ZYX Euler angles, wrapped to ±180°.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numba
import numpy as np
from numpy.typing import NDArray

from sins.core import earth
from sins.core.rotation import GIMBAL_LOCK
from sins.core.series import NavSeries

Array = NDArray[np.float64]

#: One international nautical mile, m.
NAUTICAL_MILE_M = 1852.0


@dataclass(frozen=True)
class NavErrors:
    """Error series at ``n`` common times.

    Attributes
    ----------
    t : (n,) s
    pos_ned_m : (n, 3) north, east, down position error, m
    vel_ned_mps : (n, 3) velocity error, m/s
    att_rpy_rad : (n, 3) roll, pitch, yaw error, rad
    """

    t: Array
    pos_ned_m: Array
    vel_ned_mps: Array
    att_rpy_rad: Array

    @property
    def horizontal_m(self) -> Array:
        """Horizontal position error (n,), m: the norm of the north and east errors."""
        north, east = self.pos_ned_m[:, 0], self.pos_ned_m[:, 1]
        return np.sqrt(
            north * north + east * east
        )  # errors far below hypot's overflow, at a quarter of its cost

    def at(self, index: NDArray[np.integer] | slice) -> NavErrors:
        """The errors at ``index``."""
        return NavErrors(
            t=self.t[index],
            pos_ned_m=self.pos_ned_m[index],
            vel_ned_mps=self.vel_ned_mps[index],
            att_rpy_rad=self.att_rpy_rad[index],
        )


def nav_errors(estimate: NavSeries, truth: NavSeries) -> NavErrors:
    """Errors of ``estimate`` against ``truth``.

    When the time bases differ, the truth is interpolated to the estimate's
    times that fall within the truth's span (see :meth:`NavSeries.interpolate`).
    """
    if len(estimate.t) != len(truth.t) or not np.array_equal(estimate.t, truth.t):
        inside = (estimate.t >= truth.t[0] - 1e-9) & (estimate.t <= truth.t[-1] + 1e-9)
        if not inside.any():
            raise ValueError("the estimate and the truth share no time span")
        estimate = estimate.at(np.flatnonzero(inside))
        truth = truth.interpolate(estimate.t)
    return errors_against(estimate, TruthFrame.of(truth))[0]


#: The columns of a :class:`TruthFrame`'s ``data``.
_T, _LAT, _LON, _H, _V, _Q, _RM_H, _RN_H, _COS_LAT, _EULER = 0, 1, 2, 3, 4, 7, 11, 12, 13, 14
_FRAME_COLUMNS = 17


@dataclass(frozen=True)
class TruthFrame:
    """A truth series and what every estimate compared with it needs, computed once.

    Many streams (strategies, units) are compared with one truth: its radii, ``cos lat`` and Euler
    angles are the same for all of them. ``data`` (n, 17) holds per row ``t``, ``lat``, ``lon``,
    ``h``, ``v_n`` (3), ``q_nb`` (4), ``R_M + h``, ``R_N + h``, ``cos lat`` and roll, pitch, yaw:
    one array, so that a frame is sliced and joined as cheaply as one.
    """

    data: Array

    @classmethod
    def of(cls, truth: NavSeries) -> TruthFrame:
        """The frame of ``truth``."""
        r_m, r_n = earth.radii(truth.lat)
        data = np.empty((len(truth.t), _FRAME_COLUMNS))
        data[:, _T], data[:, _LAT], data[:, _LON], data[:, _H] = truth.t, truth.lat, truth.lon, truth.h
        data[:, _V:_Q], data[:, _Q:_RM_H] = truth.v_n, truth.q_nb
        data[:, _RM_H], data[:, _RN_H] = r_m + truth.h, r_n + truth.h
        data[:, _COS_LAT] = np.cos(truth.lat)
        data[:, _EULER:] = _euler_angles(np.ascontiguousarray(truth.q_nb, dtype=float))
        return cls(data)

    def __len__(self) -> int:
        return len(self.data)

    @property
    def t(self) -> Array:
        """The times (n,), s."""
        return self.data[:, _T]

    @property
    def h(self) -> Array:
        """The heights (n,), m."""
        return self.data[:, _H]

    def rows(self, start: int, stop: int) -> TruthFrame:
        """Rows ``start .. stop`` (a view)."""
        return TruthFrame(self.data[start:stop])

    def truth(self, index: NDArray[np.integer] | slice = slice(None)) -> NavSeries:
        """The truth's states at ``index``."""
        d = self.data[index]
        return NavSeries(t=d[:, _T], lat=d[:, _LAT], lon=d[:, _LON], h=d[:, _H], v_n=d[:, _V:_Q],
                         q_nb=d[:, _Q:_RM_H])  # fmt: skip

    @staticmethod
    def join(frames: list[TruthFrame]) -> TruthFrame:
        """The frames one after the other."""
        return frames[0] if len(frames) == 1 else TruthFrame(np.concatenate([f.data for f in frames]))


def errors_against(estimate: NavSeries, frame: TruthFrame) -> tuple[NavErrors, Array]:
    """Errors of ``estimate`` against the truth of ``frame`` at the same times, and the horizontal
    error (n,), m, in one compiled pass.

    The same arithmetic, in the same order, as the numpy expressions in the module docstring
    (``tests/test_metrics.py`` holds it to them, to the last bit).
    """
    n = len(estimate.t)
    if len(frame) != n:
        raise ValueError(f"the estimate has {n} states, the truth frame {len(frame)}")
    pos, vel, att, hor = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty(n)
    lat, lon, h, v, q = (
        np.ascontiguousarray(a, dtype=float)
        for a in (estimate.lat, estimate.lon, estimate.h, estimate.v_n, estimate.q_nb)
    )
    _errors_kernel(lat, lon, h, v, q, np.ascontiguousarray(frame.data), pos, vel, att, hor)
    return NavErrors(t=estimate.t, pos_ned_m=pos, vel_ned_mps=vel, att_rpy_rad=att), hor


@numba.njit(cache=True, nogil=True, inline="always")
def _euler(x: float, y: float, z: float, w: float) -> tuple[float, float, float]:
    """ZYX Euler angles (roll, pitch, yaw) of a scalar-last quaternion, as :mod:`sins.core.rotation`."""
    c00, c10 = 1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z)
    c20, c21, c22 = 2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)
    pitch = np.arctan2(-c20, np.sqrt(c00 * c00 + c10 * c10))
    if c21 * c21 + c22 * c22 < GIMBAL_LOCK * GIMBAL_LOCK:  # gimbal lock: roll 0, yaw takes the rest
        return 0.0, pitch, np.arctan2(-2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z))
    return np.arctan2(c21, c22), pitch, np.arctan2(c10, c00)


@numba.njit(cache=True, nogil=True, inline="always")
def _wrap(d: float) -> float:
    return d - 2.0 * np.pi * np.round(d / (2.0 * np.pi))


@numba.njit(cache=True, nogil=True)
def _euler_angles(q: Array) -> Array:
    out = np.empty((q.shape[0], 3))
    for k in range(q.shape[0]):
        out[k, 0], out[k, 1], out[k, 2] = _euler(q[k, 0], q[k, 1], q[k, 2], q[k, 3])
    return out


@numba.njit(cache=True, nogil=True)
def _euler_errors(q_est: Array, q_true: Array) -> Array:
    n = q_est.shape[0]
    out = np.empty((n, 3))
    for k in range(n):
        e = _euler(q_est[k, 0], q_est[k, 1], q_est[k, 2], q_est[k, 3])
        r = _euler(q_true[k, 0], q_true[k, 1], q_true[k, 2], q_true[k, 3])
        for i in range(3):
            out[k, i] = _wrap(e[i] - r[i])
    return out


@numba.njit(cache=True, nogil=True)
def _errors_kernel(
    lat: Array, lon: Array, h: Array, v: Array, q: Array, ref: Array,
    pos: Array, vel: Array, att: Array, hor: Array,
) -> None:  # fmt: skip
    for k in range(lat.shape[0]):
        r = ref[k]
        pos[k, 0] = (lat[k] - r[_LAT]) * r[_RM_H]
        pos[k, 1] = _wrap(lon[k] - r[_LON]) * r[_RN_H] * r[_COS_LAT]
        pos[k, 2] = -(h[k] - r[_H])
        for i in range(3):
            vel[k, i] = v[k, i] - r[_V + i]
        e = _euler(q[k, 0], q[k, 1], q[k, 2], q[k, 3])
        for i in range(3):
            att[k, i] = _wrap(e[i] - r[_EULER + i])
        hor[k] = np.sqrt(pos[k, 0] * pos[k, 0] + pos[k, 1] * pos[k, 1])


@numba.njit(cache=True, nogil=True)
def _max_abs_columns(x: Array) -> Array:
    """``np.abs(x).max(axis=0)`` of an (n, k) array, NaN propagated as numpy does, in one pass."""
    out = np.abs(x[0].copy())
    for k in range(1, x.shape[0]):
        for i in range(x.shape[1]):
            a = abs(x[k, i])
            if a > out[i] or a != a:
                out[i] = a
    return out


def euler_errors(q_est: Array, q_true: Array) -> Array:
    """Roll, pitch, yaw of ``q_est`` minus those of ``q_true``, wrapped to ±π, shape (n, 3).

    The compiled equivalent of ``wrap_angle(euler_from_quat(q_est) - euler_from_quat(q_true))``
    (:mod:`sins.core.rotation`), which ``tests/test_metrics.py`` holds it to.
    """
    return _euler_errors(np.ascontiguousarray(q_est, dtype=float), np.ascontiguousarray(q_true, dtype=float))


@dataclass(frozen=True)
class DriftSummary:
    """The headline figures of a run (errors are estimate − truth).

    ``drift_rate_m_per_h`` is the final horizontal error divided by the elapsed
    time; ``*_rms_*`` are over all compared samples.
    """

    duration_s: float
    final_north_m: float
    final_east_m: float
    final_down_m: float
    final_horizontal_m: float
    max_horizontal_m: float
    rms_horizontal_m: float
    final_vn_mps: float
    final_ve_mps: float
    final_vd_mps: float
    final_roll_deg: float
    final_pitch_deg: float
    final_yaw_deg: float
    max_roll_deg: float
    max_pitch_deg: float
    max_yaw_deg: float
    drift_rate_m_per_h: float
    drift_rate_nmi_per_h: float

    def to_dict(self) -> dict[str, float]:
        """The figures keyed by field name."""
        return asdict(self)


class DriftAccumulator:
    """Summary statistics of an error series fed chunk by chunk, and a thinned copy of it.

    The statistics use every sample; the copy keeps the samples whose running
    index is a multiple of ``keep_every`` plus the last one, so long runs can
    be summarised and plotted without holding them whole. ``keep_every=0``
    keeps no copy.
    """

    def __init__(self, keep_every: int = 1) -> None:
        if keep_every < 0:
            raise ValueError(f"keep_every must be >= 0, got {keep_every}")
        self.keep_every = keep_every
        self._count = 0
        self._t0: float | None = None
        self._last: NavErrors | None = None
        self._max_hor = 0.0
        self._sum_hor2 = 0.0
        self._max_att = np.zeros(3)
        self._kept: list[NavErrors] = []

    def add(self, errors: NavErrors, horizontal: Array | None = None) -> None:
        """Take the next chunk (times continue the previous chunk's); ``horizontal``: its horizontal
        error if already computed (:func:`errors_against`)."""
        n = len(errors.t)
        if n == 0:
            return
        hor = errors.horizontal_m if horizontal is None else horizontal
        if self._t0 is None:
            self._t0 = float(errors.t[0])
        # np.maximum, not max(): a NaN (a diverged solution) stays NaN, where max(0.0, nan) read 0.0
        self._max_hor = float(np.maximum(self._max_hor, hor.max()))
        self._sum_hor2 += float(np.dot(hor, hor))
        self._max_att = np.maximum(self._max_att, _max_abs_columns(np.ascontiguousarray(errors.att_rpy_rad)))
        if self.keep_every:
            keep = kept_indices(self._count, n, self.keep_every)
            if keep.size:
                self._kept.append(errors.at(keep))
        self._count += n
        self._last = errors.at(np.array([n - 1]))

    def summary(self) -> DriftSummary:
        """Final, maximum and RMS errors and the drift rate of everything added."""
        if self._last is None or self._t0 is None:
            raise ValueError("no errors were added")
        last = self._last
        duration = float(last.t[0]) - self._t0
        final_hor = float(last.horizontal_m[0])
        rate = final_hor / (duration / 3600.0) if duration > 0 else 0.0
        att_deg = np.degrees(last.att_rpy_rad[0])
        max_att_deg = np.degrees(self._max_att)
        return DriftSummary(
            duration_s=duration,
            final_north_m=float(last.pos_ned_m[0, 0]),
            final_east_m=float(last.pos_ned_m[0, 1]),
            final_down_m=float(last.pos_ned_m[0, 2]),
            final_horizontal_m=final_hor,
            max_horizontal_m=self._max_hor,
            rms_horizontal_m=float(np.sqrt(self._sum_hor2 / self._count)),
            final_vn_mps=float(last.vel_ned_mps[0, 0]),
            final_ve_mps=float(last.vel_ned_mps[0, 1]),
            final_vd_mps=float(last.vel_ned_mps[0, 2]),
            final_roll_deg=float(att_deg[0]),
            final_pitch_deg=float(att_deg[1]),
            final_yaw_deg=float(att_deg[2]),
            max_roll_deg=float(max_att_deg[0]),
            max_pitch_deg=float(max_att_deg[1]),
            max_yaw_deg=float(max_att_deg[2]),
            drift_rate_m_per_h=rate,
            drift_rate_nmi_per_h=rate / NAUTICAL_MILE_M,
        )

    def kept(self) -> NavErrors:
        """The thinned series, ending with the last sample added."""
        if not self.keep_every:
            raise ValueError("this accumulator keeps no series (keep_every=0)")
        parts = list(self._kept)
        if self._last is not None and (self._count - 1) % self.keep_every != 0:
            parts.append(self._last)
        if not parts:
            raise ValueError("no errors were added")
        return NavErrors(
            t=np.concatenate([p.t for p in parts]),
            pos_ned_m=np.concatenate([p.pos_ned_m for p in parts]),
            vel_ned_mps=np.concatenate([p.vel_ned_mps for p in parts]),
            att_rpy_rad=np.concatenate([p.att_rpy_rad for p in parts]),
        )


def kept_indices(offset: int, n: int, every: int) -> NDArray[np.intp]:
    """Indices ``i`` in ``range(n)`` whose running index ``offset + i`` is a multiple of ``every``."""
    return np.arange((-offset) % every, n, every)


def thinned_indices(n: int, every: int) -> NDArray[np.intp]:
    """Every ``every``-th index of ``range(n)`` from 0, plus the last: a thinned series ends where it ends."""
    keep = kept_indices(0, n, every)
    return keep if n == 0 or keep[-1] == n - 1 else np.append(keep, n - 1)


def block_means(values: Array, every: int) -> Array:
    """Means of consecutive blocks of ``every`` rows of ``values`` (n, k); the last block may be shorter."""
    n = len(values)
    starts = np.arange(0, n, every)
    sums = np.add.reduceat(values, starts, axis=0) if n else values[:0]
    return sums / np.diff(np.append(starts, n))[:, None]


class BlockMeans:
    """:func:`block_means` of rows fed chunk by chunk: means of consecutive blocks of ``every`` rows
    counted from the first row fed, the last block possibly shorter (a block may span chunks).

    A block's rows are summed in order, one compiled pass a chunk (:func:`block_means`' pairwise sums
    may differ in the last bits).
    """

    def __init__(self, every: int) -> None:
        if every < 1:
            raise ValueError(f"every must be >= 1, got {every}")
        self.every = every
        self._means: list[Array] = []
        self._partial: Array | None = None  # the open block's sum
        self._count = 0  # rows in the open block

    def add(self, values: Array) -> None:
        """Take the next rows (n, k)."""
        self.add_difference((values,), np.zeros((0, 0)), np.zeros(0))

    def add_difference(self, parts: tuple[Array, ...], reference: Array, step: Array) -> None:
        """Take the next rows ``(parts side by side − reference) / step``, without making them: ``parts``
        (n, k_i) each, ``reference`` (n, Σ k_i) and ``step`` (n,), or either with no rows for none."""
        values = [np.ascontiguousarray(p, dtype=float) for p in parts]
        width = sum(v.shape[1] for v in values)
        if self._partial is None:
            self._partial = np.zeros(width)
        if not values[0].shape[0]:
            return
        every, count = self.every, self._count
        blocks = (count + values[0].shape[0]) // every
        out = np.empty((blocks, width))
        ref = np.ascontiguousarray(reference, dtype=float)
        step = np.ascontiguousarray(step, dtype=float)
        offset = 0
        for v in values:
            _block_sums(v, ref, offset, step, every, count, self._partial[offset : offset + v.shape[1]], out)
            offset += v.shape[1]
        self._count = (count + values[0].shape[0]) % every
        if blocks:
            self._means.append(out)

    def means(self) -> Array:
        """The block means so far, the open block's included, (m, k)."""
        parts = list(self._means)
        if self._count:
            assert self._partial is not None
            parts.append((self._partial / self._count)[None])
        return np.concatenate(parts) if parts else np.zeros((0, 0))


@numba.njit(cache=True, nogil=True, error_model="numpy")  # numpy's division: no zero check a row
def _block_sums(
    values: Array, ref: Array, offset: int, step: Array, every: int, count: int, partial: Array, out: Array
) -> None:
    """Columns ``offset ..`` of ``out``: the means of the blocks ``values`` completes, of the rows
    ``(values − ref[:, offset ..]) / step`` (``ref`` or ``step`` with no rows: none), the open block's
    sum ``partial`` (``count`` rows) carried in place."""
    width, has_ref, has_step = values.shape[1], ref.shape[0] > 0, step.shape[0] > 0
    block = 0
    for k in range(values.shape[0]):
        for i in range(width):
            x = values[k, i] - ref[k, offset + i] if has_ref else values[k, i]
            partial[i] += x / step[k] if has_step else x
        count += 1
        if count == every:
            for i in range(width):
                out[block, offset + i] = partial[i] / every
                partial[i] = 0.0
            block += 1
            count = 0


def summarize(errors: NavErrors) -> DriftSummary:
    """Final, maximum and RMS errors and the drift rate of a whole error series."""
    acc = DriftAccumulator(keep_every=0)
    acc.add(errors)
    return acc.summary()


__all__ = [
    "NAUTICAL_MILE_M",
    "BlockMeans",
    "DriftAccumulator",
    "DriftSummary",
    "NavErrors",
    "TruthFrame",
    "block_means",
    "errors_against",
    "euler_errors",
    "kept_indices",
    "nav_errors",
    "summarize",
    "thinned_indices",
]
