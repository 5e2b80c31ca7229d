"""The estimator laws every registered strategy keeps (scikit-learn's ``check_estimator``, for sins):
parametrised over the registry, so a new strategy is checked without editing this file.

Each strategy is fitted on a short simulated rig session of a tactical unit (the Ferraris calibration on
tests/test_ferraris.py's numpy session of holds and turns; the oracle is given the unit it corrects) and
must: be made by name with its variant's parameters; report as ``params()`` exactly its constructor's
arguments, and be made again from them with the same parameters; return itself from ``fit``; keep what
it learnt in attributes ending in ``_``; give ``predict_error`` as readings less ``correct``; correct
increments as its rates, a whole recording as its increments (no bias rule fitted); and come back from
its model file with the same parameters and the same corrections, to the last bit.
"""

from __future__ import annotations

import inspect
import json
import pickle
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from sins import compensation, imu
from sins.core.series import CalibrationData, ImuIncrements, ImuRates
from sins.errors import SinsInputError
from sins.imu import calibration
from sins.imu import spec as imu_spec

FAST = calibration.RigProcedure(position_dwell_s=8.0, rate_table=calibration.RateTable(dwell_s=4.0))
#: Parameters that keep a learner's fit short here (the laws do not depend on its size).
QUICK = {
    "mlp_window": {"steps": 200, "ensemble": 1}, "mlp_pure": {"max_epochs": 5}, "mlp_seed": {"max_epochs": 3},
    "kohonen_pure": {"iterations": 2000},
}  # fmt: skip


def _unit() -> imu.ImuModel:
    return imu_spec.draw_unit("tactical", 1, 101).only(*imu.BASELINE)


def _data(name: str) -> CalibrationData:
    if name == "ferraris":
        from test_ferraris import Hand, Unit, _numpy_session

        rng = np.random.default_rng(5)
        return _numpy_session(Unit.draw(rng), Hand(), rng)
    return calibration.simulate_rig(FAST, _unit(), seed=1)


def _make(name: str) -> compensation.Strategy:
    if name == "oracle":
        return compensation.Oracle(_unit())
    return compensation.make(name, **QUICK.get(name, {}))


@pytest.mark.parametrize("name", list(compensation.VARIANTS))
def test_every_strategy_keeps_the_estimator_laws(name: str, tmp_path: Path) -> None:
    data = _data(name)
    strategy = _make(name)
    assert strategy.label == name or name == "oracle"
    # params(): exactly the constructor's arguments, and a clone made from them says the same.
    arguments = [
        n for n, p in inspect.signature(type(strategy).__init__).parameters.items()
        if n != "self" and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
    ]  # fmt: skip
    params = strategy.params()
    if name != "oracle":  # the oracle's model is a simulation's, not a file's
        assert list(params) == arguments
        assert type(strategy)(**params).params() == params
        # The constructor keeps what it is given, each under its own name, neither converted nor checked
        # (scikit-learn's rule): check_params holds them, and make, fit, save and load call it.
        clone = type(strategy)(**params)
        assert all(getattr(clone, k) is v for k, v in params.items()), name
        assert clone.label == name  # its variant told by its parameters (mlp_seed's had said mlp_pure)
    if name not in ("none", "oracle"):  # nothing to learn: nothing to refuse, nothing to be fitted first
        # Used before fit: said so (scikit-learn's NotFittedError), not an AttributeError from inside.
        with pytest.raises(compensation.NotFittedError, match="is not fitted: call fit"):
            _make(name).correct(data.gyro[:5], data.accel[:5], None if data.temp is None else data.temp[:5])
        # One reading not finite: refused by name, not a model of NaN coefficients that corrects every
        # reading to NaN (and that its own model file's load then refused).
        gyro = data.gyro.copy()
        gyro[len(gyro) // 2, 0] = np.nan
        with pytest.raises(ValueError, match=r"1 row\(s\) of readings not finite"):
            _make(name).fit(replace(data, gyro=gyro))
    if name not in ("none", "oracle", "ferraris"):  # Ferraris's session is its own holds and turns
        # One orientation held still determines no scale factor: refused, as least squares refuses it
        # (regression_extended had fitted it, and corrected other forces by tens of m/s²).
        with pytest.raises(ValueError, match="not determined by this recording"):
            _make(name).fit(data.rows(slice(0, 500)))
    if name not in ("none", "oracle"):
        # Saved before fit: refused (the file's load would have refused it: "state.B0_ is missing").
        with pytest.raises(compensation.NotFittedError, match="is not fitted"):
            compensation.save(_make(name), tmp_path / "unfitted.json")
        assert not (tmp_path / "unfitted.json").exists()
    # Data of another type: refused by name (it was "'Recording' object has no attribute ...").
    with pytest.raises(TypeError, match=r"\.fit takes CalibrationData .*, not ImuRates"):
        _make(name).fit(ImuRates(t=data.t, omega_ib_b=data.gyro, f_ib_b=data.accel))
    # A fit starts from nothing learned (scikit-learn's refit): what an earlier fit against a trajectory
    # left (time offsets, a bias rule, provenance) is gone, not applied to the new fit's corrections.
    strategy.time_offset_s_ = np.array([0.01, 0.02])
    strategy.unit_bias_ = {"mode": "pooled"}
    strategy.fitted_on_ = {"sensor": "another"}
    assert strategy.fit(data) is strategy
    for left in ("time_offset_s_", "unit_bias_", "fitted_on_"):
        assert left not in vars(strategy), left
    learned = [k for k in vars(strategy) if k.endswith("_")]
    assert (len(learned) > 0) == (name not in ("none", "oracle"))
    probe_w, probe_f = data.gyro[::97], data.accel[::97]
    probe_t = None if data.temp is None else data.temp[::97]
    w, f = strategy.correct(probe_w, probe_f, probe_t)
    # Readings of another shape: one line, whatever the strategy (five answered with numpy's errors).
    with pytest.raises(ValueError, match=r"gyro and accel must both be \(n, 3\), got \(\d+, 2\)"):
        strategy.correct(probe_w[:, :2], probe_f[:, :2], probe_t)
    with pytest.raises(ValueError, match=r"must both be \(n, 3\), got \(3,\)"):
        strategy.correct(probe_w[0], probe_f[0], None)
    eg, ea = strategy.predict_error(probe_w, probe_f, probe_t)
    np.testing.assert_array_equal(eg, probe_w - w)
    np.testing.assert_array_equal(ea, probe_f - f)
    rates = ImuRates(t=data.t[:2000], omega_ib_b=data.gyro[:2000], f_ib_b=data.accel[:2000])
    temp = None if data.temp is None else data.temp[:2000]
    steps = rates.to_increments()
    by_steps = strategy.correct_increments(steps, temp)
    assert isinstance(by_steps, ImuIncrements) and by_steps.dtheta_b.shape == steps.dtheta_b.shape
    whole = strategy.correct_recording(steps, temp)
    np.testing.assert_array_equal(whole.dtheta_b, by_steps.dtheta_b)  # no bias rule: the same
    # One reading not finite spoils its own row, not every row after it (the window and rest strategies'
    # running sums carried a NaN to the end of the stream).
    spoilt = rates.omega_ib_b.copy()
    spoilt[1000, 0] = np.nan
    got = strategy.correct_rates(ImuRates(t=rates.t, omega_ib_b=spoilt, f_ib_b=rates.f_ib_b), temp)
    assert np.isfinite(np.delete(got.omega_ib_b, 1000, axis=0)).all()
    # A stream's chunk of one reading, or of no interval (a chunked stream may make either): corrected,
    # not a crash (before, the window and rest strategies took the median of no steps).
    one = ImuRates(t=data.t[:1], omega_ib_b=data.gyro[:1], f_ib_b=data.accel[:1])
    assert np.isfinite(strategy.correct_rates(one, None if temp is None else temp[:1]).omega_ib_b).all()
    none = ImuIncrements(t=data.t[:1], dtheta_b=np.zeros((0, 3)), dv_b=np.zeros((0, 3)))
    assert len(strategy.correct_increments(none, None if temp is None else temp[:1])) == 0
    # Pickled (a process pool's way of sending it) and back: the same corrections to the bit (the seed
    # network's neuron was a class made inside a method, which pickle cannot find).
    again = pickle.loads(pickle.dumps(strategy))
    np.testing.assert_array_equal(again.correct(probe_w, probe_f, probe_t)[0], w)
    if name == "oracle":
        return
    # Parameters from a numpy sweep (np.int64, np.float64, np.bool_) are reported as Python's: a model
    # file can hold them (before, json refused np.int64 when the model was saved).
    swept = {
        k: np.bool_(v) if isinstance(v, bool) else np.int64(v) if isinstance(v, int) else np.float64(v)
        for k, v in params.items() if isinstance(v, int | float)
    }  # fmt: skip
    assert json.dumps(type(strategy)(**{**params, **swept}).params()) == json.dumps(params)
    path = tmp_path / "model.json"
    compensation.save(strategy, path)
    back = compensation.load(path)
    assert type(back) is type(strategy) and back.params() == params and back.label == strategy.label
    w2, f2 = back.correct(probe_w, probe_f, probe_t)
    np.testing.assert_array_equal(w2, w)
    np.testing.assert_array_equal(f2, f)
    np.testing.assert_array_equal(back.correct_increments(steps, temp).dtheta_b, by_steps.dtheta_b)
    # A key it never learns (a misspelt unit_bias_) is refused by name: it had been loaded and then
    # ignored, the model correcting without the rule its file meant to give it.
    doc = json.loads(path.read_text())
    doc["state"]["unit_bais_"] = {"mode": "pooled"}
    path.write_text(json.dumps(doc))
    said = rf"malformed {back.name} model .*state\.unit_bais_ is not a fitted attribute of {back.name} \(its"
    with pytest.raises(SinsInputError, match=re.escape(str(path)) + ": " + said):
        compensation.load(path)


def test_every_saved_strategy_is_a_registered_variant() -> None:
    assert set(compensation.SAVED_STRATEGIES) <= set(compensation.VARIANTS)
    assert set(compensation.strategy_names()) == (set(compensation.VARIANTS) - {"oracle"}) | {"bias_only"}


def test_a_unit_of_an_unknown_grade_and_a_start_in_degrees_are_refused_by_name() -> None:
    """A library walk's: ``draw_unit("bogus", 1)`` raised a bare ``KeyError: 'bogus'``, and
    ``motion.Start(lat=45.0, ...)`` (degrees for radians) made a trajectory at 45 rad."""
    from sins.nav import motion

    with pytest.raises(ValueError, match=r"unknown grade 'bogus' \(known: consumer, "):
        imu_spec.draw_unit("bogus", 1)
    with pytest.raises(
        ValueError, match=r"Start\.lat is 45\.0 rad, beyond ±π/2 \(degrees given for radians\?\)"
    ):
        motion.Start(lat=45.0, lon=0.0, h=0.0)
    with pytest.raises(ValueError, match=r"Start\.h is nan, not finite"):
        motion.Start(lat=0.7, lon=0.0, h=float("nan"))
    assert motion.Start(lat=-0.5 * np.pi, lon=0.0, h=0.0).lat == -0.5 * np.pi


def _outside(allowed: compensation.ParamRange) -> list[float]:
    """Values just outside ``allowed``: below its low bound (the bound itself where it is excluded), above
    its high one, a fraction where only whole numbers are, and a number that is not finite."""
    out: list[float] = [float("nan"), float("inf")]
    if allowed.low is not None:
        out.append(allowed.low if allowed.above else allowed.low - (1 if allowed.whole else 1e-6))
    if allowed.high is not None:
        out.append(allowed.high + (1 if allowed.whole else 1e-6 * max(1.0, abs(allowed.high))))
    if allowed.whole:
        out.append((allowed.low or 0) + 1.5)
    return out


@pytest.mark.parametrize("name", sorted(set(compensation.VARIANTS) - {"oracle"}))
def test_every_number_a_strategy_takes_has_a_range_that_is_held(name: str, tmp_path: Path) -> None:
    # Every numeric parameter (or list of numbers) has a declared range, its variant's value lies in it,
    # and a value outside is refused in one line naming it: by make, by fit on a strategy built by hand,
    # and in a model file by load (a max_epochs of -3 had fitted an untrained network, 0 epochs and a
    # loss of inf; a huber_k of -1 failed in LAPACK's SVD, a batch_size of 0 in range(), a seed of 1.5
    # in torch).
    strategy = compensation.make(name)
    ranges = type(strategy).param_ranges
    assert set(ranges) <= set(strategy.params()), "a range for what the constructor does not take"
    for param, value in strategy.params().items():
        numeric = isinstance(value, int | float) and not isinstance(value, bool)
        if numeric or (isinstance(value, list) and value and isinstance(value[0], int | float)):
            assert param in ranges, f"{name}.{param} has no range"
    data = _data(name)
    fitted = _make(name).fit(data)
    model = tmp_path / "model.json"
    compensation.save(fitted, model)
    doc = json.loads(model.read_text())
    for param, allowed in ranges.items():
        default = strategy.params()[param]
        for bad in _outside(allowed):
            value = [bad] * len(default) if isinstance(default, list) else bad
            # (a network's layers and a map's sides are bounded by their constructors, in their words)
            said = rf"^([a-z_]+: )?(params\.)?{param} (is .*, expected a (whole )?number|must be)"
            with pytest.raises(ValueError, match=said):
                compensation.make(name, **{param: value})
            with pytest.raises(ValueError, match=said):  # built by hand, then fitted
                type(strategy)(**{**strategy.params(), param: value}).fit(data)
            damaged = tmp_path / "damaged.json"
            damaged.write_text(json.dumps({**doc, "params": {**doc["params"], param: value}}))
            with pytest.raises(SinsInputError) as refused:
                compensation.load(damaged)
            said = str(refused.value)
            assert said.startswith(f"{damaged}: malformed") and param in said and "\n" not in said


#: The strategies with a list parameter (a grid of candidates, a network's layers).
GRIDDED = sorted(
    name for name in set(compensation.VARIANTS) - {"oracle"}
    if any(isinstance(v, list) and v for v in compensation.make(name).params().values())
)  # fmt: skip


def test_the_gridded_strategies_are_the_learners() -> None:
    assert set(GRIDDED) >= {"mlp", "kohonen"}


@pytest.mark.parametrize("name", GRIDDED)
def test_every_grid_a_strategy_takes_is_refused_empty(name: str) -> None:
    # An empty list of candidates (mlp's decays or hidden_sizes, kohonen's sizes or sigmas) was taken by
    # make and failed in fit ("no fold could be fitted (too few blocks)"; kohonen's sigmas in min()).
    strategy = compensation.make(name)
    for param, value in strategy.params().items():
        if isinstance(value, list) and value:
            # (a network's layers are refused by its constructor, in its words: "must be 1 to 4 ...")
            said = rf"^([a-z_]+: )?{param}(: each candidate)? (is .*, expected one or more|must be)"
            with pytest.raises(ValueError, match=said):
                compensation.make(name, **{param: []})


def test_a_temperature_of_the_wrong_length_is_said_in_the_increments_terms() -> None:
    # Ten temperatures for ten increments (eleven times) read "temp must be (10,), got (9,)": sizes the
    # caller never passed (the midpoints' made from them).
    rng = np.random.default_rng(3)
    dtheta, dv = rng.normal(size=(10, 3)), rng.normal(size=(10, 3))
    imu = ImuIncrements(t=np.arange(11) * 0.01, dtheta_b=dtheta, dv_b=dv)
    with pytest.raises(ValueError, match=r"^temp must be \(11,\) \(at imu\.t\), got \(10,\)"):
        compensation.make("none").correct_increments(imu, temp=np.zeros(10))


@pytest.mark.parametrize(
    ("name", "param", "value", "said"),
    [
        ("mlp_pure", "mode", "paper", "mlp_pure: mode is 'paper', expected one of modern, seed"),
        ("mlp_pure", "hidden", (8,) * 5, "mlp_pure: hidden must be 1 to 4 layer sizes"),
        ("mlp", "hidden_sizes", ((0,),), "mlp: hidden_sizes must be 1 to 4 layer sizes"),
        ("mlp", "hidden_sizes", (16,), "mlp: hidden_sizes is (16,), expected one or more candidates"),
        ("mlp_window", "hidden", (1.5,), "mlp_window: hidden is (1.5,), expected a whole number"),
        ("kohonen_pure", "rows", 0, "kohonen_pure: rows is 0, expected a whole number"),
        ("kohonen", "sizes", (0,), "kohonen: sizes is (0,), expected a whole number"),
    ],
)
def test_a_parameter_set_after_the_constructor_is_held_by_fit_and_save(
    name: str, param: str, value: object, said: str, tmp_path: Path
) -> None:
    """A network's or a map's own bounds were held by the constructor alone: ``mode = "paper"`` set
    afterwards trained a network of neither kind and saved a file its own loader refused, and
    ``hidden_sizes = ((0,),)`` failed inside numpy. Now fit and save refuse them, in one line naming the
    strategy, before any training or writing (as load does)."""
    import re

    strategy = _make(name)
    setattr(strategy, param, value)
    with pytest.raises(ValueError, match=re.escape(said)):
        strategy.fit(_data(name))
    with pytest.raises(ValueError, match=re.escape(said)):
        compensation.save(strategy, tmp_path / "model.json")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("name", ["mlp_pure", "mlp_window"])
def test_a_fit_leaves_the_callers_torch_stream_where_it_stood(name: str) -> None:
    """A network's initial weights are drawn from torch's global generator, seeded for the fit; the
    caller's own stream is given back as it was (before, ``fit`` re-seeded it)."""
    import torch

    torch.manual_seed(123)
    expected = torch.rand(4)
    torch.manual_seed(123)
    _make(name).fit(_data(name))
    assert torch.equal(torch.rand(4), expected)


def test_a_name_a_fitted_strategy_never_learns_is_said_so() -> None:
    """``coef_`` on a fitted ``regression`` had been "not fitted: call fit() first"; unfitted, it is."""
    fitted = _make("regression").fit(_data("regression"))
    with pytest.raises(
        AttributeError, match=r"Regression learned no coef_ \(it learned: A0_, A_, B0_, B_, K_"
    ):
        _ = fitted.coef_  # type: ignore[attr-defined]
    with pytest.raises(compensation.NotFittedError, match="is not fitted: call fit"):
        _ = _make("regression").B0_
