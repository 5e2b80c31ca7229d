"""What the gap diagnosis reports: each candidate's score, disturbances outside the library, the whole.

:class:`GapReport` is what :func:`sins.gap.diagnosis.diagnose` returns; its ``to_dict`` gives the
stable JSON keys of ``sins gap --json``. :class:`EffectScore` is one candidate's verdict and
:class:`Outside` a disturbance outside the effect library (a bias step, an oscillation) that explains a
channel as well as any library effect.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.imu import BASELINE, display_unit, vocabulary

Array = NDArray[np.float64]


@dataclass(frozen=True)
class EffectScore:
    """A candidate's score in the round it was accepted or last scored: its withheld log-likelihood
    gain less what it needs to be significant (:data:`sins.gap.scoring.SIGNIFICANT_NATS`, and a random
    bias's allowance)."""

    name: str
    channels: tuple[str, ...]
    score: float
    accepted: bool
    #: Candidates this one could not be told from (gains within :data:`sins.gap.scoring.TIE_NATS`); set
    #: on accepted ones.
    indistinguishable: tuple[str, ...] = ()
    #: Why a candidate that scored above 0 was not accepted all the same ("" otherwise).
    not_accepted_because: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON form; ``score`` is None for a candidate ruled out (falsified)."""
        return {
            "name": self.name,
            "channels": list(self.channels),
            "score": self.score if np.isfinite(self.score) else None,  # None: ruled out (falsified)
            "accepted": self.accepted,
            "indistinguishable_from": list(self.indistinguishable),
            "not_accepted_because": self.not_accepted_because or None,
        }


@dataclass(frozen=True)
class Outside:
    """A disturbance outside the library that explains a channel's gap as well as any library effect."""

    channel: str
    kind: str  # "bias step" | "periodic"
    size: float  # the step's size or the oscillation's amplitude, SI units of the channel
    score: float  # withheld log-likelihood gain less SIGNIFICANT_NATS, as for the candidates
    t_s: float | None = None  # when the step happens
    period_s: float | None = None  # the oscillation's period

    def to_dict(self) -> dict[str, Any]:
        """JSON form, without the fields that do not apply."""
        return {k: v for k, v in dataclasses.asdict(self).items() if v is not None}

    def what(self) -> str:
        """The disturbance in words, in the channel's display unit."""
        size, unit = display_unit(self.channel)
        if self.kind == "periodic":
            return f"an oscillation of {self.size / size:.3g} {unit} every {self.period_s:.3g} s"
        return f"a bias step of {self.size / size:+.3g} {unit} at {self.t_s:.1f} s"

    def describe(self) -> str:
        """As a ``where`` entry: the view it belongs to, then :meth:`what`."""
        return f"{'frequency' if self.kind == 'periodic' else 'time'}: {self.what()}"


@dataclass(frozen=True)
class GapReport:
    """What :func:`sins.gap.diagnosis.diagnose` found; ``to_dict`` gives the stable JSON keys."""

    channels: dict[str, dict[str, float]]
    where: list[dict[str, Any]]
    effects: list[EffectScore]
    diagnosis: list[str]
    unexplained: list[str]
    #: Channels whose gap a disturbance outside the library (a bias step, an oscillation) explains.
    outside: list[Outside] = field(default_factory=list)
    #: Per channel: ``tau_s`` and the Allan deviation of the residual ``before`` and ``after`` the
    #: accepted effects, and of the white noise the model expects (``model``), SI units.
    allan: dict[str, dict[str, list[float]]] = field(default_factory=dict)
    #: Per channel and input: the share of the withheld excess in each quartile of that input.
    quartiles: dict[str, dict[str, list[float]]] = field(default_factory=dict)
    rows: tuple[int, int] = (0, 0)  # fit, withheld
    #: Which rows were withheld, and why, in words.
    withholding: str = ""
    #: Candidates the fit rows cannot fit because only the withheld rows excite them, with the reason:
    #: named so that an effect is never silently absent.
    unfitted: dict[str, str] = field(default_factory=dict)
    unreferenced: int = 0  # rows left out for want of a per-sample reference
    model: tuple[str, ...] = BASELINE
    residual_before: Array = field(default_factory=lambda: np.zeros((0, 6)))
    residual_after: Array = field(default_factory=lambda: np.zeros((0, 6)))
    t_withheld: Array = field(default_factory=lambda: np.zeros(0))
    #: The models' predicted errors of every referenced row, (n, 6) SI: before and after the accepted effects.
    predicted_before: Array = field(default_factory=lambda: np.zeros((0, 6)))
    predicted_after: Array = field(default_factory=lambda: np.zeros((0, 6)))
    #: Per accepted effect and channel, its fitted coefficients, SI (:func:`in_units` gives them in its
    #: parameters' units): its columns' coefficients in the order its class gives them, a delay's
    #: seconds, a quantizer's step; a random bias's σ and correlation time (s), or a walk's density.
    sizes: dict[str, dict[str, list[float]]] = field(default_factory=dict)
    #: Which statistic the verdicts were reached on, and why (``sins.unit_gap.statistic``); empty when
    #: :func:`sins.gap.diagnose` is called directly (samples).
    statistic: dict[str, Any] = field(default_factory=dict)
    #: Accepted effects whose size no unit has, and why (``sins.unit_gap.plausible``); empty when
    #: :func:`sins.gap.diagnose` is called directly.
    implausible: dict[str, str] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The stable JSON form: the findings and Allan deviations, not the series."""
        return {
            "channels": self.channels,
            "where": self.where,
            "effects": [e.to_dict() for e in self.effects],
            "diagnosis": self.diagnosis,
            "unexplained": self.unexplained,
            "outside": [o.to_dict() for o in self.outside],
            "withholding": self.withholding,
            "unfitted": self.unfitted,
            "allan": self.allan,
            "sizes": {
                name: {
                    ch: {"values": in_units(name, v)[0], "unit": in_units(name, v)[1], "si": v}
                    for ch, v in channels.items()
                }
                for name, channels in self.sizes.items()
            },
            "statistic": self.statistic or {"kind": "samples"},
            "implausible": self.implausible,
        }


def in_units(name: str, values: list[float]) -> tuple[list[float], str]:
    """An accepted effect's fitted coefficients on one channel (SI) in its file parameters' units
    (:class:`sins.imu.vocabulary.Param`), and the unit: each column's parameter where the effect has
    one vector parameter per column (``k2``; a temperature bias's ``c1`` and ``c2``), else its one
    matrix parameter's for all (a size effect's lever arm, mm; a g² sensitivity's coefficients of
    ``f_j f_k``, °/h/g², where those of the cross products are twice the symmetric tensor's element).
    A random bias's σ and correlation time, or a walk's density, are its class's parameters; an effect
    without parameters keeps SI ("SI")."""
    sensor = name.split(".")[0]
    cls = vocabulary.effect_class(name)
    params = [p for p in cls.params.get(sensor, ()) if p.shape != ()]
    vectors = [p for p in params if p.shape == (3,)]
    if len(vectors) == len(values) and vectors:
        return [v / p.factor for v, p in zip(values, vectors, strict=True)], " | ".join(
            p.unit for p in vectors
        )
    if params:
        return [v / params[0].factor for v in values], params[0].unit
    return list(values), "SI"


__all__ = [
    "EffectScore",
    "GapReport",
    "Outside",
    "in_units",
]
