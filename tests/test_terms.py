"""The physics terms between regression and the learners (``sins.compensation.terms``), on residuals made
here with numpy: the groups a channel's residual holds are found on held-back blocks, and pure noise
takes none."""

from __future__ import annotations

import numpy as np
import pytest

from sins.compensation import terms

ROWS, BLOCK_ROWS, FOLDS = 30_000, 300, 3


def _inputs(rng: np.random.Generator) -> tuple[terms.TermInputs, np.ndarray, np.ndarray]:
    """Scaled inputs held in blocks (a rig's positions and rates), a temperature ramp across them, and
    each row's block and fold."""
    blocks = ROWS // BLOCK_ROWS
    w = np.repeat(rng.uniform(-1.0, 1.0, (blocks, 3)), BLOCK_ROWS, axis=0)
    f = np.repeat(rng.normal(size=(blocks, 3)), BLOCK_ROWS, axis=0)
    f /= np.linalg.norm(f, axis=1, keepdims=True)
    t = np.linspace(-1.0, 1.0, ROWS)
    block = np.repeat(np.arange(blocks), BLOCK_ROWS)
    fold = (rng.permutation(blocks) % FOLDS)[block]
    return terms.TermInputs(w, f, t), block, fold


def _folds(r: np.ndarray, fold: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    # Regression's residual is the same whichever fold it is refitted without, here.
    return [(fold != k, r) for k in range(FOLDS)]


def test_a_channel_takes_the_group_its_residual_holds_and_no_other():
    rng = np.random.default_rng(11)
    x, block, fold = _inputs(rng)
    noise = rng.normal(size=(ROWS, 6))
    r = noise.copy()
    r[:, 1] += (
        0.3 * x.temp_offset * x.omega_ib_b[:, 1]
    )  # a temperature scale on gyro y, 0.3 of the noise at full range
    r[:, 3] += 0.2 * (x.temp_offset**2 - np.mean(x.temp_offset**2))  # a curved temperature bias on accel x
    chosen = terms.choose(x, _folds(r, fold), block, z=2.0)
    assert chosen[1] == chosen[3] == ("temperature",)
    assert [chosen[c] for c in (0, 2, 4, 5)] == [(), (), (), ()]
    # The chosen columns recover the coefficient: T·u is the last column (after 1, ω, f, T, T²).
    coef = terms.fit(terms.design(chosen[1], 1, x), r[:, 1])
    assert coef[-1] == pytest.approx(0.3, abs=0.03)  # its standard error is ~0.01 here


def test_pure_noise_takes_no_terms_at_the_guards_rate():
    # 20 sessions × 6 channels of noise alone. At 2 standard errors the group passes by chance at most
    # ~2.3 % of the time (one-sided; less, as a held-back gain on noise is negative on average): about
    # 3 of 120 channels; measured 0. Taking any held-back gain (no guard) takes 6; the
    # guard must take fewer.
    def picked(z: float) -> int:
        count = 0
        for seed in range(20):
            rng = np.random.default_rng([seed, 5])
            x, block, fold = _inputs(rng)
            chosen = terms.choose(x, _folds(rng.normal(size=(ROWS, 6)), fold), block, z=z)
            count += sum(bool(g) for g in chosen)
        return count

    with_guard, without = picked(2.0), picked(-np.inf)
    assert with_guard <= 6  # twice the bound of the chance rate
    assert with_guard < without


def test_each_vocabulary_effect_is_told_from_the_others():
    # The vocabulary's forms on numpy-made residuals, 0.3 of the noise at full scale: a scale
    # nonlinearity (u²) on gyro x, an asymmetry (|u|) on gyro z, an anisoelastic drift (f_x f_z) on gyro
    # y, an asymmetry on accel y. Held in blocks of many rates and orientations, the even forms u² and
    # |u| part, and each channel takes its own group alone.
    rng = np.random.default_rng(12)
    x, block, fold = _inputs(rng)
    r = rng.normal(size=(ROWS, 6))
    r[:, 0] += 0.3 * x.omega_ib_b[:, 0] ** 2
    r[:, 1] += 0.3 * x.f_ib_b[:, 0] * x.f_ib_b[:, 2]
    r[:, 2] += 0.3 * np.abs(x.omega_ib_b[:, 2])
    r[:, 4] += 0.3 * np.abs(x.f_ib_b[:, 1])
    chosen = terms.choose(x, _folds(r, fold), block, z=2.0)
    assert chosen == [("squares",), ("g2",), ("asymmetry",), (), ("asymmetry",), ()]
    # g2's columns: f², then f_x f_y, f_x f_z, f_y f_z (the 11th of 1, ω, f, f², f_x f_y, f_x f_z).
    assert terms.fit(terms.design(chosen[1], 1, x), r[:, 1])[11] == pytest.approx(0.3, abs=0.05)


def test_a_channel_tries_the_groups_its_sensor_may_take():
    assert terms.subsets(with_temperature=False, channel=3) == [
        ("squares",), ("asymmetry",), ("squares", "asymmetry")
    ]  # fmt: skip
    assert ("g2",) in terms.subsets(with_temperature=False, channel=0)
    assert len(terms.subsets(with_temperature=True, channel=0)) == 15
    x = terms.TermInputs(np.zeros((4, 3)), np.zeros((4, 3)), None)
    with pytest.raises(ValueError, match="temperature"):
        terms.design(("temperature",), 0, x)


def test_the_group_is_fitted_with_the_seed_columns_as_one_least_squares():
    # A rig that warms while its table turns faster: the rate rises with the temperature. Regression
    # (the seed columns alone) takes part of a temperature scale s·T·ω into its scale factor; the group
    # fitted to what it leaves with the seed columns beside it recovers s (Frisch–Waugh), the group
    # alone does not.
    rng = np.random.default_rng(3)
    x, _, _ = _inputs(rng)
    w = x.omega_ib_b.copy()
    w[:, 1] = (
        0.5 * (x.temp_offset + 1.0) + 0.2 * w[:, 1]
    )  # each block's rate, plus a rise with the temperature
    x = terms.TermInputs(w, x.f_ib_b, x.temp_offset)
    e = 0.3 * x.temp_offset * x.omega_ib_b[:, 1]
    seed = np.hstack([np.ones((ROWS, 1)), x.omega_ib_b, x.f_ib_b])
    r = e - seed @ np.linalg.lstsq(seed, e, rcond=None)[0]
    joint = terms.fit(terms.design(("temperature",), 1, x), r)
    assert joint[-1] == pytest.approx(0.3, rel=1e-9)
    alone = np.column_stack(
        [np.ones(ROWS), x.temp_offset, x.temp_offset**2, x.temp_offset * x.omega_ib_b[:, 1]]
    )
    assert abs(np.linalg.lstsq(alone, r, rcond=None)[0][-1] - 0.3) > 0.03  # measured 0.242: 19 % off


def test_a_form_the_rig_does_not_show_takes_no_coefficient():
    # A faces-down rig points one axis at a time along gravity: the products f_j f_k of g2 are rounding
    # (~1e-17) there. Scaled to unit RMS, that rounding took a coefficient of ~1e12 and the correction
    # blew up (1e30 the noise) on any other orientation; such a column now gets 0.
    rng = np.random.default_rng(4)
    faces = np.repeat(np.vstack([np.eye(3), -np.eye(3)]), 500, axis=0)
    f = faces + 1e-17 * rng.normal(size=faces.shape)
    x = terms.TermInputs(rng.uniform(-1.0, 1.0, (len(f), 3)), f, None)
    r = 0.3 * f[:, 0] ** 2 + 0.01 * rng.normal(size=len(f))
    coef = terms.fit(terms.design(("g2",), 0, x), r)
    assert np.all(coef[10:] == 0.0)  # f_x f_y, f_x f_z, f_y f_z: not shown
    assert np.abs(coef).max() < 1.0
    tilted = terms.TermInputs(x.omega_ib_b[:1], np.full((1, 3), 3**-0.5), None)
    assert (
        abs(float(terms.predict([("g2",)] + [()] * 5, [coef] + [np.zeros(0)] * 5, tilted, range(1))[0, 0]))
        < 1.0
    )
