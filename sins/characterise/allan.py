"""The overlapping Allan deviation of a rate series, with its equivalent degrees of freedom and confidence.

A series may come in several segments (the holds of a calibration session, the stretches between gaps):
each cluster difference lies inside one segment, and the squared differences of all segments are pooled.
With ``θ`` the running sum of a segment's rate and ``m`` the cluster size in samples,

    σ²(m) = Σ (θₖ₊₂ₘ − 2θₖ₊ₘ + θₖ)² / (2 m² · count),

one pass over the segment per cluster size (O(N)), at octave-spaced sizes ``m = 1, 2, 4, …`` up to an
eighth of the longest segment, so that every point averages at least eight cluster lengths.

Equivalent degrees of freedom (EDF). The estimate of ``σ²`` at ``τ`` is read as ``χ²``-distributed with
``edf`` degrees of freedom: ``σ̂² · edf / σ² ~ χ²(edf)``. The EDF depends on the noise that dominates at
``τ``; we use the simple closed forms for the overlapping Allan variance tabulated in NIST Special
Publication 1065 (Riley 2008, Table 12, after Howe, Allan and Barnes 1981), picking the form by the local
log-log slope ``μ`` of the Allan variance (``μ = −2`` quantization (white phase), ``−1`` white rate noise,
``0`` flicker (the bias-instability plateau), ``+1`` rate random walk; a rate ramp, ``+2``, takes the
random-walk form). Segments are independent, so their EDFs add. The slope comes from the fitted noise
model (:mod:`sins.characterise.noise_terms`), or ``−1`` before a fit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from sins.core.allan import segment_sums as segment_sums

Array = NDArray[np.float64]

#: Every point of a curve averages at least this many cluster lengths of its longest segment.
MIN_CLUSTERS = 8
#: The confidence of the intervals reported beside each point (two-sided).
CONFIDENCE = 0.95


@dataclass(frozen=True)
class AllanCurve:
    """One channel's overlapping Allan deviation at octave cluster sizes.

    Attributes
    ----------
    tau_s : (k,) cluster times, s
    clusters : (k,) cluster sizes, samples
    avar : (k,) Allan variance, the channel's unit squared
    edf : (k,) equivalent degrees of freedom of each point
    terms : (k,) how many cluster differences each point averages (all segments)
    lengths : the segments' lengths, samples (for the EDF at another slope)
    confidence : the two-sided confidence of :meth:`interval`
    dsum : (k,) the sum of the cluster differences themselves (all segments), for :meth:`detrended`;
        None when not kept
    """

    tau_s: Array
    clusters: NDArray[np.int64]
    avar: Array
    edf: Array
    terms: NDArray[np.int64]
    lengths: tuple[int, ...]
    confidence: float = CONFIDENCE
    dsum: Array | None = None

    @property
    def adev(self) -> Array:
        """The Allan deviation, the channel's unit."""
        return np.sqrt(self.avar)

    def interval(self) -> tuple[Array, Array]:
        """The ``confidence`` interval of the Allan deviation at each point: ``(low, high)``.

        From ``σ̂² · edf / σ² ~ χ²(edf)``: ``σ² ∈ [σ̂² edf / χ²_{(1+c)/2}, σ̂² edf / χ²_{(1−c)/2}]``.
        """
        return chi2_interval(self.avar, self.edf, self.confidence)

    def with_edf(self, edf: Array) -> AllanCurve:
        """The same curve with other equivalent degrees of freedom (k,)."""
        return AllanCurve(
            self.tau_s, self.clusters, self.avar, edf, self.terms, self.lengths, self.confidence, self.dsum
        )

    def detrended(self, slope: float) -> AllanCurve:
        """The curve of the same rate less a ramp of ``slope`` (the rate's unit per s), with no new pass.

        A ramp ``s·k`` of the rate (``s`` per sample) adds ``s·m²`` to every cluster difference at
        cluster size ``m`` (the second difference of its running sum), so the squared differences of
        the rate less the ramp sum to ``Σd² − 2 s m² Σd + s² m⁴ n``: the ramp's Allan variance
        ``R²τ²/2`` is taken out exactly, whatever the segments' offsets.

        Raises
        ------
        ValueError
            when the curve was made without its differences' sums (``dsum`` None).
        """
        if self.dsum is None:
            raise ValueError("this Allan curve keeps no sums of its differences: it cannot be detrended")
        m2 = self.clusters.astype(float) ** 2
        s = slope * float(self.tau_s[0] / self.clusters[0])  # per sample
        n = np.maximum(self.terms, 1).astype(float)
        squares = self.avar * 2.0 * m2 * n - 2.0 * s * m2 * self.dsum + s * s * m2 * m2 * self.terms
        avar = np.maximum(squares, 0.0) / (2.0 * m2 * n)
        dsum = self.dsum - s * m2 * self.terms
        return AllanCurve(
            self.tau_s, self.clusters, avar, self.edf, self.terms, self.lengths, self.confidence, dsum
        )


def chi2_interval(avar: Array, edf: Array, confidence: float = CONFIDENCE) -> tuple[Array, Array]:
    """The two-sided ``confidence`` interval of Allan deviations of variance ``avar`` and EDF ``edf``."""
    upper = stats.chi2.ppf(0.5 + confidence / 2.0, edf)
    lower = stats.chi2.ppf(0.5 - confidence / 2.0, edf)
    return np.sqrt(avar * edf / upper), np.sqrt(avar * edf / lower)


def octave_clusters(longest: int) -> NDArray[np.int64]:
    """Cluster sizes ``1, 2, 4, …`` up to ``longest / MIN_CLUSTERS`` (none for a too short segment)."""
    top = longest // MIN_CLUSTERS
    if top < 1:
        return np.zeros(0, dtype=np.int64)
    return 2 ** np.arange(int(np.log2(top)) + 1, dtype=np.int64)


def allan(
    rate: Array,
    dt: float,
    segments: Sequence[tuple[int, int]] | None = None,
    slope: Array | None = None,
    confidence: float = CONFIDENCE,
) -> AllanCurve:
    """The overlapping Allan deviation of a uniformly sampled rate at octave cluster sizes.

    Parameters
    ----------
    rate : (n,) rate samples (or a reading less its reference), any unit
    dt : the sampling step, s
    segments : ``(start, stop)`` row ranges that are each uniformly sampled; None: the whole series
    slope : (k,) the local log-log slope of the Allan variance at each cluster size, for the EDF;
        None: white rate noise (``−1``) everywhere
    confidence : of the intervals

    Returns
    -------
    AllanCurve
        empty when no segment has ``MIN_CLUSTERS`` samples.
    """
    spans = [(0, len(rate))] if segments is None else list(segments)
    clusters = octave_clusters(max((b - a for a, b in spans), default=0))
    sums = np.zeros(len(clusters))
    first = np.zeros(len(clusters))
    counts = np.zeros(len(clusters), dtype=np.int64)
    for a, b in spans:
        s, c, d = segment_sums(np.asarray(rate[a:b], dtype=float), clusters)
        sums += s
        counts += c
        first += d
    avar = sums / (2.0 * clusters.astype(float) ** 2 * np.maximum(counts, 1))
    lengths = np.array([b - a for a, b in spans])
    mu = np.full(len(clusters), -1.0) if slope is None else np.asarray(slope, dtype=float)
    edf = pooled_edf(lengths, clusters, mu)
    tau = clusters.astype(np.float64) * dt
    return AllanCurve(tau, clusters, avar, edf, counts, tuple(int(n) for n in lengths), confidence, first)


def pooled_edf(lengths: NDArray[np.integer], clusters: NDArray[np.int64], slope: Array) -> Array:
    """The EDF at each cluster size, summed over independent segments of ``lengths`` rate samples."""
    out = np.zeros(len(clusters))
    for n in lengths:
        out += edf_overlapping(int(n) + 1, clusters, slope)
    return np.maximum(out, 1.0)


def edf_overlapping(n_phase: int, clusters: NDArray[np.int64], slope: Array) -> Array:
    """The EDF of the overlapping Allan variance of one segment (NIST SP 1065, Table 12).

    Parameters
    ----------
    n_phase : the number of phase (running-sum) points, the rate samples plus one
    clusters : (k,) cluster sizes ``m``
    slope : (k,) local log-log slope of the Allan variance: the noise type at each ``m``
    """
    big_n = float(n_phase)
    out = np.zeros(len(clusters))
    for j, (m_int, mu) in enumerate(zip(clusters, slope, strict=True)):
        m = float(m_int)
        if big_n < 2.0 * m + 1.0 or big_n < 4.0:
            continue
        if mu < -1.5:  # white phase: quantization
            edf = (big_n + 1.0) * (big_n - 2.0 * m) / (2.0 * (big_n - m))
        elif mu < -0.5:  # white rate noise
            edf = (
                (3.0 * (big_n - 1.0) / (2.0 * m) - 2.0 * (big_n - 2.0) / big_n)
                * 4.0
                * m
                * m
                / (4.0 * m * m + 5.0)
            )
        elif mu < 0.5:  # flicker: the bias-instability plateau
            if m_int == 1:
                edf = 2.0 * (big_n - 2.0) ** 2 / (2.3 * big_n - 4.9)
            else:
                edf = 5.0 * big_n * big_n / (4.0 * m * (big_n + 3.0 * m))
        else:  # rate random walk (and a ramp)
            edf = (
                (big_n - 2.0)
                / m
                * ((big_n - 1.0) ** 2 - 3.0 * m * (big_n - 1.0) + 4.0 * m * m)
                / (big_n - 3.0) ** 2
            )
        out[j] = max(edf, 0.0)
    return out


__all__ = [
    "CONFIDENCE",
    "MIN_CLUSTERS",
    "AllanCurve",
    "allan",
    "chi2_interval",
    "edf_overlapping",
    "octave_clusters",
    "pooled_edf",
    "segment_sums",
]
