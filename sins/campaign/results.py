"""A campaign's results on disk: Parquet parts as units finish, the joined table, the summary.

Layout of ``--out DIR``::

    DIR/campaign.json              what the campaign runs (a resumed campaign must match it)
    DIR/parts/units-A-B.parquet    the rows of units A..B, written whole (temporary name, then rename)
    DIR/results.parquet            every row, sorted by unit, then scenario and strategy in the file's order
    DIR/summary.json               per scenario × strategy: statistics with bootstrap 95 % intervals

A part is renamed into place only once all its rows are written, so an interrupted campaign leaves
complete rows only, and ``--resume`` skips the units the parts already hold.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from sins import io
from sins.campaign.spec import CampaignSpec, describe
from sins.campaign.unit import BIAS_FIELDS, RESIDUAL_FIELDS
from sins.errors import SinsInputError

FORMAT = "sins-campaign"
SUMMARY_FORMAT = "sins-campaign-summary"
_PART = re.compile(r"units-(\d+)-(\d+)\.parquet")
#: Bootstrap resamples per statistic, and the generator's seed (fixed: a summary is reproducible).
BOOTSTRAP_RESAMPLES = 2000
BOOTSTRAP_SEED = 20081101
#: The statistics of each figure: the percentile each one is (the mean is "mean").
STATISTICS = {"mean": None, "median": 50.0, "p90": 90.0, "p95": 95.0}
#: The figures summarised per scenario × strategy.
SUMMARISED = ("final_horizontal_m", "max_horizontal_m", *RESIDUAL_FIELDS, *BIAS_FIELDS)


def prepare(out: Path, spec: CampaignSpec, resume: bool) -> set[int]:
    """Create ``out`` (or check it on ``resume``); the units already done. A folder whose campaign never
    finished a unit (its cluster could not be reached, say) is started afresh.

    Raises
    ------
    SinsInputError
        ``out`` holds another campaign, or holds results and ``resume`` is not given.
    """
    meta = {"format": FORMAT, **describe(spec)}
    parts = out / "parts"
    if out.exists() and not out.is_dir():
        raise SinsInputError(f"{out}: is a file, expected a folder for the campaign's results")
    existing = out / "campaign.json"
    if existing.exists() and (resume or done_units(parts)):
        if not resume:
            raise SinsInputError(f"{out}: already holds a campaign's results; give --resume to continue it")
        held = io.read_json_document(existing, "campaign results folder", FORMAT)
        if held != meta:
            changed = sorted(k for k in meta if held.get(k) != meta[k])
            raise SinsInputError(
                f"{existing}: holds another campaign (differs in {', '.join(changed)}); use another --out"
            )
    parts.mkdir(parents=True, exist_ok=True)
    io.write_json(existing, meta)
    return done_units(parts)


def done_units(parts: Path) -> set[int]:
    """The units whose rows the parts under ``parts`` hold (temporary names, unfinished, are ignored)."""
    done: set[int] = set()
    for path in parts.glob("units-*.parquet"):
        m = _PART.fullmatch(path.name)
        if m:
            done.update(range(int(m.group(1)), int(m.group(2)) + 1))
    return done


def write_part(parts: Path, units: list[int], rows: list[dict[str, Any]]) -> Path:
    """The rows of ``units`` as one Parquet part, renamed into place once whole."""
    path = parts / f"units-{min(units):07d}-{max(units):07d}.parquet"
    with io.atomic_path(path) as tmp:
        pq.write_table(pa.Table.from_pylist(rows), tmp)
    return path


def join(out: Path, spec: CampaignSpec) -> pa.Table:
    """Every part's rows in one table, sorted by unit, then scenario and strategy in the file's order;
    written to ``out/results.parquet`` (atomically)."""
    tables = [pq.read_table(p) for p in sorted((out / "parts").glob("units-*.parquet"))]
    table = pa.concat_tables(tables) if tables else pa.table({})
    if tables:
        scen = {s.name: i for i, s in enumerate(spec.scenarios)}
        strat = {s: i for i, s in enumerate(["none", *spec.compensation.strategies])}
        units = table.column("unit").to_numpy()
        s_idx = np.array([scen[s] for s in table.column("scenario").to_pylist()])
        g_idx = np.array([strat[s] for s in table.column("strategy").to_pylist()])
        table = table.take(np.lexsort((g_idx, s_idx, units)))
    with io.atomic_path(out / "results.parquet") as tmp:
        pq.write_table(table, tmp)
    return table


def summarise(table: pa.Table, spec: CampaignSpec) -> dict[str, Any]:
    """Per scenario × strategy and figure: mean, median, 90th and 95th percentiles over the units,
    each with a percentile-bootstrap 95 % interval (resampling units; fixed seed), and every unit's
    figures (``values``, keyed by figure, with the units' ``unit_seed``)."""
    groups: dict[str, Any] = {}
    if table.num_rows:
        scenario = np.array(table.column("scenario").to_pylist())
        strategy = np.array(table.column("strategy").to_pylist())
        # An aided scenario's rows add its aided run's and each outage's errors.
        extra = [c for c in table.column_names if c.startswith(("aided_", "outage"))]
        for sc in spec.scenarios:
            for st in dict.fromkeys(["none", *spec.compensation.strategies]):
                rows = (scenario == sc.name) & (strategy == st)
                if rows.any():
                    figures = {
                        f: np.asarray(table.column(f).to_numpy(zero_copy_only=False), dtype=float)[rows]
                        for f in (*SUMMARISED, *extra)
                    }
                    groups[f"{sc.name}/{st}"] = {
                        "scenario": sc.name,
                        "strategy": st,
                        "units": int(rows.sum()),
                        **{f: _statistics(v) for f, v in figures.items()},
                        # Each unit's figures, so that a later campaign can be tested against these
                        # units (sins.campaign.gate), paired where the seeds match.
                        "values": {
                            "unit_seed": table.column("unit_seed").to_numpy()[rows].tolist(),
                            **{f: v.tolist() for f, v in figures.items()},
                        },
                    }
    return {"format": SUMMARY_FORMAT, **describe(spec), "groups": groups}


def _statistics(values: np.ndarray) -> dict[str, Any]:
    values = values[np.isfinite(values)]
    if len(values) == 0:
        return {}
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    resampled = values[rng.integers(0, len(values), (BOOTSTRAP_RESAMPLES, len(values)))]
    out: dict[str, Any] = {}
    for name, q in STATISTICS.items():
        point = float(np.mean(values)) if q is None else float(np.percentile(values, q))
        boot = resampled.mean(axis=1) if q is None else np.percentile(resampled, q, axis=1)
        low, high = np.percentile(boot, [2.5, 97.5])
        out[name] = point
        out[f"{name}_ci95"] = [float(low), float(high)]
    return out


def write_summary(out: Path, summary: dict[str, Any]) -> Path:
    """``out/summary.json``, atomically."""
    path = out / "summary.json"
    io.write_json(path, summary)
    return path


def table_lines(summary: dict[str, Any]) -> Iterable[str]:
    """The printed table: per scenario × strategy, the final horizontal error's median and 95th
    percentile with their intervals, and the max's median."""
    yield (
        f"{'scenario':<18} {'strategy':<20} {'units':>5}  {'final horiz. median [95% CI]':>30}  "
        f"{'p95 [95% CI]':>28}  {'max median':>10}"
    )
    for g in summary["groups"].values():
        f, m = g["final_horizontal_m"], g["max_horizontal_m"]
        if not f:
            continue
        yield (
            f"{g['scenario']:<18} {g['strategy']:<20} {g['units']:>5}  "
            f"{_ci(f['median'], f['median_ci95']):>30}  {_ci(f['p95'], f['p95_ci95']):>28}  "
            f"{m['median']:>9.4g}m"
        )


def _ci(value: float, ci: list[float]) -> str:
    return f"{value:.4g} m [{ci[0]:.4g}, {ci[1]:.4g}]"


def read_summary(path: Path) -> dict[str, Any]:
    """A ``summary.json`` written by :func:`write_summary`; one-line errors otherwise."""
    return io.read_json_document(path, "campaign summary", SUMMARY_FORMAT)
