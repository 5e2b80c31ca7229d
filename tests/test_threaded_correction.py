"""A learned strategy's correction solved a chunk of rows at a time, on threads, its maps keeping each
row's winner between the fixed point's passes: the whole array's figures (``ResidualStrategy.correct``)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from sins import compensation, imu
from sins.compensation import kohonen, residual
from sins.core.series import CalibrationData
from sins.imu import calibration
from sins.imu import spec as imu_spec

FAST = calibration.RigProcedure(
    positions=18,
    position_dwell_s=6.0,
    rate_table=calibration.RateTable(rates_dps=(20.0, 100.0, 200.0), dwell_s=3.0),
    temperature=calibration.TemperatureProfile((0.0, 400.0), (15.0, 35.0)),
)


@pytest.fixture(scope="module")
def fitted() -> dict[str, tuple[CalibrationData, Any]]:
    """A rig session of a tactical unit, and a map and a network fitted on an eighth of its rows."""
    fit = calibration.simulate_rig(FAST, imu_spec.draw_unit("tactical", 3, 103).only(*imu.BASELINE), seed=3)
    small = fit.rows(slice(0, len(fit), 8))
    options: dict[str, dict[str, Any]] = {"mlp": {"hidden_sizes": ((8, 8),)}, "kohonen": {"sizes": (5, 8)}}
    return {
        name: (fit, compensation.make(name, guard=False, n_jobs=1, **kwargs).fit(small))
        for name, kwargs in options.items()
    }


@pytest.mark.parametrize("name", ["kohonen", "mlp"])
def test_a_correction_in_chunks_on_threads_is_the_whole_array_searched_each_pass(
    name: str, fitted: dict[str, tuple[CalibrationData, Any]], monkeypatch: pytest.MonkeyPatch
):
    """A correction solves its fixed point a chunk of rows at a time, on two threads from a size on, and
    a map keeps each row's winner between passes while the row stays within half the gap between its
    nearest two nodes' distances. Readings beyond the rig's box (×1.3) take the edge extrapolation too.
    The maps (numpy alone): every reading equal to the whole array's with every winner searched on every
    pass. The networks: numpy's matrix product (OpenBLAS) picks its kernel by the number of rows (one
    row, a few, many round differently), and the rows extrapolated beyond the box are evaluated a
    handful at a time: within 1e-10 of the learned correction's size; one thread and two to the last
    bit."""
    fit, model = fitted[name]
    model.n_jobs = 1
    gyro = np.vstack([fit.gyro, 1.3 * fit.gyro])
    accel = np.vstack([fit.accel, fit.accel])
    temp = None if fit.temp is None else np.concatenate([fit.temp, fit.temp])

    searched = {"rows": 0}
    margins = kohonen._Map._winners_and_margins

    def counted(self, x):
        searched["rows"] += len(x)
        return margins(self, x)

    monkeypatch.setattr(kohonen._Map, "_winners_and_margins", counted)
    monkeypatch.setattr(residual, "CORRECT_ROWS", 1_000)
    monkeypatch.setattr(residual, "THREADED_ROWS", 2_000)
    one_thread = model.correct(gyro, accel, temp)
    model.n_jobs = None  # two threads: 117 chunks
    two_threads = model.correct(gyro, accel, temp)
    for a, b in zip(one_thread, two_threads, strict=True):
        np.testing.assert_array_equal(a, b)
    if name == "kohonen":
        # On each of the two corrections every row searched once a map (a chain over one input as a map
        # over several), on the first pass, and a few again after: winners were kept.
        maps = sum(len(model._learner(s).maps) for s in ("gyro", "accel"))
        assert maps > 0 and 2 * maps * len(gyro) < searched["rows"] < 1.2 * 2 * maps * len(gyro)

    monkeypatch.setattr(residual, "CORRECT_ROWS", 10**9)

    def searched_each_pass(self, x, memo):
        return self.winners(x[:, self.win_cols])

    monkeypatch.setattr(kohonen._Map, "_kept", searched_each_pass)
    whole = model.correct(gyro, accel, temp)
    base = model._base_strategy().correct(gyro, accel)
    for a, b, c in zip(one_thread, whole, base, strict=True):
        assert np.abs(b - c).max() > 1e-7 * np.abs(c).max()  # the learner acts, far beyond the tolerance
        if name == "kohonen":
            np.testing.assert_array_equal(a, b)
        else:
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * np.abs(b - c).max())


def test_a_correction_holds_blas_to_one_thread_beside_its_own(
    fitted: dict[str, tuple[CalibrationData, Any]], monkeypatch: pytest.MonkeyPatch
):
    """The chunks' threads are the correction's parallelism: numpy's BLAS inside each learner's
    prediction runs on one thread whatever the caller set (two here, as an unset environment gives on
    two cores), and the caller's setting is back afterwards."""
    fit, model = fitted["kohonen"]
    model.n_jobs = 2
    seen: list[int] = []
    add_to = kohonen._Map.add_to

    def counted(self, *args, **kwargs):
        seen.extend(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")
        return add_to(self, *args, **kwargs)

    monkeypatch.setattr(kohonen._Map, "add_to", counted)
    monkeypatch.setattr(residual, "CORRECT_ROWS", 1_000)
    with threadpool_limits(limits=2, user_api="blas"):
        model.correct(fit.gyro, fit.accel, fit.temp)
        after = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
    assert seen and set(seen) == {1}
    assert set(after) == {2}


def test_a_maps_two_nearest_nodes_are_scipys():
    """The compiled scan of every node (a correction's search up to ``_SCANNED_NODES`` nodes) against
    scipy's k-d tree: the same two nearest nodes and the same distances to the last bit, on 3 and 5
    inputs; where two nodes tie (a node given twice) the winner is the tree's own choice and the row is
    never kept (its margin below zero); a map of one node keeps every row."""
    from scipy.spatial import cKDTree

    rng = np.random.default_rng(5)
    for inputs in (3, 5):
        codebook = rng.normal(size=(144, inputs))
        x = 1.5 * rng.normal(size=(20_000, inputs))
        near, dist = kohonen._two_nearest(x, codebook)
        d, n = cKDTree(codebook).query(x, k=2)
        np.testing.assert_array_equal(near, n)
        np.testing.assert_array_equal(dist, d)
    codebook = np.vstack([codebook, codebook[:1]])  # node 144 ties with node 0
    one = kohonen._Map([0, 1, 2, 3, 4], [0], codebook, np.eye(len(codebook)), np.zeros((len(codebook), 2, 3)))
    x = codebook[:1] + 1e-3
    win, margin = one._winners_and_margins(x)
    assert win[0] == one.winners(x)[0] and margin[0] < 0.0
    single = kohonen._Map([0, 1], [0], np.zeros((1, 2)), np.eye(1), np.zeros((1, 2, 3)))
    win, margin = single._winners_and_margins(rng.normal(size=(10, 2)))
    assert np.all(win == 0) and np.all(np.isinf(margin))


def test_the_compiled_box_is_numpys_clip():
    """``residual._boxed``: numpy's two clips (to the reach beyond the rig's box, then to the box) and
    the rows where they differ, to the last bit; a NaN stays NaN and its row counts as beyond."""
    rng = np.random.default_rng(5)
    x = rng.normal(0.0, 2.0, (5_000, 4))
    x[7, 1], x[9, 3], x[11, 0] = np.nan, np.inf, -np.inf
    lo, hi = np.array([-1.0, -2.0, 0.0, -0.5]), np.array([1.0, 0.5, 3.0, 0.5])
    width = hi - lo
    reach, inside, beyond = residual._boxed(x, lo - 0.25 * width, hi + 0.25 * width, lo, hi)
    want_reach = np.clip(x, lo - 0.25 * width, hi + 0.25 * width)
    want_inside = np.clip(want_reach, lo, hi)
    np.testing.assert_array_equal(reach, want_reach)
    np.testing.assert_array_equal(inside, want_inside)
    np.testing.assert_array_equal(beyond, np.flatnonzero((want_reach != want_inside).any(axis=1)))
    assert 7 in beyond and 0 < len(beyond) < len(x)


class _Linear(residual.ResidualStrategy):
    """A learner that is a known linear map of its scaled inputs (``x @ A``): along every input its edge
    slope is the map's own, so its extrapolation beyond the box must give the map back."""

    def _candidates(self, sensor: str, n_inputs: int) -> list[dict[str, Any]]:
        return [{}]

    def _train(self, config: dict[str, Any], points: Any, sigma: Any, seed: int) -> Any:
        raise NotImplementedError

    def _predict(self, learner: Any, x: np.ndarray, memo: dict[str, Any] | None = None) -> np.ndarray:
        return np.asarray(x @ learner, dtype=float)

    def _learner_state(self, learner: Any) -> Any:
        return np.asarray(learner).tolist()

    def _learner_from_state(self, state: Any) -> Any:
        return np.asarray(state, dtype=float)


def test_beyond_the_box_a_learner_goes_on_along_each_inputs_edge_slope() -> None:
    """Beyond the rig's box a learner goes on along its edge slope for a quarter of the box's width, and
    holds from there. A linear learner's slope is its own everywhere, so a row beyond the box on one,
    two or three inputs reads the linear map at the reach (the row clipped to a quarter width beyond
    the box), to the difference's rounding. Each input's slope is taken at the box's edge: taken from a
    prediction already carried beyond the edge along another input, the second slope held the first
    reach over the difference's step (a thousandth of the width), and EuRoC's MH_03, landing at 3.4 g
    beyond a network's box on its three accelerometer inputs, read 6,000 m/s² of residual."""
    rng = np.random.default_rng(8)
    a = rng.normal(0.0, 0.01, (3, 3))
    lo, hi = np.array([0.1, -0.6, -1.6]), np.array([3.2, 0.5, 0.0])
    width = hi - lo
    model = _Linear()
    model.box_ = {"accel": [lo.tolist(), hi.tolist()]}
    model.learners_ = {"accel": a}
    inside = lo + width * rng.random((200, 3))
    x = inside.copy()
    x[50:100, 0] = hi[0] + 0.2 * width[0]  # beyond on one input, within reach
    x[100:150, :2] = hi[:2] + 0.2 * width[:2]  # on two
    x[150:, :] = lo - [0.1, 0.2, 0.24] * width  # on three
    x[150:160, 2] = lo[2] - 3.0 * width[2]  # ... and beyond the reach on one of them: held there
    reach = np.clip(x, lo - 0.25 * width, hi + 0.25 * width)
    got = model._residual("accel", x)
    np.testing.assert_allclose(got, reach @ a, rtol=0.0, atol=1e-12)
    assert np.abs(got[150:] - np.clip(x[150:], lo, hi) @ a).max() > 1e-3  # the rows did go on


@pytest.mark.parametrize("name", ["kohonen", "mlp"])
def test_a_learned_correction_says_where_it_reads_beyond_its_training_inputs(
    name: str,
    fitted: dict[str, tuple[CalibrationData, Any]],
    tmp_path: Any,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``beyond_box``: the readings at which a learner reads beyond the box of inputs it was trained on
    by more than a twentieth of its width (on its faces, the static holds at ±1 g, noise crosses it: 41 %
    of the rig's readings did, by a hair). The rig's own readings lie within it; at three times the
    rig's specific force every reading lies beyond (the box holds ±1 g at most), and so does every
    reading whose rate on an axis is more than 1.2 times the rig's fastest reference rate on it (the
    box's width on a rate is twice that rate: a twentieth of it is a tenth of the rate, and regression's
    scale takes a few per cent). A model without a learner reads none beyond. ``sins correct`` says so,
    and the line's count is the method's."""
    from sins.cli import main
    from sins.compensation import evaluation
    from sins.io import rig

    fit, model = fitted[name]
    own = model.beyond_box(fit.gyro, fit.accel, fit.temp)
    assert not own.any(), own.mean()
    fast = 3.0 * fit.gyro
    beyond = model.beyond_box(fast, 3.0 * fit.accel, fit.temp)
    assert beyond.all()
    beyond_rate = model.beyond_box(fast, fit.accel, fit.temp)
    outside = (np.abs(fast) > 1.2 * np.abs(fit.ref_gyro).max(axis=0)).any(axis=1)
    assert outside.any() and beyond_rate[outside].all()
    plain = compensation.make("regression").fit(fit.rows(slice(0, len(fit), 8)))
    assert not plain.beyond_box(fast, 3.0 * fit.accel).any()
    # Said by the command that applies it, with the method's count.
    shocked = fit.rows(slice(0, len(fit), 16))
    shocked = CalibrationData(
        t=shocked.t, gyro=shocked.gyro, accel=np.where(np.arange(len(shocked))[:, None] % 50 == 0,
                                                        3.0 * shocked.accel, shocked.accel),
        ref_gyro=shocked.ref_gyro, ref_accel=shocked.ref_accel, temp=shocked.temp, phases=shocked.phases,
    )  # fmt: skip
    rig.write_recording(tmp_path / "rig.csv", shocked)
    compensation.save(model, tmp_path / "m.json")
    assert main(["correct", str(tmp_path / "m.json"), str(tmp_path / "rig.csv"), "--out",
                 str(tmp_path / "c.csv")]) == 0  # fmt: skip
    n = int(model.beyond_box(shocked.gyro, shocked.accel, shocked.temp).sum())
    assert n >= len(shocked) // 50
    said = evaluation.BEYOND_TRAINING.split("{n}")[0] + f"{n} readings"
    assert said in capsys.readouterr().out


def test_the_seed_papers_map_corrects_as_numpys_nearest_nodes_do() -> None:
    """``kohonen_pure``'s correction, compiled and on two threads from 65,536 rows: each reading less the
    inverse-distance mean of its four nearest nodes' errors. Against numpy's brute force written here
    (every node's distance, sorted): equal to the last bit, on both paths (a few rows and 70,000)."""
    fit = calibration.simulate_rig(FAST, imu_spec.draw_unit("consumer", 3, 104), seed=4)
    model = compensation.make("kohonen_pure", rows=8, cols=8, iterations=5000)
    model.fit(fit.rows(slice(0, None, 4)))
    rng = np.random.default_rng(9)
    rows = rng.integers(0, len(fit), 70_000)
    gyro = fit.gyro[rows] * rng.uniform(0.5, 1.5, (len(rows), 1))
    accel = fit.accel[rows] + rng.normal(0.0, 0.5, (len(rows), 3))
    xs = (np.hstack([gyro, accel]) - model.x_mean_) / model.x_scale_
    d = np.sqrt(((xs[:, None, :] - model.codebook_[None, :, :]) ** 2).sum(axis=2))
    near = np.argsort(d, axis=1, kind="stable")[:, :4]
    w = 1.0 / np.maximum(np.take_along_axis(d, near, axis=1), 1e-9)
    err = (w[:, :, None] * model.node_error_[near]).sum(axis=1) / w.sum(axis=1)[:, None]
    for n in (50, len(rows)):  # one thread, then two on halves
        g, a = model.correct(gyro[:n], accel[:n])
        np.testing.assert_array_equal(g, gyro[:n] - err[:n, :3])
        np.testing.assert_array_equal(a, accel[:n] - err[:n, 3:])
