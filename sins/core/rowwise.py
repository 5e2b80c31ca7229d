"""Row-wise arithmetic on (n, k) arrays of samples, compiled: one vector for every row, or one number
for each row.

Why: numpy's broadcasting over a short inner axis runs its inner loop once per row, several times slower
than the same operation between two (n, 3) arrays, and a streamed hour pays that in every chunk of the
corruption, the corrections and the reduction (the figures: ``docs/speed.md``). Each kernel does one IEEE
operation per element, the one numpy does, so the results are numpy's to the last bit
(``tests/test_rowwise.py``); they never fuse two operations (no multiply-add), so no rounding moves; a
division by zero gives numpy's ±inf or NaN (numba's ``error_model="numpy"``), not an exception. Arrays of
other shapes or types go to numpy's own expression, so they broadcast, or fail, as numpy would.
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _add_row(a: Array, v: Array, out: Array) -> None:
    # Three columns, unrolled: twice as fast as a loop over the columns.
    v0, v1, v2 = v[0], v[1], v[2]
    for k in range(a.shape[0]):
        out[k, 0] = a[k, 0] + v0
        out[k, 1] = a[k, 1] + v1
        out[k, 2] = a[k, 2] + v2


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _sub_row(a: Array, v: Array, out: Array) -> None:
    v0, v1, v2 = v[0], v[1], v[2]
    for k in range(a.shape[0]):
        out[k, 0] = a[k, 0] - v0
        out[k, 1] = a[k, 1] - v1
        out[k, 2] = a[k, 2] - v2


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _mul_col(a: Array, c: Array, out: Array) -> None:
    for k in range(a.shape[0]):
        ck = c[k]
        out[k, 0] = a[k, 0] * ck
        out[k, 1] = a[k, 1] * ck
        out[k, 2] = a[k, 2] * ck


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _mul_row(a: Array, v: Array, out: Array) -> None:
    v0, v1, v2 = v[0], v[1], v[2]
    for k in range(a.shape[0]):
        out[k, 0] = a[k, 0] * v0
        out[k, 1] = a[k, 1] * v1
        out[k, 2] = a[k, 2] * v2


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _outer(c: Array, v: Array, out: Array, divide: bool, column_first: bool) -> None:
    # out[k, i] = c[k] * v[i]; with divide, c[k] / v[i] (column_first) or v[i] / c[k]. One loop per
    # case: a branch inside the loop keeps it from being vectorised.
    n, m = c.shape[0], v.shape[0]
    if not divide:
        for k in range(n):
            for i in range(m):
                out[k, i] = c[k] * v[i]
    elif column_first:
        for k in range(n):
            for i in range(m):
                out[k, i] = c[k] / v[i]
    else:
        for k in range(n):
            for i in range(m):
                out[k, i] = v[i] / c[k]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _diff_over_col(a: Array, b: Array, c: Array, out: Array) -> None:
    for k in range(a.shape[0]):
        ck = c[k]
        for i in range(a.shape[1]):
            out[k, i] = (a[k, i] - b[k, i]) / ck


def _rows_and_vector(a: Any, v: Any) -> bool:
    """Whether the row kernels apply: float64 arrays, ``a`` (n, 3) and ``v`` (3,)."""
    return _floats(a, v) and a.ndim == 2 and a.shape[1] == 3 and v.shape == (3,)


def _rows_and_column(a: Any, c: Any, any_width: bool = False) -> bool:
    """Whether the kernels apply: float64 arrays, ``a`` (n, 3) (any (n, k) with ``any_width``), ``c`` (n,)."""
    return _floats(a, c) and a.ndim == 2 and (any_width or a.shape[1] == 3) and c.shape == (a.shape[0],)


def _floats(*xs: Any) -> bool:
    return all(isinstance(x, np.ndarray) and x.dtype == np.float64 for x in xs)


# Each function below runs its kernel on the shapes and type it names (three columns: the samples' axes;
# `diff_over_col` any width) and hands anything else to numpy's own expression, so that other shapes
# broadcast, and bad ones fail, exactly as numpy's would.


def add_row(a: Array, v: Array, out: Array | None = None) -> Array:
    """``a + v``: the vector ``v`` (3,) added to every row of ``a`` (n, 3) (into ``out`` if given)."""
    if not _rows_and_vector(a, v) or (out is not None and out.shape != a.shape):
        return np.add(a, v, out=out)
    out = np.empty(a.shape) if out is None else out
    _add_row(a, v, out)
    return out


def sub_row(a: Array, v: Array) -> Array:
    """``a - v``: the vector ``v`` (3,) taken from every row of ``a`` (n, 3)."""
    if not _rows_and_vector(a, v):
        return np.subtract(a, v)
    out = np.empty(a.shape)
    _sub_row(a, v, out)
    return out


def mul_row(a: Array, v: Array) -> Array:
    """``a * v``: every row of ``a`` (n, 3) times the vector ``v`` (3,), element by element."""
    if not _rows_and_vector(a, v):
        return np.multiply(a, v)
    out = np.empty(a.shape)
    _mul_row(a, v, out)
    return out


def mul_col(a: Array, c: Array) -> Array:
    """``a * c[:, None]``: row ``j`` of ``a`` (n, 3) times ``c[j]``."""
    if not _rows_and_column(a, c):
        return np.multiply(a, np.asarray(c)[:, None])
    out = np.empty(a.shape)
    _mul_col(a, c, out)
    return out


def diff_over_col(a: Array, b: Array, c: Array) -> Array:
    """``(a - b) / c[:, None]``: the difference of two (n, k) arrays, row ``j`` over ``c[j]`` (a mean rate
    from two sets of increments over their intervals ``c``)."""
    if not (_rows_and_column(a, c, any_width=True) and _floats(b) and b.shape == a.shape):
        return np.divide(np.subtract(a, b), np.asarray(c)[:, None])
    out = np.empty(a.shape)
    _diff_over_col(a, b, c, out)
    return out


def outer(c: Array, v: Array) -> Array:
    """``c[:, None] * v``: (n, k), element ``[j, i]`` is ``c[j] * v[i]``."""
    if not _column_and_vector(c, v):
        return np.multiply(np.asarray(c)[:, None], v)
    return _outer_of(c, v, divide=False, column_first=True)


def col_over_row(c: Array, v: Array) -> Array:
    """``c[:, None] / v``: (n, k), element ``[j, i]`` is ``c[j] / v[i]``."""
    if not _column_and_vector(c, v):
        return np.divide(np.asarray(c)[:, None], v)
    return _outer_of(c, v, divide=True, column_first=True)


def row_over_col(v: Array, c: Array) -> Array:
    """``v / c[:, None]``: (n, k), element ``[j, i]`` is ``v[i] / c[j]``."""
    if not _column_and_vector(c, v):
        return np.divide(v, np.asarray(c)[:, None])
    return _outer_of(c, v, divide=True, column_first=False)


def _column_and_vector(c: Any, v: Any) -> bool:
    return _floats(c, v) and c.ndim == 1 and v.ndim == 1


def _outer_of(c: Array, v: Array, divide: bool, column_first: bool) -> Array:
    out = np.empty((c.shape[0], v.shape[0]))
    _outer(c, v, out, divide, column_first)
    return out


__all__ = [
    "add_row",
    "col_over_row",
    "diff_over_col",
    "mul_col",
    "mul_row",
    "outer",
    "row_over_col",
    "sub_row",
]
