"""Readers for the real IMU datasets kept beside the project (never copied into it).

Each dataset lives in a folder under the data root (see :func:`data_root`) with
a SOURCE.md giving its origin, licence, units and columns. Each reader, one
module per dataset, converts to the package's conventions (SI, radians) and
returns the package's types; :func:`_read_dataset` gives any of them by name as a
:class:`~sins.io.Recording`, which is what :func:`sins.io.read` (``dataset=NAME``) returns:
the one public way in.
"""

from __future__ import annotations

import dataclasses
import os

import numpy as np

from sins.core.series import CalibrationData, ImuRates, NavSeries, ReferencedRecording
from sins.errors import SinsInputError
from sins.io import units
from sins.io.datasets.broad import BROAD_TRIALS, _read_broad
from sins.io.datasets.ferraris import (
    FERRARIS_FOLDER,
    FERRARIS_RATE_HZ,
    FERRARIS_SECTIONS,
    _read_ferraris,
    _read_ferraris_annotated,
)
from sins.io.datasets.npz_folders import (
    _beside_own,
    _read_npz_recording,
    _read_npz_reference,
    _read_npz_with_truth,
    is_folder_name,
    npz_names,
)
from sins.io.datasets.psins_lasergyro import _read_psins_lasergyro
from sins.io.datasets.psins_vehicle import read_psins_vehicle
from sins.io.datasets.root import ENV_VAR, data_root
from sins.io.recording import Recording

#: Dataset names for :func:`_read_dataset`, and what each is.
NAMES = {
    "ferraris": "imucal's hand-made Ferraris session of a MEMS IMU (static holds only have a reference)",
    "ferraris_annotated": "imucal's annotated Ferraris session (raw counts, 204.8 Hz, its nine sections)",
    "psins_vehicle": "PSINS vehicle MEMS IMU against its FOG-INS, as 0.1 s means (the INS's own rate)",
    "psins_lasergyro": "PSINS static ring-laser INS against Earth rate and gravity",
    **{f"broad_{s[:2]}": f"BROAD trial {s}: a MEMS IMU against optical motion capture" for s in BROAD_TRIALS},
}


def names(root: str | os.PathLike[str] | None = None) -> dict[str, str]:
    """:data:`NAMES`, with every BROAD trial in the data root's ``broad_mocap/`` (a user who has more of
    BROAD's 39 trials puts them there; each ``NN_*.mat`` is ``broad_NN``) and every ``.npz`` recording in
    a folder of the data root as ``FOLDER/NAME`` (:mod:`sins.io.datasets.npz_folders`)."""
    from sins.io.datasets.broad import trials

    found = {
        f"broad_{n}": f"BROAD trial {stem}: a MEMS IMU against optical motion capture"
        for n, stem in trials(root).items()
    }
    return {**{k: v for k, v in NAMES.items() if not k.startswith("broad_")}, **found, **npz_names(root)}


def _load_reference(
    name: str, root: str | os.PathLike[str] | None = None, origin: tuple[float, float, float] | None = None
) -> ReferencedRecording | None:
    """A dataset by name as readings beside its reference trajectory, or None where its reference is not a
    trajectory (``ferraris``: static holds and turns of known angle; ``psins_lasergyro``: a still unit).

    Raises
    ------
    SinsInputError
        for an unknown name (listing the known ones), or as the readers do.
    """
    if is_folder_name(name):
        return _read_npz_reference(name, root, origin)
    known = names(root)
    if name not in known:
        raise SinsInputError(f"no dataset {name!r} (datasets: {', '.join(known)})")
    if name == "psins_vehicle":
        from sins.io.datasets.psins_reference import _read_psins_vehicle_reference

        return _read_psins_vehicle_reference(root)
    if name.startswith("broad_"):
        from sins.io.datasets.broad_reference import _read_broad_reference

        return _read_broad_reference(name.removeprefix("broad_"), root)
    return None


def _read_dataset(
    name: str, root: str | os.PathLike[str] | None = None, origin: tuple[float, float, float] | None = None
) -> Recording:
    """A dataset by name as a :class:`~sins.io.Recording` (what :func:`sins.io.read` gives for
    ``dataset=name``): beside its reference trajectory where it has one (its per-sample form read only
    when asked for, :meth:`~sins.io.Recording.reference_inputs`), else beside its per-sample reference
    inputs (``rig``). ``origin``: where a ``FOLDER/NAME``'s world frame lies (the named datasets know).

    Raises
    ------
    SinsInputError
        for an unknown name (listing the known ones), or as the readers do.
    """
    if is_folder_name(name):  # its stamps read once: its time origin and notes kept
        own = _read_npz_recording(name, root, origin)
        if own.truth is None:  # readings alone: a command that needs a reference says so when it asks
            return dataclasses.replace(own, sensor=name.partition("/")[0], dataset=name)
        # Its readings and reference as the file holds them (rates, integrated as its path's are: the
        # referenced form's trapezoid had ended EuRoC's V1_02 1.2 m off its path's), beside the
        # referenced form the fits take (on_reference).
        return dataclasses.replace(
            own, kind="dataset", sensor=name.partition("/")[0], dataset=name,
            on_reference=_beside_own(own, name), inputs_reader=lambda: _load_with_truth(name, root, origin),
        )  # fmt: skip
    trajectory = _load_reference(name, root, origin)
    if trajectory is not None:
        return Recording(
            trajectory.imu, trajectory.source, "dataset", trajectory.reference, _si("increment"),
            sensor=trajectory.sensor, heading_known=trajectory.heading_known,
            latitude_known=trajectory.latitude_known, dataset=name, on_reference=trajectory,
            inputs_reader=lambda: _load_with_truth(name, root, origin),
        )  # fmt: skip
    data = _load_with_truth(name, root)[0]
    imu = ImuRates(t=data.t, omega_ib_b=data.gyro, f_ib_b=data.accel)
    return Recording(imu, data.source, "dataset", None, _si("rate"), temp=data.temp, rig=data, dataset=name)


def _si(form: str) -> dict[str, str]:
    return {k: units.SI[k] for k in units.FORM_KEYS[form] if k != "temp"}


def _load_with_truth(
    name: str, root: str | os.PathLike[str] | None = None, origin: tuple[float, float, float] | None = None
) -> tuple[CalibrationData, NavSeries | None]:
    """A dataset by name, and its reference trajectory at the readings' times where it has one.

    ``psins_vehicle`` has one (the FOG-INS's solution; its first and last rows, which the solution does
    not span, are left out), and every ``FOLDER/NAME`` with a reference
    (:func:`~sins.io.datasets.npz_folders._read_npz_with_truth`).
    """
    if is_folder_name(name):
        return _read_npz_with_truth(name, root, origin)
    if name == "psins_vehicle":
        # The reference is a 10 Hz navigation solution: at the MEMS's 100 Hz it lacks the 5-30 Hz
        # vibration the MEMS sees, which would pass for a sensor gap.
        data, nav = read_psins_vehicle(root, rate="fog")
        if nav is None:
            return data, None
        inside = np.flatnonzero((data.t >= nav.t[0]) & (data.t <= nav.t[-1]))
        data = data.rows(inside) if len(inside) < len(data) else data
        return data, nav.interpolate(data.t)
    return _load_rig(name, root), None


def _load_rig(name: str, root: str | os.PathLike[str] | None) -> CalibrationData:
    if name == "ferraris":
        return _read_ferraris(root)
    if name == "ferraris_annotated":
        return _read_ferraris_annotated(root)
    if name == "psins_lasergyro":
        return _read_psins_lasergyro(root)
    if name.startswith("broad_") and name in names(root):
        return _read_broad(name.removeprefix("broad_"), root)
    raise SinsInputError(f"no dataset {name!r} (datasets: {', '.join(names(root))})")


__all__ = [
    "BROAD_TRIALS",
    "ENV_VAR",
    "FERRARIS_FOLDER",
    "FERRARIS_RATE_HZ",
    "FERRARIS_SECTIONS",
    "NAMES",
    "data_root",
    "names",
]
