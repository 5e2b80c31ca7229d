"""A CSV recording with its own column names and units.

``columns`` maps sins's column names to the file's: ``t=time,gyro_x=wx,gyro_y=wy,...`` (``sins name=file
column``, separated by commas); a sins name left out is looked for under its own name. The sins names
are those of the IMU forms (``t``, ``gyro_x`` … ``accel_z`` or ``dtheta_x`` … ``dv_z``) and ``temp``;
the names given decide the form. ``units`` (:mod:`sins.io.units`) gives the units. Without a time
column, the sampling rate gives the times (``k / rate`` s). The file is read as sins's own CSVs are
(:func:`sins.io.formats.read_table`: one header row, ``#`` comment lines at the top, other columns not
even parsed) and held to the same physical ranges after the conversion.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sins.core.series import ImuIncrements, ImuRates
from sins.errors import SinsInputError
from sins.io import formats, units

Array = NDArray[np.float64]

#: The sins names ``columns`` may map.
KNOWN = (*formats.RATE_COLUMNS, *formats.INCREMENT_COLUMNS[1:], "temp")


@dataclass(frozen=True)
class ColumnsRead:
    """What :func:`_read_columns_csv` read: the samples (SI, the file's axes), the temperature (°C) or
    None, the mapping used (sins name → file column), the units (every key of the form), the form."""

    imu: ImuRates | ImuIncrements
    temp: Array | None
    mapping: dict[str, str]
    units: dict[str, str]
    form: str
    time_from_rate: bool


def parse_columns(spec: str | Mapping[str, str] | None) -> dict[str, str]:
    """``{sins name: file column}`` from ``"t=time,gyro_x=wx"`` or a mapping; ``{}`` for None.

    Raises
    ------
    SinsInputError
        a pair without ``=``, an unknown sins name (naming the known ones), a name given twice, or two
        names mapped to one file column.
    """
    if spec is None:
        return {}
    pairs = list(spec.items()) if isinstance(spec, Mapping) else units.parse_pairs(spec, "columns")
    out: dict[str, str] = {}
    for key, column in pairs:
        if key not in KNOWN:
            raise SinsInputError(f"columns: unknown sins column {key!r} (known: {', '.join(KNOWN)})")
        if key in out:
            raise SinsInputError(f"columns: {key!r} given twice")
        twice = next((k for k, c in out.items() if c == column), None)
        if twice is not None:
            raise SinsInputError(f"columns: file column {column!r} given for both {twice!r} and {key!r}")
        out[key] = column
    return out


def _read_columns_csv(
    path: str | os.PathLike[str],
    columns: str | Mapping[str, str] | None = None,
    units_spec: str | Mapping[str, str] | None = None,
    rate_hz: float | None = None,
) -> ColumnsRead:
    """Read a CSV with its own column names and units into sins's samples (SI, on the file's axes).

    Parameters
    ----------
    path : the CSV file
    columns : ``"t=time,gyro_x=wx,..."`` or a mapping (see the module docstring); None: sins's names
    units_spec : ``"t=ms,gyro=deg/s"`` or a mapping (:mod:`sins.io.units`); None: SI
    rate_hz : the sampling rate, Hz, which gives the times of a file without a time column

    Returns
    -------
    ColumnsRead
        rate-form samples as :class:`ImuRates`; increment-form ones as :class:`ImuIncrements` whose
        ``t[0]`` is the first row's time less the first step (as :func:`sins.io._read_imu`).

    Raises
    ------
    SinsInputError
        a bad ``columns`` or ``units`` text; a mapped column the header lacks (listing the header);
        both forms' names or neither form complete; no time column and no rate; a value that is not
        a finite number, time that does not increase after the conversion, or a converted reading
        beyond sins's physical ranges (naming file, line and column).
    """
    path = Path(path)
    mapping = parse_columns(columns)
    chosen = units.parse_units(units_spec)
    header = formats.read_columns(path)
    form = _form(path, mapping, header)
    names = formats.RATE_COLUMNS if form == "rate" else formats.INCREMENT_COLUMNS
    wanted = [n for n in (*names, "temp") if n in mapping or n in header]
    full = {n: mapping.get(n, n) for n in wanted}
    for name, column in full.items():
        if column not in header:
            raise SinsInputError(
                f"{path}: columns: {name}={column!r}, but the header has no column {column!r} "
                f"(it has {', '.join(header)})"
            )
    for name, column in full.items():  # a name left to its own column, whose column another name took
        other = next((n for n, c in full.items() if c == column and n != name), None)
        if other is not None:
            raise SinsInputError(
                f"{path}: columns: file column {column!r} would be read for both {name!r} and {other!r}; "
                f"map {other if name in mapping else name} to a column of its own"
            )
    missing = [n for n in names[1:] if n not in full]
    if missing:
        raise SinsInputError(
            f"{path}: no column for {', '.join(missing)} (map them in columns as NAME=FILE_COLUMN; "
            f"the header has {', '.join(header)})"
        )
    units.check_form(chosen, form, str(path))
    if "t" not in full and rate_hz is None:
        raise SinsInputError(
            f"{path}: no time column 't' (map one in columns as t=FILE_COLUMN, or give the sampling rate)"
        )
    table = formats.read_table(path, select=tuple(full.values()))
    converted = _converted(table, list(full), chosen)
    n = len(converted)
    t = converted[:, 0] if "t" in full else np.arange(n, dtype=float) / float(rate_hz or 1.0)
    _check_time(table, t, "t" in full)
    check_table = formats.Table(table.path, table.columns, converted, table.first_data_line)
    if "temp" in full:
        temp = converted[:, list(full).index("temp")]
        formats.check_range(check_table, full["temp"], temp, *formats.TEMP_DEGC, "temperature", "°C")
    return ColumnsRead(
        imu=_samples(check_table, full, t, form),
        temp=converted[:, list(full).index("temp")].copy() if "temp" in full else None,
        mapping=full,
        units={k: chosen.get(k, units.SI[k]) for k in units.FORM_KEYS[form] if k != "temp" or "temp" in full},
        form=form,
        time_from_rate="t" not in full,
    )


def _form(path: Path, mapping: dict[str, str], header: tuple[str, ...]) -> str:
    """The IMU form the mapped names (else the header's sins names) give; refuse both or neither."""
    for given, where in ((tuple(mapping), "columns"), (header, "the header")):
        rate = [c for c in formats.RATE_COLUMNS[1:] if c in given]
        inc = [c for c in formats.INCREMENT_COLUMNS[1:] if c in given]
        if rate and inc:
            raise SinsInputError(
                f"{path}: {where} mixes rate names ({', '.join(rate)}) with increment names "
                f"({', '.join(inc)}); use one form"
            )
        if rate or inc:
            return "rate" if rate else "increment"
    raise SinsInputError(
        f"{path}: which column is which? map them in columns as sins name=file column, e.g. "
        f"t=time,gyro_x=wx,...,accel_z=az (rates) or dtheta_x=...,dv_z=... (increments); the header has "
        f"{', '.join(header)}"
    )


def _converted(table: formats.Table, names: list[str], chosen: dict[str, str]) -> Array:
    """The table's values in SI, column by column (``names`` are the sins names, in the table's order)."""
    out = table.data.copy()
    for i, name in enumerate(names):
        key = units.KEY_OF[name]
        unit = chosen.get(key, units.SI[key])
        if unit != units.SI[key]:
            out[:, i] = out[:, i] * units.UNITS[key][unit]
            if key == "temp":
                out[:, i] += units.TEMP_OFFSET[unit]
    return out


def _check_time(table: formats.Table, t: Array, from_file: bool) -> None:
    """Time increasing (after the conversion) and within sins's range, naming the line."""
    if not from_file:
        return
    column = table.columns[0]
    if (r := formats.first_not_increasing(t)) is not None:
        line = formats.line_of_row(table.path, table.first_data_line - 1, r)
        raise SinsInputError(
            f"{table.path}:{line}: column {column!r}: time {formats.format_number(t[r])} s does not "
            f"increase (previous {formats.format_number(t[r - 1])} s)"
        )
    formats.check_range(table, column, t, -formats.MAX_TIME_S, formats.MAX_TIME_S, "time", "s")


def _samples(table: formats.Table, full: dict[str, str], t: Array, form: str) -> ImuRates | ImuIncrements:
    """The converted columns as samples, held to sins's ranges (file column names in messages)."""
    names = list(full)
    col = {name: table.data[:, names.index(name)] for name in names}
    if form == "rate":
        for name in formats.RATE_COLUMNS[1:]:
            limit = formats.MAX_RATE_RADPS if name.startswith("gyro") else formats.MAX_FORCE_MPS2
            unit = "rad/s" if name.startswith("gyro") else "m/s²"
            what = "rate" if name.startswith("gyro") else "specific force"
            formats.check_range(table, full[name], col[name], -limit, limit, what, unit)
        w = np.column_stack([col[f"gyro_{a}"] for a in "xyz"])
        f = np.column_stack([col[f"accel_{a}"] for a in "xyz"])
        return ImuRates(t=t.copy(), omega_ib_b=w, f_ib_b=f)
    if len(t) < 2:
        raise SinsInputError(
            f"{table.path}: increment form needs two or more rows to know the first interval"
        )
    start = t[0] - (t[1] - t[0])
    dt = np.diff(np.concatenate([[start], t]))
    for name in formats.INCREMENT_COLUMNS[1:]:
        rate = name.startswith("dtheta")
        limit = formats.MAX_RATE_RADPS if rate else formats.MAX_FORCE_MPS2
        what = ("rate" if rate else "specific force") + " (increment / interval)"
        formats.check_range(
            table, full[name], col[name] / dt, -limit, limit, what, "rad/s" if rate else "m/s²"
        )
    dtheta = np.column_stack([col[f"dtheta_{a}"] for a in "xyz"])
    dv = np.column_stack([col[f"dv_{a}"] for a in "xyz"])
    return ImuIncrements(t=np.concatenate([[start], t]), dtheta_b=dtheta, dv_b=dv)


__all__ = [
    "KNOWN",
    "ColumnsRead",
    "parse_columns",
]
