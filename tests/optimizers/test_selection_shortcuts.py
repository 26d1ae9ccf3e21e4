"""Shortcuts of the support and law searches give what the long way gives, to the bit.

- the argmin of bisected roots, bisecting only the candidates that can win, against the
  argmin of every candidate's full bisection;
- the admissible lasso on cvxpy's data canonicalized once, against ``problem.solve``;
- the swap searches of one selection sharing where supports end, against independent searches;
- the swap refinement stopped at the first size with a model within the one-standard-error
  bound, against refining every size up to the path's choice.
"""

import numpy as np
import pytest

from pysindy_xl.optimizers import admissible, selection
from pysindy_xl.optimizers._swaps import column_norms2, swap_search
from pysindy_xl.optimizers.noise_ratio import (
    _bordered_minima,
    _constrained_minima,
    _least_bordered,
    _least_constrained,
    law_forward_path,
    noise_pencil,
)


def _pencils(seed, n_problems=40):
    """Pencils of random columns, some with near-dependent and exactly repeated columns."""
    rng = np.random.default_rng(seed)
    for case in range(n_problems):
        n_columns = int(rng.integers(3, 25))
        theta = rng.normal(size=(3 * n_columns, n_columns))
        theta[:, -1] = theta[:, :3] @ rng.normal(size=3) + 1e-4 * rng.normal(size=len(theta))
        if case % 3 == 0:
            theta[:, 1] = theta[:, 0]  # ties between candidates
        spread = rng.normal(size=(n_columns, n_columns))
        moments = 1e-3 * spread @ spread.T + 1e-6 * np.eye(n_columns)
        yield theta, moments


def test_least_constrained_is_the_argmin_of_the_full_bisection():
    checked = 0
    for theta, moments in _pencils(0):
        support = np.arange(theta.shape[1])
        while len(support) > 2:
            values, vectors = noise_pencil(theta[:, support], moments[np.ix_(support, support)])
            expected = int(np.argmin(_constrained_minima(values, vectors)))
            assert _least_constrained(values, vectors) == expected
            support = np.delete(support, expected)
            checked += 1
    assert checked > 300


def test_least_bordered_is_the_argmin_of_the_full_bisection():
    for theta, moments in _pencils(1):
        gram = theta.T @ theta
        support, outside = [0, 2], np.arange(3, theta.shape[1])
        if outside.size < 2:
            continue
        values, vectors = noise_pencil(theta[:, support], moments[np.ix_(support, support)])
        args = (values, vectors.T @ gram[np.ix_(support, outside)],
                vectors.T @ moments[np.ix_(support, outside)], np.diag(gram)[outside],
                np.diag(moments)[outside])
        assert _least_bordered(*args) == int(np.argmin(_bordered_minima(*args)))
        # a subset of the candidates: the argmin among them
        chosen = np.arange(0, outside.size, 2)
        minima = _bordered_minima(*args)
        assert _least_bordered(*args, candidates=chosen) == chosen[np.argmin(minima[chosen])]


def test_forward_path_starts_with_the_best_pair():
    """The best pair by brute force: each pair's smallest noise ratio (generalized eigenvalue)."""
    import scipy.linalg
    checked = 0
    for theta, moments in _pencils(2, n_problems=10):
        n = theta.shape[1]
        ratios = np.full((n, n), np.inf)
        for i in range(n):
            for j in range(i + 1, n):
                pair = [i, j]
                ratios[i, j] = scipy.linalg.eigh(theta[:, pair].T @ theta[:, pair],
                                                 moments[np.ix_(pair, pair)],
                                                 eigvals_only=True)[0]
        best = np.unravel_index(np.argmin(ratios), ratios.shape)
        if np.sort(ratios[np.isfinite(ratios)])[1] < ratios[best] * (1 + 1e-6):
            continue  # a near tie: the bisection may pick either
        assert sorted(law_forward_path(theta, moments, max_size=2).tolist()) == sorted(best)
        checked += 1
    assert checked >= 5


def test_admissible_lasso_solves_as_cvxpy():
    cp = pytest.importorskip("cvxpy")
    if admissible._solver() != cp.CLARABEL:
        pytest.skip("Clarabel is not installed")
    rng = np.random.default_rng(3)
    n_columns, n = 8, 2
    theta = rng.normal(size=(60, n_columns))
    theta[:, 0] = theta[:, 1] - 0.5 * theta[:, 2] + 1e-3 * rng.normal(size=60)
    mass = np.zeros((5, n_columns, n, n))
    mass[:, 1, 0, 0] = mass[:, 2, 1, 1] = 1.0
    mass[:, 3, 0, 1] = mass[:, 3, 1, 0] = 0.3
    mass[:, 4] = rng.normal(size=(5, n, n))
    reference = admissible.reference_mass_matrices(mass)
    xi = cp.Variable(n_columns)
    weights = cp.Parameter(n_columns, nonneg=True)
    matrix = cp.reshape(reference.reshape(n_columns, n * n).T @ xi, (n, n), order="C")
    problem = cp.Problem(cp.Minimize(cp.sum_squares(theta @ xi) + weights @ cp.abs(xi)),
                         [(matrix + matrix.T) / 2 >> np.eye(n)])
    fast = admissible._clarabel_solves(problem, xi, weights)
    assert fast is not None
    for values in (np.zeros(n_columns), np.full(n_columns, 0.3), rng.uniform(0, 2, n_columns)):
        found = fast(values)
        weights.value = values
        problem.solve(solver=cp.CLARABEL)
        np.testing.assert_array_equal(found, xi.value)


def test_shared_swap_searches_end_where_independent_ones_do():
    rng = np.random.default_rng(4)
    for _ in range(20):
        n_rows, n_columns = 80, 14
        base = rng.normal(size=(n_rows, 4))
        xs = np.column_stack([base, base @ rng.normal(size=(4, n_columns - 4))
                              + 0.3 * rng.normal(size=(n_rows, n_columns - 4))])
        y = xs[:, [0, 5, 9]] @ [1.0, -2.0, 0.5] + 0.05 * rng.normal(size=n_rows)
        usable = np.ones(n_columns, dtype=bool)
        norms2 = column_norms2(xs)
        memo = {}
        for size in (2, 3, 4):
            for _ in range(5):
                start = rng.choice(n_columns, size, replace=False)
                alone = swap_search(xs, y, usable, start, 50, norms2=norms2)
                shared = swap_search(xs, y, usable, start, 50, norms2=norms2, memo=memo)
                np.testing.assert_array_equal(shared, alone)
        assert memo


def test_swap_refinement_stopped_early_chooses_what_refining_every_size_chooses(monkeypatch):
    rng = np.random.default_rng(5)
    problems = []
    for _ in range(30):
        n_rows, n_columns = 300, 60
        base = rng.normal(size=(n_rows, 8))
        xs = np.column_stack([base, base @ rng.normal(size=(8, n_columns - 8))
                              + 0.2 * rng.normal(size=(n_rows, n_columns - 8))])
        true = rng.choice(n_columns, 10, replace=False)
        y = xs[:, true] @ rng.uniform(0.5, 2.0, 10) + 0.5 * rng.normal(size=n_rows)
        problems.append((xs, y))
    stopped = [selection.select_support(xs, y) for xs, y in problems]
    refined_sizes = []

    def every_size(reduced, held_out, paths, seen, limit, bound, keep=(), free=None):
        found = original(reduced, held_out, paths, seen, limit, -np.inf, keep, free)
        refined_sizes.append((limit, max((c[0] for c in found), default=0)))
        return found

    original = selection._swap_candidates
    monkeypatch.setattr(selection, "_swap_candidates", every_size)
    for (xs, y), early in zip(problems, stopped, strict=True):
        full = selection.select_support(xs, y)
        assert (full.size, full.support.tolist()) == (early.size, early.support.tolist())
        np.testing.assert_allclose(early.cv_error[early.size - 1],
                                   full.cv_error[full.size - 1], rtol=1e-10)
    # the refinement went past the chosen size where every size was refined
    assert sum(largest > early.size for (_, largest), early
               in zip(refined_sizes, stopped, strict=True)) >= 5, refined_sizes
