"""One unit of a campaign: its rig session, its fitted strategies, its scenarios, its rows.

Pure sins, no distributed engine: a unit's rows depend on the campaign and the unit's index alone,
so any worker, in any order, on any machine, computes the same rows.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from sins.campaign.spec import CampaignSpec, nav_seed, rig_seed
from sins.errors import SinsInputError
from sins.imu import CHANNELS
from sins.runs import pipeline

#: The figures of a row, in the order of its columns (a :class:`sins.nav.metrics.DriftSummary`'s,
#: then the held-back rig residual's RMS and the bias left, per channel).
SUMMARY_FIELDS = (
    "final_horizontal_m",
    "max_horizontal_m",
    "rms_horizontal_m",
    "final_down_m",
    "final_roll_deg",
    "final_pitch_deg",
    "final_yaw_deg",
    "drift_rate_m_per_h",
)
RESIDUAL_FIELDS = tuple(f"residual_{ch.replace('.', '_')}" for ch in CHANNELS)
#: The bias each strategy leaves per channel: |mean| of corrected − reference on the held-back rig rows.
BIAS_FIELDS = tuple(f"bias_left_{ch.replace('.', '_')}" for ch in CHANNELS)


def run_unit(spec: CampaignSpec, unit: int) -> list[dict[str, Any]]:
    """Every row of unit ``unit`` (0-based): one per scenario × strategy, in the campaign's order
    (:func:`run_units` of the one unit)."""
    return run_units(spec, [unit])


def run_units(spec: CampaignSpec, units: Sequence[int]) -> list[dict[str, Any]]:
    """Every row of ``units``: by unit, then scenario and strategy in the campaign's order.

    Each unit's rig session is simulated and every strategy fitted once
    (:func:`sins.runs.pipeline.fit_unit`); each scenario's trajectory is then generated once and driven by
    every unit with its navigation power-on (:func:`~sins.campaign.spec.nav_seed`), corrected by each
    strategy and integrated (:func:`sins.runs.pipeline.run_units`): each unit's figures are those of
    ``sins run`` on that unit, to the last bit.
    """
    seeds = [spec.unit_seed(u) for u in units]
    fitted = [pipeline.fit_unit(spec.unit_imu(u), spec.unit_compensation(u)) for u in units]
    by_unit: list[list[dict[str, Any]]] = [[] for _ in units]
    for base in spec.scenarios:
        keep_hz = spec.series_hz if spec.series_hz > 0 else 1.0 / max(base.rate_hz, 1.0)
        # No sensor-error block means: a plot's, and the rows do not keep them.
        results = pipeline.run_units(base, fitted, [nav_seed(s) for s in seeds], keep_hz, sensor_errors=False)
        for rows, unit, seed, f, result in zip(by_unit, units, seeds, fitted, results, strict=True):
            rows.extend(_rows(spec, unit, seed, f, result))
    return [row for rows in by_unit for row in rows]


def _rows(
    spec: CampaignSpec, unit: int, seed: int, fitted: pipeline.FittedUnit, result: pipeline.ScenarioRun
) -> list[dict[str, Any]]:
    rows = []
    for strategy, run in result.runs.items():
        summary = run.summary.to_dict()
        residual = run.residual_rms or {}
        bias = fitted.biases.get(strategy, {})
        row: dict[str, Any] = {
            "unit": unit,
            "unit_seed": seed,
            "rig_seed": rig_seed(seed),
            "nav_seed": nav_seed(seed),
            "scenario": result.scenario.name,
            "strategy": strategy,
            **{k: float(summary[k]) for k in SUMMARY_FIELDS},
            **{f: float(residual.get(ch, np.nan)) for f, ch in zip(RESIDUAL_FIELDS, CHANNELS, strict=True)},
            **{f: abs(float(bias.get(ch, np.nan))) for f, ch in zip(BIAS_FIELDS, CHANNELS, strict=True)},
        }
        aided = result.aided.get(strategy)
        if aided is not None:
            # A [gnss] scenario: the aided run's figures, and each outage's error at its end and its max.
            row["aided_final_horizontal_m"] = float(aided.summary.final_horizontal_m)
            row["aided_max_horizontal_m"] = float(aided.summary.max_horizontal_m)
            for i, outage in enumerate(aided.outages, start=1):
                row[f"outage{i}_end_m"] = float(outage.final_m)
                row[f"outage{i}_max_m"] = float(outage.max_m)
        if spec.series_hz > 0:
            row["series_t_s"] = run.errors.t.astype(np.float32).tolist()
            row["series_horizontal_m"] = run.errors.horizontal_m.astype(np.float32).tolist()
        rows.append(row)
    return rows


def task(spec: CampaignSpec, units: list[int]) -> tuple[list[int], list[dict[str, Any]]]:
    """A cluster's task: ``units`` and their rows (:func:`run_units`), wherever it runs.

    Here, not beside the engine, so that a worker unpickling it imports no more than it needs (not the
    engine's Parquet writer, pyarrow, which would hold memory in every worker: ``docs/speed.md``).
    """
    _heap_for_chunks()
    # A failing task reaches the user as its error's one line in the main process; the worker's own
    # "Compute Failed" report (6-10 lines on the terminal the worker shares) would say it again.
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
    try:
        return units, run_units(spec, units)
    except ValueError as exc:  # what the campaign's files make of a unit: a rig that cannot fit it, say
        if isinstance(exc, SinsInputError):
            raise
        first, last = units[0], units[-1]
        which = f"unit {first}" if first == last else f"units {first}-{last}"
        raise SinsInputError(f"{spec.source}: {which}: {exc}") from None


#: The size below which glibc's ``malloc`` serves a block from its heap, not from a fresh ``mmap``:
#: above a chunk's arrays (a few hundred KiB each), below a rig session's whole arrays.
MMAP_THRESHOLD = 4 * 1024 * 1024


def _heap_for_chunks() -> None:
    """Let glibc keep a worker's freed arrays for the next chunk instead of giving them back at once.

    A dask nanny starts its workers with ``MALLOC_TRIM_THRESHOLD_=65536`` (to return memory to the
    system); setting it freezes glibc's ``mmap`` threshold at 128 KiB, so every array of a chunk
    (8192 × 3 doubles: 192 KiB) is mapped and unmapped again, page faults and all. Raising the
    threshold (here, on the worker, so it holds for a cluster started by hand too) keeps them in the
    heap, for a little more peak memory (the figures are in ``docs/speed.md``). Elsewhere than glibc,
    nothing to do.
    """
    import ctypes
    import ctypes.util

    if not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.mallopt(-3, MMAP_THRESHOLD)  # M_MMAP_THRESHOLD
    except (OSError, AttributeError):  # not glibc (musl has no mallopt)
        return


__all__ = [
    "BIAS_FIELDS",
    "MMAP_THRESHOLD",
    "RESIDUAL_FIELDS",
    "SUMMARY_FIELDS",
    "run_unit",
    "run_units",
    "task",
]
