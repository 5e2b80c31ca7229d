"""Campaigns: rows equal to ``sins run`` for the same unit, identical on any cluster, nothing lost to a
killed worker or an interruption, one-line refusals before any work."""

from __future__ import annotations

import json
import os
import pickle
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from conftest import refusal, wait_for

from sins import campaign, scenario
from sins.campaign import engine, folder, gate, results
from sins.cli import main

BIN = Path(sys.executable).parent


def _campaign(
    tmp_path: Path, count: int = 3, strategies: str = '["none", "regression"]', extra: str = ""
) -> Path:
    path = tmp_path / "c.toml"
    path.write_text(
        f"""name = "t"
[units]
imu = "tactical"
count = {count}
first_seed = 5
[compensation]
rig = "24pos_ratetable"
strategies = {strategies}
[[scenario]]
file = "car_drive_5min"
[keep]
series_hz = 0.1
{extra}"""
    )
    return path


def _table(out: Path) -> dict[str, list[object]]:
    return pq.read_table(out / "results.parquet").to_pydict()


def _sins_run_of(row: dict[str, Any], scenario_text: str, tmp_path: Path) -> dict[str, Any]:
    """``sins run --json`` of a row's unit as a user would write it: an IMU file with its unit_seed, the
    scenario with its navigation and rig power-ons; the JSON written."""
    (tmp_path / "unit.toml").write_text(f'grade = "tactical"\nunit_seed = {row["unit_seed"]}\n')
    drive = scenario_text.replace(
        "[imu]\nrate_hz = 100\n", f'[imu]\nrate_hz = 100\nmodel = "unit.toml"\nseed = {row["nav_seed"]}\n'
    )
    drive += (
        f'\n[compensation]\nrig = "24pos_ratetable"\nseed = {row["rig_seed"]}\n'
        'strategies = ["none", "regression"]\n'
    )
    (tmp_path / "drive.toml").write_text(drive)
    assert main(["run", str(tmp_path / "drive.toml"), "--json", str(tmp_path / "run.json")]) == 0
    return dict(json.loads((tmp_path / "run.json").read_text()))


# --------------------------------------------------------------------------- the single-unit path


def test_a_campaign_row_is_sins_run_of_that_unit_to_the_last_digit(tmp_path: Path) -> None:
    """Unit 1 of the campaign (unit_seed 6), written out as the IMU and scenario files a user would write
    with the row's seeds, run by ``sins run``: every figure equal, bit for bit."""
    spec = campaign.load(_campaign(tmp_path))
    rows = campaign.run_unit(spec, 1)
    assert {r["unit_seed"] for r in rows} == {6}
    ran = _sins_run_of(rows[0], scenario.resolve_preset("car_drive_5min").read_text(), tmp_path)["strategies"]
    assert [r["strategy"] for r in rows] == list(ran) == ["none", "oracle", "regression"]
    for row in rows:
        single = ran[row["strategy"]]
        for key in (
            "final_horizontal_m",
            "max_horizontal_m",
            "rms_horizontal_m",
            "final_down_m",
            "final_yaw_deg",
        ):
            assert row[key] == single[key], (row["strategy"], key)
        residual = single.get("residual_rms") or {}
        for ch, value in residual.items():
            assert row[f"residual_{ch.replace('.', '_')}"] == value
    # The two power-ons differ (a rig fit cannot know the drive's turn-on bias), and units differ.
    assert rows[0]["rig_seed"] != rows[0]["nav_seed"]
    assert campaign.run_unit(spec, 0)[0]["final_horizontal_m"] != rows[0]["final_horizontal_m"]


# --------------------------------------------------------------------------- clusters


def test_one_and_two_local_workers_give_identical_results_and_resume_adds_only_what_is_missing(
    tmp_path: Path,
) -> None:
    spec = campaign.load(_campaign(tmp_path))
    one = engine.run(spec, tmp_path / "one", workers=1)
    two = engine.run(spec, tmp_path / "two", workers=2)
    assert one.units_run == two.units_run == 3
    assert _table(tmp_path / "one") == _table(tmp_path / "two")
    assert one.summary == two.summary
    # A resumed campaign whose parts were partly lost recomputes only those units, identically.
    parts = sorted((tmp_path / "two" / "parts").glob("units-*.parquet"))
    parts[-1].unlink()
    again = engine.run(spec, tmp_path / "two", workers=1, resume=True)
    assert again.units_resumed == 2 and again.units_run == 1
    assert _table(tmp_path / "one") == _table(tmp_path / "two")
    # Without --resume a folder holding results is refused, and another campaign's folder always.
    refusal(lambda: engine.run(spec, tmp_path / "two", workers=1), "--resume")
    other = campaign.load(_campaign(tmp_path, count=4))
    refusal(lambda: engine.run(other, tmp_path / "two", workers=1, resume=True), "another campaign", "units")


def test_an_interrupted_campaign_leaves_complete_rows_only(tmp_path: Path) -> None:
    """Interrupted after its first task (Ctrl-C as the results stream back): the parts hold whole units
    and no temporary file; --resume finishes it with the rows an uninterrupted run writes."""
    spec = campaign.load(_campaign(tmp_path, count=4))

    def interrupt(done: int, total: int) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        engine.run(spec, tmp_path / "cut", workers=1, progress=interrupt)
    parts = tmp_path / "cut" / "parts"
    assert [p.name for p in parts.iterdir() if not p.name.startswith("units-")] == []
    held = folder.check_parts(tmp_path / "cut", spec).done
    assert 1 <= len(held) < 4
    for part in parts.glob("units-*.parquet"):
        table = pq.read_table(part).to_pydict()
        assert len(table["unit"]) == 3 * len(set(table["unit"]))  # three strategies per unit, every one
    engine.run(spec, tmp_path / "cut", workers=1, resume=True)
    engine.run(spec, tmp_path / "whole", workers=1)
    assert _table(tmp_path / "cut") == _table(tmp_path / "whole")


def _start(args: list[str], log: Path) -> subprocess.Popen[bytes]:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    return subprocess.Popen(
        args, stdout=log.open("wb"), stderr=subprocess.STDOUT, env=env, start_new_session=True
    )


def test_a_cluster_started_by_hand_gives_the_same_rows_and_a_killed_worker_loses_nothing(
    tmp_path: Path,
) -> None:
    """``dask scheduler`` and ``dask worker`` started as separate processes, as a user would; one worker
    is killed (SIGKILL) once the first results are in, another joins: the campaign completes, and its
    rows equal a local cluster's."""
    spec = campaign.load(_campaign(tmp_path, count=6))
    engine.run(spec, tmp_path / "local", workers=2)
    address_file = tmp_path / "scheduler.json"
    scheduler = _start(
        [str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
         "--scheduler-file", str(address_file)],
        tmp_path / "scheduler.log",
    )  # fmt: skip
    workers: list[subprocess.Popen[bytes]] = []
    try:
        wait_for(address_file.exists, scheduler.pid, "the scheduler")
        address = json.loads(address_file.read_text())["address"]

        def worker(name: str) -> subprocess.Popen[bytes]:
            return _start(
                [str(BIN / "dask"), "worker", address, "--nthreads", "1", "--no-dashboard", "--name", name],
                tmp_path / f"{name}.log",
            )

        workers.append(worker("a"))
        killed = []

        def kill_one(done: int, total: int) -> None:
            if not killed:
                os.killpg(workers[0].pid, signal.SIGKILL)
                killed.append(done)
                workers.append(worker("b"))

        run = engine.run(spec, tmp_path / "remote", scheduler=address, progress=kill_one)
        assert killed and run.units_run == 6
        assert _table(tmp_path / "remote") == _table(tmp_path / "local")
    finally:
        for p in [*workers, scheduler]:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
                p.wait(30)


# --------------------------------------------------------------------------- results


def test_summary_statistics_and_intervals_follow_the_rows(tmp_path: Path) -> None:
    """The summary's median, percentiles and mean are numpy's over the units' rows, and each bootstrap
    interval contains its statistic."""
    spec = campaign.load(_campaign(tmp_path, count=5))
    run = engine.run(spec, tmp_path / "out", workers=1)
    table = _table(tmp_path / "out")
    assert len(table["unit"]) == 5 * 3
    assert table["unit"] == sorted(table["unit"])
    for group in run.summary["groups"].values():
        rows = [
            i for i, (s, g) in enumerate(zip(table["scenario"], table["strategy"], strict=True))
            if (s, g) == (group["scenario"], group["strategy"])
        ]  # fmt: skip
        values = np.array(table["final_horizontal_m"])[rows]
        stats = group["final_horizontal_m"]
        assert stats["median"] == pytest.approx(np.median(values), rel=1e-12)
        assert stats["p95"] == pytest.approx(np.percentile(values, 95), rel=1e-12)
        assert stats["mean"] == pytest.approx(values.mean(), rel=1e-12)
        for name in ("mean", "median", "p90", "p95"):
            low, high = stats[f"{name}_ci95"]
            assert low <= stats[name] <= high
    assert json.loads((tmp_path / "out" / "summary.json").read_text()) == run.summary
    series = table["series_horizontal_m"][0]
    assert len(series) == len(table["series_t_s"][0]) >= 30  # 5 min at 0.1 Hz, and the start and end


def test_bootstrap_intervals_equal_a_percentile_bootstrap_by_hand() -> None:
    """The summary's intervals (scipy's percentile bootstrap) equal resampling the units by hand with the
    same generator: the 2.5th and 97.5th percentiles of each statistic over the resamples (to 1e-12; the
    two sum in other orders)."""
    from sins.campaign import results

    rng = np.random.default_rng(4)
    for n in (2, 7, 40):
        values = rng.lognormal(size=n)
        draw = np.random.default_rng(results.BOOTSTRAP_SEED).integers(0, n, (results.BOOTSTRAP_RESAMPLES, n))
        stats = results._statistics(values)
        for name, q in results.STATISTICS.items():
            boot = values[draw].mean(axis=1) if q is None else np.percentile(values[draw], q, axis=1)
            np.testing.assert_allclose(stats[f"{name}_ci95"], np.percentile(boot, [2.5, 97.5]), rtol=1e-12)


# --------------------------------------------------------------------------- refusals


@pytest.mark.parametrize(
    ("change", "fragments"),
    [
        (("count = 3", "count = 0"), ("units.count", "must be")),
        (("first_seed = 5", "first_seed = 5\ncolour = 1"), ("colour",)),
        (
            ('strategies = ["none", "regression"]', 'strategies = ["none", "magic"]'),
            ("item 2: 'magic' is not a known name (one of none,",),
        ),
        # A name given twice: refused, where it was merged without a word.
        (
            ('strategies = ["none", "regression"]', 'strategies = ["none", "regression", "none"]'),
            ("compensation.strategies: item 3: 'none' is given twice",),
        ),
        (('file = "car_drive_5min"', 'file = "no_such_drive"'), ("no_such_drive",)),
        (('imu = "tactical"', 'imu = "no_such_unit"'), ("no_such_unit",)),
    ],
)
def test_a_bad_campaign_file_is_refused_in_one_line_before_any_work(
    tmp_path: Path, change: tuple[str, str], fragments: tuple[str, ...]
) -> None:
    path = _campaign(tmp_path)
    path.write_text(path.read_text().replace(*change))
    message = refusal(lambda: campaign.load(path), *fragments)
    assert str(path) in message


def test_the_cli_runs_a_campaign_and_refuses_workers_with_a_scheduler(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _campaign(tmp_path, count=2)
    assert main(["campaign", str(path), "--workers", "1", "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert "ran 2 units" in out and "car_drive_5min" in out and "regression" in out
    assert main(["campaign", str(path), "--workers", "1", "--scheduler", "tcp://x:1"]) == 2
    assert "--workers" in capsys.readouterr().err


AIDED_DRIVE = """name = "aided"
[imu]
rate_hz = 100
[gnss]
rate_hz = 1
seed = 3
[[outage]]
start_s = 40
end_s = 70
[initial]
lat_deg = 45.0
yaw_deg = 10.0
[[segment]]
type = "accelerate"
duration_s = 20
to_speed_mps = 12
[[segment]]
type = "turn"
duration_s = 30
angle_deg = 90
[[segment]]
type = "hold"
duration_s = 50
"""


def test_an_aided_campaign_row_carries_the_outage_errors_sins_run_reports(tmp_path: Path) -> None:
    """A [gnss] scenario in a campaign: each row adds the aided run's errors and each outage's, equal to
    ``sins run``'s for the same unit; the summary and the gate carry them."""
    (tmp_path / "aided.toml").write_text(AIDED_DRIVE)
    path = _campaign(tmp_path, count=1)
    path.write_text(path.read_text().replace('file = "car_drive_5min"', 'file = "aided.toml"'))
    spec = campaign.load(path)
    rows = campaign.run_unit(spec, 0)
    ran = _sins_run_of(rows[0], AIDED_DRIVE, tmp_path)
    for row in rows:
        outage = ran["outages"][row["strategy"]][0]
        assert row["outage1_end_m"] == outage["final_horizontal_m"]
        assert row["outage1_max_m"] == outage["max_horizontal_m"]
        assert row["aided_final_horizontal_m"] == ran["aided"][row["strategy"]]["final_horizontal_m"]
    table = pa.Table.from_pylist(rows)
    summary = results.summarise(table, spec)
    assert summary["groups"]["aided/regression"]["outage1_end_m"]["median"] == rows[-1]["outage1_end_m"]
    # The gate takes the outage figures as figures it gates (it refuses one it does not), and requires
    # the aided run's (compare, which tests them, wants more than one unit: gate.check_power).
    assert {"outage1_end_m", "aided_max_horizontal_m"} <= set(summary["groups"]["aided/regression"]["values"])
    gate.check_baseline(summary, "summary", spec)
    del summary["groups"]["aided/regression"]["values"]["aided_max_horizontal_m"]
    refusal(lambda: gate.check_baseline(summary, "summary", spec), "has no aided_max_horizontal_m")


def test_an_unreachable_scheduler_is_refused_before_anything_is_written_and_a_bare_folder_restarts(
    tmp_path: Path,
) -> None:
    """``--scheduler`` with no scheduler there: one line, and no results folder left to trip a rerun. A
    folder that holds a campaign's description but no finished unit starts afresh without --resume."""
    spec = campaign.load(_campaign(tmp_path, count=1))
    refusal(lambda: engine.run(spec, tmp_path / "none", scheduler="tcp://127.0.0.1:1"), "cannot reach")
    assert not (tmp_path / "none").exists()
    for address in ("garbage", "tcp://localhost:notaport", "udp://127.0.0.1:8786"):  # a traceback before
        refusal(lambda a=address: engine.run(spec, tmp_path / "none", scheduler=a), "not a dask scheduler's")
    assert not (tmp_path / "none").exists()
    # More local workers than four a core: refused before a process or a file is made (before, --workers
    # 100000 spawned processes until the machine stalled, and left a locked folder).
    many = engine.WORKERS_PER_CORE * (os.cpu_count() or 1) + 1
    refusal(lambda: engine.run(spec, tmp_path / "many", workers=many), f"--workers {many}", "--scheduler")
    assert not (tmp_path / "many").exists()
    folder.prepare(tmp_path / "bare", spec, resume=False)  # a description, no parts
    assert engine.run(spec, tmp_path / "bare", workers=1).units_run == 1


def test_a_worker_running_a_task_imports_neither_the_engine_nor_pyarrow() -> None:
    # A worker unpickles the task by its module: what that module imports every worker holds in memory
    # (pyarrow alone ~40 MB a worker, against the 1 GB a campaign may use).
    assert engine.task.__module__ == "sins.campaign.unit"
    code = (
        "import sys, sins.campaign.unit; "
        "print(sorted(m for m in ('pyarrow', 'dask', 'distributed', 'sins.campaign.engine', 'torch') "
        "if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_a_worker_running_a_unit_without_gnss_loads_no_filter_and_no_scipy_signal_or_stats(tmp_path):
    # Each spawned worker pays its imports before its first unit: scipy.signal (for one recursion) and
    # filterpy with scipy.stats (for a check of aided scenarios) cost ~0.5 s of a 2 s first unit.
    spec = campaign.load(_campaign(tmp_path, count=1))
    (tmp_path / "spec.pkl").write_bytes(pickle.dumps(spec))  # what a worker receives
    code = (
        "import pickle, sys, sins.campaign.unit as u; "
        f"u.run_unit(pickle.loads(open({str(tmp_path / 'spec.pkl')!r}, 'rb').read()), 0); "
        "print(sorted(m for m in ('filterpy', 'scipy.signal', 'scipy.stats', 'torch') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
