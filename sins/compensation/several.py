"""The seed model fitted on several recordings of one unit at once: shared coefficients, per-recording
biases.

A MEMS unit's scale factors, misalignments, g-sensitivity and time offsets are properties of the unit;
its biases are not: they move between power-ups and days (EuRoC's ADIS16448: 4e-3 rad/s, 800 °/h, between
two days; 1e-3 rad/s within one). A fit that pooled the recordings under one bias would spread that move
over the coefficients. So the recordings share every coefficient but the biases, and each recording has
its own gyro and accelerometer bias: one least squares on the intervals of all the recordings together
(:mod:`sins.compensation.interval_fit`'s problems, stacked), the shared columns once and the bias columns
once per recording. Intervals never span two recordings, and the residual covariance lets neighbours
correlate within a recording only.

What the per-recording biases say about a new recording of the unit is the correction's business
(:mod:`sins.compensation.unit_bias`): this module fits them and reports their spread.
"""

from __future__ import annotations

import itertools
from collections.abc import Collection
from dataclasses import dataclass, field, replace
from types import SimpleNamespace

import numpy as np
from numpy.typing import NDArray

from sins.compensation.identifiability import accel_names, gyro_names
from sins.compensation.interval_fit import (
    IntervalFit,
    ReferenceQuality,
    accel_problem,
    gyro_problem,
    quality,
    solve,
    widened,
)
from sins.compensation.intervals import (
    INTERVAL_S,
    Intervals,
    choose_intervals,
    correct_increments,
    expected_dv,
    lever,
)
from sins.core.series import ReferencedRecording
from sins.imu.calibration import SeedModelFit
from sins.nav import attitude

Array = NDArray[np.float64]

#: Two recordings' sample rates within this share of each other are one rate (one model, one unit's).
SAME_RATE = 0.05
#: Gauss–Newton on the gyro stops when no coefficient moves by more than this many standard errors.
_CONVERGED_SE = 1e-3
_MAX_ITERATIONS = 8


@dataclass(frozen=True)
class SeveralFit:
    """The seed model of one unit fitted on several recordings (see the module docstring).

    ``seed``: the shared coefficients with their standard errors; its ``B0`` and ``A0`` are the mean of
    the recordings' biases. ``gyro_bias`` and ``accel_bias`` (r, 3): each recording's own, with
    ``gyro_bias_se`` and ``accel_bias_se``; the time offsets and the lever arm are shared. ``intervals``
    (r,): each recording's count; ``quality``: each recording's reference beside the sensor; ``sources``:
    the recordings' names.
    """

    seed: SeedModelFit
    gyro_bias: Array
    gyro_bias_se: Array
    accel_bias: Array
    accel_bias_se: Array
    time_offset_s: float
    time_offset_se_s: float
    accel_time_offset_s: float
    accel_time_offset_se_s: float
    lever_arm_m: Array
    intervals: tuple[int, ...]
    interval_s: float
    quality: tuple[ReferenceQuality, ...]
    sources: tuple[str, ...]
    g_sensitivity: bool
    #: Each recording's interval residuals, gyro (k, 3) rad and accelerometer (k, 3) m/s, at the fit
    #: (:mod:`sins.compensation.screening` reads them).
    residuals: tuple[tuple[Array, Array], ...] = field(default=(), repr=False)

    def for_recording(self, r: int) -> IntervalFit:
        """The fit as recording ``r`` sees it (its own biases): an :class:`IntervalFit`, what
        :func:`~sins.compensation.interval_fit.interval_reference` turns into per-sample references."""
        seed = replace(
            self.seed, B0=self.gyro_bias[r], B0_se=self.gyro_bias_se[r], A0=self.accel_bias[r],
            A0_se=self.accel_bias_se[r],
        )  # fmt: skip
        return IntervalFit(
            seed, self.time_offset_s, self.time_offset_se_s, self.accel_time_offset_s,
            self.accel_time_offset_se_s, self.intervals[r], self.interval_s, self.quality[r],
            self.lever_arm_m, self.g_sensitivity,
        )  # fmt: skip

    def bias_spread(self) -> Array:
        """The standard deviation of the recordings' gyro biases about their mean, rad/s (3,)."""
        return np.asarray(self.gyro_bias.std(axis=0, ddof=1), dtype=float)


def fit_several(
    recs: list[ReferencedRecording],
    *,
    interval_s: float = INTERVAL_S,
    g_sensitivity: bool = False,
    time_offset: bool = True,
    robust: bool = False,
    held: Collection[str] = (),
) -> SeveralFit:
    """Fit the seed model on ``recs`` (two or more recordings of one unit): shared ``B``, ``K`` (with
    ``g_sensitivity``), ``A``, time offsets and lever arm; each recording's own gyro and accelerometer
    bias. ``robust`` weights intervals by Huber's function of their residual. The shared coefficients
    named in ``held`` (:mod:`sins.compensation.identifiability`'s names) are held at zero, their standard
    errors NaN; the biases are always fitted.

    Raises
    ------
    ValueError
        naming the recording: too few intervals in one; together, too little turning or too few
        orientations to determine the shared coefficients.
    """
    if len(recs) < 2:
        raise ValueError("a fit on several recordings needs two or more")
    ivs = [choose_intervals(rec, interval_s) for rec in recs]
    dts = [np.diff(rec.imu.t) for rec in recs]
    n = len(recs)
    zeros = np.zeros((3, 3))
    seed = SeedModelFit(
        B0=np.zeros(3), B=zeros, K=zeros, A0=np.zeros(3), A=zeros, B0_se=np.full(3, np.nan),
        B_se=np.full((3, 3), np.nan), K_se=np.full((3, 3), np.nan), A0_se=np.full(3, np.nan),
        A_se=np.full((3, 3), np.nan), residual_rms=np.full(6, np.nan),
    )  # fmt: skip
    state = _State(seed, np.zeros((n, 3)), np.zeros((n, 3)), 0.0, 0.0, frozenset(held))
    joined = _joined(ivs)
    g_cov = a_cov = np.zeros((0, 0))
    g_resid = a_resid = [np.zeros((0, 3))] * n
    arm = np.zeros(3)
    for rounds in range(2):  # the accelerometer needs the gyro's attitude, the gyro's K the force
        arm, a_cov, a_resid = _accel_round(recs, ivs, dts, state, joined, time_offset, robust)
        with_k = g_sensitivity and rounds == 1
        g_cov, g_resid = _gyro_rounds(recs, ivs, dts, state, joined, with_k, time_offset, robust)
    return _result(recs, ivs, state, joined, g_cov, a_cov, g_resid, a_resid, arm, interval_s, time_offset,
                   g_sensitivity)  # fmt: skip


@dataclass
class _State:
    """The fit's estimate while it iterates: shared seed (its B0, A0 unused), per-recording biases,
    time offsets."""

    seed: SeedModelFit
    gyro_bias: Array
    accel_bias: Array
    tau: float
    tau_a: float
    held: frozenset[str] = frozenset()

    def free(self, names: tuple[str, ...], n: int) -> NDArray[np.bool_]:
        """The stacked problem's free columns: the shared ones of ``names`` (biases, the first three,
        left out) not held, then ``n`` recordings' three bias columns each."""
        return np.r_[[name not in self.held for name in names[3:]], np.ones(3 * n, dtype=bool)]

    def seed_of(self, r: int) -> SeedModelFit:
        return replace(self.seed, B0=self.gyro_bias[r], A0=self.accel_bias[r])


def check_one_unit(recs: list[ReferencedRecording]) -> None:
    """Refuse fewer than two recordings, two units, rates more than 5 % apart, or one recording's readings
    given twice (a copy under another name: the bias's spread between recordings would read zero and the
    held-back rule would judge a recording by itself). One line, both named."""
    from sins.errors import SinsInputError
    from sins.io.provenance import readings_digest

    if len(recs) < 2:
        raise SinsInputError("a fit on several recordings needs two or more")
    seen: dict[str, str] = {}
    for i, rec in enumerate(recs):
        first = recs[0]
        if i and first.sensor and rec.sensor and rec.sensor != first.sensor:
            raise SinsInputError(
                f"{rec.source}: recordings of one unit are fitted together; {first.source} is "
                f"{first.sensor}, this is {rec.sensor}"
            )
        if abs(rec.rate_hz - first.rate_hz) > SAME_RATE * first.rate_hz:
            raise SinsInputError(
                f"{rec.source}: readings at {rec.rate_hz:.6g} Hz; {first.source} at "
                f"{first.rate_hz:.6g} Hz: one model is fitted on recordings at one rate"
            )
        digest = readings_digest(rec.imu.t, rec.imu.dtheta_b, rec.imu.dv_b)
        if digest in seen:
            raise SinsInputError(
                f"{rec.source}: the same readings as {seen[digest]}: a fit on several recordings takes "
                "each once"
            )
        seen[digest] = rec.source
    _check_no_parts(recs)


def _check_no_parts(recs: list[ReferencedRecording]) -> None:
    """Refuse a recording that holds a part of another (a cut of it, or one cut from it: most of the
    shorter one's marks, :func:`sins.io.provenance.readings_marks`, in the other's): what a copy does to
    the spread between recordings and to the held-back rule, that part does."""
    from sins.errors import SinsInputError
    from sins.io.provenance import PART_SHARE, readings_marks, shared_share

    marks = [readings_marks(rec.imu.dtheta_b, rec.imu.dv_b) for rec in recs]
    for i, j in itertools.combinations(range(len(recs)), 2):
        short, long = (i, j) if len(marks[i]) <= len(marks[j]) else (j, i)
        share = shared_share(marks[short], [marks[long]])
        if share is not None and share >= PART_SHARE:
            raise SinsInputError(
                f"{recs[short].source}: about {share:.0%} of its readings are {recs[long].source}'s (a part "
                "of it): a fit on several recordings takes each reading once"
            )


def _joined(ivs: list[Intervals]) -> SimpleNamespace:
    """The stacked intervals' ends, offset so that no interval of one recording meets another's: what
    the residual covariance reads to let neighbours correlate."""
    starts, stops, offset = [], [], 0
    for iv in ivs:
        starts.append(iv.start + offset)
        stops.append(iv.stop + offset)
        offset = int(stops[-1].max()) + 2
    return SimpleNamespace(start=np.concatenate(starts), stop=np.concatenate(stops))


def _stack(parts: list[tuple[Array, Array]], shared: slice | list[int], bias: slice) -> tuple[Array, Array]:
    """Each recording's problem ``(x_r, y_r)`` stacked into one: the shared columns, then each
    recording's bias columns in a block of their own."""
    n = len(parts)
    width_shared = (
        len(range(*shared.indices(parts[0][0].shape[2]))) if isinstance(shared, slice) else len(shared)
    )
    k_total = sum(len(y) for _, y in parts)
    x = np.zeros((k_total, 3, width_shared + 3 * n))
    y = np.zeros((k_total, 3))
    row = 0
    for r, (xr, yr) in enumerate(parts):
        k = len(yr)
        x[row : row + k, :, :width_shared] = xr[:, :, shared]
        x[row : row + k, :, width_shared + 3 * r : width_shared + 3 * r + 3] = xr[:, :, bias]
        y[row : row + k] = yr
        row += k
    return x, y


def _accel_round(
    recs: list[ReferencedRecording], ivs: list[Intervals], dts: list[Array], state: _State,
    joined: SimpleNamespace, time_offset: bool, robust: bool,
) -> tuple[Array, Array, list[Array]]:  # fmt: skip
    """Four passes of the accelerometer's joint least squares (its problem is linear but for the
    inverse scale and the shift); updates ``state``; returns the lever arm, the covariance and each
    recording's residuals."""
    n = len(recs)
    q_ints, expected, arms = [], [], []
    for r, rec in enumerate(recs):
        corrected = correct_increments(rec.imu, state.seed_of(r), state.tau, state.tau_a)
        q_ints.append(attitude.propagate_increments(corrected.dtheta_b, np.array([0.0, 0.0, 0.0, 1.0])))
        expected.append(expected_dv(ivs[r], dts[r]))
        arms.append(lever(ivs[r], rec.imu, state.seed_of(r), dts[r]))
    shared = list(range(3, 15)) + ([15] if time_offset else [])
    cov = np.zeros((0, 0))
    arm = np.zeros(3)
    resid: list[Array] = []
    for _ in range(4):
        parts = [
            accel_problem(ivs[r], recs[r].imu, dts[r], q_ints[r], state.accel_bias[r], state.seed.A,
                          state.tau_a, time_offset, expected[r], arms[r])
            for r in range(n)
        ]  # fmt: skip
        x, y = _stack(parts, shared, slice(0, 3))
        step, cov, res = _solve_free(x, y, joined, robust, state.free(accel_names(time_offset), n))
        state.seed = replace(state.seed, A=state.seed.A + step[:9].reshape(3, 3))
        arm = step[9:12]  # estimated whole in every pass (the problem holds none of it)
        if time_offset:
            state.tau_a += float(step[12])
        state.accel_bias = state.accel_bias + step[len(shared) :].reshape(n, 3)
        resid = np.split(res, np.cumsum([len(p[1]) for p in parts])[:-1])
    return arm, cov, resid


def _gyro_rounds(
    recs: list[ReferencedRecording], ivs: list[Intervals], dts: list[Array], state: _State,
    joined: SimpleNamespace, with_k: bool, time_offset: bool, robust: bool,
) -> tuple[Array, list[Array]]:  # fmt: skip
    """Gauss–Newton on the gyro's joint problem; updates ``state``; returns the covariance and each
    recording's residuals."""
    n = len(recs)
    r_refs = [iv.body_turn() for iv in ivs]
    width = 3 + 9 + (9 if with_k else 0) + (1 if time_offset else 0)
    shared = list(range(3, width))
    cov = np.zeros((0, 0))
    resid: list[Array] = []
    for _ in range(_MAX_ITERATIONS):
        parts = [
            gyro_problem(ivs[r], recs[r].imu, dts[r], state.seed_of(r), state.tau, state.tau_a, with_k,
                         time_offset, r_refs[r])
            for r in range(n)
        ]  # fmt: skip
        x, y = _stack(parts, shared, slice(0, 3))
        free = state.free(gyro_names(with_k, time_offset), n)
        step, cov, res = _solve_free(x, y, joined, robust, free)
        B = state.seed.B + step[:9].reshape(3, 3)
        K = state.seed.K + step[9:18].reshape(3, 3) if with_k else state.seed.K
        state.seed = replace(state.seed, B=B, K=K)
        if time_offset:
            state.tau += float(step[len(shared) - 1])
        state.gyro_bias = state.gyro_bias + step[len(shared) :].reshape(n, 3)
        resid = np.split(res, np.cumsum([len(p[1]) for p in parts])[:-1])
        se = np.sqrt(np.maximum(np.diag(cov)[free], 1e-300))
        if np.all(np.abs(step[free]) <= _CONVERGED_SE * se):
            break
    return cov, resid


def _solve_free(
    x: Array, y: Array, joined: SimpleNamespace, robust: bool, free: NDArray[np.bool_]
) -> tuple[Array, Array, Array]:
    """:func:`~sins.compensation.interval_fit.solve` on the ``free`` columns alone: a held one gets no
    step and an infinite variance, as one recording's fit gives it (``sins fit`` prints it ``0 (held)``)."""
    step_free, cov_free, res, _ = solve(x[:, :, free], y, joined, robust)  # type: ignore[arg-type]
    return *widened(step_free, cov_free, free), res


def _result(
    recs: list[ReferencedRecording], ivs: list[Intervals], state: _State, joined: SimpleNamespace,
    g_cov: Array, a_cov: Array, g_resid: list[Array], a_resid: list[Array], arm: Array, interval_s: float,
    time_offset: bool, g_sensitivity: bool,
) -> SeveralFit:  # fmt: skip
    n = len(recs)
    g_se = np.sqrt(np.maximum(np.diag(g_cov), 0.0))
    a_se = np.sqrt(np.maximum(np.diag(a_cov), 0.0))
    n_g = len(g_se) - 3 * n
    n_a = len(a_se) - 3 * n
    nan33 = np.full((3, 3), np.nan)
    all_g, all_a = np.vstack(g_resid), np.vstack(a_resid)
    rms = np.sqrt(np.concatenate([np.mean(all_g**2, axis=0), np.mean(all_a**2, axis=0)]))
    seed = replace(
        state.seed,
        B0=state.gyro_bias.mean(axis=0), A0=state.accel_bias.mean(axis=0),
        B0_se=np.sqrt(np.mean(g_se[n_g:].reshape(n, 3) ** 2, axis=0) / n),
        A0_se=np.sqrt(np.mean(a_se[n_a:].reshape(n, 3) ** 2, axis=0) / n),
        B_se=g_se[:9].reshape(3, 3),
        K_se=g_se[9:18].reshape(3, 3) if g_sensitivity else nan33,
        A_se=a_se[:9].reshape(3, 3), residual_rms=rms,
    )  # fmt: skip
    return SeveralFit(
        seed=seed,
        gyro_bias=state.gyro_bias.copy(), gyro_bias_se=g_se[n_g:].reshape(n, 3),
        accel_bias=state.accel_bias.copy(), accel_bias_se=a_se[n_a:].reshape(n, 3),
        time_offset_s=state.tau, time_offset_se_s=float(g_se[n_g - 1]) if time_offset else 0.0,
        accel_time_offset_s=state.tau_a, accel_time_offset_se_s=float(a_se[12]) if time_offset else 0.0,
        lever_arm_m=np.asarray(arm, dtype=float),
        intervals=tuple(len(iv) for iv in ivs), interval_s=interval_s,
        quality=tuple(quality(rec.imu, iv, g, a)
                      for rec, iv, g, a in zip(recs, ivs, g_resid, a_resid, strict=True)),
        sources=tuple(rec.source for rec in recs), g_sensitivity=g_sensitivity,
        residuals=tuple(zip(g_resid, a_resid, strict=True)),
    )  # fmt: skip


__all__ = [
    "SAME_RATE",
    "SeveralFit",
    "check_one_unit",
    "fit_several",
]
