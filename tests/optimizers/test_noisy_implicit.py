"""Unforced (implicit) identification from noisy positions: the noise-ratio law selection.

Ground truth: the closed-form eigenproblems (scipy at tight tolerance) for the secular
shortcuts, and ``sympy.physics.mechanics`` systems (tests/ground_truth.py) for the fits.
"""

import warnings

import numpy as np
import pytest
import scipy.linalg
from ground_truth import random_initial_state
from support.paper import paper_catalog

import pysindy_xl as px
from pysindy_xl.optimizers import CatalogProblem
from pysindy_xl.optimizers.homogeneous import select_law
from pysindy_xl.optimizers.noise_ratio import (
    _bordered_minima,
    _bordered_secular,
    _constrained_minima,
    _smallest_bordered_root,
    _swap_secular_at_the_law,
    law_elimination_path,
    law_forward_path,
    noise_pencil,
    refine_law_by_swaps,
)


def _random_pencil(k, seed):
    rng = np.random.default_rng(seed)
    theta = rng.normal(size=(50, k))
    noise = rng.normal(size=(3 * k, k))
    return theta, noise.T @ noise


def test_pencil_matches_the_generalized_eigenproblem():
    theta, moments = _random_pencil(6, 0)
    values, vectors = noise_pencil(theta, moments)
    expected = scipy.linalg.eigh(theta.T @ theta, moments, eigvals_only=True)
    np.testing.assert_allclose(values, expected, rtol=1e-8)
    np.testing.assert_allclose(vectors.T @ moments @ vectors, np.eye(6), atol=1e-8)


def test_constrained_minima_equal_the_eigenvalue_without_the_column():
    theta, moments = _random_pencil(7, 1)
    values, vectors = noise_pencil(theta, moments)
    minima = _constrained_minima(values, vectors)
    for j in range(7):
        rest = np.delete(np.arange(7), j)
        direct = scipy.linalg.eigh(theta[:, rest].T @ theta[:, rest],
                                   moments[np.ix_(rest, rest)], eigvals_only=True)[0]
        assert minima[j] == pytest.approx(direct, rel=1e-9)


def test_bordered_minima_equal_the_eigenvalue_with_one_more_column():
    theta, moments = _random_pencil(8, 2)
    current, candidates = np.arange(5), np.arange(5, 8)
    values, vectors = noise_pencil(theta[:, current], moments[np.ix_(current, current)])
    gram = theta.T @ theta
    minima = _bordered_minima(values, vectors.T @ gram[np.ix_(current, candidates)],
                              vectors.T @ moments[np.ix_(current, candidates)],
                              np.diag(gram)[candidates], np.diag(moments)[candidates])
    for m, i in enumerate(candidates):
        support = np.append(current, i)
        direct = scipy.linalg.eigh(theta[:, support].T @ theta[:, support],
                                   moments[np.ix_(support, support)], eigvals_only=True)[0]
        assert minima[m] == pytest.approx(direct, rel=1e-9)


def test_stacked_pencils_match_each_generalized_eigenproblem():
    problems = [_random_pencil(5, seed) for seed in range(4)]
    values, vectors = noise_pencil(np.stack([p[0] for p in problems]),
                              np.stack([p[1] for p in problems]))
    for m, (theta, moments) in enumerate(problems):
        expected = scipy.linalg.eigh(theta.T @ theta, moments, eigvals_only=True)
        np.testing.assert_allclose(values[m], expected, rtol=1e-8)
        np.testing.assert_allclose(vectors[m].T @ moments @ vectors[m], np.eye(5), atol=1e-8)


def _smallest_eigenvalue(theta, moments, support):
    return scipy.linalg.eigh(theta[:, support].T @ theta[:, support],
                             moments[np.ix_(support, support)], eigvals_only=True)[0]


def test_smallest_bordered_root_is_the_best_swap_of_all_removals():
    """Candidates of different removals (each with its own pencil) compete in one call; the
    winner and its root are those of the direct eigenproblems."""
    theta, moments = _random_pencil(9, 3)
    gram = theta.T @ theta
    support, outside = [0, 1, 2, 3], np.array([4, 5, 6, 7, 8])
    current = _smallest_eigenvalue(theta, moments, support)
    values, cross_gram, cross_moments, swaps = [], [], [], []
    for removed in support:
        rest = [j for j in support if j != removed]
        pencil_values, vectors = noise_pencil(theta[:, rest], moments[np.ix_(rest, rest)])
        values.append(np.repeat(pencil_values[:, None], outside.size, axis=1))
        cross_gram.append(vectors.T @ gram[np.ix_(rest, outside)])
        cross_moments.append(vectors.T @ moments[np.ix_(rest, outside)])
        swaps += [rest + [int(i)] for i in outside]
    direct = np.array([_smallest_eigenvalue(theta, moments, s) for s in swaps])
    arrays = (np.hstack(values), np.hstack(cross_gram), np.hstack(cross_moments),
              np.tile(np.diag(gram)[outside], 4), np.tile(np.diag(moments)[outside], 4))
    # the ceiling is the support's own ratio, below each removal's (interlacing)
    assert direct.min() < current
    index, root = _smallest_bordered_root(current, *arrays)
    assert index == int(np.argmin(direct))
    assert root == pytest.approx(direct.min(), rel=1e-9)
    # below every candidate's root: nothing to report
    assert _smallest_bordered_root(0.99 * direct.min(), *arrays) is None


def test_forward_path_starts_from_the_best_pair_and_adds_the_best_column():
    theta, moments = _random_pencil(7, 4)
    pairs = [[i, j] for i in range(7) for j in range(i + 1, 7)]
    best_pair = pairs[int(np.argmin([_smallest_eigenvalue(theta, moments, p) for p in pairs]))]
    order = law_forward_path(theta, moments)
    assert sorted(order[:2].tolist()) == best_pair
    third = [_smallest_eigenvalue(theta, moments, best_pair + [i]) if i not in best_pair
             else np.inf for i in range(7)]
    assert order[2] == int(np.argmin(third))


def test_swap_screen_from_the_support_equals_each_removals_secular_function():
    """The screen of every swap, from the support's pencil alone, is the Schur complement of
    the removal's own bordered pencil at the support's ratio; its sign says which swaps lower
    the ratio (direct eigenproblems)."""
    theta, moments = _random_pencil(10, 6)
    gram = theta.T @ theta
    support, outside = np.array([0, 1, 2, 3, 4]), np.arange(5, 10)
    values, vectors = noise_pencil(theta[:, support], moments[np.ix_(support, support)])
    screen = _swap_secular_at_the_law(
        values, vectors, vectors.T @ gram[np.ix_(support, outside)],
        vectors.T @ moments[np.ix_(support, outside)], np.diag(gram)[outside],
        np.diag(moments)[outside])
    for j in range(5):
        rest = np.delete(support, j)
        rest_values, rest_vectors = noise_pencil(theta[:, rest], moments[np.ix_(rest, rest)])
        exact = _bordered_secular(values[0], rest_values[:, None],
                                  rest_vectors.T @ gram[np.ix_(rest, outside)],
                                  rest_vectors.T @ moments[np.ix_(rest, outside)],
                                  np.diag(gram)[outside], np.diag(moments)[outside])
        np.testing.assert_allclose(screen[j], exact, rtol=1e-7, atol=1e-9 * np.abs(exact).max())
        lowers = [_smallest_eigenvalue(theta, moments, np.append(rest, i)) < values[0]
                  for i in outside]
        np.testing.assert_array_equal(screen[j] < 0, lowers)
    assert (screen < 0).any() and (screen > 0).any()


def _swap_search_by_eigh(theta, moments, support):
    """Best-improvement single swaps, every swap's ratio from scipy's generalized eigh."""
    support = sorted(support)
    current = _smallest_eigenvalue(theta, moments, support)
    while True:
        swaps = [sorted(set(support) - {j} | {i}) for j in support
                 for i in range(theta.shape[1]) if i not in support]
        ratios = [_smallest_eigenvalue(theta, moments, s) for s in swaps]
        if not min(ratios) < current * (1 - 1e-9):
            return support
        support, current = swaps[int(np.argmin(ratios))], min(ratios)


def test_swap_refinement_matches_the_direct_search_and_its_memo():
    rng = np.random.default_rng(5)
    a, b, c = rng.normal(size=(3, 400))
    # a law a + b - c = 0 among correlated decoys, so that some starts need several swaps
    clean = np.column_stack([a, b, a + b - c, c, a + 0.3 * rng.normal(size=400),
                             b + 0.3 * rng.normal(size=400), rng.normal(size=(400, 4))])
    theta = clean + 0.1 * rng.normal(size=clean.shape)
    moments = 0.01 * 400 * np.eye(10)
    memo = {}
    for start in ([4, 5, 6, 7], [1, 4, 8, 9], [0, 5, 6, 7], [5, 6, 7, 8]):
        expected = _swap_search_by_eigh(theta, moments, start)
        assert refine_law_by_swaps(theta, moments, start).tolist() == expected
        assert refine_law_by_swaps(theta, moments, start, memo=memo).tolist() == expected
        assert memo[frozenset(start)] == tuple(expected)
    # a start the memo knows ends where the memo says, without a search
    memo[frozenset([4, 5, 6, 7])] = (0, 1, 2, 9)
    assert refine_law_by_swaps(theta, moments, [4, 5, 6, 7], memo=memo).tolist() == [0, 1, 2, 9]


def _quiet_imitation(seed, n_rows=4000):
    """A law ``a + b - c = 0`` whose columns are noisy, and a quiet column ``d`` that imitates
    ``a`` closely: the plain least-squares residual prefers the law that uses ``d``."""
    rng = np.random.default_rng(seed)
    a, b = rng.normal(size=(2, n_rows))
    d_clean = a + 0.08 * rng.normal(size=n_rows)   # not a law: 8 % of systematic misfit
    noise = np.array([0.15, 0.15, 0.15, 0.0])
    clean = np.column_stack([a, b, a + b, d_clean])
    theta = clean + noise * rng.normal(size=clean.shape)
    return theta, n_rows * np.diag(noise**2)[None]


@pytest.mark.parametrize("seed", range(5))
def test_noise_ratio_prefers_the_law_that_holds_over_the_quiet_imitation(seed):
    theta, moments = _quiet_imitation(seed)
    law, ratio, selection = select_law(theta, moments)
    assert selection.support.tolist() == [0, 1, 2]
    np.testing.assert_allclose(law[:3] / law[0], [1.0, 1.0, -1.0], atol=0.02)
    assert 0.8 < ratio < 1.2  # the residual is the noise and nothing else
    # plain least squares (no noise model) takes the quiet column instead of a
    quiet = np.linalg.lstsq(theta[:, [1, 3]], theta[:, 2], rcond=None)[1][0]
    noisy = np.linalg.lstsq(theta[:, [0, 1]], theta[:, 2], rcond=None)[1][0]
    assert quiet < noisy


def test_swaps_bring_back_a_column_lost_by_the_path():
    theta, moments = _quiet_imitation(0)
    total = moments[0] / np.mean(theta**2, axis=0)[None, :] / np.mean(theta**2, axis=0)[:, None]
    theta = theta / np.sqrt(np.mean(theta**2, axis=0))
    assert refine_law_by_swaps(theta, total, [1, 2, 3]).tolist() == [0, 1, 2]
    assert sorted(law_elimination_path(theta, total)[:3].tolist()) == [0, 1, 2]


def _true_law(system, library):
    friction = {(system.coords.qd[i], i): c for i, c in enumerate(system.friction)}
    return library.ideal_coefficients(lagrangian=system.lagrangian, classical=friction,
                                      forces=0.0)


def _unforced_noisy_fit(system, angles, level, seed):
    library = paper_catalog(system.coords, angles)
    t = np.arange(0.0, 15.0, 0.01)
    runs = [system.simulate(random_initial_state(system, 1000 * seed + k), t) for k in range(3)]
    rng = np.random.default_rng(seed)
    noisy = [r["q"] + level * r["q"].std(0) * rng.normal(size=r["q"].shape) for r in runs]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(library).fit(noisy, [t] * 3)
    return model, _true_law(system, model.feature_library_)


def _check_unforced(model, true, system, seed, rel_tol):
    coef = model.coefficients()
    assert model.formulation_ == "weak"
    assert model.optimizer_.selection_method_ == "noise ratio"
    np.testing.assert_array_equal(coef != 0, true != 0)
    support = true != 0
    scale = coef[support] @ true[support] / (true[support] @ true[support])
    np.testing.assert_allclose(coef[support] / scale, true[support], rtol=rel_tol)
    # valid: a fresh unforced 5 s trajectory, position RMSE below 10 % of the spread
    t = np.arange(0.0, 5.0, 0.01)
    x0 = random_initial_state(system, 777 + seed)
    truth = system.simulate(x0, t)
    simulated = model.simulate(x0, t)
    rmse = np.sqrt(np.mean((simulated[:, : system.n] - truth["q"]) ** 2, axis=0))
    assert np.all(rmse < 0.1 * np.ptp(truth["q"], axis=0))


def test_unforced_cart_pole_from_one_percent_noisy_positions(cart_pole_system):
    model, true = _unforced_noisy_fit(cart_pole_system, [1], 0.01, seed=0)
    _check_unforced(model, true, cart_pole_system, 0, rel_tol=0.03)
    selection = model.selection_
    assert selection.rule.startswith("one standard error of the noise ratio")
    # the chosen law leaves the noise and nothing else; one term less leaves much more
    chosen = selection.cv_ratio[selection.size - 1]
    assert 0.5 < chosen < 2.0
    assert selection.cv_ratio[selection.size - 2] > 3 * chosen
    with pytest.raises(ValueError, match="noise ratio"):
        model.optimizer_.plot()


def _one_noisy_unforced_run(system, seed, level=0.01):
    """The cart-pole catalog and one unforced 15 s run with noisy positions."""
    t = np.arange(0.0, 15.0, 0.01)
    run = system.simulate(random_initial_state(system, seed), t)
    noisy = run["q"] + level * run["q"].std(0) * np.random.default_rng(seed).normal(
        size=run["q"].shape)
    return paper_catalog(system.coords, [1]), t, noisy


def test_fit_quality_reports_the_noise_ratio_of_an_unforced_law(cart_pole_system):
    from pysindy_xl.quality import fit_quality, quality_lines

    library, t, noisy = _one_noisy_unforced_run(cart_pole_system, seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(library).fit(noisy, t)
    quality = fit_quality(model, {"x": noisy, "t": t})
    assert quality["cv_error"] is None
    assert quality["cv_noise_ratio"] == model.selection_.cv_ratio[model.selection_.size - 1]
    assert any("noise ratio" in line for line in quality_lines(quality))


@pytest.mark.slow
@pytest.mark.parametrize(("name", "level", "seed"), [
    ("double_pendulum", 0.01, 0), ("double_pendulum", 0.03, 1),
])
def test_unforced_noise_cells(name, level, seed, request):
    system = request.getfixturevalue(f"{name}_system")
    angles = {"cart_pole": [1], "double_pendulum": [0, 1]}[name]
    model, true = _unforced_noisy_fit(system, angles, level, seed)
    _check_unforced(model, true, system, seed, rel_tol=0.1)


@pytest.mark.slow
def test_unforced_cart_pole_at_3_percent_over_ten_seeds(cart_pole_system):
    """The bar of the unforced acceptance: the exact support and a valid model from 3 %
    noisy positions in at least 8 of 10 seeds (a rate: any one seed may go either way)."""
    exact = 0
    for seed in range(10):
        model, true = _unforced_noisy_fit(cart_pole_system, [1], 0.03, seed)
        try:
            _check_unforced(model, true, cart_pole_system, seed, rel_tol=0.1)
        except AssertionError:
            continue
        exact += 1
    assert exact >= 8


def test_swaps_start_from_the_best_admissible_path_law(cart_pole_system):
    """Unforced cart-pole at 3 %, the noise sweep's seed 4: the best path support (5 terms,
    held-out ratio 4.8) is a law with an indefinite mass matrix. Swaps from the backward
    path's support of 6 terms reach the true support, but that start was only searched once
    the search runs up to the size of the best admissible path law (before: a 4-term law
    without friction, held-out ratio 33)."""
    t = np.arange(0.0, 10.0, 0.01)
    runs = [cart_pole_system.simulate(random_initial_state(cart_pole_system, 4 + 1000 * k), t)
            for k in range(3)]
    rng = np.random.default_rng(10_004)
    noisy = [r["q"] + 0.03 * r["q"].std(0) * rng.normal(size=r["q"].shape) for r in runs]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(paper_catalog(cart_pole_system.coords, [1])).fit(noisy, [t] * 3)
    true = _true_law(cart_pole_system, model.feature_library_)
    _check_unforced(model, true, cart_pole_system, 4, rel_tol=0.1)
    assert model.selection_.cv_ratio[model.selection_.size - 1] < 3


def test_mixed_optimizer_hands_the_noise_moments_to_its_implicit_part(cart_pole_system):
    library, t, noisy = _one_noisy_unforced_run(cart_pole_system, seed=4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        implicit = px.XLSINDy(library).fit(noisy, t)
        mixed = px.XLSINDy(library, px.MixedOptimizer()).fit(noisy, t)
    assert mixed.optimizer_.mode_ == "implicit"
    assert mixed.optimizer_.implicit_optimizer_.selection_method_ == "noise ratio"
    np.testing.assert_allclose(mixed.coefficients(), implicit.coefficients(), rtol=1e-10)


def test_mass_matrices_of_the_wrong_shape_are_refused_even_without_noise_moments():
    theta = np.random.default_rng(0).normal(size=(100, 3))
    with pytest.raises(ValueError, match="mass_matrices"):
        px.ImplicitOptimizer().fit_catalog(theta, 1, [], mass_matrices=np.ones((2, 2)))


def _two_uncoupled_laws(seed, n_samples=3000, sigma=0.05):
    """Coordinate 0 holds ``2 a - 0.5 b - (2 a - 0.5 b) = 0`` on columns 0-2, coordinate 1
    holds ``c - 3 d - (c - 3 d) = 0`` on columns 3-5; column 6 (noise-free) touches both. The
    non-zero entries of columns 0-5 get noise of standard deviation ``sigma``."""
    rng = np.random.default_rng(seed)
    a, b, c, d, e = rng.normal(size=(5, n_samples))
    zero = np.zeros(n_samples)
    clean = np.vstack([np.column_stack([a, b, 2 * a - 0.5 * b, zero, zero, zero, e]),
                       np.column_stack([zero, zero, zero, c, d, c - 3 * d, -e])])
    noisy = clean + sigma * rng.normal(size=clean.shape) * (clean != 0)
    noisy[:, 6] = clean[:, 6]
    noisy_columns = clean.reshape(2, n_samples, 7).any(axis=1) & (np.arange(7) < 6)
    moments = np.stack([np.diag(sigma**2 * n_samples * block) for block in noisy_columns])
    return noisy, moments


def test_implicit_fit_support_gives_each_uncoupled_group_its_noise_ratio_law():
    theta, moments = _two_uncoupled_laws(0)
    support = np.array([True] * 6 + [False])
    opt = px.ImplicitOptimizer().fit_problem(
        CatalogProblem.from_arrays(theta, 2, [], noise_moments=moments), support)
    assert opt.selection_method_ == "given support"
    assert [g.tolist() for g in opt.law_groups_] == [[0, 1, 2], [3, 4, 5]]
    for group, law in zip(([0, 1, 2], [3, 4, 5]), ([-2.0, 0.5, 1.0], [-1.0, 3.0, 1.0]),
                          strict=True):
        block, noise = theta[:, group], moments.sum(axis=0)[np.ix_(group, group)]
        values, vectors = scipy.linalg.eigh(block.T @ block, noise)
        # scaled as the catalog's convention: +1 on the term of largest contribution
        vector = vectors[:, 0]
        vector = vector / vector[np.argmax(np.abs(vector) * np.linalg.norm(block, axis=0))]
        np.testing.assert_allclose(opt.coef_[group], vector, rtol=1e-9)
        np.testing.assert_allclose(opt.coef_[group], law, atol=0.02)
        assert values[0] == pytest.approx(opt.law_noise_ratios_[group[0] // 3], rel=1e-9)
        assert 0.9 < values[0] < 1.1  # the law holds to the noise
    assert opt.coef_[6] == 0
    # without noise moments: the smallest right singular vector of the unit-norm columns
    plain = px.ImplicitOptimizer().fit_problem(
        CatalogProblem.from_arrays(theta, 2, []), support)
    unit = theta[:, :3] / np.linalg.norm(theta[:, :3], axis=0)
    vector = np.linalg.svd(unit)[2][-1] / np.linalg.norm(theta[:, :3], axis=0)
    np.testing.assert_allclose(plain.coef_[:3], vector / vector[2], rtol=1e-9)
    assert plain.law_noise_ratios_ is None
    with pytest.raises(ValueError, match=r"support: expected a boolean array of shape \(7,\)"):
        px.ImplicitOptimizer().fit_problem(
            CatalogProblem.from_arrays(theta, 2, []), support.astype(int))
    with pytest.raises(px.NoLawFoundError, match="a law needs at least two terms"):
        px.ImplicitOptimizer().fit_problem(
            CatalogProblem.from_arrays(theta, 2, []), np.eye(7, dtype=bool)[0])
    with pytest.raises(px.NoLawFoundError, match="0 non-zero column"):
        px.ImplicitOptimizer().fit_problem(
            CatalogProblem.from_arrays(theta, 2, []), np.zeros(7, dtype=bool))
    with pytest.raises(px.NoLawFoundError, match="share a coordinate"):  # 0 and 3: uncoupled
        px.ImplicitOptimizer().fit_problem(
            CatalogProblem.from_arrays(theta, 2, []), np.isin(np.arange(7), [0, 3]))


def test_implicit_ensemble_refits_the_agreed_terms_instead_of_median_laws():
    theta, moments = _two_uncoupled_laws(1)
    ensemble = px.EnsembleOptimizer(px.ImplicitOptimizer(), n_models=6).fit_catalog(
        theta, 2, [], noise_moments=moments)
    assert ensemble.aggregate_ == "refit"
    np.testing.assert_array_equal(ensemble.coef_ != 0, [True] * 6 + [False])
    refit = px.ImplicitOptimizer().fit_problem(
        CatalogProblem.from_arrays(theta, 2, [], noise_moments=moments), ensemble.coef_ != 0)
    np.testing.assert_allclose(ensemble.coef_, refit.coef_, rtol=1e-12)
    median = np.median(ensemble.coef_samples_, axis=0)
    assert not np.allclose(ensemble.coef_, median, rtol=1e-9, atol=0)


class _OneColumnImplicit(px.ImplicitOptimizer):
    """Every subsample fit keeps column 0 alone: the agreed terms form no law."""

    def _solve(self, problem):
        self.coef_ = np.eye(problem.n_features)[0]
        return self


def test_implicit_ensemble_says_when_the_agreed_terms_form_no_law():
    theta, moments = _two_uncoupled_laws(2)
    with pytest.raises(px.NoLawFoundError, match=r"the refit on the 1 term\(s\) kept by at "
                       r"least 0.5 of the fits failed \(support: 1 non-zero column"):
        px.EnsembleOptimizer(_OneColumnImplicit(), n_models=4).fit_catalog(
            theta, 2, [], noise_moments=moments)
