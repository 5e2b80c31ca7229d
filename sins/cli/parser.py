"""The argument parser of ``sins`` and of each command: whole option names only, and one line for every
refusal, as the commands' own refusals are."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any, NoReturn


def path(text: str) -> Path:
    """A path given on the command line; an empty one refused (``Path("")`` is ``.``, the working folder,
    which a file output then called "a directory" and an input read as a folder)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty path")
    return Path(text)


class Parser(argparse.ArgumentParser):
    """Options by their whole names only (inspect's ``--truth`` had been taken for ``--truth-topic``), and
    an option refused in one line that points at the help, where argparse printed its usage first
    (``sins bias --seconds 0``: eleven lines, where ``--lat 95`` took one)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **{**kwargs, "allow_abbrev": False})

    def add_argument(self, *args: Any, **kwargs: Any) -> Any:
        """As argparse's, with ``type=Path`` read by :func:`path` (an empty path refused)."""
        if kwargs.get("type") is Path:
            kwargs["type"] = path
        return super().add_argument(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        """``PROG: error: MESSAGE (PROG --help)`` on stderr, exit 2."""
        self.exit(2, f"{self.prog}: error: {message} ({self.prog} --help)\n")


__all__ = [
    "Parser",
    "path",
]
