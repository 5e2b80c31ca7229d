"""``sins.compensation.outages``: free-inertial outages from every second of a referenced recording,
against closed forms on a unit written with numpy alone, and against an independent navigation (numpy
and scipy's ``Rotation``, ``tools/broad_free_inertial.py``) on a real recording.

Closed forms (a unit at rest and level at 45° N, body axes along north, east, down, reading exactly
Earth's rate and the plumb line's specific force; the vertical held): nothing is left by its own
readings; an accelerometer bias ``b`` along north leaves ``b T²/2``; a gyro bias ``ω`` about north rolls
the unit and tips gravity's specific force into east, ``g ω T³/6``."""

from __future__ import annotations

import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from sins.compensation import outages
from sins.core import earth
from sins.core.series import ImuIncrements, NavSeries, ReferencedRecording
from sins.errors import SinsInputError
from tests.conftest import dataset_folder

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))

LAT = np.radians(45.0)
DT_S = 0.005
G_M_S2 = 9.8  # the plumb line's size here is not judged: the vertical is held


def _at_rest(seconds: float, accel_bias: float = 0.0, gyro_bias: float = 0.0) -> ReferencedRecording:
    """The unit at rest (see the module docstring), its accelerometer reading ``accel_bias`` (m/s²) more
    along north and its gyro ``gyro_bias`` (rad/s) more about north; its reference at every reading."""
    t = DT_S * np.arange(round(seconds / DT_S) + 1)
    n = len(t) - 1
    w_ie = earth.OMEGA_IE * np.array([np.cos(LAT), 0.0, -np.sin(LAT)])
    dtheta = np.tile((w_ie + np.array([gyro_bias, 0.0, 0.0])) * DT_S, (n, 1))
    dv = np.tile(np.array([accel_bias, 0.0, -G_M_S2]) * DT_S, (n, 1))
    m = len(t)
    reference = NavSeries(
        t=t, lat=np.full(m, LAT), lon=np.zeros(m), h=np.zeros(m), v_n=np.zeros((m, 3)),
        q_nb=np.tile([0.0, 0.0, 0.0, 1.0], (m, 1)),
    )  # fmt: skip
    return ReferencedRecording(imu=ImuIncrements(t=t, dtheta_b=dtheta, dv_b=dv), reference=reference,
                               source="numpy unit")  # fmt: skip


def test_a_units_own_readings_leave_nothing_and_every_second_starts_one() -> None:
    """12 s at rest: outages of 2 s start at 0, 1, …, 10 s (11 of them), and each ends where it began,
    to a micrometre (the Earth rate's second-order terms)."""
    rec = _at_rest(12.0)
    out = outages.outages(rec.imu, rec, 2.0)
    np.testing.assert_allclose(out.start_s, np.arange(11.0), atol=1e-12)
    assert out.summary()["outages"] == 11
    assert np.all(out.horizontal_m < 1e-6), out.horizontal_m


@pytest.mark.parametrize("length_s", [2.0, 5.0])
def test_an_accelerometer_bias_leaves_its_double_integral(length_s: float) -> None:
    """``b = 0.01 m/s²`` along north: ``b T²/2`` at every outage's end, to 0.1 % (Coriolis on the
    velocity error turns it by ``2 Ω sin φ T/3``, 1e-4 of it); the summary's RMS, median and 95th
    percentile are that one figure."""
    bias = 0.01
    rec = _at_rest(12.0, accel_bias=bias)
    summary = outages.outages(rec.imu, rec, length_s).summary()
    want = 0.5 * bias * length_s**2
    for key in ("rms_m", "median_m", "p95_m"):
        assert summary[key] == pytest.approx(want, rel=1e-3), (key, summary)


def test_a_gyro_bias_leaves_gravity_tipped_into_the_horizontal() -> None:
    """``ω = 1 mrad/s`` about north over 5 s: a roll of ``ω t`` tips the plumb line's specific force into
    east, ``g ω T³/6`` at the end (204 mm), to 1 % (the roll's sine, and the ``b T²/2``-free start)."""
    omega = 1e-3
    rec = _at_rest(8.0, gyro_bias=omega)
    out = outages.outages(rec.imu, rec, 5.0)
    want = G_M_S2 * omega * 5.0**3 / 6.0
    np.testing.assert_allclose(out.horizontal_m, want, rtol=1e-2)


def test_a_bad_length_is_one_line_naming_the_recording() -> None:
    """Not positive, or longer than the reference: refused, naming the recording."""
    rec = _at_rest(3.0)
    for length, said in ((0.0, "give a positive number"), (np.nan, "give a positive number"),
                         (5.0, "does not fit within the reference's 3 s")):  # fmt: skip
        with pytest.raises(SinsInputError, match=said) as refused:
            outages.outages(rec.imu, rec, length)
        assert "numpy unit" in str(refused.value) and "\n" not in str(refused.value)


def test_a_reference_whose_positions_do_not_follow_its_velocities_is_refused() -> None:
    """Outages are judged by position: a reference moving 0.5 m/s north whose positions stay put (a file
    written without positions) is refused, one line naming it; the same with its positions moving is
    judged, and how far its positions are from its velocities' integral is given beside."""
    rec = _at_rest(6.0)
    ref = rec.reference
    moving = replace(ref, v_n=np.tile([0.5, 0.0, 0.0], (len(ref.t), 1)))
    with pytest.raises(SinsInputError, match="positions do not follow its velocities") as refused:
        outages.outages(rec.imu, replace(rec, reference=moving), 2.0)
    assert "numpy unit" in str(refused.value) and "\n" not in str(refused.value)
    r_m, _ = earth.radii(LAT)
    placed = replace(moving, lat=LAT + 0.5 * ref.t / r_m)
    summary = outages.outages(rec.imu, replace(rec, reference=placed), 2.0).summary()
    assert summary["outages"] == 5 and summary["reference_mismatch_m"] < 1e-6, summary
    # Positions 2 % ahead of the velocities (a reference of its own making): judged, and the 2 cm by
    # which the reference itself disagrees over each 2 s outage said beside the figures.
    ahead = replace(moving, lat=LAT + 0.51 * ref.t / r_m)
    summary = outages.outages(rec.imu, replace(rec, reference=ahead), 2.0).summary()
    assert summary["reference_mismatch_m"] == pytest.approx(0.02, rel=1e-3), summary


def test_sins_outages_match_an_independent_navigation_on_a_real_recording() -> None:
    """BROAD's unit B (trial 05's middle third, as ``tools/another_unit.py`` cuts it; its reference's
    position the integral of its velocity, as the tool's; as the tool writes it, with none, it is
    refused), raw readings: every 2 s outage's horizontal
    error is the tool's (numpy and scipy alone, gravity 9.81 m/s², no Earth rate) within 2 mm of the
    RMS's 116 mm (1.1 mm seen), and the 5 s outages' RMS within 1.5 % of 1.18 m (0.7 % seen: sins's
    Earth rate at the nominal 45° N, which the tool leaves out, ``g Ω T³/6`` ≈ 9 mm)."""
    if not (dataset_folder("broad_mocap")).is_dir():
        pytest.skip(f"no BROAD data at {dataset_folder('broad_mocap')}")
    from another_unit import write_parts
    from broad_free_inertial import window_errors

    from sins import io

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write_parts(io.read(dataset="broad_05").beside_reference(), "05", 3, folder)
        part = dict(np.load(folder / "05_2.npz"))
        part["p_m"] = cumulative_trapezoid(part["v_m_s"], part["t_s"], axis=0, initial=0.0)
        np.savez(folder / "p.npz", **part)
        rec = io.read(str(folder / "p.npz")).beside_reference()
        unplaced = io.read(str(folder / "05_2.npz")).beside_reference()  # the part as written: no positions
    with pytest.raises(SinsInputError, match="positions do not follow its velocities"):
        outages.outages(unplaced.imu, unplaced, 2.0)
    for length, check in ((2.0, "each"), (5.0, "rms")):
        theirs = window_errors(rec.imu, part, length, 1.0)  # from 1 s in, every second
        ours = outages.outages(rec.imu, rec, length)
        assert ours.start_s[1] == pytest.approx(1.0, abs=DT_S)
        mine = ours.horizontal_m[1 : 1 + len(theirs)]
        assert len(mine) == len(theirs) > 50
        if check == "each":
            assert np.max(np.abs(mine - theirs)) < 2e-3, np.abs(mine - theirs).max()
        else:
            rms = lambda x: float(np.sqrt(np.mean(x * x)))  # noqa: E731
            assert rms(mine) == pytest.approx(rms(theirs), rel=0.015), (rms(mine), rms(theirs))
