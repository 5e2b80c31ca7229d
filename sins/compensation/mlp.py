"""Feed-forward network strategies (torch): ``mlp`` learns what regression leaves; ``mlp_pure`` is the
seed paper's network from readings to errors.

``mlp`` (:class:`ResidualMLP`) is the one to pick: the seed model's least-squares
fit first, then a small tanh network of the residual over the reference inputs,
its size, weight decay and training length chosen by cross-validation over
held-back blocks, and a per-channel guard that keeps regression's correction
where the network does not earn its place (:mod:`sins.compensation.residual`).

``mlp_pure`` and ``mlp_seed`` (:class:`MLP`) keep the seed paper's question
askable. Inputs are the six readings (and the temperature when the calibration
data has it); outputs are the six errors, reading − reference. Training uses the
readings as inputs because in operation only readings exist; the correction
is ``reading − predicted error``.

Two training modes:

* ``"seed"``: the seed paper's network. Every neuron is a sigmoid
  ``1/(1+exp(−a(x−c)))`` (gain ``a``, learnable centre ``c``), trained by
  back-propagation pattern by pattern with learning rate ``alpha`` until the
  summed squared error ``ε = ½ΣΣ(a−t)²`` per pattern falls below
  ``residual`` (or ``max_epochs`` pass); targets are scaled into the sigmoid's
  range [0.1, 0.9].
* ``"modern"``: the same topology with a linear output layer, inputs and
  outputs standardised, Adam on mini-batches, and early stopping on the last
  ``validation`` fraction of every calibration phase.
"""

from __future__ import annotations

import operator
import threading
from collections.abc import Callable, Generator, Iterator
from contextlib import contextmanager
from typing import Any, ClassVar

import numba
import numpy as np
from numpy.typing import NDArray

from sins.compensation.base import SEED_RANGE, ParamRange, Strategy, checked_array, state_array
from sins.compensation.points import Points
from sins.compensation.residual import ResidualStrategy
from sins.core.series import CalibrationData
from sins.imu import calibration

Array = NDArray[np.float64]


#: The largest network a model may hold: layers, and neurons a layer. Eight times the widest the
#: registry's variants fit (32), and twice as deep; a network is evaluated on a recording's rows at once,
#: so its width sets the memory a correction takes (an hour at 100 Hz: 0.7 GB a layer of 256).
MAX_LAYERS, MAX_WIDTH = 4, 256
#: ``mlp_pure``'s ways of training (the module docstring).
MODES = ("modern", "seed")


def check_hidden(
    hidden: Any, where: str, layers: int = MAX_LAYERS, width: int = MAX_WIDTH
) -> tuple[int, ...]:
    """``hidden`` as layer sizes, 1 to ``layers`` layers of 1 to ``width`` neurons (by default
    :data:`MAX_LAYERS`, :data:`MAX_WIDTH`; ``mlp_window`` bounds its own); else ``ValueError`` naming
    ``where``. What a model file may give, and what :meth:`MLP.fit` takes."""
    sizes = [_whole(h) for h in hidden] if isinstance(hidden, list | tuple) else []
    if not 1 <= len(sizes) <= layers or not all(h is not None and 1 <= h <= width for h in sizes):
        raise ValueError(
            f"{where} must be 1 to {layers} layer sizes, each a whole number from 1 to {width}; "
            f"got {str(hidden)[:60]}"
        )
    return tuple(h for h in sizes if h is not None)


def _whole(value: Any) -> int | None:
    """``value`` as an int if it is of a whole number type (numpy's too), else None; a boolean is not."""
    if isinstance(value, bool):
        return None
    try:
        return operator.index(value)
    except TypeError:
        return None


def _check_weights(weights: Any, shapes: list[tuple[int, ...]], where: str) -> None:
    """``weights``: one nested list of each of ``shapes``, in order (a network's parameters)."""
    if not isinstance(weights, list) or len(weights) != len(shapes):
        raise ValueError(f"{where} must be {len(shapes)} arrays, one per parameter of the network")
    for i, shape in enumerate(shapes):
        checked_array(weights[i], shape, f"{where}[{i}]")


def _features(gyro: Array, accel: Array, temp: Array | None) -> Array:
    parts = [gyro, accel] + ([] if temp is None else [np.asarray(temp, dtype=float)[:, None]])
    return np.hstack(parts)


class MLP(Strategy):
    """The seed paper's network from readings to errors, ``mlp_pure`` and ``mlp_seed`` (module docstring).

    Parameters
    ----------
    hidden : hidden layer sizes
    mode : "modern" or "seed"
    alpha : learning rate (per pattern in "seed" mode, Adam's in "modern")
    gain : the sigmoid's slope ``a`` ("seed" mode)
    residual : stop when the mean per-pattern ``ε`` falls below this ("seed" mode, scaled units)
    max_epochs, batch_size, patience, validation : "modern" mode's training loop
    seed : initial weights and shuffling
    """

    name = "mlp_pure"
    state_keys = (*Strategy.state_keys, "accel_seed_", "gyro_seed_", "uses_temp_", "x_mean_", "x_scale_",
                  "y_mean_", "y_scale_", "epochs_", "final_error_", "weights_")  # fmt: skip
    #: ``validation`` a share of the rows: none or all of them leaves nothing to train or to stop by.
    param_ranges: ClassVar[dict[str, ParamRange]] = {
        "hidden": ParamRange(1, MAX_WIDTH, whole=True),
        "alpha": ParamRange(0, 10, above=True),
        "gain": ParamRange(0, 100, above=True),
        "residual": ParamRange(0, 1e6),
        "max_epochs": ParamRange(1, 100_000, whole=True),
        "batch_size": ParamRange(1, 10**8, whole=True),
        "patience": ParamRange(1, 100_000, whole=True),
        "validation": ParamRange(0, 0.9, above=True),
        "seed": SEED_RANGE,
    }

    def __init__(
        self,
        hidden: tuple[int, ...] = (32, 32),
        mode: str = "modern",
        alpha: float = 3e-3,
        gain: float = 1.0,
        residual: float = 1e-5,
        max_epochs: int = 200,
        batch_size: int = 512,
        patience: int = 10,
        validation: float = 0.2,
        seed: int = 0,
    ) -> None:
        # Kept as given (scikit-learn's rule); check_params holds them, for make, fit, save and load alike.
        self.hidden = hidden
        self.mode = mode
        self.alpha = alpha
        self.gain = gain
        self.residual = residual
        self.max_epochs = max_epochs
        self.batch_size = batch_size
        self.patience = patience
        self.validation = validation
        self.seed = seed
        #: Called as ``progress(epochs_done, max_epochs)`` after each epoch (a progress bar's); not saved.
        self.progress: Callable[[int, int], None] | None = None

    def kind(self) -> str:
        """``mlp_seed`` where trained as the seed paper does (``mode="seed"``)."""
        return "mlp_seed" if self.mode == "seed" else self.name

    def check_params(self) -> None:
        """As every strategy's (:meth:`Strategy.check_params`), and ``mode`` one of :data:`MODES`,
        ``hidden`` within :func:`check_hidden`'s bounds: set after the constructor, a ``mode`` of "paper"
        had trained a network of neither kind and saved a file its own loader refused."""
        super().check_params()
        if self.mode not in MODES:
            raise ValueError(f"{self.label}: mode is {self.mode!r}, expected one of {', '.join(MODES)}")
        check_hidden(self.hidden, f"{self.label}: hidden")

    def _network(self, n_in: int) -> Any:
        import torch
        from torch import nn

        Sigmoid = _sigmoid()
        layers: list[nn.Module] = []
        width = n_in
        for h in self.hidden:
            layers += [nn.Linear(width, h, bias=False, dtype=torch.float64), Sigmoid(h, self.gain)]
            width = h
        layers.append(nn.Linear(width, 6, bias=self.mode == "modern", dtype=torch.float64))
        if self.mode == "seed":
            layers.append(Sigmoid(6, self.gain))
        return nn.Sequential(*layers)

    # ------------------------------------------------------------------ fit

    def fit(self, data: CalibrationData) -> MLP:
        """Train the network from readings (and temperature) to errors in ``mode``; returns self."""
        import torch

        data.check_readings()
        self._net = None  # an earlier fit's network is not this one's, whether or not this one ends
        calibration.fit_seed_model(data)  # rows that do not determine a linear model teach no network
        ok = data.has_reference
        if ok.sum() < 10:
            raise ValueError(f"{data.source or 'recording'}: too few rows with a reference to train on")
        self.uses_temp_ = data.temp is not None
        x = _features(data.gyro, data.accel, data.temp)[ok]
        y = np.hstack([data.gyro - data.ref_gyro, data.accel - data.ref_accel])[ok]
        self.x_mean_, self.x_scale_ = x.mean(axis=0), np.where(x.std(axis=0) > 0, x.std(axis=0), 1.0)
        if self.mode == "seed":
            # Min-max into [0.1, 0.9], the sigmoid's useful range.
            lo, hi = y.min(axis=0), y.max(axis=0)
            self.y_mean_ = lo - 0.125 * (hi - lo)
            self.y_scale_ = np.where(hi > lo, 1.25 * (hi - lo), 1.0)
        else:
            self.y_mean_, self.y_scale_ = y.mean(axis=0), np.where(y.std(axis=0) > 0, y.std(axis=0), 1.0)
        xs = torch.from_numpy((x - self.x_mean_) / self.x_scale_)
        ys = torch.from_numpy((y - self.y_mean_) / self.y_scale_)
        with seeded(self.seed):
            net = self._network(xs.shape[1])
        if self.mode == "seed":
            self.epochs_, self.final_error_ = self._train_seed(net, xs, ys)
        else:
            rows = np.flatnonzero(ok)
            held = np.zeros(len(data), dtype=bool)
            if data.phases:
                _, val_part = data.split(self.validation)
                held[np.searchsorted(data.t, val_part.t)] = True
            else:
                held[int(len(data) * (1 - self.validation)) :] = True
            val_mask = torch.from_numpy(held[rows])
            with one_thread():  # see one_thread; 2 threads took 25x the CPU time on a busy machine
                self.epochs_, self.final_error_ = self._train_modern(net, xs, ys, val_mask)
        self.weights_ = [p.detach().numpy().copy() for p in net.parameters()]
        self._net = net
        return self

    def _train_seed(self, net: Any, xs: Any, ys: Any) -> tuple[int, float]:
        """Back-propagation pattern by pattern (plain SGD at ``alpha`` on each pattern's ``ε``), in the
        patterns' order torch's generator deals each epoch. The steps are compiled (:func:`_seed_epoch`):
        autograd's cost per pattern outweighs a network this small (``docs/speed.md``, "Fitting
        compensation")."""
        import torch

        params = list(net.parameters())
        flat = np.concatenate([p.detach().numpy().ravel() for p in params])
        weights = params[0::2]  # each layer's weights, then its sigmoids' centres
        shapes = np.array([w.shape for w in weights], dtype=np.int64)
        x, t = np.ascontiguousarray(xs.numpy()), np.ascontiguousarray(ys.numpy())
        gen = torch.Generator().manual_seed(self.seed)
        epsilon = float("inf")
        epochs = 0
        while epochs < self.max_epochs:
            epochs += 1
            order = torch.randperm(len(xs), generator=gen).numpy().astype(np.int64)
            epsilon = _seed_epoch(flat, shapes, x, t, order, float(self.gain), float(self.alpha)) / len(xs)
            if self.progress is not None:
                self.progress(epochs, self.max_epochs)
            if epsilon < self.residual:
                break
        with torch.no_grad():
            at = 0
            for p in params:
                p.copy_(torch.from_numpy(flat[at : at + p.numel()].reshape(p.shape)))
                at += p.numel()
        return epochs, epsilon

    def _train_modern(self, net: Any, xs: Any, ys: Any, val_mask: Any) -> tuple[int, float]:
        import torch

        train_x, train_y = xs[~val_mask], ys[~val_mask]
        val_x, val_y = xs[val_mask], ys[val_mask]
        if len(val_x) == 0:
            val_x, val_y = train_x, train_y
        optimiser = torch.optim.Adam(net.parameters(), lr=self.alpha)
        gen = torch.Generator().manual_seed(self.seed)
        best, best_state, stale, epochs = float("inf"), None, 0, 0
        while epochs < self.max_epochs:
            epochs += 1
            order = torch.randperm(len(train_x), generator=gen)
            for start in range(0, len(order), self.batch_size):
                batch = order[start : start + self.batch_size]
                optimiser.zero_grad()
                loss = ((net(train_x[batch]) - train_y[batch]) ** 2).mean()
                loss.backward()
                optimiser.step()
            if self.progress is not None:
                self.progress(epochs, self.max_epochs)
            with torch.no_grad():
                val = float(((net(val_x) - val_y) ** 2).mean())
            if val < best * (1.0 - 1e-4):
                best, stale = val, 0
                best_state = {k: v.clone() for k, v in net.state_dict().items()}
            else:
                stale += 1
                if stale >= self.patience:
                    break
        if best_state is not None:
            net.load_state_dict(best_state)
        return epochs, best

    # ------------------------------------------------------------------ use

    def _restore(self) -> Any:
        import torch

        net = getattr(self, "_net", None)
        if net is None:
            net = self._network(len(self.x_mean_))
            with torch.no_grad():
                for p, w in zip(net.parameters(), self.weights_, strict=True):
                    p.copy_(torch.from_numpy(np.asarray(w, dtype=float)).reshape(p.shape))
            self._net = net
        return net

    def correct(self, gyro: Array, accel: Array, temp: Array | None = None) -> tuple[Array, Array]:
        """Subtract the network's predicted error (needs ``temp`` if trained with temperature)."""
        import torch

        if self.uses_temp_ and temp is None:
            raise ValueError("this mlp was trained with temperature: give the temperature series")
        x = _features(gyro, accel, temp if self.uses_temp_ else None)
        with torch.no_grad():
            out = self._restore()(torch.from_numpy((x - self.x_mean_) / self.x_scale_)).numpy()
        err = out * self.y_scale_ + self.y_mean_
        return gyro - err[:, :3], accel - err[:, 3:]

    def get_state(self) -> dict[str, Any]:
        """The fitted state, the network's weights as nested lists."""
        state = {k: v for k, v in super().get_state().items() if k != "weights_"}
        state["weights_"] = [np.asarray(w).tolist() for w in self.weights_]
        return state

    def check_state(self, state: dict[str, Any]) -> None:
        """The topology within :func:`check_hidden`'s bounds, and every array of the state the shape the
        network of ``hidden`` has: scales of its inputs (6, with the temperature 7) and outputs (6), and
        ``weights_`` layer by layer as :meth:`_network` orders its parameters. Nothing is built."""
        super().check_state(state)
        check_hidden(self.hidden, "params.hidden")
        uses_temp = state.get("uses_temp_", False)
        if not isinstance(uses_temp, bool):
            raise ValueError("state.uses_temp_ must be true or false")
        n_in = 6 + uses_temp
        for key, size in (("x_mean_", n_in), ("x_scale_", n_in), ("y_mean_", 6), ("y_scale_", 6)):
            state_array(state, key, (size,))
        if not (np.abs(state_array(state, "x_scale_", (n_in,))) > 0).all():
            raise ValueError("state.x_scale_ holds a zero (the inputs are divided by it)")
        shapes: list[tuple[int, ...]] = []
        width = n_in
        for h in self.hidden:
            shapes += [(h, width), (h,)]  # a layer's weights (no bias), its sigmoids' centres
            width = h
        shapes += [(6, width), (6,)]  # the output layer's weights; its bias ("modern") or centres ("seed")
        _check_weights(state.get("weights_"), shapes, "state.weights_")

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore the state and weights; the network is rebuilt on first use."""
        weights = state.get("weights_", [])
        super().set_state({k: v for k, v in state.items() if k != "weights_"})
        self.weights_ = [np.asarray(w, dtype=float) for w in weights]
        self.uses_temp_ = bool(state.get("uses_temp_", False))
        self._net = None


@numba.njit(cache=True)
def _seed_epoch(
    flat: Array, shapes: NDArray[np.int64], x: Array, t: Array, order: NDArray[np.int64], gain: float,
    alpha: float,
) -> float:  # fmt: skip
    """One epoch of ``mlp_seed``'s training, in place on the parameters ``flat`` (each layer's weights
    (out, in) row-major, then its sigmoids' centres (out)); layer ``l`` is ``a = σ(gain (W a_prev − c))``.
    For each pattern of ``order``: forward, ``ε = ½ Σ (a − t)²``, its gradient back through the layers
    (each layer's input gradient taken before its weights move, as autograd does), and ``p -= alpha ∂ε/∂p``.
    Returns Σ ε over the patterns (each before its own step)."""
    layers = shapes.shape[0]
    width = max(int(shapes[:, 0].max()), x.shape[1])
    offsets = np.zeros(layers, dtype=np.int64)
    for k in range(1, layers):
        offsets[k] = offsets[k - 1] + shapes[k - 1, 0] * shapes[k - 1, 1] + shapes[k - 1, 0]
    act = np.zeros((layers + 1, width))
    grad, below = np.zeros(width), np.zeros(width)
    total = 0.0
    for i in order:
        act[0, : x.shape[1]] = x[i]
        for k in range(layers):
            n_out, n_in, at = shapes[k, 0], shapes[k, 1], offsets[k]
            for r in range(n_out):
                z = 0.0
                for j in range(n_in):
                    z += flat[at + r * n_in + j] * act[k, j]
                act[k + 1, r] = 1.0 / (1.0 + np.exp(-gain * (z - flat[at + n_out * n_in + r])))
        for r in range(t.shape[1]):
            d = act[layers, r] - t[i, r]
            total += 0.5 * d * d
            grad[r] = d
        for k in range(layers - 1, -1, -1):
            n_out, n_in, at = shapes[k, 0], shapes[k, 1], offsets[k]
            for r in range(n_out):
                a = act[k + 1, r]
                grad[r] *= gain * a * (1.0 - a)  # ∂ε/∂z of this layer's sums
            for j in range(n_in):
                below[j] = 0.0
                for r in range(n_out):
                    below[j] += flat[at + r * n_in + j] * grad[r]
            for r in range(n_out):
                for j in range(n_in):
                    flat[at + r * n_in + j] -= alpha * grad[r] * act[k, j]
                flat[at + n_out * n_in + r] += alpha * grad[r]  # ∂ε/∂c = −∂ε/∂z
            grad[:n_in] = below[:n_in]
    return total


# --------------------------------------------------------------------------- physics first


#: Training lengths (L-BFGS iterations) whose held-back scores are compared.
CHECKPOINTS = (25, 50, 100, 200, 400)


class ResidualMLP(ResidualStrategy):
    """``mlp``: regression, then a tanh network of its residual (see the module docstring).

    Candidates: hidden layers ``hidden_sizes`` × weight decay ``decays``, each trained
    by full-batch L-BFGS on the averaged points and scored after each length of
    :data:`CHECKPOINTS` until two lengths in a row have not lowered its held-back
    loss (:data:`~sins.compensation.residual.PATIENCE`); the best on the held-back
    blocks is retrained on all data.
    The output layer starts at zero, so an untrained network is regression.
    """

    name = "mlp"
    param_ranges: ClassVar[dict[str, ParamRange]] = {
        **ResidualStrategy.param_ranges,
        "decays": ParamRange(0, 10),
    }

    def __init__(
        self,
        hidden_sizes: tuple[tuple[int, ...], ...] = ((16, 16), (32, 32)),
        decays: tuple[float, ...] = (1e-6, 1e-4),
        folds: int = 3,
        guard: bool = True,
        guard_z: float = 2.0,
        seed: int = 0,
        n_jobs: int | None = None,
        physics: bool = True,
    ) -> None:
        super().__init__(folds=folds, guard=guard, guard_z=guard_z, seed=seed, n_jobs=n_jobs, physics=physics)
        self.hidden_sizes = hidden_sizes  # kept as given; check_params holds them
        self.decays = decays

    def check_params(self) -> None:
        """As every strategy's, and ``hidden_sizes`` one or more candidates, each a list of layer sizes
        within :func:`check_hidden`'s bounds: ``[]`` had failed in fit ("no fold could be fitted"), and
        ``[16]`` (one candidate's sizes, not a list of them) in Python's words."""
        super().check_params()
        grid = self.hidden_sizes
        if not (isinstance(grid, list | tuple) and grid and all(isinstance(h, list | tuple) for h in grid)):
            raise ValueError(
                f"{self.label}: hidden_sizes is {str(grid)[:60]}, expected one or more candidates, each a "
                "list of layer sizes ([[16]]: one network of 16)"
            )
        self._hidden_grid()

    def _hidden_grid(self) -> list[tuple[int, ...]]:
        """The candidates of ``hidden_sizes``, each as :func:`check_hidden` gives it."""
        return [check_hidden(h, f"{self.label}: hidden_sizes") for h in self.hidden_sizes]

    def _candidates(self, sensor: str, n_inputs: int) -> list[dict[str, Any]]:
        decays = [float(d) for d in self.decays]
        return [{"hidden": list(h), "decay": d} for h in self._hidden_grid() for d in decays]

    def _train(self, config: dict[str, Any], points: Points, sigma: Array, seed: int) -> Any:
        snapshots = dict(self._lbfgs(config, points, sigma, seed))
        return {"hidden": list(config["hidden"]), "sigma": sigma.tolist(), "snapshots": snapshots}

    def _stages(
        self, config: dict[str, Any], points: Points, sigma: Array, seed: int
    ) -> Generator[list[tuple[dict[str, Any], Any]], None, None]:
        """One stage per training length of :data:`CHECKPOINTS`: the network as it stands there."""
        base = {k: v for k, v in config.items() if k != "iterations"}
        for length, weights in self._lbfgs(config, points, sigma, seed):
            yield [({**base, "iterations": length}, _NetLearner(config["hidden"], sigma.tolist(), weights))]

    def _lbfgs(
        self, config: dict[str, Any], points: Points, sigma: Array, seed: int
    ) -> Generator[tuple[int, list[Array]], None, None]:
        """Full-batch L-BFGS on ``points`` on one torch thread, yielding the weights at each training
        length (``config``'s ``iterations`` alone where it has them, else every one of
        :data:`CHECKPOINTS`); training goes on from where the last length left it."""
        import torch

        with one_thread():
            with seeded(seed):
                net = _tanh_network(points.x.shape[1], tuple(config["hidden"]))
            x = torch.from_numpy(points.x)
            y = torch.from_numpy(points.y / sigma)
            w = torch.from_numpy(points.n / points.n.sum())[:, None]
            weights = [p for name, p in net.named_parameters() if name.endswith("weight")]
            decay = config["decay"]
            optimiser = torch.optim.LBFGS(
                net.parameters(), lr=1.0, max_iter=CHECKPOINTS[0], history_size=20,
                tolerance_grad=1e-12, tolerance_change=1e-15, line_search_fn="strong_wolfe",
            )  # fmt: skip

            def closure() -> Any:
                optimiser.zero_grad()
                loss = (w * (net(x) - y) ** 2).sum() + decay * sum((p * p).sum() for p in weights)
                loss.backward()
                return loss

            lengths = [config["iterations"]] if "iterations" in config else list(CHECKPOINTS)
            done = 0
            for length in lengths:
                optimiser.param_groups[0]["max_iter"] = length - done
                optimiser.param_groups[0]["max_eval"] = int(1.25 * (length - done))
                optimiser.step(closure)
                done = length
                yield length, [p.detach().numpy().copy() for p in net.parameters()]

    def _variants(self, config: dict[str, Any], learner: Any) -> list[tuple[dict[str, Any], Any]]:
        base = {k: v for k, v in config.items() if k != "iterations"}
        return [
            ({**base, "iterations": length}, _NetLearner(learner["hidden"], learner["sigma"], weights))
            for length, weights in learner["snapshots"].items()
        ]

    def _predict(self, learner: Any, x: Array, memo: dict[str, Any] | None = None) -> Array:
        return learner.predict(x)

    def _learner_state(self, learner: Any) -> Any:
        return {
            "hidden": list(learner.hidden),
            "sigma": list(learner.sigma),
            "weights": [np.asarray(w).tolist() for w in learner.weights],
        }

    def _check_learner(self, learner: Any, n_inputs: int, where: str) -> None:
        """A residual network: ``hidden`` one of :attr:`hidden_sizes` (what :meth:`fit` chooses among),
        ``sigma`` (3,), and ``weights`` of the shapes :func:`_tanh_network` gives them."""
        super()._check_learner(learner, n_inputs, where)
        hidden = check_hidden(learner.get("hidden"), f"{where}.hidden")
        if hidden not in self._hidden_grid():
            raise ValueError(f"{where}.hidden {list(hidden)} is none of the candidates, params.hidden_sizes")
        state_array(learner, "sigma", (3,), where)
        shapes: list[tuple[int, ...]] = []
        width = n_inputs
        for h in hidden:
            shapes += [(h, width), (h,)]
            width = h
        _check_weights(learner.get("weights"), [*shapes, (3, width), (3,)], f"{where}.weights")

    def _learner_from_state(self, state: Any) -> Any:
        return _NetLearner(
            state["hidden"], state["sigma"], [np.asarray(w, dtype=float) for w in state["weights"]]
        )


_INIT_LOCK = threading.Lock()


@contextmanager
def seeded(seed: int) -> Iterator[None]:
    """torch's global generator seeded at ``seed`` for a network's initial weights (its layers draw from
    it), and given back as it was afterwards: a fit leaves the caller's own torch stream where it stood.
    One network at a time (a lock): the generator is global to the process, threads share it."""
    import torch

    with _INIT_LOCK, torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        yield


_THREADS_LOCK = threading.Lock()
_one_thread_depth = 0
_threads_before = 0


@contextmanager
def one_thread() -> Iterator[None]:
    """Torch on one thread for the while: the residual networks are small (a thread is as fast), and a
    sum split over threads rounds differently, which L-BFGS's line search turns into another solution:
    the same fit gave 486 m and 614 m of drift on the quality suite on one and two threads. Nested and
    concurrent holders share one setting, restored when the last lets go (the cross-validation trains
    on several Python threads at once, each on one torch thread)."""
    import torch

    global _one_thread_depth, _threads_before
    with _THREADS_LOCK:
        if _one_thread_depth == 0:
            _threads_before = torch.get_num_threads()
        torch.set_num_threads(1)  # again in each holder's thread: OpenMP keeps the count per thread
        _one_thread_depth += 1
    try:
        yield
    finally:
        with _THREADS_LOCK:
            _one_thread_depth -= 1
            if _one_thread_depth == 0:
                torch.set_num_threads(_threads_before)


def _tanh_network(n_in: int, hidden: tuple[int, ...]) -> Any:
    import torch
    from torch import nn

    layers: list[nn.Module] = []
    width = n_in
    for h in hidden:
        layers += [nn.Linear(width, h, dtype=torch.float64), nn.Tanh()]
        width = h
    out = nn.Linear(width, 3, dtype=torch.float64)
    nn.init.zeros_(out.weight)
    nn.init.zeros_(out.bias)
    return nn.Sequential(*layers, out)


#: Rows a trained network is evaluated on at a time: a layer's activations of 8,192 rows (1 MB at 16
#: units) stay in a core's cache. Two correction threads on 65,536-row blocks had each other's
#: activations fighting for memory (1.38 s a million readings against 0.94 s, the same threads).
_PREDICT_ROWS = 8_192


class _NetLearner:
    """A trained residual network: its layers' weights and the output scale (σ per channel).

    Evaluated with numpy, not torch: ``tanh(x Wᵀ + b)`` layer by layer, then the linear output. The same
    network to rounding (numpy's ``tanh`` and OpenBLAS's products against torch's: within 3e-15 of the
    largest output on EuRoC's networks, the median row within two units in its last place), three times
    as fast in its ``tanh``, and a correction never imports torch (``docs/speed.md``, "Correcting a
    recording")."""

    def __init__(self, hidden: list[int], sigma: list[float], weights: list[Array]) -> None:
        self.hidden = [int(h) for h in hidden]
        self.sigma = np.asarray(sigma, dtype=float)
        self.weights = weights
        pairs = [np.asarray(w, dtype=float) for w in weights]
        # Each layer's weight (out, in) as torch's Linear keeps it, held transposed for ``x @ Wᵀ``.
        self._layers = [
            (np.ascontiguousarray(pairs[i].reshape(pairs[i + 1].size, -1).T), pairs[i + 1].ravel())
            for i in range(0, len(pairs), 2)
        ]

    def predict(self, x: Array) -> Array:
        """The network's residual at ``x`` (n, inputs), :data:`_PREDICT_ROWS` rows at a time."""
        x = np.ascontiguousarray(x, dtype=float)
        out = np.empty((len(x), 3))
        for lo in range(0, len(x), _PREDICT_ROWS):
            h = x[lo : lo + _PREDICT_ROWS]
            for w_t, b in self._layers[:-1]:
                h = np.tanh(h @ w_t + b)
            w_t, b = self._layers[-1]
            out[lo : lo + _PREDICT_ROWS] = h @ w_t + b
        scaled: Array = out * self.sigma
        return scaled


_SIGMOID: Any = None


def _sigmoid() -> Any:
    """The seed network's neuron, ``1/(1+exp(−a(x−c)))`` with a learnable centre per neuron: a torch
    module made once, on first use (torch is imported only by the learned strategies), and reachable as
    this module's ``Sigmoid`` (:func:`__getattr__`) so that a fitted network pickles and unpickles."""
    global _SIGMOID
    if _SIGMOID is None:
        import torch
        from torch import nn

        class Sigmoid(nn.Module):
            def __init__(self, width: int, gain: float) -> None:
                super().__init__()
                self.gain = gain
                self.centre = nn.Parameter(torch.zeros(width, dtype=torch.float64))

            def forward(self, x: torch.Tensor) -> torch.Tensor:
                return torch.sigmoid(self.gain * (x - self.centre))

        Sigmoid.__qualname__ = "Sigmoid"
        _SIGMOID = Sigmoid
    return _SIGMOID


def __getattr__(name: str) -> Any:
    if name == "Sigmoid":  # made on first use (see _sigmoid): what pickle looks up
        return _sigmoid()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "CHECKPOINTS",
    "MAX_LAYERS",
    "MAX_WIDTH",
    "MLP",
    "MODES",
    "ResidualMLP",
    "check_hidden",
    "one_thread",
    "seeded",
]
