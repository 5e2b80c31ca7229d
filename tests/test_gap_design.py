"""The gap diagnosis a chunk of rows at a time (issue 32): what it computes per chunk equals what numpy
and scipy compute on the whole arrays, and a diagnosis cut into small chunks is the diagnosis of one.

Chunks are made small here (a few hundred rows) so that every reduction crosses many chunk boundaries
on short series; the oracles are numpy's ``lstsq`` and SVD, scipy's ``lfilter``, ``PPoly`` and FFT on
the whole arrays.
"""

from __future__ import annotations

import numpy as np
import numpy_gap as ng
import pytest

from sins.core.series import CalibrationData
from sins.gap import candidates, channel, design, diagnose, disturbance, lattice, randombias
from sins.gap.design import Design, Projection
from sins.imu.numerics import hermite_slopes


@pytest.fixture
def small_chunks(monkeypatch: pytest.MonkeyPatch) -> int:
    monkeypatch.setattr(candidates, "CHUNK_ROWS", 337)
    return 337


def _columns(n: int, rng: np.random.Generator) -> np.ndarray:
    """A bias, two inputs of very different size, their product, and a column that is a combination of
    two others to rounding (a rank numpy's cut-off drops)."""
    t = np.linspace(0.0, 1.0, n)
    u = np.column_stack([np.ones(n), 1e-4 * np.sin(7.0 * t), 30.0 * rng.standard_normal(n)])
    return np.column_stack([u, u[:, 1] * u[:, 2], 2.0 * u[:, 0] - 3e4 * u[:, 1]])


def test_chunked_least_squares_is_numpys_on_the_whole(small_chunks: int):
    """Coefficients, predictions and residuals of the stacked QR factor against ``numpy.linalg.lstsq``
    on the whole rows: the same to rounding (1e-9 of the coefficients' size, the rank-deficient
    direction dropped alike), with numpy's default cut-off and with ``rcond=1e-3``."""
    rng = np.random.default_rng(0)
    n = 5_000
    a = _columns(n, rng)
    rows = rng.random(n) < 0.7
    y = a[:, :4] @ np.array([1.0, 2e3, 0.01, 5.0]) + 0.1 * rng.standard_normal(n)
    design = Design.from_array(a)
    scale = np.abs(a[rows]).max(axis=0)
    np.testing.assert_array_equal(design.scaled(rows).scale, scale)
    for rcond in (None, 1e-3):
        ours, found = design.lstsq(y, rows, rcond)
        np.testing.assert_array_equal(found, scale)  # the same pass finds the scale
        numpys, *_ = np.linalg.lstsq(a[rows] / scale, y[rows], rcond=rcond)
        np.testing.assert_allclose(ours, numpys, rtol=0, atol=1e-9 * np.abs(numpys).max())
        np.testing.assert_allclose(
            design.scaled_by(found).predict(ours), (a / scale) @ numpys, rtol=1e-9, atol=1e-9
        )
    projection = Projection.of(design, rows)
    left = y[rows] - (a[rows] / scale) @ np.linalg.lstsq(a[rows] / scale, y[rows], rcond=None)[0]
    assert projection.residual(y) == pytest.approx(left @ left, rel=1e-8)
    scaled = design.scaled_by(scale)
    np.testing.assert_allclose(scaled.gram(~rows), (a[~rows] / scale).T @ (a[~rows] / scale), rtol=1e-12)
    factor = design.factor(rows, gram_rows=~rows)
    np.testing.assert_allclose(factor.gram, a[~rows].T @ a[~rows], rtol=1e-12)


def test_whitened_least_squares_filters_every_column_over_every_row(small_chunks: int):
    """Generalised least squares beside a random bias: each column and the target through
    :func:`randombias.innovations` (scipy's ``lfilter`` over all rows, from the mean of the first 100),
    then least squares on the chosen rows. The filter's state carried across chunks gives the
    whole-array filter's values, so the coefficients are numpy's to rounding."""
    rng = np.random.default_rng(1)
    n = 4_000
    a = _columns(n, rng)[:, :4]
    rows = np.arange(n) % 100 < 70
    y = (
        np.cumsum(rng.standard_normal(n)) * 0.05
        + a @ np.array([1.0, 3e3, 0.02, 1.0])
        + rng.standard_normal(n)
    )
    phi, gain = 1.0, 0.05
    design = Design.from_array(a).scaled(rows)
    whitened = np.column_stack([randombias.innovations(c, phi, gain) for c in (a / design.scale).T])
    numpys, *_ = np.linalg.lstsq(whitened[rows], randombias.innovations(y, phi, gain)[rows], rcond=None)
    ours = design.whitened_lstsq(y, rows, None, phi, gain)
    np.testing.assert_allclose(ours, numpys, rtol=0, atol=1e-9 * np.abs(numpys).max())


def test_the_random_bias_grid_sums_are_lfilters():
    """The compiled pass over every filter of a grid: each filter's sum of squared innovations on the
    chosen rows, per group, is that of scipy's ``lfilter`` innovations to 1e-12."""
    rng = np.random.default_rng(2)
    n = 20_000
    y = np.cumsum(rng.standard_normal(n)) * 0.01 + rng.standard_normal(n)
    rows = rng.random(n) < 0.7
    group = (np.arange(n) * 4) // n
    filters = [(phi, randombias.steady_gain(phi, q, 1.0)[0]) for phi in (1.0, 0.99) for q in (1e-6, 1e-2)]
    ours = randombias._grid_sums(y, rows, filters, group)
    for g, (phi, gain) in enumerate(filters):
        nu = randombias.innovations(y, phi, gain)
        for k in range(4):
            part = rows & (group == k)
            assert ours[g, k] == pytest.approx(float(nu[part] @ nu[part]), rel=1e-12)


def test_the_delayed_reference_is_the_whole_curve_to_the_last_bit(small_chunks: int):
    """:meth:`ReferenceInputs.lag`, evaluated a chunk at a time on that chunk's pieces of the curve,
    against the whole curve (:func:`candidates.kinked_hermite`) on a table's rate whose kinks fall on
    rows, a few of them at chunk boundaries, for delays within a row, of several rows, on a
    breakpoint and negative: equal, bit for bit. The kinks found a chunk at a time are those
    :func:`sins.imu.numerics.hermite_slopes` finds on the whole."""
    t = np.arange(4_000) / 50.0
    knots = [0.0, 6.74, 13.48, 20.0, 33.7, 40.0, 67.4, 70.0, 79.98]  # 6.74 s = row 337: a boundary
    u = np.interp(t, knots, [0.0, 0.0, 2.0, 2.0, -1.0, -1.0, 3.0, 0.0, 0.0])
    ref = np.column_stack([u, 0.5 * u, np.sin(t)])
    data = CalibrationData(t=t, gyro=ref, accel=ref, ref_gyro=ref, ref_accel=ref)
    x = candidates.reference_inputs(data)
    right, left = hermite_slopes(t, ref, np.gradient(ref, t, axis=0))
    kinks = x.kinks["gyro", 0]
    np.testing.assert_array_equal(right[kinks.rows, 0], kinks.right)
    assert set(kinks.rows) == set(
        np.flatnonzero((right[:, 0] != x.rate("gyro")[:, 0]) | (left[:, 0] != x.rate("gyro")[:, 0]))
    )
    assert {336, 337, 338} & set(kinks.rows)
    for axis in range(3):
        whole = candidates.kinked_hermite(t, ref[:, axis], x.rate("gyro")[:, axis])
        for tau in (1e-3, 0.02, 0.0731, -0.013, 0.0):
            expected = whole(np.clip(t - tau, t[0], t[-1])) - ref[:, axis]
            np.testing.assert_array_equal(x.lag("gyro", axis, tau), expected)


def test_the_delayed_reference_on_uneven_times_is_scipys_to_the_last_bit(small_chunks: int):
    """The same on a recording whose rows are unevenly spaced (a jitter of ±30 % of a step, and a gap of
    two seconds where rows were lost): each row's interval is stepped from its neighbour's where a few
    steps settle it and searched where they do not (across the gap), and the values are still the whole
    curve's (scipy's ``PPoly``) bit for bit, for delays within a row, of many rows, across the gap and
    negative."""
    rng = np.random.default_rng(7)
    step = np.full(3_000, 0.02) * (1.0 + 0.3 * rng.uniform(-1.0, 1.0, 3_000))
    step[1_500] = 2.0  # rows lost
    t = np.cumsum(step)
    ref = np.column_stack([np.sin(0.7 * t), np.cos(1.3 * t) + 0.1 * t, rng.standard_normal(3_000)])
    data = CalibrationData(t=t, gyro=ref, accel=ref, ref_gyro=ref, ref_accel=ref)
    x = candidates.reference_inputs(data)
    for axis in range(3):
        whole = candidates.kinked_hermite(t, ref[:, axis], x.rate("gyro")[:, axis])
        curve = x.curve("gyro", axis)
        for tau in (3e-3, 0.0173, 0.9, 2.5, -0.041, -1.7):
            expected = whole(np.clip(t - tau, t[0], t[-1])) - ref[:, axis]
            np.testing.assert_array_equal(curve.lag(tau), expected)
            np.testing.assert_array_equal(x.lag("gyro", axis, tau), expected)


@pytest.mark.parametrize("made", ["a chunk at a time", "whole"])
def test_the_delayed_inputs_of_a_chunk_are_the_whole_delayed_inputs_to_the_last_bit(
    small_chunks: int, made: str
):
    """The inputs at ``t − τ`` a delayed channel's columns are built from
    (:class:`candidates.DelayedInputs`), made a chunk of rows at a time (what a model keeps) and whole
    (for one fit's passes), against the same made whole here: the reference plus scipy's ``PPoly``
    lag of every axis, and their rates of change ``central_differences`` of those whole arrays (and
    numpy's ``gradient``, whose formulas it writes out, to rounding), on uneven rows with a
    temperature; chunks that start and end anywhere, one of a single row at each end. Equal, bit for
    bit."""
    rng = np.random.default_rng(11)
    n = 2_023  # 6 × 337 + 1: the last chunk of the diagnosis's own spans is one row
    t = np.cumsum(np.full(n, 0.01) * (1.0 + 0.2 * rng.uniform(-1.0, 1.0, n)))
    omega = np.column_stack([np.sin(0.9 * t), np.cos(2.1 * t), 0.3 * rng.standard_normal(n)])
    force = np.column_stack([9.8 * np.cos(0.4 * t), rng.standard_normal(n), np.sin(3.0 * t)])
    temp = 20.0 + 0.01 * t
    data = CalibrationData(t=t, gyro=omega, accel=force, ref_gyro=omega, ref_accel=force, temp=temp)
    x = candidates.reference_inputs(data)
    tau = 0.0237
    late = channel.delayed_inputs(x, tau)
    late = late.whole() if made == "whole" else late
    whole = {}
    for sensor, u in (("gyro", omega), ("accel", force)):
        curves = [candidates.kinked_hermite(t, u[:, j], x.rate(sensor)[:, j]) for j in range(3)]
        # the reference plus its lag, as the diagnosis forms them (not the curve's value alone)
        lagged = u + np.column_stack(
            [c(np.clip(t - tau, t[0], t[-1])) - u[:, j] for j, c in enumerate(curves)]
        )
        whole[sensor] = lagged, candidates.central_differences(lagged, t), np.gradient(lagged, t, axis=0)
    for lo, hi in [(0, 1), (0, 337), (336, 1_000), (1_000, 2_022), (2_022, 2_023), (5, 6), (0, n)]:
        part = late.rows(lo, hi)
        np.testing.assert_array_equal(part.t, t[lo:hi])
        np.testing.assert_array_equal(part.temp, temp[lo:hi])
        for sensor in ("gyro", "accel"):
            lagged, rate, numpys = whole[sensor]
            np.testing.assert_array_equal(part.of(sensor), lagged[lo:hi])
            np.testing.assert_array_equal(part.rate(sensor), rate[lo:hi])
            np.testing.assert_allclose(part.rate(sensor), numpys[lo:hi], rtol=1e-9, atol=1e-9)


def test_a_step_and_a_hum_are_found_alike_in_chunks(small_chunks: int):
    """A bias step's time and size and an oscillation's period and amplitude, from chunked suffix sums
    and eight transforms of the unpadded series, against the same from whole arrays with one chunk:
    the step's time exactly, its size and the hum's period and amplitude to 1e-9."""
    rng = np.random.default_rng(3)
    n = 6_000
    t = np.arange(n) * 0.1
    rows = np.arange(n) % 1000 < 700
    a = np.column_stack([np.ones(n), np.sin(2 * np.pi * t / t[-1])])
    y = 0.4 * (t > 222.2) + 0.3 * np.sin(2 * np.pi * t / 37.0) + rng.standard_normal(n)
    y -= a @ np.linalg.lstsq(a[rows], y[rows], rcond=None)[0]
    chunked = disturbance.best_step(y, a, rows, t), disturbance.best_oscillation(y, a, rows, t)
    candidates.CHUNK_ROWS = 1 << 20  # the monkeypatch restores it
    whole = disturbance.best_step(y, a, rows, t), disturbance.best_oscillation(y, a, rows, t)
    assert chunked[0][0] == whole[0][0]
    np.testing.assert_allclose(chunked[0][1], whole[0][1], rtol=1e-9)
    np.testing.assert_allclose(chunked[1], whole[1], rtol=1e-9)
    # The periodogram's peak against numpy's rfft of the series padded eightfold.
    x = np.where(rows, y - y[rows].mean(), 0.0)
    power = np.abs(np.fft.rfft(x, 8 * n)) ** 2
    freq = np.fft.rfftfreq(8 * n, 0.1)
    power[freq < 3.0 / t[-1]] = 0.0
    assert disturbance._periodogram_peak(x, 0.1, 3.0 / t[-1]) == pytest.approx(
        freq[np.argmax(power)], rel=1e-12
    )


def test_a_diagnosis_in_small_chunks_is_the_diagnosis_in_one(monkeypatch: pytest.MonkeyPatch):
    """A five-minute numpy-written recording (a 3 ms accelerometer delay on a tumbling rig, 50 Hz,
    15,000 rows) diagnosed in chunks of 337 rows and in one: the same verdicts and candidates, every
    channel's figures to 1e-9 and every score to 1e-6 nats (rounding in the stacked factors and the
    sums)."""
    built = ng.build(ng.Case("accel.time_offset", 0, "continuous_tumble", 50.0, 5.0, "cycle", 3.0))
    s = built.proc.session
    data = CalibrationData(
        t=s.t, gyro=built.gyro, accel=built.accel, ref_gyro=s.ref_gyro, ref_accel=s.ref_accel, temp=s.temp
    )
    one = diagnose(data, holdout=ng.HOLDOUT)
    monkeypatch.setattr(candidates, "CHUNK_ROWS", 337)
    many = diagnose(data, holdout=ng.HOLDOUT)
    assert many.diagnosis == one.diagnosis == ["accel.time_offset"]
    assert many.unexplained == one.unexplained and len(many.outside) == len(one.outside)
    for ch, figures in one.channels.items():
        for key, value in figures.items():
            assert many.channels[ch][key] == pytest.approx(value, rel=1e-9), (ch, key)
    assert [e.name for e in many.effects] == [e.name for e in one.effects]
    for a, b in zip(many.effects, one.effects, strict=True):
        assert a.score == pytest.approx(b.score, abs=1e-6), a.name
    np.testing.assert_allclose(many.predicted_after, one.predicted_after, rtol=0, atol=1e-9)
    assert many.rows == one.rows


def test_the_print_habit_probes_the_values_a_concatenation_would():
    """:func:`lattice.print_habit` reads every ``k``-th finite nonzero value of the file's columns one
    after another; picked column by column in place, they are the same values as from the columns
    concatenated (NaN, zeros and columns of nothing but zeros among them)."""
    rng = np.random.default_rng(4)
    columns = (
        rng.standard_normal((5_000, 3)).round(4),
        np.where(rng.random((7_001, 3)) < 0.1, 0.0, rng.standard_normal((7_001, 3))),
        np.full((100, 3), np.nan),
        np.zeros((10, 3)),
        rng.standard_normal(3_333),
    )
    values = np.concatenate([np.ravel(c) for c in columns])
    values = values[np.isfinite(values) & (values != 0.0)]
    np.testing.assert_array_equal(lattice._probe(columns), values[:: len(values) // lattice._HABIT_PROBE])
    assert lattice.print_habit(*columns) == lattice.Printed(None, None)
    assert lattice.print_habit(columns[0]) == lattice.Printed(5, 4)  # four decimals of values up to ±5


def test_the_baseline_block_of_a_chunk_is_the_baseline_columns():
    """The baseline's columns as a chunk's design builds them (filled a sensor at a time) are
    :func:`candidates.baseline_columns`' of the same rows, to the bit."""
    rng = np.random.default_rng(5)
    t = np.arange(500) / 100.0
    w, f = rng.standard_normal((500, 3)), rng.standard_normal((500, 3))
    x = candidates.reference_inputs(CalibrationData(t=t, gyro=w, accel=f, ref_gyro=w, ref_accel=f))
    for sensor in ("gyro", "accel"):
        part = x.rows(123, 456)
        np.testing.assert_array_equal(
            channel._baseline_block(sensor, part), candidates.baseline_columns(sensor, w[123:456], f[123:456])
        )


def test_free_memory_is_handed_back_once_the_heap_holds_more_than_its_threshold(monkeypatch):
    """``release_free_memory`` trims glibc's heap only past ``TRIM_ABOVE_BYTES`` free (what trimming
    after every fit cost is the next arrays' pages again), and trims as before where ``mallinfo2`` is
    missing (glibc before 2.33); on this machine's glibc the heap's own figure is read."""
    trims: list[int] = []

    class Libc:
        def malloc_trim(self, pad: int) -> int:
            trims.append(pad)
            return 1

    class Info:
        fordblks = design.TRIM_ABOVE_BYTES - 1

    monkeypatch.setattr(design, "_LIBC", Libc())
    monkeypatch.setattr(design, "_MALLINFO2", Info)
    design.release_free_memory()
    assert trims == []
    Info.fordblks = design.TRIM_ABOVE_BYTES + 1
    design.release_free_memory()
    assert trims == [0]
    monkeypatch.setattr(design, "_MALLINFO2", None)
    design.release_free_memory()
    assert trims == [0, 0]
    monkeypatch.undo()
    if design._MALLINFO2 is not None:  # glibc 2.33 or later: the struct reads as glibc fills it
        info = design._MALLINFO2()
        assert 0 < info.uordblks <= info.arena and info.fordblks <= info.arena
