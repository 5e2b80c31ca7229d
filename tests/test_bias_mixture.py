"""The online bias estimate from a mixture prior (sins.compensation.online_bias, bias_spread.mixture_width):
its posterior against the linear-Gaussian formulas written independently (covariance form, scipy's
multivariate normal for the evidence), its behaviour on numpy flights whose bias lies near a training
recording's, and how a fit chooses it on held-back recordings (which is what keeps it off a unit whose
new recordings' biases lie near none of the training ones': there it follows a wrong one for tens of
seconds, the guide's "A new recording's bias")."""

from __future__ import annotations

import numpy as np
import pytest
from numpy_units import recordings
from scipy.stats import multivariate_normal
from test_several import _bounded_flight

from sins.compensation import bias_spread, online_bias, referenced, unit_bias

BIAS = np.array([0.02, -0.01, 0.005])


def test_the_mixture_is_the_linear_gaussian_posterior_mean() -> None:
    """Rows in blocks (one block per update), ten unknowns, three components about different bias
    changes: at every update, each component's posterior mean in the covariance form
    ``μ + P Hᵀ (H P Hᵀ + I)⁻¹ (y − H μ)`` and its evidence ``N(y; H μ, H P Hᵀ + I)``, weighted; the
    estimate is the mixture's bias change within 1e-9 of its size."""
    rng = np.random.default_rng(11)
    m, rows = 5, 2
    h = rng.normal(0.0, 1.0, (m, rows, 10))
    y = rng.normal(0.0, 3.0, (m, rows))
    lam0 = np.diag(rng.uniform(0.5, 4.0, 10))
    centres = rng.normal(0.0, 1.0, (3, 3))
    grams = lam0 + np.cumsum(np.einsum("mra,mrb->mab", h, h), axis=0)
    rhss = np.cumsum(np.einsum("mra,mr->ma", h, y), axis=0)
    squares = np.cumsum((y**2).sum(axis=1))
    got = online_bias._mixture(grams, rhss, squares, lam0, centres)
    for upto in range(1, m + 1):
        hh, yy = h[:upto].reshape(-1, 10), y[:upto].reshape(-1)
        logs, means = [], []
        cov_x = np.linalg.inv(lam0)
        for c in centres:
            mu = np.zeros(10)
            mu[4:7] = c
            cov_y = hh @ cov_x @ hh.T + np.eye(len(yy))
            logs.append(multivariate_normal(hh @ mu, cov_y).logpdf(yy))
            means.append(mu + cov_x @ hh.T @ np.linalg.solve(cov_y, yy - hh @ mu))
        weight = np.exp(np.array(logs) - max(logs))
        want = (weight / weight.sum()) @ np.array(means)[:, 4:7]
        np.testing.assert_allclose(got[upto - 1], want, rtol=0, atol=1e-9 * np.abs(want).max())


def _tracks(seed: int, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The online estimate of a numpy flight's bias (:data:`BIAS`) from the training biases ``BIAS +
    offsets``: from their pooled Gaussian and from their mixture; with each step's time."""
    imu = _bounded_flight(seed, bias=BIAS)
    biases = BIAS + offsets
    prior, spread = biases.mean(axis=0), biases.std(axis=0, ddof=1)
    pooled = unit_bias.BiasRule(mode="online", prior=prior, spread=spread)
    mixed = unit_bias.BiasRule(
        mode="online", prior=prior, spread=spread, components=biases,
        component_width=bias_spread.mixture_width(biases, spread), mixture=True,
    )  # fmt: skip
    return unit_bias.bias_track(pooled, imu), unit_bias.bias_track(mixed, imu), imu.t[:-1]


def _horizontal_error(track: np.ndarray, t: np.ndarray) -> float:
    """Mean horizontal miss of a bias track over 30-50 s, rad/s: where the Gaussian estimate is still
    settling on these flights (2.4e-3 off at 20 s, 0.3-0.9e-3 at 40 s)."""
    at = (t >= 30.0) & (t < 50.0)
    return float(np.linalg.norm((track - BIAS)[at, :2], axis=1).mean())


#: Six training biases in three clusters (days) 0.2-0.4 mrad/s wide, 5 mrad/s apart.
DAYS = np.array([
    [0.2e-3, -0.2e-3, 0.1e-3], [-0.3e-3, 0.1e-3, 0.2e-3],
    [4.0e-3, 3.0e-3, 1.0e-3], [3.7e-3, 3.3e-3, 0.8e-3],
    [-3.0e-3, 4.0e-3, -2.0e-3], [-3.2e-3, 4.2e-3, -2.1e-3],
])  # fmt: skip


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_a_bias_near_a_training_days_is_found_sooner(seed: int) -> None:
    """The flight's bias lies within 0.3 mrad/s of one day's two recordings: the mixture's estimate over
    30-50 s misses by at most half the Gaussian's (measured 0.11-0.28 against 0.68-0.90 mrad/s on seeds
    3-9) and by under 0.4 mrad/s."""
    pooled, mixed, t = _tracks(seed, DAYS)
    assert _horizontal_error(mixed, t) < min(0.5 * _horizontal_error(pooled, t), 0.4e-3)


def test_the_width_is_the_clusters_where_the_biases_cluster() -> None:
    """Leave one out: biases in tight pairs far apart take a width near the pairs' own (under a fifth
    of the spread; the pairs lie 0.3-0.5 mrad/s apart, the days 5); biases 1-1.4 mrad/s from each other
    and nothing nearer take a width of their distances' order (the likelihood of a point at distance d
    in three axes peaks at d/√3); and the width is the maximum of the leave-one-out likelihood written
    with scipy's multivariate normal."""
    spread = DAYS.std(axis=0, ddof=1)
    assert np.all(bias_spread.mixture_width(DAYS, spread) < 0.2 * spread)  # measured 0.117
    apart = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]) * 1e-3
    assert np.all(bias_spread.mixture_width(apart, np.full(3, 1e-3)) > 0.5e-3)  # measured 0.66e-3

    def loo(share: float) -> float:
        total = 0.0
        for j in range(len(DAYS)):
            others = np.delete(DAYS, j, axis=0)
            total += np.log(np.mean([multivariate_normal(o, np.diag((share * spread) ** 2)).pdf(DAYS[j])
                                     for o in others]))  # fmt: skip
        return total

    shares = 2.0 ** np.linspace(-6.0, 0.0, 61)
    best = shares[int(np.argmax([loo(s) for s in shares]))]
    np.testing.assert_allclose(bias_spread.mixture_width(DAYS, spread), best * spread, rtol=1e-12)


def test_the_mixture_is_chosen_on_held_back_recordings_only_where_they_can_judge_it() -> None:
    """A fit on three recordings holds two in each held-back fold, too few for a mixture: it is not
    judged, so not taken. On four, each fold holds three, and the mixture's choices are judged beside the
    modes; the rule says which it took, and a model file keeps it."""
    recs, _, _ = recordings(12, count=4)
    three = referenced.fit_several("bias_only", recs[:3]).rule
    assert three is not None and not three.mixture
    assert set(three.held_back_deg) == {*unit_bias.MODES, "raw"}
    four = referenced.fit_several("bias_only", recs).rule
    assert four is not None and set(four.held_back_deg) == {*unit_bias.CHOICES, "raw"}
    assert four.choice in (*unit_bias.CHOICES, unit_bias.READINGS) and len(four.components) == 4
    back = unit_bias.BiasRule.from_dict(four.to_dict())
    assert back.choice == four.choice and np.array_equal(back.components, four.components)


def test_a_rule_file_without_the_mixture_reads_as_before_and_a_bad_one_is_refused() -> None:
    doc = unit_bias.BiasRule(mode="online").to_dict()
    for key in ("components", "component_width", "mixture"):
        doc.pop(key)
    old = unit_bias.BiasRule.from_dict(doc)
    assert not old.mixture and old.components.shape == (0, 3) and old.choice == "online"
    with pytest.raises(ValueError, match="mixture"):
        unit_bias.BiasRule.from_dict({**doc, "mixture": "yes"})
    with pytest.raises(ValueError, match="components"):
        unit_bias.BiasRule.from_dict({**doc, "components": [[0.0, np.nan, 0.0]]})
    assert unit_bias.with_mode(old, "nearest+online (mixture)").choice == "nearest+online (mixture)"
