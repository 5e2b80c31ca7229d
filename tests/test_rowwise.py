"""sins.core.rowwise's compiled row arithmetic gives numpy's broadcasting results to the last bit, and
sins.imu.numerics.apply_matrix gives ``rows @ matrix.T``'s: both replace numpy expressions in the corruption,
the corrections and the rig fits, whose outputs must not move by a rounding."""

from __future__ import annotations

import numpy as np
import pytest

from sins.core import rowwise
from sins.imu.numerics import apply_matrix

SPECIALS = np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 5e-324, -2.2e-308, 1e308, -1.0, 3.0])


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal shapes and bit patterns (NaN against NaN, signed zeros told apart)."""
    if a.shape != b.shape:
        return False
    nan_a, nan_b = np.isnan(a), np.isnan(b)
    return bool((nan_a == nan_b).all() and (a.view(np.uint64)[~nan_a] == b.view(np.uint64)[~nan_b]).all())


def _cases(rng: np.random.Generator):
    """(n, k) operands and matching vectors and columns: widths 3 (the unrolled path) and 6, 0 to 300
    rows, magnitudes over 20 decades, strided views, and special values mixed in."""
    for n in (0, 1, 2, 7, 300):
        for k in (3, 6, 1):
            scale = 10.0 ** rng.uniform(-10, 10, size=(n, k))
            a = rng.standard_normal((n, k)) * scale
            if n > 2:
                a.flat[rng.integers(0, a.size, 4)] = rng.choice(SPECIALS, 4)
            v = rng.standard_normal(k) * 10.0 ** rng.uniform(-5, 5, k)
            c = rng.standard_normal(n) * 10.0 ** rng.uniform(-5, 5, n)
            if n > 2:
                c[rng.integers(0, n, 2)] = rng.choice(SPECIALS, 2)
            yield a, v, c
            wide = np.zeros((n, 2 * k))
            wide[:, ::2] = a
            yield wide[:, ::2], v, c  # a strided view


@pytest.mark.parametrize(
    "name, ours, numpys",
    [
        ("add_row", lambda a, v, c: rowwise.add_row(a, v), lambda a, v, c: a + v),
        ("sub_row", lambda a, v, c: rowwise.sub_row(a, v), lambda a, v, c: a - v),
        ("mul_row", lambda a, v, c: rowwise.mul_row(a, v), lambda a, v, c: a * v),
        ("mul_col", lambda a, v, c: rowwise.mul_col(a, c), lambda a, v, c: a * c[:, None]),
        ("mul_col 0.5 dt", lambda a, v, c: rowwise.mul_col(a, 0.5 * c), lambda a, v, c: 0.5 * c[:, None] * a),
        ("outer", lambda a, v, c: rowwise.outer(c, v), lambda a, v, c: v * c[:, None]),
        ("col_over_row", lambda a, v, c: rowwise.col_over_row(c, v), lambda a, v, c: c[:, None] / v),
        ("row_over_col", lambda a, v, c: rowwise.row_over_col(v, c), lambda a, v, c: v / c[:, None]),
    ],
)
def test_each_kernel_gives_numpys_bits(name, ours, numpys):
    rng = np.random.default_rng(7)
    with np.errstate(all="ignore"):
        for a, v, c in _cases(rng):
            assert _same_bits(ours(a, v, c), numpys(a, v, c)), (name, a.shape)


def test_add_row_in_place_and_a_mismatched_width_is_not_read_past():
    a = np.arange(6.0).reshape(2, 3)
    out = rowwise.add_row(a, np.array([1.0, 2.0, 3.0]), out=a)
    assert out is a
    np.testing.assert_array_equal(a, [[1.0, 3.0, 5.0], [4.0, 6.0, 8.0]])


def test_the_bit_check_can_fail():
    """The comparison above tells a signed zero and a last-bit difference apart."""
    assert not _same_bits(np.array([0.0]), np.array([-0.0]))
    assert not _same_bits(np.array([1.0]), np.array([np.nextafter(1.0, 2.0)]))
    assert _same_bits(np.array([np.nan, 1.0]), np.array([np.nan, 1.0]))


def test_apply_matrix_gives_matmuls_bits():
    """Over 0 to 9,000 rows (chunk sizes the stream meets), magnitudes over 11 decades, strided rows."""
    rng = np.random.default_rng(11)
    for n in [*range(0, 40), 127, 128, 129, 1000, 4096, 8198]:
        for _ in range(3):
            rows = rng.standard_normal((n, 3)) * 10.0 ** rng.uniform(-8, 3)
            matrix = rng.standard_normal((3, 3)) * 10.0 ** rng.uniform(-6, 0)
            strided = np.hstack([rows, rows])[:, ::2]
            for x in (rows, strided):
                assert _same_bits(apply_matrix(matrix, x), x @ matrix.T), n


def test_diff_over_col_gives_numpys_bits_and_refuses_unlike_shapes():
    rng = np.random.default_rng(3)
    with np.errstate(all="ignore"):
        for a, _, c in _cases(rng):
            b = rng.standard_normal(a.shape) * 10.0 ** rng.uniform(-5, 5, a.shape)
            assert _same_bits(rowwise.diff_over_col(a, b, c), (a - b) / c[:, None]), a.shape
    with pytest.raises(ValueError, match="broadcast"):
        rowwise.diff_over_col(np.zeros((2, 3)), np.zeros((2, 6)), np.ones(2))


@pytest.mark.parametrize(
    "ours, numpys",
    [
        (lambda a, v: rowwise.add_row(a, v), lambda a, v: a + v),
        (lambda a, v: rowwise.sub_row(a, v), lambda a, v: a - v),
        (lambda a, v: rowwise.mul_row(a, v), lambda a, v: a * v),
        (lambda a, v: rowwise.mul_col(a, v), lambda a, v: a * np.asarray(v)[:, None]),
        (lambda a, v: rowwise.outer(v, a), lambda a, v: np.asarray(v)[:, None] * a),
        (lambda a, v: rowwise.row_over_col(a, v), lambda a, v: a / np.asarray(v)[:, None]),
    ],
)
def test_other_shapes_and_types_go_to_numpy_and_fail_as_numpy_does(ours, numpys):
    """A model file fuzzed to a scalar, a short vector, integers or text must meet numpy's own broadcasting
    or error, not a compiled kernel reading past an array's end (found by tests/test_fuzz.py)."""
    rows = np.arange(6.0).reshape(2, 3)
    for a, v in [
        (rows, 2.0),
        (rows, np.array(2.0)),
        (rows.astype(int), np.array([1, 2, 3])),
        (rows, np.array([1.0, 2.0])),
        (rows, np.array(["x", "y", "z"], dtype=object)),
        (np.arange(3.0), np.arange(3.0)),
    ]:
        with np.errstate(all="ignore"):
            try:
                expected = numpys(a, v)
            except (ValueError, TypeError, IndexError) as exc:
                with pytest.raises(type(exc)):
                    ours(a, v)
                continue
            np.testing.assert_array_equal(ours(a, v), expected)
