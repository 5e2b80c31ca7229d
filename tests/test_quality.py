"""The compensation-quality gate `sins check`."""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from sins import compensation, quality
from sins.cli import main

SUITE = Path(__file__).resolve().parents[1] / "scenarios" / "suite"


def test_shipped_suite_holds_against_its_shipped_baseline(capsys: pytest.CaptureFixture[str]):
    assert main(["check", str(SUITE / "quality.toml"), "--baseline", str(SUITE / "baseline.json")]) == 0
    out = capsys.readouterr().out
    assert "metrics hold" in out
    cases = quality.read_baseline(SUITE / "baseline.json")
    assert set(cases) == {"linear", "nonlinear", "temperature"}
    for strategies in cases.values():
        assert {"none", "oracle", "regression", "mlp", "kohonen"} <= set(strategies)


@pytest.fixture
def small_suite(tmp_path: Path) -> Path:
    """The linear case alone, with regression only: quick to run twice."""
    for name in ("linear.toml", "imu_linear.toml", "rig.toml"):
        shutil.copy(SUITE / name, tmp_path / name)
    case = tmp_path / "linear.toml"
    case.write_text(
        case.read_text().replace(
            'strategies = ["regression", "mlp", "kohonen"]', 'strategies = ["regression"]'
        )
    )
    suite = tmp_path / "suite.toml"
    suite.write_text('[[case]]\nname = "linear"\nscenario = "linear.toml"\n')
    return suite


def test_a_degraded_strategy_fails_the_gate_and_is_named(
    small_suite: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
):
    baseline = small_suite.parent / "baseline.json"
    assert main(["check", str(small_suite), "--baseline", str(baseline), "--update-baseline"]) == 0
    assert main(["check", str(small_suite), "--baseline", str(baseline)]) == 0
    capsys.readouterr()

    original = compensation.Regression.correct
    original_increments = compensation.Regression.correct_increments

    def degraded(self, gyro, accel, temp=None):  # type: ignore[no-untyped-def]
        w, f = original(self, gyro, accel, temp)
        return w + 1e-4, f  # 20 °/h left in every gyro: +20 % over 30 °/h of noise per sample

    def degraded_increments(self, imu, temp=None):  # type: ignore[no-untyped-def]
        # The same 20 °/h on the increments, which regression corrects without the rate form.
        out = original_increments(self, imu, temp)
        return dataclasses.replace(out, dtheta_b=out.dtheta_b + 1e-4 * np.diff(imu.t)[:, None])

    monkeypatch.setattr(compensation.Regression, "correct", degraded)  # fmt: skip
    monkeypatch.setattr(compensation.Regression, "correct_increments", degraded_increments)  # fmt: skip
    assert main(["check", str(small_suite), "--baseline", str(baseline)]) == 1
    out = capsys.readouterr().out
    assert "linear/regression final_horizontal_m: regressed by +" in out
    assert "linear/regression residual_rms.gyro.x: regressed" in out
    regressions = out.split("regressed or went missing")[1]
    assert "linear/oracle" not in regressions and "linear/none" not in regressions  # only the degraded one


def test_missing_or_foreign_baselines_are_refused(small_suite: Path, capsys: pytest.CaptureFixture[str]):
    assert main(["check", str(small_suite), "--baseline", str(small_suite.parent / "none.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--update-baseline" in err
    foreign = small_suite.parent / "foreign.json"
    foreign.write_text('{"strategies": {}}')
    assert main(["check", str(small_suite), "--baseline", str(foreign)]) == 2
    assert "not a sins quality baseline" in capsys.readouterr().err


def test_comparison_rules():
    tol = {"horizontal": 0.10, "residual": 0.05}
    base = {"c": {"s": {"final_horizontal_m": 100.0, "residual_rms.gyro.x": 1e-4, "gone": 1.0}}}
    new = {"c": {"s": {"final_horizontal_m": 110.4, "residual_rms.gyro.x": 0.9e-4, "fresh": 2.0}}}
    verdicts = {c.metric: c.verdict for c in quality.compare(base, new, tol)}
    # 10 % of 100 m plus the 0.5 m floor is 10.5 m: 110.4 holds; 10 % better on the residual improves.
    assert verdicts == {"final_horizontal_m": "held", "residual_rms.gyro.x": "improved", "gone": "missing",
                        "fresh": "new"}  # fmt: skip
    new["c"]["s"]["final_horizontal_m"] = 110.6
    assert {c.metric: c.verdict for c in quality.compare(base, new, tol)}["final_horizontal_m"] == "regressed"
    # Below the floors nothing is judged: a millimetre drift that doubles is still held.
    tiny = quality.compare(
        {"c": {"s": {"max_horizontal_m": 0.001}}}, {"c": {"s": {"max_horizontal_m": 0.002}}}, tol
    )
    assert tiny[0].verdict == "held" and np.isclose(tiny[0].relative, 1.0)


def _no_runs(*args: object, **kwargs: object) -> None:
    raise AssertionError("a case ran before the inputs were checked")


@pytest.mark.parametrize(
    ("cases", "fragment"),
    [
        ({}, 'a "cases" table with at least one case'),
        ({"linear": {}}, "cases.linear: expected a table of strategies"),
        ({"linear": {"regression": {}}}, "cases.linear.regression: expected a table of metrics"),
        ({"linear": {"regression": {"max_horizontal_m": 1.0}}}, "has no final_horizontal_m"),
        ({"linear": {"regression": {"final_horizontal_m": None, "max_horizontal_m": 1.0}}}, "got None"),
        ({"linear": {"regression": {"final_horizontal_m": 1.0, "max_horizontal_m": 1.0, "colour": 1.0}}},
         "colour: not a metric"),
        ({"other": {"regression": {"final_horizontal_m": 1.0, "max_horizontal_m": 1.0}}}, "no such case"),
        ({"linear\nx": {"r": {"final_horizontal_m": 1.0, "max_horizontal_m": 1.0}}}, "cases.linear\\nx"),
    ],
    ids=["no-cases", "no-strategies", "no-metrics", "dropped-metric", "null", "unknown-metric",
         "unknown-case", "line-break-in-a-name"],
)  # fmt: skip
def test_a_baseline_that_tests_nothing_or_drops_a_metric_is_refused_before_the_runs(
    small_suite: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    cases: dict[str, object],
    fragment: str,
) -> None:
    """Today ``"cases": {}`` passed with "all 0 metrics hold"; now every way a baseline would test less
    than it says is one line, before any case runs."""
    baseline = small_suite.parent / "baseline.json"
    baseline.write_text(json.dumps({"format": quality.BASELINE_FORMAT, "cases": cases}))
    monkeypatch.setattr(quality, "measure", _no_runs)
    assert main(["check", str(small_suite), "--baseline", str(baseline)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(baseline) in err and fragment in err, err


def test_a_case_that_cannot_run_and_an_unwritable_baseline_are_refused_before_the_runs(
    small_suite: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """A second case without compensation failed only after the first had run; ``--update-baseline``
    into a missing folder only after all of them."""
    monkeypatch.setattr(quality, "measure", _no_runs)
    bare = small_suite.parent / "bare.toml"
    bare.write_text('name = "bare"\n[imu]\nrate_hz = 10\n[initial]\nlat_deg = 45\n'
                    '[[segment]]\ntype = "hold"\nduration_s = 5\n')  # fmt: skip
    suite = small_suite.parent / "two.toml"
    suite.write_text(small_suite.read_text() + '[[case]]\nname = "bare"\nscenario = "bare.toml"\n')
    assert (
        main(["check", str(suite), "--baseline", str(small_suite.parent / "b.json"), "--update-baseline"])
        == 2
    )
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "case[2].scenario" in err and "[compensation]" in err, err
    missing = small_suite.parent / "no" / "b.json"
    assert main(["check", str(small_suite), "--baseline", str(missing), "--update-baseline"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(missing) in err, err
