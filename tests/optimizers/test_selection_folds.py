"""The held-out scores of the cross-validated selection (each fold's training rows reduced on
the scored columns) against numpy's lstsq on each fold's training rows, and the updates that
the paths and swaps use instead of refactorizations against direct ones."""

import numpy as np
import pytest
import scipy.linalg

from pysindy_xl.optimizers import _forward
from pysindy_xl.optimizers._folds import HeldOutRows, fold_labels
from pysindy_xl.optimizers._forward import forward_order
from pysindy_xl.optimizers._swaps import first_swaps, swap_search
from pysindy_xl.optimizers._triangular import without_columns


def _columns(n_rows, n_columns, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n_rows, n_columns)) @ (np.eye(n_columns)
                                                + 0.5 * rng.normal(size=(n_columns,) * 2))
    x *= np.logspace(-2, 2, n_columns)
    return x, x[:, :3] @ [1.0, -2.0, 0.5] + 0.05 * rng.normal(size=n_rows)


def _direct_errors(x, y, supports, n_blocks, n_folds):
    """Held-out relative mean squared error by lstsq on each fold's training rows (inf where
    the training rows do not determine the support)."""
    xs = x / np.sqrt(np.mean(x**2, axis=0))
    ys = y / np.sqrt(np.mean(y**2))
    labels = fold_labels(len(y), n_blocks, n_folds)
    errors = np.full((n_folds, len(supports)), np.inf)
    for fold in set(labels.tolist()):
        train, test = labels != fold, labels == fold
        if not train.any():
            continue
        for m, support in enumerate(supports):
            coef, _, rank, _ = np.linalg.lstsq(xs[train][:, support], ys[train], rcond=None)
            if rank == len(support):
                errors[fold, m] = np.mean((xs[test][:, support] @ coef - ys[test]) ** 2)
    return errors


def _held_out(x, y, n_blocks, n_folds, whole=False):
    return HeldOutRows(x / np.sqrt(np.mean(x**2, axis=0)), y, n_blocks, n_folds, whole=whole)


@pytest.mark.parametrize("whole", [False, True])
@pytest.mark.parametrize(("n_rows", "n_columns", "n_blocks"),
                         [(600, 8, 1), (300, 40, 3), (150, 40, 3)])
def test_nested_errors_solve_the_training_rows(n_rows, n_columns, n_blocks, whole):
    # many rows per column, and a fold part shorter than the columns; the folds reduced on
    # the scored columns or once on all of them
    x, y = _columns(n_rows, n_columns)
    order = np.random.default_rng(1).permutation(n_columns)[: n_columns - 3]
    held_out = _held_out(x, y, n_blocks, 5, whole)
    assert [f[0] for f in held_out.folds] == list(range(5))
    errors = held_out.nested_errors(order)
    expected = _direct_errors(x, y, [order[: k + 1] for k in range(len(order))], n_blocks, 5)
    finite = np.isfinite(expected)
    np.testing.assert_array_equal(np.isfinite(errors), finite)
    np.testing.assert_allclose(errors[finite], expected[finite], rtol=1e-7)


@pytest.mark.parametrize("whole", [False, True])
def test_nested_errors_with_fewer_training_rows_than_columns(whole):
    # models larger than the training rows are undetermined (inf), the others exact
    x, y = _columns(45, 40)
    errors = _held_out(x, y, 1, 5, whole).nested_errors(np.arange(40))
    expected = _direct_errors(x, y, [np.arange(k + 1) for k in range(40)], 1, 5)
    assert np.isinf(errors[:, 36:]).all()
    np.testing.assert_allclose(errors[:, :30], expected[:, :30], rtol=1e-7)


@pytest.mark.parametrize("whole", [False, True])
def test_support_errors_solve_the_training_rows(whole):
    x, y = _columns(300, 30, seed=2)
    supports = [np.array([1, 4, 7]), np.array([0, 4]), np.arange(30), np.array([29]),
                np.array([3, 17, 25, 8])]
    errors = _held_out(x, y, 2, 5, whole).support_errors(supports)
    np.testing.assert_allclose(errors, _direct_errors(x, y, supports, 2, 5), rtol=1e-8)


def test_reduction_from_the_folds_solves_all_rows():
    x, y = _columns(400, 20, seed=3)
    xs = x / np.sqrt(np.mean(x**2, axis=0))
    r_factor, rhs = HeldOutRows(xs, y, 2, 5, whole=True).reduction()
    np.testing.assert_allclose(r_factor.T @ r_factor, xs.T @ xs, rtol=1e-10,
                               atol=1e-10 * np.abs(xs.T @ xs).max())
    np.testing.assert_allclose(r_factor.T @ rhs, xs.T @ y, rtol=1e-10,
                               atol=1e-10 * np.abs(xs.T @ y).max())


@pytest.mark.parametrize("whole", [False, True])
def test_folds_with_an_empty_fold(whole):
    # fewer rows per block than folds: some folds have no rows and are skipped
    x, y = _columns(9, 3)
    held_out = _held_out(x, y, 3, 5, whole)
    labels = fold_labels(9, 3, 5)
    assert sorted(f[0] for f in held_out.folds) == sorted(set(labels.tolist()))
    errors = held_out.nested_errors([0, 1])
    assert np.isinf(errors[sorted(set(range(5)) - set(labels.tolist()))]).all()


@pytest.mark.parametrize(("m", "n", "removed"), [(60, 60, 7), (200, 180, 40), (30, 40, 5),
                                                 (50, 50, 1), (6, 6, 5)])
def test_column_removal_matches_a_new_qr(m, n, removed):
    """The staircase update equals a Householder QR of the remaining columns (up to the signs
    of the rows) at rounding level."""
    rng = np.random.default_rng(m + n)
    r_factor = np.triu(rng.normal(size=(m, n)) * np.logspace(0, 3, n))
    kept = np.sort(rng.choice(n, n - removed, replace=False))
    updated = without_columns(r_factor, kept, block=8)
    direct = scipy.linalg.qr(r_factor[:, kept], mode="r")[0][: min(m, len(kept))]
    assert updated.shape == direct.shape
    assert np.array_equal(np.triu(updated), updated)
    np.testing.assert_allclose(np.abs(updated), np.abs(direct), rtol=0,
                               atol=1e-12 * np.abs(direct).max())


def _forward_by_refitting(x, y, steps):
    """Forward selection by a new least-squares fit of every enlarged support."""
    chosen = []
    for _ in range(steps):
        best, best_rss = None, np.inf
        for c in range(x.shape[1]):
            if c in chosen:
                continue
            columns = x[:, chosen + [c]]
            rss = np.sum((y - columns @ np.linalg.lstsq(columns, y, rcond=None)[0]) ** 2)
            if rss < best_rss:
                best, best_rss = c, rss
        chosen.append(best)
    return chosen


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_forward_order_matches_refitting(seed):
    # correlated columns on different scales: the cheap gain bounds must not change a pick
    x, y = _columns(200, 25, seed=seed)
    order = forward_order(np.ones(25, dtype=bool), x, y, max_steps=12)
    assert order[:12].tolist() == _forward_by_refitting(x, y, 12)
    assert sorted(order.tolist()) == list(range(25))


def _forward_by_orthogonalizing(x, y, steps):
    """Forward selection on explicitly orthogonalized columns (every column's part off the
    chosen ones, updated a step)."""
    orthogonal, residual, chosen = x.copy(), y.copy(), []
    for _ in range(steps):
        norms2 = np.sum(orthogonal**2, axis=0)
        gain = (orthogonal.T @ residual) ** 2 / np.where(norms2 > 0, norms2, np.inf)
        gain[chosen] = -np.inf
        j = int(np.argmax(gain))
        direction = orthogonal[:, j] / np.sqrt(norms2[j])
        residual = residual - direction * (direction @ residual)
        orthogonal -= np.outer(direction, direction @ orthogonal)
        chosen.append(j)
    return chosen


@pytest.mark.parametrize("seed", [0, 11, 17, 18, 21])
def test_forward_order_with_cancelling_norm_updates(seed, monkeypatch):
    # column 5 is 1e7 times column 0 plus a unit part: once 5 is chosen, the norm of column
    # 0's part off it is a difference of numbers 1e14 times larger, wrong in the first digit;
    # the picks must still be those of the explicit orthogonalization (they are not from the
    # cheap values alone on these seeds); the bounds are used however small the problem
    monkeypatch.setattr(_forward, "_EXACT_WORK", 0)
    rng = np.random.default_rng(seed)
    base = rng.normal(size=(200, 5))
    f, g, h = rng.normal(size=(3, 200))
    x = np.column_stack([base, 1e7 * base[:, 0] + f, f + 0.3 * g + 0.2 * base[:, 1] + 0.1 * h, g,
                         0.1 * rng.normal(size=(200, 40))])  # enough candidates for the bounds
    y = 3 * base[:, 0] + 2 * base[:, 1] + f + 0.01 * rng.normal(size=200)
    order = forward_order(np.ones(48, dtype=bool), x, y, max_steps=5)
    assert order[:5].tolist() == _forward_by_orthogonalizing(x, y, 5)


def _swaps_by_refitting(x, y, support, max_swaps=50):
    """Best-improvement single swaps by refitting every exchanged support."""
    support = list(support)

    def rss(columns):
        a = x[:, columns]
        return np.sum((y - a @ np.linalg.lstsq(a, y, rcond=None)[0]) ** 2)

    current = rss(support)
    for _ in range(max_swaps):
        best, best_rss = None, current
        for j in range(len(support)):
            for c in range(x.shape[1]):
                if c in support:
                    continue
                trial = support[:j] + [c] + support[j + 1:]
                value = rss(trial)
                if value < best_rss - 1e-9 * current:
                    best, best_rss = trial, value
        if best is None:
            break
        support, current = best, best_rss
    return sorted(support)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_swap_search_matches_refitting(seed):
    """The updated basis of the swap search reaches the supports of direct refits."""
    rng = np.random.default_rng(seed)
    x, _ = _columns(150, 18, seed=seed)
    y = x[:, [2, 5, 11, 14]] @ rng.normal(size=4) + 0.01 * rng.normal(size=150)
    start = rng.choice(18, 4, replace=False)
    found = swap_search(x, y, np.ones(18, dtype=bool), start, max_swaps=50)
    assert found.tolist() == _swaps_by_refitting(x, y, start)


def test_first_swaps_hand_over_the_basis_of_the_swapped_support():
    """The (Q, Q^T x) that the first step hands to the search span the swapped support, are
    orthonormal, and the search from it ends where a search from scratch does."""
    rng = np.random.default_rng(4)
    x, _ = _columns(200, 30, seed=4)
    y = x[:, [3, 8, 20, 27]] @ rng.normal(size=4) + 0.01 * rng.normal(size=200)
    usable = np.ones(30, dtype=bool)
    order = rng.permutation(30)
    first = first_swaps(x, y, usable, order, list(range(1, 9)))
    swapped_sizes = [k for k, (_, swapped, _) in first.items() if swapped is not None]
    assert swapped_sizes
    for k in swapped_sizes:
        rss, swapped, (basis, in_span) = first[k]
        np.testing.assert_allclose(basis.T @ basis, np.eye(k), atol=1e-12)
        np.testing.assert_allclose(in_span, basis.T @ x, atol=1e-10 * np.abs(x).max())
        projected = basis @ (basis.T @ x[:, swapped])
        np.testing.assert_allclose(projected, x[:, swapped], atol=1e-10 * np.abs(x).max())
        handed = swap_search(x, y, usable, swapped, 49, rss=rss, previous=order[:k],
                             start=(basis, in_span))
        fresh = swap_search(x, y, usable, swapped, 49, rss=rss, previous=order[:k])
        assert handed.tolist() == fresh.tolist()


def test_reduction_needs_the_folds_on_all_columns():
    x, y = _columns(60, 4)
    with pytest.raises(ValueError, match="whole"):
        _held_out(x, y, 1, 5).reduction()
