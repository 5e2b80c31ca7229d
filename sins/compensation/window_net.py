"""``mlp_window``: the seed model, then a feed-forward network of the gyro's error from a window of past
readings, trained on several recordings of one unit and kept only where it predicts held-back recordings.

What the published gyro denoisers learn (Brossard et al. 2020 and successors) is a function of the past
readings, gyro and accelerometer, not of one reading: a MEMS gyro's error in motion depends on the
motion's recent history (vibration rectification, the bias at rest against the bias in motion, the
thermal state the accelerometer's level betrays). This strategy gives the mission's network that input:

* **Inputs**: for each reading, the mean rate, the mean specific force and the spread (RMS about the
  mean, summed over the axes) of each over consecutive blocks of the past (:data:`EDGES_S`: 0.25 s near
  the reading, doubling to 8 s), of the seed-corrected readings: 8 numbers a block, causal (the reading
  itself and what follows are not in them). Made every :data:`STRIDE` readings and held until the next
  (the correction is a slow function of the past: 20 evaluations a second at 200 Hz).
* **Target**: what the seed model with the unit's mean bias leaves of each reference interval, as the
  constant rate that would close it (:func:`~sins.compensation.interval_fit.interval_reference`): the
  per-recording part of the bias is in it, so the network is asked to tell it from the readings.
* **Network**: tanh layers ``hidden``, Adam with weight decay for ``steps`` full-batch steps, inputs and
  targets standardised; ``ensemble`` networks from different seeds averaged (their spread is the
  network's own noise).
* **Guard**: each recording held back in turn (up to :data:`MAX_FOLDS` folds of whole recordings), the
  networks trained on the others. Given the recordings beside their references (a fit on several), each
  held-back recording is judged by what the network is for: the open-loop attitude of its gyro
  integrated alone (:func:`~sins.compensation.unit_bias.open_loop_deg`), with and without the network;
  the network is kept only where the mean gain over the held-back recordings is above ``guard_z``
  standard errors' level as Student's t over them (their own spread;
  :func:`~sins.compensation.base.recordings_threshold`). Without them (one recording: its first part
  against its last :data:`HOLD_LAST`), each gyro axis by the held-back intervals' squared error, as the
  other learners' guard does. Held-back folds train two at a time (threads; torch on one thread each).

``correct`` (sample by sample) applies the seed model only; ``correct_increments`` and ``correct_rates``,
which see a recording in order, apply the network too.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from sins.compensation.base import (
    GUARD_Z_RANGE,
    SEED_RANGE,
    ParamRange,
    checked_array,
    recordings_threshold,
    state_array,
    sum_standard_error,
)
from sins.compensation.mlp import check_hidden, seeded
from sins.compensation.regression import Regression
from sins.compensation.window import GyroWindow
from sins.core.series import CalibrationData, ImuIncrements, ReferencedRecording

Array = NDArray[np.float64]

#: Block edges of the past window, s before the reading (nearest first).
EDGES_S = (0.0, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
#: Inputs per block: mean rate (3), mean specific force (3), rate spread, force spread.
PER_BLOCK = 8
#: Inputs in all.
FEATURES = PER_BLOCK * (len(EDGES_S) - 1)
#: Readings between two evaluations of the network (held between them).
STRIDE = 10
#: The most folds of held-back recordings the guard trains.
MAX_FOLDS = 6
#: One recording alone: the part of it held back for the guard.
HOLD_LAST = 0.25
#: The largest network a model file may ask for: layers and width.
MAX_LAYERS, MAX_WIDTH = 3, 128


class WindowNet(GyroWindow):
    """The seed model, then a network of the gyro's error from a window of past readings (module
    docstring)."""

    name = "mlp_window"
    state_keys = (*GyroWindow.state_keys, "held_back_gain_", "held_back_gain_se_", "axes_", "networks_")
    param_ranges: ClassVar[dict[str, ParamRange]] = {
        "hidden": ParamRange(1, MAX_WIDTH, whole=True),
        "weight_decay": ParamRange(0, 10),
        "steps": ParamRange(1, 100_000, whole=True),
        "ensemble": ParamRange(1, 16, whole=True),
        "guard_z": GUARD_Z_RANGE,
        "seed": SEED_RANGE,
    }

    def __init__(
        self,
        hidden: tuple[int, ...] = (32, 32),
        weight_decay: float = 1e-3,
        steps: int = 1500,
        ensemble: int = 3,
        guard: bool = True,
        guard_z: float = 2.0,
        seed: int = 0,
        g_sensitivity: bool = False,
    ) -> None:
        super().__init__(g_sensitivity=g_sensitivity)
        # Kept as given (scikit-learn's rule); check_params holds them.
        self.hidden = hidden
        self.weight_decay = weight_decay
        self.steps = steps
        self.ensemble = ensemble
        self.guard = guard
        self.guard_z = guard_z
        self.seed = seed
        self.progress: Callable[[int, int], None] | None = None

    def check_params(self) -> None:
        """As every strategy's, and ``hidden`` within mlp's :func:`~sins.compensation.mlp.check_hidden`
        at :data:`MAX_LAYERS` of :data:`MAX_WIDTH`: a layer of 1.5 neurons is refused, not made one of 1."""
        super().check_params()
        check_hidden(self.hidden, f"{self.label}: hidden", MAX_LAYERS, MAX_WIDTH)

    def fit_beyond(self, data: CalibrationData) -> WindowNet:
        """One recording's per-sample references (the seed model set first): the network on its first
        part, judged on the last :data:`HOLD_LAST` for the guard, then trained on all of it."""
        n = len(data)
        cut = round((1.0 - HOLD_LAST) * n)
        return self.fit_recordings([data.rows(slice(0, cut)), data.rows(slice(cut, n))])

    def fit_recordings(
        self, parts: list[CalibrationData], recordings: list[ReferencedRecording] | None = None
    ) -> WindowNet:
        """Several recordings' per-sample references (each with the seed model's mean bias, so that what
        moves between recordings is in the target), the seed model set first (:meth:`set_fit`); with
        ``recordings`` (the same recordings beside their references) the guard judges held-back
        recordings by their open-loop attitude (module docstring); returns self.

        Raises
        ------
        ValueError
            when the recordings hold fewer than 500 readings with a reference.
        """
        from concurrent.futures import ThreadPoolExecutor

        from sins.compensation.mlp import one_thread

        sets = [self._examples(p) for p in parts]
        if sum(len(y) for _, y in sets) < 50:
            raise ValueError("mlp_window needs more readings with a reference (at least 500)")
        folds = _folds(len(sets))
        total = (len(folds) + 1) * self.ensemble
        self._done = 0
        with one_thread(), ThreadPoolExecutor(2) as pool:
            trained = list(pool.map(lambda held: self._train([s for i, s in enumerate(sets) if i not in held],
                                                             total=total), folds))  # fmt: skip
        if recordings is not None:
            gains = np.array([self._open_loop_gain(nets, recordings[i]) for nets, held in zip(trained, folds,
                              strict=True) for i in held])  # fmt: skip
            self.held_back_gain_ = np.full(3, gains.mean())
            self.held_back_gain_se_ = np.full(3, sum_standard_error(gains) / len(gains))  # of the mean
            bar = recordings_threshold(self.guard_z, len(gains))  # their spread estimated from them
        else:
            per_fold = np.array([sum(_sse_gain(nets, sets[i]) for i in held) for nets, held in
                                 zip(trained, folds, strict=True)])  # fmt: skip
            self.held_back_gain_ = per_fold.sum(axis=0)
            self.held_back_gain_se_ = sum_standard_error(per_fold)
            bar = self.guard_z
        keep = self.held_back_gain_ > bar * self.held_back_gain_se_ if self.guard else np.ones(3, bool)
        self.axes_ = keep.astype(float)
        with one_thread():
            self.networks_ = self._train(sets, total=total) if keep.any() else []
        return self

    def _open_loop_gain(self, nets: list[dict[str, Array]], rec: ReferencedRecording) -> float:
        """How much the networks lower ``rec``'s open-loop attitude error (deg), the seed model's alone
        against the seed model's and theirs."""
        from sins.compensation import unit_bias

        seed = Regression.correct_increments(self, rec.imu)  # the seed model alone, not the window
        dt = np.diff(seed.t)
        error = _held_prediction(
            nets, seed.dtheta_b / dt[:, None], seed.dv_b / dt[:, None], float(np.median(dt))
        )
        with_net = ImuIncrements(t=seed.t, dtheta_b=seed.dtheta_b - error * dt[:, None], dv_b=seed.dv_b)
        return unit_bias.open_loop_deg(seed, rec) - unit_bias.open_loop_deg(with_net, rec)

    @property
    def window_axes(self) -> list[str]:
        """The gyro axes whose network passed the guard."""
        return [a for a, k in zip("xyz", getattr(self, "axes_", np.zeros(3)), strict=True) if k]

    def window_error(self, omega_ib_b: Array, f_ib_b: Array, dt: float) -> Array:
        """The gyro error (n, 3), rad/s, the networks predict in seed-corrected readings every ``dt`` s
        (held for :data:`STRIDE` readings; zero on axes the guard refused)."""
        nets = getattr(self, "networks_", [])
        if not nets:
            return np.zeros_like(omega_ib_b)
        return np.asarray(_held_prediction(nets, omega_ib_b, f_ib_b, dt) * self.axes_, dtype=float)

    def check_state(self, state: dict[str, Any]) -> None:
        """The seed model's arrays, then the networks': ``axes_`` (3,), ``networks_`` a list of at most
        ``ensemble`` flat weight dictionaries of the shapes ``hidden`` gives."""
        super().check_state(state)
        state_array(state, "axes_", (3,))
        nets = state.get("networks_", [])
        if not isinstance(nets, list) or len(nets) > self.ensemble:
            raise ValueError(f"state.networks_ must be a list of at most {self.ensemble} networks")
        for k, net in enumerate(nets):
            _check_flat(net, self.hidden, f"state.networks_[{k}]")

    def set_state(self, state: dict[str, Any]) -> None:
        """As the base does; the networks stay dictionaries of arrays."""
        nets = state.get("networks_", [])
        super().set_state({k: v for k, v in state.items() if k != "networks_"})
        self.networks_ = [{k: np.asarray(v, dtype=float) for k, v in net.items()} for net in nets]

    def get_state(self) -> dict[str, Any]:
        """As the base does, the networks' arrays as lists."""
        state = super().get_state()
        state["networks_"] = [{k: np.asarray(v).tolist() for k, v in net.items()} for net in self.networks_]
        return state

    # ------------------------------------------------------------------ training

    def _examples(self, data: CalibrationData) -> tuple[Array, Array]:
        """Inputs and targets of one recording's references: the window of the seed-corrected readings
        at every :data:`STRIDE`-th reading with a reference, and what the seed model leaves there."""
        omega, accel = self.correct(data.gyro, data.accel)
        dt = float(np.median(np.diff(data.t)))
        rows, x = window_inputs(omega, accel, dt)
        y = (omega - data.ref_gyro)[rows]
        ok = np.isfinite(y).all(axis=1)
        return x[ok], y[ok]

    def _train(self, sets: list[tuple[Array, Array]], *, total: int) -> list[dict[str, Array]]:
        """``ensemble`` networks on the examples of ``sets``, each from its own seed."""
        x = np.vstack([s[0] for s in sets])
        y = np.vstack([s[1] for s in sets])
        out = []
        for k in range(self.ensemble):
            out.append(_train_one(x, y, self.hidden, self.weight_decay, self.steps, self.seed + k))
            self._done += 1
            if self.progress is not None:
                self.progress(self._done, total)
        return out


def _sse_gain(nets: list[dict[str, Array]], examples: tuple[Array, Array]) -> Array:
    """Per gyro axis, how much the networks lower the squared error of held-back ``examples``."""
    x, y = examples
    pred = _mean_prediction(nets, x)
    return np.asarray(np.sum(y * y, axis=0) - np.sum((y - pred) ** 2, axis=0), dtype=float)


def window_inputs(omega_ib_b: Array, f_ib_b: Array, dt: float) -> tuple[NDArray[np.intp], Array]:
    """The rows every :data:`STRIDE` readings and their inputs (rows, :data:`FEATURES`): for each block
    of :data:`EDGES_S` before the row (the row itself not in it), the mean rate, the mean specific force,
    and the RMS spread of each about its mean (summed over the axes). A block reaching before the first
    reading holds what the recording has; an empty one (the first rows) repeats the first reading."""
    n = len(omega_ib_b)
    both = np.hstack([omega_ib_b, f_ib_b, omega_ib_b**2, f_ib_b**2])
    sums = np.vstack([np.zeros((1, 12)), np.nancumsum(both, axis=0)])
    rows = np.arange(0, n, STRIDE)
    out = np.empty((len(rows), FEATURES))
    for k, (near, far) in enumerate(itertools.pairwise(EDGES_S)):
        hi = np.maximum(rows - round(near / dt), 0)
        lo = np.maximum(rows - round(far / dt), 0)
        count = (hi - lo)[:, None]
        mean = np.where(count > 0, (sums[hi] - sums[lo]) / np.maximum(count, 1), both[0])
        w, f = mean[:, :3], mean[:, 3:6]
        spread_w = np.sqrt(np.maximum(mean[:, 6:9] - w * w, 0.0).sum(axis=1))
        spread_f = np.sqrt(np.maximum(mean[:, 9:12] - f * f, 0.0).sum(axis=1))
        out[:, k * PER_BLOCK : (k + 1) * PER_BLOCK] = np.column_stack([w, f, spread_w, spread_f])
    return rows, out


def _folds(n: int) -> list[list[int]]:
    """Recordings held back together: each alone up to :data:`MAX_FOLDS`, else dealt in turn."""
    k = min(n, MAX_FOLDS)
    return [list(range(i, n, k)) for i in range(k)]


def _train_one(
    x: Array, y: Array, hidden: tuple[int, ...], decay: float, steps: int, seed: int
) -> dict[str, Array]:
    """One tanh network, inputs and targets standardised, Adam with weight decay, full batch."""
    import torch

    x_mean, x_scale = x.mean(axis=0), np.where(x.std(axis=0) > 0, x.std(axis=0), 1.0)
    y_scale = np.where(y.std(axis=0) > 0, y.std(axis=0), 1.0)
    with seeded(seed):
        net = _network(x.shape[1], hidden)
    xt = torch.from_numpy(((x - x_mean) / x_scale).astype(np.float32))
    yt = torch.from_numpy((y / y_scale).astype(np.float32))
    opt = torch.optim.Adam(net.parameters(), lr=3e-3, weight_decay=decay)
    for _ in range(steps):
        opt.zero_grad()
        loss = ((net(xt) - yt) ** 2).mean()
        loss.backward()
        opt.step()
    flat = {f"p{i}": p.detach().numpy().astype(float).copy() for i, p in enumerate(net.parameters())}
    return {**flat, "x_mean": x_mean, "x_scale": x_scale, "y_scale": y_scale}


def _network(n_in: int, hidden: tuple[int, ...]) -> Any:
    import torch
    from torch import nn

    layers: list[Any] = []
    width = n_in
    for h in hidden:
        layers += [nn.Linear(width, h), nn.Tanh()]
        width = h
    layers.append(nn.Linear(width, 3))
    return nn.Sequential(*layers).to(torch.float32)


def _held_prediction(nets: list[dict[str, Array]], omega_ib_b: Array, f_ib_b: Array, dt: float) -> Array:
    """The networks' mean gyro error (n, 3) at every reading: predicted every :data:`STRIDE` readings from
    the window before, and held until the next."""
    rows, x = window_inputs(omega_ib_b, f_ib_b, dt)
    held = np.repeat(np.arange(len(rows)), np.diff(np.r_[rows, len(omega_ib_b)]))
    return _mean_prediction(nets, x)[held]


def _mean_prediction(nets: list[dict[str, Array]], x: Array) -> Array:
    """The networks' mean prediction on inputs ``x`` (numpy: a forward pass needs no torch)."""
    out = np.zeros((len(x), 3))
    for net in nets:
        h = (x - net["x_mean"]) / net["x_scale"]
        layers = (len([k for k in net if k.startswith("p")])) // 2
        for i in range(layers):
            h = h @ net[f"p{2 * i}"].T + net[f"p{2 * i + 1}"]
            if i < layers - 1:
                h = np.tanh(h)
        out += h * net["y_scale"]
    return out / max(len(nets), 1)


def _check_flat(net: Any, hidden: tuple[int, ...], where: str) -> None:
    """A saved network's arrays against the shapes ``hidden`` gives (before any is used)."""
    if not isinstance(net, dict):
        raise ValueError(f"{where} is not an object")
    sizes = [FEATURES, *hidden, 3]
    want: dict[str, tuple[int, ...]] = {"x_mean": (FEATURES,), "x_scale": (FEATURES,), "y_scale": (3,)}
    for i in range(len(sizes) - 1):
        want[f"p{2 * i}"] = (sizes[i + 1], sizes[i])
        want[f"p{2 * i + 1}"] = (sizes[i + 1],)
    if set(net) != set(want):
        raise ValueError(f"{where} holds {sorted(net)}; expected {sorted(want)}")
    for key, shape in want.items():
        checked_array(net[key], shape, f"{where}.{key}")


__all__ = [
    "EDGES_S",
    "FEATURES",
    "HOLD_LAST",
    "MAX_FOLDS",
    "MAX_LAYERS",
    "MAX_WIDTH",
    "PER_BLOCK",
    "STRIDE",
    "WindowNet",
    "window_inputs",
]
