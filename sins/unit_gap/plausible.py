"""Accepted effects whose fitted size no MEMS unit has: said beside the diagnosis, so that a reader takes
them for what they likely are (an unmodelled effect or the reference's own error that the effect's columns
absorb), not for the unit's.

An effect is accepted on its withheld likelihood gain, which says that its columns explain something, not
that the unit has it at that size. Three effects have a size beyond which no unit has them:

* ``*.scale_nonlinearity``: ``k2·u`` is a scale error at input ``u``; at the recording's largest input
  it must stay within a consumer unit's scale-factor bound
  (:func:`sins.compensation.identifiability.class_bounds`: 10 % gyro, 5 % accelerometer), the loosest
  class sins knows;
* ``*.scale_asymmetry``: ``ka`` is the difference of the scale factors for either sign: the same bound;
* ``accel.size_effect``: the lever arm of an accelerometer from the unit's centre stays within the unit's
  case (:data:`MAX_LEVER_ARM_M`); metres are a reference whose point is not the IMU's;
* ``gyro.g2_sensitivity``: at 1 g, where sensitivities are specified, each coefficient's drift stays
  within the class's g-sensitivity bound (a consumer unit's 500 °/h/g: 500 °/h/g²; sins's typical unit
  has 3 °/h/g², the cases of ``tools/gap_real_cases.py`` add 180): a walk's 100 Hz copy of a EuRoC
  sequence had 4e5 °/h/g² accepted, EuRoC's MH_02 as it is 3.5e3.

The verdicts are left as they are: the label says what the size means, the gain what the data says.
"""

from __future__ import annotations

import numpy as np

from sins.compensation.identifiability import DEFAULT_GRADE, G_SENSITIVITY, class_bounds
from sins.core.earth import G0
from sins.imu.spec import DEG_PER_H

#: The largest lever arm of an accelerometer from a unit's centre, m: a board-level MEMS unit's case
#: is a few centimetres across, the largest tactical units' about 15 cm.
MAX_LEVER_ARM_M = 0.1


def implausible(sizes: dict[str, dict[str, list[float]]], largest: dict[str, float]) -> dict[str, str]:
    """Per accepted effect beyond a unit's size (see the module docstring), why, in words.

    ``sizes``: :attr:`sins.gap.GapReport.sizes` (effect → channel → coefficients, SI); ``largest``:
    each channel's largest absolute reading over the recording, SI (rad/s, m/s²).
    """
    bound = class_bounds(DEFAULT_GRADE).bound
    g2_limit = bound[f"gyro.{G_SENSITIVITY}"] / G0  # rad/s per (m/s²)²: the g-sensitivity bound's at 1 g
    g2_said = g2_limit * G0**2 / DEG_PER_H  # °/h at 1 g
    out = {}
    for effect, channels in sizes.items():
        sensor, kind = effect.split(".", 1)
        scale_bound = bound.get(f"{sensor}.scale", np.inf)
        beyond = []
        for ch, values in channels.items():
            axis = ch.split(".")[1]
            if kind == "g2_sensitivity" and float(np.max(np.abs(values))) > g2_limit:
                beyond.append(f"{axis} {float(np.max(np.abs(values))) * G0**2 / DEG_PER_H:.3g} °/h/g²")
            elif kind == "scale_nonlinearity":
                error = abs(values[0]) * largest.get(ch, 0.0)
                if error > scale_bound:
                    beyond.append(f"{axis} a {100 * error:.3g} % scale error at its largest input")
            elif kind == "scale_asymmetry" and abs(values[0]) > scale_bound:
                beyond.append(f"{axis} {100 * abs(values[0]):.3g} % between the signs")
            elif kind == "size_effect" and float(np.linalg.norm(values)) > MAX_LEVER_ARM_M:
                beyond.append(f"{axis} {float(np.linalg.norm(values)):.3g} m from the unit's centre")
        if not beyond:
            continue
        limit = (
            f"a lever arm within {MAX_LEVER_ARM_M:g} m, its case"
            if kind == "size_effect"
            else f"at 1 g, a {DEFAULT_GRADE} unit's g-sensitivity bound of {g2_said:.3g} °/h"
            if kind == "g2_sensitivity"
            else f"a {DEFAULT_GRADE} unit's scale bound of {100 * scale_bound:g} %"
        )
        out[effect] = (
            f"{'; '.join(beyond)}: beyond what a unit has ({limit}); more likely its columns absorb "
            + ("the reference's point being elsewhere than the IMU's" if kind == "size_effect" else
               "an effect the library lacks or the reference's own error")
        )  # fmt: skip
    return out


__all__ = [
    "MAX_LEVER_ARM_M",
    "implausible",
]
