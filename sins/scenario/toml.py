"""TOML files read into typed values, with one-line errors that name the file and the key.

:class:`TomlKeys` wraps one table: each accessor checks a key's type and range and marks it used, and
:meth:`TomlKeys.done` refuses the keys nobody read. Scenario, IMU, rig and quality-suite files are all
read through it.
"""

from __future__ import annotations

import difflib
import math
from pathlib import Path
from typing import Any, NamedTuple, TypeVar

from sins.errors import SinsInputError
from sins.io import documents
from sins.io.documents import short

_MISSING: Any = object()

_S = TypeVar("_S", bound=str)


class Bound(NamedTuple):
    """The range a numeric field must lie in (closed unless ``*_open``), its unit, and why.

    The bounds are listed per file in the guide (``docs/guide/scenarios.md``), and
    ``tests/test_bounds.py`` walks every one; seeds and counts are read by :meth:`TomlKeys.integer`.
    """

    low: float
    high: float
    unit: str = ""
    why: str = ""
    low_open: bool = False
    high_open: bool = False


#: The largest seed: what numpy's generators and a TOML integer (64-bit signed) both take.
MAX_SEED = 2**63 - 1


class TomlKeys:
    """Typed access to one TOML table that remembers which keys were used.

    Parameters
    ----------
    source : the file's name, first in every error
    where : the table's dotted place in the file ("" for the top level)
    table : the parsed table; anything else is refused
    """

    def __init__(self, source: str, where: str, table: Any) -> None:
        self.source = source
        self.where = where
        if not isinstance(table, dict):
            raise self.error(f"expected a table, got {_kind(table)}")
        self.table = table
        self.used: set[str] = set()
        self.asked: set[str] = set()  # every key looked for, there or not: the keys this table takes

    def error(self, message: str, key: str | None = None) -> SinsInputError:
        """The one-line error to raise for ``key`` (or the table), naming the file and key."""
        place = f"{self.where}.{key}" if key and self.where else (key or self.where)
        return SinsInputError(f"{self.source}: {place}: {message}" if place else f"{self.source}: {message}")

    def has(self, key: str) -> bool:
        """Whether the table has ``key`` (without marking it used; it is one the table takes)."""
        self.asked.add(key)
        return key in self.table

    def _default(self, key: str, default: Any) -> Any:
        """The default for an absent key, or the error for an absent required one."""
        if default is _MISSING:
            given = [k for k in self.table if k not in self.asked]  # not read yet: perhaps a misspelling
            near = difflib.get_close_matches(key, given, n=1, cutoff=0.85)
            hint = f" ({near[0]!r} is given: misspelt?)" if near else ""
            raise self.error(f"missing required key{hint}", key)
        return default

    def get(self, key: str) -> Any:
        """The raw value of ``key``, marked as used."""
        self.used.add(key)
        return self.table[key]

    def number(
        self,
        key: str,
        default: Any = _MISSING,
        *,
        low: float | None = None,
        high: float | None = None,
        low_open: bool = False,
        high_open: bool = False,
    ) -> float:
        """A finite number within ``low`` and ``high`` (open where ``*_open``); ``default`` if absent."""
        if not self.has(key):
            return float(self._default(key, default))
        value = self.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(f"expected a number, got {_kind(value)} {short(value)}", key)
        try:
            value = float(value)
        except OverflowError:
            raise self.error("number too large", key) from None
        if not math.isfinite(value):
            raise self.error(f"must be finite, got {short(value)}", key)
        value += 0.0  # -0.0 becomes 0.0: numpy's samplers refuse a "negative" zero spread
        if low is not None and (value < low or (low_open and value == low)):
            raise self.error(f"must be {'>' if low_open else '>='} {low:g}, got {value:g}", key)
        if high is not None and (value > high or (high_open and value == high)):
            raise self.error(f"must be {'<' if high_open else '<='} {high:g}, got {value:g}", key)
        return value

    def bounded(self, key: str, bound: Bound, default: Any = _MISSING) -> float:
        """A finite number within ``bound``; ``default`` if absent. The message of a value outside
        gives the bound, its unit and why it is there."""
        value = self.number(key, default)
        if self.has(key):
            self._check_bound(key, value, bound)
        return value

    def _check_bound(self, key: str, value: float, bound: Bound, item: str = "") -> None:
        unit = f" {bound.unit}" if bound.unit else ""
        why = f" ({bound.why})" if bound.why else ""
        if value < bound.low or (bound.low_open and value == bound.low):
            raise self.error(f"{item}must be {'>' if bound.low_open else '>='} {bound.low:g}{unit}{why}, "
                             f"got {value:g}", key)  # fmt: skip
        if value > bound.high or (bound.high_open and value == bound.high):
            raise self.error(f"{item}must be {'<' if bound.high_open else '<='} {bound.high:g}{unit}{why}, "
                             f"got {value:g}", key)  # fmt: skip

    def bounded_numbers(self, key: str, bound: Bound, default: Any = _MISSING) -> list[float]:
        """A non-empty array of finite numbers, each within ``bound``; ``default`` if absent."""
        values = self.numbers(key, default)
        if self.has(key):
            for i, v in enumerate(values):
                self._check_bound(key, v, bound, f"item {i + 1}: ")
        return values

    def integer(self, key: str, default: int, low: int = 0, high: int = MAX_SEED) -> int:
        """A whole number in ``[low, high]`` (a seed, a count); ``default`` if absent.

        A float with a whole value (``3.0``) is taken; ``1.5``, ``1e300`` or a boolean are refused.
        """
        if not self.has(key):
            return default
        value = self.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(f"expected a whole number, got {_kind(value)} {short(value)}", key)
        if isinstance(value, float) and not (math.isfinite(value) and value == math.floor(value)):
            raise self.error(f"expected a whole number, got {short(value)}", key)
        if not low <= value <= high:
            raise self.error(f"must be in [{low}, {high}], got {value:g}", key)
        return int(value)

    def string(self, key: str, default: Any = _MISSING, choices: tuple[str, ...] = ()) -> str:
        """A string, one of ``choices`` when given; ``default`` if absent."""
        if not self.has(key):
            return str(self._default(key, default))
        value = self.get(key)
        if not isinstance(value, str):
            raise self.error(f"expected a string, got {_kind(value)} {short(value)}", key)
        if choices and value not in choices:
            raise self.error(f"must be one of {', '.join(choices)}; got {short(value)}", key)
        return value

    def choice(self, key: str, choices: tuple[_S, ...], default: Any = _MISSING) -> _S:
        """One of ``choices`` (a ``Literal``'s values), typed as that ``Literal``; ``default`` if absent.

        The same checks and messages as :meth:`string` with ``choices``.
        """
        value = self.string(key, default, choices)
        # The element of ``choices`` equal to the value carries the Literal type; no cast needed.
        return choices[choices.index(value)]

    def numbers(self, key: str, default: Any = _MISSING) -> list[float]:
        """A non-empty array of finite numbers."""
        if not self.has(key):
            return list(self._default(key, default))
        value = self.get(key)
        if not isinstance(value, list) or not value:
            raise self.error(f"expected a non-empty array of numbers, got {_kind(value)}", key)
        out = []
        for i, item in enumerate(value):
            if isinstance(item, bool) or not isinstance(item, int | float) or not math.isfinite(float(item)):
                raise self.error(f"item {i + 1}: expected a finite number, got {short(item)}", key)
            out.append(float(item))
        return out

    def strings(self, key: str, default: Any = _MISSING, choices: tuple[str, ...] = ()) -> list[str]:
        """An array of strings, each among ``choices`` when given, none twice."""
        if not self.has(key):
            return list(self._default(key, default))
        value = self.get(key)
        if not isinstance(value, list):
            raise self.error(f"expected an array of strings, got {_kind(value)}", key)
        allowed = f" (one of {', '.join(choices)})" if choices else ""
        for i, item in enumerate(value):
            if not isinstance(item, str):
                raise self.error(f"item {i + 1}: expected a string{allowed}, got {short(item)}", key)
            if choices and item not in choices:
                raise self.error(f"item {i + 1}: {short(item)} is not a known name{allowed}", key)
            if item in value[:i]:  # a second run of the same name, silently merged before
                raise self.error(f"item {i + 1}: {short(item)} is given twice", key)
        return list(value)

    def boolean(self, key: str, default: bool) -> bool:
        """A boolean; ``default`` if absent."""
        if not self.has(key):
            return default
        value = self.get(key)
        if not isinstance(value, bool):
            raise self.error(f"expected true or false, got {_kind(value)} {short(value)}", key)
        return value

    def tables(self, key: str) -> list[TomlKeys]:
        """The array of tables ``[[key]]``, each as a :class:`TomlKeys`; empty if absent."""
        if not self.has(key):
            return []
        value = self.get(key)
        if not isinstance(value, list):
            raise self.error(f"expected an array of tables ([[{key}]]), got {_kind(value)}", key)
        return [TomlKeys(self.source, f"{key}[{i + 1}]", item) for i, item in enumerate(value)]

    def sub(self, key: str) -> TomlKeys:
        """The sub-table ``key`` as a :class:`TomlKeys` (empty if absent)."""
        value = self.get(key) if self.has(key) else {}
        return TomlKeys(self.source, key, value)

    def done(self, allowed: tuple[str, ...] = ()) -> None:
        """Refuse keys that were never read (unknown or not valid in this context)."""
        for key in self.table:
            if key not in self.used and key not in allowed:
                known = ", ".join(sorted(self.asked | set(allowed))) or "none"
                raise self.error(f"unknown key (keys taken here: {known})", key)


def _kind(value: Any) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "an array",
            dict: "a table"}.get(type(value), type(value).__name__)  # fmt: skip


def read_toml(path: Path, what: str) -> dict[str, Any]:
    """A TOML file parsed; one-line errors name the file and ``what`` kind of file it is
    (:func:`sins.io.documents.read_toml`, the one reader of every TOML file).

    Parameters
    ----------
    path : the file
    what : the kind of file, for the messages ("scenario", "IMU", "rig", "suite")

    Raises
    ------
    SinsInputError
        the file is missing, unreadable, not UTF-8 or not valid TOML, nested too deep, or holds an
        integer beyond 64 bits or a NUL byte.
    """
    return documents.read_toml(path, what)


__all__ = [
    "MAX_SEED",
    "Bound",
    "TomlKeys",
    "read_toml",
]
