"""``kohonen``: what regression leaves, learned with a self-organising local linear map (the seed paper's
map from readings to errors, ``kohonen_pure``, is :mod:`sins.compensation.kohonen_pure`).

``kohonen`` (:class:`LocalLinearMap`) is the one to pick: the seed model's
least-squares fit first, then the self-organising local linear map of Ritter,
Martinetz and Schulten over the reference inputs (:mod:`sins.compensation.residual`). Each
node ``j`` has a prototype ``c_j`` and a local linear model ``a_j + B_j (x − c_j)``
of the residual; a prediction blends the models of the winner's lattice
neighbourhood, ``Σ_j h_j (a_j + B_j (x − c_j)) / Σ_j h_j`` with
``h_j = exp(−|g_j − g_win|² / 2σ²)`` on the lattice, so it interpolates where a
node that stores one mean is a staircase. The prototypes are placed by
Kohonen's batch map (vectorised here: minisom's batch mode loops over the
samples in Python). With the prototypes and σ fixed the prediction is linear in
the ``a_j`` and ``B_j``, so they are solved for jointly by weighted least
squares, with a penalty that makes lattice neighbours' models agree (the map's
cooperation: nodes no data reached inherit their neighbours' planes) and a
small ridge. Map size and σ are chosen on held-back blocks.

"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any, ClassVar

import numba
import numpy as np
from numpy.typing import NDArray

from sins.compensation.base import ParamRange, state_array
from sins.compensation.points import Points
from sins.compensation.residual import ResidualStrategy

Array = NDArray[np.float64]


#: The largest map a model may hold: nodes a side (the registry's fits use 20 for ``kohonen_pure``, at
#: most 12 for ``kohonen``). A correction compares every reading with every node, a block of 65,536 rows
#: at a time: a 32 × 32 map holds that at 0.5 GB.
MAX_SIDE = 32


# --------------------------------------------------------------------------- physics first


class LocalLinearMap(ResidualStrategy):
    """``kohonen``: regression, then self-organising local linear maps of its residual (module docstring).

    The gyros' residual is the sum of a map over ``(ω, T)`` and a map over ``(f, T)``,
    the accelerometers' one map over ``(f, T)``: the library's errors are functions of
    the rate or of the specific force (and temperature), and a map of all seven
    inputs at once must place its nodes in a space a rig covers only along a few
    lines, where a plane's slope across them is set by chance. The maps' planes are
    solved for together. Candidates: square maps of ``sizes`` nodes a side ×
    lattice neighbourhoods ``sigmas``.
    """

    name = "kohonen"
    param_ranges: ClassVar[dict[str, ParamRange]] = {
        **ResidualStrategy.param_ranges,
        "sizes": ParamRange(1, MAX_SIDE, whole=True),
        "sigmas": ParamRange(0, 100, above=True),
        "smoothing": ParamRange(0, 1e6),
        "slope_ridge": ParamRange(0, 1e6),
        "som_iterations": ParamRange(1, 100_000, whole=True),
    }

    def __init__(
        self,
        sizes: tuple[int, ...] = (5, 8, 12),
        sigmas: tuple[float, ...] = (0.7, 1.2),
        smoothing: float = 1e-2,
        slope_ridge: float = 1e-5,
        som_iterations: int = 30,
        folds: int = 3,
        guard: bool = True,
        guard_z: float = 2.0,
        seed: int = 0,
        n_jobs: int | None = None,
        physics: bool = True,
    ) -> None:
        super().__init__(folds=folds, guard=guard, guard_z=guard_z, seed=seed, n_jobs=n_jobs, physics=physics)
        self.sizes = sizes  # kept as given; check_params holds them
        self.sigmas = sigmas
        self.smoothing = smoothing
        self.slope_ridge = slope_ridge
        self.som_iterations = som_iterations

    def _candidates(self, sensor: str, n_inputs: int) -> list[dict[str, Any]]:
        return [{"size": int(n)} for n in self.sizes]

    @staticmethod
    def _groups(n_inputs: int) -> list[tuple[list[int], list[int]]]:
        """Each map's ``(winner columns, plane columns)``: gyro inputs ``[ω, f(, T)]``, accel ``[f(, T)]``.

        For the gyros, a chain over the rate about each axis (a scale factor's curve is a function
        of its own axis's rate; a map over the three rates at once would have to extrapolate from the
        few axes a table turns about to every direction a vehicle turns in); for both sensors a sheet
        over the specific force (g² sensitivity, a scale factor's curve in force), and a chain over
        temperature whose planes also slope in rate and force (a scale factor that drifts with it).
        Temperature is not in the rate and force maps: a rig visits each rate at one temperature, so
        a slope in it there is set by chance.
        """
        temp = [n_inputs - 1] if n_inputs in (4, 7) else []
        gyro = n_inputs >= 6
        groups = [([i], [i]) for i in range(3)] if gyro else []
        force = [3, 4, 5] if gyro else [0, 1, 2]
        groups.append((force, force))
        return [*groups, (temp, [*temp, *range(n_inputs - 1)])] if temp else groups

    def _train(self, config: dict[str, Any], points: Points, sigma: Array, seed: int) -> Any:
        """The maps placed once; their planes fitted for each neighbourhood (``config``'s or all of
        ``sigmas``): ``{sigma: learner}``."""
        size = int(config["size"])
        # Placing prototypes needs the input set's shape, not every point: at most 2,000 of them.
        rng = np.random.default_rng(seed)
        some = points.x if len(points.x) <= 2000 else points.x[rng.choice(len(points.x), 2000, replace=False)]
        placed = []
        temp_last = points.x.shape[1] in (4, 7)
        for win_cols, plane_cols in self._groups(points.x.shape[1]):
            # A rate chain has as many nodes as a sheet: its one input gets the resolution a sheet spreads
            # over two. Temperature, slow and smooth, gets a chain of ``size``.
            if len(win_cols) > 1:
                grid = lattice(size, 2)
            else:
                grid = lattice(size if win_cols == [points.x.shape[1] - 1] and temp_last else size * size, 1)
            codebook = batch_map(some[:, win_cols], grid, self.som_iterations)
            winners = _nearest(points.x[:, win_cols], codebook)
            placed.append(_Placed(win_cols, plane_cols, grid, codebook, winners))
        widths = [float(config["sigma"])] if "sigma" in config else [float(w) for w in self.sigmas]
        return {w: self._planes(points, sigma, placed, w) for w in widths}

    def _variants(self, config: dict[str, Any], learner: Any) -> list[tuple[dict[str, Any], Any]]:
        return [({"size": config["size"], "sigma": w}, fitted) for w, fitted in learner.items()]

    def _planes(self, points: Points, sigma: Array, placed: list[_Placed], width: float) -> _MapLearner:
        """Every node's plane for lattice neighbourhood ``width``, by penalised weighted least squares."""
        from scipy import sparse

        designs, penalties, blends = [], [], []
        for pl in placed:
            blend = neighbourhood_weights(pl.grid, width, pl.codebook)
            centres = _centres(pl.codebook, pl.win_cols, pl.plane_cols)
            designs.append(_local_design(points.x[:, pl.plane_cols], centres, blend, pl.winners))
            across = [i for i, c in enumerate(pl.plane_cols) if c not in pl.win_cols]
            penalties.append(_smoothness(centres, pl.grid, across))
            blends.append(blend)
        design = sparse.hstack(designs).tocsr()
        smooth = sparse.block_diag(penalties).tocsr()
        weight = points.n / points.n.sum()
        normal = (design.T @ design.multiply(weight[:, None])).toarray()
        nodes = sum(len(pl.grid) for pl in placed)
        normal += (self.smoothing / nodes) * (smooth.T @ smooth).toarray()
        # Where the data cannot set a slope (across a table's axis, say), the plane is flat; the offsets
        # get only a trace of ridge, to keep the system well posed.
        ridge = np.concatenate(
            [np.r_[1e-8, np.full(len(pl.plane_cols), self.slope_ridge)].repeat(1).tolist() * len(pl.grid)
             for pl in placed]
        )  # fmt: skip
        normal += np.diag(ridge)
        rhs = design.T @ (weight[:, None] * points.y / sigma)
        theta = np.linalg.solve(normal, rhs)
        maps, at = [], 0
        for pl, blend in zip(placed, blends, strict=True):
            k, d = len(pl.grid), len(pl.plane_cols)
            planes = theta[at : at + k * (d + 1)].reshape(k, d + 1, 3)
            maps.append(_Map(pl.win_cols, pl.plane_cols, pl.codebook, blend, planes))
            at += k * (d + 1)
        return _MapLearner(maps, sigma)

    def _predict(self, learner: Any, x: Array, memo: dict[str, Any] | None = None) -> Array:
        return learner.predict(x, memo)

    def _learner_state(self, learner: Any) -> Any:
        return {
            "sigma": learner.sigma.tolist(),
            "maps": [
                {"winner_columns": m.win_cols, "plane_columns": m.plane_cols,
                 "codebook": m.codebook.tolist(), "blend": m.blend.tolist(), "planes": m.planes.tolist()}
                for m in learner.maps
            ],
        }  # fmt: skip

    def _check_learner(self, learner: Any, n_inputs: int, where: str) -> None:
        """Fitted maps: ``sigma`` (3,), and at most one map per group of :meth:`_groups`, each of the
        nodes one of :attr:`sizes` gives (``n`` for a temperature chain, ``n²`` otherwise: what
        :meth:`fit` chooses among) over columns of the ``n_inputs``: ``codebook`` (k, winner columns),
        ``blend`` (k, k), ``planes`` (k, plane columns + 1, 3)."""
        super()._check_learner(learner, n_inputs, where)
        state_array(learner, "sigma", (3,), where)
        maps = learner.get("maps")
        if not isinstance(maps, list) or not 1 <= len(maps) <= len(self._groups(n_inputs)):
            raise ValueError(f"{where}.maps must be 1 to {len(self._groups(n_inputs))} maps")
        allowed = {int(n) for size in self.sizes for n in (size, size * size)}
        for i, m in enumerate(maps):
            at = f"{where}.maps[{i}]"
            if not isinstance(m, dict):
                raise ValueError(f"{at} must be an object")
            columns = [
                _columns_in(m.get(k), n_inputs, f"{at}.{k}") for k in ("winner_columns", "plane_columns")
            ]
            codebook = m.get("codebook")
            nodes = len(codebook) if isinstance(codebook, list) else 0
            if nodes not in allowed:
                raise ValueError(f"{at}.codebook has {nodes} nodes; params.sizes make {sorted(allowed)}")
            state_array(m, "codebook", (nodes, len(columns[0])), at)
            state_array(m, "blend", (nodes, nodes), at)
            state_array(m, "planes", (nodes, len(columns[1]) + 1, 3), at)

    def _learner_from_state(self, state: Any) -> Any:
        maps = [
            _Map([int(c) for c in m["winner_columns"]], [int(c) for c in m["plane_columns"]],
                 *(np.asarray(m[k], dtype=float) for k in ("codebook", "blend", "planes")))
            for m in state["maps"]
        ]  # fmt: skip
        return _MapLearner(maps, np.asarray(state["sigma"], dtype=float))


def _columns_in(value: Any, n_inputs: int, where: str) -> list[int]:
    """A map's input columns: distinct whole numbers below ``n_inputs``, at least one."""
    ok = isinstance(value, list) and 1 <= len(value) <= n_inputs and len(set(map(str, value))) == len(value)
    if not ok or not all(isinstance(c, int) and not isinstance(c, bool) and 0 <= c < n_inputs for c in value):
        raise ValueError(f"{where} must be distinct input columns, 0 to {n_inputs - 1}")
    return list(value)


def check_map(size: Any, where: str) -> int:
    """``size``, a map's nodes a side, a whole number from 1 to :data:`MAX_SIDE`; else ``ValueError``."""
    if (
        isinstance(size, bool | np.bool_)
        or not isinstance(size, int | np.integer)
        or not 1 <= size <= MAX_SIDE
    ):
        raise ValueError(
            f"{where} must be a whole number of nodes from 1 to {MAX_SIDE}, got {str(size)[:40]}"
        )
    return int(size)


@dataclass(frozen=True)
class _Placed:
    """A map placed over its winner columns: its lattice ``grid``, prototypes, each point's winner."""

    win_cols: list[int]
    plane_cols: list[int]
    grid: Array
    codebook: Array
    winners: NDArray[np.intp]


def _centres(codebook: Array, win_cols: list[int], plane_cols: list[int]) -> Array:
    """Each node's plane centre over the plane columns: its prototype, and 0 (the scaled range's
    middle) in the columns it does not win by."""
    centres = np.zeros((len(codebook), len(plane_cols)))
    for i, c in enumerate(plane_cols):
        if c in win_cols:
            centres[:, i] = codebook[:, win_cols.index(c)]
    return centres


def _smoothness(centres: Array, grid: Array, across: list[int]) -> Any:
    """Rows ``a_i + B_i (c_j − c_i) − a_j`` for every pair of lattice neighbours, both ways (sparse):
    neighbours' planes agree where they meet. And, for the plane columns the map is not placed over
    (``across``: the rate and force a temperature chain's planes slope in), rows ``B_i − B_j``: the
    meeting rows cannot tie those slopes (the centres differ only in temperature), so without these each
    node would take its slope from the few orientations the rig held at its temperature."""
    from scipy import sparse

    k, d = centres.shape
    d2 = ((grid[:, None, :] - grid[None, :, :]) ** 2).sum(axis=2)
    edges = np.argwhere(np.triu(d2 == 1.0)) if len(grid) > 1 else np.zeros((1, 2), dtype=np.intp)
    pairs = np.vstack([edges, edges[:, ::-1]])
    a, b = pairs[:, 0], pairs[:, 1]
    m = len(pairs)
    rows = np.repeat(np.arange(m), d + 2)
    cols = np.column_stack([a * (d + 1), a[:, None] * (d + 1) + 1 + np.arange(d), b * (d + 1)])
    vals = np.column_stack([np.ones(m), centres[b] - centres[a], -np.ones(m)])
    meet = sparse.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(m, k * (d + 1)))
    if not across or len(grid) == 1:
        return meet
    slope = np.asarray(across, dtype=np.intp)
    n = len(edges) * len(slope)
    rows = np.repeat(np.arange(n), 2)
    cols = np.column_stack(
        [(edges[:, :1] * (d + 1) + 1 + slope).ravel(), (edges[:, 1:] * (d + 1) + 1 + slope).ravel()]
    )
    vals = np.tile([1.0, -1.0], n)
    tie = sparse.csr_matrix((vals, (rows, cols.ravel())), shape=(n, k * (d + 1)))
    return sparse.vstack([meet, tie])


def batch_map(x: Array, grid: Array, iterations: int) -> Array:
    """Kohonen's batch map: prototypes (k, d) for the lattice ``grid`` (k, q) over points ``x`` (m, d).

    Started on the points' first ``q`` principal components, spanning ±2 standard deviations; each
    pass moves every prototype to the neighbourhood-weighted mean of the points
    its lattice neighbours win, the neighbourhood shrinking geometrically from
    half the map to half a node.
    """
    mean = x.mean(axis=0)
    centred = x - mean
    _, s, vt = np.linalg.svd(centred, full_matrices=False)
    q = min(grid.shape[1], len(s))
    spread = s[:q] / np.sqrt(max(len(x), 1))
    span = np.ptp(grid, axis=0)
    unit = (grid - grid.mean(axis=0)) / np.where(span > 0, span / 2.0, 1.0)  # in [-1, 1]
    codebook = mean + sum(unit[:, [c]] * 2.0 * spread[c] * vt[c] for c in range(q))
    lattice = ((grid[:, None, :] - grid[None, :, :]) ** 2).sum(axis=2)
    start, end = max(float(span.max()) / 2.0, 0.5), 0.5
    for it in range(iterations):
        width = start * (end / start) ** (it / max(iterations - 1, 1))
        h = np.exp(-lattice[:, _nearest(x, codebook)] / (2.0 * width * width))  # (k, m)
        total = h.sum(axis=1)
        moved = total > 1e-12
        codebook[moved] = (h[moved] @ x) / total[moved, None]
    return np.asarray(codebook)


def neighbourhood_weights(grid: Array, sigma: float, codebook: Array | None = None) -> Array:
    """``h[w, j]``: node ``j``'s share of a prediction won by node ``w`` (rows sum to 1; cut at 2σ).

    Gaussian in lattice distance; with the prototypes given, also in their input distance, on the
    scale of twice the mean distance from a prototype to its nearest: where a rig's inputs come in
    clusters (six faces down) the lattice folds between them, and a lattice neighbour in another
    cluster is no neighbour of the input.
    """
    lattice = ((grid[:, None, :] - grid[None, :, :]) ** 2).sum(axis=2)
    h = np.where(lattice <= 4.0 * sigma * sigma, np.exp(-lattice / (2.0 * sigma * sigma)), 0.0)
    if codebook is not None and len(codebook) > 1:
        apart = ((codebook[:, None, :] - codebook[None, :, :]) ** 2).sum(axis=2)
        nearest = np.sqrt(np.where(np.eye(len(codebook), dtype=bool), np.inf, apart).min(axis=1))
        scale = max(2.0 * float(nearest.mean()), 1e-6)
        h = h * np.exp(-apart / (2.0 * scale * scale))
    out: Array = h / h.sum(axis=1, keepdims=True)
    return out


def _nearest(x: Array, codebook: Array) -> NDArray[np.intp]:
    """Index of each row's nearest prototype (Euclidean). Chains over one input (rate, temperature) are
    searched by bisection, not through the (n, k) distance matrix: the training asks this of every row
    on every epoch."""
    if codebook.shape[1] == 1 and len(codebook) > 1:
        order = np.argsort(codebook[:, 0], kind="stable")
        values = codebook[order, 0]
        right = np.clip(np.searchsorted(values, x[:, 0]), 1, len(values) - 1)
        left = right - 1
        pick = np.where(x[:, 0] - values[left] <= values[right] - x[:, 0], left, right)
        return order[pick]
    d2 = (x * x).sum(axis=1)[:, None] - 2.0 * x @ codebook.T + (codebook * codebook).sum(axis=1)[None, :]
    return np.argmin(d2, axis=1)


def lattice(size: int, dims: int) -> Array:
    """Node coordinates (size**dims, dims) of a square lattice of ``dims`` dimensions."""
    return np.array(list(itertools.product(range(size), repeat=dims)), dtype=float)


def _local_design(x: Array, centres: Array, blend: Array, winners: NDArray[np.intp]) -> Any:
    """Sparse (m, k·(d+1)) matrix: row ``i`` holds ``h_j [1, x_i − c_j]`` in node ``j``'s columns."""
    from scipy import sparse

    m, d = x.shape
    k = len(centres)
    rows, cols, vals = [], [], []
    for w in np.unique(winners):
        members = np.flatnonzero(winners == w)
        nodes = np.flatnonzero(blend[w] > 0)
        h = blend[w, nodes]  # (q,)
        local = x[members][:, None, :] - centres[nodes][None, :, :]  # (r, q, d)
        block = np.concatenate([np.ones((len(members), len(nodes), 1)), local], axis=2) * h[None, :, None]
        col = nodes[:, None] * (d + 1) + np.arange(d + 1)[None, :]  # (q, d+1)
        rows.append(np.repeat(members, len(nodes) * (d + 1)))
        cols.append(np.tile(col.ravel(), len(members)))
        vals.append(block.ravel())
    return sparse.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(m, k * (d + 1))
    )


#: What a row's winner margin leaves for the rounding of the distances it is made of: the scaled inputs
#: and the nodes lie within a few units of the origin, where a distance rounds by ~1e-15.
_MARGIN_SLACK = 1e-9


class _Map:
    """One fitted map: the columns it picks its winner by and those its planes span, prototypes (k, w),
    blending weights (k, k) and planes (k, d+1, 3) in units of the learner's ``sigma``."""

    def __init__(
        self, win_cols: list[int], plane_cols: list[int], codebook: Array, blend: Array, planes: Array
    ) -> None:
        self.win_cols, self.plane_cols = win_cols, plane_cols
        self.codebook, self.blend, self.planes = codebook, blend, planes
        centres = _centres(codebook, win_cols, plane_cols)
        # Won by node w: Σ_j h_wj (a_j + B_j (x − c_j)) = Σ_j h_wj (a_j − B_j c_j) + (Σ_j h_wj B_j) x.
        offsets = planes[:, 0, :] - np.einsum("kdc,kd->kc", planes[:, 1:, :], centres)
        self._offset = np.ascontiguousarray(blend @ offsets)  # (k, 3)
        self._slope = np.ascontiguousarray(np.einsum("wk,kdc->wdc", blend, planes[:, 1:, :]))  # (k, d, 3)
        self._win_idx = np.asarray(win_cols, dtype=np.intp)
        self._plane_idx = np.asarray(plane_cols, dtype=np.intp)
        self._tree: Any = None

    def winners(self, x: Array) -> NDArray[np.intp]:
        """Each row's nearest prototype. A chain over one input by bisection (:func:`_nearest`); a map over
        several through a k-d tree built once (scipy's ``cKDTree``, exact Euclidean distances): the (n, k)
        distance matrix :func:`_nearest` forms for training took 3/4 of a correction's time at 144 nodes,
        the tree a twentieth of that (``tools/bench_correction.py``, ``docs/speed.md``)."""
        if self.codebook.shape[1] == 1:
            return _nearest(x, self.codebook)
        _, win = self._search().query(x)
        return np.asarray(win, dtype=np.intp)

    def _search(self) -> Any:
        """The prototypes' k-d tree, built on first use."""
        if self._tree is None:
            from scipy.spatial import cKDTree

            self._tree = cKDTree(self.codebook)
        return self._tree

    def add_to(self, out: Array, x: Array, memo: dict[str, Any] | None = None) -> None:
        """The map's output at ``x`` (each row's winner's plane, :func:`_add_planes`) added to ``out``;
        ``memo`` kept between calls on the same rows (:meth:`_kept`)."""
        win = self.winners(x[:, self.win_cols]) if memo is None else self._kept(x, memo)
        _add_planes(np.ascontiguousarray(x), self._plane_idx, win, self._offset, self._slope, out)

    def _kept(self, x: Array, memo: dict[str, Any]) -> NDArray[np.intp]:
        """Each row's winner, found again only for the rows that may have a new one (``x`` holds every
        input column; the map's are :attr:`win_cols`).

        A correction's passes move a row's input by about the residual, far less than the nodes lie
        apart. Where a row's winner was found at ``a`` with distances ``d1 < d2`` to its nearest two
        nodes, any input within ``(d2 − d1)/2`` of ``a`` has the same winner (the triangle inequality:
        its distance to the winner is below ``d1 + δ``, to any other node above ``d2 − δ``); a row that
        moved that far or more from where its winner was found is searched again (:func:`_moved`). The
        same winners as a search each pass, so the same output to the last bit
        (``tests/test_threaded_correction.py``), for one search in place of three
        (``tools/bench_correction.py``). A chain over one input keeps its winners the same way: the
        margin holds on a line as anywhere, and a row near a tie takes the bisection's choice."""
        if memo.get("anchor") is None or len(memo["anchor"]) != len(x):
            at = np.ascontiguousarray(x[:, self.win_cols])
            win, margin = self._winners_and_margins(at)
            memo.update(anchor=at, margin=margin, win=win)
            return win
        again = _moved(np.ascontiguousarray(x), self._win_idx, memo["anchor"], memo["margin"])
        if again.size:
            at = np.ascontiguousarray(x[again][:, self.win_cols])
            win, margin = self._winners_and_margins(at)
            memo["anchor"][again], memo["margin"][again], memo["win"][again] = at, margin, win
        return memo["win"]

    def _winners_and_margins(self, x: Array) -> tuple[NDArray[np.intp], Array]:
        """:meth:`winners`, and how far each row may move and keep its winner (half the gap between its
        nearest two nodes' distances, less :data:`_MARGIN_SLACK` for the distances' rounding). Every
        node's distance from every row, compiled (:func:`_two_nearest`), up to :data:`_SCANNED_NODES`
        nodes; the k-d tree's two nearest beyond. A row whose two nearest are within the slack of a tie
        takes :meth:`winners`' choice, so either way the winners are the tree's."""
        if len(self.codebook) <= _SCANNED_NODES:
            near, dist = _two_nearest(np.ascontiguousarray(x), np.ascontiguousarray(self.codebook))
        else:
            dist, near = self._search().query(x, k=2)
        win = np.asarray(near[:, 0], dtype=np.intp)
        margin = 0.5 * (dist[:, 1] - dist[:, 0]) - _MARGIN_SLACK
        tied = np.flatnonzero(~(margin > 0.0))
        if tied.size:  # equally near nodes: the winner a search of the nearest alone gives, every pass
            win[tied] = self.winners(x[tied])
        return win, margin


#: The most nodes whose distances from each row :meth:`_Map._winners_and_margins` computes every one of:
#: up to here 1.25-4 times faster than scipy's k-d tree at 2-5 inputs, beyond it slower at two or three
#: (``tools/bench_nearest.py``; EuRoC's maps have 25 and 144 nodes of three inputs).
_SCANNED_NODES = 256


@numba.njit(cache=True, nogil=True)
def row_squared_distances(x: Array, i: int, nodes_t: Array, out: Array) -> None:  # pragma: no cover
    """Into ``out`` (k,): row ``i`` of ``x``'s squared Euclidean distance from each node of ``nodes_t``
    (w, k: the codebook transposed), every squared difference summed over the columns in order, as
    scipy's k-d tree sums them, column by column (a loop over the nodes the compiler vectorises)."""
    out[:] = 0.0
    for c in range(nodes_t.shape[0]):
        xc = x[i, c]
        for j in range(nodes_t.shape[1]):
            e = xc - nodes_t[c, j]
            out[j] += e * e


@numba.njit(cache=True, nogil=True)
def _two_nearest(x: Array, codebook: Array) -> tuple[NDArray[np.intp], Array]:  # pragma: no cover  (compiled)
    """Each row's nearest two nodes (n, 2) and their Euclidean distances (n, 2), nearest first
    (:func:`row_squared_distances`)."""
    n, k = x.shape[0], codebook.shape[0]
    nodes = np.ascontiguousarray(codebook.T)  # (w, k)
    near = np.zeros((n, 2), dtype=np.intp)
    dist = np.empty((n, 2))
    d = np.empty(k)
    for i in range(n):
        row_squared_distances(x, i, nodes, d)
        d1, d2, j1, j2 = np.inf, np.inf, 0, 0
        for j in range(k):
            dj = d[j]
            if dj < d2:  # few are: one test for most nodes
                if dj < d1:
                    d2, j2 = d1, j1
                    d1, j1 = dj, j
                else:
                    d2, j2 = dj, j
        near[i, 0], near[i, 1] = j1, j2
        dist[i, 0], dist[i, 1] = np.sqrt(d1), np.sqrt(d2)
    return near, dist


@numba.njit(cache=True, nogil=True)
def _add_planes(
    x: Array, cols: NDArray[np.intp], win: NDArray[np.intp], offset: Array, slope: Array, out: Array
) -> None:  # pragma: no cover  (compiled)
    """``out += offset[win] + einsum("nd,ndc->nc", x[:, cols], slope[win])``, numpy's sums to the last bit
    (each row's products summed from zero in the inputs' order, then added to its offset), without
    gathering the columns or each row's (d, 3) slope."""
    n, d, c = x.shape[0], cols.shape[0], offset.shape[1]
    for i in range(n):
        w = win[i]
        for k in range(c):
            acc = 0.0
            for j in range(d):
                acc += x[i, cols[j]] * slope[w, j, k]
            out[i, k] += offset[w, k] + acc


@numba.njit(cache=True, nogil=True)
def _moved(
    x: Array, cols: NDArray[np.intp], anchor: Array, margin: Array
) -> NDArray[np.intp]:  # pragma: no cover  (compiled)
    """The rows of ``x`` whose columns ``cols`` lie ``margin`` or farther from ``anchor`` (Euclidean), or
    are not numbers: those :meth:`_Map._kept` searches again."""
    n, w = anchor.shape
    far = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        s = 0.0
        for c in range(w):
            e = x[i, cols[c]] - anchor[i, c]
            s += e * e
        far[i] = not (np.sqrt(s) < margin[i])
    return np.flatnonzero(far)


class _MapLearner:
    """Fitted maps whose predictions add up, in units of ``sigma`` (3,)."""

    def __init__(self, maps: list[_Map], sigma: Array) -> None:
        self.maps, self.sigma = maps, sigma

    def predict(self, x: Array, memo: dict[str, Any] | None = None) -> Array:
        """The maps' sum at ``x``; ``memo`` (one dict for the same rows on each call) lets each map keep
        its rows' winners (:meth:`_Map._kept`). Every step is row by row and forms nothing larger than
        a few columns of the rows (the winners by a scan, a k-d tree or bisection), so ``x`` is taken
        whole."""
        out = np.zeros((len(x), 3))
        for i, m in enumerate(self.maps):
            m.add_to(out, x, None if memo is None else memo.setdefault(f"map{i}", {}))
        return out * self.sigma


__all__ = [
    "MAX_SIDE",
    "LocalLinearMap",
    "batch_map",
    "check_map",
    "lattice",
    "neighbourhood_weights",
    "row_squared_distances",
]
