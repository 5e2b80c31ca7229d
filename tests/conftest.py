"""Helpers shared by the test modules."""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from sins.errors import SinsInputError
from sins.io.datasets.root import data_root


def dataset_folder(name: str) -> Path:
    """A dataset's folder under the data root, or a placeholder path when the root cannot be
    resolved (the working directory is gone, say): the data tests then skip, naming it."""
    try:
        return data_root() / name
    except OSError:
        return Path("(no data root)")


def refusal(call: Callable[[], Any], *fragments: str) -> str:
    """Run ``call``, expect a one-line SinsInputError containing every fragment; return the message."""
    with pytest.raises(SinsInputError) as info:
        call()
    message = str(info.value)
    assert "\n" not in message and "\r" not in message, message
    for fragment in fragments:
        assert fragment in message, f"{fragment!r} not in {message!r}"
    return message


# Tests use one thread for torch (reproducible, and fair to a 2-core CI machine). torch reads
# OMP_NUM_THREADS when it is first imported, so setting it here covers a test that imports torch
# itself; importing torch here instead would put ~230 MB into every test process, the many that
# never touch it included. Set, not defaulted: a shell's own value would give that first test more.
os.environ["OMP_NUM_THREADS"] = "1"


def pytest_runtest_setup(item: pytest.Item) -> None:
    """Hold torch at one thread where an earlier test set it otherwise."""
    torch = sys.modules.get("torch")
    if torch is not None and torch.get_num_threads() != 1:
        torch.set_num_threads(1)
