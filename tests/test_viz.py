"""The Rerun bridge: recordings read back, the logged figures equal the run's, refusals."""

from __future__ import annotations

import gc
import json
import socket
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import refusal

import sins
from sins import scenario
from sins.cli import main
from sins.core import earth
from sins.errors import SinsInputError
from sins.imu import CHANNELS, DEG_PER_H, MG
from sins.runs import pipeline

# The bridge is ``sins.viz.viewer``, imported (with rerun under it) by the first test that uses it, not when
# pytest collects this module: every test process collects every module, and rerun costs each ~100 MB.


@pytest.fixture(autouse=True, scope="module")
def _rerun_installed() -> None:
    pytest.importorskip("rerun", reason="rerun-sdk is a dependency of sins; install the project")


def _rerun() -> Any:
    import rerun

    return rerun


IMU = """\
[[effect]]
name = "gyro.bias"
bias_dph = [4.0, -3.0, 5.0]
[[effect]]
name = "accel.bias"
bias_mg = [0.8, -1.1, 0.6]
[[effect]]
name = "gyro.scale_misalignment"
matrix_ppm = [[300, 120, -80], [-150, -250, 60], [90, -40, 400]]
[[effect]]
name = "gyro.noise"
arw_deg_per_rt_h = 0.05
"""

RIG = """\
[rig]
rate_hz = 50
[positions]
count = 24
dwell_s = 4
[rate_table]
rates_dps = [50, 200]
dwell_s = 3
"""

SCENARIO = """\
name = "viz_drive"
description = "two minutes with a turn"
[imu]
rate_hz = 100
model = "{imu}"
seed = 3
[compensation]
rig = "{rig}"
seed = 4
strategies = ["oracle", "regression"]
[navigation]
vertical = "damp"
[initial]
lat_deg = 45.0
lon_deg = 7.0
alt_m = 200.0
[[segment]]
type = "accelerate"
duration_s = 20
to_speed_mps = 15
[[segment]]
type = "turn"
duration_s = 30
angle_deg = 90
[[segment]]
type = "hold"
duration_s = 70.05
"""


def _read(path: Path) -> dict[str, dict[str, np.ndarray]]:
    """Every time-indexed column of a recording: entity → {"t": seconds, component: values}."""
    out: dict[str, dict[str, list[np.ndarray]]] = defaultdict(lambda: defaultdict(list))
    rr = _rerun()
    for chunk in rr.chunk.RrdReader(path).stream():
        if chunk.is_static:
            out[chunk.entity_path]["static"].append(np.array([1]))
            continue
        batch = chunk.to_record_batch()
        if "sim_time" in batch.schema.names:
            t = batch.column("sim_time").to_numpy().astype("int64") / 1e9
        elif "unit" in batch.schema.names:  # a campaign's final errors, by unit
            t = batch.column("unit").to_numpy().astype(float)
        else:  # the gap's Allan deviations, by octave of the cluster time
            t = batch.column(sins.viz.viewer.ALLAN_TIMELINE).to_numpy().astype(float)
        out[chunk.entity_path]["t"].append(t)
        for name in batch.schema.names:
            if ":" in name:  # "Archetype:component"
                values = np.array(batch.column(name).to_pylist(), dtype=float)
                values = values[:, 0] if values.ndim == 2 and values.shape[1] == 1 else values
                out[chunk.entity_path][name.split(":")[1]].append(values)
    return {e: {k: np.concatenate(v) for k, v in cols.items()} for e, cols in out.items()}


@pytest.fixture(scope="module")
def drive(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, pipeline.ScenarioRun]:
    folder = tmp_path_factory.mktemp("viz")
    (folder / "imu.toml").write_text(IMU)
    (folder / "rig.toml").write_text(RIG)
    path = folder / "drive.toml"
    path.write_text(SCENARIO.format(imu=folder / "imu.toml", rig=folder / "rig.toml"))
    return path, pipeline.run_scenario(scenario.load(path))


@pytest.fixture(scope="module")
def recorded(drive: tuple[Path, pipeline.ScenarioRun], tmp_path_factory: pytest.TempPathFactory):
    _, result = drive
    out = sins.viz.viewer.save(result, tmp_path_factory.mktemp("rrd") / "drive.rrd", summary="the table")
    return result, _read(out)


def test_entity_paths_and_row_counts(recorded) -> None:
    result, logged = recorded
    strategies = ["none", "oracle", "regression"]
    assert list(result.runs) == strategies
    n_nav, n_imu = len(result.truth.t), len(result.sensor_t)
    assert n_nav == 1201 + 1  # 10 Hz of 120.05 s: every 10th of 12006 samples, and the last
    expected = {f"/world/{s}/vehicle": n_nav for s in ["truth", *strategies]}
    expected |= {f"/errors/{panel}/{s}": n_nav for panel in sins.viz.viewer.ERROR_PANELS for s in strategies}
    labels = ["raw" if s == "none" else s for s in strategies]
    expected |= {
        f"/imu/{sins.viz.viewer.imu_entity(ch)}/{label}": n_imu for ch in CHANNELS for label in labels
    }
    for entity, rows in expected.items():
        assert entity in logged, entity
        assert len(logged[entity]["t"]) == rows, entity
    for static in ("/world/truth/path", "/world/regression/path", "/scenario", "/summary", "/world"):
        assert "static" in logged[static], static


def test_logged_final_errors_equal_the_runs_metrics(recorded) -> None:
    result, logged = recorded
    for name, run in result.runs.items():
        s = run.summary
        final = {p: logged[f"/errors/{p}/{name}"]["scalars"][-1] for p in sins.viz.viewer.ERROR_PANELS}
        assert logged[f"/errors/horizontal_m/{name}"]["t"][-1] == pytest.approx(result.truth.t[-1], abs=1e-9)
        assert final["horizontal_m"] == s.final_horizontal_m
        assert final["down_m"] == s.final_down_m
        speed = np.linalg.norm([s.final_vn_mps, s.final_ve_mps, s.final_vd_mps])
        assert final["velocity_mps"] == pytest.approx(speed, rel=1e-12)
        for axis in ("roll", "pitch", "yaw"):
            wanted = getattr(s, f"final_{axis}_deg")
            assert final[f"{axis}_deg"] == pytest.approx(wanted, rel=1e-12, abs=1e-15)
        assert logged[f"/errors/horizontal_m/{name}"]["scalars"].max() == pytest.approx(
            s.max_horizontal_m, rel=0.05
        )  # the thinned series (10 of 100 Hz) sees nearly the true maximum of a slow drift


def test_paths_start_at_the_origin_and_end_at_the_final_error(recorded) -> None:
    result, logged = recorded
    truth = logged["/world/truth/vehicle"]["translation"].reshape(-1, 3)
    np.testing.assert_allclose(truth[0], 0.0, atol=1e-6)
    for name, run in result.runs.items():
        path = logged[f"/world/{name}/vehicle"]["translation"].reshape(-1, 3)
        # Path separation at the end = the NED position error, up to the turn of the local frame over
        # the ~1.4 km drive (1.4 km / R = 2.2e-4 rad: 2 cm on an 85 m error) and float32 storage.
        np.testing.assert_allclose(path[-1] - truth[-1], run.errors.pos_ned_m[-1], rtol=0, atol=0.05)
        quat = logged[f"/world/{name}/vehicle"]["quaternion"].reshape(-1, 4)
        np.testing.assert_allclose(quat, run.solution.q_nb, rtol=0, atol=1e-6)  # stored as float32


def test_imu_error_signals_are_the_block_means_of_the_stream(recorded) -> None:
    result, logged = recorded
    raw = logged["/imu/gyro_x_deg_per_h/raw"]["scalars"]
    np.testing.assert_allclose(raw, result.runs["none"].sensor_error[:, 0] / DEG_PER_H)
    # The raw gyro x error is its 4 °/h bias + scale·ω + noise; its mean over the run is near the bias.
    assert np.mean(raw) == pytest.approx(4.0, abs=1.0)
    oracle = logged["/imu/accel_y_mg/oracle"]["scalars"]
    np.testing.assert_allclose(oracle, 0.0, atol=1e-9)  # the oracle removes all of a noiseless accel error
    assert np.mean(logged["/imu/accel_y_mg/raw"]["scalars"]) == pytest.approx(-1.1, abs=0.05)
    assert MG > 0


def test_one_more_run_beside_others(drive, tmp_path: Path) -> None:
    """A campaign logs extra runs under prefixes of their own into one recording."""
    _, result = drive
    path = tmp_path / "campaign.rrd"
    rr = _rerun()
    rec = rr.RecordingStream(sins.viz.viewer.APPLICATION_ID)
    rec.save(path)
    origin = (float(result.truth.lat[0]), float(result.truth.lon[0]), float(result.truth.h[0]))
    for member in range(2):
        sins.viz.viewer.log_run(
            rec, "regression", result.runs["regression"], origin, prefix=f"campaign/{member}"
        )
    rec.flush()
    rec.disconnect()
    logged = _read(path)
    for member in range(2):
        assert len(logged[f"/campaign/{member}/errors/horizontal_m/regression"]["t"]) == len(result.truth.t)


def test_local_ned_keeps_ecef_distances_and_matches_the_radii_to_first_order() -> None:
    lat0, lon0, h0 = np.radians(45.0), np.radians(7.0), 200.0
    lat = lat0 + np.array([1e-5, 0.0, 0.0, 3e-3])
    lon = lon0 + np.array([0.0, 1e-5, 0.0, -2e-3])
    h = h0 + np.array([0.0, 0.0, 10.0, 50.0])
    ned = earth.local_ned(lat, lon, h, lat0, lon0, h0)
    xyz = np.stack(earth.lla_to_ecef(lat, lon, h), axis=1) - np.array(earth.lla_to_ecef(lat0, lon0, h0))
    np.testing.assert_allclose(np.linalg.norm(ned, axis=1), np.linalg.norm(xyz, axis=1), rtol=1e-12)
    r_m, r_n = earth.radii(lat0)
    np.testing.assert_allclose(ned[0], [(r_m + h0) * 1e-5, 0, 0], atol=1e-3)  # second order: ~R·dφ²
    np.testing.assert_allclose(ned[1], [0, (r_n + h0) * np.cos(lat0) * 1e-5, 0], atol=1e-3)
    np.testing.assert_allclose(ned[2], [0, 0, -10.0], atol=1e-9)


def test_cli_saves_a_recording_and_refuses_what_cannot_work(
    drive, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    path, _ = drive
    out = tmp_path / "run.rrd"
    assert main(["run", str(path), "--rerun", str(out)]) == 0
    assert out.exists() and "wrote" in capsys.readouterr().out
    assert not list(tmp_path.glob(".*tmp"))  # the temporary name is gone

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["run", str(path), "--spawn"]) == 2
    err = capsys.readouterr()
    assert err.out == ""  # refused before the run, not after it
    assert err.err.count("\n") == 1 and "--rerun" in err.err and "--serve" in err.err

    assert main(["run", str(path), "--rerun", str(tmp_path / "nowhere" / "x.rrd")]) == 2
    assert "does not exist" in capsys.readouterr().err
    refusal(lambda: sins.viz.viewer.check_rrd_path(tmp_path / "run.csv"), "must end in .rrd")


def test_serve_keeps_the_outputs_it_said_it_wrote(
    drive, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # --serve ends only by an interrupt, which had removed the --json and --rerun files it had said were
    # written ("none of its outputs written"): they land before the wait now. (The server is stubbed and
    # the wait interrupted at once: what is judged is the files, not the viewer.)
    import time

    path, _ = drive
    monkeypatch.setattr(sins.viz.viewer, "serve", lambda result, **kw: "http://localhost:1/")

    def interrupted(seconds: float) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(time, "sleep", interrupted)
    out, rrd = tmp_path / "run.json", tmp_path / "run.rrd"
    assert main(["run", str(path), "--json", str(out), "--rerun", str(rrd), "--serve"]) == 130
    said = capsys.readouterr()
    assert "serving the Rerun web viewer" in said.out and "none of its outputs" not in said.err, said.err
    assert json.loads(out.read_text())["scenario"]["name"] == "viz_drive" and rrd.stat().st_size > 0
    assert not list(tmp_path.glob(".*tmp"))


def test_a_full_disk_is_one_line(drive, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # A recording written where no byte fits (/dev/full, written in place as devices are): rerun's own
    # file sink had raised "Failed to encode LogMsg ... No space left on device" with a traceback (exit 1),
    # and on a disk that filled as it wrote, hung in its flush past SIGINT and SIGTERM. The bytes are
    # written by Python now: one line, exit 2.
    if not Path("/dev/full").exists():
        pytest.skip("no /dev/full on this system")
    path, _ = drive
    full = tmp_path / "full.rrd"
    full.symlink_to("/dev/full")
    assert main(["run", str(path), "--rerun", str(full)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"sins: error: {full}: No space left on device") and err.count("\n") <= 2, err


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_serve_works_headless_and_gives_the_address(drive) -> None:
    import urllib.request

    _, result = drive
    web, grpc = _free_port(), _free_port()
    address = sins.viz.viewer.serve(result, summary="the table", web_port=web, grpc_port=grpc)
    assert address.startswith(f"http://localhost:{web}/?url=rerun%2Bhttp") and str(grpc) in address
    with urllib.request.urlopen(f"http://127.0.0.1:{web}/", timeout=600) as page:  # a deadlock guard
        assert page.status == 200 and b"<html" in page.read().lower()
    # The data's own server stays up once serve() has returned: it lived with a local recording stream,
    # and a browser had got the viewer's page with nothing to show (the connection refused).
    gc.collect()
    with socket.create_connection(("127.0.0.1", grpc), timeout=10):
        pass


def test_serve_refuses_a_taken_port_before_the_run(drive, capsys: pytest.CaptureFixture[str]) -> None:
    path, _ = drive
    with socket.socket() as taken:
        taken.bind(("0.0.0.0", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["run", str(path), "--serve", "--web-port", str(port)]) == 2
    said = capsys.readouterr()
    assert said.out == "" and f"--serve: port {port} is taken" in said.err, said  # no table: before the run


def test_each_saved_run_is_a_recording_of_its_own(drive, tmp_path: Path) -> None:
    """Two files of one scenario opened together: rerun pools files of one recording id, and every run of
    a scenario had its name as its id (two power-ons drawn as one zig-zag per strategy)."""
    rr = _rerun()
    _, result = drive
    readers = [rr.chunk.RrdReader(sins.viz.viewer.save(result, tmp_path / f"{k}.rrd")) for k in range(2)]
    ids = [r.recordings()[0].recording_id for r in readers]
    assert ids[0] != ids[1] and result.scenario.name not in ids
    batches = [c.to_record_batch() for c in readers[0].stream() if c.entity_path == "/__properties"]
    key = "RecordingInfo:name"
    names = [b.column(key).to_pylist() for b in batches if key in b.schema.names]
    assert names == [[[result.scenario.name]]], names  # the recording's name in the viewer's list


def test_an_rrd_name_says_its_flag_and_dev_null_is_taken(tmp_path: Path) -> None:
    assert sins.viz.viewer.check_rrd_path("/dev/null") == Path("/dev/null")
    assert sins.viz.viewer.check_rrd_path(tmp_path / ".rrd") == tmp_path / ".rrd"
    with pytest.raises(SinsInputError, match=r"^--rerun .*x\.rrdx: a Rerun recording's name must end in"):
        sins.viz.viewer.check_rrd_path(tmp_path / "x.rrdx", "--rerun")


def test_a_gap_diagnosis_logs_its_withheld_residuals_and_where_they_part(tmp_path: Path) -> None:
    import dataclasses

    from sins import gap, imu
    from sins.imu import calibration
    from sins.imu import spec as imu_spec

    rig = calibration.RigProcedure(position_dwell_s=6.0, rate_table=calibration.RateTable(dwell_s=3.0))
    unit = imu_spec.draw_unit("tactical", 1).only(*imu.BASELINE)
    data = calibration.simulate_rig(rig, unit, seed=1)
    gyro = data.gyro.copy()
    gyro[:, 0] += np.radians(0.05) * np.sin(2 * np.pi * data.t / 20.0)  # a gap on gyro x to localise
    report = gap.diagnose(dataclasses.replace(data, gyro=gyro))
    logged = _read(sins.viz.viewer.save_gap(report, tmp_path / "gap.rrd"))
    held = report.rows[1]
    for ch in CHANNELS:
        for label in ("before", "after"):
            assert len(logged[f"/gap/{sins.viz.viewer.imu_entity(ch)}/{label}"]["t"]) == held
    unit_size = DEG_PER_H
    np.testing.assert_allclose(
        logged["/gap/gyro_x_deg_per_h/before"]["scalars"], report.residual_before[:, 0] / unit_size
    )
    assert "static" in logged["/gap/report"]
    # Allan deviation by octave: the model's line is the floor's white noise, σ / √m, in log10 °/h.
    allan = report.allan["gyro.x"]
    model = logged["/gap/allan/gyro_x_deg_per_h/model"]
    clusters = 2.0 ** model["t"]
    floor = report.channels["gyro.x"]["noise_floor"] / unit_size
    np.testing.assert_allclose(model["scalars"], np.log10(floor / np.sqrt(clusters)), rtol=1e-6)
    before = logged["/gap/allan/gyro_x_deg_per_h/before"]["scalars"]
    assert np.max(before - model["scalars"]) > np.log10(3.0)  # the sinusoid stands out
    assert np.allclose(allan["tau_s"], clusters * np.median(np.diff(data.t)))
    # The excess by input quartile, as bar charts: shares of the excess, summing to one.
    assert set(report.quartiles["gyro.x"]) <= {"omega", "|ω|", "|f|", "rate of change", "time", "temperature"}
    assert "static" in logged["/gap/quartiles/gyro_x_deg_per_h/time"]
    assert sum(report.quartiles["gyro.x"]["time"]) == pytest.approx(1.0)


def test_several_gap_diagnoses_go_side_by_side_under_their_names(tmp_path: Path) -> None:
    """Reports made up here: each recording's residuals under its own name, two names that make one
    path told apart by their place, nothing of one logged under the other."""
    from sins.gap import GapReport

    rng = np.random.default_rng(3)
    t = np.arange(50) * 0.5
    floor = {ch: {"noise_floor": 1e-4, "rms_before": 2e-4, "rms_after": 1e-4} for ch in CHANNELS}
    reports = {
        name: GapReport(
            channels=floor, where=[], effects=[], diagnosis=[], unexplained=[], t_withheld=t,
            residual_before=rng.normal(0, 1e-4, (50, 6)), residual_after=rng.normal(0, 1e-4, (50, 6)),
        )
        for name in ("unit/a", "unit_a", "other")
    }  # fmt: skip
    logged = _read(sins.viz.viewer.save_gap(reports, tmp_path / "gaps.rrd"))
    for prefix, name in (("unit_a", "unit/a"), ("unit_a_2", "unit_a"), ("other", "other")):
        np.testing.assert_array_equal(
            logged[f"/{prefix}/gap/gyro_y_deg_per_h/before"]["scalars"],
            reports[name].residual_before[:, 1] / DEG_PER_H,
        )
        assert len(logged[f"/{prefix}/gap/accel_z_mg/after"]["t"]) == 50
    assert not any(entity.startswith("/gap/") for entity in logged)


def test_a_campaign_logs_its_percentile_bands_and_each_units_final_error(tmp_path: Path) -> None:
    """Rows made up here (units' error series that grow at known rates): the logged bands are numpy's
    percentiles across units at each time, and the points each unit's final error."""
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 300.0, 10.0)
    rows: dict[str, list[object]] = {k: [] for k in ("unit", "scenario", "strategy", "final_horizontal_m",
                                                     "series_t_s", "series_horizontal_m")}  # fmt: skip
    growth = {"none": rng.uniform(1.0, 3.0, 9), "regression": rng.uniform(0.1, 0.3, 9)}
    for unit in range(9):
        for strategy, rates in growth.items():
            series = rates[unit] * t
            rows["unit"].append(unit)
            rows["scenario"].append("drive")
            rows["strategy"].append(strategy)
            rows["final_horizontal_m"].append(float(series[-1]))
            rows["series_t_s"].append(t.tolist())
            rows["series_horizontal_m"].append(series.tolist())
    logged = _read(sins.viz.viewer.save_campaign(rows, tmp_path / "c.rrd"))
    for strategy, rates in growth.items():
        all_series = rates[:, None] * t[None, :]
        for q in sins.viz.viewer.CAMPAIGN_PERCENTILES:
            band = logged[f"/campaign/drive/horizontal_m/{strategy}/p{q}"]
            assert np.allclose(band["t"], t)
            assert np.allclose(band["scalars"], np.percentile(all_series, q, axis=0), rtol=1e-12)
        points = logged[f"/campaign/drive/final_m/{strategy}"]
        assert np.array_equal(points["t"], np.arange(9))
        assert np.allclose(points["scalars"], rates * t[-1], rtol=1e-12)
