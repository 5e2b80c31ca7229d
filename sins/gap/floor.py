"""The noise floor a channel's residual is measured against, and where the excess over it lies.

The noise floor of a channel is the white-noise level the model expects, measured without the model:
the spread of first differences of the residual (:func:`noise_floor`), which slowly varying unmodelled
errors do not reach (and which holds rounding's spread as well), within the fit rows and within the
withheld rows, the larger of the two; and of the residual before the accepted effects and after them,
the smaller (an effect that moves the reading by jumps, a clip reached or a delay across a step, lifts
the differences before it). Rounding's spread depends on where each hold's mean sits in its
lattice cell: where readings leave their level a few times an hour, one portion may see more of it than
the other, or none. A channel whose withheld RMS exceeds its floor by :data:`SIGNIFICANT_RATIO` has a
gap. Where the gap lies is told by input quartiles (:func:`quartile_shares`) and by the residual's Allan
deviation against that white noise (:func:`allan_deviation`, :func:`allan_curves`), summed up in words by
:func:`concentrates`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sins.core.allan import allan_deviation as allan_deviation
from sins.gap.candidates import ReferenceInputs, spans

Array = NDArray[np.float64]

#: A channel's withheld residual counts as above its floor beyond this ratio (3 % plus sampling error).
SIGNIFICANT_RATIO = 1.03
#: Below any real sensor's noise (2e-5 °/h, 1e-11 g): the floor of noiseless (simulated) readings, SI units.
TINY = 1e-10
#: The most an accepted effect's residual may lower a channel's floor: the differences before an effect
#: that moves the reading by jumps (a clip reached, a delay across a step) are lifted by the jumps, the
#: floor after a heavy clip 0.02-0.4 of the one before; a floor a hundred times lower is no white noise
#: but a model reproducing the readings all but exactly (a quantizer far coarser than the noise, its
#: readings held on their levels: 2e-9 rad/s left of 7e-5).
FLOOR_DROP = 0.01
#: Input quartiles reported where the excess concentrates.
_FEATURES = ("|ω|", "|f|", "temperature", "rate of change", "time")


def noise_level(residual: Array, rows: NDArray[np.bool_] | None = None) -> float:
    """The RMS of a residual's noise where it may be correlated from one row to the next: from its
    first differences, ``sqrt(mean(Δr_t²) + mean(Δr_t Δr_{t+1}))``.

    For noise whose autocovariances are ``γ_0, γ_1`` (and none beyond a row), the differences' are
    ``d_0 = 2γ_0 − 2γ_1`` and ``d_1 = 2γ_1 − γ_0``, so ``d_0 + d_1 = γ_0``: the noise's variance,
    whatever ``γ_1``. A reference differentiated from positions or attitudes has such noise, anti-
    correlated from row to row, where :func:`noise_floor`'s ``d_0 / 2 = γ_0 − γ_1`` stands above its
    RMS (a 10 Hz solution through splines: 0.80-0.86 of it). For white noise both are ``σ²``, with
    the same sampling spread (measured: 0.9-1.0 % at 8,600 rows, 4.8 % at 300). What varies slowly
    enters as ``γ_0 − γ_2`` of its own, small beside the noise where its changes over two rows are.
    With ``rows``, only differences between consecutive rows all in it count; falls back to
    :func:`noise_floor` where the sum is not positive (a few rows) or no pair of differences is left.
    """
    d = np.diff(residual)
    if rows is None:
        pairs = np.ones(max(len(d) - 1, 0), dtype=bool)
        single = np.ones(len(d), dtype=bool)
    else:
        single = rows[1:] & rows[:-1]
        pairs = single[1:] & single[:-1]
    if not pairs.any():
        return noise_floor(residual, rows)
    d0 = float(np.mean(d[single] ** 2))
    d1 = float(np.mean(d[:-1][pairs] * d[1:][pairs]))
    return float(np.sqrt(d0 + d1)) if d0 + d1 > 0.0 else noise_floor(residual, rows)


def noise_floor(residual: Array, rows: NDArray[np.bool_] | None = None) -> float:
    """White-noise level of a residual series from its first differences: ``std(Δr) / √2``.

    Differencing removes what varies slowly (unmodelled scale, temperature or bias effects) and
    keeps white noise of any distribution, quantised readings' included, at twice its variance.
    With ``rows``, only differences between consecutive rows both in it count (0 where none do).
    """
    d = np.diff(residual)
    if rows is not None:
        d = d[rows[1:] & rows[:-1]]
    return float(np.std(d) / np.sqrt(2.0)) if len(d) else 0.0


def allan_curves(before: Array, after: Array, floor: float, step_s: float) -> dict[str, list[float]]:
    """The Allan deviations of a channel's residual, every row in time order, at octave clusters.

    Octaves up to an eighth of the rows, so that every point averages at least eight clusters.
    Returns ``tau_s``, the residual's deviation ``before`` and ``after`` the accepted effects, and the
    white noise's (``model``), the floor over ``√m``.
    """
    clusters = 2 ** np.arange(int(np.log2(max(len(before) // 8, 1))) + 1)
    return {
        "tau_s": list(clusters * step_s),
        "before": list(allan_deviation(before, clusters)),
        "after": list(allan_deviation(after, clusters)),
        "model": list(floor / np.sqrt(clusters)),
    }


def input_features(x: ReferenceInputs, withheld: NDArray[np.bool_]) -> dict[str, Array]:
    """The inputs whose quartiles :func:`quartile_shares` tells the excess by, on the withheld rows:
    ``|ω|``, ``|f|``, temperature, rate of change (``|ω̇|``) and time, built a chunk of rows at a
    time. Inputs that do not vary over the recording are left out (a static unit's rate of change:
    1e-19 from uneven time stamps)."""
    out = {}
    for name in _FEATURES:
        if name == "temperature" and x.temp is None:
            continue
        parts = [_feature(name, x.rows(lo, hi)) for lo, hi in spans(len(x.t))]
        top = max(float(np.max(v)) for v in parts)
        spread = top - min(float(np.min(v)) for v in parts)
        if spread <= 1e-9 * max(1.0, top, -min(float(np.min(v)) for v in parts)):
            continue
        out[name] = np.concatenate(
            [v[withheld[lo:hi]] for v, (lo, hi) in zip(parts, spans(len(x.t)), strict=True)]
        )
    return out


def _feature(name: str, x: ReferenceInputs) -> Array:
    """One input of :func:`input_features` on a chunk of rows."""
    if name == "|ω|":
        return np.asarray(np.linalg.norm(x.omega_ib_b, axis=1))
    if name == "|f|":
        return np.asarray(np.linalg.norm(x.f_ib_b, axis=1))
    if name == "rate of change":
        return np.asarray(np.linalg.norm(x.omega_dot_b, axis=1))
    return x.temp if name == "temperature" and x.temp is not None else x.t


def quartile_shares(
    residual: Array, floor: float, features: dict[str, Array], withheld: NDArray[np.bool_]
) -> dict[str, list[float]]:
    """For each input (:func:`input_features`, on the withheld rows), the share of a channel's
    withheld excess power in each of its quartiles. A channel with no excess gives nothing."""
    excess = residual[withheld] ** 2 - floor**2
    if float(np.sum(np.maximum(excess, 0.0))) <= 0.0:
        return {}
    out = {}
    for name, v in features.items():
        bins = np.searchsorted(np.quantile(v, [0.25, 0.5, 0.75]), v, side="right")
        # A bin may sit below the floor: shares are of the bins above it.
        per_bin = np.maximum([np.sum(excess[bins == b]) for b in range(4)], 0.0)
        out[name] = list(per_bin / max(float(np.sum(per_bin)), 1e-300))
    return out


def concentrates(shares: dict[str, list[float]], allan: dict[str, list[float]]) -> list[str]:
    """Where a channel's excess sits: an input quartile holding most of it, and the time scale at
    which the residual's Allan deviation stands furthest above the white noise the model expects."""
    out: list[str] = []
    for name, share in shares.items():
        top = int(np.argmax(share))
        if share[top] > 0.5:
            label = ("lowest", "second", "third", "highest")[top]
            out.append(f"{name}: {label} quartile holds {100 * share[top]:.0f} % of the excess")
    ratio = np.array(allan["before"]) / np.maximum(np.array(allan["model"]), 1e-300)
    if len(ratio) and ratio.max() > 1.5:  # 2.25× the variance: beyond the scatter of eight clusters
        k = int(np.argmax(ratio))
        tau = f"τ = {allan['tau_s'][k]:.3g} s"
        out.append(f"frequency: Allan deviation at {tau} is {ratio[k]:.1f}× the model's white noise")
    return out


__all__ = [
    "FLOOR_DROP",
    "SIGNIFICANT_RATIO",
    "TINY",
    "allan_curves",
    "allan_deviation",
    "concentrates",
    "input_features",
    "noise_floor",
    "noise_level",
    "quartile_shares",
]
