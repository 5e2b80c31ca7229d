"""Helpers shared by the test modules."""

from __future__ import annotations

import contextlib
import ctypes
import gc
import math
import os
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from sins.errors import SinsInputError
from sins.io.datasets.root import data_root


def dataset_folder(name: str) -> Path:
    """A dataset's folder under the data root, or a placeholder path when the root cannot be
    resolved (the working directory is gone, say): the data tests then skip, naming it."""
    try:
        return data_root() / name
    except OSError:
        return Path("(no data root)")


def refusal(call: Callable[[], Any], *fragments: str) -> str:
    """Run ``call``, expect a one-line SinsInputError containing every fragment; return the message."""
    with pytest.raises(SinsInputError) as info:
        call()
    message = str(info.value)
    assert "\n" not in message and "\r" not in message, message
    for fragment in fragments:
        assert fragment in message, f"{fragment!r} not in {message!r}"
    return message


# Tests use one thread for torch (reproducible, and fair to a 2-core CI machine). torch reads
# OMP_NUM_THREADS when it is first imported, so setting it here covers a test that imports torch
# itself; importing torch here instead would put ~230 MB into every test process, the many that
# never touch it included. Set, not defaulted: a shell's own value would give that first test more.
os.environ["OMP_NUM_THREADS"] = "1"


@pytest.fixture(autouse=True, scope="module")
def _memory_back_after_each_file() -> Iterator[None]:
    """Each test file's freed memory handed back to the system after it: a worker runs several files,
    and glibc keeps what a file freed, so the next file's peak stood on the last one's (1.26 GB in one
    worker of the a-f session, whose largest file alone peaks at 0.66 GB)."""
    yield
    gc.collect()
    with contextlib.suppress(OSError, AttributeError):  # not glibc: nothing to hand back this way
        ctypes.CDLL("libc.so.6").malloc_trim(0)


def pytest_runtest_setup(item: pytest.Item) -> None:
    """Hold torch at one thread where an earlier test set it otherwise."""
    torch = sys.modules.get("torch")
    if torch is not None and torch.get_num_threads() != 1:
        torch.set_num_threads(1)


# --------------------------------------------------------------------------- hangs: no progress, not slowness

#: A process tree (a process and its children) that gains less than STALL_CPU_S of CPU time over
#: STALL_S of wall time makes no progress: it is blocked (a FIFO's reader, a deadlock), not slow. A
#: loaded machine slows a process, it does not stop it: at load 8 on two cores each busy process still
#: gets a quarter of a core, 30 s of CPU in those 120 s. Wall time alone bounds nothing in this suite.
STALL_S = 120.0
STALL_CPU_S = 0.5


def tree_cpu_s(pid: int) -> float:
    """CPU time (user + system, s) of process ``pid``, its live children and the children it reaped."""
    import psutil

    try:
        proc = psutil.Process(pid)
        times = proc.cpu_times()
        total = times.user + times.system + times.children_user + times.children_system
        for child in proc.children(recursive=True):
            try:
                t = child.cpu_times()
                total += t.user + t.system
            except psutil.Error:
                pass
        return float(total)
    except psutil.Error:
        return float("nan")


class Progress:
    """Whether a process tree has stalled: its CPU time sampled by :meth:`stalled`, judged over the last
    :data:`STALL_S` seconds (see above)."""

    def __init__(self, pid: int, stall_s: float = STALL_S, stall_cpu_s: float = STALL_CPU_S) -> None:
        import time

        self.pid, self.stall_s, self.stall_cpu_s = pid, stall_s, stall_cpu_s
        self.samples = [(time.monotonic(), tree_cpu_s(pid))]

    def cpu_s(self) -> float:
        """CPU time the tree has used since this watch began, s."""
        return tree_cpu_s(self.pid) - self.samples[0][1]

    def stalled(self) -> bool:
        """Sample now; True when the last :data:`STALL_S` seconds gained less than :data:`STALL_CPU_S`."""
        import time

        now, cpu = time.monotonic(), tree_cpu_s(self.pid)
        if cpu != cpu:  # the process has ended: nothing to wait for
            return False
        self.samples.append((now, cpu))
        old = [s for s in self.samples if s[0] <= now - self.stall_s]
        if not old:
            return False
        self.samples = [old[-1]] + [s for s in self.samples if s[0] > now - self.stall_s]
        return cpu - old[-1][1] < self.stall_cpu_s


class Stalled(AssertionError):
    """A child process made no progress (see :data:`STALL_S`)."""


def run_process(args: list[str], *, check: bool = False, capture_output: bool = False, **kwargs: Any) -> Any:
    """``subprocess.run`` without a wall-clock timeout: the child runs as long as it takes, and is killed
    (:class:`Stalled` raised) only when its tree stops progressing (:class:`Progress`)."""
    import subprocess

    if capture_output:
        kwargs.setdefault("stdout", subprocess.PIPE)
        kwargs.setdefault("stderr", subprocess.PIPE)
    with subprocess.Popen(args, **kwargs) as proc:
        out, err = communicate(proc, args)
    done = subprocess.CompletedProcess(args, proc.returncode, out, err)
    if check:
        done.check_returncode()
    return done


def communicate(proc: Any, args: Any = None, input: Any = None) -> tuple[Any, Any]:
    """``proc.communicate()`` for as long as the child progresses (:class:`Progress`); a stalled child
    is killed and :class:`Stalled` raised."""
    import subprocess

    watch = Progress(proc.pid)
    while True:
        try:
            return proc.communicate(input=input, timeout=5.0)
        except subprocess.TimeoutExpired:
            input = None  # sent whole on the first call
            if watch.stalled():
                proc.kill()
                proc.communicate()
                why = f"no progress in {STALL_S:g} s (under {STALL_CPU_S:g} s of CPU)"
                raise Stalled(f"{(args or proc.args)!s:.200}: {why}") from None


def wait_for(condition: Callable[[], bool], pid: int, what: str) -> None:
    """Wait until ``condition()``, as long as process ``pid`` lives and progresses (:class:`Progress`)."""
    import time

    watch = Progress(pid)
    while not condition():
        if watch.stalled() or math.isnan(tree_cpu_s(pid)):
            raise Stalled(f"{what}: its process ended or made no progress")
        time.sleep(0.2)
