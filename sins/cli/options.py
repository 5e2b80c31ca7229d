"""The options commands share: argument types, datasets by name, how to read a recording, pictures."""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sins.errors import SinsInputError

if TYPE_CHECKING:
    from sins.io.recording import Recording


def positive(text: str) -> float:
    """An argument type: a finite number above 0."""
    value = float(text)
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text}")
    return value


def finite(text: str) -> float:
    """An argument type: a finite number (``nan`` and ``inf`` refused)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text}")
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


def add_dataset(p: argparse.ArgumentParser, *, repeat: str = "") -> None:
    """``--dataset NAME`` (sins.io.datasets.NAMES, written out: importing the readers would slow every
    command's start); with ``repeat`` (what several do, for the help), given once per recording."""
    p.add_argument(
        "--dataset", metavar="NAME", action="append" if repeat else "store",
        help="a real dataset from the data root instead of a file: ferraris, ferraris_annotated, "
        "psins_vehicle, psins_lasergyro, broad_05, broad_18 (and broad_NN for every NN_*.mat in the data "
        "root's broad_mocap/), or FOLDER/NAME for any NAME.npz in a folder of the data root "
        "(euroc/V1_01_easy)" + (f"; repeat it {repeat}" if repeat else ""),
    )  # fmt: skip


def add_recording_options(p: argparse.ArgumentParser) -> None:
    """The options that say how to read a recording that is not a sins CSV (:func:`sins.io.read`;
    the formats guide lists them): every command that takes a recording path adds them, and passes
    :func:`recording_options` on."""
    g = p.add_argument_group(
        "recording formats",
        "a sins CSV, a CSV with its own columns, a ROS 1 bag, a ROS 2 bag folder, an MCAP file, a "
        "EuRoC/TUM-VI folder or an .npz of t_s, gyro_rad_s, accel_m_s2 (docs/guide/formats.md)",
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
        help="where a bag's, EuRoC's or an .npz's local reference frame lies, degrees, degrees, metres "
        "(default: a bag's first NavSatFix, else 45° N, 0° E, 0 m)",
    )  # fmt: skip


def read_recording(
    args: argparse.Namespace,
    recording: str | os.PathLike[str] | None,
    dataset: str | None,
    truth: str | os.PathLike[str] | None = None,
    progress: Callable[[int, int], None] | None = None,
    options: dict[str, Any] | None = None,
    raw: str = "",
) -> Recording:
    """A command's recording through :func:`sins.io.read`: a path with :func:`add_recording_options`'s
    flags (or the reader ``options`` given), or a dataset's name (the refusals said in the command's own
    flags); ``raw``: a recording a model corrected already is refused, for that reason."""
    from sins import io
    from sins.io.provenance import read_provenance

    if (recording is None) == (dataset is None):
        raise SinsInputError("give a RECORDING or --dataset NAME (one of them)")
    if raw and recording is not None and (by := read_provenance(recording).corrected_by):
        raise SinsInputError(f"{recording}: already corrected ({by}); {raw}: give the raw recording")
    chosen = recording_options(args) if options is None else options
    if dataset is not None:
        if truth is not None:
            raise SinsInputError("--truth goes with a RECORDING, not with --dataset")
        return io.read(dataset=dataset, **chosen)  # a format option given is refused: none applies
    return io.read(recording, truth=truth, **chosen, progress=progress)


def check_distinct(paths: list[str], datasets: list[str], command: str) -> None:
    """Refuse a recording given twice to a command that takes several (``gap``: its verdicts would agree
    with themselves; ``evaluate``: its mean would count it twice; ``fit``: it would weigh twice, and the
    guard holding recordings back would judge the fit on a copy of a recording it was fitted on), before
    any is read: by name, and by the file itself (device and inode), so that ``./r.npz`` beside ``r.npz``,
    a link to it, or a data root's ``FOLDER/NAME`` beside its path is the same recording too."""
    from sins.io.datasets.npz_folders import npz_path

    seen: set[str] = set()
    files: dict[tuple[int, int], str] = {}
    for name, is_path in [(p, True) for p in paths] + [(d, False) for d in datasets]:
        if name in seen:
            raise SinsInputError(f"{command}: {name} is given twice")
        seen.add(name)
        try:  # a name that is no file (yet) is the readers' to refuse
            st = os.stat(name if is_path else npz_path(name))
        except (OSError, SinsInputError):
            continue
        if (st.st_dev, st.st_ino) in files:
            raise SinsInputError(f"{command}: {name} and {files[st.st_dev, st.st_ino]} are one recording")
        files[st.st_dev, st.st_ino] = name


def recording_options(args: argparse.Namespace) -> dict[str, Any]:
    """The keyword arguments of :func:`sins.io.read` from :func:`add_recording_options`'s flags."""
    origin = None if args.origin is None else _origin(args.origin)
    return {
        "topic": args.topic, "truth_topic": args.truth_topic, "columns": args.columns, "units": args.units,
        "frame": args.frame, "rate_hz": args.rate, "origin": origin,
    }  # fmt: skip


def _origin(text: str) -> tuple[float, float, float]:
    """``(lat, lon, h)`` in rad, rad, m from ``"LAT,LON,H"`` in degrees, degrees, metres."""
    parts = text.split(",")
    try:
        lat, lon, h = (float(p) for p in parts)
    except ValueError:
        raise SinsInputError(f"--origin {text!r}: expected LAT,LON,H (degrees, degrees, metres)") from None
    from sins.core.earth import MAX_HEIGHT_M, MAX_LAT_DEG  # the readers' bounds (numpy: not at start-up)

    if not (abs(lat) <= MAX_LAT_DEG and abs(lon) <= 360.0 and abs(h) <= MAX_HEIGHT_M):
        raise SinsInputError(f"--origin {text!r}: latitude ±{MAX_LAT_DEG:g}°, longitude ±360°, height ±1e5 m")
    return math.radians(lat), math.radians(lon), h


def add_plot(p: argparse.ArgumentParser, what: str) -> None:
    """``--plot OUT.png|.html``: a picture of ``what`` without a display (:mod:`sins.viz.plots`)."""
    p.add_argument(
        "--plot", type=Path, metavar="OUT.png|.html",
        help=f"draw {what} as a PNG image, or an HTML page holding it (no display needed)",
    )  # fmt: skip


def vertical_tau(args: argparse.Namespace, t: Any) -> float:
    """``--vertical-tau-s`` (10 s unless given; given, only with ``--vertical damp``, which reads it),
    refused naming the flag where the integrator refuses it beside the times ``t``."""
    from sins.nav.strapdown import damp_loop_problem

    if args.vertical_tau_s is not None and args.vertical != "damp":
        raise SinsInputError(f"--vertical-tau-s goes with --vertical damp (the channel is {args.vertical})")
    tau = 10.0 if args.vertical_tau_s is None else args.vertical_tau_s
    if problem := damp_loop_problem(args.vertical, tau, t):
        raise SinsInputError(f"--vertical-tau-s {tau:g}: {problem}")
    return float(tau)


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


__all__ = [
    "add_dataset",
    "add_plot",
    "add_recording_options",
    "check_distinct",
    "count",
    "dataset_inputs",
    "finite",
    "fraction",
    "positive",
    "read_recording",
    "recording_options",
    "seed",
    "vertical_tau",
]
