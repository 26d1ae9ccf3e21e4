"""Shared sparse-regression numerics: batched Lasso on a Gram matrix, column scaling, null vectors.

The workhorse is :func:`lasso_gram`, which solves many Lasso problems that share one design
matrix at once, from its Gram matrix only:

    for every column k:  min_x  1/2 x^T G x - b_k^T x + alpha * ||x||_1   s.t. x_i = 0 where
                                                                           mask[i, k] is False

which is ``min 1/2 ||A x - y_k||^2 + alpha ||x||_1`` for ``G = A^T A`` and ``b_k = A^T y_k``.
SINDy-PI (``y_k`` = column k of ``A`` itself, ``x_k = 0``) is the case ``B = G`` with the
diagonal masked out.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import scipy.linalg
from sklearn.exceptions import ConvergenceWarning

__all__ = ["LassoResult", "column_norms", "kkt_violation", "lasso_gram", "null_vector",
           "soft_threshold", "triangular_factor"]


def column_norms(matrix, rtol: float = 1e-12) -> tuple[np.ndarray, np.ndarray]:
    """Euclidean norms of the columns and which of them count as non-zero: more than ``rtol``
    times the largest.

    Examples
    --------
    >>> import numpy as np
    >>> column_norms(np.array([[3.0, 0.0], [4.0, 0.0]]))
    (array([5., 0.]), array([ True, False]))
    """
    norms = np.linalg.norm(matrix, axis=0)
    top = np.max(norms, initial=0.0)
    return norms, (norms > 0) & (norms > rtol * top)


def triangular_factor(matrix) -> np.ndarray:
    """Upper-triangular ``R`` with ``R^T R = A^T A`` (economic QR), shape (min(n_rows, F), F).

    ``||A x - A y|| = ||R x - R y||`` for all x, y, so every least-squares quantity on ``A``
    can be computed on the small ``R`` instead, with better conditioning than the Gram matrix.
    """
    matrix = np.asarray(matrix, dtype=float)
    # "raw": the same factorization, but R is cut from the leading rows before ``triu``
    # (mode "r" masks the whole tall array, which costs as much as the factorization)
    return scipy.linalg.qr(matrix, mode="raw", check_finite=False)[1]


def soft_threshold(values, threshold):
    """Proximal operator of ``threshold * |.|``: ``sign(v) * max(|v| - threshold, 0)``."""
    # "+ 0.0" turns the -0.0 of negative entries shrunk to zero into 0.0.
    return np.sign(values) * np.maximum(np.abs(values) - threshold, 0.0) + 0.0


def kkt_violation(gram, targets, coef, alpha, mask=None) -> np.ndarray:
    """Largest violation of the Lasso optimality conditions, per column.

    At an optimum ``g = G x - b`` satisfies ``g_i = -alpha sign(x_i)`` where ``x_i != 0`` and
    ``|g_i| <= alpha`` where ``x_i = 0`` (masked entries are free of conditions). Arguments
    as in :func:`lasso_gram`; returns one violation per column, shape (K,).
    """
    grad = gram @ coef - targets
    alpha = np.broadcast_to(np.asarray(alpha, dtype=float), (coef.shape[1],))
    violation = np.where(
        coef != 0, np.abs(grad + alpha * np.sign(coef)), np.maximum(np.abs(grad) - alpha, 0.0)
    )
    if mask is not None:
        violation = np.where(mask, violation, 0.0)
    return violation.max(axis=0, initial=0.0)


@dataclasses.dataclass
class LassoResult:
    """Outcome of :func:`lasso_gram`.

    Attributes
    ----------
    coef : ndarray, shape (F, K)
    n_iter : int
        Proximal-gradient iterations, all continuation stages together.
    converged : ndarray of bool, shape (K,)
    violation : ndarray, shape (K,)
        Final optimality violation (see :func:`kkt_violation`), in the units of ``alpha``.
    """

    coef: np.ndarray
    n_iter: int
    converged: np.ndarray
    violation: np.ndarray


_CUT = 1e-9


def _significant(coef, cut=_CUT):
    """Entries above ``cut`` times their column's largest magnitude (the working support)."""
    top = np.max(np.abs(coef), axis=0, initial=0.0)
    return np.abs(coef) > cut * top


def _polish_support(gram, targets, coef, alpha, mask, columns, slack):
    """Exact Lasso solution on the current significant support and signs, where optimal.

    For column k with support S (entries above ``_CUT`` times the largest) and signs s, the
    Lasso optimum (if S, s are right) solves ``G_SS x_S = b_S - alpha s``. Accept it when the
    signs agree and the conditions off the support hold; this finishes in one linear solve what
    proximal gradient approaches slowly (with a tiny alpha its iterates keep tiny non-zero
    entries long after the support is found). Returns the indices of the finished columns.
    """
    finished = []
    for k in columns:
        support = np.flatnonzero(_significant(coef[:, k]))
        if support.size == 0:
            continue
        signs = np.sign(coef[support, k])
        try:
            x = np.linalg.solve(
                gram[np.ix_(support, support)], targets[support, k] - alpha[k] * signs
            )
        except np.linalg.LinAlgError:
            continue
        if not np.all(np.sign(x) == signs):
            continue
        candidate = np.zeros(coef.shape[0])
        candidate[support] = x
        grad = gram @ candidate - targets[:, k]
        off = np.ones(coef.shape[0], dtype=bool)
        off[support] = False
        if mask is not None:
            off &= mask[:, k]
        if np.all(np.abs(grad[off]) <= alpha[k] + slack[k]):
            coef[:, k] = candidate
            finished.append(k)
    return finished


def _fista(
    gram, targets, alpha, mask, coef, lipschitz, tol, max_iter, check_every, callback=None,
    callback_every=100,
):
    """Accelerated proximal gradient with per-column adaptive restart; updates ``coef``.

    ``callback(coef, converged) -> bool`` is called every ``callback_every`` iterations; True
    stops the iterations.
    """
    n_cols = coef.shape[1]
    active = np.arange(n_cols)
    converged = np.zeros(n_cols, dtype=bool)
    momentum = coef.copy()
    t = np.ones(n_cols)
    previous_pattern = np.sign(coef) * _significant(coef)
    # Signed support at the last exact-finish attempt of each column: never retry the same one.
    attempted = [None] * n_cols
    n_iter = 0
    while active.size and n_iter < max_iter:
        n_iter += 1
        y = momentum[:, active]
        step_point = y - (gram @ y - targets[:, active]) / lipschitz
        new = soft_threshold(step_point, alpha[active] / lipschitz)
        if mask is not None:
            new *= mask[:, active]
        change = new - coef[:, active]
        # Gradient-based restart (O'Donoghue & Candes): drop momentum when it points uphill.
        restart = np.einsum("ij,ij->j", y - new, change) > 0
        t_new = (1.0 + np.sqrt(1.0 + 4.0 * t[active] ** 2)) / 2.0
        beta = np.where(restart, 0.0, (t[active] - 1.0) / t_new)
        t[active] = np.where(restart, 1.0, t_new)
        coef[:, active] = new
        momentum[:, active] = new + beta * change
        if n_iter % check_every:
            continue
        sub_mask = None if mask is None else mask[:, active]
        violation = kkt_violation(gram, targets[:, active], new, alpha[active], sub_mask)
        done = violation <= tol[active]
        pattern = np.sign(new) * _significant(new)
        stable = np.all(pattern == previous_pattern[:, active], axis=0) & ~done
        previous_pattern[:, active] = pattern
        candidates = []
        for k, column, ok in zip(active, pattern.T, stable, strict=True):
            if ok and (attempted[k] is None or not np.array_equal(attempted[k], column)):
                attempted[k] = column.copy()
                candidates.append(k)
        if candidates:
            finished = _polish_support(gram, targets, coef, alpha, mask, candidates, tol)
            done[np.isin(active, finished)] = True
        converged[active[done]] = True
        momentum[:, active[done]] = coef[:, active[done]]
        active = active[~done]
        if callback is not None and n_iter % callback_every == 0 and active.size:
            if callback(coef, converged.copy()):
                break
    return n_iter, converged


def lasso_gram(gram, targets, alpha, mask=None, coef_init=None, tol: float = 1e-4,
               max_iter: int = 20_000, continuation: bool = True, check_every: int = 10,
               warn: bool = True, callback=None, atol: float = 1e-8,
               callback_every: int = 100) -> LassoResult:
    """Solve K Lasso problems sharing one Gram matrix, all at once (see the module docstring).

    The solver is accelerated proximal gradient (FISTA) on all columns
    together (one matrix-matrix product per iteration), with per-column adaptive restart, a
    continuation path on ``alpha`` (from the smallest value that zeroes every column down to
    ``alpha``, each stage warm-started from the previous one; columns given a non-zero warm
    start skip it) and an exact finish: once a column's signed support is stable, the optimum
    on that support is computed by one linear solve and accepted when it satisfies the
    optimality conditions.

    Parameters
    ----------
    gram : array, shape (F, F)
        Symmetric positive semi-definite; scale the design's columns to unit norm beforehand so
        that ``alpha`` and ``tol`` are scale free.
    targets : array, shape (F, K)
        ``A^T y_k`` for each right-hand side.
    alpha : float or array of shape (K,)
        L1 weight(s), > 0.
    mask : array of bool, shape (F, K), optional
        Entries allowed to be non-zero (default: all).
    coef_init : array, shape (F, K), optional
        Warm start; its non-zero columns start directly at ``alpha`` (no continuation).
    tol : float
        Convergence when the largest optimality violation (:func:`kkt_violation`) of a column is
        at most ``max(tol * alpha, atol)``.
    max_iter : int
        Budget of proximal-gradient iterations over all stages.
    continuation : bool
        Use the alpha path (much faster for small alpha).
    check_every : int
        Iterations between convergence checks.
    warn : bool
        Emit a :class:`~sklearn.exceptions.ConvergenceWarning` when some column did not converge.
    callback : callable, optional
        ``callback(coef, converged) -> bool``, called every ``callback_every`` iterations of
        a stage (``converged``: boolean per column, at the current stage's alpha); returning
        True stops early (the caller decides that what it needs has converged; the other
        columns may be left at an intermediate stage of the continuation path).
    atol : float
        Absolute floor of the convergence threshold: the rounding level of the gradient on
        unit-norm columns, below which a tiny ``alpha`` could not be resolved.
    callback_every : int, default 100
        Iterations between calls of ``callback`` (a multiple of ``check_every`` sees the
        latest convergence flags).

    Returns
    -------
    LassoResult

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a = rng.normal(size=(100, 5)); a /= np.linalg.norm(a, axis=0)
    >>> y = a @ np.array([[1.0, 0.0], [0.0, 0.0], [0.0, -2.0], [0.0, 0.0], [0.5, 0.0]])
    >>> result = lasso_gram(a.T @ a, a.T @ y, alpha=1e-6)
    >>> np.round(result.coef, 4), bool(result.converged.all())
    (array([[ 1. ,  0. ],
           [ 0. ,  0. ],
           [ 0. , -2. ],
           [ 0. ,  0. ],
           [ 0.5,  0. ]]), True)
    """
    gram = np.asarray(gram, dtype=float)
    targets = np.asarray(targets, dtype=float)
    if gram.ndim != 2 or gram.shape[0] != gram.shape[1]:
        raise ValueError(f"gram: expected a square matrix, got shape {gram.shape}")
    if targets.ndim != 2 or targets.shape[0] != gram.shape[0]:
        raise ValueError(f"targets: expected shape ({gram.shape[0]}, K), got {targets.shape}")
    if not (np.all(np.isfinite(gram)) and np.all(np.isfinite(targets))):
        raise ValueError("gram, targets: contain NaN or inf")
    n_cols = targets.shape[1]
    alpha = np.broadcast_to(np.asarray(alpha, dtype=float), (n_cols,)).copy()
    if np.any(~np.isfinite(alpha)) or np.any(alpha <= 0):
        raise ValueError(f"alpha: expected positive finite value(s), got {alpha}")
    if mask is not None:
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != targets.shape:
            raise ValueError(f"mask: expected shape {targets.shape}, got {mask.shape}")
    if not tol > 0:
        raise ValueError(f"tol: expected a positive value, got {tol!r}")
    if int(max_iter) < 1:
        raise ValueError(f"max_iter: expected a positive integer, got {max_iter!r}")

    lipschitz = max(float(np.linalg.eigvalsh(gram)[-1]), 1e-300)
    masked_targets = targets if mask is None else np.where(mask, targets, 0.0)
    if coef_init is None:
        coef = np.zeros_like(targets)
    else:
        coef = np.array(coef_init, dtype=float)
        if coef.shape != targets.shape:
            raise ValueError(f"coef_init: expected shape {targets.shape}, got {coef.shape}")
        if mask is not None:
            coef *= mask
    warm = np.any(coef != 0, axis=0)

    stages = [alpha]
    if continuation:
        # Above alpha_max = max|b_k| the solution is zero; walk down by decades to alpha.
        alpha_max = np.max(np.abs(masked_targets), axis=0, initial=0.0)
        alpha_max[warm] = alpha[warm]
        current = np.maximum(alpha, alpha_max / 10.0)
        stages = []
        while np.any(current > alpha):
            stages.append(current)
            current = np.maximum(alpha, current / 10.0)
        stages.append(alpha)

    n_iter = 0
    for k, stage_alpha in enumerate(stages):
        last = k == len(stages) - 1
        # Intermediate stages only need a warm start: loose tolerance, bounded effort.
        # (Warm-started columns already run at alpha and get the final tolerance throughout.)
        stage_tol = np.maximum(np.where(warm | last, tol, 0.1) * stage_alpha, atol)
        budget = int(max_iter) - n_iter if last else max(1, min(500, int(max_iter) - n_iter))
        if budget <= 0:
            break
        used, converged = _fista(
            gram, masked_targets, stage_alpha, mask, coef, lipschitz, stage_tol, budget,
            int(check_every), callback, int(callback_every),
        )
        n_iter += used
        if used < budget and not np.all(converged):
            break  # stopped by the callback

    violation = kkt_violation(gram, masked_targets, coef, alpha, mask)
    converged = violation <= np.maximum(tol * alpha, atol) * (1 + 1e-9)
    if warn and not np.all(converged):
        warnings.warn(
            f"lasso_gram: {int(np.sum(~converged))} of {n_cols} problems did not converge in "
            f"{int(max_iter)} iterations (largest optimality violation "
            f"{np.max(violation / alpha):.2e} x alpha); raise max_iter or alpha",
            ConvergenceWarning,
            stacklevel=2,
        )
    return LassoResult(coef=coef, n_iter=n_iter, converged=converged, violation=violation)


def null_vector(matrix) -> tuple[np.ndarray, float]:
    """Unit vector ``v`` minimizing ``||A v||`` (last right singular vector, its entry of
    largest magnitude positive) and that minimum (zero when fewer rows than columns).

    Examples
    --------
    >>> import numpy as np
    >>> v, s = null_vector(np.array([[1.0, -1.0], [2.0, -2.0], [0.5, -0.5]]))
    >>> np.round(v * np.sqrt(2), 6), round(s, 12)
    (array([1., 1.]), 0.0)
    """
    matrix = np.asarray(matrix, dtype=float)
    k = matrix.shape[1]
    if matrix.shape[0] < k:
        matrix = np.vstack([matrix, np.zeros((k - matrix.shape[0], k))])
    _, singular, vt = np.linalg.svd(matrix, full_matrices=False)
    vector = vt[-1]
    vector = vector * np.sign(vector[np.argmax(np.abs(vector))])
    return vector, float(singular[-1])
