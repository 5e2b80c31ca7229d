"""The scenario reference (``docs/guide/scenarios.md``, "Every key") against the validator: every key it
accepts is listed, nothing else is, each numeric key with its bound's unit, and each constant default
as the validator applies it.

The keys are read from the validator at work: :class:`sins.scenario.toml.TomlKeys`'s accessors are
recorded while documents that take every branch (each segment type and its alternatives, waypoints, a
truth file, oscillations, every alignment method) are validated. The accessor calls written in
``sins/scenario/validate.py`` are counted too, so a key added there without a document that reaches it
still fails here until the reference lists it."""

from __future__ import annotations

import ast
import inspect
import re
from pathlib import Path
from typing import Any

import pytest

from sins.runs import pipeline
from sins.scenario import toml as toml_module
from sins.scenario import validate

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "guide" / "scenarios.md"
ACCESSORS = ("number", "bounded", "integer", "string", "choice", "numbers", "bounded_numbers", "strings",
             "boolean")  # fmt: skip
TABLE_ARRAYS = ("segment", "oscillation", "waypoint", "outage")

BASE = {"initial": {"lat_deg": 45.0}, "segment": [{"type": "hold", "duration_s": 1.0}]}
SEGMENTS = [
    {"type": "hold", "duration_s": 2.0},
    {"type": "accelerate", "duration_s": 2.0, "to_speed_mps": 5.0, "ramp_s": 0.5},
    {"type": "accelerate", "duration_s": 2.0, "delta_speed_mps": 1.0},
    {"type": "turn", "duration_s": 2.0, "rate_dps": 3.0, "coordinated": True},
    {"type": "turn", "duration_s": 2.0, "angle_deg": 3.0},
    {"type": "climb", "duration_s": 2.0, "angle_deg": 3.0},
    {"type": "attitude", "duration_s": 2.0, "roll_deg": 3.0},
]
DOCUMENTS: list[dict[str, Any]] = [
    {"name": "a", "description": "every segment", "imu": {"rate_hz": 50, "seed": 1, "model": "tactical",
     "times_s": [0, 5], "temps_degc": [10, 20]}, "compensation": {"rig": "24pos_ratetable"},
     "navigation": {"vertical": "damp"}, "initial": {"lat_deg": 45.0, "speed_mps": 1.0}, "segment": SEGMENTS,
     "oscillation": [{"channel": "roll", "amplitude_deg": 1.0, "period_s": 5.0},
                     {"channel": "heave", "amplitude_m": 1.0, "period_s": 5.0}]},
    {"initial": {"lat_deg": 45.0}, "waypoint": [{"north_m": 100.0, "speed_mps": 5.0},
                                                {"east_m": 100.0, "speed_mps": 5.0}]},
    {"truth": {"file": "truth.csv"}},
    {**BASE, "gnss": {"sigma_vel_mps": 0.1, "filter_grade": "tactical"},
     "outage": [{"start_s": 0.1, "end_s": 0.5}]},
    {**BASE, "gnss": {"sigma_m": 2.0}, "alignment": {"method": "static", "heading_sigma_deg": 1.0}},
    {**BASE, "gnss": {}, "alignment": {"method": "gnss_velocity"}},
    {**BASE, "gnss": {}, "alignment": {"method": "truth"}},
    {**BASE, "gnss": {}, "alignment": {"method": "auto"}},
]  # fmt: skip

_MISSING = inspect.signature(toml_module.TomlKeys.bounded).parameters["default"].default


def _place(where: str, key: str) -> str:
    """``segment[2]`` + ``ramp_s`` -> ``[[segment]] ramp_s``; ``imu`` + ``rate_hz`` -> ``[imu] rate_hz``."""
    table = re.sub(r"\[\d+\]$", "", where)
    if not table:
        return key
    return f"[[{table}]] {key}" if table in TABLE_ARRAYS else f"[{table}] {key}"


def _read_keys(monkeypatch: pytest.MonkeyPatch) -> dict[str, list[Any]]:
    """Every key the validator reads from :data:`DOCUMENTS` and every default it passes for it."""
    seen: dict[str, list[Any]] = {}
    for name in ACCESSORS:
        original = getattr(toml_module.TomlKeys, name)
        signature = inspect.signature(original)

        def recording(
            self: Any, *args: Any, _original: Any = original, _sig: Any = signature, **kw: Any
        ) -> Any:
            bound = _sig.bind(self, *args, **kw)
            bound.apply_defaults()
            default = bound.arguments.get("default", _MISSING)
            seen.setdefault(_place(self.where, bound.arguments["key"]), []).append(default)
            return _original(self, *args, **kw)

        monkeypatch.setattr(toml_module.TomlKeys, name, recording)
    return seen


def _validate_all(tmp_path: Path) -> None:
    (tmp_path / "truth.csv").write_text(
        "t,lat,lon,alt,vn,ve,vd,roll,pitch,yaw\n" + "".join(f"{k},45,7,0,0,0,0,0,0,0\n" for k in range(5))
    )
    for doc in DOCUMENTS:
        validate.from_dict(doc, source=tmp_path / "s.toml")
    for name in pipeline.presets():  # the shipped presets take the same paths
        validate.load(pipeline.resolve_scenario(name))


def _reference() -> dict[str, tuple[str, str]]:
    """``{key: (unit, default)}`` from the guide's "Every key" table."""
    text = GUIDE.read_text(encoding="utf-8")
    section = text[text.index("## Every key") :]
    section = section[: section.index("\n## ", 1)]
    rows = {}
    for line in section.splitlines():
        match = re.match(r"\|\s*`([^`]+)`\s*\|([^|]*)\|([^|]*)\|([^|]*)\|\s*$", line)
        if match:
            key, unit, default, what = (g.strip() for g in match.groups())
            assert what, f"{key}: says nothing"
            rows[key] = (unit, default)
    return rows


def _written_keys() -> set[str]:
    """The keys named by accessor calls in validate.py's source (a string literal as the key)."""
    tree = ast.parse((ROOT / "sins" / "scenario" / "validate.py").read_text(encoding="utf-8"))
    keys = set()
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr in ACCESSORS
        ):
            if node.args and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
                keys.add(node.args[0].value)
    return keys


def _format(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_format(v) for v in value) + "]"
    return f"{value:g}"


def _check_keys(seen: dict[str, list[Any]], reference: dict[str, tuple[str, str]]) -> None:
    assert sorted(set(seen) - set(reference)) == [], "accepted but not in the reference"
    assert sorted(set(reference) - set(seen)) == [], "in the reference but never read by the validator"
    leaf = {k.split()[-1] for k in reference}
    assert sorted(_written_keys() - leaf) == [], "read in validate.py but not in the reference"


def _check_units_and_defaults(seen: dict[str, list[Any]], reference: dict[str, tuple[str, str]]) -> None:
    checked = 0
    for key, defaults in seen.items():
        unit, documented = reference[key]
        place = key.replace("[[", "").replace("]]", ".").replace("[", "").replace("] ", ".")
        bound = validate.SCENARIO_BOUNDS.get(place)
        if bound is not None:
            assert unit == bound.unit, f"{key}: unit {unit!r}, the validator's {bound.unit!r}"
        given = [d for d in defaults if d is not _MISSING]
        if given and all(d == given[0] for d in given):  # a constant default: stated as applied
            assert _format(given[0]) in documented, (
                f"{key}: default {_format(given[0])} not in {documented!r}"
            )
            checked += 1
        else:  # required, or computed from other keys: the reference says which in words
            assert documented, key
    assert checked >= 30  # most keys have a constant default; the check must not pass by matching none


@pytest.fixture
def keys(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, list[Any]]:
    """The keys the validator read, and the defaults it passed for them."""
    seen = _read_keys(monkeypatch)
    _validate_all(tmp_path)
    return seen


def test_every_key_the_validator_accepts_is_in_the_reference(keys: dict[str, list[Any]]) -> None:
    _check_keys(keys, _reference())


def test_the_reference_gives_each_keys_unit_and_default(keys: dict[str, list[Any]]) -> None:
    _check_units_and_defaults(keys, _reference())


@pytest.mark.parametrize(
    "drift",
    ["a row left out", "a row the validator does not read", "another default", "another unit"],
)
def test_a_reference_that_drifts_from_the_validator_fails(keys: dict[str, list[Any]], drift: str) -> None:
    reference = _reference()
    if drift == "a row left out":
        del reference["[gnss] latency_s"]
    elif drift == "a row the validator does not read":
        reference["[gnss] elevation_mask_deg"] = ("°", "10")
    elif drift == "another default":
        reference["[gnss] markov_tau_s"] = ("s", "10")
    else:
        reference["[imu] rate_hz"] = ("kHz", "100")
    with pytest.raises(AssertionError):
        _check_keys(keys, reference)
        _check_units_and_defaults(keys, reference)
