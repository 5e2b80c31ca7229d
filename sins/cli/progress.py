"""Progress on long work: a bar on a terminal, a line every few seconds in a log, nothing when quiet."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

#: A job's first progress line in a log comes after this long, s (shorter jobs write none) ...
LOG_FIRST_S = 5.0
#: ... and the next ones at most this often, s.
LOG_EVERY_S = 10.0


class LogProgress:
    """Progress for a log (stderr not a terminal): plain lines, the first after :data:`LOG_FIRST_S`, then
    one every :data:`LOG_EVERY_S` while the job runs (a heartbeat thread writes them, so a job whose
    steps are long still shows it is alive), and a closing line if any was written. The part of tqdm's
    interface the commands use (``n``, ``total``, ``update``, ``set_postfix_str``, ``set_description``).
    """

    def __init__(self, description: str, unit: str, stream: Any = None) -> None:
        import threading

        self.description = description
        self.unit = unit if not unit or unit.endswith("s") else f"{unit}s"  # "12 rows" in a line
        self.stream = stream if stream is not None else sys.stderr
        self.n: int = 0
        self.total: int | None = None
        self.postfix = ""
        self.lines = 0
        self._start = time.monotonic()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._beat, name="sins-progress", daemon=True)
        self._thread.start()

    def _beat(self) -> None:
        wait = LOG_FIRST_S
        while not self._stop.wait(wait):
            self._line(self._state())
            wait = LOG_EVERY_S

    def _state(self) -> str:
        of = f"/{self.total}" if self.total else ""
        done = f"{self.n}{of} {self.unit}" if self.n or self.total else "working"
        return done + (f", {self.postfix}" if self.postfix else "")

    def _line(self, text: str) -> None:

        elapsed = time.monotonic() - self._start
        print(f"{self.description}: {text} ({elapsed:.0f} s)", file=self.stream, flush=True)
        self.lines += 1

    def update(self, count: int = 1) -> None:
        """``count`` more done."""
        self.n += count

    def set_postfix_str(self, text: str) -> None:
        """What is being done now (named in the next line)."""
        self.postfix = text

    def set_description(self, text: str) -> None:
        """Another stage of the job."""
        self.description = text

    def stop(self) -> None:
        """Stop the heartbeat."""
        self._stop.set()
        self._thread.join()

    def close(self) -> None:
        """Stop, and write a closing line if the job wrote any."""
        self.stop()
        if self.lines:
            self._line("done" + (f", {self.n} {self.unit}" if self.n else ""))


@contextmanager
def progress_bar(description: str, unit: str) -> Iterator[Any]:
    """Progress on stderr: a tqdm bar on a terminal; plain lines for a log or CI when the job runs past
    :data:`LOG_FIRST_S` (:class:`LogProgress`), nothing for a shorter one."""
    if not sys.stderr.isatty():
        log = LogProgress(description, unit)
        try:
            yield log
        except BaseException:
            log.stop()  # no closing line: the job's error is the last one
            raise
        log.close()
        return
    from tqdm import tqdm

    # A job without a count (one stage) shows its name and the time it has taken, not a rate of nothing.
    shape = {"unit": f" {unit}"} if unit else {"bar_format": "{desc}: {elapsed}"}
    with tqdm(desc=description, leave=False, file=sys.stderr, **shape) as bar:
        yield bar


def advance(bar: Any, done: int, total: int | None = None) -> None:
    """Move ``bar`` to ``done`` of ``total`` (a tqdm bar)."""
    if total is not None:
        bar.total = total
    bar.update(done - bar.n)


def row_progress(bar: Any) -> Callable[[int, int], None] | None:
    """A ``progress(done, total)`` callback advancing ``bar``, or None without a bar."""
    if bar is None:
        return None
    return lambda done, total: advance(bar, done, total)


__all__ = [
    "LOG_EVERY_S",
    "LOG_FIRST_S",
    "LogProgress",
    "advance",
    "progress_bar",
    "row_progress",
]
