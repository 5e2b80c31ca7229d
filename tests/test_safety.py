"""Nothing a user runs destroys their data or hangs (issue 41): outputs that never replace an input or
each other, special files written in place or refused, inputs that are regular files, a campaign that
does not take over a user's folder, corrected files that say so, SIGTERM that leaves no temporary file.

Every case checks the bytes of every input before and after (SHA-256): a refusal is one line on stderr
naming the output, exit status 2, and nothing changed.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import stat
import subprocess
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import communicate, wait_for
from test_fuzz import IMU_MODEL, RIG, SCENARIO, assert_one_line, run_cli, to_toml

from sins import io
from sins.cli import main
from sins.errors import SinsInputError
from sins.io import provenance
from sins.io.atomic import atomic_path
from sins.io.datasets.root import data_root
from sins.io.paths import check_writable
from sins.io.recording import RATE_HZ_RANGE

STATIC_ROWS = 2400  # two minutes at 20 Hz


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Small valid inputs: a scenario and its simulated tactical unit (increments with temperature)
    and truth, a 10 Hz rig session and the model fitted on it, a static recording."""
    d = tmp_path_factory.mktemp("safety")
    (d / "s.toml").write_text(to_toml(SCENARIO))
    (d / "imu.toml").write_text(to_toml(IMU_MODEL))
    (d / "rig.toml").write_text(to_toml(RIG))
    for argv in (
        ["simulate", str(d / "s.toml"), "--model", "tactical", "--imu", str(d / "inc.csv"), "--truth",
         str(d / "truth.csv")],
        ["calibrate", str(d / "rig.toml"), "--imu", str(d / "imu.toml"), "--out", str(d / "rig.csv")],
        ["fit", str(d / "rig.csv"), "--strategy", "regression", "--out", str(d / "m.json")],
    ):  # fmt: skip
        rc, _, err = run_cli(argv)
        assert rc == 0, err
    rng = np.random.default_rng(1)
    gravity = np.array([0.0, 0.0, -9.80665])
    readings = np.column_stack([np.arange(STATIC_ROWS) / 20.0, rng.normal(0.0, 1e-3, (STATIC_ROWS, 3)),
                                gravity + rng.normal(0.0, 2e-3, (STATIC_ROWS, 3))])  # fmt: skip
    header = "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"
    np.savetxt(d / "static.csv", readings, delimiter=",", header=header, comments="", fmt="%.17g")
    return d


def _digests(paths: list[Path]) -> dict[Path, str]:
    return {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in paths if p.is_file()}


def _copy(files: Path, tmp: Path, *names: str) -> list[Path]:
    return [Path(shutil.copy(files / n, tmp / n)) for n in names]


#: Each case: the files copied in, the command (``{n}``: the path of file n in the folder; split on
#: spaces), and the output it must refuse to write.
ALIASES: dict[str, tuple[tuple[str, ...], str, str]] = {
    "correct onto its recording": (
        ("m.json", "inc.csv"),
        "correct {m.json} {inc.csv} --out {inc.csv}",
        "--out",
    ),
    "integrate onto its truth": (
        ("inc.csv", "truth.csv"),
        "integrate {inc.csv} --truth {truth.csv} --out {truth.csv}",
        "--out",
    ),
    "fit onto its rig recording": (("rig.csv",), "fit {rig.csv} --strategy none --out {rig.csv}", "--out"),
    "evaluate onto its model": (
        ("m.json", "rig.csv"),
        "evaluate {m.json} {rig.csv} --json {m.json}",
        "--json",
    ),
    "inspect onto its recording": (("inc.csv",), "inspect {inc.csv} --json {inc.csv}", "--json"),
    "characterise onto its recording": (
        ("static.csv",),
        "characterise {static.csv} --static --out {static.csv}",
        "--out",
    ),
    "fit's two outputs one file": (
        ("rig.csv", "m.json"),
        "fit {rig.csv} --strategy none --out {m.json} --json {m.json}",
        "--json",
    ),
    "simulate onto its scenario": (("s.toml",), "simulate {s.toml} --imu {s.toml} --truth t2.csv", "--imu"),
    "calibrate onto its IMU file": (
        ("rig.toml", "imu.toml"),
        "calibrate {rig.toml} --imu {imu.toml} --out {imu.toml}",
        "--out",
    ),
    "run onto its scenario": (("s.toml",), "run {s.toml} --json {s.toml}", "--json"),
    "a hard link to the input": (("inc.csv",), "inspect {inc.csv} --json link.json", "--json"),
    "the input by another path": (("inc.csv",), "inspect {inc.csv} --json sub/../inc.csv", "--json"),
}


def _named(arg: str, folder: Path, names: tuple[str, ...]) -> str:
    """``{n}`` in ``arg`` replaced by the path of file n in ``folder``."""
    for name in names:
        arg = arg.replace("{" + name + "}", str(folder / name))
    return arg


def _run_in(folder: Path, argv: str, names: tuple[str, ...]) -> tuple[int, str]:
    """``sins ARGV`` (``{n}``: file n's path in ``folder``) run in ``folder``, where its relative names
    resolve; its exit status and stderr."""
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        rc, _, err = run_cli([_named(a, folder, names) for a in argv.split()])
    finally:
        os.chdir(cwd)
    return rc, err


@pytest.mark.parametrize("case", sorted(ALIASES))
def test_no_output_replaces_an_input(files: Path, tmp_path: Path, case: str) -> None:
    """Before, each of these wrote over its input and ended 0 ("wrote m.json", the model gone)."""
    names, argv, flag = ALIASES[case]
    inputs = _copy(files, tmp_path, *names)
    (tmp_path / "sub").mkdir()
    os.link(tmp_path / names[0], tmp_path / "link.json")
    before = _digests([*inputs, tmp_path / "link.json"])
    rc, err = _run_in(tmp_path, argv, names)
    assert rc == 2 and err.startswith(f"sins: error: {flag} "), err
    assert_one_line(err, [Path(flag)])
    assert "input of this command" in err or "is also" in err, err
    assert _digests([*inputs, tmp_path / "link.json"]) == before


def _others(folder: Path) -> None:
    """Files a user keeps beside the inputs, each written by its own library, under names that do not say
    what they hold (a name that does is refused before its file is looked at: see
    :func:`test_an_output_named_for_another_format_is_refused`): an .npz recording (numpy) as
    ``recording``, a MATLAB recording (scipy) as ``session.dat``, a Parquet table (pyarrow), a link named
    ``link.json`` to the recording."""
    import pyarrow as pa
    import pyarrow.parquet as pq
    import scipy.io

    np.savez(folder / "rec.npz", t_s=np.arange(3.0), gyro_rad_s=np.zeros((3, 3)))
    os.rename(folder / "rec.npz", folder / "recording")
    scipy.io.savemat(folder / "rec.mat", {"imu_gyr": np.zeros((3, 3))})
    os.rename(folder / "rec.mat", folder / "session.dat")
    pq.write_table(pa.table({"t": [0.0, 1.0]}), folder / "table.parquet")
    (folder / "link.json").symlink_to(folder / "recording")
    # A picture, a page and a Rerun recording of the user's own (rerun, under another application id).
    (folder / "photo.png").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)))
    (folder / "page.html").write_text("<!DOCTYPE html>\n<html><body>my notes</body></html>\n")
    import rerun as rr

    rec = rr.RecordingStream("another_application")
    rec.save(folder / "other.rrd")
    rec.log("x", rr.Scalars([1.0]))
    rec.flush()
    rec.disconnect()
    readings = np.column_stack([np.arange(3.0), np.zeros((3, 5)), np.full(3, 9.8)])
    np.savetxt(folder / "logger.csv", readings, delimiter=",", header="t,gx,gy,gz,ax,ay,az", comments="")


#: What a refusal says a user's own text holds, where a table or an IMU file would go.
NOT_SINS = "text sins did not write (a recording, table or scenario of yours?)"
#: Each case: the files copied in, the command (as in :data:`ALIASES`), the output it must refuse to
#: write (a file none of its inputs, holding what that output never is), and what the refusal says it holds.
KEPT: dict[str, tuple[tuple[str, ...], str, str, str]] = {
    "evaluate's report onto a recording": (
        ("m.json", "rig.csv"), "evaluate {m.json} {rig.csv} --json recording", "--json", "a zip archive",
    ),
    "a report through a link to a recording": (
        ("inc.csv",), "inspect {inc.csv} --json link.json", "--json", "a zip archive",
    ),
    "a report onto a model": (("inc.csv", "m.json"), "inspect {inc.csv} --json {m.json}", "--json",
                              "a compensation model"),
    "a corrected table onto a MATLAB recording": (
        ("m.json", "inc.csv"), "correct {m.json} {inc.csv} --out session.dat", "--out", "a MATLAB file",
    ),
    "a model onto a CSV recording": (
        ("rig.csv", "static.csv"), "fit {rig.csv} --strategy none --out {static.csv}", "--out",
        "text that is not JSON",
    ),
    "corrected readings onto a logger's CSV recording": (
        ("m.json", "inc.csv"), "correct {m.json} {inc.csv} --out logger.csv", "--out",
        NOT_SINS,
    ),
    "a simulated unit onto a logger's CSV recording": (
        ("s.toml",), "simulate {s.toml} --imu logger.csv --truth t.csv", "--imu",
        NOT_SINS,
    ),
    "an IMU file onto a hand-written scenario": (
        ("static.csv", "s.toml"), "characterise {static.csv} --static --out scenario.toml", "--out",
        NOT_SINS,
    ),
    # A plot or a recording had replaced any PNG, any text and any Rerun recording (a walk's photo,
    # shopping list and page): only those sins drew or wrote now.
    "a plot onto a user's picture": (
        ("s.toml",), "run {s.toml} --plot photo.png", "--plot", "a PNG image sins did not draw",
    ),
    "a plot's page onto a user's page": (
        ("s.toml",), "run {s.toml} --plot page.html", "--plot", "text sins did not write (a page",
    ),
    "a recording onto another application's": (
        ("s.toml",), "run {s.toml} --rerun other.rrd", "--rerun", "a Rerun recording of another application",
    ),
    "a CSV solution onto a Parquet table": (
        ("inc.csv", "truth.csv"), "integrate {inc.csv} --truth {truth.csv} --out table.csv", "--out",
        "a Parquet table",
    ),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(KEPT))
def test_an_output_never_replaces_a_file_that_holds_what_it_is_not(
    files: Path, tmp_path: Path, case: str
) -> None:
    """A mistyped or tab-completed output name that is a user's recording, model or table, not an input
    of the command: refused in one line before the work, the file unchanged (before, ``sins evaluate M R
    --json rec.npz`` put its report where the recording was, and ended 0)."""
    names, argv, flag, holds = KEPT[case]
    inputs = _copy(files, tmp_path, *names)
    _others(tmp_path)
    if case == "a CSV solution onto a Parquet table":
        shutil.copy(tmp_path / "table.parquet", tmp_path / "table.csv")
    if case == "an IMU file onto a hand-written scenario":
        shutil.copy(tmp_path / "s.toml", tmp_path / "scenario.toml")
    others = ("recording", "session.dat", "table.parquet", "table.csv", "logger.csv", "scenario.toml",
              "photo.png", "page.html", "other.rrd")  # fmt: skip
    kept = [*inputs, *(tmp_path / n for n in others)]
    before = _digests(kept)
    rc, err = _run_in(tmp_path, argv, names)
    assert rc == 2 and err.startswith(f"sins: error: {flag} "), err
    assert_one_line(err, [Path(flag)])
    assert f"holds {holds}" in err and "does not replace it" in err, err
    assert _digests(kept) == before and (tmp_path / "link.json").is_symlink()


#: Each case: the files copied in, the command (as in :data:`ALIASES`), the output refused, the suffix
#: and what the refusal says sins writes there.
NAMED: dict[str, tuple[tuple[str, ...], str, str, str]] = {
    "corrected readings as .npz": (
        ("m.json", "inc.csv"), "correct {m.json} {inc.csv} --out c.npz", "--out c.npz", "a CSV table",
    ),
    "corrected readings as .parquet": (
        ("m.json", "inc.csv"), "correct {m.json} {inc.csv} --out c.parquet", "--out c.parquet", "a CSV table",
    ),
    "simulated readings as .json": (
        ("s.toml",), "simulate {s.toml} --imu i.json --truth t.csv", "--imu i.json", "a CSV table",
    ),
    "a rig session as .mat": (
        ("rig.toml", "imu.toml"), "calibrate {rig.toml} --imu {imu.toml} --out r.mat", "--out r.mat",
        "a CSV table",
    ),
    "a model as .csv": (("rig.csv",), "fit {rig.csv} --strategy none --out m.csv", "--out m.csv",
                        "a compensation model"),
    "a report as .csv": (
        ("m.json", "rig.csv"), "evaluate {m.json} {rig.csv} --json e.csv", "--json e.csv", "JSON",
    ),
    "an IMU file as .csv": (
        ("static.csv",), "characterise {static.csv} --static --out imu.csv", "--out imu.csv", "a TOML file",
    ),
    "a report as .parquet": (("inc.csv",), "inspect {inc.csv} --json i.parquet", "--json i.parquet", "JSON"),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(NAMED))
def test_an_output_named_for_another_format_is_refused(files: Path, tmp_path: Path, case: str) -> None:
    """An output whose suffix names a format other than the one written: refused in one line before the
    work, nothing written. Before, ``sins correct M R --out c.npz`` wrote CSV text under that name, which
    every reader of .npz, sins's own included, then refused as a damaged archive."""
    names, argv, shown, writes = NAMED[case]
    _copy(files, tmp_path, *names)
    rc, err = _run_in(tmp_path, argv, names)
    suffix = Path(shown.split()[1]).suffix
    assert rc == 2 and err.startswith(f"sins: error: {shown}: {suffix} names "), err
    assert f"sins writes {writes} there" in err, err
    assert_one_line(err, [Path(shown.split()[0])])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names)


def test_the_library_writers_refuse_a_name_for_another_format(files: Path, tmp_path: Path) -> None:
    """The check is the writers' own, not only the commands': a table, a JSON document or a model under
    a name that says another format is refused, and names that say no format are written."""
    from sins import compensation
    from sins.core.series import ImuRates
    from sins.errors import SinsInputError

    readings = ImuRates(t=np.arange(3.0), omega_ib_b=np.zeros((3, 3)), f_ib_b=np.ones((3, 3)))
    model = compensation.load(files / "m.json")
    writers: list[tuple[Callable[[Path], None], str]] = [
        (lambda p: io.write_imu(p, readings), "r.npz"),
        (lambda p: io.write_json(p, [1]), "d.csv"),
        (lambda p: compensation.save(model, p), "m.toml"),
    ]
    for write, name in writers:
        with pytest.raises(SinsInputError, match=f"{name}: \\.{name.split('.')[1]} names "):
            write(tmp_path / name)
        write(tmp_path / f"{name}.txt")  # a suffix that names no format
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.csv.txt", "m.toml.txt", "r.npz.txt"]


def test_an_output_replaces_what_it_wrote_before(files: Path, tmp_path: Path) -> None:
    """What an output is may be replaced: a model by a model, a report sins wrote by a report or a model,
    a table or an IMU file sins wrote by another, an empty file by anything."""
    rig, model = _copy(files, tmp_path, "rig.csv", "m.json")
    report = tmp_path / "report.json"
    assert run_cli(["inspect", str(rig), "--json", str(report)])[0] == 0  # a report: "sins" its first key
    assert next(iter(json.loads(report.read_text()))) == "sins"
    (tmp_path / "empty.out").touch()
    inc, truth, scenario, static = _copy(files, tmp_path, "inc.csv", "truth.csv", "s.toml", "static.csv")
    imu, solution = tmp_path / "imu2.csv", tmp_path / "solution.csv"
    for argv in (
        ["fit", str(rig), "--strategy", "none", "--out", str(model)],
        ["fit", str(rig), "--strategy", "none", "--out", str(report)],
        # A table sins wrote (its first line "# sins VERSION: ..."), written again by the same command.
        *[["simulate", str(scenario), "--imu", str(imu), "--truth", str(tmp_path / "t2.csv")]] * 2,
        *[["integrate", str(inc), "--truth", str(truth), "--out", str(solution)]] * 2,
        *[["characterise", str(static), "--static", "--out", str(tmp_path / "imu.toml")]] * 2,
        ["inspect", str(rig), "--json", str(tmp_path / "inspected.json")],
        ["inspect", str(rig), "--json", str(tmp_path / "inspected.json")],
        ["inspect", str(rig), "--json", str(tmp_path / "empty.out")],
    ):
        rc, _, err = run_cli(argv)
        assert rc == 0, (argv, err)
    assert json.loads(report.read_text())["strategy"] == "none"
    assert (tmp_path / "empty.out").stat().st_size > 0


def test_a_users_own_json_is_not_replaced_by_a_report_or_a_model(files: Path, tmp_path: Path) -> None:
    """A JSON file that sins did not write (a user's settings, another tool's results, a dataset's
    metadata) is refused by every command that writes JSON there, in one line and before the work, and is
    left as it was: ``sins fit --out``, ``--json`` of fit, evaluate, inspect and gap. Before, any JSON
    could be replaced by any report or model; a report now opens with ``"sins": VERSION``."""
    rig, model = _copy(files, tmp_path, "rig.csv", "m.json")
    mine = tmp_path / "settings.json"
    mine.write_text('{"editor.fontSize": 14, "figures": [1, 2]}\n')
    digest = hashlib.sha256(mine.read_bytes()).hexdigest()
    for argv in (
        ["fit", str(rig), "--strategy", "none", "--out", str(mine)],
        ["fit", str(rig), "--strategy", "none", "--out", str(tmp_path / "m2.json"), "--json", str(mine)],
        ["evaluate", str(model), str(rig), "--json", str(mine)],
        ["inspect", str(rig), "--json", str(mine)],
        ["gap", str(rig), "--json", str(mine)],
    ):
        rc, _, err = run_cli(argv)
        assert rc == 2 and len(err.strip().splitlines()) == 1, (argv, err)
        assert f"{mine}: holds JSON sins did not write" in err, err
        assert hashlib.sha256(mine.read_bytes()).hexdigest() == digest
    assert not (tmp_path / "m2.json").exists()


def test_sins_documents_are_replaced_only_by_their_own_kind(files: Path, tmp_path: Path) -> None:
    """A model and a quality baseline (the shipped one) are inputs of other commands: only a model
    replaces a model, only a baseline a baseline; both replace a report sins wrote, and neither, nor a
    report, replaces JSON sins did not write (a user's own)."""
    from sins.errors import SinsInputError
    from sins.io.paths import replaceable

    model, baseline = files / "m.json", Path(__file__).parents[1] / "scenarios" / "suite" / "baseline.json"
    plain, report = tmp_path / "plain.json", tmp_path / "report.json"
    plain.write_text("[1, 2]\n")
    report.write_text('{"sins": "0.1.0", "figures": [1, 2]}\n')
    inspection = tmp_path / "inspection.json"  # as `sins inspect --json` wrote it before the mark
    inspection.write_text('{"format": "sins-inspection", "rows": 10}\n')
    replaceable(inspection, "i", "json")
    replaceable(model, "m", "sins.compensation")
    replaceable(baseline, "b", "sins.quality-baseline")
    for kind in ("sins.compensation", "sins.quality-baseline", "json", "text"):
        replaceable(report, "r", kind)
    replaceable(plain, "p", "text")
    refused = [(model, "sins.quality-baseline", "a compensation model"),
               (baseline, "sins.compensation", "a quality baseline"),
               (model, "json", "a compensation model"), (baseline, "text", "a quality baseline"),
               *((plain, kind, "JSON sins did not write") for kind in
                 ("sins.compensation", "sins.quality-baseline", "json"))]  # fmt: skip
    for path, kind, holds in refused:
        with pytest.raises(SinsInputError, match=f"holds {holds}[ ;]"):
            replaceable(path, "x", kind)
    with pytest.raises(ValueError, match="output kind 'table'"):
        replaceable(plain, "p", "table")
    # A TOML file opens with a table's name in brackets, which is not JSON: a scenario or an IMU file is
    # text that a JSON output does not replace.
    for i, toml in enumerate(("[imu]\nmodel = 'tactical'\n", "[[case]]\nname = 'linear'\n")):
        path = tmp_path / f"t{i}.toml"
        path.write_text(toml)
        with pytest.raises(SinsInputError, match="holds text that is not JSON; sins writes JSON"):
            replaceable(path, "t", "json")
        replaceable(path, "t", "text")
    # A campaign's summary is a campaign baseline (the shipped one): the suite's --update-baseline, and
    # any report, had replaced it (it opens "sins-..." as a report does); only a campaign's replaces it.
    campaign = Path(__file__).parents[1] / "sins" / "scenarios" / "campaign" / "tactical_drives_baseline.json"
    replaceable(campaign, "c", "sins-campaign-summary")
    for kind in ("sins.quality-baseline", "json", "sins.compensation"):
        with pytest.raises(SinsInputError, match="holds a campaign's summary"):
            replaceable(campaign, "c", kind)
    with pytest.raises(SinsInputError, match="holds a quality baseline"):
        replaceable(baseline, "b", "sins-campaign-summary")


def device(folder: Path, name: str) -> Path:
    """A character device to write to: as root, a node of our own in ``folder`` for the kernel's
    ``name`` (``null``, ``full``), so that a regression replaces that node and not the machine's
    ``/dev/null`` (the atomic rename did that, as root); else ``/dev/NAME`` itself, which a user cannot
    replace."""
    real = Path("/dev") / name
    try:
        node = folder / f"dev-{name}"
        os.mknod(node, stat.S_IFCHR | 0o666, os.stat(real).st_rdev)
        return node
    except (PermissionError, OSError):
        return real


def test_a_character_device_is_written_in_place_and_a_fifo_refused(files: Path, tmp_path: Path) -> None:
    """An output that is the null device stays the device (the atomic rename once made ``/dev/null`` a
    regular file, as root); the full device is one line (no space); a FIFO is refused before the work,
    without waiting for a reader."""
    (rig,) = _copy(files, tmp_path, "rig.csv")
    null = device(tmp_path, "null")
    rc, _, err = run_cli(["fit", str(rig), "--strategy", "none", "--out", str(null)])
    assert rc == 0, err
    assert stat.S_ISCHR(os.stat(null).st_mode)
    full = device(tmp_path, "full")
    if full.exists():
        rc, _, err = run_cli(["fit", str(rig), "--strategy", "none", "--out", str(full)])
        assert rc == 2 and str(full) in err and "space" in err, err
        assert stat.S_ISCHR(os.stat(full).st_mode)
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    rc, _, err = run_cli(["fit", str(rig), "--strategy", "none", "--out", str(fifo)])
    assert rc == 2 and "FIFO" in err, err
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)


def test_a_symbolic_link_is_followed_and_stays_a_link(files: Path, tmp_path: Path) -> None:
    (rig,) = _copy(files, tmp_path, "rig.csv")
    (tmp_path / "kept").mkdir()
    link = tmp_path / "m.json"
    link.symlink_to(tmp_path / "kept" / "model.json")
    rc, _, err = run_cli(["fit", str(rig), "--strategy", "none", "--out", str(link)])
    assert rc == 0, err
    assert (
        link.is_symlink() and json.loads((tmp_path / "kept" / "model.json").read_text())["strategy"] == "none"
    )
    # A link to an input is that input.
    (tmp_path / "rig_link.csv").symlink_to(rig)
    before = _digests([rig])
    rc, _, err = run_cli(["fit", str(rig), "--strategy", "none", "--out", str(tmp_path / "rig_link.csv")])
    assert rc == 2 and "input of this command" in err, err
    assert _digests([rig]) == before


def test_bias_only_on_a_rig_recording_is_one_line(files: Path, tmp_path: Path) -> None:
    # A walk's `sins fit rig.csv --strategy bias_only` ended in a traceback of 21 lines (the progress
    # bar's unit asked make() for a strategy fitted against a trajectory only), whose hint named the
    # very command run; ferraris and oracle were refused in one line.
    rig = files / "rig.csv"
    rc, _, err = run_cli(["fit", str(rig), "--strategy", "bias_only", "--out", str(tmp_path / "m.json")])
    assert rc == 2 and "bias_only is fitted against a trajectory's reference, and this is a rig" in err, err
    assert_one_line(err, [rig])
    assert not (tmp_path / "m.json").exists()


def test_a_fit_whose_reader_goes_away_keeps_its_model(files: Path, tmp_path: Path) -> None:
    # `sins fit … | head -2`: the pipe's reader gone, the fit's print met a broken pipe and the command
    # ended there, its model (done) thrown away ("none of its outputs written"). Now the rest of what it
    # prints goes nowhere, the model lands, and it exits with SIGPIPE's status, quietly.
    model = tmp_path / "m.json"
    sins = Path(sys.executable).parent / "sins"
    argv = [str(sins), "fit", str(files / "rig.csv"), "--strategy", "regression", "--out", str(model)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # every print meets a closed pipe
    err = proc.stderr.read().decode()
    assert proc.wait(120) == 141 and "none of its outputs written" not in err, err
    assert json.loads(model.read_text())["strategy"] == "regression"


def test_a_fit_keeps_its_model_when_both_streams_lose_their_reader(files: Path, tmp_path: Path) -> None:
    # `sins fit … 2>&1 | head`: stderr lost its reader too, and the next note or progress line there met
    # the broken pipe inside the work (stdout alone was guarded). Both streams are now.
    model = tmp_path / "m.json"
    sins = Path(sys.executable).parent / "sins"
    argv = [str(sins), "fit", str(files / "rig.csv"), "--strategy", "regression", "--out", str(model)]
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    assert proc.stdout is not None
    proc.stdout.close()
    assert proc.wait(120) == 141
    assert json.loads(model.read_text())["strategy"] == "regression"


def test_a_command_whose_output_is_closed_runs_as_print_would(tmp_path: Path) -> None:
    # `sins scenarios >&-` (cron, a daemon): Python's sys.stdout is None, which print takes and drops; the
    # stream guard had raised an AttributeError on it, a traceback and exit 1.
    sins = Path(sys.executable).parent / "sins"
    proc = subprocess.run([str(sins), "scenarios"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                          text=True, timeout=120, preexec_fn=lambda: os.close(1))  # fmt: skip
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr


def test_a_signal_its_parent_ignores_stays_ignored() -> None:
    # `sins … &` from a script: Ctrl-C is not the background job's, and it had become so (the handler
    # was installed over the ignored signal). A signal set to be ignored stays ignored within a command.
    from sins.cli.signals import signals_as_exceptions

    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with signals_as_exceptions():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, before)


def test_a_commands_outputs_land_together_or_not_at_all(tmp_path: Path) -> None:
    """``sins simulate --imu A --truth B``: where the second write fails (``/dev/full``: no space), the
    first is not left replaced beside it; before, the new IMU file stood beside another run's truth (or
    an old one). The refusal says which outputs were kept as they were; the pair written when both can
    be is complete."""
    imu = tmp_path / "i.csv"
    old = "# sins 0.1.0: an earlier run's readings\nOLD\n"  # a table sins wrote: replaceable
    imu.write_text(old)
    rc, _, err = run_cli(["simulate", "car_drive_5min", "--imu", str(imu), "--truth", "/dev/full"])
    assert rc == 2 and "No space left on device" in err, err
    assert f"none of its outputs written ({imu}: not replaced)" in err, err
    assert imu.read_text() == old and sorted(p.name for p in tmp_path.iterdir()) == ["i.csv"]
    truth = tmp_path / "t.csv"
    rc, _, err = run_cli(["simulate", "car_drive_5min", "--imu", str(imu), "--truth", str(truth)])
    assert rc == 0 and imu.read_text() != old and truth.is_file(), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["i.csv", "t.csv"]


def test_a_campaign_does_not_take_over_a_folder_of_the_users(tmp_path: Path) -> None:
    """A folder with files of its own and no ``campaign.json`` (or one that is not sins's): before, the
    campaign wrote its ``summary.json`` (and ``campaign.json``) over the user's."""
    out = tmp_path / "mine"
    out.mkdir()
    (out / "summary.json").write_text('{"mine": true}\n')
    rc, _, err = run_cli(["campaign", "tactical_drives", "--out", str(out)])
    assert rc == 2 and "no campaign.json" in err and str(out) in err, err
    assert (out / "summary.json").read_text() == '{"mine": true}\n'
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]
    # A campaign.json of the user's own is no campaign's: before, it and summary.json were replaced.
    (out / "campaign.json").write_text('{"my": "notes"}\n')
    rc, _, err = run_cli(["campaign", "tactical_drives", "--out", str(out)])
    assert rc == 2 and "campaign.json: not a sins campaign" in err and err.count("\n") == 1, err
    assert (out / "campaign.json").read_text() == '{"my": "notes"}\n'
    assert (out / "summary.json").read_text() == '{"mine": true}\n'


# --------------------------------------------------------------------------- inputs


def _fifo(tmp_path: Path, name: str) -> Path:
    path = tmp_path / name
    os.mkfifo(path)
    return path


INPUTS: dict[str, Callable[[Path, Path], tuple[list[str], str]]] = {
    "a FIFO as the recording": lambda f, t: (["inspect", str(_fifo(t, "f.csv"))], "FIFO"),
    "a FIFO as the truth": lambda f, t: (["integrate", str(f / "inc.csv"), "--truth", str(_fifo(t, "t.csv"))],
                                         "FIFO"),
    "/dev/zero as the recording": lambda f, t: (["inspect", "/dev/zero"], "character device"),
    "a FIFO as the model": lambda f, t: (["evaluate", str(_fifo(t, "m.json")), str(f / "rig.csv")], "FIFO"),
    "a FIFO as the scenario": lambda f, t: (["run", str(_fifo(t, "s.toml"))], "FIFO"),
    "a folder as the truth": lambda f, t: (["integrate", str(f / "inc.csv"), "--truth", str(t)], "directory"),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(INPUTS))
def test_inputs_that_would_hang_or_never_end_are_refused_in_one_line(
    files: Path, tmp_path: Path, case: str
) -> None:
    """Before, a FIFO blocked its reader for ever and ``/dev/zero`` was read until memory ran out."""
    argv, fragment = INPUTS[case](files, tmp_path)
    rc, _, err = run_cli(argv)
    assert rc == 2 and fragment in err and err.count("\n") == 1, err


def test_a_euroc_stamp_beyond_64_bits_is_one_line(tmp_path: Path) -> None:
    """Before: OverflowError (a traceback) turning the stamps into int64."""
    imu = tmp_path / "mav0" / "imu0" / "data.csv"
    imu.parent.mkdir(parents=True)
    rows = [f"{1_403_636_579_758_555_392 + 5_000_000 * k},0,0,0,0,0,9.8" for k in range(50)]
    rows[20] = "99999999999999999999,0,0,0,0,0,9.8"
    imu.write_text("#timestamp [ns],w_x,w_y,w_z,a_x,a_y,a_z\n" + "\n".join(rows) + "\n")
    rc, _, err = run_cli(["inspect", str(tmp_path)])
    assert rc == 2 and f"{imu}:22:" in err and "beyond" in err and err.count("\n") == 1, err


@pytest.mark.parametrize("rate", ["1e300", "1e-300"])
def test_a_stated_rate_beyond_the_documented_limits_is_refused(files: Path, rate: str) -> None:
    """Before, ``--rate 1e300`` passed ``sins inspect`` and ``1e-300`` made times of 6e303 s."""
    rc, _, err = run_cli(["inspect", str(files / "static.csv"), "--rate", rate])
    assert rc == 2 and "0.1 Hz to 100000 Hz" in err, err
    low, high = RATE_HZ_RANGE
    assert (low, high) == (0.1, 1e5)


@pytest.mark.parametrize(
    "argv",
    [["simulate", "S", "--imu", "", "--truth", "T"], ["fit", "", "--strategy", "regression", "--out", "M"],
     ["fit", "RIG", "--strategy", "regression", "--out", ""], ["inspect", ""]],
    ids=["output", "input", "model", "inspect"],
)  # fmt: skip
def test_an_empty_path_is_refused_as_empty(
    files: Path, tmp_path: Path, argv: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    """``Path("")`` is ``.``: before, an empty output was "--out .: is a directory" and an empty
    recording was read as the working folder ("a folder, but neither a ROS 2 bag ...")."""
    named = {"S": files / "s.toml", "RIG": files / "rig.csv"}
    named |= {"T": tmp_path / "t.csv", "M": tmp_path / "m.json"}
    try:
        rc = main([str(named.get(a, a)) if a else a for a in argv])
    except SystemExit as ended:  # argparse's refusal (an empty path option)
        rc = int(ended.code or 0)
    err = capsys.readouterr().err
    assert rc == 2 and "empty path" in err and err.count("\n") == 1, err
    assert "is a directory" not in err and "neither a ROS" not in err, err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "flag", [["--rerun", "R"], ["--drive", "0:1"], ["--outage", "2"], ["--bias-from-rest"]]
)
def test_what_judges_against_a_trajectory_is_refused_on_a_rig(
    files: Path, tmp_path: Path, flag: list[str]
) -> None:
    """``--rerun`` on a rig recording had been ignored: exit 0, the table, and no file."""
    argv = ["evaluate", str(files / "m.json"), str(files / "rig.csv"), *flag]
    rc, _, err = run_cli([str(tmp_path / "e.rrd") if a == "R" else a for a in argv])
    assert rc == 2 and f"{flag[0]}: against a trajectory only" in err and "rig.csv" in err, err
    assert not list(tmp_path.iterdir())


def test_the_library_refuses_an_empty_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The readers and writers themselves, called from Python: ``""`` is not the working folder."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SinsInputError, match="empty path"):
        io.read("")
    with pytest.raises(SinsInputError, match="--out: an empty name"):
        check_writable("", flag="--out")
    with pytest.raises(SinsInputError, match="an empty name"), atomic_path(""):
        pass
    assert not list(tmp_path.iterdir())


# --------------------------------------------------------------------------- corrected files


def test_a_corrected_file_says_so_and_is_not_corrected_twice_unless_told(files: Path, tmp_path: Path) -> None:
    """``sins simulate``'s own output (increments with temperature): before, a ValueError (30000 vs
    29999 rows) in the writer. The corrected file keeps the unit's ``sensor`` line, adds ``corrected
    by`` naming the model and its digest, and keeps the temperature column as read; correcting it again
    is refused unless ``--again``, which adds a second line."""
    model, rec = _copy(files, tmp_path, "m.json", "inc.csv")
    # The rig's model was fitted on another simulated unit: read this recording as the same one.
    text = rec.read_text().replace("sensor: " + _unit_of(files / "inc.csv"), "sensor: " + _rig_unit(files))
    rec.write_text(text)
    out = tmp_path / "c.csv"
    rc, _, err = run_cli(["correct", str(model), str(rec), "--out", str(out)])
    assert rc == 0, err
    said = provenance.read_provenance(out)
    digest = hashlib.sha256(model.read_bytes()).hexdigest()[:16]
    assert said.sensor == _rig_unit(files) and said.corrections == 1
    assert f"model {model} (sha256 {digest})" in said.corrected_by
    assert io.read(out).corrected_by == said.corrected_by
    np.testing.assert_array_equal(io.read_table(out).column("temp"), io.read_table(rec).column("temp"))
    again = tmp_path / "c2.csv"
    rc, _, err = run_cli(["correct", str(model), str(out), "--out", str(again)])
    assert rc == 2 and "already corrected" in err and "--again" in err and not again.exists(), err
    rc, _, err = run_cli(["correct", str(model), str(out), "--out", str(again), "--again"])
    assert rc == 0 and provenance.read_provenance(again).corrections == 2, err


def _rig_unit(files: Path) -> str:
    return provenance.read_provenance(files / "rig.csv").sensor


def _unit_of(recording: Path) -> str:
    """A recording's ``sensor`` line (a simulated unit's: its IMU file, unit seed and content digest)."""
    return provenance.read_provenance(recording).sensor


def test_readings_a_model_corrected_already_are_neither_judged_nor_fitted_on(
    files: Path, tmp_path: Path
) -> None:
    """``sins correct`` refuses its own output (the model twice); ``evaluate`` had judged a model on it
    (the corrected readings shown as "raw", the model's figure a double correction) and ``fit`` had made
    a model of what the correction left, its unit that of the raw readings, so that it passed the unit
    check on them later. Both refuse it now, in one line saying why; the raw recording is taken."""
    model, rec = _copy(files, tmp_path, "m.json", "inc.csv")
    rec.write_text(rec.read_text().replace(_unit_of(rec), _rig_unit(files)))
    corrected = tmp_path / "c.csv"
    assert run_cli(["correct", str(model), str(rec), "--out", str(corrected)])[0] == 0
    truth, refit = str(files / "truth.csv"), str(tmp_path / "r.json")
    for argv, why in (
        (["evaluate", str(model), str(corrected), "--truth", truth], "judging a model on them applies"),
        (["fit", str(corrected), "--truth", truth, "--strategy", "regression", "--out", refit],
         "a model fitted on them is of what that correction left"),
    ):  # fmt: skip
        rc, _, err = run_cli(argv)
        assert rc == 2 and f"{corrected}: already corrected" in err and why in err, err
        assert_one_line(err, [corrected])
    assert not (tmp_path / "r.json").exists()
    assert run_cli(["evaluate", str(model), str(rec), "--truth", truth])[0] == 0


def test_a_correction_that_no_reader_would_read_back_is_not_written(files: Path, tmp_path: Path) -> None:
    # A model whose gyro bias is 1e11 rad/s (within a model file's bounds, 1e12) had written corrected
    # readings of -1e11 rad/s, which sins inspect then refused (beyond 1e4 rad/s): sins wrote a file it
    # does not read. The correction is refused now, nothing written.
    model, rec = _copy(files, tmp_path, "m.json", "inc.csv")
    rec.write_text(rec.read_text().replace(_unit_of(rec), _rig_unit(files)))
    doc = json.loads(model.read_text())
    doc["state"]["B0_"] = [1e11, 0.0, 0.0]
    model.write_text(json.dumps(doc))
    out = tmp_path / "c.csv"
    rc, _, err = run_cli(["correct", str(model), str(rec), "--out", str(out)])
    assert rc == 2 and "reach a rate of 1.0" in err and "beyond the 10000 rad/s" in err, err
    assert_one_line(err, [model])
    assert not out.exists()


def test_a_simulated_unit_is_told_by_its_content_not_its_files_name(tmp_path: Path) -> None:
    # A consumer unit in a file named tactical.toml read as "simulated tactical unit (unit seed 1)", as
    # the tactical preset's did, and a model of the one corrected the other (gyro x 1381 -> 1358 °/h).
    # The sensor line now holds the unit's content digest: another content under the same name is
    # another unit, and a copy elsewhere of the same file is the same.
    from sins.cli.common import simulated_unit

    for folder, grade in (("a", "tactical"), ("b", "tactical"), ("c", "consumer")):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "tactical.toml").write_text(to_toml({"grade": grade, "unit_seed": 1}))
    a, b, c = (simulated_unit(tmp_path / f / "tactical.toml") for f in "abc")
    assert a == b and a != c and a.startswith("simulated tactical unit (unit seed 1, content ")


def test_a_model_of_another_unit_is_refused_on_every_path(files: Path, tmp_path: Path) -> None:
    """The model was fitted on the rig's simulated unit (its file says which): the tactical unit
    simulated in ``inc.csv`` is another one, for ``correct`` and ``evaluate`` alike."""
    assert _rig_unit(files).startswith("simulated imu unit")
    out = tmp_path / "c.csv"
    rc, _, err = run_cli(["correct", str(files / "m.json"), str(files / "inc.csv"), "--out", str(out)])
    assert (
        rc == 2 and "the model was fitted on simulated imu unit" in err and "simulated tactical unit" in err
    )
    assert not out.exists()


BROAD_18 = data_root() / "broad_mocap" / "18_undisturbed_fast_translation_with_breaks_B.mat"


@pytest.mark.skipif(not BROAD_18.exists(), reason="BROAD not in the data root")
def test_a_rig_model_is_not_applied_to_a_dataset_of_another_unit(files: Path, tmp_path: Path) -> None:
    """Before, a model fitted on a simulated rig corrected ``--dataset broad_18`` without a word."""
    rc, _, err = run_cli(
        ["correct", str(files / "m.json"), "--dataset", "broad_18", "--out", str(tmp_path / "c.csv")]
    )
    assert rc == 2 and "BROAD IMU B" in err and "simulated imu unit" in err, err


def test_one_file_column_read_into_two_channels_is_refused(files: Path) -> None:
    rc, _, err = run_cli(["inspect", str(files / "static.csv"), "--columns", "gyro_x=gyro_y"])
    assert rc == 2 and "'gyro_y' would be read for both 'gyro_x' and 'gyro_y'" in err, err


# --------------------------------------------------------------------------- SIGTERM


def _as_at_a_terminal() -> None:
    """A child's signals at their defaults, as a terminal's command has them: a suite run in the
    background has SIGINT ignored, under nohup SIGHUP too, and sins keeps a signal its parent ignores
    (``nohup sins …`` must survive its terminal)."""
    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, signal.SIG_DFL)


CHILD = """
import sys, time
from pathlib import Path
import sins.cli.correct as correct

ready = Path(sys.argv[1])

def stall(bar):
    def progress(done, total):
        ready.write_text("writing")
        while True:  # until SIGTERM
            time.sleep(0.05)
    return progress

correct.row_progress = stall
from sins.cli import main
sys.exit(main(sys.argv[2:]))
"""


@pytest.mark.parametrize(("signum", "said"), [(signal.SIGTERM, "terminated"), (signal.SIGHUP, "hung up")])
def test_sigterm_while_writing_leaves_no_temporary_file(
    files: Path, tmp_path: Path, signum: int, said: str
) -> None:
    """Before, a killed ``sins correct`` left its 5 MB ``.tmp`` behind: SIGTERM now ends the command
    as Ctrl-C does, every ``finally`` run (exit 143, one line); SIGHUP (a closed terminal) alike, where
    it had left the temporary file and said nothing (exit 129)."""
    model, rec = _copy(files, tmp_path, "m.json", "inc.csv")
    rec.write_text(rec.read_text().replace(_unit_of(rec), _rig_unit(files)))
    out, ready = tmp_path / "out" / "c.csv", tmp_path / "ready"
    out.parent.mkdir()
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(ready), "correct", str(model), str(rec), "--out", str(out)],
        stderr=subprocess.PIPE, text=True, preexec_fn=_as_at_a_terminal,
    )  # fmt: skip
    try:
        wait_for(lambda: ready.exists() or child.poll() is not None, child.pid, "the child's write")
        assert child.poll() is None, child.communicate()[1]
        assert [p.name for p in out.parent.iterdir() if p.name.endswith(".tmp")]  # mid-write
        child.send_signal(signum)
        _, err = communicate(child)
    finally:
        if child.poll() is None:
            child.kill()
    assert child.returncode == 128 + signum and err.strip().endswith(f"sins: {said}"), err
    assert list(out.parent.iterdir()) == []


SWALLOWING_CHILD = """
import os, signal, sys, time
import sins.cli.correct as correct
import sins.core.deferred as deferred

how = sys.argv[1]

def swallow(bar):  # a library's callback that swallows the Ctrl-C raised in it (numba's cache notice)
    def progress(done, total):
        if how in ("go on", "fail", "bad input"):
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(1.0)
            except KeyboardInterrupt:
                pass
            if how == "fail":
                raise RuntimeError("no compiled object yet")
            if how == "bad input":  # a reader turning any library error into one of bad input
                from sins.errors import SinsInputError
                raise SinsInputError("failed for want of it")
    return progress

rename = deferred._rename

def late(pending):  # a Ctrl-C while the outputs land
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(0.2)
    rename(pending)

correct.row_progress = swallow
deferred._rename = late if how == "landing" else rename
from sins.cli import main
sys.exit(main(sys.argv[2:], process=True))  # the console script's command
"""


@pytest.mark.parametrize("how", ["go on", "fail", "bad input", "landing"])
def test_a_swallowed_interrupt_still_ends_the_command(files: Path, tmp_path: Path, how: str) -> None:
    """A Ctrl-C while numba's compilation cache called back into Python was swallowed there: the command
    went on and wrote its outputs (exit 0), or numba failed after it with a traceback (exit 1). A signal
    seen now ends the command as interrupted (130, one line, nothing written), however it was swallowed;
    one that comes while the outputs land, after the work, is too late to undo them and is held off."""
    model, rec = _copy(files, tmp_path, "m.json", "inc.csv")
    rec.write_text(rec.read_text().replace(_unit_of(rec), _rig_unit(files)))
    out = tmp_path / "out" / "c.csv"
    out.parent.mkdir()
    child = subprocess.run(
        [sys.executable, "-c", SWALLOWING_CHILD, how, "correct", str(model), str(rec), "--out", str(out)],
        capture_output=True, text=True, timeout=120, preexec_fn=_as_at_a_terminal,
    )  # fmt: skip
    assert "Traceback" not in child.stderr, child.stderr
    if how == "landing":
        assert child.returncode == 0 and out.exists(), child.stderr
        assert "interrupted" not in child.stderr
    else:
        assert child.returncode == 130 and "sins: interrupted" in child.stderr, child.stderr
        assert list(out.parent.iterdir()) == []


# --------------------------------------------------------------------------- bags and messages


def _still_bag(
    path: Path, *, pose_topics: tuple[str, ...] = ("/pose",), zero_quaternion_at: int | None = None,
    nan_reading_at: int | None = None, seconds: float = 60.0, poses_end_s: float | None = None,
    quaternion: np.ndarray | None = None, poses_start_s: float = 0.0,
) -> Path:  # fmt: skip
    """A ROS 1 bag of a unit at rest heading east at 45° N (FLU: Earth's rate and gravity with white
    noise), with its own constant pose on each topic of ``pose_topics`` at 20 Hz (from ``poses_start_s``
    until ``poses_end_s``)."""
    from rosbags.rosbag1 import Writer
    from test_readers import T0_NS, _imu_msg, _pose_msg, _typestore

    ts = _typestore(True)
    rng = np.random.default_rng(5)
    n = int(seconds * 100)
    lat = np.radians(45.0)
    w_enu = 7.292115e-5 * np.array([0.0, np.cos(lat), np.sin(lat)])  # the body's FLU is ENU here
    w = w_enu + 3e-4 * rng.standard_normal((n, 3)) + np.radians(5.0 / 3600.0)
    f = np.array([0.0, 0.0, 9.8061992]) + 0.01 * rng.standard_normal((n, 3)) + 1e-3
    if nan_reading_at is not None:
        w[nan_reading_at, 1] = np.nan
    with Writer(path) as writer:
        imu = writer.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=ts)
        poses = [writer.add_connection(t, "geometry_msgs/msg/PoseStamped", typestore=ts) for t in pose_topics]
        for k in range(n):
            ns = T0_NS + 10_000_000 * k
            writer.write(imu, ns, ts.serialize_ros1(_imu_msg(ts, ns, w[k], f[k], k), "sensor_msgs/msg/Imu"))
            if k % 5 == 0 and k / 100 >= poses_start_s and (poses_end_s is None or k / 100 <= poses_end_s):
                q = np.zeros(4) if k // 5 == zero_quaternion_at else np.array([0.0, 0.0, 0.0, 1.0])
                if quaternion is not None and k // 5 == 3:
                    q = quaternion
                msg = _pose_msg(ts, "pose", ns, np.zeros(3), q)
                for c in poses:
                    writer.write(c, ns, ts.serialize_ros1(msg, "geometry_msgs/msg/PoseStamped"))
    return path


def test_a_still_bag_with_its_own_poses_is_fitted_for_its_biases_alone(tmp_path: Path) -> None:
    """Before, ``sins fit`` on a still bag wrote scale factors of 1e10 ppm, exit 0. The biases the bag
    was written with (5 °/h on each gyro, 1 mm/s² on each accelerometer, FLU turned into FRD) come back
    within 4 standard errors; everything else is held at zero."""
    bag = _still_bag(tmp_path / "still.bag")
    out, doc = tmp_path / "m.json", tmp_path / "f.json"
    # The bag was written at 45° N; without a fix in it, the place is given.
    argv = ["fit", str(bag), "--origin", "45,0,0", "--strategy", "regression", "--out", str(out)]
    rc, stdout, err = run_cli([*argv, "--json", str(doc)])
    assert rc == 0, err
    fit = json.loads(doc.read_text())
    kept = [c for c in fit["coefficients"] if c["se"] is not None]
    assert {(c["sensor"], c["term"]) for c in kept} == {("gyro", "bias"), ("accel", "bias")}
    frd = np.array([1.0, -1.0, -1.0])
    for c in kept:
        i = "xyz".index(c["axis"])
        truth = 5.0 * frd[i] if c["sensor"] == "gyro" else 1e-3 / 9.80665e-6 * frd[i]
        assert abs(c["value"] - truth) < 4.0 * c["se"], (c, truth)
    assert "held at zero" in stdout


def test_bag_messages_name_the_topic_and_the_option(tmp_path: Path) -> None:
    """A zero quaternion: before, numpy's warnings then "came out nan" naming no topic. Two pose topics:
    before, "give it with --truth" (no word of --truth-topic). A NaN reading: before,
    "np.float64(nan) is not finite". An empty ``.bag``: before, read as a CSV."""
    zero = _still_bag(tmp_path / "zero.bag", zero_quaternion_at=7, seconds=5.0)
    rc, _, err = run_cli(["integrate", str(zero)])
    assert rc == 2 and "topic /pose: message 8: orientation" in err and "norm 0" in err, err
    # Found by the long fuzz run: a quaternion of 1e200 made numpy warn of an overflow (a second line).
    huge = _still_bag(tmp_path / "huge.bag", quaternion=np.array([1e200, 0.0, 0.0, 1.0]), seconds=5.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rc, _, err = run_cli(["integrate", str(huge)])
    assert rc == 2 and "message 4: orientation (x, y, z, w) has norm inf" in err, err
    assert [str(w.message) for w in caught] == []
    two = _still_bag(tmp_path / "two.bag", pose_topics=("/a", "/b"), seconds=25.0)
    for argv in (
        ["integrate", str(two)],
        ["fit", str(two), "--strategy", "regression", "--out", str(tmp_path / "m")],
    ):
        rc, _, err = run_cli(argv)
        assert rc == 2 and "2 pose topics (/a, /b)" in err and "--truth-topic TOPIC" in err, err
    nan = _still_bag(tmp_path / "nan.bag", nan_reading_at=12, seconds=5.0)
    rc, _, err = run_cli(["inspect", str(nan)])
    assert rc == 2 and "message 13: angular_velocity.y nan is not finite" in err, err
    (tmp_path / "empty.bag").write_bytes(b"")
    rc, _, err = run_cli(["inspect", str(tmp_path / "empty.bag")])
    assert rc == 2 and "named as a ROS 1 bag, but it is empty" in err, err


def test_readings_before_the_recordings_own_reference_begins_are_left_out_with_a_note(
    tmp_path: Path,
) -> None:
    """A motion capture starts seconds after the IMU (BROAD's does, 4 s): against the recording's own
    reference the readings before it are left out, said so, and the run starts at the reference's first
    pose (3 s) and ends at its last (19.95 s, the readings' last 0.04 s cut as a short tail)."""
    late = _still_bag(tmp_path / "late.bag", seconds=20.0, poses_start_s=3.0)
    out = tmp_path / "late.json"
    rc, _, err = run_cli(["integrate", str(late), "--json", str(out)])
    assert rc == 0 and "the first 300 intervals come before its own reference begins at 3 s" in err, err
    assert json.loads(out.read_text())["duration_s"] == pytest.approx(19.95 - 3.0, abs=1e-9)


def test_a_recording_is_characterised_against_its_own_reference_over_that_references_span(
    tmp_path: Path,
) -> None:
    """A bag whose poses start 2 s after its readings and end 3 s before them: ``sins characterise``
    takes the readings within the poses' span (2 s to 27 s at 100 Hz: 2,501 rows), where it took every
    reading and failed outside the span."""
    bag = _still_bag(tmp_path / "span.bag", seconds=30.0, poses_start_s=2.0, poses_end_s=27.0)
    out = tmp_path / "span.json"
    rc, _, err = run_cli(["characterise", str(bag), "--json", str(out)])
    assert rc == 0, err
    assert json.loads(out.read_text())["rows"] == 2501


def test_a_parquet_solution_reads_back_as_a_truth(files: Path, tmp_path: Path) -> None:
    """The formats guide says a solution reads back as a truth file; before, a Parquet one did not. The
    integration against the solution it wrote is exact (every error zero)."""
    sol = tmp_path / "sol.parquet"
    rc, _, err = run_cli(
        ["integrate", str(files / "inc.csv"), "--truth", str(files / "truth.csv"), "--out", str(sol)]
    )
    assert rc == 0, err
    rc, _, err = run_cli(
        ["integrate", str(files / "inc.csv"), "--truth", str(sol), "--json", str(tmp_path / "j.json")]
    )
    assert rc == 0, err
    summary = json.loads((tmp_path / "j.json").read_text())
    assert summary["max_horizontal_m"] < 1e-6 and abs(summary["final_yaw_deg"]) < 1e-9


def test_the_help_and_the_behaviour_agree_on_a_reference_ending_early(tmp_path: Path) -> None:
    """``--within-truth``'s help says what happens past a truth file's end (refused) and past the
    recording's own reference (a short tail cut with a note, a longer one refused), and so it is: a
    bag whose poses end 0.5 s before its readings is cut; one whose poses end after a third, refused."""
    from sins.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    text = " ".join(sub.choices["integrate"].format_help().split())
    assert "a tail of up to 1 s or 1 % of the recording is cut with a note, a longer one refused" in text
    tail = _still_bag(tmp_path / "tail.bag", seconds=20.0, poses_end_s=19.4)
    rc, _, err = run_cli(["integrate", str(tail)])
    assert rc == 0 and "where its own reference ends" in err, err
    short = _still_bag(tmp_path / "short.bag", seconds=20.0, poses_end_s=7.0)
    rc, _, err = run_cli(["integrate", str(short)])
    assert rc == 2 and "--within-truth" in err, err
    rc, _, err = run_cli(["integrate", str(short), "--within-truth"])
    assert rc == 0, err


def test_a_session_of_turns_known_by_their_angles_fits_regression(tmp_path: Path) -> None:
    """The Ferraris session's turns give only their angles: before, ``sins fit --strategy regression``
    said "fit with g_sensitivity=False", an option no command has; now the g-sensitivity is left out,
    said so, and the fit written."""
    from conftest import dataset_folder

    if not (dataset_folder("imucal_ferraris")).exists():
        pytest.skip("the Ferraris session is not in the data root")
    rc, out, err = run_cli(
        ["fit", "--dataset", "ferraris", "--strategy", "regression", "--out", str(tmp_path / "m.json")]
    )
    assert rc == 0 and "cannot tell the g-sensitivity: left out" in out, err


def test_a_huge_quaternion_in_an_npz_is_one_line_without_numpy_warnings(tmp_path: Path) -> None:
    """Found by the long fuzz run: a ``q_wxyz`` row of 1e300 made numpy warn of an overflow (a line on
    the user's terminal) before the reader's refusal."""
    from test_npz import _write

    q = np.tile([1.0, 0.0, 0.0, 0.0], (400, 1))
    q[9] = [1e300, 0.0, 0.0, 0.0]
    _write(tmp_path / "r.npz", q_wxyz=q)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rc, _, err = run_cli(["inspect", str(tmp_path / "r.npz")])
    assert rc == 2 and "q_wxyz: row 10 has norm inf" in err and err.count("\n") == 1, err
    assert [str(w.message) for w in caught] == []


def test_a_recording_the_system_will_not_let_sins_read_is_said_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A file sins may not read (mode 000 for a user who is not root) is refused as such, not taken for a
    damaged one: before, the format sniffers swallowed the error and an ``.npz`` read as "its first bytes
    are not a zip archive's". The refusal is the system's own, so it is planted here as the system
    gives it (root reads a file of mode 000 anyway)."""
    path = tmp_path / "r.npz"
    np.savez(path, t_s=np.arange(3.0))
    real_open = os.open

    def refusing(file: object, *args: object, **kwargs: object) -> int:
        if Path(str(file)) == path:
            raise PermissionError(13, "Permission denied", str(file))
        return real_open(file, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(os, "open", refusing)
    with pytest.raises(SinsInputError) as info:
        io.read(path)
    assert str(info.value) == f"{path}: cannot read: Permission denied", info.value


def test_the_disk_check_counts_what_an_output_takes_where_it_lands(tmp_path: Path) -> None:
    """``/dev/null`` takes no room (before, a run was refused by /dev's free space: "/dev/null would need
    up to 180 GB, /dev has 12.6 GB free"); a link is counted where its target lies."""
    from sins.io.limits import check_disk

    check_disk({Path("/dev/null"): 1e18}, "s.toml")
    far = tmp_path / "far"
    far.mkdir()
    link = tmp_path / "out.csv"
    link.symlink_to(far / "out.csv")
    with pytest.raises(SinsInputError, match=f"{far} has .* free"):
        check_disk({link: 1e18}, "s.toml")


def test_a_commands_own_stream_is_not_an_output(tmp_path: Path) -> None:
    """``--json /dev/stdout`` with the output redirected to a file had replaced that file with the JSON
    (the printed table, written to the replaced file, lost), and into a pipe it failed "cannot write in
    /proc/N/fd". Refused in one line, nothing written; a terminal is a character device, written in place."""
    log = tmp_path / "log.txt"
    with open(log, "w") as out:
        done = subprocess.run(
            [sys.executable, "-c", "import sins.cli; sins.cli.console()", "run", "static", "--json",
             "/dev/stdout"], stdout=out, stderr=subprocess.STDOUT, timeout=600, check=False,
        )  # fmt: skip
    text = log.read_text()
    assert done.returncode == 2 and "--json /dev/stdout: is this command's own stream" in text, text
    assert text.count("\n") == 1 and not list(tmp_path.glob(".*tmp"))
    with pytest.raises(SinsInputError, match="own stream"), open(log, "w") as out:
        os.dup2(out.fileno(), 1000)
        try:
            with atomic_path("/proc/self/fd/1000"):
                pass
        finally:
            os.close(1000)


def test_a_rename_that_fails_at_the_end_leaves_every_output_as_it_was(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The outputs' renames come last (:mod:`sins.core.deferred`); where one of them fails, those renamed
    before it are put back and no temporary file is left. Before, a folder made at the second output's
    name while the command ran left the first output replaced and the second's temporary file behind
    (``sins simulate --imu a.csv --truth b.csv``: "b.csv: Is a directory", a.csv new)."""
    from sins.core import deferred
    from sins.io.atomic import atomic_text

    a, b, c = tmp_path / "a.csv", tmp_path / "b.csv", tmp_path / "c.csv"
    a.write_text("old a\n")
    discarded: list[Path] = []
    with pytest.raises(IsADirectoryError, match=r"b\.csv"), deferred.all_or_nothing(discarded):
        for path in (a, b):
            with atomic_text(path) as fh:
                fh.write("new\n")
        b.mkdir()  # made by someone else after the write, before the renames
    assert a.read_text() == "old a\n" and discarded == [a, b]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.csv"]
    # A rename that fails after one has landed (the one check above cannot see it: a disk gone, say):
    # the first put back, a new third one removed, the kept copies gone.
    b.rmdir()
    b.write_text("old b\n")
    real = os.replace

    def failing(src: Any, dst: Any) -> None:
        if Path(dst) == b and Path(src).name.startswith(".b.csv."):
            raise PermissionError(13, "Permission denied")
        real(src, dst)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(PermissionError, match=r"b\.csv"), deferred.all_or_nothing():
        for path in (a, c, b):
            with atomic_text(path) as fh:
                fh.write("new\n")
    monkeypatch.setattr(os, "replace", real)
    assert a.read_text() == "old a\n" and b.read_text() == "old b\n" and not c.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.csv"]
    # All land where all can: the kept second names are removed.
    with deferred.all_or_nothing():
        for path in (a, c, b):
            with atomic_text(path) as fh:
                fh.write("new\n")
    assert [p.read_text() for p in (a, b, c)] == ["new\n"] * 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.csv", "c.csv"]


def test_a_command_stopped_before_it_wrote_an_output_names_that_one_among_those_kept(tmp_path: Path) -> None:
    """An interrupt while the second of two outputs was being written: both are kept as they were, and
    the message named the first alone ("none of its outputs written (a.csv: not replaced)"); the outputs
    the command declared before its work (:func:`sins.io.paths.check_outputs`) that exist are named too,
    a new one that was never begun is not (it replaces nothing)."""
    from sins.core import deferred
    from sins.io.atomic import atomic_text
    from sins.io.paths import check_outputs

    a, b, c = tmp_path / "a.csv", tmp_path / "b.csv", tmp_path / "c.json"
    a.write_text("old a\n")
    b.write_text("old b\n")
    discarded: list[Path] = []
    with pytest.raises(KeyboardInterrupt), deferred.all_or_nothing(discarded):
        check_outputs({"--imu": a, "--truth": b, "--json": c})
        with atomic_text(a) as fh:
            fh.write("new\n")
        with atomic_text(b) as fh:
            fh.write("half")
            raise KeyboardInterrupt
    assert discarded == [a, b] and a.read_text() == "old a\n" and b.read_text() == "old b\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.csv"]
