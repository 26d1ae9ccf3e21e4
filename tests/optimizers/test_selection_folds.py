"""The fold systems of the cross-validated selection (the R of all folds but one, combined by
triangular-pentagonal QRs) against numpy's lstsq on each fold's training rows."""

import numpy as np
import pytest

from pysindy_xl.optimizers.selection import _systems, fold_labels


def _columns(n_rows, n_columns, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n_rows, n_columns)) @ (np.eye(n_columns)
                                                + 0.5 * rng.normal(size=(n_columns,) * 2))
    x *= np.logspace(-2, 2, n_columns)
    return x, x[:, :3] @ [1.0, -2.0, 0.5] + 0.05 * rng.normal(size=n_rows)


@pytest.mark.parametrize(("n_rows", "n_columns", "n_blocks"),
                         [(600, 8, 1), (300, 40, 3), (150, 40, 3), (90, 40, 1)])
def test_fold_systems_solve_the_training_rows(n_rows, n_columns, n_blocks):
    # many rows per column, a fold part shorter than the columns, and training rows fewer
    # than the columns (then only the residual's size is compared: lstsq is not unique)
    x, y = _columns(n_rows, n_columns)
    scale = np.sqrt(np.mean(x**2, axis=0))
    y_rms = np.sqrt(np.mean(y**2))
    labels = fold_labels(n_rows, n_blocks, 5)
    reduced, folds = _systems(x, y, n_blocks, 5)
    assert [f[0] for f in folds] == list(range(5))
    for fold, x_test, y_test, r_factor, rhs in folds:
        train = labels != fold
        np.testing.assert_array_equal(x_test, (x / scale)[~train])
        np.testing.assert_allclose(y_test, y[~train] / y_rms)
        assert r_factor.shape == (min(train.sum(), n_columns + 1), n_columns)
        assert np.allclose(np.tril(r_factor, -1), 0)
        # R^T R and R^T (Q^T y) are the training rows' normal equations
        xs = x[train] / scale
        np.testing.assert_allclose(r_factor.T @ r_factor, xs.T @ xs, rtol=1e-9,
                                   atol=1e-9 * np.abs(xs.T @ xs).max())
        np.testing.assert_allclose(r_factor.T @ rhs, xs.T @ y[train] / y_rms, rtol=1e-9,
                                   atol=1e-9 * np.abs(xs.T @ y[train]).max() / y_rms)
        if train.sum() > n_columns:
            expected = np.linalg.lstsq(xs, y[train] / y_rms, rcond=None)[0]
            found = np.linalg.lstsq(r_factor, rhs, rcond=None)[0]
            np.testing.assert_allclose(found, expected, rtol=1e-8, atol=1e-10)
    # the reduced system of all rows
    active, r_all, rhs_all = reduced
    assert active.all()
    if n_rows > n_columns + 1:
        xs = x / scale
        np.testing.assert_allclose(r_all.T @ r_all, xs.T @ xs, rtol=1e-9,
                                   atol=1e-9 * np.abs(xs.T @ xs).max())
        np.testing.assert_allclose(r_all.T @ rhs_all, xs.T @ y, rtol=1e-9,
                                   atol=1e-9 * np.abs(xs.T @ y).max())


def test_fold_systems_with_an_empty_fold():
    # fewer rows per block than folds: some folds have no rows and are skipped
    x, y = _columns(9, 3)
    reduced, folds = _systems(x, y, 3, 5)
    labels = fold_labels(9, 3, 5)
    assert sorted(f[0] for f in folds) == sorted(set(labels.tolist()))
    for fold, _, _, r_factor, _ in folds:
        xs = (x / np.sqrt(np.mean(x**2, axis=0)))[labels != fold]
        np.testing.assert_allclose(r_factor.T @ r_factor, xs.T @ xs, atol=1e-10)
