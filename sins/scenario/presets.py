"""The presets shipped with sins: scenarios, rig procedures and IMU models, found by name.

A name is looked up in one place for both the command line (``sins run car_drive``,
``sins calibrate 24pos_ratetable --imu tactical``) and the files that name a preset
(``[imu] model = "tactical"``, ``[compensation] rig = "24pos_ratetable"``).
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path
from typing import Literal

from sins.errors import SinsInputError
from sins.io.documents import with_article
from sins.scenario.toml import TomlKeys

#: A kind of preset: scenarios (``""``, the folder's top level), rig procedures, IMU models or campaigns.
PresetKind = Literal["", "rig", "imu", "campaign"]

# What a kind is called in the messages.
_WHAT: dict[PresetKind, str] = {"": "scenario", "rig": "rig", "imu": "IMU", "campaign": "campaign"}


def preset_dir() -> Path:
    """The folder of the presets shipped with the package (``sins/scenarios``)."""
    return Path(str(resources.files("sins") / "scenarios"))


def presets(kind: PresetKind = "") -> dict[str, Path]:
    """Shipped presets by name: scenarios (``kind=""``), ``"rig"`` procedures or ``"imu"`` models."""
    return {p.stem: p for p in sorted((preset_dir() / kind).glob("*.toml"))}


def find_preset(
    name_or_path: str | os.PathLike[str], kind: PresetKind, base: Path | None = None
) -> Path | None:
    """A file named by a path or by a preset name of ``kind``; None if it is neither.

    Parameters
    ----------
    name_or_path : a path (relative to ``base``) or a preset name
    kind : which presets a name refers to
    base : the folder a relative path starts from (the naming file's); None: the working directory

    Returns
    -------
    ``base / name_or_path`` if it ends in ``.toml`` or exists (a path is never a name, so a missing
    ``.toml`` file is reported as such when read); otherwise the preset of that name; otherwise None.
    """
    path = Path(name_or_path) if base is None else base / name_or_path
    if path.suffix == ".toml" or path.exists():
        return path
    return presets(kind).get(str(name_or_path))


def resolve_preset(name_or_path: str | os.PathLike[str], kind: PresetKind = "") -> Path:
    """A file path from a path or a preset name of ``kind``, as the command line takes them.

    Raises
    ------
    SinsInputError
        it is neither an existing file nor a preset; the message lists the presets of ``kind``.
    """
    path = find_preset(name_or_path, kind) if str(name_or_path).strip() else None
    if path is None:
        known = presets(kind)
        raise SinsInputError(
            f"{str(name_or_path) or repr('')}: no such {_WHAT[kind]} file or preset (presets: "
            f"{', '.join(known) or 'none'})"
        )
    return path


def preset_or_path(keys: TomlKeys, key: str, kind: PresetKind, base: Path) -> Path:
    """The file a TOML key names: a path relative to ``base`` (the naming file's folder), or a preset
    name of ``kind``; a one-line error naming the file and key if it is neither."""
    value = keys.string(key)
    path = find_preset(value, kind, base) if value.strip() else None  # "" would be base itself
    if path is None:
        raise keys.error(f"no such file or {kind or 'scenario'} preset: {value!r}", key)
    if path.is_dir() or not path.exists():  # said with the file and key that name it, not the path alone
        why = "is a folder" if path.is_dir() else f"no such file (in {path.parent})"
        raise keys.error(f"{value!r} {why}, expected {with_article(_WHAT[kind])} file or preset", key)
    return path


__all__ = [
    "PresetKind",
    "find_preset",
    "preset_dir",
    "preset_or_path",
    "presets",
    "resolve_preset",
]
