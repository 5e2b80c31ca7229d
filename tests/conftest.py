"""Helpers shared by the test modules."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from sins.errors import SinsInputError


def refusal(call: Callable[[], Any], *fragments: str) -> str:
    """Run ``call``, expect a one-line SinsInputError containing every fragment; return the message."""
    with pytest.raises(SinsInputError) as info:
        call()
    message = str(info.value)
    assert "\n" not in message and "\r" not in message, message
    for fragment in fragments:
        assert fragment in message, f"{fragment!r} not in {message!r}"
    return message
