"""The files a command reads and writes, checked before any work: inputs that are regular files of a size
the memory holds, outputs that can be written and are none of the inputs.

**Inputs** (:func:`check_input`): only regular files (and, where a format is a folder, folders) are
read. A FIFO blocks its reader until a writer comes, ``/dev/zero`` never ends, a device is not a
recording: each is refused in one line, before it is opened. A regular file larger than the memory
could hold once read (:data:`READ_FACTOR` times its size) is refused too.

**Outputs** (:func:`check_outputs`), the one check every command that writes makes before its work:

* the name: its suffix does not name another format than the one written (CSV text is not written
  to ``corrected.npz``, nor a model to ``m.csv``: :func:`check_named`);
* the place: the folder exists and can be written (tried with a temporary file, not read off the
  permission bits, which bind neither root nor a read-only mount); the name is not a folder;
* what is there: a regular file is replaced (:mod:`sins.io.atomic`: a temporary name, then a rename),
  unless no one may write it (its mode) or it holds what the output never is (a recording, an archive
  or an image where JSON or text is written; where a CSV table or an IMU file is, any text but a file
  sins wrote: :func:`replaceable`);
  a character device (``/dev/null``, ``/dev/full``) is written in place, never replaced; a FIFO, a
  socket or a block device is refused; a symbolic link is followed to its target (which is written;
  the link stays);
* not an input: an output that is the same file as any input of the command (same device and inode,
  or the same path once links are resolved: a hard link, ``./x`` beside ``x``), a file that exists
  inside an input folder, or the same file as another output of the command, is refused (a new file
  in an input folder replaces nothing, and is written). sins never writes over what it reads;
* not a campaign's: a file in a campaign's results folder (one holding a ``campaign.json`` of
  :data:`CAMPAIGN_FORMAT`, or a folder of it) is written by that campaign alone (``sins campaign --out
  DIR``, which names it among its folders): a report or a table of another command there had replaced
  its identity or its results, and the campaign could not resume.
"""

from __future__ import annotations

import os
import re
import stat
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path

from sins.core import deferred
from sins.errors import SinsInputError
from sins.io.limits import available_memory, format_size

#: The ``format`` of a campaign's ``campaign.json``, which marks its results folder
#: (:mod:`sins.campaign.folder`).
CAMPAIGN_FORMAT = "sins-campaign"

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
    try:  # opened once here: a file sins may not read is said so, not taken for a damaged one by a sniffer
        os.close(os.open(path, os.O_RDONLY))
    except OSError as exc:
        raise SinsInputError(f"{path}: cannot read: {exc.strerror or exc}") from None
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


#: The names of a process's own streams: ``/dev/stdout``, ``/dev/fd/1``, ``/proc/self/fd/1``.
_STREAM = re.compile(r"\A/(dev/std(in|out|err)|dev/fd/\d+|proc/(self|\d+)/fd/\d+)\Z")


def own_stream(path: str | os.PathLike[str], shown: str) -> None:
    """Refuse a process's stream (``/dev/stdout``) as an output unless it is a terminal, written in place:
    redirected to a file, the file was replaced (the command's printed table with it, written to the
    file replaced), and to a pipe it could not be written ("cannot write in /proc/N/fd").

    Raises
    ------
    SinsInputError
        ``shown: is this command's own output stream ...``.
    """
    if _STREAM.match(os.path.abspath(path)) and not writes_in_place(path):
        raise SinsInputError(
            f"{shown}: is this command's own stream (a file or pipe here), which sins does not write "
            "through: name a file (or /dev/null)"
        )


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


#: The kinds of file a command writes (:func:`check_outputs`' ``kinds``, :func:`replaceable`,
#: :func:`check_named`), besides the formats of sins's own JSON documents that other commands read
#: (:data:`_DOCUMENTS`): ``csv`` a table as text, ``toml`` an IMU file, ``text`` any other text.
KINDS = ("json", "csv", "toml", "text", "image", "rrd", "parquet")
#: sins's JSON documents that are inputs, by their ``format``: only an output of the same replaces one.
_DOCUMENTS = {"sins.compensation": "a compensation model", "sins.quality-baseline": "a quality baseline",
              "sins-campaign-summary": "a campaign's summary (a campaign baseline)"}  # fmt: skip
#: The first bytes of the files that are not text which sins reads or writes, and what each is.
_SIGNATURES = (
    (b"PK\x03\x04", "a zip archive (an .npz recording?)"),
    (b"PK\x05\x06", "a zip archive (an .npz recording?)"),
    (b"\x89HDF\r\n\x1a\n", "an HDF5 file"),
    (b"MATLAB 5.0 MAT-file", "a MATLAB file (a recording?)"),
    (b"#ROSBAG", "a ROS 1 bag"),
    (b"\x89MCAP", "an MCAP recording"),
    (b"SQLite format 3\x00", "an SQLite database (a ROS 2 bag?)"),
    (b"\x1f\x8b", "a gzip file"),
    (b"\x89PNG", "a PNG image"),
    (b"%PDF", "a PDF"),
    (b"RRF", "a Rerun recording"),
    (b"PAR1", "a Parquet table"),
)
#: What :func:`_holds` calls a text file that sins wrote: its first line ``# sins VERSION: ...`` (every
#: table and IMU file a command writes opens so; a solution of sins before it did opened ``# solution of``,
#: an IMU file ``# IMU noise model from `sins characterise```). Text that does not is a user's (a logger's
#: recording, a reference, a hand-written scenario), which a table or an IMU file does not replace; sins's
#: own they do, run again.
SINS_TEXT = "a file sins wrote"
#: What :func:`_holds` calls a JSON report sins wrote: an object whose first key is ``"sins"``, its version
#: (:func:`sins.io.json_files.write_report`), or whose ``"format"`` names a sins kind that is no input
#: (``sins inspect --json`` before the mark). Other JSON is a user's, which a report does not replace.
SINS_REPORT = "a report sins wrote"
#: What :func:`_holds` calls the pictures sins drew: a PNG with matplotlib's ``Software: sins`` text chunk
#: (:func:`sins.viz.plots.save`), the HTML page that holds one, a Rerun recording of sins's application
#: id. A plot or a recording replaces these, not a user's own image, page or recording.
SINS_PNG, SINS_PAGE, SINS_RRD = (
    "a PNG image sins drew",
    "a web page sins wrote",
    "a Rerun recording sins wrote",
)
_SINS_PAGE = re.compile(
    r'\A<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>[^<]*</title></head>\n'
    r'<body><h1 style="font-family: sans-serif; font-size: 1\.2em">'
)
#: The first key of every report a command writes: the version of the sins that wrote it.
REPORT_KEY = "sins"
_SINS_REPORT = re.compile(r'\A\ufeff?\s*\{\s*"' + REPORT_KEY + r'"\s*:\s*"')
_SINS_LINE = re.compile(r"\A\ufeff?# (sins \d|solution of |IMU noise model from `sins characterise`)")
#: What an output of each kind may replace, by what :func:`_holds` says a file is (and an empty file).
_REPLACES = {
    "json": (SINS_REPORT,),
    "csv": (SINS_TEXT,),
    "toml": (SINS_TEXT,),
    "text": ("JSON", "text", SINS_TEXT, SINS_REPORT),
    "image": (SINS_PNG, SINS_PAGE),  # a plot's .png, or its .html page
    "rrd": (SINS_RRD,),
    "parquet": ("a Parquet table",),
}
_WRITES = {"json": "JSON", "csv": "a CSV table", "toml": "a TOML file", "text": "text", "image": "an image",
           "rrd": "a Rerun recording", "parquet": "a Parquet table", **_DOCUMENTS}  # fmt: skip
#: The formats that common suffixes name. An output is never written under a suffix that names another
#: format than its own: every reader, sins's own included, would take it for that format (CSV text in
#: an ``.npz`` reads as a damaged archive, in a ``.parquet`` as a damaged table).
_NAMED = {
    ".npz": "a NumPy archive", ".npy": "a NumPy array", ".mat": "a MATLAB file", ".h5": "an HDF5 file",
    ".hdf5": "an HDF5 file", ".bag": "a ROS 1 bag", ".mcap": "an MCAP recording", ".db3": "a ROS 2 bag",
    ".parquet": "a Parquet table", ".feather": "an Arrow table", ".pkl": "a pickle", ".xlsx": "a spreadsheet",
    ".png": "an image", ".jpg": "an image", ".pdf": "a PDF", ".svg": "an SVG image", ".html": "a web page",
    ".rrd": "a Rerun recording", ".zip": "a zip archive", ".gz": "a gzip file", ".xz": "an xz file",
    ".json": "JSON", ".toml": "TOML", ".yaml": "YAML", ".yml": "YAML", ".csv": "a CSV table",
}  # fmt: skip
#: The suffixes of :data:`_NAMED` under which an output of each kind is written (a document: as JSON).
_OWN_SUFFIXES = {
    "json": (".json",), "csv": (".csv",), "toml": (".toml",), "text": (".csv", ".json", ".toml"),
    "image": (".png", ".html"), "rrd": (".rrd",), "parquet": (".parquet",),
}  # fmt: skip
#: A JSON document's ``format``, where it opens with it (as sins writes its documents).
_FORMAT = re.compile(r'\A\ufeff?\s*\{\s*"format"\s*:\s*"([^"\\]*)"')
#: How JSON opens: an object's first key (or its end), an array's first value (or its end); not a TOML
#: table's ``[name]`` or ``[[name]]``.
_JSON_START = re.compile(r'\A\ufeff?\s*(\{\s*["}]|(\[\s*)+(\]|[-0-9"{]|true\b|false\b|null\b))')


def _holds(path: Path) -> str | None:
    """What an existing file holds, by its first 4 KiB: "empty", one of :data:`_DOCUMENTS`' formats,
    :data:`SINS_TEXT`, :data:`SINS_REPORT`, "JSON", "text", one of :data:`_SIGNATURES`' names, or "binary
    data"; None where it cannot be read."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096)
    except OSError:
        return None
    if not head:
        return "empty"
    for magic, what in _SIGNATURES:
        if head.startswith(magic):
            if magic == b"\x89PNG" and b"tEXtSoftware\x00sins" in head:
                return SINS_PNG
            if magic == b"RRF" and b"\n\x04sins" in head[:1024]:  # its store's application id, "sins"
                return SINS_RRD
            return what
    if b"\x00" in head:
        return "binary data"
    try:
        text = head.decode("utf-8")
    except UnicodeDecodeError as exc:
        if exc.start < len(head) - 4:  # not a character cut at the 4 KiB boundary
            return "binary data"
        text = head[: exc.start].decode("utf-8")
    document = _FORMAT.match(text)
    if document is not None and document.group(1) in _DOCUMENTS:
        return document.group(1)
    if document is not None and document.group(1).startswith("sins"):  # an inspection before the mark
        return SINS_REPORT
    if _SINS_LINE.match(text):
        return SINS_TEXT
    if _SINS_PAGE.match(text):
        return SINS_PAGE
    if _SINS_REPORT.match(text):
        return SINS_REPORT
    return "JSON" if _JSON_START.match(text) else "text"


def replaceable(path: Path, shown: str, kind: str) -> None:
    """Refuse to replace an existing file that holds what an output of ``kind`` (:data:`KINDS`, or a
    ``format`` of :data:`_DOCUMENTS`) never is: a recording, an archive or an image where JSON or text
    is written, text where an image is, a model where anything but a model is, and where a CSV table or
    an IMU file is written anything but a file sins wrote (:data:`SINS_TEXT`: a user's recording or
    scenario), and where a report or a model is written JSON sins did not write (:data:`SINS_REPORT`: a
    user's own). A mistyped or tab-completed output name would otherwise put a result where a user's
    recording, model or file was (the rename is atomic, and final). An empty file may be replaced by any.

    Raises
    ------
    SinsInputError
        ``shown: holds ...; sins writes ... there and does not replace it: ...``.
    """
    if kind not in _WRITES:
        raise ValueError(f"output kind {kind!r} (known: {', '.join(_WRITES)})")
    holds = _holds(path)
    allowed = _REPLACES.get(kind, (SINS_REPORT, kind))  # a document: a report or its own format
    if holds is None or holds == "empty" or holds in allowed:
        return
    seen = {
        "text": "text that is not JSON", "a PNG image": "a PNG image sins did not draw (a picture of yours?)",
        "a Rerun recording": "a Rerun recording of another application", **_DOCUMENTS,
    }.get(holds, holds)  # fmt: skip
    if kind in ("csv", "toml") and holds in ("text", "JSON"):
        seen = "text sins did not write (a recording, table or scenario of yours?)"
    elif kind in ("image", "rrd") and holds in ("text", "JSON"):
        seen = "text sins did not write (a page or notes of yours?)"
    elif holds == "JSON":  # where a report or a model goes
        seen = 'JSON sins did not write (a file of yours? a report of an older sins, without "sins" first?)'
    raise SinsInputError(
        f"{shown}: holds {seen}; sins writes {_WRITES[kind]} there and does not replace it: remove it "
        "or write elsewhere"
    )


def check_named(path: str | os.PathLike[str], kind: str, flag: str = "") -> None:
    """Refuse an output of ``kind`` (:data:`KINDS`, or a document's ``format``) whose name ends in a
    suffix that names another format (:data:`_NAMED`): ``corrected.npz`` for CSV text, ``m.csv`` for a
    model. A suffix that names no format (``.txt``, ``.dat``, none) is the user's to choose.

    Raises
    ------
    SinsInputError
        ``[flag ]path: .npz names a NumPy archive; sins writes a CSV table there: name it .csv``.
    """
    own = _OWN_SUFFIXES.get(kind, _OWN_SUFFIXES["json"])  # a document is JSON
    suffix = Path(path).suffix.lower()
    if suffix in _NAMED and suffix not in own:
        shown = f"{flag} {path}" if flag else f"{path}"
        raise SinsInputError(
            f"{shown}: {suffix} names {_NAMED[suffix]}; sins writes {_WRITES[kind]} there: name it {own[0]}"
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
    if not os.fspath(path).strip():  # Path("") is ".", the working folder: name what was given
        raise SinsInputError(f"{flag or 'output'}: an empty name, expected a file name to write")
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
        own_stream(path, shown)
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


def _campaign_of(real: str) -> Path | None:
    """The campaign results folder that holds the file at ``real`` (its folder or the one above, where
    a ``campaign.json`` of :data:`CAMPAIGN_FORMAT` is), or None."""
    for folder in list(Path(real).parents)[:2]:
        try:
            head = (folder / "campaign.json").read_bytes()[:4096].decode("utf-8", "replace")
        except OSError:
            continue
        found = _FORMAT.match(head)
        if found is not None and found.group(1) == CAMPAIGN_FORMAT:
            return folder
    return None


def _inside(folder: str, path: str) -> bool:
    return path != folder and path.startswith(folder.rstrip(os.sep) + os.sep)


def check_outputs(
    outputs: Mapping[str, str | os.PathLike[str] | None],
    inputs: Iterable[str | os.PathLike[str] | None] = (),
    folders: Mapping[str, str | os.PathLike[str] | None] | None = None,
    kinds: Mapping[str, str] | None = None,
) -> None:
    """The one check of a command's outputs before its work (see the module docstring).

    Parameters
    ----------
    outputs : ``{flag: path}`` of the files the command will write (None: not asked for)
    inputs : every file and folder it reads (None entries skipped)
    folders : ``{flag: path}`` of folders it writes into (a campaign's results)
    kinds : ``{flag: kind}`` (:data:`KINDS`): what each output is, so that a name whose suffix names
        another format (:func:`check_named`) and an existing file holding what it never is (a recording
        where JSON goes, :func:`replaceable`) are refused

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
        campaign = _campaign_of(real)
        if campaign is not None and not any(_inside(os.path.realpath(d), real) for d in dirs.values()):
            raise SinsInputError(
                f"{flag} {path}: is in the results folder of a campaign ({campaign}), which only that "
                "campaign writes (sins campaign --out, --resume): write elsewhere"
            )
        kind = (kinds or {}).get(flag)
        if kind is not None:  # after the inputs, and a file held before its name: each says more
            if os.path.isfile(real):
                replaceable(Path(real), f"{flag} {path}", kind)
            check_named(path, kind, flag)
    deferred.declare(target(p) for p in files.values() if not writes_in_place(p))
    for flag, path in dirs.items():
        real = os.path.realpath(path)
        for source, _, source_real in read:
            if real == source_real:
                raise SinsInputError(
                    f"{flag} {path}: is an input of this command ({source}); write elsewhere"
                )


__all__ = [
    "CAMPAIGN_FORMAT",
    "KINDS",
    "READ_FACTOR",
    "REPORT_KEY",
    "SINS_PAGE",
    "SINS_PNG",
    "SINS_REPORT",
    "SINS_RRD",
    "SINS_TEXT",
    "check_input",
    "check_named",
    "check_outputs",
    "check_writable",
    "own_stream",
    "read_only",
    "replaceable",
    "target",
    "writes_in_place",
]
