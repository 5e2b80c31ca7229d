"""Streamed corrupted runs (issue 20): the IMU model carried from chunk to chunk gives the whole array's
readings to the last bit, and ``sins run`` with an IMU model integrates them chunk by chunk, keeping only
what is bounded whatever the duration.

The references are independent of the streamed path: the whole array corrupted in one call, and the
whole-array run assembled here from the library's pieces (simulate, corrupt, correct, integrate,
compare), as ``sins run`` did before it streamed.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sins import compensation, scenario
from sins.core.series import ImuIncrements
from sins.imu import Quantization, QuantizationNoise, TimeOffset, spec
from sins.imu.stream import IncrementStream
from sins.nav import motion, trajectory
from sins.nav.metrics import BlockMeans, block_means
from sins.runs import pipeline

SEED = 20261125
D = np.radians

#: Every effect of the library on both sensors (typical sizes, twice) beside a tactical unit's baseline;
#: the time offsets and the accelerometers' quantization are added by hand (delays of either sign).
EVERY_EFFECT = (
    "gyro.scale_nonlinearity", "gyro.scale_asymmetry", "gyro.g2_sensitivity", "gyro.temperature_bias",
    "gyro.temperature_scale", "gyro.bias_instability", "gyro.rate_random_walk",
    "gyro.quantization", "accel.scale_nonlinearity", "accel.scale_asymmetry", "accel.temperature_bias",
    "accel.temperature_scale", "accel.size_effect", "accel.bias_instability",
    "accel.rate_random_walk", "accel.saturation",
)  # fmt: skip


def _drive(rate_hz: float = 100.0) -> tuple[ImuIncrements, np.ndarray]:
    """50 s of turning and accelerating (ideal increments) and a warming cabin."""
    car = motion.SegmentMotion.from_segments(
        motion.Start(lat=D(45.0), lon=D(7.6), h=250.0, yaw=D(30.0)),
        [
            motion.Hold(5),
            motion.Accelerate(10, delta_speed=15.0, ramp=2.0),
            motion.Turn(20, rate=D(30.0), ramp=1.0),
            motion.Climb(15, angle=D(5.0), ramp=2.0),
        ],
    )
    _, imu = trajectory.generate(car, rate_hz=rate_hz)
    return imu, np.linspace(10.0, 35.0, len(imu.t))


def _model(saturation_dps: float | None = None, delays_s: tuple[float, float] = (0.013, -0.007)):
    rng = np.random.default_rng(SEED)
    effects = [spec.typical_effect(name, rng, 2.0) for name in EVERY_EFFECT]
    effects += [TimeOffset("gyro", np.array([delays_s[0], 0.0, -0.002])),
                TimeOffset("accel", np.array([0.0, delays_s[1], 0.004]))]  # fmt: skip
    effects += [Quantization("accel", np.full(3, 2e-3))]
    effects += [QuantizationNoise("gyro", np.full(3, 5e-6)), QuantizationNoise("accel", np.full(3, 1e-4))]
    model = spec.draw_unit("tactical", 3).with_effects(*effects)
    if saturation_dps is not None:
        from sins.imu import Saturation

        model = model.with_effects(Saturation("gyro", np.full(3, D(saturation_dps))))
    return model


def _streamed(model, imu: ImuIncrements, temp: np.ndarray, sizes: list[int], seed: int = 7) -> ImuIncrements:
    stream = IncrementStream(model, seed, 0.01)
    parts, k = [], 0
    for size in sizes:
        end = min(len(imu), k + size)
        if end == k:
            break
        chunk = ImuIncrements(imu.t[k : end + 1], imu.dtheta_b[k:end], imu.dv_b[k:end])
        parts.append(stream.push(chunk, temp[k : end + 1]))
        k = end
    assert k == len(imu)
    parts.append(stream.finish())
    t = np.concatenate([parts[0].t] + [p.t[1:] for p in parts[1:] if len(p.t)])
    return ImuIncrements(t, np.vstack([p.dtheta_b for p in parts]), np.vstack([p.dv_b for p in parts]))


@pytest.mark.parametrize("saturation_dps", [None, 20.0])
def test_a_stream_in_chunks_of_any_size_reads_as_the_whole_array_to_the_last_bit(saturation_dps):
    """Chunks of 1 to 700 intervals, across delays of either sign (lead and lag), clipping, carried
    quantization, both random biases and the temperature: every reading equal, not merely close."""
    imu, temp = _drive()
    model = _model(saturation_dps)
    whole = model.corrupt_increments(imu, temp=temp, seed=7, dt_nominal=0.01)
    # The effects matter: the readings differ from the ideal ones by more than rounding.
    assert np.abs(whole.dtheta_b - imu.dtheta_b).max() > 1e-6
    rng = np.random.default_rng(SEED + 1)
    for sizes in ([1] * 40 + [len(imu)], list(rng.integers(1, 700, 200)), [len(imu) // 2, len(imu)]):
        out = _streamed(model, imu, temp, [int(s) for s in sizes])
        np.testing.assert_array_equal(out.t, imu.t)
        np.testing.assert_array_equal(out.dtheta_b, whole.dtheta_b)
        np.testing.assert_array_equal(out.dv_b, whole.dv_b)


def test_a_plain_unit_writes_each_chunk_at_once_and_reads_as_the_whole_array():
    """A unit of affine effects, random biases and white noise needs no neighbours: the stream keeps no
    margin, writes every interval of a chunk as it comes, and still reads as the whole array."""
    imu, temp = _drive()
    model = spec.draw_unit("tactical", 3)  # bias, scale/misalignment, g-sensitivity, noise, bias instability
    stream = IncrementStream(model, 7, 0.01)
    assert stream.margin() == 0 and IncrementStream(_model(), 7, 0.01).margin() > 0
    first = stream.push(ImuIncrements(imu.t[:11], imu.dtheta_b[:10], imu.dv_b[:10]), temp[:11])
    assert len(first) == 10
    whole = model.corrupt_increments(imu, temp=temp, seed=7, dt_nominal=0.01)
    assert np.abs(whole.dtheta_b - imu.dtheta_b).max() > 1e-6
    rng = np.random.default_rng(SEED + 3)
    for sizes in ([1] * 40 + [len(imu)], list(rng.integers(1, 700, 200))):
        out = _streamed(model, imu, temp, [int(s) for s in sizes])
        np.testing.assert_array_equal(out.dtheta_b, whole.dtheta_b)
        np.testing.assert_array_equal(out.dv_b, whole.dv_b)


def test_units_of_different_margins_driven_together_read_as_each_alone():
    """A task's units share the generated rows; a unit whose stream keeps a margin (a delayed channel)
    takes them later than a plain one, and each still gets its own run, to the last bit."""
    sc = scenario.load(pipeline.resolve_scenario("car_drive_5min"))
    plain = scenario.ImuSpec("tactical", 3, (), ())
    delayed = scenario.ImuSpec("tactical", 4, (TimeOffset("gyro", np.array([0.013, 0.0, -0.002])),), ())
    units = [pipeline.fit_unit(s, None) for s in (plain, delayed)]
    together = pipeline.run_units(sc, units, [5, 6], keep_hz=1.0)
    for unit, seed, run in zip(units, [5, 6], together, strict=True):
        alone = pipeline.run_units(sc, [unit], [seed], keep_hz=1.0)[0]
        assert run.runs.keys() == alone.runs.keys()
        for name, r in run.runs.items():
            assert r.summary == alone.runs[name].summary
            np.testing.assert_array_equal(r.errors.pos_ned_m, alone.runs[name].errors.pos_ned_m)
            np.testing.assert_array_equal(r.sensor_error, alone.runs[name].sensor_error)
    assert together[0].runs["none"].summary != together[1].runs["none"].summary


def test_the_ideal_imu_is_an_identity_unit_of_the_one_engine():
    """Without an IMU model the engine's one unit gives the ideal increments as they are: over four
    chunks its run is the whole-array integration of the exact ideal IMU (final and largest errors
    exactly, the RMS to the rounding of a sum taken in chunks, the kept states bit for bit), and driven
    beside a unit whose stream holds intervals back it is the same as alone."""
    sc = scenario.load(pipeline.resolve_scenario("car_drive_5min"))  # 30,000 samples, vertical damped
    assert sc.imu_model is None
    run = pipeline.run_scenario(sc, keep_hz=1.0)
    assert run.samples > 3 * trajectory.CHUNK and list(run.runs) == ["none"] and run.sensor_t is None
    truth, ideal = pipeline.simulate(sc)
    whole = pipeline.navigate(ideal, truth, sc.vertical, sc.vertical_tau_s)
    streamed = run.runs["none"]
    for field in dataclasses.fields(whole.summary):
        a, b = getattr(streamed.summary, field.name), getattr(whole.summary, field.name)
        if field.name.startswith("rms"):
            assert a == pytest.approx(b, rel=1e-12), field.name
        else:
            assert a == b, (field.name, a, b)
    kept = np.searchsorted(truth.t, streamed.solution.t)
    np.testing.assert_array_equal(streamed.solution.t, truth.t[kept])
    for name in ("lat", "lon", "h", "v_n", "q_nb"):
        np.testing.assert_array_equal(getattr(streamed.solution, name), getattr(whole.solution, name)[kept])
        np.testing.assert_array_equal(getattr(run.truth, name), getattr(truth, name)[kept])
    delayed = scenario.ImuSpec("tactical", 4, (TimeOffset("gyro", np.array([0.013, 0.0, -0.002])),), ())
    beside = pipeline.run_units(sc, [pipeline.fit_unit(delayed, None), None], [6, sc.imu_seed], keep_hz=1.0)
    assert beside[1].runs["none"].summary == streamed.summary and beside[1].sensor_t is None
    np.testing.assert_array_equal(beside[1].runs["none"].errors.pos_ned_m, streamed.errors.pos_ned_m)
    assert beside[0].runs["none"].summary.final_horizontal_m > 10.0  # the tactical unit drifts


def test_a_stream_refuses_chunks_that_do_not_follow_each_other():
    imu, temp = _drive()
    stream = IncrementStream(_model(), 1, 0.01)
    stream.push(ImuIncrements(imu.t[:11], imu.dtheta_b[:10], imu.dv_b[:10]), temp[:11])
    with pytest.raises(ValueError, match="follow each other"):
        stream.push(ImuIncrements(imu.t[12:21], imu.dtheta_b[12:20], imu.dv_b[12:20]), temp[12:21])
    with pytest.raises(ValueError, match="dt_nominal"):
        IncrementStream(_model(), 1, 0.0)


def test_block_means_fed_in_chunks_are_the_whole_arrays():
    rng = np.random.default_rng(SEED + 2)
    values = rng.normal(size=(1003, 4))
    acc = BlockMeans(10)
    k = 0
    for size in rng.integers(0, 37, 200):
        acc.add(values[k : k + size])
        k += size
    acc.add(values[k:])
    np.testing.assert_allclose(acc.means(), block_means(values, 10), rtol=1e-13, atol=1e-15)
    # Fed as parts less a reference over a step, without the rows being made: the same sums, bit for bit.
    ref, step = rng.normal(size=(1003, 4)), rng.uniform(0.5, 2.0, 1003)
    made, parts = BlockMeans(10), BlockMeans(10)
    for lo, hi in ((0, 5), (5, 5), (5, 438), (438, 1003)):
        made.add((values[lo:hi] - ref[lo:hi]) / step[lo:hi, None])
        parts.add_difference((values[lo:hi, :1], values[lo:hi, 1:]), ref[lo:hi], step[lo:hi])
    np.testing.assert_array_equal(parts.means(), made.means())


def _whole_array_run(
    sc: scenario.Scenario, strategies: dict[str, compensation.Strategy]
) -> dict[str, object]:
    """The run as ``sins run`` made it before it streamed: every array whole."""
    assert sc.imu_model is not None
    nav_model = scenario.load_imu(sc.imu_model).model(run_seed=sc.imu_seed)
    truth, ideal = pipeline.simulate(sc)
    temp = np.interp(ideal.t, *sc.temperature)
    corrupted = nav_model.corrupt_increments(ideal, temp=temp, seed=sc.imu_seed, dt_nominal=1.0 / sc.rate_hz)
    out = {}
    for name, strategy in strategies.items():
        corrected = strategy.correct_increments(corrupted, temp)
        out[name] = pipeline.navigate(corrected, truth, sc.vertical, sc.vertical_tau_s).summary
    return out


def test_sins_run_with_an_imu_model_streams_to_the_whole_arrays_final_errors(tmp_path):
    """The shipped drive's first 141 s at 100 Hz (over one chunk) with a tactical unit, regression
    fitted on a rig session and the oracle: the streamed run's final and largest errors are the whole-array
    run's exactly, its RMS to the rounding of a sum taken in chunks."""
    doc = scenario.read_toml(pipeline.resolve_scenario("car_drive_compensated"), "scenario")
    doc["segment"] = doc["segment"][:6]
    doc["compensation"]["strategies"] = ["none", "regression", "oracle"]
    sc = scenario.from_dict(doc, pipeline.resolve_scenario("car_drive_compensated"))
    run = pipeline.run_scenario(sc)
    assert run.samples > trajectory.CHUNK
    nav_model = scenario.load_imu(sc.imu_model).model(run_seed=sc.imu_seed)  # type: ignore[arg-type]
    strategies = {"none": compensation.make("none"), "oracle": compensation.Oracle(nav_model)}
    strategies["regression"] = _refit_regression(sc)
    reference = _whole_array_run(sc, strategies)
    for name, summary in reference.items():
        got = run.runs[name].summary
        for field in dataclasses.fields(summary):
            a, b = getattr(got, field.name), getattr(summary, field.name)
            if field.name.startswith(("final_", "max_", "duration", "drift")):
                assert a == b, (name, field.name, a, b)
            else:
                assert a == pytest.approx(b, rel=1e-12), (name, field.name)


def _refit_regression(sc: scenario.Scenario) -> compensation.Strategy:
    from sins.imu import calibration

    assert sc.compensation is not None and sc.imu_model is not None
    rig_model = scenario.load_imu(sc.imu_model).model(run_seed=sc.compensation.seed)
    data = calibration.simulate_rig(
        scenario.load_rig(sc.compensation.rig), rig_model, seed=sc.compensation.seed
    )
    fit, _ = data.split(sc.compensation.validation)
    return compensation.make("regression").fit(fit)


def test_a_long_runs_thinned_series_stay_bounded():
    """Six hours at 100 Hz keep no more than MAX_KEPT samples a series: memory does not grow with the
    duration (the summaries still use every sample)."""
    sc = scenario.from_dict(
        {
            "name": "six_hours",
            "imu": {"rate_hz": 100},
            "initial": {"lat_deg": 45.0, "lon_deg": 7.6, "alt_m": 250.0},
            "segment": [{"type": "hold", "duration_s": 6 * 3600.0}],
        }
    )
    run = pipeline.run_scenario(sc)
    assert run.samples == 6 * 3600 * 100
    assert len(run.truth.t) <= pipeline.MAX_KEPT + 2
    assert len(run.runs["none"].errors.t) <= pipeline.MAX_KEPT + 2


@pytest.mark.parametrize("keep_hz", [0.0, -1.0, float("nan")])
def test_a_rate_of_kept_samples_that_is_not_positive_is_refused_as_itself(keep_hz):
    # 0 divided by zero, -1 kept every sample, NaN was blamed on the scenario file ("cannot convert").
    hold = {"type": "hold", "duration_s": 5.0}
    sc = scenario.from_dict(
        {"name": "still", "imu": {"rate_hz": 10}, "initial": {"lat_deg": 45.0}, "segment": [hold]}
    )
    with pytest.raises(ValueError, match=r"^keep_hz .*: expected a positive rate of kept samples"):
        pipeline.run_scenario(sc, keep_hz=keep_hz)


def test_the_compiled_recursions_equal_the_array_code_they_replace():
    # Each compiled loop against the numpy/scipy code it replaced (written out here), to the last bit:
    # the same operations in the same order, so equal, not close.
    from scipy.signal import lfilter

    from sins.imu.numerics import ar1
    from sins.imu.stream import _gauss_markov_kernel, _reconstruct_own, _running_sum

    rng = np.random.default_rng(SEED)
    n = 5000
    dt = 0.01 * (1.0 + 1e-13 * rng.normal(size=n - 1))  # regular up to the time stamps' rounding
    tau, sigma = np.array([30.0, 300.0, 3000.0]), np.array([1e-6, 2e-5, 3e-4])
    xi = rng.normal(size=(n - 1, 3))
    phi = np.exp(-dt[:, None] / tau)
    start = sigma * rng.normal(size=3)
    # Regular samples: one coefficient a channel, scipy's linear filter.
    a = np.exp(-0.01 / tau)
    drive = sigma * np.sqrt(1.0 - a * a) * xi
    expected = np.empty((n, 3))
    expected[0] = start
    for i in range(3):
        expected[1:, i], _ = lfilter([1.0], [1.0, -a[i]], drive[:, i], zi=[a[i] * start[i]])
    out = np.empty((n, 3))
    out[0] = start
    _gauss_markov_kernel(np.zeros((0, 3)), sigma, xi, a, out)
    np.testing.assert_array_equal(out, expected)
    out[1:] = 0.0  # the whole-array path's recursion (sins.imu.numerics), fed the same drive
    ar1(a[None, :], drive, out, uniform=True)
    np.testing.assert_array_equal(out, expected)
    # Irregular samples: each interval's own coefficient, step by step.
    drive = sigma * np.sqrt(1.0 - phi * phi) * xi
    for k in range(1, n):
        expected[k] = phi[k - 1] * expected[k - 1] + drive[k - 1]
    _gauss_markov_kernel(phi, sigma, xi, np.zeros(0), out)
    np.testing.assert_array_equal(out, expected)
    # The quadratic reconstruction at a Gauss node, the array expressions of issue 20.
    mean = rng.normal(size=(n, 3)) * np.array([1e-3, 1.0, 1e3])
    steps = 0.01 + 1e-4 * rng.random(n)
    for s in (-0.5 / np.sqrt(3.0), 0.5 / np.sqrt(3.0)):
        for m in (mean, mean[:1], mean[:2]):
            prev, nxt = np.vstack([m[:1], m[:-1]]), np.vstack([m[1:], m[-1:]])
            slope, curve = 0.5 * (nxt - prev), 0.5 * (nxt - 2.0 * m + prev)
            if len(m) > 1:
                slope[0], slope[-1] = nxt[0] - prev[0], nxt[-1] - prev[-1]
                curve[0] = curve[-1] = 0.0
            value, rate = _reconstruct_own(m, steps[: len(m)], s)
            np.testing.assert_array_equal(value, m + slope * s + curve * (s * s - 1.0 / 12.0))
            np.testing.assert_array_equal(rate, (slope + 2.0 * curve * s) / steps[: len(m), None])
    # The running integral carried past trimmed intervals: a cumulative sum's last row.
    cum0 = rng.normal(size=3)
    np.testing.assert_array_equal(_running_sum(cum0, mean), np.cumsum(np.vstack([cum0, mean]), axis=0)[-1])


def test_an_affine_effect_integrated_on_the_increments_is_its_gauss_node_integral(
    monkeypatch: pytest.MonkeyPatch,
):
    # The quadratic through the neighbours' means keeps each interval's mean and the two-node Gauss rule
    # is exact for it, so an affine effect's integral is the effect applied to the ideal increments.
    # Forcing the affine effects through the nodes must give the same readings but for rounding: the
    # increments are up to ~5e-3 rad and ~0.1 m/s, a rounding of them ~1e-18 and ~1.4e-17 (measured
    # 8.7e-19 and 1.4e-17 apart; the errors integrated are up to 1.3e-5 rad and 4.7e-4 m/s).
    from sins.imu import effects as imu_effects

    imu, temp = _drive()
    unit = spec.draw_unit("tactical", 5)  # bias, scale/misalignment, g-sensitivity, noise, bias instability
    exact = unit.corrupt_increments(imu, temp, seed=3)
    for kind in (imu_effects.Bias, imu_effects.ScaleMisalignment, imu_effects.GSensitivity):
        monkeypatch.setattr(kind, "affine", False)
    at_nodes = unit.corrupt_increments(imu, temp, seed=3)
    np.testing.assert_allclose(exact.dtheta_b, at_nodes.dtheta_b, rtol=0, atol=1e-17)
    np.testing.assert_allclose(exact.dv_b, at_nodes.dv_b, rtol=0, atol=1e-16)
    assert not np.array_equal(exact.dtheta_b, imu.dtheta_b)  # there were errors to integrate
