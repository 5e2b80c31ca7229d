"""Navigation: vehicle motion and its trajectory, the strapdown integrator, the vertical channel, and
error metrics. Pure functions over arrays; nothing here knows about IMU errors.

The names a user needs are importable from here (``from sins.nav import SegmentMotion, generate,
integrate``), each from its module the first time it is used. Rotations and the Earth are at the base
layer (:mod:`sins.core.rotation`, :mod:`sins.core.earth`), below the data containers the rest builds on.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from sins import _lazy

if TYPE_CHECKING:
    from sins.nav.metrics import DriftSummary, NavErrors, nav_errors, summarize
    from sins.nav.motion import (
        Accelerate,
        Climb,
        Hold,
        Kinematics,
        Motion,
        Oscillation,
        RecordedMotion,
        Rotate,
        SegmentMotion,
        Start,
        Turn,
        WaypointMotion,
    )
    from sins.nav.strapdown import InitialState, advance, integrate, integrate_batch, start
    from sins.nav.trajectory import generate, generate_chunks, ideal_rates
    from sins.nav.vertical import VERTICAL_MODES, VerticalMode

#: Each name importable from here, and the module that defines it.
NAMES = {
    **dict.fromkeys(
        (
            "Accelerate",
            "Climb",
            "Hold",
            "Kinematics",
            "Motion",
            "Oscillation",
            "RecordedMotion",
            "Rotate",
            "SegmentMotion",
            "Start",
            "Turn",
            "WaypointMotion",
        ),
        "sins.nav.motion",
    ),
    **dict.fromkeys(("generate", "generate_chunks", "ideal_rates"), "sins.nav.trajectory"),
    **dict.fromkeys(
        ("InitialState", "advance", "integrate", "integrate_batch", "start"), "sins.nav.strapdown"
    ),
    **dict.fromkeys(("DriftSummary", "NavErrors", "nav_errors", "summarize"), "sins.nav.metrics"),
    **dict.fromkeys(("VERTICAL_MODES", "VerticalMode"), "sins.nav.vertical"),
}


#: A name of :data:`NAMES`, imported from its module on first use (PEP 562); the names, for completion.
__getattr__, __dir__ = _lazy(globals(), NAMES)


__all__ = [
    "NAMES",
    "VERTICAL_MODES",
    "Accelerate",
    "Climb",
    "DriftSummary",
    "Hold",
    "InitialState",
    "Kinematics",
    "Motion",
    "NavErrors",
    "Oscillation",
    "RecordedMotion",
    "Rotate",
    "SegmentMotion",
    "Start",
    "Turn",
    "VerticalMode",
    "WaypointMotion",
    "advance",
    "generate",
    "generate_chunks",
    "ideal_rates",
    "integrate",
    "integrate_batch",
    "nav_errors",
    "start",
    "summarize",
]
