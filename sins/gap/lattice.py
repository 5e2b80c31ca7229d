"""Readings on a lattice: finding the step, and the probability of each reading under a quantizer.

A quantizer outputs ``offset + m·step`` for integers ``m``. Two kinds are modelled, both driven by
a predicted (unrounded, noiseless) reading ``ŷ`` and white noise ``σ`` before the rounding, written
in lattice units as ``μ = (ŷ − offset) / step`` and ``s = σ / step``:

* *rounded*: each reading is rounded on its own (as :meth:`sins.imu.ImuModel.corrupt_rates` does),
  ``m_k = round(μ_k + w_k)``. The readings are independent,
  ``P(m) = Φ((m + ½ − μ)/s) − Φ((m − ½ − μ)/s)``.
* *carried*: increments are rounded with the remainder carried to the next (a ΔΘ/ΔV output, as
  :meth:`sins.imu.ImuModel.corrupt_increments` makes), so the readings' running sum is the rounded
  running sum of ``μ + w``. Each reading then depends on where the running sum lay in its lattice
  cell, which the readings so far say only in part: :func:`carried` filters that position on a grid
  of cells.

Either gives ``P(m_k | m_<k)`` for every row, so a quantizer's likelihood of the readings can be held
against a continuous model's probability of the same lattice bins (:func:`binned`), the readings'
recorded resolution being the lattice step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize
from scipy.special import log_ndtr, ndtr

Array = NDArray[np.float64]

#: A probability no reading falls below: a reading the model calls impossible costs ln 1e-12 ≈ −28 nats.
_FLOOR = 1e-12
#: The logarithm of the standard normal density's normaliser.
_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)
#: The prior standard deviation of :func:`fit_rounded`'s correction to the means, in lattice steps.
_PRIOR_STEPS = 1.0
#: The prior standard deviation of :func:`fit_rounded`'s log noise about its start (a factor of e).
_PRIOR_LOG_S = 1.0
#: Cells of the running sum's position in its lattice cell, in :func:`carried`.
CELLS = 16
#: The most lattice steps :func:`find` lets the smallest gap between readings span.
_MAX_STEPS_PER_GAP = 1000
#: Readings taking fewer distinct values than this share of their number are held on levels.
_LEVELS_SHARE = 0.01
#: Points per period of the tabulated excess of the expected rounding over its argument.
_TABLE = 512


@dataclass(frozen=True)
class Lattice:
    """Readings ``offset + m·step``: the step and offset in the readings' units."""

    step: float
    offset: float

    def index(self, reading: Array) -> Array:
        """The lattice index ``m`` of each reading, as floats."""
        return np.round((reading - self.offset) / self.step)

    def units(self, value: Array) -> Array:
        """Values in lattice units, ``(value − offset) / step``."""
        return (value - self.offset) / self.step


@dataclass(frozen=True)
class Printed:
    """How a file printed its numbers: at most ``digits`` significant digits, or ``decimals`` digits
    after the point (None: not limited; a float printed to read back exactly is neither)."""

    digits: int | None = None
    decimals: int | None = None

    def half_unit(self, values: Array) -> Array:
        """Half a unit in the last printed place of each value: how far printing may have moved it."""
        half = np.zeros_like(values, dtype=np.float64)
        if self.decimals is not None:
            half = np.full_like(half, 0.5 * 10.0**-self.decimals)
        if self.digits is not None:
            tiny = np.finfo(np.float64).tiny
            exponent = np.floor(np.log10(np.maximum(np.abs(values), tiny)))
            by_digits = np.where(values == 0.0, 0.0, 0.5 * 10.0 ** (exponent - self.digits + 1))
            # Either format may be the one printed (a value read back from both): the looser bound.
            half = np.maximum(half, by_digits)
        return half


#: A print that keeps this many significant digits reads back every float (or nearly: 1e-15 apart).
_FULL_DIGITS = 15
#: Values sampled to learn how a file printed its numbers.
_HABIT_PROBE = 4000
#: A step finer than this many half units of the print that set it is the print's resolution. At 100
#: a level lies within the print's slack of a wrong divisor's lattice by chance one time in 45 at most,
#: so the five levels beyond the two that set a held step pass together one time in 2e8.
_PRINT_MARGIN = 100.0


def print_habit(*columns: Array) -> Printed:
    """How the columns of one file were printed: the fewest significant digits, and the fewest decimals,
    that every value of every column reads back from (a file prints its columns one way, so a column
    whose values need few digits, readings on a round lattice, is told by the others).

    A column's values read back from ``d`` significant digits when each equals the float its ``%.{d-1}e``
    text reads as; ``_FULL_DIGITS`` or more, or more than 12 decimals, mean the print holds the float.
    """
    probe = _probe(columns)
    if len(probe) == 0:
        return Printed()
    digits = next(
        (d for d in range(1, _FULL_DIGITS) if all(float(f"{v:.{d - 1}e}") == v for v in probe)), None
    )
    decimals = next((n for n in range(13) if all(float(f"{v:.{n}f}") == v for v in probe)), None)
    return Printed(digits, decimals)


def _probe(columns: tuple[Array, ...]) -> Array:
    """Every ``k``-th finite nonzero value of the columns one after another, ``k`` the count over
    :data:`_HABIT_PROBE`: the values picked from each column in place, never all of them in one
    array (a long recording's twelve columns would be as large as its readings again)."""

    def kept(column: Array) -> NDArray[np.bool_]:
        values = np.ravel(column)
        return np.isfinite(values) & (values != 0.0)

    counts = [int(np.count_nonzero(kept(c))) for c in columns]
    if sum(counts) == 0:
        return np.zeros(0)
    stride, offset, parts = max(1, sum(counts) // _HABIT_PROBE), 0, []
    for column, count in zip(columns, counts, strict=True):
        first = (-offset) % stride  # the first pick in this column, counted from its first value kept
        parts.append(np.ravel(column)[np.flatnonzero(kept(column))[first::stride]])
        offset += count
    return np.concatenate(parts)


def find(reading: Array, tolerance: float = 1e-6, printed: Printed = Printed()) -> Lattice | None:
    """The coarsest lattice every reading lies on, or None.

    The step is the smallest gap between distinct values, or, for readings held on a few levels
    (fewer distinct values than :data:`_LEVELS_SHARE` of the readings), that gap over the least whole
    number (up to :data:`_MAX_STEPS_PER_GAP`) that puts every reading within ``tolerance`` steps of a
    lattice point: where rounding is far coarser than the noise, static readings may never leave
    their levels, and no two levels need lie one step apart. The readings must take fewer distinct
    values than half their number (else the gaps are only the spread of a continuous reading).

    Readings printed to a limited number of places (``printed``, from :func:`print_habit` of the
    file) lie on their lattice only to within half a unit in the last place: a reading of 250 °/s
    printed to 10 significant digits may sit 1e-6 of a 0.06 °/s step off it. There each reading may
    lie that much farther from the lattice, and the step and offset are refined by least squares
    over the readings' lattice indices (the smallest gap alone holds the print's error, which grows
    with the index). A step within :data:`_PRINT_MARGIN` half units of the print that set it is the
    file's resolution, not a quantizer's: None.
    """
    values = np.unique(reading[np.isfinite(reading)])
    if len(values) < 2 or len(values) >= 0.5 * len(reading):
        return None
    gaps = np.diff(values)
    gaps = gaps[gaps > 1e-12 * max(float(np.abs(values).max()), 1e-300)]
    if len(gaps) == 0:
        return None
    smallest, nearest_zero = float(gaps.min()), float(values[np.argmin(np.abs(values))])
    half_unit = printed.half_unit(values)
    at_smallest = float(half_unit[np.argmin(np.diff(values)) + np.array([0, 1])].max())
    probe = values[:: max(1, len(values) // 64)]  # most wrong steps fail on a few values: test those first
    # Readings that move visit neighbouring lattice points: only readings held on a few levels can
    # leave their smallest gap more than one step wide (else the divisor found would be the
    # resolution a file was printed at, not a quantizer's).
    held = len(values) < _LEVELS_SHARE * len(reading)
    for k in range(1, (_MAX_STEPS_PER_GAP if held else 1) + 1):
        step = smallest / k
        if step <= _PRINT_MARGIN * at_smallest:
            return None
        offset = nearest_zero - step * np.round(nearest_zero / step)
        if not half_unit.any():
            if _misfit(probe, step, offset) <= tolerance and _misfit(values, step, offset) <= tolerance:
                return Lattice(step, offset)
            continue
        step, offset = _refined(values, step, offset, at_smallest / step)
        # Half a unit of print, and a tenth more for the fitted step's and offset's own error.
        slack = tolerance + 1.1 * half_unit / step
        if (_misfits(values, step, offset) <= slack).all():
            return Lattice(step, offset)
    return None


def _refined(values: Array, step: float, offset: float, error: float) -> tuple[float, float]:
    """The step and offset of the lattice ``values`` lie on, by least squares over their indices,
    from a step ``error`` steps off: indices are trusted out to where that error could reach a
    quarter step, and each fit lets them reach farther."""
    for _ in range(8):
        m = np.round((values - offset) / step)
        near = np.abs(m - np.round((0.0 - offset) / step)) <= 0.25 / max(error, 1e-300)
        if len(np.unique(m[near])) < 2:
            break
        design = np.column_stack([np.ones(int(near.sum())), m[near]])
        (offset, step), *_ = np.linalg.lstsq(design, values[near], rcond=None)
        offset, step = float(offset), float(step)
        if near.all():
            break
        # The fit's step error over indices up to M is about the print's error over M: a quarter of the
        # old reach's error at most, so the trusted reach at least quadruples.
        error /= 4.0
    return step, offset


def _misfits(values: Array, step: float, offset: float) -> Array:
    """How far each value lies from the lattice ``offset + m·step``, in steps."""
    m = (values - offset) / step
    return np.abs(m - np.round(m))


def _misfit(values: Array, step: float, offset: float) -> float:
    """The farthest any value lies from the lattice ``offset + m·step``, in steps."""
    m = (values - offset) / step
    return float(np.abs(m - np.round(m)).max())


def rounded(m: Array, mu: Array, s: float) -> tuple[Array, Array, Array]:
    """Each reading rounded on its own: ``ln P(m_k)``, and the mean and variance of ``m_k``, of every row."""
    first, second = _rounding_moments(mu, s)
    return rounded_loglik(m, mu, s), mu + first, second - first**2


def rounded_loglik(m: Array, mu: Array, s: float) -> Array:
    """``ln P(m_k)`` of each reading rounded on its own, without :func:`rounded`'s moments (a tenth
    of its cost), for choosing among quantizers."""
    p = ndtr((m + 0.5 - mu) / s) - ndtr((m - 0.5 - mu) / s)
    return np.log(np.maximum(p, _FLOOR))


def fit_rounded(m: Array, mu: Array, columns: Array, s: float) -> tuple[Array, float]:
    """The correction ``δ`` to the means ``μ + A δ`` (``A`` the columns) and the noise ``s`` that make
    readings rounded on their own most likely: a Gaussian regression censored to each reading's
    lattice cell, started from ``δ = 0`` and the given ``s`` (in steps, kept within 0.001–10), and
    held near them by weak priors.

    Least squares on rounded readings misplaces the mean wherever the noise is small against the
    step: a reading that leaves its usual lattice point one time in twenty lies near a rounding
    edge, not a twentieth of a step from the point. The log-likelihood is concave in ``(δ/s, 1/s)``,
    but flat where it is a set of inequalities: a static hold whose readings never leave their
    level says only that its mean lies well inside the cell, and where each hold whose readings do
    change has a mean of its own, the noise scales those means and is not identified at all.
    Gaussian priors on ``δ`` (:data:`_PRIOR_STEPS` steps) and on ``ln s`` (about the start,
    :data:`_PRIOR_LOG_S`) make the maximum unique there, the point of that set nearest the start,
    and hardly move an identified one (12 levels of 1,000 readings at 0.15 step of noise: the
    means within 0.002 step and the noise within 3 % on three seeds, as before the priors). The
    readings' probabilities are taken in logarithms throughout, so that readings far from the
    start's means still pull the search (a floored probability has no gradient).
    """

    def cost(theta: Array) -> tuple[float, Array]:
        delta, log_s = theta[:-1], theta[-1]
        sd = float(np.exp(log_s))
        z1 = (m + 0.5 - mu - columns @ delta) / sd
        z0 = z1 - 1.0 / sd
        # ln(Φ(z1) − Φ(z0)); where both edges lie above the mean, ln(Φ(−z0) − Φ(−z1)) keeps the digits.
        upper = z0 > 0.0
        near, far = np.where(upper, -z0, z1), np.where(upper, -z1, z0)
        log_near = log_ndtr(near)
        log_p = log_near + np.log(-np.expm1(log_ndtr(far) - log_near))
        d1 = np.exp(-0.5 * z1 * z1 - _LOG_SQRT_2PI - log_p)  # φ(z1) / P
        d0 = np.exp(-0.5 * z0 * z0 - _LOG_SQRT_2PI - log_p)
        d_mu = -(d1 - d0) / sd  # ∂ ln P / ∂ μ
        d_log_s = -(z1 * d1 - z0 * d0)
        prior, prior_s = delta / _PRIOR_STEPS**2, (log_s - log_s0) / _PRIOR_LOG_S**2
        grad = np.concatenate([columns.T @ d_mu - prior, [d_log_s.sum() - prior_s]])
        return -float(log_p.sum() - 0.5 * delta @ prior - 0.5 * (log_s - log_s0) * prior_s), -grad

    k = columns.shape[1]
    log_s0 = float(np.log(np.clip(s, 1e-3, 10.0)))
    start = np.concatenate([np.zeros(k), [log_s0]])
    bounds = [(None, None)] * k + [(np.log(1e-3), np.log(10.0))]
    found = minimize(cost, start, jac=True, method="L-BFGS-B", bounds=bounds)
    return found.x[:-1], float(np.exp(found.x[-1]))


def expected_rounding(z: Array, s: float) -> Array:
    """``E[round(z + w)]`` for ``w ~ N(0, s²)``."""
    return z + _rounding_moments(z, s)[0]


def _rounding_moments(z: Array, s: float) -> tuple[Array, Array]:
    """``E[e]`` and ``E[e²]`` of ``e = round(z + w) − z``, ``w ~ N(0, s²)``: sums over the nearest
    lattice points (points beyond ``±(4 + 6 s)`` hold less than 1e-9). Both are periodic in ``z``."""
    base = np.floor(z)
    first, second = np.zeros_like(z), np.zeros_like(z)
    reach = int(np.ceil(4 + 6 * s))
    for j in range(-reach, reach + 1):
        e = base + j - z
        p = ndtr((e + 0.5) / s) - ndtr((e - 0.5) / s)
        first += e * p
        second += e * e * p
    return first, second


def carried(m: Array, mu: Array, s: float, cells: int = CELLS) -> tuple[Array, Array, Array]:
    """Increments rounded with the remainder carried: ``ln P(m_k | m_<k)``, and the mean and variance
    of ``m_k`` given ``m_<k``, of every row.

    The running sum ``S_k = S_{k−1} + μ_k + w_k`` is output as ``R_k = round(S_k)``, and the reading is
    ``m_k = R_k − R_{k−1}``. The state is the position ``u = S − R`` in ``[−½, ½)``, held as masses at
    the centres of ``cells`` equal cells (uniform at the start). ``s`` below half a cell is raised to
    it: the grid cannot hold a position more sharply.
    """
    s = max(float(s), 0.5 / cells)
    # The moments of round(z + w) − z are periodic in z: tabulated over one period, interpolated.
    first, second = _rounding_moments(np.linspace(0.0, 1.0, _TABLE + 1), s)
    m, mu = (np.ascontiguousarray(a, dtype=np.float64) for a in (m, mu))
    return _carried(m, mu, s, cells, first, second)


@numba.njit(cache=True, nogil=True)
def _cdf(x: float) -> float:
    return 0.5 * math.erfc(-x / math.sqrt(2.0))


@numba.njit(cache=True, nogil=True)
def _carried(
    m: Array, mu: Array, s: float, cells: int, first: Array, second: Array
) -> tuple[Array, Array, Array]:
    # With the cells' centres at u_i = −½ + (i + ½)/M and edges at b_j = −½ + j/M, the reading m moves
    # the mass at u_i into cell j when w lies between x_n and x_{n+1}, n = j − i + m·M, where
    # x_n = (n − ½)/M − μ. One F_n = Φ(x_n / s) per n in m·M − M … m·M + M serves every (i, j): the
    # new masses are a discrete convolution of the old with F's differences, and P(m) their sum.
    n_rows, big, table = len(m), cells, len(first) - 1
    p = np.full(big, 1.0 / big)
    new = np.empty(big)
    f = np.empty(2 * big + 1)
    loglik = np.empty(n_rows)
    expected = np.empty(n_rows)
    variance = np.empty(n_rows)
    for k in range(n_rows):
        d, obs = mu[k], m[k]
        # From position u_i the reading is round(z_i + w), z_i = u_i + μ: mix its moments over i.
        mean = square = 0.0
        for i in range(big):
            z = (i + 0.5) / big - 0.5 + d
            pos = (z - np.floor(z)) * table
            a = min(int(pos), table - 1)
            e1 = first[a] + (pos - a) * (first[a + 1] - first[a])
            e2 = second[a] + (pos - a) * (second[a + 1] - second[a])
            mean += p[i] * (z + e1)
            square += p[i] * (z * z + 2.0 * z * e1 + e2)
        expected[k] = mean
        variance[k] = max(square - mean * mean, 0.0)
        for t in range(2 * big + 1):
            f[t] = _cdf(((obs * big - big + t - 0.5) / big - d) / s)
        norm = 0.0
        for j in range(big):
            acc = 0.0
            for i in range(big):
                a = j - i + big
                acc += p[i] * (f[a + 1] - f[a])
            new[j] = acc
            norm += acc
        loglik[k] = math.log(max(norm, _FLOOR))
        if norm > 1e-300:
            for j in range(big):
                p[j] = new[j] / norm
        else:  # a reading the model called impossible: start afresh
            p[:] = 1.0 / big
    return loglik, expected, variance


def binned(residual: Array, step: float, sigma: float) -> Array:
    """``ln P`` of each reading's lattice bin under a continuous Gaussian model: the residual
    (reading − prediction) ``N(0, σ²)``, coarsened to the bin ``± step/2`` about the reading."""
    p = ndtr((residual + 0.5 * step) / sigma) - ndtr((residual - 0.5 * step) / sigma)
    return np.log(np.maximum(p, _FLOOR))
