"""Record what the effect vocabulary drives, and check later that a refactoring left it unchanged.

Usage::

    .venv/bin/python tools/check_vocab_outputs.py record DIR
    .venv/bin/python tools/check_vocab_outputs.py compare DIR

It keeps a SHA-256 of the recordings ``sins calibrate`` writes for several IMU models (the grade presets,
the nonlinear tactical unit, and a unit with every effect of the library) on both rigs, ``sins effects``
(the listing), and ``sins gap --json`` of a few rigs (simulated recordings with and without the effects
beyond the baseline, and the Ferraris recording when the data root has it). ``compare`` runs them again
and names every file that differs; for a gap report it says whether the verdicts (the effects found and
the diagnosis) are equal and the largest relative change of any figure.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

from sins.cli import main as sins_main

#: A unit with every effect of the library on both sensors, small enough for a rig to stay in range.
EVERY_EFFECT = """
grade = "tactical"
unit_seed = 3

[[effect]]
name = "gyro.scale_nonlinearity"
k2_ppm_per_dps = [20, -15, 25]
[[effect]]
name = "accel.scale_nonlinearity"
k2_ppm_per_g = [300, -200, 250]
[[effect]]
name = "gyro.scale_asymmetry"
ka_ppm = [300, -200, 100]
[[effect]]
name = "accel.scale_asymmetry"
ka_ppm = [200, 100, -300]
[[effect]]
name = "gyro.g2_sensitivity"
tensor_dph_per_g2 = [
  [[0.5, 0.1, 0.0], [0.1, -0.3, 0.0], [0.0, 0.0, 0.2]],
  [[-0.2, 0.0, 0.1], [0.0, 0.4, 0.0], [0.1, 0.0, -0.3]],
  [[0.3, 0.0, 0.0], [0.0, 0.2, 0.1], [0.0, 0.1, 0.5]],
]
[[effect]]
name = "gyro.temperature_bias"
c1_dph_per_degc = [0.5, -0.3, 0.2]
c2_dph_per_degc2 = [0.01, 0.0, -0.02]
[[effect]]
name = "accel.temperature_scale"
s1_ppm_per_degc = [10, -5, 8]
[[effect]]
name = "accel.size_effect"
lever_arms_mm = [[5, 0, 1], [0, 4, 0], [2, 0, 6]]
[[effect]]
name = "gyro.time_offset"
delay_ms = [1, 1, 1]
[[effect]]
name = "accel.quantization"
step_mg = [0.5, 0.5, 0.5]
[[effect]]
name = "gyro.quantization_noise"
q_arcsec = [0.5, 0.5, 0.5]
[[effect]]
name = "gyro.rate_random_walk"
rrw_dph_per_rt_h = [1, 1, 1]
[[effect]]
name = "accel.saturation"
limit_g = [8, 8, 8]
"""

IMUS = ("consumer", "tactical", "navigation", "tactical_nonlinear", "every")
RIGS = ("24pos_ratetable", "26pos_tilted")
GAPS = (("tactical_nonlinear", "24pos_ratetable"), ("every", "26pos_tilted"), ("tactical", "24pos_ratetable"))


def _sins(*args: str) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        code = sins_main(list(args))
    if code not in (0, None):
        raise SystemExit(f"sins {' '.join(args)}: exit {code}")
    return out.getvalue()


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _run(tmp: Path) -> dict[str, Any]:
    (tmp / "every.toml").write_text(EVERY_EFFECT)
    found: dict[str, Any] = {"effects": hashlib.sha256(_sins("effects").encode()).hexdigest()}
    for unit in IMUS:
        model = str(tmp / "every.toml") if unit == "every" else unit
        for rig in RIGS:
            out = tmp / f"{unit}_{rig}.csv"
            _sins("calibrate", rig, "--imu", model, "--out", str(out), "--seed", "1")
            found[f"calibrate/{unit}/{rig}"] = _digest(out)
            print(f"calibrate {unit} {rig}: {found[f'calibrate/{unit}/{rig}'][:12]}", file=sys.stderr)
    for unit, rig in GAPS:
        report = tmp / f"gap_{unit}_{rig}.json"
        _sins("gap", str(tmp / f"{unit}_{rig}.csv"), "--json", str(report))
        found[f"gap/{unit}/{rig}"] = json.loads(report.read_text())
        print(f"gap {unit} {rig}", file=sys.stderr)
    return found


def _verdicts(report: dict[str, Any]) -> Any:
    """What the diagnosis decided: the effects in their order, accepted or not and why, the diagnosis,
    what is unexplained or outside, where the gaps are (not the figures)."""
    decided = ("name", "accepted", "indistinguishable_from", "not_accepted_because")
    effects = [{k: e.get(k) for k in decided} for e in report.get("effects", [])]
    found = {k: report.get(k) for k in ("diagnosis", "unexplained", "outside", "withholding", "unfitted")}
    return {"effects": effects, "where": [w.get("channel") for w in report.get("where", [])], **found}


def _largest_change(a: Any, b: Any) -> float:
    if isinstance(a, dict) and isinstance(b, dict):
        return max([_largest_change(a[k], b[k]) for k in a if k in b] or [0.0])
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return max([_largest_change(x, y) for x, y in zip(a, b, strict=True)] or [0.0])
    if isinstance(a, float) and isinstance(b, float) and a != b:
        return abs(a - b) / max(abs(a), abs(b))
    return 0.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("record", "compare"))
    parser.add_argument("folder", type=Path)
    args = parser.parse_args()
    # One folder, the same on every run: the recordings' headers and the reports name their files.
    work = Path(tempfile.gettempdir()) / "sins_check_vocab_outputs"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir()
    try:
        found = _run(work)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    path = args.folder / "vocab_outputs.json"
    if args.action == "record":
        args.folder.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(found, indent=1, sort_keys=True))
        print(f"recorded {len(found)} outputs in {path}")
        return
    before = json.loads(path.read_text())
    differ = 0
    for key, value in before.items():
        if found.get(key) == value:
            print(f"equal     {key}")
            continue
        differ += 1
        if key.startswith("gap/"):
            same = _verdicts(value) == _verdicts(found[key])
            change = _largest_change(value, found[key])
            verdicts = "equal" if same else "DIFFER"
            print(f"DIFFERS   {key}: verdicts {verdicts}, largest relative change {change:.2e}")
        else:
            print(f"DIFFERS   {key}")
    print(f"{differ} of {len(before)} outputs differ")
    raise SystemExit(1 if differ else 0)


if __name__ == "__main__":
    main()
