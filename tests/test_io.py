"""CSV edge of the package: round trips, refusals with one-line messages, atomic writes, rate quadrature."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from conftest import refusal
from scipy.spatial.transform import Rotation

from sins import io
from sins.core.series import ImuIncrements, ImuRates, NavSeries

SEED = 20240611

RATE_HEADER = ",".join(io.RATE_COLUMNS)
INC_HEADER = ",".join(io.INCREMENT_COLUMNS)
TRUTH_HEADER = ",".join(io.TRUTH_COLUMNS)


# --------------------------------------------------------------------------- helpers


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def _random_truth(rng: np.random.Generator, n: int = 300) -> NavSeries:
    yaw = rng.uniform(-np.pi, np.pi, n)
    pitch = rng.uniform(-np.radians(60.0), np.radians(60.0), n)
    roll = rng.uniform(-np.pi, np.pi, n)
    q = Rotation.from_euler("ZYX", np.column_stack([yaw, pitch, roll])).as_quat()
    return NavSeries(
        t=100.0 + np.cumsum(rng.uniform(1e-3, 0.1, n)),
        lat=rng.uniform(-np.pi / 2, np.pi / 2, n),
        lon=rng.uniform(-np.pi, np.pi, n),
        h=rng.normal(0.0, 3000.0, n),
        v_n=rng.normal(0.0, 50.0, (n, 3)),
        q_nb=q,
    )


def _rows(n: int, width: int, start: float = 0.0) -> list[str]:
    return [
        ",".join([f"{start + 0.01 * (k + 1):.2f}"] + [f"{0.1 * (k + j):g}" for j in range(width - 1)])
        for k in range(n)
    ]


# --------------------------------------------------------------------------- round trips


def test_truth_round_trip(tmp_path: Path) -> None:
    rng = np.random.default_rng(SEED)
    truth = _random_truth(rng)
    path = tmp_path / "truth.csv"
    io.write_truth(path, truth, comment="a comment\nover two lines")
    back = io.read_truth(path)
    # Values stored as written (%.17g round-trips float64): time, height and velocity are bit for bit.
    assert np.array_equal(back.t, truth.t)
    assert np.array_equal(back.h, truth.h)
    assert np.array_equal(back.v_n, truth.v_n)
    # The file holds degrees, and these are exactly np.degrees(lat) ...
    table = io.read_table(path)
    assert table.columns == io.TRUTH_COLUMNS  # the names carry their units (issue 34)
    assert np.array_equal(table.column("lat_deg"), np.degrees(truth.lat))
    assert np.array_equal(table.column("lon_deg"), np.degrees(truth.lon))
    # ... but radians(degrees(x)) is x only to within one rounding of the conversion: 1 ulp.
    assert np.all(np.abs(back.lat - truth.lat) <= np.spacing(np.abs(truth.lat)))
    assert np.all(np.abs(back.lon - truth.lon) <= np.spacing(np.abs(truth.lon)))
    # Attitude goes through Euler degrees: a few roundings of angles up to π, |pitch| <= 60° keeps
    # the Euler extraction well conditioned (measured 7e-16).
    sign = np.sign(np.sum(back.q_nb * truth.q_nb, axis=1))[:, None]
    assert np.abs(back.q_nb * sign - truth.q_nb).max() < 2e-15


def test_rate_imu_round_trip_with_extra_columns(tmp_path: Path) -> None:
    rng = np.random.default_rng(SEED + 1)
    n = 257
    imu = ImuRates(
        t=np.cumsum(rng.uniform(1e-3, 2e-2, n)),
        omega_ib_b=rng.normal(0.0, 0.3, (n, 3)),
        f_ib_b=rng.normal(0.0, 9.8, (n, 3)),
    )
    extra = {"temp": rng.uniform(-20.0, 60.0, n), "odometer_m": rng.normal(0.0, 1e-3, n)}
    path = tmp_path / "imu.csv"
    io.write_imu(path, imu, extra=extra, comment="rate form")
    samples, table = io.read(path).imu, io.read_table(path)
    assert isinstance(samples, ImuRates)
    # %.17g round-trips every float64: exact equality.
    assert np.array_equal(samples.t, imu.t)
    assert np.array_equal(samples.omega_ib_b, imu.omega_ib_b)
    assert np.array_equal(samples.f_ib_b, imu.f_ib_b)
    assert table.columns == (*io.RATE_COLUMNS, "temp", "odometer_m")
    assert np.array_equal(table.column("temp"), extra["temp"])
    assert np.array_equal(table.column("odometer_m"), extra["odometer_m"])


def test_increment_imu_round_trip_with_extra_columns(tmp_path: Path) -> None:
    rng = np.random.default_rng(SEED + 2)
    n = 199
    t = 3.0 + np.concatenate([[0.0], np.cumsum(rng.uniform(1e-3, 2e-2, n))])
    imu = ImuIncrements(t=t, dtheta_b=rng.normal(0.0, 1e-3, (n, 3)), dv_b=rng.normal(0.0, 0.1, (n, 3)))
    extra = {"temp": rng.uniform(-20.0, 60.0, n), "odometer_m": rng.normal(0.0, 1e-4, n)}
    path = tmp_path / "imu.csv"
    io.write_imu(path, imu, extra=extra)
    samples, table = io.read(path).imu, io.read_table(path)
    assert isinstance(samples, ImuIncrements)
    assert np.array_equal(samples.dtheta_b, imu.dtheta_b)
    assert np.array_equal(samples.dv_b, imu.dv_b)
    # Without a known start, the reader extrapolates the first interval from the next one.
    assert np.array_equal(samples.t[1:], imu.t[1:])
    assert samples.t[0] == imu.t[1] - (imu.t[2] - imu.t[1])
    # With the start known (the truth's first time), the time base comes back exactly.
    exact = io.increments_from_table(table, float(imu.t[0]))
    assert np.array_equal(exact.t, imu.t)
    assert np.array_equal(exact.dtheta_b, imu.dtheta_b)
    assert np.array_equal(exact.dv_b, imu.dv_b)
    assert np.array_equal(table.column("temp"), extra["temp"])
    assert np.array_equal(table.column("odometer_m"), extra["odometer_m"])


def test_comment_is_written_as_hash_lines_before_the_header(tmp_path: Path) -> None:
    path = tmp_path / "t.csv"
    io.write_table(path, ["t", "a"], np.array([[0.0, 1.0], [1.0, 2.0]]), comment="one\ntwo")
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[:3] == ["# one", "# two", "t,a"]
    table = io.read_table(path)
    assert table.first_data_line == 4
    assert np.array_equal(table.data, [[0.0, 1.0], [1.0, 2.0]])


def test_a_table_written_in_blocks_is_numpys_one_call_text_and_reports_its_rows(tmp_path: Path) -> None:
    """The blocks (what a progress bar needs) change nothing: the text is ``numpy.savetxt`` of the whole
    array in one call, and progress is reported after every block, ending at the row count."""
    rng = np.random.default_rng(SEED)
    n = 2 * io.formats.WRITE_BLOCK_ROWS + 17
    data = rng.normal(0.0, 1e3, (n, 3))
    path = tmp_path / "blocks.csv"
    calls: list[tuple[int, int]] = []
    io.write_table(
        path, ["t", "a", "b"], data, comment="c", progress=lambda done, total: calls.append((done, total))
    )
    whole = tmp_path / "whole.csv"
    np.savetxt(whole, data, delimiter=",", fmt="%.17g", header="# c\nt,a,b", comments="")
    assert path.read_bytes() == whole.read_bytes()
    block = io.formats.WRITE_BLOCK_ROWS
    assert calls == [(block, n), (2 * block, n), (n, n)]


# --------------------------------------------------------------------------- refusals


COMMENTS = "# recorded by a test\n# second comment line\n"  # two lines before the header


def test_missing_required_column(tmp_path: Path) -> None:
    header = RATE_HEADER.replace(",gyro_y", "")
    path = _write(tmp_path / "imu.csv", COMMENTS + header + "\n" + "\n".join(_rows(3, 6)) + "\n")
    refusal(lambda: io.read_table(path, required=io.RATE_COLUMNS), f"{path}:3:", "'gyro_y'")
    refusal(lambda: io.read(path), f"{path}:3:", "'gyro_y'")


def test_truth_read_with_the_names_before_and_after_they_carried_units(tmp_path: Path) -> None:
    """The same rows under ``lat, lon, alt, roll, pitch, yaw`` and under ``lat_deg, lon_deg, h_m,
    roll_deg, pitch_deg, yaw_deg`` give the same trajectory, bit for bit; a column missing under both
    names is refused by its new name, and an old name's range error names the old column."""
    rows = "\n".join(["0,45,7,100,1,2,3,10,-5,170", "1,45.001,7.002,101,1,2,3,11,-4,-175"]) + "\n"
    old = io.read_truth(
        _write(tmp_path / "old.csv", ",".join(io.formats.TRUTH_COLUMNS_UNSUFFIXED) + "\n" + rows)
    )
    new = io.read_truth(_write(tmp_path / "new.csv", ",".join(io.TRUTH_COLUMNS) + "\n" + rows))
    for field in ("t", "lat", "lon", "h", "v_n", "q_nb"):
        assert np.array_equal(getattr(old, field), getattr(new, field)), field
    assert new.h[0] == 100.0 and new.lat[0] == np.radians(45.0)
    mixed = "t,lat,lon_deg,alt,vn,ve,vd,roll_deg,pitch,yaw_deg\n" + rows
    assert np.array_equal(io.read_truth(_write(tmp_path / "mixed.csv", mixed)).q_nb, new.q_nb)
    header = ",".join(io.TRUTH_COLUMNS).replace(",pitch_deg", "")
    refusal(lambda: io.read_truth(_write(tmp_path / "none.csv", header + "\n" + rows)), "'pitch_deg'")
    bad = ",".join(io.formats.TRUTH_COLUMNS_UNSUFFIXED) + "\n" + rows.replace(",170", ",1e9")
    refusal(lambda: io.read_truth(_write(tmp_path / "bad.csv", bad)), "'yaw'")


def test_truth_missing_column(tmp_path: Path) -> None:
    header = TRUTH_HEADER.replace(",vd", "")
    path = _write(tmp_path / "truth.csv", header + "\n" + "\n".join(_rows(3, 9)) + "\n")
    refusal(lambda: io.read_truth(path), f"{path}:1:", "'vd'")


@pytest.mark.parametrize("comments", ["", COMMENTS], ids=["no-comments", "two-comment-lines"])
def test_non_numeric_cell(tmp_path: Path, comments: str) -> None:
    rows = _rows(6, 7)
    cells = rows[3].split(",")
    cells[4] = "abc"  # data row 4, column accel_x
    rows[3] = ",".join(cells)
    path = _write(tmp_path / "imu.csv", comments + RATE_HEADER + "\n" + "\n".join(rows) + "\n")
    line = comments.count("\n") + 1 + 4
    refusal(lambda: io.read_table(path, required=io.RATE_COLUMNS), f"{path}:{line}:", "'accel_x'", "abc")
    refusal(lambda: io.read(path), f"{path}:{line}:", "'accel_x'", "abc")


@pytest.mark.parametrize("bad", ["nan", "NaN", "inf", "-inf", "1e999"])
def test_non_finite_value(tmp_path: Path, bad: str) -> None:
    rows = _rows(5, 7)
    cells = rows[2].split(",")
    cells[3] = bad  # data row 3, column gyro_z
    rows[2] = ",".join(cells)
    path = _write(tmp_path / "imu.csv", COMMENTS + RATE_HEADER + "\n" + "\n".join(rows) + "\n")
    refusal(lambda: io.read_table(path), f"{path}:6:", "'gyro_z'", "non-finite")
    refusal(lambda: io.read(path), f"{path}:6:", "'gyro_z'")


@pytest.mark.parametrize("bad_t", ["0.02", "0.01"], ids=["equal", "decreasing"])
def test_non_increasing_time(tmp_path: Path, bad_t: str) -> None:
    rows = _rows(5, 7)  # times 0.01 .. 0.05
    rows[2] = bad_t + rows[2][rows[2].index(",") :]  # data row 3 goes back to (or stays at) row 2's time
    path = _write(tmp_path / "imu.csv", COMMENTS + INC_HEADER + "\n" + "\n".join(rows) + "\n")
    refusal(lambda: io.read_table(path), f"{path}:6:", "'t'", "does not increase")
    refusal(lambda: io.read(path), f"{path}:6:", "'t'")


@pytest.mark.parametrize("width", [6, 8], ids=["too-few", "too-many"])
def test_wrong_number_of_values(tmp_path: Path, width: int) -> None:
    rows = _rows(5, 7)
    rows[3] = ",".join(["0.04"] + ["1"] * (width - 1))
    path = _write(tmp_path / "imu.csv", COMMENTS + RATE_HEADER + "\n" + "\n".join(rows) + "\n")
    refusal(lambda: io.read_table(path), f"{path}:7:", f"expected 7 values, found {width}")


@pytest.mark.parametrize("text", ["", "\n\n", "# only a comment\n"], ids=["empty", "blank", "comment-only"])
def test_empty_file(tmp_path: Path, text: str) -> None:
    path = _write(tmp_path / "imu.csv", text)
    refusal(lambda: io.read_table(path), str(path), "empty")
    refusal(lambda: io.read(path), str(path), "empty")
    refusal(lambda: io.read_truth(path), str(path), "empty")


def test_header_only(tmp_path: Path) -> None:
    path = _write(tmp_path / "imu.csv", COMMENTS + INC_HEADER + "\n")
    refusal(lambda: io.read_table(path), str(path), "no data rows")
    refusal(lambda: io.read(path), str(path), "no data rows")


def test_duplicate_column(tmp_path: Path) -> None:
    path = _write(
        tmp_path / "imu.csv", COMMENTS + RATE_HEADER + ",temp,temp\n" + "\n".join(_rows(2, 9)) + "\n"
    )
    refusal(lambda: io.read_table(path), f"{path}:3:", "'temp'", "twice")


def test_mixed_imu_forms(tmp_path: Path) -> None:
    header = "t,gyro_x,gyro_y,gyro_z,dv_x,dv_y,dv_z"
    path = _write(tmp_path / "imu.csv", COMMENTS + header + "\n" + "\n".join(_rows(3, 7)) + "\n")
    refusal(lambda: io.read(path), f"{path}:3:", "mixes", "gyro_x", "dv_x")
    refusal(lambda: io.imu_form(tuple(header.split(",")), path, 3), f"{path}:3:", "mixes")


def test_neither_imu_form(tmp_path: Path) -> None:
    path = _write(tmp_path / "imu.csv", COMMENTS + "t,a,b\n" + "\n".join(_rows(3, 3)) + "\n")
    refusal(lambda: io.read(path), f"{path}:3:", "not an IMU file")
    assert io.imu_form(io.RATE_COLUMNS, path) == "rate"
    assert io.imu_form(io.INCREMENT_COLUMNS, path) == "increment"


def test_nonexistent_file(tmp_path: Path) -> None:
    path = tmp_path / "missing" / "imu.csv"
    refusal(lambda: io.read_table(path), str(path), "no such file")
    refusal(lambda: io.read(path), str(path), "no such file")
    refusal(lambda: io.read_truth(path), str(path), "no such file")


def test_directory_instead_of_file(tmp_path: Path) -> None:
    refusal(lambda: io.read_table(tmp_path), str(tmp_path), "is a directory")
    refusal(lambda: io.read(tmp_path), str(tmp_path), "a folder")


def test_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "imu.csv"
    path.write_bytes(b"t,a\n0,\xff\xfe\n")
    refusal(lambda: io.read_table(path), str(path), "not UTF-8")


def test_truth_latitude_out_of_range(tmp_path: Path) -> None:
    rows = ["0,45,7,0,0,0,0,0,0,0", "1,95,7,0,0,0,0,0,0,0"]
    path = _write(tmp_path / "truth.csv", COMMENTS + TRUTH_HEADER + "\n" + "\n".join(rows) + "\n")
    refusal(lambda: io.read_truth(path), f"{path}:5:", "'lat_deg'", "95")


def test_truth_latitude_line_number_after_a_blank_line(tmp_path: Path) -> None:
    text = TRUTH_HEADER + "\n0,45,7,0,0,0,0,0,0,0\n\n# pause\n1,95,7,0,0,0,0,0,0,0\n"
    path = _write(tmp_path / "truth.csv", text)
    # Other checks (non-numeric, non-finite, time) do count those lines; the latitude check says line 3.
    refusal(lambda: io.read_truth(path), f"{path}:5:", "'lat_deg'")


def test_line_numbers_skip_blank_and_comment_rows_in_the_body(tmp_path: Path) -> None:
    text = COMMENTS + "t,a\n0,1\n\n# a pause in the recording\n1,nan\n"
    path = _write(tmp_path / "t.csv", text)
    refusal(lambda: io.read_table(path), f"{path}:7:", "'a'")


def test_utf8_bom_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "imu.csv"
    path.write_bytes(b"\xef\xbb\xbf" + (INC_HEADER + "\n" + "\n".join(_rows(3, 7)) + "\n").encode())
    samples = io.read(path).imu
    assert len(samples) == 3


def test_underscore_number_is_located(tmp_path: Path) -> None:
    path = _write(tmp_path / "t.csv", "t,a\n0,1\n1,1_000\n")
    refusal(lambda: io.read_table(path), f"{path}:3:", "'a'")


def test_messages_show_plain_numbers(tmp_path: Path) -> None:
    nan = _write(tmp_path / "nan.csv", "t,a\n0,1\n1,nan\n")
    back = _write(tmp_path / "back.csv", "t,a\n0,1\n0,2\n")
    for path in (nan, back):
        message = refusal(lambda p=path: io.read_table(p), str(path))
        assert "np.float64" not in message


# --------------------------------------------------------------------------- atomic writes


def test_write_into_nonexistent_directory(tmp_path: Path) -> None:
    target = tmp_path / "no" / "such" / "out.csv"
    truth = _random_truth(np.random.default_rng(SEED), n=4)
    refusal(lambda: io.write_table(target, ["t"], np.zeros((1, 1))), str(target), "does not exist")
    refusal(lambda: io.write_truth(target, truth), str(target))
    refusal(lambda: io.write_json(target.with_suffix(".json"), {"a": 1}), str(target.with_suffix(".json")))
    assert not (tmp_path / "no").exists()


def _failing_savetxt(fh, data, **kwargs) -> None:
    fh.write("t,a\n0,1\n0.5,")  # part of the file, then the disk fills up
    fh.flush()
    raise OSError(28, "No space left on device")


@pytest.mark.parametrize("existing", [False, True], ids=["new-target", "existing-target"])
def test_failed_write_leaves_nothing_behind(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, existing: bool
) -> None:
    target = tmp_path / "imu.csv"
    old = "t,a\n0,42\n"
    if existing:
        target.write_text(old, encoding="utf-8")
    before = sorted(p.name for p in tmp_path.iterdir())
    monkeypatch.setattr(np, "savetxt", _failing_savetxt)
    imu = ImuRates(t=np.arange(3.0), omega_ib_b=np.zeros((3, 3)), f_ib_b=np.ones((3, 3)))
    with pytest.raises(OSError, match="No space left"):
        io.write_imu(target, imu)
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # no temporary file either
    if existing:
        assert target.read_text(encoding="utf-8") == old


def test_failed_json_write_leaves_existing_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "out.json"
    target.write_text('{"old": true}\n', encoding="utf-8")

    def failing_dump(obj, fh, **kwargs) -> None:
        fh.write('{"new": ')
        raise TypeError("not serialisable")

    monkeypatch.setattr(json, "dump", failing_dump)
    with pytest.raises(TypeError):
        io.write_json(target, {"new": object()})
    assert [p.name for p in tmp_path.iterdir()] == ["out.json"]
    assert target.read_text(encoding="utf-8") == '{"old": true}\n'


def test_successful_write_replaces_existing_file(tmp_path: Path) -> None:
    target = tmp_path / "t.csv"
    target.write_text("old\n", encoding="utf-8")
    io.write_table(target, ["t", "a"], np.array([[0.0, 1.5]]))
    assert target.read_text(encoding="utf-8") == "t,a\n0,1.5\n"
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]


def test_write_onto_a_directory_is_refused(tmp_path: Path) -> None:
    (tmp_path / "out.csv").mkdir()
    refusal(lambda: io.write_table(tmp_path / "out.csv", ["t"], np.zeros((1, 1))), "out.csv")


# --------------------------------------------------------------------------- increments_from_table


@pytest.mark.parametrize("start", [0.01, 0.02], ids=["equal", "after"])
def test_increments_start_must_precede_first_row(tmp_path: Path, start: float) -> None:
    path = _write(tmp_path / "imu.csv", COMMENTS + INC_HEADER + "\n" + "\n".join(_rows(3, 7)) + "\n")
    table = io.read_table(path, required=io.INCREMENT_COLUMNS)
    refusal(lambda: io.increments_from_table(table, start), f"{path}:4:", "'t'")
    inc = io.increments_from_table(table, 0.0)
    assert np.array_equal(inc.t, [0.0, 0.01, 0.02, 0.03])


# --------------------------------------------------------------------------- rate quadrature


def _polynomials(rng: np.random.Generator) -> list[np.polynomial.Polynomial]:
    """Six polynomials of degree 0..3 (one per IMU column) with random coefficients."""
    degrees = [0, 1, 2, 3, 3, 2]
    return [
        np.polynomial.Polynomial(rng.uniform(-2.0, 2.0, d + 1) + np.eye(d + 1)[-1] * 3.0) for d in degrees
    ]


def _rates_and_exact(t: np.ndarray, polys: list[np.polynomial.Polynomial]) -> tuple[ImuRates, np.ndarray]:
    x = np.column_stack([p(t) for p in polys])
    antiderivatives = [p.integ() for p in polys]
    exact = np.column_stack([a(t[1:]) - a(t[:-1]) for a in antiderivatives])
    return ImuRates(t=t, omega_ib_b=x[:, :3], f_ib_b=x[:, 3:]), exact


def test_to_increments_is_exact_for_cubics_inside() -> None:
    rng = np.random.default_rng(SEED + 3)
    polys = _polynomials(rng)
    t = 2.0 + np.arange(151) * 0.01
    rates, exact = _rates_and_exact(t, polys)
    inc = rates.to_increments()
    assert np.array_equal(inc.t, t)
    got = np.hstack([inc.dtheta_b, inc.dv_b])
    # The 4-point rule integrates cubics exactly; what is left is rounding in the rule and in the
    # reference's difference of antiderivatives (~1e-16 × |antiderivative| / |increment| ≈ 1e-13).
    scale = np.abs(exact).max(axis=0)
    assert (np.abs(got - exact)[1:-1] / scale).max() < 1e-12
    # The two end intervals use the trapezoid rule: for a cubic, trapezoid - integral = h³/12 f''(mid)
    # exactly (the odd cubic term cancels about the midpoint).
    h = 0.01
    for k in (0, len(t) - 2):
        mid = 0.5 * (t[k] + t[k + 1])
        predicted = np.array([h**3 / 12.0 * p.deriv(2)(mid) for p in polys])
        # rtol: rounding (~1e-15) against errors of ~1e-7 where f'' != 0; atol: the reference's
        # difference of antiderivatives of size ~20 rounds to ~4e-15 where f'' = 0.
        np.testing.assert_allclose(got[k] - exact[k], predicted, rtol=1e-7, atol=1e-14)
    # The check is not vacuous: the end errors are far above the interior ones.
    assert np.abs(got[0] - exact[0])[3] > 1e-8


def test_to_increments_uses_trapezoid_where_the_step_changes() -> None:
    rng = np.random.default_rng(SEED + 4)
    polys = _polynomials(rng)
    t = np.concatenate([np.arange(40) * 0.01, 0.39 + np.arange(1, 41) * 0.02])
    rates, exact = _rates_and_exact(t, polys)
    got = np.hstack([rates.to_increments().dtheta_b, rates.to_increments().dv_b])
    dt = np.diff(t)
    x = np.column_stack([p(t) for p in polys])
    trapezoid = 0.5 * (x[:-1] + x[1:]) * dt[:, None]
    scale = np.abs(exact).max(axis=0)
    # Interval k (0-based) uses the cubic rule only when its two neighbours have the same step.
    k = np.arange(len(dt))
    uniform = (k > 0) & (k < len(dt) - 1)
    uniform[1:-1] &= np.isclose(dt[:-2], dt[1:-1], rtol=1e-9) & np.isclose(dt[2:], dt[1:-1], rtol=1e-9)
    assert (~uniform[1:-1]).sum() == 2  # the two intervals around the step change
    assert (np.abs(got - exact)[uniform] / scale).max() < 1e-12  # exact for cubics, as above
    np.testing.assert_allclose(got[~uniform], trapezoid[~uniform], rtol=1e-14, atol=1e-18)  # same formula


@pytest.mark.parametrize(
    "t0",
    [
        0.0,
        1000.0,
        pytest.param(
            86400.0,
        ),
    ],
)
def test_to_increments_fourth_order_at_absolute_times(t0: float) -> None:
    rng = np.random.default_rng(SEED + 5)
    polys = _polynomials(rng)
    t = t0 + np.arange(201) * 0.01  # 100 Hz, time stamps as a logger writes them
    tau = t - t0  # exact (Sterbenz), so the reference is taken over the actual float intervals
    rates_tau, exact = _rates_and_exact(tau, polys)
    rates = ImuRates(t=t, omega_ib_b=rates_tau.omega_ib_b, f_ib_b=rates_tau.f_ib_b)
    inc = rates.to_increments()
    got = np.hstack([inc.dtheta_b, inc.dv_b])
    # The cubic rule on a grid perturbed by time-stamp rounding (1.5e-11 s at 86400 s) errs by ~1e-12
    # relative; the trapezoid rule would err by ~1e-5, so 1e-9 tells them apart.
    scale = np.abs(exact).max(axis=0)
    assert (np.abs(got - exact)[1:-1] / scale).max() < 1e-9


def test_to_increments_needs_two_samples() -> None:
    with pytest.raises(ValueError):
        ImuRates(t=np.array([0.0]), omega_ib_b=np.zeros((1, 3)), f_ib_b=np.zeros((1, 3))).to_increments()
    two = ImuRates(t=np.array([0.0, 0.5]), omega_ib_b=np.ones((2, 3)), f_ib_b=np.full((2, 3), 2.0))
    inc = two.to_increments()
    assert np.array_equal(inc.dtheta_b, np.full((1, 3), 0.5))
    assert np.array_equal(inc.dv_b, np.full((1, 3), 1.0))


def test_a_killed_writers_temporary_file_is_removed_by_the_next_write(tmp_path: Path) -> None:
    """A SIGKILL leaves ``.NAME.PID.XXXX.tmp`` beside the output (full size, hidden). The next write of
    the same file removes it once its process no longer runs and it has not been written for
    ``STALE_S``; a live writer's file, a recent one and a file of another name are left alone."""
    import subprocess
    import time

    from sins.io import atomic

    dead = subprocess.Popen(["true"])
    dead.wait()  # a process id that no process has now
    path = tmp_path / "t.csv"
    old = time.time() - 2 * atomic.STALE_S
    files = {
        "killed": tmp_path / f".t.csv.{dead.pid}.abc123.tmp",
        "recent": tmp_path / f".t.csv.{dead.pid}.def456.tmp",
        "alive": tmp_path / f".t.csv.{os.getpid()}.ghi789.tmp",
        "other": tmp_path / f".u.csv.{dead.pid}.jkl012.tmp",
    }
    for name, f in files.items():
        f.write_text("x")
        if name != "recent":
            os.utime(f, (old, old))
    io.write_table(path, ["t"], np.array([[0.0], [1.0]]))
    assert {n for n, f in files.items() if f.exists()} == {"recent", "alive", "other"}
    assert io.read_table(path).data.shape == (2, 1)


def test_written_files_get_the_permissions_open_would_give_not_a_temporary_files(tmp_path: Path) -> None:
    """Written through a temporary file (owner-only by default), the result has 0o666 less the umask,
    as a plain ``open`` gives: a baseline or a recording is readable by the group as any other file; a
    file replaced keeps its mode, and a read-only one is refused."""
    umask = os.umask(0o022)
    os.umask(umask)
    path = tmp_path / "t.csv"
    io.write_table(path, ["t"], np.zeros((2, 1)))
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]
    # A file replaced keeps its own permissions: a private one stays private (it became 0644 before).
    path.chmod(0o600)
    io.write_table(path, ["t"], np.array([[1.0], [2.0]]))
    assert path.stat().st_mode & 0o777 == 0o600 and io.read_table(path).data[0, 0] == 1.0
    # One marked read-only is not replaced (a rename needs only the folder's permission): refused.
    path.chmod(0o444)
    refusal(lambda: io.write_table(path, ["t"], np.zeros((2, 1))), str(path), "is read-only (mode 0444)")
    assert path.stat().st_mode & 0o777 == 0o444 and io.read_table(path).data[0, 0] == 1.0
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]
