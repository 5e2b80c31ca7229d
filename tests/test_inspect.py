"""``sins inspect`` on recordings written here with numpy: silent on clean ones, and each planted mistake
named with the option that mends it (and gone once that option is passed)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from conftest import dataset_folder
from scipy.integrate import cumulative_trapezoid
from scipy.spatial.transform import Rotation, Slerp

from sins import io
from sins.cli import main
from sins.core.series import ImuRates
from sins.io import filled, inspection

OMEGA = 7.292115e-5  # Earth's rate, rad/s
G = 9.8062  # normal gravity at 45° N, m/s²
LAT = np.radians(45.0)
RATE = ("t", "gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
INCREMENT = ("t", "dtheta_x", "dtheta_y", "dtheta_z", "dv_x", "dv_y", "dv_z")


# --------------------------------------------------------------------------- numpy recordings


def static(seconds: float = 120.0, rate: float = 100.0, grade: str = "tactical", seed: int = 1) -> dict:
    """A still, level unit heading 30°: Earth's rate and gravity on FRD axes, a bias and white noise.

    Tactical: 0.1 °/√h and 100 µg/√Hz (2.9e-4 rad/s and 0.01 m/s² a sample at 100 Hz), 1 °/h and 1 mg
    biases; MEMS: ten times the noise, 200 °/h and 10 mg.
    """
    rng = np.random.default_rng(seed)
    n = int(seconds * rate)
    gyro_sigma, accel_sigma, gyro_bias, accel_bias = {
        "tactical": (2.9e-4, 0.01, np.radians(1.0) / 3600, 0.0098),
        "mems": (2.9e-3, 0.1, np.radians(200.0) / 3600, 0.098),
    }[grade]
    yaw = np.radians(30.0)
    w_n = OMEGA * np.array([np.cos(LAT), 0.0, -np.sin(LAT)])
    w_b = np.array([np.cos(yaw) * w_n[0], -np.sin(yaw) * w_n[0], w_n[2]])
    unit = rng.standard_normal((2, 3))
    unit /= np.linalg.norm(unit, axis=1)[:, None]
    return {
        "t": np.arange(n) / rate,
        "w": w_b + gyro_bias * unit[0] + gyro_sigma * rng.standard_normal((n, 3)),
        "f": [0.0, 0.0, -G] + accel_bias * unit[1] + accel_sigma * rng.standard_normal((n, 3)),
    }


def drive(rate: float = 100.0, seed: int = 2) -> dict:
    """A level car on FRD axes: 30 s still, then accelerations, turns both ways and a stop; the specific
    force is (dv/dt, v · yaw rate, -g) and the rate Earth's plus the yaw rate (tactical noise)."""
    rng = np.random.default_rng(seed)
    plan = [(30, 0.0, 0.0), (10, 1.5, 0.0), (15, 0.0, 0.0), (15, 0.0, 6.0), (10, 0.0, 0.0), (15, 0.0, -6.0),
            (10, 0.0, 0.0), (8, 0.0, 10.0), (12, 0.0, 0.0), (10, -1.5, 0.0), (15, 0.0, 0.0)]  # fmt: skip
    n = int(sum(p[0] for p in plan) * rate)
    accel, yaw_rate = np.zeros(n), np.zeros(n)
    k = 0
    for seconds, a, peak_dps in plan:
        m = int(seconds * rate)
        accel[k : k + m] = a
        yaw_rate[k : k + m] = 2.0 * np.radians(peak_dps) * np.sin(np.pi * np.arange(m) / m) ** 2
        k += m
    speed = np.cumsum(accel) / rate
    yaw = np.radians(10.0) + np.cumsum(yaw_rate) / rate
    w_n = OMEGA * np.array([np.cos(LAT), 0.0, -np.sin(LAT)])
    w = np.column_stack([np.cos(yaw) * w_n[0], -np.sin(yaw) * w_n[0], w_n[2] + yaw_rate])
    f = np.column_stack([accel, speed * yaw_rate, np.full(n, -G)])
    return {
        "t": np.arange(n) / rate,
        "w": w + 4.8e-6 + 2.9e-4 * rng.standard_normal((n, 3)),
        "f": f + [0.005, -0.004, 0.006] + 0.01 * rng.standard_normal((n, 3)),
        "speed": speed, "yaw_rate": yaw_rate,
    }  # fmt: skip


def drive_npz(path: Path, position_noise_m: float = 0.0) -> dict:
    """:func:`drive` in the ``.npz`` form with its exact reference, on z-up axes: the FRD body and NED world
    turned half a turn about north (x kept, y and z negated), so the body reads ``(f_x, −f_y, −f_z)`` and
    turns by minus the yaw about the world's up. With ``position_noise_m``, the positions carry white noise
    of that size and the velocity is differenced from them (numpy's gradient), as a motion capture's
    poses converted by a user would be. Returns the arrays written."""
    d = drive()
    yaw = np.radians(10.0) + cumulative_trapezoid(d["yaw_rate"], dx=0.01, initial=0.0)  # the rate's integral
    heading = np.column_stack([np.cos(yaw), -np.sin(yaw), np.zeros(len(yaw))])
    v = d["speed"][:, None] * heading
    p = np.cumsum(v, axis=0) / 100.0
    if position_noise_m:
        p = p + np.random.default_rng(5).normal(0.0, position_noise_m, p.shape)
        v = np.gradient(p, d["t"], axis=0)
    arrays = {
        "t_s": d["t"], "gyro_rad_s": d["w"] * FLU, "accel_m_s2": d["f"] * FLU,
        "q_wxyz": Rotation.from_euler("z", -yaw[:, None]).as_quat(scalar_first=True), "v_m_s": v, "p_m": p,
    }  # fmt: skip
    np.savez(path, **arrays)
    return arrays


def write(path: Path, t: np.ndarray, a: np.ndarray, b: np.ndarray, names: tuple[str, ...] = RATE) -> Path:
    """A sins-style CSV written with numpy alone (17 digits)."""
    np.savetxt(
        path, np.column_stack([t, a, b]), delimiter=",", fmt="%.17g", header=",".join(names), comments=""
    )
    return path


def inspect_cli(path: Path, *options: str) -> dict:
    """``sins inspect PATH --json`` as a user runs it; the JSON document."""
    out = path.with_suffix(".json")
    assert main(["inspect", str(path), *options, "--json", str(out)]) == 0
    return json.loads(out.read_text(encoding="utf-8"))


def flag(finding: dict) -> list[str]:
    """The option a finding names, as command-line arguments."""
    return [{"rate": "--rate"}.get(finding["option"], "--" + finding["option"]), finding["value"]]


# --------------------------------------------------------------------------- clean recordings


@pytest.mark.parametrize("grade", ["tactical", "mems"])
def test_a_clean_static_recording_is_silent(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], grade: str
) -> None:
    d = static(grade=grade)
    doc = inspect_cli(write(tmp_path / "still.csv", d["t"], d["w"], d["f"]))
    assert doc["findings"] == []
    assert "no likely mistakes found" in capsys.readouterr().out
    # The figures the silence rests on: all of it at rest, gravity's size within a bias (1 mg tactical,
    # 10 mg MEMS) of normal gravity, and Earth's rate within the tactical bias (1 of its 15 °/h).
    assert doc["rest"]["seconds"] == pytest.approx(120.0, abs=1.0)
    assert doc["rest"]["gravity_ratio"] == pytest.approx(1.0, abs=0.011)
    if grade == "tactical":
        assert doc["rest"]["earth_rate_ratio"] == pytest.approx(1.0, abs=0.1)
    assert doc["rate_hz"] == pytest.approx(100.0) and doc["gaps"] == [] and doc["clipping"] == []


def test_a_dead_accelerometer_is_named_not_a_crash(tmp_path: Path) -> None:
    """Accelerometer columns of zeros (dead, or not recorded): before, the unit search divided by gravity's
    ratio of zero and ``sins inspect`` ended in a ZeroDivisionError."""
    d = static(grade="tactical")
    doc = inspect_cli(write(tmp_path / "dead.csv", d["t"], d["w"], 0.0 * d["f"]))
    assert [f["code"] for f in doc["findings"]] == ["gravity_unknown"], doc["findings"]


def test_a_clean_drive_is_silent_and_its_axes_are_frd(tmp_path: Path) -> None:
    d = drive()
    doc = inspect_cli(write(tmp_path / "drive.csv", d["t"], d["w"], d["f"]))
    assert doc["findings"] == []
    assert doc["axes"] == "frd"  # gravity at rest gives d, the turns' lateral force r, and so f
    assert doc["rest"]["seconds"] >= 30.0


@pytest.mark.parametrize("position_noise_m", [0.0, 1e-3])
def test_beside_a_reference_a_steady_cruise_is_not_rest(tmp_path: Path, position_noise_m: float) -> None:
    """The drive's 47 s of straight cruise at 15 m/s read like rest to the readings alone (level,
    steady, no turn: a CSV without a reference counts them in); beside a reference that moves, only its
    30 s standing start and 15 s final stop are rest. (A vehicle cruising was reported at rest: PSINS's
    drive, 45 s of it at 11-16 m/s.) The same with 1 mm of noise on the positions and the velocity
    differenced from them (0.07 m/s of noise on each axis at rest): travel is judged by the chord over
    the window, not by a velocity."""
    arrays = drive_npz(tmp_path / "drive.npz", position_noise_m)
    csv = write(tmp_path / "drive.csv", arrays["t_s"], arrays["gyro_rad_s"], arrays["accel_m_s2"])
    alone = inspect_cli(csv)
    assert alone["rest"]["seconds"] > 80.0, alone["rest"]
    doc = inspect_cli(tmp_path / "drive.npz")
    assert doc["rest"]["seconds"] == pytest.approx(45.0, abs=2.0), doc["rest"]
    assert doc["findings"] == []


# --------------------------------------------------------------------------- planted mistakes

FLU = np.array([1.0, -1.0, -1.0])


def _rfu(a: np.ndarray) -> np.ndarray:
    """FRD rows on axes named after ENU: x right, y forward, z up."""
    return np.column_stack([a[:, 1], a[:, 0], -a[:, 2]])


def _gap(d: dict) -> dict:
    keep = np.r_[0:6000, 6050 : len(d["t"])]  # 50 rows at 100 Hz: 0.5 s
    return {k: v[keep] for k, v in d.items()}


def _clipped(d: dict) -> dict:
    w = d["w"].copy()
    w[:, 2] = np.clip(w[:, 2], -0.15, 0.15)  # turns reach 0.21 rad/s (12 °/s)
    return {**d, "w": w}


def _slow(d: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[str, ...]]:
    """Increments of a unit sampling at 98 Hz, stamped as if at 100 Hz: a 2 % rate error."""
    return d["t"][1:] + 0.01, d["w"][1:] / 98.0, d["f"][1:] / 98.0, INCREMENT


#: name: (recording, its rows as (t, a, b, header), the finding's code, the option and value that mend it)
PLANTED: dict[str, tuple[Callable[[], dict], Callable[[dict], tuple], str, str | None, str | None]] = {
    "deg/s read as rad/s": (static, lambda d: (d["t"], np.degrees(d["w"]), d["f"], RATE), "gyro_unit",
                            "units", "gyro=deg/s"),
    "g read as m/s²": (static, lambda d: (d["t"], d["w"], d["f"] / 9.80665, RATE), "accel_unit", "units",
                       "accel=g"),
    "ms read as s": (static, lambda d: (1000.0 * d["t"], d["w"], d["f"], RATE), "time_unit", "units", "t=ms"),
    "FLU axes": (static, lambda d: (d["t"], d["w"] * FLU, d["f"] * FLU, RATE), "axes", "frame", "flu"),
    "ENU-named axes": (drive, lambda d: (d["t"], _rfu(d["w"]), _rfu(d["f"]), RATE), "axes", "frame", "rfu"),
    "increments read as rates": (static, lambda d: (d["t"], d["w"] / 100.0, d["f"] / 100.0, RATE),
                                 "increments_as_rates", "columns",
                                 "dtheta_x=gyro_x,dtheta_y=gyro_y,dtheta_z=gyro_z,dv_x=accel_x,dv_y=accel_y,"
                                 "dv_z=accel_z"),
    "2 % rate error": (static, _slow, "interval", None, None),
    "0.5 s gap": (lambda: _gap(drive()), lambda d: (d["t"], d["w"], d["f"], RATE), "gaps", None, None),
    "clipping": (lambda: _clipped(drive()), lambda d: (d["t"], d["w"], d["f"], RATE), "clipping", None, None),
}  # fmt: skip


def test_a_file_sins_corrected_keeps_its_recordings_axes_unflagged(tmp_path: Path) -> None:
    """``sins correct`` writes the readings on the axes of the recording it corrected, whatever they are
    called (a EuRoC sequence's: x up), and says so in its header. ``sins inspect`` had flagged its
    own output's axes and advised --frame, which would turn readings the model had already corrected."""
    d = static()
    path = write(tmp_path / "flu.csv", d["t"], d["w"] * FLU, d["f"] * FLU)
    assert [f["code"] for f in inspect_cli(path)["findings"]] == ["axes"]
    corrected = tmp_path / "corrected.csv"
    said = "# corrected by: regression model m.json (sha256 0123456789abcdef), fitted on unit 7\n"
    corrected.write_text(said + path.read_text())
    assert inspect_cli(corrected)["findings"] == []


@pytest.mark.parametrize("name", list(PLANTED))
def test_each_planted_mistake_is_named_with_what_to_pass(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str
) -> None:
    make, rows, code, option, value = PLANTED[name]
    t, a, b, header = rows(make())
    path = write(tmp_path / "rec.csv", t, a, b, header)
    doc = inspect_cli(path)
    found = [f for f in doc["findings"] if f["code"] == code]
    assert len(found) >= 1, doc["findings"]
    # Nothing else is blamed (a clipped or gapped drive, say, is not also a frame mistake).
    assert {f["code"] for f in doc["findings"]} == {code}, doc["findings"]
    printed = capsys.readouterr().out
    if option is None:
        assert found[0]["advice"] and found[0]["advice"] in printed
        return
    assert (found[0]["option"], found[0]["value"]) == (option, value)
    assert f"pass --{option} {value}" in printed
    # The advice taken, the recording reads clean.
    assert inspect_cli(path, *flag(found[0]))["findings"] == []


def test_the_planted_figures(tmp_path: Path) -> None:
    """What the findings say, against what was planted."""
    d = _gap(drive())
    gaps = inspect_cli(write(tmp_path / "gap.csv", d["t"], d["w"], d["f"]))["gaps"]
    assert len(gaps) == 1 and gaps[0]["start_s"] == pytest.approx(59.99) and gaps[0]["missing"] == 50
    d = _clipped(drive())
    clips = inspect_cli(write(tmp_path / "clip.csv", d["t"], d["w"], d["f"]))["clipping"]
    assert {(c["channel"], c["level"]) for c in clips} == {("gyro_z", 0.15), ("gyro_z", -0.15)}
    assert sum(c["samples"] for c in clips) == int(np.sum(np.abs(d["w"][:, 2]) == 0.15))
    slow = inspect_cli(write(tmp_path / "slow.csv", *_slow(static())))["findings"][0]
    assert "98.0" in slow["what"] and "+2.0 %" in slow["what"]


def test_clipping_in_increments_is_found_as_rates(tmp_path: Path) -> None:
    """A clipped drive written as increments (each rate times its step; the steps of ``t = k / 100``
    differ in their last bits, and so do the increments of one clipped rate): found as the rate it sticks
    at, in rad/s, as in rate form. A new-user walk's clipped EuRoC .npz (read as increments) was called
    clean, and a clipping reported on increments showed an angle as a rate."""
    d = _clipped(drive())
    dt = np.diff(d["t"])[:, None]
    assert (
        len(np.unique(d["w"][1:, 2][np.abs(d["w"][1:, 2]) == 0.15] * dt[np.abs(d["w"][1:, 2]) == 0.15, 0]))
        > 2
    )
    clips = inspect_cli(write(tmp_path / "clip.csv", d["t"][1:], d["w"][1:] * dt, d["f"][1:] * dt, INCREMENT))
    found = {(c["channel"], round(c["level"], 12)) for c in clips["clipping"]}
    assert found == {("gyro_z", 0.15), ("gyro_z", -0.15)}


def test_a_clip_is_at_the_channels_largest_size_either_way() -> None:
    """A sine of 2 rad/s clipped at ±1.5 (numpy) sticks at both levels: found. The same sine held at
    its own minimum -1.2 for three readings, reaching +2.0 the other way, is equal readings in motion, not
    a range (a range is symmetric about zero to within the bias, :data:`~sins.io.frame_check.CLIP_ASYMMETRY`):
    EuRoC's MH_02 gyro y, three readings at -1.248 rad/s where it reads +1.678, was called the unit
    saturating. Its mirror, and a one-sided clip at +1.5 whose other side reaches -1.4 (within the bias's
    asymmetry, 0.2), are judged alike."""
    from sins.io.frame_check import stuck

    s = 2.0 * np.sin(np.linspace(0.0, 6.0 * np.pi, 3000))
    clipped = np.clip(s, -1.5, 1.5)
    for level in (1.5, -1.5):
        found = stuck(clipped, level)
        assert found is not None and found[0] == int(np.sum(clipped == level)), level
    held = np.where(s < -1.2, -1.2 + 0.01 * (s + 1.2), s)  # below -1.2 only the run set next
    held[1000:1003] = held.min() - 0.01
    assert int(np.sum(held == held.min())) == 3 and held.max() == pytest.approx(2.0, abs=1e-4)
    assert stuck(held, float(held.min())) is None and stuck(-held, float(-held.min())) is None
    one_sided = np.clip(np.where(s < 0.0, 0.7 * s, s), None, 1.5)  # reaches -1.4 the other way
    assert stuck(one_sided, 1.5) is not None


def test_a_stated_rate_is_checked_against_the_stamps(tmp_path: Path) -> None:
    d = static(seconds=30.0, rate=98.0)
    path = write(tmp_path / "rec.csv", d["t"], d["w"], d["f"])
    assert inspect_cli(path, "--rate", "98")["findings"] == []
    found = inspect_cli(path, "--rate", "100")["findings"]
    assert [f["code"] for f in found] == ["rate_mismatch"] and "-2.0 %" in found[0]["what"]


def test_mistakes_on_top_of_given_units_keep_them(tmp_path: Path) -> None:
    """A file in deg/s whose accelerations are in g, read with gyro=deg/s only: pass both."""
    d = static(seconds=30.0)
    path = write(tmp_path / "rec.csv", d["t"], np.degrees(d["w"]), d["f"] / 9.80665)
    found = inspect_cli(path, "--units", "gyro=deg/s")["findings"]
    assert [(f["option"], f["value"]) for f in found] == [("units", "gyro=deg/s,accel=g")]
    assert inspect_cli(path, "--units", "gyro=deg/s,accel=g")["findings"] == []


def test_quantized_readings_clip_only_far_from_their_median() -> None:
    """A quiet unit read through 16-bit steps (0.061 °/s, 0.6 mg: 3.7 and 0.6 times its noise) sits on its
    extreme step for runs of three at rest, which is not clipping; the same steps on a clipped drive are."""
    lsb_w, lsb_f = np.radians(0.061), 0.6e-3 * 9.80665

    def quantized(d: dict) -> io.Recording:
        w, f = np.round(d["w"] / lsb_w) * lsb_w, np.round(d["f"] / lsb_f) * lsb_f
        units = {"t": "s", "gyro": "rad/s", "accel": "m/s^2"}
        return io.Recording(ImuRates(t=d["t"], omega_ib_b=w, f_ib_b=f), "quantized", "sins csv", units=units)

    still = quantized(static(seconds=60.0))
    w_x = still.imu.omega_ib_b[:, 0]
    at_top = np.diff(np.concatenate([[0], (w_x == w_x.max()).astype(int), [0]]))
    assert (np.flatnonzero(at_top == -1) - np.flatnonzero(at_top == 1)).max() >= 3  # the case is there
    assert inspection.inspect(still).findings == ()
    clipped = inspection.inspect(quantized(_clipped(drive())))
    assert [f.code for f in clipped.findings] == ["clipping", "clipping"]


# --------------------------------------------------------------------------- a real recording

FERRARIS = dataset_folder("imucal_ferraris") / "example_ferraris_session.csv"
FERRARIS_COLUMNS = "gyro_x=gyr_x,gyro_y=gyr_y,gyro_z=gyr_z,accel_x=acc_x,accel_y=acc_y,accel_z=acc_z"


@pytest.mark.skipif(not FERRARIS.is_file(), reason=f"real data absent: {FERRARIS}")
def test_a_real_uncalibrated_mems_session(tmp_path: Path) -> None:
    """imucal's hand-turned Ferraris session (deg/s, m/s², 102.4 Hz, no time column; SOURCE.md): read
    as rad/s its hand turns reach 895 'rad/s', which names deg/s; read right, its first hold (x up) shows
    the unit's uncalibrated offset, 10.34 m/s² (SOURCE.md's own numpy check: 10.341), and the gyro bias
    SOURCE.md gives, [-0.60, -0.37, 0.06] °/s; the six holds' orientations keep the axes unjudged."""
    local = tmp_path / "ferraris.csv"
    local.symlink_to(FERRARIS)
    found = inspect_cli(local, "--columns", FERRARIS_COLUMNS, "--rate", "102.4")["findings"]
    assert sorted((f["code"], f["value"]) for f in found) == [
        ("gravity_size", None),
        ("gyro_range", "gyro=deg/s"),
    ]
    doc = inspect_cli(local, "--columns", FERRARIS_COLUMNS, "--rate", "102.4", "--units", "gyro=deg/s")
    assert [f["code"] for f in doc["findings"]] == ["gravity_size"]
    rest = doc["rest"]
    assert rest["gravity_ratio"] * inspection.GRAVITY == pytest.approx(10.341, abs=0.02)
    np.testing.assert_allclose(np.degrees(rest["rate"]), [-0.60, -0.37, 0.06], atol=0.02)
    assert rest["orientations"] == 2 and doc["axes"] is None


LASERGYRO = dataset_folder("psins_lasergyro_static") / "lasergyro.imu.xz"


@pytest.mark.skipif(not LASERGYRO.is_file(), reason=f"real data absent: {LASERGYRO}")
def test_a_real_ring_laser_unit_shows_earth_rate_and_gravity() -> None:
    """PSINS's static ring-laser INS (31 min at 100 Hz, read and turned into FRD by its dataset reader):
    it resolves Earth's rate, so it is silent read right, and its rate read as deg/s is named."""
    data = io.read(dataset="psins_lasergyro").reference_inputs()[0]
    units = {"t": "s", "gyro": "rad/s", "accel": "m/s^2"}
    rec = io.Recording(ImuRates(t=data.t, omega_ib_b=data.gyro, f_ib_b=data.accel), "lasergyro", "sins csv",
                       units=units)  # fmt: skip
    result = inspection.inspect(rec)
    assert result.findings == () and result.axes == "__d"
    assert result.rest is not None and result.rest.rate_resolved
    # A navigation-grade unit: Earth's rate (SOURCE.md: 15.041 °/h, its latitude's) and gravity within
    # 1 % of the nominal 7.292e-5 rad/s and 9.806 m/s² (measured: 0.998 and 0.999).
    assert result.rest.earth_rate_ratio == pytest.approx(1.0, abs=0.01)
    assert result.rest.gravity_ratio == pytest.approx(1.0, abs=0.01)
    in_degrees = io.Recording(ImuRates(t=data.t, omega_ib_b=np.degrees(data.gyro), f_ib_b=data.accel),
                              "lasergyro", "sins csv", units=units)  # fmt: skip
    assert [(f.code, f.value) for f in inspection.inspect(in_degrees).findings] == [
        ("gyro_unit", "gyro=deg/s")
    ]


PSINS_VEHICLE = dataset_folder("psins_fog_mems_vehicle")


@pytest.mark.skipif(not PSINS_VEHICLE.is_dir(), reason=f"real data absent: {PSINS_VEHICLE}")
def test_a_real_vehicle_that_never_stops_has_no_rest(capsys: pytest.CaptureFixture[str]) -> None:
    """PSINS's drive: its reference moves at 11.5-15.8 m/s throughout (its own velocities), and a steady
    stretch of it had been reported as 45 s at rest (its readings alone are as still as a stop's); the
    report says why none is found."""
    rec = io.read(dataset="psins_vehicle")
    assert rec.truth is not None and np.linalg.norm(rec.truth.v_n, axis=1).min() > 11.0
    assert inspection.inspect(rec).rest is None
    assert main(["inspect", "--dataset", "psins_vehicle"]) == 0
    said = capsys.readouterr().out
    assert "at rest: no stretch of two seconds or more found (beside the reference: where it shows" in said


BROAD = dataset_folder("broad_mocap")


@pytest.mark.skipif(not BROAD.is_dir(), reason=f"real data absent: {BROAD}")
def test_a_dataset_is_inspected_by_name_and_no_reader_option_is_offered(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``sins inspect --dataset broad_05``: BROAD's unit reads gravity along +z at rest (its own axes, as
    the dataset's reader keeps them, ``__u``), and beside its reference those are the body's axes: the
    reference's attitude agrees with them, so no finding, and no --frame to pass, which a dataset
    refuses. (Before a reference judged them, FRD's convention did, and called them a likely mistake.)"""
    assert main(["inspect", "--dataset", "broad_05"]) == 0
    out = capsys.readouterr().out
    assert "dataset, increment form" in out and "): __u" in out, out
    assert "no likely mistakes found" in out and "--frame" not in out, out
    assert main(["inspect", "--dataset", "broad_05", "--frame", "flu"]) == 2
    assert "frame does not apply to a dataset" in capsys.readouterr().err


@pytest.mark.skipif(not BROAD.is_dir(), reason=f"real data absent: {BROAD}")
def test_broads_two_trials_find_one_clock_offset_of_their_capture_system() -> None:
    """BROAD's reference is optical motion capture of the same unit in both trials: the shift at which
    its turns agree best with the gyro's is one offset of the capture system's clock, found again on the
    other trial within 0.5 ms (measured: 4.27 and 4.23 ms early) and under the 5 ms from which it is
    named. A lag estimate that followed each trial's motion would not replicate so."""
    lags = []
    for name in ("broad_05", "broad_18"):
        found = inspection.inspect(io.read(dataset=name))
        assert found.reference_lag is not None, name
        assert "reference_lag" not in [f.code for f in found.findings], name
        lags.append(found.reference_lag.lag_s)
    assert abs(lags[0] - lags[1]) < 5e-4 and all(-0.005 < lag < 0.0 for lag in lags), lags


EUROC = dataset_folder("euroc")


@pytest.mark.skipif(not EUROC.is_dir(), reason=f"real data absent: {EUROC}")
def test_a_reference_filled_by_interpolation_is_named(tmp_path: Path) -> None:
    """EuRoC's V1_02 as it is holds no filled span. With 1 s of its reference slerped from 40 s on (by
    scipy, as a converter fills a motion capture's lost markers), ``sins inspect`` names it
    (``reference_filled``), its inner epochs, and ``sins fit`` would set those aside
    (``sins.compensation.screening``)."""
    arrays = dict(np.load(EUROC / "V1_02_medium.npz"))
    t = arrays["t_s"]
    a = int(np.searchsorted(t, t[0] + 40.0))
    b = a + 200
    q = np.asarray(arrays["q_wxyz"], dtype=float).copy()
    ends = Rotation.from_quat(q[[a, b]], scalar_first=True)
    q[a : b + 1] = Slerp(t[[a, b]], ends)(t[a : b + 1]).as_quat(scalar_first=True)
    np.savez(tmp_path / "gap.npz", **{**arrays, "q_wxyz": q})
    clean = inspection.inspect(io.read(EUROC / "V1_02_medium.npz"))
    assert "reference_filled" not in [f.code for f in clean.findings]
    gap = io.read(tmp_path / "gap.npz")
    [finding] = [f for f in inspection.inspect(gap).findings if f.code == "reference_filled"]
    assert "1 span(s)" in finding.what and "sins fit sets these spans aside" in finding.advice
    t_ref, (t, w, _) = gap.truth.t, gap.mean_rates()
    assert filled.filled_spans(t_ref, gap.truth.q_nb, t, w) == ((t_ref[a + 1], t_ref[b - 1]),)
