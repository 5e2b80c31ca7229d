"""A campaign's results folder, owned by one campaign: its lock, its identity, its parts checked.

* **The lock** (:func:`locked`): ``DIR/campaign.lock``, held with ``flock`` for the whole run and
  naming its holder (pid, host, start). A second campaign into a held folder is refused in one line. A
  lock left by a run that died (killed, the machine rebooted) is stale: the kernel released its
  ``flock`` with the process, and the next run takes the folder over. On a filesystem without locks
  the holder's pid is looked up on this host (a dead one is stale); a lock taken on another host cannot
  be looked up there, and is refused naming the host and the file to delete once that run has ended.
* **The identity** (:func:`identity`): a SHA-256 of what the campaign resolves to and of the bytes of
  every file it uses (the campaign file, the IMU, rig and scenario files, a scenario's truth file),
  written in ``campaign.json`` and in the Parquet metadata of every part. Moving the files elsewhere
  keeps it; editing any of them changes it.
* **The parts** (:func:`check_parts`): each part is read whole and checked: readable (every page
  against its checksum: zeroed bytes may decode as other numbers), of this
  campaign's identity, with the columns of a row and their types, every unit of its name's range with
  one row per scenario × strategy and the unit's seeds, no unit in two parts. A part that fails is moved
  to ``DIR/rejected/`` and its units are run again: checked on ``--resume``, and again after the units
  ran, before the join, so damage while a campaign runs is repaired too.
"""

from __future__ import annotations

import contextlib
import datetime
import errno
import fcntl
import hashlib
import json
import os
import re
import socket
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from sins import io
from sins.campaign.spec import CampaignSpec, describe
from sins.campaign.unit import BIAS_FIELDS, RESIDUAL_FIELDS, SUMMARY_FIELDS
from sins.errors import SinsInputError
from sins.io.documents import printable
from sins.io.paths import CAMPAIGN_FORMAT, check_writable
from sins.scenario import TruthFileSpec

FORMAT = CAMPAIGN_FORMAT
LOCK_NAME = "campaign.lock"
#: The key of a part's Parquet metadata that holds the campaign's identity.
IDENTITY_KEY = b"sins.campaign.identity"
PART = re.compile(r"units-(\d+)-(\d+)\.parquet")
#: The columns every row has, by kind (a part missing one, or holding another kind, is damaged).
INTEGER_COLUMNS = ("unit", "unit_seed", "rig_seed", "nav_seed")
TEXT_COLUMNS = ("scenario", "strategy")
FIGURE_COLUMNS = (*SUMMARY_FIELDS, *RESIDUAL_FIELDS, *BIAS_FIELDS)
SERIES_COLUMNS = ("series_t_s", "series_horizontal_m")
#: An aided scenario's figures (``aided_final_horizontal_m``, ``outage2_max_m``, ...).
AIDED_COLUMN = re.compile(r"aided_(final|max)_horizontal_m|outage[1-9][0-9]*_(end|max)_m")


def identity(spec: CampaignSpec) -> str:
    """The campaign's identity: SHA-256 (hex) of what it resolves to and of every file it uses."""
    digest = hashlib.sha256()
    resolved = {k: v for k, v in describe(spec).items() if k not in ("source", "imu", "rig")}
    digest.update(json.dumps(resolved, sort_keys=True).encode())
    files = [("campaign", spec.source), ("imu", spec.imu.source), ("rig", spec.compensation.rig)]
    for sc in spec.scenarios:
        files.append((f"scenario {sc.name}", sc.source))
        if isinstance(sc.trajectory, TruthFileSpec):
            files.append((f"truth {sc.name}", sc.trajectory.path))
    for role, path in files:
        digest.update(f"\0{role}\0".encode())
        if path is not None:
            try:
                digest.update(Path(path).read_bytes())
            except OSError as exc:
                raise SinsInputError(f"{path}: cannot read: {exc.strerror or exc}") from None
    return digest.hexdigest()


# --------------------------------------------------------------------------- the lock


@contextlib.contextmanager
def locked(out: Path, spec: CampaignSpec) -> Iterator[None]:
    """Hold ``out``'s lock for the block (``out`` is created); released, and its file removed, after.

    Raises
    ------
    SinsInputError
        another campaign holds ``out``, naming its pid, host and start; or ``out`` cannot be created.
    """
    check_writable(out, folder=True)
    check_owned(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SinsInputError(f"{out}: cannot create the folder: {exc.strerror or exc}") from None
    path = out / LOCK_NAME
    fd = _acquire(path)
    try:
        holder = {"pid": os.getpid(), "host": socket.gethostname(), "campaign": spec.name,
                  "started": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")}  # fmt: skip
        os.ftruncate(fd, 0)
        os.pwrite(fd, (json.dumps(holder) + "\n").encode(), 0)
        yield
    finally:
        with contextlib.suppress(OSError):
            path.unlink()
        os.close(fd)  # releases the flock (after the unlink: no one takes the old file meanwhile)


def check_owned(out: Path) -> None:
    """Refuse a results folder that holds files of its own and is not a campaign's (no
    ``campaign.json`` that is a sins campaign's, by its ``format``: a file of that name is not enough):
    a campaign writes ``campaign.json``, ``summary.json`` and ``results.parquet`` there, and would
    replace a user's files of those names.

    Raises
    ------
    SinsInputError
        naming the folder and one of the files it holds, or its ``campaign.json`` that is not sins's.
    """
    if not out.is_dir():
        return
    if (out / "campaign.json").exists():
        io.read_json_document(out / "campaign.json", "campaign results folder", FORMAT)  # sins's, or refused
        return
    others = sorted(p.name for p in out.iterdir() if p.name != LOCK_NAME)
    if others:
        more = ", ..." if len(others) > 1 else ""
        raise SinsInputError(
            f"{out}: holds {len(others)} file(s) ({printable(others[0])[:80]}{more}) and no campaign.json: "
            "not a campaign's results folder; give a new or empty --out"
        )


def _acquire(path: Path) -> int:
    """An open descriptor of ``path`` holding its lock (see the module docstring for stale locks)."""
    for _ in range(5):  # the file may be replaced between our open and our lock: try again
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as exc:
            raise SinsInputError(f"{path}: cannot open the campaign's lock: {exc.strerror or exc}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            kernel = True
        except OSError as exc:
            if exc.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                kernel = False  # a filesystem without locks: judge the holder by its pid
            else:
                holder = _holder(fd)
                os.close(fd)
                raise _in_use(path, holder) from None
        try:
            same = os.fstat(fd).st_ino == os.stat(path).st_ino
        except OSError:
            same = False
        if not same:
            os.close(fd)
            continue
        holder = _holder(fd)
        if holder and holder.get("host") != socket.gethostname():
            os.close(fd)
            raise SinsInputError(
                f"{path.parent}: locked by {_who(holder)}, on another machine, which this one cannot ask; "
                f"if that campaign has ended, delete {path}"
            )
        if holder and not kernel and holder.get("pid") != os.getpid() and _alive(holder.get("pid")):
            os.close(fd)
            raise _in_use(path, holder)
        return fd  # free, or a stale lock of a run that died on this host: taken over
    raise SinsInputError(f"{path}: the lock keeps changing hands; is another campaign starting there?")


def _in_use(path: Path, holder: dict[str, Any]) -> SinsInputError:
    return SinsInputError(f"{path.parent}: in use by {_who(holder)}; wait for it to end or use another --out")


def _holder(fd: int) -> dict[str, Any]:
    """What a lock file says of its holder ({} when empty or unreadable)."""
    try:
        doc = json.loads(os.pread(fd, 4096, 0).decode("utf-8") or "{}")
    except (OSError, ValueError):
        return {}
    return doc if isinstance(doc, dict) else {}


def _who(holder: dict[str, Any]) -> str:
    if not holder:
        return "another campaign"
    fields = (holder.get("campaign"), holder.get("pid"), holder.get("host"), holder.get("started"))
    name, pid, host, started = (printable(str(f)) for f in fields)
    return f"campaign {name} (pid {pid} on {host}, since {started})"


def _alive(pid: Any) -> bool:
    if isinstance(pid, bool) or not isinstance(pid, int) or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    except OverflowError:
        return False
    return True


# --------------------------------------------------------------------------- the folder and its parts


@dataclass
class Parts:
    """The parts a folder holds that passed :func:`check_parts`: the units they hold, their tables, and
    a line for each part rejected (moved to ``rejected/``, its units to run again)."""

    identity: str
    done: set[int] = field(default_factory=set)
    tables: list[pa.Table] = field(default_factory=list)
    rejected: list[str] = field(default_factory=list)


def prepare(out: Path, spec: CampaignSpec, resume: bool) -> Parts:
    """Check ``out`` (its lock held) for ``spec``: write ``campaign.json``; the parts it holds, checked.

    A folder that holds no results (a bare ``campaign.json``: the cluster could not be reached, say) is
    started afresh.

    Raises
    ------
    SinsInputError
        ``out`` holds another campaign's results, or results and ``resume`` is not given.
    """
    ident = identity(spec)
    meta = {"format": FORMAT, **describe(spec), "identity": ident}
    existing = out / "campaign.json"
    has_results = bool(part_files(out)) or (out / "results.parquet").exists()
    if has_results:
        if existing.exists():
            held = io.read_json_document(existing, "campaign results folder", FORMAT)
            if _other(held, meta):
                changed = [k for k in meta if k not in ("format", "identity") and held.get(k) != meta[k]]
                what = ", ".join(sorted(changed)) or "the content of its files"
                raise SinsInputError(
                    f"{existing}: holds another campaign (differs in {what}); use another --out"
                )
        if not resume:
            raise SinsInputError(f"{out}: already holds a campaign's results; give --resume to continue it")
    (out / "parts").mkdir(parents=True, exist_ok=True)
    io.write_json(existing, meta)
    return check_parts(out, spec, ident)


def _other(held: dict[str, Any], meta: dict[str, Any]) -> bool:
    """Whether ``campaign.json`` describes another campaign (by identity; by description when it was
    written before identities were)."""
    if "identity" in held:
        return bool(held["identity"] != meta["identity"])
    return any(held.get(k) != v for k, v in meta.items() if k != "identity")


def part_files(out: Path) -> list[Path]:
    """The parts under ``out/parts`` (temporary names, unfinished, are not parts)."""
    folder = out / "parts"
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.glob("units-*.parquet") if PART.fullmatch(p.name))


def check_parts(out: Path, spec: CampaignSpec, ident: str | None = None) -> Parts:
    """Every part of ``out`` read and checked (module docstring); a part that fails is moved to
    ``out/rejected/`` and named in :attr:`Parts.rejected`."""
    ident = identity(spec) if ident is None else ident
    parts = Parts(ident)
    for path in part_files(out):
        table, why = _read_part(path, spec, ident)
        if table is not None:
            units = set(range(*_span(path)))
            if units & parts.done:
                table, why = None, "holds units another part holds"
            else:
                parts.done |= units
                parts.tables.append(table)
                continue
        parts.rejected.append(f"{path}: {why}; moved to {_reject(out, path)}, its units run again")
    return parts


def _span(path: Path) -> tuple[int, int]:
    m = PART.fullmatch(path.name)
    assert m is not None
    return int(m.group(1)), int(m.group(2)) + 1


def _read_part(path: Path, spec: CampaignSpec, ident: str) -> tuple[pa.Table | None, str]:
    """The part's table, or None and why it cannot be trusted."""
    try:
        table = pq.read_table(path, page_checksum_verification=True)
    except Exception as exc:  # pyarrow raises many kinds on damaged bytes: any of them means damaged
        return None, f"unreadable ({type(exc).__name__}: {printable(str(exc))[:200]})"
    held = (table.schema.metadata or {}).get(IDENTITY_KEY)
    if held != ident.encode():
        return None, "written by another campaign" if held else "carries no campaign identity"
    why = _schema_problem(table.schema, spec) or _rows_problem(table, spec, *_span(path))
    return (None, why) if why else (table, "")


def _schema_problem(schema: pa.Schema, spec: CampaignSpec) -> str:
    """Why the part's columns are not a row's ("" if they are)."""
    kinds = {**dict.fromkeys(INTEGER_COLUMNS, pa.types.is_integer), **dict.fromkeys(TEXT_COLUMNS, _is_text),
             **dict.fromkeys(FIGURE_COLUMNS, pa.types.is_floating)}  # fmt: skip
    if spec.series_hz > 0:
        kinds |= dict.fromkeys(SERIES_COLUMNS, _is_float_list)
    for name, ok in kinds.items():
        if name not in schema.names:
            return f"has no column {name}"
        if not ok(schema.field(name).type):
            return f"column {name} is {schema.field(name).type}"
    for name in schema.names:
        if name not in kinds and not AIDED_COLUMN.fullmatch(name):
            return f"has a column no row has ({printable(name)[:80]})"
        if name not in kinds and not (pa.types.is_floating(schema.field(name).type) or pa.types.is_null(
                schema.field(name).type)):  # fmt: skip
            return f"column {name} is {schema.field(name).type}"
    return ""


def _is_text(kind: pa.DataType) -> bool:
    return bool(pa.types.is_string(kind) or pa.types.is_large_string(kind))


def _is_float_list(kind: pa.DataType) -> bool:
    return bool(pa.types.is_list(kind) and pa.types.is_floating(kind.value_type))


def _rows_problem(table: pa.Table, spec: CampaignSpec, first: int, stop: int) -> str:
    """Why the part's rows are not units ``first..stop-1``, one per scenario × strategy ("" if they are)."""
    scenarios = [s.name for s in spec.scenarios]
    strategies = list(dict.fromkeys(["none", *spec.compensation.strategies]))
    if stop > spec.count:
        return f"holds units beyond the campaign's {spec.count}"
    if table.num_rows != (stop - first) * len(scenarios) * len(strategies):
        return (
            f"has {table.num_rows} rows, not one per unit x scenario x strategy of its {stop - first} units"
        )
    if table.column("unit").null_count or table.column("unit_seed").null_count:
        return "has rows without a unit"
    unit = table.column("unit").to_numpy()
    columns = (unit.tolist(), table.column("scenario").to_pylist(), table.column("strategy").to_pylist())
    rows = set(zip(*columns, strict=True))
    wanted = {(u, sc, st) for u in range(first, stop) for sc in scenarios for st in strategies}
    if rows != wanted:
        return "does not hold one row per unit x scenario x strategy of its units"
    seeds = np.array([spec.unit_seed(int(u)) for u in unit])
    for name, expected in (("unit_seed", seeds), ("rig_seed", 2 * seeds), ("nav_seed", 2 * seeds + 1)):
        column = table.column(name)
        if column.null_count or not np.array_equal(column.to_numpy(), expected):
            return f"has {name}s that are not its units'"
    return ""


def _reject(out: Path, path: Path) -> Path:
    """Move a part that failed its check to ``out/rejected/`` (a new name if one is there already)."""
    folder = out / "rejected"
    folder.mkdir(exist_ok=True)
    target = folder / path.name
    n = 1
    while target.exists():
        n += 1
        target = folder / f"{path.name}.{n}"
    os.replace(path, target)
    return target


__all__ = [
    "AIDED_COLUMN",
    "FIGURE_COLUMNS",
    "FORMAT",
    "IDENTITY_KEY",
    "INTEGER_COLUMNS",
    "LOCK_NAME",
    "PART",
    "SERIES_COLUMNS",
    "TEXT_COLUMNS",
    "Parts",
    "check_owned",
    "check_parts",
    "identity",
    "locked",
    "part_files",
    "prepare",
]
