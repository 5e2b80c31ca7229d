"""A fitted model judged on a recording, as ``sins evaluate`` prints and writes it.

Two kinds of judgement, by the reference the recording has: against a rig's per-sample reference inputs,
channel by channel (:func:`evaluate_rig`: RMS before and after, the bias left, what is left beyond the
white noise); against a reference trajectory, by the attitude the corrected gyro holds open loop and,
over a window, the corrected unit's free-inertial drift (:func:`evaluate_referenced`). Each gives an
:class:`Evaluation`: the report's lines, the JSON document (:meth:`Evaluation.to_dict`) and what the
pictures are drawn from. Several recordings judged open loop by one model are summed up by
:func:`across` (each one's AOE and the mean: the published benchmarks' figure).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from sins.compensation import terms_left
from sins.core import rotation
from sins.core.text import fixed_width
from sins.errors import SinsInputError
from sins.io import frame_check
from sins.io.filled import spans_said
from sins.io.inspection import gaps_note
from sins.io.provenance import PART_SHARE

if TYPE_CHECKING:
    from sins.compensation.base import Strategy
    from sins.compensation.judging import OpenLoop
    from sins.core.series import CalibrationData, ImuIncrements, ImuRates, ReferencedRecording

#: The open-loop table's columns.
OPEN_LOOP_HEAD = ["readings", "total", "heading", "inclination", "AOE"]
#: The label of the raw readings' row.
RAW = "none (raw readings)"
#: The figures of a length's outages in ``sins evaluate --outage``'s document, m.
OUTAGE_FIGURES = ("rms_m", "median_m", "p95_m")
#: Said of a judgement on readings the model was fitted on (:func:`_fitted_here`).
FITTED_HERE = (
    "the model was fitted on these readings: the figures say how it fits its own data, not how it does on "
    "a recording it has not seen (judge it on another)"
)
#: Said of a judgement on a part of readings the model was fitted on (``{share}``: its share of them).
PART_FITTED_HERE = (
    "about {share:.0%} of these readings were in the model's fit (a part of a recording it was fitted on): "
    "the figures are not those of a recording it has not seen (judge it on another)"
)
#: What ``sins evaluate`` says of a model that leaves the gyro as read (its bias rule ``readings``).
GYRO_AS_READ = (
    "the model leaves the gyro as read (its fit found every bias rule worse than the raw readings on a "
    "held-back recording): its open loop is the raw one"
)

#: What ``sins evaluate`` and ``sins correct`` say where a learned part reads beyond its training inputs.
BEYOND_TRAINING = (
    "the learned correction reads beyond the inputs it was trained on at {n} readings ({share:.2g} %, the "
    "first {first_s:.1f} s in): there it goes on along its slope at their edge for a quarter of their "
    "range, and holds beyond"
)


def beyond_training(
    strategy: Strategy, readings: ImuRates | ImuIncrements, temp: NDArray[np.float64] | None = None
) -> tuple[dict[str, Any], str]:
    """Where a learned part of ``strategy`` reads beyond the inputs it was trained on
    (:meth:`Strategy.beyond_box`) over ``readings`` (rates, or increments as their mean rates; ``temp``
    at ``readings.t``): the count and share of such readings (the JSON's ``beyond_training_box``) and a
    line saying so ("" where none). A landing's 3.4 g lay beyond EuRoC's learners' box on all three
    accelerometer inputs."""
    from sins.core.series import ImuIncrements

    if isinstance(readings, ImuIncrements):
        t, omega_ib_b, f_ib_b = readings.mean_rates()
        temp = None if temp is None else 0.5 * (temp[:-1] + temp[1:])
    else:
        t, omega_ib_b, f_ib_b = readings.t, readings.omega_ib_b, readings.f_ib_b
    beyond = strategy.beyond_box(omega_ib_b, f_ib_b, temp)
    n = int(beyond.sum())
    document = {"readings": n, "share": n / max(len(beyond), 1)}
    if not n:
        return document, ""
    first_s = float(t[int(np.argmax(beyond))] - readings.t[0])
    return document, BEYOND_TRAINING.format(n=n, share=100.0 * n / len(beyond), first_s=first_s)


@dataclass(frozen=True)
class Evaluation:
    """One judgement: ``lines`` (the report), ``document`` (the JSON object, :meth:`to_dict`), and for
    the pictures ``channels`` (a rig's per-channel figures) or ``runs`` (each open loop by its label) with
    ``table`` (the open-loop table as text); ``scope`` what part of the recording was judged."""

    lines: list[str]
    document: dict[str, Any]
    channels: dict[str, dict[str, float]] | None = None
    runs: dict[str, OpenLoop] = field(default_factory=dict)
    table: str = ""
    scope: str = ""

    def to_dict(self) -> dict[str, Any]:
        """The figures as ``sins evaluate --json`` writes them (beside the model, strategy and recording)."""
        return self.document


def evaluate_rig(
    strategy: Strategy, data: CalibrationData, where: str, last: float | None = None
) -> Evaluation:
    """Per channel of a rig recording: RMS before and after, the bias left, and what is left beyond the
    white noise; over ``last`` of each phase (a fraction) or the whole recording.

    Raises
    ------
    SinsInputError
        naming ``where``: a ``last`` the phases cannot be split at.
    """
    from sins.compensation.base import residual_rms
    from sins.compensation.fitted_on import marks_of, readings_of
    from sins.imu import display_unit

    fitted_here, share = _in_fit(strategy, readings_of(data), marks_of(data))
    held_back = float((getattr(strategy, "fitted_on_", None) or {}).get("held_back") or 0.0)
    if fitted_here and last and held_back:
        # The last `last` of each phase, judged, and the last `held_back` of it, which the fit held back:
        # the rest was in the fit (--last 0.5 of a fit holding back 0.2: 60 %, where it read "fitted on
        # these readings" and a share of 1.0, the marks being the whole recording's).
        inside = max(0.0, last - held_back) / last
        fitted_here, share = False, (inside or None)
    if last:
        try:
            _, data = data.split(last)
        except ValueError as exc:
            raise SinsInputError(f"{where}: {exc}") from None
    channels = residual_rms(strategy, data)
    scope = f"the last {last:g} of each phase" if last else "the whole recording"
    rows = []
    for name, v in channels.items():
        size, unit = display_unit(name)
        rows.append([
            name, unit, f"{v['rms_before'] / size:.4f}", f"{v['rms_after'] / size:.4f}",
            f"{v['mean_after'] / size:+.4f}", f"{v['beyond_noise'] / size:.4f}",
        ])  # fmt: skip
    lines = [
        f"{where}, {scope}: reading - reference",
        fixed_width(["channel", "unit", "rms before", "rms after", "bias left", "beyond noise"], rows),
        "beyond noise: the RMS left after the white noise (from the residual's sample-to-sample changes)",
        *_fitted_lines(fitted_here, share),
    ]
    document = {"channels": channels, "fitted_on_this_recording": _fitted(fitted_here, share),
                "share_in_fit": share}  # fmt: skip
    return Evaluation(lines, document, channels=channels, scope=scope)


def evaluate_referenced(
    strategy: Strategy,
    rec: ReferencedRecording,
    where: str,
    *,
    last: float | None = None,
    bias_from_rest: bool = False,
    drive: tuple[float, float] | None = None,
    outage_s: tuple[float, ...] = (),
    stage: Callable[[str], None] | None = None,
) -> Evaluation:
    """The gyro integrated alone from the reference's first attitude (raw, corrected and, with
    ``bias_from_rest``, corrected less the opening rest's bias), RMS and AOE against the reference, over
    the ``last`` fraction or all; with ``drive`` (start, end s) the free-inertial drift over that window
    and with ``outage_s`` outages of each length (:mod:`sins.compensation.outages`), raw and corrected.
    ``stage(text)`` is told each step as it starts."""
    from sins.compensation import fitted_on, judging

    fitted_here, share = _in_fit(strategy, fitted_on.readings_of(rec), fitted_on.marks_of(rec))
    if last:
        span = rec.imu.t[-1] - rec.imu.t[0]
        rec = judging.between(rec, rec.imu.t[-1] - last * span, rec.imu.t[-1])
    rows, attitude, runs = [], {}, {}
    variants: list[tuple[str, Strategy | None, bool]] = [
        (RAW, None, False),
        (strategy.label, strategy, False),
    ]
    if bias_from_rest:
        variants.append((f"{strategy.label}, gyro bias from the opening rest", strategy, True))
    for label, s, rest in variants:
        if stage is not None:
            stage(f"open loop: {label}")
        runs[label] = judging.open_loop(s, rec, bias_from_rest=rest)
        r = runs[label].rmse()
        aoe = runs[label].aoe_deg()
        attitude[label] = {**r.to_dict(), "aoe_deg": aoe}
        rows.append(
            [label, f"{r.total_deg:.3f}", f"{r.heading_deg:.3f}", f"{r.inclination_deg:.3f}", f"{aoe:.3f}"]
        )
    judged = "the judged rows (movement phases)" if rec.judged is not None else "every reference epoch"
    lines = [
        f"{where}: the gyro integrated alone from the reference's first attitude, RMS error against "
        f"{rec.reference_name} over {judged}, degrees (AOE: over every epoch)"
    ]
    notes, clock, filled_s = _reference_notes(rec)
    lines += notes
    unit = (getattr(strategy, "fitted_on_", None) or {}).get("sensor")
    if unit and not rec.sensor:  # a unit's check needs the recording to name one (a path's may not)
        lines.append(f"the recording names no unit: it is judged as {unit}'s, the model's")
    lines += _fitted_lines(fitted_here, share)
    beyond, beyond_said = beyond_training(strategy, rec.imu)
    lines += [beyond_said] if beyond_said else []
    as_read = strategy.leaves_gyro_as_read()
    # The readings as the model corrects them (before its bias rule), once for what reads them below.
    model_corrected = rec.imu if as_read else strategy.correct_increments(rec.imu)
    if as_read:
        lines.append(GYRO_AS_READ)
    elif said := _prior_said(strategy, model_corrected):
        lines.append(said)
    if stage is not None:
        stage("the gyro terms the model leaves")
    left = terms_left.gyro_terms_left(model_corrected, rec)
    lines += [terms_left.said(left)] if left["terms"] else []
    table = fixed_width(OPEN_LOOP_HEAD, rows)
    lines.append(table)
    document: dict[str, Any] = {
        "open_loop_attitude": attitude[strategy.label],
        "open_loop_attitude_raw": attitude[RAW],
        "reference_clock_ms": None if clock is None else 1e3 * clock.lag_s,
        "reference_filled_s": [list(s) for s in filled_s],
        "fitted_on_this_recording": _fitted(fitted_here, share),
        "share_in_fit": share,
        "gyro_as_read": as_read,
        "beyond_training_box": beyond,
        "gyro_terms_left": left,
    }
    if bias_from_rest:
        document["open_loop_attitude_bias_from_rest"] = attitude[variants[-1][0]]
    document |= {"drive": _drive(strategy, rec, drive, lines, stage)} if drive is not None else {}
    document |= {"free_inertial_outages": _outages(strategy, rec, outage_s, lines, stage)} if outage_s else {}
    return Evaluation(lines, document, runs=runs, table=table)


def _prior_said(strategy: Strategy, corrected: ImuIncrements) -> str:
    """Where a model fitted on several recordings took this recording's gyro bias prior, in words
    (:func:`sins.compensation.unit_bias.prior_said`, on the readings as the model ``corrected`` them);
    "" for another model."""
    rule = getattr(strategy, "unit_bias_", None)
    if not isinstance(rule, dict):
        return ""
    from sins.compensation import unit_bias

    return unit_bias.prior_said(unit_bias.BiasRule.from_dict(rule), corrected)


def _reference_notes(
    rec: ReferencedRecording,
) -> tuple[list[str], frame_check.ReferenceLag | None, tuple[tuple[float, float], ...]]:
    """What ``sins evaluate`` says of the judged recording's reference: its frame's Earth rate, its clock
    against the readings' (``frame_check.recording_lag``), the readings' own gaps and the reference's
    spans filled by interpolation."""
    from sins.compensation import screening

    notes: list[str] = []
    if not rec.latitude_known:
        notes.append("the reference's frame has no known latitude or heading: Earth's rate is left out")
    elif not rec.heading_known:
        notes.append(
            "the reference's frame has no known north: only the vertical part of Earth's rate is put in"
        )
    clock = frame_check.recording_lag(rec)
    if clock is not None and abs(clock.lag_s) >= frame_check.REFERENCE_LAG_S:
        notes.append(
            f"the reference's clock sits {frame_check.clock_sits(clock.lag_s)} (its turns "
            "against the gyro's): every figure is judged against it as stamped, the rate times that "
            f"added to each error (add {-clock.lag_s:+.4f} s to its times to align them)"
        )
    if gaps := gaps_note(rec.imu.t):  # sins inspect's gaps, as sins integrate says them
        notes.append(gaps)
    if clipped := _clipped(rec):
        notes.append(clipped)
    filled_s = screening.filled(rec)
    if filled_s:
        notes.append(
            f"the reference holds {spans_said(filled_s)} filled by interpolation (sins.io.filled): every "
            "figure is judged against it as it is there too"
        )
    return notes, clock, filled_s


def _clipped(rec: ReferencedRecording) -> str:
    """The readings' channels stuck at their extremes (``sins inspect``'s clipping), in words ("" where
    none is): a clipped gyro's open loop is not the motion's, whatever the model."""
    found = frame_check.clipped_channels(rec.imu)
    if not found:
        return ""
    said = ", ".join(f"{c.channel} at {c.level:+.6g} on {c.samples} readings" for c in found)
    return f"the readings stick at their extremes ({said}): clipped at the sensor's range, not the motion"


def across(judged: dict[str, Evaluation], label: str) -> Evaluation:
    """Several recordings judged open loop by one model (``label``, as :func:`evaluate_referenced` names
    its row): each one's AOE, raw and corrected, and their means over the recordings, each recording
    weighing the same (as Brossard et al. 2020 average their judged sequences). The document holds every
    recording's own document and ``mean`` in their keys (``mean.open_loop_attitude.aoe_deg``)."""
    import numpy as np

    if not judged:
        raise ValueError("across: no recording judged")
    raw = [e.document["open_loop_attitude_raw"]["aoe_deg"] for e in judged.values()]
    corrected = [e.document["open_loop_attitude"]["aoe_deg"] for e in judged.values()]
    mean_raw, mean = float(np.mean(raw)), float(np.mean(corrected))
    rows = [[name, f"{r:.3f}", f"{c:.3f}"] for name, r, c in zip(judged, raw, corrected, strict=True)]
    table = fixed_width(
        ["recording", f"{RAW}: AOE", f"{label}: AOE"], [*rows, ["mean", f"{mean_raw:.3f}", f"{mean:.3f}"]]
    )
    lines = [f"\nacross {len(judged)} recordings: the gyro's open-loop AOE, degrees", table]
    fitted = [name for name, e in judged.items() if e.document.get("fitted_on_this_recording")]
    if fitted:
        lines.append(
            f"the model was fitted on {len(fitted)} of the {len(judged)} recordings judged "
            f"({', '.join(fitted)}): the mean is not a held-back figure"
        )
    worse = {n: c - r for n, r, c in zip(judged, raw, corrected, strict=True) if c > r}
    if worse:  # a mean better than raw had hidden them (a walk's unit: +0.35° on one of three)
        said = ", ".join(f"{n} (+{d:.3g}°)" for n, d in worse.items())
        lines.append(f"worse than the raw readings on {len(worse)} of the {len(judged)}: {said}")
    left = {n: e.document.get("gyro_terms_left", {}).get("terms", []) for n, e in judged.items()}
    if any(left.values()):  # each recording's own line said it; here, which of them, side by side
        said = "; ".join(f"{n} ({_terms_text(terms)})" for n, terms in left.items() if terms)
        lines.append(f"gyro terms the model leaves beyond a unit's spread: {said}")
    mean_outages = _outages_across(judged, label, lines)
    document = {
        "recordings": [{"recording": name, **e.to_dict()} for name, e in judged.items()],
        "mean": {
            "open_loop_attitude": {"aoe_deg": mean},
            "open_loop_attitude_raw": {"aoe_deg": mean_raw},
            **({"free_inertial_outages": mean_outages} if mean_outages else {}),
        },
        "fitted_on": fitted,
        "worse_than_raw": list(worse),
        "gyro_terms_left_on": [n for n, terms in left.items() if terms],
    }
    return Evaluation(lines, document, table=table)


def _outages_across(judged: dict[str, Evaluation], label: str, lines: list[str]) -> list[dict[str, Any]]:
    """Each outage length's RMS horizontal error, raw and corrected, per recording and their means over
    the recordings (each weighing the same); its table added to ``lines``. Nothing where none was asked."""
    per = [e.document.get("free_inertial_outages", []) for e in judged.values()]
    if not per[0]:
        return []
    out, rows = [], []
    for k, first in enumerate(per[0]):
        raw = [p[k]["raw"]["rms_m"] for p in per]
        fixed = [p[k]["corrected"]["rms_m"] for p in per]
        length = f"{first['length_s']:g}"
        rows += [[n, length, f"{r:.4f}", f"{c:.4f}"] for n, r, c in zip(judged, raw, fixed, strict=True)]
        rows.append(["mean", length, f"{np.mean(raw):.4f}", f"{np.mean(fixed):.4f}"])
        out.append({"length_s": first["length_s"], "raw": {"rms_m": float(np.mean(raw))},
                    "corrected": {"rms_m": float(np.mean(fixed))}})  # fmt: skip
    lines += ["\nfree-inertial outages: the RMS horizontal error at their ends, m",
              fixed_width(["recording", "outage s", f"{RAW}: RMS", f"{label}: RMS"], rows)]  # fmt: skip
    return out


def _terms_text(terms: list[dict[str, Any]]) -> str:
    """Gyro terms left (:func:`sins.compensation.terms_left.gyro_terms_left`'s), short."""
    return ", ".join(f"{t['name']} {t['value']:.3g} {t['unit']}" for t in terms)


def _in_fit(strategy: Strategy, digest: str, marks: list[str]) -> tuple[bool | None, float | None]:
    """Whether the model was fitted on the readings of ``digest`` (among ``fitted_on_["readings"]``; None
    where the model file does not say: one written before it did), and the share of their ``marks``
    among those of the readings it was fitted on (``fitted_on_["marks"]``; None where the file keeps
    none or the readings are too short to tell: :func:`sins.io.provenance.shared_share`; the first is then
    None too, where the readings are not the whole of one: it cannot be told)."""
    from sins.io.provenance import shared_share

    fitted = getattr(strategy, "fitted_on_", None) or {}
    said, held = fitted.get("readings"), fitted.get("marks")
    share = shared_share(marks, held) if isinstance(held, list) else None
    whole = digest in said if isinstance(said, list) else None
    if whole is False and isinstance(held, list) and share is None:
        whole = None  # too short for its marks to tell whether it is a part of a training recording
    return whole, share


def _fitted(whole: bool | None, share: float | None) -> bool | None:
    """Whether the judged readings were (all or in good part) in the model's fit."""
    return True if whole or (share is not None and share >= PART_SHARE) else whole


def _fitted_lines(whole: bool | None, share: float | None) -> list[str]:
    """What the report says of readings that were in the model's fit, whole or in part."""
    if whole:
        return [FITTED_HERE]
    if share is not None and share >= PART_SHARE:
        return [PART_FITTED_HERE.format(share=share)]
    return []


#: Beyond this reference pitch (degrees) a drive's roll and yaw errors are said to be ill-conditioned.
STEEP_PITCH_DEG = 60.0


def _drive(
    strategy: Strategy,
    rec: ReferencedRecording,
    window: tuple[float, float],
    lines: list[str],
    stage: Callable[[str], None] | None,
) -> dict[str, Any]:
    """The raw and corrected units' free-inertial drift over ``window``; its table added to ``lines``."""
    from sins.compensation import judging

    start, end = window
    out, rows = {}, []
    for label, s in ((RAW, None), (strategy.label, strategy)):
        if stage is not None:
            stage(f"free inertial: {label}")
        d = judging.drive_errors(s, rec, start, end)
        out[label] = d.to_dict()
        figures = [*d.attitude_rms_deg, d.attitude_angle_rms_deg, *d.velocity_rms_mps]
        rows.append([label, *(f"{x:.4f}" for x in figures), f"{d.horizontal_final_m:.3f}"])
    start, end = d.start_s, d.end_s  # the window as navigated: its end clipped to the reference's last epoch
    lines.append(
        f"\nfree inertial from the reference's state at {start:g} s to {end:g} s (vertical held), RMS errors"
    )
    head = ["readings", "roll °", "pitch °", "yaw °", "angle °", "vN m/s", "vE m/s", "vD m/s", "hor end m"]
    lines.append(fixed_width(head, rows))
    inside = (rec.reference.t >= start) & (rec.reference.t <= end)
    pitch = rotation.euler_from_quat(rec.reference.q_nb[inside])[1]
    steepest = float(np.degrees(np.max(np.abs(pitch)))) if pitch.size else 0.0
    if steepest > STEEP_PITCH_DEG:  # EuRoC's body x points up: its pitch lies near -90°
        lines.append(
            f"the reference pitches to {steepest:.0f}° here, where roll and yaw are ill-conditioned (their "
            "errors grow and cancel): the attitude error's angle is the figure to read"
        )
    return out


def _outages(
    strategy: Strategy,
    rec: ReferencedRecording,
    lengths_s: tuple[float, ...],
    lines: list[str],
    stage: Callable[[str], None] | None,
) -> list[dict[str, Any]]:
    """The raw and corrected readings' free-inertial outages of each length; their table added to
    ``lines``."""
    from sins.compensation import judging, outages

    streams = {RAW: rec.imu, strategy.label: judging.corrected(strategy, rec)}
    out, rows = [], []
    for length in lengths_s:
        figures = {}
        for label, imu in streams.items():
            if stage is not None:
                stage(f"outages of {length:g} s: {label}")
            figures[label] = outages.outages(imu, rec, length).summary()
        raw, fixed = figures[RAW], figures[strategy.label]
        out.append({"length_s": length, "outages": raw["outages"], "every_s": outages.EVERY_S,
                    "reference_mismatch_m": raw["reference_mismatch_m"],
                    "raw": {k: raw[k] for k in OUTAGE_FIGURES},
                    "corrected": {k: fixed[k] for k in OUTAGE_FIGURES}})  # fmt: skip
        rows.append([f"{length:g}", str(raw["outages"]), *(f"{f[k]:.4f}" for f in (raw, fixed)
                                                          for k in OUTAGE_FIGURES)])  # fmt: skip
    lines.append(
        f"\nfree-inertial outages from every {outages.EVERY_S:g} s of the reference (vertical held): the "
        "horizontal error at each outage's end, m"
    )
    head = ["outage s", "outages", "raw: RMS", "median", "95 %", f"{strategy.label}: RMS", "median", "95 %"]
    lines.append(fixed_width(head, rows))
    floor = ", ".join(f"{1e3 * o['reference_mismatch_m']:.1f} mm over {o['length_s']:g} s" for o in out)
    lines.append(f"the reference's positions and its velocities' integral differ by {floor} (RMS): errors "
                 "near that are the reference's as much as the unit's")  # fmt: skip
    return out


__all__ = [
    "BEYOND_TRAINING",
    "FITTED_HERE",
    "GYRO_AS_READ",
    "OPEN_LOOP_HEAD",
    "OUTAGE_FIGURES",
    "PART_FITTED_HERE",
    "RAW",
    "STEEP_PITCH_DEG",
    "Evaluation",
    "across",
    "beyond_training",
    "evaluate_referenced",
    "evaluate_rig",
]
