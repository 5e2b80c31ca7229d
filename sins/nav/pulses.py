"""One scalar channel of a motion as a function of time: back-to-back smooth pulses plus sinusoids.

The ramp shape is the C2 "smoothstep" S(x) = 10x³ - 15x⁴ + 6x⁵ (integral from 0: 2.5x⁴ - 3x⁵ + x⁶): its
first and second derivatives vanish at both ends, so acceleration and angular rate stay continuous and
only the third derivative jumps (at :meth:`Channel.breakpoints`). :class:`sins.nav.motion.SegmentMotion`
builds its speed, course, flight-path angle, attitude offsets and heave from such channels.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


# Compiled because a scenario evaluates its channels at every quadrature node of an hour-long run.
@numba.njit(cache=True, nogil=True)
def _evaluate_pieces(
    edges: Array, base: Array, rate_amp: Array, value_amp: Array, ramp: Array, t: Array
) -> tuple[Array, Array, Array]:
    n = t.shape[0]
    value = np.empty(n)
    d1 = np.empty(n)
    d2 = np.empty(n)
    last = base.shape[0] - 1
    i = 0
    for k in range(n):
        tk = t[k]
        # Times usually arrive sorted: walk forward, fall back to bisection.
        if tk < edges[i] or (i < last and tk >= edges[i + 1]):
            i = min(max(np.searchsorted(edges, tk, side="right") - 1, 0), last)
        length = edges[i + 1] - edges[i]
        r = ramp[i]
        ra = rate_amp[i]
        va = value_amp[i]
        if tk < edges[0]:
            value[k], d1[k], d2[k] = base[0], 0.0, 0.0
            continue
        if tk >= edges[last + 1]:
            value[k], d1[k], d2[k] = base[last] + ra * (length - r), 0.0, 0.0
            continue
        tau = tk - edges[i]
        if tau < r or tau > length - r:
            up = tau < r
            x = tau / r if up else (length - tau) / r
            x2 = x * x
            x3 = x2 * x
            p = x3 * (10.0 - 15.0 * x + 6.0 * x2)
            s_int = x3 * x * (2.5 - 3.0 * x + x2)
            s_d1 = 30.0 * x2 * (1.0 - x) * (1.0 - x) / r
            d2p = 60.0 * x * (1.0 - 3.0 * x + 2.0 * x2) / (r * r)
            if up:
                integral = r * s_int
                dp = s_d1
            else:
                integral = length - r - r * s_int
                dp = -s_d1
        else:
            p, dp, d2p = 1.0, 0.0, 0.0
            integral = tau - 0.5 * r
        value[k] = base[i] + ra * integral + va * p
        d1[k] = ra * p + va * dp
        d2[k] = ra * dp + va * d2p
    return value, d1, d2


@dataclass(frozen=True)
class Channel:
    """A scalar function of time made of back-to-back smooth pieces plus sinusoids.

    Piece ``i`` covers ``[edges[i], edges[i+1])``. Inside it the trapezoid
    ``P(t)`` rises from 0 to 1 over ``ramp[i]`` seconds with a smoothstep,
    stays at 1, and falls back over the last ``ramp[i]`` seconds. The channel is

        value(t) = base[i] + rate_amp[i] * ∫P + value_amp[i] * P(t) + Σ sinusoids

    so ``rate_amp`` makes a lasting change (the derivative is the pulse: a turn,
    an acceleration) and ``value_amp`` a temporary excursion (a climb). Before
    the first edge and after the last the channel holds its end values.
    Sinusoids are ``amplitude * sin(2π t / period + phase)``.
    """

    edges: Array
    base: Array
    rate_amp: Array
    value_amp: Array
    ramp: Array
    sin_amplitude: Array = field(default_factory=lambda: np.zeros(0))
    sin_period: Array = field(default_factory=lambda: np.ones(0))
    sin_phase: Array = field(default_factory=lambda: np.zeros(0))

    def evaluate(self, t: Array) -> tuple[Array, Array, Array]:
        """Value, first and second time derivative at times ``t``, shape (n,) each."""
        t = np.ascontiguousarray(t, dtype=float)
        if len(self.base) == 1 and self.rate_amp[0] == 0.0 and self.value_amp[0] == 0.0:
            value = np.full(t.shape, self.base[0])
            d1 = np.zeros(t.shape)
            d2 = np.zeros(t.shape)
        else:
            value, d1, d2 = _evaluate_pieces(
                self.edges, self.base, self.rate_amp, self.value_amp, self.ramp, t
            )
        if self.sin_amplitude.size:
            w = 2.0 * np.pi / self.sin_period
            arg = np.outer(t, w) + self.sin_phase
            value = value + np.sin(arg) @ self.sin_amplitude
            d1 = d1 + np.cos(arg) @ (self.sin_amplitude * w)
            d2 = d2 - np.sin(arg) @ (self.sin_amplitude * w * w)
        return value, d1, d2

    def breakpoints(self) -> Array:
        """Times where the third derivative may jump: piece edges and ramp ends."""
        t_a, t_b = self.edges[:-1], self.edges[1:]
        active = (self.rate_amp != 0.0) | (self.value_amp != 0.0)
        pts = [self.edges, (t_a + self.ramp)[active], (t_b - self.ramp)[active]]
        return np.unique(np.concatenate(pts))


__all__ = ["Channel"]
