"""A structural check of a MATLAB v5 MAT file before scipy reads it.

scipy's v5 reader is not hardened against damaged files (its documentation says so): a data element
whose type code is out of range makes it read through a null or wild pointer and crash the process
(scipy PR 25349), which no ``except`` can turn into a message. :func:`check_mat_v5` walks the file's
element tags first, as the format defines them, and refuses a damaged file in one line.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

from sins.errors import SinsInputError

#: Element type codes scipy can read inside an array (miINT8 … miUINT64, miMATRIX, miUTF8/16/32).
_DATA_TYPES = frozenset({1, 2, 3, 4, 5, 6, 7, 9, 12, 13, 14, 16, 17, 18})
_MATRIX, _COMPRESSED = 14, 15
#: The most a compressed variable may inflate to, bytes (a damaged stream may claim anything).
MAX_INFLATED = 2**31
#: The most elements an array may declare (2⁴⁰: 8 TB of doubles; scipy multiplies the dimensions in a
#: size_t that a damaged header can wrap).
MAX_ELEMENTS = 2**40


def check_mat_v5(path: str | Path, raw: bytes, refusal: str = "damaged MAT file") -> None:
    """Refuse ``raw`` (the bytes of the MAT file ``path``) unless every element tag is one scipy reads.

    A file without a v5 header (128 bytes, version 0x0100, an endian indicator) is left to scipy,
    which refuses it or reads it as another version. In a v5 file each top-level element must be a
    matrix or a
    compressed matrix lying within the file; inside each matrix (and each nested cell or struct
    field), every element's type code known and its length within its parent; the dimensions
    non-negative with at most :data:`MAX_ELEMENTS` elements.

    Raises
    ------
    SinsInputError
        ``path: {refusal}: ...`` naming the byte offset.
    """
    order = {b"IM": "<", b"MI": ">"}.get(raw[126:128]) if len(raw) >= 128 else None
    if order is None or struct.unpack_from(f"{order}H", raw, 124)[0] != 0x0100:
        return
    try:
        _elements(path, raw, 128, len(raw), order, top=True, base=0)
    except _Damage as exc:
        raise SinsInputError(f"{path}: {refusal}: {exc}") from None


class _Damage(Exception):
    """What is wrong, and where."""


def _fail(path: str | Path, offset: int, what: str) -> _Damage:
    return _Damage(f"{what} at byte {offset}")


def _tag(
    path: str | Path, buf: bytes, off: int, end: int, order: str, padded: bool = True
) -> tuple[int, int, int, int]:
    """``(type, length, data offset, next offset)`` of the element tagged at ``off``; an element's data
    is padded to 8 bytes inside a matrix, not at the top level (as MATLAB writes and scipy reads)."""
    if off + 8 > end:
        raise _fail(path, off, "a truncated element tag")
    first, second = struct.unpack_from(f"{order}II", buf, off)
    if first >> 16:  # small data element: length and type in the first word, data in the second
        mdtype, nbytes = first & 0xFFFF, first >> 16
        if nbytes > 4:
            raise _fail(path, off, f"a small element of {nbytes} bytes")
        return mdtype, nbytes, off + 4, off + 8
    data, nbytes = off + 8, second
    if data + nbytes > end:
        raise _fail(path, off, f"an element of {nbytes} bytes beyond its end")
    return first, nbytes, data, data + nbytes + (-nbytes % 8 if padded else 0)


def _elements(path: str | Path, buf: bytes, off: int, end: int, order: str, top: bool, base: int) -> None:
    """Check the elements in ``buf[off:end]`` (the file's top level when ``top``, else a matrix's)."""
    index = 0
    while off < end:
        if top and end - off < 8 and not any(buf[off:end]):
            return  # padding at the end of a stream
        mdtype, nbytes, data, following = _tag(path, buf, off, end, order, padded=not top)
        if top:
            if mdtype == _COMPRESSED:
                inflated = _inflate(path, buf[data : data + nbytes], base + off)
                _elements(path, inflated, 0, len(inflated), order, top=True, base=base + data)
            elif mdtype == _MATRIX:
                _elements(path, buf, data, data + nbytes, order, top=False, base=base)
            else:
                raise _fail(path, base + off, f"a top-level element of type {mdtype} (not a matrix)")
        else:
            if mdtype not in _DATA_TYPES:
                raise _fail(path, base + off, f"an element of unknown type {mdtype}")
            if mdtype == _MATRIX:
                _elements(path, buf, data, data + nbytes, order, top=False, base=base)
            elif index == 1:  # the dimensions
                _check_dims(path, buf, data, nbytes, mdtype, order, base + off)
        index += 1
        off = following


def _check_dims(
    path: str | Path, buf: bytes, data: int, nbytes: int, mdtype: int, order: str, at: int
) -> None:
    code = {5: "i", 6: "I"}.get(mdtype)
    if code is None or nbytes % 4:
        raise _fail(path, at, f"dimensions of type {mdtype} and {nbytes} bytes")
    count = 1
    for (d,) in struct.iter_unpack(f"{order}{code}", buf[data : data + nbytes]):
        if d < 0:
            raise _fail(path, at, f"a negative dimension {d}")
        count *= d
    if count > MAX_ELEMENTS:
        raise _fail(path, at, f"an array of {count} elements")


def _inflate(path: str | Path, chunk: bytes, at: int) -> bytes:
    inflater = zlib.decompressobj()
    try:
        out = inflater.decompress(chunk, MAX_INFLATED)
    except zlib.error as exc:
        raise _fail(path, at, f"a compressed element that does not inflate ({exc})") from None
    if inflater.unconsumed_tail:
        raise _fail(path, at, f"a compressed element inflating beyond {MAX_INFLATED} bytes")
    return out


__all__ = [
    "MAX_ELEMENTS",
    "MAX_INFLATED",
    "check_mat_v5",
]
