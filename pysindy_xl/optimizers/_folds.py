"""Held-out errors of nested and arbitrary supports over contiguous folds of rows (the scores of
:func:`~pysindy_xl.optimizers.selection.select_support`).

Each fold's training rows are reduced to the triangular system of only the columns the scored
models use, so the cost follows the models scored, not the catalog's width (or, when the scores
use most columns, once on all of them).
"""

from __future__ import annotations

import numpy as np

from ._triangular import solve_triangular, triangular_system


def fold_labels(n_rows: int, n_blocks: int, n_folds: int) -> np.ndarray:
    """Fold of each row: contiguous stretches within each of ``n_blocks`` equal row blocks."""
    per_block = n_rows // n_blocks
    position = np.arange(n_rows) % per_block
    return np.minimum(position * n_folds // per_block, n_folds - 1)


class HeldOutRows:
    """Unit-RMS columns ``xs`` and target split into folds: the rows each fold holds out and
    trains on (folds without test or training rows skipped), errors relative to the mean
    square of ``y``.

    Each fold's rows are reduced to ``[R | Q^T y]``, and the training system of a fold is the
    QR of the other folds' stacked reductions (at most ``(n_folds - 1)(k + 1)`` rows instead of
    all its training rows). With ``whole``, this is done once on all columns and every score
    re-triangularizes the columns it needs (a QR of ``(F + 1) x k`` per fold: the cheaper way
    when the scores use about half the columns or more); otherwise each score reduces the
    rows on just its columns.

    Parameters
    ----------
    xs : ndarray, shape (n_rows, F)
        Columns (already scaled).
    y : ndarray, shape (n_rows,)
        Target.
    n_blocks, n_folds : int
        Equal row blocks (coordinates) and folds within each.
    whole : bool, default False
        Reduce the folds on all columns once.
    """

    def __init__(self, xs, y, n_blocks: int, n_folds: int, whole: bool = False):
        self.xs, self.y = xs, y
        self.y_rms = np.sqrt(max(float(np.mean(y**2)), 1e-300))
        self.n_folds = n_folds
        labels = fold_labels(len(y), n_blocks, n_folds)
        self.parts = [np.flatnonzero(labels == fold) for fold in range(n_folds)]
        self.folds = [(fold, rows) for fold, rows in enumerate(self.parts)
                      if 0 < len(rows) < len(y)]
        self._whole = None
        if whole:
            parts = self._reduced_parts(np.arange(xs.shape[1]))
            self._whole = (parts, list(self._training_systems(np.arange(xs.shape[1]), parts)))

    @property
    def whole(self) -> bool:
        """Whether the folds are reduced on all columns."""
        return self._whole is not None

    def reduction(self):
        """The reduction of all rows from the folds' reductions on all columns.

        Returns
        -------
        r_factor, rhs : ndarray
            ``(R, Q^T y)`` of ``[xs | y]`` as :func:`triangular_system` gives them.

        Raises
        ------
        ValueError
            Without ``whole``.
        """
        if self._whole is None:
            raise ValueError("whole: the folds were not reduced on all columns")
        stacked = np.vstack([part for part in self._whole[0] if part is not None])
        return triangular_system(stacked[:, :-1], stacked[:, -1])

    def _reduced_parts(self, columns):
        """``[R | Q^T y]`` of each fold's rows on ``columns`` (None for a fold without rows)."""
        xs = self.xs[:, columns]
        return [np.column_stack(triangular_system(xs[rows], self.y[rows])) if len(rows)
                else None for rows in self.parts]

    def _training_systems(self, columns, parts):
        """Per fold ``(fold, R, Q^T y, x_test, y_test)`` on ``columns`` from the reductions
        ``parts`` of the folds' rows, ``y`` divided by its RMS."""
        for fold, test in self.folds:
            others = np.vstack([part for g, part in enumerate(parts)
                                if g != fold and part is not None])
            r_factor, rhs = triangular_system(others[:, :-1], others[:, -1])
            yield (fold, r_factor, rhs / self.y_rms, self.xs[np.ix_(test, columns)],
                   self.y[test] / self.y_rms)

    def _systems(self, columns):
        """:meth:`_training_systems` on ``columns``."""
        columns = np.asarray(columns, dtype=int)
        if self._whole is None:
            yield from self._training_systems(columns, self._reduced_parts(columns))
            return
        for fold, r_factor, rhs, x_test, y_test in self._whole[1]:
            yield (fold, *triangular_system(r_factor[:, columns], rhs), x_test[:, columns],
                   y_test)

    def nested_errors(self, order) -> np.ndarray:
        """Held-out errors of every nested model ``order[:k]``.

        Parameters
        ----------
        order : array of int
            Columns, most needed first.

        Returns
        -------
        ndarray, shape (n_folds, len(order))
            Mean squared held-out error relative to the mean square of ``y``, of the model of
            the first ``k`` columns at ``[fold, k - 1]`` (inf where a model is undetermined on
            a fold's training rows, and for folds skipped).
        """
        order = np.asarray(order, dtype=int)
        size = len(order)
        errors = np.full((self.n_folds, size), np.inf)
        for fold, r_factor, rhs, x_test, y_test in self._systems(order):
            usable = min(size, r_factor.shape[0])
            diag = np.abs(np.diag(r_factor))[:usable]
            ok = diag > 1e-12 * max(diag.max(initial=0.0), 1e-300)
            usable = int(np.argmin(ok)) if not ok.all() else usable
            # all nested models at once: beta_k = inv(R)[:, :k+1] @ rhs[:k+1], so the
            # predictions are cumulative sums of the columns of W = x_test inv(R) times rhs
            # (one triangular solve with the test rows, no inverse and no product with it)
            weights = solve_triangular(r_factor[:usable, :usable], x_test[:, :usable].T, trans=1)
            residual = np.cumsum(weights * rhs[:usable, None], axis=0) - y_test
            errors[fold, :usable] = np.mean(residual**2, axis=1)
        return errors

    def support_errors(self, supports) -> np.ndarray:
        """Held-out errors of arbitrary supports, from each fold's training rows reduced on
        the union of the supports' columns.

        Parameters
        ----------
        supports : list of array of int
            The supports.

        Returns
        -------
        ndarray, shape (n_folds, len(supports))
            Relative mean squared held-out error of each support (inf where it is
            undetermined, and for folds skipped).
        """
        supports = [np.asarray(support, dtype=int) for support in supports]
        errors = np.full((self.n_folds, len(supports)), np.inf)
        if not supports:
            return errors
        columns = np.unique(np.concatenate(supports))
        local = [np.searchsorted(columns, support) for support in supports]
        for fold, r_factor, rhs, x_test, y_test in self._systems(columns):
            # the rank cut of a least-squares solve on the reduction of all F columns
            height = min(len(self.y) - len(y_test), self.xs.shape[1] + 1)
            for m, support in enumerate(local):
                coef, _, rank, _ = np.linalg.lstsq(
                    r_factor[:, support], rhs,
                    rcond=np.finfo(float).eps * max(height, len(support)))
                if rank < len(support):
                    continue
                # np.mean's sum and division, without its overhead (thousands of calls per fit)
                squares = (x_test[:, support] @ coef - y_test) ** 2
                errors[fold, m] = np.add.reduce(squares) / len(squares)
        return errors
