"""A still unit's biases: each channel's mean reading less Earth's rate and gravity, with a standard error
that counts the noise's colour; the attitude they imply; a warm-up trend.

At rest a gyro reads ``ω_b = C_bn Ω_n + b_g`` and an accelerometer ``f_b = C_bn (0, 0, −g) + b_a``, with
``Ω_n = Ω (cos φ, 0, −sin φ)`` (Earth's rate, 7.292115e-5 rad/s, at latitude ``φ``) and ``g`` normal
gravity at ``φ`` and the height. The bias is the mean reading less that expectation; the expectation needs
the attitude ``C_nb``:

* **given** (a levelled table facing a known heading, :func:`estimate_bias`'s ``attitude``), or a
  reference's (a dataset's per-sample Earth rate and gravity, a bag's odometry): every axis's bias
  follows. A per-sample reference is taken away row by row, so every rest counts, each against its own
  reference (:class:`Rest`: its own attitude and gravity, never their average over rests that face
  different ways); a recording without one is judged on its opening rest, whose one attitude the data
  level. An error ``δ`` in the given tilt moves the level accelerometers' biases by ``g δ`` (171 µg per
  0.01°), an error in the heading the level gyros' by ``Ω cos φ δ``;
* **levelled** from the data (:func:`sins.aiding.alignment.still_attitude`): roll and pitch from the mean
  specific force, the heading from the levelled mean rate (gyrocompassing) where the gyro resolves it.
  A still unit cannot tell a tilt from a level accelerometer bias, nor a heading error from an east gyro
  bias (:func:`sins.aiding.alignment.static_limits`): levelled, the accelerometers' bias is the part
  along gravity, ``|f| − g``, and the gyros' has no east part. The heading is *resolved* when the
  measured level rate lies within :data:`LEVEL_RATE_TOL` of ``Ω cos φ`` and the noise leaves it within
  :data:`~sins.aiding.alignment.GYROCOMPASS_MAX_SIGMA_RAD`; otherwise only the vertical part of Earth's
  rate is taken away and each gyro's bias carries up to ``Ω cos φ`` times its axis's level part
  (:attr:`ChannelBias.heading_bound`).

**Standard error.** The mean of ``n`` readings of white noise of deviation ``σ`` has ``σ/√n``; coloured
noise (a Gauss–Markov bias, flicker, a rate random walk) averages down more slowly. The error reported
is the larger of two figures. The batch-means standard error of what is averaged (the reading less its
row's expectation; :mod:`sins.characterise.mean_error`) needs no model. The Allan deviation of the
channel's fitted noise model (:mod:`sins.characterise`, the IEEE terms the data resolve) at the
averaging time ``T`` (the rows' span) sees correlations longer than a batch: for white noise
``N/√T = σ/√n`` exactly;
for a Gauss–Markov bias of correlation time ``T_c ≪ T`` it is ``√(2 σ_b² T_c / T)``, the standard error
of the mean of such a process; for flicker and a random walk, whose mean has no fixed value to converge
to, it is how far two such means ``T`` apart differ over ``√2``: the bias of this run, as repeatable as
the noise lets it be. A model whose fit misses part of the curve (quantization alone, beside a
vibration hump) can fall below what the data average to; the batch means do not. The white-noise figure,
the spread about each rest's own mean over ``√n``, is reported beside it (:attr:`ChannelBias.sigma_white`).

**Warm-up.** The rate's least-squares line over the rows (:func:`sins.characterise.trend.fit_ramp`),
judged against the slow noise the Allan curve allows: *significant* at 3σ. The bias reported is the mean,
the bias at the rows' middle; a warm-up that settles exponentially shows as a significant line.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.aiding import alignment, ekf
from sins.characterise.analysis import ChannelResult, characterise, residual
from sins.characterise.mean_error import batch_means_sigma, pooled_rests_sigma, white_sigma
from sins.characterise.rests import EARTH_RATE_TOL, check_rest_rows, earth_rate_rows, first_rows, rest_groups
from sins.characterise.still import motion, still_rows
from sins.core import earth, rotation
from sins.core.series import CalibrationData
from sins.errors import MissingInputError, SinsInputError
from sins.imu import CHANNELS, DEG_PER_H, UG
from sins.io.inspection import GRAVITY_OFF
from sins.io.recording import Recording

Array = NDArray[np.float64]

#: The heading is gyrocompassed only where the measured level rate lies within this fraction of Earth's
#: level rate ``Ω cos φ`` (a gyro bias a fifth of it, 2 °/h at 45°, already turns the heading by ~11°
#: if it points east).
LEVEL_RATE_TOL = 0.2
#: Latitudes beyond this, rad, have too little level Earth rate to gyrocompass on (cos 89° = 0.017).
MAX_GYROCOMPASS_LAT = math.radians(89.0)
#: The rows used are drawn as the means of this many blocks at most.
BLOCKS = 200
#: The display units: °/h for gyros, µg for accelerometers.
DISPLAY = {"gyro": (DEG_PER_H, "°/h"), "accel": (UG, "µg")}


@dataclass(frozen=True)
class ChannelBias:
    """One channel at rest, SI units (rad/s or m/s²).

    Attributes
    ----------
    channel : ``gyro.x`` … ``accel.z``
    mean : the reading's mean over the rows used
    expected : Earth's rate or gravity on this axis in the attitude used (what is taken away)
    bias : ``mean − expected``
    sigma : its standard error: the larger of the fitted noise model's Allan deviation at the averaging
        time and the batch-means standard error (see the module's text)
    sigma_white : what white noise alone would give, the standard deviation of the reading less its
        expectation about each rest's own mean, over ``√n``
    heading_bound : a gyro's part of Earth's level rate an unknown heading may leave in ``bias`` (its
        axis's level part times ``Ω cos φ``); 0 where the heading is known
    trend : the rate's fitted slope, per s
    trend_sigma : its standard error under the noise model
    trend_significant : ``|trend|`` at least 3 standard errors of the slowest noise the curve allows
    """

    channel: str
    mean: float
    expected: float
    bias: float
    sigma: float
    sigma_white: float
    heading_bound: float
    trend: float
    trend_sigma: float
    trend_significant: bool

    @property
    def sensor(self) -> str:
        """``gyro`` or ``accel``."""
        return self.channel.split(".")[0]

    def to_dict(self) -> dict[str, Any]:
        """The SI figures, and the bias and its error in the display unit."""
        size, unit = DISPLAY[self.sensor]
        out: dict[str, Any] = {k: v for k, v in self.__dict__.items() if k != "channel"}
        out |= {"unit": unit, "bias_display": self.bias / size, "sigma_display": self.sigma / size}
        return out


@dataclass(frozen=True)
class RestAttitude:
    """The attitude the biases are taken in.

    Attributes
    ----------
    roll, pitch : rad
    yaw : rad, or None where the heading is neither given nor resolved
    source : ``"given"``, ``"reference"`` (a dataset's Earth rate and gravity, a recording's trajectory)
        or ``"levelled"`` (roll and pitch from gravity, the heading gyrocompassed where resolved)
    tilt_sigma, yaw_sigma : levelled: the 1σ the readings' noise leaves in roll and pitch, and in a
        resolved heading (the standard errors over ``g`` and ``Ω cos φ``), rad; else 0 (None: no heading)
    level_rate_ratio : the measured level rate over ``Ω cos φ`` (levelled; 1 for a gyro without bias)
    heading_note : why the heading is not resolved, in words ("" where it is)
    """

    roll: float
    pitch: float
    yaw: float | None
    source: str
    tilt_sigma: float = 0.0
    yaw_sigma: float | None = 0.0
    level_rate_ratio: float = float("nan")
    heading_note: str = ""

    @property
    def C_nb(self) -> Array:
        """The direction cosine matrix (heading 0 where it is not known)."""
        return rotation.dcm_from_euler(self.roll, self.pitch, self.yaw or 0.0)


@dataclass(frozen=True)
class Rest:
    """One rest of a recording taken against a per-row reference: consecutive still rows whose reference
    specific force keeps its direction (:func:`sins.characterise.rests.rest_groups`: a Ferraris hold, a
    BROAD break).

    Attributes
    ----------
    start_s, end_s, rows : its rows' first and last times, s, and how many
    attitude : the roll and pitch its reference's mean specific force implies, source ``"reference"``;
        the heading only where the reference's rate is Earth's on every row (a static rig's), else None
    gravity : the size of its reference's mean specific force, m/s² (the gravity taken away there)
    rate : the size of its reference's mean rate, rad/s (Earth's, where the reference holds it; 0 where it
        leaves it out; a trajectory's residual motion else)
    """

    start_s: float
    end_s: float
    rows: int
    attitude: RestAttitude
    gravity: float
    rate: float

    def to_dict(self) -> dict[str, Any]:
        """The JSON entry: SI units, angles in degrees."""
        a = self.attitude
        return {
            "start_s": self.start_s, "end_s": self.end_s, "rows": self.rows,
            "roll_deg": math.degrees(a.roll), "pitch_deg": math.degrees(a.pitch),
            "yaw_deg": None if a.yaw is None else math.degrees(a.yaw), "heading_note": a.heading_note,
            "gravity_mps2": self.gravity, "rate_radps": self.rate,
        }  # fmt: skip


@dataclass(frozen=True)
class BiasEstimate:
    """A still unit's biases (see the module's text).

    Attributes
    ----------
    source : the recording or dataset
    start_s, end_s : the rows used, s
    rows : how many
    rate_hz : the sampling rate
    lat, h : where Earth's rate and gravity were taken, rad and m
    location : where those came from, in words
    attitude : the attitude they were taken in
    channels : ``gyro.x`` … ``accel.z`` → :class:`ChannelBias`
    notes : what was done, one line each
    rests : against a per-row reference, each rest's own attitude and gravity (:class:`Rest`); then
        ``attitude`` is the one rest's, or NaN where rests in several attitudes are pooled
    block_t, block_bias : the rows used in up to :data:`BLOCKS` blocks: each block's middle time (k,) s
        and mean reading less what was taken away (k, 6), for a picture of the rest (not in the JSON)
    """

    source: str
    start_s: float
    end_s: float
    rows: int
    rate_hz: float
    lat: float
    h: float
    location: str
    attitude: RestAttitude
    channels: dict[str, ChannelBias] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    rests: tuple[Rest, ...] = ()
    block_t: Array = field(default_factory=lambda: np.zeros(0))
    block_bias: Array = field(default_factory=lambda: np.zeros((0, 6)))

    @property
    def seconds(self) -> float:
        """The span averaged, s."""
        return self.rows / self.rate_hz

    def vector(self, sensor: str, what: str = "bias") -> Array:
        """``bias`` (or ``sigma``, ``mean`` …) of the three axes of ``sensor`` (3,), SI."""
        return np.array([getattr(self.channels[f"{sensor}.{a}"], what) for a in "xyz"])

    @property
    def gravity(self) -> float:
        """The gravity taken away, m/s²: its size in the attitude used, or against a reference the rests'
        own sizes averaged by rows (the mean of vectors of rests facing different ways is no gravity:
        Ferraris's six holds averaged to 0.51 m/s²)."""
        if self.rests:
            return self.rest_figure("gravity")
        return float(np.linalg.norm(self.vector("accel", "expected")))

    def rate_is_earths(self) -> bool:
        """Whether the rests' reference rate is Earth's (:data:`sins.characterise.rests.EARTH_RATE_TOL`)."""
        return abs(self.rest_figure("rate") / earth.OMEGA_IE - 1.0) <= EARTH_RATE_TOL

    def rest_figure(self, name: str) -> float:
        """A :class:`Rest` figure (``gravity``, ``rate``) averaged over the rests by their rows."""
        return float(sum(getattr(r, name) * r.rows for r in self.rests) / sum(r.rows for r in self.rests))

    def to_dict(self) -> dict[str, Any]:
        """The JSON document: SI units (rad, rad/s, m/s², s), each channel also in °/h or µg."""
        a = self.attitude
        return {
            "format": "sins-bias",
            "source": self.source,
            "start_s": self.start_s,
            "end_s": self.end_s,
            "rows": self.rows,
            "rate_hz": self.rate_hz,
            "lat_deg": math.degrees(self.lat) if math.isfinite(self.lat) else None,
            "h_m": self.h if math.isfinite(self.h) else None,
            "location": self.location,
            # Against a reference, its rate at rest is Earth's only where it says so (EuRoC's 69.9 °/h is
            # its trajectory's own motion): that figure apart, Earth's rate null where it is not.
            "earth_rate_radps": earth.OMEGA_IE if not self.rests or self.rate_is_earths() else None,
            "reference_rate_radps": self.rest_figure("rate") if self.rests else None,
            "gravity_mps2": self.gravity,
            "attitude": {
                "roll_deg": math.degrees(a.roll), "pitch_deg": math.degrees(a.pitch),
                "yaw_deg": None if a.yaw is None else math.degrees(a.yaw), "source": a.source,
                "tilt_sigma_deg": math.degrees(a.tilt_sigma),
                "yaw_sigma_deg": None if a.yaw_sigma is None else math.degrees(a.yaw_sigma),
                "level_rate_ratio": a.level_rate_ratio, "heading_note": a.heading_note,
            },
            "channels": {ch: c.to_dict() for ch, c in self.channels.items()},
            "rests": [r.to_dict() for r in self.rests],
            "notes": list(self.notes),
        }  # fmt: skip


def _expected(C_nb: Array, lat: float, h: float, heading_known: bool) -> tuple[Array, Array, Array]:
    """Earth's rate and gravity in the body axes (3,) each, and each gyro's heading bound (3,): without
    the heading, the vertical part of Earth's rate alone, and the level part's size on each axis."""
    omega_n = np.array(earth.earth_rate_n(lat), dtype=float)
    g_n = np.array([0.0, 0.0, -float(earth.normal_gravity(lat, h))])
    if heading_known:
        return C_nb.T @ omega_n, C_nb.T @ g_n, np.zeros(3)
    vertical = np.array([0.0, 0.0, omega_n[2]])
    level_part = np.hypot(C_nb[0], C_nb[1])  # each body axis's level length (columns of C_nb)
    return C_nb.T @ vertical, C_nb.T @ g_n, earth.OMEGA_IE * math.cos(lat) * level_part


def _levelled(mean: Array, sigma: Array, lat: float) -> RestAttitude:
    """Roll and pitch from gravity, the heading by gyrocompassing where the gyro resolves it."""
    roll, pitch, yaw = alignment.still_attitude(mean[3:], mean[:3])
    g = float(np.linalg.norm(mean[3:]))
    tilt = float(np.max(sigma[3:])) / g
    level = rotation.dcm_from_euler(roll, pitch, 0.0) @ mean[:3]
    level_rate = earth.OMEGA_IE * math.cos(lat)
    ratio = float(np.hypot(level[0], level[1])) / level_rate if level_rate > 0 else math.inf
    yaw_sigma = float(np.max(sigma[:3])) / level_rate + abs(math.tan(lat)) * tilt
    note = ""
    if abs(lat) > MAX_GYROCOMPASS_LAT:
        note = f"at {math.degrees(lat):.3g}° the level Earth rate is too small to gyrocompass on"
    elif abs(ratio - 1.0) > LEVEL_RATE_TOL:
        excess = abs(ratio - 1.0) * level_rate / DEG_PER_H
        note = (
            f"the level rate is {ratio:.3g} × Earth's level rate Ω cos φ ({level_rate / DEG_PER_H:.3g} °/h): "
            f"a gyro bias of at least {excess:.3g} °/h, which a still unit cannot tell from its heading"
        )
    elif yaw_sigma > alignment.GYROCOMPASS_MAX_SIGMA_RAD:
        note = (
            f"the gyro noise over the rows leaves the heading 1σ {math.degrees(yaw_sigma):.3g}° (more than "
            f"{math.degrees(alignment.GYROCOMPASS_MAX_SIGMA_RAD):g}°)"
        )
    if note:
        return RestAttitude(roll, pitch, None, "levelled", tilt, None, ratio, note)
    return RestAttitude(roll, pitch, yaw, "levelled", tilt, yaw_sigma, ratio)


def _from_reference(reference: Array) -> RestAttitude:
    """The attitude a rest's reference rows (k, 6) imply: roll and pitch from their mean specific force;
    the heading from their mean rate where it is Earth's on every row (gyrocompassing the reference)."""
    mean = reference.mean(axis=0)
    roll, pitch, yaw = alignment.still_attitude(mean[3:], mean[:3])
    if earth_rate_rows(reference).all():
        return RestAttitude(roll, pitch, yaw, "reference")
    rate = float(np.linalg.norm(mean[:3])) / DEG_PER_H
    note = (
        f"the reference's rate at rest, {rate:.3g} °/h, is not Earth's ({earth.OMEGA_IE / DEG_PER_H:.4g} °/h)"
    )
    return RestAttitude(roll, pitch, None, "reference", yaw_sigma=None, heading_note=note)


def _rests(t: Array, reference: Array, groups: list[list[tuple[int, int]]]) -> tuple[Rest, ...]:
    """The rests (see :class:`Rest`) of a per-row ``reference`` (n, 6), each of its ``groups`` of still
    row ranges (:func:`sins.characterise.rests.rest_groups`)."""
    out = []
    for group in groups:
        ref = np.concatenate([reference[a:b] for a, b in group])
        mean = ref.mean(axis=0)
        out.append(Rest(float(t[group[0][0]]), float(t[group[-1][1] - 1]), len(ref), _from_reference(ref),
                        float(np.linalg.norm(mean[3:])), float(np.linalg.norm(mean[:3]))))  # fmt: skip
    return tuple(out)


def _standard_errors(
    result: dict[str, ChannelResult], seconds: float, t: Array, averaged: Array,
    segments: tuple[tuple[int, int], ...],
) -> Array:  # fmt: skip
    """Each channel's (6,) standard error of its mean over ``seconds``: the larger of its noise model's
    Allan deviation there and the batch-means standard error of what is averaged at times ``t``
    (:func:`sins.characterise.mean_error.batch_means_sigma`), a resolved ramp left out of both (it is the
    trend, reported apart: a 5 mg warm-up had put 27 µg into the batch means' figure where the noise
    gave 0.4). The batch means need no model: a model fitted as quantization alone falls as 1/τ, and on
    EuRoC's MH_01 accelerometers, whose Allan curve rises over 5-40 ms (a vibration hump), it had said
    8.57 µg where the batch means say 48.6."""
    tau = np.array([seconds])
    model = np.array([math.sqrt(max(float(result[ch].fit.avar(tau)[0]), 0.0)) for ch in CHANNELS])
    slopes = np.array([r.ramp.value if r.ramp is not None and r.ramp.resolved else 0.0
                       for r in (result[ch] for ch in CHANNELS)])  # fmt: skip
    detrended = averaged - np.outer(np.asarray(t, dtype=float) - float(t[0]), slopes)
    return np.asarray(np.fmax(model, batch_means_sigma(detrended, segments)), dtype=float)


def _channels(result: dict[str, ChannelResult], mean: Array, sigma: Array, white: Array, expected: Array,
              bound: Array) -> dict[str, ChannelBias]:  # fmt: skip
    """Each channel's bias, its standard error and its trend."""
    out = {}
    for i, ch in enumerate(CHANNELS):
        ramp = result[ch].ramp
        assert ramp is not None  # characterise_channel always fits one
        out[ch] = ChannelBias(
            ch, float(mean[i]), float(expected[i]), float(mean[i] - expected[i]), float(sigma[i]),
            float(white[i]), float(bound[i]), ramp.value, ramp.sigma, ramp.resolved,
        )  # fmt: skip
    return out


def _check_gravity(force: Array, lat: float, h: float, source: str) -> None:
    """Refuse a rest whose mean specific force (rows, 3; m/s²) lies beyond ``sins inspect``'s bound
    (:data:`sins.io.inspection.GRAVITY_OFF`) from normal gravity, where no bias or scale error explains
    it but a unit mistaken does: readings in g
    read as m/s² had given an accelerometer bias of 0.9 g and an alignment that fell 1.9e6 m."""
    rho = float(np.linalg.norm(force.mean(axis=0))) / float(earth.normal_gravity(lat, h))
    if abs(rho - 1.0) > GRAVITY_OFF:
        raise SinsInputError(
            f"{source}: at rest the specific force is {rho:.4g} × gravity, beyond any accelerometer's bias "
            "or scale error: check its unit (sins inspect names it)"
        )


def estimate_bias(
    t: Array,
    readings: Array,
    lat: float,
    h: float = 0.0,
    *,
    attitude: tuple[float, float, float] | None = None,
    attitude_source: str = "given",
    reference: Array | None = None,
    keep: NDArray[np.bool_] | None = None,
    source: str = "",
    location: str = "given",
    progress: Callable[[int, int], None] | None = None,
) -> BiasEstimate:
    """The biases of a still unit (see the module's text).

    Parameters
    ----------
    t : (n,) s
    readings : (n, 6) gyro and accelerometer rates, rad/s and m/s², FRD
    lat, h : where it stood, rad and m
    attitude : ``(roll, pitch, yaw)`` rad where it is known (``attitude_source`` says how: "given",
        "reference"); None: levelled from the data
    reference : (n, 6) Earth's rate and gravity in the body axes per row (a dataset's reference), taken
        away row by row instead; the rests are pooled, each against its own reference, and each rest's
        attitude is what its reference implies (:class:`Rest`)
    keep : (n,) the rows to use (default all)
    source, location : for messages and the report
    progress : ``progress(channels_done, 6)`` while the noise is fitted

    Raises
    ------
    SinsInputError
        too few rows for the noise fit (one line naming ``source``), a channel without noise.
    """
    check_rest_rows(t, readings, reference, keep, source)
    if reference is None:
        _check_gravity(
            np.asarray(readings, dtype=float)[keep if keep is not None else slice(None), 3:], lat, h, source
        )
    res = residual(t, readings, None, source, keep)
    rows = np.zeros(len(t), dtype=bool)
    for a, b in res.segments:
        rows[a:b] = True
    readings = np.asarray(readings, dtype=float)
    ref = None if reference is None else np.asarray(reference, dtype=float)
    # What is averaged: each row less its own expectation (a constant one without a reference, added back
    # below); each rest is taken about its own mean, so rests in other attitudes are not noise.
    averaged = readings if ref is None else readings - ref
    mean, n = readings[rows].mean(axis=0), int(rows.sum())
    white = white_sigma(averaged, res.segments)
    result = characterise(res, progress=progress).channels
    sigma = _standard_errors(result, n * res.dt, t, averaged, res.segments)
    rests: tuple[Rest, ...] = ()
    if ref is not None:
        expected, bound = ref[rows].mean(axis=0), np.zeros(6)
        groups = rest_groups(np.asarray(t, dtype=float), ref, res.segments)
        rests = _rests(np.asarray(t, dtype=float), ref, groups)
        if len(groups) > 1:  # rests that disagree beyond their noise count (mean_error.pooled_rests_sigma)
            sigma = np.fmax(sigma, pooled_rests_sigma(averaged, groups))
        nan = math.nan  # rests in several attitudes pooled: no one attitude (each rest's in rests)
        att = (
            rests[0].attitude
            if len(rests) == 1
            else RestAttitude(nan, nan, None, "reference", yaw_sigma=None)
        )
    else:
        att = _levelled(mean, sigma, lat)
        if attitude is not None:
            att = RestAttitude(*attitude, attitude_source, level_rate_ratio=att.level_rate_ratio)
        gyro, accel, gyro_bound = _expected(att.C_nb, lat, h, att.yaw is not None)
        expected, bound = np.r_[gyro, accel], np.r_[gyro_bound, np.zeros(3)]
        averaged = readings - expected
    idx = np.flatnonzero(rows)
    block_t, block_bias = _blocks(np.asarray(t, dtype=float)[rows], averaged[rows])
    return BiasEstimate(
        source, float(t[idx[0]]), float(t[idx[-1]]), n, 1.0 / res.dt, lat, h, location, att,
        _channels(result, mean, sigma, white, expected, bound), tuple(res.notes) + tuple(res.warnings),
        rests, block_t, block_bias,
    )  # fmt: skip


def _blocks(t: Array, values: Array) -> tuple[Array, Array]:
    """The means of up to :data:`BLOCKS` consecutive blocks of rows: times (k,) and values (k, 6)."""
    size = max(1, len(t) // BLOCKS)
    k = len(t) // size
    cut = k * size
    return t[:cut].reshape(k, size).mean(axis=1), values[:cut].reshape(k, size, 6).mean(axis=1)


def in_attitude(
    estimate: BiasEstimate, attitude: tuple[float, float, float], source: str = "given"
) -> BiasEstimate:
    """``estimate``'s biases taken again in another attitude (roll, pitch, yaw rad): Earth's rate and
    gravity in it taken from the same means (no refit: the errors and trends stay)."""
    att = RestAttitude(*attitude, source, level_rate_ratio=estimate.attitude.level_rate_ratio)
    gyro, accel, _ = _expected(att.C_nb, estimate.lat, estimate.h, True)
    expected = np.r_[gyro, accel]
    old = np.array([estimate.channels[ch].expected for ch in CHANNELS])
    channels = {
        ch: replace(c, expected=float(expected[i]), bias=c.mean - float(expected[i]), heading_bound=0.0)
        for i, (ch, c) in enumerate(estimate.channels.items())
    }
    blocks = estimate.block_bias + old - expected
    return replace(estimate, attitude=att, channels=channels, block_bias=blocks)


def opening_rest(t: Array, readings: Array, source: str = "") -> tuple[NDArray[np.bool_], str]:
    """The rows a still unit's biases are taken from: every row where the recording does not move
    (:func:`sins.characterise.still.motion`), else its opening rest (the still rows from the first up to
    the first that is not, :func:`sins.characterise.still.still_rows`), and a note saying which.

    Raises
    ------
    SinsInputError
        a recording that moves from its start.
    """
    n = len(t)
    if motion(t, readings) is None:
        return np.ones(n, dtype=bool), ""
    dt = float(np.median(np.diff(t)))
    still = still_rows(readings, dt)
    # The opening rest: still_rows drops one window at either end of a run, so it starts a window late.
    first = int(np.argmax(still)) if still.any() else n
    stop = first + int(np.argmax(~still[first:])) if not still[first:].all() else n
    if first >= n or t[first] - t[0] > 1.0:
        raise SinsInputError(
            f"{source or 'recording'}: the unit moves from its start; the biases need it at rest "
            "(a still recording, or one that opens with a rest)"
        )
    keep = np.zeros(n, dtype=bool)
    keep[first:stop] = True
    note = f"the unit moves after {t[stop - 1] - t[0]:.4g} s: the biases are its opening rest's"
    return keep, note


def location_of(rec: Recording) -> tuple[float, float, str] | None:
    """``(lat, h, where)`` a recording says it lies at: its reference's or its fixes' mean, or None (a
    room frame placed at a nominal origin, EuRoC's or an ``.npz``'s, says no latitude: ``latitude_known``
    False; its 45° N had been reported as where the unit stood)."""
    if rec.truth is not None and rec.latitude_known:
        return float(np.mean(rec.truth.lat)), float(np.mean(rec.truth.h)), "the recording's reference"
    if rec.fixes is not None and len(rec.fixes.t):
        return float(np.mean(rec.fixes.lat)), float(np.mean(rec.fixes.h)), "the recording's fixes"
    return None


def recording_bias(
    rec: Recording,
    lat: float | None = None,
    h: float | None = None,
    attitude: tuple[float, float, float] | None = None,
    seconds: float | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> BiasEstimate:
    """:func:`estimate_bias` of a recording (any format sins reads) at rest: the whole of a still one,
    else its opening rest; ``seconds`` keeps the first that many.

    The latitude and height are the given ones, else the recording's (its reference's or its fixes'
    mean); the attitude the given one, else the reference's (a bag's odometry) at rest, else levelled.

    Raises
    ------
    SinsInputError
        no latitude given or read; a recording that moves from its start; too few rows.
    """
    t, omega, force = rec.mean_rates()
    readings = np.hstack([omega, force])
    if seconds is not None:
        within = first_rows(t, seconds, rec.source)
        t, readings = t[within], readings[within]
    keep, note = opening_rest(t, readings, rec.source)
    read = location_of(rec)
    where = "given"
    if lat is None:
        if read is None:
            raise MissingInputError(
                f"{rec.source}: no latitude (lat): the recording has no fixes or reference to read it from, "
                "and Earth's rate and gravity depend on it", needs="lat",
            )  # fmt: skip
        lat, where = read[0], read[2]
        h = read[1] if h is None else h
    how = "given"
    if attitude is None and rec.truth is not None:
        mid = float(np.mean(t[keep]))
        roll, pitch, yaw = rotation.euler_from_quat(rec.truth.interpolate(np.array([mid])).q_nb[0])
        attitude, how = (float(roll), float(pitch), float(yaw)), "reference"
    estimate = estimate_bias(
        t, readings, lat, 0.0 if h is None else h, attitude=attitude, attitude_source=how, keep=keep,
        source=rec.source, location=where, progress=progress,
    )  # fmt: skip
    return replace(estimate, notes=tuple(rec.notes) + ((note,) if note else ()) + estimate.notes)


def dataset_bias(
    data: CalibrationData,
    name: str,
    progress: Callable[[int, int], None] | None = None,
    *,
    location: tuple[float, float, str] | None = None,
    seconds: float | None = None,
) -> BiasEstimate:
    """:func:`estimate_bias` of a dataset against its own reference inputs, row by row, over the rows
    where the unit stood still (all of a still recording; every rest of one that moves, each against its
    own reference: Ferraris's holds, BROAD's breaks); ``seconds`` keeps the first that many.

    Where it stood: ``location`` (``(lat, h, where)``, a trajectory's, :func:`location_of`), else the
    latitude the reference's Earth rate implies (its vertical part is ``−Ω sin φ``) where the reference's
    rate is Earth's on every row used (:func:`sins.characterise.rests.earth_rate_rows`), else not known
    (NaN): a reference without Earth's rate (Ferraris's) implies none, and had read 0°, and EuRoC's, whose
    rate at rest is its trajectory's residual motion (56-175 °/h), −90°.

    Raises
    ------
    SinsInputError
        a dataset without a reference at rest, or without a rest long enough for the noise fit.
    """
    readings = np.hstack([data.gyro, data.accel])
    reference = np.hstack([data.ref_gyro, data.ref_accel])
    keep: NDArray[np.bool_] = np.asarray(np.isfinite(reference).all(axis=1))
    if seconds is not None:
        keep &= first_rows(data.t, seconds, name)
    if motion(data.t, readings) is not None:
        keep &= still_rows(readings, _step(data.t))
    if not keep.any():
        raise SinsInputError(f"{name}: no row at rest with a reference to take the biases against")
    h = math.nan
    if location is not None:
        lat, h, where = location
    elif earth_rate_rows(reference[keep]).all():
        ref = reference[keep]
        down = -ref[:, 3:] / np.linalg.norm(ref[:, 3:], axis=1, keepdims=True)
        vertical = np.clip(-np.sum(ref[:, :3] * down, axis=1) / earth.OMEGA_IE, -1.0, 1.0)
        lat, where = float(np.mean(np.arcsin(vertical))), "the latitude the reference's Earth rate implies"
    else:
        lat, where = math.nan, "not known: the reference's rate at rest is not Earth's"
    note = () if keep.all() else (f"the rows at rest: {int(keep.sum())} of {len(keep)}",)
    estimate = estimate_bias(data.t, readings, lat, h, reference=reference, keep=keep, source=name,
                             location=where, progress=progress)  # fmt: skip
    return replace(estimate, notes=note + estimate.notes)


def _step(t: Array) -> float:
    return float(np.median(np.diff(t)))


def alignment_accuracy(
    estimate: BiasEstimate, gyro_bias_sigma: float = 0.0, accel_bias_sigma: float = 0.0
) -> tuple[float, float]:
    """The 1σ of a coarse alignment on ``estimate``'s rows: tilt and heading, rad.

    :func:`sins.aiding.alignment.coarse_covariance` with the noise the estimate measured (each sensor's
    largest standard error at the averaging time, as a white noise of that much over the span) and the
    bias levels given (rad/s, m/s²; 1σ per axis, a unit's grade): tilt ``hypot(σ_ba, σ_f) / g``, heading
    ``hypot(σ_bg, σ_ω) / (Ω cos φ) + |tan φ|·tilt``. With the levels 0, the noise's part alone.
    """
    seconds = estimate.seconds
    arw = float(np.max(estimate.vector("gyro", "sigma"))) * math.sqrt(seconds)
    vrw = float(np.max(estimate.vector("accel", "sigma"))) * math.sqrt(seconds)
    config = ekf.FilterConfig(arw_rad_rt_s=arw, vrw_mps_rt_s=vrw, gyro_bias_sigma=gyro_bias_sigma,
                              accel_bias_sigma=accel_bias_sigma)  # fmt: skip
    P0 = alignment.coarse_covariance(config, estimate.lat, seconds, 0.0)
    return float(math.sqrt(P0[6, 6])), float(math.sqrt(P0[8, 8]))


__all__ = [
    "BLOCKS",
    "DISPLAY",
    "LEVEL_RATE_TOL",
    "MAX_GYROCOMPASS_LAT",
    "BiasEstimate",
    "ChannelBias",
    "Rest",
    "RestAttitude",
    "alignment_accuracy",
    "dataset_bias",
    "estimate_bias",
    "in_attitude",
    "location_of",
    "opening_rest",
    "recording_bias",
]
