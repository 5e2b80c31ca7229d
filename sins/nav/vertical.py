"""The vertical channel's modes, named once for the integrator, scenario files and the command line.

``"free"`` leaves the channel inertial (unstable, time constant ≈ 570 s), ``"hold"`` sets height and
vertical velocity from a reference height each step, ``"damp"`` feeds the height error back through a
second-order loop; :mod:`sins.nav.strapdown` implements them. This module imports nothing heavy so that
the command line can offer the choices without starting numba (the CLI starts without numpy).
"""

from __future__ import annotations

from typing import Final, Literal, get_args

#: How the integrator treats the vertical channel.
VerticalMode = Literal["free", "hold", "damp"]

#: The modes in the order the messages list them.
VERTICAL_MODES: Final[tuple[VerticalMode, ...]] = get_args(VerticalMode)


__all__ = [
    "VERTICAL_MODES",
    "VerticalMode",
]
