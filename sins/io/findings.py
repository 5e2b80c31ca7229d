"""What a recording's sanity check reports (:func:`sins.io.inspection.inspect`), as plain data: each likely
mistake (:class:`Finding`), the stretches without samples, the clipped readings, the rest, and the whole
:class:`Inspection`; and the one-second windows of the readings the checks reason from."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Finding:
    """One likely mistake: ``code`` (stable), ``what`` the data show (one line, with figures), the reader
    option that mends it and its ``value`` (``option="units", value="accel=g"``: ``--units accel=g``),
    or ``advice`` where no option does."""

    code: str
    what: str
    option: str | None = None
    value: str | None = None
    advice: str = ""


@dataclass(frozen=True)
class Gap:
    """A stretch without samples: from ``start_s`` for ``length_s``, about ``missing`` samples."""

    start_s: float
    length_s: float
    missing: int


@dataclass(frozen=True)
class Clipping:
    """Readings stuck at a channel's extreme ``level`` (SI): ``samples`` in ``runs``, the first at
    ``first_s``."""

    channel: str
    level: float
    samples: int
    runs: int
    first_s: float


@dataclass(frozen=True)
class Rest:
    """The readings at rest: how long, the mean specific force and rate (SI, FRD as read), their sizes
    against normal gravity and Earth's rate, whether the rate's mean is resolved (its standard error
    below a tenth of it, the windows agreeing), and ``orientations``: 2 where a fifth or more of the
    quiet windows hold gravity 20° or more away (a rig session, a hand-held unit), whose axes the rest
    then does not show."""

    seconds: float
    specific_force: tuple[float, float, float]
    rate: tuple[float, float, float]
    gravity_ratio: float
    earth_rate_ratio: float
    rate_resolved: bool
    orientations: int = 1


@dataclass(frozen=True)
class ReferenceLag:
    """How the reference's clock sits against the readings': its turns agree best with the gyro's when
    it is read ``lag_s`` later than stamped (positive: the reference lags, its attitude at ``t`` the
    body's at ``t - lag_s``); ``agreement`` the correlation of the turns there, ``as_stamped`` at none."""

    lag_s: float
    agreement: float
    as_stamped: float


@dataclass(frozen=True)
class Inspection:
    """What :func:`inspect` found: the figures, and the :class:`Finding` list (empty when clean)."""

    source: str
    form: str
    rows: int
    span_s: float
    rate_hz: float
    jitter: float
    stated_rate_hz: float | None
    gaps: tuple[Gap, ...]
    rest: Rest | None
    clipping: tuple[Clipping, ...]
    axes: str | None
    findings: tuple[Finding, ...] = field(default=())
    reference_lag: ReferenceLag | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain types for JSON (SI units)."""
        return asdict(self)


@dataclass(frozen=True)
class Windows:
    """One-second windows of the mean rates: per window the mean and the spread of ω and f."""

    length: int
    mean_w: Array
    mean_f: Array
    spread_w: Array
    spread_f: Array


__all__ = [
    "Clipping",
    "Finding",
    "Gap",
    "Inspection",
    "ReferenceLag",
    "Rest",
    "Windows",
]
