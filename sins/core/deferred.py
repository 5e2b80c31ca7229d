"""Renames deferred to the end of a command, so that its outputs land together or not at all.

:func:`sins.io.atomic.atomic_path` writes each output to a temporary name beside it; within an
:func:`all_or_nothing` block (the ``sins`` command wraps every command in one, a campaign's aside) it
keeps that complete file and leaves its rename to the block's end. Plain ``os`` and a context variable:
the command line enters the block before it imports anything numerical (a refusal before the work
imports nothing heavy).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from contextvars import ContextVar
from pathlib import Path

#: The renames deferred to the end of an :func:`all_or_nothing` block (temporary file, target), or None.
_PENDING: ContextVar[list[tuple[Path, Path]] | None] = ContextVar("sins_pending_renames", default=None)


@contextlib.contextmanager
def all_or_nothing(discarded: list[Path] | None = None) -> Iterator[None]:
    """Within the block, each :func:`sins.io.atomic.atomic_path` in this thread keeps its complete
    temporary file and defers its rename to the block's end: a command's outputs land together, or none
    does where a later write or the work after it fails or is interrupted (a model file beside a stale
    ``--json``, a new IMU file beside the truth file of another run, before). Each temporary file is
    then removed, and the targets it would have replaced are added to ``discarded``, for the message."""
    pending: list[tuple[Path, Path]] = []
    token = _PENDING.set(pending)
    try:
        yield
    except BaseException:
        for tmp, path in pending:
            tmp.unlink(missing_ok=True)
            if discarded is not None:
                discarded.append(path)
        raise
    finally:
        _PENDING.reset(token)
    _rename(pending)


def land() -> None:
    """Rename the current block's outputs written so far now, not at its end: for a command that then
    waits until it is interrupted (``sins run --serve``), whose outputs, said to be written, the interrupt
    had removed. Outside a block, nothing to do."""
    found = _PENDING.get()
    if found:
        _rename(found)
        found.clear()


def _rename(pending: list[tuple[Path, Path]]) -> None:
    """Each temporary file to its target, in order; where one fails, the later ones removed."""
    for k, (tmp, path) in enumerate(pending):
        try:
            os.replace(tmp, path)
        except OSError as exc:
            for later, _ in pending[k + 1 :]:
                later.unlink(missing_ok=True)
            raise OSError(exc.errno, exc.strerror or str(exc), str(path)) from None


def pending() -> list[tuple[Path, Path]] | None:
    """The current block's deferred renames (temporary file, target), to add to; None outside one."""
    return _PENDING.get()


__all__ = ["all_or_nothing", "land", "pending"]
