"""What every command shares: tables, progress, argument types, the checks before the work."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.pipeline import ScenarioRun

#: The object ``add_subparsers`` returns, to which each subcommand adds its parser.
Subparsers = argparse._SubParsersAction

_COLUMNS = (
    ("final N m", "final_north_m", "{:.3f}"),
    ("final E m", "final_east_m", "{:.3f}"),
    ("final D m", "final_down_m", "{:.3f}"),
    ("final hor m", "final_horizontal_m", "{:.3f}"),
    ("max hor m", "max_horizontal_m", "{:.3f}"),
    ("roll °", "final_roll_deg", "{:.4f}"),
    ("pitch °", "final_pitch_deg", "{:.4f}"),
    ("yaw °", "final_yaw_deg", "{:.4f}"),
    ("m/h", "drift_rate_m_per_h", "{:.3f}"),
    ("nmi/h", "drift_rate_nmi_per_h", "{:.4f}"),
)


def fixed_width(head: list[str], rows: list[list[str]]) -> str:
    """Columns padded to their widest cell: the first left-aligned, the rest right-aligned."""
    widths = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]

    def line(cells: list[str]) -> str:
        return "  ".join(
            c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(cells, widths, strict=True))
        )

    return "\n".join(line(r) for r in [head, *rows])


def format_table(summaries: dict[str, dict[str, Any]]) -> str:
    """A fixed-width table: one row per strategy, the headline errors as columns."""
    head = ["strategy"] + [c[0] for c in _COLUMNS]
    rows = [[name] + [fmt.format(s[key]) for _, key, fmt in _COLUMNS] for name, s in summaries.items()]
    return fixed_width(head, rows)


def check_finite(values: dict[str, Any], where: str) -> None:
    """Refuse a result with a non-finite number rather than print it: the inputs took the computation
    beyond what floating point holds (readings near the physical limits, held for long)."""
    for key, value in values.items():
        if isinstance(value, float) and not math.isfinite(value):
            raise SinsInputError(
                f"{where}: {key} came out {value}; the inputs drive the computation beyond finite numbers "
                "(check the values they hold)"
            )


def display_unit(channel: str) -> tuple[float, str]:
    """:func:`sins.imu.display_unit`, imported when a table needs it (the CLI starts without numpy)."""
    from sins.imu import display_unit

    return display_unit(channel)


@contextmanager
def progress_bar(description: str, unit: str) -> Iterator[Any]:
    """A tqdm bar on a terminal (stderr), None otherwise: logs and CI get the plain result lines only."""
    if not sys.stderr.isatty():
        yield None
        return
    from tqdm import tqdm

    with tqdm(desc=description, unit=f" {unit}", leave=False, file=sys.stderr) as bar:
        yield bar


def advance(bar: Any, done: int, total: int | None = None) -> None:
    """Move ``bar`` to ``done`` of ``total`` (a tqdm bar)."""
    if total is not None:
        bar.total = total
    bar.update(done - bar.n)


def row_progress(bar: Any) -> Callable[[int, int], None] | None:
    """A ``progress(done, total)`` callback advancing ``bar``, or None without a bar."""
    if bar is None:
        return None
    return lambda done, total: advance(bar, done, total)


def settings(config: dict[str, Any]) -> str:
    """A chosen configuration as ``key value, key value``."""
    return ", ".join(f"{k} {v}" for k, v in config.items())


def positive(text: str) -> float:
    """An argument type: a finite number above 0."""
    value = float(text)
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text}")
    return value


def count(text: str) -> int:
    """An argument type: a whole number of at least 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {text}")
    return value


def seed(text: str) -> int:
    """An argument type: a seed, a whole number in [0, 2⁶³ − 1] (what a TOML file's seeds take)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text}") from None
    if not 0 <= value <= 2**63 - 1:
        raise argparse.ArgumentTypeError(f"must be in [0, 2**63 - 1], got {text}")
    return value


def fraction(text: str) -> float:
    """An argument type: a fraction in (0, 1)."""
    value = float(text)
    if not 0.0 < value < 1.0:
        raise argparse.ArgumentTypeError(f"must be a fraction in (0, 1), got {text}")
    return value


def add_dataset(p: argparse.ArgumentParser) -> None:
    """``--dataset NAME`` (sins.io.datasets.NAMES, written out: importing the readers would slow every
    command's start)."""
    p.add_argument(
        "--dataset", metavar="NAME",
        help="a real dataset from the data root instead of a file: ferraris, psins_vehicle, psins_lasergyro, "
        "broad_05, broad_18",
    )  # fmt: skip


def check_viewer_args(args: argparse.Namespace) -> None:
    """Refuse what cannot work before the run, not after it."""
    if not (args.rerun or args.spawn or args.serve):
        return
    from sins import viz

    if args.spawn and not viz.has_display():
        raise SinsInputError(
            f"--spawn: {viz.NO_DISPLAY}; use --rerun OUT.rrd to save a recording, "
            "or --serve for the web viewer"
        )
    if args.rerun:
        viz.check_rrd_path(args.rerun)


def show(args: argparse.Namespace, result: ScenarioRun, summary: str) -> None:
    """Hand the run to Rerun as the flags ask: save, spawn the native viewer, serve the web viewer."""
    if not (args.rerun or args.spawn or args.serve):
        return
    from sins import viz

    if args.rerun:
        viz.save(result, args.rerun, summary=summary)
        print(f"wrote {args.rerun} (open it with: rerun {args.rerun})")
    if args.spawn:
        viz.spawn(result, summary=summary)
    if args.serve:
        try:
            address = viz.serve(result, summary=summary, web_port=args.web_port)
        except SinsInputError as exc:
            raise SinsInputError(f"--serve: {exc}") from None
        print(f"serving the Rerun web viewer at {address}  (Ctrl-C stops)", flush=True)
        import time

        while True:  # the servers live as long as this process
            time.sleep(3600)
