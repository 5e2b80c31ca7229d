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
    (``accel_less_gyro_s``); ``says``: one line for the report. None where the gyro turns too little to
    tell."""
    lag = frame_check.recording_lag(rec)
    if lag is None:
        return None
    says = (
        f"its clock sits {frame_check.clock_sits(lag.lag_s)} (its turns against the gyro's, "
        f"correlation {lag.agreement:.4f}; {lag.as_stamped:.4f} as stamped)"
    )
    out: dict[str, Any] = {"lag_s": lag.lag_s, "agreement": lag.agreement, "as_stamped": lag.as_stamped}
    offsets = [v[0] for v in sizes.get("gyro.time_offset", {}).values()]
    if offsets:
        delay = float(np.mean(offsets))
        # A reference ahead by L shifts the gyro's turns as a delay of L does: offset ≈ -lag.
        out["gyro_time_offset_s"] = delay
        out["explained_by_clock"] = bool(abs(delay + lag.lag_s) <= AGREE_S)
        if out["explained_by_clock"]:
            says += (
                f": the gyro's time offset ({1e3 * delay:.2f} ms) is that clock's, as far as these data "
                "tell (a delay of the sensor and a reference ahead look alike)"
            )
        else:
            says += (
                f": the gyro's time offset ({1e3 * delay:.2f} ms) is {1e3 * (delay + lag.lag_s):+.2f} ms "
                "beyond that clock's, the sensor's own delay as far as these data tell"
            )
    accel = [v[0] for v in sizes.get("accel.time_offset", {}).values()]
    if accel:  # a reference's clock moves both sensors' offsets alike: their difference is the sensors'
        out["accel_time_offset_s"] = float(np.mean(accel))
        says += f"; the accelerometer's time offset {1e3 * out['accel_time_offset_s']:.2f} ms"
        if offsets:
            out["accel_less_gyro_s"] = out["accel_time_offset_s"] - out["gyro_time_offset_s"]
            says += (
                f", {1e3 * out['accel_less_gyro_s']:+.2f} ms from the gyro's: the sensors' own difference, "
                "which no reference's clock moves"
            )
    out["says"] = says
    return out


__all__ = ["AGREE_S", "BOTH_SIGNS", "one_clock", "reference_clock"]
