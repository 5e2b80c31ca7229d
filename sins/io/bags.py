"""ROS 1 bags, ROS 2 bags and MCAP files (read with ``rosbags``): ``sensor_msgs/Imu`` as readings, poses as
the reference trajectory, ``sensor_msgs/NavSatFix`` as geodetic fixes.

* A ROS 2 bag is a folder with ``metadata.yaml`` beside its ``.db3`` (SQLite) or ``.mcap`` files; a
  ROS 1 bag a ``.bag`` file; an MCAP file (ROS 2 messages in CDR) or a lone ``.db3`` is read as well.
* Readings: the IMU topic is the one ``sensor_msgs/Imu`` topic, or the one named. Times are the
  messages' header stamps (the sensor's clock; the recorder's times where every stamp is zero),
  in seconds from the first reading's stamp; ``t0_ns`` keeps that stamp. ROS's body frame is FLU (REP
  103): the readings are turned into FRD (y and z negated) unless another frame is named.
* Reference: ``nav_msgs/Odometry``, ``geometry_msgs/PoseStamped``, ``PoseWithCovarianceStamped`` or
  ``TransformStamped``, the one such topic or the one named. Its poses are of the body (REP 103's FLU,
  which the IMU is taken to be aligned with: no ``tf`` lookup) in a local ENU frame (REP 103/105's
  ``odom`` or ``map``); placed on the ellipsoid at the first valid ``NavSatFix`` or at a given origin
  (:func:`sins.io.local.enu_track`). Odometry's twist is in the body frame (its ``child_frame_id``), as
  the message defines; the other types' velocities are differentiated from the positions.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sins.core import rotation
from sins.core.series import ImuRates, NavSeries
from sins.errors import MissingInputError, SinsInputError
from sins.io import axes, formats, local

Array = NDArray[np.float64]

#: How a note begins when a bag has several pose topics and none was named (no reference read).
SEVERAL_POSES = "no reference read"
IMU_TYPE = "sensor_msgs/msg/Imu"
FIX_TYPE = "sensor_msgs/msg/NavSatFix"
#: Message types read as the reference trajectory.
POSE_TYPES = (
    "nav_msgs/msg/Odometry",
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/PoseWithCovarianceStamped",
    "geometry_msgs/msg/TransformStamped",
)


@dataclass(frozen=True)
class GeodeticFixes:
    """Positions on the ellipsoid: ``t`` (n,) s, ``lat``, ``lon`` (n,) rad, ``h`` (n,) m (ellipsoidal)."""

    t: Array
    lat: Array
    lon: Array
    h: Array


@dataclass(frozen=True)
class BagRead:
    """What :func:`_read_bag` read. ``imu`` in SI on FRD axes (after ``frame``); ``receive_t`` the recorder's
    time of each reading, s from the same ``t0_ns``; ``truth`` and ``fixes`` None where the bag has none."""

    imu: ImuRates
    t0_ns: int
    receive_t: Array
    imu_topic: str
    truth: NavSeries | None
    truth_topic: str | None
    fixes: GeodeticFixes | None
    notes: tuple[str, ...]


def bag_kind(path: Path) -> str | None:
    """``"ros2 bag"``, ``"ros1 bag"`` or ``"mcap"`` (a lone ``.db3`` counts as a ROS 2 bag), or None."""
    if path.is_dir():
        return "ros2 bag" if (path / "metadata.yaml").is_file() else None
    try:
        with open(path, "rb") as fh:
            head = fh.read(16)
    except OSError:
        return None
    if head.startswith(b"#ROSBAG V2.0"):
        return "ros1 bag"
    if head.startswith(b"\x89MCAP0\r\n"):
        return "mcap"
    if head.startswith(b"SQLite format 3\x00") and path.suffix == ".db3":
        return "ros2 bag"
    return None


def _read_bag(
    path: str | os.PathLike[str],
    topic: str | None = None,
    truth_topic: str | None = None,
    *,
    frame: str = axes.FLU,
    origin: tuple[float, float, float] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> BagRead:
    """Read a bag's IMU readings, its reference trajectory and its fixes (see the module docstring).

    Parameters
    ----------
    path : a ROS 2 bag folder, a ROS 1 ``.bag``, an ``.mcap`` or a ``.db3`` file
    topic : the IMU topic; None: the bag's only ``sensor_msgs/Imu`` topic
    truth_topic : the reference topic; None: the bag's only pose topic (none, or a note, when several)
    frame : the readings' axes (:mod:`sins.io.axes`), FLU by ROS's convention
    origin : ``(lat, lon, h)`` (rad, rad, m) of the poses' local frame; None: the first valid fix, else
        :data:`sins.io.local.NOMINAL_ORIGIN` (said in the notes)
    progress : called as ``progress(messages_read, messages)``

    Raises
    ------
    SinsInputError
        a file rosbags cannot read (its message in one line); a named topic the bag lacks or of another
        type; no IMU topic; stamps that do not increase (naming the topic and message); readings
        beyond sins's physical ranges.
    MissingInputError
        several IMU topics and none named (``needs="topic"``), or a named reference topic absent
        (``needs="truth_topic"``).
    """
    path = Path(path)
    m_frame = axes.frame_matrix(frame)
    suffix = {"ros1 bag": ".bag", "mcap": ".mcap"}.get(bag_kind(path) or "", path.suffix)
    if path.is_file() and path.suffix != suffix:
        raise SinsInputError(
            f"{path}: {bag_kind(path)} file: rosbags reads it only under a name ending {suffix}"
        )
    try:
        got = _collect(path, topic, truth_topic, progress)
    except (SinsInputError, KeyboardInterrupt):
        raise
    except Exception as exc:  # rosbags raises a dozen types (and struct, sqlite, zstd ones) on damaged files
        text = " ".join(str(exc).split()) or type(exc).__name__
        raise SinsInputError(f"{path}: cannot read it as a bag: {text}") from None
    notes = list(got.notes)
    imu, t0, receive_t, more = _imu(path, got.imu_topic, got.rows[got.imu_topic], m_frame, frame)
    notes += more
    fixes = None if got.fix_topic is None else _fixes(path, got.fix_topic, got.rows[got.fix_topic], t0)
    truth = None
    if got.ref_topic is not None:
        ref = got.ref_topic
        truth, more = _truth(path, ref, got.types[ref], got.rows[ref], t0, fixes, origin)
        notes += more
    return BagRead(imu, t0, receive_t, got.imu_topic, truth, got.ref_topic, fixes.fixes if fixes else None,
                   tuple(notes) + (fixes.notes if fixes else ()))  # fmt: skip


@dataclass(frozen=True)
class _Collected:
    """The messages' numbers per topic (see :func:`_row`), the topics' types, the chosen topics."""

    rows: dict[str, list[tuple[Any, ...]]]
    types: dict[str, str]
    imu_topic: str
    ref_topic: str | None
    fix_topic: str | None
    notes: tuple[str, ...]


def _collect(
    path: Path, topic: str | None, truth_topic: str | None, progress: Callable[[int, int], None] | None
) -> _Collected:
    """Choose the topics and read their messages' numbers (everything rosbags is asked for is here)."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    with AnyReader([path], default_typestore=get_typestore(Stores.LATEST)) as reader:
        types = {name: info.msgtype or "" for name, info in reader.topics.items()}
        imu_topic = _imu_topic(path, types, topic)
        ref_topic, notes = _truth_topic(path, types, truth_topic)
        fix_topic = next((n for n, t in sorted(types.items()) if t == FIX_TYPE), None)
        wanted = {imu_topic, *(t for t in (ref_topic, fix_topic) if t is not None)}
        conns = [c for c in reader.connections if c.topic in wanted]
        total = sum(c.msgcount for c in conns)
        rows: dict[str, list[tuple[Any, ...]]] = {name: [] for name in wanted}
        for done, (conn, received, raw) in enumerate(reader.messages(connections=conns), start=1):
            msg = reader.deserialize(raw, conn.msgtype)
            rows[conn.topic].append(_row(types[conn.topic], msg, received))
            if progress is not None and (done % 20000 == 0 or done == total):
                progress(done, total)
    return _Collected(rows, types, imu_topic, ref_topic, fix_topic, tuple(notes))


def _listing(types: dict[str, str]) -> str:
    return (
        ", ".join(f"{name} ({kind.replace('/msg/', '/')})" for name, kind in sorted(types.items())) or "none"
    )


def _imu_topic(path: Path, types: dict[str, str], topic: str | None) -> str:
    """The named IMU topic (checked) or the bag's only one."""
    if topic is not None:
        if topic not in types:
            raise SinsInputError(f"{path}: no topic {topic!r} (topics: {_listing(types)})")
        if types[topic] != IMU_TYPE:
            raise SinsInputError(
                f"{path}: topic {topic!r} holds {types[topic]}, not sensor_msgs/Imu readings"
            )
        return topic
    found = sorted(n for n, t in types.items() if t == IMU_TYPE)
    if not found:
        raise SinsInputError(f"{path}: no sensor_msgs/Imu topic (topics: {_listing(types)})")
    if len(found) > 1:
        raise MissingInputError(
            f"{path}: {len(found)} sensor_msgs/Imu topics ({', '.join(found)}); name the one to read",
            needs="topic",
        )
    return found[0]


def _truth_topic(path: Path, types: dict[str, str], truth_topic: str | None) -> tuple[str | None, list[str]]:
    """The named reference topic (checked), the bag's only one, or None (with a note when several)."""
    if truth_topic is not None:
        if types.get(truth_topic) not in POSE_TYPES:
            kinds = ", ".join(t.replace("/msg/", "/") for t in POSE_TYPES)
            held = f"holds {types[truth_topic]}" if truth_topic in types else "is not in the bag"
            raise MissingInputError(
                f"{path}: reference topic {truth_topic!r} {held}; a reference is one of {kinds} "
                f"(topics: {_listing(types)})",
                needs="truth_topic",
            )
        return truth_topic, []
    found = sorted(n for n, t in types.items() if t in POSE_TYPES)
    if len(found) > 1:
        return None, [f"{SEVERAL_POSES}: {len(found)} pose topics ({', '.join(found)}); name the one to read"]
    return (found[0] if found else None), []


def _stamp(header: Any, received: int) -> tuple[int, int]:
    return int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec), int(received)


def _xyz(v: Any) -> tuple[float, float, float]:
    return float(v.x), float(v.y), float(v.z)


def _xyzw(q: Any) -> tuple[float, float, float, float]:
    return float(q.x), float(q.y), float(q.z), float(q.w)


def _row(msgtype: str, msg: Any, received: int) -> tuple[Any, ...]:
    """One message's numbers: stamp and receive time (ns), then the type's fields."""
    stamp = _stamp(msg.header, received)
    if msgtype == IMU_TYPE:
        return (*stamp, *_xyz(msg.angular_velocity), *_xyz(msg.linear_acceleration))
    if msgtype == FIX_TYPE:
        return (
            *stamp,
            int(msg.status.status),
            float(msg.latitude),
            float(msg.longitude),
            float(msg.altitude),
        )
    if msgtype.endswith("Odometry"):
        pose = msg.pose.pose
        return (*stamp, *_xyz(pose.position), *_xyzw(pose.orientation), *_xyz(msg.twist.twist.linear))
    if msgtype.endswith("TransformStamped"):
        return (*stamp, *_xyz(msg.transform.translation), *_xyzw(msg.transform.rotation))
    pose = msg.pose.pose if msgtype.endswith("CovarianceStamped") else msg.pose
    return (*stamp, *_xyz(pose.position), *_xyzw(pose.orientation))


def _increasing(path: Path, topic: str, stamps: NDArray[np.int64]) -> None:
    if (k := formats.first_not_increasing(stamps)) is not None:
        raise SinsInputError(
            f"{path}: topic {topic}: message {k + 1}'s header stamp {stamps[k]} ns does not increase "
            f"(message {k}'s is {stamps[k - 1]} ns)"
        )


def _imu(
    path: Path, topic: str, rows: list[tuple[Any, ...]], m_frame: Array, frame: str
) -> tuple[ImuRates, int, Array, list[str]]:
    """The readings (FRD, s from the first stamp), that stamp, the receive times, notes."""
    if len(rows) < 2:
        raise SinsInputError(f"{path}: topic {topic} has {len(rows)} message(s); two or more are needed")
    stamps = np.array([r[0] for r in rows], dtype=np.int64)
    received = np.array([r[1] for r in rows], dtype=np.int64)
    notes = [f"IMU topic {topic}: {len(rows)} readings, axes {frame} turned into FRD"]
    if not stamps.any():
        stamps = received
        notes.append("every header stamp is zero: the recorder's times are used")
    _increasing(path, topic, stamps)
    t0 = int(stamps[0])
    values = np.array([r[2:] for r in rows], dtype=float)
    _check_values(path, topic, values)
    imu = ImuRates(
        t=(stamps - t0) / 1e9,
        omega_ib_b=axes.to_frd(values[:, :3], m_frame),
        f_ib_b=axes.to_frd(values[:, 3:], m_frame),
    )
    return imu, t0, (received - t0) / 1e9, notes


def _check_values(path: Path, topic: str, values: Array) -> None:
    """Finite readings within sins's ranges, naming the message and the field."""
    limits = np.repeat([formats.MAX_RATE_RADPS, formats.MAX_FORCE_MPS2], 3)
    bad = ~(np.abs(values) <= limits)
    if bad.any():
        k, c = (int(i) for i in np.argwhere(bad)[0])
        field = ("angular_velocity", "linear_acceleration")[c // 3] + "." + "xyz"[c % 3]
        raise SinsInputError(
            f"{path}: topic {topic}: message {k + 1}: {field} {float(values[k, c])!r} is not finite or "
            f"beyond ±{limits[c]:g} {'rad/s' if c < 3 else 'm/s²'}, outside any physical range"
        )


@dataclass(frozen=True)
class _Fixes:
    fixes: GeodeticFixes | None
    notes: tuple[str, ...]


def _fixes(path: Path, topic: str, rows: list[tuple[Any, ...]], t0: int) -> _Fixes:
    """The valid fixes (status >= 0, finite), s from ``t0``; the count of the others in a note."""
    if not rows:
        return _Fixes(None, ())
    a = np.array([r[2:] for r in rows], dtype=float)
    stamps = np.array([r[0] for r in rows], dtype=np.int64)
    ok = (a[:, 0] >= 0) & np.isfinite(a[:, 1:]).all(axis=1) & (np.abs(a[:, 1]) <= 90.0)
    notes = [f"fixes from {topic}: {int(ok.sum())} of {len(rows)}"]
    if not ok.all():
        notes[0] += f" ({int((~ok).sum())} without a fix or with non-finite positions left out)"
    if not ok.any():
        return _Fixes(None, tuple(notes))
    _increasing(path, topic, stamps[ok])
    lat, lon, h = np.radians(a[ok, 1]), np.radians(a[ok, 2]), a[ok, 3]
    return _Fixes(GeodeticFixes(t=(stamps[ok] - t0) / 1e9, lat=lat, lon=lon, h=h), tuple(notes))


def _truth(
    path: Path,
    topic: str,
    msgtype: str,
    rows: list[tuple[Any, ...]],
    t0: int,
    fixes: _Fixes | None,
    origin: tuple[float, float, float] | None,
) -> tuple[NavSeries | None, list[str]]:
    """The poses as a geodetic trajectory of the FRD body, and notes on where it was placed."""
    if len(rows) < 2:
        return None, [f"reference {topic}: {len(rows)} pose(s), too few for a trajectory"]
    stamps = np.array([r[0] for r in rows], dtype=np.int64)
    _increasing(path, topic, stamps)
    a = np.array([r[2:] for r in rows], dtype=float)
    if not np.isfinite(a).all():
        k = int(np.argmax(~np.isfinite(a).all(axis=1)))
        raise SinsInputError(f"{path}: topic {topic}: message {k + 1} holds a non-finite pose")
    with np.errstate(over="ignore"):  # a quaternion of 1e200: its norm overflows to inf, refused below
        norm = np.linalg.norm(a[:, 3:7], axis=1)
    if not (np.abs(norm - 1.0) <= 1e-3).all():  # as EuRoC's: a zero quaternion is not a rotation
        k = int(np.argmax(~(np.abs(norm - 1.0) <= 1e-3)))
        raise SinsInputError(
            f"{path}: topic {topic}: message {k + 1}: orientation (x, y, z, w) has norm "
            f"{float(norm[k]):.6g}, not a unit quaternion"
        )
    q = rotation.quat_normalize(a[:, 3:7])
    v_enu = None
    if msgtype.endswith("Odometry"):
        v_enu = np.einsum("nij,nj->ni", rotation.dcm_from_quat(q), a[:, 7:10])
    where, note = _origin(origin, fixes.fixes if fixes else None)
    truth = local.enu_track(
        (stamps - t0) / 1e9, a[:, :3], where, q_enu_body=q, v_enu=v_enu,
        body_to_frd=axes.frame_matrix(axes.FLU), source=f"{path}: topic {topic}",
    )  # fmt: skip
    return truth, [f"reference {topic} ({msgtype.replace('/msg/', '/')}): {len(rows)} poses, ENU and FLU "
                   f"turned into NED and FRD, {note}"]  # fmt: skip


def _origin(
    origin: tuple[float, float, float] | None, fixes: GeodeticFixes | None
) -> tuple[tuple[float, float, float], str]:
    if origin is not None:
        return origin, f"origin {local.describe_origin(origin)} as given"
    if fixes is not None:
        first = (float(fixes.lat[0]), float(fixes.lon[0]), float(fixes.h[0]))
        return first, f"origin at the first fix, {local.describe_origin(first)}"
    # Placed nowhere, the ENU frame's latitude is not the unit's: Earth's rate cannot be placed in it, as
    # in a room's (:func:`sins.io.recording._read_path` sets the flags that leave it out).
    return (
        local.NOMINAL_ORIGIN,
        f"origin at {local.NOMINAL_PLACE} (no fix in the bag): its latitude is not known, so Earth's rate is "
        "left out of what is judged against it (give --origin for the place)",
    )


__all__ = [
    "FIX_TYPE",
    "IMU_TYPE",
    "POSE_TYPES",
    "SEVERAL_POSES",
    "BagRead",
    "GeodeticFixes",
    "bag_kind",
]
