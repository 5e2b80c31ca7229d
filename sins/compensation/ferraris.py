"""Ferraris calibration: the seed model from six static holds and three turns of a known angle.

The method of Ferraris, Grimaldi and Parvis (Sensors and Materials 7(5), 1995), as imucal implements it
(github.com/mad-lab-fau/imucal, ``FerrarisCalibration``), for a unit turned by hand against a box:

* **holds** ``x_p, x_a, y_p, y_a, z_p, z_a``: each axis up, then down, at rest. Their mean readings give
  the accelerometer's scale and misalignment from each pair's difference and its bias from each pair's
  own axis; the gyro's bias from all six, and its g-sensitivity from each pair's difference;
* **turns** ``x_rot, y_rot, z_rot``: a whole turn about each axis, from rest to rest. The integrated
  gyro readings, less the bias and the g-sensitivity, against the known angle give the gyro's scale and
  misalignment (three turns, nine coefficients: determined exactly).

:class:`Ferraris` fits the seed model ``gyro = ω + B0 + B ω + K f``, ``accel = f + A0 + A f`` this way;
:func:`to_imucal` writes a seed model in imucal's parameters and :func:`check_session` measures what a
correction does to a session's holds, turns and the motions between holds.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from sins.compensation.base import Array, ParamRange, Strategy
from sins.core import rotation
from sins.core.series import CalibrationData, ImuIncrements, RigPhase
from sins.errors import SinsInputError
from sins.imu import calibration
from sins.nav import attitude

#: The static holds, in pairs (axis up, axis down) for x, y and z.
HOLDS = ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")
#: The turns, about x, y and z.
TURNS = ("x_rot", "y_rot", "z_rot")
#: A turn must begin and end at rest: the mean rate of its first and of its last three samples (bias
#: removed) below this fraction of its peak rate. Hand turns end within 1 % of the peak in both imucal
#: sessions; a turn cut short (by ``--validation``, say) ends near the peak.
_TURN_REST_FRACTION = 0.1


class Ferraris(Strategy):
    """The seed model from a Ferraris session (see the module docstring), sklearn style.

    ``fit(data)`` needs the nine named phases: the six holds (static, with a reference specific force
    along their own axis, ``+`` for ``*_p``) and the three turns (rotation phases with ``angle_rad``
    about their own axis); a :func:`~sins.io.datasets._read_ferraris` session has them.

    Estimators, per pair ``k`` (holds ``k_p``, ``k_a`` with mean readings ``U_p``, ``U_a`` and reference
    specific forces ``F_p ≈ +g e_k``, ``F_a ≈ −g e_k``):

    * ``I + A = [U_p − U_a] [F_p − F_a]⁻¹`` (columns over the three pairs);
    * ``A0_k``: the ``k`` component of ``((U_p + U_a) − (I + A)(F_p + F_a)) / 2``, from the pair on its own
      axis only. A hold placed by hand a small angle τ off moves that component by ``g(1 − cos τ)``,
      against ``g sin τ`` on the other axes, which imucal and this fit leave out of the bias (least
      squares over all six holds takes them in);
    * ``K = [G_p − G_a] [F_p − F_a]⁻¹`` from the gyro's hold means less their reference rate (0 in the
      readers), with ``g_sensitivity``; else 0;
    * ``B0``: the mean over the six holds of ``G − K F``, each hold weighted alike (imucal pools the
      samples, so that a longer hold weighs more);
    * ``I + B = W Θ⁻¹``: column ``k`` of ``W`` is turn ``k``'s readings less ``B0 + K f̂`` summed over its
      rows times the median sample interval (imucal's rectangle rule), with ``f̂`` the corrected specific
      force; column ``k`` of ``Θ`` is its ``angle_rad``. The turn's axis is taken as the body axis, as
      imucal takes it (the accelerometer's view of the axis during a hand turn is no better: see
      docs/validation.md).

    Standard errors (``*_se_``, same shapes and units):

    * a hold's mean: batch means (``batches`` consecutive blocks; a hold's readings are not white);
    * the holds' placement, ``placement_rad_``: one hold's tilt off its axis, 1σ per axis, from the
      pairs' half-sums. A pair placed ``α`` and ``β`` off (σ each) moves the off-axis half-sum by
      ``g(α + β)/2`` and the difference's column by ``(α − β)/2``, both σ/√2;
    * ``A``: the means' noise and, off the diagonal, σ/√2 of placement; on the diagonal and in ``A0``
      the placement reaches the pair's own axis through the misalignment (``Σ_j A_kj (α_j − β_j)/2``
      and ``g Σ_j A_kj (α_j + β_j)/2``);
    * ``K`` and ``B0``: the holds' noise. Not in them: the Earth's rate, which the readers' reference
      leaves out (heading unknown). In the holds it is indistinguishable from g-sensitivity: ``K``'s
      diagonal holds ``Ω sin φ / g`` and each off-diagonal up to ``Ω cos φ / g`` besides the sensor's
      own (5.7e-6 and 4.8e-6 (rad/s)/(m/s²) at 49.6° N);
    * ``B``: the turn's angle, known to ``turn_sd_deg`` (by hand against a box: the recording cannot
      tell it, and the default 2° is an assumption), the bias's error times the turn's duration and the
      readings' noise summed over the turn; and the turn's axis, taken to be off the body axis as far as
      a hold is placed (σ per axis: the same hand and box), which moves the off-diagonal entries by σ
      and the diagonal through the misalignment.

    None holds the error of the reference ``g`` itself (the readers assume the latitude: < 3e-4 of it).

    Corrections invert the seed model exactly, as :class:`~sins.compensation.regression.Regression`'s.
    """

    name = "ferraris"
    state_keys = (*Strategy.state_keys, "A_", "A0_", "A_se_", "A0_se_", "placement_rad_", "K_", "B0_",
                  "K_se_", "B0_se_", "B_", "B_se_")  # fmt: skip
    param_ranges: ClassVar[dict[str, ParamRange]] = {
        "turn_sd_deg": ParamRange(0, 90),
        "batches": ParamRange(1, 1000, whole=True),
    }

    def __init__(self, g_sensitivity: bool = True, turn_sd_deg: float = 2.0, batches: int = 10) -> None:
        self.g_sensitivity = g_sensitivity
        self.turn_sd_deg = turn_sd_deg
        self.batches = batches

    def fit(self, data: CalibrationData) -> Ferraris:
        """Fit the seed model from the session's holds and turns; returns self.

        Raises
        ------
        SinsInputError
            one line, naming the recording: a hold or turn missing or of the wrong kind, a hold's
            reference not along its axis, a turn without its angle or not from rest to rest.
        """
        data.check_readings()
        holds, turns = _session_phases(data)
        acc, acc_se, _ = _hold_means(data.accel, holds, self.batches)
        gyr, gyr_se, gyr_sd = _hold_means(data.gyro, holds, self.batches)
        f_ref = np.array([data.ref_accel[p.start : p.stop].mean(axis=0) for p in holds])
        w_ref = np.array([data.ref_gyro[p.start : p.stop].mean(axis=0) for p in holds])
        self.A_, self.A0_, self.A_se_, self.A0_se_, self.placement_rad_ = _accelerometer(acc, acc_se, f_ref)
        rest = _gyro_at_rest(gyr - w_ref, gyr_se, f_ref, self.g_sensitivity)
        self.K_, self.B0_, self.K_se_, self.B0_se_ = rest
        white = np.sqrt(np.mean(gyr_sd**2, axis=0))  # the gyro's per-sample noise at rest, rad/s
        self.B_, self.B_se_ = self._gyro_turns(data, turns, white)
        return self

    def _gyro_turns(self, data: CalibrationData, turns: list[RigPhase], white: Array) -> tuple[Array, Array]:
        """``B`` and its standard error from the turns, the rest fitted; ``white`` (3,) the gyro's
        per-sample noise, rad/s."""
        dt = float(np.median(np.diff(data.t)))
        theta = np.array([p.angle_rad for p in turns], dtype=float).T  # column k: turn k's angle vector
        w_sum = np.empty((3, 3))
        spread = np.empty((3, 3))  # column k: the variance the bias's error and the noise add to w_sum[:, k]
        zeros = np.zeros((3, 3))
        for k, p in enumerate(turns):
            rows = slice(p.start, p.stop)
            _, f_hat = calibration.invert_seed_model(
                np.zeros(3), zeros, zeros, self.A0_, self.A_, data.gyro[rows], data.accel[rows]
            )
            rate = data.gyro[rows] - self.B0_ - f_hat @ self.K_.T
            _check_from_rest(data.source, p, rate)
            n = p.stop - p.start
            w_sum[:, k] = rate.sum(axis=0) * dt
            spread[:, k] = (self.B0_se_ * n * dt) ** 2 + white**2 * n * dt**2
        ib = w_sum @ np.linalg.inv(theta)
        size = np.linalg.norm(theta, axis=0)
        # A turn's axis off the body axis by u (placement_rad_ per axis): entry (j, k) moves by u_j off the
        # diagonal, and the diagonal by Σ_j≠k (I + B)_kj u_j.
        off = ~np.eye(3, dtype=bool)
        coupling = np.where(off, ib, 0.0) ** 2 @ np.ones(3)
        axis = np.where(off, 1.0, np.diag(coupling)) * self.placement_rad_**2
        se = np.sqrt((ib * math.radians(self.turn_sd_deg) / size) ** 2 + spread / size**2 + axis)
        return ib - np.eye(3), se

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """Invert the fitted seed model exactly (``temp`` unused)."""
        return calibration.invert_seed_model(self.B0_, self.B_, self.K_, self.A0_, self.A_, gyro, accel)

    def correct_increments(self, imu: ImuIncrements, temp: Array | None = None) -> ImuIncrements:
        """Invert the seed model on the increments themselves (it is affine; see ``Regression``)."""
        imu = self.aligned_increments(imu)  # a time offset fitted against a reference, read first
        dtheta_b, dv_b = calibration.invert_seed_model(
            self.B0_, self.B_, self.K_, self.A0_, self.A_, imu.dtheta_b, imu.dv_b, dt=np.diff(imu.t)
        )
        return ImuIncrements(t=imu.t, dtheta_b=dtheta_b, dv_b=dv_b)


# --------------------------------------------------------------------------- the estimators


def _session_phases(data: CalibrationData) -> tuple[list[RigPhase], list[RigPhase]]:
    """The six holds and the three turns by name, checked; one-line refusals name the recording."""
    where = data.source or "recording"
    by_name = {p.name: p for p in data.phases}
    missing = [n for n in (*HOLDS, *TURNS) if n not in by_name]
    if missing:
        raise SinsInputError(
            f"{where}: a Ferraris calibration needs the six holds {', '.join(HOLDS)} and the three turns "
            f"{', '.join(TURNS)} as named phases; missing {', '.join(missing)}"
        )
    holds, turns = [by_name[n] for n in HOLDS], [by_name[n] for n in TURNS]
    for k, p in enumerate(holds):
        axis, sign = k // 2, 1.0 if k % 2 == 0 else -1.0
        ref = data.ref_accel[p.start : p.stop]
        if p.kind != "static" or p.stop - p.start < 2 or not np.isfinite(ref).all():
            raise SinsInputError(
                f"{where}: hold {p.name!r} must be a static phase of two or more rows with a reference "
                f"specific force on every row (found {p.kind}, {p.stop - p.start} rows)"
            )
        f = ref.mean(axis=0)
        if not sign * f[axis] > 0.95 * np.linalg.norm(f):
            raise SinsInputError(
                f"{where}: hold {p.name!r}: its reference specific force {np.round(f, 4).tolist()} m/s² "
                f"is not along {'+' if sign > 0 else '-'}{'xyz'[axis]}"
            )
        if not np.isfinite(data.ref_gyro[p.start : p.stop]).all():
            raise SinsInputError(f"{where}: hold {p.name!r} has no reference rate on some rows (0 at rest)")
    for k, p in enumerate(turns):
        if p.angle_rad is None:
            raise SinsInputError(
                f"{where}: turn {p.name!r} has no known angle (angle_rad); a turn's angle holds for the "
                "whole turn only, so fit on the whole session with nothing held back"
            )
        angle = np.asarray(p.angle_rad, dtype=float)
        if p.stop - p.start < 7 or not abs(angle[k]) > 0.95 * np.linalg.norm(angle):
            raise SinsInputError(
                f"{where}: turn {p.name!r} must be a phase of seven or more rows turning about "
                f"{'xyz'[k]} (found {p.stop - p.start} rows, angle_rad {p.angle_rad})"
            )
    return holds, turns


def _hold_means(x: Array, holds: list[RigPhase], batches: int) -> tuple[Array, Array, Array]:
    """Per hold (6, 3): the mean of ``x``, its standard error by batch means, and the readings' spread.

    The hold's rows are cut into ``batches`` consecutive blocks (fewer if it is short, at least two rows
    each); the standard error is the spread of the block means over ``√blocks``, which takes in the
    correlation of readings within a block, unlike ``sd/√n``.
    """
    mean, se, sd = (np.empty((len(holds), 3)) for _ in range(3))
    for i, p in enumerate(holds):
        rows = x[p.start : p.stop]
        n = len(rows)
        b = max(min(batches, n // 2), 1)
        mean[i] = rows.mean(axis=0)
        sd[i] = rows.std(axis=0, ddof=1)
        if b < 2:
            se[i] = sd[i] / math.sqrt(n)
            continue
        size = n // b
        blocks = rows[: size * b].reshape(b, size, 3).mean(axis=1)
        se[i] = blocks.std(axis=0, ddof=1) / math.sqrt(b)
    return mean, se, sd


def _pairs(values: Array) -> tuple[Array, Array]:
    """Per-hold rows (6, 3) as two (3, 3) matrices, column ``k`` the ``k_p`` and the ``k_a`` hold."""
    return values[0::2].T, values[1::2].T


def _accelerometer(acc: Array, acc_se: Array, f_ref: Array) -> tuple[Array, Array, Array, Array, float]:
    """``A``, ``A0``, their standard errors and one hold's placement error (rad, 1σ per axis).

    A pair placed ``α`` and ``β`` off (the off-axis parts of the up axis, σ each) moves the off-axis
    half-sum by ``g(α + β)/2`` and the difference's column by ``(α − β)/2``: both σ/√2, so the
    half-sums' RMS over ``g`` is σ/√2. Through the misalignment ``M_kj`` the tilts reach the pair's own
    axis too, at first order: ``A0_k`` by ``g Σ_j M_kj (α_j + β_j)/2`` and ``M_kk`` by
    ``Σ_j M_kj (α_j − β_j)/2``.
    """
    u_p, u_a = _pairs(acc)
    f_p, f_a = _pairs(f_ref)
    s_p, s_a = _pairs(acc_se)
    d_f = f_p - f_a
    m = (u_p - u_a) @ np.linalg.inv(d_f)
    half_sum = ((u_p + u_a) - m @ (f_p + f_a)) / 2.0
    a0 = np.diag(half_sum).copy()
    off = ~np.eye(3, dtype=bool)
    g = float(np.mean(np.abs(np.diag(d_f)))) / 2.0
    sigma = math.sqrt(2.0) * float(np.sqrt(np.mean((half_sum - a0[:, None])[off] ** 2)) / g)
    coupling = np.where(off, m, 0.0) ** 2 @ np.ones(3)  # Σ_j≠k M_kj², per row k
    # Entry (j, k) of M comes from column k's difference: its noise over |ΔF_k|.
    noise = np.sqrt(s_p**2 + s_a**2) / np.abs(np.diag(d_f))[None, :]
    m_se = np.sqrt(noise**2 + np.where(off, 1.0, np.diag(coupling)) * sigma**2 / 2.0)
    a0_se = np.sqrt((np.diag(s_p) ** 2 + np.diag(s_a) ** 2) / 4.0 + g**2 * sigma**2 / 2.0 * coupling)
    return m - np.eye(3), a0, m_se, a0_se, sigma


def _gyro_at_rest(
    gyr: Array, gyr_se: Array, f_ref: Array, g_sensitivity: bool
) -> tuple[Array, Array, Array, Array]:
    """``K``, ``B0`` and their standard errors from the holds' gyro means less their reference rate."""
    g_p, g_a = _pairs(gyr)
    f_p, f_a = _pairs(f_ref)
    s_p, s_a = _pairs(gyr_se)
    d_f = np.diag(f_p - f_a)
    if g_sensitivity:
        k = (g_p - g_a) @ np.linalg.inv(f_p - f_a)
        k_se = np.sqrt(s_p**2 + s_a**2) / np.abs(d_f)[None, :]
    else:
        k, k_se = np.zeros((3, 3)), np.zeros((3, 3))
    b0 = (gyr - f_ref @ k.T).mean(axis=0)
    b0_se = np.sqrt((gyr_se**2).sum(axis=0)) / len(gyr)
    return k, b0, k_se, b0_se


def _check_from_rest(source: str, phase: RigPhase, rate: Array) -> None:
    """Refuse a turn that does not begin and end at rest (see :data:`_TURN_REST_FRACTION`)."""
    speed = np.linalg.norm(rate, axis=1)
    ends = max(float(speed[:3].mean()), float(speed[-3:].mean()))
    peak = float(speed.max())
    if not ends <= _TURN_REST_FRACTION * peak:
        raise SinsInputError(
            f"{source or 'recording'}: turn {phase.name!r} does not begin and end at rest "
            f"({math.degrees(ends):.1f} °/s at an end against {math.degrees(peak):.1f} °/s at its peak): "
            "a turn must be whole (fit on the whole session, nothing held back)"
        )


# --------------------------------------------------------------------------- imucal's parameters


@dataclass(frozen=True)
class ImucalCalibration:
    """A Ferraris calibration in imucal's parameters (``FerrarisCalibrationInfo``).

    Accelerometer: gains ``K_a`` (3, 3) diagonal, input units per m/s²; misalignment ``R_a`` (3, 3), rows
    of unit length; bias ``b_a`` (3,), input units. Gyro: gains ``K_g`` (input units per °/s),
    misalignment ``R_g``, acceleration sensitivity ``K_ga`` (input units per m/s²), bias ``b_g``.
    """

    K_a: Array
    R_a: Array
    b_a: Array
    K_g: Array
    R_g: Array
    K_ga: Array
    b_g: Array


def to_imucal(
    B0: Array, B: Array, K: Array, A0: Array, A: Array, *,
    accel_unit_mps2: float = 1.0, gyro_unit_dps: float = 1.0,
) -> ImucalCalibration:  # fmt: skip
    """The seed model's coefficients (SI, as :class:`Ferraris` fits them) in imucal's parameters.

    imucal calibrates raw readings ``a`` and ``w`` (its input units) as

        ``acc = R_a⁻¹ K_a⁻¹ (a − b_a)``,  ``gyr = R_g⁻¹ K_g⁻¹ (w − K_ga acc − b_g)``

    in m/s² and °/s, so ``a = K_a R_a f + b_a`` and ``w = K_g R_g ω° + K_ga f + b_g`` (``ω°`` in °/s).
    sins reads ``accel = c_a a`` and ``gyro = c_g (π/180) w`` in SI, with ``c_a = accel_unit_mps2`` and
    ``c_g = gyro_unit_dps`` (one input unit in m/s² and in °/s); its seed model is
    ``accel = (I + A) f + A0`` and ``gyro = (I + B) ω + K f + B0``. Term by term:

        ``K_a R_a = (I + A) / c_a``,  ``b_a = A0 / c_a``,
        ``K_g R_g = (I + B) / c_g``,  ``K_ga = K / (c_g π/180)``,  ``b_g = B0 / (c_g π/180)``,

    each product split as imucal splits it: ``K`` the rows' lengths, ``R`` the rows made unit. A turn
    taken the other way round (imucal's −360° against a session's +360°) negates ``R_g`` and leaves the
    rest as it is.

    Parameters
    ----------
    B0, B, K, A0, A : the seed model's coefficients, rad/s, 1, (rad/s)/(m/s²), m/s², 1
    accel_unit_mps2 : one of imucal's accelerometer input units, m/s² (1 for readings in m/s²)
    gyro_unit_dps : one of imucal's gyro input units, °/s (1 for readings in °/s)
    """
    per_rad = gyro_unit_dps * math.pi / 180.0  # one gyro input unit, rad/s

    def split(m: Array) -> tuple[Array, Array]:
        gains = np.linalg.norm(m, axis=1)
        return np.diag(gains), m / gains[:, None]

    k_a, r_a = split((np.eye(3) + np.asarray(A)) / accel_unit_mps2)
    k_g, r_g = split((np.eye(3) + np.asarray(B)) / gyro_unit_dps)
    return ImucalCalibration(
        K_a=k_a, R_a=r_a, b_a=np.asarray(A0) / accel_unit_mps2,
        K_g=k_g, R_g=r_g, K_ga=np.asarray(K) / per_rad, b_g=np.asarray(B0) / per_rad,
    )  # fmt: skip


@dataclass(frozen=True)
class ComparisonRow:
    """One of imucal's parameters, one entry: its value in a reference calibration and in a sins fit (in
    imucal's units), and the fit's standard error there (to first order; NaN for ``R``'s diagonal,
    which the unit rows fix to ``1 − O(misalignment²)``)."""

    parameter: str
    entry: tuple[int, ...]
    reference: float
    sins: float
    se: float


def compare_with_imucal(
    fitted: Ferraris,
    reference: ImucalCalibration,
    *,
    accel_unit_mps2: float = 1.0,
    gyro_unit_dps: float = 1.0,
) -> tuple[ComparisonRow, ...]:
    """Every gain, misalignment and bias of ``reference`` beside ``fitted``'s, in imucal's parameters.

    Gains ``K_a``, ``K_g`` (their diagonals), misalignments ``R_a``, ``R_g``, the gyro's acceleration
    sensitivity ``K_ga`` and the biases ``b_a``, ``b_g``, in that order; units as :func:`to_imucal`.
    """
    ours = to_imucal(
        fitted.B0_, fitted.B_, fitted.K_, fitted.A0_, fitted.A_,
        accel_unit_mps2=accel_unit_mps2, gyro_unit_dps=gyro_unit_dps,
    )  # fmt: skip
    per_rad = gyro_unit_dps * math.pi / 180.0
    off = ~np.eye(3, dtype=bool)
    # First order: a gain is its row's length, so it moves with the diagonal entry; an entry of R moves
    # with the matching entry of (I + A) or (I + B) over its row's length.
    se = {
        "K_a": np.diag(fitted.A_se_) / accel_unit_mps2,
        "R_a": np.where(off, fitted.A_se_ / np.linalg.norm(np.eye(3) + fitted.A_, axis=1)[:, None], np.nan),
        "b_a": fitted.A0_se_ / accel_unit_mps2,
        "K_g": np.diag(fitted.B_se_) / gyro_unit_dps,
        "R_g": np.where(off, fitted.B_se_ / np.linalg.norm(np.eye(3) + fitted.B_, axis=1)[:, None], np.nan),
        "K_ga": fitted.K_se_ / per_rad,
        "b_g": fitted.B0_se_ / per_rad,
    }
    rows = []
    for name in ("K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g"):
        ref, mine = np.asarray(getattr(reference, name), dtype=float), getattr(ours, name)
        if name in ("K_a", "K_g"):
            ref, mine = np.diag(ref), np.diag(mine)
        for entry in np.ndindex(ref.shape):
            rows.append(
                ComparisonRow(name, entry, float(ref[entry]), float(mine[entry]), float(se[name][entry]))
            )
    return tuple(rows)


# --------------------------------------------------------------------------- what a correction does


@dataclass(frozen=True)
class HoldCheck:
    """One hold after correction: ``|f̄| − |f_ref|`` (m/s²), the angle between ``f̄`` and the reference
    (rad: the hold's placement, where the sensor is calibrated) and the mean rate less the reference
    (3,) rad/s; ``f̄`` is the hold's mean corrected specific force."""

    name: str
    force_error_mps2: float
    tilt_rad: float
    rate_radps: Array


@dataclass(frozen=True)
class TurnCheck:
    """One turn after correction: the integrated rate (3,) rad/s·s (rectangle rule at the median
    sample interval) and the known angle (3,) rad."""

    name: str
    angle_rad: Array
    expected_rad: Array


@dataclass(frozen=True)
class TransitionCheck:
    """The motion from one hold to the next, which no fit sees: the corrected gyro carries the first
    hold's mean specific force into the second's body axes (open-loop attitude); ``error_rad`` is its
    angle from the second hold's mean, ``turned_rad`` how far the unit turned, ``seconds`` how long."""

    start: str
    end: str
    seconds: float
    turned_rad: float
    error_rad: float


@dataclass(frozen=True)
class SessionCheck:
    """What a correction does to a session: its holds, turns and the motions between holds."""

    holds: tuple[HoldCheck, ...]
    turns: tuple[TurnCheck, ...]
    transitions: tuple[TransitionCheck, ...]


def check_session(strategy: Strategy, data: CalibrationData) -> SessionCheck:
    """The holds, turns and transitions of a Ferraris-like session after ``strategy``'s correction.

    Holds: every static phase with a reference. Turns: every phase with a known ``angle_rad``.
    Transitions: every pair of consecutive static phases with rows between them and no phase there (the
    example session has five; the annotated one, whose sections abut, none). The holds and turns a
    Ferraris fit used come out as fitted (``|f̄|`` ≈ g and the turns at their angle by construction);
    the transitions are motions no fit saw.
    """
    gyro, accel = strategy.correct(data.gyro, data.accel, data.temp)
    dt = float(np.median(np.diff(data.t)))
    holds, turns = [], []
    for p in data.phases:
        rows = slice(p.start, p.stop)
        if p.angle_rad is not None:
            turns.append(TurnCheck(p.name, gyro[rows].sum(axis=0) * dt, np.asarray(p.angle_rad, dtype=float)))
        elif p.kind == "static" and np.isfinite(data.ref_accel[rows]).all():
            f, f_ref = accel[rows].mean(axis=0), data.ref_accel[rows].mean(axis=0)
            holds.append(
                HoldCheck(
                    p.name, float(np.linalg.norm(f) - np.linalg.norm(f_ref)), _angle_between(f, f_ref),
                    gyro[rows].mean(axis=0) - data.ref_gyro[rows].mean(axis=0),
                )
            )  # fmt: skip
    ordered = sorted(data.phases, key=lambda p: p.start)
    transitions = []
    for a, b in itertools.pairwise(ordered):
        if a.kind != "static" or b.kind != "static" or b.start <= a.stop:
            continue
        rows = slice(a.stop - 1, b.start + 1)  # from the first hold's last row to the next one's first
        q = attitude.propagate(data.t[rows], gyro[rows], np.array([0.0, 0.0, 0.0, 1.0]))
        c_nb = rotation.dcm_from_quat(q[-1])  # n: the body axes at the first hold
        carried = c_nb.T @ accel[a.start : a.stop].mean(axis=0)
        turned = 2.0 * math.atan2(float(np.linalg.norm(q[-1, :3])), abs(float(q[-1, 3])))
        transitions.append(
            TransitionCheck(
                a.name, b.name, float(data.t[b.start] - data.t[a.stop - 1]), turned,
                _angle_between(carried, accel[b.start : b.stop].mean(axis=0)),
            )
        )  # fmt: skip
    return SessionCheck(tuple(holds), tuple(turns), tuple(transitions))


def _angle_between(u: Array, v: Array) -> float:
    """The angle between two vectors, rad (atan2 of the cross and dot products: exact near 0 and π)."""
    return math.atan2(float(np.linalg.norm(np.cross(u, v))), float(np.dot(u, v)))


__all__ = [
    "HOLDS",
    "TURNS",
    "ComparisonRow",
    "Ferraris",
    "HoldCheck",
    "ImucalCalibration",
    "SessionCheck",
    "TransitionCheck",
    "TurnCheck",
    "check_session",
    "compare_with_imucal",
    "to_imucal",
]
