"""A navigation engineer's first hour with a unit: ``sins bias`` on still recordings written here (ROS bags
with rosbags, CSVs and EuRoC folders with numpy) of a known bias and noise, and ``sins integrate`` started
from an alignment on the opening rest, judged against closed forms written out here.

The oracles are independent of sins: the readings are Earth's rate (7.292115e-5 rad/s) and normal gravity
(9.8061992 m/s² at 45° N, less the free-air 3.086e-6 /s² per metre) turned into the body axes with scipy,
plus the bias, plus white noise and a first-order Gauss–Markov process drawn with scipy's ``lfilter``; the
standard error of the mean of such noise is the closed form of an AR(1) process; the error growth of a
still unit's biases is the short-time series of the Schuler solutions.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import dataset_folder
from scipy.signal import lfilter
from scipy.spatial.transform import Rotation

from sins import io
from sins.cli import main
from sins.core.series import ImuRates
from sins.nav import budget

SEED = 44
OMEGA = 7.292115e-5
LAT_DEG, LON_DEG, H_M = 45.0, 7.5, 100.0
G_45 = 9.8061992 - 3.086e-6 * H_M  # Somigliana at 45° N, sea level, less the free-air gradient
DPH = math.pi / 180.0 / 3600.0
UG = 9.80665e-6
ATT_DEG = (2.0, -1.0, 30.0)  # roll, pitch, yaw
FLU = np.array([1.0, -1.0, -1.0])  # FRD into ROS's FLU
T0_NS = 1_700_000_000_000_000_000
#: The issue's unit: gyro biases of a consumer MEMS, FRD, °/h.
MEMS_GYRO_DPH = (412.5, 618.8, -825.1)
ACCEL_UG = (300.0, -500.0, 200.0)


def _C_nb(att_deg: tuple[float, float, float] = ATT_DEG) -> np.ndarray:
    roll, pitch, yaw = np.radians(att_deg)
    return Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_matrix()


def _inputs(att_deg: tuple[float, float, float] = ATT_DEG) -> tuple[np.ndarray, np.ndarray]:
    """Earth's rate and gravity in the body axes of a unit standing still at 45° N, 100 m."""
    lat = math.radians(LAT_DEG)
    C = _C_nb(att_deg)
    return C.T @ (OMEGA * np.array([math.cos(lat), 0.0, -math.sin(lat)])), C.T @ np.array([0.0, 0.0, -G_45])


def still_unit(
    seconds: float,
    gyro_bias: np.ndarray,
    accel_bias: np.ndarray,
    white: np.ndarray,
    gm: np.ndarray | None = None,
    tc_s: float = 1.0,
    rate: float = 100.0,
    seed: int = SEED,
    att_deg: tuple[float, float, float] = ATT_DEG,
) -> tuple[ImuRates, np.ndarray]:
    """A still unit's readings (FRD, SI) and the standard error of each channel's mean (6,): white noise
    of ``white`` (6,) per sample plus a stationary AR(1) process of deviation ``gm`` and correlation
    time ``tc_s``, whose mean of n samples has variance ``s²/n² [n (1+φ)/(1−φ) − 2φ (1−φⁿ)/(1−φ)²]``."""
    rng = np.random.default_rng(seed)
    n = round(seconds * rate)
    omega, force = _inputs(att_deg)
    noise = rng.standard_normal((n, 6)) * white
    var = white**2 / n
    if gm is not None:
        phi = math.exp(-1.0 / (rate * tc_s))
        drive = rng.standard_normal((n, 6)) * gm * math.sqrt(1.0 - phi**2)
        start = rng.standard_normal(6) * gm * phi
        noise += lfilter([1.0], [1.0, -phi], drive, axis=0, zi=start[None, :])[0]
        var = var + gm**2 / n**2 * (n * (1 + phi) / (1 - phi) - 2 * phi * (1 - phi**n) / (1 - phi) ** 2)
    values = np.r_[omega + gyro_bias, force + accel_bias] + noise
    return ImuRates(t=np.arange(n) / rate, omega_ib_b=values[:, :3], f_ib_b=values[:, 3:]), np.sqrt(var)


# --------------------------------------------------------------------------- writers


def _bag(path: Path, imu: ImuRates, kind: str = "ros2", fix: bool = True) -> Path:
    """A bag of ``kind`` (ros1, ros2, ros2-mcap) with the readings on /imu in FLU and, with ``fix``, a
    NavSatFix at 45° N, 7.5° E, 100 m every second."""
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore

    ros1 = kind == "ros1"
    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    serialize = ts.serialize_ros1 if ros1 else ts.serialize_cdr
    t = ts.types
    storage = StoragePlugin.MCAP if kind == "ros2-mcap" else StoragePlugin.SQLITE3
    writer = Writer1(path) if ros1 else Writer2(path, version=9, storage_plugin=storage)

    def header(ns: int, frame: str, seq: int):  # type: ignore[no-untyped-def]
        stamp = t["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
        if ros1:
            return t["std_msgs/msg/Header"](seq=seq, stamp=stamp, frame_id=frame)
        return t["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    vec, quat = t["geometry_msgs/msg/Vector3"], t["geometry_msgs/msg/Quaternion"]
    w, f = imu.omega_ib_b * FLU, imu.f_ib_b * FLU
    with writer:
        c_imu = writer.add_connection("/imu", "sensor_msgs/msg/Imu", typestore=ts)
        c_fix = writer.add_connection("/fix", "sensor_msgs/msg/NavSatFix", typestore=ts) if fix else None
        for k, tk in enumerate(imu.t):
            ns = T0_NS + round(tk * 1e9)
            msg = t["sensor_msgs/msg/Imu"](
                header=header(ns, "imu", k), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0),
                orientation_covariance=np.full(9, -1.0),
                angular_velocity=vec(x=w[k, 0], y=w[k, 1], z=w[k, 2]),
                angular_velocity_covariance=np.zeros(9),
                linear_acceleration=vec(x=f[k, 0], y=f[k, 1], z=f[k, 2]),
                linear_acceleration_covariance=np.zeros(9),
            )  # fmt: skip
            writer.write(c_imu, ns, serialize(msg, "sensor_msgs/msg/Imu"))
            if c_fix is not None and k % 100 == 0:
                fix_msg = t["sensor_msgs/msg/NavSatFix"](
                    header=header(ns, "gps", k),
                    status=t["sensor_msgs/msg/NavSatStatus"](status=0, service=1),
                    latitude=LAT_DEG, longitude=LON_DEG, altitude=H_M, position_covariance=np.zeros(9),
                    position_covariance_type=0,
                )  # fmt: skip
                writer.write(c_fix, ns, serialize(fix_msg, "sensor_msgs/msg/NavSatFix"))
    return path


def _euroc(root: Path, imu: ImuRates) -> Path:
    """A EuRoC folder (mav0/imu0/data.csv, ns stamps, the readings on S taken as FRD)."""
    folder = root / "mav0" / "imu0"
    folder.mkdir(parents=True)
    ns = T0_NS + np.round(imu.t * 1e9).astype(np.int64)
    head = "#timestamp [ns]," + ",".join(
        [f"w_RS_S_{a} [rad s^-1]" for a in "xyz"] + [f"a_RS_S_{a} [m s^-2]" for a in "xyz"]
    )
    rows = np.hstack([imu.omega_ib_b, imu.f_ib_b])
    lines = [head] + [
        f"{s}," + ",".join(repr(float(x)) for x in row) for s, row in zip(ns, rows, strict=True)
    ]
    (folder / "data.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return root


def _json(path: Path) -> dict:
    return json.loads(path.read_text(encoding="utf-8"))


# --------------------------------------------------------------------------- sins bias


def test_bias_on_a_bag_lands_within_3_sigma_and_its_sigma_counts_the_noise_colour(tmp_path: Path) -> None:
    """The issue's MEMS unit on a ROS 2 bag with fixes: 200 s at 100 Hz, white noise and a Gauss–Markov
    process of 1 s that dominates the mean's error (white noise alone would give a fifth of it)."""
    gyro_b, accel_b = np.array(MEMS_GYRO_DPH) * DPH, np.array(ACCEL_UG) * UG
    white = np.r_[[3e-4] * 3, [0.01] * 3]
    imu, sigma = still_unit(200.0, gyro_b, accel_b, white, gm=white / 3.0)
    bag = _bag(tmp_path / "still", imu)
    out = tmp_path / "bias.json"
    assert main(["bias", str(bag), "--attitude", ",".join(map(str, ATT_DEG)), "--json", str(out)]) == 0
    doc = _json(out)
    assert doc["location"] == "the recording's fixes"
    assert doc["lat_deg"] == pytest.approx(LAT_DEG, abs=1e-9) and doc["h_m"] == pytest.approx(H_M, abs=1e-6)
    assert doc["attitude"]["source"] == "given" and doc["rows"] == 20000
    truth = np.r_[gyro_b, accel_b]
    for i, (name, c) in enumerate(doc["channels"].items()):
        assert abs(c["bias"] - truth[i]) <= 3.0 * c["sigma"], (name, (c["bias"] - truth[i]) / c["sigma"])
        assert 1 / 1.5 <= c["sigma"] / sigma[i] <= 1.5, (name, c["sigma"] / sigma[i])
        assert c["sigma_white"] < 0.5 * sigma[i]  # what a white-noise error would have claimed
    assert doc["channels"]["gyro.x"]["unit"] == "°/h" and doc["channels"]["accel.z"]["unit"] == "µg"


def test_levelled_the_tilt_takes_the_level_accelerometer_bias_and_the_heading_is_not_resolved(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Without an attitude: roll and pitch are those of the mean specific force (bias included), the
    heading of a gyro biased 75 × Earth's level rate is refused, and each gyro's bias carries at most
    its axis's share of Earth's level rate."""
    gyro_b, accel_b = np.array(MEMS_GYRO_DPH) * DPH, np.array(ACCEL_UG) * UG
    white = np.r_[[3e-4] * 3, [0.01] * 3]
    imu, sigma = still_unit(60.0, gyro_b, accel_b, white)
    io.write_imu(tmp_path / "still.csv", imu)
    out = tmp_path / "bias.json"
    assert (
        main(["bias", str(tmp_path / "still.csv"), "--lat", "45", "--height", "100", "--json", str(out)]) == 0
    )
    assert "heading not resolved" in capsys.readouterr().out
    doc = _json(out)
    att = doc["attitude"]
    assert att["source"] == "levelled" and att["yaw_deg"] is None and "cannot tell" in att["heading_note"]
    omega, force = _inputs()
    f = force + accel_b  # the mean specific force, without noise
    roll, pitch = math.atan2(-f[1], -f[2]), math.atan2(f[0], math.hypot(f[1], f[2]))
    tilt = 3.0 * math.radians(att["tilt_sigma_deg"])
    assert math.radians(att["roll_deg"]) == pytest.approx(roll, abs=tilt)
    assert math.radians(att["pitch_deg"]) == pytest.approx(pitch, abs=tilt)
    level = Rotation.from_euler("ZYX", [0.0, pitch, roll]).as_matrix() @ (omega + gyro_b)
    assert att["level_rate_ratio"] == pytest.approx(
        math.hypot(*level[:2]) / (OMEGA * math.cos(math.radians(45))), rel=0.01
    )
    ch = doc["channels"]
    for i, axis in enumerate("xyz"):
        c = ch[f"gyro.{axis}"]
        assert abs(c["bias"] - gyro_b[i]) <= 3.0 * c["sigma"] + c["heading_bound"]
    # Levelled, the accelerometers' bias is the part along gravity, |f| − g, on every axis.
    along = np.array([ch[f"accel.{a}"]["bias"] for a in "xyz"])
    assert np.linalg.norm(along) == pytest.approx(abs(np.linalg.norm(f) - G_45), abs=3.0 * sigma[5])


@pytest.mark.parametrize("kind", ["ros1", "mcap", "euroc"])
def test_bias_reads_every_recording_format(tmp_path: Path, kind: str) -> None:
    """The same still readings as a ROS 1 bag, an MCAP file and a EuRoC folder: the same means (the
    floats written, turned back into FRD exactly) and the bias of the given attitude within 3σ."""
    gyro_b, accel_b = np.array([10.0, -20.0, 5.0]) * DPH, np.array(ACCEL_UG) * UG
    imu, _ = still_unit(30.0, gyro_b, accel_b, np.r_[[3e-4] * 3, [0.01] * 3], seed=SEED + 1)
    if kind == "euroc":
        path = _euroc(tmp_path / "MH", imu)
    elif kind == "ros1":
        path = _bag(tmp_path / "still.bag", imu, "ros1", fix=False)
    else:
        path = next(_bag(tmp_path / "still", imu, "ros2-mcap", fix=False).glob("*.mcap"))
    out = tmp_path / "bias.json"
    args = ["bias", str(path), "--lat", "45", "--height", "100", "--attitude", "2,-1,30", "--json", str(out)]
    assert main(args) == 0
    doc = _json(out)
    means = np.r_[imu.omega_ib_b.mean(axis=0), imu.f_ib_b.mean(axis=0)]
    truth = np.r_[gyro_b, accel_b]
    for i, c in enumerate(doc["channels"].values()):
        assert c["mean"] == pytest.approx(means[i], rel=1e-12, abs=1e-15)
        assert abs(c["bias"] - truth[i]) <= 3.0 * c["sigma"]


def test_bias_of_the_psins_ring_laser_dataset() -> None:
    """The PSINS static ring-laser INS against its own reference: the latitude its Earth rate implies is
    the header's 34.246048° (SOURCE.md), the rate taken away Earth's 15.041 °/h, and a navigation-grade
    gyro's biases below 1 °/h."""
    dataset_folder("psins_lasergyro_static")
    from sins.characterise.bias import dataset_bias

    est = dataset_bias(io.read(dataset="psins_lasergyro").reference_inputs()[0], "psins_lasergyro")
    assert math.degrees(est.lat) == pytest.approx(34.246048, abs=1e-6)
    assert np.linalg.norm(est.vector("gyro", "expected")) / DPH == pytest.approx(15.041, abs=1e-3)
    assert np.all(np.abs(est.vector("gyro")) < 1.0 * DPH)
    assert est.rows == 184718 and est.attitude.source == "reference"


# --------------------------------------------------------------------------- sins integrate, no reference


def _nav_noise() -> np.ndarray:
    """A navigation-grade unit's white noise per sample at 100 Hz: 0.002 °/√h and 20 µg/√Hz."""
    arw = math.radians(0.002) / 60.0 * 10.0
    vrw = 20e-6 * 9.80665 * 10.0
    return np.r_[[arw] * 3, [vrw] * 3]


def test_an_aligned_attitude_lies_within_its_stated_accuracy(tmp_path: Path) -> None:
    """A navigation-grade unit (biases of the grade's size) on a bag: --align 30 --grade navigation
    states 1σ from the noise and the grade's bias levels; the attitude lies within 3σ of the truth, and
    the noise's part alone is the closed form (the accelerometers' standard error over g)."""
    C = _C_nb()
    gyro_b = C.T @ (np.array([0.008, -0.006, 0.01]) * DPH)
    accel_b = np.array([40.0, -30.0, 50.0]) * UG
    imu, _ = still_unit(60.0, gyro_b, accel_b, _nav_noise(), seed=SEED + 2)
    bag = _bag(tmp_path / "nav", imu)
    out = tmp_path / "run.json"
    args = ["integrate", str(bag), "--align", "30", "--grade", "navigation", "--json", str(out)]
    assert main(args) == 0
    doc = _json(out)
    a = doc["alignment"]
    assert doc["start"] == "aligned" and a["rows"] == 3000 and doc["origin_deg"][0] == pytest.approx(LAT_DEG)
    tilt, heading = a["tilt_sigma_deg"], a["heading_sigma_deg"]
    for got, want, sd in ((a["roll_deg"], ATT_DEG[0], tilt), (a["pitch_deg"], ATT_DEG[1], tilt),
                          (a["yaw_deg"], ATT_DEG[2], heading)):  # fmt: skip
        assert abs(got - want) <= 3.0 * sd, (got, want, sd)
    noise_tilt = math.degrees(_nav_noise()[3] / math.sqrt(3000) / G_45)
    assert a["tilt_sigma_noise_deg"] == pytest.approx(noise_tilt, rel=0.5)
    assert a["tilt_sigma_deg"] > 2.0 * a["tilt_sigma_noise_deg"]  # the grade's 0.05 mg counted


def test_a_still_units_position_error_after_60_s_follows_its_measured_bias(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Aligned on 30 s, a still unit drifts by what the alignment leaves: the level accelerometer biases
    are in the tilt and the east gyro bias in the heading, so the level error is the north gyro bias
    ``ε = |Ω_h + b_h| − Ω cos φ`` (the levelled rate's excess over Earth's) through ``g ε t³/6``, and the
    height error the vertical accelerometer bias ``|f| − g`` through ``b t²/2`` (both the short-time
    Schuler and vertical solutions, exact to (ω_s t)²/20 = 0.3 % and (t/τ)²/12 = 0.1 % at 60 s). The
    tolerance is 3σ of what the noise adds: the alignment's tilt (½ g σθ t²), the accelerometer's
    velocity random walk (σ_v t^1.5/√3), the gyro's angle random walk (g σ_θ t^2.5/√20) and the window's
    rate error (g σ_ω t³/6)."""
    C = _C_nb()
    lat = math.radians(LAT_DEG)
    gyro_n = np.array([1.5, 0.05, 0.8]) * DPH
    accel_b = np.array(ACCEL_UG) * UG
    noise = _nav_noise()
    imu, _ = still_unit(90.0, C.T @ gyro_n, accel_b, noise, seed=SEED + 3)
    io.write_imu(tmp_path / "still.csv", imu)
    out = tmp_path / "run.json"
    origin = f"{LAT_DEG},{LON_DEG},{H_M}"
    args = ["integrate", str(tmp_path / "still.csv"), "--origin", origin, "--align", "30",
            "--out", str(tmp_path / "sol.csv"), "--json", str(out)]  # fmt: skip
    assert main(args) == 0
    assert "for a unit that stood still, these are its errors" in capsys.readouterr().out
    doc = _json(out)
    t = doc["duration_s"]
    assert t == pytest.approx(60.0, abs=0.02)
    level = OMEGA * math.cos(lat)
    eps = math.hypot(level + gyro_n[0], gyro_n[1]) - level
    _, force = _inputs()
    b_up = np.linalg.norm(force + accel_b) - G_45  # a unit reading less than gravity falls
    dt, n_align = 0.01, 3000
    per_axis = math.sqrt(
        (0.5 * t**2 * noise[3] / math.sqrt(n_align)) ** 2
        + (noise[3] * math.sqrt(dt) * t**1.5 / math.sqrt(3)) ** 2
        + (G_45 * noise[0] * math.sqrt(dt) * t**2.5 / math.sqrt(20)) ** 2
        + (G_45 * noise[0] / math.sqrt(n_align) * t**3 / 6) ** 2
    )  # fmt: skip
    assert doc["final_horizontal_offset_m"] == pytest.approx(
        G_45 * eps * t**3 / 6, abs=3 * math.sqrt(2) * per_axis
    )
    assert doc["final_offset_ned_m"][2] == pytest.approx(
        -b_up * t**2 / 2, abs=3 * noise[3] * math.sqrt(dt) * t**1.5
    )
    # The command's own prediction, from the biases it measured on the 30 s, says the same.
    predicted = np.array(doc["predicted_offset_ned_m"])
    assert math.hypot(*predicted[:2]) == pytest.approx(G_45 * eps * t**3 / 6, rel=0.1)
    assert predicted[2] == pytest.approx(-b_up * t**2 / 2, rel=0.1)
    # The solution file as from a reference: one row per IMU time from the alignment's end.
    sol = io.read_truth(tmp_path / "sol.csv")
    assert sol.t[0] == pytest.approx(30.0, abs=0.011) and len(sol.t) == 6000


def test_the_drift_a_still_units_biases_predict_holds_over_half_an_hour(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Aligned on a minute, navigated for half an hour: the printed prediction (the rest's mean readings
    navigated as the recording is) meets the solution of a unit whose readings are those means, as
    noise-free ones are: within 0.5 % of the horizontal drift and 1 % of the height, for a free channel,
    and a held one stays at 0. Each bias's own growth (the budget) leaves out the level velocity's
    Coriolis force on the vertical channel, which by then changes the height by more than half (here the
    budget's 6.1 km against 2.4 km; a tactical unit's 3.6 km against 7.1 km), and was the prediction."""
    C = _C_nb()
    gyro_n = np.array([1.5, 0.05, 0.8]) * DPH
    imu, _ = still_unit(1800.0, C.T @ gyro_n, np.array(ACCEL_UG) * UG, np.zeros(6), rate=20.0)
    io.write_imu(tmp_path / "still.csv", imu)
    out = tmp_path / "run.json"
    args = ["integrate", str(tmp_path / "still.csv"), "--origin", f"{LAT_DEG},{LON_DEG},{H_M}", "--align",
            "60", "--heading", str(ATT_DEG[2]), "--json", str(out)]  # fmt: skip
    assert main(args) == 0
    doc = _json(out)
    final, predicted = np.array(doc["final_offset_ned_m"]), np.array(doc["predicted_offset_ned_m"])
    assert np.hypot(*predicted[:2]) == pytest.approx(np.hypot(*final[:2]), rel=5e-3)
    assert predicted[2] == pytest.approx(final[2], rel=1e-2)
    b_up = np.linalg.norm(_inputs()[1] + np.array(ACCEL_UG) * UG) - G_45
    alone = budget.vertical_bias_growth(-b_up, np.array([1740.0]), math.radians(LAT_DEG))[0]
    assert abs(alone / final[2] - 1.0) > 0.5  # the coupling the budget leaves out: 6.1 km against 2.4 km
    assert main([*args, "--vertical", "hold"]) == 0
    assert _json(out)["predicted_offset_ned_m"][2] == 0.0
    capsys.readouterr()


def test_the_budget_terms_are_the_short_time_forms() -> None:
    """:mod:`sins.nav.budget` against the series of its closed forms at 60 s: ½ b t², g ε t³/6, ½ b t²."""
    lat, t = math.radians(45.0), np.array([60.0])
    w2 = budget.schuler_frequency(lat) ** 2 * 60.0**2
    g = 9.8061992
    assert budget.accel_bias_growth(1e-3, t, lat)[0] == pytest.approx(0.5e-3 * 3600 * (1 - w2 / 12), rel=1e-5)
    assert budget.gyro_bias_growth(1e-6, t, lat)[0] == pytest.approx(
        g * 1e-6 * 60**3 / 6 * (1 - w2 / 20), rel=1e-4
    )
    tau2 = budget.mean_radius(lat) / (2 * g)
    assert budget.vertical_bias_growth(1e-3, t, lat)[0] == pytest.approx(
        0.5e-3 * 3600 * (1 + 3600 / (12 * tau2)), rel=1e-5
    )
    ned = budget.bias_error_ned([1e-6, 2e-6, 0.0], [1e-3, -1e-3, 2e-3], t, lat)[0]
    a, gy = budget.accel_bias_growth(1.0, t, lat)[0], budget.gyro_bias_growth(1.0, t, lat)[0]
    np.testing.assert_allclose(ned[:2], [1e-3 * a - 2e-6 * gy, -1e-3 * a + 1e-6 * gy], rtol=1e-12)


def test_refusals_without_a_reference(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    imu, _ = still_unit(20.0, np.zeros(3), np.zeros(3), np.r_[[3e-4] * 3, [0.01] * 3])
    csv = tmp_path / "still.csv"
    io.write_imu(csv, imu)

    def refused(*args: str) -> str:
        assert main(list(args)) == 2
        # The error is one line, the last; a loaded machine may show a progress line before it.
        err = capsys.readouterr().err.splitlines()[-1]
        assert err.startswith("sins: error: "), err
        return err

    assert "--origin LAT,LON,H" in refused("integrate", str(csv), "--align", "5")
    assert "--align" in refused("integrate", str(csv), "--heading", "30")
    assert "exclude each other" in refused("integrate", str(csv), "--origin", "45,7,0", "--attitude", "0,0,0",
                                           "--align", "5")  # fmt: skip
    assert "leaving nothing to navigate" in refused(
        "integrate", str(csv), "--origin", "45,7,0", "--align", "60"
    )
    err = refused("integrate", str(csv))
    assert "no reference trajectory" in err and "--truth TRUTH.csv" in err and "--align SECONDS" in err
    assert "--lat DEG" in refused("bias", str(csv))
    # The library says what it misses in its own terms; the command line adds its flag.
    from sins.characterise import bias as library_bias
    from sins.errors import MissingInputError

    with pytest.raises(MissingInputError) as missing:
        library_bias.recording_bias(io.read(csv))
    assert missing.value.needs == "lat" and "--" not in str(missing.value)
    assert "latitude" in refused("bias", str(csv), "--lat", "91")
    assert "a height within ±1e5 m" in refused("bias", str(csv), "--lat", "45", "--height", "1e12")
    # A gyro bias far above Earth's level rate: no heading to gyrocompass, and none given.
    big, _ = still_unit(20.0, np.array(MEMS_GYRO_DPH) * DPH, np.zeros(3), np.r_[[3e-4] * 3, [0.01] * 3])
    io.write_imu(tmp_path / "mems.csv", big)
    assert "--heading DEG" in refused(
        "integrate", str(tmp_path / "mems.csv"), "--origin", "45,7,0", "--align", "10"
    )
    # Given the heading, the same unit aligns.
    assert (
        main(
            [
                "integrate",
                str(tmp_path / "mems.csv"),
                "--origin",
                "45,7,0",
                "--align",
                "10",
                "--heading",
                "30",
            ]
        )
        == 0
    )
    assert "heading given: 30.0000°" in capsys.readouterr().out
    # The accelerometer written in g, read as m/s²: no bias nor scale error brings a rest to 0.102 g.
    # It had given an accelerometer bias of 0.9 g, and an alignment that fell 1.9e6 m, without a word.
    in_g = ImuRates(t=imu.t, omega_ib_b=imu.omega_ib_b, f_ib_b=imu.f_ib_b / 9.80665)
    io.write_imu(tmp_path / "in_g.csv", in_g)
    said = "at rest the specific force is 0.102 × gravity, beyond any accelerometer's bias or scale error"
    assert said in refused("bias", str(tmp_path / "in_g.csv"), "--lat", "45")
    assert said in refused("integrate", str(tmp_path / "in_g.csv"), "--origin", "45,7,0", "--align", "10")
    assert main(["bias", str(tmp_path / "in_g.csv"), "--lat", "45", "--units", "accel=g"]) == 0


def test_a_start_without_a_reference_refuses_a_heading_or_a_solution_that_is_not_finite(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Readings at the edge of the physical ranges held for 55 h drive a free solution beyond floating
    point: refused in one line, as against a truth (before, exit 0 and a table and files of NaN). A
    heading of NaN is refused by the option (before, 54,001 rows of NaN)."""
    n = 200_000
    path = tmp_path / "huge.csv"
    readings = np.column_stack([np.arange(n, dtype=float), np.zeros((n, 3)), np.full((n, 3), 9e5)])
    head = "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"
    np.savetxt(path, readings, delimiter=",", fmt="%.9g", header=head, comments="")
    out = tmp_path / "s.csv"
    assert main(["integrate", str(path), "--origin", "45,0,0", "--attitude", "0,0,0", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "the position came out non-finite after 199999 s" in err and "free vertical" in err, err
    assert "beyond a unit's ranges" in err and err.count("\n") == 1 and not out.exists(), err
    with pytest.raises(SystemExit) as info:
        main(["integrate", str(path), "--origin", "45,0,0", "--align", "60", "--heading", "nan"])
    assert info.value.code == 2 and "--heading: must be a finite number" in capsys.readouterr().err


# --------------------------------------------------------------------------- a walk through sins bias


def _numpy_batch_means(values: np.ndarray, rests: list[tuple[int, int]], batches: int = 30) -> np.ndarray:
    """The batch-means standard error of a mean pooled over rests, in numpy alone: batches of a thirtieth
    of the rows inside each rest, their means' variance about the rest's mean, times batch rows / rows."""
    n = sum(b - a for a, b in rests)
    m = n // batches
    square, dof = np.zeros(values.shape[1]), 0
    for a, b in rests:
        k = (b - a) // m
        if k < 2:
            continue
        means = values[a : a + k * m].reshape(k, m, -1).mean(axis=1)
        square += ((means - means.mean(axis=0)) ** 2).sum(axis=0)
        dof += k - 1
    return np.sqrt(square / dof * m / n)


def test_the_mean_error_by_batch_means_is_white_for_white_noise_and_above_it_for_gauss_markov() -> None:
    """White noise: 1σ = σ/√n; an AR(1) of φ = 0.92 (correlation 12 rows): √((1+φ)/(1−φ)) = 4.9 times
    that. 30 batches leave 29 degrees of freedom (the 1σ spreads by 1/√58, 13 %): held within 3 of it.
    Three rests with offsets of ±10 σ (other attitudes) change neither figure."""
    from sins.characterise.mean_error import batch_means_sigma, white_sigma

    rng = np.random.default_rng(SEED)
    n, phi = 30_000, 0.92
    white = rng.standard_normal((n, 2))
    gm = lfilter([1.0], [1.0, -phi], rng.standard_normal((n, 2)), axis=0) * math.sqrt(1 - phi**2)
    rests = [(0, 9_000), (9_000, 21_000), (21_000, n)]
    offsets = np.repeat([[10.0, -10.0], [-10.0, 0.0], [0.0, 10.0]], [9_000, 12_000, 9_000], axis=0)
    spread = 3.0 / math.sqrt(2 * 29)
    for noise, factor in ((white, 1.0), (gm, math.sqrt((1 + phi) / (1 - phi)))):
        values = noise + offsets
        got = batch_means_sigma(values, rests) * math.sqrt(n)
        np.testing.assert_allclose(got, factor, rtol=spread)
        np.testing.assert_allclose(got, _numpy_batch_means(values, rests) * math.sqrt(n), rtol=1e-12)
        # If white: the spread about each rest's own mean, 1 for either (the AR(1) is of unit variance;
        # its sample variance spreads by √((1+φ²)/(1−φ²)/(2n)), 1.4 %: 5 % is over 3 of it).
        np.testing.assert_allclose(white_sigma(values, rests) * math.sqrt(n), 1.0, rtol=0.05)


def test_seconds_is_a_positive_number_and_keeps_seconds_times_rate_rows(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--seconds -5``, ``nan`` and ``0`` were taken, then refused as "0 rows; an Allan analysis…";
    ``--seconds 2`` at 100 Hz kept 201 rows (t ≤ t0 + 2). Now the option refuses them, and the first
    2 s are 200 rows, 0-1.99 s; 1 s, 100 rows, is too few for the noise fit and says so."""
    imu, _ = still_unit(20.0, np.zeros(3), np.zeros(3), np.r_[[3e-4] * 3, [0.01] * 3])
    csv = tmp_path / "still.csv"
    io.write_imu(csv, imu)
    for bad in ("-5", "nan", "0", "inf"):
        with pytest.raises(SystemExit) as info:
            main(["bias", str(csv), "--lat", "45", "--seconds", bad])
        assert info.value.code == 2 and "--seconds: must be a positive number" in capsys.readouterr().err
    out = tmp_path / "b.json"
    assert main(["bias", str(csv), "--lat", "45", "--seconds", "2", "--json", str(out)]) == 0
    doc = _json(out)
    assert doc["rows"] == 200 and doc["end_s"] == pytest.approx(1.99)
    assert main(["bias", str(csv), "--lat", "45", "--seconds", "1"]) == 2
    err = capsys.readouterr().err
    assert "the first 1 s keep 100 rows at 100 Hz" in err and "at least 128 (1.28 s)" in err, err


def test_a_recording_without_a_rest_long_enough_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A unit still for 1 s, then turning: its rest is too short for the noise fit, said as a rest (it was
    "the longest stretch of referenced rows without a gap has 75"); so is PSINS's vehicle, which never
    stands still (96 rows, 9.6 s at its 10 Hz, against 128)."""
    imu, _ = still_unit(10.0, np.zeros(3), np.zeros(3), np.r_[[3e-4] * 3, [0.01] * 3])
    turning = imu.t >= 1.0
    imu.omega_ib_b[turning, 2] += 0.5 * np.sin(2 * math.pi * 0.5 * imu.t[turning])  # rad/s
    io.write_imu(tmp_path / "turns.csv", imu)
    assert main(["bias", str(tmp_path / "turns.csv"), "--lat", "45"]) == 2
    err = capsys.readouterr().err.splitlines()[-1]
    assert "no rest long enough for the biases" in err and "needs 128 in one stretch (1.28 s)" in err, err
    dataset_folder("psins_fog_mems_vehicle")
    assert main(["bias", "--dataset", "psins_vehicle"]) == 2
    err = capsys.readouterr().err.splitlines()[-1]
    assert "psins_vehicle: no rest long enough" in err and "96 rows (9.6 s at 10 Hz)" in err, err


def _dataset_bias(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[dict, str]:
    out = tmp_path / f"{name.replace('/', '_')}.json"
    assert main(["bias", "--dataset", name, "--json", str(out)]) == 0
    return _json(out), capsys.readouterr().out


def test_ferraris_holds_are_rests_each_in_its_own_attitude(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Ferraris's six holds face six ways: the header had averaged their gravity to 0.51 m/s² at roll
    −25°, and said "at −0.0000°" from a reference without Earth's rate. Now: each hold's attitude (an
    axis up or down: multiples of 90°), gravity 9.81 m/s² (SOURCE.md's check, to the 3 mm/s² any
    European latitude moves it), and no latitude."""
    dataset_folder("imucal_ferraris")
    doc, text = _dataset_bias("ferraris", tmp_path, capsys)
    assert doc["lat_deg"] is None and "latitude not known" in text and "0.510587" not in text
    assert (
        doc["gravity_mps2"] == pytest.approx(9.81, abs=3e-3)
        and doc["earth_rate_radps"] is None
        and doc["reference_rate_radps"] == 0.0
    )
    assert len(doc["rests"]) == 6 and sum(r["rows"] for r in doc["rests"]) == doc["rows"]
    for r in doc["rests"]:
        assert r["gravity_mps2"] == pytest.approx(9.81, abs=3e-3) and r["yaw_deg"] is None
        for angle in (r["roll_deg"], r["pitch_deg"]):
            assert abs(angle / 90.0 - round(angle / 90.0)) < 1e-9, r


def test_ferraris_white_figure_is_the_spread_within_each_hold(tmp_path: Path) -> None:
    """ "1σ if white" was the spread of the readings across holds facing different ways (1.17e4 µg on
    accel.x); now it lies inside SOURCE.md's within-hold spread, 0.011–0.018 m/s², over √rows."""
    dataset_folder("imucal_ferraris")
    out = tmp_path / "f.json"
    assert main(["bias", "--dataset", "ferraris", "--json", str(out)]) == 0
    doc = _json(out)
    n = doc["rows"]
    for axis in "xyz":
        white = doc["channels"][f"accel.{axis}"]["sigma_white"]
        assert 0.011 / math.sqrt(n) <= white <= 0.018 / math.sqrt(n), (axis, white / UG)


def test_a_referenced_dataset_is_placed_where_its_reference_lies(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """EuRoC's room frame is placed at 45° N only nominally, its latitude not known (formats.md), BROAD
    was recorded in Berlin (52.51° N, its reader's): the header had said −90° and −9.13°, from the
    reference's rate at rest, which is the trajectory's residual motion (56-175 °/h), not Earth's rate,
    and said it was Earth's. BROAD's five breaks are five rests."""
    dataset_folder("euroc")
    doc, text = _dataset_bias("euroc/MH_01_easy", tmp_path, capsys)
    assert doc["lat_deg"] is None and "latitude not known" in text
    assert "69.87 °/h (not Earth's 15.04 °/h: the reference's own motion at rest)" in text
    assert all(r["yaw_deg"] is None and "not Earth's" in r["heading_note"] for r in doc["rests"])
    dataset_folder("broad_mocap")
    doc, text = _dataset_bias("broad_05", tmp_path, capsys)
    assert doc["lat_deg"] == pytest.approx(52.51, abs=1e-3) and len(doc["rests"]) == 5
    assert doc["gravity_mps2"] == pytest.approx(9.8127, abs=2e-3)  # normal gravity in Berlin, its reader's


def test_a_1_sigma_is_at_least_the_batch_means_of_what_is_averaged(tmp_path: Path) -> None:
    """On EuRoC's MH_01 the noise model (a quantization) gave accel.x a 1σ of 8.57 µg where numpy's
    batch means of the readings less their reference over the rests give 48.6: every 1σ is now at least
    the batch means' (the same rows, each rest's stretches found again by the times the report gives)."""
    dataset_folder("euroc")
    out = tmp_path / "e.json"
    assert main(["bias", "--dataset", "euroc/MH_01_easy", "--json", str(out)]) == 0
    doc = _json(out)
    data = io.read(dataset="euroc/MH_01_easy").reference_inputs()[0]
    error = np.hstack([data.gyro - data.ref_gyro, data.accel - data.ref_accel])
    rows = np.zeros(len(data.t), dtype=bool)
    for r in doc["rests"]:
        rows |= (data.t >= r["start_s"] - 1e-9) & (data.t <= r["end_s"] + 1e-9)
    edges = np.diff(np.r_[0, rows.astype(int), 0])
    rests = list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True))
    assert sum(b - a for a, b in rests) == doc["rows"]
    batch = _numpy_batch_means(error, rests)
    sigma = np.array([c["sigma"] for c in doc["channels"].values()])
    assert np.all(sigma >= batch * (1 - 1e-9)), sigma / batch


def test_a_warm_up_ramp_stays_out_of_the_biass_1_sigma() -> None:
    """A still level unit at 45° N, 10 min at 100 Hz, white noise of 1e-3 m/s² on the accelerometers, and
    a 5 mg ramp on accel x (mean unchanged): the ramp is the trend, reported apart, and the batch means
    had taken it for noise (27 µg of 1σ where the noise gives σ/√n = 0.41 µg). Within 3 × 13 % of σ/√n
    (the batch means' spread) on x as on y, which has no ramp."""
    rng = np.random.default_rng(0)
    t = np.arange(60_000) / 100.0
    lat = math.radians(45.0)
    omega = 7.292115e-5
    readings = np.array([omega * math.cos(lat), 0.0, -omega * math.sin(lat), 0.0, 0.0, -9.80665])
    readings = readings + rng.standard_normal((len(t), 6)) * np.r_[[1e-4] * 3, [1e-3] * 3]
    readings[:, 3] += 5e-3 * 9.80665 * (t / t[-1] - 0.5)
    from sins.characterise.bias import estimate_bias

    e = estimate_bias(t, readings, lat, 0.0)
    assert e.channels["accel.x"].trend_significant
    white = 1e-3 / math.sqrt(len(t))
    for ch in ("accel.x", "accel.y"):
        assert e.channels[ch].sigma == pytest.approx(white, rel=0.39), ch


def test_rests_that_disagree_bound_the_pooled_bias(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Ferraris's six holds read accelerometer biases up to 4e4 µg apart (its scale factors and
    misalignments, seen in six attitudes): the pooled bias had been given ±25 µg, each hold's noise. Its
    1σ is now at least the holds' own means' spread over √6 (numpy, over the rests' spans the report
    gives; 5 % for rows at a span's edges that the still test left out)."""
    dataset_folder("imucal_ferraris")
    doc, _ = _dataset_bias("ferraris", tmp_path, capsys)
    data = io.read(dataset="ferraris").reference_inputs()[0]
    error = np.hstack([data.gyro - data.ref_gyro, data.accel - data.ref_accel])
    spans = [(data.t >= r["start_s"] - 1e-9) & (data.t <= r["end_s"] + 1e-9) for r in doc["rests"]]
    means = np.array([error[span].mean(axis=0) for span in spans])
    between = means.std(axis=0, ddof=1) / math.sqrt(len(means))
    sigma = np.array([c["sigma"] for c in doc["channels"].values()])
    # The random-effects figure against the plain spread of the six means over √6: the same where the
    # holds' noise is small beside their spread (Ferraris's accelerometers), within the rows' weights.
    assert np.all(sigma[3:] >= 0.8 * between[3:]), (sigma, between)
    assert sigma[3] > 1e-3 * 9.80665  # over a mg, where each hold's noise said 25 µg


def test_rests_that_agree_keep_their_noises_figure_and_rests_apart_their_spread() -> None:
    """Four rests of 2,000 rows of white noise (σ 1): agreeing, the pooled mean's error is σ/√8000
    (within the batch means' 3 × 13 %); offset by 0, 10, -10, 5, it is their spread over √4, the
    noise a part in 10⁴ of it (within 5 %: the spread estimated from four means)."""
    from sins.characterise.mean_error import pooled_rests_sigma

    rng = np.random.default_rng(4)
    noise = rng.standard_normal((8000, 1))
    groups = [[(k * 2000, (k + 1) * 2000)] for k in range(4)]
    assert pooled_rests_sigma(noise, groups)[0] == pytest.approx(1 / math.sqrt(8000), rel=0.39)
    offsets = np.repeat([0.0, 10.0, -10.0, 5.0], 2000)[:, None]
    means = np.array([(noise + offsets)[a:b].mean() for ((a, b),) in groups])
    got = pooled_rests_sigma(noise + offsets, groups)[0]
    assert got == pytest.approx(means.std(ddof=1) / 2.0, rel=0.05)


def test_a_free_solution_gone_non_finite_names_the_likely_causes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A still 100 Hz unit whose stamps are in ms, read as s: 30 s become 8.3 h at 0.1 Hz, over which
    the free vertical channel (e-folding in about 9.5 min) leaves floating point. Before, "the last
    position came out nan" and nothing of why; with the unit given it navigates."""
    rng = np.random.default_rng(1)
    n = 3000
    t_ms = np.arange(n) * 10.0
    f_ib_b = np.array([0.0, 0.0, -9.80665]) + rng.normal(0.0, 2e-3, (n, 3))
    readings = np.column_stack([t_ms, rng.normal(0.0, 1e-3, (n, 3)), f_ib_b])
    path = tmp_path / "ms.csv"
    head = "t,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z"
    np.savetxt(path, readings, delimiter=",", fmt="%.10g", header=head, comments="")
    argv = ["integrate", str(path), "--origin", "45,0,0", "--attitude", "0,0,0"]
    assert main(argv) == 2
    err = capsys.readouterr().err.splitlines()[-1]
    assert "free vertical channel, which diverges over 8.33 h" in err, err
    assert "times in another unit (the readings come at 0.1 Hz)" in err, err
    assert main([*argv, "--vertical", "hold"]) == 0  # the channel held: finite, if nonsense
    assert main([*argv, "--units", "t=ms"]) == 0


def test_a_gap_in_a_still_recording_is_said(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``sins bias`` averaged across 5 s without readings without a word (``sins integrate`` says so)."""
    imu, _ = still_unit(200.0, np.zeros(3), np.zeros(3), _nav_noise())
    keep = np.r_[0:5000, 5500 : len(imu.t)]
    io.write_imu(
        tmp_path / "gap.csv",
        ImuRates(t=imu.t[keep], omega_ib_b=imu.omega_ib_b[keep], f_ib_b=imu.f_ib_b[keep]),
    )
    assert main(["bias", str(tmp_path / "gap.csv"), "--lat", str(LAT_DEG)]) == 0
    err = capsys.readouterr().err
    assert (
        "1 gap(s) in the readings (the longest 5.01 s at 49.99 s), the rows on either side averaged" in err
    ), err
