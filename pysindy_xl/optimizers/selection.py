"""Noise-aware choice of the sparsity (:func:`select_support`): nested paths of supports scored by
cross-validation.

A fixed threshold prunes small true terms on clean data and keeps noise terms on noisy data.
Backward elimination (smallest squared t-statistic) and forward selection give one nested
model per size, refined by single swaps (:func:`refine_by_swaps`); each is scored by
cross-validation over contiguous blocks of rows of each of ``n_blocks`` coordinates (errors
relative to the mean square of ``y``), and the smallest within one standard error of the best
*path* model is chosen. ``x`` (n_rows, F) and ``y`` (n_rows,) are the columns and target.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg
import scipy.linalg.lapack

from ._base import independent_columns
from ._swaps import first_swaps, swap_search

__all__ = ["elimination_path", "forward_path", "cross_validated_size", "cross_validated_supports",
           "refine_by_swaps", "select_support", "SelectionResult"]


def _scaled(x):
    scale = np.sqrt(np.mean(x**2, axis=0))
    active = scale > 0
    return active, np.where(active, scale, 1.0)


def _reduced(x, y):
    """``(non_zero_columns, R, Q^T y)`` of the unit-RMS columns: least squares on any subset of the
    columns is the same on the reduced system.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    active, scale = _scaled(x)
    xs = x / scale
    if xs.shape[0] > xs.shape[1] + 1:
        xs, y = _triangular_system(xs, y)
    return active, xs, y


def _triangular_system(x, y):
    """``(R, Q^T y)`` from one QR of ``[x | y]``; the last row keeps the residual norm."""
    stacked = np.column_stack([x, y])
    r_factor = scipy.linalg.qr(stacked, mode="r", check_finite=False)[0][: stacked.shape[1]]
    return r_factor[:, :-1], r_factor[:, -1]


def elimination_path(x, y) -> np.ndarray:
    """Column order from most to least needed, by backward elimination.

    The column whose removal raises the least-squares residual least goes first; zero columns
    last.

    Parameters
    ----------
    x : array, shape (n_rows, F)
        Columns.
    y : array, shape (n_rows,)
        Target.

    Returns
    -------
    ndarray of int, shape (F,)
        The column order.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> x = rng.normal(size=(300, 6))
    >>> elimination_path(x, x @ [0.0, 3.0, 0.0, 0.01, 0.0, -1.0])[:3].tolist()
    [1, 5, 3]
    """
    return _elimination_order(*_reduced(x, y))


def _elimination_order(active_mask, xs, y) -> np.ndarray:
    """:func:`elimination_path` on a reduced system."""
    active = list(np.flatnonzero(active_mask))
    removed = list(np.flatnonzero(~active_mask))
    while len(active) > xs.shape[0]:
        # more columns than rows: keep the best-conditioned set that the rows can determine
        pivots = scipy.linalg.qr(xs[:, active], mode="r", pivoting=True, check_finite=False)[1]
        for j in sorted(pivots[xs.shape[0]:], reverse=True):
            removed.append(active.pop(j))
    while active:
        r_sub, qty = _triangular_system(xs[:, active], y)
        r_sub, qty = r_sub[: len(active)], qty[: len(active)]
        diag = np.abs(np.diag(r_sub))
        if diag.min(initial=np.inf) <= 1e-12 * diag.max(initial=0.0):
            # an (almost) dependent column: drop the one that the others explain best
            drop_local = [int(np.argmin(diag))]
        else:
            beta = scipy.linalg.solve_triangular(r_sub, qty, check_finite=False)
            inverse = scipy.linalg.solve_triangular(r_sub, np.eye(len(active)), check_finite=False)
            increase = beta**2 / np.sum(inverse**2, axis=1)
            # far from the interesting sizes, drop several columns per refit
            n_drop = max(1, len(active) // 10) if len(active) > 40 else 1
            drop_local = list(np.argsort(increase, kind="stable")[:n_drop])
        for j in sorted(drop_local, reverse=True):
            removed.append(active.pop(j))
    return np.array(removed[::-1], dtype=int)


def forward_path(x, y) -> np.ndarray:
    """Column order from most to least needed, by forward stepwise selection.

    Orthogonal least squares: finds a true term that a correlated pair imitates, where
    elimination may keep the pair.

    Parameters
    ----------
    x : array, shape (n_rows, F)
        Columns.
    y : array, shape (n_rows,)
        Target.

    Returns
    -------
    ndarray of int
        The column order.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> x = rng.normal(size=(300, 6))
    >>> forward_path(x, x @ [0.0, 3.0, 0.0, 0.01, 0.0, -1.0])[:3].tolist()
    [1, 5, 3]
    """
    return _forward_order(*_reduced(x, y))


def _forward_order(active_mask, xs, residual, max_steps=None) -> np.ndarray:
    """:func:`forward_path` on a reduced system; after ``max_steps`` picks the remaining
    columns follow in column order (unscored by the selection).
    """
    orthogonal = xs.copy()
    chosen = []
    candidates = active_mask.copy()
    steps = xs.shape[1] if max_steps is None else int(max_steps)
    while candidates.any() and len(chosen) < steps:
        norms2 = np.sum(orthogonal**2, axis=0)
        usable = candidates & (norms2 > 1e-20 * np.sum(xs**2, axis=0))
        if not usable.any():
            break
        gain = np.where(usable, (orthogonal.T @ residual) ** 2 / np.where(usable, norms2, 1),
                        -np.inf)
        j = int(np.argmax(gain))
        direction = orthogonal[:, j] / np.sqrt(norms2[j])
        residual = residual - direction * (direction @ residual)
        orthogonal -= np.outer(direction, direction @ orthogonal)
        chosen.append(j)
        candidates[j] = False
    return np.array(chosen + [j for j in range(xs.shape[1]) if j not in set(chosen)], dtype=int)


def refine_by_swaps(x, y, support, max_swaps: int = 50) -> np.ndarray:
    """Local best subset of a fixed size, by single swaps.

    Makes the exchange of a selected for an unselected column that lowers
    ``||y - x_S beta_S||^2`` most, while it does (at most ``max_swaps``): the local optimality of
    L0Learn's heuristics (Hazimeh and Mazumder, 2020), which greedy paths lack.

    Parameters
    ----------
    x : array, shape (n_rows, F)
        Columns.
    y : array, shape (n_rows,)
        Target.
    support : array of int
        Starting columns.
    max_swaps : int, default 50
        At most this many swaps.

    Returns
    -------
    support : ndarray of int
        Refined columns, sorted.

    Examples
    --------
    A true column imitated by a correlated pair, recovered by a swap:

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b, noise = rng.normal(size=(3, 500))
    >>> x = np.column_stack([a + 0.1 * b, a - 0.1 * b, a, rng.normal(size=500)])
    >>> y = 2 * x[:, 2] + x[:, 3] + 1e-3 * noise
    >>> refine_by_swaps(x, y, [0, 1]).tolist()
    [2, 3]
    """
    active, xs, y = _reduced(x, y)
    support = np.asarray(support, dtype=int)
    if len(support) == 0:
        return support
    return swap_search(xs, y, active, support, int(max_swaps))


def fold_labels(n_rows: int, n_blocks: int, n_folds: int) -> np.ndarray:
    """Fold of each row: contiguous stretches within each of ``n_blocks`` equal row blocks."""
    per_block = n_rows // n_blocks
    position = np.arange(n_rows) % per_block
    return np.minimum(position * n_folds // per_block, n_folds - 1)


def _systems(x, y, n_blocks: int, n_folds: int) -> tuple[tuple, list]:
    """:func:`_reduced` of the rows and, per fold, ``(fold, x_test, y_test, R, Q^T y)``: unit-RMS
    columns, the training rows reduced (the QR of the other folds' stacked systems), ``y``
    divided by its RMS; folds without test or training rows skipped.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    active, scale = _scaled(x)
    xs = x / scale
    y_rms = np.sqrt(max(float(np.mean(y**2)), 1e-300))
    labels = fold_labels(len(y), n_blocks, n_folds)
    rows = [labels == fold for fold in range(n_folds)]
    parts = [_StackedR.of(np.column_stack(_triangular_system(xs[r], y[r]))) for r in rows
             if r.any()]
    present = [fold for fold in range(n_folds) if rows[fold].any()]
    # the systems of all folds but one, from prefix and suffix combinations (2 n_folds
    # triangular-pentagonal QRs instead of a QR of n_folds - 1 stacked systems per fold)
    prefix, suffix = [None], [None]
    for part in parts:
        prefix.append(part if prefix[-1] is None else prefix[-1].plus(part))
    for part in parts[::-1]:
        suffix.append(part if suffix[-1] is None else suffix[-1].plus(part))
    suffix = suffix[::-1]  # suffix[k]: parts k and later
    reduced = ((active, *prefix[-1].system()) if xs.shape[0] > xs.shape[1] + 1
               else (active, xs, y))
    folds = []
    for k, fold in enumerate(present):
        if not rows[fold].all():
            before, after = prefix[k], suffix[k + 1]
            others = before if after is None else after if before is None else before.plus(after)
            r_factor, rhs = others.system()
            folds.append((fold, xs[rows[fold]], y[rows[fold]] / y_rms, r_factor, rhs / y_rms))
    return reduced, folds


class _StackedR:
    """The R factor of stacked rows, ``(m, m)`` upper triangular, and how many rows it stands
    for; :meth:`plus` stacks two by LAPACK's triangular-pentagonal QR (``dtpqrt``), which uses
    their shape (a fifth of the work of a QR of the stacked rows).
    """

    def __init__(self, r_factor, n_rows):
        self.r_factor, self.n_rows = r_factor, n_rows

    @classmethod
    def of(cls, part):
        """From an upper trapezoidal ``(rows, m)`` part (the R of some rows)."""
        m = part.shape[1]
        r_factor = np.zeros((m, m), order="F")
        r_factor[: part.shape[0]] = part
        return cls(r_factor, part.shape[0])

    def plus(self, other):
        """The R factor of both stacks of rows."""
        m = self.r_factor.shape[0]
        height = min(other.n_rows, m)  # other's non-zero rows: upper trapezoidal
        if height == 0:
            return self
        top, _, _, info = scipy.linalg.lapack.dtpqrt(
            height, min(32, m), self.r_factor, other.r_factor[:height], overwrite_a=False,
            overwrite_b=False)
        if info != 0:
            raise np.linalg.LinAlgError(f"dtpqrt failed (info {info})")
        return _StackedR(np.asfortranarray(np.triu(top)), self.n_rows + other.n_rows)

    def system(self):
        """``(R, Q^T y)`` of the columns and target (the last column), as
        :func:`_triangular_system` gives them."""
        r_factor = self.r_factor[: min(self.n_rows, self.r_factor.shape[0])]
        return r_factor[:, :-1], r_factor[:, -1]


def cross_validated_size(x, y, order, n_blocks: int = 1, n_folds: int = 5):
    """Held-out error of every nested model ``order[:k]``.

    Parameters
    ----------
    x : array, shape (n_rows, F)
        Columns.
    y : array, shape (n_rows,)
        Target.
    order : array of int
        Columns from most to least needed.
    n_blocks : int, default 1
        Coordinate blocks of the rows (folds are contiguous within each).
    n_folds : int, default 5
        Folds.

    Returns
    -------
    ndarray, shape (n_folds, len(order))
        Held-out error of the model of the first ``k`` columns at index ``k - 1``.
    """
    return _nested_errors(_systems(x, y, n_blocks, n_folds)[1], order, n_folds)


def _nested_errors(folds, order, n_folds: int) -> np.ndarray:
    """:func:`cross_validated_size` on the fold systems."""
    order = np.asarray(order, dtype=int)
    size = len(order)
    errors = np.full((n_folds, size), np.inf)
    for fold, x_test, y_test, r_natural, rhs_natural in folds:
        # the R of x_train[:, order] from a square QR
        r_factor, rhs = _triangular_system(r_natural[:, order], rhs_natural)
        usable = min(size, r_factor.shape[0])
        diag = np.abs(np.diag(r_factor))[:usable]
        ok = diag > 1e-12 * max(diag.max(initial=0.0), 1e-300)
        usable = int(np.argmin(ok)) if not ok.all() else usable
        # all nested models at once: beta_k = inv(R)[:, :k+1] @ rhs[:k+1], so the predictions
        # are cumulative sums of the columns of W = x_test inv(R) times rhs (one triangular
        # solve with the test rows, no inverse and no product with it)
        weights = scipy.linalg.solve_triangular(
            r_factor[:usable, :usable], x_test[:, order[:usable]].T, trans="T",
            check_finite=False)
        residual = np.cumsum(weights * rhs[:usable, None], axis=0) - y_test
        errors[fold, :usable] = np.mean(residual**2, axis=1)
    return errors


def cross_validated_supports(x, y, supports, n_blocks: int = 1, n_folds: int = 5):
    """Held-out error of arbitrary supports.

    Parameters
    ----------
    x : array, shape (n_rows, F)
        Columns.
    y : array, shape (n_rows,)
        Target.
    supports : list of array of int
        The supports.
    n_blocks : int, default 1
        Coordinate blocks of the rows.
    n_folds : int, default 5
        Folds.

    Returns
    -------
    ndarray, shape (n_folds, len(supports))
        Held-out errors (inf where a support is undetermined).
    """
    return _support_errors(_systems(x, y, n_blocks, n_folds)[1], supports, n_folds)


def _support_errors(folds, supports, n_folds: int) -> np.ndarray:
    """:func:`cross_validated_supports` on the fold systems."""
    errors = np.full((n_folds, len(supports)), np.inf)
    for fold, x_test, y_test, r_factor, rhs in folds:
        for m, support in enumerate(supports):
            support = np.asarray(support, dtype=int)
            coef, _, rank, _ = np.linalg.lstsq(r_factor[:, support], rhs, rcond=None)
            if rank < len(support):
                continue
            errors[fold, m] = np.mean((x_test[:, support] @ coef - y_test) ** 2)
    return errors


class ChosenSupport:
    """What a selection result shares: the columns ``order[:size]`` it chose."""

    order: np.ndarray
    size: int

    @property
    def support(self) -> np.ndarray:
        """Selected columns, sorted."""
        return np.sort(self.order[: self.size])


@dataclasses.dataclass
class SelectionResult(ChosenSupport):
    """What the sparsity selection chose and why (returned by :func:`select_support`).

    Parameters
    ----------
    order : ndarray of int
        Columns from most to least needed.
    cv_error, cv_spread : ndarray
        Mean held-out relative squared error of each model size (index ``k - 1``) and its
        standard error over the folds.
    size : int
        Chosen number of terms.
    best_size : int
        Size of the best path model (the rule's reference).
    rule : str
        How ``size`` was chosen.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.random.default_rng(0).normal(size=(200, 4))
    >>> result = select_support(x, x @ [1.0, 0.0, 0.5, 0.0])
    >>> result.support.tolist(), result.size, result.rule
    ([0, 2], 2, 'one standard error (backward path)')
    """

    order: np.ndarray
    cv_error: np.ndarray
    cv_spread: np.ndarray
    size: int
    best_size: int
    rule: str


# the forward path and its scores stop at max(3 b, b + 40) terms, b the backward path's best size:
# a forward model far larger than the best backward one is never the sparsest within one standard
# error, and the greedy steps past it cost O(F^2) each on catalogs of a thousand columns
_FORWARD_REACH, _FORWARD_MARGIN = 3, 40


def select_support(x, y, n_blocks: int = 1, n_folds: int = 5, max_size=None,
                   resolution: float = 1e-8, swaps: bool = True, keep=None) -> SelectionResult:
    """Sparsest model within one standard error of the best path model's held-out error.

    Parameters
    ----------
    x, y, n_blocks, n_folds
        Columns (n_rows, F), target (n_rows,), equal row blocks (coordinates) and folds.
    max_size : int, optional
        Largest model considered (default: all columns).
    resolution : float, default 1e-8
        Held-out relative errors this close to the best count as equal (on clean data extra
        terms fit quadrature errors).
    swaps : bool, default True
        Refine the path models by single swaps.
    keep : array of int, optional
        Columns in every model (profiled out of the paths).

    Returns
    -------
    SelectionResult

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> x = rng.normal(size=(400, 8))
    >>> y = x @ [2.0, 0, 0, 0.01, 0, 0, -1.0, 0]
    >>> select_support(x, y + 1e-9 * rng.normal(size=400)).support.tolist()   # clean: keeps 0.01
    [0, 3, 6]
    >>> select_support(x, y + 0.3 * rng.normal(size=400)).support.tolist()    # noisy: drops it
    [0, 6]
    >>> select_support(x, y + 0.3 * rng.normal(size=400), keep=[3]).support.tolist()
    [0, 3, 6]
    """
    # candidate models: (size, held-out mean, its standard error, how found, column order)
    candidates, seen, paths = [], set(), []
    reduced, folds = _systems(x, y, n_blocks, n_folds)
    keep = np.unique(np.asarray([] if keep is None else keep, dtype=int))
    reduced = _without_dependent_columns(reduced, keep)
    free, local = _profiled(reduced, keep)
    scored = None  # the forward path is scored up to a few times the backward best size
    for path in ("backward", "forward"):
        if path == "backward":
            order = _elimination_order(*local)
        else:
            order = _forward_order(*local, max_steps=scored)
        order = np.concatenate([keep, free[order]]).astype(int)
        if max_size is not None:
            order = order[: max(int(max_size), len(keep))]
        errors = _nested_errors(folds, order[:scored], n_folds)
        mean, spread = fold_summary(errors)
        mean = np.concatenate([mean, np.full(len(order) - len(mean), np.inf)])
        mean[: max(len(keep) - 1, 0)] = np.inf  # models without every kept column
        paths.append((path, order, mean))
        for k in np.flatnonzero(np.isfinite(mean)):
            key = frozenset(order[: k + 1].tolist())
            if key not in seen:
                seen.add(key)
                candidates.append((int(k) + 1, mean[k], spread[k], f"{path} path", order))
        if path == "backward" and np.isfinite(mean).any():
            best_size = int(np.argmin(mean)) + 1
            scored = max(_FORWARD_REACH * best_size, best_size + _FORWARD_MARGIN)
    if not candidates:
        raise ValueError("x: no model size can be cross-validated on these rows")
    # the reference is the best path model (the winner's curse of the refinements)
    best = min(candidates, key=lambda c: c[1])
    tolerance = max(best[2], resolution)
    if swaps:
        path_choice = min(c[0] for c in candidates if c[1] <= best[1] + tolerance)
        candidates += _swap_candidates(local, folds, paths, seen, path_choice, n_folds, keep, free)
    size, mean, _, how, order = min((c for c in candidates if c[1] <= best[1] + tolerance),
                                    key=lambda c: (c[0], c[1]))
    n_sizes = max(c[0] for c in candidates)
    cv_error, cv_spread = np.full(n_sizes, np.inf), np.full(n_sizes, np.inf)
    for k, m, sd, *_ in candidates:
        if m < cv_error[k - 1]:
            cv_error[k - 1], cv_spread[k - 1] = m, sd
    return SelectionResult(order=order, cv_error=cv_error, cv_spread=cv_spread, size=size,
                           best_size=best[0], rule=f"one standard error ({how})")


def fold_summary(errors):
    """Mean and standard error over the folds of each model (inf where a fold failed)."""
    n_folds = errors.shape[0]
    finite = np.all(np.isfinite(errors), axis=0)
    mean = np.full(errors.shape[1], np.inf)
    spread = np.full(errors.shape[1], np.inf)
    mean[finite] = errors[:, finite].mean(axis=0)
    spread[finite] = errors[:, finite].std(axis=0, ddof=1) / np.sqrt(n_folds)
    return mean, spread


_DEPENDENCE_RTOL = 1e-6


def _without_dependent_columns(reduced, keep):
    """``reduced`` with the columns that are exact combinations of earlier ones (``keep``
    first, then column order) made inactive.

    Among exactly dependent columns (``qd^2 cos^2 q + qd^2 sin^2 q = qd^2``) every path and
    swap would otherwise choose by rounding, so a perturbation of the columns by 1e-12 could
    change the support (and did, with OpenBLAS's Haswell kernels). The tolerance lies far above
    rounding: a column whose part off the others is under 1e-6 of its norm has a variance
    inflation of 1e12 and cannot be told from them on data anyway.
    """
    active, xs, y = reduced
    priority = np.concatenate([keep, np.setdiff1d(np.arange(xs.shape[1]), keep)]).astype(int)
    independent = np.zeros(xs.shape[1], dtype=bool)
    kept = independent_columns(np.where(active, xs, 0.0), priority, rtol=_DEPENDENCE_RTOL)[0]
    independent[kept] = True
    return active & independent, xs, y


def _profiled(reduced, keep):
    """The columns besides ``keep`` and their reduced system with ``keep`` projected out."""
    active, xs, y = reduced
    free = np.setdiff1d(np.arange(xs.shape[1]), keep)
    if not len(keep):
        return free, reduced
    basis = np.linalg.qr(xs[:, keep])[0]
    rest = xs[:, free] - basis @ (basis.T @ xs[:, free])
    left = np.sum(rest**2, axis=0) > 1e-20 * np.maximum(np.sum(xs[:, free] ** 2, axis=0), 1e-300)
    return free, (active[free] & left, rest, y - basis @ (basis.T @ y))


def _swap_candidates(reduced, folds, paths, seen, limit, n_folds, keep=(), free=None):
    """Swap refinements of the path models of at most ``limit`` terms, scored on ``folds``; only
    the ``free`` columns are exchanged.
    """
    active, xs, y_reduced = reduced
    n_keep = len(keep)
    if n_keep:
        position = {int(c): k for k, c in enumerate(free)}
        paths = [(path, np.array([position[int(c)] for c in order[n_keep:]], dtype=int),
                  mean[n_keep:]) for path, order, mean in paths]
        limit -= n_keep
    refined, visited = [], set()  # starts already refined and local optima reached
    for path, order, mean in paths:
        sizes = [k for k in range(1, min(limit, len(order)) + 1) if np.isfinite(mean[k - 1])]
        first = first_swaps(xs, y_reduced, active, order, sizes)
        for k in sizes:
            start = frozenset(order[:k].tolist())
            if start in visited:
                continue
            if k not in first:
                support = swap_search(xs, y_reduced, active, order[:k], max_swaps=50)
            elif first[k][1] is None:  # no exchange improves the start
                support = np.sort(order[:k])
            else:
                rss, swapped = first[k]
                support = swap_search(xs, y_reduced, active, swapped, max_swaps=49, rss=rss,
                                       previous=order[:k])
            visited.update((start, frozenset(support.tolist())))
            rest = order[~np.isin(order, support)]
            if n_keep:  # back to the columns of the folds
                support, rest = np.concatenate([keep, free[support]]), free[rest]
            key = frozenset(support.tolist())
            if key not in seen:
                seen.add(key)
                refined.append((path, support, np.concatenate([support, rest])))
    if not refined:
        return []
    mean, spread = fold_summary(_support_errors(
        folds, [support for _, support, _ in refined], n_folds))
    return [(len(support), mean[m], spread[m], f"{path} path, swap-refined", order)
            for m, (path, support, order) in enumerate(refined) if np.isfinite(mean[m])]
