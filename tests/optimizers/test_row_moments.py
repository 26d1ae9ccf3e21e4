"""Row-resolved noise (``CatalogProblem.noise_draws``): each cross-validation fold of the
unforced selection is judged against its own rows' noise, not a share of the block's."""

import numpy as np
import pytest

from pysindy_xl.optimizers import CatalogProblem
from pysindy_xl.optimizers.homogeneous import RowMoments, select_law
from pysindy_xl.weak.noise import draw_moments


def _heteroscedastic_law(seed, n_rows=3000, n_draws=8):
    """Columns ``[a, b, a - 2 b, c, d]`` with errors whose spread grows tenfold along the
    rows (as the weak rows' noise grows where the motion is fast), and draws of those errors
    from the same distribution."""
    rng = np.random.default_rng(seed)
    a, b, c, d = rng.normal(size=(4, n_rows))
    clean = np.column_stack([a, b, a - 2 * b, c, d])
    envelope = np.geomspace(0.02, 0.2, n_rows)[:, None]
    theta = clean + envelope * rng.normal(size=clean.shape)
    draws = envelope * rng.normal(size=(n_draws,) + clean.shape)
    return theta, draws


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_true_law_holds_to_each_folds_own_noise(seed):
    theta, draws = _heteroscedastic_law(seed)
    moments = draw_moments(draws, 1)
    law, _, own = select_law(theta, moments, noise_draws=draws)
    _, _, shared = select_law(theta, moments)
    assert np.flatnonzero(law).tolist() == [0, 1, 2]
    np.testing.assert_allclose(law[:3] / law[0], [1.0, -2.0, -1.0], rtol=0.02)
    # the held-out ratio of the law on its own rows' noise is 1 in every fold; on shares of
    # the whole block's noise it follows the envelope (about 0.2 to 3 over the folds)
    assert abs(own.cv_ratio[2] - 1.0) < 0.2 and own.cv_spread[2] < 0.1
    assert shared.cv_spread[2] > 3 * own.cv_spread[2]


def test_row_moments_of_a_set_of_rows_are_those_of_its_draws():
    draws = np.random.default_rng(0).normal(size=(4, 10, 3))
    rows = np.array([1, 2, 7])
    expected = np.einsum("drf,drg->fg", draws[:, rows], draws[:, rows]) / 4
    np.testing.assert_allclose(RowMoments(draws)(rows), expected)
    np.testing.assert_allclose(RowMoments(draws).columns([0, 2])(rows),
                               expected[np.ix_([0, 2], [0, 2])])
    np.testing.assert_allclose(RowMoments(draws, floor=0.5)(rows), expected + 1.5 * np.eye(3))


def test_problem_keeps_draws_and_moments_consistent():
    rng = np.random.default_rng(1)
    theta = rng.normal(size=(40, 3)) * np.repeat([1.0, 1e3], 20)[:, None]
    draws = 0.01 * rng.normal(size=(5, 40, 3)) * np.repeat([1.0, 1e3], 20)[None, :, None]
    problem = CatalogProblem.from_arrays(theta, 2, [], noise_draws=draws)
    np.testing.assert_allclose(problem.noise_moments, draw_moments(draws, 2))
    for part in (problem.balanced(), problem.subsample(np.arange(3, 15)),
                 problem.subproblem(np.array([False, True]), np.array([2, 0]))):
        np.testing.assert_allclose(part.noise_moments,
                                   draw_moments(part.noise_draws, part.n_coordinates))
        assert part.noise_draws.shape[1:] == part.theta.shape
    # the subsample's moments are its own rows', not a share of the block's
    sub = problem.subsample(np.arange(5))
    np.testing.assert_allclose(sub.noise_moments[1], np.einsum(
        "drf,drg->fg", draws[:, 20:25], draws[:, 20:25]) / 5)


@pytest.mark.parametrize("draws, message", [
    (np.zeros((2, 39, 3)), "noise_draws: expected shape"),
    (np.zeros((0, 40, 3)), "noise_draws: expected shape"),
    (np.full((2, 40, 3), np.nan), "noise_draws"),
])
def test_draws_of_the_wrong_shape_or_not_finite_are_refused(draws, message):
    with pytest.raises(ValueError, match=message):
        CatalogProblem.from_arrays(np.ones((40, 3)), 2, [], noise_draws=draws)


def test_only_optimizers_that_use_the_draws_get_them():
    from pysindy_xl.optimizers import ExplicitOptimizer, ImplicitOptimizer, solve_problem

    seen = {}

    class Spy(ImplicitOptimizer):
        def _solve(self, problem):
            seen[self.catalog_tags().uses_noise_draws] = problem.noise_draws is not None
            return super()._solve(problem)

    class QuietSpy(Spy):
        uses_noise_draws = False

    theta, draws = _heteroscedastic_law(0, n_rows=400)
    problem = CatalogProblem.from_arrays(theta, 1, [], noise_draws=draws)
    for optimizer in (Spy(), QuietSpy()):
        solve_problem(optimizer, problem)
    assert seen == {True: True, False: False}
    assert not ExplicitOptimizer().uses_noise_draws and ImplicitOptimizer().uses_noise_draws


@pytest.mark.slow
def test_three_link_pendulum_from_five_percent_noisy_positions():
    """A chaotic three-link pendulum, unforced, 5 % noise on the positions: the true
    15-term law, its held-out ratio 1 in every fold (on even shares of the blocks' noise
    the folds of this cell spread from 0.2 to 3.4, and a 13-term law won)."""
    from support.unforced_cells import fit_unforced_cell

    model, true = fit_unforced_cell("triple_pendulum", 0.05, seed=0)
    coef = model.coefficients()
    assert np.array_equal(coef != 0, true != 0)
    scale = (coef @ true) / (coef @ coef)
    errors = np.abs(scale * coef[true != 0] / true[true != 0] - 1)
    assert np.median(errors) < 0.02 and errors.max() < 0.3  # the largest: friction
    selection = model.optimizer_.selection_
    ratio, spread = selection.cv_ratio[selection.size - 1], selection.cv_spread[selection.size - 1]
    assert abs(ratio - 1.0) < 0.2 and spread < 0.15
