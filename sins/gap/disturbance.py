"""Disturbances outside the IMU effect library, fitted to a residual beside regressors.

A single bias step and an oscillation: what a one-off event or a hum leaves in a sensor's residual
(a shock, a mount resonance, a vibrating test bed). The sim-to-real diagnosis (:mod:`sins.gap`)
fits both to each channel it is about to explain with a library effect; where one does as well, the
effect cannot claim the channel. Each is fitted on the fit ``rows`` only, the regressors ``columns``
refitted beside it.
"""

from __future__ import annotations

import bisect

import numpy as np
from numpy.typing import NDArray
from scipy import fft
from scipy.optimize import minimize_scalar

from sins.gap.candidates import spans
from sins.gap.design import Design, Factor, Projection

Array = NDArray[np.float64]

#: A single bias step may not fall in the first or last 5 % of the fit rows (there it is an outlier).
STEP_MARGIN = 0.05


def _design(columns: Design | Array) -> Design:
    return columns if isinstance(columns, Design) else Design.from_array(columns)


def best_step(
    residual: Array, columns: Design | Array, rows: NDArray[np.bool_], t: Array, factor: Factor | None = None
) -> tuple[float, float]:
    """The single bias step that best fits the fit rows' residual, the model's regressors refitted beside it.

    With ``M`` the projection off the regressors ``A``, a step ``s`` after fit row ``k`` explains
    ``(sᵀ M e)² / sᵀ M s`` of the residual ``e = M y``'s sum of squares; ``sᵀ M e`` is a suffix sum
    of ``e`` and ``sᵀ M s = (n − k) − (Aᵀs)ᵀ (AᵀA)⁻¹ (Aᵀs)``, with ``Aᵀs`` a suffix sum of ``A``'s
    rows, so every ``k`` costs one pass (from the last chunk of rows to the first, :mod:`sins.gap.design`).
    ``factor``: the columns' factor on ``rows`` with their Gram matrix there, if the caller has it.
    Returns the step's time (halfway between the rows either side) and its size.
    """
    e = residual[rows]
    n = len(e)
    unscaled = _design(columns)
    if factor is None:
        factor = unscaled.factor(rows, gram_rows=rows)  # the columns' scale and Gram matrix in one pass
    design = unscaled.scaled_by(factor.scale)
    suffix_e = np.cumsum(e[::-1])[::-1][1:]  # the step starts at fit row k = 1 … n − 1
    del e
    inverse = np.linalg.pinv(factor.scaled_gram())
    quad = np.empty(max(n - 1, 0))  # (Aᵀs)ᵀ (AᵀA)⁻¹ (Aᵀs) for a step after each fit row
    carry, end = np.zeros(len(inverse)), n
    for lo, hi in reversed(spans(design.n)):
        a = design.block(lo, hi)[rows[lo:hi]]
        if len(a) == 0:
            continue
        within = np.cumsum(a[::-1], axis=0)[::-1] + carry  # each fit row's sum to the last
        carry, start = within[0], end - len(a)
        after = np.arange(start, end) - 1  # the step after this fit row starts at each of these
        ok = after >= 0
        quad[after[ok]] = np.einsum("ki,ij,kj->k", within[ok], inverse, within[ok])
        end = start
    denominator = np.subtract(np.arange(n - 1, 0, -1), quad, out=quad)  # sᵀ M s, in place
    explained = np.square(suffix_e)
    np.divide(explained, np.maximum(denominator, 1e-300), out=explained)
    explained[denominator <= 1e-9 * n] = -1.0
    margin = max(1, int(STEP_MARGIN * n))
    explained[: margin - 1] = explained[n - 1 - margin :] = -1.0
    j = int(np.argmax(explained))
    tf = t[rows][j : j + 2]
    return 0.5 * float(tf[0] + tf[1]), float(suffix_e[j] / denominator[j])


def _periodogram_peak(x: Array, step: float, lowest_hz: float) -> float:
    """The frequency of the largest power of ``x`` padded eightfold with zeros, at or above
    ``lowest_hz``: bin ``8m + r`` of the padded transform is bin ``m`` of ``x`` turned by
    ``e^(−2πi r j / 8n)``, so transforms of ``n`` points give it, never one of ``8n``; and as ``x`` is
    real, bin ``8n − b`` is bin ``b``'s conjugate, so the turns ``r ≤ 4`` give every bin up to ``4n``
    (bins ``8m + r`` beyond it as the mirrors of ``8m' + 8 − r`` below it). The bins allowed of each
    turn, up to ``4n`` and at or above ``lowest_hz``, are a run of consecutive ``m``: found by
    bisection with the test each bin would take, so no array of bins is built."""
    n = len(x)
    padded = 8 * n
    best, peak = -1.0, 0.0
    for r in range(5):
        power = _turned_power(x, r, padded)
        for mirrored in (False, True)[: 2 if r in (1, 2, 3) else 1]:
            # b and its mirror 8n − b (r = 0 and 4 mirror onto their own turn)
            lo, hi = _allowed_run(n, r, mirrored, step, lowest_hz)
            if lo < hi:
                m = lo + int(np.argmax(power[lo:hi]))
                if power[m] > best:
                    b = padded - (8 * m + r) if mirrored else 8 * m + r
                    best, peak = float(power[m]), float(np.float64(b) / (padded * step))
        del power  # before the next turn's transform
    return peak


def _allowed_run(n: int, r: int, mirrored: bool, step: float, lowest_hz: float) -> tuple[int, int]:
    """The ``m`` (``lo ≤ m < hi``) whose bin ``b`` (``8m + r``, or ``8n − 8m − r`` ``mirrored``) of
    the eightfold padded transform is at most ``4n`` with ``b / (8n step) ≥ lowest_hz``, that
    frequency computed as a whole array of bins would compute it (so the run is the same to the
    bin: the division is monotone in ``b``)."""
    padded = 8 * n

    def high_enough(m: int) -> bool:
        b = padded - (8 * m + r) if mirrored else 8 * m + r
        return bool(np.float64(b) / (padded * step) >= lowest_hz)

    if mirrored:  # b falls as m rises: at most 4n from m ≥ (4n − r) / 8, high enough up to some m
        lo = max(-(-(4 * n - r) // 8), 0)
        hi = bisect.bisect_left(range(n), True, key=lambda m: not high_enough(m))
        return lo, hi
    hi = min(max((4 * n - r) // 8 + 1, 0), n)  # b rises with m: at most 4n up to m = (4n − r) / 8
    lo = bisect.bisect_left(range(hi), True, key=high_enough)
    return lo, hi


def _turned_power(x: Array, r: int, padded: int) -> Array:
    """``|FFT(x e^(−2πi r j / padded))|²``, the turn built a chunk at a time into the transform's own
    array (no n-long angle, cosine or sine)."""
    if r == 0:
        z = fft.fft(x)
    else:
        z = np.empty(len(x), dtype=np.complex128)
        for lo, hi in spans(len(x)):
            angle = (-2.0 * np.pi * r / padded) * np.arange(lo, hi)
            z.real[lo:hi] = x[lo:hi] * np.cos(angle)
            z.imag[lo:hi] = x[lo:hi] * np.sin(angle)
        z = fft.fft(z, overwrite_x=True)
    # The power in the transform's own real parts (a view): no n-long arrays beside it.
    power, imag = z.real, z.imag
    np.square(power, out=power)
    power += np.square(imag, out=imag)
    return np.asarray(power)


def best_oscillation(
    residual: Array, columns: Design | Array, rows: NDArray[np.bool_], t: Array, factor: Factor | None = None
) -> tuple[float, float]:
    """The period and amplitude of the strongest oscillation in the fit rows' residual.

    The peak of the periodogram of the residual with the withheld rows zeroed (they may not
    choose), padded eightfold, refined to the frequency whose sine and cosine, fitted beside the
    regressors, leave the least; periods longer than a third of the recording are left to the drifts.
    The sine and cosine are fitted on what the regressors leave of them and of the residual (their
    projections off the regressors, :class:`~sins.gap.design.Projection`), the same least squares.
    ``factor``: the columns' factor on ``rows``, if the caller has it.
    """
    step = float(np.median(np.diff(t)))
    x = residual - residual[rows].mean()
    x[~rows] = 0.0  # the withheld rows may not choose
    peak = _periodogram_peak(x, step, 3.0 / (t[-1] - t[0]))
    del x
    projection = Projection.of(_design(columns), rows, factor)
    tf, y = t[rows], residual[rows]
    on_y = projection.coordinates(y[:, None])
    left_y = float(y @ y - np.sum(on_y**2))

    def fitted(f_hz: float) -> tuple[float, Array]:
        wave = np.column_stack([np.cos(2 * np.pi * f_hz * tf), np.sin(2 * np.pi * f_hz * tf)])
        on_wave = projection.coordinates(wave)
        gram = wave.T @ wave - on_wave.T @ on_wave
        cross = wave.T @ y - on_wave.T @ on_y[:, 0]
        coef, *_ = np.linalg.lstsq(gram, cross, rcond=None)
        return left_y - float(cross @ coef), coef

    half_bin = 0.5 / (8 * len(t) * step)
    best = minimize_scalar(
        lambda f: fitted(f)[0], bounds=(peak - half_bin, peak + half_bin), method="bounded"
    )
    f_hz = float(best.x)
    return 1.0 / f_hz, float(np.hypot(*fitted(f_hz)[1]))


__all__ = [
    "STEP_MARGIN",
    "best_oscillation",
    "best_step",
]
