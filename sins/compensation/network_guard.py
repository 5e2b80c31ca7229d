"""The held-back guard of the seed paper's networks on several recordings of one unit.

``mlp_pure``, ``mlp_seed`` and ``kohonen_pure`` correct with a network of their own, from readings to
errors, in place of the seed model (:func:`sins.compensation.referenced.replaces_seed_model`). The
learners built on the seed model (``mlp``, ``kohonen``, ``mlp_window``) keep it wherever their held-back
gain does not clear their guard; these networks have no seed model beneath them to keep. So, fitted on
several recordings, each is judged as those are: every recording held back whole in turn, the network
and least squares (``regression``) each fitted on the others with their own bias rule
(:func:`sins.compensation.referenced.fit_several`), and the held-back recording corrected by each as
``sins evaluate`` corrects it. Each sensor is judged by what it is for, the accelerometer first: what
it leaves of each interval's velocity change against the reference (:func:`velocity_spread`); where the
network's does not beat least squares' by :data:`GUARD_Z` standard errors of the mean gain over the
recordings, least squares' accelerometer replaces it (:attr:`sins.compensation.base.Strategy.accel_seed_`;
held back on EuRoC the networks' accelerometers had been 0.4-2.8 % behind). Then the gyro, by the
open-loop attitude error (AOE, the benchmark's metric: :func:`sins.compensation.unit_bias.open_loop_deg`)
of that model: the network is written only where its mean gain over least squares exceeds
:data:`GUARD_Z` standard errors; elsewhere least squares' model is (what the recordings determine), and
the fit says why. Where the network's accelerometer earns its place and its gyro does not, the network's
accelerometer is written beside least squares' gyro and least squares' bias rule
(:attr:`sins.compensation.base.Strategy.gyro_seed_`), where held back that gyro's AOE is not behind least
squares' on the mean (under a rule without an online estimate it is least squares' to rounding; the
online estimate reads the accelerometer). Beside the network's own rule it had not been: that rule's rest
offsets are the network gyro's (BROAD's unit B, `kohonen_pure`: 34.6, -12.4, 21.5 °/h against least
squares' 92.3, 15.6, -9.1), which moved `mlp_seed`'s held-back open-loop attitude by -0.03° ± 0.24° on
the mean. Blocks of one
recording share its day, its motion and its reference, so the recordings are the folds, as the other
guards' are; with fewer than :data:`MIN_RECORDINGS` none can be held back and leave several to fit on,
and the network has not shown what it adds.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from sins.compensation.base import Strategy
    from sins.core.series import ImuIncrements, ReferencedRecording

#: The networks the guard judges (registered names; ``mlp_seed`` is ``mlp_pure`` with the paper's settings).
NETWORKS = ("mlp_pure", "kohonen_pure")
#: The network is kept where its mean held-back gain exceeds this many standard errors (the learners' own).
GUARD_Z = 2.0
#: What the network is judged against.
BASELINE = "regression"
#: The fewest recordings the guard judges on: each held back leaves two or more to fit on.
MIN_RECORDINGS = 3
#: How far behind least squares' AOE (deg, the mean held back) least squares' gyro beside the network's
#: accelerometer may be and still be written (:attr:`NetworkGuard.accel_alone`): rounding alone. The
#: same gyro corrected by another path differed by 1e-13° on BROAD's unit B.
ROUNDING_DEG = 1e-9


@dataclass(frozen=True)
class NetworkGuard:
    """The held-back judgement of a network (``label``) against least squares on each recording
    (``sources``), the network and least squares fitted on the others. The accelerometer first: what the
    network's leaves of each interval's velocity change (:func:`velocity_spread`, m/s per axis:
    ``accel_network_m_s``) against least squares' (``accel_baseline_m_s``), both beside the network's
    gyro. Then the gyro, by the open-loop attitude error, deg, of the model that would be written: the
    network whole (``network_deg``), or with least squares' accelerometer where the network's did not
    earn its place (``hybrid_deg``: the online bias rule reads the accelerometer too), against least
    squares (``baseline_deg``); and the network's accelerometer beside least squares' gyro and bias rule
    (``seed_gyro_deg``), written where the accelerometer earns its place and the gyro does not
    (:attr:`accel_alone`). No recordings where it could not be judged, and ``unjudged`` says why
    (too few recordings to hold one back, or a fit on the others refused)."""

    label: str
    sources: tuple[str, ...]
    network_deg: tuple[float, ...]
    baseline_deg: tuple[float, ...]
    hybrid_deg: tuple[float, ...] = ()
    accel_network_m_s: tuple[tuple[float, ...], ...] = ()
    accel_baseline_m_s: tuple[tuple[float, ...], ...] = ()
    #: The AOE of the network's accelerometer beside least squares' gyro and bias rule, deg (empty where
    #: not measured: :attr:`accel_alone` is then False).
    seed_gyro_deg: tuple[float, ...] = ()
    guard_z: float = GUARD_Z
    unjudged: str = ""

    def __post_init__(self) -> None:
        figures = (self.network_deg, self.baseline_deg, self.hybrid_deg, self.accel_network_m_s,
                   self.accel_baseline_m_s)  # fmt: skip
        measured = len(self.seed_gyro_deg) in (0, len(self.sources))  # empty: not measured
        if any(len(f) != len(self.sources) for f in figures) or not measured:
            raise ValueError(f"{self.label}'s guard: every figure one per recording ({len(self.sources)})")

    @property
    def threshold(self) -> float:
        """The standard errors a mean gain must exceed: :attr:`guard_z` as Student's t over the recordings
        (:func:`~sins.compensation.base.recordings_threshold`)."""
        from sins.compensation.base import recordings_threshold

        return recordings_threshold(self.guard_z, len(self.sources))

    @property
    def judged(self) -> bool:
        """Whether there were recordings enough to hold back (:data:`MIN_RECORDINGS`)."""
        return len(self.sources) >= MIN_RECORDINGS

    @property
    def accel_gains_pct(self) -> np.ndarray:
        """How much less the network's accelerometer leaves than least squares', per held-back recording,
        % of least squares' spread, the mean over the three axes (positive: the network wins)."""
        base = np.asarray(self.accel_baseline_m_s, dtype=float).reshape(-1, 3)
        net = np.asarray(self.accel_network_m_s, dtype=float).reshape(-1, 3)
        return np.asarray(100.0 * ((base - net) / base).mean(axis=1))

    @property
    def accel_kept(self) -> bool:
        """Whether the network's accelerometer earns its place: judged, its mean gain above
        :attr:`threshold` standard errors."""
        mean, error = _mean_and_error(self.accel_gains_pct)
        return self.judged and mean > self.threshold * error

    @property
    def written_deg(self) -> tuple[float, ...]:
        """The AOE of the model that would be written: the network whole, or with least squares'
        accelerometer (:attr:`accel_kept`)."""
        return self.network_deg if self.accel_kept else self.hybrid_deg

    @property
    def gains_deg(self) -> np.ndarray:
        """Least squares' AOE less :attr:`written_deg`'s, per held-back recording (positive: the network
        wins)."""
        return np.asarray(self.baseline_deg) - np.asarray(self.written_deg)

    @property
    def mean_gain_deg(self) -> float:
        """The mean of :attr:`gains_deg` over the recordings (NaN where not :attr:`judged`)."""
        return _mean_and_error(self.gains_deg)[0] if self.judged else float("nan")

    @property
    def standard_error_deg(self) -> float:
        """The standard error of :attr:`mean_gain_deg` over the recordings (NaN where not :attr:`judged`)."""
        return _mean_and_error(self.gains_deg)[1] if self.judged else float("nan")

    @property
    def seed_gyro_gain_deg(self) -> float:
        """Least squares' AOE less that of the network's accelerometer beside least squares' gyro and
        rule, the mean over the recordings (NaN where not measured or not :attr:`judged`)."""
        if not self.judged or len(self.seed_gyro_deg) != len(self.sources):
            return float("nan")
        return float(np.mean(np.asarray(self.baseline_deg) - np.asarray(self.seed_gyro_deg)))

    @property
    def accel_alone(self) -> bool:
        """Whether the network's accelerometer is written beside least squares' gyro and bias rule: it
        earns its place (:attr:`accel_kept`), the network's gyro does not (:attr:`kept`), and held back
        least squares' gyro beside it is not behind least squares' own on the mean (beyond
        :data:`ROUNDING_DEG`)."""
        return self.accel_kept and not self.kept and self.seed_gyro_gain_deg >= -ROUNDING_DEG

    @property
    def kept(self) -> bool:
        """Whether the network earns its place: judged, its mean gain above :attr:`threshold` standard
        errors. Not judged (too few recordings to hold one back), it has not shown it."""
        return self.judged and self.mean_gain_deg > self.threshold * self.standard_error_deg

    def lines(self) -> list[str]:
        """What the guard found, in words: each recording's figures, then the verdicts."""
        if not self.judged:
            return [
                f"{self.label}'s guard holds each recording back whole and fits on the others: "
                f"{self.unjudged}; least squares' model ({BASELINE}) is written, not {self.label}'s "
                "(--no-guard writes the network unjudged)"
            ]
        mm = lambda v: " ".join(f"{1e3 * x:.1f}" for x in v)  # noqa: E731
        rows = [
            f"  {s}: accelerometer {mm(an)} against {mm(ab)} mm/s; AOE {w:.3f}° against {b:.3f}°"
            for s, an, ab, w, b in zip(self.sources, self.accel_network_m_s, self.accel_baseline_m_s,
                                       self.written_deg, self.baseline_deg, strict=True)
        ]  # fmt: skip
        head = (
            f"{self.label} held back against least squares (each recording in turn, both fitted on the "
            "others): the accelerometer by what it leaves of each interval's velocity change (its spread "
            "over the intervals, x y z), then the gyro by the open-loop attitude error (AOE) of the model "
            "it would write (with least squares' accelerometer where the network's is not kept)"
        )
        mean, error = _mean_and_error(self.accel_gains_pct)
        bar = f"{self.threshold:.3g} standard errors (Student's t over {len(self.sources)} recordings)"
        accel = f"accelerometer: mean gain {mean:+.1f} % ± {error:.1f} %, " + (
            f"above {bar}: the network's is kept"
            if self.accel_kept
            else f"not above {bar}: least squares' replaces the network's"
        )
        gain = f"gyro: mean gain {self.mean_gain_deg:+.3f}° ± {self.standard_error_deg:.3f}°"
        if self.kept:
            how = "" if self.accel_kept else " with least squares' accelerometer"
            verdict = f"{gain}, above {bar}: {self.label} is written{how}"
        elif self.accel_alone:
            held = self.seed_gyro_gain_deg
            said = f"{held:+.3f}° on the mean" if abs(held) >= 5e-4 else "the same to 0.001°"
            verdict = (
                f"{gain}, not above {bar}: {self.label}'s accelerometer is "
                f"written beside least squares' gyro and bias rule (held back, their AOE against least "
                f"squares' own: {said})"
            )
        else:
            verdict = (
                f"{gain}, not above {bar}: least squares' model ({BASELINE}) is "
                f"written, not {self.label}'s (--no-guard writes the network unjudged)"
            )
        return [head, *rows, accel, verdict]

    def to_dict(self) -> dict[str, Any]:
        """The judgement as plain JSON values (``sins fit --json``'s ``network_guard``, and the model
        file's ``fitted_on_``)."""
        judged = lambda value: value if self.judged else None  # noqa: E731
        mean, error = _mean_and_error(self.accel_gains_pct)
        return {
            "strategy": self.label, "baseline": BASELINE, "recordings": list(self.sources),
            "network_aoe_deg": list(self.network_deg), "baseline_aoe_deg": list(self.baseline_deg),
            "hybrid_aoe_deg": list(self.hybrid_deg), "seed_gyro_aoe_deg": list(self.seed_gyro_deg),
            "accel_network_m_s": [list(v) for v in self.accel_network_m_s],
            "accel_baseline_m_s": [list(v) for v in self.accel_baseline_m_s],
            "accel_mean_gain_pct": judged(mean), "accel_standard_error_pct": judged(error),
            "accel_earns_its_place": self.accel_kept, "mean_gain_deg": judged(self.mean_gain_deg),
            "standard_error_deg": judged(self.standard_error_deg),
            "guard_z": self.guard_z, "threshold": self.threshold if self.judged else None,
            "earns_its_place": self.kept,
            "written": self.label if self.kept or self.accel_alone else BASELINE,
            "accelerometer": self.label if self.accel_kept and (self.kept or self.accel_alone) else BASELINE,
            "gyro": self.label if self.kept else BASELINE,
            "unjudged": self.unjudged or None,
        }  # fmt: skip


def _mean_and_error(gains: np.ndarray) -> tuple[float, float]:
    """The mean of per-recording ``gains`` and its standard error (NaN with fewer than two)."""
    from sins.compensation.base import sum_standard_error

    if len(gains) < 2:
        return float("nan"), float("nan")
    return float(gains.mean()), float(sum_standard_error(gains)) / len(gains)


def velocity_spread(
    corrected: ImuIncrements, rec: ReferencedRecording, interval_s: float | None = None
) -> np.ndarray:
    """What ``corrected`` (``rec``'s readings corrected) leaves of each interval's velocity change
    (:func:`sins.compensation.intervals.velocity_residual`, intervals of ``interval_s``: the fit's, by
    default :data:`~sins.compensation.intervals.INTERVAL_S`), its spread over the intervals per axis, m/s
    (3,): each recording's own mean left out, as its own accelerometer bias is no model's (the models
    correct at the recordings' mean bias)."""
    from sins.compensation import intervals
    from sins.nav import attitude

    iv = intervals.choose_intervals(rec, interval_s or intervals.INTERVAL_S)
    q_nb = attitude.propagate_increments(corrected.dtheta_b, np.array([0.0, 0.0, 0.0, 1.0]))
    residual = intervals.velocity_residual(iv, intervals.dcm(q_nb), corrected.dv_b, np.diff(corrected.t))
    return np.asarray(residual.std(axis=0))


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
    interval_s: float | None = None,
) -> NetworkGuard:
    """Network ``name`` judged against least squares on ``recs`` (``names`` name them), each held back in
    turn: ``fit(strategy_name, recordings)`` fits a strategy on the others as the whole fit does (its
    settings, its screen, its bias rule), the velocity change judged over the fit's ``interval_s``. No
    figures with fewer than :data:`MIN_RECORDINGS`, nor where a fit on the others is refused (its reason
    kept): a recording held back leaves fewer to determine the shared model, and a fit the whole set
    determines may not be determined without one of them."""
    from sins.errors import SinsInputError

    if len(recs) < MIN_RECORDINGS:
        return NetworkGuard(name, (), (), (), unjudged=f"that takes {MIN_RECORDINGS} recordings or more")
    folds = []
    for k, rec in enumerate(recs):
        if stage is not None:
            stage(f"the network's guard: recording {k + 1} of {len(recs)} held back")
        others = [r for i, r in enumerate(recs) if i != k]
        try:
            # Least squares first: a fold whose shared model is refused is found before a network trains.
            baseline = fit(BASELINE, others)
            network = fit(name, others)
        except SinsInputError as exc:
            why = f"with {names[k]} held back, the fit on the others was refused ({exc})"
            return NetworkGuard(name, (), (), (), unjudged=why)
        folds.append(_fold(network, baseline, rec, interval_s))
    network_deg, baseline_deg, hybrid_deg, seed_gyro_deg, accel_network, accel_baseline = zip(
        *folds, strict=True
    )
    return NetworkGuard(
        name, tuple(names), network_deg, baseline_deg, hybrid_deg, accel_network, accel_baseline,
        seed_gyro_deg,
    )  # fmt: skip


def _fold(
    network: Strategy, baseline: Strategy, rec: ReferencedRecording, interval_s: float | None = None
) -> tuple[Any, ...]:
    """One held-back recording's figures: the AOE of ``rec`` corrected by the network, by least squares,
    by the network with least squares' accelerometer, and by the network's accelerometer beside least
    squares' gyro and bias rule (:func:`with_seed_gyro`), deg; the spread of the velocity change the
    network's accelerometer leaves and least squares' does beside the network's gyro
    (:func:`velocity_spread`), m/s."""
    from sins.compensation import unit_bias
    from sins.compensation.regression import Regression
    from sins.core.series import ImuIncrements

    assert isinstance(baseline, Regression)  # least squares' model: the seed model's coefficients
    hybrid = copy.copy(network)
    hybrid.accel_seed_ = np.vstack([baseline.A0_, baseline.A_])
    corrected: dict[str, ImuIncrements] = {}
    models = {"network": network, "baseline": baseline, "hybrid": hybrid}
    models["seed_gyro"] = with_seed_gyro(network, baseline)
    for key, model in models.items():
        imu = model.correct_recording(rec.imu)
        assert isinstance(imu, ImuIncrements)  # a recording's readings are its increments
        corrected[key] = imu
    aoe = {key: unit_bias.open_loop_deg(imu, rec) for key, imu in corrected.items()}
    # Least squares' accelerometer is judged beside the network's gyro (the hybrid), not its own.
    spread = {
        k: tuple(velocity_spread(corrected[k], rec, interval_s).tolist()) for k in ("network", "hybrid")
    }
    return (
        aoe["network"],
        aoe["baseline"],
        aoe["hybrid"],
        aoe["seed_gyro"],
        spread["network"],
        spread["hybrid"],
    )


def with_seed_gyro(network: Strategy, baseline: Strategy) -> Strategy:
    """A copy of ``network`` that corrects the gyro as least squares' model ``baseline`` does and takes a
    recording's gyro bias by ``baseline``'s rule (its :attr:`~sins.compensation.base.Strategy.gyro_seed_`
    and ``unit_bias_``; the time offsets are the seed model's, the same in both): the network's
    accelerometer beside least squares' gyro."""
    from sins.compensation.regression import Regression

    assert isinstance(baseline, Regression)  # least squares' model: the seed model's coefficients
    out = copy.copy(network)
    out.gyro_seed_ = np.vstack([baseline.B0_, baseline.B_, baseline.K_, baseline.A0_, baseline.A_])
    for key in ("unit_bias_", "time_offset_s_"):
        if key in vars(baseline):
            setattr(out, key, copy.deepcopy(getattr(baseline, key)))
        else:
            vars(out).pop(key, None)
    return out


__all__ = [
    "BASELINE",
    "GUARD_Z",
    "MIN_RECORDINGS",
    "NETWORKS",
    "ROUNDING_DEG",
    "NetworkGuard",
    "guards",
    "judged",
    "velocity_spread",
    "with_seed_gyro",
]
