"""The held-back guard of the networks that replace the seed model, fitted on several recordings
(``sins.compensation.network_guard``): its verdict from hand-computed figures, and on a numpy unit whose
errors are the seed model's own, where least squares is exact and no network can beat it held back."""

from __future__ import annotations

import numpy as np
import pytest
from numpy_units import recordings

from sins import imu
from sins.cli import main
from sins.compensation import fitting, network_guard
from sins.imu import calibration
from sins.imu import spec as imu_spec


def test_the_network_is_kept_only_where_its_mean_gain_clears_two_standard_errors() -> None:
    """Gains 0.3, 0.1, 0.2°: mean 0.2°, standard error 0.1/√3 = 0.0577°, 3.5 of them: kept. Gains 0.3,
    -0.2, 0.2°: mean 0.1°, standard deviation √(0.14/2) = 0.2646°, standard error 0.1528°: refused."""
    kept = network_guard.NetworkGuard("kohonen_pure", ("a", "b", "c"), (1.0, 2.0, 3.0), (1.3, 2.1, 3.2))
    assert kept.mean_gain_deg == pytest.approx(0.2)
    assert kept.standard_error_deg == pytest.approx(0.1 / np.sqrt(3.0))
    assert kept.kept and kept.to_dict()["written"] == "kohonen_pure"
    assert kept.lines()[-1].endswith("above 2 standard errors: kohonen_pure is written")
    refused = network_guard.NetworkGuard("mlp_seed", ("a", "b", "c"), (1.0, 2.2, 3.0), (1.3, 2.0, 3.2))
    assert refused.mean_gain_deg == pytest.approx(0.1)
    assert refused.standard_error_deg == pytest.approx(np.sqrt(0.14 / 2.0) / np.sqrt(3.0))
    assert not refused.kept
    doc = refused.to_dict()
    assert doc["written"] == "regression" and doc["earns_its_place"] is False
    assert doc["network_aoe_deg"] == [1.0, 2.2, 3.0] and doc["recordings"] == ["a", "b", "c"]
    assert "least squares' model (regression) is written, not mlp_seed's" in refused.lines()[-1]
    assert refused.lines()[2] == "  b: 2.200° against 2.000°"


def test_a_unit_whose_errors_are_the_seed_models_gets_least_squares_not_the_network() -> None:
    """Three recordings of a numpy unit whose errors are exactly the seed model's (bias, scale,
    misalignment, delays, white noise), each with its own bias: least squares fits the unit's own model,
    a self-organising map only approximates it, so held back the map loses on average and the fit writes
    least squares' model, saying why, in its lines, its document and the model file."""
    recs, _, _ = recordings(4)
    outcome = fitting.fit_several("kohonen_pure", recs, ["a", "b", "c"])
    assert outcome.strategy.name == "regression"
    doc = outcome.document["network_guard"]
    assert doc["strategy"] == "kohonen_pure" and doc["written"] == "regression"
    assert doc["mean_gain_deg"] < 0.0, doc
    assert outcome.strategy.fitted_on_["network_guard"] == doc
    assert any("kohonen_pure held back against least squares" in line for line in outcome.lines)
    # With the guard off the network is written as fitted, unjudged, and the fit says so.
    unguarded = fitting.fit_several("kohonen_pure", recs, ["a", "b", "c"], guard=False)
    assert unguarded.strategy.name == "kohonen_pure" and "network_guard" not in unguarded.document
    assert "the guard is off: kohonen_pure is written without being judged held back" in unguarded.lines


def test_two_recordings_cannot_judge_a_network_and_least_squares_is_written() -> None:
    """Held back whole, one of two recordings leaves one to fit on, which a fit on several refuses: the
    network has not shown what it adds, and least squares' model is written, the fit saying why."""
    recs, _, _ = recordings(4, count=2)
    outcome = fitting.fit_several("mlp_seed", recs, ["a", "b"])
    assert outcome.strategy.name == "regression"
    doc = outcome.document["network_guard"]
    assert doc["earns_its_place"] is False and doc["mean_gain_deg"] is None and doc["written"] == "regression"
    assert any("that takes 3 recordings or more; least squares' model" in line for line in outcome.lines)


def test_a_fit_the_others_cannot_determine_leaves_the_network_unjudged() -> None:
    """A numpy unit of EuRoC's readings (tools/euroc_units.py, seed 1209) had its fit on three recordings
    determined but one on two of them refused: the network's fit was refused with it. Now the network
    is not judged, and least squares' model, which the three determine, is written."""
    from sins.errors import SinsInputError

    def refused(name: str, on: list[object]) -> object:
        raise SinsInputError(
            "b.npz + c.npz: accel bias z was held at zero and then moved: the fit is unstable"
        )

    verdict = network_guard.judged("kohonen_pure", [object()] * 3, ["a", "b", "c"], refused)  # type: ignore[list-item,arg-type]
    assert not verdict.judged and not verdict.kept and verdict.to_dict()["written"] == "regression"
    assert (
        "with a held back, the fit on the others was refused (b.npz + c.npz: accel bias z"
        in verdict.lines()[0]
    )


def test_no_guard_on_one_recording_is_refused_for_a_network(capsys: pytest.CaptureFixture[str]) -> None:
    """The networks' guard judges recordings held back whole: with one recording there is none to lift.
    Refused before anything is read (the file does not exist)."""
    assert main(["fit", "absent.npz", "--strategy", "kohonen_pure", "--no-guard", "--out", "m.json"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--no-guard: kohonen_pure has no guard" in err[0], err
    assert "kohonen_pure on several recordings" in err[0]


def test_a_network_fitted_on_one_recording_is_said_to_be_unjudged() -> None:
    """One recording has none to hold back whole: the network is written as fitted, and the fit says it
    was not judged against least squares; least squares' own fit says nothing of the kind."""
    recs, _, _ = recordings(4)
    network = fitting.fit_referenced("kohonen_pure", recs[0], where="a")
    assert network.strategy.name == "kohonen_pure"
    said = [line for line in network.lines if "written unjudged" in line]
    assert said == [
        "kohonen_pure is written unjudged: its guard judges it against least squares with each recording "
        "held back whole, on 3 recordings or more of the unit"
    ], network.lines
    plain = fitting.fit_referenced("regression", recs[0], where="a")
    assert not any("unjudged" in line for line in plain.lines)
    # A rig recording is always fitted alone: a fit on several takes recordings beside a trajectory.
    rig = calibration.simulate_rig(
        calibration.RigProcedure(position_dwell_s=4.0, rate_table=calibration.RateTable(dwell_s=2.0)),
        imu_spec.draw_unit("consumer", 6, 106).only(*imu.BASELINE),
        seed=6,
    )
    on_rig = fitting.fit_rig("kohonen_pure", rig, where="rig.csv", sensor="unit")
    assert on_rig.strategy.name == "kohonen_pure"
    assert [line for line in on_rig.lines if "unjudged" in line] == [
        "kohonen_pure is written unjudged: its guard judges it against least squares with each recording "
        "held back whole, on 3 recordings or more beside their reference trajectories (a rig recording is "
        "fitted alone)"
    ]
