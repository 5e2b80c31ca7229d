"""``mlp_window`` (sins.compensation.window_net): its causal window inputs against a brute-force numpy
reckoning, a motion-dependent gyro error learned where it exists and refused by the guard where it does
not, and its model file."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np
import pytest
from conftest import refusal

from sins import compensation
from sins.compensation import window_net
from sins.compensation.window_net import EDGES_S, STRIDE, WindowNet, window_inputs
from sins.core.series import CalibrationData, ImuRates
from sins.imu.calibration import SeedModelFit

RATE_HZ = 200.0


def test_window_inputs_are_the_past_blocks_means_and_spreads() -> None:
    rng = np.random.default_rng(1)
    n = 4000
    w, f = rng.normal(0, 1, (n, 3)), rng.normal(0, 1, (n, 3)) + np.array([0.0, 0.0, 9.8])
    dt = 1.0 / RATE_HZ
    rows, x = window_inputs(w, f, dt)
    np.testing.assert_array_equal(rows, np.arange(0, n, STRIDE))
    for r in (0, 5, 1000, 3990):  # row 5 is not a stride row: take the nearest row below
        k = r // STRIDE
        row = rows[k]
        for b, (near, far) in enumerate(itertools.pairwise(EDGES_S)):
            lo, hi = max(row - round(far / dt), 0), max(row - round(near / dt), 0)
            got = x[k, 8 * b : 8 * b + 8]
            if hi == lo:  # before the recording: the first reading, no spread
                np.testing.assert_allclose(got, [*w[0], *f[0], 0.0, 0.0], atol=1e-12)
                continue
            ww, ff = w[lo:hi], f[lo:hi]
            want = [*ww.mean(0), *ff.mean(0), np.sqrt(ww.var(0).sum()), np.sqrt(ff.var(0).sum())]
            np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


def test_the_inputs_are_causal() -> None:
    rng = np.random.default_rng(2)
    w, f = rng.normal(0, 1, (3000, 3)), rng.normal(0, 1, (3000, 3))
    _, x = window_inputs(w, f, 1 / RATE_HZ)
    w2, f2 = w.copy(), f.copy()
    w2[1500:], f2[1500:] = 0.0, 0.0  # the future changed
    _, x2 = window_inputs(w2, f2, 1 / RATE_HZ)
    np.testing.assert_array_equal(x[: 1500 // STRIDE + 1], x2[: 1500 // STRIDE + 1])


def _recording(seed: int, gain_z: float) -> CalibrationData:
    """A minute of a unit whose motors' vibration comes and goes; its gyro's z axis reads ``gain_z`` times
    the vibration level of the past second as a bias (vibration rectification); a bias of its own per
    recording (1e-3 rad/s) and white noise on every axis. Numpy only."""
    rng = np.random.default_rng(seed)
    n = round(60 * RATE_HZ)
    t = np.arange(n) / RATE_HZ
    level = 0.5 + 0.5 * np.sin(2 * np.pi * rng.uniform(0.02, 0.05) * t + rng.uniform(0, 6))  # 0..1
    vib = level[:, None] * 3.0 * np.sin(2 * np.pi * 47.0 * t[:, None] + rng.uniform(0, 6, 3))
    accel = np.array([0.0, 0.0, -9.81]) + vib + rng.normal(0, 0.02, (n, 3))
    rate = 0.2 * np.sin(2 * np.pi * 0.1 * t[:, None] + rng.uniform(0, 6, 3))
    # The rectified bias follows the level with a second's lag (a mean over the past second).
    past = np.convolve(level, np.ones(200) / 200)[:n]
    gyro = rate + rng.normal(0, 1e-3, 3) + rng.normal(0, 3e-3, (n, 3))
    gyro[:, 2] += gain_z * past
    return CalibrationData(
        t=t, gyro=gyro, accel=accel, ref_gyro=rate, ref_accel=accel - vib, source=f"r{seed}"
    )


def _seeded(**params: object) -> WindowNet:
    z = np.zeros((3, 3))
    nan = np.full((3, 3), np.nan)
    seed = SeedModelFit(B0=np.zeros(3), B=z, K=z, A0=np.zeros(3), A=z, B0_se=np.zeros(3), B_se=nan,
                        K_se=nan, A0_se=np.zeros(3), A_se=nan, residual_rms=np.zeros(6))  # fmt: skip
    net = WindowNet(steps=400, ensemble=1, **params)  # type: ignore[arg-type]
    net.set_fit(seed)
    return net


def test_a_motion_dependent_error_is_learned_and_only_where_it_is() -> None:
    """Four recordings with a rectified bias of up to 0.01 rad/s on z: the guard (each recording held
    back in turn) keeps the network on z and refuses it on x and y, where there is nothing to learn but
    each recording's own bias and the noise; on a fifth recording the network takes most of z's error
    away and changes x and y by less than the noise."""
    parts = [_recording(s, 0.01) for s in range(4)]
    net = _seeded().fit_recordings(parts)
    assert net.window_axes == ["z"], (net.held_back_gain_, net.held_back_gain_se_)
    # What sins fit says of it (a walk found it said nothing of the networks' guard): the gain and the axes.
    from sins.compensation.fitting import _window_lines

    said, doc = _window_lines(net, "squared error")
    assert said[0].endswith("-> the networks correct gyro z") and doc["window_guard"][
        "gyro_axes_corrected"
    ] == ["z"]
    new = _recording(9, 0.01)
    out = net.correct_rates(ImuRates(t=new.t, omega_ib_b=new.gyro, f_ib_b=new.accel))
    before = new.gyro - new.ref_gyro
    after = out.omega_ib_b - new.ref_gyro
    slow = lambda e: np.convolve(e, np.ones(400) / 400, mode="valid")  # noqa: E731  (the noise averaged)
    assert np.std(slow(after[:, 2])) < 0.3 * np.std(slow(before[:, 2]))
    np.testing.assert_array_equal(after[:, :2], before[:, :2])


def test_the_guard_refuses_a_network_with_nothing_to_learn() -> None:
    parts = [_recording(s, 0.0) for s in range(4)]
    net = _seeded().fit_recordings(parts)
    assert net.window_axes == [] and net.networks_ == []
    from sins.compensation.fitting import _window_lines

    said, doc = _window_lines(net, "deg")
    assert (
        said[0].endswith("-> the networks are not used: least squares")
        and doc["window_guard"]["unit"] == "deg"
    )


def test_model_file_round_trip_and_a_damaged_network(tmp_path: Path) -> None:
    net = _seeded().fit_recordings([_recording(s, 0.01) for s in range(3)])
    path = tmp_path / "m.json"
    compensation.save(net, path)
    back = compensation.load(path)
    rec = _recording(7, 0.01)
    rates = ImuRates(t=rec.t, omega_ib_b=rec.gyro, f_ib_b=rec.accel)
    np.testing.assert_array_equal(back.correct_rates(rates).omega_ib_b, net.correct_rates(rates).omega_ib_b)
    doc = json.loads(path.read_text())
    if doc["state"]["networks_"]:
        doc["state"]["networks_"][0]["p0"] = [[0.0]]
        path.write_text(json.dumps(doc))
        refusal(lambda: compensation.load(path), str(path), "networks_[0].p0")


def test_parameters_out_of_bounds_are_refused() -> None:
    # The constructor keeps what it is given (scikit-learn's rule); check_params (make, fit, save and
    # load call it) refuses it.
    with pytest.raises(ValueError, match=r"^mlp_window: hidden is \(1000,\), expected a whole number"):
        WindowNet(hidden=(1000,)).check_params()
    with pytest.raises(ValueError, match=r"^mlp_window: hidden must be 1 to 3 layer sizes"):
        WindowNet(hidden=(8, 8, 8, 8)).check_params()
    with pytest.raises(ValueError, match="ensemble is 0, expected a whole number from 1 to 16"):
        WindowNet(ensemble=0).check_params()
    assert window_net.FEATURES == 8 * (len(EDGES_S) - 1)


def test_the_guard_over_recordings_judges_by_students_t(monkeypatch: pytest.MonkeyPatch) -> None:
    """Held back over three recordings, open-loop gains of 0.3, 0.1 and 0.2° are 3.46 standard errors of
    their mean: kept at 2, refused at 2 standard errors' level as Student's t over three (4.53, their
    spread estimated from them); gains of 0.21, 0.19 and 0.20° (34.6) are kept. The gains are set by hand
    (``_open_loop_gain``), the networks trained as they are."""
    parts = [_recording(s, 0.0) for s in range(3)]
    for gains, kept in (((0.3, 0.1, 0.2), False), ((0.21, 0.19, 0.20), True)):
        given = iter(gains)
        monkeypatch.setattr(WindowNet, "_open_loop_gain", lambda self, nets, rec, it=given: next(it))
        net = _seeded().fit_recordings(parts, recordings=[object()] * 3)  # type: ignore[list-item]
        assert net.held_back_gain_[0] == pytest.approx(0.2)
        assert (net.window_axes == ["x", "y", "z"]) is kept, (gains, net.window_axes)
