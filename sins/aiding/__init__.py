"""Aided navigation: a simulated GNSS receiver, the GNSS/INS error-state filter and initial alignment.

``gnss`` simulates and checks fixes; ``ekf`` is the 15-state loosely coupled filter on the strapdown
integrator; ``alignment`` levels, gyrocompasses and hands the filter its start; ``policy`` picks which
alignment starts a run; ``outages`` measures an aided run's error over its outage windows.

The main names are importable from here (``from sins.aiding import GnssConfig, FilterConfig``), each
from its module the first time it is used: the filter's module imports filterpy, which a run without
``[gnss]`` never loads.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from sins import _lazy

if TYPE_CHECKING:
    from sins.aiding.alignment import AlignmentConfig, MotionConfig
    from sins.aiding.ekf import AidedResult, FilterConfig
    from sins.aiding.gnss import GnssConfig, GnssFixes, Outage
    from sins.aiding.outages import OutageError, outage_errors
    from sins.aiding.policy import AlignmentPlan, plan_alignment, run_aligned

#: Each name importable from here, and the module that defines it (``sins.aiding.gnss.simulate`` and
#: ``sins.aiding.ekf.run`` keep their module's name: alone, "simulate" and "run" would not say what).
NAMES = {
    **dict.fromkeys(("AlignmentConfig", "MotionConfig"), "sins.aiding.alignment"),
    **dict.fromkeys(("AidedResult", "FilterConfig"), "sins.aiding.ekf"),
    **dict.fromkeys(("GnssConfig", "GnssFixes", "Outage"), "sins.aiding.gnss"),
    **dict.fromkeys(("OutageError", "outage_errors"), "sins.aiding.outages"),
    **dict.fromkeys(("AlignmentPlan", "plan_alignment", "run_aligned"), "sins.aiding.policy"),
}


#: A name of :data:`NAMES`, imported from its module on first use (PEP 562); the names, for completion.
__getattr__, __dir__ = _lazy(globals(), NAMES)


__all__ = [
    "NAMES",
    "AidedResult",
    "AlignmentConfig",
    "AlignmentPlan",
    "FilterConfig",
    "GnssConfig",
    "GnssFixes",
    "MotionConfig",
    "Outage",
    "OutageError",
    "outage_errors",
    "plan_alignment",
    "run_aligned",
]
