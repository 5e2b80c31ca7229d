"""One channel's model of its reading error, and how each kind of candidate is fitted in it.

The model of a channel's reading error ``e = reading − reference`` is the baseline (the seed
model's bias, scale/misalignment and g-sensitivity rows, fitted by least squares, plus white noise)
and any effects accepted so far (:class:`ChannelModel`). A candidate (:mod:`sins.gap.candidates`)
enters it by its kind:

- *regressors* (scale nonlinearity and asymmetry, g² sensitivity, temperature bias and scale,
  size effect): columns added to the channel's least-squares fit;
- *delay* (time offset): the reading is the reference at ``t − τ``, cubic Hermite between rows;
  ``τ`` is found by a 1-D search beside the regressors (:func:`_fit_delay`);
- *processes* (bias instability, rate random walk): a first-order Gauss–Markov or random-walk bias
  under the white noise, fitted by the likelihood of the fit rows' innovations, the regressors
  refitted beside it by generalised least squares, and predicted one step ahead by the
  steady-state Kalman filter (:mod:`sins.gap.randombias`);
- *output maps* (quantization, saturation): a quantizer on the readings' lattice (each reading
  rounded, or increments rounded with the remainder carried, after white noise whose level it
  fits; :mod:`sins.gap.lattice`), or the prediction clipped at the readings' pile-up.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize_scalar

from sins.gap import lattice, randombias
from sins.gap.candidates import Candidate, DelayedInputs, ReferenceInputs
from sins.gap.design import Design, Maker, Projection
from sins.gap.floor import TINY, noise_floor
from sins.gap.lattice import Printed

Array = NDArray[np.float64]

#: The white noise before rounding, in quantization steps, tried for the quantization candidate.
_NOISE_PER_STEP = (0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.45, 0.7, 1.0)
#: Points of the delay's scan over its span of four steps (quarter steps; :func:`_fit_delay`).
_DELAY_GRID = 17
#: The two quantizers (see :mod:`sins.gap.lattice`).
_QUANTIZERS = {"rounded": lattice.rounded, "carried": lattice.carried}
#: Their readings' log-probabilities alone, for choosing one (the carried kind's filter gives all at once).
_QUANTIZER_LOGLIK: dict[str, Callable[[Array, Array, float], Array]] = {
    "rounded": lattice.rounded_loglik,
    "carried": lambda m, mu, s: lattice.carried(m, mu, s)[0],
}


#: Numbers that read back exactly: the default print of a recording (a lattice needs no slack).
_FULL_PRECISION = Printed()


@dataclass(frozen=True, eq=False)
class ChannelModel:
    """One channel's model: regressor columns, and an optional delay, random bias and output map.

    Built by :meth:`baseline`, extended by :meth:`with_candidate` and :meth:`with_columns`, and
    fitted by :meth:`fitted`, which returns a new model holding its prediction and what the fit
    settled (the delay, the quantizer); no model changes once built. A model built on a fitted one
    keeps its delay and quantizer: they are settled once, when the effect is first tried.

    Attributes
    ----------
    x : the reference inputs of every row
    sensor, axis : the channel ("gyro", 0 is ``gyro.x``)
    reading : (n,) the readings, SI units (the reference is ``x``'s: :attr:`error` is the difference)
    fit : (n,) the fit rows
    lattice : the fit rows' readings' lattice, None where they lie on none
    columns : the regressors, blocks of columns built a chunk of rows at a time (:mod:`sins.gap.design`):
        the baseline's, then each accepted effect's
    delayed : whether the reading is the reference at ``t − τ``
    delay_s : ``τ``, once fitted
    process : "bias_instability" | "rate_random_walk" | None
    process_on_trial : whether the process must pass :func:`sins.gap.randombias.falsified` (a
        candidate's must; one the simulation's model holds from the start need not)
    output : "quantization" | "saturation" | None
    quantizer : the quantizer's kind and white noise per step, once fitted
    predicted : (n,) the predicted error of every row, once fitted
    loglik_rows : (n,) a quantizer's ln P of every row's reading, once fitted
    fit_loglik : the process's innovations' log-likelihood on the fit rows, once fitted
    coefficients : the regressors' coefficients, of the unscaled columns in :attr:`columns`' order, once
        fitted (beside a random bias, its generalised least squares')
    """

    x: ReferenceInputs
    sensor: str
    axis: int
    reading: Array
    fit: NDArray[np.bool_]
    lattice: lattice.Lattice | None
    columns: tuple[Maker, ...]
    delayed: bool = False
    delay_s: float | None = None
    process: str | None = None
    process_on_trial: bool = True
    output: str | None = None
    quantizer: tuple[str, float] | None = None
    predicted: Array | None = None
    loglik_rows: Array | None = None
    fit_loglik: float = np.nan
    coefficients: Array | None = None
    #: A random bias's size once fitted, SI: a Gauss–Markov bias's stationary σ and correlation time τ
    #: (s), a walk's density (per √s) (:func:`sins.gap.randombias.sizes`).
    process_size: tuple[float, ...] | None = None

    @property
    def late(self) -> DelayedInputs | None:
        """With a delay, once fitted: how to make the inputs at ``t − τ`` (:func:`delayed_inputs`),
        which the columns are built from. A sensor that reads its input late forms every error of it
        from what it read (a scale factor scales the delayed input), so beside a large lag (a rig that
        steps its orientation within a row: a 3 ms delay at 20 Hz lags the force by 2.3 m/s² there) the
        scale and misalignment of the lag itself are not the noise's (they had left the accelerometers
        at 1.07-1.08 of their floor, and the delay 17 % long)."""
        return None if self.delay_s is None else delayed_inputs(self.x, self.delay_s)

    @classmethod
    def baseline(
        cls,
        x: ReferenceInputs,
        sensor: str,
        axis: int,
        reading: Array,
        fit: NDArray[np.bool_],
        printed: Printed = _FULL_PRECISION,
    ) -> ChannelModel:
        """The baseline's model of one channel (unfitted): its columns, and its readings' lattice
        (sought under the file's print, ``printed``)."""
        columns = (partial(_baseline_block, sensor),)
        return cls(x, sensor, axis, reading, fit, lattice.find(reading[fit], printed=printed), columns)

    def with_candidate(self, cand: Candidate, on_trial: bool = True) -> ChannelModel:
        """This model with ``cand`` added (unfitted); ``on_trial``: see :attr:`process_on_trial`."""
        if cand.kind == "regressors":
            assert cand.columns is not None
            return self.with_columns(partial(_axis_block, cand.columns, self.axis))
        if cand.kind == "delay":
            return dataclasses.replace(self, delayed=True, delay_s=None)
        if cand.kind == "process":
            return dataclasses.replace(self, process=cand.name.split(".")[1], process_on_trial=on_trial)
        return dataclasses.replace(self, output=cand.name.split(".")[1], quantizer=None, loglik_rows=None)

    def with_columns(self, columns: Maker) -> ChannelModel:
        """This model with the regressors ``columns`` added (unfitted): a block of columns of any
        rows, from their reference inputs."""
        return dataclasses.replace(self, columns=(*self.columns, columns))

    def design(self) -> Design:
        """The regressors' columns, unscaled (of the inputs at ``t − τ`` with a fitted delay)."""
        return Design(self.late or self.x, self.columns)

    def widths(self) -> list[int]:
        """How many columns each block of :attr:`columns` has (the baseline's, then each regressor
        effect's in the order they were added)."""
        one = self.x.rows(0, 1)
        return [int(np.asarray(make(one)).reshape(1, -1).shape[1]) for make in self.columns]

    def tried(self, cand: Candidate) -> ChannelModel:
        """This model with ``cand`` added, fitted."""
        return self.with_candidate(cand).fitted()

    @property
    def n_params(self) -> int:
        """The number of fitted parameters: columns, the process's (two or one), the output map's, τ."""
        k = self.design().width
        if self.process is not None:
            k += 2 if self.process == "bias_instability" else 1
        return k + (self.output is not None) + self.delayed

    @property
    def reference(self) -> Array:
        """(n,) the reference of the channel's own axis."""
        return self.x.of(self.sensor)[:, self.axis]

    @property
    def error(self) -> Array:
        """(n,) reading − reference of every row: computed when asked for (a long recording's six
        channels' errors, held, would be as large as its readings)."""
        return self.reading - self.reference

    @property
    def residual(self) -> Array:
        """The error the fitted model leaves on every row: ``error − predicted`` (NaN if falsified)."""
        assert self.predicted is not None, "fit the model first"
        return self.error - self.predicted

    def fit_rows_loglik(self) -> float:
        """The fit rows' Gaussian log-likelihood (own variance): of the process's innovations where
        the model has a random bias, of its residual otherwise. Once fitted."""
        return (
            self.fit_loglik
            if self.process is not None
            else randombias.log_likelihood(self.residual[self.fit])
        )

    def fitted(self) -> ChannelModel:
        """This model with every parameter fitted on the fit rows and the predicted error of every row.

        A process that :func:`sins.gap.randombias.falsified` rules out predicts NaN everywhere.
        """
        design = self.design()
        rows, rcond = self.fit, None
        if self.output == "saturation":
            # Clipped readings say nothing of the unclipped model; what the other rows hardly
            # excite (an axis that is only ever clipped when it sees gravity) is left at zero.
            seen = self.reading[self.fit]
            rows, rcond = self.fit & (self.reading < seen.max()) & (self.reading > seen.min()), 1e-3
        delay_s, error = self.delay_s, self.error
        lag: Array | None = None  # what a delay adds to the error: the reference at t − τ less at t
        if self.delayed:
            if delay_s is None:
                # First beside the columns of the inputs at t, then beside those at t − τ (the
                # channel's errors are those of the input it reads late): a second search from there.
                delay_s = _fit_delay(self.x, self.sensor, self.axis, error, design, rows, self.fit)
                design = Design(delayed_inputs(self.x, delay_s).whole(), self.columns)
                delay_s = _fit_delay(self.x, self.sensor, self.axis, error, design, rows, self.fit)
            # Made whole for this fit's passes over the rows, and let go with it: the model keeps τ.
            design = Design(delayed_inputs(self.x, delay_s).whole(), self.columns)
            lag = self.x.lag(self.sensor, self.axis, delay_s)
            error = error - lag
        # The columns scaled on the fit rows, whichever rows fit them.
        coef, scale = design.lstsq(error, rows, rcond, scale_rows=self.fit)
        design = design.scaled_by(scale)
        pred = design.predict(coef)
        fit_loglik, process_size = self.fit_loglik, self.process_size
        if self.process is not None:
            least_squares = error - pred
            del pred  # what least squares leave is all the random bias's fit needs of them
            process = self._with_random_bias(error, least_squares, design, rows, rcond)
            if process is None:  # not this process: see randombias.falsified
                return dataclasses.replace(self, delay_s=delay_s, predicted=np.full_like(error, np.nan))
            pred, fit_loglik, coef, process_size = process
        if lag is not None:
            pred = pred + lag
        quantizer, loglik_rows = self.quantizer, self.loglik_rows
        if self.output == "quantization":
            pred, quantizer, loglik_rows = self._quantized(pred, design)
        elif self.output == "saturation":
            reference = self.reference
            top, bottom = float(self.reading[self.fit].max()), float(self.reading[self.fit].min())
            pred = np.clip(reference + pred, bottom, top) - reference
        return dataclasses.replace(
            self,
            delay_s=delay_s,
            quantizer=quantizer,
            predicted=pred,
            loglik_rows=loglik_rows,
            fit_loglik=fit_loglik,
            coefficients=coef / scale,
            process_size=process_size,
        )

    def _with_random_bias(
        self, error: Array, residual: Array, design: Design, rows: NDArray[np.bool_], rcond: float | None
    ) -> tuple[Array, float, Array, tuple[float, ...]] | None:
        """Given what least squares leave of ``error`` (``residual``), the regressors refitted beside
        the random bias and the bias's one-step prediction added: the predicted error of every row,
        the process's fit-row log-likelihood, the regressors' coefficients and the bias's size
        (:func:`sins.gap.randombias.sizes`) (None: falsified).

        A random bias misleads least squares: a walk's level in each static position passes for
        scale factors. Generalised least squares instead: the innovations filter is linear, so the
        regressors that whiten best are those fitted to the filtered error and columns. (Each series
        is let go as soon as it has served: a long recording's rows are many.)
        """
        first = self._fit_process(residual)
        del residual
        phi, gain = first.phi, first.gain
        del first
        coef = design.whitened_lstsq(error, rows, rcond, phi, gain)
        pred = design.predict(coef)
        y = error - pred
        process = self._fit_process(y)
        if self.process_on_trial and randombias.falsified(process, self.fit, self.x.t):
            return None
        out = np.add(pred, y, out=pred)
        out -= process.innovations
        return out, process.fit_loglik, coef, randombias.sizes(process.phi, process.q, self.x.step_s)

    def _fit_process(self, y: Array) -> randombias.RandomBiasFit:
        """The random bias under the residual ``y``, its white part from first differences within the
        fit rows (as the floor's), not straddling the withheld blocks: a walk's increments over a
        block would inflate it."""
        r = max(noise_floor(y, self.fit) ** 2, TINY**2)
        walk = self.process == "rate_random_walk"
        return randombias.fit(y, self.fit, self.x.step_s, r, walk)

    def _quantized(self, pred: Array, design: Design) -> tuple[Array, tuple[str, float], Array]:
        """The expected reading of the quantizer the fit rows' likelihood prefers, as an error; the
        quantizer (kind and noise per step) and its ln P of every row's reading.

        Rounded or carried, and the white noise before the rounding (per step, over
        :data:`_NOISE_PER_STEP`): chosen once; the models built on this one keep them. For the
        rounded kind the regressors and the noise are then refitted by the readings' own likelihood
        (:func:`lattice.fit_rounded`): least squares on rounded readings misplaces the mean.
        """
        grid = self.lattice
        assert grid is not None
        reference = self.reference
        m = grid.index(self.reading)
        mu = grid.units(reference + pred)
        quantizer = self.quantizer
        if quantizer is None:
            choices = [(k, s) for k in _QUANTIZERS for s in _NOISE_PER_STEP]
            if abs(grid.offset) > 1e-9 * grid.step:
                choices = [c for c in choices if c[0] == "rounded"]  # differences of a lattice have no offset
            quantizer = max(
                choices, key=lambda c: float(_QUANTIZER_LOGLIK[c[0]](m, mu, c[1])[self.fit].sum())
            )
        kind, s = quantizer
        if kind == "rounded":
            # The censored fit's columns on the fit rows, whole: only readings on a lattice come here.
            delta, s = lattice.fit_rounded(m[self.fit], mu[self.fit], design.matrix(self.fit), s)
            mu, quantizer = mu + design.predict(delta), ("rounded", s)
        loglik_rows, expected, _ = _QUANTIZERS[kind](m, mu, s)
        return expected * grid.step + grid.offset - reference, quantizer, loglik_rows


def delayed_inputs(x: ReferenceInputs, delay_s: float) -> DelayedInputs:
    """The reference inputs at ``t − τ`` (the rate and the force of every axis along their Hermite
    curves, :meth:`~sins.gap.candidates.ReferenceInputs.lag`): what a sensor reading its input
    ``delay_s`` late forms its errors from, made a chunk of rows at a time as the columns ask
    (:class:`~sins.gap.candidates.DelayedInputs`). The simulator delays the whole input alike
    (:func:`sins.imu.effect_set.shift_samples`)."""
    return DelayedInputs(x, delay_s)


def _baseline_block(sensor: str, x: ReferenceInputs) -> Array:
    """The baseline's columns of a chunk of rows: :func:`~sins.gap.candidates.baseline_columns`'s,
    filled a sensor's three columns at a time (every pass over the rows builds them)."""
    u = x.of(sensor)
    out = np.empty((len(u), 7 if sensor == "gyro" else 4))
    out[:, 0] = 1.0
    out[:, 1:4] = u
    if sensor == "gyro":
        out[:, 4:7] = x.f_ib_b
    return out


def _axis_block(columns: Callable[[ReferenceInputs, int], Array], axis: int, x: ReferenceInputs) -> Array:
    """A regressor candidate's columns of one axis, for a chunk of rows."""
    return columns(x, axis)


def _fit_delay(
    x: ReferenceInputs,
    sensor: str,
    axis: int,
    error: Array,
    design: Design,
    rows: NDArray[np.bool_],
    fit: NDArray[np.bool_],
) -> float:
    """The delay τ whose lag, with the regressors (``design``, scaled on the ``fit`` rows) fitted
    beside it, leaves the least on ``rows``.

    To first order the lag is ``−τ u̇``, a column whose coefficient is ``τ``; the search refines it
    within two rows either side, where the rest matters: a step in the reference (a rig turning
    faster than a row) is smoothed differently from its slope. One pass over the rows factors the
    regressors, that column and the error together: the first order's fit, and the regressors'
    own factor, whose projection each step of the search leaves its lag's error to.
    """

    def slope(part: ReferenceInputs) -> Array:
        return -part.rate(sensor, axis)[:, None]

    k = design.width
    both = design.with_makers(slope).factor(rows, error, scale_rows=fit)
    first = float(dataclasses.replace(both, scale=np.append(both.scale[:k], 1.0)).solve()[-1])
    projection = Projection.of(design, rows, both.leading(k))
    curve = x.curve(sensor, axis)  # built once: each step of the search asks it one lag

    def left(tau: float) -> float:
        return projection.residual(error - curve.lag(tau))

    # What is left is not unimodal over two steps where the reference steps within a row (a rig that
    # turns faster than a row): a bounded search over the whole span had settled in another valley
    # (−50 ms for a 3 ms delay at 20 Hz) and kept the first order's 3.5 ms. So the span is scanned on a
    # grid of quarter steps first, and the search refines about the best point of it.
    grid = first + np.linspace(-2.0, 2.0, _DELAY_GRID) * x.step_s
    values = [left(float(tau)) for tau in grid]
    best = int(np.argmin(values))
    spacing = float(grid[1] - grid[0])
    found = minimize_scalar(
        left, bounds=(grid[best] - spacing, grid[best] + spacing), method="bounded",
        options={"xatol": 1e-3 * x.step_s},
    )  # fmt: skip
    candidates = [(float(found.fun), float(found.x)), (float(values[best]), float(grid[best]))]
    return min(candidates)[1]


__all__ = [
    "ChannelModel",
    "delayed_inputs",
]
