"""Disturbances outside the IMU effect library, fitted to a residual beside regressors.

A single bias step and an oscillation: what a one-off event or a hum leaves in a sensor's residual
(a shock, a mount resonance, a vibrating test bed). The sim-to-real diagnosis (:mod:`sins.gap`)
fits both to each channel it is about to explain with a library effect; where one does as well, the
effect cannot claim the channel. Each is fitted on the fit ``rows`` only, the regressors ``columns``
refitted beside it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize_scalar

Array = NDArray[np.float64]

#: A single bias step may not fall in the first or last 5 % of the fit rows (there it is an outlier).
STEP_MARGIN = 0.05


def best_step(residual: Array, columns: Array, rows: NDArray[np.bool_], t: Array) -> tuple[float, float]:
    """The single bias step that best fits the fit rows' residual, the model's regressors refitted beside it.

    With ``M`` the projection off the regressors ``A``, a step ``s`` after fit row ``k`` explains
    ``(sᵀ M e)² / sᵀ M s`` of the residual ``e = M y``'s sum of squares; ``sᵀ M e`` is a suffix sum
    of ``e`` and ``sᵀ M s = (n − k) − (Aᵀs)ᵀ (AᵀA)⁻¹ (Aᵀs)``, with ``Aᵀs`` a suffix sum of ``A``'s
    rows, so every ``k`` costs one pass. Returns the step's time (halfway between the rows either
    side) and its size.
    """
    e, a, tf = residual[rows], columns[rows], t[rows]
    n = len(e)
    a = a / np.maximum(np.abs(a).max(axis=0), 1e-300)
    suffix_e = np.cumsum(e[::-1])[::-1][1:]  # the step starts at fit row k = 1 … n − 1
    suffix_a = np.cumsum(a[::-1], axis=0)[::-1][1:]
    inverse = np.linalg.pinv(a.T @ a)
    denominator = np.arange(n - 1, 0, -1) - np.einsum("ki,ij,kj->k", suffix_a, inverse, suffix_a)
    explained = np.where(denominator > 1e-9 * n, suffix_e**2 / np.maximum(denominator, 1e-300), -1.0)
    margin = max(1, int(STEP_MARGIN * n))
    explained[: margin - 1] = explained[n - 1 - margin :] = -1.0
    j = int(np.argmax(explained))
    return 0.5 * float(tf[j] + tf[j + 1]), float(suffix_e[j] / denominator[j])


def best_oscillation(
    residual: Array, columns: Array, rows: NDArray[np.bool_], t: Array
) -> tuple[float, float]:
    """The period and amplitude of the strongest oscillation in the fit rows' residual.

    The peak of the periodogram of the residual with the withheld rows zeroed (they may not
    choose), padded eightfold, refined to the frequency whose sine and cosine, fitted beside the
    regressors, leave the least; periods longer than a third of the recording are left to the drifts.
    """
    step = float(np.median(np.diff(t)))
    x = np.where(rows, residual - residual[rows].mean(), 0.0)
    n = 8 * len(x)
    power = np.abs(np.fft.rfft(x, n)) ** 2
    freq = np.fft.rfftfreq(n, step)
    power[freq < 3.0 / (t[-1] - t[0])] = 0.0
    peak = float(freq[int(np.argmax(power))])
    scale = np.maximum(np.abs(columns[rows]).max(axis=0), 1e-300)
    a, tf, y = columns[rows] / scale, t[rows], residual[rows]

    def fitted(f_hz: float) -> tuple[float, Array]:
        w = np.column_stack([a, np.cos(2 * np.pi * f_hz * tf), np.sin(2 * np.pi * f_hz * tf)])
        coef, *_ = np.linalg.lstsq(w, y, rcond=None)
        return float(np.sum((y - w @ coef) ** 2)), coef

    half_bin = 0.5 / (n * step)
    best = minimize_scalar(
        lambda f: fitted(f)[0], bounds=(peak - half_bin, peak + half_bin), method="bounded"
    )
    f_hz = float(best.x)
    return 1.0 / f_hz, float(np.hypot(*fitted(f_hz)[1][-2:]))


__all__ = [
    "STEP_MARGIN",
    "best_oscillation",
    "best_step",
]
