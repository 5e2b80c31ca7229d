"""The online bias estimate's prior where it starts from the pooled one (sins.compensation.online_bias,
bias_spread.predictive_bound): the training recordings' spread along gravity, wider across it by the
predictive Student-t's 95 % half-width over the normal's.

A few recordings' mean and spread are estimates, and a new power-up is one more draw; a prior held to
their spread keeps a new power-up's bias from the velocity that shows it across gravity; along
gravity the velocity barely sees the bias, and a wider prior there let it wander on a numpy unit (the
guide's "Tried and not taken"). The checks: the precision against the covariance written out and
inverted by numpy; the bound against Student's t's tabulated quantiles; on numpy flights (tests/
test_several.py's ``_bounded_flight``: numpy and scipy's Rotation only) a bias across gravity found
closer, one along it left where the old prior left it; the rule's field in model files.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_several import _bounded_flight

from sins.compensation import bias_spread, online_bias, unit_bias

#: The pooled prior's spread on each axis, rad/s.
SIGMA = np.full(3, 1e-3)
SEEDS = range(1, 9)


def _estimate(bias: np.ndarray, seed: int, across: float) -> np.ndarray:
    """The online estimate's mean over the flight's last 30 s, rad/s, from a prior of zero."""
    imu = _bounded_flight(seed, bias=bias)
    track = np.zeros((len(imu.t) - 1, 3))
    rate_hz = 1.0 / float(np.median(np.diff(imu.t)))
    est = online_bias.estimate(imu, track, np.zeros(3), SIGMA, 1.0, 0.03, None, across)
    return np.asarray(est[-round(30 * rate_hz) :].mean(axis=0))


def test_the_bound_is_the_predictive_t_from_tabulated_quantiles() -> None:
    """Student's t's 97.5 % quantiles of 2, 4 and 5 degrees of freedom are 4.303, 2.776 and 2.571, the
    normal's 1.960 (tables): 4.303 · √(4/3) / 1.960 = 2.535 for three recordings, 2.776 · √(6/5) / 1.960
    = 1.552 for five, 2.571 · √(7/6) / 1.960 = 1.417 for six; it falls towards 1 as recordings accrue."""
    assert bias_spread.predictive_bound(3) == pytest.approx(2.535, abs=2e-3)
    assert bias_spread.predictive_bound(5) == pytest.approx(1.552, abs=2e-3)
    assert bias_spread.predictive_bound(6) == pytest.approx(1.417, abs=2e-3)
    assert 1.0 < bias_spread.predictive_bound(200) < 1.01


def test_the_precision_inverts_the_covariance_written_out() -> None:
    """``D (k² I − (k² − 1) ũũᵀ) D`` built and inverted by numpy; its variance along the body's up is the
    spread's, and along any direction D-orthogonal to ũ, k² times it."""
    rng = np.random.default_rng(4)
    for _ in range(5):
        sigma, up, k = rng.uniform(1e-4, 3e-3, 3), rng.normal(size=3), rng.uniform(1.0, 16.0)
        up /= np.linalg.norm(up)
        d = np.diag(sigma)
        u = d @ up / np.linalg.norm(d @ up)
        cov = d @ (k**2 * np.eye(3) - (k**2 - 1.0) * np.outer(u, u)) @ d
        np.testing.assert_allclose(online_bias._bias_precision(sigma, up, k), np.linalg.inv(cov), rtol=1e-9)
        assert up @ cov @ up == pytest.approx(up @ d @ d @ up, rel=1e-9)
        w = np.linalg.solve(d, np.cross(u, rng.normal(size=3)))  # D w ⊥ ũ: across gravity
        assert w @ cov @ w == pytest.approx(k**2 * (w @ d @ d @ w), rel=1e-9)
    np.testing.assert_allclose(online_bias._bias_precision(SIGMA, np.array([0.0, 0.0, 1.0]), 1.0),
                               np.diag(1.0 / SIGMA**2), rtol=1e-12)  # fmt: skip


def test_a_bias_across_gravity_is_found_closer_and_one_along_it_stays_where_it_was() -> None:
    """Eight flights (z up, tilts of 15° at most) from a prior of zero held to 1 mrad/s. A bias of 6 and
    -5 mrad/s across gravity (six spreads away, as a new power-up of a unit fitted on three recordings may
    draw): at three recordings' bound, what is left of it after 90 s is under half the old prior's on the
    median (measured: 0.04-0.18 against 0.15-0.54 mrad/s, the median ratio 0.32; one flight nearly ties,
    0.92). A bias of 6 mrad/s along gravity: the estimate is the old prior's within 0.1 mrad/s on every
    flight (measured: 0.035 at most)."""
    across_bias, along_bias = np.array([6e-3, -5e-3, 0.0]), np.array([0.0, 0.0, 6e-3])
    k = bias_spread.predictive_bound(3)
    ratios = []
    for seed in SEEDS:
        old, new = _estimate(across_bias, seed, 1.0), _estimate(across_bias, seed, k)
        ratios.append(np.hypot(*(new - across_bias)[:2]) / np.hypot(*(old - across_bias)[:2]))
        old, new = _estimate(along_bias, seed, 1.0), _estimate(along_bias, seed, k)
        assert np.abs(new - old).max() < 1e-4, (seed, old, new)
    assert np.median(ratios) < 0.5, ratios


def test_the_rule_keeps_its_width_and_old_files_read_as_before() -> None:
    """``rule_from`` sets ``online_across`` to the bound of its recordings, three or more (two recordings'
    spread is one difference; a chi-squared bound of × 16 there had taken a numpy unit fitted on two from
    3.35° to 6.52° under ``online``, tests/test_several.py); a model file round-trips it; one written
    before it (no key) reads 1, the old prior; a value below 1 is refused, naming the key."""
    rng = np.random.default_rng(2)
    biases = rng.normal(0.0, 1e-3, (3, 3))
    streams = [
        _bounded_flight(seed, bias=b, duration_s=20.0) for seed, b in zip((1, 2, 3), biases, strict=True)
    ]
    rule = unit_bias.rule_from(biases, streams, mode="online")
    assert rule.online_across == pytest.approx(bias_spread.predictive_bound(3))
    assert unit_bias.rule_from(biases[:2], streams[:2], mode="online").online_across == 1.0
    doc = rule.to_dict()
    assert unit_bias.BiasRule.from_dict(doc).online_across == rule.online_across
    old = {k: v for k, v in doc.items() if k != "online_across"}
    assert unit_bias.BiasRule.from_dict(old).online_across == 1.0
    with pytest.raises(ValueError, match="online_across"):
        unit_bias.BiasRule.from_dict({**doc, "online_across": 0.5})
