"""sins's own JSON files: written atomically, read back only when their ``"format"`` says what they are.

Model files, quality baselines, campaign summaries and folders are JSON objects with a ``"format"`` key
naming the kind; :func:`read_json_document` refuses any other file in one line (through
:func:`sins.io.documents.read_json`, the one reader of every JSON file), and :func:`write_json` writes
through :func:`sins.io.atomic.atomic_text`. A command's JSON report (``--json``) opens with the key
``"sins"`` (:func:`write_report`): the mark by which a later report knows a file sins wrote, which it may
replace, from a user's own JSON, which it does not (:func:`sins.io.paths.replaceable`). A report is
read by other programs (jq, JavaScript), whose JSON has no ``NaN`` nor ``Infinity``: a figure that is
not finite is written ``null`` there (sins's own files keep them: :func:`read_json_document` reads
them back as written).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from sins.errors import SinsInputError
from sins.io import documents
from sins.io.atomic import atomic_text
from sins.io.paths import REPORT_KEY, check_named


def write_json(path: str | os.PathLike[str], obj: Any, *, strict: bool = False) -> None:
    """Write JSON (indented, keys in insertion order) to a temporary name then rename; a name that says
    another format (``m.csv``, ``m.npz``) is refused (:func:`sins.io.paths.check_named`). ``strict``:
    every float that is not finite written ``null`` (standard JSON), else ``NaN``/``Infinity`` as Python
    writes them (sins's own files, read back as they were: a model file's, a summary's NaN)."""
    check_named(path, "json")
    doc = _finite_or_null(obj) if strict else obj
    with atomic_text(path) as fh:
        json.dump(doc, fh, indent=2, allow_nan=not strict)
        fh.write("\n")


def _finite_or_null(obj: Any) -> Any:
    """``obj`` with every float that is not finite (NaN, ±inf; numpy's included) as None, through dicts,
    lists and tuples."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, Mapping):
        return {k: _finite_or_null(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite_or_null(v) for v in obj]
    return obj


def write_report(path: str | os.PathLike[str], doc: Mapping[str, Any]) -> None:
    """A command's JSON report: ``doc`` after a first key :data:`REPORT_KEY` (``"sins": VERSION``), written
    as :func:`write_json` writes with ``strict``: standard JSON, a figure that is not finite ``null``
    (``sins bias``'s level rate ratio of a referenced rest is NaN: no JSON reader outside Python takes
    ``NaN``). The key is what marks the file as sins's: a report run again replaces
    it, and no report replaces a JSON file that lacks it (a user's own)."""
    from sins import __version__  # here, not at import: sins's package imports io lazily

    write_json(
        path, {REPORT_KEY: __version__, **{k: v for k, v in doc.items() if k != REPORT_KEY}}, strict=True
    )


def read_json_document(
    path: str | os.PathLike[str], what: str, format_name: str, missing_hint: str = ""
) -> dict[str, Any]:
    """A JSON object whose ``"format"`` is ``format_name``; one-line errors for anything else.

    ``what`` names the kind of file in messages ("model file", "baseline");
    ``missing_hint`` is added when the file does not exist.

    Raises
    ------
    SinsInputError
        one line naming the file: missing or unreadable, not JSON (as
        :func:`sins.io.documents.read_json` refuses it), or not an object whose ``"format"`` is
        ``format_name``.
    """
    path = Path(path)
    doc = documents.read_json(path, what, missing_hint)  # the one reader: one line whatever the bytes
    if not isinstance(doc, dict) or doc.get("format") != format_name:
        raise SinsInputError(f'{path}: not a sins {what} (no "format": "{format_name}")')
    return doc


__all__ = ["REPORT_KEY", "read_json_document", "write_json", "write_report"]
