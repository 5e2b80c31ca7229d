"""The closing check: simulate the written model for as long as the recording, and overlay the Allan curves.

The model (an :class:`~sins.imu.ImuModel`, the IMU file as sins reads it) corrupts a unit standing still
under the recording's mean reading (Earth rate and gravity, for a static unit: quantization needs an input
that crosses its levels), in increment form (so quantization carries its remainder as the unit's own output
does), over segments as long as the recording's; the simulated readings' Allan curves are computed as the real
ones were. At
each cluster time the ratio of the two Allan variances is, if the model holds, ``F``-distributed with the
points' EDFs; where it lies outside the ``F`` interval of :data:`CHECK_CONFIDENCE` (widened by the model
error the fit allowed each curve, :attr:`~sins.characterise.noise_terms.NoiseFit.tolerance`), the
curves *part*: that is the noise side of the sim-to-real gap, named by channel, cluster times and the factor.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from sins.characterise.allan import allan
from sins.characterise.analysis import Characterisation
from sins.core.series import ImuIncrements
from sins.imu import CHANNELS, ImuModel
from sins.imu.stream import IncrementStream

Array = NDArray[np.float64]

#: Two-sided confidence of the parting test at each point (0.99: over ~100 points of six channels, about
#: one parts by chance).
CHECK_CONFIDENCE = 0.99
#: Rows simulated per chunk (bounded memory for recordings of any length).
CHUNK_ROWS = 1 << 18


def simulate_static(
    model: ImuModel, dt: float, rows: int, seed: int = 0, input_rate: Array | None = None
) -> Array:
    """The readings (rows, 6) of a unit at rest, rad/s and m/s², as each interval's mean.

    The model corrupts the increments of a constant input ``input_rate`` (6,) (default zero) chunk by chunk
    (:class:`~sins.imu.stream.IncrementStream`); the readings are the increments over ``dt``.
    """
    rate = np.zeros(6) if input_rate is None else np.asarray(input_rate, dtype=float)
    stream = IncrementStream(model, seed, dt)
    out = np.empty((rows, 6))
    done = 0
    written = 0

    def take(part: ImuIncrements) -> None:
        nonlocal written
        k = len(part)
        out[written : written + k, :3] = part.dtheta_b / dt
        out[written : written + k, 3:] = part.dv_b / dt
        written += k

    while done < rows:
        k = min(CHUNK_ROWS, rows - done)
        t = (done + np.arange(k + 1, dtype=float)) * dt
        ideal = np.broadcast_to(rate * dt, (k, 6))
        take(stream.push(ImuIncrements(t=t, dtheta_b=ideal[:, :3].copy(), dv_b=ideal[:, 3:].copy())))
        done += k
    take(stream.finish())
    return out


@dataclass(frozen=True)
class Parting:
    """A run of cluster times where one channel's real and simulated curves part.

    Attributes
    ----------
    channel : ``gyro.x`` … ``accel.z``
    tau_s : ``(first, last)`` cluster time of the run, s
    ratio : the real Allan deviation over the simulated one where they part most
    fitted : whether the run lies where the terms were fitted (False: cluster times the fit left out,
        where the noise model was already found not to hold)
    """

    channel: str
    tau_s: tuple[float, float]
    ratio: float
    fitted: bool = True

    def what(self) -> str:
        """In words: ``gyro.x: the real unit 3.2x the model at τ = 0.01-0.04 s``."""
        side = "above" if self.ratio > 1.0 else "below"
        a, b = self.tau_s
        span = f"{a:.3g} s" if a == b else f"{a:.3g}-{b:.3g} s"
        where = "" if self.fitted else " (left out of the fit)"
        if not math.isfinite(self.ratio):
            what = "the model has no noise where the real unit has"
        else:
            digits = 3 if abs(math.log(self.ratio)) >= 0.01 else 4  # not "1x" for 0.9996
            what = f"the real unit {self.ratio:.{digits}g}x the model's deviation ({side})"
        return f"{self.channel}: {what} at τ = {span}{where}"


@dataclass(frozen=True)
class ClosingCheck:
    """The real and simulated Allan curves side by side, and where they part.

    Attributes
    ----------
    seed : of the simulation
    confidence : of the parting test
    channels : channel → ``tau_s``, ``real_adev``, ``sim_adev``, ``model_adev`` (the fitted terms'),
        ``band_low``/``band_high`` (where the simulated deviation may lie, given the real one, at
        ``confidence``), ``parted`` (bool per point)
    partings : the runs of parted points, channel by channel
    """

    seed: int
    confidence: float
    channels: dict[str, dict[str, list[Any]]] = field(default_factory=dict)
    partings: tuple[Parting, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """The JSON document."""
        return {
            "seed": self.seed,
            "confidence": self.confidence,
            "channels": self.channels,
            "partings": [
                {
                    "channel": p.channel,
                    "tau_s": list(p.tau_s),
                    # JSON has no infinity: a deviation the model puts at zero parts without a ratio
                    # (``what`` says so).
                    "ratio": p.ratio if math.isfinite(p.ratio) else None,
                    "fitted": p.fitted,
                    "what": p.what(),
                }
                for p in self.partings
            ],
        }


def closing_check(result: Characterisation, model: ImuModel, seed: int = 0,
                  confidence: float = CHECK_CONFIDENCE,
                  progress: Callable[[int, int], None] | None = None) -> ClosingCheck:  # fmt: skip
    """Simulate ``model`` as long as the recording, in segments as long as its, and compare the curves.

    Parameters
    ----------
    result : the real recording's characterisation
    model : the unit to simulate (``scenario.load_imu(path).model()`` of the written file)
    seed : of the simulation
    confidence : two-sided, of the ``F`` test at each cluster time
    progress : called as ``progress(channels_done, channels)`` after the simulation and each channel

    Returns
    -------
    ClosingCheck
    """
    lengths = [b - a for a, b in result.segments]
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(int)
    spans = tuple((int(s), int(s + n)) for s, n in zip(starts, lengths, strict=True))
    sim = simulate_static(model, result.dt, int(sum(lengths)), seed, result.input_mean)
    if progress is not None:
        progress(0, len(result.channels))
    channels: dict[str, dict[str, list[Any]]] = {}
    partings: list[Parting] = []
    for ch, r in result.channels.items():
        real = r.curve
        simulated = allan(sim[:, CHANNELS.index(ch)], result.dt, spans)
        edf = real.edf
        slack = 1.0 + 2.0 * r.fit.tolerance  # the model error the fit allowed, on both curves
        lo = stats.f.ppf(0.5 - confidence / 2.0, edf, edf) / slack
        hi = stats.f.ppf(0.5 + confidence / 2.0, edf, edf) * slack
        # A simulated curve of zero (a channel the model has no noise on) against a real one: apart.
        has = simulated.avar > 0.0
        ratio = np.where(
            has, real.avar / np.where(has, simulated.avar, 1.0), np.where(real.avar > 0.0, np.inf, 1.0)
        )
        parted = (ratio < lo) | (ratio > hi)
        in_fit = ~np.isin(real.tau_s, np.asarray(r.fit.excluded_tau_s, dtype=float))
        channels[ch] = {
            "tau_s": real.tau_s.tolist(),
            "real_adev": real.adev.tolist(),
            "sim_adev": simulated.adev.tolist(),
            "model_adev": np.sqrt(r.fit.resolved_avar(real.tau_s, real.clusters)).tolist(),
            "band_low": np.sqrt(real.avar / hi).tolist(),
            "band_high": np.sqrt(real.avar / lo).tolist(),
            "parted": [bool(p) for p in parted],
        }
        k = 0
        while k < len(parted):
            if not parted[k]:
                k += 1
                continue
            j = k
            while (
                j + 1 < len(parted)
                and parted[j + 1]
                and (ratio[j + 1] > 1.0) == (ratio[k] > 1.0)
                and in_fit[j + 1] == in_fit[k]
            ):
                j += 1
            run = np.sqrt(ratio[k : j + 1])
            worst = float(run[np.argmax(np.abs(np.log(run)))])
            partings.append(Parting(ch, (float(real.tau_s[k]), float(real.tau_s[j])), worst, bool(in_fit[k])))
            k = j + 1
        if progress is not None:
            progress(len(channels), len(result.channels))
    return ClosingCheck(seed, confidence, channels, tuple(partings))


__all__ = [
    "CHECK_CONFIDENCE",
    "CHUNK_ROWS",
    "ClosingCheck",
    "Parting",
    "closing_check",
    "simulate_static",
]
