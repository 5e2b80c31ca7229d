"""The held-back guard of the seed paper's networks on several recordings of one unit.

``mlp_pure``, ``mlp_seed`` and ``kohonen_pure`` correct with a network of their own, from readings to
errors, in place of the seed model (:func:`sins.compensation.referenced.replaces_seed_model`). The
learners built on the seed model (``mlp``, ``kohonen``, ``mlp_window``) keep it wherever their held-back
gain does not clear their guard; these networks have no seed model beneath them to keep. So, fitted on
several recordings, each is judged as those are: every recording held back whole in turn, the network
and least squares (``regression``) each fitted on the others with their own bias rule
(:func:`sins.compensation.referenced.fit_several`), and the held-back recording corrected by each as
``sins evaluate`` corrects it and judged by its open-loop attitude (AOE, the benchmark's metric:
:func:`sins.compensation.unit_bias.open_loop_deg`). The network is written only where its mean gain over
least squares exceeds :data:`GUARD_Z` standard errors of that mean over the recordings; elsewhere least
squares' model is (what the recordings determine), and the fit says why. Blocks of one recording share
its day, its motion and its reference, so the recordings are the folds, as the other guards' are; with
fewer than :data:`MIN_RECORDINGS` none can be held back and leave several to fit on, and the network has
not shown what it adds.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from sins.compensation.base import Strategy
    from sins.core.series import ReferencedRecording

#: The networks the guard judges (registered names; ``mlp_seed`` is ``mlp_pure`` with the paper's settings).
NETWORKS = ("mlp_pure", "kohonen_pure")
#: The network is kept where its mean held-back gain exceeds this many standard errors (the learners' own).
GUARD_Z = 2.0
#: What the network is judged against.
BASELINE = "regression"
#: The fewest recordings the guard judges on: each held back leaves two or more to fit on.
MIN_RECORDINGS = 3


@dataclass(frozen=True)
class NetworkGuard:
    """The held-back judgement of a network (``label``) against least squares: each recording's
    (``sources``) open-loop attitude error, deg, corrected by the network fitted on the others
    (``network_deg``) and by least squares fitted on them (``baseline_deg``); no recordings where it
    could not be judged, and ``unjudged`` says why (too few recordings to hold one back, or a fit on the
    others refused)."""

    label: str
    sources: tuple[str, ...]
    network_deg: tuple[float, ...]
    baseline_deg: tuple[float, ...]
    guard_z: float = GUARD_Z
    unjudged: str = ""

    @property
    def judged(self) -> bool:
        """Whether there were recordings enough to hold back (:data:`MIN_RECORDINGS`)."""
        return len(self.sources) >= MIN_RECORDINGS

    @property
    def gains_deg(self) -> np.ndarray:
        """Least squares' error less the network's, per held-back recording (positive: the network wins)."""
        return np.asarray(self.baseline_deg) - np.asarray(self.network_deg)

    @property
    def mean_gain_deg(self) -> float:
        """The mean of :attr:`gains_deg` over the recordings (NaN where not :attr:`judged`)."""
        return float(self.gains_deg.mean()) if self.judged else float("nan")

    @property
    def standard_error_deg(self) -> float:
        """The standard error of :attr:`mean_gain_deg` over the recordings (NaN where not :attr:`judged`)."""
        gains = self.gains_deg
        return float(gains.std(ddof=1) / np.sqrt(len(gains))) if self.judged else float("nan")

    @property
    def kept(self) -> bool:
        """Whether the network earns its place: judged, its mean gain above :attr:`guard_z` standard
        errors. Not judged (too few recordings to hold one back), it has not shown it."""
        return self.judged and self.mean_gain_deg > self.guard_z * self.standard_error_deg

    def lines(self) -> list[str]:
        """What the guard found, in words: each recording's figures, then the verdict."""
        if not self.judged:
            return [
                f"{self.label}'s guard holds each recording back whole and fits on the others: "
                f"{self.unjudged}; least squares' model ({BASELINE}) is written, not {self.label}'s "
                "(--no-guard writes the network unjudged)"
            ]
        rows = [
            f"  {s}: {n:.3f}° against {b:.3f}°"
            for s, n, b in zip(self.sources, self.network_deg, self.baseline_deg, strict=True)
        ]
        head = (
            f"{self.label} held back against least squares (each recording in turn, both fitted on the "
            "others; open-loop attitude error, AOE):"
        )
        gain = f"mean gain {self.mean_gain_deg:+.3f}° ± {self.standard_error_deg:.3f}°"
        if self.kept:
            verdict = f"{gain}, above {self.guard_z:g} standard errors: {self.label} is written"
        else:
            verdict = (
                f"{gain}, not above {self.guard_z:g} standard errors: least squares' model ({BASELINE}) is "
                f"written, not {self.label}'s (--no-guard writes the network unjudged)"
            )
        return [head, *rows, verdict]

    def to_dict(self) -> dict[str, Any]:
        """The judgement as plain JSON values (``sins fit --json``'s ``network_guard``, and the model
        file's ``fitted_on_``)."""
        return {
            "strategy": self.label, "baseline": BASELINE, "recordings": list(self.sources),
            "network_aoe_deg": list(self.network_deg), "baseline_aoe_deg": list(self.baseline_deg),
            "mean_gain_deg": self.mean_gain_deg if self.judged else None,
            "standard_error_deg": self.standard_error_deg if self.judged else None,
            "guard_z": self.guard_z, "earns_its_place": self.kept,
            "written": self.label if self.kept else BASELINE, "unjudged": self.unjudged or None,
        }  # fmt: skip


def guards(name: str) -> bool:
    """Whether strategy ``name`` (as ``sins fit --strategy`` names it) is one of the networks this guard
    judges (:data:`NETWORKS`, and their variants: ``mlp_seed``)."""
    from sins.compensation.registry import VARIANTS

    return name in VARIANTS and VARIANTS[name][0] in NETWORKS


def judged(
    name: str,
    recs: list[ReferencedRecording],
    names: list[str],
    fit: Callable[[str, list[ReferencedRecording]], Strategy],
    stage: Callable[[str], Any] | None = None,
) -> NetworkGuard:
    """Network ``name`` judged against least squares on ``recs`` (``names`` name them), each held back in
    turn: ``fit(strategy_name, recordings)`` fits a strategy on the others as the whole fit does (its
    settings, its screen, its bias rule). No figures with fewer than :data:`MIN_RECORDINGS`, nor where a
    fit on the others is refused (its reason kept): a recording held back leaves fewer to determine the
    shared model, and a fit the whole set determines may not be determined without one of them."""
    from sins.compensation import unit_bias
    from sins.core.series import ImuIncrements
    from sins.errors import SinsInputError

    if len(recs) < MIN_RECORDINGS:
        return NetworkGuard(name, (), (), (), unjudged=f"that takes {MIN_RECORDINGS} recordings or more")
    network: list[float] = []
    baseline: list[float] = []
    for k, rec in enumerate(recs):
        if stage is not None:
            stage(f"the network's guard: recording {k + 1} of {len(recs)} held back")
        others = [r for i, r in enumerate(recs) if i != k]
        # Least squares first: a fold whose shared model is refused is found before a network trains.
        for strategy_name, out in ((BASELINE, baseline), (name, network)):
            try:
                corrected = fit(strategy_name, others).correct_recording(rec.imu)
            except SinsInputError as exc:
                why = f"with {names[k]} held back, the fit on the others was refused ({exc})"
                return NetworkGuard(name, (), (), (), unjudged=why)
            assert isinstance(corrected, ImuIncrements)  # a recording's readings are its increments
            out.append(unit_bias.open_loop_deg(corrected, rec))
    return NetworkGuard(name, tuple(names), tuple(network), tuple(baseline))


__all__ = ["BASELINE", "GUARD_Z", "MIN_RECORDINGS", "NETWORKS", "NetworkGuard", "guards", "judged"]
