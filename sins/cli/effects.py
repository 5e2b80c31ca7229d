"""``sins effects``: the IMU error effects, their parameters and units; ``--grades``: each grade's values."""

from __future__ import annotations

import argparse

from sins.cli.common import Subparsers, fixed_width

#: A grade field's unit, by the end of its name (``gyro_bias_dph`` is in °/h), longest first.
GRADE_UNITS = (
    ("_dph_per_g", "°/h/g"),
    ("_deg_per_rt_h", "°/√h"),
    ("_ug_per_rt_hz", "µg/√Hz"),
    ("_dph", "°/h"),
    ("_mg", "mg"),
    ("_ug", "µg"),
    ("_ppm", "ppm"),
    ("_s", "s"),
)


#: Words for the fields whose names are abbreviations (the rest read from the name itself).
GRADE_LABELS = {
    "gyro_turn_on_dph": "gyro turn-on bias", "accel_turn_on_mg": "accel turn-on bias",
    "arw_deg_per_rt_h": "gyro noise (angle random walk)", "vrw_ug_per_rt_hz": "accel noise density",
    "gyro_instability_dph": "gyro bias instability", "accel_instability_ug": "accel bias instability",
    "instability_tau_s": "bias instability time constant", "g_sensitivity_dph_per_g": "gyro g-sensitivity",
}  # fmt: skip


def grade_table() -> str:
    """Every grade's values (:data:`sins.imu.spec.GRADES`), one row per field, a column per grade."""
    import dataclasses

    from sins.imu.spec import GRADES

    grades = list(GRADES.values())
    rows = []
    for f in dataclasses.fields(grades[0]):
        if f.name in ("name", "description"):
            continue
        suffix, unit = next((s, u) for s, u in GRADE_UNITS if f.name.endswith(s))
        label = GRADE_LABELS.get(f.name, f.name[: -len(suffix)].replace("_", " "))
        rows.append([label, unit, *(f"{getattr(g, f.name):g}" for g in grades)])
    head = ["value", "unit", *(g.name for g in grades)]
    about = "\n".join(f"  {g.name}: {g.description}" for g in grades)
    return (
        "IMU grades (sins run --imu GRADE, or grade = in an IMU file): a unit draws its bias, scale\n"
        "factors, misalignments and g-sensitivity from normal spreads of these 1σ (turn-on: again at each\n"
        "power-on); noise and bias instability are the grade's own values\n"
        f"{about}\n\n{fixed_width(head, rows)}"
    )


def _cmd_effects(args: argparse.Namespace) -> int:
    from sins import imu
    from sins.imu import spec as imu_spec

    if args.grades:
        print(grade_table())
        return 0
    for name, spec in imu_spec.parameters().items():
        params = ", ".join(f"{p.key} [{p.unit}]" for p in spec.params)
        marker = "  (baseline)" if name in imu.BASELINE else ""
        print(f"{name:<26} {spec.description}{marker}\n{'':<26} {params}")
    return 0


def add(sub: Subparsers) -> None:
    """Add ``sins effects`` to ``sub``."""
    p = sub.add_parser(
        "effects", help="list the IMU error effects, their parameters and units (or the grades)"
    )
    p.add_argument(
        "--grades", action="store_true",
        help="list each IMU grade's values instead: the spreads units are drawn from, noise, instability",
    )  # fmt: skip
    p.set_defaults(func=_cmd_effects)


__all__ = [
    "GRADE_LABELS",
    "GRADE_UNITS",
    "add",
    "grade_table",
]
