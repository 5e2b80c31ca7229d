"""A unit's compensation strategies fitted once on its simulated rig session, to drive any scenario.

:func:`fit_unit` simulates the rig session of a scenario's ``[compensation]`` (its own power-on of the
unit) and fits and judges each strategy on it; the :class:`FittedUnit` it returns is what
:func:`sins.runs.pipeline.run_units` drives, and what a campaign fits once per unit.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from sins import scenario

if TYPE_CHECKING:
    from sins.compensation import Strategy
    from sins.imu import ImuModel


@dataclass(frozen=True)
class FittedUnit:
    """One unit's strategies, fitted on its rig session, ready to drive any number of scenarios.

    ``strategies`` holds every strategy but the oracle, whose model is each navigation run's own
    (:meth:`for_run`); ``residuals`` the RMS of each one's corrected readings on the held-back rig
    rows, per channel, SI units (the oracle's knowing the rig session's unit), and ``biases`` their
    mean (the bias each strategy leaves).
    """

    spec: scenario.ImuSpec
    compensation: scenario.CompensationSpec | None
    strategies: dict[str, Strategy]
    residuals: dict[str, dict[str, float]]
    biases: dict[str, dict[str, float]] = field(default_factory=dict)

    def for_run(self, nav_model: ImuModel) -> dict[str, Strategy]:
        """The strategies in the scenario's order, the oracle knowing ``nav_model``."""
        from sins import compensation

        names = ["none", *(self.compensation.strategies if self.compensation else ())]
        out: dict[str, Strategy] = {}
        for name in names:
            out[name] = compensation.Oracle(nav_model) if name == "oracle" else self.strategies[name]
        return out


def fit_unit(
    spec: scenario.ImuSpec,
    comp: scenario.CompensationSpec | None,
    progress: Callable[[int, int], None] | None = None,
) -> FittedUnit:
    """Simulate the unit's rig session (power-on ``comp.seed``) and fit every strategy of ``comp``.

    Without ``comp``, only ``"none"``. ``progress(strategies_done, strategies)`` is called as each is
    fitted and judged.
    """
    from sins import compensation
    from sins.imu import calibration

    strategies: dict[str, Strategy] = {"none": compensation.make("none")}
    residuals: dict[str, dict[str, float]] = {}
    biases: dict[str, dict[str, float]] = {}
    if comp is None:
        return FittedUnit(spec, comp, strategies, residuals, biases)
    rig = scenario.load_rig(comp.rig)
    rig_model = spec.model(run_seed=comp.seed)
    data = calibration.simulate_rig(rig, rig_model, seed=comp.seed)
    fit, held = data.split(comp.validation)
    for name in comp.strategies:
        if name == "oracle":
            # On the rig it knows the rig session's unit; in navigation, the navigation run's.
            judged: Strategy = compensation.Oracle(rig_model)
        else:
            judged = strategies[name] = compensation.make(name).fit(fit)
        channels = compensation.residual_rms(judged, held)
        residuals[name] = {ch: v["rms_after"] for ch, v in channels.items()}
        biases[name] = {ch: v["mean_after"] for ch, v in channels.items()}
        if progress is not None:
            progress(len(residuals), len(comp.strategies))
    return FittedUnit(spec, comp, strategies, residuals, biases)


__all__ = ["FittedUnit", "fit_unit"]
