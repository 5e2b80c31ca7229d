"""What ``sins gap`` reads: every recording ``sins fit`` reads (:func:`sins.io.read`), each with its own
reference.

A recording comes as a dataset's name (``--dataset broad_05``, ``--dataset euroc/V1_01_easy``) or a path:
a sins rig CSV (``ref_`` columns: per-sample reference inputs), a recording in any format sins reads (a
CSV, an ``.npz``, a EuRoC/TUM-VI folder, a ROS bag or MCAP) beside its own reference or a ``--truth``
trajectory. A :class:`GapInput` holds both forms a recording can be diagnosed in: its readings beside
per-sample reference inputs (the per-sample statistic; for a trajectory, the exact ideal IMU of the
motion through it: splines, differentiated), and, where the reference is a trajectory, the readings
beside it at its epochs (the interval statistic, :mod:`sins.unit_gap.intervals`). The per-sample form
of a trajectory is made only when asked for.

A reference's spans filled by interpolation (:mod:`sins.io.filled`: a converter's slerp across a lost
marker) are set aside from the trajectory form, as ``sins fit`` sets them aside: the diagnosis looks
for what the unit's model lacks, and those spans are what the reference lacks (three 1 s slerped gaps
in EuRoC's MH_01 made its clean diagnosis name a gyro y bias step). The per-sample form keeps them; the
report says where they are (``statistic.reference_filled``). A reference whose world frame is tilted
from gravity is levelled in the trajectory form (:mod:`sins.compensation.world_tilt`): the tilt leaves
gravity in its horizontal axes, which the diagnosis would read as the accelerometer's error; the report
gives the tilt (``statistic.reference_tilt``). The per-sample form reads the reference as given.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sins.compensation import screening, world_tilt
from sins.compensation.several import SAME_RATE
from sins.core.series import CalibrationData, NavSeries, ReferencedRecording
from sins.errors import MissingInputError, SinsInputError
from sins.io.recording import ideal_inputs

Samples = tuple[CalibrationData, NavSeries | None]


@dataclass
class GapInput:
    """One recording to diagnose: what the user named it, its trajectory form (None: its reference is
    per-sample inputs), and how to make its per-sample form (made once, when first asked for)."""

    name: str
    referenced: ReferencedRecording | None
    make_samples: Callable[[], Samples]
    _samples: Samples | None = field(default=None, repr=False)
    #: The reference's spans filled by interpolation, s, set aside from ``referenced``.
    filled_s: tuple[tuple[float, float], ...] = ()
    #: The reference's world frame against gravity (None: per-sample reference inputs).
    tilt: world_tilt.WorldTilt | None = None

    def samples(self) -> Samples:
        """The readings beside per-sample reference inputs, and the trajectory at their times (None
        without one)."""
        if self._samples is None:
            self._samples = self.make_samples()
        return self._samples


def read_gap_input(
    recording: str | os.PathLike[str] | None,
    *,
    dataset: str | None = None,
    truth: str | os.PathLike[str] | None = None,
    options: dict[str, Any] | None = None,
) -> GapInput:
    """A recording by dataset name or path, read by :func:`sins.io.read` (as ``sins fit`` reads it).

    Raises
    ------
    SinsInputError
        one line naming the recording: both or neither of a path and a dataset, ``truth`` beside a
        dataset, a recording without any reference, and as the reader does.
    """
    from sins import io
    from sins.runs import readings

    if dataset is not None and truth is not None:
        raise SinsInputError("gap: --truth goes with a RECORDING, not with --dataset")
    if recording is not None:
        _check_csv(Path(recording), truth, options)
    rec = io.read(recording, dataset=dataset, truth=truth, **(options or {}))
    name = rec.name
    if rec.rig is not None:
        rig = rec.rig
        return GapInput(name, None, lambda: (rig, None))
    if not rec.has_trajectory:
        raise MissingInputError(f"{name}: the recording has no reference trajectory", needs="truth")
    referenced = rec.beside_reference()
    spans = screening.filled(referenced)
    if spans:
        referenced = screening.without(referenced, list(spans))
    tilt = world_tilt.estimate(referenced)  # its filled spans already set aside (world_tilt.levelled's)
    referenced = world_tilt.level(referenced, tilt)
    if rec.inputs_reader is not None:  # a dataset's own per-sample form
        return GapInput(name, referenced, rec.inputs_reader, filled_s=spans, tilt=tilt)
    if truth is not None:  # readings and a truth file: the exact ideal IMU, in either form
        return GapInput(name, referenced, lambda: readings.gap_data(rec), filled_s=spans, tilt=tilt)
    return GapInput(name, referenced, lambda: ideal_inputs(rec), filled_s=spans, tilt=tilt)


def check_one_unit(inputs: list[GapInput]) -> None:
    """Refuse recordings of two units (each's reference names its unit, as :func:`sins.io.read` finds
    it), or at two rates: ``sins gap`` reads several recordings as one unit's, its verdicts across them
    and each one's model judged on the next; ``sins fit`` refuses such a pair alike. One line, both
    named. A 100 Hz copy beside its 200 Hz original had been diagnosed as one unit's, a g² sensitivity
    of 115 °/s/g² accepted on it and judged on the other."""
    named = [(i.name, r.sensor) for i in inputs if (r := i.referenced) is not None and r.sensor]
    for name, sensor in named[1:]:
        if sensor != named[0][1]:
            raise SinsInputError(
                f"{name}: recordings of one unit are diagnosed together; {named[0][0]} is {named[0][1]}, "
                f"this is {sensor} (diagnose each on its own)"
            )
    rates = [(i.name, _rate_hz(i)) for i in inputs]
    (first, first_hz), *others = rates
    for name, rate in others:
        if abs(rate - first_hz) > SAME_RATE * first_hz:
            raise SinsInputError(
                f"{name}: readings at {rate:.6g} Hz; {first} at {first_hz:.6g} Hz: recordings of one unit "
                "are diagnosed together at one rate (diagnose each on its own)"
            )


def _rate_hz(gap_input: GapInput) -> float:
    """A recording's median sample rate, Hz: its trajectory form's, or its per-sample form's (a rig's)."""
    if gap_input.referenced is not None:
        return gap_input.referenced.rate_hz
    t = gap_input.samples()[0].t
    return float(1.0 / np.median(np.diff(t)))


def _check_csv(path: Path, truth: str | os.PathLike[str] | None, options: dict[str, Any] | None) -> None:
    """A CSV of sins's or its own columns, without a trajectory and without ``ref_`` columns: the
    trajectory is what is missing (said before its columns are read as some other form)."""
    from sins.io import rig

    if truth is not None or path.suffix.lower() != ".csv" or (options or {}).get("columns"):
        return
    if path.is_file() and not rig.is_rig_csv(path):
        raise MissingInputError(
            f"{path}: no ref_ columns (a rig recording has them); an IMU recording needs its trajectory "
            "(a truth file)",
            needs="truth",
        )


__all__ = [
    "GapInput",
    "check_one_unit",
    "read_gap_input",
]
