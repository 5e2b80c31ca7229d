"""The one way sins reads an IMU recording: :func:`read`, by a path or a dataset's name, giving a
:class:`~sins.io.recording.Recording`.

A path's reader is picked by what the path is (:func:`sins.io.recording.recording_kind`): a folder with
``metadata.yaml`` (a ROS 2 bag), a ROS 1 bag or an MCAP file (by their first bytes), a EuRoC/TUM-VI
folder or ASL file, an ``.npz`` recording, a rig CSV (``ref_`` columns), else a CSV: sins's own IMU
forms or, with ``columns`` or ``units``, one with its own columns and units. A dataset's name is read
from the data root (:mod:`sins.io.datasets`). The format readers behind it are internal (their names
start with ``_``).
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from sins.core.earth import MAX_HEIGHT_M, MAX_LAT_DEG
from sins.core.series import NavSeries
from sins.errors import ArgumentError, LateStartError, SinsInputError
from sins.io import rig
from sins.io.datasets import _read_dataset
from sins.io.datasets.npz_folders import is_folder_name
from sins.io.formats import read_truth
from sins.io.recording import RATE_HZ_RANGE, Recording, _read_path, _rig_recording
from sins.io.tables import format_number


def read(
    source: str | os.PathLike[str] | None = None,
    *,
    dataset: str | None = None,
    truth: str | os.PathLike[str] | NavSeries | None = None,
    root: str | os.PathLike[str] | None = None,
    topic: str | None = None,
    columns: str | Mapping[str, str] | None = None,
    units: str | Mapping[str, str] | None = None,
    frame: str | None = None,
    rate_hz: float | None = None,
    truth_topic: str | None = None,
    origin: tuple[float, float, float] | None = None,
    t_start: float | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Recording:
    """Read an IMU recording: by its path (``source``) or a dataset's name (``dataset``), one of them.

    Parameters
    ----------
    source : a sins CSV (IMU or rig), a CSV with its own columns, an ``.npz``, a ROS 1 bag, a ROS 2 bag
        folder, an MCAP file, or a EuRoC/TUM-VI folder
    dataset : a dataset's name (:func:`sins.io.datasets.names`: ``ferraris``, ``broad_05``,
        ``euroc/V1_01_easy``), read from the data root (``root``, default :func:`sins.io.datasets.data_root`)
    truth : the reference trajectory beside the readings (a truth CSV, or a :class:`NavSeries`); it
        replaces a recording's own, and in increment form the first interval starts at its first time
        (unless ``t_start`` says otherwise)
    topic : a bag's IMU topic, where it has several ``sensor_msgs/Imu`` topics
    columns : a CSV's own columns, ``"t=time,gyro_x=wx,..."`` (:mod:`sins.io.columns`)
    units : the readings' units, ``"t=ms,gyro=deg/s,accel=g"`` (:mod:`sins.io.units`); for a bag or
        EuRoC (SI by their definitions) a unit rescales what they hold
    frame : the readings' axes (:mod:`sins.io.axes`); None: ``flu`` for bags (REP 103), ``frd`` otherwise
        (EuRoC's S taken as it is)
    rate_hz : the sampling rate, Hz (within :data:`~sins.io.recording.RATE_HZ_RANGE`): the times of a
        CSV without a time column; elsewhere the stated rate :func:`sins.io.inspection.inspect` checks the
        stamps against
    truth_topic : a bag's reference topic, where it has several
    origin : ``(lat, lon, h)`` in rad, rad, m, where a local reference frame starts (bags: default the
        first fix, else :data:`sins.io.local.NOMINAL_ORIGIN`; EuRoC, ``.npz`` and a ``FOLDER/NAME``
        dataset: default :data:`~sins.io.local.NOMINAL_ORIGIN`)
    t_start : increment form: where the first interval starts; None: the truth's first time where one
        is given, else the first row's time less the first step
    progress : ``progress(done, total)`` while a bag is read

    Raises
    ------
    SinsInputError
        one line naming the file (or dataset), and the line, column, key, topic or message where it
        applies; both or neither of ``source`` and ``dataset``; an option that does not apply (``columns``
        for a bag, ``topic`` for a CSV, ``truth`` beside a dataset or a rig recording).
    MissingInputError
        a bag with several IMU topics and no ``topic`` (``needs="topic"``), or a ``truth_topic`` the
        bag lacks (``needs="truth_topic"``).
    """
    if (source is None) == (dataset is None):
        raise SinsInputError("read: give a recording's path or a dataset's name (one of them)")
    _check_origin(origin)
    given = {"topic": topic, "columns": columns, "units": units, "frame": frame, "rate_hz": rate_hz,
             "truth_topic": truth_topic, "origin": origin, "t_start": t_start}  # fmt: skip
    if dataset is not None:
        own = is_folder_name(dataset)  # a FOLDER/NAME .npz: where its room frame lies may be given
        extra = [
            k for k, v in {**given, "truth": truth}.items() if v is not None and (k != "origin" or not own)
        ]
        if extra:
            fixed = (
                "the .npz form fixes its units, axes and reference; origin places its room frame"
                if own
                else "its reader fixes its units, axes and reference"
            )
            raise ArgumentError(f"{dataset}: {{names}} does not apply to a dataset ({fixed})", tuple(extra))
        return _timed(_read_dataset(dataset, root, origin if own else None))
    if not os.fspath(source).strip():  # type: ignore[arg-type]  # Path("") is ".", the working folder
        raise SinsInputError("read: an empty path, expected a recording's file or folder")
    path = Path(source)  # type: ignore[arg-type]
    if rig.is_rig_csv(path):
        extra = [k for k, v in {**given, "truth": truth}.items() if v is not None and k != "rate_hz"]
        if extra:
            raise SinsInputError(
                f"{path}: a rig recording (ref_ columns) is read in its own columns, units and axes, beside "
                f"its own reference; {', '.join(extra)} does not apply"
            )
        rec = _rig_recording(path)
        if rate_hz is not None:
            rec = dataclasses.replace(rec, stated_rate_hz=float(rate_hz), stated_by="the given rate")
        return _timed(rec)
    reference = truth if isinstance(truth, NavSeries) or truth is None else read_truth(truth)
    try:
        rec = _read_path(path, topic, columns, units, frame=frame, rate_hz=rate_hz, truth_topic=truth_topic,
                         origin=origin, t_start=_start(t_start, reference), progress=progress)  # fmt: skip
        rec = _timed(rec)
    except LateStartError as exc:
        if t_start is not None or reference is None:
            raise
        named = "the truth" if isinstance(truth, NavSeries) else str(truth)
        raise SinsInputError(  # the reference is what begins too late, not the readings
            f"{named}: begins at {format_number(reference.t[0])} s, not before {path}'s first "
            f"increment ends ({format_number(exc.first_end_s)} s): an increment needs its interval's start"
        ) from None
    if reference is None:
        return rec
    # A truth file is geodetic: its north and latitude are known, whatever the recording's own frame.
    given_from = "truth" if isinstance(truth, NavSeries) else str(truth)
    return dataclasses.replace(
        rec, truth=reference, truth_from=given_from, heading_known=True, latitude_known=True
    )


def _check_origin(origin: tuple[float, float, float] | None) -> None:
    """Refuse an origin that is not three finite numbers within the navigation's bounds, in radians: given
    in degrees by mistake, ``(45.0, 7.0, 100.0)`` had placed the frame at 58.3° N, and NaN every latitude."""
    if origin is None:
        return
    try:
        lat, lon, h = (float(x) for x in origin)
    except (TypeError, ValueError):
        raise SinsInputError(f"origin {origin!r}: expected (lat, lon, h) in rad, rad, m") from None
    max_lat = math.radians(MAX_LAT_DEG)
    if not (abs(lat) <= max_lat and abs(lon) <= 2.0 * math.pi and abs(h) <= MAX_HEIGHT_M):
        raise SinsInputError(
            f"origin ({lat:g}, {lon:g}, {h:g}): expected (lat, lon, h) in radians and metres, the latitude "
            f"within ±{max_lat:.4g} rad (±{MAX_LAT_DEG:g}°), the longitude ±2π, the height ±1e5 m"
        )


def _timed(rec: Recording) -> Recording:
    """``rec``, refused where its readings come at no IMU's rate (outside
    :data:`~sins.io.recording.RATE_HZ_RANGE`, by the median interval): times in another unit, read as
    seconds. Every command stops here, in one line, where steps of 1e-300 s had been integrated without a
    word and ``sins characterise`` had failed inside scipy's splines."""
    t = rec.imu.t
    if len(t) < 2:
        return rec
    med = float(np.median(np.diff(t)))  # the readers hold the times increasing: med > 0
    rate, (low, high) = 1.0 / med, RATE_HZ_RANGE
    if not low <= rate <= high:
        raise SinsInputError(
            f"{rec.source}: one reading every {med:.3g} s ({rate:.3g} Hz), no IMU's rate (sins reads "
            f"{low:g} Hz to {high:g} Hz): check the time column's unit"
        )
    return rec


def _start(t_start: float | None, reference: NavSeries | None) -> float | None:
    """Where the first increment starts: as given, else the reference's first time (where one is)."""
    return float(reference.t[0]) if t_start is None and reference is not None else t_start


__all__ = [
    "read",
]
