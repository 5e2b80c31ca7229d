"""Numeric CSV tables: one header row, one row per sample, comma separated, ``#`` comment lines allowed.

:func:`read_table` reads any such file into a :class:`Table` (column names and a float array), refusing
a bad file with one line naming the file, the line and the column: a missing or repeated column, a
non-numeric or non-finite value, a time column that does not increase. :func:`write_table` writes one
with 17 significant digits (every float64 comes back bit for bit) to a temporary name, then renames it
(:func:`sins.io.atomic.atomic_path`). sins's own forms of such tables (IMU files, truth files, rig
recordings) are :mod:`sins.io.formats` and :mod:`sins.io.rig`.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

import numpy as np
from numpy.typing import NDArray

from sins.errors import SinsInputError
from sins.io.atomic import atomic_text
from sins.io.paths import check_input, check_named

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Table:
    """A numeric CSV table: column names and a (rows, columns) float array.

    ``first_data_line`` is the 1-based line number after the header, for messages.
    """

    path: Path
    columns: tuple[str, ...]
    data: Array
    first_data_line: int

    def column(self, name: str) -> Array:
        """The values (rows,) of column ``name``."""
        return self.data[:, self.columns.index(name)]

    def has(self, name: str) -> bool:
        """Whether the header has column ``name``."""
        return name in self.columns


def read_table(
    path: str | os.PathLike[str],
    required: tuple[str, ...] = (),
    *,
    select: tuple[str, ...] | None = None,
    nan_ok: tuple[str, ...] = (),
) -> Table:
    """Read a numeric CSV with a header; validate values and the time column.

    The fast path is pyarrow's multi-threaded CSV reader (correctly rounded,
    so values written by :func:`write_table` come back bit for bit); anything it
    cannot take goes through a strict Python parser that either reads the file
    (comment or blank lines in the body, say) or names the bad cell.

    Parameters
    ----------
    path : the CSV file
    required : columns the header must have
    select : parse only these columns, in this order (each must be in the
        header); the others are skipped unparsed, so they may hold text.
        ``None`` (the default) parses every column.
    nan_ok : columns where NaN is a value (a rig's missing reference, say);
        ±inf is still refused there, and NaN everywhere else.

    Raises
    ------
    SinsInputError
        one line naming the file, and the line and column where it applies.
    """
    path = Path(path)
    if path.suffix.lower() == ".parquet":
        header_line, columns, whole = 0, *_read_parquet(path)
    else:
        header_line, columns = read_header(path)
    if len(set(columns)) != len(columns):
        dup = next(c for c in columns if columns.count(c) > 1)
        raise SinsInputError(f"{path}:{header_line}: column {dup!r} appears twice in the header")
    for name in required:
        if name not in columns:
            raise SinsInputError(
                f"{path}:{header_line}: missing required column {name!r} (header has {', '.join(columns)})"
            )
    wanted = columns if select is None else tuple(select)
    for name in wanted:
        if name not in columns:
            raise SinsInputError(
                f"{path}:{header_line}: missing required column {name!r} (header has {', '.join(columns)})"
            )
    if header_line == 0:  # Parquet: every column read, the wanted ones taken
        data: Array = whole[:, [columns.index(c) for c in wanted]]
    else:
        fast = _read_fast(path, header_line, columns, wanted)
        data = fast if fast is not None else _read_slow(path, header_line, columns, wanted)
    if len(data) == 0:
        raise SinsInputError(f"{path}: no data rows after the header")
    columns = wanted
    bad = ~np.isfinite(data)
    for name in nan_ok:
        if name in columns:
            c = columns.index(name)
            bad[:, c] = np.isinf(data[:, c])
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise SinsInputError(
            f"{path}:{line_of_row(path, header_line, int(r))}: column {columns[c]!r}: "
            f"non-finite value {format_number(data[r, c])}"
        )
    if "t" in columns:
        t = data[:, columns.index("t")]
        if (r := first_not_increasing(t)) is not None:
            raise SinsInputError(
                f"{path}:{line_of_row(path, header_line, r)}: column 't': time {format_number(t[r])} "
                f"does not increase (previous {format_number(t[r - 1])})"
            )
    return Table(path=path, columns=columns, data=data, first_data_line=header_line + 1)


def _read_parquet(path: Path) -> tuple[tuple[str, ...], Array]:
    """A Parquet file's column names and its numbers as floats (rows, columns): what sins writes as a
    solution (``sins integrate --out X.parquet``), read back as a table whose "lines" are rows."""
    check_input(path)
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(path)
        columns = tuple(table.column_names)
        data = (
            np.column_stack(
                [np.asarray(table.column(c).to_numpy(zero_copy_only=False), dtype=float) for c in columns]
            )
            if columns
            else np.empty((table.num_rows, 0))
        )
    except (ValueError, TypeError, OSError, ArithmeticError) as exc:  # pyarrow's errors derive from these
        raise SinsInputError(f"{path}: not a Parquet table of numbers ({type(exc).__name__})") from None
    return columns, data.reshape(table.num_rows, len(columns))


def format_number(value: float) -> str:
    """A float as text that reads back exactly (``repr``), for messages."""
    return repr(float(value))


def open_text(path: Path) -> TextIO:
    """``path`` opened as UTF-8 text (a byte-order mark skipped).

    Raises
    ------
    SinsInputError
        one line naming the file: missing, a directory, or not readable.
    """
    check_input(path)  # a FIFO or a device is refused before it is opened
    try:
        return open(path, encoding="utf-8-sig")  # tolerate the byte-order mark spreadsheets write
    except FileNotFoundError:
        raise SinsInputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise SinsInputError(f"{path}: is a directory, expected a CSV file") from None
    except OSError as exc:
        raise SinsInputError(f"{path}: cannot read: {exc.strerror or exc}") from None


def _data_lines(path: Path, header_line: int) -> Iterator[tuple[int, str]]:
    """``(line number, text)`` of each data row (not blank, not a comment) after the header."""
    with open_text(path) as fh:
        try:
            for number, text in enumerate(fh, start=1):
                if number > header_line and text.strip() and not text.lstrip().startswith("#"):
                    yield number, text
        except UnicodeDecodeError as exc:
            raise SinsInputError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None


def read_header(path: Path) -> tuple[int, tuple[str, ...]]:
    """1-based line number of the header (after blank and ``#`` lines) and its column names.

    Raises
    ------
    SinsInputError
        as :func:`open_text`, and for a file that is not UTF-8 or has no header row.
    """
    with open_text(path) as fh:
        try:
            for number, text in enumerate(fh, start=1):
                if text.strip() and not text.lstrip().startswith("#"):
                    return number, tuple(c.strip() for c in text.split(","))
        except UnicodeDecodeError as exc:
            raise SinsInputError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    raise SinsInputError(f"{path}: empty file, expected a header row")


def read_columns(path: str | os.PathLike[str]) -> tuple[str, ...]:
    """The column names of a CSV file's header, without reading its rows."""
    return read_header(Path(path))[1]


def _fill(column: Any, out: NDArray[np.float64]) -> None:
    """``out[:] =`` a parsed float64 column's values, read from its chunks' value buffers: pyarrow's
    ``to_numpy`` imports pandas to convert (0.2-0.3 s, a third of a small command's start-up). A chunk
    with nulls (none here: the parse takes no null values) goes through ``to_numpy``."""
    at = 0
    for c in column.chunks:
        if c.null_count == 0 and len(c):
            values = np.frombuffer(c.buffers()[1], np.float64, count=len(c), offset=8 * c.offset)
            out[at : at + len(c)] = values
        else:
            out[at : at + len(c)] = c.to_numpy(zero_copy_only=False)
        at += len(c)


def _read_fast(
    path: Path, header_line: int, columns: tuple[str, ...], wanted: tuple[str, ...] | None = None
) -> Array | None:
    """The ``wanted`` columns (default all) via pyarrow, or None when the file needs the careful parser."""
    import pyarrow as pa
    import pyarrow.csv as pacsv

    wanted = columns if wanted is None else wanted
    try:
        table = pacsv.read_csv(
            path,
            read_options=pacsv.ReadOptions(skip_rows=header_line - 1),
            convert_options=pacsv.ConvertOptions(
                column_types=dict.fromkeys(wanted, pa.float64()),
                null_values=[],
                strings_can_be_null=False,
                # Only when selecting: pyarrow then finds the columns by the header it parsed; one it
                # parsed differently from _read_header raises ArrowKeyError (the careful parser then reads).
                include_columns=list(wanted) if wanted != columns else None,
            ),
        )
    except (pa.ArrowInvalid, pa.ArrowTypeError, pa.ArrowKeyError, UnicodeDecodeError, OSError):
        return None
    if tuple(table.column_names) != wanted:
        return None
    data = np.empty((table.num_rows, len(wanted)))
    for i, column in enumerate(table.columns):
        _fill(column, data[:, i])
    del table, column
    # pyarrow's allocator keeps what the parse took for its next table (300 MB after a 3.57 M-row rig
    # recording, beside the 400 MB of values): the values are numpy's now, so give it back.
    pa.default_memory_pool().release_unused()
    return data


def _read_slow(
    path: Path, header_line: int, columns: tuple[str, ...], wanted: tuple[str, ...] | None = None
) -> Array:
    """Parse the ``wanted`` columns (default all) row by row; raise naming the first bad cell."""
    wanted = columns if wanted is None else wanted
    picks = [columns.index(name) for name in wanted]
    rows: list[list[float]] = []
    for number, text in _data_lines(path, header_line):
        cells = text.rstrip("\r\n").split(",")
        if len(cells) != len(columns):
            raise SinsInputError(f"{path}:{number}: expected {len(columns)} values, found {len(cells)}")
        row = []
        for name, cell in zip(wanted, [cells[i] for i in picks], strict=True):
            try:
                if "_" in cell:  # Python's float() takes 1_000; other tools do not
                    raise ValueError
                row.append(float(cell))
            except ValueError:
                raise SinsInputError(
                    f"{path}:{number}: column {name!r}: not a number: {cell.strip()!r}"
                ) from None
        rows.append(row)
    return np.array(rows, dtype=float).reshape(len(rows), len(wanted))


def first_not_increasing(t: NDArray[np.float64] | NDArray[np.int64]) -> int | None:
    """The first row of the stamps ``t`` that does not come after the row before it, or None: what every
    reader's refusal names (by row, line or message, beside the two stamps)."""
    bad = np.flatnonzero(np.diff(t) <= 0)
    return int(bad[0]) + 1 if bad.size else None


def line_of_row(path: Path, header_line: int, row: int) -> int:
    """The file line holding data row ``row`` (0-based), counting blank and comment lines (a Parquet
    file's row, 1-based)."""
    if path.suffix.lower() == ".parquet":
        return row + 1
    for i, (number, _) in enumerate(_data_lines(path, header_line)):
        if i == row:
            return number
    return header_line + 1 + row


#: Rows formatted per call when writing a table: progress every ~0.5 s, memory for the text bounded.
WRITE_BLOCK_ROWS = 100_000


def write_table(
    path: str | os.PathLike[str],
    columns: list[str],
    data: Array,
    comment: str = "",
    progress: Callable[[int, int], None] | None = None,
) -> None:
    """Write a CSV with a header, 17 significant digits, to a temporary name then rename.

    ``progress(rows_written, rows)`` is called after each block of :data:`WRITE_BLOCK_ROWS` rows.

    Raises
    ------
    SinsInputError
        a name that says another format (``x.npz``, ``x.parquet``: :func:`sins.io.paths.check_named`).
    """
    check_named(path, "csv")
    header = "".join(f"# {line}\n" for line in comment.splitlines()) + ",".join(columns)
    n = len(data)
    with atomic_text(path) as fh:
        fh.write(header + "\n")
        for start in range(0, n, WRITE_BLOCK_ROWS):
            np.savetxt(fh, data[start : start + WRITE_BLOCK_ROWS], delimiter=",", fmt="%.17g")
            if progress is not None:
                progress(min(start + WRITE_BLOCK_ROWS, n), n)


__all__ = [
    "WRITE_BLOCK_ROWS",
    "Table",
    "first_not_increasing",
    "format_number",
    "line_of_row",
    "open_text",
    "read_columns",
    "read_header",
    "read_table",
    "write_table",
]
