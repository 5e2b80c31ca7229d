"""Quantizers' likelihoods (sins.gap.lattice) against Monte Carlo and particle-filter oracles."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from sins.gap import lattice


def test_the_lattice_is_found_with_its_step_and_offset_and_only_where_there_is_one():
    rng = np.random.default_rng(0)
    x = rng.normal(0.0, 3e-3, 5000)
    step, offset = 7.3e-4, 2.1e-4
    found = lattice.find(np.round((x - offset) / step) * step + offset)
    assert found is not None
    assert found.step == pytest.approx(step, rel=1e-9) and found.offset == pytest.approx(offset, abs=1e-12)
    assert lattice.find(x) is None  # continuous readings
    assert lattice.find(np.zeros(100)) is None  # one value says nothing of a step
    assert lattice.find(np.round(x / step) * step + 1e-3 * step * rng.standard_normal(5000)) is None


def test_the_step_is_found_where_no_two_levels_lie_one_step_apart():
    """Static holds rounded far coarser than their noise never leave their levels: the step is the
    levels' common divisor, not their smallest gap (readings held on levels only). Seven levels
    drawn from a continuous law share none: for each tried divisor, each level beyond the two that
    set it lies within 1e-6 steps of the lattice by chance one time in 5e5, and five would have to."""
    step, offset = 0.0588399, 0.011
    levels = np.array([-167, -118, -96, 0, 22, 96, 145])
    found = lattice.find(np.repeat(levels * step + offset, 300))
    assert found is not None
    assert found.step == pytest.approx(step, rel=1e-9) and found.offset == pytest.approx(offset, abs=1e-9)
    drawn = np.random.default_rng(3).uniform(-10.0, 10.0, 7)
    assert lattice.find(np.repeat(drawn, 300)) is None
    # Moving readings (°/s) rounded to 0.0610865 and printed to four decimals, as BROAD's gyro z:
    # every value lies on the 1e-4 lattice, 611 times finer than the smallest gap. Taken as printed
    # exactly, no lattice holds them (the readings visit neighbouring levels, so none is sought below
    # that gap); told how the file was printed, the quantizer's is found under the print's rounding.
    rng = np.random.default_rng(4)
    moving = 100.0 * np.sin(np.linspace(0.0, 20.0, 40000)) + 0.05 * rng.standard_normal(40000)
    printed = np.round(np.round(moving / 0.0610865) * 0.0610865, 4)
    assert lattice.find(printed) is None
    habit = lattice.print_habit(printed, np.round(moving, 4))
    assert habit.decimals == 4
    found = lattice.find(printed, printed=habit)
    assert found is not None and found.step == pytest.approx(0.0610865, rel=1e-6)


def _print(values: np.ndarray, fmt: str) -> np.ndarray:
    """Values as a file printed with ``fmt`` reads them back."""
    return np.array([float(fmt % v) for v in values])


def test_a_lattice_under_ten_significant_digits_is_found_from_earth_rate_to_250_deg_per_s():
    """Issue 19's case: a gyro quantised to 0.06 °/s under 0.01 °/s of noise, every reading an integer
    count, printed with 10 significant digits. At 250 °/s the print moves a reading 5e-10 rad/s, 5e-7
    of a step, and the smallest gap holds that error (5e-10 of the step), which reaches 2e-6 steps by
    4,000 steps: the step is refined over the indices, and each reading allowed its print's slack."""
    rng = np.random.default_rng(5)
    step = np.radians(0.06)
    rates = np.radians([0.0042, 10.0, -10.0, 50.0, -50.0, 120.0, -120.0, 250.0, -250.0])
    truth = np.repeat(rates, 5000) + np.radians(0.01) * rng.standard_normal(45000)
    reading = _print(np.round(truth / step) * step, "%.10g")
    habit = lattice.print_habit(reading, _print(truth, "%.10g"))
    assert habit == lattice.Printed(digits=10)
    assert lattice.find(reading) is None  # trusted to the last bit, the print's rounding breaks it
    found = lattice.find(reading, printed=habit)
    assert found is not None
    assert found.step == pytest.approx(step, rel=1e-9) and abs(found.offset) < 1e-9 * step
    assert (found.index(reading) == np.round(truth / step)).mean() > 0.999


def test_print_rounding_alone_is_no_lattice():
    """A file's own resolution is not a quantizer: continuous readings printed to four decimals, or to
    five significant digits, held still (few levels) or moving."""
    rng = np.random.default_rng(6)
    still = 2e-4 + 3e-5 * rng.standard_normal(20000)  # rad/s: a static gyro, noise below 1e-4
    moving = 0.3 * np.sin(np.linspace(0.0, 30.0, 20000)) + 1e-3 * rng.standard_normal(20000)
    for values in (still, moving):
        for fmt in ("%.4f", "%.5g"):
            reading = _print(values, fmt)
            habit = lattice.print_habit(reading)
            assert habit.decimals == 4 or habit.digits == 5, (fmt, habit)
            assert lattice.find(reading, printed=habit) is None, fmt


def test_the_print_habit_is_the_files_not_a_round_columns():
    """Readings on a round lattice (0.001) need few digits; the file's other columns show it printed
    every float exactly, so the lattice is the sensor's."""
    rng = np.random.default_rng(7)
    truth = rng.normal(0.0, 0.05, 5000)
    reading = _print(truth, "%.3f")  # a device that counts in thousandths and writes the counts as decimals
    assert lattice.print_habit(reading).decimals is not None  # alone, it looks printed to 3 decimals
    habit = lattice.print_habit(reading, truth)
    assert habit == lattice.Printed()
    found = lattice.find(reading, printed=habit)
    assert found is not None and found.step == pytest.approx(0.001, rel=1e-9)


def test_rounded_readings_probability_mean_and_variance_match_monte_carlo():
    """P(m), E[m] and Var[m] of round(μ + w), w ~ N(0, s²), against 20,000 draws at 200 points: the
    mean within 5 standard errors (sd ≤ s + ½), the variance within 0.02 (its sampling sd is below
    0.004 here), the probability of the drawn index within 5 binomial standard errors."""
    rng = np.random.default_rng(1)
    mu, s = rng.uniform(-3.0, 3.0, 200), 0.35
    draws = np.round(mu[:, None] + s * rng.standard_normal((200, 20000)))
    m = draws[:, 0]
    loglik, mean, var = lattice.rounded(m, mu, s)
    np.testing.assert_array_less(np.abs(mean - draws.mean(axis=1)), 5 * (s + 0.5) / np.sqrt(20000))
    np.testing.assert_allclose(var, draws.var(axis=1), atol=0.02)
    p_hat = (draws == m[:, None]).mean(axis=1)
    p = np.exp(loglik)
    np.testing.assert_array_less(np.abs(p - p_hat), 5 * np.sqrt(p * (1 - p) / 20000) + 1e-4)
    # The expected reading: plain rounding far below a step of noise, the value itself far above.
    away = mu[np.abs(mu - np.round(mu)) < 0.4]
    np.testing.assert_allclose(lattice.expected_rounding(away, 0.02), np.round(away), atol=1e-6)
    np.testing.assert_allclose(lattice.expected_rounding(mu, 3.0), mu, atol=1e-6)


def _carried_readings(mu: np.ndarray, s: float, rng: np.random.Generator) -> np.ndarray:
    running = np.round(np.cumsum(mu + s * rng.standard_normal(len(mu))) + rng.uniform(-0.5, 0.5))
    return np.diff(np.concatenate([[0.0], running]))


@pytest.mark.parametrize("s", [0.2, 0.6])
def test_carried_readings_match_a_particle_filter(s: float):
    """The grid filter against a bootstrap particle filter (100,000 particles) on 200 readings of
    carried rounding: each reading's ln P within 0.06 nats, the sum within 1 nat (the grid's 16 cells
    and the particles' sampling), and the predictive mean within 0.02 of a step."""
    rng = np.random.default_rng(2)
    mu = 0.03 + 0.3 * np.sin(np.arange(200) / 20.0)
    m = _carried_readings(mu, s, rng)
    loglik, mean, _ = lattice.carried(m, mu, s)
    u = rng.uniform(-0.5, 0.5, 100_000)
    oracle_ll, oracle_mean = [], []
    for k in range(len(m)):
        z = u + mu[k] + s * rng.standard_normal(len(u))
        index = np.round(z)
        oracle_mean.append(index.mean())
        kept = index == m[k]
        oracle_ll.append(np.log(kept.mean()))
        u = rng.choice((z - index)[kept], len(u))
    np.testing.assert_allclose(loglik, oracle_ll, atol=0.06)
    assert loglik.sum() == pytest.approx(sum(oracle_ll), abs=1.0)
    np.testing.assert_allclose(mean, oracle_mean, atol=0.02)


def test_each_quantizer_is_told_from_the_other_by_its_likelihood():
    """On 2,000 readings with noise at 0.2 steps, each kind's own model is more likely than the other
    by far more than any parameter penalty; both beat the continuous model's probability of the bins."""
    rng = np.random.default_rng(3)
    mu, s = 0.37 + 0.2 * np.sin(np.arange(2000) / 50.0), 0.2
    carried_m = _carried_readings(mu, s, rng)
    rounded_m = np.round(mu + s * rng.standard_normal(len(mu)))
    for m, own, other in (
        (carried_m, lattice.carried, lattice.rounded),
        (rounded_m, lattice.rounded, lattice.carried),
    ):
        assert own(m, mu, s)[0].sum() > other(m, mu, s)[0].sum() + 100.0
        residual = m - mu
        continuous = lattice.binned(residual, 1.0, float(np.sqrt(np.mean(residual**2)))).sum()
        assert own(m, mu, s)[0].sum() > continuous + 100.0


def test_a_continuous_models_bin_probability_tends_to_its_density_times_the_step():
    r = np.linspace(-3.0, 3.0, 61)
    np.testing.assert_allclose(lattice.binned(r, 1e-3, 1.0), np.log(norm.pdf(r) * 1e-3), atol=1e-6)


def test_rounded_readings_regression_recovers_the_mean_least_squares_misplaces():
    """Readings rounded at 0.15 step of noise, 1,000 at each of 12 levels of an input (a rig's
    positions): the censored regression recovers the intercept and slope within 0.01 step (its
    errors on three seeds were below 0.002) and the noise within 10 % (3 % there), from a start at
    0.05 or 0.3 step; least squares on the rounded readings is off by more than 0.02 step. (With
    three levels the three parameters are not identified: the likelihood has a ridge.)"""
    rng = np.random.default_rng(1)
    u = np.repeat(rng.uniform(-3.0, 3.0, 12), 1000)
    beta, s = np.array([0.37, 2.3]), 0.15
    columns = np.column_stack([np.ones_like(u), u])
    m = np.round(columns @ beta + s * rng.standard_normal(len(u)))
    least_squares = np.linalg.lstsq(columns, m, rcond=None)[0]
    assert np.abs(least_squares - beta).max() > 0.02
    for start in (0.05, 0.3):
        delta, s_fit = lattice.fit_rounded(m, columns @ least_squares, columns, start)
        np.testing.assert_allclose(least_squares + delta, beta, atol=0.01)
        assert s_fit == pytest.approx(s, rel=0.1)


def test_the_rounded_regression_is_pulled_by_readings_its_start_calls_impossible():
    """26 static holds of 500 readings at 0.04 step of noise (5 holds ever change reading), searched
    from a noise of 0.01, 0.04 and 0.1 step: at 0.01 most of the changing readings lie beyond 10σ
    of the least-squares means, where a floored probability gives the search no gradient (it stayed
    there, 7,500 nats short). Each start reaches the same likelihood within 0.05 nats; the means
    agree within 0.003 step and the noise within 5 % (the prior on ln s holds each near its start
    by about 1 %)."""
    rng = np.random.default_rng(4)
    u = np.repeat(rng.uniform(-3.0, 3.0, 26), 500)
    columns = np.column_stack([np.ones_like(u), u])
    m = np.round(columns @ np.array([0.31, 7.3]) + 0.04 * rng.standard_normal(len(u)))
    mu = columns @ np.linalg.lstsq(columns, m, rcond=None)[0]
    fits = [lattice.fit_rounded(m, mu, columns, start) for start in (0.01, 0.04, 0.1)]
    loglik = [lattice.rounded(m, mu + columns @ delta, s)[0].sum() for delta, s in fits]
    assert max(loglik) - min(loglik) < 0.05
    for delta, s in fits[:2]:
        np.testing.assert_allclose(delta, fits[2][0], atol=0.003)
        assert s == pytest.approx(fits[2][1], rel=0.05)
