"""Recordings in the ``.npz`` form (:mod:`sins.io.npz`) in any folder of the data root, by the name
``FOLDER/NAME`` (``euroc/V1_01_easy`` is ``<data root>/euroc/V1_01_easy.npz``).

The recordings of one folder are taken to be of one unit: the folder's name is the unit's identity in a
model fitted on them (``fitted_on_["sensor"]``), so a model fitted on ``euroc/…`` is refused on another
folder's recordings as fitted on another unit.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np

from sins.core.series import CalibrationData, NavSeries, ReferencedRecording
from sins.errors import SinsInputError
from sins.io import npz
from sins.io.datasets.root import data_root, dataset_file
from sins.io.recording import Recording, _read_path, ideal_inputs


def is_folder_name(name: str) -> bool:
    """Whether ``name`` has the ``FOLDER/NAME`` form of an ``.npz`` recording in the data root."""
    return "/" in name


def npz_names(root: str | os.PathLike[str] | None = None) -> dict[str, str]:
    """``{"FOLDER/NAME": description}`` for every ``NAME.npz`` in a folder of the data root."""
    where = data_root(root)
    if not where.is_dir():
        return {}
    found = {}
    for folder in sorted(p for p in where.iterdir() if p.is_dir()):
        for file in sorted(folder.glob("*.npz")):
            found[f"{folder.name}/{file.stem}"] = f"an .npz recording in {folder.name}/ (readings, reference)"
    return found


def npz_path(name: str, root: str | os.PathLike[str] | None = None) -> Path:
    """The file of ``FOLDER/NAME``.

    Raises
    ------
    SinsInputError
        a name not of that form, or no such file (naming where it was looked for).
    """
    folder, _, stem = name.partition("/")
    if not folder or not stem or "/" in stem or stem in (".", "..") or folder in (".", ".."):
        raise SinsInputError(
            f"dataset {name!r}: expected FOLDER/NAME (NAME.npz in a folder of the data root)"
        )
    if stem.lower().endswith(".npz"):
        raise SinsInputError(
            f"dataset {name!r}: the name without .npz ({folder}/{stem[:-4]}), or the file's path"
        )
    return dataset_file(folder, f"{stem}.npz", root)


def _read_npz_recording(
    name: str, root: str | os.PathLike[str] | None = None, origin: tuple[float, float, float] | None = None
) -> Recording:
    """``FOLDER/NAME`` as the :class:`~sins.io.Recording` :func:`~sins.io.read` reads from its path (its
    world frame placed at ``origin``, if given).

    Raises
    ------
    SinsInputError
        as :func:`npz_path` and :func:`sins.io.npz._read_npz`.
    """
    path = npz_path(name, root)
    if not npz.is_npz(path):
        raise SinsInputError(f"{path}: not an .npz archive")
    return _read_path(path, origin=origin)


def _read_npz_reference(
    name: str, root: str | os.PathLike[str] | None = None, origin: tuple[float, float, float] | None = None
) -> ReferencedRecording:
    """``FOLDER/NAME``'s readings beside its reference; the unit is the folder.

    Raises
    ------
    SinsInputError
        as :func:`_read_npz_recording`, or a recording without the reference keys.
    """
    return _beside_own(_read_npz_recording(name, root, origin), name)


def _beside_own(rec: Recording, name: str) -> ReferencedRecording:
    """``FOLDER/NAME``'s recording ``rec`` beside its own reference; the unit is the folder."""
    if rec.truth is None:
        raise SinsInputError(
            f"{rec.source}: no reference (keys {', '.join(npz.REFERENCE_KEYS)}): it cannot be fitted or "
            "judged against"
        )
    return dataclasses.replace(rec, sensor=name.partition("/")[0]).beside_reference()


def _read_npz_with_truth(
    name: str, root: str | os.PathLike[str] | None = None, origin: tuple[float, float, float] | None = None
) -> tuple[CalibrationData, NavSeries | None]:
    """``FOLDER/NAME`` as :func:`with_truth` gives it."""
    return with_truth(_read_npz_recording(name, root, origin))


def with_truth(rec: Recording) -> tuple[CalibrationData, NavSeries | None]:
    """A recording as readings beside per-sample reference inputs and its reference at their times:
    :func:`sins.io.recording.ideal_inputs`; without a reference, NaN inputs and None."""
    if rec.truth is None:
        t, gyro, accel = rec.mean_rates()
        nan = np.full_like(gyro, np.nan)
        return CalibrationData(
            t=t, gyro=gyro, accel=accel, ref_gyro=nan, ref_accel=nan, source=rec.source
        ), None
    return ideal_inputs(rec)


__all__ = [
    "is_folder_name",
    "npz_names",
    "npz_path",
    "with_truth",
]
