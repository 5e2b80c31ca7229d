"""How fast the recording readers go: a ROS 2 bag, a ROS 1 bag and a EuRoC folder of N readings, written
here, read with ``sins.io.read``; and ``sins.io.inspection.inspect`` on the result.

    .venv/bin/python tools/bench_readers.py [--rows 200000]

Prints the readings per second of each (median of three reads). Write-time is not measured.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from sins import io
from sins.io import inspection


def _imu(ts, ns: int, w: np.ndarray, f: np.ndarray):  # type: ignore[no-untyped-def]
    t = ts.types
    header_type = t["std_msgs/msg/Header"]
    stamp = t["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
    fields = {"stamp": stamp, "frame_id": "imu"}
    if "seq" in header_type.__dataclass_fields__:
        fields["seq"] = 0
    vec = t["geometry_msgs/msg/Vector3"]
    return t["sensor_msgs/msg/Imu"](
        header=header_type(**fields),
        orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=np.zeros(9),
        angular_velocity=vec(x=w[0], y=w[1], z=w[2]),
        angular_velocity_covariance=np.zeros(9),
        linear_acceleration=vec(x=f[0], y=f[1], z=f[2]),
        linear_acceleration_covariance=np.zeros(9),
    )


def write_bag(path: Path, ros1: bool, w: np.ndarray, f: np.ndarray) -> Path:
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    serialize = ts.serialize_ros1 if ros1 else ts.serialize_cdr
    with Writer1(path) if ros1 else Writer2(path, version=9) as writer:
        conn = writer.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=ts)
        for k in range(len(w)):
            ns = 1_700_000_000_000_000_000 + k * 5_000_000
            writer.write(conn, ns, serialize(_imu(ts, ns, w[k], f[k]), "sensor_msgs/msg/Imu"))
    return path


def write_euroc(root: Path, w: np.ndarray, f: np.ndarray) -> Path:
    folder = root / "mav0" / "imu0"
    folder.mkdir(parents=True)
    ns = 1_403_636_579_758_555_392 + np.arange(len(w), dtype=np.int64) * 5_000_000
    with open(folder / "data.csv", "w", encoding="utf-8") as fh:
        fh.write("#timestamp [ns],wx,wy,wz,ax,ay,az\n")
        for k in range(len(w)):
            fh.write(f"{ns[k]}," + ",".join(repr(float(x)) for x in (*w[k], *f[k])) + "\n")
    return root


def timed(call, repeats: int = 3) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=200_000)
    rows = parser.parse_args().rows
    rng = np.random.default_rng(0)
    w, f = rng.normal(0, 0.1, (rows, 3)), rng.normal([0, 0, 9.8], 0.1, (rows, 3))
    with tempfile.TemporaryDirectory() as tmp:
        paths = {
            "ROS 2 bag (SQLite)": write_bag(Path(tmp) / "ros2", False, w, f),
            "ROS 1 bag": write_bag(Path(tmp) / "run.bag", True, w, f),
            "EuRoC folder": write_euroc(Path(tmp) / "euroc", w, f),
        }
        print(f"{rows} readings at 200 Hz ({rows / 200 / 60:.1f} min); median of 3 reads")
        for name, path in paths.items():
            seconds = timed(lambda path=path: io.read(path))
            print(f"{name:20s} {seconds:7.2f} s  {rows / seconds / 1e3:8.1f} k readings/s")
        rec = io.read(paths["ROS 1 bag"])
        seconds = timed(lambda: inspection.inspect(rec))
        print(f"{'inspect':20s} {seconds:7.2f} s  {rows / seconds / 1e3:8.1f} k readings/s")


if __name__ == "__main__":
    main()
