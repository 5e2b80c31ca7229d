"""The arithmetic the IMU's effects and streams share: cubic Hermite curves through samples, a
first-order recursion, a regular-sampling test, a 3×3 matrix applied row by row, and the seeded
generator of one effect's random draws."""

from __future__ import annotations

import zlib
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def ar1(phi: Array, drive: Array, out: Array, uniform: bool) -> None:
    """``out[k] = phi[k-1] out[k-1] + drive[k-1]`` (in place), vectorised over channels; ``uniform``:
    ``phi`` is one row (1, 3), every interval's."""
    if len(phi) == 0:
        return
    if uniform:
        _ar1_uniform(np.ascontiguousarray(phi[0], dtype=float), drive, out)
        return
    for k in range(1, len(out)):
        out[k] = phi[k - 1] * out[k - 1] + drive[k - 1]


@numba.njit(cache=True, nogil=True)
def _ar1_uniform(a: Array, drive: Array, out: Array) -> None:  # pragma: no cover  (compiled)
    """``out[k] = a out[k-1] + drive[k-1]`` per channel, one coefficient a channel: the arithmetic of
    ``scipy.signal.lfilter([1], [1, -a])`` to the last bit (``tests/test_stream.py``), without importing
    scipy.signal (about 1 s in a fresh process, with scipy.stats, which every campaign worker and every
    corrupted ``sins run`` paid for this one recursion)."""
    for i in range(3):
        v, c = out[0, i], a[i]
        for k in range(1, out.shape[0]):
            v = c * v + drive[k - 1, i]
            out[k, i] = v


def uniform_steps(t: Array) -> bool:
    """Whether ``t`` is sampled regularly: its steps equal to 1 ppm of their median or to the
    rounding of the time stamps (which grows with ``|t|``)."""
    t = np.ascontiguousarray(t, dtype=float)
    if len(t) < 2:
        return True
    low, high, largest = _step_range(t)
    spread = high - low
    rounding = 16.0 * np.finfo(float).eps * largest
    # The median lies between the smallest and largest step: most calls are settled without it.
    if spread <= 1e-6 * low + rounding:
        return True
    if spread > 1e-6 * high + rounding:
        return False
    return bool(spread <= 1e-6 * np.median(np.diff(t)) + rounding)


@numba.njit(cache=True, nogil=True)
def _step_range(t: Array) -> tuple[float, float, float]:
    """The smallest and largest step of ``t`` (at least two samples) and its largest ``|t|``, in one
    pass (each chunk of a stream asks)."""
    low = high = t[1] - t[0]
    largest = max(abs(t[0]), abs(t[1]))
    for k in range(2, t.shape[0]):
        step = t[k] - t[k - 1]
        low, high, largest = min(low, step), max(high, step), max(largest, abs(t[k]))
    return low, high, largest


def apply_matrix(matrix: NDArray[Any], rows: NDArray[Any]) -> Array:
    """``matrix`` (3, 3) applied to every row of ``rows`` (n, 3): ``rows @ matrix.T``.

    Through a C-ordered copy of the transpose: numpy's ``matmul`` takes a loop five times slower for
    a transposed (Fortran-ordered) 3×3 on thousands of rows, with the same arithmetic (the same
    bits from 2 rows up, ``tests/test_rowwise.py``); a single row goes the way ``@`` sends it.
    """
    if rows.ndim == 2 and rows.shape[0] > 1:
        return np.asarray(rows @ np.ascontiguousarray(matrix.T), dtype=np.float64)
    return np.asarray(rows @ matrix.T, dtype=np.float64)


def random_stream(seed: int | None, name: str) -> np.random.Generator:
    """The generator of one effect's random draws in a run: its own stream of the run's seed, so that
    adding or removing another effect leaves its draws alone."""
    return np.random.default_rng([0 if seed is None else seed, zlib.crc32(name.encode())])


#: A one-sided slope replaces the central one at a row where the central stencil's second difference
#: stands out from both one-sided stencils' by more than 1 / this: a kink (a rig's rate switched to a
#: ramp, a turn started), not curvature.
KINK_RATIO = 0.1


def hermite_slopes(t: Array, y: Array, central: Array) -> tuple[Array, Array]:
    """The slopes a cubic Hermite curve through samples ``y`` (n, k) leaves and enters each row with:
    the central ones, except at a kink.

    A rig's commanded rate is piecewise linear, and the force turns as a rotation starts: where the
    slope changes at a row, the central slope there is the mean of the two sides, and the curve bends
    across the intervals on both (a lag of τ then errs by τ times half the change of slope). Where
    the central stencil's second difference stands out from both one-sided stencils' (each below
    :data:`KINK_RATIO` of it), each side takes its own one-sided slope, exact on a straight side.
    Elsewhere, smooth curvature and inflections included, both are the central slope.
    """
    right, left = central.copy(), central.copy()
    n = len(t)
    if n > 4:
        h = np.diff(t)[:, None]
        secant = np.diff(y, axis=0) / h
        bend = np.abs(np.diff(secant, axis=0))  # the stencil centred on rows 1 .. n-2
        # Rows 2 .. n-3 have a centred stencil and both one-sided ones.
        centre, back, ahead = bend[1:-1], bend[:-2], bend[2:]
        kink = (ahead < KINK_RATIO * centre) & (back < KINK_RATIO * centre)
        rows = slice(2, n - 2)
        forward = secant[2:-1] + (secant[2:-1] - secant[3:]) * h[2:-1] / (h[2:-1] + h[3:])
        backward = secant[1:-2] + (secant[1:-2] - secant[:-3]) * h[1:-2] / (h[1:-2] + h[:-3])
        right[rows] = np.where(kink, forward, central[rows])
        left[rows] = np.where(kink, backward, central[rows])
    return right, left


def cubic_hermite(t: Array, y: Array, dy: Array, when: Array, dy_in: Array | None = None) -> Array:
    """Samples ``y`` (n, k) at times ``t``, with slopes ``dy``, interpolated at ``when`` (within
    ``t``'s span) by cubic Hermite pieces; ``dy_in``, if given, are the slopes each interval
    enters its end row with (``dy`` those it leaves its start row with; see :func:`hermite_slopes`).

    Written out in the Hermite basis. The gap diagnosis delays its reference with a scipy ``PPoly``
    (:meth:`sins.gap.candidates.ReferenceInputs.lag`), the same curve in power form: the two agree to
    the last few bits only, so each keeps its own.
    """
    dy_in = dy if dy_in is None else dy_in
    k = np.clip(np.searchsorted(t, when, side="right") - 1, 0, len(t) - 2)
    h = (t[k + 1] - t[k])[:, None]
    s = ((when - t[k]) / h[:, 0])[:, None]
    return (
        (1 + 2 * s) * (1 - s) ** 2 * y[k] + s * (1 - s) ** 2 * h * dy[k]
        + s * s * (3 - 2 * s) * y[k + 1] + s * s * (s - 1) * h * dy_in[k + 1]
    )  # fmt: skip


__all__ = [
    "KINK_RATIO",
    "apply_matrix",
    "ar1",
    "cubic_hermite",
    "hermite_slopes",
    "random_stream",
    "uniform_steps",
]
