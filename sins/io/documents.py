"""JSON and TOML documents, read through one reader: whatever the bytes, a value or one line.

Python's parsers raise more than their own error types on hostile input: ``RecursionError`` on arrays
nested a few thousand deep (TOML) or a hundred thousand (JSON); ``ValueError`` on an integer of more
than 4,300 digits (CPython's limit on converting long digit strings) and on a path with a NUL byte.
:func:`read_json` and :func:`read_toml` turn each into one :class:`~sins.errors.SinsInputError` line
naming the file, and refuse, naming the place in the document:

* nesting deeper than :data:`MAX_DEPTH` (a sins document nests a dozen levels at most);
* an integer outside 64 bits (no sins file holds one, and a float made of one overflows far from the
  file, in whatever computation first meets it);
* a NUL byte in any string or key (it would end a file name short, or fail where one is opened).

Every JSON and TOML file sins reads goes through here: scenario, IMU, rig, campaign and suite files
(:func:`sins.scenario.read_toml`), model files, baselines, summaries and campaign folders
(:func:`sins.io.read_json_document`), and the Ferraris dataset's section list.
"""

from __future__ import annotations

import json
import os
import reprlib
import stat
import tomllib
from pathlib import Path
from typing import Any

from sins.errors import SinsInputError
from sins.io.paths import check_input

#: The deepest nesting of tables and arrays a document may have (a model file's maps nest 10 deep).
MAX_DEPTH = 64
#: The integers a document may hold: what a TOML integer (64-bit signed) and an unsigned 64-bit seed take.
INT_RANGE = (-(2**63), 2**64 - 1)
#: The largest document read, bytes: a campaign summary of 100,000 units is ~80 MB; parsed, a document
#: takes ~10 times its size in memory.
MAX_BYTES = 256 * 1024 * 1024


def read_toml(path: str | os.PathLike[str], what: str) -> dict[str, Any]:
    """A TOML file parsed; one-line errors name the file and ``what`` kind of file it is.

    Raises
    ------
    SinsInputError
        the file is missing, unreadable, not UTF-8, not valid TOML, nested too deep, or holds an
        integer beyond 64 bits or a NUL byte in a string or key.
    """
    path = _path(path, what)
    raw = _read_bytes(path, f"{what} file")
    try:
        doc = tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as exc:
        raise SinsInputError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except tomllib.TOMLDecodeError as exc:
        raise SinsInputError(f"{path}: invalid TOML: {_one_line(str(exc))}") from None
    except RecursionError:
        raise SinsInputError(f"{path}: invalid TOML: nested deeper than {MAX_DEPTH} levels") from None
    except ValueError as exc:  # an integer of more digits than Python converts
        raise SinsInputError(f"{path}: invalid TOML: {_why(exc)}") from None
    check_document(doc, str(path))
    return doc


def read_json(path: str | os.PathLike[str], what: str, missing_hint: str = "", sins: bool = True) -> Any:
    """A JSON file parsed (``NaN`` and ``Infinity`` taken, as sins writes them).

    ``what`` names the kind of file ("model file", "campaign summary"; a file of sins's own format
    unless ``sins`` is false); ``missing_hint`` is added when the file does not exist.

    Raises
    ------
    SinsInputError
        ``PATH: no such WHAT``, ``PATH:LINE: not a sins WHAT (not JSON: why, column C)`` or ``PATH: not a
        sins WHAT (why)``: the file is missing, unreadable, not UTF-8, not JSON, nested too deep, or holds
        an integer beyond 64 bits or a NUL byte in a string or key.
    """
    path = _path(path, what)
    try:
        raw = _read_bytes(path, what)
    except SinsInputError as exc:
        if missing_hint and not path.exists():
            raise SinsInputError(f"{exc} ({missing_hint})") from None
        raise
    noun = f"sins {what}" if sins else what
    try:
        # utf-8-sig: a byte-order mark an editor added is read past, as the CSV readers do.
        doc = json.loads(raw.decode("utf-8-sig"), object_pairs_hook=_unique)
    except _TwiceError as exc:
        raise SinsInputError(f"{path}: not a {noun} ({exc})") from None
    except UnicodeDecodeError as exc:
        why = f"not UTF-8: {exc.reason} at byte {exc.start}"
        raise SinsInputError(f"{path}: not a {noun} ({why})") from None
    except RecursionError:
        raise SinsInputError(f"{path}: not a {noun} (nested deeper than {MAX_DEPTH} levels)") from None
    except json.JSONDecodeError as exc:
        raise SinsInputError(
            f"{path}:{exc.lineno}: not a {noun} (not JSON: {exc.msg}, column {exc.colno})"
        ) from None
    except ValueError as exc:  # an integer of more digits than Python converts
        raise SinsInputError(f"{path}: not a {noun} ({_why(exc)})") from None
    check_document(doc, str(path))
    return doc


def check_document(doc: Any, source: str) -> None:
    """Refuse nesting deeper than :data:`MAX_DEPTH`, an integer outside :data:`INT_RANGE` and a NUL
    byte in a string or key, naming ``source`` and the place (``a.b[3]``). Iterative: a document nested
    deeper than Python recurses is refused, not a ``RecursionError``; a place is spelt only for an error."""
    if _bad(doc):
        raise SinsInputError(f"{source}: the document: {_bad(doc)}")
    stack: list[tuple[dict[Any, Any] | list[Any], str, int]] = []
    if isinstance(doc, dict | list):
        stack.append((doc, "", 1))
    while stack:
        container, place, depth = stack.pop()
        in_list = isinstance(container, list)
        for key, item in enumerate(container) if in_list else container.items():  # type: ignore[union-attr]
            if isinstance(key, str) and "\0" in key:
                raise SinsInputError(f"{source}: {place or 'the document'}: a key holds a NUL byte")
            if type(item) is float:  # most of a document's values (a summary's): nothing to check
                continue
            if isinstance(item, dict | list):
                inner = _place(place, key, in_list)
                if depth >= MAX_DEPTH:
                    raise SinsInputError(f"{source}: {inner}: nested deeper than {MAX_DEPTH} levels")
                stack.append((item, inner, depth + 1))
            elif isinstance(item, str | int) and (why := _bad(item)):
                raise SinsInputError(f"{source}: {_place(place, key, in_list)}: {why}")


def _place(place: str, key: Any, in_list: bool) -> str:
    """The dotted place of ``key`` within ``place``: ``a.b``, ``a[3]``."""
    if in_list:
        return f"{place}[{key}]"
    return f"{place}.{printable(key)}" if place else printable(key)


def _bad(value: Any) -> str:
    """Why a scalar may not be in a document ("" if it may)."""
    if isinstance(value, str) and "\0" in value:
        return "the text holds a NUL byte"
    if isinstance(value, int) and not isinstance(value, bool) and not INT_RANGE[0] <= value <= INT_RANGE[1]:
        return "the integer is beyond 64 bits"
    return ""


_SHORT = reprlib.Repr()
_SHORT.maxlevel, _SHORT.maxlist, _SHORT.maxdict, _SHORT.maxstring, _SHORT.maxother = 2, 6, 4, 40, 40


def short(value: Any, limit: int = 80) -> str:
    """A value from a file, for a one-line message: its ``repr`` bounded as it is made (a huge array
    costs no more than a number), escaped, and cut to ``limit`` characters."""
    text = printable(_SHORT.repr(value))
    return text if len(text) <= limit else text[: limit - 3] + "..."


def printable(text: str) -> str:
    """``text`` with line breaks and other control characters escaped (``\\n``, ``\\x00``): a key or
    name from a file put in a one-line message stays one line."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)


def _path(path: str | os.PathLike[str], what: str) -> Path:
    text = os.fspath(path)
    if "\0" in str(text):
        raise SinsInputError(f"{printable(str(text))}: a {what} path cannot hold a NUL byte")
    return Path(text)


def with_article(noun: str) -> str:
    """``noun`` with its article: "an IMU file", "a rig file"."""
    return f"{'an' if noun[:1] in 'AEIOUaeiou' else 'a'} {noun}"


def _read_bytes(path: Path, noun: str) -> bytes:
    """The file's bytes. Its kind is looked at before it is opened: opening a pipe waits for a writer,
    and reading ``/dev/zero`` never ends."""
    try:
        info = path.stat()
        if stat.S_ISDIR(info.st_mode):
            raise SinsInputError(f"{path}: is a directory, expected {with_article(noun)}")
        check_input(path)  # a FIFO or a device, refused before it is opened
        if info.st_size > MAX_BYTES:
            raise SinsInputError(
                f"{path}: {info.st_size} bytes, more than {with_article(noun)} may hold ({MAX_BYTES})"
            )
        return path.read_bytes()
    except FileNotFoundError:
        raise SinsInputError(f"{path}: no such {noun}") from None
    except OSError as exc:
        raise SinsInputError(f"{path}: cannot read: {exc.strerror or exc}") from None


class _TwiceError(ValueError):
    """A key given twice in one JSON object."""


def _unique(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object's pairs as a dict, refusing a key given twice: Python's parser keeps the last one
    and drops the first without a word (a model file edited by hand, two ``"B_"``)."""
    out = dict(pairs)
    if len(out) < len(pairs):
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                raise _TwiceError(f"the key {short(key)} twice in one object")
            seen.add(key)
    return out


def _why(exc: ValueError) -> str:
    """A parser's ValueError in a user's words (CPython's digit limit advises a call to raise it)."""
    if "integer string conversion" in str(exc):
        return "an integer of more than 4300 digits"
    return _one_line(str(exc))


def _one_line(text: str) -> str:
    return " ".join(printable(part) for part in text.split())


__all__ = [
    "INT_RANGE",
    "MAX_BYTES",
    "MAX_DEPTH",
    "check_document",
    "printable",
    "read_json",
    "read_toml",
    "short",
    "with_article",
]
