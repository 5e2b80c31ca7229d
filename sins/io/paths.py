"""The files a command reads and writes, checked before any work: inputs that are regular files of a size
the memory holds, outputs that can be written and are none of the inputs.

**Inputs** (:func:`check_input`): only regular files (and, where a format is a folder, folders) are
read. A FIFO blocks its reader until a writer comes, ``/dev/zero`` never ends, a device is not a
recording: each is refused in one line, before it is opened. A regular file larger than the memory
could hold once read (:data:`READ_FACTOR` times its size) is refused too.

**Outputs** (:func:`check_outputs`), the one check every command that writes makes before its work:

* the place: the folder exists and can be written (tried with a temporary file, not read off the
  permission bits, which bind neither root nor a read-only mount); the name is not a folder;
* what is there: a regular file is replaced (:mod:`sins.io.atomic`: a temporary name, then a rename);
  a character device (``/dev/null``, ``/dev/full``) is written in place, never replaced; a FIFO, a
  socket or a block device is refused; a symbolic link is followed to its target (which is written;
  the link stays);
* not an input: an output that is the same file as any input of the command (same device and inode,
  or the same path once links are resolved: a hard link, ``./x`` beside ``x``), a file inside an input
  folder, or the same file as another output of the command, is refused. sins never writes over
  what it reads.
"""

from __future__ import annotations

import os
import stat
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path

from sins.errors import SinsInputError
from sins.io.limits import available_memory, format_size

#: Memory a read takes per byte of the file (the text, the parsed numbers and their copies): a file
#: above the available memory divided by this is refused before it is read.
READ_FACTOR = 3.0

_KINDS = {
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFSOCK: "a socket",
}


def _kind(mode: int) -> str:
    return _KINDS.get(stat.S_IFMT(mode), "not a regular file")


def check_input(path: str | os.PathLike[str], *, folder: bool = False) -> Path:
    """``path`` as a Path if it is a regular file (or, with ``folder``, a folder) sins may read.

    Raises
    ------
    SinsInputError
        ``path: no such file``; ``path: is a FIFO (named pipe), not a file: sins reads regular files``
        (devices and sockets alike; a folder where a file is wanted); a file too large for the memory.
    """
    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise SinsInputError(f"{path}: no such file" + (" or folder" if folder else "")) from None
    except OSError as exc:
        raise SinsInputError(f"{path}: cannot read: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        if folder:
            return path
        raise SinsInputError(f"{path}: is a directory, expected a file")
    if not stat.S_ISREG(st.st_mode):
        raise SinsInputError(f"{path}: is {_kind(st.st_mode)}, not a regular file: sins reads regular files")
    available = available_memory()
    if available is not None and st.st_size * READ_FACTOR > available:
        need = format_size(st.st_size * READ_FACTOR)
        raise SinsInputError(
            f"{path}: {format_size(st.st_size)}; reading it needs about {need} of memory, "
            f"{format_size(available)} available"
        )
    return path


def target(path: str | os.PathLike[str]) -> Path:
    """Where writing ``path`` lands: a symbolic link followed to its target (the link is kept), the path
    itself otherwise."""
    path = Path(path)
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def writes_in_place(path: str | os.PathLike[str]) -> bool:
    """Whether an output at ``path`` is written in place rather than replaced: a character device
    (``/dev/null``), which a rename would turn into a regular file."""
    try:
        return stat.S_ISCHR(os.stat(path).st_mode)
    except OSError:
        return False


def read_only(path: Path, shown: str) -> None:
    """Refuse to replace an existing file that no one may write (no write bit in its mode): whoever
    marked it so meant it kept, and a rename over it needs only the folder's permission (root's
    writes pass any permission; the mode still says what was meant).

    Raises
    ------
    SinsInputError
        ``shown: is read-only ...``.
    """
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return
    if stat.S_ISREG(mode) and not mode & 0o222:
        raise SinsInputError(
            f"{shown}: is read-only (mode {stat.S_IMODE(mode):04o}); sins does not replace a file marked so: "
            "make it writable or write elsewhere"
        )


def check_writable(path: str | os.PathLike[str], folder: bool = False, flag: str = "") -> None:
    """Refuse, before the work, an output that could not be written after it (see the module
    docstring): a file whose folder is missing or not writable, a file name that is a folder, a FIFO,
    socket or block device; with ``folder``, a folder that is a file, or whose nearest existing parent
    is not writable (it will be created). ``flag`` (``--out``) prefixes the message.

    Raises
    ------
    SinsInputError
        ``[flag ]path: why``, naming the output as the user gave it.
    """
    shown = f"{flag} {path}" if flag else f"{path}"
    path = Path(path)
    if folder:
        if path.exists() and not path.is_dir():
            raise SinsInputError(f"{shown}: is a file, expected a folder for the results")
        probe = path
        while not probe.exists() and probe != probe.parent:
            probe = probe.parent
        if not probe.is_dir():
            raise SinsInputError(f"{shown}: cannot create the folder: {probe} is not a folder")
    else:
        real = target(path)
        if real.is_dir():
            raise SinsInputError(f"{shown}: is a directory, expected a file name to write")
        try:
            mode = os.stat(real).st_mode
        except OSError:
            mode = stat.S_IFREG
        if stat.S_ISCHR(mode):
            return  # written in place (/dev/null); opening it is the writer's test
        if not stat.S_ISREG(mode):
            raise SinsInputError(f"{shown}: is {_kind(mode)}; sins writes regular files (or /dev/null)")
        read_only(real, shown)
        probe = real.parent
        if not probe.is_dir():
            raise SinsInputError(f"{shown}: directory {probe} does not exist")
    try:
        with tempfile.TemporaryFile(dir=probe):
            pass
    except OSError as exc:
        raise SinsInputError(f"{shown}: cannot write in {probe}: {exc.strerror or exc}") from None


def _identity(path: Path) -> tuple[tuple[int, int] | None, str]:
    """A path's file identity (device, inode) where it exists, and its resolved path."""
    try:
        st = os.stat(path)
        ident: tuple[int, int] | None = (st.st_dev, st.st_ino)
    except OSError:
        ident = None
    return ident, os.path.realpath(path)


def _inside(folder: str, path: str) -> bool:
    return path != folder and path.startswith(folder.rstrip(os.sep) + os.sep)


def check_outputs(
    outputs: Mapping[str, str | os.PathLike[str] | None],
    inputs: Iterable[str | os.PathLike[str] | None] = (),
    folders: Mapping[str, str | os.PathLike[str] | None] | None = None,
) -> None:
    """The one check of a command's outputs before its work (see the module docstring).

    Parameters
    ----------
    outputs : ``{flag: path}`` of the files the command will write (None: not asked for)
    inputs : every file and folder it reads (None entries skipped)
    folders : ``{flag: path}`` of folders it writes into (a campaign's results)

    Raises
    ------
    SinsInputError
        one line naming the output (and the input it would replace).
    """
    files = {flag: Path(p) for flag, p in outputs.items() if p is not None}
    dirs = {flag: Path(p) for flag, p in (folders or {}).items() if p is not None}
    for flag, path in files.items():
        check_writable(path, flag=flag)
    for flag, path in dirs.items():
        check_writable(path, folder=True, flag=flag)
    read = [(Path(p), *_identity(Path(p))) for p in inputs if p is not None]
    seen: list[tuple[str, Path, tuple[int, int] | None, str]] = []
    for flag, path in files.items():
        ident, real = _identity(target(path))
        if writes_in_place(path):
            continue  # /dev/null may be given twice, and stands for no file
        for source, source_ident, source_real in read:
            same = (ident is not None and ident == source_ident) or real == source_real
            if same or (source.is_dir() and _inside(source_real, real) and os.path.exists(real)):
                what = "is" if same else "is inside"
                raise SinsInputError(
                    f"{flag} {path}: {what} an input of this command ({source}); sins never writes over "
                    "what it reads: write elsewhere"
                )
        for other_flag, other, other_ident, other_real in seen:
            if (ident is not None and ident == other_ident) or real == other_real:
                raise SinsInputError(
                    f"{flag} {path}: is also {other_flag} {other}; give each output its own file"
                )
        seen.append((flag, path, ident, real))
    for flag, path in dirs.items():
        real = os.path.realpath(path)
        for source, _, source_real in read:
            if real == source_real:
                raise SinsInputError(
                    f"{flag} {path}: is an input of this command ({source}); write elsewhere"
                )


__all__ = [
    "READ_FACTOR",
    "check_input",
    "check_outputs",
    "check_writable",
    "read_only",
    "target",
    "writes_in_place",
]
