"""Cross-validated scoring of the sparsity selection against brute-force least squares on
every fold (numpy's lstsq on the training rows, error on the held-out rows)."""

import numpy as np
import pytest

from pysindy_xl.optimizers import select_support
from pysindy_xl.optimizers.selection import (
    cross_validated_size,
    cross_validated_supports,
    fold_labels,
)


def _problem(n_rows=240, n_columns=12, seed=0):
    rng = np.random.default_rng(seed)
    # correlated columns on very different scales, a sparse law and some noise
    x = rng.normal(size=(n_rows, n_columns)) @ (np.eye(n_columns)
                                                + 0.4 * rng.normal(size=(n_columns,) * 2))
    scales = np.logspace(-3, 3, n_columns)
    coef = np.zeros(n_columns)
    coef[[1, 4, 7]] = np.array([1.0, -0.5, 0.2]) / scales[[1, 4, 7]]
    x *= scales
    return x, x @ coef + 0.01 * rng.normal(size=n_rows)


def _brute_force(x, y, supports, n_blocks, n_folds):
    """Held-out relative mean squared error of each support, fold by fold, by lstsq."""
    labels = fold_labels(len(y), n_blocks, n_folds)
    y_scale = np.mean(y**2)
    errors = np.zeros((n_folds, len(supports)))
    for fold in range(n_folds):
        train, test = labels != fold, labels == fold
        for m, support in enumerate(supports):
            coef = np.linalg.lstsq(x[train][:, support], y[train], rcond=None)[0]
            errors[fold, m] = np.mean((x[test][:, support] @ coef - y[test]) ** 2) / y_scale
    return errors


@pytest.mark.parametrize("n_blocks", [1, 3])
def test_nested_scores_equal_fold_by_fold_least_squares(n_blocks):
    """Every nested model of a shuffled, truncated column order scores as a direct fit on
    each fold's training rows does (the scores come from one reduction of each fold,
    re-triangularized in the path's order)."""
    x, y = _problem()
    order = np.random.default_rng(1).permutation(x.shape[1])[:9]
    errors = cross_validated_size(x, y, order, n_blocks=n_blocks, n_folds=4)
    expected = _brute_force(x, y, [order[: k + 1] for k in range(len(order))], n_blocks, 4)
    np.testing.assert_allclose(errors, expected, rtol=1e-8)


def test_support_scores_equal_fold_by_fold_least_squares():
    x, y = _problem(seed=2)
    supports = [np.array([1, 4, 7]), np.array([0, 4]), np.arange(12), np.array([11])]
    errors = cross_validated_supports(x, y, supports, n_blocks=2, n_folds=5)
    np.testing.assert_allclose(errors, _brute_force(x, y, supports, 2, 5), rtol=1e-8)


def test_selection_finds_the_law_across_scales():
    """The three terms of the law, on columns scaled 1e-3 to 1e3, and no other."""
    x, y = _problem()
    result = select_support(x, y, n_blocks=2)
    assert result.support.tolist() == [1, 4, 7]


def _product_catalog(n_rows=600, seed=0):
    """Columns of a trigonometric product catalog with its exact identities
    (``v cos^2 + v sin^2 = v``) and a near-identity at 1e-8 (a quadrature-level remainder), a
    sparse law and noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 20, n_rows)
    q = np.sin(0.7 * t) + 0.5 * np.sin(1.9 * t + 1)
    v = np.cos(0.3 * t) + 0.4 * rng.normal(size=n_rows).cumsum() / np.sqrt(n_rows)
    base = [v, v * np.cos(q), v * np.sin(q), q, q * v]
    columns = base + [b * np.cos(q) ** 2 for b in base] + [b * np.sin(q) ** 2 for b in base]
    columns += [v + 1e-8 * np.cos(5 * t), rng.normal(size=n_rows)]
    scales = np.logspace(-2, 2, len(columns))
    x = np.column_stack(columns) * scales
    y = x[:, [0, 1, 3]] @ (np.array([1.0, 0.3, -2.0]) / scales[[0, 1, 3]])
    return x, y + 0.05 * np.std(y) * rng.normal(size=n_rows)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_selection_does_not_flip_at_the_rounding_level(seed):
    # exactly dependent columns leave the choice between equivalent supports to rounding,
    # unless the selection settles it: perturbations of 1e-12 keep the support
    x, y = _product_catalog(seed=seed)
    support = select_support(x, y, n_blocks=2).support
    # the law in its simplest columns (the earliest of each identity)
    assert set(support) >= {0, 1, 3} and len(support) <= 5
    for draw in range(4):
        noise = np.random.default_rng(100 + draw).normal(size=x.shape)
        perturbed = select_support(x * (1 + 1e-12 * noise), y, n_blocks=2).support
        assert perturbed.tolist() == support.tolist()
