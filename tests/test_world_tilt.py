"""The tilt of a reference's world frame from gravity (:mod:`sins.compensation.world_tilt`): its verdict from
hand figures, and a numpy recording's reference levelled by it (``tests/numpy_unit_gap.py``, no sins)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import numpy_unit_gap as nu
import pytest

from sins import io
from sins.compensation import fitting, referenced, world_tilt
from sins.compensation.world_tilt import _verdict

DEG = np.pi / 180.0


@pytest.mark.parametrize(
    ("tilt_deg", "se_deg", "levelled", "said"),
    [
        ((0.5, -0.3), (0.02, 0.02), True, "read levelled"),  # chi-square 850
        ((0.05, 0.0), (0.02, 0.02), True, "read levelled"),  # 6.25: beyond 5.991
        ((0.03, 0.03), (0.02, 0.02), False, "within its noise"),  # 4.5
        ((0.9, 0.9), (0.2, 0.02), False, "not determined within 0.1°"),  # a unit that hardly turns
    ],
)
@pytest.mark.parametrize("predicts", [True, False])
def test_the_verdict_from_hand_figures(
    tilt_deg: tuple[float, float], se_deg: tuple[float, float], levelled: bool, said: str, predicts: bool
) -> None:
    """Levelled where both standard errors are within 0.1°, the chi-square of two degrees of freedom
    is beyond its 95 % point (5.991) and the tilt predicts held-back intervals (gain 3 against its 1
    standard error, or not: 1 against 1)."""
    held_back = (predicts, 3.0 if predicts else 1.0, 1.0)
    found = _verdict(np.asarray(tilt_deg) * DEG, np.diag((np.asarray(se_deg) * DEG) ** 2), held_back)
    if levelled and not predicts:
        levelled, said = False, "does not predict held-back intervals (gain 1.0 standard errors"
    assert found.levelled is levelled and said in found.says, found.says
    assert found.to_dict()["tilt_deg"] == pytest.approx(list(tilt_deg))


def _angles_deg(q_a: np.ndarray, q_b: np.ndarray) -> np.ndarray:
    """The angle between two attitudes at each epoch (unit quaternions, either order of scalar)."""
    return np.degrees(2 * np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", q_a, q_b)), -1.0, 1.0)))


def test_a_levelled_reference_is_level_and_turned_by_the_tilt_alone(tmp_path: Path) -> None:
    """numpy's recording with its world turned 0.4° about north and -0.3° about east (0.5°), beside the
    same recording in the level room (the same draws): levelled, its tilt estimated again is zero
    within 5 % of its standard error (measured 1.4 %: what the estimate's first order in the tilt leaves),
    and its attitude is the level room's within the estimate's error (0.007° per axis here;
    as given, 0.5° from it)."""
    level = nu.write(tmp_path / "level.npz", nu.recording(3, "clean"))
    tilted = nu.write(tmp_path / "tilted.npz", nu.recording(3, "clean", world_tilt_deg=(0.4, -0.3)))
    rec = io.read(tilted).beside_reference()
    turned, tilt = world_tilt.levelled(rec)
    assert tilt.levelled
    again = world_tilt.estimate(turned)
    assert np.all(np.abs(again.tilt_rad) < 0.05 * again.se_rad), (again.tilt_rad, again.se_rad)
    q_level = io.read(level).beside_reference().reference.q_nb
    assert np.max(_angles_deg(q_level, turned.reference.q_nb)) < 0.05
    assert np.min(_angles_deg(q_level, rec.reference.q_nb)) > 0.45


def test_a_fit_against_a_tilted_world_finds_the_units_accelerometer(tmp_path: Path) -> None:
    """numpy's unit (its accelerometer's bias 34, 42, 4 mm/s² and its scale and misalignment of 3e-3
    drawn by ``numpy_unit_gap.unit_errors``) beside a reference whose room is turned 0.4° about north and
    -0.3° about east: ``sins fit``'s path levels the reference and finds the bias within 3 standard errors
    and every element of the matrix within 1e-3 (measured on motion seeds 3-5: within 1.3 and 4.6e-4);
    the fit on the reference as given had the bias 2.9-14.6 standard errors off and the matrix up to
    6.7e-3-8.6e-3, twice the unit's own (what the levelling guards against)."""
    _, _, a0, a = nu.unit_errors()
    path = nu.write(tmp_path / "tilted.npz", nu.recording(3, "clean", world_tilt_deg=(0.4, -0.3)))
    rec = io.read(path).beside_reference()
    outcome = fitting.fit_referenced("regression", rec, where="tilted")
    as_given = referenced.fit("regression", rec)
    assert outcome.document["reference_tilt"]["levelled"]
    assert outcome.strategy.fitted_on_["reference_tilt"]["levelled"]
    se = as_given.intervals.seed.A0_se
    model = outcome.strategy
    assert np.all(np.abs(model.A0_ - a0) < 3 * se), (model.A0_ - a0) / se
    assert np.max(np.abs(model.A_ - a)) < 1e-3, model.A_ - a
    assert np.max(np.abs(as_given.strategy.A_ - a)) > 5e-3


def test_inspect_says_how_the_references_world_stands_against_gravity(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``sins inspect`` beside a reference says what ``sins fit`` and ``sins gap`` will read of its world
    frame: numpy's room turned 0.4° about north and -0.3° about east is levelled by a tilt within 3
    standard errors of those, the level room (the same draws) is read as given; ``--json`` keeps it as
    ``reference_tilt``."""
    from sins.cli import main

    found = {}
    for name, tilt_deg in (("level", (0.0, 0.0)), ("tilted", (0.4, -0.3))):
        path = nu.write(tmp_path / f"{name}.npz", nu.recording(3, "clean", world_tilt_deg=tilt_deg))
        out = tmp_path / f"{name}.json"
        assert main(["inspect", str(path), "--json", str(out)]) == 0
        line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("the reference, as"))
        found[name] = (line, json.loads(out.read_text())["reference_tilt"], tilt_deg)
    for name, (line, tilt, truth_deg) in found.items():
        assert tilt["levelled"] is (name == "tilted"), tilt
        assert ("read levelled" if name == "tilted" else "read as given") in line, line
        off = np.abs(np.asarray(tilt["tilt_deg"]) - truth_deg) / np.asarray(tilt["standard_error_deg"])
        assert np.all(off < 3.0), (name, tilt)
