"""The seed model fitted against a reference trajectory on intervals, as calibration does.

A real unit's reference (an optical motion capture, a better INS) gives attitude and velocity, not rates
and forces: differentiated, its noise grows with the sample rate and soon exceeds the sensor's many times
(motion capture differentiated at 285 Hz: 0.4–1.6 °/s against a MEMS gyro's 0.1 °/s). Integrated, the
sensor's noise grows only with the square root of the time. So the fit compares, over each interval
between two reference epochs, what the corrected readings integrate to with what the reference says
happened:

* gyro: the rotation the corrected increments compose to, ``R_meas = Π exp(dθ_j)``, against the
  reference's ``R_ref = C_a^T Φ C_b`` (``Φ`` the navigation frame's own turn in inertial space over the
  interval: Earth's rate, and the transport rate of a moving reference); the residual
  ``log(R_meas^T R_ref)`` (a rotation vector in the interval's end axes) is linear, to first order, in
  a change of the coefficients: a change ``δ_j`` of step ``j``'s increment turns it by
  ``Q_b^T Q_j δ_j`` (``Q`` the attitude the corrected increments integrate to). Gauss–Newton iterates
  to the least squares; the composition is exact, so fast turning within an interval (the coning a sum
  of rates would miss) costs nothing.
* accelerometer: the velocity change the corrected increments make, turned into NED by the reference's
  attitude at the interval's start carried through the interval by the gyro, with normal gravity and the
  Coriolis and transport terms, against the reference's velocity change: linear in the coefficients.

Reference noise sits in the residual, not in the regressors, so it widens the standard errors but does
not bias the coefficients (a per-sample fit on differentiated references puts it in the regressors and
shrinks every scale factor towards zero). A time offset of the gyro against the reference (a filter's
delay, a clock offset) is fitted beside the coefficients and applied by shifting the readings.

:func:`fit_intervals` returns an :class:`IntervalFit`; :func:`interval_reference` turns it into per-sample
references, so that every strategy's own ``fit`` can learn what the seed model leaves.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from sins.compensation import identifiability
from sins.compensation.identifiability import Holds
from sins.compensation.intervals import (
    INTERVAL_S,
    Intervals,
    choose_intervals,
    correct_increments,
    dcm,
    expected_dv,
    interval_sums,
    lever,
    shift_derivative,
    shift_increments,
    shifted,
)
from sins.core import rotation
from sins.core.series import CalibrationData, ImuIncrements, ReferencedRecording
from sins.imu.calibration import SeedModelFit
from sins.nav import attitude

Array = NDArray[np.float64]

#: Gauss–Newton stops when no coefficient moves by more than this many of its standard errors.
_CONVERGED_SE = 1e-3
_MAX_ITERATIONS = 8
#: Steps whose Jacobians are held at once (~ 60 MB with 22 coefficients).
_CHUNK_STEPS = 100_000


@dataclass(frozen=True)
class ReferenceQuality:
    """How good the reference is beside the sensor, from the fit's residuals (RMS over axes).

    ``still_deg`` / ``still_mps``: the residual of the intervals where the reference stood still
    (turned by less than 0.5° and moved at less than 2 cm/s), where the unit's errors that grow with
    the motion vanish: the reference's own noise and the sensor's; ``sensor_still_deg`` /
    ``sensor_still_mps``: the sensor's part, from its readings' spread in those intervals (None without
    still intervals); ``moving_deg`` / ``moving_mps``: the residual of the other intervals. ``still``:
    how many intervals stood still.
    """

    still: int
    still_deg: float | None
    still_mps: float | None
    sensor_still_deg: float | None
    sensor_still_mps: float | None
    moving_deg: float
    moving_mps: float

    def summary(self) -> str:
        """One line for reports: what the reference limits."""
        moving = f"interval residual {self.moving_deg:.3g}° and {self.moving_mps:.3g} m/s RMS in motion"
        if self.still_deg is None or self.sensor_still_deg is None or self.still_mps is None:
            return moving + "; no still intervals to tell the reference's noise from the sensor's"
        assert self.sensor_still_mps is not None
        ratio_g = self.still_deg / max(self.sensor_still_deg, 1e-300)
        ratio_a = self.still_mps / max(self.sensor_still_mps, 1e-300)
        rest = f"{moving}; at rest {self.still_deg:.3g}° and {self.still_mps:.3g} m/s"
        if max(ratio_g, ratio_a) > 2.0:
            return (
                f"{rest}, {ratio_g:.1f}x and {ratio_a:.1f}x the sensor's own noise over an interval: the "
                "reference's noise sets the standard errors"
            )
        return f"{rest}, near the sensor's own noise: the sensor, not the reference, sets the standard errors"


@dataclass(frozen=True)
class IntervalFit:
    """The seed model, with the gyro's time offset, fitted on intervals (see the module docstring).

    ``seed``: the coefficients with their standard errors (reading − truth, SI; ``K`` zero when not
    fitted); ``time_offset_s``: the readings lag the reference by this much (apply by reading them
    ``time_offset_s`` later), with ``time_offset_se_s``; ``intervals``: how many, ``interval_s`` their
    nominal length; ``quality``: the reference beside the sensor.
    """

    seed: SeedModelFit
    time_offset_s: float
    time_offset_se_s: float
    accel_time_offset_s: float
    accel_time_offset_se_s: float
    intervals: int
    interval_s: float
    quality: ReferenceQuality
    lever_arm_m: Array
    g_sensitivity: bool = True
    g_sensitivity_test: tuple[bool, float, float] | None = None
    iterations: int = 0
    weights: Array | None = field(default=None, repr=False)
    #: Each interval's residual, gyro (k, 3) rad and accelerometer (k, 3) m/s, at the fit
    #: (:mod:`sins.compensation.screening` reads them); None where not kept.
    residuals: tuple[Array, Array] | None = field(default=None, repr=False)

    def corrected(self, imu: ImuIncrements) -> ImuIncrements:
        """``imu`` shifted by the time offsets and corrected by the seed model."""
        return correct_increments(imu, self.seed, self.time_offset_s, self.accel_time_offset_s)


def fit_intervals(
    rec: ReferencedRecording,
    *,
    interval_s: float = INTERVAL_S,
    g_sensitivity: bool | Literal["auto"] = "auto",
    time_offset: bool = True,
    robust: bool = False,
    huber_k: float = 1.345,
    holds: Holds | None = None,
) -> IntervalFit:
    """Fit the seed model (and the gyro's time offset) on intervals between reference epochs.

    Parameters
    ----------
    rec : the readings beside their reference
    interval_s : the nominal interval between the reference epochs compared, s
    g_sensitivity : fit the gyro's ``K`` (else zero); "auto" keeps it only where it predicts intervals
        it was not fitted on, by more than two standard errors of that gain over five contiguous folds
        (a recording whose rests all face one way cannot tell ``K·g`` from the bias)
    time_offset : fit the gyro's time offset against the reference (else zero)
    robust : weight intervals by Huber's function of their standardised residual (threshold
        ``huber_k``), so that a few bad reference epochs (a marker swap) do not pull the fit
    holds : the coefficients held at zero (:func:`sins.compensation.identifiability.assess`: those
        the intervals do not determine; their standard errors come out infinite); None fits every one

    Returns
    -------
    IntervalFit
        standard errors from the residuals with their correlation between neighbouring intervals (they
        share a reference epoch) taken into account.

    Raises
    ------
    ValueError
        when the recording has too few intervals or does not determine the coefficients (too little
        turning, too few orientations).
    """
    iv = choose_intervals(rec, interval_s)
    imu, dt = rec.imu, np.diff(rec.imu.t)
    zeros, no_se = np.zeros((3, 3)), np.full((3, 3), np.nan)
    seed = SeedModelFit(
        B0=np.zeros(3), B=zeros, K=zeros, A0=np.zeros(3), A=zeros,
        B0_se=np.full(3, np.nan), B_se=no_se, K_se=no_se, A0_se=np.full(3, np.nan), A_se=no_se,
        residual_rms=np.full(6, np.nan),
    )  # fmt: skip
    tau = tau_se = tau_a = tau_a_se = 0.0
    gyro_weights = None
    k_verdict: tuple[bool, float, float] | None = None
    iterations = 0
    # The accelerometer needs the attitude through each interval (from the gyro) and the gyro's K needs
    # the corrected force: two rounds settle both (the accelerometer's fit moves by far less than its
    # standard error between them).
    for rounds in range(2):
        corrected = correct_increments(imu, seed, tau, tau_a)
        q_int = attitude.propagate_increments(corrected.dtheta_b, np.array([0.0, 0.0, 0.0, 1.0]))
        A0, A, a_se, a_resid, lever_arm, tau_a, tau_a_se = _fit_accel(
            iv, imu, dt, q_int, seed, tau_a, time_offset, robust, huber_k, holds
        )
        seed = _with(seed, A0=A0, A=A, A0_se=a_se[:3], A_se=a_se[3:12].reshape(3, 3))
        with_k = bool(g_sensitivity) and rounds == 1
        before = seed
        seed, tau, tau_se, g_resid, gyro_weights, n, x, z = _fit_gyro(
            iv, imu, dt, seed, tau, tau_a, with_k, time_offset, robust, huber_k, holds
        )
        iterations += n
        if with_k and g_sensitivity == "auto":
            keep, gain, gain_se = _keeps_k(x, z)
            k_verdict = (keep, gain, gain_se)
            if not keep:
                seed, tau, tau_se, g_resid, gyro_weights, n, _, _ = _fit_gyro(
                    iv, imu, dt, before, tau, tau_a, False, time_offset, robust, huber_k, holds
                )
                iterations += n
    resid = np.concatenate([_rms(g_resid), _rms(a_resid)])
    seed = _with(seed, residual_rms=resid)
    quality = _quality(imu, iv, g_resid, a_resid)
    kept = bool(g_sensitivity) if k_verdict is None else k_verdict[0]
    return IntervalFit(
        seed, tau, tau_se, tau_a, tau_a_se, len(iv), interval_s, quality, lever_arm, kept, k_verdict,
        iterations, gyro_weights, (g_resid, a_resid),
    )  # fmt: skip


def fit_biases(
    rec: ReferencedRecording, *, interval_s: float = INTERVAL_S, holds: Holds | None = None
) -> IntervalFit:
    """The gyro's and the accelerometer's biases alone, on intervals: the model of a filter that
    estimates biases only (the PSINS demo's); no scale, misalignment, time offsets or lever arm.

    Raises
    ------
    ValueError
        as :func:`fit_intervals`.
    """
    iv = choose_intervals(rec, interval_s)
    imu, dt = rec.imu, np.diff(rec.imu.t)
    zeros, nan3, nan33 = np.zeros((3, 3)), np.full(3, np.nan), np.full((3, 3), np.nan)
    seed = SeedModelFit(
        B0=np.zeros(3), B=zeros, K=zeros, A0=np.zeros(3), A=zeros,
        B0_se=nan3, B_se=nan33, K_se=nan33, A0_se=nan3, A_se=nan33, residual_rms=np.full(6, np.nan),
    )  # fmt: skip
    c_ref_a = dcm(iv.q_start)
    r_ref = iv.body_turn()
    expected = expected_dv(iv, dt)
    for _ in range(3):  # the gyro's bias moves the attitude the accelerometer is turned by
        corrected = correct_increments(imu, seed)
        q = attitude.propagate_increments(corrected.dtheta_b, np.array([0.0, 0.0, 0.0, 1.0]))
        x = _gyro_design(q, np.eye(3), [dt[:, None]], None, iv)
        rot = dcm(q)
        r_meas = np.einsum("kji,kjl->kil", rot[iv.start], rot[iv.stop])
        y = rotation.rotvec_from_quat(rotation.quat_from_dcm(np.einsum("kji,kjl->kil", r_meas, r_ref)))
        step, cov_g, g_resid, _ = _solve_held(
            x, y, iv, False, 1.345, holds, identifiability.bias_names("gyro")
        )
        xa, ya = np.empty((len(iv), 3, 3)), np.empty((len(iv), 3))
        for k, (a, b) in enumerate(zip(iv.start, iv.stop, strict=True)):
            c_nb = c_ref_a[k] @ rot[a].T @ (0.5 * (rot[a:b] + rot[a + 1 : b + 1]))
            ya[k] = expected[k] - np.einsum("jab,jb->a", c_nb, corrected.dv_b[a:b])
            xa[k] = -np.einsum("jab,j->ab", c_nb, dt[a:b])
        step_a, cov_a, a_resid, _ = _solve_held(
            xa, ya, iv, False, 1.345, holds, identifiability.bias_names("accel")
        )
        seed = _with(
            seed, B0=seed.B0 + step, A0=seed.A0 + step_a,
            B0_se=np.sqrt(np.diag(cov_g)), A0_se=np.sqrt(np.diag(cov_a)),
        )  # fmt: skip
    seed = _with(seed, residual_rms=np.concatenate([_rms(g_resid), _rms(a_resid)]))
    quality = _quality(imu, iv, g_resid, a_resid)
    return IntervalFit(seed, 0.0, 0.0, 0.0, 0.0, len(iv), interval_s, quality, np.zeros(3), False)


def interval_reference(
    rec: ReferencedRecording, fit: IntervalFit, interval_s: float | None = None
) -> CalibrationData:
    """Per-sample references from the intervals, for strategies that learn from samples.

    Readings: the steps' mean rates and forces, read at the fitted time offsets, at the steps'
    middles. Reference: the seed model's correction of each reading, plus what the seed model leaves
    of its interval, as the constant body rate (and specific force) that would close the interval's
    residual. A learner of what the seed model leaves therefore sees each interval's residual, held
    over its samples; the seed model itself is reproduced. Steps outside every interval have no
    reference (NaN).
    """
    iv = choose_intervals(rec, interval_s or fit.interval_s)
    imu, dt = rec.imu, np.diff(rec.imu.t)
    shifted = ImuIncrements(
        t=imu.t,
        dtheta_b=shift_increments(imu, fit.time_offset_s, accel=False).dtheta_b,
        dv_b=shift_increments(imu, fit.accel_time_offset_s, gyro=False).dv_b,
    )
    corrected = fit.corrected(imu)
    q = attitude.propagate_increments(corrected.dtheta_b, np.array([0.0, 0.0, 0.0, 1.0]))
    rot = dcm(q)
    c_a = dcm(iv.q_start)
    r_meas = np.einsum("kji,kjl->kil", rot[iv.start], rot[iv.stop])
    r_ref = iv.body_turn()
    y_gyro = rotation.rotvec_from_quat(rotation.quat_from_dcm(np.einsum("kji,kjl->kil", r_meas, r_ref)))
    ref_gyro = np.full((len(dt), 3), np.nan)
    ref_accel = np.full((len(dt), 3), np.nan)
    expected = expected_dv(iv, dt) + np.einsum("kab,b->ka", lever(iv, imu, fit.seed, dt), fit.lever_arm_m)
    for k, (a, b) in enumerate(zip(iv.start, iv.stop, strict=True)):
        steps = dt[a:b]
        # Gyro: a constant δ over the interval turns its end by (Q_b^T Σ Q_j dt_j) δ.
        m = rot[b].T @ np.einsum("jab,j->ab", rot[a + 1 : b + 1], steps)
        delta = np.linalg.lstsq(m, y_gyro[k], rcond=1e-6)[0]
        ref_gyro[a:b] = corrected.dtheta_b[a:b] / steps[:, None] + delta
        # Accelerometer: the velocity change less gravity's against the corrected increments in NED.
        c_nb = c_a[k] @ rot[a].T @ (0.5 * (rot[a:b] + rot[a + 1 : b + 1]))
        made = np.einsum("jab,jb->a", c_nb, corrected.dv_b[a:b])
        spread = np.einsum("jab,j->ab", c_nb, steps)
        closing = np.linalg.lstsq(spread, expected[k] - made, rcond=1e-6)[0]
        ref_accel[a:b] = corrected.dv_b[a:b] / steps[:, None] + closing
    mid = 0.5 * (imu.t[:-1] + imu.t[1:])
    return CalibrationData(
        t=mid,
        gyro=shifted.dtheta_b / dt[:, None],
        accel=shifted.dv_b / dt[:, None],
        ref_gyro=ref_gyro,
        ref_accel=ref_accel,
        source=rec.source,
    )


def _rms(x: Array) -> Array:
    return np.asarray(np.sqrt(np.mean(x * x, axis=0)), dtype=float)


def _with(seed: SeedModelFit, **changes: Array) -> SeedModelFit:
    return SeedModelFit(**{**seed.__dict__, **changes})


def _fit_gyro(
    iv: Intervals, imu: ImuIncrements, dt: Array, seed: SeedModelFit, tau: float, tau_a: float,
    g_sensitivity: bool, time_offset: bool, robust: bool, huber_k: float, holds: Holds | None = None,
) -> tuple[SeedModelFit, float, float, Array, Array | None, int, Array, Array]:  # fmt: skip
    """Gauss–Newton on the gyro's coefficients (B0, B, K if asked, τ if asked). Returns the fit, τ and
    its standard error, the residuals, the weights, the iterations, and the last linearisation as
    pseudo-observations ``z ≈ x θ`` (``x`` (k, 3, p), ``z`` (k, 3)) for :func:`_keeps_k`."""
    r_ref = iv.body_turn()
    weights: Array | None = None
    cov = np.zeros((0, 0))
    iteration = 0
    while iteration < _MAX_ITERATIONS:
        iteration += 1
        x, y = gyro_problem(iv, imu, dt, seed, tau, tau_a, g_sensitivity, time_offset, r_ref)
        names = identifiability.gyro_names(g_sensitivity, time_offset)
        step, cov, resid, weights = _solve_held(x, y, iv, robust, huber_k, holds, names)
        theta = _gyro_vector(seed, tau, g_sensitivity, time_offset)
        seed, tau = _gyro_update(seed, tau, step, g_sensitivity, time_offset)
        se = np.sqrt(np.maximum(np.diag(cov), 1e-300))
        if np.all(np.abs(step) <= _CONVERGED_SE * se):
            break
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    nan = np.full((3, 3), np.nan)
    seed = _with(
        seed,
        B0_se=se[:3], B_se=se[3:12].reshape(3, 3),
        K_se=se[12:21].reshape(3, 3) if g_sensitivity else nan,
    )  # fmt: skip
    tau_se = float(se[-1]) if time_offset else 0.0
    return seed, tau, tau_se, resid, weights, iteration, x, y + np.einsum("kap,p->ka", x, theta)


def gyro_problem(
    iv: Intervals, imu: ImuIncrements, dt: Array, seed: SeedModelFit, tau: float, tau_a: float,
    g_sensitivity: bool, time_offset: bool, r_ref: Array | None = None,
) -> tuple[Array, Array]:  # fmt: skip
    """The gyro's linearised problem at ``seed``: each interval's Jacobian ``x`` (k, 3, p) (columns B0,
    B, K if asked, τ if asked) and residual rotation ``y`` (k, 3) of the corrected increments against the
    reference (``r_ref`` :meth:`Intervals.body_turn`, computed when not given)."""
    r_ref = iv.body_turn() if r_ref is None else r_ref
    corrected = correct_increments(imu, seed, tau, tau_a)
    dtheta, dv = corrected.dtheta_b, corrected.dv_b
    q = attitude.propagate_increments(dtheta, np.array([0.0, 0.0, 0.0, 1.0]))
    b_inv = np.asarray(np.linalg.inv(np.eye(3) + seed.B), dtype=float)
    blocks = [dt[:, None], dtheta] + ([dv] if g_sensitivity else [])
    extra = shift_derivative(imu.t, imu.dtheta_b, tau) @ b_inv.T if time_offset else None
    x = _gyro_design(q, b_inv, blocks, extra, iv)
    q_a, q_b = dcm(q[iv.start]), dcm(q[iv.stop])
    r_meas = np.einsum("kji,kjl->kil", q_a, q_b)
    y = rotation.rotvec_from_quat(rotation.quat_from_dcm(np.einsum("kji,kjl->kil", r_meas, r_ref)))
    return x, y


def _gyro_vector(seed: SeedModelFit, tau: float, g_sensitivity: bool, time_offset: bool) -> Array:
    """The gyro's parameters in :func:`_gyro_design`'s column order."""
    parts = [seed.B0, seed.B.ravel()] + ([seed.K.ravel()] if g_sensitivity else [])
    return np.concatenate(parts + ([np.array([tau])] if time_offset else []))


#: Folds of contiguous intervals on which :func:`predicts_held_back` judges columns (the g-sensitivity).
_K_FOLDS = 5
#: ... and the held-back gain it asks of K, in standard errors of that gain (the learners' guard rule).
_K_GUARD_Z = 2.0


def _keeps_k(x: Array, z: Array) -> tuple[bool, float, float]:
    """Whether the gyro's g-sensitivity ``K`` predicts intervals it was not fitted on
    (:func:`predicts_held_back` without K's columns). Returns the verdict, the gain (rad²) and its
    standard error."""
    return predicts_held_back(x, z, np.r_[0:12, 21 : x.shape[2]])


def predicts_held_back(x: Array, z: Array, without: NDArray[np.intp]) -> tuple[bool, float, float]:
    """Whether the columns of ``x`` (k, 3, p) not in ``without`` predict intervals they were not fitted
    on: least squares of ``z`` (k, 3) with every column and with ``without`` alone on all of
    :data:`_K_FOLDS` contiguous folds but one, the held-back fold's squared residuals compared, interval
    by interval; the columns are kept where the gain exceeds :data:`_K_GUARD_Z` standard errors (the
    learners' guard rule). Returns the verdict, the gain and its standard error."""
    k = len(z)
    fold = np.minimum(np.arange(k) * _K_FOLDS // k, _K_FOLDS - 1)
    diff = np.zeros(k)
    for f in range(_K_FOLDS):
        train, held = fold != f, fold == f
        sse = []
        for cols in (np.arange(x.shape[2]), without):
            xs = x[:, :, cols]
            theta = np.linalg.lstsq(xs[train].reshape(-1, len(cols)), z[train].reshape(-1), rcond=None)[0]
            r = z[held] - np.einsum("kap,p->ka", xs[held], theta)
            sse.append(np.sum(r * r, axis=1))
        diff[held] = sse[1] - sse[0]
    gain, se = float(diff.sum()), float(np.sqrt(k) * diff.std())
    return gain > _K_GUARD_Z * se, gain, se


def _gyro_design(q: Array, b_inv: Array, blocks: list[Array], extra: Array | None, iv: Intervals) -> Array:
    """Each interval's Jacobian (k, 3, p): a change ``δ_j`` of step ``j``'s corrected increment turns
    the interval's end by ``Q_b^T Q_j δ_j`` (``Q_j`` the attitude after step ``j``). Columns: B0, then
    B and K row-major (``∂x/∂M[r, c] = −(I + B)⁻¹ e_r u_c``, ``u`` the block's column ``c``), then τ.
    Built a chunk of intervals at a time: the per-step Jacobians of a long recording would not fit."""
    width = 3 * sum(block.shape[1] for block in blocks) + (extra is not None)
    out = np.empty((len(iv), 3, width))
    per_chunk = max(1, _CHUNK_STEPS // max(1, int(np.max(iv.stop - iv.start))))
    for k0 in range(0, len(iv), per_chunk):
        k1 = min(len(iv), k0 + per_chunk)
        s0, s1 = int(iv.start[k0]), int(iv.stop[k1 - 1])
        cols = [-b_inv[:, r][None, :] * block[s0:s1, c : c + 1]
                for block in blocks for r in range(3) for c in range(block.shape[1])]  # fmt: skip
        if extra is not None:
            cols.append(extra[s0:s1])
        f = np.stack(cols, axis=2)
        w = np.matmul(dcm(q[s0 + 1 : s1 + 1]), f).reshape(s1 - s0, 3 * width)
        part = interval_sums(w, iv.start[k0:k1] - s0, iv.stop[k0:k1] - s0).reshape(-1, 3, width)
        out[k0:k1] = np.einsum("kba,kbp->kap", dcm(q[iv.stop[k0:k1]]), part)
    return out


def _gyro_update(
    seed: SeedModelFit, tau: float, step: Array, g_sensitivity: bool, time_offset: bool
) -> tuple[SeedModelFit, float]:
    B0, B = seed.B0 + step[:3], seed.B + step[3:12].reshape(3, 3)
    K = seed.K + step[12:21].reshape(3, 3) if g_sensitivity else seed.K
    return _with(seed, B0=B0, B=B, K=K), tau + (float(step[-1]) if time_offset else 0.0)


def _fit_accel(
    iv: Intervals, imu: ImuIncrements, dt: Array, q_int: Array, seed: SeedModelFit, tau_a: float,
    time_offset: bool, robust: bool, huber_k: float, holds: Holds | None = None,
) -> tuple[Array, Array, Array, Array, Array, float, float]:  # fmt: skip
    """Least squares of the accelerometer's A0, A, time offset (if asked) and the lever arm ``r`` (the
    accelerometer's place relative to the reference's point, body axes) on the intervals' velocity
    changes; a few passes settle the inverse ``(I + A)⁻¹`` and the shift. Returns A0, A, their
    standard errors (12,), the residuals, ``r``, the offset and its standard error."""
    A0, A = seed.A0.copy(), seed.A.copy()
    expected = expected_dv(iv, dt)
    arm_matrix = lever(iv, imu, seed, dt)
    width = 16 if time_offset else 15
    cov = np.zeros((width, width))
    resid = np.zeros((len(iv), 3))
    for _ in range(4):
        x, y = accel_problem(iv, imu, dt, q_int, A0, A, tau_a, time_offset, expected, arm_matrix)
        step, cov, resid, _ = _solve_held(
            x, y, iv, robust, huber_k, holds, identifiability.accel_names(time_offset)
        )
        A0, A = A0 + step[:3], A + step[3:12].reshape(3, 3)
        if time_offset:
            tau_a += float(step[15])
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return A0, A, se[:12], resid, step[12:15], tau_a, float(se[15]) if time_offset else 0.0


def accel_problem(
    iv: Intervals, imu: ImuIncrements, dt: Array, q_int: Array, A0: Array, A: Array, tau_a: float,
    time_offset: bool, expected: Array, arm_matrix: Array,
) -> tuple[Array, Array]:  # fmt: skip
    """The accelerometer's linear problem at ``A0``, ``A``, ``tau_a``: each interval's Jacobian ``x``
    (k, 3, 15 or 16) (columns A0, A, the lever arm ``r``, τ if asked) and the velocity change the
    corrected increments leave ``y`` (k, 3); ``q_int`` the attitude the corrected gyro integrates to,
    ``expected`` :func:`~sins.compensation.intervals.expected_dv`, ``arm_matrix``
    :func:`~sins.compensation.intervals.lever`."""
    width = 16 if time_offset else 15
    # Interval k's velocity change in the reference's world is turn_k Σ_j mid_j u_j over its steps j, with
    # turn_k = C_ref(k) Q(k)ᵀ (Q the attitude the corrected gyro integrates to, at the interval's start),
    # mid_j that attitude at step j's middle (to first order) and u_j = (I + A)⁻¹ (dv_j − A0 dt_j) the
    # step's corrected increment. Its derivatives: −Σ_j mid_j dt_j (I + A)⁻¹ e_r for A0_r, and
    # −(Σ_j mid_j u_j,c) (I + A)⁻¹ e_r for A[r, c]: so only Σ_j mid_j ⊗ (dt_j, u_j) is summed over the
    # steps (and Σ_j mid_j ∂u_j/∂τ for the time offset), a chunk of intervals at a time (interval_sums).
    # A loop over the intervals, each step's 12 columns turned by its attitude, took half of a fit's time
    # on EuRoC's six recordings.
    turn = np.einsum("kab,kcb->kac", dcm(iv.q_start), dcm(q_int[iv.start]))
    a_inv = np.asarray(np.linalg.inv(np.eye(3) + A), dtype=float)
    dv = (shifted(imu.t, imu.dv_b, tau_a) - A0 * dt[:, None]) @ a_inv.T
    lag = shift_derivative(imu.t, imu.dv_b, tau_a) @ a_inv.T if time_offset else None
    sums = np.empty((len(iv), 3, 3, 4))  # Σ mid_j u_j,c (c < 3) and Σ mid_j dt_j (last)
    lagged = np.zeros((len(iv), 3))  # Σ mid_j ∂u_j/∂τ, with the time offset
    per_chunk = max(1, _CHUNK_STEPS // max(1, int(np.max(iv.stop - iv.start))))
    for k0 in range(0, len(iv), per_chunk):
        k1 = min(len(iv), k0 + per_chunk)
        s0, s1 = int(iv.start[k0]), int(iv.stop[k1 - 1])
        rot = dcm(q_int[s0 : s1 + 1])
        mid = 0.5 * (rot[:-1] + rot[1:])
        u = np.concatenate([dv[s0:s1], dt[s0:s1, None]], axis=1)
        per_step = (mid[:, :, :, None] * u[:, None, None, :]).reshape(len(u), 36)
        if lag is not None:
            per_step = np.concatenate([per_step, np.einsum("nab,nb->na", mid, lag[s0:s1])], axis=1)
        part = interval_sums(per_step, iv.start[k0:k1] - s0, iv.stop[k0:k1] - s0)
        sums[k0:k1] = part[:, :36].reshape(-1, 3, 3, 4)
        if lag is not None:
            lagged[k0:k1] = part[:, 36:]
    turned = np.einsum("kab,kbcp->kacp", turn, sums)  # (k, 3, 3 [c], 4 [u_c, dt])
    x = np.empty((len(iv), 3, width))
    y = expected - np.einsum("kacc->ka", turned[:, :, :, :3])
    x[:, :, :3] = -turned[:, :, :, 3] @ a_inv  # A0_r: −(turn Σ mid dt) (I + A)⁻¹ e_r
    for r in range(3):
        for c in range(3):
            x[:, :, 3 + 3 * r + c] = -turned[:, :, :, c] @ a_inv[:, r]
    if time_offset:
        x[:, :, 15] = np.einsum("kab,kb->ka", turn, lagged)
    # The accelerometer's Δv is the reference point's plus Δ(C (ω × r)) = lever r: on y's side, −lever.
    # r is estimated whole in every pass (y holds none of it); the rest by increments.
    x[:, :, 12:15] = -arm_matrix
    return x, y


def solve(
    x: Array, y: Array, iv: Intervals, robust: bool = False, huber_k: float = 1.345
) -> tuple[Array, Array, Array, Array | None]:
    """Weighted least squares of ``y ≈ x θ`` over intervals (see :func:`_solve`)."""
    return _solve(x, y, iv, robust, huber_k)


def _solve(
    x: Array, y: Array, iv: Intervals, robust: bool, huber_k: float
) -> tuple[Array, Array, Array, Array | None]:
    """Weighted least squares of ``y ≈ x θ`` over intervals; the covariance a sandwich that lets
    neighbouring intervals' residuals correlate (they share an epoch). Returns θ, its covariance, the
    residuals (k, 3) and the weights (None unless robust)."""
    k, _, p = x.shape
    if 3 * k <= p:
        raise ValueError(f"{k} intervals for {p} coefficients")
    scale = np.sqrt(np.mean(x * x, axis=(0, 1)))
    scale = np.where(scale > 0.0, scale, 1.0)
    xs = x / scale
    weights = np.ones(k)
    for _ in range(6 if robust else 1):
        root = np.sqrt(weights)[:, None, None]
        a, b = (root * xs).reshape(-1, p), (np.sqrt(weights)[:, None] * y).reshape(-1)
        theta, _, rank, sv = np.linalg.lstsq(a, b, rcond=None)
        if rank < p or sv[-1] < 1e-9 * sv[0]:
            raise ValueError(
                "the intervals do not determine every coefficient (the recording turns too little or "
                "in too few directions for them)"
            )
        resid = y - np.einsum("kap,p->ka", xs, theta)
        if not robust:
            break
        mad = np.median(np.abs(resid - np.median(resid, axis=0)), axis=0) / 0.6745
        z = np.abs(resid) / np.where(mad > 0.0, mad, 1.0)
        weights = np.minimum(1.0, huber_k / np.maximum(z, 1e-12)).min(axis=1)
    wx = np.sqrt(weights)[:, None, None] * xs
    bread = np.linalg.inv(np.einsum("kap,kaq->pq", wx, wx))
    score = np.einsum("kap,ka->kp", wx, np.sqrt(weights)[:, None] * resid)
    meat = score.T @ score
    joined = iv.stop[:-1] == iv.start[1:]
    lag = score[:-1][joined].T @ score[1:][joined]
    meat = meat + lag + lag.T
    cov = bread @ meat @ bread
    # The lag term can make a small variance negative in rounding; the plain one bounds it below then.
    plain = bread @ (score.T @ score) @ bread
    diag = np.where(np.diag(cov) > 0.0, np.diag(cov), np.diag(plain))
    np.fill_diagonal(cov, diag)
    cov = cov / np.outer(scale, scale)
    return theta / scale, cov, resid, weights if robust else None


def _solve_held(
    x: Array,
    y: Array,
    iv: Intervals,
    robust: bool,
    huber_k: float,
    holds: Holds | None,
    names: tuple[str, ...],
) -> tuple[Array, Array, Array, Array | None]:
    """:func:`_solve` on the columns not held (all without ``holds``); a held one gets no step and an
    infinite variance."""
    if holds is None:
        return _solve(x, y, iv, robust, huber_k)
    free = holds.free(names)
    if not free.any():
        raise ValueError(
            "the intervals determine none of the coefficients: " + "; ".join(holds.reasons.values())
        )
    step, cov, resid, weights = _solve(x[:, :, free], y, iv, robust, huber_k)
    return *widened(step, cov, free), resid, weights


def widened(step: Array, cov: Array, free: NDArray[np.bool_]) -> tuple[Array, Array]:
    """A solve on the ``free`` columns alone, widened to every column: a held one gets no step and an
    infinite variance (what ``sins fit`` prints ``0 (held)``)."""
    full_step, full_cov = np.zeros(len(free)), np.zeros((len(free), len(free)))
    full_step[free] = step
    full_cov[np.ix_(free, free)] = cov
    full_cov[~free, ~free] = np.inf
    return full_step, full_cov


def quality(imu: ImuIncrements, iv: Intervals, g_resid: Array, a_resid: Array) -> ReferenceQuality:
    """The residuals of still and moving intervals, and the sensor's own spread where still."""
    return _quality(imu, iv, g_resid, a_resid)


def _quality(imu: ImuIncrements, iv: Intervals, g_resid: Array, a_resid: Array) -> ReferenceQuality:
    """The residuals of still and moving intervals, and the sensor's own spread where still."""
    turn = rotation.turn_between(iv.q_start, iv.q_stop)
    speed = np.maximum(np.linalg.norm(iv.v_start, axis=1), np.linalg.norm(iv.v_stop, axis=1))
    still = (np.linalg.norm(turn, axis=1) < np.radians(0.5)) & (speed < 0.02)
    rms = lambda x: float(np.sqrt(np.mean(x * x)))  # noqa: E731
    dt = np.diff(imu.t)
    sensor: list[float | None] = [None, None]
    if still.sum() >= 5:
        for i, d in enumerate((imu.dtheta_b, imu.dv_b)):
            # White noise of σ per step integrates to σ·dt·√L over an interval of L steps.
            spread = [np.std(d[a:b] / dt[a:b, None], axis=0) * float(np.median(dt)) * np.sqrt(b - a)
                      for a, b in zip(iv.start[still], iv.stop[still], strict=True)]  # fmt: skip
            sensor[i] = rms(np.array(spread))
    moving = ~still if (~still).any() else still
    return ReferenceQuality(
        still=int(still.sum()),
        still_deg=float(np.degrees(rms(g_resid[still]))) if still.sum() >= 5 else None,
        still_mps=rms(a_resid[still]) if still.sum() >= 5 else None,
        sensor_still_deg=None if sensor[0] is None else float(np.degrees(sensor[0])),
        sensor_still_mps=sensor[1],
        moving_deg=float(np.degrees(rms(g_resid[moving]))),
        moving_mps=rms(a_resid[moving]),
    )


__all__ = [
    "IntervalFit",
    "ReferenceQuality",
    "accel_problem",
    "fit_biases",
    "fit_intervals",
    "gyro_problem",
    "interval_reference",
    "predicts_held_back",
    "quality",
    "solve",
    "widened",
]
