"""Which alignment starts an aided run, resolved against the trajectory, and the run it starts.

A scenario's ``[alignment]`` (:class:`AlignmentTable`: any object with its fields, such as
:class:`sins.scenario.AidingSpec`) says ``static``, ``gnss_velocity``, ``truth`` or ``auto``;
:func:`plan_alignment` resolves it against the truth into an :class:`AlignmentPlan`, and
:func:`run_aligned` runs the filter from it. ``auto`` aligns still on the stop the trajectory starts
with when it lasts :data:`AUTO_MIN_STOP_S` or more and gyrocompassing finds north within
:data:`sins.aiding.alignment.GYROCOMPASS_MAX_SIGMA_RAD` for the filter's grade (or the heading comes
from elsewhere); in motion from the GNSS velocity otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from sins.aiding import alignment, ekf
from sins.aiding.gnss import GnssFixes
from sins.core.series import ImuIncrements, NavSeries
from sins.errors import SinsInputError
from sins.nav import strapdown

#: The shortest stop at the start an automatic alignment aligns still on, s.
AUTO_MIN_STOP_S = 30.0
#: The longest still window an automatic alignment uses (the fine alignment gains little after), s.
AUTO_MAX_STATIC_S = 300.0


class AlignmentTable(Protocol):
    """What an ``[alignment]`` table says (:class:`sins.scenario.AidingSpec` has these fields)."""

    @property
    def alignment(self) -> str:
        """``"auto"``, ``"static"``, ``"gnss_velocity"`` or ``"truth"``."""

    @property
    def static_s(self) -> float | None:
        """The still window, s (None: ``auto`` takes the stop's length, up to :data:`AUTO_MAX_STATIC_S`)."""

    @property
    def coarse_s(self) -> float:
        """The coarse alignment's window, s."""

    @property
    def heading_sigma_rad(self) -> float | None:
        """A static alignment's heading from elsewhere: the truth's, off by a draw of this σ, rad (None:
        gyrocompass)."""

    @property
    def min_speed_mps(self) -> float:
        """The in-motion alignment's speed (:class:`sins.aiding.alignment.MotionConfig`), m/s."""

    @property
    def sideslip_sigma_rad(self) -> float:
        """The in-motion alignment's angle between heading and course over ground, 1σ, rad."""

    @property
    def seed(self) -> int:
        """Draws the heading's error."""


@dataclass(frozen=True)
class AlignmentPlan:
    """How every strategy's aided run starts: ``[alignment]`` resolved against the trajectory.

    ``method`` is ``"static"``, ``"gnss_velocity"`` or ``"truth"``; a static one aligns over
    ``static_s`` (coarse over ``coarse_s``), s, with ``heading`` ``(heading, σ)`` in rad from elsewhere
    or None to gyrocompass; an in-motion one waits for ``min_speed_mps`` with ``sideslip_sigma_rad``;
    ``where`` names the scenario in its refusal.
    """

    method: str
    static_s: float = 0.0
    coarse_s: float = 0.0
    heading: tuple[float, float] | None = None
    min_speed_mps: float = 5.0
    sideslip_sigma_rad: float = 0.0
    where: str = ""


def plan_alignment(
    table: AlignmentTable, truth: NavSeries, config: ekf.FilterConfig, where: str = ""
) -> AlignmentPlan:
    """``table`` resolved against ``truth`` for a filter tuned as ``config`` (``auto``: module docstring).

    Raises
    ------
    SinsInputError
        a static alignment longer than the run, or on a vehicle that moves within it (naming ``where``).
    """
    method, static_s = table.alignment, table.static_s
    if method == "auto":
        stop = initial_stop_s(truth)
        static_s = static_s if static_s is not None else min(stop, AUTO_MAX_STATIC_S)
        coarse = min(table.coarse_s, static_s)
        north = table.heading_sigma_rad is not None or (
            coarse > 0
            and np.sqrt(alignment.coarse_covariance(config, float(truth.lat[0]), coarse, 1.0)[8, 8])
            <= alignment.GYROCOMPASS_MAX_SIGMA_RAD
        )
        enough = stop >= max(static_s, AUTO_MIN_STOP_S) - 1e-9
        method = "static" if enough and north else "gnss_velocity"
    if method == "static":
        assert static_s is not None  # the scenario's validation asks for it
        heading = static_heading(table, truth, static_s, where)
        return AlignmentPlan("static", static_s, min(table.coarse_s, static_s), heading)
    return AlignmentPlan(
        method, min_speed_mps=table.min_speed_mps, sideslip_sigma_rad=table.sideslip_sigma_rad, where=where
    )


def initial_stop_s(truth: NavSeries) -> float:
    """How long the vehicle stands still (no speed, no turn) from the first sample, s."""
    yaw = np.unwrap(truth.euler()[2])
    moving = (np.linalg.norm(truth.v_n, axis=1) > 1e-6) | (np.abs(yaw - yaw[0]) > 1e-9)
    if not moving.any():
        return float(truth.t[-1] - truth.t[0])
    return float(truth.t[max(int(np.argmax(moving)) - 1, 0)] - truth.t[0])


def static_heading(
    table: AlignmentTable, truth: NavSeries, static_s: float, where: str = ""
) -> tuple[float, float] | None:
    """The heading told to a static alignment over ``static_s``: ``(heading, σ)`` in rad, the truth's
    off by a draw of ``table.heading_sigma_rad`` (seeded by ``table.seed``), or None to gyrocompass.

    Raises
    ------
    SinsInputError
        ``static_s`` longer than the run, or the vehicle moves within it (naming ``where``).
    """
    still = truth.t <= truth.t[0] + static_s + 1e-9
    if truth.t[-1] < truth.t[0] + static_s - 1e-9:
        raise SinsInputError(
            f"{where}: alignment.static_s: {static_s:g} s is longer than the run's "
            f"{truth.t[-1] - truth.t[0]:g} s"
        )
    speed = float(np.max(np.linalg.norm(truth.v_n[still], axis=1)))
    turn = np.abs(np.diff(np.unwrap(truth.euler()[2][still])))
    if speed > 1e-6 or float(np.sum(turn)) > 1e-9:
        raise SinsInputError(
            f"{where}: alignment.static_s: the vehicle moves within the first {static_s:g} s "
            f"(speed up to {speed:.3g} m/s); an alignment needs it still"
        )
    if table.heading_sigma_rad is None:
        return None
    draw = np.random.default_rng([table.seed, 3]).standard_normal()
    return float(truth.euler()[2][0] + table.heading_sigma_rad * draw), table.heading_sigma_rad


def run_aligned(
    plan: AlignmentPlan, imu: ImuIncrements, fixes: GnssFixes, config: ekf.FilterConfig, truth: NavSeries
) -> tuple[ekf.AidedResult, int, float | None]:
    """The filter over ``imu`` and ``fixes``, started as ``plan`` says.

    Returns the result, the IMU sample it starts at (an in-motion alignment's fix; 0 otherwise) and
    the in-motion alignment's heading σ told to the filter (rad; None for the others). ``truth`` is
    the start of ``method = "truth"``.

    Raises
    ------
    SinsInputError
        as :func:`sins.aiding.alignment.aligned_run` and :func:`~sins.aiding.alignment.in_motion_run`
        (the latter naming ``plan.where``).
    """
    if plan.method == "static":
        setup = alignment.AlignmentConfig(static_s=plan.static_s, coarse_s=plan.coarse_s)
        return alignment.aligned_run(imu, fixes, config, setup, heading=plan.heading), 0, None
    if plan.method == "gnss_velocity":
        motion = alignment.MotionConfig(
            min_speed_mps=plan.min_speed_mps, sideslip_sigma_rad=plan.sideslip_sigma_rad
        )
        try:
            start, result = alignment.in_motion_run(imu, fixes, config, motion)
        except SinsInputError as exc:
            raise SinsInputError(f"{plan.where}: {exc}") from None
        return result, start.index, start.heading_sigma_rad
    return ekf.run(imu, fixes, config, strapdown.InitialState.from_series(truth)), 0, None


__all__ = [
    "AUTO_MAX_STATIC_S",
    "AUTO_MIN_STOP_S",
    "AlignmentPlan",
    "AlignmentTable",
    "initial_stop_s",
    "plan_alignment",
    "run_aligned",
    "static_heading",
]
