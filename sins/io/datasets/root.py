"""Where the real datasets live: the data root (``../shared/data``, or ``SINS_DATA``)."""

from __future__ import annotations

import os
from pathlib import Path

#: The environment variable that points at the data root.
ENV_VAR = "SINS_DATA"


def data_root(override: str | os.PathLike[str] | None = None) -> Path:
    """The folder that holds the datasets.

    In this order: ``override`` when given; else the environment variable
    ``SINS_DATA`` when set and non-empty; else ``../shared/data`` relative to
    the current working directory when that is a folder; else ``../shared/data``
    relative to the repository root (the parent of the ``sins`` package
    folder), whether or not it exists (the readers then say it is missing).

    Parameters
    ----------
    override : an explicit data root, or None

    Returns
    -------
    Path
        absolute (``~`` expanded); not checked to exist when given by ``override``
        or ``SINS_DATA``.
    """
    if override is not None:
        return Path(override).expanduser().absolute()
    env = os.environ.get(ENV_VAR, "")
    if env:
        return Path(env).expanduser().absolute()
    here = Path.cwd() / ".." / "shared" / "data"
    if here.is_dir():
        return here.resolve()
    return (Path(__file__).resolve().parents[3] / ".." / "shared" / "data").resolve()


def dataset_file(folder: str, name: str, root: str | os.PathLike[str] | None = None) -> Path:
    """``<data root>/<folder>/<name>``, or a one-line error saying how to point at the data."""
    from sins.errors import SinsInputError

    where = data_root(root) / folder
    if not where.is_dir():
        raise SinsInputError(
            f"{where}: no such data folder; set {ENV_VAR} (from Python: root=) to point at the folder that "
            f"holds {folder}/ (the project's ../shared/data)"
        )
    path = where / name
    if not path.is_file():
        raise SinsInputError(
            f"{path}: no such file; set {ENV_VAR} (from Python: root=) to point at the data root that holds "
            f"{folder}/"
        )
    return path


def check_magnitude(
    path: str | os.PathLike[str], variable: str, values: object, limit: float, unit: str, nan_ok: bool = False
) -> None:
    """Refuse the first element of ``values`` (rows × columns) beyond ``±limit`` (or not finite, unless
    ``nan_ok``, where NaN marks a missing value), naming the file, the variable, row and column (from 1).

    The readers convert a dataset's units, and a damaged file can hold anything: this keeps the values
    they return within the physical ranges of sins's own files (see :mod:`sins.io.formats`).
    """
    import numpy as np

    from sins.errors import SinsInputError

    a = np.asarray(values, dtype=float)
    a = a.reshape(len(a), -1) if a.ndim else a.reshape(1, 1)
    bad = np.abs(a) > limit if nan_ok else ~(np.abs(a) <= limit)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise SinsInputError(
            f"{path}: {variable}: row {r + 1}, column {c + 1}: {a[r, c]:g} {unit} is beyond "
            f"±{limit:g} {unit}, outside any physical range (a damaged file?)"
        )


__all__ = [
    "ENV_VAR",
    "check_magnitude",
    "data_root",
    "dataset_file",
]
