"""Compensation fitted on one rig procedure, judged on others (the issue's cross-rig check, CI-sized).

The unit and the fitting procedure are written with numpy alone (``tests/numpy_rigs.py``): the issue's
baseline unit, tumbled through random orientations and turned on a table in seven mounts at 100 Hz
while the chamber warms 10 -> 40 °C. It is judged on sessions of the same unit with fresh noise from
sins's own 26-position tilted rig (100 Hz) and from a numpy procedure with six faces and a table to
300 °/s, beyond the 250 °/s the fit saw (200 Hz). Residuals are in units of the judged session's true
white noise per sample; ``tools/bench_crossrig.py`` runs the same over 20 units, ten regimes, a
continuously tumbling procedure and a 1-hour drive.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import numpy_rigs as nr
import pytest

from sins import compensation, imu
from sins.core.series import CalibrationData
from sins.imu import calibration

STRATEGIES = ("regression", "mlp", "kohonen")


def _sins_rig() -> nr.Session:
    rig = calibration.RigProcedure(
        positions=26, position_dwell_s=5.0,
        rate_table=calibration.RateTable(rates_dps=(20.0, 100.0, 200.0), dwell_s=3.0),
        temperature=calibration.TemperatureProfile((0.0, 500.0), (25.0, 35.0)),
    )  # fmt: skip
    data = calibration.simulate_rig(rig, imu.ImuModel(), seed=0)  # the reference alone
    assert data.temp is not None
    return nr.Session(data.t, data.ref_gyro, data.ref_accel, data.temp, rig.rate_hz, "sins_rig")


@pytest.fixture(scope="module")
def sessions() -> dict[str, nr.Session]:
    return {
        "fit": nr.tumble_and_table(rate_hz=100.0, seed=1, holds=20, hold_s=6.0),
        "sins_rig": _sins_rig(),
        "faces_200hz": nr.faces_and_axis_table(rate_hz=200.0, seed=2, hold_s=6.0),
    }


def _recording(session: nr.Session, unit: nr.Unit, seed: int) -> CalibrationData:
    gyro, accel = unit.read(session.ref_gyro, session.ref_accel, session.temp, session.rate_hz,
                            np.random.default_rng(seed))  # fmt: skip
    return CalibrationData(session.t, gyro, accel, session.ref_gyro, session.ref_accel, session.temp)


def _judged(unit: nr.Unit, sessions: dict[str, nr.Session]) -> dict[str, dict[str, np.ndarray]]:
    """Per judged procedure and strategy, the residual RMS per channel in units of the white noise."""
    fitted = {name: compensation.make(name).fit(_recording(sessions["fit"], unit, 1)) for name in STRATEGIES}
    out: dict[str, dict[str, np.ndarray]] = {}
    for judge in ("sins_rig", "faces_200hz"):
        session = sessions[judge]
        data = _recording(session, unit, 2)
        noise = np.r_[np.full(3, unit.gyro_noise), np.full(3, unit.accel_noise)] * np.sqrt(session.rate_hz)
        out[judge] = {
            name: np.array([v["rms_after"] for v in compensation.residual_rms(s, data).values()]) / noise
            for name, s in fitted.items()
        }
    return out


def test_on_a_seed_model_unit_every_strategy_reaches_the_noise_on_other_rigs(sessions):
    unit = nr.baseline_unit(np.random.default_rng(10))
    for judge, by_strategy in _judged(unit, sessions).items():
        for name, residual in by_strategy.items():
            # The bound, 1.05x the white noise on every channel (measured 1.000-1.006).
            assert (residual <= 1.05).all(), (judge, name, residual)


@pytest.mark.parametrize(
    ("field", "channel"),
    [("gyro_k2", 1), ("accel_tc1", 5)],
    ids=["gyro.scale_nonlinearity", "accel.temperature_bias"],
)
def test_a_nonlinear_effect_is_learned_on_one_rig_and_holds_on_others(sessions, field: str, channel: int):
    """One effect the seed model lacks, sized to 3x the channel's noise (RMS over the fitting session):
    the learned strategies leave at most 1.15x the noise and half regression's excess over it."""
    base = nr.baseline_unit(np.random.default_rng(11))
    shape = np.zeros(3)
    shape[channel % 3] = 1.0
    probe = nr.Unit(**{field: shape})
    fit = sessions["fit"]
    effect = np.hstack(probe.errors(fit.ref_gyro, fit.ref_accel, fit.temp))[:, channel]
    noise = (base.gyro_noise if channel < 3 else base.accel_noise) * np.sqrt(fit.rate_hz)
    unit = dataclasses.replace(base, **{field: shape * 3.0 * noise / np.sqrt(np.mean(effect**2))})
    for judge, by_strategy in _judged(unit, sessions).items():
        regression = by_strategy["regression"][channel]
        # The effect shows on this procedure: regression at least 25 % above the noise. (On the faces
        # procedure, a 20-29 °C soak, a third of the fit's 10-40 °C, the temperature bias leaves 1.36.)
        assert regression > 1.25, (judge, regression)
        for name in ("mlp", "kohonen"):
            learned = by_strategy[name][channel]
            assert learned <= 1.15, (judge, name, learned)
            assert learned - 1.0 <= 0.5 * (regression - 1.0), (judge, name, learned, regression)
            assert (by_strategy[name] <= 1.05).sum() >= 5, (judge, name, by_strategy[name])


def test_a_temperature_scale_the_fitting_rig_confounds_with_its_table_holds_on_tumbling(sessions, tmp_path):
    """A gyro scale factor that drifts with temperature, on a rig that turns its table only while the
    chamber warms: a learner alone cannot tell temperature from rate there, and on continuous tumbling
    (all axes at once, 15-30 °C, 50 Hz) leaves 1.23x (mlp) and 1.27x (kohonen) the noise on this unit
    (``physics=False``). The temperature terms, fitted with the seed model's columns, carry it: measured
    1.002x for both, regression 4.54x."""
    base = nr.baseline_unit(np.random.default_rng(12))
    fit = sessions["fit"]
    probe = nr.Unit(gyro_ts=np.array([0.0, 1.0, 0.0]))
    effect = probe.errors(fit.ref_gyro, fit.ref_accel, fit.temp)[0][:, 1]
    noise = base.gyro_noise * np.sqrt(fit.rate_hz)
    unit = dataclasses.replace(base, gyro_ts=probe.gyro_ts * 3.0 * noise / np.sqrt(np.mean(effect**2)))
    tumble = nr.continuous_tumble(rate_hz=50.0, seed=3)
    data = _recording(tumble, unit, 2)
    judged_noise = base.gyro_noise * np.sqrt(tumble.rate_hz)
    residual = {}
    for name in STRATEGIES:
        strategy = compensation.make(name).fit(_recording(fit, unit, 1))
        residual[name] = compensation.residual_rms(strategy, data)["gyro.y"]["rms_after"] / judged_noise
        if name != "regression":
            assert strategy.terms_["gyro.y"]["groups"] == ["temperature"], name
            assert set(strategy.terms_) == {"gyro.y"}, (name, strategy.terms_)
            # The model file carries the terms: the same corrections to the last bit.
            compensation.save(strategy, tmp_path / f"{name}.json")
            again = compensation.load(tmp_path / f"{name}.json")
            for a, b in zip(again.correct(data.gyro, data.accel, data.temp),
                            strategy.correct(data.gyro, data.accel, data.temp), strict=True):  # fmt: skip
                np.testing.assert_array_equal(a, b)
    assert residual["regression"] > 2.0, residual
    assert residual["mlp"] <= 1.05 and residual["kohonen"] <= 1.05, residual
