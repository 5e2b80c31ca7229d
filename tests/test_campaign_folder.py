"""A campaign folder owned by one campaign (issue 35, items 1-3): a lock held for the run, an identity in
``campaign.json`` and in every part, parts checked when read and run again when damaged or foreign; and
issue 33's first item, results whose columns are the union of all rows'.

Each numbered item of the issue fails on the code before it: two campaigns mixed their rows in one
folder, a folder without ``campaign.json`` was adopted by another campaign, a damaged part counted as
done (a traceback, or a message naming no file), a foreign one raised ``KeyError``.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from conftest import communicate, refusal, run_process

from sins import campaign
from sins.campaign import engine, folder, results
from sins.campaign.unit import BIAS_FIELDS, RESIDUAL_FIELDS, SUMMARY_FIELDS
from sins.cli import main

#: A rig session of a minute at 10 Hz: a unit fits in a fraction of a second.
RIG = """[rig]
lat_deg = 45.0
rate_hz = 10
[positions]
count = 6
dwell_s = 4.0
[rate_table]
rates_dps = [30.0]
axes = ["z"]
orientations = ["up"]
dwell_s = 4.0
"""

DRIVE = """name = "drive"
[imu]
rate_hz = 20
[initial]
lat_deg = 45.0
yaw_deg = 10.0
[[segment]]
type = "accelerate"
duration_s = 5
to_speed_mps = 5
[[segment]]
type = "turn"
duration_s = 5
angle_deg = 45
"""


def _campaign(
    tmp_path: Path, count: int = 2, first_seed: int = 3, name: str = "tiny", extra: str = ""
) -> Path:
    (tmp_path / "rig.toml").write_text(RIG)
    (tmp_path / "drive.toml").write_text(DRIVE)
    path = tmp_path / f"{name}.toml"
    path.write_text(
        f'name = "{name}"\n[units]\nimu = "tactical"\ncount = {count}\nfirst_seed = {first_seed}\n'
        '[compensation]\nrig = "rig.toml"\nstrategies = ["none", "regression"]\n'
        f'[[scenario]]\nfile = "drive.toml"\n{extra}[keep]\nseries_hz = 1\n'
    )
    return path


def _rows(spec: campaign.CampaignSpec, units: list[int]) -> list[dict[str, Any]]:
    """Rows shaped as a unit's (seeds, names, every figure), made up: what a part's check reads."""
    rows = []
    for u in units:
        seed = spec.unit_seed(u)
        for sc in spec.scenarios:
            for st in dict.fromkeys(["none", *spec.compensation.strategies]):
                seeds = {"unit_seed": seed, "rig_seed": 2 * seed, "nav_seed": 2 * seed + 1}
                row: dict[str, Any] = {"unit": u, **seeds, "scenario": sc.name, "strategy": st}
                row |= {f: float(u + 1) for f in (*SUMMARY_FIELDS, *RESIDUAL_FIELDS, *BIAS_FIELDS)}
                row |= {"series_t_s": [0.0, 1.0], "series_horizontal_m": [0.0, 0.5]}
                rows.append(row)
    return rows


def _table(out: Path) -> dict[str, list[object]]:
    return pq.read_table(out / "results.parquet").to_pydict()


# --------------------------------------------------------------------------- the lock


def test_a_second_campaign_into_a_held_folder_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Item 1: today both campaigns ran and ``results.parquet`` mixed their rows. Held here by this
    process, then by another one: the second campaign is refused at once, naming the holder."""
    path = _campaign(tmp_path)
    spec = campaign.load(path)
    out = tmp_path / "out"
    with folder.locked(out, spec):
        assert main(["campaign", str(path), "--out", str(out), "--workers", "1"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"in use by campaign tiny (pid {os.getpid()} on" in err, err
    code = (
        "import sys, time; from pathlib import Path; from sins import campaign; "
        "from sins.campaign import folder; spec = campaign.load(sys.argv[1])\n"
        "with folder.locked(Path(sys.argv[2]), spec):\n    print('held', flush=True); time.sleep(600)"
    )
    holder = subprocess.Popen(
        [sys.executable, "-c", code, str(path), str(out)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        refusal(lambda: engine.run(spec, out, workers=1), str(out), f"pid {holder.pid}", "another --out")
    finally:
        holder.kill()  # SIGKILL: no chance to remove its lock file
        holder.wait()
    # Its lock is stale now (the kernel released the flock with the process): the folder is taken over.
    assert json.loads((out / folder.LOCK_NAME).read_text())["pid"] == holder.pid
    with folder.locked(out, spec):
        assert json.loads((out / folder.LOCK_NAME).read_text())["pid"] == os.getpid()
    assert not (out / folder.LOCK_NAME).exists()


def test_a_lock_left_on_this_host_is_stale_and_another_hosts_is_named(tmp_path: Path) -> None:
    spec = campaign.load(_campaign(tmp_path))
    out = tmp_path / "out"
    out.mkdir()
    dead = subprocess.Popen(["true"])
    dead.wait()
    lock = out / folder.LOCK_NAME
    lock.write_text(json.dumps({"pid": dead.pid, "host": socket.gethostname(), "campaign": "old"}))
    with folder.locked(out, spec):  # a dead pid on this host: taken over
        pass
    lock.write_text(json.dumps({"pid": 4242, "host": "elsewhere.example", "campaign": "far", "started": "x"}))
    refusal(
        lambda: folder.locked(out, spec).__enter__(), "elsewhere.example", "another machine", f"delete {lock}"
    )


# --------------------------------------------------------------------------- parts checked when read


def _zeroed(raw: bytes) -> bytes:
    middle = len(raw) // 2
    return raw[: middle - 64] + bytes(128) + raw[middle + 64 :]


@pytest.mark.parametrize(
    ("damage", "why"),
    [
        (lambda raw: b"garbage", "unreadable"),
        (lambda raw: b"", "unreadable"),
        (lambda raw: raw[: len(raw) // 2], "unreadable"),
        (_zeroed, "unreadable"),
    ],
    ids=["garbage", "empty", "truncated", "zeroed-bytes"],
)
def test_a_damaged_part_is_rejected_when_read(tmp_path: Path, damage: Any, why: str) -> None:
    """Item 3: today a damaged part counted as done (``ArrowInvalid`` traceback; zeroed bytes: "Corrupt
    snappy compressed data." naming no file). Now it is moved aside, named, and its units are to run."""
    spec = campaign.load(_campaign(tmp_path))
    out = tmp_path / "out"
    parts = folder.prepare(out, spec, resume=False)
    assert parts.done == set()
    good = results.write_part(out / "parts", [0], _rows(spec, [0]), parts.identity)
    bad = results.write_part(out / "parts", [1], _rows(spec, [1]), parts.identity)
    bad.write_bytes(damage(bad.read_bytes()))
    checked = folder.check_parts(out, spec)
    assert checked.done == {0} and len(checked.tables) == 1
    assert len(checked.rejected) == 1 and str(bad) in checked.rejected[0] and why in checked.rejected[0]
    assert good.exists() and not bad.exists() and (out / "rejected" / bad.name).exists()


def test_a_part_of_another_campaign_or_of_other_rows_is_rejected(tmp_path: Path) -> None:
    """A part written by another campaign (today: ``KeyError: 'static'`` at the join), one without an
    identity, one whose rows are not its name's units, or whose columns are not a row's."""
    spec = campaign.load(_campaign(tmp_path))
    (tmp_path / "o").mkdir()
    other = campaign.load(_campaign(tmp_path / "o", first_seed=9))
    out = tmp_path / "out"
    ident = folder.prepare(out, spec, resume=False).identity
    assert folder.identity(other) != ident
    parts = out / "parts"
    results.write_part(parts, [0], _rows(other, [0]), folder.identity(other))
    pq.write_table(pa.Table.from_pylist(_rows(spec, [1])), parts / "units-0000001-0000001.parquet")
    results.write_part(parts, [2], _rows(spec, [0]), ident)  # unit 0's rows named as unit 2's
    rows = _rows(spec, [3])
    for row in rows:
        row["colour"] = "blue"
    results.write_part(parts, [3], rows, ident)
    checked = folder.check_parts(out, spec)
    assert checked.done == set() and len(checked.rejected) == 4
    reasons = " | ".join(checked.rejected)
    for fragment in ("written by another campaign", "carries no campaign identity", "beyond the campaign",
                     "a column no row has"):  # fmt: skip
        assert fragment in reasons, reasons


def test_a_folder_without_its_description_is_not_adopted_by_another_campaign(tmp_path: Path) -> None:
    """Item 2: with ``campaign.json`` removed, another campaign into the folder (no ``--resume``) ran
    no unit and labelled the first campaign's rows as its own. Now: refused without ``--resume``; with
    it, the foreign parts are set aside and every unit is to run."""
    spec = campaign.load(_campaign(tmp_path))
    out = tmp_path / "out"
    ident = folder.prepare(out, spec, resume=False).identity
    results.write_part(out / "parts", [0, 1], _rows(spec, [0, 1]), ident)
    (out / "campaign.json").unlink()
    (tmp_path / "b").mkdir()
    other = campaign.load(_campaign(tmp_path / "b", name="other", first_seed=7))
    refusal(lambda: folder.prepare(out, other, resume=False), str(out), "--resume")
    parts = folder.prepare(out, other, resume=True)
    assert parts.done == set() and "written by another campaign" in parts.rejected[0]
    # Once the other campaign holds results there, the first is refused outright, even with --resume.
    results.write_part(out / "parts", [0], _rows(other, [0]), parts.identity)
    refusal(lambda: folder.prepare(out, spec, resume=True), "holds another campaign", "first_seed")


def test_damaged_and_foreign_parts_run_again_and_the_results_equal_an_uninterrupted_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """End to end: a campaign run whole; a copy with one part's bytes zeroed and the other replaced by a
    foreign campaign's, resumed, while the first part it writes is damaged on the way (checked again
    after the units ran): every part is rejected and run again, and ``results.parquet`` equals the whole
    run's."""
    spec = campaign.load(_campaign(tmp_path))
    whole = engine.run(spec, tmp_path / "whole", workers=1)
    assert whole.units_run == 2 and whole.rejected == ()
    cut = tmp_path / "cut"
    shutil.copytree(tmp_path / "whole", cut)
    first, second = sorted((cut / "parts").glob("units-*.parquet"))
    first.write_bytes(_zeroed(first.read_bytes()))
    (tmp_path / "f").mkdir()
    foreign = campaign.load(_campaign(tmp_path / "f", first_seed=50))
    second.unlink()
    results.write_part(cut / "parts", [1], _rows(foreign, [1]), folder.identity(foreign))
    write_part = results.write_part
    damaged: list[Path] = []

    def damaging(parts: Path, units: list[int], rows: list[dict[str, Any]], identity: str) -> Path:
        path = write_part(parts, units, rows, identity)
        if not damaged:
            damaged.append(path)
            path.write_bytes(path.read_bytes()[:100])
        return path

    monkeypatch.setattr(results, "write_part", damaging)
    again = engine.run(spec, cut, workers=1, resume=True)
    assert damaged and len(again.rejected) == 3 and again.units_resumed == 0
    assert _table(cut) == _table(tmp_path / "whole")
    assert again.summary == whole.summary


def test_a_resume_around_a_finished_middle_part_runs_the_units_either_side_as_tasks_of_their_own(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A walkthrough's Ctrl-C left only the middle part; resumed, the units either side of it went to
    one task, named by their span, whose part the check refused (a row for every unit between) and the
    campaign ended without results. Tasks now hold consecutive units alone."""
    assert engine.batches([0, 1, 2, 5, 6, 9], 2) == [[0, 1], [2], [5, 6], [9]]
    spec = campaign.load(_campaign(tmp_path, count=3))
    monkeypatch.setattr(engine, "units_per_task", lambda units, workers: 3)  # tasks of many units, as at 120
    out = tmp_path / "out"
    results.write_part(out / "parts", [1], _rows(spec, [1]), folder.prepare(out, spec, resume=False).identity)
    again = engine.run(spec, out, workers=1, resume=True)
    assert (again.units_resumed, again.units_run, again.rejected) == (1, 2, ())
    assert (out / "results.parquet").is_file()


# --------------------------------------------------------------------------- Ctrl-C, a port in use


def test_an_interrupted_campaign_prints_one_line_and_another_into_its_folder_is_refused_meanwhile(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``sins campaign`` in its own process group, as a terminal runs it, with dask's dashboard port
    8787 taken: while it runs a second campaign into its folder is refused in one line; Ctrl-C (SIGINT
    to the group, workers included) prints ``sins: interrupted`` and nothing else (today: 38-45 lines
    of dask tracebacks, and "Port 8787 is already in use"); the parts it left are whole and resume to
    the rows of an uninterrupted run."""
    path = _campaign(tmp_path, count=6)
    out = tmp_path / "out"
    port = socket.socket()
    try:
        port.bind(("127.0.0.1", 8787))
        port.listen()
    except OSError:
        pass  # in use already: the warning it would cause is the same
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    sins = str(Path(sys.executable).parent / "sins")
    run = subprocess.Popen(
        [sins, "campaign", str(path), "--out", str(out), "--workers", "2"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 300
        while not list((out / "parts").glob("units-*.parquet")) and run.poll() is None:
            assert time.monotonic() < deadline, "no part written in 300 s"
            time.sleep(0.2)
        assert main(["campaign", str(path), "--out", str(out), "--workers", "1"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"pid {run.pid}" in err, err
        os.killpg(run.pid, signal.SIGINT)
        _, stderr = communicate(run)
    finally:
        if run.poll() is None:
            os.killpg(run.pid, signal.SIGKILL)
        port.close()
    if run.returncode == 0:
        pytest.skip("the campaign ended before the interrupt reached it (a fast machine)")
    assert run.returncode == 130
    assert [line for line in stderr.decode().splitlines() if not _progress(line)] == ["sins: interrupted"]
    assert not (out / folder.LOCK_NAME).exists()
    assert [p.name for p in (out / "parts").iterdir() if not p.name.startswith("units-")] == []


# --------------------------------------------------------------------------- issue 33: the union of rows


AIDED = """name = "aided"
[imu]
rate_hz = 20
[gnss]
rate_hz = 1
seed = 3
[[outage]]
start_s = 20
end_s = 30
[alignment]
method = "truth"
[initial]
lat_deg = 45.0
yaw_deg = 10.0
[[segment]]
type = "accelerate"
duration_s = 10
to_speed_mps = 8
[[segment]]
type = "turn"
duration_s = 30
angle_deg = 60
"""


def test_rows_of_a_free_inertial_scenario_first_keep_every_aided_column() -> None:
    """``pa.Table.from_pylist`` (today's writer) takes its columns from the first row: a free-inertial
    row first drops every aided figure of the rows after it."""
    free = {"unit": 0, "final_horizontal_m": 1.0}
    rows = [free, {**free, "aided_final_horizontal_m": 0.5, "outage1_end_m": 3.0}]
    assert "outage1_end_m" not in pa.Table.from_pylist(rows).column_names
    table = results.rows_table(rows)
    assert table.column_names == ["unit", "final_horizontal_m", "aided_final_horizontal_m", "outage1_end_m"]
    assert table.column("outage1_end_m").to_pylist() == [None, 3.0]


def test_a_campaign_with_a_free_inertial_scenario_first_keeps_and_prints_the_aided_figures(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 33, item 1, run as a user runs it: ``results.parquet`` has the aided and outage columns
    (null on the free-inertial rows), the summary has their statistics for the aided scenario's groups
    only, and the printed table shows them."""
    (tmp_path / "aided.toml").write_text(AIDED)
    path = _campaign(tmp_path, count=2, extra='[[scenario]]\nfile = "aided.toml"\n')
    assert main(["campaign", str(path), "--out", str(tmp_path / "out"), "--workers", "1"]) == 0
    printed = capsys.readouterr().out
    table = _table(tmp_path / "out")
    for column in ("aided_final_horizontal_m", "aided_max_horizontal_m", "outage1_end_m", "outage1_max_m"):
        values = np.array(table[column], dtype=float)
        aided = np.array(table["scenario"]) == "aided"
        assert np.isfinite(values[aided]).all() and np.isnan(values[~aided]).all(), column
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert "outage1_end_m" in summary["groups"]["aided/regression"]
    assert "outage1_end_m" not in summary["groups"]["drive/regression"]
    median = summary["groups"]["aided/regression"]["outage1_end_m"]["median"]
    assert "aided navigation (GNSS/INS) in aided" in printed and "outage 1 end" in printed
    assert f"{median:.4g} m" in printed


# --------------------------------------------------------------------------- checks before the work


def test_a_scenario_sins_run_refuses_at_once_is_refused_before_the_cluster(tmp_path: Path) -> None:
    """A 0.002 s scenario: today it reached the campaign only after every unit's rig fit, with 6-10
    lines of dask's "Compute Failed" before the error."""
    path = _campaign(tmp_path)
    campaign.load(path)  # the sound drive
    (tmp_path / "drive.toml").write_text(
        DRIVE.split("[[segment]]")[0] + '[[segment]]\ntype = "hold"\nduration_s = 0.002\n'
    )
    refusal(
        lambda: campaign.load(path), str(path), "scenario[1].file", "drive.toml", "shorter than one sample"
    )


@pytest.mark.parametrize(
    ("alignment", "fragment"),
    [('method = "static"\nstatic_s = 100', "longer than the run"),
     ('method = "static"\nstatic_s = 20', "moves within the first 20 s"),
     ('method = "gnss_velocity"\nmin_speed_mps = 10000', "never reaches 10000 m/s")],
    ids=["static-longer-than-the-run", "static-while-moving", "min-speed"],
)  # fmt: skip
def test_an_alignment_the_trajectory_cannot_give_is_refused_before_the_cluster(
    tmp_path: Path, alignment: str, fragment: str
) -> None:
    (tmp_path / "aided.toml").write_text(AIDED.replace('method = "truth"', alignment))
    path = _campaign(tmp_path, extra='[[scenario]]\nfile = "aided.toml"\n')
    refusal(lambda: campaign.load(path), str(path), "scenario[2].file", "aided.toml", fragment)


def test_a_wrong_kind_of_file_and_a_vanishing_series_rate_name_the_campaign_file_and_key(
    tmp_path: Path,
) -> None:
    path = _campaign(tmp_path)
    text = path.read_text()
    path.write_text(text.replace('imu = "tactical"', 'imu = "drive.toml"'))
    refusal(lambda: campaign.load(path), str(path), "units.imu", "drive.toml")
    path.write_text(text.replace('rig = "rig.toml"', 'rig = "drive.toml"'))
    refusal(lambda: campaign.load(path), str(path), "compensation.rig", "drive.toml")
    path.write_text(text.replace("series_hz = 1", "series_hz = 1e-300"))  # today: IndexError in a worker
    refusal(lambda: campaign.load(path), str(path), "keep.series_hz", "at least 1e-06 Hz")


def test_outputs_that_cannot_be_written_are_refused_before_the_work(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--rerun`` and ``--update-baseline`` into a place that cannot take them failed only after all the
    work; ``--out`` under a file likewise. Now refused first, naming the output (never a temporary
    file): the engine is never called."""
    path = _campaign(tmp_path)

    def no_work(*args: Any, **kwargs: Any) -> None:
        raise AssertionError("the campaign ran before its outputs were checked")

    monkeypatch.setattr(engine, "run", no_work)
    (tmp_path / "file").write_text("")
    # A folder that refuses new files, as a read-only one does (root is not refused by permissions).
    locked = tmp_path / "read-only"
    locked.mkdir()
    make = tempfile.TemporaryFile

    def refusing(*args: Any, **kwargs: Any) -> Any:
        if Path(kwargs.get("dir") or ".") == locked:
            raise PermissionError(13, "Permission denied")
        return make(*args, **kwargs)

    monkeypatch.setattr(tempfile, "TemporaryFile", refusing)
    rrd = str(locked / "s.rrd")
    cases = [
        (["campaign", str(path), "--out", str(tmp_path / "o"), "--rerun", rrd], rrd),
        (["campaign", str(path), "--out", str(locked / "o")], str(locked / "o")),
        (["campaign", str(path), "--out", str(tmp_path / "file" / "o")], str(tmp_path / "file" / "o")),
        (["check", str(path), "--baseline", str(locked / "b.json"), "--update-baseline"], "b.json"),
        (["check", str(path), "--baseline", str(tmp_path / "no" / "b.json"), "--update-baseline"], "b.json"),
    ]  # fmt: skip
    for argv, named in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and named in err and ".tmp" not in err, err


def test_a_write_that_fails_names_the_target_not_the_temporary_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A folder that refuses new files (as a non-root user sees a read-only one), a disk that fills:
    today the error named ``.run.json.XXXX.tmp``, which the user never asked for."""
    from sins import io

    def refused(*args: Any, **kwargs: Any) -> Any:
        raise PermissionError(13, "Permission denied", str(tmp_path / ".run.json.abc123.tmp"))

    target = tmp_path / "run.json"
    with monkeypatch.context() as m:
        m.setattr(tempfile, "mkstemp", refused)
        with pytest.raises(PermissionError) as info:
            io.write_json(target, {"a": 1})
    assert info.value.filename == str(target)

    def full(obj: Any, fh: Any, **kwargs: Any) -> None:
        raise OSError(28, "No space left on device", fh.name)

    monkeypatch.setattr(json, "dump", full)
    with pytest.raises(OSError, match="No space left") as info:
        io.write_json(target, {"a": 1})
    assert info.value.filename == str(target) and list(tmp_path.iterdir()) == []


def test_a_unit_its_rig_cannot_fit_is_one_line_from_the_cluster(tmp_path: Path) -> None:
    """A rig of one table rate and no positions cannot determine the seed model: the task's
    ``ValueError`` came back as a traceback, after the worker's 6-10 lines of "Compute Failed". Now
    one line naming the campaign file and the unit, and nothing from the worker."""
    path = _campaign(tmp_path, count=1)
    (tmp_path / "rig.toml").write_text(RIG.replace("count = 6", "count = 0"))
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    sins = str(Path(sys.executable).parent / "sins")
    run = run_process([sins, "campaign", str(path), "--out", str(tmp_path / "out"), "--workers", "1"],
                      capture_output=True, text=True, env=env)  # fmt: skip
    assert run.returncode == 2
    # Progress lines (after 5 s of work, on a loaded machine) aside, the error is one line.
    said = [line for line in run.stderr.splitlines() if not _progress(line)]
    assert len(said) == 1 and f"{path}: unit 0: simulated rig" in said[0], run.stderr


def _progress(line: str) -> bool:
    """A log's progress line (``campaign NAME: working (5 s)``, ``...: done``), which a long job on a busy
    machine writes to stderr beside its result (:class:`sins.cli.progress.LogProgress`)."""
    return not line.startswith("sins:") and re.search(r": .* \(\d+ s\)$", line) is not None


def test_another_command_does_not_write_into_a_campaigns_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # A walk replaced a campaign's campaign.json by `sins inspect --json` and its results.parquet by
    # `sins integrate --out` (both exit 0): the campaign then refused to resume ("not a sins campaign
    # results folder"). Every output in its folder, or a folder of it, is refused now but the
    # campaign's own (its --out among the command's folders).
    from sins.cli import main
    from sins.io import paths

    camp = tmp_path / "camp"
    (camp / "parts").mkdir(parents=True)
    identity = '{"format": "sins-campaign", "identity": "abc"}\n'
    (camp / "campaign.json").write_text(identity)
    scenario = tmp_path / "short.toml"
    scenario.write_text('[initial]\nlat_deg = 45.0\n[[segment]]\ntype = "hold"\nduration_s = 5\n')
    for out in (camp / "campaign.json", camp / "summary.json", camp / "parts" / "x.json"):
        assert main(["run", str(scenario), "--json", str(out)]) == 2
        err = capsys.readouterr().err
        assert (
            f"--json {out}: is in the results folder of a campaign ({camp})" in err and err.count("\n") == 1
        )
    assert (camp / "campaign.json").read_text() == identity and not (camp / "summary.json").exists()
    assert main(["run", str(scenario), "--json", str(tmp_path / "beside.json")]) == 0  # beside it: fine
    paths.check_outputs({"--plot": camp / "errors.png"}, folders={"--out": camp})  # the campaign's own
