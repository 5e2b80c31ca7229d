"""The seed model's scale and misalignment compared across recordings of one unit
(sins.compensation.seed_terms): the rule against scipy's chi-square written by hand, and ``sins fit`` on
several recordings written with numpy alone (tests/numpy_unit_gap.py: one unit over several motions)
saying where one recording's own differs. ``sins gap``'s use of it is in tests/test_unit_gap.py."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import numpy_unit_gap as nu
import pytest
from scipy.stats import chi2

from sins.cli import main
from sins.compensation.seed_terms import differing


def _model(y_from_x: float, se: float, scale_y: float = 0.0) -> dict[str, Any]:
    """A recording's seed model as ``of_fit`` keeps it: every term zero ± 1e-4 but gyro and accelerometer
    y←x (± ``se``) and scale y."""
    matrix, errors = np.zeros((3, 3)), np.full((3, 3), 1e-4)
    matrix[1, 0], errors[1, 0], matrix[1, 1] = y_from_x, se, scale_y
    return {s: {"matrix": matrix.tolist(), "se": errors.tolist()} for s in ("gyro", "accel")}


def _terms(*models: dict[str, Any]) -> list[str]:
    return [d["term"] for d in differing({f"r{i}": m for i, m in enumerate(models)})["differ"]]


def test_seed_terms_differ_by_both_tests_and_no_fewer() -> None:
    """A term differs where its values are not one value within their standard errors (chi-square above
    scipy's 99.9 % quantile, written here from the weighted mean by hand) and span more than a consumer
    unit's spread (gyro: misalignment 10 mrad, scale 2 %; accelerometer: 5 mrad, 1 %); either alone is not
    enough; another class's spreads where asked. A value beyond the class's bound (five spreads) is said
    so. A term not fitted on a recording (standard error zero) is left out there."""
    both = ["gyro misalignment y←x", "accel misalignment y←x"]
    # Two values 12 mrad apart: chi-square (12/√2 / se)² against the quantile on one degree of freedom.
    se_at = 12e-3 / np.sqrt(2.0 * chi2.ppf(0.999, 1))  # the standard error that puts it at the quantile
    assert _terms(_model(0.0, 0.9 * se_at), _model(12e-3, 0.9 * se_at)) == both
    assert _terms(_model(0.0, 1.1 * se_at), _model(12e-3, 1.1 * se_at)) == []
    # Many standard errors apart: beyond the accelerometer's spread alone (7 mrad), within both (4 mrad).
    assert _terms(_model(0.0, 1e-5), _model(7e-3, 1e-5)) == ["accel misalignment y←x"]
    assert _terms(_model(0.0, 1e-5), _model(4e-3, 1e-5)) == []
    # Scales 1.5 % and 2.5 % apart, standard errors of 1e-4.
    assert _terms(_model(0.0, 1e-4, 0.0), _model(0.0, 1e-4, 1.5e-2)) == ["accel scale y"]
    assert _terms(_model(0.0, 1e-4, 0.0), _model(0.0, 1e-4, 2.5e-2)) == ["gyro scale y", "accel scale y"]
    # A value beyond the class's bound (five spreads: the gyro's misalignment 50 mrad) is said so.
    found = differing({"a": _model(0.0, 1e-5), "b": _model(60e-3, 1e-5)})["differ"]
    assert [d["beyond_bound"] for d in found] == [["b"], ["b"]]
    assert differing({"a": _model(0.0, 1e-5), "b": _model(40e-3, 1e-5)})["differ"][0]["beyond_bound"] == []
    # By an industrial unit's spreads (1 mrad, 0.8 mrad) the 4 mrad that a consumer unit's take is not.
    industrial = differing({"a": _model(0.0, 1e-5), "b": _model(4e-3, 1e-5)}, "industrial")
    assert [d["term"] for d in industrial["differ"]] == both and industrial["grade"] == "industrial"
    # Not fitted (standard error zero) on one of two: nothing to compare.
    assert _terms(_model(0.0, 0.0), _model(12e-3, 1e-5)) == []


def test_a_recording_apart_is_named_only_where_the_others_agree_without_it() -> None:
    """Three recordings, one 20 mrad off the two that agree: that one is apart. Three spread evenly 12
    mrad apart (each pair beyond the spread without the third): none is."""
    found = differing({"a": _model(0.0, 1e-4), "b": _model(1e-3, 1e-4), "c": _model(21e-3, 1e-4)})
    assert [(d["term"], d["apart"]) for d in found["differ"]] == [
        ("gyro misalignment y←x", "c"),
        ("accel misalignment y←x", "c"),
    ]
    even = differing({"a": _model(0.0, 1e-4), "b": _model(12e-3, 1e-4), "c": _model(24e-3, 1e-4)})
    assert [d["apart"] for d in even["differ"]] == [None, None]


def test_fit_on_several_says_where_one_recordings_own_misalignment_differs(tmp_path: Path) -> None:
    """``sins fit`` on three motions of one unit: their own seed models agree. With 20 mrad more of the x
    rate read on gyro y in the third, that term differs (by about the 20 added) and the third is apart;
    the shared fit, which takes them as one, says so."""

    def fitted(effect: str) -> dict[str, Any]:
        paths = [
            nu.write(
                tmp_path / f"m{m}_{effect}.npz",
                nu.recording(m, effect if m == 5 else "clean", duration_s=90.0),
            )
            for m in (3, 4, 5)
        ]
        out = tmp_path / "fit.json"
        assert main(["fit", *map(str, paths), "--strategy", "regression", "--out", str(tmp_path / "m.json"),
                     "--json", str(out)]) == 0  # fmt: skip
        return json.loads(out.read_text())["seed_terms"]

    clean = fitted("clean")
    assert len(clean["compared"]) == 3 and clean["differ"] == []
    added = fitted("gyro y←x")
    assert [d["term"] for d in added["differ"]] == ["gyro misalignment y←x"]
    term = added["differ"][0]
    assert term["apart"].endswith("m5_gyro y←x.npz")
    values = [v for v, _ in term["values"].values()]
    assert values[2] - np.mean(values[:2]) == pytest.approx(20.0, abs=1.0)
