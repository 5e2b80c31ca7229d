"""Recordings in other formats: ROS 1 and ROS 2 bags and MCAP (written here with rosbags), the EuRoC/TUM-VI
layout and CSVs with their own columns and units (written here with numpy), read back into sins's terms."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import refusal
from scipy.spatial.transform import Rotation

from sins import io
from sins.cli import main
from sins.core.earth import local_ned
from sins.errors import MissingInputError, SinsInputError
from sins.io import axes

SEED = 33
T0_NS = 1_700_000_000_123_456_789  # a Unix-time stamp: seconds alone would lose the nanoseconds
FLU = np.array([1.0, -1.0, -1.0])  # REP 103's FLU into FRD: y and z negated, x kept


def _assert_one_line_error(rc: int, err: str, *fragments: str) -> None:
    assert rc == 2, err
    assert err.startswith("sins: error: ") and err.count("\n") == 1, err
    for fragment in fragments:
        assert fragment in err, (fragment, err)


# --------------------------------------------------------------------------- bags, written with rosbags


def _typestore(ros1: bool):  # type: ignore[no-untyped-def]
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)


def _header(ts, ns: int, frame: str, seq: int = 0):  # type: ignore[no-untyped-def]
    header, time = ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    stamp = time(sec=ns // 10**9, nanosec=ns % 10**9)
    if "seq" in header.__dataclass_fields__:  # ROS 1's header has a sequence number
        return header(seq=seq, stamp=stamp, frame_id=frame)
    return header(stamp=stamp, frame_id=frame)


def _imu_msg(ts, ns: int, w: np.ndarray, f: np.ndarray, seq: int):  # type: ignore[no-untyped-def]
    vec, quat = ts.types["geometry_msgs/msg/Vector3"], ts.types["geometry_msgs/msg/Quaternion"]
    return ts.types["sensor_msgs/msg/Imu"](
        header=_header(ts, ns, "imu_link", seq), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=np.full(9, -1.0), angular_velocity=vec(x=w[0], y=w[1], z=w[2]),
        angular_velocity_covariance=np.zeros(9), linear_acceleration=vec(x=f[0], y=f[1], z=f[2]),
        linear_acceleration_covariance=np.zeros(9),
    )  # fmt: skip


def _odometry_msg(ts, ns: int, p: np.ndarray, q: np.ndarray, v_body: np.ndarray):  # type: ignore[no-untyped-def]
    t = ts.types
    pose = t["geometry_msgs/msg/Pose"](
        position=t["geometry_msgs/msg/Point"](x=p[0], y=p[1], z=p[2]),
        orientation=t["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3]),
    )
    zero = t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    twist = t["geometry_msgs/msg/Twist"](
        linear=t["geometry_msgs/msg/Vector3"](x=v_body[0], y=v_body[1], z=v_body[2]), angular=zero
    )
    return t["nav_msgs/msg/Odometry"](
        header=_header(ts, ns, "odom"), child_frame_id="base_link",
        pose=t["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
        twist=t["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36)),
    )  # fmt: skip


def _pose_msg(ts, kind: str, ns: int, p: np.ndarray, q: np.ndarray):  # type: ignore[no-untyped-def]
    """A ``geometry_msgs/PoseStamped`` or ``TransformStamped`` of the body in ``odom``."""
    t = ts.types
    quat = t["geometry_msgs/msg/Quaternion"](x=q[0], y=q[1], z=q[2], w=q[3])
    if kind == "pose":
        pose = t["geometry_msgs/msg/Pose"](position=t["geometry_msgs/msg/Point"](x=p[0], y=p[1], z=p[2]),
                                           orientation=quat)  # fmt: skip
        return t["geometry_msgs/msg/PoseStamped"](header=_header(ts, ns, "odom"), pose=pose)
    moved = t["geometry_msgs/msg/Transform"](
        translation=t["geometry_msgs/msg/Vector3"](x=p[0], y=p[1], z=p[2]), rotation=quat
    )
    return t["geometry_msgs/msg/TransformStamped"](
        header=_header(ts, ns, "odom"), child_frame_id="base_link", transform=moved
    )


def _fix_msg(ts, ns: int, lat: float, lon: float, alt: float, status: int):  # type: ignore[no-untyped-def]
    t = ts.types
    return t["sensor_msgs/msg/NavSatFix"](
        header=_header(ts, ns, "gps"), status=t["sensor_msgs/msg/NavSatStatus"](status=status, service=1),
        latitude=lat, longitude=lon, altitude=alt, position_covariance=np.zeros(9),
        position_covariance_type=0,
    )  # fmt: skip


def _bag_data(n: int = 400) -> dict[str, np.ndarray]:
    """Random readings (every bit of the floats matters), 100 Hz stamps, and a level drive in ENU."""
    rng = np.random.default_rng(SEED)
    t = np.arange(n) / 100.0
    yaw_enu = np.radians(20.0) + 0.05 * t  # the FLU body's heading, counter-clockwise from east
    speed = 10.0
    east, north = np.cumsum(speed * np.cos(yaw_enu)) / 100.0, np.cumsum(speed * np.sin(yaw_enu)) / 100.0
    p = np.column_stack([east, north, 0.02 * t])
    return {
        "ns": T0_NS + np.arange(n, dtype=np.int64) * 10_000_000,
        "w": rng.normal(0.0, 0.3, (n, 3)),
        "f": rng.normal(0.0, 3.0, (n, 3)) + np.array([0.0, 0.0, 9.8]),
        "p": p,
        "q": Rotation.from_euler("z", yaw_enu[:, None]).as_quat(),  # scalar-last, as ROS and scipy
        "v_body": np.column_stack([np.full(n, speed), np.zeros(n), np.full(n, 0.02)]),
        "yaw_enu": yaw_enu,
    }


def _write_bag(
    path: Path,
    kind: str,
    d: dict[str, np.ndarray],
    *,
    imu_topics: tuple[str, ...] = ("/imu",),
    odometry: bool = True,
    fixes: bool = True,
    stamps: np.ndarray | None = None,
    pose: str = "odometry",
) -> Path:
    """A bag of ``kind`` ("ros1", "ros2", "ros2-mcap") with the readings on each IMU topic (in FLU, as
    ROS has them), odometry at every fourth reading and a fix every tenth (the first without a fix)."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2

    ros1 = kind == "ros1"
    ts = _typestore(ros1)
    serialize = ts.serialize_ros1 if ros1 else ts.serialize_cdr
    storage = StoragePlugin.MCAP if kind == "ros2-mcap" else StoragePlugin.SQLITE3
    writer = Writer1(path) if ros1 else Writer2(path, version=9, storage_plugin=storage)
    stamps = d["ns"] if stamps is None else stamps
    with writer:
        imu = [writer.add_connection(name, "sensor_msgs/msg/Imu", typestore=ts) for name in imu_topics]
        pose_type = {"odometry": "nav_msgs/msg/Odometry", "pose": "geometry_msgs/msg/PoseStamped",
                     "transform": "geometry_msgs/msg/TransformStamped"}[pose]  # fmt: skip
        odo = writer.add_connection("/odom", pose_type, typestore=ts) if odometry else None
        gps = writer.add_connection("/fix", "sensor_msgs/msg/NavSatFix", typestore=ts) if fixes else None
        for k, ns in enumerate(d["ns"].tolist()):
            received = ns + 2_000_000  # the recorder gets each message 2 ms after its stamp
            for c in imu:
                msg = _imu_msg(ts, int(stamps[k]), d["w"][k], d["f"][k], k)
                writer.write(c, received, serialize(msg, "sensor_msgs/msg/Imu"))
            if odo is not None and k % 4 == 0:
                if pose == "odometry":
                    msg = _odometry_msg(ts, ns, d["p"][k], d["q"][k], d["v_body"][k])
                else:
                    msg = _pose_msg(ts, pose, ns, d["p"][k], d["q"][k])
                writer.write(odo, received, serialize(msg, pose_type))
            if gps is not None and k % 10 == 0:
                msg = _fix_msg(ts, ns, 45.0 + 1e-5 * k, 7.5, 250.0 + k, -1 if k == 0 else 0)
                writer.write(gps, received, serialize(msg, "sensor_msgs/msg/NavSatFix"))
    return path


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("bags")
    data = _bag_data()
    out = {
        "ros2": _write_bag(d / "ros2", "ros2", data),
        "ros2-mcap": _write_bag(d / "ros2mcap", "ros2-mcap", data),
        "ros1": _write_bag(d / "drive.bag", "ros1", data),
    }
    # An MCAP file on its own, without the bag folder's metadata.yaml.
    out["mcap"] = Path(shutil.copy(next(out["ros2-mcap"].glob("*.mcap")), d / "alone.mcap"))
    return out


@pytest.mark.parametrize("kind", ["ros2", "ros2-mcap", "ros1", "mcap"])
def test_a_bag_reads_back_the_floats_written_turned_from_flu_into_frd(
    bags: dict[str, Path], kind: str
) -> None:
    d = _bag_data()
    rec = io.read(bags[kind])
    assert rec.kind == {"ros2": "ros2 bag", "ros2-mcap": "ros2 bag", "ros1": "ros1 bag", "mcap": "mcap"}[kind]
    # Exact: the conversion only negates y and z.
    np.testing.assert_array_equal(rec.imu.omega_ib_b, d["w"] * FLU)
    np.testing.assert_array_equal(rec.imu.f_ib_b, d["f"] * FLU)
    assert rec.t0_ns == T0_NS
    # Times from the first stamp: within half a nanosecond's rounding of k / 100 s.
    np.testing.assert_allclose(rec.imu.t, np.arange(len(d["w"])) / 100.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rec.receive_t, rec.imu.t + 0.002, rtol=0, atol=1e-12)
    assert rec.frame == "flu"


@pytest.mark.parametrize("kind", ["ros2", "ros1"])
def test_a_bags_odometry_is_the_truth_in_ned_and_frd_placed_at_the_first_valid_fix(
    bags: dict[str, Path], kind: str
) -> None:
    d = _bag_data()
    rec = io.read(bags[kind])
    truth = rec.truth
    assert truth is not None and len(truth.t) == 100
    assert rec.heading_known and rec.latitude_known  # a fix places the ENU frame
    # The first fix has no fix (status -1) and is left out, said in the notes; the origin is the second.
    assert rec.fixes is not None and len(rec.fixes.t) == 39
    lat0, lon0, h0 = np.radians(45.0 + 1e-4), np.radians(7.5), 260.0
    assert rec.fixes.lat[0] == np.radians(45.0 + 1e-4) and rec.fixes.h[0] == 260.0
    assert any("1 without a fix" in note for note in rec.notes)
    # Positions: back in the origin's NED through ECEF (sins's forward transform, independent of the
    # reader's inverse): north = ENU y, east = x, down = -z, to 1e-6 m (the inverse's 1e-12 rad).
    ned = local_ned(truth.lat, truth.lon, truth.h, lat0, lon0, h0)
    p = d["p"][::4]
    np.testing.assert_allclose(ned, np.column_stack([p[:, 1], p[:, 0], -p[:, 2]]), rtol=0, atol=1e-6)
    # Attitude: a level FLU body heading yaw_enu (counter-clockwise from east) is an FRD body heading
    # 90° - yaw_enu clockwise from north; the NED axes 40 m from the origin turn by under 1e-5 rad.
    roll, pitch, yaw = truth.euler()
    expected = np.angle(np.exp(1j * (np.pi / 2 - d["yaw_enu"][::4])))
    np.testing.assert_allclose(np.angle(np.exp(1j * (yaw - expected))), 0.0, atol=2e-5)
    np.testing.assert_allclose(np.column_stack([roll, pitch]), 0.0, atol=2e-5)
    # Velocity: the body's 10 m/s forward and 0.02 m/s up, in NED; the same 1e-5 rad turn at most.
    v = 10.0 * np.column_stack([np.sin(d["yaw_enu"][::4]), np.cos(d["yaw_enu"][::4]), np.zeros(100)])
    np.testing.assert_allclose(truth.v_n, v + np.array([0.0, 0.0, -0.02]), rtol=0, atol=2e-4)


@pytest.mark.parametrize("pose", ["pose", "transform"])
def test_poses_and_transforms_are_a_truth_with_differentiated_velocity(tmp_path: Path, pose: str) -> None:
    d = _bag_data()
    rec = io.read(_write_bag(tmp_path / pose, "ros2", d, pose=pose), origin=(0.8, 0.1, 50.0))
    assert rec.truth is not None and any("as given" in note for note in rec.notes)
    ned = local_ned(rec.truth.lat, rec.truth.lon, rec.truth.h, 0.8, 0.1, 50.0)
    p = d["p"][::4]
    np.testing.assert_allclose(ned, np.column_stack([p[:, 1], p[:, 0], -p[:, 2]]), rtol=0, atol=1e-6)
    # Differences of 25 Hz poses on an arc turning 0.05 rad/s at 10 m/s. The path (a cumulative sum at
    # 100 Hz) lags its velocity by half a step: 0.05 × 0.005 × 10 = 2.5e-3 m/s inside, where the
    # differences are central; the two ends' one-sided ones turn 0.02 s more: 1e-2 m/s more.
    yaw = d["yaw_enu"][::4]
    v = np.column_stack([10.0 * np.sin(yaw), 10.0 * np.cos(yaw), np.full(100, -0.02)])
    np.testing.assert_allclose(rec.truth.v_n[1:-1], v[1:-1], rtol=0, atol=3e-3)
    np.testing.assert_allclose(rec.truth.v_n[[0, -1]], v[[0, -1]], rtol=0, atol=1.5e-2)


def test_an_imu_topic_is_chosen_when_there_are_several(tmp_path: Path) -> None:
    d = _bag_data(50)
    bag = _write_bag(
        tmp_path / "two", "ros2", d, imu_topics=("/imu/a", "/imu/b"), odometry=False, fixes=False
    )
    with pytest.raises(MissingInputError) as info:
        io.read(bag)
    assert info.value.needs == "topic" and "/imu/a, /imu/b" in str(info.value)
    assert io.read(bag, topic="/imu/b").imu.omega_ib_b[0, 0] == d["w"][0, 0]
    refusal(lambda: io.read(bag, topic="/nope"), "no topic '/nope'", "/imu/a (sensor_msgs/Imu)")
    rc = main(["inspect", str(bag)])
    assert rc == 2


def test_the_cli_names_the_topic_flag(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag = _write_bag(tmp_path / "two.bag", "ros1", _bag_data(20), imu_topics=("/a", "/b"), odometry=False)
    _assert_one_line_error(main(["inspect", str(bag)]), capsys.readouterr().err, "/a, /b", "--topic TOPIC")
    assert main(["inspect", str(bag), "--topic", "/a"]) == 0


def test_bag_refusals_are_one_line(tmp_path: Path, bags: dict[str, Path]) -> None:
    d = _bag_data(30)
    back = d["ns"].copy()
    back[7] = back[5]
    bag = _write_bag(tmp_path / "back", "ros2", d, odometry=False, fixes=False, stamps=back)
    refusal(lambda: io.read(bag), "topic /imu: message 8's header stamp", "does not increase")
    # Every stamp zero (a driver that never sets them): the recorder's times, said in the notes.
    zero = _write_bag(
        tmp_path / "zero.bag", "ros1", d, odometry=False, fixes=False, stamps=np.zeros(30, np.int64)
    )
    rec = io.read(zero)
    assert any("recorder's times" in note for note in rec.notes)
    np.testing.assert_allclose(rec.imu.t, np.arange(30) / 100.0, atol=1e-12)
    damaged = tmp_path / "damaged.bag"
    damaged.write_bytes((bags["ros1"]).read_bytes()[:3000])
    refusal(lambda: io.read(damaged), str(damaged), "cannot read it as a bag")
    refusal(lambda: io.read(bags["ros1"], columns="t=time"), "columns: does not apply")
    refusal(lambda: io.read(bags["ros1"], truth_topic="/imu"), "holds sensor_msgs/msg/Imu")
    refusal(lambda: io.read(bags["ros1"], units="t=ms"), "t does not apply")
    refusal(lambda: io.read(tmp_path), "neither a ROS 2 bag", "EuRoC")
    renamed = Path(shutil.copy(bags["ros1"], tmp_path / "drive.data"))
    refusal(lambda: io.read(renamed), "ros1 bag file", "name ending .bag")


def _static_flu_bag(
    path: Path, seconds: float = 120.0, axes_of: np.ndarray = FLU, stretch: float = 1.0
) -> Path:
    """A still unit heading north-east at 45° N: gravity and Earth's rate with white noise, on FLU axes
    (``axes_of`` the signs that turn FRD into the bag's axes), stamped ``stretch`` times slower than its
    recorder's clock."""
    rng = np.random.default_rng(SEED + 1)
    n = int(seconds * 100)
    lat, yaw = np.radians(45.0), np.radians(45.0)
    c, s = np.cos(yaw), np.sin(yaw)
    w_n = 7.292115e-5 * np.array([np.cos(lat), 0.0, -np.sin(lat)])
    w_frd = np.array([c * w_n[0], -s * w_n[0], w_n[2]])
    g = 9.8061992  # Somigliana's normal gravity at 45° N, sea level (1e-7 is far below the noise)
    d = {
        "ns": T0_NS + np.arange(n, dtype=np.int64) * 10_000_000,
        "w": (w_frd + 3e-4 * rng.standard_normal((n, 3))) * axes_of,
        "f": (np.array([0.0, 0.0, -g]) + 0.01 * rng.standard_normal((n, 3))) * axes_of,
    }
    stamps = T0_NS + np.round(np.arange(n) * 10_000_000 * stretch).astype(np.int64)
    return _write_bag(path, "ros2", d, odometry=False, fixes=False, stamps=stamps)


def test_inspect_on_bags_names_frd_readings_and_a_drifting_sensor_clock(tmp_path: Path) -> None:
    def findings(bag: Path, *options: str) -> list[tuple[str, str | None]]:
        out = tmp_path / "inspect.json"
        assert main(["inspect", str(bag), *options, "--json", str(out)]) == 0
        return [(f["code"], f["value"]) for f in json.loads(out.read_text(encoding="utf-8"))["findings"]]

    assert findings(_static_flu_bag(tmp_path / "flu", 30.0)) == []
    # A driver that wrote FRD into ROS's FLU message: read as FLU, z points up; the file's axes are frd.
    frd = _static_flu_bag(tmp_path / "frd", 30.0, axes_of=np.ones(3))
    assert findings(frd) == [("axes", "frd")]
    assert findings(frd, "--frame", "frd") == []
    # Header stamps 2 % slower than the recorder's clock over the same 30 s.
    assert findings(_static_flu_bag(tmp_path / "slow", 30.0, stretch=1.02)) == [("clock_mismatch", None)]


def test_characterise_static_on_a_bag_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag = _static_flu_bag(tmp_path / "still")
    out = tmp_path / "still.json"
    assert main(["characterise", str(bag), "--static", "--json", str(out)]) == 0
    doc = json.loads(out.read_text(encoding="utf-8"))
    # 3e-4 rad/s and 0.01 m/s² white noise at 100 Hz: N = σ / √rate; the fit within 10 % (12,000 rows).
    assert doc["rows"] == 12000 and doc["rate_hz"] == pytest.approx(100.0)
    n_gyro = doc["channels"]["gyro.z"]["terms"]["white"]["value"]
    n_accel = doc["channels"]["accel.z"]["terms"]["white"]["value"]
    assert n_gyro == pytest.approx(3e-4 / 10.0, rel=0.1)
    assert n_accel == pytest.approx(0.01 / 10.0, rel=0.1)


def test_integrate_a_bag_against_its_own_odometry(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    d = _bag_data()
    bag = _write_bag(tmp_path / "drive", "ros2", d)
    out = tmp_path / "run.json"
    assert main(["integrate", str(bag), "--json", str(out)]) == 0
    assert "against its own reference" in capsys.readouterr().out
    doc = json.loads(out.read_text(encoding="utf-8"))
    assert doc["truth"] is None and np.isfinite(doc["final_horizontal_m"])
    no_truth = _write_bag(tmp_path / "alone", "ros2", d, odometry=False, fixes=False)
    _assert_one_line_error(main(["integrate", str(no_truth)]), capsys.readouterr().err,
                           "no reference trajectory", "--truth TRUTH.csv")  # fmt: skip


# --------------------------------------------------------------------------- EuRoC and TUM-VI, numpy-written

ASL_IMU_HEADER = (
    "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
    "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"
)


def _asl(path: Path, header: str, ns: np.ndarray, values: np.ndarray) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = [header] + [
        f"{s}," + ",".join(repr(float(x)) for x in row) for s, row in zip(ns, values, strict=True)
    ]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _euroc(root: Path, reference: str = "state_groundtruth_estimate0") -> dict[str, np.ndarray]:
    rng = np.random.default_rng(SEED + 2)
    n = 1000
    ns = 1_403_636_579_758_555_392 + np.arange(n, dtype=np.int64) * 5_000_000  # EuRoC's 200 Hz
    w, f = rng.normal(0.0, 0.2, (n, 3)), rng.normal([9.8, 0.0, 0.0], 0.5, (n, 3))
    _asl(root / "mav0" / "imu0" / "data.csv", ASL_IMU_HEADER, ns, np.hstack([w, f]))
    (root / "mav0" / "imu0" / "sensor.yaml").write_text("sensor_type: imu\nrate_hz: 200\n", encoding="utf-8")
    ref_ns = ns[::4] + 1_000_000
    t = (ref_ns - ns[0]) / 1e9
    p = np.column_stack([2.0 * np.cos(0.5 * t), 2.0 * np.sin(0.5 * t), 1.0 + 0.1 * t])
    q = Rotation.from_euler("z", (0.5 * t + np.pi / 2)[:, None])  # the body's x along the circle, in R (ENU)
    wxyz = np.column_stack([q.as_quat()[:, 3], q.as_quat()[:, :3]])
    v = np.column_stack([-np.sin(0.5 * t), np.cos(0.5 * t), np.full(len(t), 0.1)])  # 2 m × 0.5 rad/s
    cols = [p, wxyz] if reference != "state_groundtruth_estimate0" else [p, wxyz, v, np.zeros((len(t), 6))]
    header = "#timestamp," + ",".join(["c"] * sum(c.shape[1] for c in cols))
    _asl(root / "mav0" / reference / "data.csv", header, ref_ns, np.hstack(cols))
    return {"ns": ns, "w": w, "f": f, "t_ref": t, "p": p, "v": v, "yaw_r": 0.5 * t + np.pi / 2}


@pytest.mark.parametrize("reference", ["state_groundtruth_estimate0", "mocap0"])
def test_euroc_layout_reads_back_exactly_with_its_reference(tmp_path: Path, reference: str) -> None:
    d = _euroc(tmp_path / "MH_01", reference)
    origin = (np.radians(47.37), np.radians(8.55), 400.0)
    rec = io.read(tmp_path / "MH_01", origin=origin)
    assert rec.kind == "euroc" and rec.t0_ns == d["ns"][0] and rec.stated_rate_hz == 200.0
    # The readings are the file's floats on S as they are (repr round-trips every float).
    np.testing.assert_array_equal(rec.imu.omega_ib_b, d["w"])
    np.testing.assert_array_equal(rec.imu.f_ib_b, d["f"])
    np.testing.assert_allclose(rec.imu.t, np.arange(1000) * 0.005, rtol=0, atol=1e-12)
    truth = rec.truth
    assert truth is not None
    np.testing.assert_allclose(truth.t, d["t_ref"], rtol=0, atol=1e-12)
    ned = local_ned(truth.lat, truth.lon, truth.h, *origin)
    np.testing.assert_allclose(ned, np.column_stack([d["p"][:, 1], d["p"][:, 0], -d["p"][:, 2]]), atol=1e-6)
    # R's yaw counter-clockwise from its x axis (east) is 90° less it clockwise from north.
    yaw = truth.euler()[2]
    np.testing.assert_allclose(np.angle(np.exp(1j * (yaw - (np.pi / 2 - d["yaw_r"])))), 0.0, atol=1e-6)
    v_ned = np.column_stack([d["v"][:, 1], d["v"][:, 0], -d["v"][:, 2]])
    # mocap0 has no velocity: differentiated from 50 Hz poses on a 2 m circle (error ω² r dt² / 6 ≈ 7e-5 m/s
    # inside, a first difference's ω² r dt / 2 ≈ 5e-3 at the two ends).
    atol = 1e-6 if reference == "state_groundtruth_estimate0" else 6e-3
    np.testing.assert_allclose(truth.v_n, v_ned, rtol=0, atol=atol)


def test_euroc_refusals_name_the_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _euroc(tmp_path / "bad")
    data = tmp_path / "bad" / "mav0" / "imu0" / "data.csv"
    lines = data.read_text(encoding="utf-8").splitlines()
    lines[5] = lines[5].replace(lines[5].split(",")[3], "x1")
    data.write_text("\n".join(lines) + "\n", encoding="utf-8")
    refusal(lambda: io.read(tmp_path / "bad"), f"{data}:6: column 'w_RS_S_z [rad s^-1]'")
    lines[5] = f"{int(lines[4].split(',')[0])}," + ",".join(["0.0"] * 6)
    data.write_text("\n".join(lines) + "\n", encoding="utf-8")
    refusal(lambda: io.read(data), f"{data}:6:", "does not increase")
    _assert_one_line_error(main(["inspect", str(tmp_path / "bad")]), capsys.readouterr().err, ":6:")


def test_a_euroc_reference_beyond_physics_or_not_a_file_is_named(tmp_path: Path) -> None:
    """The reference's position and velocity are held to the ``.npz`` reader's bounds (1e6 m, 1e3 m/s):
    one row at 1e300 m had fitted a model, 1e30 m/s integrated to a drift table. A folder or a FIFO where
    the reference's file should be is named, not taken for a recording without a reference."""
    _euroc(tmp_path / "bad")
    ref = tmp_path / "bad" / "mav0" / "state_groundtruth_estimate0" / "data.csv"
    good = ref.read_text(encoding="utf-8")
    for column, value, said in ((1, "1e300", "column 2: 1e+300 m is beyond ±1e+06"),
                                (9, "-2e3", "column 10: -2000 m/s is beyond ±1000")):  # fmt: skip
        lines = good.splitlines()
        cells = lines[7].split(",")
        cells[column] = value
        lines[7] = ",".join(cells)
        ref.write_text("\n".join(lines) + "\n", encoding="utf-8")
        refusal(lambda: io.read(tmp_path / "bad"), f"{ref}:8: {said}")
    ref.unlink()
    ref.mkdir()
    refusal(lambda: io.read(tmp_path / "bad"), str(ref))
    ref.rmdir()
    os.mkfifo(ref)
    refusal(lambda: io.read(tmp_path / "bad"), str(ref))


def test_an_asl_file_given_by_path_keeps_the_files_read_beside_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``mav0/imu0/data.csv`` given alone is read with its ``mav0``'s reference and ``sensor.yaml``: those
    are inputs too. Before, ``--out`` over the reference wrote the solution there and ``--json`` over
    ``sensor.yaml`` replaced it, both exiting 0; a new file beside them is still allowed."""
    _euroc(tmp_path / "MH_01")
    mav = tmp_path / "MH_01" / "mav0"
    data, truth, yaml = (
        mav / "imu0" / "data.csv",
        mav / "state_groundtruth_estimate0" / "data.csv",
        mav / "imu0" / "sensor.yaml",
    )
    before = {p: p.read_bytes() for p in (truth, yaml)}
    for argv in (["integrate", str(data), "--out", str(truth)], ["inspect", str(data), "--json", str(yaml)]):
        _assert_one_line_error(main(argv), capsys.readouterr().err, "is inside an input of this command")
    assert {p: p.read_bytes() for p in before} == before
    assert main(["inspect", str(data), "--json", str(mav / "imu0" / "new.json")]) == 0


# --------------------------------------------------------------------------- CSV with its own columns


def _own_csv(path: Path, n: int = 500) -> dict[str, np.ndarray]:
    """A logger's CSV: a label, milliseconds, deg/s, g, °F, in its own column order, written with numpy."""
    rng = np.random.default_rng(SEED + 3)
    ms = 1000.0 + 5.0 * np.arange(n)
    dps, g = rng.normal(0.0, 20.0, (n, 3)), rng.normal([0.0, 0.0, -1.0], 0.1, (n, 3))
    temp_f = rng.normal(70.0, 1.0, n)
    body = np.column_stack([ms, g, dps, temp_f])
    text = "\n".join(
        "run1," + ",".join(repr(float(x)) for x in row) for row in body
    )  # fmt: skip
    path.write_text("# logger v2\nlabel,time_ms,ax,ay,az,wx,wy,wz,temp_F\n" + text + "\n", encoding="utf-8")
    return {"ms": ms, "dps": dps, "g": g, "temp_f": temp_f}


COLUMNS = "t=time_ms,gyro_x=wx,gyro_y=wy,gyro_z=wz,accel_x=ax,accel_y=ay,accel_z=az,temp=temp_F"
UNITS = "t=ms,gyro=deg/s,accel=g,temp=degF"


def test_a_csv_with_its_own_columns_and_units(tmp_path: Path) -> None:
    d = _own_csv(tmp_path / "log.csv")
    rec = io.read(tmp_path / "log.csv", columns=COLUMNS, units=UNITS)
    # Each value times its unit's factor (one rounding: the file's floats are read exactly).
    np.testing.assert_array_equal(rec.imu.t, d["ms"] * 1e-3)
    np.testing.assert_array_equal(rec.imu.omega_ib_b, d["dps"] * (np.pi / 180.0))
    np.testing.assert_array_equal(rec.imu.f_ib_b, d["g"] * 9.80665)
    np.testing.assert_allclose(rec.temp, (d["temp_f"] - 32.0) * 5.0 / 9.0, rtol=1e-14)
    assert rec.units == {"t": "ms", "gyro": "deg/s", "accel": "g", "temp": "degF"}
    # The same file on FLU axes: y and z negated, exactly.
    flu = io.read(tmp_path / "log.csv", columns=COLUMNS, units=UNITS, frame="flu")
    np.testing.assert_array_equal(flu.imu.f_ib_b, rec.imu.f_ib_b * FLU)


def test_a_csv_without_time_takes_the_rate_and_increments_map_too(tmp_path: Path) -> None:
    d = _own_csv(tmp_path / "log.csv", 100)
    rec = io.read(tmp_path / "log.csv", columns=COLUMNS.replace("t=time_ms,", ""),
                                units=UNITS.replace("t=ms,", ""), rate_hz=200.0)  # fmt: skip
    np.testing.assert_array_equal(rec.imu.t, np.arange(100) / 200.0)
    assert rec.time_from_rate and rec.stated_rate_hz == 200.0
    inc = COLUMNS.replace("gyro_", "dtheta_").replace("accel_", "dv_")
    rec = io.read(tmp_path / "log.csv", columns=inc, units="t=ms,dtheta=deg,dv=g*s", t_start=0.995)
    assert rec.form == "increment" and rec.imu.t[0] == 0.995
    np.testing.assert_array_equal(rec.imu.dtheta_b, d["dps"] * (np.pi / 180.0))


@pytest.mark.parametrize(
    ("columns", "units", "fragment"),
    [
        ("t=time_ms,gyro_q=wx", None, "unknown sins column 'gyro_q'"),
        (COLUMNS.replace("wz", "omega_z"), UNITS, "no column 'omega_z' (it has label, time_ms"),
        (COLUMNS.replace(",accel_z=az", ""), UNITS, "no column for accel_z"),
        (COLUMNS, "t=ms,gyro=furlongs/s", "not a unit sins knows for gyro (accepted: rad/s, mrad/s, deg/s"),
        (COLUMNS, "t=ms,dv=m/s", "key 'dv' does not apply"),
        (COLUMNS, "speed=m/s", "unknown key 'speed'"),
        (COLUMNS + ",dv_x=ax", None, "file column 'ax' given for both 'accel_x' and 'dv_x'"),
        (COLUMNS.replace("t=time_ms,", ""), UNITS.replace("t=ms,", ""), "no time column 't'"),
        ("gyro_x", None, "expected key=value pairs"),
        (COLUMNS.replace("time_ms", "label"), None, "column 'label': not a number: 'run1'"),
    ],
)
def test_bad_columns_and_units_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], columns: str, units: str | None, fragment: str
) -> None:
    _own_csv(tmp_path / "log.csv", 20)
    argv = ["inspect", str(tmp_path / "log.csv"), "--columns", columns] + (
        ["--units", units] if units else []
    )
    _assert_one_line_error(main(argv), capsys.readouterr().err, fragment)


@pytest.mark.parametrize(
    ("frame", "fragment"),
    [("fru", "left-handed (x × y must give z): did you mean frd?"), ("ffd", "two axes lie along one line"),
     ("xyz", "expected three letters")],
)  # fmt: skip
def test_bad_frames_are_one_line(frame: str, fragment: str) -> None:
    refusal(lambda: axes.frame_matrix(frame), fragment)


def test_every_right_handed_frame_turns_exactly_and_round_trips() -> None:
    frames = axes.right_handed_frames()
    assert len(frames) == 24 and frames[0] == "frd" and "flu" in frames and "rfu" in frames
    rng = np.random.default_rng(SEED)
    v = rng.normal(size=(5, 3))
    for frame in frames:
        m = axes.frame_matrix(frame)
        assert axes.frame_letters(m) == frame and np.linalg.det(m) == pytest.approx(1.0)
        np.testing.assert_array_equal(axes.to_frd(v, m), v @ m.T)


def test_the_cli_reads_a_sins_csv_as_before_and_refuses_options_that_do_not_apply(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "imu.csv"
    np.savetxt(path, np.column_stack([np.arange(50) / 100.0, np.zeros((50, 6))]), delimiter=",",
               header=",".join(io.RATE_COLUMNS), comments="")  # fmt: skip
    rec = io.read(path)
    assert rec.kind == "sins csv" and rec.units == {"t": "s", "gyro": "rad/s", "accel": "m/s^2"}
    _assert_one_line_error(main(["inspect", str(path), "--topic", "/imu"]), capsys.readouterr().err,
                           "topic: does not apply", "a CSV file")  # fmt: skip
    _assert_one_line_error(
        main(["inspect", str(path), "--origin", "1,2"]), capsys.readouterr().err, "LAT,LON,H"
    )
    _assert_one_line_error(main(["inspect", str(tmp_path / "none.bag")]), capsys.readouterr().err,
                           "no such file or folder")  # fmt: skip
    with pytest.raises(SinsInputError):
        io.read(path, units="gyro=deg/s", frame="frd", columns="dv_x=gyro_x")


def test_the_formats_guide_lists_every_unit_and_spelling() -> None:
    """Every unit and alias the readers accept is in the guide's table, so the two cannot drift apart."""
    from sins.io import units

    guide = (Path(__file__).resolve().parents[1] / "docs" / "guide" / "formats.md").read_text(
        encoding="utf-8"
    )
    for key, table in units.UNITS.items():
        row = next(line for line in guide.splitlines() if line.startswith(f"| `{key}` |"))
        assert [u.strip(" `") for u in row.split("|")[3].split(",")] == list(table), key
    for alias in units.ALIASES:
        assert f"`{alias}`" in guide, alias


# --------------------------------------------------------------------------- one motion, three forms


def _turning_unit(n: int = 2001) -> dict[str, np.ndarray]:
    """A still unit turning about every axis at 200 Hz (numpy and scipy): smooth body rates integrated
    step by step into its attitude in a room frame (ENU, z up), gravity's reaction in its axes; every
    value a float32's, as EuRoC's ``.npz`` holds them (SOURCE.md), so that each form holds the same."""
    t = np.arange(n) * 0.005
    w = np.column_stack([0.4 * np.sin(1.3 * t), 0.3 * np.cos(0.7 * t), 0.2 + 0.1 * np.sin(0.5 * t)])
    w = w.astype(np.float32).astype(float)
    mid = 0.5 * (w[:-1] + w[1:]) * 0.005  # the trapezoid's turns, as a rate-form reading is integrated
    steps = [Rotation.from_rotvec([0.2, -0.1, 0.3])]
    for turn in Rotation.from_rotvec(mid):
        steps.append(steps[-1] * turn)
    att = Rotation.concatenate(steps)
    f = att.inv().apply([0.0, 0.0, 9.80665]).astype(np.float32).astype(float)
    xyzw = att.as_quat().astype(np.float32).astype(float)
    return {
        "t": t,
        "w": w,
        "f": f,
        "wxyz": np.column_stack([xyzw[:, 3], xyzw[:, :3]]),
        "zero": np.zeros((n, 3)),
    }


def _three_forms(root: Path, d: dict[str, np.ndarray]) -> dict[str, Path]:
    """``d`` as an ``.npz``, a EuRoC folder (integer ns) and a ROS 2 bag with Odometry and no fix (FLU: the
    readings' y and z negated, and the attitude's axes with them)."""
    np.savez(root / "unit.npz", t_s=d["t"], gyro_rad_s=d["w"], accel_m_s2=d["f"], q_wxyz=d["wxyz"],
             v_m_s=d["zero"], p_m=d["zero"])  # fmt: skip
    ns = T0_NS + np.arange(len(d["t"]), dtype=np.int64) * 5_000_000
    _asl(root / "euroc" / "mav0" / "imu0" / "data.csv", ASL_IMU_HEADER, ns, np.hstack([d["w"], d["f"]]))
    ref = np.hstack([d["zero"], d["wxyz"], d["zero"], np.zeros((len(ns), 6))])
    reference = root / "euroc" / "mav0" / "state_groundtruth_estimate0" / "data.csv"
    _asl(reference, "#timestamp," + ",".join(["c"] * 16), ns, ref)
    flu = (Rotation.from_quat(d["wxyz"][:, [1, 2, 3, 0]]) * Rotation.from_rotvec([np.pi, 0.0, 0.0])).as_quat()
    bag = {"ns": ns, "w": d["w"] * FLU, "f": d["f"] * FLU, "p": d["zero"], "q": flu, "v_body": d["zero"]}
    return {
        "npz": root / "unit.npz",
        "euroc": root / "euroc",
        "bag": _write_bag(root / "bag", "ros2", bag, fixes=False),
    }


def test_one_motion_as_npz_euroc_folder_and_bag_without_a_fix_is_read_and_judged_alike(
    tmp_path: Path,
) -> None:
    """None of the three frames has a known heading or latitude: each says Earth's rate is left out of
    what is judged against it, and leaves it out. The bag's poses, with no fix and no origin given, had
    been judged with Earth's rate put in at 45° N, a latitude nobody gave (a new user's walk: MH_02 as a
    bag judged at 122.988° of AOE, as a EuRoC folder and an ``.npz`` at 123.055°), and the EuRoC folder's
    notes did not say it. The open loop's errors agree within float32 rounding of
    the attitude written (1e-7 rad; Earth's rate over these 10 s is 7e-4 rad), and so do the
    integrations (``sins integrate``, which puts Earth's rate in at 45° N in any frame, alike)."""
    from sins.compensation.judging import frame_turn, open_loop
    from sins.runs import pipeline

    paths = _three_forms(tmp_path, _turning_unit())
    read = {k: io.read(p) for k, p in paths.items()}
    loops, ends = {}, {}
    for kind, rec in read.items():
        assert not rec.heading_known and not rec.latitude_known, kind
        assert sum("so Earth's rate is left out of what is judged against it" in n for n in rec.notes) == 1
        beside = rec.beside_reference()
        assert not frame_turn(beside).any(), kind
        loops[kind] = open_loop(None, beside)
        sol = pipeline.integrate_recording(rec).solution
        radius = 6.37e6  # lat and lon in metres, to compare with the height's
        ends[kind] = np.array(
            [radius * sol.lat[-1], radius * sol.lon[-1], sol.h[-1], *sol.v_n[-1], *sol.q_nb[-1]]
        )
    for kind, step in (("euroc", 1), ("bag", 4)):  # the bag's odometry is at every fourth reading
        np.testing.assert_allclose(loops[kind].t, loops["npz"].t[::step], rtol=0, atol=1e-12)
        np.testing.assert_allclose(loops[kind].total, loops["npz"].total[::step], rtol=0, atol=1e-7)
        # The same float32 values read, the times the same to 1e-18 s and the bag's FLU attitude turned back
        # in float64: the last state agrees far inside float32's rounding (6e-8 of a unit quaternion).
        np.testing.assert_allclose(ends[kind], ends["npz"], rtol=0, atol=1e-7)
    # Its place given, the bag's frame is ENU there (REP 103), as a fix would place it: Earth's rate is in.
    placed = io.read(paths["bag"], origin=(0.8, 0.1, 50.0))
    assert placed.latitude_known and placed.heading_known
    assert not any("Earth's rate is left out" in n for n in placed.notes)
