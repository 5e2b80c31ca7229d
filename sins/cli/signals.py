"""How a command ends on a signal: Ctrl-C (SIGINT), SIGTERM and SIGHUP end it as an exception in the main
thread, every ``finally`` run (a write in progress removes its temporary file), and never after its
outputs have begun to land.

Two things can hide a signal from the command's own code. A library's callback into Python swallows the
exception raised in it: numba's compilation cache notifies through a ctypes callback, and a Ctrl-C in the
instant it ran was printed as "Exception ignored" and then either ignored (the command went on, wrote its
outputs and exited 0) or followed by numba's own ``RuntimeError`` and a traceback. So every signal is
also recorded (:class:`Seen`): a command that returns, or fails, after one was seen ends as interrupted.
And once the work is done its outputs land (:mod:`sins.core.deferred`): an interrupt in those renames had
replaced some files and not others, or all of them and then exited 130 without a word. From
:meth:`Seen.landing` on, the signals are held off: the command has done what it said.

A reader that goes away (``| head``: SIGPIPE, Python's ``BrokenPipeError``) does not end the command
either (:class:`PipeOut`): what it prints then goes nowhere, and its outputs land.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, TextIO


class Terminated(BaseException):
    """SIGTERM or SIGHUP arrived (a BaseException, as KeyboardInterrupt is: no ``except Exception``
    swallows it, and every ``finally`` runs, so a write in progress removes its temporary file);
    ``signum`` the signal's number."""

    def __init__(self, signum: int = signal.SIGTERM) -> None:
        super().__init__(signum)
        self.signum = int(signum)


#: The signals that end a command as SIGTERM does: SIGHUP too (a closed terminal, a dropped ssh session
#: had ended it at once, its temporary files of hundreds of MB left behind and nothing said).
ENDING = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


def _ending(signum: int) -> BaseException:
    """The exception a signal ends a command with: Ctrl-C's own, or :class:`Terminated`."""
    return KeyboardInterrupt() if signum == signal.SIGINT else Terminated(signum)


class Seen:
    """The signals a command received (:func:`signals_as_exceptions`), in order; ``late``: those that
    came while its outputs landed, held off then (delivered after, where the block is not the process's
    whole command)."""

    def __init__(self) -> None:
        self.signums: list[int] = []
        self.late: list[int] = []
        self._landing = False

    def handle(self, signum: int, frame: object) -> None:
        """The handler: record the signal, and raise it as the command's end (unless landing)."""
        if self._landing:
            self.late.append(signum)
            return
        self.signums.append(signum)
        raise _ending(signum)

    def raise_if_any(self) -> None:
        """Raise the first signal seen, where something between its handler and here swallowed it."""
        if self.signums:
            raise _ending(self.signums[0])

    def landing(self) -> None:
        """The work is done and its outputs land now: a signal from here on is too late to undo them,
        and is held off (the raise of one seen and swallowed comes first)."""
        self.raise_if_any()
        self._landing = True


@contextlib.contextmanager
def signals_as_exceptions(*, process: bool = False) -> Iterator[Seen]:
    """Within the block, SIGINT raises KeyboardInterrupt and SIGTERM and SIGHUP (:data:`ENDING`) raise
    :class:`Terminated` in the main thread, instead of ending the process at once with its files half
    written, and each is recorded in the :class:`Seen` yielded. A signal its parent set to be ignored
    (``sins … &`` from a script: Ctrl-C is not the job's) stays ignored. After the block the handlers
    before are restored (a signal held off while the outputs landed is in :attr:`Seen.late`, for the
    caller to deliver once the command is over: :func:`sins.cli.main`); where the
    block is the ``process``'s whole command (the console script's), every signal is ignored instead
    until the process exits (a Ctrl-C there had ended a command that had written its outputs with 130
    and no word: the interpreter's exit puts back the default action of a handled signal, not of an
    ignored one). Elsewhere than the main thread, nothing changes (and nothing is recorded)."""
    seen = Seen()
    if threading.current_thread() is not threading.main_thread():
        yield seen
        return
    taken = [s for s in (signal.SIGINT, *ENDING) if signal.getsignal(s) is not signal.SIG_IGN]
    previous = {s: signal.signal(s, seen.handle) for s in taken}
    try:
        yield seen
    finally:
        if process:
            seen._landing = True
            for s in previous:
                signal.signal(s, signal.SIG_IGN)
        else:
            for s, handler in previous.items():
                signal.signal(s, handler)


class PipeOut:
    """A standard stream a command prints to, which outlives its reader: where the reader goes away
    (``sins fit … | head -2``, or ``2>&1 | head``), the rest of what is printed goes nowhere and the
    command goes on, its outputs landing as they would (:attr:`broken` says so: the command then exits
    141, SIGPIPE's). A broken pipe had ended the command where it printed: a fit done, its model thrown
    away. A stream that is not there (``>&-``: Python's ``None``) takes what is printed and drops it, as
    ``print`` does."""

    def __init__(self, out: TextIO | None) -> None:
        self._out = out
        self.broken = False

    def write(self, text: str) -> int:
        """Write ``text`` while a reader reads; after, take it and drop it."""
        if not self.broken and self._out is not None:
            try:
                return self._out.write(text)
            except BrokenPipeError:
                self._gone()
        return len(text)

    def flush(self) -> None:
        """Flush while a reader reads (a reader gone found here too)."""
        if not self.broken and self._out is not None:
            try:
                self._out.flush()
            except BrokenPipeError:
                self._gone()

    def _gone(self) -> None:
        """The reader went away: what the stream still holds, and the interpreter's flush at exit, go to
        the null device, quietly (Python had said "Exception ignored … BrokenPipeError" at exit)."""
        self.broken = True
        with contextlib.suppress(OSError, ValueError, AttributeError):  # a stream with no descriptor
            null = os.open(os.devnull, os.O_WRONLY)
            try:
                os.dup2(null, self._out.fileno())  # type: ignore[union-attr]
            finally:
                os.close(null)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._out, name)


@dataclass
class Pipes:
    """The two standard streams as :class:`PipeOut` (:func:`pipes_outliving_their_readers`)."""

    out: PipeOut
    err: PipeOut

    @property
    def broken(self) -> bool:
        """Whether either stream's reader went away."""
        return self.out.broken or self.err.broken

    def flush(self) -> None:
        """Flush both (a reader gone found here at the latest)."""
        self.out.flush()
        self.err.flush()


@contextlib.contextmanager
def pipes_outliving_their_readers() -> Iterator[Pipes]:
    """Within the block, ``sys.stdout`` and ``sys.stderr`` are :class:`PipeOut` of themselves (flushed
    at the block's end); the streams before are restored after."""
    pipes = Pipes(PipeOut(sys.stdout), PipeOut(sys.stderr))
    sys.stdout, sys.stderr = pipes.out, pipes.err
    try:
        yield pipes
        pipes.flush()
    finally:
        sys.stdout, sys.stderr = pipes.out._out, pipes.err._out


__all__ = [
    "ENDING",
    "PipeOut",
    "Pipes",
    "Seen",
    "Terminated",
    "pipes_outliving_their_readers",
    "signals_as_exceptions",
]
