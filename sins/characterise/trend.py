"""A rate ramp, fitted to the rate itself as a deterministic trend, with its uncertainty from the noise.

The ramp ``R`` (rad/s², m/s³) is the common slope of a least-squares line through each segment of the
rate, one intercept per segment:

    R̂ = Σₛ Σₖ uₖ xₖ / (dt Σₛ Dₛ),   uₖ = k − (nₛ − 1)/2,   Dₛ = nₛ (nₛ² − 1)/12.

Its variance is not the white-noise formula's: the slow noise terms (a rate random walk, flicker, a
Gauss–Markov bias) make trends of their own. For one segment, the slope ``Σ wₖ xₖ`` (``wₖ = uₖ/D``) of
noise of two-sided spectrum ``S(f)`` per sample has variance ``∫ |W(f)|² S(f) df`` over
``−½ < f ≤ ½``, with ``W(f) = Σ wₖ e^(−2πifk)``; centred, ``|W(f)| = |Dₙ'(ω)| / D`` where
``Dₙ(ω) = sin(nω/2) / sin(ω/2)`` and ``ω = 2πf``. ``S`` is the noise terms' spectrum
(:func:`sins.characterise.noise_terms.spectrum`). The integral runs on a fine linear grid of ``f`` below
``40/n`` (the window's main lobes) and a logarithmic one above, where the grid's scattered phases
average the oscillation (checked against 400 simulated series of each noise type in the tests). The
segments are taken as independent (exact for white noise and a rate random walk, whose slopes in
disjoint segments are independent once each has its own intercept).

Which noise? The Allan curve reaches an eighth of the recording; the slope's variance depends on the
noise at the recording's whole length, four to eight times slower, where slow terms the curve does not
resolve may still be. So the ramp is judged with the largest ``σ`` of the full model's (every candidate
term, as fitted) and of it with the flicker or the rate random walk at its upper bound
(:meth:`sins.characterise.selection.Weights.slow_models`): a ramp is resolved only when no noise the
curve allows would have made it. The ``σ`` reported beside a resolved ramp is the full model's, its
standard error; the one it was judged with is reported too (what the bound changes on a rig
recording: ``docs/guide/characterise.md``).

The ramp is *resolved* when ``|R̂| ≥ 3σ`` (the judging ``σ``); the Allan analysis then works on the
rate less it (:meth:`sins.characterise.allan.AllanCurve.detrended`). Unresolved, it is bounded by
``|R̂| + 3σ`` and left in the data. The noise it is judged against is the curve's without it
(:func:`sins.characterise.analysis.characterise_channel`): with it, a rate random walk would take its
rise and hide it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sins.characterise.allan import MIN_CLUSTERS
from sins.characterise.noise_terms import spectrum

Array = NDArray[np.float64]

#: A ramp is resolved at this many standard errors.
RESOLVED_SIGMA = 3.0
#: An unresolved ramp's bound: its estimate's size plus this many judging standard errors (3σ, as the
#: noise terms' bounds).
UPPER_SIGMA = 3.0


@dataclass(frozen=True)
class Ramp:
    """The rate's fitted ramp.

    Attributes
    ----------
    value : the slope, the rate's unit per s (signed)
    sigma : its standard error under the full noise model (every candidate term as fitted)
    sigma_slow : the largest standard error under the slow noise the curve allows (the ramp is judged
        with it)
    """

    value: float
    sigma: float
    sigma_slow: float

    @property
    def resolved(self) -> bool:
        """Whether ``|value| ≥ 3 sigma_slow``."""
        return abs(self.value) >= RESOLVED_SIGMA * self.sigma_slow

    @property
    def upper(self) -> float:
        """The largest ramp the data allow: ``|value| + 3 sigma_slow``."""
        return abs(self.value) + UPPER_SIGMA * self.sigma_slow


def slope(rate: Array, dt: float, segments: Sequence[tuple[int, int]]) -> float:
    """The least-squares common slope of ``rate`` over ``segments`` (one intercept each), per s."""
    num = den = 0.0
    for a, b in segments:
        n = b - a
        u = np.arange(n, dtype=float) - 0.5 * (n - 1)
        num += float(u @ np.asarray(rate[a:b], dtype=float))
        den += n * (n * n - 1.0) / 12.0
    return num / den / dt if den > 0.0 else 0.0


def slope_variance(n: int, dt: float, coefficients: Array, tau_c_s: float | None) -> float:
    """The variance of the least-squares slope (per s) of ``n`` samples at ``dt`` of the noise of squared
    coefficients ``coefficients`` (6,) and correlation time ``tau_c_s`` (see the module's text)."""
    if n < 3:
        return math.inf
    d = n * (n * n - 1.0) / 12.0
    edge = 40.0 / n
    if edge >= 0.5:
        f = np.linspace(0.0, 0.5, 20001)[1:]
    else:
        f = np.concatenate([np.linspace(0.0, edge, 4001)[1:], np.geomspace(edge, 0.5, 20000)[1:]])
    df = np.gradient(f)
    w = 2.0 * np.pi * f
    s, c = np.sin(0.5 * w), np.cos(0.5 * w)
    derivative = (0.5 * n * np.cos(0.5 * n * w) * s - 0.5 * np.sin(0.5 * n * w) * c) / (s * s)
    integrand = (derivative / d) ** 2 * spectrum(f, dt, coefficients, tau_c_s)
    return 2.0 * float(np.sum(integrand * df)) / (dt * dt)


def fit_ramp(rate: Array, dt: float, segments: Sequence[tuple[int, int]], models: Sequence[Array],
             tau_c_s: float | None, value: float | None = None) -> Ramp:  # fmt: skip
    """The ramp of ``rate`` over ``segments``: its σ under the first of the noise ``models`` (each the
    squared coefficients (6,), correlation time ``tau_c_s``) and the largest under any of them.

    ``value``: the slope when already computed (:func:`slope`). The segments' slopes are pooled with
    weights ``Dₛ``, so ``σ² = Σ Dₛ² σₛ² / (Σ Dₛ)²``.
    """
    r = slope(rate, dt, segments) if value is None else value
    weights = [(b - a) * ((b - a) ** 2 - 1.0) / 12.0 for a, b in segments]
    total = sum(weights)
    if total <= 0.0 or not models:
        return Ramp(r, math.inf, math.inf)
    pairs = list(zip(weights, segments, strict=True))
    var = [sum(w * w * slope_variance(b - a, dt, c, tau_c_s) for w, (a, b) in pairs) for c in models]
    return Ramp(r, math.sqrt(var[0]) / total, math.sqrt(max(var)) / total)


def needs_length(size: float, dt: float, coefficients: Array, tau_c_s: float | None, length_s: float
                 ) -> float | None:  # fmt: skip
    """The length of one recording that would resolve a ramp of ``size`` (``3σ``) under this noise:
    the shortest of ``length_s · 2ʲ``, ``j = 1 … 20`` (None when none would, or for no ramp)."""
    if not size > 0.0:
        return None
    for j in range(1, 21):
        n = int(length_s * 2.0**j / dt)
        if (
            n >= 2 * MIN_CLUSTERS
            and RESOLVED_SIGMA * math.sqrt(slope_variance(n, dt, coefficients, tau_c_s)) <= size
        ):
            return float(n * dt)
    return None


__all__ = [
    "RESOLVED_SIGMA",
    "UPPER_SIGMA",
    "Ramp",
    "fit_ramp",
    "needs_length",
    "slope",
    "slope_variance",
]
