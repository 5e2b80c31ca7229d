"""The noise terms written as an IMU file sins can simulate (``scenarios/imu/*.toml``).

The file has no grade: it is made of ``[[effect]]`` tables only, in the familiar units of
:func:`sins.imu.spec.parameters`, so ``sins run`` (a scenario's ``[imu] model``) and ``sins calibrate --imu``
read it as it is. Each term maps to one effect, per sensor and axis:

* ``N`` → ``noise`` (``arw_deg_per_rt_h``, ``vrw_ug_per_rt_hz``);
* the Gauss–Markov bias → ``bias_instability`` (``σ_b`` as ``sigma_dph`` / ``sigma_ug``, ``tau_s``);
* the IEEE bias instability ``B`` (flicker): sins has no flicker effect, so where no Gauss–Markov bias
  is resolved beside it the file has the Gauss–Markov bias of the same peak (``σ_b = 0.664 B / 0.617``)
  placed at the middle (geometric) of the cluster times the flicker floor holds (``T`` = that ``τ`` /
  1.89), with a comment: within 15 % of the floor's Allan variance an octave either side, 30 % at one and a
  half, 44 % at two, below it further out, where the closing check then shows the curves part; beside a
  resolved Gauss–Markov bias, a comment only;
* ``K`` → ``rate_random_walk`` (``rrw_dph_per_rt_h``, ``rrw_ug_per_rt_s``);
* ``Q`` → ``quantization_noise`` (``q_arcsec``, ``q_ug_s``: ``q = Q``) where the white noise per sample
  is below half a step of the quantizer that ``Q`` would mean (``N √dt < √12 Q / 2``, no white noise
  included), else ``quantization`` (``step_dps``, ``step_mg``).
  The term is white noise of the integrated output (Allan variance ``3Q²/τ²``), which
  ``quantization_noise`` simulates exactly (:class:`~sins.imu.QuantizationNoise`). ``quantization``
  rounds each increment to ``step · dt`` and carries the remainder, so the angle (velocity) error is
  uniform in a step, ``Q = step · dt / √12``: ``step = √12 Q / dt`` (in the rate form, which rounds
  each rate sample without a carry, that step is white noise instead); but the rounding errors are
  independent from sample to sample, as the term needs, only when the input moves by about half a step
  or more between samples (its white noise of ``N √dt`` per sample, at a standard deviation of half a
  step, leaves the remainder's law uniform to 1 %: ``exp(−π²/2)``). Below that, a unit at rest rounds
  to a deterministic sawtooth, whose Allan curve is not the term's, and the file has the noise
  instead; above it, the rounding is the
  unit's own (its readings on a lattice, as the gap diagnosis sees them);
* ``R`` has no effect in sins: the file names it in a comment, not simulated.

A term the recording does not resolve is written as zero, with its upper bound in a comment. The file
has no deterministic errors (bias, scale factor, misalignment): an Allan analysis cannot see them. Every
value is checked against the ranges the IMU file's readers accept (:func:`sins.imu.spec.parameters`)
before anything is written, and a file sins could not read back is refused in one line (a "unit" with
1e9 µg/√Hz of noise is a recording in other units, not an IMU). It is written under a temporary name and
renamed, so a failure leaves no half-written file.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from sins.characterise.analysis import DISPLAY, UNBOUNDED, Characterisation, display, duration
from sins.characterise.noise_terms import FLICKER_FACTOR, GM_PEAK, GM_PEAK_X
from sins.errors import SinsInputError
from sins.imu import CHANNELS, DEG, MG, UG, ImuModel, spec
from sins.io.atomic import atomic_text
from sins.io.paths import check_named

#: Per sensor, the effects written: (term, effect, parameter), the parameter in the file's unit.
EFFECTS = {
    "gyro": (
        ("white", "gyro.noise", "arw_deg_per_rt_h"),
        ("gauss_markov", "gyro.bias_instability", "sigma_dph"),
        ("rate_random_walk", "gyro.rate_random_walk", "rrw_dph_per_rt_h"),
        ("quantization", "gyro.quantization", "step_dps"),
        ("quantization_noise", "gyro.quantization_noise", "q_arcsec"),
    ),
    "accel": (
        ("white", "accel.noise", "vrw_ug_per_rt_hz"),
        ("gauss_markov", "accel.bias_instability", "sigma_ug"),
        ("rate_random_walk", "accel.rate_random_walk", "rrw_ug_per_rt_s"),
        ("quantization", "accel.quantization", "step_mg"),
        ("quantization_noise", "accel.quantization_noise", "q_ug_s"),
    ),
}
#: A bias instability's correlation time where the recording resolves none (its σ is then zero).
DEFAULT_TAU_S = 100.0


def rounding_is_dithered(result: Characterisation, channel: str) -> bool:
    """Whether a channel's white noise per sample reaches half the step of the quantizer its ``Q`` means
    (``N √dt ≥ √12 Q / 2``): then rounding with the remainder carried makes the term's independent
    errors, and the file writes ``quantization``; else ``quantization_noise`` (see the module's text)."""
    fit = result.channels[channel].fit
    q, n = fit.terms["quantization"].value, fit.terms["white"].value or 0.0
    return q is None or n * math.sqrt(result.dt) >= math.sqrt(12.0) * q / 2.0


def flicker_as_gauss_markov(result: Characterisation, channel: str) -> tuple[float, float] | None:
    """``(σ_b, T)`` of the Gauss–Markov bias the file simulates for a channel's resolved flicker ``B``
    (see the module's text), SI; None when the channel has no flicker or has its own Gauss–Markov bias."""
    r = result.channels[channel]
    flicker = r.fit.terms["flicker"]
    if flicker.value is None or r.fit.terms["gauss_markov"].resolved:
        return None
    taus = flicker.support_tau_s or tuple(float(t) for t in r.curve.tau_s)
    centre = math.sqrt(min(taus) * max(taus))
    return flicker.value * FLICKER_FACTOR / GM_PEAK, centre / GM_PEAK_X


def _gauss_markov(result: Characterisation, channel: str) -> tuple[float | None, float | None]:
    """The channel's simulated Gauss–Markov bias ``(σ_b, T)``: its own, or its flicker's (SI)."""
    r = result.channels[channel]
    if r.fit.terms["gauss_markov"].resolved:
        return r.fit.terms["gauss_markov"].value, r.fit.tau_c_s
    return flicker_as_gauss_markov(result, channel) or (None, None)


def _file_value(result: Characterisation, channel: str, term: str) -> float:
    """The term of one channel in the file's unit (zero when not resolved, or when the channel's ``Q``
    goes to the other of ``quantization`` and ``quantization_noise``)."""
    r = result.channels[channel]
    dithered = rounding_is_dithered(result, channel)
    if term == "quantization_noise":
        value = None if dithered else r.fit.terms["quantization"].value
        return 0.0 if value is None else value / DISPLAY[r.sensor]["quantization"][0]
    value = _gauss_markov(result, channel)[0] if term == "gauss_markov" else r.fit.terms[term].value
    if value is None or (term == "quantization" and not dithered):
        return 0.0
    if term == "quantization":
        step = math.sqrt(12.0) * value / result.dt  # rad/s or m/s²
        return step / (DEG if r.sensor == "gyro" else MG)
    if term == "white" and r.sensor == "gyro":
        return value / (DEG / 60.0)
    if r.sensor == "accel":
        return value / UG
    return value / DISPLAY["gyro"][term][0]


def _axes(values: list[float]) -> str:
    return "[" + ", ".join(f"{v:.6g}" for v in values) + "]"


def effect_tables(result: Characterisation) -> list[tuple[str, dict[str, list[float]]]]:
    """The file's ``[[effect]]`` tables: (effect name, parameters in the file's units, per axis).

    A sensor is written when all three of its axes were characterised; an effect when one of its axes
    has the term (``noise`` always, so the file is never empty).
    """
    tables = []
    for sensor, effects in EFFECTS.items():
        channels = [f"{sensor}.{a}" for a in "xyz"]
        if not all(ch in result.channels for ch in channels):
            continue
        for term, name, key in effects:
            values = [_file_value(result, ch, term) for ch in channels]
            if term != "white" and not any(values):
                continue
            params = {key: values}
            if term == "gauss_markov":
                params["tau_s"] = [_gauss_markov(result, ch)[1] or DEFAULT_TAU_S for ch in channels]
            tables.append((name, params))
    return tables


def imu_model(result: Characterisation) -> ImuModel:
    """The model the file describes, built from the same tables (as ``sins.scenario.load_imu`` reads it).

    Raises
    ------
    SinsInputError
        one line naming the recording, the effect and the value, when a term lies outside what an IMU
        file holds (:func:`sins.imu.spec.parameters`' ranges): the file would not be read back.
    """
    effects = []
    for name, params in effect_tables(result):
        try:
            effects.append(spec.effect_from_params(name, params))
        except ValueError as exc:
            raise SinsInputError(
                f"{result.source or 'recording'}: {exc}: no IMU has such noise, and sins would not read the "
                "file back (are the readings in rad/s and m/s², and the time in seconds?)"
            ) from None
    return ImuModel(tuple(effects))


def model_toml(result: Characterisation) -> str:
    """The IMU file's text for a characterisation (see the module's text)."""
    from sins import __version__

    lines = [
        f"# sins {__version__}: IMU noise model from `sins characterise` of {result.source}",
        f"# {result.rows} rows at {1.0 / result.dt:.6g} Hz, longest stretch {duration(result.length_s)}.",
        "# Noise only: an Allan analysis does not see biases, scale factors or misalignments.",
        "# Unresolved terms are zero here (their upper bounds in the comments).",
    ]
    for ch in CHANNELS:
        if ch not in result.channels:
            continue
        r = result.channels[ch]
        ramp = r.fit.terms["rate_ramp"]
        unit = DISPLAY[r.sensor]["rate_ramp"][1]
        if ramp.resolved:
            sigma = display(r.sensor, "rate_ramp", ramp.sigma)
            lines.append(
                f"# {ch}: rate ramp R = {display(r.sensor, 'rate_ramp', ramp.value)} ± {sigma} {unit}, "
                "not simulated (sins has no rate-ramp effect)"
            )
        lines += _flicker_comment(result, ch)
        if not rounding_is_dithered(result, ch):
            lines.append(
                f"# {ch}: Q as white noise of the integrated output (quantization_noise): its white noise"
                " per sample is below half the step Q means, and rounding a nearly constant input would"
                " make a sawtooth, not the IEEE term's independent errors"
            )
        for term in ("quantization", "white", "flicker", "gauss_markov", "rate_random_walk"):
            t = r.fit.terms[term]
            if not t.resolved and t.upper is not None:
                size, symbol = DISPLAY[r.sensor][term]
                lines.append(f"# {ch}: {term} not resolved, at most {t.upper / size:.4g} {symbol}")
            elif not t.resolved:
                lines.append(f"# {ch}: {term} not resolved, {UNBOUNDED}")
    for name, params in effect_tables(result):
        lines += ["", "[[effect]]", f'name = "{name}"']
        lines += [f"{key} = {_axes(values)}" for key, values in params.items()]
    return "\n".join(lines) + "\n"


def _flicker_comment(result: Characterisation, channel: str) -> list[str]:
    """The comment on a channel's flicker term: how the file simulates it, or that it does not."""
    r = result.channels[channel]
    flicker = r.fit.terms["flicker"]
    if flicker.value is None:
        return []
    b = f"{display(r.sensor, 'flicker', flicker.value)} {DISPLAY[r.sensor]['flicker'][1]}"
    approx = flicker_as_gauss_markov(result, channel)
    if approx is None:
        return [f"# {channel}: flicker B = {b}, not simulated (sins has no flicker effect, and the channel "
                "has its own Gauss-Markov bias)"]  # fmt: skip
    return [f"# {channel}: flicker B = {b}, simulated as the Gauss-Markov bias of the same Allan peak at "
            f"tau = {GM_PEAK_X * approx[1]:.4g} s (sins has no flicker effect)"]  # fmt: skip


def write_model(path: str | os.PathLike[str], result: Characterisation) -> Path:
    """Write the IMU file for ``result`` at ``path`` atomically (a temporary name in the same folder, then
    renamed); returns the path.

    Raises
    ------
    SinsInputError
        as :func:`imu_model`, before anything is written.
    """
    path = Path(path)
    check_named(path, "toml")
    imu_model(result)
    text = model_toml(result)
    with atomic_text(path) as fh:  # links followed, devices written in place (sins.io.atomic)
        fh.write(text)
    return path


__all__ = [
    "DEFAULT_TAU_S",
    "EFFECTS",
    "effect_tables",
    "flicker_as_gauss_markov",
    "imu_model",
    "model_toml",
    "rounding_is_dithered",
    "write_model",
]
