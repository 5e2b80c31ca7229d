"""Running a campaign on dask.distributed: a local cluster of the machine's cores, or any scheduler.

The only module that imports dask. Units are grouped into tasks of a few units each; results
come back as tasks finish and are written at once as Parquet parts (:mod:`sins.campaign.results`).
A worker lost mid-campaign costs only its running tasks: the scheduler gives them to another worker
(up to ``distributed.scheduler.allowed-failures`` times), and a task's rows depend only on the campaign
and its units, so a rerun task writes the rows it would have written.
"""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sins.campaign import results
from sins.campaign.spec import CampaignSpec
from sins.campaign.unit import task
from sins.errors import SinsInputError

#: Tasks per worker the units are split into: enough that a slow task does not idle the others at the
#: end, few enough that each task's start-up (a worker's first import of torch, say) is paid rarely.
TASKS_PER_WORKER = 4
#: The most units in one task: a task's units share each scenario's generated trajectory (its cost
#: split among them: ~70 ns a unit-sample of a tactical unit's ~410 with 8 units, ~18 with 32), and a
#: task is what a lost worker costs and how often results come back (32 one-hour units of
#: ``regression`` alone: ~2 min of a core).
MAX_UNITS_PER_TASK = 32


def units_per_task(units: int, workers: int) -> int:
    """How many of ``units`` one task runs on ``workers`` workers: :data:`TASKS_PER_WORKER` tasks a
    worker, at most :data:`MAX_UNITS_PER_TASK` units a task."""
    return max(1, min(MAX_UNITS_PER_TASK, math.ceil(units / (TASKS_PER_WORKER * max(1, workers)))))


@dataclass(frozen=True)
class CampaignRun:
    """What :func:`run` did: the results folder, the units run now and before, the wall time."""

    out: Path
    units_run: int
    units_resumed: int
    wall_s: float
    summary: dict[str, Any]


def run(
    spec: CampaignSpec,
    out: Path,
    workers: int | None = None,
    scheduler: str | None = None,
    resume: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> CampaignRun:
    """Run every unit not yet in ``out`` on a dask cluster, then join and summarise the rows.

    Parameters
    ----------
    spec : the campaign (:func:`sins.campaign.spec.load`)
    out : the results folder (created; on ``resume`` it must hold the same campaign)
    workers : processes of the local cluster (default: the machine's cores); not with ``scheduler``
    scheduler : the address of a running dask scheduler (``tcp://HOST:PORT``): its workers must see
        the campaign's files at the same paths and have sins installed
    resume : continue a campaign from the parts ``out`` holds
    progress : called as ``progress(units_done, units)`` as tasks finish
    """
    from dask.distributed import Client, LocalCluster, as_completed

    start = time.perf_counter()
    if scheduler:
        _connect(scheduler).close()  # refuse an address with no scheduler before writing anything
    done = results.prepare(out, spec, resume)
    todo = [u for u in range(spec.count) if u not in done]
    if todo:
        if scheduler:
            client = _connect(scheduler)
            cluster = None
        else:
            n = workers or os.cpu_count() or 1
            # One thread per worker process: the kernels and torch are single-threaded by design here,
            # and processes sidestep the GIL in the numpy glue.
            cluster = LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                env={"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"},
            )  # fmt: skip
            client = Client(cluster)
        try:
            n_workers = max(1, len(client.scheduler_info()["workers"]))
            size = units_per_task(len(todo), n_workers)
            batches = [todo[i : i + size] for i in range(0, len(todo), size)]
            futures = [
                client.submit(task, spec, batch, key=f"sins-campaign-{spec.name}-{batch[0]}-{batch[-1]}")
                for batch in batches
            ]
            finished = len(done)
            for future in as_completed(futures):
                batch, rows = future.result()
                results.write_part(out / "parts", batch, rows)
                finished += len(batch)
                if progress:
                    progress(finished, spec.count)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    table = results.join(out, spec)
    summary = results.summarise(table, spec)
    results.write_summary(out, summary)
    return CampaignRun(out, len(todo), len(done), time.perf_counter() - start, summary)


def _connect(address: str) -> Any:
    from dask.distributed import Client

    try:
        return Client(address, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise SinsInputError(f"--scheduler {address}: cannot reach a dask scheduler there ({exc})") from None


def log_progress(stream: Any = sys.stdout) -> Callable[[int, int], None]:
    """A progress callback printing a plain line at each tenth of the units (for logs and CI)."""
    last = [-1]

    def report(done: int, total: int) -> None:
        tenth = 10 * done // total
        if tenth != last[0]:
            last[0] = tenth
            print(f"campaign: {done}/{total} units", file=stream, flush=True)

    return report
