"""Writes that never leave half a file: a temporary name in the target's folder, renamed when complete.

Every file sins writes goes through :func:`atomic_path` (or :func:`atomic_text` for text): a reader never
sees a partly written file, and a run stopped by an error or an interrupt leaves none behind.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import TextIO

from sins.errors import SinsInputError
from sins.io.paths import read_only, target, writes_in_place

#: The process's umask, read once at import (reading it means setting it, which threads would race).
_UMASK = os.umask(0o022)
os.umask(_UMASK)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary file beside ``path`` to write, renamed to ``path`` when the block ends without an
    error and removed otherwise: a reader never sees half a file, and an interrupted run leaves none.

    A new file gets the permissions a plain ``open`` would give it (``0o666`` less the umask), not the
    owner-only mode of a temporary file; a file replaced keeps its own (a private 0600 file stays
    private), and one marked read-only (no write bit) is refused (:func:`sins.io.paths.read_only`). A
    symbolic link is followed: its target is replaced, the link kept. A character device
    (``/dev/null``) is written in place, not replaced; a FIFO, socket or block device is refused
    (:mod:`sins.io.paths`). An ``OSError`` while writing (a full disk, a folder not writable) is raised
    again with ``path`` as its file name, not the temporary one.
    """
    given = Path(path)
    if writes_in_place(given):  # /dev/null, /dev/full: written as they are, never renamed over
        try:
            yield given
        except OSError as exc:  # /dev/full: no space
            raise OSError(exc.errno, exc.strerror or str(exc), str(given)) from None
        return
    path = target(given)  # a symbolic link: its target is replaced, the link kept
    directory = path.parent
    if not directory.is_dir():
        raise SinsInputError(f"{given}: directory {directory} does not exist")
    if path.is_dir():
        raise SinsInputError(f"{given}: is a directory, expected a file name to write")
    if path.exists() and not path.is_file():
        raise SinsInputError(f"{given}: is not a regular file; sins writes regular files (or /dev/null)")
    read_only(path, str(given))
    try:
        mode = stat.S_IMODE(os.stat(path).st_mode)  # a file replaced keeps its permissions
    except OSError:
        mode = 0o666 & ~_UMASK
    try:
        fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError):  # a full disk, say: the target named, not the temporary file
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
        raise


@contextlib.contextmanager
def atomic_text(path: str | os.PathLike[str]) -> Iterator[TextIO]:
    """:func:`atomic_path` opened for writing UTF-8 text: the file handle to write into."""
    with atomic_path(path) as tmp, tmp.open("w", encoding="utf-8") as fh:
        yield fh


__all__ = ["atomic_path", "atomic_text"]
