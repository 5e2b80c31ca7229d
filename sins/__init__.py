"""sins: a strapdown inertial navigation simulator with learned IMU error correction.

``import sins`` gives the main entry points (:data:`ENTRY_POINTS`: the data, ``generate``,
``draw_unit``, ``simulate_rig``, ``integrate``, ``run_scenario`` …) and the subpackages
(:data:`SUBMODULES`: ``sins.compensation``, ``sins.runs``, ``sins.characterise`` …), each imported
the first time it is used, so that ``import sins`` itself is quick. The library guide
(``docs/guide/library.md``) walks through them: simulate, corrupt, compensate, integrate, plot.

Conventions (stated once, here; every module follows them)
----------------------------------------------------------
Frames
    ``n``  local-level navigation frame, North-East-Down (NED).
    ``b``  body frame, x forward, y right, z down (FRD).
    ``e``  Earth-centred Earth-fixed (ECEF);  ``i``  inertial.
Names
    Quantity first, then frames: ``v_n`` (velocity of the body relative to
    Earth, resolved in n), ``omega_ib_b`` (angular rate of b relative to i,
    resolved in b), ``f_ib_b`` (specific force), ``C_nb`` (direction cosine
    matrix that rotates b-vectors into n: ``x_n = C_nb @ x_b``), ``q_nb``.
    The true or reference quantity carries its frames (``omega_ib_b``,
    ``f_ib_b``, ``omega_dot_b``; a corrected reading is an estimate of it and
    is named so too); a sensor's readings of it are ``gyro`` and ``accel``
    (and their references ``ref_gyro``, ``ref_accel``), the CSV columns' names.
Quaternions
    Scalar-last ``[x, y, z, w]`` (the order of scipy and Rerun), Hamilton
    product, ``q_nb`` represents the same rotation as ``C_nb``.
Euler angles
    ZYX: yaw about down (clockwise from north seen from above), then pitch,
    then roll; ``C_nb = Rz(yaw) @ Ry(pitch) @ Rx(roll)``, the same as
    ``scipy.spatial.transform.Rotation.from_euler("ZYX", [yaw, pitch, roll])``.
Units
    SI and radians everywhere inside the package. Degrees and other units only
    at the edges (scenario files, CSV position/attitude columns, CLI) and such
    names carry a suffix (``lat_deg``, ``yaw_deg``, ``bias_mg``).
Arrays
    Time-major: a series of 3-vectors has shape ``(n, 3)``.
Randomness
    Only through an explicit ``numpy.random.Generator`` or seed passed in.
Earth
    WGS84 ellipsoid, Somigliana normal gravity with the standard height
    correction, Earth rate 7.292115e-5 rad/s; transport rate and Coriolis
    terms are always modelled.
IMU samples
    Increment form (:class:`~sins.core.series.ImuIncrements`): ``t`` holds the
    n+1 step boundaries and row ``k`` of ``dtheta_b``, ``dv_b`` the integrals
    of ``omega_ib_b`` and ``f_ib_b`` over ``(t[k], t[k+1]]``; a file's row
    is stamped with its step's end. Rate form: instantaneous values at
    ``t[k]``. (Stated here only; ``tests/test_trajectory.py`` holds it.)
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from sins.errors import SinsInputError

if TYPE_CHECKING:  # what the lazy names below are, for type checkers and editors
    from sins import aiding as aiding
    from sins import campaign as campaign
    from sins import characterise as characterise
    from sins import compensation as compensation
    from sins import gap as gap
    from sins import imu as imu
    from sins import io as io
    from sins import nav as nav
    from sins import runs as runs
    from sins import scenario as scenario
    from sins import viz as viz
    from sins.core.series import CalibrationData, ImuIncrements, ImuRates, NavSeries, ReferencedRecording
    from sins.imu import ImuModel
    from sins.imu.calibration import RigProcedure, simulate_rig
    from sins.imu.spec import GRADES, Grade, draw_unit
    from sins.nav.metrics import nav_errors, summarize
    from sins.nav.strapdown import InitialState, integrate
    from sins.nav.trajectory import generate
    from sins.runs.pipeline import resolve_scenario, run_scenario
    from sins.runs.replay import navigate
    from sins.runs.results import ScenarioRun
    from sins.runs.unit_fit import fit_unit

__version__ = "0.1.0"

#: The main entry points, each imported from its module the first time it is asked for: ``import sins``
#: loads none of them (nor numpy, numba, torch, rerun, dask or matplotlib).
ENTRY_POINTS = {
    # the data: time-major arrays in SI units (sins.core.series)
    "NavSeries": "sins.core.series",
    "ImuIncrements": "sins.core.series",
    "ImuRates": "sins.core.series",
    "CalibrationData": "sins.core.series",
    "ReferencedRecording": "sins.core.series",
    # simulate: the truth and the exact ideal IMU along a motion (sins.nav.motion builds one)
    "generate": "sins.nav.trajectory",
    # corrupt: an IMU's error model, a unit of a grade, a rig session
    "ImuModel": "sins.imu",
    "Grade": "sins.imu.spec",
    "GRADES": "sins.imu.spec",
    "draw_unit": "sins.imu.spec",
    "RigProcedure": "sins.imu.calibration",
    "simulate_rig": "sins.imu.calibration",
    # integrate and judge
    "InitialState": "sins.nav.strapdown",
    "integrate": "sins.nav.strapdown",
    "nav_errors": "sins.nav.metrics",
    "summarize": "sins.nav.metrics",
    # runs: a scenario in one call, a unit fitted once, a recorded IMU against its truth
    "resolve_scenario": "sins.runs.pipeline",
    "run_scenario": "sins.runs.pipeline",
    "ScenarioRun": "sins.runs.results",
    "fit_unit": "sins.runs.unit_fit",
    "navigate": "sins.runs.replay",
}

#: The subpackages and modules a notebook reaches from here (``sins.compensation.make("mlp")``), imported
#: when first used; not in ``__all__``, so that ``from sins import *`` does not import rerun or torch.
SUBMODULES = (
    "aiding",
    "campaign",
    "characterise",
    "compensation",
    "gap",
    "imu",
    "io",
    "nav",
    "runs",
    "scenario",
    "viz",
)


def _lazy(
    namespace: dict[str, Any], names: dict[str, str], submodules: tuple[str, ...] = ()
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """A package's PEP 562 ``__getattr__`` and ``__dir__`` (``namespace`` its ``globals()``): each of
    ``names`` imported from the module it maps to on first use, then a plain attribute; each of
    ``submodules`` as the package's submodule. ``sins``, ``sins.nav`` and ``sins.aiding`` use it."""
    package = namespace["__name__"]

    def __getattr__(name: str) -> Any:
        if name in submodules:
            return importlib.import_module(f"{package}.{name}")
        if name not in names:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(names[name]), name)
        namespace[name] = value  # the next use is a plain attribute
        return value

    def __dir__() -> list[str]:
        return sorted({*namespace, *names, *submodules})

    return __getattr__, __dir__


#: An entry point or a submodule, imported on first use; the names above, for completion in a notebook.
__getattr__, __dir__ = _lazy(globals(), ENTRY_POINTS, SUBMODULES)


__all__ = [
    "ENTRY_POINTS",
    "GRADES",
    "SUBMODULES",
    "CalibrationData",
    "Grade",
    "ImuIncrements",
    "ImuModel",
    "ImuRates",
    "InitialState",
    "NavSeries",
    "ReferencedRecording",
    "RigProcedure",
    "ScenarioRun",
    "SinsInputError",
    "__version__",
    "draw_unit",
    "fit_unit",
    "generate",
    "integrate",
    "nav_errors",
    "navigate",
    "resolve_scenario",
    "run_scenario",
    "simulate_rig",
    "summarize",
]
