"""Renames deferred to the end of a command, so that its outputs land together or not at all.

:func:`sins.io.atomic.atomic_path` writes each output to a temporary name beside it; within an
:func:`all_or_nothing` block (the ``sins`` command wraps every command in one, a campaign's aside) it
keeps that complete file and leaves its rename to the block's end. Plain ``os`` and a context variable:
the command line enters the block before it imports anything numerical (a refusal before the work
imports nothing heavy).
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import shutil
from collections.abc import Iterable, Iterator
from contextvars import ContextVar
from pathlib import Path

#: The renames deferred to the end of an :func:`all_or_nothing` block (temporary file, target), or None.
_PENDING: ContextVar[list[tuple[Path, Path]] | None] = ContextVar("sins_pending_renames", default=None)
#: The outputs the block's command said it will write (:func:`declare`), or None outside a block.
_DECLARED: ContextVar[list[Path] | None] = ContextVar("sins_declared_outputs", default=None)


@contextlib.contextmanager
def all_or_nothing(discarded: list[Path] | None = None) -> Iterator[None]:
    """Within the block, each :func:`sins.io.atomic.atomic_path` in this thread keeps its complete
    temporary file and defers its rename to the block's end: a command's outputs land together, or none
    does where a later write or the work after it fails or is interrupted (a model file beside a stale
    ``--json``, a new IMU file beside the truth file of another run, before), or where a rename at the
    end fails (:func:`_rename`). Each temporary file is then removed, and the targets it would have
    replaced are added to ``discarded``, for the message."""
    pending: list[tuple[Path, Path]] = []
    declared: list[Path] = []
    token, said = _PENDING.set(pending), _DECLARED.set(declared)
    try:
        yield
    except BaseException:
        _remove(tmp for tmp, _ in pending)
        if discarded is not None:  # those written, then those it had not come to that exist
            discarded.extend(path for _, path in pending)
            discarded.extend(p for p in declared if p.is_file() and p not in discarded)
        raise
    finally:
        _PENDING.reset(token)
        _DECLARED.reset(said)
    try:
        _rename(pending)
    except OSError:
        if discarded is not None:
            discarded.extend(path for _, path in pending)
        raise


def declare(paths: Iterable[Path]) -> None:
    """The files the current block's command will write (their targets, links followed), said before its
    work: where it fails or is interrupted before writing one of them, the message names it among those
    not replaced too. Outside a block, nothing to do."""
    found = _DECLARED.get()
    if found is not None:
        found.extend(p for p in paths if p not in found)


def land() -> None:
    """Rename the current block's outputs written so far now, not at its end: for a command that then
    waits until it is interrupted (``sins run --serve``), whose outputs, said to be written, the interrupt
    had removed; an interrupt after it names none of them as not written. Outside a block, nothing to
    do."""
    found, declared = _PENDING.get(), _DECLARED.get()
    if found:
        _rename(found)
        found.clear()
    if declared:
        declared.clear()


def _rename(pending: list[tuple[Path, Path]]) -> None:
    """Each temporary file to its target, in order; where one fails, every target is left as it was and
    every temporary file removed. A target that became a folder while the command ran is refused before
    any rename; each target that exists is kept under a second name (a hard link, or a copy where the
    file system has none) until all have landed, so that one renamed before a later rename failed (a
    disk gone, a folder's permissions changed) is put back. Before, the first output stayed replaced
    beside the failure and the failed one's temporary file was left behind."""
    for _, path in pending:
        if path.is_dir():
            _remove(tmp for tmp, _ in pending)
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
    kept: list[Path | None] = []
    try:
        for _, path in pending:
            kept.append(_kept(path))
    except OSError as exc:
        _remove([*(tmp for tmp, _ in pending), *(k for k in kept if k is not None)])
        raise OSError(exc.errno, exc.strerror or str(exc), str(pending[len(kept)][1])) from None
    done = 0
    try:
        for tmp, path in pending:
            os.replace(tmp, path)
            done += 1
    except OSError as exc:
        for (_, path), old in zip(pending[:done], kept, strict=False):
            if old is None:
                path.unlink(missing_ok=True)  # it was new
            else:
                os.replace(old, path)
        _remove([*(tmp for tmp, _ in pending[done:]), *(k for k in kept[done:] if k is not None)])
        raise OSError(exc.errno, exc.strerror or str(exc), str(pending[done][1])) from None
    _remove(k for k in kept if k is not None)


def _kept(path: Path) -> Path | None:
    """A second name for ``path``'s file beside it, None where there is no file: a hard link, or a copy.
    Named as a temporary file is (``.NAME.PID.XXXX.tmp``), so that one a killed run left is swept by the
    next write of ``path`` (:func:`sins.io.atomic._sweep_stale`)."""
    if not path.is_file():
        return None
    while True:
        kept = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
        try:
            os.link(path, kept)
            return kept
        except FileExistsError:
            continue
        except OSError:  # no hard links here (some network and FAT file systems)
            shutil.copy2(path, kept)
            return kept


def _remove(paths: Iterable[Path]) -> None:
    """Remove each file of ``paths`` (gone already: nothing to do)."""
    for p in paths:
        p.unlink(missing_ok=True)


def pending() -> list[tuple[Path, Path]] | None:
    """The current block's deferred renames (temporary file, target), to add to; None outside one."""
    return _PENDING.get()


__all__ = ["all_or_nothing", "declare", "land", "pending"]
