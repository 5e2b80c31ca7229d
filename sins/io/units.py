"""The units a recording's columns may be in, and the ``units`` option that names them.

A ``units`` text is ``key=unit`` pairs separated by commas (``t=ms,gyro=deg/s,accel=g``); each key is
a group of columns: ``t``; ``gyro`` and ``accel`` (rate form); ``dtheta`` and ``dv`` (increment form);
``temp``. A key left out keeps sins's own unit (:data:`SI`). Every unit a key accepts is in
:data:`UNITS` (with the spellings of :data:`ALIASES`); ``g`` is standard gravity, 9.80665 m/s², as in
data sheets, not the local gravity.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from sins.core.earth import G0
from sins.errors import SinsInputError

#: Per key, each unit's factor into sins's unit (a value in the unit times the factor is SI).
UNITS: dict[str, dict[str, float]] = {
    "t": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "min": 60.0, "h": 3600.0},
    "gyro": {
        "rad/s": 1.0, "mrad/s": 1e-3, "deg/s": math.pi / 180.0, "deg/h": math.pi / 180.0 / 3600.0,
        "rev/s": 2.0 * math.pi, "rpm": 2.0 * math.pi / 60.0,
    },
    "accel": {"m/s^2": 1.0, "cm/s^2": 1e-2, "ft/s^2": 0.3048, "g": G0, "mg": G0 * 1e-3, "ug": G0 * 1e-6},
    "dtheta": {
        "rad": 1.0, "mrad": 1e-3, "urad": 1e-6, "deg": math.pi / 180.0, "arcsec": math.pi / 648000.0,
    },
    "dv": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3, "ft/s": 0.3048, "g*s": G0, "mg*s": G0 * 1e-3,
           "ug*s": G0 * 1e-6},
    "temp": {"degC": 1.0, "K": 1.0, "degF": 5.0 / 9.0},
}  # fmt: skip

#: Temperature offsets: °C = factor × value + offset.
TEMP_OFFSET = {"degC": 0.0, "K": -273.15, "degF": -32.0 * 5.0 / 9.0}

#: sins's own unit per key.
SI = {"t": "s", "gyro": "rad/s", "accel": "m/s^2", "dtheta": "rad", "dv": "m/s", "temp": "degC"}

#: Other spellings of the units, and what they mean.
ALIASES = {
    "sec": "s", "msec": "ms", "µs": "us", "usec": "us", "nsec": "ns",
    "rad/sec": "rad/s", "°/s": "deg/s", "dps": "deg/s", "deg/sec": "deg/s", "°/h": "deg/h", "dph": "deg/h",
    "m/s2": "m/s^2", "m/s²": "m/s^2", "cm/s2": "cm/s^2", "cm/s²": "cm/s^2", "ft/s2": "ft/s^2",
    "ft/s²": "ft/s^2", "µg": "ug", "°": "deg", "µrad": "urad", "g·s": "g*s", "mg·s": "mg*s",
    "ug·s": "ug*s", "µg·s": "ug*s", "µg*s": "ug*s", "°C": "degC", "C": "degC", "°F": "degF", "F": "degF",
}  # fmt: skip

#: Which key each sins column belongs to.
KEY_OF = {
    "t": "t", "temp": "temp",
    **{f"gyro_{a}": "gyro" for a in "xyz"}, **{f"accel_{a}": "accel" for a in "xyz"},
    **{f"dtheta_{a}": "dtheta" for a in "xyz"}, **{f"dv_{a}": "dv" for a in "xyz"},
}  # fmt: skip

#: The keys each IMU form may use.
FORM_KEYS = {"rate": ("t", "gyro", "accel", "temp"), "increment": ("t", "dtheta", "dv", "temp")}


def canonical(key: str, unit: str) -> str:
    """``unit``'s name in :data:`UNITS` for ``key``, or a one-line error listing the accepted ones."""
    name = ALIASES.get(unit, unit)
    if key not in UNITS:
        raise SinsInputError(f"units: unknown key {key!r} (keys: {', '.join(UNITS)})")
    if name not in UNITS[key]:
        raise SinsInputError(
            f"units: {key}={unit!r} is not a unit sins knows for {key} (accepted: {', '.join(UNITS[key])})"
        )
    return name


def parse_units(spec: str | Mapping[str, str] | None) -> dict[str, str]:
    """``{key: unit}`` (canonical names) from ``"t=ms,gyro=deg/s"`` or a mapping; ``{}`` for None.

    Raises
    ------
    SinsInputError
        a pair without ``=``, a key given twice, an unknown key or unit (naming the accepted ones).
    """
    if spec is None:
        return {}
    pairs = list(spec.items()) if isinstance(spec, Mapping) else parse_pairs(spec, "units")
    out: dict[str, str] = {}
    for key, unit in pairs:
        if key in out:
            raise SinsInputError(f"units: key {key!r} given twice")
        out[key] = canonical(key, unit)
    return out


def check_form(units: Mapping[str, str], form: str, source: str) -> None:
    """Refuse keys of the other IMU form (``gyro`` for increments, ``dv`` for rates)."""
    for key in units:
        if key not in FORM_KEYS[form]:
            raise SinsInputError(
                f"units: key {key!r} does not apply: {source} is in {form} form "
                f"(keys {', '.join(FORM_KEYS[form])})"
            )


def factor(units: Mapping[str, str], key: str) -> float:
    """The factor into SI of ``key``'s unit in ``units`` (1 where the key is left out)."""
    return UNITS[key][units.get(key, SI[key])]


def spec_text(units: Mapping[str, str]) -> str:
    """``units`` written back as the option's text (``t=ms,gyro=deg/s``)."""
    return ",".join(f"{k}={v}" for k, v in units.items())


def parse_pairs(spec: str, option: str) -> list[tuple[str, str]]:
    """``[(key, value)]`` from an option's ``"k=v,k=v"`` text (white space around each part ignored), or
    a one-line error naming ``option``."""
    pairs = []
    for part in str(spec).split(","):
        if not part.strip():
            continue
        key, sep, value = part.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise SinsInputError(f"{option}: expected key=value pairs separated by commas, found {part!r}")
        pairs.append((key.strip(), value.strip()))
    if not pairs:
        raise SinsInputError(f"{option}: empty; expected key=value pairs separated by commas")
    return pairs


__all__ = [
    "ALIASES",
    "FORM_KEYS",
    "KEY_OF",
    "SI",
    "TEMP_OFFSET",
    "UNITS",
    "canonical",
    "check_form",
    "factor",
    "parse_pairs",
    "parse_units",
    "spec_text",
]
