"""What ``sins fit`` says of a new recording that opens moving (sins.compensation.referenced.choose_rule's
``moving_held_back_deg``): the rule judged once more on each held-back recording from its first motion, as
such a recording arrives, beside its raw readings there; reported, and nothing corrected differently.
Judged on a unit made by numpy from EuRoC's real readings (``tools/euroc_units.py``, skipped without the
data) and against its held-back figures computed here by hand."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import dataset_folder
from scipy.spatial.transform import Rotation

from sins.cli import main
from sins.compensation import unit_bias

EUROC = dataset_folder("euroc")
needs_euroc = pytest.mark.skipif(not (EUROC / "V1_01_easy.npz").is_file(), reason=f"no EuRoC data in {EUROC}")


def test_the_figures_are_kept_in_the_rules_file() -> None:
    """``moving_held_back_deg`` round-trips; a file written before it reads without it; a value of
    another kind is refused in one line."""
    rule = unit_bias.BiasRule(mode="rest", moving_held_back_deg={"rule": [10.3, 2.0], "raw": [9.8, 5.0]})
    back = unit_bias.BiasRule.from_dict(json.loads(json.dumps(rule.to_dict())))
    assert back.moving_held_back_deg == rule.moving_held_back_deg
    old = {k: v for k, v in rule.to_dict().items() if k != "moving_held_back_deg"}
    assert unit_bias.BiasRule.from_dict(old).moving_held_back_deg == {}
    with pytest.raises(ValueError, match="bias rule moving_held_back_deg: expected an object of lists"):
        unit_bias.BiasRule.from_dict({**rule.to_dict(), "moving_held_back_deg": {"rule": 1.0}})


def test_the_advice_to_open_at_rest_is_given_where_the_rule_reads_a_rest() -> None:
    """The line names every held-back recording left worse from its first motion; it advises an opening
    rest only under a rule that reads one (``rest``, ``nearest`` and their ``+online``), not under
    ``online`` or ``pooled``, which a rest would not change."""
    from sins.compensation import fitting

    moving = {"rule": [2.0, 1.0, 4.5], "raw": [1.5, 3.0, 4.0]}
    lines = {
        mode: fitting._rule_lines(
            unit_bias.BiasRule(mode=mode, moving_held_back_deg=moving), ["a", "b", "c"], ""
        )
        for mode in unit_bias.MODES
    }
    for mode, said in lines.items():
        assert len(said) == 2 and "a 2.00° against 1.50°, c 4.50° against 4.00°" in said[1], said
        assert "leaves 2.50° against the raw readings' 2.83°" in said[1], said
        assert ("has its bias read there" in said[1]) == mode.startswith(("rest", "nearest")), (mode, said)
    calm = fitting._rule_lines(
        unit_bias.BiasRule(mode="rest", moving_held_back_deg={"rule": [1.0], "raw": [2.0]}), ["a"], ""
    )
    assert calm[1].endswith("rest leaves 1.00° against the raw readings' 2.00°, worse than raw on none")


def _raw_from_first_motion(path: Path) -> float:
    """The AOE (deg) of a recording's raw gyro from the end of its opening rest (the rest as sins finds
    it), integrated with scipy's ``Rotation`` alone: each step the mean of its two readings, from the
    reference's attitude at the first epoch on or after the cut, RMS over every epoch from there."""
    with np.load(path) as z:
        t, gyro, accel, q = (
            z["t_s"],
            z["gyro_rad_s"].astype(float),
            z["accel_m_s2"].astype(float),
            z["q_wxyz"],
        )
    mid = 0.5 * (gyro[:-1] + gyro[1:]), 0.5 * (accel[:-1] + accel[1:])
    cut = unit_bias.opening_rest(mid[0], mid[1], float(np.median(np.diff(t))))
    ref = Rotation.from_quat(q[cut:].astype(float), scalar_first=True)
    steps = Rotation.from_rotvec(mid[0][cut:] * np.diff(t[cut:])[:, None])
    est = [ref[0]]
    for step in steps:
        est.append(est[-1] * step)
    angles = (ref.inv() * Rotation.concatenate(est)).magnitude()
    return float(np.degrees(np.sqrt(np.mean(angles**2))))


@needs_euroc
def test_a_unit_fitted_on_recordings_that_open_at_rest_says_what_a_moving_opener_gets(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``tools/euroc_units.py``'s unit 2702 (EuRoC read calibrated, with a scale error, misalignment and a
    new bias per recording, by numpy alone): its three training recordings open with a rest, and held
    back whole they chose ``rest``, whose branch for a recording that opens moving (the online estimate
    from the pooled prior) none of them judged. From their first motion it leaves V1_01 worse than its
    readings (36.98° against 35.30°), and ``sins fit`` says so. Judged, MH_03, which opens moving, goes
    from 22.01° to 8.75° (under the pooled prior alone, as sins took it before: 22.95°), and V2_01, which
    opens with a rest, from 23.61° to 9.78°. The raw figure from the first motion is checked against
    scipy's ``Rotation`` integrating the readings."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
    from euroc_units import make_unit  # numpy and scipy alone

    make_unit(2702, "calib", EUROC, tmp_path / "u")
    monkeypatch.setenv("SINS_DATA", str(tmp_path))
    model, fit_json, out = tmp_path / "m.json", tmp_path / "fit.json", tmp_path / "e.json"
    train = ["V1_02_medium", "V1_01_easy", "MH_05_difficult"]
    sets = [a for n in train for a in ("--dataset", f"u/{n}")]
    assert main(["fit", *sets, "--strategy", "regression", "--out", str(model), "--json", str(fit_json)]) == 0
    said = capsys.readouterr().out
    rule = json.loads(fit_json.read_text())["bias_rule"]
    assert rule["mode"] == "rest"
    moving = rule["moving_held_back_deg"]
    assert len(moving["rule"]) == len(moving["raw"]) == 3
    assert moving["rule"][1] > moving["raw"][1] + 1.0  # V1_01, from its first motion
    # Whole, with its rest, every held-back recording was better than raw under the rule taken.
    whole = rule["held_back_each_deg"]
    assert all(v < r for v, r in zip(whole["rest"], whole["raw"], strict=True))
    assert moving["raw"][0] == pytest.approx(
        _raw_from_first_motion(tmp_path / "u" / "V1_02_medium.npz"), rel=1e-4
    )
    mean_rule, mean_raw = np.mean(moving["rule"]), np.mean(moving["raw"])
    line = next(x for x in said.splitlines() if x.startswith("a recording that opens moving"))
    assert f"rest leaves {mean_rule:.2f}° against the raw readings' {mean_raw:.2f}°" in line, line
    assert "u/V1_01_easy 36.98° against 35.30°" in line and "worse than raw on" in line, line
    assert "opens with a rest of 1 s or more has its bias read there" in line

    def judged(name: str) -> tuple[float, float]:
        assert main(["evaluate", str(model), "--dataset", f"u/{name}", "--json", str(out)]) == 0
        doc = json.loads(out.read_text())
        return doc["open_loop_attitude"]["aoe_deg"], doc["open_loop_attitude_raw"]["aoe_deg"]

    (moving_aoe, moving_raw), (rest_aoe, rest_raw) = judged("MH_03_medium"), judged("V2_01_easy")
    assert moving_aoe < 0.5 * moving_raw and rest_aoe < 0.5 * rest_raw
