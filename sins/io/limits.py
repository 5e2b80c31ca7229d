"""Resource limits, checked before the work: will an output fit on its disk, a computation in memory?

A scenario of 1e9 s at 1 kHz would write petabytes of CSV; without a check the run starts, fills the
disk or the memory hours later and dies. The commands estimate what they need from the sample count
(:func:`csv_bytes` for the CSV writers, a per-sample figure for whole arrays) and refuse up front, in
one line that names the file and the size it would need (:func:`check_disk`, :func:`check_memory`).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import stat
from pathlib import Path

from sins.errors import SinsInputError

#: The longest value the CSV writers write (``%.17g``: sign, 17 digits, point, ``e-308``) and its comma.
CSV_BYTES_PER_VALUE = 25


def format_size(nbytes: float) -> str:
    """A byte count in decimal units (``1.5 GB``)."""
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if abs(nbytes) < 1000.0 or unit == "PB":
            return f"{nbytes:.0f} {unit}" if unit == "B" else f"{nbytes:.3g} {unit}"
        nbytes /= 1000.0
    raise AssertionError("unreachable")


def csv_bytes(rows: float, columns: int, comment: str = "") -> float:
    """The most bytes a CSV of ``rows`` × ``columns`` values written by :func:`~sins.io.write_table` takes."""
    return rows * columns * CSV_BYTES_PER_VALUE + len(comment.encode()) + 16 * columns


def available_memory() -> int | None:
    """Memory the process can use without swapping, bytes: ``MemAvailable`` (Linux, counts the page
    cache it would free), else free physical pages × page size; None where neither is known."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, ValueError, OSError):
        return None


def check_memory(nbytes: float, what: str, source: str | os.PathLike[str]) -> None:
    """Refuse ``what`` (e.g. "simulating 1e9 samples") when it needs more memory than is available.

    Raises
    ------
    SinsInputError
        ``source: what needs about X of memory, Y available``.
    """
    available = available_memory()
    if available is not None and nbytes > available:
        raise SinsInputError(
            f"{source}: {what} needs about {format_size(nbytes)} of memory, {format_size(available)} "
            "available; shorten it or lower the rate"
        )


def check_disk(outputs: dict[Path, float], source: str | os.PathLike[str]) -> None:
    """Refuse when the files ``{path: bytes}`` would not fit on their disks (those sharing one added up).

    Raises
    ------
    SinsInputError
        ``source: path (and others) need up to X, folder has Y free``. A folder that does not exist
        is left for the writer to refuse.
    """
    by_folder: dict[Path, list[Path]] = {}
    for path in outputs:
        real = Path(os.path.realpath(path))  # a link's target is what is written (sins.io.atomic)
        with contextlib.suppress(OSError):  # paths.writes_in_place's test: paths imports this module
            if stat.S_ISCHR(real.stat().st_mode):  # /dev/null takes no room: /dev's is not the question
                continue
        by_folder.setdefault(real.parent, []).append(Path(path))
    devices: dict[int, tuple[Path, float, list[Path]]] = {}
    for folder, paths in by_folder.items():
        try:
            device = folder.stat().st_dev
        except OSError:
            continue
        _, total, names = devices.get(device, (folder, 0.0, []))
        devices[device] = (folder, total + sum(outputs[p] for p in paths), names + paths)
    for folder, need, paths in devices.values():
        free = shutil.disk_usage(folder).free
        if need > free:
            listed = " and ".join(str(p) for p in paths)
            raise SinsInputError(
                f"{source}: {listed} would need up to {format_size(need)}, {folder} has "
                f"{format_size(free)} free; shorten the run, lower the rate or write elsewhere"
            )


__all__ = [
    "CSV_BYTES_PER_VALUE",
    "available_memory",
    "check_disk",
    "check_memory",
    "csv_bytes",
    "format_size",
]
