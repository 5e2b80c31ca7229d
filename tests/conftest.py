"""Helpers shared by the test modules."""

from __future__ import annotations

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


@pytest.fixture(autouse=True, scope="session")
def _torch_on_one_thread() -> None:
    """Tests use one thread for torch (reproducible, and fair to a 2-core CI machine)."""
    try:
        import torch
    except ImportError:
        return
    torch.set_num_threads(1)
