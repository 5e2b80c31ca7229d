"""The held-back guard of the networks that replace the seed model, fitted on several recordings
(``sins.compensation.network_guard``): its verdict from hand-computed figures, and on a numpy unit whose
errors are the seed model's own, where least squares is exact and no network can beat it held back."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest
from numpy_units import recordings

from sins import compensation, imu
from sins.cli import main
from sins.compensation import fitting, network_guard
from sins.compensation.base import Strategy
from sins.compensation.regression import Regression
from sins.imu import calibration
from sins.imu import spec as imu_spec


def _guard(
    label: str,
    aoe: tuple[float, ...],
    hybrid: tuple[float, ...],
    accel: tuple[float, ...],
    seed_gyro: tuple[float, ...] = (),
) -> network_guard.NetworkGuard:
    """A guard on recordings a, b, c: least squares' AOE 1.3, 2.1, 3.2° and accelerometer spread 1 m/s on
    every axis, the network's ``aoe`` (whole) and ``hybrid`` (with least squares' accelerometer), deg,
    its accelerometer's spread ``accel`` m/s on every axis, and ``seed_gyro`` (its accelerometer beside
    least squares' gyro and rule; none: not measured), deg."""
    same = lambda v: tuple((x, x, x) for x in v)  # noqa: E731
    return network_guard.NetworkGuard(
        label, ("a", "b", "c"), aoe, (1.3, 2.1, 3.2), hybrid, same(accel), same((1.0, 1.0, 1.0)), seed_gyro
    )


def test_the_network_is_kept_only_where_its_mean_gain_clears_students_t_over_the_recordings() -> None:
    """The threshold is Student's t over the recordings at the normal's level of 2 standard errors:
    4.53 over three recordings (t with 2 degrees of freedom, ``scipy.stats.t``), 2.65 over six. The
    accelerometer first. Spreads 0.90, 0.92, 0.88 of least squares': gains 10, 8, 12 %, mean 10 %,
    standard error 2/√3 = 1.15 % (8.7 of them): kept, and the gyro judged with the network whole: gains
    0.21, 0.19, 0.20°, mean 0.2°, standard error 0.01/√3 = 0.00577° (34.6): kept. Gains 0.3, 0.1, 0.2°
    (3.46 standard errors: kept by the normal's 2, one null gain in eleven passing it over three
    recordings): refused. Spreads 0.90, 1.05, 0.95: gains 10, -5, 5 %, mean 3.3 %, standard error 4.4 %:
    least squares' accelerometer, and the gyro judged with it (``hybrid``): gains 0.3, -0.2, 0.2°, mean
    0.1°, standard deviation √(0.14/2) = 0.2646°, standard error 0.1528°: refused; gains 0.21, 0.19,
    0.20° with it: written with least squares' accelerometer."""
    from scipy.stats import norm, t

    assert _guard("x", (1.0,) * 3, (1.0,) * 3, (1.0,) * 3).threshold == pytest.approx(
        t.ppf(norm.cdf(2.0), 2), rel=1e-12
    )
    assert compensation.base.recordings_threshold(2.0, 3) == pytest.approx(4.5265, abs=1e-4)
    assert compensation.base.recordings_threshold(2.0, 6) == pytest.approx(2.6486, abs=1e-4)
    assert compensation.base.recordings_threshold(2.0, 1) == np.inf
    kept = _guard("kohonen_pure", (1.09, 1.91, 3.0), (9.0, 9.0, 9.0), (0.90, 0.92, 0.88))
    assert kept.accel_gains_pct == pytest.approx([10.0, 8.0, 12.0])
    assert kept.accel_kept and kept.mean_gain_deg == pytest.approx(0.2)
    assert kept.standard_error_deg == pytest.approx(0.01 / np.sqrt(3.0))
    wide = _guard("kohonen_pure", (1.0, 2.0, 3.0), (9.0, 9.0, 9.0), (0.90, 0.92, 0.88))
    assert wide.mean_gain_deg / wide.standard_error_deg == pytest.approx(2.0 * np.sqrt(3.0))
    assert not wide.kept and wide.to_dict()["written"] == "regression"
    doc = kept.to_dict()
    assert kept.kept and doc["written"] == "kohonen_pure" and doc["accelerometer"] == "kohonen_pure"
    assert doc["accel_mean_gain_pct"] == pytest.approx(10.0)
    assert doc["accel_standard_error_pct"] == pytest.approx(2.0 / np.sqrt(3.0))
    bar = "above 4.53 standard errors (Student's t over 3 recordings)"
    assert kept.lines()[-1].endswith(f"{bar}: kohonen_pure is written"), kept.lines()[-1]
    assert kept.lines()[-2].endswith(f"{bar}: the network's is kept")
    assert kept.to_dict()["threshold"] == pytest.approx(4.5265, abs=1e-4)
    refused = _guard("mlp_seed", (9.0, 9.0, 9.0), (1.0, 2.3, 3.0), (0.90, 1.05, 0.95))
    assert refused.accel_gains_pct == pytest.approx([10.0, -5.0, 5.0])
    assert not refused.accel_kept and refused.mean_gain_deg == pytest.approx(0.1)
    assert refused.standard_error_deg == pytest.approx(np.sqrt(0.14 / 2.0) / np.sqrt(3.0))
    assert not refused.kept
    doc = refused.to_dict()
    assert doc["written"] == "regression" and doc["earns_its_place"] is False
    assert doc["accelerometer"] == "regression" and doc["accel_earns_its_place"] is False
    assert doc["network_aoe_deg"] == [9.0, 9.0, 9.0] and doc["hybrid_aoe_deg"] == [1.0, 2.3, 3.0]
    assert doc["recordings"] == ["a", "b", "c"]
    assert "least squares' model (regression) is written, not mlp_seed's" in refused.lines()[-1]
    assert refused.lines()[2] == (
        "  b: accelerometer 1050.0 1050.0 1050.0 against 1000.0 1000.0 1000.0 mm/s; AOE 2.300° against 2.100°"
    )
    hybrid = _guard("mlp_pure", (9.0, 9.0, 9.0), (1.09, 1.91, 3.0), (0.90, 1.05, 0.95))
    doc = hybrid.to_dict()
    assert hybrid.kept and doc["written"] == "mlp_pure" and doc["accelerometer"] == "regression"
    assert hybrid.lines()[-1].endswith("mlp_pure is written with least squares' accelerometer")
    with pytest.raises(ValueError, match="every figure one per recording"):
        network_guard.NetworkGuard("mlp_pure", ("a", "b", "c"), (1.0, 2.0, 3.0), (1.3, 2.1, 3.2))


def test_an_accelerometer_that_earns_its_place_is_written_beside_least_squares_gyro() -> None:
    """The network's accelerometer 10, 8, 12 % ahead (kept, as above) and its gyro behind (AOE 9° on
    each): beside least squares' gyro and bias rule, whose AOE held back is least squares' own (1.3, 2.1,
    3.2°), the network is written for its accelerometer alone; 0.1° behind on one recording, it is not,
    and least squares' model is written."""

    def guard(seed_gyro: tuple[float, ...]) -> network_guard.NetworkGuard:
        return _guard("kohonen_pure", (9.0, 9.0, 9.0), (9.0, 9.0, 9.0), (0.90, 0.92, 0.88), seed_gyro)

    alone = guard((1.3, 2.1, 3.2 + 1e-13))  # the same gyro by another path: rounding
    assert alone.accel_kept and not alone.kept and alone.accel_alone
    doc = alone.to_dict()
    assert (doc["written"], doc["accelerometer"], doc["gyro"]) == (
        "kohonen_pure",
        "kohonen_pure",
        "regression",
    )
    assert doc["seed_gyro_aoe_deg"] == [1.3, 2.1, 3.2 + 1e-13]
    assert (
        "kohonen_pure's accelerometer is written beside least squares' gyro and bias rule"
        in alone.lines()[-1]
    )
    behind = guard((1.3, 2.2, 3.2))
    assert not behind.accel_alone and behind.to_dict()["written"] == "regression"
    assert behind.seed_gyro_gain_deg == pytest.approx(-0.1 / 3.0)
    unmeasured = guard(())
    assert not unmeasured.accel_alone and unmeasured.to_dict()["written"] == "regression"


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


def test_the_guard_judges_the_velocity_change_over_the_fits_own_intervals() -> None:
    """Three 16 s recordings, fitted with ``--interval-s 0.5`` (16 intervals of 1 s each, 20 needed):
    the guard judged each held-back recording's velocity change over intervals of 1 s whatever the fit's,
    and the fit ended in a traceback (PSINS's vehicle MEMS cut into six parts). Now over the fit's: every
    fold judged, least squares' model written (the numpy unit's errors are the seed model's)."""
    from sins.compensation import judging

    recs, _, _ = recordings(4)
    short = [judging.between(r, r.imu.t[0] + 5.0, r.imu.t[0] + 21.0) for r in recs]
    with pytest.raises(ValueError, match="16 intervals of 1 s"):
        network_guard.velocity_spread(short[0].imu, short[0])
    outcome = fitting.fit_several("kohonen_pure", short, ["a", "b", "c"], interval_s=0.5)
    doc = outcome.document["network_guard"]
    assert doc["recordings"] == ["a", "b", "c"] and doc["mean_gain_deg"] is not None, doc
    assert len(network_guard.velocity_spread(short[0].imu, short[0], 0.5)) == 3


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


def _kept_and_refused(
    written: Strategy,
    key: str,
    readings: tuple[np.ndarray, np.ndarray],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> str:
    """``written`` saved and loaded: its ``key`` and its corrections of ``readings`` to the bit; the file
    with ``key``'s first row cut is then refused by ``sins correct`` in one line naming the file, which
    is returned."""
    path = tmp_path / "m.json"
    compensation.save(written, path)
    again = compensation.load(path)
    assert np.array_equal(getattr(again, key), getattr(written, key))
    pairs = zip(again.correct(*readings), written.correct(*readings), strict=True)
    assert all(np.array_equal(x, y) for x, y in pairs)
    doc = json.loads(path.read_text())
    doc["state"][key] = doc["state"][key][1:]
    path.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["correct", str(path), "absent.csv", "--out", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "m.json" in err, err
    return err


class _Seeded(Strategy):
    """A stand-in for a network: the seed model's inverse through :meth:`correct` (as a network's own
    correction runs), so that what the guard puts in place of its accelerometer is seen."""

    name = "seeded"

    def __init__(self, B: np.ndarray, A: np.ndarray) -> None:
        self.B, self.A = B, A

    def fit(self, data: object) -> _Seeded:  # type: ignore[override]
        return self

    def correct(self, gyro: np.ndarray, accel: np.ndarray, temp: np.ndarray | None = None) -> tuple:  # type: ignore[type-arg]
        z = np.zeros(3)
        return calibration.invert_seed_model(z, self.B, np.zeros((3, 3)), z, self.A, gyro, accel)


def test_a_network_whose_accelerometer_loses_held_back_is_judged_with_least_squares_one() -> None:
    """Four recordings of a calibrated numpy unit (no gyro bias, scale or delay; accelerometer
    misalignment of 0.3 %). The stand-in network corrects the gyro exactly and the accelerometer with a
    scale 2 % off; least squares the other way round (gyro 1 % off, accelerometer exact). Held back, the
    network's accelerometer leaves more of every recording's velocity change (a 2 % scale of gravity's
    and the motion's changing share, against the sensor's 1 cm/s noise), so least squares' replaces it,
    and the gyro, judged with it, wins on every recording (4.4 standard errors, above Student's 3.31 over
    four; over the first three, 3.2 of 4.53): the network is written with least squares' accelerometer.
    The accelerometer does not move the AOE here (no bias rule reads it)."""
    recs, unit, _ = recordings(8, count=4, calibrated=True)
    a_true = unit.A  # type: ignore[attr-defined]
    baseline = Regression()
    baseline.B0_, baseline.B_, baseline.K_ = np.zeros(3), 0.01 * np.eye(3), np.zeros((3, 3))
    baseline.A0_, baseline.A_ = np.zeros(3), a_true
    network = _Seeded(np.zeros((3, 3)), a_true + 0.02 * np.eye(3))
    fits = {network_guard.BASELINE: baseline, "mlp_pure": network}
    verdict = network_guard.judged("mlp_pure", recs, ["a", "b", "c", "d"], lambda name, on: fits[name])
    assert (verdict.accel_gains_pct < 0.0).all() and not verdict.accel_kept, verdict
    assert verdict.hybrid_deg == pytest.approx(verdict.network_deg, rel=1e-9)
    assert (verdict.gains_deg > 0.0).all() and verdict.kept, verdict
    assert verdict.to_dict()["accelerometer"] == "regression" and verdict.to_dict()["written"] == "mlp_pure"


def test_the_written_network_corrects_its_accelerometer_as_least_squares_does(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Where the guard keeps the network for its gyro and not its accelerometer, the model written is the
    network with least squares' accelerometer: its force equals least squares' model's to rounding, its
    rate the network's own; the model file keeps both to the bit, and one whose ``accel_seed_`` is not
    (4, 3) is refused in one line naming the file."""
    recs, _, _ = recordings(4)
    names = ["a", "b", "c"]
    verdict = _guard("kohonen_pure", (9.0, 9.0, 9.0), (1.09, 1.91, 3.0), (0.90, 1.05, 0.95))
    monkeypatch.setattr(network_guard, "judged", lambda *args: verdict)
    written = fitting.fit_several("kohonen_pure", recs, names).strategy
    least_squares = fitting.fit_several("regression", recs, names).strategy
    assert written.name == "kohonen_pure" and written.accel_seed_.shape == (4, 3)
    alone = copy.copy(written)
    del alone.accel_seed_
    gyro, accel = recs[1].imu.dtheta_b / 0.01, recs[1].imu.dv_b / 0.01
    rate, force = written.correct(gyro, accel)
    assert np.array_equal(rate, alone.correct(gyro, accel)[0])
    np.testing.assert_allclose(force, least_squares.correct(gyro, accel)[1], rtol=0.0, atol=1e-12)
    assert not np.allclose(force, alone.correct(gyro, accel)[1], rtol=0.0, atol=1e-6)
    refused = _kept_and_refused(written, "accel_seed_", (gyro, accel), tmp_path, capsys)
    assert "accel_seed_ has shape (3, 3), expected (4, 3)" in refused


def test_a_network_whose_gyro_loses_and_accelerometer_wins_gets_least_squares_gyro() -> None:
    """The other way round from the test above, on the same calibrated numpy unit: the stand-in network
    corrects the accelerometer exactly and the gyro with a scale 1 % off; least squares the gyro exactly
    and the accelerometer 2 % off. Held back the network's accelerometer wins on every recording and its
    gyro loses on every one; least squares' gyro beside the network's accelerometer leaves least squares'
    AOE (no bias rule reads the accelerometer here), so the network is written for its accelerometer
    alone (it had been least squares' model whole)."""
    recs, unit, _ = recordings(8, calibrated=True)
    a_true = unit.A  # type: ignore[attr-defined]
    baseline = Regression()
    baseline.B0_, baseline.B_, baseline.K_ = np.zeros(3), np.zeros((3, 3)), np.zeros((3, 3))
    baseline.A0_, baseline.A_ = np.zeros(3), a_true + 0.02 * np.eye(3)
    network = _Seeded(0.01 * np.eye(3), a_true)
    fits = {network_guard.BASELINE: baseline, "mlp_pure": network}
    verdict = network_guard.judged("mlp_pure", recs, ["a", "b", "c"], lambda name, on: fits[name])
    assert (verdict.accel_gains_pct > 0.0).all() and verdict.accel_kept, verdict
    assert (verdict.gains_deg < 0.0).all() and not verdict.kept, verdict
    assert verdict.seed_gyro_deg == pytest.approx(verdict.baseline_deg, rel=1e-12), verdict
    assert verdict.accel_alone and verdict.to_dict()["gyro"] == "regression", verdict
    written = network_guard.with_seed_gyro(network, baseline)
    gyro, accel = recs[1].imu.dtheta_b / 0.01, recs[1].imu.dv_b / 0.01
    rate, force = written.correct(gyro, accel)
    np.testing.assert_allclose(rate, baseline.correct(gyro, accel)[0], rtol=0.0, atol=1e-15)
    assert np.array_equal(force, network.correct(gyro, accel)[1])


def test_the_network_written_for_its_accelerometer_keeps_least_squares_gyro_and_rule(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Where the guard writes the network for its accelerometer alone, the model written corrects the
    gyro as least squares' model fitted on the same recordings does (to rounding) and takes a new
    recording's bias by least squares' rule (the same rule, to the bit), its force the network's own;
    the model file keeps ``gyro_seed_`` to the bit, and one that is not (11, 3) is refused in one line
    naming the file."""
    recs, _, _ = recordings(4)
    names = ["a", "b", "c"]
    verdict = _guard("kohonen_pure", (9.0, 9.0, 9.0), (9.0, 9.0, 9.0), (0.90, 0.92, 0.88), (1.3, 2.1, 3.2))
    monkeypatch.setattr(network_guard, "judged", lambda *args: verdict)
    outcome = fitting.fit_several("kohonen_pure", recs, names)
    written = outcome.strategy
    least_squares = fitting.fit_several("regression", recs, names).strategy
    assert written.name == "kohonen_pure" and written.gyro_seed_.shape == (11, 3)
    assert written.unit_bias_ == least_squares.unit_bias_
    assert outcome.document["bias_rule"] == least_squares.unit_bias_
    alone = copy.copy(written)
    del alone.gyro_seed_
    gyro, accel = recs[1].imu.dtheta_b / 0.01, recs[1].imu.dv_b / 0.01
    rate, force = written.correct(gyro, accel)
    np.testing.assert_allclose(rate, least_squares.correct(gyro, accel)[0], rtol=0.0, atol=1e-12)
    assert np.array_equal(force, alone.correct(gyro, accel)[1])
    assert not np.allclose(rate, alone.correct(gyro, accel)[0], rtol=0.0, atol=1e-6)
    refused = _kept_and_refused(written, "gyro_seed_", (gyro, accel), tmp_path, capsys)
    assert "gyro_seed_ has shape (10, 3), expected (11, 3)" in refused
