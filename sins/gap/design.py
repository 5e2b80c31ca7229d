"""A channel's regressor columns, built a chunk of rows at a time, and least squares over them.

Every column of a channel's model is a function of the reference inputs row by row: the baseline's
bias, rates and forces, a candidate's products of them, a bias step's or a hum's function of time. Held
whole, the columns of six channels outgrow memory on a long recording (the figures are in
``docs/speed.md``, "Figures behind the code's constants and choices"). A :class:`Design` keeps how to
build them (:data:`Maker`) and builds :data:`~sins.gap.candidates.CHUNK_ROWS` rows at a time, reducing
each chunk as it comes:

- least squares (:meth:`Design.lstsq`) from the QR factor of the chosen rows, each chunk stacked under
  the factor so far and factored again (``R`` of ``[R; chunk]``, a tall-skinny QR): the factor of the
  whole, so the coefficients are those of ``numpy.linalg.lstsq`` on the whole, to rounding, with its
  cut-off of small singular values;
- the same with the columns and the target whitened by a first-order filter, run over every row in
  time order (:meth:`Design.whitened_lstsq`, generalised least squares beside a random bias);
- the projection of any number of series off the columns (:class:`Projection`), from the factor's
  singular values and the products ``Aᵀb`` (the columns kept between series where they are small);
- predictions ``A c`` (:meth:`Design.predict`) and Gram matrices over chosen rows (:meth:`Design.gram`).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import dataclasses
import functools
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from sins.gap.candidates import DelayedInputs, ReferenceInputs, spans

Array = NDArray[np.float64]
Rows = NDArray[np.bool_]

#: Builds a block of columns, (m, k), from the reference inputs of m consecutive rows
#: (:meth:`~sins.gap.candidates.ReferenceInputs.rows`).
Maker = Callable[[ReferenceInputs], Array]

#: The most a :class:`Projection` keeps of its columns between the series it is asked about (a search
#: over a delay asks it of dozens): 32 MB, ten columns of 400,000 rows (over half an hour at 200 Hz).
KEPT_BYTES = 1 << 25


@dataclass(frozen=True, eq=False)
class Design:
    """The columns ``A`` (n, k) of a channel's least squares, built per chunk of rows from ``makers``
    (each a block of columns, side by side), each column divided by ``scale`` where given."""

    x: ReferenceInputs | DelayedInputs
    makers: tuple[Maker, ...]
    scale: Array | None = None

    @classmethod
    def from_array(cls, columns: Array) -> Design:
        """Columns given whole, (n, k): for a caller that has them (a test, a short series)."""
        return cls(_Given(np.asarray(columns, dtype=np.float64)), (_given,))  # type: ignore[arg-type]

    @property
    def n(self) -> int:
        """The rows."""
        return len(self.x.t)

    @functools.cached_property
    def width(self) -> int:
        """The columns (of a row's block, built once: every pass over the rows asks)."""
        return int(self.block(0, 1).shape[1])

    def block(self, start: int, stop: int) -> Array:
        """The columns of rows ``start … stop``, (stop − start, k)."""
        part = self.x.rows(start, stop)
        blocks = [np.asarray(make(part), dtype=np.float64).reshape(stop - start, -1) for make in self.makers]
        if len(blocks) == 1:  # a maker's block may be a view of the inputs: divide into a copy
            return blocks[0] if self.scale is None else blocks[0] / self.scale
        a = np.hstack(blocks)
        return a if self.scale is None else np.divide(a, self.scale, out=a)

    def matrix(self, rows: Rows | None = None) -> Array:
        """The whole columns, or those of ``rows``: for short recordings and tests."""
        a = self.block(0, self.n)
        return a if rows is None else a[rows]

    def with_makers(self, *makers: Maker) -> Design:
        """These columns and more, unscaled."""
        return Design(self.x, (*self.makers, *makers))

    def scaled(self, rows: Rows) -> Design:
        """Each column divided by its largest magnitude on ``rows`` (1e-300 at least): columns of
        like size, so that a cut-off of small singular values means the same for each. (A pass
        over the rows: :meth:`factor` finds the scale in its own.)"""
        assert self.scale is None, "scale an unscaled design"
        top = np.zeros(self.width)
        for _, _, a in self._chunks(rows):
            if len(a):
                top = np.maximum(top, np.abs(a).max(axis=0))
        return self.scaled_by(np.maximum(top, 1e-300))

    def scaled_by(self, scale: Array) -> Design:
        """Each column divided by ``scale``."""
        return dataclasses.replace(self, scale=scale)

    def predict(self, coef: Array) -> Array:
        """``A c`` for every row, (n,)."""
        out = np.empty(self.n)
        for lo, hi in spans(self.n):
            out[lo:hi] = self.block(lo, hi) @ coef
        return out

    def gram(self, rows: Rows) -> Array:
        """``AᵀA`` over ``rows``, (k, k)."""
        out = np.zeros((self.width, self.width))
        for _, _, a in self._chunks(rows):
            out += a.T @ a
        return out

    def masked_products(self, rows: Rows, b: Array, blocks: list[Array] | None = None) -> Array:
        """``Aᵀb`` over ``rows``, where ``b`` (n, p) holds every row's values: the other rows' are
        zeroed, not the columns' rows gathered (a copy of ``A`` saved per chunk). ``blocks``: the
        columns a chunk at a time, if the caller keeps them (else built as they are asked for)."""
        out = np.zeros((self.width, b.shape[1]))
        for k, (lo, hi) in enumerate(spans(self.n)):
            a = self.block(lo, hi) if blocks is None else blocks[k]
            out += a.T @ np.where(rows[lo:hi, None], b[lo:hi], 0.0)
        return out

    def products(self, rows: Rows, b: Array) -> Array:
        """``Aᵀb`` over ``rows``, where ``b`` (m, p) holds the values of those rows only, in order."""
        out = np.zeros((self.width, b.shape[1]))
        taken = 0
        for _, _, a in self._chunks(rows):
            out += a.T @ b[taken : taken + len(a)]
            taken += len(a)
        return out

    def factor(
        self,
        rows: Rows,
        target: Array | None = None,
        scale_rows: Rows | None = None,
        gram_rows: Rows | None = None,
    ) -> Factor:
        """In one pass over the rows: the QR factor of the (unscaled) columns on ``rows``, with
        ``Qᵀy`` of ``target`` (n,) if given; each column's largest magnitude on ``scale_rows``
        (``rows`` if None), the scale the factor's solutions are for (:class:`Factor`); and, with
        ``gram_rows``, the columns' Gram matrix on those rows, unscaled."""
        assert self.scale is None, "factor the unscaled columns"
        k, extra = self.width, target is not None
        r, top, gram = np.zeros((0, k + extra)), np.zeros(k), np.zeros((k, k))
        for lo, hi in spans(self.n):
            a = self.block(lo, hi)
            mine = rows[lo:hi]
            # The factor so far, then the rows' columns and target side by side, gathered under it:
            # what is factored again (no stacking copy).
            stack = np.empty((len(r) + int(mine.sum()), k + extra))
            stack[: len(r)] = r
            own = stack[len(r) :]
            np.compress(mine, a, axis=0, out=own[:, :k])
            if target is not None:
                np.compress(mine, target[lo:hi], out=own[:, k])
            # The rows already gathered serve the scale where they are the same rows (no second copy).
            scaled_by = own[:, :k] if scale_rows is None or scale_rows is rows else a[scale_rows[lo:hi]]
            if len(scaled_by):
                top = np.maximum(top, np.abs(scaled_by).max(axis=0))  # max(max, −min), in one pass
            if gram_rows is not None:
                other = a[gram_rows[lo:hi]]
                gram += other.T @ other
            if len(own):
                r = np.asarray(np.linalg.qr(stack, mode="r"))
        return Factor(r, k, int(rows.sum()), np.maximum(top, 1e-300), gram)

    def lstsq(
        self, target: Array, rows: Rows, rcond: float | None = None, scale_rows: Rows | None = None
    ) -> tuple[Array, Array]:
        """The coefficients ``c`` minimising ``|A c − y|`` over ``rows`` of the columns scaled on
        ``scale_rows`` (``rows`` if None; :meth:`scaled`), and that scale: ``numpy.linalg.lstsq`` of
        the rows' scaled columns and target, with its ``rcond`` (None: ``eps`` times the larger
        dimension)."""
        factor = self.factor(rows, target, scale_rows)
        return factor.solve(rcond), factor.scale

    def whitened_lstsq(
        self, target: Array, rows: Rows, rcond: float | None, phi: float, gain: float
    ) -> Array:
        """:meth:`lstsq` of the columns and target each passed through the innovations filter of a
        random bias (:func:`sins.gap.randombias.innovations`: over every row in time order, from the
        mean of the first 100), on ``rows``: generalised least squares beside the bias."""
        b, a = [0.0, phi * gain], [1.0, -phi * (1.0 - gain)]
        head = np.column_stack([self.block(0, min(100, self.n)), target[:100]])
        state = np.array([[float(np.mean(head[:, j])) for j in range(head.shape[1])]])
        r = np.zeros((0, head.shape[1]))
        for lo, hi in spans(self.n):
            chunk = np.column_stack([self.block(lo, hi), target[lo:hi]])
            predicted, state = lfilter(b, a, chunk, axis=0, zi=state)
            r = _stacked(r, (chunk - predicted)[rows[lo:hi]])
        return Factor(r, self.width, int(rows.sum()), np.ones(self.width)).solve(rcond)  # scaled already

    def _chunks(self, rows: Rows) -> Iterator[tuple[int, int, Array]]:
        """Each chunk's span and the columns of its rows among ``rows``, built as they are asked for."""
        for lo, hi in spans(self.n):
            yield lo, hi, self.block(lo, hi)[rows[lo:hi]]


#: The free memory glibc's heap may keep before :func:`release_free_memory` hands it back, bytes. Handing
#: back costs the next arrays their pages again (the kernel's time, ~6 % of a short diagnosis when done
#: between every fit); below this, what is kept is not worth it.
TRIM_ABOVE_BYTES = 64 << 20


class _MallInfo2(ctypes.Structure):
    """glibc's ``struct mallinfo2`` (2.33 and later): the heap's figures, ``size_t`` each."""

    _fields_ = [
        (name, ctypes.c_size_t)
        for name in (
            "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks",
            "keepcost",
        )
    ]  # fmt: skip


def release_free_memory() -> None:
    """Hand the C allocator's free pages back to the system, where it is glibc's (``malloc_trim``;
    elsewhere nothing), once its heap holds more than :data:`TRIM_ABOVE_BYTES` free. numpy takes a
    chunk's arrays (a few MB each) from glibc's heap, and glibc keeps what is freed there resident for
    the next: over a long diagnosis hundreds of MB that no array holds. Called between the stages that
    build and drop a recording's worth of chunks."""
    trim = getattr(_LIBC, "malloc_trim", None)
    if trim is None:
        return
    if _MALLINFO2 is not None and _MALLINFO2().fordblks < TRIM_ABOVE_BYTES:
        return
    trim(0)


def _libc() -> ctypes.CDLL | None:
    try:
        return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
    except OSError:
        return None


_LIBC = _libc() if sys.platform.startswith("linux") else None


def _mallinfo2() -> Callable[[], _MallInfo2] | None:
    """glibc's ``mallinfo2`` (the heap's free bytes without walking it), or None before glibc 2.33."""
    function = getattr(_LIBC, "mallinfo2", None)
    if function is None:
        return None
    function.restype = _MallInfo2
    function.argtypes = []
    return function


_MALLINFO2 = _mallinfo2()


@dataclass(frozen=True, eq=False)
class _Given:
    """Columns given whole, in the place of reference inputs (:meth:`Design.from_array`)."""

    columns: Array

    @property
    def t(self) -> Array:  # what gives a design its length
        return self.columns[:, 0]

    def rows(self, start: int, stop: int) -> _Given:
        return _Given(self.columns[start:stop])


def _given(part: _Given) -> Array:
    return part.columns


def _stacked(r: Array, block: Array) -> Array:
    """The QR factor ``R`` of ``[r; block]``: the factor so far, updated with more rows."""
    if len(block) == 0:
        return r
    return np.asarray(np.linalg.qr(np.vstack([r, block]), mode="r"))


@dataclass(frozen=True)
class Factor:
    """The upper-triangular factor ``r`` of ``[A, y]`` on ``m`` rows (its first ``k`` columns are
    ``A``'s factor, the next ``Qᵀy``), ``A`` unscaled; the solutions are for ``A``'s columns divided by
    ``scale`` (a column scale commutes with the factor: ``A S = Q (R S)``); ``gram``: ``A``'s Gram
    matrix on other rows, unscaled, if asked for."""

    r: Array
    k: int
    m: int
    scale: Array
    gram: Array | None = None

    def scaled_gram(self) -> Array:
        """:attr:`gram` of the scaled columns (a column all zero there stays zero: divided one scale
        at a time, never by a product of two that underflows)."""
        assert self.gram is not None, "ask the factor for a Gram matrix"
        return np.asarray(self.gram / self.scale / self.scale[:, None])

    def leading(self, k: int) -> Factor:
        """The factor of the first ``k`` columns alone (the leading block of a QR factor is theirs)."""
        return Factor(self.r[:k, :k], k, self.m, self.scale[:k])

    def _scaled(self) -> Array:
        """The factor of the scaled columns, (at most k, k)."""
        return self.r[: min(self.r.shape[0], self.k), : self.k] / self.scale

    def solve(self, rcond: float | None = None) -> Array:
        """The least-squares coefficients of ``y`` on the scaled columns, as ``numpy.linalg.lstsq``
        gives them (the same singular values, hence the same cut-off)."""
        rows = min(self.r.shape[0], self.k)
        cut = np.finfo(np.float64).eps * max(self.m, self.k) if rcond is None else rcond
        r = np.zeros((max(rows, 1), self.k))
        r[:rows] = self._scaled()
        qty = np.zeros(max(rows, 1))
        qty[:rows] = self.r[:rows, self.k]
        coef, *_ = np.linalg.lstsq(r, qty, rcond=cut)
        return np.asarray(coef)

    def singular(self) -> tuple[Array, Array, NDArray[np.bool_]]:
        """The scaled columns' singular values, right singular vectors (rows of ``Vᵀ``), and which
        of them ``numpy.linalg.lstsq`` keeps (above ``eps`` times the larger dimension of the largest)."""
        _, s, vt = np.linalg.svd(self._scaled(), full_matrices=False)
        keep = s > s[0] * max(self.m, self.k) * np.finfo(np.float64).eps if len(s) else s > 0
        return s, vt, keep


@dataclass(frozen=True, eq=False)
class Projection:
    """The projection onto the columns of a design on some rows: ``‖P b‖`` for any series ``b``,
    from the products ``Aᵀb`` and the columns' singular values (the columns kept as
    ``numpy.linalg.lstsq`` keeps them)."""

    design: Design
    rows: Rows
    basis: Array  # (k, r): V S⁻¹ over the kept singular values

    @classmethod
    def of(cls, design: Design, rows: Rows, factor: Factor | None = None) -> Projection:
        """The projection onto ``design``'s columns (unscaled) on ``rows``, scaled there (a pass over
        the rows, unless their ``factor`` is given)."""
        factor = design.factor(rows) if factor is None else factor
        s, vt, keep = factor.singular()
        return cls(design.scaled_by(factor.scale), rows, vt[keep].T / s[keep])

    def coordinates(self, b: Array) -> Array:
        """The coordinates (r, p) of the rows' ``b`` (m, p: those rows only, in order) in an
        orthonormal basis of the columns' span: ``‖P b‖² = Σ`` their squares."""
        return self.basis.T @ self.design.products(self.rows, b)

    def residual(self, y: Array) -> float:
        """``min_c ‖y − A c‖²`` over the rows, of a series ``y`` (n,) of every row. A search asks it
        of many series: the columns are built on the first call and kept where they take at most
        :data:`KEPT_BYTES` (:meth:`Design.masked_products` over them)."""
        taken = y[self.rows]
        on = self.basis.T @ self.design.masked_products(self.rows, y[:, None], self._kept)
        return float(taken @ taken - np.sum(on**2))

    @functools.cached_property
    def _kept(self) -> list[Array] | None:
        """The design's columns a chunk at a time, built once, or None where they would take more
        than :data:`KEPT_BYTES`."""
        design = self.design
        if 8 * design.n * design.width > KEPT_BYTES:
            return None
        return [design.block(lo, hi) for lo, hi in spans(design.n)]


__all__ = [
    "KEPT_BYTES",
    "TRIM_ABOVE_BYTES",
    "Design",
    "Factor",
    "Projection",
    "release_free_memory",
]
