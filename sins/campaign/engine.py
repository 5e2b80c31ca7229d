"""Running a campaign on dask.distributed: a local cluster of the machine's cores, or any scheduler.

The only module that imports dask. Units are grouped into tasks of a few units each; results
come back as tasks finish and are written at once as Parquet parts (:mod:`sins.campaign.results`).
A worker lost mid-campaign costs only its running tasks: the scheduler gives them to another worker
(up to ``distributed.scheduler.allowed-failures`` times), and a task's rows depend only on the campaign
and its units, so a rerun task writes the rows it would have written.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import signal
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sins.campaign import folder, results
from sins.campaign.spec import CampaignSpec
from sins.campaign.unit import task
from sins.core import deferred
from sins.errors import SinsInputError

#: Tasks per worker the units are split into: enough that a slow task does not idle the others at the
#: end, few enough that each task's start-up (a worker's first import of torch, say) is paid rarely.
TASKS_PER_WORKER = 4
#: The most local worker processes a core may be given (``--workers 100000`` spawned processes until the
#: machine stalled): a larger cluster is started by hand and given as a scheduler.
WORKERS_PER_CORE = 4
#: The most units in one task: a task's units share each scenario's generated trajectory (its cost split
#: among them, small beside a unit's own from 8 units up), and a task is what a lost worker costs and how
#: often results come back (the figures: ``docs/speed.md``).
MAX_UNITS_PER_TASK = 32


def units_per_task(units: int, workers: int) -> int:
    """How many of ``units`` one task runs on ``workers`` workers: :data:`TASKS_PER_WORKER` tasks a
    worker, at most :data:`MAX_UNITS_PER_TASK` units a task."""
    return max(1, min(MAX_UNITS_PER_TASK, math.ceil(units / (TASKS_PER_WORKER * max(1, workers)))))


def batches(todo: list[int], size: int) -> list[list[int]]:
    """``todo`` (increasing unit numbers) in tasks of at most ``size`` units, each a run of consecutive
    units: a task's part is named by its first and last unit, and its check expects a row for every unit
    between them. (A resume with a finished part between two missing units had put both in one task,
    whose part the check then refused: the campaign ended without results.)"""
    out: list[list[int]] = []
    for u in todo:
        if out and u == out[-1][-1] + 1 and len(out[-1]) < size:
            out[-1].append(u)
        else:
            out.append([u])
    return out


#: How many times the units a check finds missing or damaged are run: once, and once more for parts
#: damaged while the campaign ran; a part damaged again means a disk that loses what is written to it.
RUNS = 2


@dataclass(frozen=True)
class CampaignRun:
    """What :func:`run` did: the results folder, the units run now and before, the wall time, the
    summary, and a line per part that failed its check (its units were run again)."""

    out: Path
    units_run: int
    units_resumed: int
    wall_s: float
    summary: dict[str, Any]
    rejected: tuple[str, ...] = ()


def run(
    spec: CampaignSpec,
    out: Path,
    workers: int | None = None,
    scheduler: str | None = None,
    resume: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> CampaignRun:
    """Run every unit not yet in ``out`` on a dask cluster, then join and summarise the rows.

    ``out`` is locked for the run (:func:`sins.campaign.folder.locked`); its parts are checked before
    (on ``resume``) and after the units ran, and the units of a part that fails are run again.

    Parameters
    ----------
    spec : the campaign (:func:`sins.campaign.spec.load`)
    out : the results folder (created; on ``resume`` it must hold the same campaign)
    workers : processes of the local cluster (default: the machine's cores); not with ``scheduler``
    scheduler : the address of a running dask scheduler (``tcp://HOST:PORT``): its workers must see
        the campaign's files at the same paths and have sins installed
    resume : continue a campaign from the parts ``out`` holds
    progress : called as ``progress(units_done, units)`` as tasks finish

    Raises
    ------
    SinsInputError
        ``out`` is held by another campaign, holds another campaign's results, or holds results and
        ``resume`` is not given; the scheduler cannot be reached; parts keep failing their check.
    """
    start = time.perf_counter()
    cores = os.cpu_count() or 1
    if workers is not None and workers > WORKERS_PER_CORE * cores:
        raise SinsInputError(
            f"--workers {workers}: more than {WORKERS_PER_CORE} processes a core ({cores} cores here); each "
            "worker is a process of its own (for a larger cluster, start one and give --scheduler)"
        )
    if scheduler:
        _connect(scheduler).close()  # refuse an address with no scheduler before writing anything
    with folder.locked(out, spec):
        parts = folder.prepare(out, spec, resume)
        resumed, ran, rejected = len(parts.done), 0, list(parts.rejected)
        for attempt in range(RUNS + 1):
            todo = [u for u in range(spec.count) if u not in parts.done]
            if not todo:
                break
            if attempt == RUNS:
                raise SinsInputError(
                    f"{out}: parts failed their check again after their units ran: {rejected[-1]}"
                )
            _compute(spec, out, todo, parts, workers, scheduler, progress)
            ran += len(todo)
            parts = folder.check_parts(out, spec, parts.identity)
            rejected += parts.rejected
        with deferred.all_or_nothing():  # the table and its summary land together (a signal between had
            table = results.join(out, spec, parts.tables)  # left the table alone)
            summary = results.summarise(table, spec)
            results.write_summary(out, summary)
    return CampaignRun(out, ran, resumed, time.perf_counter() - start, summary, tuple(rejected))


def _compute(
    spec: CampaignSpec,
    out: Path,
    todo: list[int],
    parts: folder.Parts,
    workers: int | None,
    scheduler: str | None,
    progress: Callable[[int, int], None] | None,
) -> None:
    """Run ``todo`` on a cluster (started here unless ``scheduler``), writing each task's rows as a part."""
    from dask.distributed import Client, KilledWorker, as_completed

    client: Any = None
    cluster: Any = None
    n = min(workers or os.cpu_count() or 1, len(todo))  # a worker beyond the units would wait for none
    with _quiet_dask(), _DeferredInterrupt() as interrupt:
        try:
            if scheduler:
                client = _connect(scheduler)
            else:
                cluster = _local_cluster(n)
                interrupt.check()
                client = Client(cluster)
                interrupt.check()
                client.wait_for_workers(n, timeout=WORKERS_WAIT_S)
            interrupt.check()
            n_workers = max(1, len(client.scheduler_info()["workers"]))
            size = units_per_task(len(todo), n_workers)
            key = f"sins-campaign-{parts.identity[:16]}"
            pending = as_completed(
                [client.submit(task, spec, b, key=f"{key}-{b[0]}-{b[-1]}") for b in batches(todo, size)]
            )
            finished = len(parts.done)
            while not pending.is_empty():
                ready = pending.next_batch(block=False) if pending.has_ready() else []
                for future in ready:
                    batch, rows = future.result()
                    results.write_part(out / "parts", batch, rows, parts.identity)
                    finished += len(batch)
                    if progress:
                        progress(finished, spec.count)
                interrupt.check()
                if not ready:
                    time.sleep(POLL_S)
        except TimeoutError:
            raise SinsInputError(
                f"--workers {n}: the cluster's workers did not start in {WORKERS_WAIT_S:g} s"
            ) from None
        except KilledWorker:
            raise SinsInputError(
                "a campaign task killed every worker that ran it, as often as dask retries one (out of "
                "memory, say): lower --workers, or give the workers more memory; --resume keeps what ran"
            ) from None
        finally:
            if client is not None:
                client.close()
            if cluster is not None:
                cluster.close()


#: How often the main process looks for finished tasks (and a Ctrl-C) while none is ready, s.
POLL_S = 0.05


class _DeferredInterrupt:
    """Ctrl-C held while dask's calls run, raised at :meth:`check` (between them).

    A ``KeyboardInterrupt`` raised inside dask.distributed's synchronous calls cancels their futures
    half-way: closing the cluster then failed with dask's own ``UnboundLocalError`` (twice: once
    more at exit). Raised between the calls, the cluster closes in order.
    """

    hit = False

    def __enter__(self) -> _DeferredInterrupt:
        self.previous: Any = None
        if threading.current_thread() is threading.main_thread():
            self.previous = signal.signal(signal.SIGINT, self._note)
        return self

    def _note(self, signum: int, frame: Any) -> None:
        self.hit = True

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if Ctrl-C was pressed since the block began."""
        if self.hit:
            raise KeyboardInterrupt

    def __exit__(self, *exc: object) -> None:
        if self.previous is not None:
            signal.signal(signal.SIGINT, self.previous)
        if self.hit and exc[0] is None:
            raise KeyboardInterrupt


def _connect(address: str) -> Any:
    from dask.distributed import Client
    from distributed.comm import parse_address
    from distributed.comm.registry import get_backend

    try:
        # The address read before a client is made: Client starts its event loop's thread first, and a
        # loaded machine (the test suite's other workers) let distributed's own 10 s wait for that thread
        # lapse, an AssertionError of distributed's, before "garbage" was read as no address at all.
        scheme, location = parse_address(address)
        get_backend(scheme).resolve_address(location)
        return Client(address, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise SinsInputError(f"--scheduler {address}: cannot reach a dask scheduler there ({exc})") from None
    except ValueError as exc:  # not an address at all ("missing port number", an unknown protocol)
        why = " ".join(str(exc).split())
        raise SinsInputError(
            f"--scheduler {address}: not a dask scheduler's address, tcp://HOST:PORT ({why})"
        ) from None


def _local_cluster(n: int) -> Any:
    """A local cluster of ``n`` worker processes, one thread each, that Ctrl-C does not reach.

    Ctrl-C reaches every process of the terminal's process group: each worker printed its
    ``KeyboardInterrupt`` traceback (38-45 lines) before ``sins: interrupted``. The workers are spawned
    with SIGINT ignored, which a new Python interpreter keeps, and this process stops them when it is
    interrupted. Only the spawning is shielded (the scheduler starts first, then the workers are
    asked for and SIGINT comes back once each has a pid), so a Ctrl-C is missed for a moment at most.
    The dashboard's port is any free one: two local campaigns at once each warned that 8787 was in use.
    """
    from dask.distributed import LocalCluster

    # One thread per worker process: the kernels and torch are single-threaded by design here, and
    # processes sidestep the GIL in the numpy glue.
    cluster = LocalCluster(
        n_workers=0, threads_per_worker=1, processes=True, dashboard_address=":0",
        env={"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"},
    )  # fmt: skip
    try:
        with _sigint_ignored(), _workers_quiet():
            cluster.scale(n)
            deadline = time.monotonic() + SPAWN_WAIT_S
            while len(_spawned()) < n and time.monotonic() < deadline:
                time.sleep(0.01)
    except BaseException:
        cluster.close()
        raise
    return cluster


#: How long the workers' processes may take to be spawned (not started: spawned), and started, s.
SPAWN_WAIT_S = 60.0
WORKERS_WAIT_S = 300.0


def _spawned() -> list[int]:
    """The pids of the worker processes spawned so far: this process's children running
    multiprocessing's ``spawn_main`` (dask lists a worker only once it has started)."""
    import psutil

    pids = []
    for child in psutil.Process().children():
        try:
            if any("spawn_main" in part for part in child.cmdline()):
                pids.append(child.pid)
        except psutil.Error:  # gone, or not yet readable
            continue
    return pids


@contextlib.contextmanager
def _sigint_ignored() -> Iterator[None]:
    """SIGINT ignored for the block, where signals can be set (the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def _workers_quiet() -> Iterator[None]:
    """Worker processes spawned in the block start with dask's log lines off (its environment
    variable for the ``distributed`` logger, which a worker reads when it imports dask, before any task
    can quiet it): a worker stopped at Ctrl-C while still unpickling its first task warned that the task
    was cancelled, a line :func:`_quiet_dask` cannot reach in another process. Left as the user set it,
    if they did."""
    name = "DASK_LOGGING__DISTRIBUTED"
    if name in os.environ:
        yield
        return
    os.environ[name] = "critical"
    try:
        yield
    finally:
        os.environ.pop(name, None)


@contextlib.contextmanager
def _quiet_dask() -> Iterator[None]:
    """dask's own log lines and warnings kept from the terminal while a cluster lives and closes: its
    warnings on cancelled tasks and on workers killed at Ctrl-C, a port in use; what matters reaches
    the user as the one line of the error it raises here."""
    logger = logging.getLogger("distributed")
    level = logger.level
    logger.setLevel(logging.CRITICAL + 1)
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", module="distributed")
            yield
    finally:
        logger.setLevel(level)


__all__ = [
    "MAX_UNITS_PER_TASK",
    "POLL_S",
    "RUNS",
    "SPAWN_WAIT_S",
    "TASKS_PER_WORKER",
    "WORKERS_PER_CORE",
    "WORKERS_WAIT_S",
    "CampaignRun",
    "batches",
    "run",
    "units_per_task",
]
