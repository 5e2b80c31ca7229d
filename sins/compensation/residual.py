"""Physics first, then learning: the machinery shared by the learned strategies ``mlp`` and ``kohonen``.

A learned strategy here starts from the seed model's least-squares fit
(:class:`~sins.compensation.Regression`), adds the physics terms each
channel's held-back blocks ask for (:mod:`sins.compensation.terms`), and learns
only what those leave: the residual ``x̂ − x_ref`` of the regression-corrected
readings ``x̂`` against the rig's reference, less the terms. Consequences, each a
reason for the design:

* **Inputs are the reference, not the readings.** The residual is learned as a
  function of the rig's reference inputs (noise-free), so a learner cannot
  predict the readings' own noise from the readings (the pure networks do,
  and what they learn that way does not carry to another rig). In operation
  the inputs are the regression-corrected readings, whose noise is 1e-4 of
  the inputs' range.
* **Inputs the error depends on**, scaled by their physical range: the gyros'
  residual is a function of ``(ω, f, T)``, the accelerometers' of ``(f, T)``;
  ``ω`` by the largest rate the rig turned at (one scale for the three axes,
  at least 1 °/s), ``f`` by ``G0``, ``T`` by half the temperature span
  (temperature is an input only where the data span 2 °C or more). Outside
  the box the rig covered a learner goes on along its edge slope for a
  quarter of the box, and holds beyond (``_residual``).
* **Points, not rows.** The learners train on averaged points of the reference inputs and the
  residual, one per fine input cell and time block, and on runs of rows where the residual repeats
  one draw (:mod:`sins.compensation.points`).
* **Capacity chosen by data.** The session is cut into blocks of like input (a new block where the
  coarse reference input changes, at least 1 s and at most 20 s long), dealt at random (``seed``) into
  ``folds`` folds; several recordings fitted together are each a fold instead. For each fold the
  regression is refitted on the others, every candidate learner trained on their residuals and scored
  on the fold's: the held-back blocks are orientations, rates and temperatures (or a recording) the
  learner did not see. An iterative learner is trained on all folds side by side and scored after each
  training length; it stops once ``PATIENCE`` lengths in a row have not lowered its held-back loss
  summed over the folds (longer training then fits the training folds' noise closer: the lengths it
  would have gone on to are not chosen unless the held-back loss turns down again after rising twice).
* **An honest guard.** Per channel, the chosen learner's held-back gain over regression and the terms
  (sum of squared residuals) is compared with its sampling error over the held-back blocks, or, where
  the folds are recordings, over the recordings (a new recording is the draw a model meets; blocks of
  one recording share its day, its motion and its reference, and their spread had passed a learner that
  gained on one of three recordings and lost on the other two), ``guard_z`` then as Student's t over
  them; a channel not above it predicts their correction (unless ``guard=False``). The terms pass the
  same test against regression alone (at ``guard_z`` itself).

Subclasses supply the learner: its candidate settings, training and prediction.
"""

from __future__ import annotations

import time
from abc import abstractmethod
from collections.abc import Callable, Generator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, ClassVar

import numba
import numpy as np
from numpy.typing import NDArray
from threadpoolctl import threadpool_limits

from sins.compensation import terms
from sins.compensation.base import (
    GUARD_Z_RANGE,
    SEED_RANGE,
    ParamRange,
    Strategy,
    recordings_threshold,
    state_array,
    sum_standard_error,
)
from sins.compensation.points import (
    MIN_REPEATS,
    Points,
    aggregate,
    block_gains,
    held_loss,
    input_columns,
    repeats,
    segment,
)
from sins.compensation.regression import Regression
from sins.core import earth
from sins.core.series import CalibrationData
from sins.imu import CHANNELS
from sins.imu.vocabulary import SENSORS

Array = NDArray[np.float64]

_MIN_RATE_SCALE = np.radians(1.0)
_MIN_TEMP_SPAN = 2.0
#: The one-sided difference that gives a learner's edge slope, as a fraction of the box: small enough to
#: stay within the edge node of a map whose data sit on the box's face (static holds at ±1 g).
EDGE_STEP = 1e-3
#: ``beyond_box``'s share of the box's width (on its face, a static hold at ±1 g, noise crosses it).
BEYOND_SAID = 0.05
#: Fixed-point passes of a correction after the first (see ``correct``).
_PASSES = 2
#: Rows a correction solves at a time, chunk by chunk (each step is row by row): a few MB whatever its length.
CORRECT_ROWS = 65_536
#: The rows from which a correction solves its chunks on two threads by default (``n_jobs=None``): numpy,
#: the maps' compiled kernels and scipy's k-d tree let go of the GIL for a chunk's work; below a few
#: chunks a thread pool costs more than it brings.
THREADED_ROWS = 4 * CORRECT_ROWS
#: The points a fold trains on from which the cross-validation's candidates train on two threads by
#: default (``n_jobs=None``). The trainings' Python steps hold the GIL between small torch and numpy
#: calls, so two threads pay off only where each call has enough rows to work on: ``mlp`` on a rig
#: (``tools/bench_compensation.py --jobs 2 1``, medians, 2 cores) with about 2,300 points a fold took the
#: same wall time on two threads for 1.5× the CPU; with 4,800, 30 % less wall time for 1.2× the CPU;
#: with 7,100, 37 % less for 1.05×.
THREADED_POINTS = 4_000
#: A candidate's cross-validation stops after this many stages of training in a row that did not lower
#: its held-back loss (see ``_cross_validate``).
PATIENCE = 2


@numba.njit(cache=True, nogil=True)
def _boxed(
    x: Array, reach_lo: Array, reach_hi: Array, lo: Array, hi: Array
) -> tuple[Array, Array, NDArray[np.intp]]:  # pragma: no cover  (compiled)
    """``reach = clip(x, reach_lo, reach_hi)``, ``inside = clip(reach, lo, hi)`` (numpy's ``clip``: a
    NaN stays NaN) and the rows where they differ, in one pass over the rows (a correction asks this of
    every row on every pass; numpy's two clips and comparison took an eighth of it)."""
    n, d = x.shape
    reach, inside = np.empty((n, d)), np.empty((n, d))
    out = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        for j in range(d):
            v = x[i, j]
            if v < reach_lo[j]:
                v = reach_lo[j]
            elif v > reach_hi[j]:
                v = reach_hi[j]
            reach[i, j] = v
            if v < lo[j]:
                v = lo[j]
            elif v > hi[j]:
                v = hi[j]
            inside[i, j] = v
            if v != reach[i, j]:
                out[i] = True
    return reach, inside, np.flatnonzero(out)


def _columns(sensor: str, x: terms.TermInputs) -> Array:
    """:func:`input_columns` of scaled inputs."""
    return input_columns(sensor, x.w, x.f, x.t)


@dataclass(frozen=True)
class _Job:
    """A candidate setting of one sensor to cross-validate: per fold its training and held-back points
    and its seed; ``sigma`` the sensor's residual scale."""

    sensor: str
    config: dict[str, Any]
    folds: list[tuple[Points, Points, int]]
    sigma: Array

    def loss(self, preds: list[Array]) -> float:
        """The held-back loss of one prediction per fold, summed over the folds."""
        return sum(held_loss(held, p, self.sigma) for (_, held, _), p in zip(self.folds, preds, strict=True))


class _Trial:
    """A candidate setting's held-back record: its weighted loss, and per held-back block and channel
    the gain over regression and regression's own sum of squares."""

    def __init__(self, config: dict[str, Any]) -> None:
        self.config = config
        self.score = 0.0
        self.gains: list[Array] = []
        self.base: list[Array] = []

    def add(self, held: Points, pred: Array, sigma: Array) -> None:
        self.score += held_loss(held, pred, sigma)
        gain, base = block_gains(held, pred)
        self.gains.append(gain)
        self.base.append(base)

    def verdicts(self, z: float, by_fold: bool = False) -> list[dict[str, Any]]:
        """Per channel: the gain and its standard error as fractions of regression's sum of squares,
        and whether the gain is above ``z`` of them: the held-back blocks taken as independent draws, or
        (``by_fold``) the recordings, each its blocks' sum, ``z`` then as Student's t over them."""
        base, z = np.vstack(self.base), recordings_threshold(z, len(self.gains)) if by_fold else z
        gains = np.array([g.sum(axis=0) for g in self.gains]) if by_fold else np.vstack(self.gains)
        out = []
        for c in range(gains.shape[1]):
            total, base_sse = float(gains[:, c].sum()), float(base[:, c].sum())
            se = float(sum_standard_error(gains[:, c]))
            out.append({
                "gain_fraction": total / base_sse if base_sse > 0 else 0.0,
                "gain_se_fraction": se / base_sse if base_sse > 0 else 0.0,
                "earns_its_place": bool(total > z * se),
            })  # fmt: skip
        return out


def _with_reference(recordings: NDArray[np.intp], data: CalibrationData) -> NDArray[np.intp]:
    """The recording of each row of ``data`` that has a reference; ``ValueError`` for another length."""
    if np.shape(recordings) != (len(data),):
        raise ValueError(f"recordings: {len(recordings)} rows; the data have {len(data)}")
    return np.asarray(recordings)[data.has_reference]


class ResidualStrategy(Strategy):
    """Regression first, then a learner of what it leaves (see the module docstring).

    Parameters
    ----------
    folds : cross-validation folds over the session's blocks
    guard : fall back to regression on channels where the learner does not earn its place
    guard_z : standard errors the held-back gain must exceed
    seed : fold assignment and the learner's own randomness
    physics : first fit each channel the physics terms (:mod:`sins.compensation.terms`) that earn their
        place on the held-back blocks, and learn what they leave
    n_jobs : threads that train the cross-validation's candidates side by side, and that correct a
        recording's chunks of :data:`CORRECT_ROWS` rows; None: two where a fold trains on
        :data:`THREADED_POINTS` points or more, or a recording has :data:`THREADED_ROWS` rows or more,
        else one. The results do not depend on it (each training is sequential and seeded on its own,
        each row corrected alone), so it is not saved with the model
    """

    param_ranges: ClassVar[dict[str, ParamRange]] = {
        "folds": ParamRange(2, 50, whole=True), "guard_z": GUARD_Z_RANGE, "seed": SEED_RANGE,
        "n_jobs": ParamRange(1, 256, whole=True, none=True)}  # fmt: skip
    state_keys = Strategy.state_keys + tuple(
        "base_ uses_temp_ scaling_ box_ blocks_ cv_folds_ terms_ repeats_ sigma_ configs_ cv_scores_ guard_ "
        "used_ fit_seconds_ learners_".split())  # fmt: skip

    def __init__(
        self,
        folds: int = 3,
        guard: bool = True,
        guard_z: float = 2.0,
        seed: int = 0,
        n_jobs: int | None = None,
        physics: bool = True,
    ) -> None:
        self.folds = folds
        self.guard = guard
        self.guard_z = guard_z
        self.seed = seed
        self.n_jobs = n_jobs
        self.physics = physics
        #: Called as ``progress(done, total)`` as the cross-validation's trainings finish (a progress
        #: bar, say); not a parameter, and not saved.
        self.progress: Callable[[int, int], None] | None = None

    # ------------------------------------------------------------------ what a learner supplies

    @abstractmethod
    def _candidates(self, sensor: str, n_inputs: int) -> list[dict[str, Any]]:
        """Learner settings to try, cheapest first."""

    @abstractmethod
    def _train(self, config: dict[str, Any], points: Points, sigma: Array, seed: int) -> Any:
        """A learner fitted to ``points`` (residuals in units of ``sigma`` per channel, weights ``n``)."""

    @abstractmethod
    def _predict(self, learner: Any, x: Array, memo: dict[str, Any] | None = None) -> Array:
        """Residual predictions (m, 3) at scaled inputs ``x`` (m, d), in the data's units. ``memo``, where
        given, is the same dict on each pass of a correction over the same rows: a learner may keep there
        what a row's next input, close to its last, lets it reuse (it must predict the same to the last
        bit as without)."""

    def _variants(self, config: dict[str, Any], learner: Any) -> list[tuple[dict[str, Any], Any]]:
        """Settings derived from one training run (training lengths, say) with their learners."""
        return [(config, learner)]

    def _stages(
        self, config: dict[str, Any], points: Points, sigma: Array, seed: int
    ) -> Generator[list[tuple[dict[str, Any], Any]], None, None]:
        """Training under ``config`` in stages (an iterative learner's training lengths), yielding after
        each the variants it reached in that stage with their learners; the cross-validation may stop
        between stages. By default one stage: :meth:`_train`'s :meth:`_variants`."""
        yield self._variants(config, self._train(config, points, sigma, seed))

    @abstractmethod
    def _learner_state(self, learner: Any) -> Any:
        """The fitted learner as plain lists and numbers."""

    @abstractmethod
    def _learner_from_state(self, state: Any) -> Any:
        """The learner :meth:`_learner_state` describes."""

    # ------------------------------------------------------------------ fit

    def fit(
        self,
        data: CalibrationData,
        recordings: NDArray[np.intp] | None = None,
        base: Regression | None = None,
    ) -> ResidualStrategy:
        """Fit regression (or take ``base``, fitted already: a reference's intervals' seed model, in every
        fold), choose each sensor's learner on held-back blocks, retrain it; returns self. ``recordings``
        (one per row): each row's recording where several are fitted together; the folds are then the
        recordings, and the guard judges a learner on recordings it was not trained on."""
        started = time.perf_counter()
        self.__dict__.pop("_restored", None)
        kept = None if recordings is None else _with_reference(recordings, data)
        data = data.rows_with_reference()
        if len(data) < 10:
            raise ValueError(f"{data.source or 'recording'}: too few rows with a reference to train on")
        whole = base if base is not None else Regression().fit(data)
        self.base_, self._base = whole.get_state(), whole
        self._set_scaling(data)
        x_terms = self._scaled(data.ref_gyro, data.ref_accel, data.temp)
        scaled = {s: _columns(s, x_terms) for s in SENSORS}
        block = segment(scaled["gyro"][:, :6], data.t)
        fold, n_folds = self._fold_of(block, kept, data.source)
        self.blocks_, self.cv_folds_ = int(block[-1]) + 1, n_folds
        # The held-back residuals the terms and the learners are chosen on: a given base's, made once.
        given = None if base is None else self._targets(base, data)
        folds: list[tuple[int, NDArray[np.bool_], Array]] = []
        for k in range(n_folds):
            train = fold != k
            try:  # each fold's regression, refitted without the fold, where no base is given
                fold_base = base if base is not None else Regression().fit(data.rows(np.flatnonzero(train)))
            except ValueError:
                continue  # this fold's training part cannot determine the seed model
            folds.append((k, train, self._targets(fold_base, data) if given is None else given))
        # Physics first: the terms least squares carries, each channel's chosen on the held-back blocks.
        groups: list[tuple[str, ...]] = [() for _ in CHANNELS]
        if self.physics:
            groups = terms.choose(
                x_terms, [(train, t) for _, train, t in folds], block, self.guard_z, by_fold=kept is not None
            )
        targets = self._targets(whole, data) if given is None else given
        self.terms_ = {
            ch: {"groups": list(g), "coef": terms.fit(terms.design(g, c, x_terms), targets[:, c]).tolist()}
            for c, (ch, g) in enumerate(zip(CHANNELS, groups, strict=True))
            if g
        }
        targets = targets - self._terms(x_terms, range(6))
        self.repeats_ = {s: repeats(targets[:, 3 * i : 3 * i + 3], block) for i, s in enumerate(SENSORS)}
        sigma = np.sqrt(np.mean(targets**2, axis=0))
        self.sigma_ = np.where(sigma > 0, sigma, 1.0)
        # The learners learn what regression and the terms leave, both refitted without the fold.
        for i, (k, train, t) in enumerate(folds):
            left = t - terms.predict(groups, self._fold_terms(groups, x_terms, train, t), x_terms, range(6))
            folds[i] = (k, train, left)
        trials = self._cross_validate(scaled, block, folds)
        self.learners_: dict[str, Any] = {}
        self.configs_: dict[str, dict[str, Any]] = {}
        self.cv_scores_ = {s: {k: t.score for k, t in trials[s].items()} for s in SENSORS}
        self.guard_: dict[str, dict[str, Any]] = {}
        used = np.zeros(6, dtype=bool)
        for si, sensor in enumerate(SENSORS):
            cols = slice(3 * si, 3 * si + 3)
            if not trials[sensor]:
                raise ValueError(f"{data.source or 'recording'}: no fold could be fitted (too few blocks)")
            best = min(trials[sensor].values(), key=lambda t: t.score)
            self.configs_[sensor] = best.config
            for c, verdict in enumerate(best.verdicts(self.guard_z, by_fold=kept is not None)):
                self.guard_[CHANNELS[3 * si + c]] = verdict
                used[3 * si + c] = verdict["earns_its_place"] or not self.guard
            points = aggregate(scaled[sensor], targets[:, cols], block, self.repeats_[sensor])
            learner = self._train(best.config, points, self.sigma_[cols], self.seed)
            self.learners_[sensor] = self._final(best.config, learner)
        self.used_ = used
        self.fit_seconds_ = time.perf_counter() - started
        return self

    def _fold_of(
        self, block: NDArray[np.intp], recordings: NDArray[np.intp] | None, source: str
    ) -> tuple[NDArray[np.intp], int]:
        """Each row's fold and how many: ``folds`` of blocks at random, or each of ``recordings``."""
        if recordings is None:
            dealt = np.random.default_rng([self.seed, 17]).permutation(int(block[-1]) + 1) % self.folds
            return dealt[block], self.folds
        kept, fold = np.unique(recordings, return_inverse=True)
        if len(kept) < 2:
            raise ValueError(f"{source or 'recording'}: recordings as folds need two or more")
        return fold, len(kept)

    @staticmethod
    def _fold_terms(
        groups: list[tuple[str, ...]], x: terms.TermInputs, train: NDArray[np.bool_], targets: Array
    ) -> list[Array]:
        """The chosen terms' coefficients fitted on one fold's training rows."""
        x_train = x.rows(train)
        return [
            terms.fit(terms.design(g, c, x_train), targets[train, c]) if g else np.zeros(0)
            for c, g in enumerate(groups)
        ]

    def _cross_validate(
        self,
        scaled: dict[str, Array],
        block: NDArray[np.intp],
        folds: list[tuple[int, NDArray[np.bool_], Array]],
    ) -> dict[str, dict[str, _Trial]]:
        """Per sensor and candidate setting, its held-back record over the folds: for each fold ``k``,
        every candidate trained on the residuals its training rows leave (regression and the chosen
        terms, refitted without the fold) and scored on the fold's.

        A candidate is trained on every fold side by side, stage by stage (:meth:`_stages`), and its
        training stops once :data:`PATIENCE` stages in a row have not lowered its held-back loss summed
        over the folds: longer training then only fits the training folds' noise closer."""
        jobs: list[_Job] = []
        for si, sensor in enumerate(SENSORS):
            cols = slice(3 * si, 3 * si + 3)
            fold_points = []
            for k, train, fold_targets in folds:
                held = ~train
                run = self.repeats_[sensor]
                pts_train = aggregate(scaled[sensor][train], fold_targets[train, cols], block[train], run)
                pts_held = aggregate(scaled[sensor][held], fold_targets[held, cols], block[held], run)
                fold_points.append((pts_train, pts_held, self.seed + k))
            for config in self._candidates(sensor, scaled[sensor].shape[1]):
                jobs.append(_Job(sensor, config, fold_points, self.sigma_[cols]))
        results: list[list[tuple[dict[str, Any], list[Array]]]] = []
        largest = max((len(train.n) for job in jobs for train, _, _ in job.folds), default=0)
        threads = self.n_jobs or (2 if largest >= THREADED_POINTS else 1)
        with ThreadPoolExecutor(threads) as pool:
            for result in pool.map(self._run_job, jobs):
                results.append(result)
                if self.progress is not None:
                    self.progress(len(results), len(jobs))
        # Scored in the jobs' order, whatever order they finished in: the trials' sums come out the same.
        trials: dict[str, dict[str, _Trial]] = {s: {} for s in SENSORS}
        for job, variants in zip(jobs, results, strict=True):
            for variant, preds in variants:
                trial = trials[job.sensor].setdefault(_key(variant), _Trial(variant))
                for (_, pts_held, _), pred in zip(job.folds, preds, strict=True):
                    trial.add(pts_held, pred, job.sigma)
        return trials

    def _run_job(self, job: _Job) -> list[tuple[dict[str, Any], list[Array]]]:
        """One candidate trained on every fold in stages: each variant it passed through, with its
        predictions on each fold's held-back points (see :meth:`_cross_validate`)."""
        stages = [self._stages(job.config, train, job.sigma, seed) for train, _, seed in job.folds]
        out: list[tuple[dict[str, Any], list[Array]]] = []
        best, stale = np.inf, 0
        try:
            for per_fold in zip(*stages, strict=True):
                found: dict[str, tuple[dict[str, Any], list[Array]]] = {}
                for (_, held, _), variants in zip(job.folds, per_fold, strict=True):
                    for variant, fitted in variants:
                        preds = found.setdefault(_key(variant), (variant, []))[1]
                        preds.append(self._predict(fitted, held.x))
                out.extend(found.values())
                loss = min(job.loss(preds) for _, preds in found.values())
                best, stale = (loss, 0) if loss < best else (best, stale + 1)
                if stale >= PATIENCE:
                    break
        finally:
            for stage in stages:
                stage.close()
        return out

    def _final(self, config: dict[str, Any], learner: Any) -> Any:
        """The learner to keep from a final training run under ``config`` (its variant's, say)."""
        for variant, fitted in self._variants(config, learner):
            if _key(variant) == _key(config):
                return fitted
        return learner

    @staticmethod
    def _targets(base: Regression, data: CalibrationData) -> Array:
        w, f = base.correct(data.gyro, data.accel)
        return np.hstack([w - data.ref_gyro, f - data.ref_accel])

    # ------------------------------------------------------------------ inputs

    def _set_scaling(self, data: CalibrationData) -> None:
        rate = max(float(np.abs(data.ref_gyro).max()), _MIN_RATE_SCALE)
        self.uses_temp_ = bool(
            data.temp is not None and np.ptp(np.asarray(data.temp, dtype=float)) >= _MIN_TEMP_SPAN
        )
        centre, half = 0.0, 1.0
        if self.uses_temp_ and data.temp is not None:
            lo, hi = float(np.min(data.temp)), float(np.max(data.temp))
            centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        self.scaling_ = {"rate": rate, "accel": earth.G0, "temp_centre": centre, "temp_half": half}
        box = {s: self._scale(s, data.ref_gyro, data.ref_accel, data.temp) for s in SENSORS}
        self.box_ = {s: [box[s].min(axis=0).tolist(), box[s].max(axis=0).tolist()] for s in SENSORS}

    def _scaled(self, w: Array, f: Array, temp: Array | None) -> terms.TermInputs:
        """Rate, force and temperature in the physical scales (the rig's largest rate, ``G0``, half the
        temperature span about its centre): the terms' inputs, and the learners' (:meth:`_scale`)."""
        s = self.scaling_
        t = None
        if self.uses_temp_:
            if temp is None:
                raise ValueError(f"this {self.name} was fitted with temperature: give the temperature series")
            t = (np.asarray(temp, dtype=float) - s["temp_centre"]) / s["temp_half"]
        return terms.TermInputs(w / s["rate"], f / s["accel"], t)

    def _scale(self, sensor: str, w: Array, f: Array, temp: Array | None) -> Array:
        """A sensor's learner inputs (:func:`input_columns`) in the physical scales."""
        return _columns(sensor, self._scaled(w, f, temp))

    def _terms(self, x: terms.TermInputs, channels: range) -> Array:
        """The chosen terms' residual on ``channels`` (n, len(channels)); 0 on a channel without."""
        chosen = self.terms_
        groups = [tuple(chosen[ch]["groups"]) if ch in chosen else () for ch in CHANNELS]
        coef = [
            np.asarray(chosen[ch]["coef"], dtype=float) if ch in chosen else np.zeros(0) for ch in CHANNELS
        ]
        return terms.predict(groups, coef, x, channels)

    def _residual(self, sensor: str, x: Array, memo: dict[str, Any] | None = None) -> Array:
        """The learned residual at scaled inputs ``x``. Beyond the box the rig covered, the learner goes
        on along each input's slope at the box's edge (a one-sided difference over the last 0.1 % of the
        range; not one carried beyond along another input already, which read 6,000 m/s² at a landing)
        for up to a quarter of the range, and holds from there: a scale factor's curve that the rig
        followed to 250 °/s is better continued to 300 than cut flat, and guessed no further. ``memo``:
        what the learner may keep between the passes of one correction over the same rows."""
        lo, hi = (np.asarray(b, dtype=float) for b in self.box_[sensor])
        width = np.maximum(hi - lo, 1e-12)
        reach, inside, beyond = _boxed(np.ascontiguousarray(x), lo - 0.25 * width, hi + 0.25 * width, lo, hi)
        learner = self._learner(sensor)
        at_edge: Array = self._predict(learner, inside, memo)
        pred = at_edge.copy()
        for d in range(x.shape[1]):
            if (rows := beyond[reach[beyond, d] != inside[beyond, d]]).size == 0:
                continue
            step = EDGE_STEP * width[d] * np.sign(reach[rows, d] - inside[rows, d])
            back = inside[rows].copy()
            back[:, d] -= step
            slope = (at_edge[rows] - self._predict(learner, back)) / step[:, None]
            pred[rows] += slope * (reach[rows, d] - inside[rows, d])[:, None]
        return pred

    def beyond_box(self, gyro: Array, accel: Array, temp: Array | None = None) -> NDArray[np.bool_]:
        """The readings at which a learner used reads beyond the box of inputs it was trained on by more
        than :data:`BEYOND_SAID` of its width (:meth:`_residual`), at regression's correction of them."""
        out = np.zeros(len(gyro), dtype=bool)
        if not self.used_.any() or len(gyro) == 0:
            return out
        x = self._scaled(*self._base_strategy().correct(gyro, accel), None if temp is None else temp)
        for si, sensor in enumerate(SENSORS):
            if self.used_[3 * si : 3 * si + 3].any():
                lo, hi = (np.asarray(b, dtype=float) for b in self.box_[sensor])
                columns = _columns(sensor, x)
                margin = BEYOND_SAID * (hi - lo)
                out |= ((columns < lo - margin) | (columns > hi + margin)).any(axis=1)
        return out

    # ------------------------------------------------------------------ use

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """Regression's correction ``x̂``, less the learned residual at the inputs, solved for by
        fixed-point iteration ``x ← x̂ − r(x)``: where regression is far off (a scale nonlinearity it
        folded into a scale factor) ``x̂`` itself is off by the residual, and ``r(x̂)`` by its slope times
        that; each pass multiplies what is left by the slope (2e-2 for 3 °/s at 300 °/s). Solved
        :data:`CORRECT_ROWS` rows at a time, on two threads from :data:`THREADED_ROWS` rows (``n_jobs``):
        the whole array's figures, a map's to the last bit; a network's within its rounding (numpy's
        matrix product picks its kernel by the rows it is given: a chunk, a handful extrapolated beyond
        the box), and on one thread or two the same to the last bit."""
        w_hat, f_hat = self._base_strategy().correct(gyro, accel)
        if not (self.terms_ or self.used_.any()) or len(w_hat) == 0:
            return w_hat, f_hat
        temp_arr = None if temp is None else np.asarray(temp, dtype=float)
        chunks = [slice(s, s + CORRECT_ROWS) for s in range(0, len(w_hat), CORRECT_ROWS)]
        # Each chunk's solution written into its rows of the output (no parts joined after).
        w_out, f_out = np.empty_like(w_hat), np.empty_like(f_hat)

        def solve(rows: slice) -> None:
            w_out[rows], f_out[rows] = self._solve(
                w_hat[rows], f_hat[rows], None if temp_arr is None else temp_arr[rows]
            )

        threads = self.n_jobs or (2 if len(w_hat) >= THREADED_ROWS else 1)
        # BLAS on one thread (numpy's products of a chunk are small): its own threads beside the
        # chunks' made four on two cores, and two chunks at a time were hardly faster than one
        # (docs/speed.md); and one thread or two, whatever the environment, the same sums.
        with threadpool_limits(limits=1, user_api="blas"):
            if threads == 1 or len(chunks) == 1:
                for rows in chunks:
                    solve(rows)
            else:
                # Two rows first (written again by their chunk): the learners build what they make on
                # first use (a network, a k-d tree) before threads share them.
                solve(slice(0, 2))
                with ThreadPoolExecutor(threads) as pool:
                    list(pool.map(solve, chunks))
        return w_out, f_out

    def _solve(self, w_hat: Array, f_hat: Array, temp: Array | None) -> tuple[Array, Array]:
        """:meth:`correct`'s fixed point on some rows, from regression's correction of them."""
        hat = (w_hat, f_hat)
        w, f = w_hat, f_hat
        with_terms = bool(self.terms_)
        memos: dict[str, dict[str, Any]] = {sensor: {} for sensor in SENSORS}
        for _ in range(1 + _PASSES):
            out = []
            x = self._scaled(w, f, temp)  # once a pass, for the terms and both sensors' learners
            for si, sensor in enumerate(SENSORS):
                mask = self.used_[3 * si : 3 * si + 3]
                pred: Array | float = 0.0
                if mask.any():
                    pred = self._residual(sensor, _columns(sensor, x), memos[sensor]) * mask
                if with_terms:
                    pred = pred + self._terms(x, range(3 * si, 3 * si + 3))
                out.append(hat[si] - pred)
            w, f = out
        return w, f

    def _base_strategy(self) -> Regression:
        if getattr(self, "_base", None) is None:  # a loaded model: made once, on first use
            self._base = Regression()
            self._base.set_state(self.base_)
        return self._base

    def _learner(self, sensor: str) -> Any:
        cache = self.__dict__.setdefault("_restored", {})
        if sensor not in cache:
            learner = self.learners_[sensor]
            cache[sensor] = self._learner_from_state(learner) if isinstance(learner, dict) else learner
        return cache[sensor]

    def get_state(self) -> dict[str, Any]:
        """The fitted state, each sensor's learner as plain lists and numbers."""
        state = {k: v for k, v in super().get_state().items() if k != "learners_"}
        state["learners_"] = {s: self._learner_state(self._learner(s)) for s in self.learners_}
        return state

    def check_state(self, state: dict[str, Any]) -> None:
        """What correcting reads of the state, before anything is built of it: regression's state
        (:meth:`Regression.check_state`), ``sigma_`` (6, positive), ``used_`` (6 booleans), the scales
        and boxes of the inputs, each channel's terms (known groups, one coefficient per column), and each
        sensor's learner (:meth:`_check_learner`, one for every sensor whose channels use it)."""
        super().check_state(state)
        base = state.get("base_")
        if not isinstance(base, dict):
            raise ValueError("state.base_ must be regression's state (an object)")
        Regression().check_state(base)
        if not (state_array(state, "sigma_", (6,)) > 0).all():
            raise ValueError("state.sigma_ must be positive")
        used = state.get("used_")
        if not isinstance(used, list) or len(used) != 6 or not all(isinstance(u, bool) for u in used):
            raise ValueError("state.used_ must be 6 booleans")
        uses_temp = state.get("uses_temp_", False)
        if not isinstance(uses_temp, bool):
            raise ValueError("state.uses_temp_ must be true or false")
        scaling = state.get("scaling_")
        if not isinstance(scaling, dict) or any(
            not (_finite(scaling.get(k)) and scaling[k] > 0) for k in _SCALES
        ):
            raise ValueError(f"state.scaling_ must give {', '.join(_SCALES)}, positive numbers")
        if not _finite(scaling.get("temp_centre")):
            raise ValueError("state.scaling_.temp_centre must be a finite number")
        n_inputs = {"gyro": 6 + uses_temp, "accel": 3 + uses_temp}
        box, learners = state.get("box_"), state.get("learners_")
        if not isinstance(box, dict) or not isinstance(learners, dict):
            raise ValueError("state.box_ and state.learners_ must be objects by sensor")
        for sensor in SENSORS:
            state_array(box, sensor, (2, n_inputs[sensor]), "state.box_")
            if sensor in learners:
                self._check_learner(learners[sensor], n_inputs[sensor], f"state.learners_.{sensor}")
            elif any(used[3 * SENSORS.index(sensor) : 3 * SENSORS.index(sensor) + 3]):
                raise ValueError(f"state.learners_ has no {sensor} learner, which used_ says corrects")
        terms.check_state(state.get("terms_", {}), uses_temp)

    def _check_learner(self, learner: Any, n_inputs: int, where: str) -> None:
        """Refuse a learner's state that :meth:`_learner_from_state` cannot make a learner of, on inputs
        of ``n_inputs`` columns, or that is larger than :meth:`fit` could have chosen (ValueError naming
        ``where``). The subclasses know their learners; here, only that it is an object."""
        if not isinstance(learner, dict):
            raise ValueError(f"{where} must be an object")

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore the state; the learners are rebuilt from it on first use."""
        for k, v in state.items():
            setattr(self, k, v)  # sigma_, used_ and learners_ then made of their kinds
        self.sigma_ = np.asarray(state["sigma_"], dtype=float)
        self.used_ = np.asarray(state["used_"], dtype=bool)
        self.learners_ = dict(state["learners_"])
        self.__dict__.pop("_restored", None)
        self.__dict__.pop("_base", None)


#: The scales a saved state must give, each a positive number.
_SCALES = ("rate", "accel", "temp_half")


def _finite(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and bool(np.isfinite(value))


def _key(config: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v}" for k, v in sorted(config.items()))


__all__ = [
    "BEYOND_SAID",
    "CORRECT_ROWS",
    "EDGE_STEP",
    "MIN_REPEATS",
    "PATIENCE",
    "THREADED_POINTS",
    "THREADED_ROWS",
    "Points",
    "ResidualStrategy",
    "aggregate",
    "input_columns",
    "repeats",
    "segment",
]
