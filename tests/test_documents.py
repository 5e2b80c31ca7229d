"""The one reader of every JSON and TOML file sins reads: whatever the bytes, a value or one line.

Issue 35's tracebacks, each through the command a user would run: arrays nested 3,000 deep in TOML and
100,000 deep in JSON (``RecursionError``), a 5,000-digit integer (``ValueError: Exceeds the limit``), a
NUL byte in a name. And a hypothesis property: any document, nested or not, is read or refused in one
line naming the file, and what sins writes is read back equal.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
from conftest import refusal
from hypothesis import given, settings
from hypothesis import strategies as st

from sins import compensation, scenario
from sins.cli import main
from sins.errors import SinsInputError
from sins.io import documents, write_json

DEEP_TOML = "a = " + "[" * 3000 + "]" * 3000 + "\n"
DEEP_JSON = "[" * 100_000 + "]" * 100_000
LONG_INT = "9" * 5000


def _one_line(capsys: pytest.CaptureFixture[str], *fragments: str) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("sins: error: ") and "Traceback" not in err, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    return err


@pytest.mark.parametrize(
    ("text", "fragment"),
    [(DEEP_TOML, "nested deeper than 64"), (f"a = {LONG_INT}\n", "4300 digits"),
     ("a = 99999999999999999999\n", "beyond 64 bits"), ('name = "a\\u0000b"\n', "NUL")],
    ids=["nested", "5000-digit", "beyond-64-bit", "nul"],
)  # fmt: skip
def test_a_hostile_toml_file_is_one_line_wherever_sins_reads_toml(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, fragment: str
) -> None:
    """Today's code: RecursionError and ValueError tracebacks from ``sins run``, ``sins campaign`` and
    ``sins check`` (scenario, campaign and suite files)."""
    path = tmp_path / "hostile.toml"
    path.write_text(text)
    for argv in (["run", str(path)], ["campaign", str(path), "--out", str(tmp_path / "o")],
                 ["check", str(path), "--baseline", str(tmp_path / "b.json")]):  # fmt: skip
        assert main(argv) == 2
        _one_line(capsys, str(path), fragment)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("text", "fragment"),
    [(DEEP_JSON, "nested deeper than 64"), (f'{{"format": "sins.compensation", "version": {LONG_INT}}}',
     "4300 digits"), ('{"format": "sins.compensation", "x\\u0000": 1}', "NUL")],
    ids=["nested", "5000-digit", "nul-key"],
)  # fmt: skip
def test_a_hostile_json_file_is_one_line_wherever_sins_reads_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, fragment: str
) -> None:
    """A model file (``sins evaluate``), a quality baseline and a campaign baseline (``sins check``):
    today each raised RecursionError or ValueError."""
    path = tmp_path / "hostile.json"
    path.write_text(text)
    suite = Path(__file__).resolve().parents[1] / "scenarios" / "suite" / "quality.toml"
    for argv in (["evaluate", str(path), str(tmp_path / "rec.csv")],
                 ["check", str(suite), "--baseline", str(path)],
                 ["check", "tactical_drives", "--baseline", str(path)]):  # fmt: skip
        assert main(argv) == 2
        _one_line(capsys, str(path), fragment)


def test_a_campaign_name_with_a_nul_byte_or_a_slash_is_refused(tmp_path: Path) -> None:
    """Today: ``ValueError: embedded null byte`` from the results folder the name makes."""
    for name, fragment in (("a\\u0000b", "NUL"), ("a/b", "cannot name a folder"), ("", "cannot name")):
        path = tmp_path / "c.toml"
        path.write_text(
            f'name = "{name}"\n[units]\nimu = "tactical"\ncount = 1\n[[scenario]]\nfile = "car_drive"\n'
        )
        refusal(lambda p=path: scenario_campaign(p), str(path), fragment)


def scenario_campaign(path: Path) -> Any:
    from sins import campaign

    return campaign.load(path)


def test_devices_folders_and_missing_files_are_refused_without_reading_them(tmp_path: Path) -> None:
    """``/dev/zero`` as a model file would be read forever; a folder or a missing file is named."""
    refusal(lambda: compensation.load("/dev/zero"), "/dev/zero", "not a regular file")
    refusal(lambda: compensation.load(tmp_path), str(tmp_path), "is a directory")
    refusal(lambda: scenario.load(tmp_path / "none.toml"), "none.toml", "no such scenario file")


# --------------------------------------------------------------------------- properties

_SCALARS = st.one_of(
    st.none(), st.booleans(), st.floats(allow_nan=False), st.text(max_size=8),
    st.integers(min_value=-(2**70), max_value=2**70),
)  # fmt: skip
_DOCS = st.recursive(
    _SCALARS,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=4),
    max_leaves=30,
)


def _depth(value: Any) -> int:
    if isinstance(value, dict):
        return 1 + max((_depth(v) for v in value.values()), default=0)
    if isinstance(value, list):
        return 1 + max((_depth(v) for v in value), default=0)
    return 0


def _fits(value: Any) -> bool:
    """What the reader takes: no integer beyond 64 bits, no NUL, not too deep."""
    if isinstance(value, dict):
        return all("\0" not in k and _fits(v) for k, v in value.items())
    if isinstance(value, list):
        return all(_fits(v) for v in value)
    if isinstance(value, str):
        return "\0" not in value
    if isinstance(value, int) and not isinstance(value, bool):
        return documents.INT_RANGE[0] <= value <= documents.INT_RANGE[1]
    return True


@settings(max_examples=150, deadline=None, derandomize=True, database=None)
@given(doc=_DOCS, wrap=st.integers(0, 80))
def test_any_json_document_is_read_back_equal_or_refused_in_one_line(
    tmp_path_factory: pytest.TempPathFactory, doc: Any, wrap: int
) -> None:
    """Nested ``wrap`` more levels: a document the reader takes (the oracle :func:`_fits`, depth at most
    64) comes back equal to what was written; any other is one ``SinsInputError`` line naming the file."""
    for _ in range(wrap):
        doc = [doc]
    path = tmp_path_factory.mktemp("doc") / "d.json"
    path.write_text(json.dumps(doc))
    if _fits(doc) and _depth(doc) <= documents.MAX_DEPTH:
        assert documents.read_json(path, "test file") == doc
    else:
        refusal(lambda: documents.read_json(path, "test file"), str(path))


@settings(max_examples=100, deadline=None, derandomize=True, database=None)
@given(depth=st.integers(1, 5000), digits=st.integers(1, 6000), nul=st.booleans())
def test_any_toml_nesting_or_integer_is_read_or_refused_in_one_line(
    tmp_path_factory: pytest.TempPathFactory, depth: int, digits: int, nul: bool
) -> None:
    path = tmp_path_factory.mktemp("doc") / "d.toml"
    text = "\\u0000" if nul else "x"
    path.write_text(f'a = {"[" * depth}1{"]" * depth}\nb = {"7" * digits}\nc = "{text}"\n')
    ok = depth < documents.MAX_DEPTH and int("7" * min(digits, 30)) <= documents.INT_RANGE[1] and not nul
    try:
        doc = documents.read_toml(path, "test")
    except SinsInputError as exc:
        assert not ok and "\n" not in str(exc) and str(path) in str(exc), str(exc)
    else:
        assert ok and doc["b"] == int("7" * digits)


def test_what_sins_writes_it_reads_back_nan_included(tmp_path: Path) -> None:
    doc = {"format": "x", "values": [1.0, math.nan, -0.0, 2**63 - 1], "nested": {"k": [[1, 2], {"z": None}]}}
    write_json(tmp_path / "d.json", doc)
    back = documents.read_json(tmp_path / "d.json", "test file")
    assert math.isnan(back["values"][1])
    back["values"][1] = doc["values"][1] = 0.0
    assert back == doc


def test_a_report_is_standard_json_a_figure_that_is_not_finite_null(tmp_path: Path) -> None:
    """A command's report is read by jq and JavaScript, whose JSON has no NaN: ``sins bias --dataset
    psins_lasergyro --json`` wrote ``"level_rate_ratio": NaN``. Every figure that is not finite, nested
    or numpy's, is null; the rest as given; a sins file (write_json) still keeps its NaN."""
    import numpy as np

    from sins.io import write_report

    doc = {"a": math.nan, "b": [1.5, math.inf, (-math.inf, 2)], "c": {"d": np.float64("nan"), "e": "NaN"}}
    write_report(tmp_path / "r.json", doc)
    text = (tmp_path / "r.json").read_text(encoding="utf-8")

    def refuse(constant: str) -> None:
        raise AssertionError(f"{constant} in a report")

    back = json.loads(text, parse_constant=refuse)  # what a strict reader takes
    assert back["a"] is None and back["b"] == [1.5, None, [None, 2]] and back["c"] == {"d": None, "e": "NaN"}


def test_a_key_given_twice_is_refused_and_a_byte_order_mark_read_past(tmp_path: Path) -> None:
    """Python's parser keeps the last of a key given twice and drops the first without a word (a model
    file edited by hand, with two ``"B0_"``); a byte-order mark an editor added made a model file "not
    JSON", where the CSV readers read past one."""
    from sins import imu
    from sins.imu import calibration
    from sins.imu import spec as imu_spec

    rig = calibration.RigProcedure(position_dwell_s=4.0, rate_table=calibration.RateTable(dwell_s=2.0))
    unit = imu_spec.draw_unit("tactical", 1, 101).only(*imu.BASELINE)
    path = tmp_path / "m.json"
    compensation.save(compensation.make("regression").fit(calibration.simulate_rig(rig, unit, seed=1)), path)
    text = path.read_text()
    twice = text.replace('"B0_": [', '"B0_": [0.0, 0.0, 0.0],\n    "B0_": [', 1)
    assert twice != text
    path.write_text(twice)
    refusal(lambda: compensation.load(path), str(path), "not a sins model file (the key 'B0_' twice in one")
    path.write_bytes(b"\xef\xbb\xbf" + text.encode())
    assert compensation.load(path).params() == compensation.make("regression").params()
