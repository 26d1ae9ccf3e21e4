"""Noise-aware choice of the sparsity (:func:`select_support`): nested paths of supports scored by
cross-validation.

A fixed threshold prunes small true terms on clean data and keeps noise terms on noisy data.
Backward elimination (smallest squared t-statistic) and forward selection give one nested
model per size, refined by single swaps (:func:`refine_by_swaps`); each is scored by
cross-validation over contiguous blocks of rows of each of ``n_blocks`` coordinates (errors
relative to the mean square of ``y``), and the smallest within one standard error of the best
*path* model is chosen. ``x`` (n_rows, F) and ``y`` (n_rows,) are the columns and target.

Each path is scored up to the reach ``max(3 b, b + 40)`` of the best backward size ``b`` (the
backward path's window grows until it holds the reach of its own best size): a model that much
larger than the best is never the sparsest within one standard error, and the cost of the scores
then follows the models scored instead of the catalog's width.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg
import scipy.linalg.lapack

from ._base import independent_columns
from ._folds import HeldOutRows, fold_labels  # noqa: F401 (fold_labels kept)
from ._forward import forward_order
from ._swaps import column_norms2, first_swaps, swap_search
from ._triangular import solve_triangular, triangular_system, without_columns

__all__ = ["elimination_path", "forward_path", "cross_validated_size", "cross_validated_supports",
           "refine_by_swaps", "select_support", "SelectionResult"]


def _scaled(x):
    scale = np.sqrt(np.mean(x**2, axis=0))
    active = scale > 0
    return active, np.where(active, scale, 1.0)


def _reduced(x, y, held_out=None):
    """``(non_zero_columns, R, Q^T y)`` of the unit-RMS columns: least squares on any subset of the
    columns is the same on the reduced system. ``held_out`` (a function of the unit-RMS rows
    returning :class:`HeldOutRows`) also returns the folds, whose reductions of all columns
    give ``R`` if they have them.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    active, scale = _scaled(x)
    xs = x / scale
    folds = None if held_out is None else held_out(xs, y)
    reduced = (active, xs, y)
    if xs.shape[0] > xs.shape[1] + 1:
        whole = folds is not None and folds.whole
        r_factor, rhs = folds.reduction() if whole else triangular_system(xs, y)
        reduced = (active, np.ascontiguousarray(r_factor), rhs)
    return reduced if held_out is None else (reduced, folds)


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
    # [R | Q^T y] of the active columns, re-triangularized after each refit's removals
    system = np.column_stack([xs, y])
    if np.tril(system, -1).any():
        system = np.column_stack(triangular_system(xs[:, active], y))
    else:  # already reduced: only the inactive columns' steps to remove
        system = without_columns(system, active + [xs.shape[1]])
    while active:
        n_active = len(active)
        r_sub, qty = system[:n_active, :n_active], system[:n_active, n_active]
        diag = np.abs(np.diag(r_sub))
        if diag.min(initial=np.inf) <= 1e-12 * diag.max(initial=0.0):
            # an (almost) dependent column: drop the one that the others explain best
            drop_local = [int(np.argmin(diag))]
        else:
            beta = solve_triangular(r_sub, qty)
            inverse, info = scipy.linalg.lapack.dtrtri(r_sub)
            if info != 0:
                raise np.linalg.LinAlgError(f"dtrtri failed (info {info})")
            increase = beta**2 / np.sum(inverse**2, axis=1)
            # far from the interesting sizes, drop several columns per refit
            n_drop = max(1, n_active // 10) if n_active > 40 else 1
            drop_local = list(np.argsort(increase, kind="stable")[:n_drop])
        for j in sorted(drop_local, reverse=True):
            removed.append(active.pop(j))
        if active:
            left = np.ones(n_active + 1, dtype=bool)
            left[drop_local] = False
            system = without_columns(system, np.flatnonzero(left))
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
    return forward_order(*_reduced(x, y))


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
    return _held_out(x, y, n_blocks, n_folds).nested_errors(order)


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
    return _held_out(x, y, n_blocks, n_folds).support_errors(supports)


def _held_out(x, y, n_blocks, n_folds):
    """The folds of the unit-RMS columns."""
    x = np.asarray(x, dtype=float)
    return HeldOutRows(x / _scaled(x)[1], np.asarray(y, dtype=float), n_blocks, n_folds)


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
        standard error over the folds: the best of the path models of that size and their
        swap refinements (refined up to the chosen size); inf for the sizes past every
        path's reach.
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


# the paths are scored up to the reach max(3 b, b + 40) of the best backward size b: a model far
# larger than the best one is never the sparsest within one standard error, and the steps and
# scores past it cost O(F^2) to O(F^3) each on catalogs of a thousand columns
_REACH_FACTOR, _REACH_MARGIN = 3, 40


def _reach(best_size: int) -> int:
    """How many terms of a path are scored when its best size is ``best_size``."""
    return max(_REACH_FACTOR * best_size, best_size + _REACH_MARGIN)


def _path_summary(errors, length: int, n_keep: int):
    """Mean and spread over the folds of a path's nested models, inf past the scored ones and
    for the models without every kept column."""
    mean, spread = fold_summary(errors)
    mean = np.concatenate([mean, np.full(length - len(mean), np.inf)])
    spread = np.concatenate([spread, np.full(length - len(spread), np.inf)])
    mean[: max(n_keep - 1, 0)] = np.inf
    return mean, spread


def _within_reach(held_out, order, n_keep: int) -> np.ndarray:
    """Held-out errors of the nested models ``order[:k]`` up to the reach of the best of them:
    the window of scored sizes grows until it holds the reach of its best size (or the path).
    """
    reach = min(len(order), _reach(_REACH_MARGIN + n_keep))  # the first window
    while True:
        errors = held_out.nested_errors(order[:reach])
        mean = _path_summary(errors, reach, n_keep)[0]
        if reach == len(order) or not np.isfinite(mean).any():
            return errors
        wanted = _reach(int(np.argmin(mean)) + 1)
        if wanted <= reach:
            return errors
        reach = min(len(order), wanted)


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
    keep = np.unique(np.asarray([] if keep is None else keep, dtype=int))
    # the folds are reduced on all columns once when the first backward window holds half
    # of them or more
    first_window = _reach(_REACH_MARGIN + len(keep))
    reduced, held_out = _reduced(x, y, lambda xs, ys: HeldOutRows(
        xs, ys, n_blocks, n_folds, whole=2 * min(xs.shape[1], first_window) >= xs.shape[1]))
    reduced = _without_dependent_columns(reduced, keep)
    free, local = _profiled(reduced, keep)
    scored = None  # the forward path is scored up to the reach of the backward best size
    for path in ("backward", "forward"):
        if path == "backward":
            order = _elimination_order(*local)
        else:
            order = forward_order(*local, max_steps=scored)
        order = np.concatenate([keep, free[order]]).astype(int)
        if max_size is not None:
            order = order[: max(int(max_size), len(keep))]
        if path == "backward":
            errors = _within_reach(held_out, order, len(keep))
        else:
            errors = held_out.nested_errors(order[:scored])
        mean, spread = _path_summary(errors, len(order), len(keep))
        paths.append((path, order, mean))
        for k in np.flatnonzero(np.isfinite(mean)):
            key = frozenset(order[: k + 1].tolist())
            if key not in seen:
                seen.add(key)
                candidates.append((int(k) + 1, mean[k], spread[k], f"{path} path", order))
        if path == "backward" and np.isfinite(mean).any():
            scored = _reach(int(np.argmin(mean)) + 1)
    if not candidates:
        raise ValueError("x: no model size can be cross-validated on these rows")
    # the reference is the best path model (the winner's curse of the refinements)
    best = min(candidates, key=lambda c: c[1])
    tolerance = max(best[2], resolution)
    if swaps:
        path_choice = min(c[0] for c in candidates if c[1] <= best[1] + tolerance)
        candidates += _swap_candidates(local, held_out, paths, seen, path_choice,
                                       best[1] + tolerance, keep, free)
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


def _swap_candidates(reduced, held_out, paths, seen, limit, bound, keep=(), free=None):
    """Swap refinements of the path models of at most ``limit`` terms, scored on ``held_out``
    (:class:`HeldOutRows`); only the ``free`` columns are exchanged.

    The sizes are refined in increasing order, every path's model of a size before the next
    size, up to the first size with a refined model whose held-out mean is within ``bound``:
    a larger model cannot be the sparsest one within it, and the searches from the larger
    starts cost the most. A search only passes through supports of its own size, so what it
    shares with the others (the supports already visited, where the supports it passes
    through end) is the same in this order as path by path.
    """
    active, xs, y_reduced = reduced
    n_keep = len(keep)
    if n_keep:
        position = {int(c): k for k, c in enumerate(free)}
        paths = [(path, np.array([position[int(c)] for c in order[n_keep:]], dtype=int),
                  mean[n_keep:]) for path, order, mean in paths]
        limit -= n_keep
    visited = set()  # starts already refined and local optima reached
    memo = {}  # supports the searches went through, to where they ended
    norms2 = column_norms2(xs)
    in_support = np.zeros(xs.shape[1], dtype=bool)
    starts = []  # per path: its name, order, sizes to refine and their first swaps
    for path, order, mean in paths:
        sizes = [k for k in range(1, min(limit, len(order)) + 1) if np.isfinite(mean[k - 1])]
        starts.append((path, order, set(sizes),
                       first_swaps(xs, y_reduced, active, order, sizes, norms2)))
    out = []
    for k in range(1, limit + 1):
        refined = []
        for path, order, sizes, first in starts:
            start = frozenset(order[:k].tolist())
            if k not in sizes or start in visited:
                continue
            if k not in first:
                support = swap_search(xs, y_reduced, active, order[:k], max_swaps=50,
                                      norms2=norms2, memo=memo)
            elif first[k][1] is None:  # no exchange improves the start
                support = np.sort(order[:k])
            else:
                rss, swapped, state = first[k]
                support = swap_search(xs, y_reduced, active, swapped, max_swaps=49, rss=rss,
                                      previous=order[:k], norms2=norms2, start=state, memo=memo)
            visited.update((start, frozenset(support.tolist())))
            in_support[:] = False
            in_support[support] = True
            rest = order[~in_support[order]]  # (np.isin's overhead, many times per fit)
            if n_keep:  # back to the columns of the folds
                support, rest = np.concatenate([keep, free[support]]), free[rest]
            key = frozenset(support.tolist())
            if key not in seen:
                seen.add(key)
                refined.append((path, support, np.concatenate([support, rest])))
        if not refined:
            continue
        mean, spread = fold_summary(held_out.support_errors([s for _, s, _ in refined]))
        out += [(len(support), mean[m], spread[m], f"{path} path, swap-refined", order)
                for m, (path, support, order) in enumerate(refined) if np.isfinite(mean[m])]
        if np.any(mean <= bound):
            break
    return out
