"""The gyro bias of a recording the model was not fitted on: what a model fitted on several recordings of
one unit does about it at correction time, causally and from the recording alone.

A MEMS gyro's bias moves between power-ups and days by more than anything else in its model (EuRoC's
ADIS16448: 4e-3 rad/s between days, 1e-3 within one; 1e-3 rad/s over two minutes is 4° of open-loop
attitude). :mod:`sins.compensation.several` fits each training recording's own bias; a new recording's is
estimated from the recording itself, by one of these :data:`MODES`:

``pooled``
    the training recordings' mean bias (what a calibration does when it knows nothing of the day).
``rest``
    the mean rate over the recording's opening rest (:func:`opening_rest`, found from the readings: the
    specific force's direction and the mean rate both steady), plus the training recordings' own
    difference between their bias in motion and at their opening rest (a vehicle's motors, a hand's
    tremor: the bias at rest is not the bias in motion); where the recording opens moving, ``online``
    (below) from the pooled prior, which alone would read nothing of the recording.
``nearest``
    the bias of the training recordings whose opening rests read most like this recording's: each
    training recording weighted by how likely its rest's mean rate is this one's, given the two rests'
    own noise and how far a rest says what the bias in flight will be (the training recordings' spread
    of bias in motion less bias at rest); ``online`` where the recording opens moving, no training
    recording opened with a rest, or none lies within reach (:data:`NEAREST_CHI2`). A unit's bias moves
    most between power-ups and days, and a rest of a few seconds tells the day's bias apart where the
    days differ by more than a rest's noise and its motors' effect: the prior is then the day's, not the
    mean of all days. Its spread is what such priors missed by on the training recordings, each in turn
    predicted from the others (leave one out); with three training rests or more, the day's bias is
    weighed against the rest's own reading by what each misses by (:func:`blended_nearest_prior`).
``online``
    the bias's horizontal components (and what of the vertical one the motion reveals) estimated as the
    recording goes, from the one thing every recording of a vehicle that stays within reach knows: its
    velocity stays bounded (:mod:`sins.compensation.online_bias`; the true velocity as noise of
    ``sigma_v``, the accelerometer's bias held to the training recordings' own spread:
    :func:`accel_spread`), regularised towards the prior by its spread: ``online`` from ``pooled``'s,
    ``rest+online`` from ``rest``'s, ``nearest+online`` from ``nearest``'s. Readings are corrected by
    the last estimate made before them (causal).

Every mode that reads a rest (``rest``, ``nearest`` and their ``+online``) takes, while the unit rests,
the rest's mean rate so far, weighted against the pooled prior by their precisions (the rest's standard
error from its rates' spread so far): the bias at rest is what a resting unit's readings tell, and a
recording that never moves is corrected by its own readings, not by the prior.

Each ``+online`` mode has a twin among :data:`CHOICES`, ``online (mixture)`` and so on, whose online
estimate, where it would start from the pooled prior, starts instead from a mixture: one Gaussian about
each training recording's own bias (:func:`mixture_width`), weighed at every update by how well each
explains the velocity so far (:func:`sins.compensation.online_bias.estimate`). A unit whose biases recur
by day or power-up has a new recording of a day it saw placed on that day's bias sooner; one of a new day
is led astray for tens of seconds, so the twins are chosen like the modes, on held-back recordings, and
only where the folds hold :data:`MIXTURE_MIN` recordings or more.

The mode is chosen on held-back training recordings (``sins.compensation.referenced.choose_rule``): each
recording judged by its open-loop attitude with the seed model and the prior made from the others, never
from its own reference. A mode is taken only where it is no worse than the readings as they are on every
held-back recording and better on their mean (:mod:`sins.compensation.rule_choice`); where none is,
the rule is :data:`READINGS`: the model leaves the gyro as read (a
unit whose readings come calibrated already, its bias removed by its maker or its converter, gains
nothing from a model fitted on a few recordings and loses what the fit's own errors add).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.compensation import online_bias
from sins.compensation.bias_spread import (
    MIN_SPREAD,
    accel_spread,
    mixture_width,
    predictive_bound,
    shrunk,
)
from sins.core.series import ImuIncrements, ImuRates, ReferencedRecording
from sins.nav import attitude

Array = NDArray[np.float64]

#: The ways of estimating a recording's bias (see the module docstring).
MODES = ("pooled", "rest", "online", "rest+online", "nearest", "nearest+online")
#: The modes that estimate the bias online (:mod:`sins.compensation.online_bias`).
ONLINE_MODES = ("online", "rest+online", "nearest+online")
#: What a choice's name adds where its online estimate starts from the training recordings' biases'
#: mixture (:attr:`BiasRule.mixture`) rather than the pooled Gaussian.
MIXTURE = " (mixture)"
#: Every choice a rule is chosen among on held-back recordings, simplest first: the modes, then the
#: online ones from the mixture prior.
CHOICES = (*MODES, *(m + MIXTURE for m in ONLINE_MODES))
#: The training recordings the online estimate's mixture prior needs (each one's bias predicted from at
#: least two others when its width is chosen); with fewer, the pooled prior's Gaussian.
MIXTURE_MIN = 3
#: The rule where every mode was worse than the readings on a held-back recording: the gyro as read.
READINGS = "readings"
#: Window of the rest detection, s.
REST_WINDOW_S = 0.5
#: A rest's specific force turns by less than this, deg (the reference's own rest test: 0.5° of turn;
#: a window's mean force under motor vibration is good to about 0.2°).
REST_MAX_TILT_DEG = 1.0
#: ... and its mean rate moves by less than this, rad/s (0.5° of turn over a window).
REST_MAX_RATE_STEP = 0.02
#: The shortest opening rest used, s.
MIN_REST_S = 1.0
#: ``nearest``: a training recording's rest is within reach of this one's below this squared
#: distance (the 99th percentile of chi-squared with 3 degrees of freedom: the three axes' differences,
#: each in its standard deviations): beyond every one, the day is new, and the prior is ``pooled``.
NEAREST_CHI2 = 11.34
#: The training recordings with an opening rest that measure what ``nearest``'s matches miss by (each
#: predicted from the others: with two, one match each and nothing to weigh it by).
MEASURED_RESTS = 3


@dataclass(frozen=True)
class BiasRule:
    """What a model does about a new recording's gyro bias (see the module docstring).

    ``prior`` (3,) rad/s: the bias left in the model's corrected readings on average over the training
    recordings (the model's own bias removes the mean; this is its remainder, ~0); ``spread`` (3,):
    the training recordings' standard deviation about it; ``rest_offset`` (3,): bias in motion less the
    bias at the opening rest, averaged over the training recordings that open with one (zero where none
    does); ``rest_spread`` (3,): its spread; ``sigma_v_mps``: the true velocity's size in the online
    model; ``sigma_accel_mps2``: the accelerometer bias's prior size there (the training recordings' own
    accelerometer biases' spread, :func:`accel_spread`); ``held_back_deg``: the
    open-loop attitude error of each mode on the held-back training recordings (mean), what chose it,
    and (``raw``) of their readings as they are; ``held_back_each_deg``: the same per recording, in the
    order the model was fitted on them; ``components`` (k, 3): each training recording's bias, shifted
    as ``prior`` is, and ``component_width`` (3,): the width of each about it (:func:`mixture_width`),
    the prior of the online estimate where the pooled one would be under ``mixture`` (else, or with
    fewer than :data:`MIXTURE_MIN` of them, the pooled prior's Gaussian); ``moving_held_back_deg``: the
    open-loop attitude of the rule (``rule``) and of the raw readings (``raw``) on each held-back
    recording from its first motion (its opening rest cut away), deg: what the rule does with a new
    recording that opens moving, said by ``sins fit`` (reported, not used); ``online_across``: how many
    times wider than ``spread`` the online estimate's prior is across gravity where it starts from the
    pooled prior's Gaussian (:func:`predictive_bound` of the training recordings: a few recordings' spread is
    often far below the unit's; along gravity the velocity barely sees the bias, so it keeps ``spread``);
    1 in files written before it.
    """

    mode: str = "pooled"
    prior: Array = field(default_factory=lambda: np.zeros(3))
    spread: Array = field(default_factory=lambda: np.full(3, 1e-3))
    rest_offset: Array = field(default_factory=lambda: np.zeros(3))
    rest_spread: Array = field(default_factory=lambda: np.full(3, 1e-3))
    sigma_v_mps: float = 1.0
    sigma_accel_mps2: float = 0.2
    rest_rates: Array = field(default_factory=lambda: np.zeros((0, 3)))
    rest_rates_se: Array = field(default_factory=lambda: np.zeros((0, 3)))
    rest_biases: Array = field(default_factory=lambda: np.zeros((0, 3)))
    nearest_spread: Array = field(default_factory=lambda: np.full(3, 1e-3))
    nearest_blend: bool = False
    components: Array = field(default_factory=lambda: np.zeros((0, 3)))
    component_width: Array = field(default_factory=lambda: np.full(3, 1e-3))
    mixture: bool = False
    held_back_deg: dict[str, float] = field(default_factory=dict)
    held_back_each_deg: dict[str, list[float]] = field(default_factory=dict)
    moving_held_back_deg: dict[str, list[float]] = field(default_factory=dict)
    online_across: float = 1.0

    def __post_init__(self) -> None:
        if self.mode not in (*MODES, READINGS):
            raise ValueError(f"bias rule mode {self.mode!r} (known: {', '.join((*MODES, READINGS))})")
        for key in ("prior", "spread", "rest_offset", "rest_spread", "nearest_spread", "component_width"):
            value = np.asarray(getattr(self, key), dtype=float)
            if value.shape != (3,) or not np.isfinite(value).all():
                raise ValueError(f"bias rule {key}: expected 3 finite numbers")
            object.__setattr__(self, key, value)
        for key in ("rest_rates", "rest_rates_se", "rest_biases"):
            value = np.asarray(getattr(self, key), dtype=float)
            value = value.reshape(0, 3) if value.size == 0 else value
            if value.ndim != 2 or value.shape[1] != 3 or not np.isfinite(value).all():
                raise ValueError(f"bias rule {key}: expected rows of 3 finite numbers")
            if len(value) != len(np.asarray(self.rest_rates).reshape(-1, 3)):
                raise ValueError(f"bias rule {key}: expected as many rows as rest_rates")
            object.__setattr__(self, key, value)
        if np.any(self.rest_rates_se <= 0.0) or np.any(self.nearest_spread <= 0.0):
            raise ValueError("bias rule: rest_rates_se and nearest_spread must be positive")
        components = np.asarray(self.components, dtype=float)
        components = components.reshape(0, 3) if components.size == 0 else components
        if components.ndim != 2 or components.shape[1] != 3 or not np.isfinite(components).all():
            raise ValueError("bias rule components: expected rows of 3 finite numbers")
        object.__setattr__(self, "components", components)
        if np.any(self.component_width <= 0.0):
            raise ValueError("bias rule: component_width must be positive")
        if not (0.0 < self.sigma_v_mps < 1e3 and 0.0 < self.sigma_accel_mps2 < 1e3):
            raise ValueError("bias rule: sigma_v_mps and sigma_accel_mps2 must be in (0, 1000)")
        if not 1.0 <= self.online_across < 1e3:
            raise ValueError("bias rule online_across: expected a number in [1, 1000)")
        if np.any(self.spread <= 0.0) or np.any(self.rest_spread <= 0.0):
            raise ValueError("bias rule: spreads must be positive")
        for key in ("nearest_blend", "mixture"):
            if not isinstance(getattr(self, key), bool):
                raise ValueError(f"bias rule {key}: expected true or false")

    def to_dict(self) -> dict[str, Any]:
        """The rule as a JSON object (what a model file keeps)."""
        return {
            "mode": self.mode, "prior": self.prior.tolist(), "spread": self.spread.tolist(),
            "rest_offset": self.rest_offset.tolist(), "rest_spread": self.rest_spread.tolist(),
            "sigma_v_mps": self.sigma_v_mps, "sigma_accel_mps2": self.sigma_accel_mps2,
            "rest_rates": self.rest_rates.tolist(), "rest_rates_se": self.rest_rates_se.tolist(),
            "rest_biases": self.rest_biases.tolist(), "nearest_spread": self.nearest_spread.tolist(),
            "nearest_blend": self.nearest_blend, "components": self.components.tolist(),
            "component_width": self.component_width.tolist(), "mixture": self.mixture,
            "held_back_deg": dict(self.held_back_deg),
            "held_back_each_deg": {k: list(v) for k, v in self.held_back_each_deg.items()},
            "moving_held_back_deg": {k: list(v) for k, v in self.moving_held_back_deg.items()},
            "online_across": self.online_across,
        }  # fmt: skip

    @property
    def choice(self) -> str:
        """The rule's name among :data:`CHOICES`: its mode, and whether its online estimate starts from
        the mixture prior."""
        return self.mode + MIXTURE if self.mixture and self.mode in ONLINE_MODES else self.mode

    @property
    def misses_measured(self) -> bool:
        """Whether the training rests measure what ``nearest``'s matches miss by: at least
        :data:`MEASURED_RESTS` of them (each predicted from the others)."""
        return len(self.rest_rates) >= MEASURED_RESTS

    @classmethod
    def from_dict(cls, doc: dict[str, Any]) -> BiasRule:
        """The rule :meth:`to_dict` wrote; ``ValueError`` naming what is wrong."""
        known = {f for f in cls.__dataclass_fields__}
        odd = [k for k in doc if k not in known]
        if odd:
            raise ValueError(f"bias rule: unknown key {odd[0]!r}")
        held = doc.get("held_back_deg", {})
        if not isinstance(held, dict):
            raise ValueError("bias rule held_back_deg: expected an object")
        lists = {k: doc.get(k, {}) for k in ("held_back_each_deg", "moving_held_back_deg")}
        for key, got in lists.items():
            if not isinstance(got, dict) or not all(isinstance(v, list) for v in got.values()):
                raise ValueError(f"bias rule {key}: expected an object of lists")
        return cls(**{
            **doc, "held_back_deg": {str(k): float(v) for k, v in held.items()},
            **{key: {str(k): [float(x) for x in v] for k, v in got.items()} for key, got in lists.items()},
        })  # fmt: skip


def opening_rest(omega_ib_b: Array, f_ib_b: Array, dt: float) -> int:
    """How many readings the recording's opening rest holds (0 where it opens moving or rests less than
    :data:`MIN_REST_S`): the leading windows of :data:`REST_WINDOW_S` whose mean specific force points
    within :data:`REST_MAX_TILT_DEG` of the first window's and whose mean rate stays within
    :data:`REST_MAX_RATE_STEP` of it. From the readings alone (their bias, up to 0.08 rad/s here, is the
    first window's as much as any other's: only changes are tested)."""
    n = max(1, round(REST_WINDOW_S / dt))
    k_all = len(omega_ib_b) // n
    if k_all < 2:
        return 0
    rate = omega_ib_b[: k_all * n].reshape(k_all, n, 3).mean(axis=1)
    force = f_ib_b[: k_all * n].reshape(k_all, n, 3).mean(axis=1)
    norm = np.linalg.norm(force, axis=1)
    if norm[0] <= 0.0:
        return 0
    cos = (force @ force[0]) / np.maximum(norm * norm[0], 1e-300)
    steady = (np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) < REST_MAX_TILT_DEG) & (
        np.abs(rate - rate[0]).max(axis=1) < REST_MAX_RATE_STEP
    )
    k = len(steady) if steady.all() else int(np.argmin(steady))
    return k * n if k * n * dt >= MIN_REST_S else 0


def rest_of(imu: ImuIncrements) -> tuple[int, Array, float]:
    """:func:`opening_rest` of increments ``imu``: its length in steps, with the readings as rates
    (n, 3) rad/s and their median interval, s, that it was found from."""
    _, omega_ib_b, f_ib_b = imu.mean_rates()
    dt = float(np.median(np.diff(imu.t)))
    return opening_rest(omega_ib_b, f_ib_b, dt), omega_ib_b, dt


#: The modes that take a recording's prior from its opening rest (:func:`_rest_prior`).
FROM_REST = ("rest", "rest+online", "nearest", "nearest+online")


def _rest_prior(rule: BiasRule, imu: ImuIncrements) -> tuple[int, Array | None, Array]:
    """What the rule takes from a recording's opening rest (its corrected increments ``imu``): the
    rest's length in steps (0: it opens moving, or the mode takes nothing from a rest), the prior it
    gives with its spread (``rest``: the rest's mean rate plus the training recordings' motion offset;
    ``nearest``: :func:`nearest_prior`), or None and the pooled spread where it gives none."""
    if rule.mode not in FROM_REST:
        return 0, None, rule.spread
    rest, omega, dt = rest_of(imu)
    if not rest:
        return 0, None, rule.spread
    still = omega[:rest]
    if rule.mode.startswith("rest"):
        return rest, still.mean(axis=0) + rule.rest_offset, rule.rest_spread
    prior_of = blended_nearest_prior if rule.nearest_blend else nearest_prior
    near = prior_of(rule, still.mean(axis=0), _rest_se(still, dt))
    return rest, near, (rule.spread if near is None else rule.nearest_spread)


def bias_track(rule: BiasRule, imu: ImuIncrements) -> Array:
    """The bias the rule takes for each step of ``imu`` (corrected readings), rad/s (n, 3): at each step,
    from the readings before it only. ``ValueError`` under :data:`READINGS`, which takes no bias: the gyro
    is kept as read (:func:`applied`), not the model's correction of it."""
    if rule.mode == READINGS:
        raise ValueError("the readings rule takes no bias: the gyro is kept as read (unit_bias.applied)")
    track = np.tile(rule.prior, (len(imu.t) - 1, 1))
    rest, own, sigma = _rest_prior(rule, imu)
    prior = rule.prior if own is None else own
    if own is not None:  # before the rest has ended nothing better than the pooled prior is known
        track[rest:] = own
    # A rest mode whose recording gives it no prior (it opens moving, or its rest reads like no training
    # recording's) estimates the bias online from the pooled prior, as its +online twin does there.
    if rule.mode in ONLINE_MODES or (own is None and rule.mode in FROM_REST):
        mixed = own is None and _mixed(rule)
        track = online_bias.estimate(
            imu, track, prior, rule.component_width if mixed else sigma, rule.sigma_v_mps,
            rule.sigma_accel_mps2, rule.components if mixed else None,
            rule.online_across if own is None and not mixed else 1.0,
        )  # fmt: skip
    if rest:  # while the unit rests, its own readings so far tell its bias (the rest's, not the flight's)
        track[:rest] = _resting(rule, imu, rest)
    return track


def _resting(rule: BiasRule, imu: ImuIncrements, rest: int) -> Array:
    """The bias over the opening rest's ``rest`` steps, each from the steps before it: the pooled prior
    (give or take its spread) and the rest's mean rate so far (give or take its standard error, from the
    rates' spread so far) weighted by their precisions. Causal to the rest window: the first
    :data:`REST_WINDOW_S` keeps the prior (the rest is told from whole windows)."""
    dt = np.diff(imu.t)[:rest, None]
    omega = imu.dtheta_b[:rest] / dt
    out = np.tile(rule.prior, (rest, 1))
    first = max(2, round(REST_WINDOW_S / float(np.median(dt))))
    if rest <= first:
        return out
    count = np.arange(first, rest)[:, None]  # step k's estimate takes the steps before it
    mean = np.cumsum(omega, axis=0)[first - 1 : rest - 1] / count
    square = np.cumsum(omega**2, axis=0)[first - 1 : rest - 1] / count
    se2 = np.maximum(square - mean**2, MIN_SPREAD**2) / count
    w_prior, w_rest = 1.0 / rule.spread**2, 1.0 / se2
    out[first:] = (w_prior * rule.prior + w_rest * mean) / (w_prior + w_rest)
    return out


def prior_said(rule: BiasRule, imu: ImuIncrements) -> str:
    """Where the rule took the prior of a recording's gyro bias (its corrected increments ``imu``), in
    words ("" for a rule that takes no prior from the recording): what ``sins evaluate`` says, so that a
    judged figure can be read with the rule's reason beside it."""
    if rule.mode not in FROM_REST:
        return ""
    rest, own, _ = _rest_prior(rule, imu)
    head = f"a new recording's gyro bias (rule {rule.choice}): "
    if not rest:
        return head + "it opens moving, so its prior is " + (
            _MIXED_SAID if _mixed(rule)
            else "the training recordings' mean bias as far as they determine it (none on an axis where "
            "they cannot tell it from zero: shrunk), estimated online from there"
        ) + _ALONG_SAID  # fmt: skip
    rest_s = f"its opening rest of {rest * float(np.median(np.diff(imu.t))):.1f} s"
    head += f"{rest_s}'s mean rate so far while it rests; "
    if rule.mode.startswith("rest"):
        return head + "after it, the rest's mean rate and the training recordings' motion offset"
    if own is None:
        far = _rest_distance(rule, imu, rest)
        said = f" ({far:.3g} standard deviations from the nearest: another unit, a new day?)" if far else ""
        after = _MIXED_SAID if _mixed(rule) else "their mean, estimated online from there"
        return head + f"the rest reads like no training recording's{said}, so after it {after}"
    said = "the rest reads like some training recordings' rests: after it, their bias"
    weighed = rule.nearest_blend and rule.misses_measured
    return head + said + (" weighed against the rest's own reading by what each missed by" if weighed else "")


#: What ``prior_said`` adds of a recording that opens moving: the part no velocity shows.
_ALONG_SAID = (
    "; its part along gravity turns the heading, which the velocity shows only through the vehicle's "
    "tilts: where they are small, the heading's error is the prior's"
)
#: What ``prior_said`` adds where the online estimate starts from the mixture prior.
_MIXED_SAID = (
    "each training recording's own bias (shifted as their mean is), as a mixture whose components the "
    "online estimate weighs by how well each explains the velocity so far"
)


def _mixed(rule: BiasRule) -> bool:
    """Whether the rule's online estimate starts from the mixture prior where the pooled one would be."""
    return rule.choice.endswith(MIXTURE) and len(rule.components) >= MIXTURE_MIN


def _rest_distance(rule: BiasRule, imu: ImuIncrements, rest: int) -> float:
    """How far a recording's opening rest (its first ``rest`` steps) reads from the nearest training
    recording's, in standard deviations (the root of :func:`nearest_prior`'s squared distance); 0 where
    no training recording opened with a rest. A walk's BROAD unit, judged by a EuRoC model, read as far
    as its bias is from EuRoC's: said, where before only "reads like no training recording's"."""
    if not len(rule.rest_rates):
        return 0.0
    still = imu.dtheta_b[:rest] / np.diff(imu.t)[:rest, None]
    d2 = _rest_d2(rule, still.mean(axis=0), _rest_se(still, float(np.median(np.diff(imu.t)))))
    return float(np.sqrt(d2.min()))


def _rest_d2(
    rule: BiasRule, rest_rate: Array, rest_se: Array, keep: NDArray[np.bool_] | None = None
) -> Array:
    """Each (kept) training recording's rest's squared distance from a rest of mean rate ``rest_rate``
    (± ``rest_se``), summed over the axes, each axis's difference in standard deviations: two rests of
    one day differ by their noise and by each one's own bias at rest less in motion."""
    keep = np.ones(len(rule.rest_rates), dtype=bool) if keep is None else keep
    var = rest_se**2 + rule.rest_rates_se[keep] ** 2 + 2.0 * rule.rest_spread**2
    return np.asarray((((rule.rest_rates[keep] - rest_rate) ** 2) / var).sum(axis=1), dtype=float)


def nearest_prior(
    rule: BiasRule, rest_rate: Array, rest_se: Array, leave_out: int | None = None
) -> Array | None:
    """``nearest``'s prior for a recording whose opening rest's mean rate is ``rest_rate`` (± ``rest_se``),
    rad/s: the training recordings' biases (:attr:`BiasRule.rest_biases`) weighted by the likelihood of
    their rests' mean rates being this one's, each axis's difference in standard deviations of the two
    rests' noise and the spread of bias in motion less bias at rest (``rest_spread``); None where no
    training recording's rest lies within :data:`NEAREST_CHI2` (``leave_out``: one training recording
    left out, to judge the others' prediction of it)."""
    matched = _matches(rule, rest_rate, rest_se, leave_out)
    if matched is None:
        return None
    w, keep = matched
    return np.asarray(w @ rule.rest_biases[keep], dtype=float)


def _matches(
    rule: BiasRule, rest_rate: Array, rest_se: Array, leave_out: int | None = None
) -> tuple[Array, NDArray[np.bool_]] | None:
    """The training recordings (a mask) whose rests lie within :data:`NEAREST_CHI2` of this rest and
    their normalised likelihood weights; None where none does."""
    keep = np.ones(len(rule.rest_rates), dtype=bool)
    if leave_out is not None:
        keep[leave_out] = False
    if not keep.any():
        return None
    d2 = _rest_d2(rule, rest_rate, rest_se, keep)
    if d2.min() > NEAREST_CHI2:
        return None
    w = np.exp(-0.5 * (d2 - d2.min()))
    return w / w.sum(), keep


def blended_nearest_prior(rule: BiasRule, rest_rate: Array, rest_se: Array) -> Array | None:
    """``nearest``'s prior: the matched training recordings' biases (:func:`nearest_prior`, which missed
    by :attr:`BiasRule.nearest_spread` held back) and this rest's mean rate plus their own bias in motion
    less at rest (which misses by the two rests' noise and two offsets' spread), per axis each weighted by
    the other's variance (:func:`_matches_share`). A unit of a few days keeps the matches; one whose every
    recording is a new power-up, where a match is one more draw, the rest's reading. None where no
    training recording's rest is near."""
    matched = _matches(rule, rest_rate, rest_se)
    if matched is None:
        return None
    w, keep = matched
    near = w @ rule.rest_biases[keep]
    from_rest = rest_rate + w @ (rule.rest_biases[keep] - rule.rest_rates[keep])
    share = _matches_share(rule, rest_se, w, keep)
    return np.asarray(share * near + (1.0 - share) * from_rest, dtype=float)


def _matches_share(rule: BiasRule, rest_se: Array, w: Array, keep: NDArray[np.bool_]) -> Array:
    """Per axis, the matches' share of :func:`blended_nearest_prior`: the rest's reading's variance over
    the two variances' sum; 1 with fewer than :data:`MEASURED_RESTS` training rests (a miss unmeasured)."""
    if not rule.misses_measured:
        return np.ones(3)
    var_near = rule.nearest_spread**2
    var_rest = rest_se**2 + w @ rule.rest_rates_se[keep] ** 2 + 2.0 * rule.rest_spread**2
    return np.asarray(var_rest / (var_near + var_rest), dtype=float)


def _rest_se(omega: Array, dt: float) -> Array:
    """The standard error of a rest's mean rate, rad/s (3,): by batch means over windows of
    :data:`REST_WINDOW_S` (a motor's vibration and the bias's own wander are not white), at least the
    readings' white-noise standard error."""
    n = max(1, round(REST_WINDOW_S / dt))
    k = len(omega) // n
    white = omega.std(axis=0) / np.sqrt(len(omega))
    if k < 2:
        return np.maximum(white, MIN_SPREAD)
    means = omega[: k * n].reshape(k, n, 3).mean(axis=1)
    return np.maximum(np.maximum(means.std(axis=0, ddof=1) / np.sqrt(k), white), MIN_SPREAD)


def corrected(rule: BiasRule, imu: ImuIncrements) -> ImuIncrements:
    """``imu`` with :func:`bias_track`'s bias taken away."""
    dt = np.diff(imu.t)
    return ImuIncrements(t=imu.t, dtheta_b=imu.dtheta_b - bias_track(rule, imu) * dt[:, None], dv_b=imu.dv_b)


def with_mode(rule: BiasRule, mode: str) -> BiasRule:
    """``rule`` with another mode, or another of :data:`CHOICES` (its mode and its prior)."""
    if mode.endswith(MIXTURE):
        return replace(rule, mode=mode.removesuffix(MIXTURE), mixture=True)
    return replace(rule, mode=mode, mixture=False)


def applied(
    rule: BiasRule, readings: ImuRates | ImuIncrements, corrected: ImuRates | ImuIncrements
) -> ImuRates | ImuIncrements:
    """A whole recording's correction under ``rule``: ``corrected`` (the model's correction of
    ``readings``, in their form) less the rule's bias; under :data:`READINGS`, the gyro of ``readings``
    as read beside ``corrected``'s accelerometer."""
    if rule.mode != READINGS:
        return corrected_any(rule, corrected)
    if isinstance(readings, ImuIncrements) and isinstance(corrected, ImuIncrements):
        return ImuIncrements(t=corrected.t, dtheta_b=readings.dtheta_b, dv_b=corrected.dv_b)
    assert isinstance(readings, ImuRates) and isinstance(corrected, ImuRates)
    return ImuRates(t=corrected.t, omega_ib_b=readings.omega_ib_b, f_ib_b=corrected.f_ib_b)


def corrected_any(rule: BiasRule, readings: ImuRates | ImuIncrements) -> ImuRates | ImuIncrements:
    """Readings in either form with :func:`bias_track`'s bias taken away: rates through their steps'
    mean rates (a sample is corrected by the estimate of the steps before it; the first by the prior)."""
    if isinstance(readings, ImuIncrements):
        return corrected(rule, readings)
    dt = np.diff(readings.t)[:, None]
    steps = ImuIncrements(
        t=readings.t,
        dtheta_b=0.5 * (readings.omega_ib_b[:-1] + readings.omega_ib_b[1:]) * dt,
        dv_b=0.5 * (readings.f_ib_b[:-1] + readings.f_ib_b[1:]) * dt,
    )
    track = bias_track(rule, steps)
    per_sample = np.vstack([track[:1], track])
    return ImuRates(t=readings.t, omega_ib_b=readings.omega_ib_b - per_sample, f_ib_b=readings.f_ib_b)


def rule_from(
    biases: Array,
    streams: list[ImuIncrements],
    *,
    mode: str = "pooled",
    model_bias: Array | None = None,
    accel_biases: Array | None = None,
    held_back_deg: dict[str, float] | None = None,
    held_back_each_deg: dict[str, list[float]] | None = None,
) -> BiasRule:
    """A rule from training recordings: ``biases`` (r, 3) the bias each recording's ``streams`` (the
    model's corrected readings) still hold, fitted against its reference. The prior is their mean,
    less what of ``model_bias`` (the gyro bias the model takes away, rad/s, the training recordings'
    mean bias) they do not determine (:func:`shrunk`); the spread their standard deviation (at least
    :data:`MIN_SPREAD`); the rest offset the mean of bias less opening-rest rate over the recordings
    that open with a rest; with ``accel_biases`` (r, 3), each recording's own accelerometer bias (m/s²),
    the online estimate's prior on the accelerometer's bias is their spread's upper bound
    (:func:`accel_spread`); ``mode`` one of :data:`CHOICES` (or :data:`READINGS`)."""
    offsets, rates, ses, rested = [], [], [], []
    for b, s in zip(biases, streams, strict=True):
        rest, omega, dt = rest_of(s)
        if rest:
            offsets.append(b - omega[:rest].mean(axis=0))
            rates.append(omega[:rest].mean(axis=0))
            ses.append(_rest_se(omega[:rest], dt))
            rested.append(b)
    spread = np.maximum(biases.std(axis=0, ddof=1) if len(biases) > 1 else np.full(3, 1e-3), MIN_SPREAD)
    off = np.array(offsets) if offsets else np.zeros((1, 3))
    rest_spread = np.maximum(off.std(axis=0, ddof=1), MIN_SPREAD) if len(off) > 1 else spread
    prior = biases.mean(axis=0)
    if model_bias is not None and len(biases) > 1:
        prior = prior - shrunk(np.asarray(model_bias, dtype=float), spread, len(biases))
    rule = BiasRule(
        prior=prior, spread=spread, rest_offset=off.mean(axis=0),
        rest_spread=rest_spread, rest_rates=np.array(rates).reshape(-1, 3),
        rest_rates_se=np.array(ses).reshape(-1, 3), rest_biases=np.array(rested).reshape(-1, 3),
        held_back_deg=held_back_deg or {}, held_back_each_deg=held_back_each_deg or {},
    )  # fmt: skip
    if accel_biases is not None and len(accel_biases) > 1:
        rule = replace(rule, sigma_accel_mps2=accel_spread(accel_biases))
    if len(biases) >= MIXTURE_MIN:  # two recordings' spread is one difference
        rule = replace(rule, online_across=predictive_bound(len(biases)))
    if len(biases) >= MIXTURE_MIN:
        shifted = biases - biases.mean(axis=0) + prior
        rule = replace(rule, components=shifted, component_width=mixture_width(biases, spread))
    rule = with_mode(rule, mode)
    return replace(rule, nearest_spread=_nearest_spread(rule, spread), nearest_blend=True)


def _nearest_spread(rule: BiasRule, pooled: Array) -> Array:
    """What ``nearest``'s prior missed by on the training recordings with a rest, each predicted from the
    others (RMS per axis; a recording none of the others is near is predicted by the pooled prior, as a
    new one would be); the pooled spread where fewer than three have a rest."""
    if not rule.misses_measured:
        return pooled
    misses = []
    for i in range(len(rule.rest_rates)):
        near = nearest_prior(rule, rule.rest_rates[i], rule.rest_rates_se[i], leave_out=i)
        misses.append(rule.rest_biases[i] - (rule.prior if near is None else near))
    return np.asarray(np.maximum(np.sqrt(np.mean(np.square(misses), axis=0)), MIN_SPREAD), dtype=float)


def open_loop_deg(readings: ImuIncrements, rec: ReferencedRecording) -> float:
    """The absolute orientation error of ``readings`` (corrected increments on ``rec``'s steps)
    integrated alone from the reference's first attitude: RMS over every reference epoch on the steps'
    grid, deg. Earth's rate is left out (the rule is judged on recordings of a room frame and on those
    of a known one alike; over a few minutes it is below the figures that choose a mode)."""
    first = int(np.searchsorted(readings.t, rec.reference.t[0]))
    q = attitude.propagate_increments(readings.dtheta_b[first:], rec.reference.q_nb[0])
    at = np.clip(np.searchsorted(readings.t, rec.reference.t) - first, 0, len(q) - 1)
    total, _, _ = attitude.attitude_errors(q[at], rec.reference.q_nb)
    return float(np.degrees(np.sqrt(np.mean(total**2))))


__all__ = [
    "CHOICES",
    "FROM_REST",
    "MEASURED_RESTS",
    "MIN_REST_S",
    "MIXTURE",
    "MIXTURE_MIN",
    "MODES",
    "NEAREST_CHI2",
    "ONLINE_MODES",
    "READINGS",
    "REST_MAX_RATE_STEP",
    "REST_MAX_TILT_DEG",
    "REST_WINDOW_S",
    "BiasRule",
    "applied",
    "bias_track",
    "blended_nearest_prior",
    "corrected",
    "corrected_any",
    "nearest_prior",
    "open_loop_deg",
    "opening_rest",
    "prior_said",
    "rest_of",
    "rule_from",
    "with_mode",
]
