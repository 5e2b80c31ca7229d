"""What every command shares: tables, progress, argument types, the checks before the work."""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.runs.pipeline import ScenarioRun
    from sins.scenario import Scenario

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


#: Per-hour drift rates (the final horizontal error over the duration) are withheld for runs shorter than
#: this, s: a drift that grows as t² or t³ scaled from minutes to an hour says nothing (a 60 s bag's
#: 1.2 km reads 73,700 m/h) ...
MIN_RATE_S = 600.0
#: ... and marked as extrapolated for runs shorter than an hour.
HOUR_S = 3600.0
_RATE_KEYS = ("drift_rate_m_per_h", "drift_rate_nmi_per_h")


def format_table(summaries: dict[str, dict[str, Any]]) -> str:
    """A fixed-width table: one row per strategy, the headline errors as columns. The per-hour rates of a
    run under :data:`MIN_RATE_S` read "-", of one under an hour end in "*" (an extrapolation), each with
    a line below saying so."""
    head = ["strategy"] + [c[0] for c in _COLUMNS]
    rows, notes = [], set()
    for name, s in summaries.items():
        duration = float(s.get("duration_s", HOUR_S))
        cells = [name]
        for _, key, fmt in _COLUMNS:
            cell = fmt.format(s[key])
            if key in _RATE_KEYS and duration < MIN_RATE_S:
                cell = "-"
                notes.add(f"m/h, nmi/h: withheld for a run under {MIN_RATE_S / 60:g} min ({duration:.4g} s)")
            elif key in _RATE_KEYS and duration < HOUR_S:
                cell += "*"
                notes.add(
                    f"* the {duration:.4g} s run's final horizontal error scaled to an hour: an extrapolation"
                )
            cells.append(cell)
        rows.append(cells)
    return "\n".join([fixed_width(head, rows), *sorted(notes)])


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


#: A job's first progress line in a log comes after this long, s (shorter jobs write none) ...
LOG_FIRST_S = 5.0
#: ... and the next ones at most this often, s.
LOG_EVERY_S = 10.0


class LogProgress:
    """Progress for a log (stderr not a terminal): plain lines, the first after :data:`LOG_FIRST_S`, then
    one every :data:`LOG_EVERY_S` while the job runs (a heartbeat thread writes them, so a job whose
    steps are long still shows it is alive), and a closing line if any was written. The part of tqdm's
    interface the commands use (``n``, ``total``, ``update``, ``set_postfix_str``, ``set_description``).
    """

    def __init__(self, description: str, unit: str, stream: Any = None) -> None:
        import threading
        import time

        self.description = description
        self.unit = unit if not unit or unit.endswith("s") else f"{unit}s"  # "12 rows" in a line
        self.stream = stream if stream is not None else sys.stderr
        self.n: int = 0
        self.total: int | None = None
        self.postfix = ""
        self.lines = 0
        self._start = time.monotonic()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._beat, name="sins-progress", daemon=True)
        self._thread.start()

    def _beat(self) -> None:
        wait = LOG_FIRST_S
        while not self._stop.wait(wait):
            self._line(self._state())
            wait = LOG_EVERY_S

    def _state(self) -> str:
        of = f"/{self.total}" if self.total else ""
        done = f"{self.n}{of} {self.unit}" if self.n or self.total else "working"
        return done + (f", {self.postfix}" if self.postfix else "")

    def _line(self, text: str) -> None:
        import time

        elapsed = time.monotonic() - self._start
        print(f"{self.description}: {text} ({elapsed:.0f} s)", file=self.stream, flush=True)
        self.lines += 1

    def update(self, count: int = 1) -> None:
        """``count`` more done."""
        self.n += count

    def set_postfix_str(self, text: str) -> None:
        """What is being done now (named in the next line)."""
        self.postfix = text

    def set_description(self, text: str) -> None:
        """Another stage of the job."""
        self.description = text

    def stop(self) -> None:
        """Stop the heartbeat."""
        self._stop.set()
        self._thread.join()

    def close(self) -> None:
        """Stop, and write a closing line if the job wrote any."""
        self.stop()
        if self.lines:
            self._line("done" + (f", {self.n} {self.unit}" if self.n else ""))


@contextmanager
def progress_bar(description: str, unit: str) -> Iterator[Any]:
    """Progress on stderr: a tqdm bar on a terminal; plain lines for a log or CI when the job runs past
    :data:`LOG_FIRST_S` (:class:`LogProgress`), nothing for a shorter one."""
    if not sys.stderr.isatty():
        log = LogProgress(description, unit)
        try:
            yield log
        except BaseException:
            log.stop()  # no closing line: the job's error is the last one
            raise
        log.close()
        return
    from tqdm import tqdm

    # A job without a count (one stage) shows its name and the time it has taken, not a rate of nothing.
    shape = {"unit": f" {unit}"} if unit else {"bar_format": "{desc}: {elapsed}"}
    with tqdm(desc=description, leave=False, file=sys.stderr, **shape) as bar:
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


def add_dataset(p: argparse.ArgumentParser, *, repeat: bool = False) -> None:
    """``--dataset NAME`` (sins.io.datasets.NAMES, written out: importing the readers would slow every
    command's start); with ``repeat``, given once per recording."""
    p.add_argument(
        "--dataset", metavar="NAME", action="append" if repeat else "store",
        help="a real dataset from the data root instead of a file: ferraris, ferraris_annotated, "
        "psins_vehicle, psins_lasergyro, broad_05, broad_18 (and broad_NN for every NN_*.mat in the data "
        "root's broad_mocap/), or FOLDER/NAME for any NAME.npz in a folder of the data root "
        "(euroc/V1_01_easy)" + ("; repeat it to fit on several recordings of one unit" if repeat else ""),
    )  # fmt: skip


def add_npz_dataset(p: argparse.ArgumentParser, positional: str) -> None:
    """``--dataset FOLDER/NAME`` for a command that reads a recording file: any ``NAME.npz`` in a folder
    of the data root, in place of the ``positional`` argument (:func:`npz_dataset` resolves it)."""
    p.add_argument(
        "--dataset", metavar="FOLDER/NAME",
        help=f"instead of {positional}: NAME.npz in a folder of the data root (euroc/V1_01_easy)",
    )  # fmt: skip


def npz_dataset(args: argparse.Namespace, positional: str) -> None:
    """Set ``args.<positional>`` to the file ``--dataset FOLDER/NAME`` names (one of them must be given).

    Raises
    ------
    SinsInputError
        for both or neither, or a name that is not ``FOLDER/NAME`` of an ``.npz`` in the data root.
    """
    given = getattr(args, positional)
    if (given is None) == (args.dataset is None):
        raise SinsInputError(f"give a {positional.upper()} or --dataset FOLDER/NAME (one of them)")
    if args.dataset is not None:
        from sins.io.datasets import npz_folders

        if not npz_folders.is_folder_name(args.dataset):
            raise SinsInputError(
                f"--dataset {args.dataset}: this command reads recordings as files; name an .npz one as "
                "FOLDER/NAME (the datasets by name go with fit, evaluate, correct, gap and characterise)"
            )
        setattr(args, positional, npz_folders.npz_path(args.dataset))


def add_recording_options(p: argparse.ArgumentParser) -> None:
    """The options that say how to read a recording that is not a sins CSV (``sins.io.read_recording_any``;
    the formats guide lists them): every command that takes a recording path adds them, and passes
    :func:`recording_options` on."""
    g = p.add_argument_group(
        "recording formats",
        "a sins CSV, a CSV with its own columns, a ROS 1 bag, a ROS 2 bag folder, an MCAP file or a "
        "EuRoC/TUM-VI folder (docs/guide/formats.md)",
    )
    g.add_argument("--topic", metavar="TOPIC", help="a bag's sensor_msgs/Imu topic, where it has several")
    g.add_argument(
        "--truth-topic", metavar="TOPIC",
        help="a bag's reference topic (Odometry, PoseStamped, TransformStamped), where it has several",
    )  # fmt: skip
    g.add_argument(
        "--columns", metavar="MAP", help="a CSV's own columns, sins name=file column: t=time,gyro_x=wx,..."
    )
    g.add_argument(
        "--units", metavar="MAP",
        help="the readings' units: t=ms,gyro=deg/s,accel=g (keys t, gyro, accel, dtheta, dv, temp)",
    )  # fmt: skip
    g.add_argument(
        "--frame", metavar="AXES",
        help="the readings' axes, three letters from f/b, r/l, d/u: frd (default), flu (ROS; bags' default)",
    )  # fmt: skip
    g.add_argument(
        "--rate", type=positive, metavar="HZ",
        help="the sampling rate: the times of a CSV without a time column; else the rate stated for the unit",
    )  # fmt: skip
    g.add_argument(
        "--origin", metavar="LAT,LON,H",
        help="where a bag's or EuRoC's local reference frame lies, degrees, degrees, metres "
        "(default: a bag's first NavSatFix, else 0,0,0)",
    )  # fmt: skip


def recording_options(args: argparse.Namespace) -> dict[str, Any]:
    """The keyword arguments of ``sins.io.read_recording_any`` from :func:`add_recording_options`'s flags."""
    return {
        "topic": args.topic,
        "truth_topic": args.truth_topic,
        "columns": args.columns,
        "units": args.units,
        "frame": args.frame,
        "rate_hz": args.rate,
        "origin": None if args.origin is None else _origin(args.origin),
    }


def _origin(text: str) -> tuple[float, float, float]:
    """``(lat, lon, h)`` in rad, rad, m from ``"LAT,LON,H"`` in degrees, degrees, metres."""
    parts = text.split(",")
    try:
        lat, lon, h = (float(p) for p in parts)
    except ValueError:
        raise SinsInputError(f"--origin {text!r}: expected LAT,LON,H (degrees, degrees, metres)") from None
    if not (abs(lat) <= 90.0 and abs(lon) <= 360.0 and abs(h) <= 1e5):
        raise SinsInputError(f"--origin {text!r}: latitude within ±90°, longitude ±360°, height ±1e5 m")
    return math.radians(lat), math.radians(lon), h


#: Why ``--spawn`` cannot open the native viewer (:func:`has_display`).
NO_DISPLAY = "no display to open the native viewer on (DISPLAY and WAYLAND_DISPLAY are unset)"


def has_display() -> bool:
    """Whether a native window can open here (always on macOS and Windows; X11 or Wayland elsewhere):
    :func:`sins.viz.viewer.has_display`, asked without importing the viewer's bridge (rerun takes seconds to
    import, and ``--spawn`` without a display is refused before any work)."""
    if sys.platform in ("darwin", "win32"):
        return True
    import os

    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def check_viewer_args(args: argparse.Namespace) -> None:
    """Refuse what cannot work before the run, not after it: ``--spawn`` without a display at once."""
    if not (args.rerun or args.spawn or args.serve):
        return
    if args.spawn and not has_display():
        raise SinsInputError(
            f"--spawn: {NO_DISPLAY}; use --rerun OUT.rrd to save a recording, or --serve for the web viewer"
        )
    if args.rerun:
        from sins.viz import viewer as viz

        viz.check_rrd_path(args.rerun)  # its suffix; the place is check_outputs's


def show(args: argparse.Namespace, result: ScenarioRun, summary: str) -> None:
    """Hand the run to Rerun as the flags ask: save, spawn the native viewer, serve the web viewer."""
    if not (args.rerun or args.spawn or args.serve):
        return
    from sins.viz import viewer as viz

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


def add_plot(p: argparse.ArgumentParser, what: str) -> None:
    """``--plot OUT.png|.html``: a picture of ``what`` without a display (:mod:`sins.viz.plots`)."""
    p.add_argument(
        "--plot", type=Path, metavar="OUT.png|.html",
        help=f"draw {what} as a PNG image, or an HTML page holding it (no display needed)",
    )  # fmt: skip


def check_outputs(
    outputs: dict[str, Path | None],
    inputs: Iterable[str | os.PathLike[str] | None] = (),
    folders: dict[str, Path | None] | None = None,
) -> None:
    """The one check of a command's outputs, before the work (:func:`sins.io.paths.check_outputs`):
    each can be written, none is an input (``inputs``: every file and folder the command reads) or
    another output. ``outputs`` and ``folders`` map each flag to its path (None: not asked for)."""
    from sins.io.paths import check_outputs as check

    check(outputs, inputs, folders)


def dataset_inputs(name: str | None) -> list[Path]:
    """The folder of the data root a ``--dataset`` is read from (``FOLDER/NAME``'s folder, a named
    dataset's own), as an input no output may be inside: an output there must not be one of its files."""
    if name is None:
        return []
    from sins.io.datasets.broad import BROAD_FOLDER
    from sins.io.datasets.ferraris import FERRARIS_FOLDER
    from sins.io.datasets.psins_lasergyro import PSINS_LASERGYRO_FOLDER
    from sins.io.datasets.psins_vehicle import PSINS_VEHICLE_FOLDER
    from sins.io.datasets.root import data_root

    folders = {"broad_": BROAD_FOLDER, "ferraris": FERRARIS_FOLDER, "psins_lasergyro": PSINS_LASERGYRO_FOLDER,
               "psins_vehicle": PSINS_VEHICLE_FOLDER}  # fmt: skip
    folder = (
        name.split("/")[0] if "/" in name else next((f for k, f in folders.items() if name.startswith(k)), "")
    )
    try:
        return [data_root() / folder] if folder else []
    except OSError:
        return []


def unit_of(recording: str | os.PathLike[str] | None, dataset: str | None, inputs: Any) -> str:
    """The unit a recording or dataset was read from ("" where it does not say): a dataset's named
    sensor, else its name; a recording's own (a sins CSV's ``# sensor:`` line, :mod:`sins.io.provenance`)."""
    named = str(getattr(inputs, "sensor", "") or "")
    if dataset is not None:
        return named or f"the {dataset} dataset's unit"
    if named or recording is None:
        return named
    from sins.io import provenance

    return provenance.read_provenance(recording).sensor


def simulated_unit(imu_file: Path | None) -> str:
    """What a file of a simulated unit's readings says of the unit (its ``# sensor:`` line): the IMU file
    and the unit it draws (a power-on seed is the same unit again)."""
    if imu_file is None:
        return "ideal IMU (simulated)"
    from sins import scenario

    spec = scenario.load_imu(imu_file)
    return f"simulated {imu_file.stem} unit (unit seed {spec.unit_seed})"


def scenario_inputs(sc: Scenario) -> list[Path | None]:
    """The files a scenario reads: its own, its IMU and rig files, its truth file."""
    from sins.scenario import TruthFileSpec

    truth = sc.trajectory.path if isinstance(sc.trajectory, TruthFileSpec) else None
    rig = sc.compensation.rig if sc.compensation is not None else None
    return [sc.source, sc.imu_model, rig, truth]


def check_plot(args: argparse.Namespace) -> None:
    """Refuse a ``--plot`` path that cannot be written, before the work."""
    if getattr(args, "plot", None):
        from sins.viz import plots

        plots.check_plot_path(args.plot)


def save_plot(path: Path, figure: Callable[[], Any], title: str) -> None:
    """Build the figure (``figure()``, a :mod:`sins.viz.plots` call) and save it at ``path``."""
    with progress_bar(f"drawing {path}", ""):  # matplotlib's import and a grid's layout take seconds
        from sins.viz import plots

        plots.save(figure(), path, title)
    print(f"wrote {path}")


__all__ = [
    "HOUR_S",
    "LOG_EVERY_S",
    "LOG_FIRST_S",
    "MIN_RATE_S",
    "NO_DISPLAY",
    "LogProgress",
    "Subparsers",
    "add_dataset",
    "add_npz_dataset",
    "add_plot",
    "add_recording_options",
    "advance",
    "check_finite",
    "check_outputs",
    "check_plot",
    "check_viewer_args",
    "count",
    "dataset_inputs",
    "display_unit",
    "fixed_width",
    "format_table",
    "fraction",
    "has_display",
    "npz_dataset",
    "positive",
    "progress_bar",
    "recording_options",
    "row_progress",
    "save_plot",
    "scenario_inputs",
    "seed",
    "settings",
    "show",
    "simulated_unit",
    "unit_of",
]
