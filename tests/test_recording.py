"""Rig recordings (calibration data in rate form with reference columns): round trips, refusals, split."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import refusal
from hypothesis import given, settings
from hypothesis import strategies as st

from sins import io
from sins.core.series import CalibrationData, RigPhase
from sins.io import tables
from sins.io.rig import _read_rig

SEED = 20240917

#: The format's own reader: these round trips carry floats (1e300) beyond any sensor, which
#: ``sins.io.read`` refuses as a recording (``check_recording_range``); the format itself keeps them.
read_rig = _read_rig

FIELDS = ("t", "gyro", "accel", "ref_gyro", "ref_accel")


# --------------------------------------------------------------------------- helpers


def _random_recording(rng: np.random.Generator, n: int = 400) -> CalibrationData:
    """Random readings and references with awkward floats, NaN reference rows, temp and phases."""
    t = 1e3 + np.cumsum(rng.uniform(1e-4, 0.02, n))
    gyro = rng.normal(0.0, 2.0, (n, 3))
    accel = rng.normal(0.0, 10.0, (n, 3))
    # Floats that a careless writer or parser would not bring back bit for bit.
    gyro[0] = [-0.0, 5e-324, np.nextafter(1.0, 2.0)]
    accel[0] = [1e300, -2.2250738585072014e-308, 0.1]
    ref_gyro = rng.normal(0.0, 2.0, (n, 3))
    ref_accel = rng.normal(0.0, 10.0, (n, 3))
    ref_gyro[100:150] = np.nan  # a hand rotation: no per-sample reference
    ref_accel[100:150] = np.nan
    ref_accel[7, 1] = np.nan  # a single missing cell
    phases = (
        RigPhase("static +x up", 10, 60, "static"),
        RigPhase("rate +z 100 dps; fast", 60, 100, "rotation"),
        RigPhase('hand turn 100% "x"', 100, 150, "rotation", (-2.0 * math.pi, 1e-17, -0.0)),
        RigPhase("  °/s\tweird = name\n", 200, 260, "static"),
        RigPhase("", 300, 301, "rotation", (0.1, 0.2, 0.30000000000000004)),
        RigPhase("last", 301, n, "static"),
    )
    return CalibrationData(
        t=t,
        gyro=gyro,
        accel=accel,
        ref_gyro=ref_gyro,
        ref_accel=ref_accel,
        temp=rng.normal(25.0, 5.0, n),
        phases=phases,
        source="random",
    )


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def _assert_same(back: CalibrationData, data: CalibrationData) -> None:
    for name in FIELDS:
        assert np.array_equal(_bits(getattr(back, name)), _bits(getattr(data, name))), name
    if data.temp is None:
        assert back.temp is None
    else:
        assert back.temp is not None and np.array_equal(_bits(back.temp), _bits(data.temp))
    assert back.phases == data.phases
    assert repr(back.phases) == repr(data.phases)  # == misses the sign of -0.0 in angle_rad


HEADER = ",".join((*io.RECORDING_COLUMNS, "temp", "phase"))


def _row(k: int, phase: str = "0") -> list[str]:
    t = f"{0.01 * (k + 1):.2f}"
    return [t, *[f"{0.001 * (k + j):g}" for j in range(12)], "21.5", phase]


def _save(path: Path, rows: list[list[str]], comments: tuple[str, ...] = (), header: str = HEADER) -> Path:
    lines = [*comments, header, *(",".join(r) for r in rows)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _rows(phases: list[str]) -> list[list[str]]:
    return [_row(k, p) for k, p in enumerate(phases)]


# --------------------------------------------------------------------------- round trips


def test_round_trip_is_exact(tmp_path: Path) -> None:
    data = _random_recording(np.random.default_rng(SEED))
    path = tmp_path / "rig.csv"
    io.write_recording(path, data, comment="session 7\nphase labels below")
    back = read_rig(path)
    _assert_same(back, data)
    assert back.source == str(path)
    text = path.read_text(encoding="utf-8").splitlines()
    # The documented comment form, after the free comment; the header then has temp and phase.
    assert text[0] == "# session 7"
    assert text[3] == "# phase 1: name=rate +z 100 dps%3B fast; kind=rotation"
    assert text[4] == ("# phase 2: name=hand turn 100%25 %22x%22; kind=rotation; "
                       "angle_rad=-6.283185307179586,1e-17,-0.0")  # fmt: skip
    assert text[8] == HEADER


def test_round_trip_without_phases_or_temp(tmp_path: Path) -> None:
    rng = np.random.default_rng(SEED + 1)
    full = _random_recording(rng, n=50)
    data = CalibrationData(full.t, full.gyro, full.accel, full.ref_gyro, full.ref_accel)
    path = tmp_path / "plain.csv"
    io.write_recording(path, data)
    assert path.read_text().splitlines()[0] == ",".join(io.RECORDING_COLUMNS)
    back = read_rig(path)
    _assert_same(back, data)
    assert back.temp is None and back.phases == ()


def test_written_recording_takes_the_fast_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The phase lines, whatever the names, leave the file to pyarrow (the slow parser is for odd files)."""
    data = _random_recording(np.random.default_rng(SEED + 2))
    path = tmp_path / "rig.csv"
    io.write_recording(path, data)

    def no_slow(*args: object) -> None:
        raise AssertionError("fell back to the slow parser")

    monkeypatch.setattr(tables, "_read_slow", no_slow)
    _assert_same(read_rig(path), data)


@settings(max_examples=60, deadline=None)
@given(name=st.text(max_size=24), kind=st.sampled_from(io.PHASE_KINDS))
def test_any_phase_name_survives(tmp_path_factory: pytest.TempPathFactory, name: str, kind: str) -> None:
    path = tmp_path_factory.mktemp("names") / "rig.csv"
    z = np.zeros((3, 3))
    data = CalibrationData(np.array([0.0, 0.1, 0.2]), z, z, z, z, phases=(RigPhase(name, 1, 3, kind),))
    io.write_recording(path, data)
    assert read_rig(path).phases == data.phases


def test_writer_refuses_what_could_not_be_read_back(tmp_path: Path) -> None:
    data = _random_recording(np.random.default_rng(SEED + 3))
    path = tmp_path / "rig.csv"
    bad_gyro = data.gyro.copy()
    bad_gyro[3, 1] = np.nan
    arrays = (data.t, data.gyro, data.accel, data.ref_gyro, data.ref_accel)
    overlapping = (RigPhase("a", 5, 9, "static"), RigPhase("b", 2, 4, "static"))
    cases = [
        (CalibrationData(data.t, bad_gyro, *arrays[2:]), "gyro"),
        (CalibrationData(data.t[::-1], *arrays[1:]), "increase"),
        (CalibrationData(*arrays, phases=overlapping), "time order"),
        (CalibrationData(*arrays, phases=(RigPhase("a", 5, 5, "static"),)), "empty"),
        (CalibrationData(*arrays, phases=(RigPhase("a", 5, 9, "spin"),)), "kind"),
    ]
    for bad, fragment in cases:
        with pytest.raises(ValueError, match=fragment):
            io.write_recording(path, bad)
    with pytest.raises(ValueError, match="phase directive"):
        io.write_recording(path, data, comment="notes\nphase 2: the slow one")
    # A gyro of 5 rows beside 400 times is refused where it is made, before any writer sees it.
    with pytest.raises(ValueError, match=r"CalibrationData\.gyro: expected shape \(400, 3\) for 400 rows"):
        CalibrationData(data.t, data.gyro[:5], *arrays[2:])
    assert not path.exists()


# --------------------------------------------------------------------------- files from other tools


def test_recording_from_another_tool(tmp_path: Path) -> None:
    """Another column order, CRLF, a text column and a numeric one with NaN (both ignored), no phases."""
    columns = ["label", "ref_accel_z", "accel_x", "t", "gyro_z", "ref_gyro_x", "ref_gyro_y", "gyro_x",
               "board_temp", "accel_y", "ref_accel_x", "ref_gyro_z", "accel_z", "gyro_y",
               "ref_accel_y"]  # fmt: skip
    rng = np.random.default_rng(SEED + 4)
    values = {c: rng.normal(0.0, 3.0, 5).round(6) for c in columns if c != "label"}
    values["t"] = np.array([0.5, 0.51, 0.52, 0.53, 0.54])
    values["board_temp"][2] = np.nan
    values["ref_gyro_y"][1] = np.nan
    lines = ["# exported by rigtool 2.1", ",".join(columns)]
    for k in range(5):
        lines.append(",".join("hold x up" if c == "label" else repr(float(values[c][k])) for c in columns))
    path = tmp_path / "other.csv"
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode("utf-8"))
    back = read_rig(path)
    assert np.array_equal(back.t, values["t"])
    for name in ("gyro", "accel", "ref_gyro", "ref_accel"):
        expected = np.column_stack([values[f"{name}_{a}"] for a in "xyz"])
        assert np.array_equal(getattr(back, name), expected, equal_nan=True), name
    assert back.temp is None and back.phases == ()


def test_phases_without_comment_lines_get_default_names_and_kinds(tmp_path: Path) -> None:
    rows = _rows(["-1", "0", "0", "1", "1", "2", "2", "3"])
    for k in (3, 4):  # phase 1 turns about z at 1 rad/s
        rows[k][9] = "1.0"
    for k in (1, 2):  # phase 0 at rest, reference including Earth's rate
        rows[k][7:10] = ["7.2e-5", "0", "0"]
    for k in (5, 6):  # phase 2 has no reference rate
        rows[k][7:10] = ["nan", "nan", "nan"]
    rows[7][7:10] = ["0", "0", "0"]
    path = _save(tmp_path / "rig.csv", rows, comments=("# phase 3: name=  spaced  ",))
    back = read_rig(path)
    assert back.phases == (
        RigPhase("phase 0", 1, 3, "static"),
        RigPhase("phase 1", 3, 5, "rotation"),
        RigPhase("phase 2", 5, 7, "rotation"),
        RigPhase("spaced", 7, 8, "static"),
    )


# --------------------------------------------------------------------------- refusals


def test_refusals_name_file_line_and_column(tmp_path: Path) -> None:
    phases = ["0", "0", "0", "1", "1", "-1"]
    comment = ("# phase 0: name=hold; kind=static",)
    # The header is on line 2 and data row k on line 3 + k.

    path = _save(tmp_path / "ok.csv", _rows(phases), comment)
    assert len(read_rig(path)) == 6

    header = HEADER.replace(",ref_accel_y", "")
    rows = [r[:11] + r[12:] for r in _rows(phases)]
    path = _save(tmp_path / "noref.csv", rows, comment, header=header)
    refusal(lambda: io.read(path).rig, f"{path}:2:", "'ref_accel_y'", "needs reference columns")

    def broken(name: str, row: int, column: int, value: str) -> Path:
        rows = _rows(phases)
        rows[row][column] = value
        return _save(tmp_path / f"{name}.csv", rows, comment)

    cases = [
        (broken("nan_gyro", 2, 2, "nan"), "5", "'gyro_y'", "non-finite"),
        (broken("inf_temp", 4, 13, "inf"), "7", "'temp'", "inf"),
        (broken("inf_ref", 1, 7, "-inf"), "4", "'ref_gyro_x'", "-inf"),
        (broken("time", 3, 0, "0.01"), "6", "'t'", "does not increase"),
        (broken("gap", 4, 14, "0"), "7", "'phase'", "contiguous"),
        (broken("frac", 1, 14, "0.5"), "4", "'phase'", "not a phase index"),
        (broken("neg", 5, 14, "-2"), "8", "'phase'", "not a phase index"),
        (broken("nan_phase", 0, 14, "nan"), "3", "'phase'", "non-finite"),
        (broken("text", 3, 5, "1,5"), "6", "expected 15 values"),
    ]
    for bad, line, *fragments in cases:
        refusal(lambda bad=bad: io.read(bad).rig, f"{bad}:{line}:", *map(str, fragments))


def test_refuses_bad_phase_lines(tmp_path: Path) -> None:
    rows = _rows(["0", "0", "1"])
    cases = [
        (("# phase 0: colour=red",), "1", "name, kind, angle_rad"),
        (("# phase 0: name=a; name=b",), "1", "twice"),
        (("# phase 0: kind=spin",), "1", "'spin'"),
        (("# phase 1: angle_rad=1,2",), "1", "three"),
        (("# phase 1: angle_rad=1,nan,2",), "1", "not finite"),
        (("# phase 0: name=%FF",), "1", "%-escape"),
        (("# ok", "# phase 0: name=a", "# phase 0: name=b"), "3", "twice"),
        (("# phase 0: name=a", "# phase 5: name=b"), "2", "no rows"),
    ]
    for k, (comments, line, fragment) in enumerate(cases):
        path = _save(tmp_path / f"bad{k}.csv", rows, comments)
        refusal(lambda path=path: io.read(path).rig, f"{path}:{line}:", fragment)
    header = HEADER.removesuffix(",phase")
    path = _save(tmp_path / "nocol.csv", [r[:-1] for r in rows], ("# x", "# phase 0: name=a"), header=header)
    refusal(lambda: io.read(path).rig, f"{path}:2:", "no 'phase' column")


def test_refuses_increment_form(tmp_path: Path) -> None:
    header = HEADER.replace("gyro_", "dtheta_").replace("accel_", "dv_").replace("ref_dtheta", "ref_gyro")
    header = header.replace("ref_dv", "ref_accel")
    path = _save(tmp_path / "inc.csv", _rows(["0"]), header=header)
    refusal(lambda: io.read(path).rig, f"{path}:1:", "rate form")


# --------------------------------------------------------------------------- fit / validation split


def _read_back(tmp_path: Path, data: CalibrationData) -> CalibrationData:
    path = tmp_path / "rig.csv"
    io.write_recording(path, data)
    return read_rig(path)


def _held(fraction: float, length: int) -> int:
    """Rows held back from a phase: the fraction rounded half up, at least one, and never all."""
    return min(max(int(np.floor(fraction * length + 0.5)), 1), length - 1) if length > 1 else 0


def test_split_by_phase(tmp_path: Path) -> None:
    rec = _read_back(tmp_path, _random_recording(np.random.default_rng(SEED + 5)))
    validation = 0.25
    fit, val = rec.split(validation)
    # t is increasing, so it names the rows: disjoint, covering, each portion in time order.
    assert np.intersect1d(fit.t, val.t).size == 0
    assert np.array_equal(np.sort(np.concatenate([fit.t, val.t])), rec.t)
    assert np.all(np.diff(fit.t) > 0) and np.all(np.diff(val.t) > 0)
    in_phase = np.zeros(len(rec), dtype=bool)
    for p in rec.phases:
        in_phase[p.start : p.stop] = True
        held = _held(validation, p.stop - p.start)
        cut = p.stop - held
        # The last `held` rows of the phase, contiguous in each portion and re-indexed there.
        for part, lo, hi in ((fit, p.start, cut), (val, cut, p.stop)):
            mine = [q for q in part.phases if q.name == p.name]
            if hi == lo:
                assert not mine
                continue
            (q,) = mine
            assert q.kind == p.kind
            assert np.array_equal(part.t[q.start : q.stop], rec.t[lo:hi])
            assert np.array_equal(part.gyro[q.start : q.stop], rec.gyro[lo:hi])
            assert q.angle_rad == (p.angle_rad if hi - lo == p.stop - p.start else None)
    # Rows outside every phase are all fitted.
    assert np.isin(rec.t[~in_phase], fit.t).all()
    assert len(val) == sum(_held(validation, p.stop - p.start) for p in rec.phases)


def test_split_whole_recording_and_too_short(tmp_path: Path) -> None:
    rec = _read_back(tmp_path, _random_recording(np.random.default_rng(SEED + 6)))
    fit, val = rec.split(0.2, by_phase=False)
    assert np.array_equal(fit.t, rec.t[:320]) and np.array_equal(val.t, rec.t[320:])
    one = _read_back(tmp_path, rec.rows(slice(0, 1)))
    with pytest.raises(ValueError, match="too short"):
        one.split(0.2)
    z = np.zeros((4, 3))
    pairs = (RigPhase("a", 0, 2, "static"), RigPhase("b", 2, 4, "static"))
    fit2, val2 = _read_back(tmp_path, CalibrationData(np.arange(4.0), z, z, z, z, phases=pairs)).split(0.2)
    assert list(fit2.t) == [0.0, 2.0] and list(val2.t) == [1.0, 3.0]  # a two-row phase gives one row each way
    singles = tuple(RigPhase(name, i, i + 1, "static") for i, name in enumerate("abcd"))
    with pytest.raises(ValueError, match="too short"):
        _read_back(tmp_path, CalibrationData(np.arange(4.0), z, z, z, z, phases=singles)).split(0.2)


def _phase_less(pieces: list[tuple[float, np.ndarray, np.ndarray]], rate_hz: float) -> CalibrationData:
    """A recording without phases from ``(seconds, ref_gyro (3,) or (n, 3), ref_accel ...)`` pieces."""
    gyro, accel = [], []
    for seconds, w, f in pieces:
        n = round(seconds * rate_hz)
        gyro.append(np.broadcast_to(w, (n, 3)))
        accel.append(np.broadcast_to(f, (n, 3)))
    g, a = np.vstack(gyro), np.vstack(accel)
    return CalibrationData(np.arange(len(g)) / rate_hz, g, a, g, a)


def test_a_recording_without_phases_is_withheld_in_stretches_of_like_input() -> None:
    """Holds, constant table rates and turns between them are each a stretch; the end of each is withheld,
    so a table rate met once, late in the recording (issue 19's clipped gyro), is fitted as well as
    judged. Transitions are their own stretches, a rate stepped within a row too (a row that starts the
    new level and is fitted, as the first row of a phase is): joined to the level before, it would lie
    in that stretch's withheld end, and no fitted row would see the input change."""
    rate_hz, up = 100.0, np.array([0.0, 0.0, -9.80665])
    ramp = np.linspace(0.0, 1.0, 200)[:, None]
    turn = ramp * np.array([0.0, 9.80665, 0.0]) + up * (1.0 - 0.1 * ramp)  # the force turning, 2 s
    pieces = [(30.0, np.zeros(3), up), (2.0, np.array([0.3, 0.0, 0.0]), turn)]
    pieces += [(10.0, np.array([0.0, 0.0, r]), up) for r in (0.5, 1.0, 2.0, 4.4)]
    data = _phase_less(pieces, rate_hz)
    stretches = data.stretches()
    # The turn ends with the row where the reference leaves it (the first of the next piece, moving
    # too); each step between table rates is a stretch of one row.
    seconds = [(b - a) / rate_hz for a, b in stretches]
    expected = [30.0, 2.0, 10.0, 0.01, 10.0, 0.01, 10.0, 0.01, 10.0]
    assert seconds == pytest.approx(expected, abs=0.011), seconds
    held = data.held_back(0.3, like_input=True)
    top = np.abs(data.ref_gyro[:, 2] - 4.4) < 1e-12
    assert held[top].mean() == pytest.approx(0.3, abs=0.002) and (~held[top]).any()
    assert held[-1] and not held[0]
    # Without like_input, the whole tail: the top rate is withheld entirely, as before.
    assert data.held_back(0.3)[top].all()


def test_continuous_motion_is_withheld_in_interleaved_blocks_and_flicker_is_merged() -> None:
    rng = np.random.default_rng(SEED + 9)
    rate_hz, n = 50.0, 50 * 300
    w = np.column_stack([np.sin(np.arange(n) / 300.0), np.zeros(n), np.zeros(n)])
    moving = CalibrationData(np.arange(n) / rate_hz, w, w, w, w)
    lengths = [b - a for a, b in moving.stretches()]
    assert len(lengths) == 5 and max(lengths) <= 60 * rate_hz and sum(lengths) == n
    # A static reference whose rows flicker past the steady threshold now and then (one row in 500)
    # stays one stretch: a flicker is too short to be a stretch of its own, and returns to the level.
    f = np.tile([0.0, 0.0, -9.8], (n, 1)) + (rng.random((n, 1)) < 0.002) * 1e-3
    still = CalibrationData(np.arange(n) / rate_hz, f, f, np.zeros((n, 3)), f)
    assert [b - a for a, b in still.stretches(longest_s=1e9)] == [n]
