"""The reference's clock against the readings', for the diagnosis of a recording beside a reference
trajectory: what the reference limits includes where its clock sits.

A delay of the gyro's readings and a reference whose clock runs ahead by the same time are one and the
same to any diagnosis against that reference: the gyro's turns and the reference's are shifted against
each other either way. So ``gyro.time_offset`` found beside a reference is the sum of the sensor's delay
and the reference clock's lead, and this module says how much of it the reference's clock alone shows
(:func:`sins.io.frame_check.reference_lag`, from the turns of the attitude, not from the candidate
effects): where the two agree, the "delay" may be the reference's. Only the difference between the
accelerometer's delay and the gyro's is the sensor's alone. BROAD's two trials: the gyro's time offset
3.8 and 4.2 ms (the axes' mean), the capture system's clock 4.3 and 4.2 ms ahead.

So where both sensors are found late with one sign, the part they share is not named as either sensor's
effect (:func:`shared_delay`): the report takes it for the clock between the readings and the reference,
and names a sensor's offset only where it is later than the other's by more than the axes' spread
allows. The model fitted for the shrink keeps both. A sensor's own delay (its filters, its sampling) is
never negative, so the clock's part is at most the earlier sensor's: the shared part is that sensor's
offset, and the later one is named for the rest. BROAD's clean trials had both sensors named (the gyro
3.75 and 4.16 ms, the accelerometer 2.52 and 2.88 ms), so a delay added to either could not be named
beyond them; they now name the gyro's 1.2-1.3 ms beyond the accelerometer's.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from sins.core.series import ReferencedRecording
from sins.io import frame_check

#: A gyro time offset within this of the reference clock's lead (s) is said to be explainable by it:
#: the lag's own spread between BROAD's trials was 0.04 ms, the fitted offsets' across axes 1 ms.
AGREE_S = 0.001
#: How many standard errors of the axes' means a sensor's offset must be later than the other's for the
#: difference to be named as its own (:func:`shared_delay`).
APART_SE = 2.0
#: Why a delay is not named where a sensor's axes are late by delays of both signs (:func:`one_clock`).
BOTH_SIGNS = "its axes are late by delays of both signs, which one sensor's clock is not"


def one_clock(delays: Mapping[str, float]) -> bool:
    """Whether a sensor's delays per axis (channel → delay, any one unit) can be one clock's: all of one
    sign. One sensor's readings run on one clock, and a delay added to them is sized within a fifth on
    every axis (EuRoC's four bases with the accelerometer 5 and 10 ms late, per sample: 4.0-5.2 and
    9.9-10.7 ms, each found with thousands of nats); a reference whose velocity is differentiated from its
    positions had its accelerometer named per sample, x -1.43 ms and y +0.72 ms at 21 nats, and BROAD's
    trial 18 read from where it starts moving had its accelerometer's intervals take x -2.4, y +0.9,
    z +1.9 ms, which no sensor's clock is. The per-sample delays (:mod:`sins.unit_gap.delays`) and the
    intervals' (:mod:`sins.unit_gap.search`) both keep to it."""
    values = list(delays.values())
    return all(v > 0 for v in values) or all(v < 0 for v in values)


def reference_clock(
    rec: ReferencedRecording, sizes: dict[str, dict[str, list[float]]]
) -> dict[str, Any] | None:
    """How the reference's clock sits against the readings' (``lag_s``, positive where the reference
    lags; the correlations of the turns there and as stamped) and, where the diagnosis sized a
    ``gyro.time_offset`` (``sizes``, the report's, SI), whether that offset is within :data:`AGREE_S` of the
    clock's lead, and where it sized ``accel.time_offset``, that offset and its difference from the gyro's
    (``accel_less_gyro_s``); where it sized both with one sign, the delay they share
    (``shared_delay``, :func:`shared_delay`), which the report does not name as either sensor's;
    ``says``: one line for the report. None where the gyro turns too little to tell and no delay is
    shared."""
    lag = frame_check.recording_lag(rec)
    shared = shared_delay(sizes)
    if lag is None and shared is None:
        return None
    out: dict[str, Any] = {}
    said = []
    if lag is not None:
        out.update(lag_s=lag.lag_s, agreement=lag.agreement, as_stamped=lag.as_stamped)
        said.append(
            f"its clock sits {frame_check.clock_sits(lag.lag_s)} (its turns against the gyro's, "
            f"correlation {lag.agreement:.4f}; {lag.as_stamped:.4f} as stamped)"
        )
    offsets = {n: [v[0] for v in sizes.get(n, {}).values()] for n in DELAY_NAMES}
    if offsets["gyro.time_offset"]:
        out["gyro_time_offset_s"] = float(np.mean(offsets["gyro.time_offset"]))
    if offsets["accel.time_offset"]:
        out["accel_time_offset_s"] = float(np.mean(offsets["accel.time_offset"]))
    if len(out.keys() & {"gyro_time_offset_s", "accel_time_offset_s"}) == 2:
        # A reference's clock moves both sensors' offsets alike: their difference is the sensors'.
        out["accel_less_gyro_s"] = out["accel_time_offset_s"] - out["gyro_time_offset_s"]
    if lag is not None and "gyro_time_offset_s" in out:
        # A reference ahead by L shifts the gyro's turns as a delay of L does: offset ≈ -lag.
        out["explained_by_clock"] = bool(abs(out["gyro_time_offset_s"] + lag.lag_s) <= AGREE_S)
    if shared is not None:
        out["shared_delay"] = shared
        said.append(shared["says"])
    elif "gyro_time_offset_s" in out or "accel_time_offset_s" in out:
        said.append(_one_sensor_said(out))
    out["says"] = ": ".join(said)
    return out


def _one_sensor_said(out: dict[str, Any]) -> str:
    """The words for a sensor's time offset where no delay is shared (:func:`reference_clock`)."""
    if "gyro_time_offset_s" not in out:
        return f"the accelerometer's time offset {1e3 * out['accel_time_offset_s']:.2f} ms, the gyro's none"
    delay_ms = 1e3 * out["gyro_time_offset_s"]
    if "explained_by_clock" not in out:
        said = f"the gyro's time offset {delay_ms:.2f} ms"
    elif out["explained_by_clock"]:
        said = (
            f"the gyro's time offset ({delay_ms:.2f} ms) is that clock's, as far as these data tell (a delay "
            "of the sensor and a reference ahead look alike)"
        )
    else:
        said = (
            f"the gyro's time offset ({delay_ms:.2f} ms) is {delay_ms + 1e3 * out['lag_s']:+.2f} ms beyond "
            "that clock's, the sensor's own delay as far as these data tell"
        )
    if "accel_less_gyro_s" in out:  # no one shared delay (:func:`shared_delay`): each the sensor's
        said += (
            f"; the accelerometer's time offset {1e3 * out['accel_time_offset_s']:.2f} ms, "
            f"{1e3 * out['accel_less_gyro_s']:+.2f} ms from the gyro's: the sensors' own difference, which "
            "no reference's clock moves"
        )
    return said


def shared_delay(sizes: Mapping[str, Mapping[str, list[float]]]) -> dict[str, Any] | None:
    """The delay both sensors share, where the diagnosis sized both ``gyro.time_offset`` and
    ``accel.time_offset`` (``sizes``, the report's, SI) with one sign on every axis: ``shared_s`` (the
    earlier sensor's offset, the axes' mean), ``own_s`` (how much later the other sensor is),
    ``apart_se`` (that difference over its standard error, from each sensor's spread over its axes; with a
    single axis on either, the spread is taken as :data:`AGREE_S`), ``of_the_clock`` (the effects the
    report takes for the clock: the earlier sensor's, and the later one's too where the two are not
    :data:`APART_SE` apart) and ``says``. None where either is missing or the signs differ."""
    per_axis = {n: [v[0] for v in sizes.get(n, {}).values()] for n in DELAY_NAMES}
    if not all(per_axis.values()):
        return None
    means = {n: float(np.mean(v)) for n, v in per_axis.items()}
    if not one_clock({ch: v[0] for n in DELAY_NAMES for ch, v in sizes[n].items()}):
        return None
    earlier, later = sorted(DELAY_NAMES, key=lambda n: means[n])
    own = means[later] - means[earlier]
    se = float(np.sqrt(sum(_spread(v) ** 2 / len(v) for v in per_axis.values())))
    apart = own / se if se > 0 else float("inf") if own > 0 else 0.0
    clock_part = [earlier] if apart > APART_SE else [earlier, later]
    sensor, first = (_WORD[n.split(".")[0]] for n in (later, earlier))
    says = (
        f"both sensors {'late' if means[later] > 0 else 'early'}: the {first}'s offset "
        f"{1e3 * means[earlier]:.2f} ms, the {sensor}'s {1e3 * means[later]:.2f} ms: a delay both share "
        "is the clock's between the readings and the reference as far as these data tell (a sensor's "
        "delay and a reference ahead look alike), and is not named as either sensor's"
    )
    if apart > APART_SE:
        says += f"; the {sensor}'s {1e3 * own:.2f} ms beyond it ({apart:.1f} SE) is its own, named"
    else:
        says += (
            f"; the {sensor}'s {1e3 * own:.2f} ms beyond it is within {APART_SE:g} standard errors "
            f"({apart:.1f}): the clock's too"
        )
    return {
        "shared_s": means[earlier], "own_s": own, "apart_se": apart, "of_the_clock": clock_part,
        "says": says,
    }  # fmt: skip


def of_the_clock(statistic: Mapping[str, Any]) -> list[str]:
    """The time offsets a report (its ``statistic``) took for the reference's clock and did not name
    (:func:`shared_delay`, as :func:`reference_clock` holds it); none where it took none."""
    return list(statistic.get("reference_clock", {}).get("shared_delay", {}).get("of_the_clock", []))


def _spread(per_axis: list[float]) -> float:
    """A sensor's spread of its fitted delay over its axes (s): their standard deviation, or
    :data:`AGREE_S` where a single axis gives none."""
    return float(np.std(per_axis, ddof=1)) if len(per_axis) > 1 else AGREE_S


_WORD = {"gyro": "gyro", "accel": "accelerometer"}
#: The sensors' time offsets, in the order :func:`shared_delay` reads them.
DELAY_NAMES = ("gyro.time_offset", "accel.time_offset")

__all__ = [
    "AGREE_S",
    "APART_SE",
    "BOTH_SIGNS",
    "DELAY_NAMES",
    "of_the_clock",
    "one_clock",
    "reference_clock",
    "shared_delay",
]
