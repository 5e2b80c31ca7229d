"""Writes that never leave half a file: a temporary name in the target's folder, renamed when complete.

Every file sins writes goes through :func:`atomic_path` (or :func:`atomic_text` for text): a reader never
sees a partly written file, and a run stopped by an error or an interrupt leaves none behind. A run
killed outright (SIGKILL) leaves its temporary file; the next write of the same file removes it once its
writer no longer runs (:data:`STALE_S`).
"""

from __future__ import annotations

import contextlib
import os
import re
import stat
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TextIO

from sins.core import deferred
from sins.errors import SinsInputError
from sins.io.paths import own_stream, read_only, target, writes_in_place

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
    if not os.fspath(path).strip():  # Path("") is ".", the working folder
        raise SinsInputError("an empty name, expected a file name to write")
    given = Path(path)
    if writes_in_place(given):  # /dev/null, /dev/full: written as they are, never renamed over
        try:
            yield given
        except OSError as exc:  # /dev/full: no space
            raise OSError(exc.errno, exc.strerror or str(exc), str(given)) from None
        return
    own_stream(given, str(given))  # /dev/stdout redirected to a file had replaced that file
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
    _sweep_stale(path)
    try:
        fd, name = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=directory)
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, mode)
        pending = deferred.pending()
        if pending is None:
            os.replace(tmp, path)
        else:
            pending.append((tmp, path))  # renamed with the command's other outputs (sins.core.deferred)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError):  # a full disk, say: the target named, not the temporary file
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None
        raise


#: A temporary file of a writer that no longer runs is removed when this old, s: a writer on another
#: machine sharing the folder (whose process id means nothing here) writes into its file as it goes.
STALE_S = 600.0


def _sweep_stale(path: Path) -> None:
    """Remove the temporary files a killed writer of ``path`` left beside it (``.NAME.PID.XXXX.tmp``, full
    size and hidden: a SIGKILL, which no ``finally`` sees): those whose process no longer runs and which
    have not been written for :data:`STALE_S`. Others' files, and a live writer's, are left alone."""
    pattern = re.compile(rf"\.{re.escape(path.name)}\.(\d+)\.[A-Za-z0-9_]+\.tmp")
    try:
        names = [e.name for e in os.scandir(path.parent) if e.name.startswith(f".{path.name}.")]
    except OSError:
        return
    for name in names:
        m = pattern.fullmatch(name)
        if m is None or _running(int(m.group(1))):
            continue
        stale = path.parent / name
        with contextlib.suppress(OSError):
            if time.time() - stale.stat().st_mtime > STALE_S:
                stale.unlink()


def _running(pid: int) -> bool:
    """Whether a process ``pid`` runs on this machine."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True  # another user's: running; a number no process can have: leave its file alone
    return True


@contextlib.contextmanager
def atomic_text(path: str | os.PathLike[str]) -> Iterator[TextIO]:
    """:func:`atomic_path` opened for writing UTF-8 text: the file handle to write into."""
    with atomic_path(path) as tmp, tmp.open("w", encoding="utf-8") as fh:
        yield fh


__all__ = ["STALE_S", "atomic_path", "atomic_text"]
