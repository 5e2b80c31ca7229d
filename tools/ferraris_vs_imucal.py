"""sins's Ferraris calibration beside imucal's, and what it does to the two imucal sessions.

    .venv/bin/python tools/ferraris_vs_imucal.py

Prints (markdown, for docs/validation.md and the compensation guide):

1. every gain, misalignment and bias of imucal's ``FerrarisCalibration`` of the annotated session
   (``annotated_session.csv``, run here at sins's g and the session's +360° turns) beside sins's
   ``Ferraris`` fit of the same rows, with sins's standard error of each;
2. imucal's stored snapshot (``example_cal_snapshot.json``: g = 9.81, −360°) against imucal run here
   and against sins, through the mapping the g and the turn's sign imply;
3. per session (``ferraris``: the example, 102.4 Hz, physical units; ``ferraris_annotated``), before and
   after: |f| − g and the gyro at rest in each hold, each turn's integrated angle, and the motions
   between holds (the gravity direction carried by the corrected gyro from one hold to the next).

Needs imucal (the test extra) and the data in ../shared/data/imucal_ferraris (or SINS_DATA).
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import importlib.metadata
import json
import math
import sys

import numpy as np
import pandas as pd
from imucal import FerrarisCalibration, ferraris_regions_from_df

from sins import compensation, io
from sins.compensation.base import NoCompensation, Strategy
from sins.compensation.ferraris import Ferraris, ImucalCalibration, check_session, compare_with_imucal
from sins.core.series import CalibrationData
from sins.errors import SinsInputError
from sins.io import datasets
from sins.io.datasets import ferraris as reader

UNITS = {
    "accel_unit_mps2": reader.ANNOTATED_ACCEL_MPS2_PER_COUNT,
    "gyro_unit_dps": reader.ANNOTATED_GYRO_DPS_PER_COUNT,
}
PARAMS = ("K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g")
UNIT_TEXT = {
    "K_a": "counts/(m/s²)", "R_a": "1", "b_a": "counts", "K_g": "counts/(°/s)", "R_g": "1",
    "K_ga": "counts/(m/s²)", "b_g": "counts",
}  # fmt: skip


def imucal_run(grav: float, angle_deg: float) -> ImucalCalibration:
    """imucal's Ferraris calibration of the annotated session, read as imucal's own test reads it."""
    path = datasets.data_root() / reader.FERRARIS_FOLDER / "annotated_session.csv"
    frame = pd.read_csv(path, header=0, index_col=0)
    info = FerrarisCalibration(grav=grav, expected_angle=angle_deg).compute(
        ferraris_regions_from_df(frame),
        sampling_rate_hz=reader.ANNOTATED_RATE_HZ,
        from_acc_unit="a.u.",
        from_gyr_unit="a.u.",
    )
    return ImucalCalibration(**{p: np.asarray(getattr(info, p), dtype=float) for p in PARAMS})


def snapshot() -> ImucalCalibration:
    path = datasets.data_root() / reader.FERRARIS_FOLDER / "example_cal_snapshot.json"
    doc = json.loads(path.read_text(encoding="utf-8"))
    return ImucalCalibration(**{p: np.asarray(doc[p], dtype=float) for p in PARAMS})


def as_snapshot(cal: ImucalCalibration, g: float) -> ImucalCalibration:
    """A calibration at g and +360° as imucal's defaults (g = 9.81, −360°) would give it: the gains per
    m/s² scale by g/9.81 (the holds' difference is divided by 2·9.81 instead of 2g), R_g changes sign."""
    return ImucalCalibration(
        K_a=cal.K_a * g / 9.81, R_a=cal.R_a, b_a=cal.b_a, K_g=cal.K_g, R_g=-cal.R_g,
        K_ga=cal.K_ga * g / 9.81, b_g=cal.b_g,
    )  # fmt: skip


def fmt(x: float, digits: int = 6) -> str:
    return "—" if not np.isfinite(x) else f"{x:.{digits}g}"


def comparison_table(fitted: Ferraris, reference: ImucalCalibration) -> None:
    print("| parameter | entry | imucal | sins | sins − imucal | sins se | \\|Δ\\|/se |")
    print("|---|---|---|---|---|---|---|")
    for row in compare_with_imucal(fitted, reference, **UNITS):
        delta = row.sins - row.reference
        ratio = abs(delta) / row.se if np.isfinite(row.se) and row.se > 0 else float("nan")
        entry = ",".join(str(i + 1) for i in row.entry)
        print(
            f"| {row.parameter} ({UNIT_TEXT[row.parameter]}) | {entry} | {fmt(row.reference)} "
            f"| {fmt(row.sins)} | {delta:.1e} | {fmt(row.se, 3)} | {fmt(ratio, 2)} |"
        )


def worst(fitted: Ferraris, reference: ImucalCalibration) -> str:
    rows = compare_with_imucal(fitted, reference, **UNITS)
    ratio = max(abs(r.sins - r.reference) / r.se for r in rows if np.isfinite(r.se))
    rel = max(abs(r.sins - r.reference) / abs(r.reference) for r in rows if r.reference != 0)
    return f"largest |Δ|/se {ratio:.3g}, largest relative difference {rel:.2g}"


def bias_only(fitted: Ferraris) -> Ferraris:
    """The fit's biases alone (what a user who only removes the holds' offsets gets)."""
    out = copy.copy(fitted)
    out.A_, out.B_, out.K_ = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
    return out


def session_table(name: str, data: CalibrationData) -> None:
    fitted = Ferraris().fit(data)
    lsq = compensation.make("regression", g_sensitivity=False).fit(data)
    rows: list[tuple[str, Strategy]] = [
        ("none (raw readings)", NoCompensation()),
        ("bias only (the holds' offsets)", bias_only(fitted)),
        ("regression (least squares, K off)", lsq),
        ("ferraris", fitted),
    ]
    checks = [(label, check_session(s, data)) for label, s in rows]
    first = checks[0][1]
    print(f"\n#### {name}: {len(data)} rows, {data.source}\n")
    holds = " | ".join(h.name for h in first.holds)
    print(f"|f| − g per hold, mm/s² (and max |gyro| at rest, °/s)\n\n| correction | {holds} | gyro at rest |")
    print("|---|" + "---|" * (len(first.holds) + 1))
    for label, c in checks:
        f = " | ".join(f"{1e3 * h.force_error_mps2:+.1f}" for h in c.holds)
        rest = max(float(np.abs(np.degrees(h.rate_radps)).max()) for h in c.holds)
        print(f"| {label} | {f} | {rest:.4f} |")
    print("\nEach turn's integrated angle about its own axis and off it, deg\n")
    print("| correction | " + " | ".join(t.name for t in first.turns) + " |")
    print("|---|" + "---|" * len(first.turns))
    for label, c in checks:
        cells = []
        for k, t in enumerate(c.turns):
            deg = np.degrees(t.angle_rad)
            cells.append(f"{deg[k]:.2f} ({np.linalg.norm(np.delete(deg, k)):.2f})")
        print(f"| {label} | " + " | ".join(cells) + " |")
    if not first.transitions:
        print("\n(no motions between holds in this file)")
        return
    print("\nThe motions between holds: the first hold's gravity carried by the corrected gyro, error, deg\n")
    head = " | ".join(
        f"{t.start}→{t.end} ({t.seconds:.1f} s, {math.degrees(t.turned_rad):.0f}°)" for t in first.transitions
    )
    print(f"| correction | {head} | RMS |")
    print("|---|" + "---|" * (len(first.transitions) + 1))
    for label, c in checks:
        errs = np.degrees([t.error_rad for t in c.transitions])
        cells = " | ".join(f"{e:.2f}" for e in errs)
        print(f"| {label} | {cells} | {math.sqrt(float(np.mean(errs**2))):.2f} |")


def accelerometer_axes(data: CalibrationData, fitted: Ferraris) -> CalibrationData:
    """The session with each turn's angle about the axis its mean corrected specific force points along
    (the vertical, if the unit turned about it), in place of the body axis."""
    _, f = fitted.correct(data.gyro, data.accel)
    phases = []
    for p in data.phases:
        if p.angle_rad is not None:
            k = "xyz".index(p.name[0])
            up = f[p.start : p.stop].mean(axis=0)
            up = up / (np.linalg.norm(up) * np.sign(up[k]))  # the axis, pointing along +k
            angle = p.angle_rad[k]  # the turn's signed angle about its own axis
            p = dataclasses.replace(p, angle_rad=(angle * up[0], angle * up[1], angle * up[2]))
        phases.append(p)
    return dataclasses.replace(data, phases=tuple(phases))


def axes_table(data: CalibrationData) -> None:
    """How far the accelerometer sees each turn's axis off the body axis, and what taking the turns
    about those axes does to the motions between holds."""
    fitted = Ferraris().fit(data)
    moved = accelerometer_axes(data, fitted)
    tilts = []
    for p in moved.phases:
        if p.angle_rad is not None:
            along = abs(p.angle_rad["xyz".index(p.name[0])]) / np.linalg.norm(p.angle_rad)
            tilts.append(f"{math.degrees(math.acos(along)):.2f}°")
    print(f"\nThe turns' axes as the accelerometer sees them, off the body axes: {', '.join(tilts)}")
    for label, d in (("body axes (imucal's)", data), ("the accelerometer's axes", moved)):
        c = check_session(Ferraris().fit(d), data)
        if c.transitions:
            rms = math.sqrt(float(np.mean(np.degrees([t.error_rad for t in c.transitions]) ** 2)))
            print(f"turns about {label}: the motions between holds, RMS {rms:.2f}°")


def main() -> None:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    data = io.read(dataset="ferraris_annotated").reference_inputs()[0]
    fitted = Ferraris().fit(data)
    g = float(np.abs(data.ref_accel[data.phases[0].start, 0]))
    here = imucal_run(g, reader.ANNOTATED_TURN_DEG)
    version = importlib.metadata.version("imucal")
    print(f"### imucal {version} beside sins: the annotated session, g = {g:.6f} m/s², +360°\n")
    comparison_table(fitted, here)
    print(f"\nsins against imucal run here: {worst(fitted, here)}")
    snap, default = snapshot(), imucal_run(9.81, -360.0)
    same = max(float(np.abs(getattr(snap, p) - getattr(default, p)).max()) for p in PARAMS)
    print(f"imucal run at its defaults (9.81 m/s², −360°) against its snapshot: largest |Δ| {same:.2g}")
    mapped = as_snapshot(here, g)
    again = max(float(np.abs(getattr(snap, p) - getattr(mapped, p)).max()) for p in PARAMS)
    print(f"imucal run here, mapped to the snapshot's g and sign, against it: largest |Δ| {again:.2g}")
    print(f"sins, mapped the same way, against the snapshot: {worst_mapped(fitted, snap, g)}")
    for name in ("ferraris", "ferraris_annotated"):
        session_table(name, io.read(dataset=name).reference_inputs()[0])
        axes_table(io.read(dataset=name).reference_inputs()[0])


def worst_mapped(fitted: Ferraris, snap: ImucalCalibration, g: float) -> str:
    """sins's fit against the snapshot: the snapshot mapped back to sins's g and turn sign."""
    back = ImucalCalibration(
        K_a=snap.K_a * 9.81 / g, R_a=snap.R_a, b_a=snap.b_a, K_g=snap.K_g, R_g=-snap.R_g,
        K_ga=snap.K_ga * 9.81 / g, b_g=snap.b_g,
    )  # fmt: skip
    return worst(fitted, back)


if __name__ == "__main__":
    try:
        main()
    except SinsInputError as exc:  # the data not found, say: one line and status 2, as the CLI does
        print(f"ferraris_vs_imucal: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
