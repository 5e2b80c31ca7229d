"""Campaign throughput: issue 21's unit-hour on 1 and 2 processes, stream-hours per second of campaigns
on a local dask cluster of 1 and 2 workers with their peak memory, one core's time per stream-sample by
stage, and units sharing a trajectory.

Usage::

    .venv/bin/python tools/bench_campaign.py [--units 8] [--workers 1 2] [--strategies none regression]
        [--cluster-units 48] [--direct] [--kernel-units 32] [--only-kernel]

First the kernel (``--kernel-units`` units, 0 to skip): issue 21's unit-hour is one unit driven one
hour at 100 Hz, its readings corrupted, corrected with ``regression`` and integrated once, reduced to
its errors against the truth. The units are fitted first (their CPU time printed apart), then driven
in tasks sharing a trajectory (as many units as a 1,000-unit campaign puts in one) on process pools
of each ``--workers`` count: wall time, unit-hours per second, the time 1,000 would take, and the
ratio of the rates.

Then campaigns, where a unit is a tactical unit calibrated on the 24-position + rate-table rig and
driven through the one-hour ``car_drive`` once per strategy, ``none`` and the oracle always with them
(three streams with the defaults): a stream-hour is one stream's hour of 100 Hz samples, corrupted
(once per unit for all its streams), corrected, integrated and reduced. A campaign of
``--cluster-units`` units on a local cluster of each ``--workers`` count (``--direct``: 334 units,
1,002 stream-hours, on the last count): wall time, stream-hours per second, and the peak memory of
this process and its workers together, sampled every 0.2 s, both proportional (PSS: a shared library
page split among the processes that map it, the tree's cost to the machine) and resident (RSS: counted
in every process). Then ``--units`` units in this process as a campaign task runs them
(``sins.campaign.unit.run_units``: rig fits, then one generated trajectory driven by every unit), the
main thread's CPU time split by stage (generation runs on a second thread and is counted apart), in ns
of one core per stream-sample. Last, the CPU time per stream-sample of units driven one call each and
all sharing one trajectory. CPU times stand up to a shared machine better than wall times; compare
figures of one run only.
"""

from __future__ import annotations

import argparse
import collections
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import psutil

from sins import campaign, compensation
from sins.campaign import engine, unit
from sins.compensation import base
from sins.imu import stream
from sins.nav import metrics
from sins.runs import pipeline

CAMPAIGN = """name = "bench"
[units]
imu = "tactical"
count = {units}
first_seed = 1
[compensation]
rig = "24pos_ratetable"
strategies = {strategies}
[[scenario]]
file = "car_drive"
[keep]
series_hz = 0.01
"""

SAMPLES_PER_HOUR = 360_000
#: The stage that runs on the prefetching thread, shared by the units of a task.
GENERATE = "generate: truth, ideal IMU, truth frames"


def load(folder: Path, units: int, strategies: list[str]) -> campaign.CampaignSpec:
    """The benchmark's campaign of ``units`` units, written to ``folder``."""
    path = folder / "bench.toml"
    path.write_text(CAMPAIGN.format(units=units, strategies=repr(strategies).replace("'", '"')))
    return campaign.load(path)


def streams_of(spec: campaign.CampaignSpec) -> int:
    """Streams per unit and scenario: none, every strategy, the oracle (a campaign always has it)."""
    assert spec.compensation is not None
    return len(dict.fromkeys(["none", *spec.compensation.strategies]))


@contextmanager
def stage_clock() -> Iterator[collections.Counter[str]]:
    """Main-thread CPU seconds per stage while in the block, by wrapping the stages' entry points."""
    spent: collections.Counter[str] = collections.Counter()
    wrapped = [
        (pipeline, "fit_unit", "fit: rig session and strategies"),
        (stream.IncrementStream, "push", "corrupt"),
        (stream.IncrementStream, "finish", "corrupt"),
        (base.NoCompensation, "correct_increments", "correct: none"),
        (base.Oracle, "correct_increments", "correct: oracle"),
        (compensation.Regression, "correct_increments", "correct: regression"),
        (pipeline.strapdown, "advance", "integrate"),
        (pipeline, "errors_against", "reduce: errors against the truth"),
        (metrics.DriftAccumulator, "add", "reduce: statistics, thinned series"),
    ]
    saved = [(obj, name, getattr(obj, name)) for obj, name, _ in wrapped]

    def timed(fn: Callable[..., Any], label: str) -> Callable[..., Any]:
        def call(*args: Any, **kwargs: Any) -> Any:
            t0 = time.thread_time()
            try:
                return fn(*args, **kwargs)
            finally:
                spent[label] += time.thread_time() - t0

        return call

    def timed_items(fn: Callable[..., Iterator[Any]], label: str) -> Callable[..., Iterator[Any]]:
        # A generator runs on the thread that asks for its next item: the prefetching one.
        def items(*args: Any, **kwargs: Any) -> Iterator[Any]:
            it = fn(*args, **kwargs)
            while True:
                t0 = time.thread_time()
                item = next(it, None)
                spent[label] += time.thread_time() - t0
                if item is None:
                    return
                yield item

        return items

    for (obj, name, label), (_, _, fn) in zip(wrapped, saved, strict=True):
        setattr(obj, name, timed(fn, label))
    shared = pipeline._shared
    pipeline._shared = timed_items(shared, GENERATE)  # type: ignore[assignment]
    try:
        yield spent
    finally:
        for obj, name, fn in saved:
            setattr(obj, name, fn)
        pipeline._shared = shared  # type: ignore[assignment]


def stages(spec: campaign.CampaignSpec, units: int) -> None:
    """CPU time per stream-sample by stage, for ``units`` units run as one campaign task."""
    unit.run_units(spec, [0])  # compiled kernels loaded, caches warm
    with stage_clock() as spent:
        main0 = time.thread_time()
        unit.run_units(spec, list(range(1, units + 1)))
        main = time.thread_time() - main0
    samples = units * streams_of(spec) * SAMPLES_PER_HOUR
    print(
        f"{units} units x {streams_of(spec)} streams of 1 h at 100 Hz in one task (this process), "
        f"CPU time per stream-sample:"
    )
    on_main = {k: v for k, v in spent.items() if k != GENERATE}
    rows = [*sorted(on_main.items()), ("other (main thread)", main - sum(on_main.values()))]
    rows.append((GENERATE + " (second thread)", spent[GENERATE]))
    cpu = main + spent[GENERATE]
    for label, seconds in rows:
        print(f"  {label:<52} {seconds / units:6.3f} s/unit {seconds / samples * 1e9:6.0f} ns  "
              f"{100 * seconds / cpu:4.0f} %")  # fmt: skip
    print(f"  {'total':<52} {cpu / units:6.3f} s/unit {cpu / samples * 1e9:6.0f} ns")


def sharing(spec: campaign.CampaignSpec, units: int) -> None:
    """CPU time per stream-sample of units driven one call each against all sharing one trajectory."""
    fitted = [pipeline.fit_unit(spec.unit_imu(u), spec.unit_compensation(u)) for u in range(units)]
    seeds = [campaign.nav_seed(spec.unit_seed(u)) for u in range(units)]
    base_sc = spec.scenarios[0]
    samples = units * streams_of(spec) * SAMPLES_PER_HOUR
    t0 = time.process_time()
    for f, seed in zip(fitted, seeds, strict=True):
        pipeline.run_units(base_sc, [f], [seed], keep_hz=0.01, sensor_errors=False)
    alone = time.process_time() - t0
    t0 = time.process_time()
    pipeline.run_units(base_sc, fitted, seeds, keep_hz=0.01, sensor_errors=False)
    shared = time.process_time() - t0
    print(
        f"driving only (fits apart), CPU per stream-sample: {alone / samples * 1e9:.0f} ns a unit alone, "
        f"{shared / samples * 1e9:.0f} ns {units} units sharing one trajectory ({alone / shared:.2f}x)"
    )


class _RegressionOnly(pipeline.FittedUnit):
    """A fitted unit driven with ``regression`` alone: no ``none`` or oracle stream beside it."""

    def for_run(self, nav_model: Any) -> dict[str, Any]:
        return {"regression": self.strategies["regression"]}


def _fit(job: tuple[campaign.CampaignSpec, int]) -> tuple[_RegressionOnly, float]:
    """Unit ``u`` fitted, and the CPU seconds it took."""
    spec, u = job
    t0 = time.process_time()
    f = pipeline.fit_unit(spec.unit_imu(u), spec.unit_compensation(u))
    only = _RegressionOnly(f.spec, f.compensation, f.strategies, f.residuals, f.biases)
    return only, time.process_time() - t0


def _drive(job: tuple[Any, list[_RegressionOnly], list[int], int]) -> float:
    """Drive fitted units through the scenario in tasks of ``size`` sharing a trajectory, as a campaign
    task does; the process's CPU seconds."""
    sc, fitted, seeds, size = job
    t0 = time.process_time()
    for i in range(0, len(fitted), size):
        pipeline.run_units(sc, fitted[i : i + size], seeds[i : i + size], keep_hz=0.01, sensor_errors=False)
    return time.process_time() - t0


def kernel(spec: campaign.CampaignSpec, units: int, workers: list[int]) -> None:
    """Issue 21's unit-hour: one unit driven one hour at 100 Hz, its readings corrupted, corrected with
    ``regression`` and integrated once, and reduced to its errors; the units fitted beforehand (their
    cost printed apart). Wall time on process pools of each ``workers`` count, each worker warmed first
    (compiled kernels loaded)."""
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max(workers)) as pool:  # the fits, on every process
        done = list(pool.map(_fit, [(spec, u) for u in range(units)], chunksize=8))
    fitted = [f for f, _ in done]
    fit_s = sum(cpu for _, cpu in done)
    seeds = [campaign.nav_seed(spec.unit_seed(u)) for u in range(units)]
    sc = spec.scenarios[0]
    print(
        f"kernel: {units} units fitted in {fit_s:.1f} s of CPU ({fit_s / units:.3f} s a unit: rig session, "
        f"none and regression fits, residuals)"
    )
    rates, core_rate = {}, 0.0
    for n in workers:
        with ProcessPoolExecutor(n) as pool:
            list(pool.map(_drive, [(sc, fitted[:1], seeds[:1], 1)] * n))  # warm every worker
            share = -(-units // n)
            # Tasks as large as a campaign of 1,000 units on n workers would run.
            size = engine.units_per_task(1000, n)
            jobs = [(sc, fitted[i : i + share], seeds[i : i + share], size) for i in range(0, units, share)]
            t0 = time.perf_counter()
            cpu = sum(pool.map(_drive, jobs))
            wall = time.perf_counter() - t0
        rates[n] = rate = units / wall
        ns = cpu / units / SAMPLES_PER_HOUR * 1e9
        if n == 1:
            core_rate = units / cpu
        print(
            f"kernel on {n} process(es): {units} unit-hours (corrupt, correct with regression, integrate, "
            f"reduce) in {wall:.1f} s: {rate:.2f} unit-hours/s, {ns:.0f} ns "
            f"of CPU a unit-sample; 1,000 unit-hours would take {1000 / rate:.0f} s "
            f"({1000 * fit_s / units / n:.0f} s more to fit 1,000 units on {n})"
        )
    if 1 in rates and 2 in rates:
        # One process is not one core: its second thread generates the next chunk of the trajectory.
        print(
            f"kernel, 2 processes / 1: {rates[2] / rates[1]:.2f}x the rate; 2 processes / one core's rate "
            f"(the 1-process run's CPU time, {core_rate:.2f} unit-hours/s): {rates[2] / core_rate:.2f}x"
        )


class PeakMemory:
    """The largest memory of this process and its descendants together, sampled: resident (RSS, every
    shared library page counted once per process that maps it) and proportional (PSS, a shared page
    split among the processes that share it, so the sum is what the tree costs the machine)."""

    def __init__(self, every_s: float = 0.2) -> None:
        self.peak = 0  # RSS
        self.peak_pss = 0
        self.at_peak: list[int] = []  # each process's RSS at the RSS peak, largest first
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, args=(every_s,), daemon=True)

    def _watch(self, every_s: float) -> None:
        me = psutil.Process()
        while not self._stop.is_set():
            sizes, pss = [], 0
            for p in [me, *me.children(recursive=True)]:
                try:
                    info = p.memory_full_info()
                except psutil.Error:  # gone meanwhile
                    continue
                sizes.append(info.rss)
                pss += info.pss
            if sum(sizes) > self.peak:
                self.peak, self.at_peak = sum(sizes), sorted(sizes, reverse=True)
            self.peak_pss = max(self.peak_pss, pss)
            self._stop.wait(every_s)

    def __enter__(self) -> PeakMemory:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()


def _wait_for_workers_to_exit(timeout_s: float = 30.0) -> None:
    """Until the last cluster's workers are gone (at most ``timeout_s``): the next cluster's peak
    memory must not count them."""

    def big_children() -> bool:
        for p in psutil.Process().children(recursive=True):
            try:
                if p.memory_info().rss > 100e6:
                    return True
            except psutil.Error:  # gone meanwhile
                pass
        return False

    end = time.monotonic() + timeout_s
    while time.monotonic() < end and big_children():
        time.sleep(0.2)


def cluster_rates(folder: Path, units: int, workers: list[int], strategies: list[str]) -> None:
    """Campaigns of ``units`` units on local clusters of each ``workers`` count."""
    spec = load(folder, units, strategies)
    rates = {}
    for n in workers:
        with PeakMemory() as rss:
            run = engine.run(spec, folder / f"out{units}-{n}", workers=n)
        _wait_for_workers_to_exit()
        unit_hours = units * streams_of(spec)
        rates[n] = rate = unit_hours / run.wall_s
        by_process = " + ".join(f"{m / 1e6:.0f}" for m in rss.at_peak)
        print(
            f"{n} worker(s): {units} units x {streams_of(spec)} streams of 1 h at 100 Hz in "
            f"{run.wall_s:.1f} s (cluster start-up included): {rate:.2f} stream-hours/s "
            f"({rate * SAMPLES_PER_HOUR / 1e6:.2f} M samples/s); 1,000 stream-hours would take "
            f"{1000 / rate:.0f} s; peak memory {rss.peak_pss / 1e6:.0f} MB proportional (PSS), "
            f"{rss.peak / 1e6:.0f} MB resident ({by_process} MB by process)"
        )
    if 1 in rates and 2 in rates:
        print(f"2 workers / 1 worker: {rates[2] / rates[1]:.2f}x the rate")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=8, help="units of parts 1 and 2")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--strategies", nargs="+", default=["none", "regression"])
    parser.add_argument("--cluster-units", type=int, default=48, help="units of part 3's campaigns")
    parser.add_argument(
        "--direct", action="store_true", help="334 units (1,002 stream-hours) on the last worker count"
    )
    parser.add_argument(
        "--kernel-units", type=int, default=32, help="units of the kernel's throughput (0: skip it)"
    )
    parser.add_argument("--only-kernel", action="store_true", help="the kernel's throughput alone")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        spec = load(folder, max(args.units, args.cluster_units) + 1, args.strategies)
        if args.kernel_units:
            kernel(load(folder, args.kernel_units, ["regression"]), args.kernel_units, args.workers)
        if args.only_kernel:
            return
        # The clusters first, while this process holds little beyond what `sins campaign` would.
        if args.direct:
            units = -(-1000 // streams_of(spec))
            cluster_rates(folder, units, args.workers[-1:], args.strategies)
        else:
            cluster_rates(folder, args.cluster_units, args.workers, args.strategies)
        stages(spec, args.units)
        sharing(spec, args.units)


if __name__ == "__main__":
    main()
