"""Shared sparse-regression numerics: batched Lasso on a Gram matrix (:func:`lasso_gram`, which
solves ``min 1/2 x^T G x - b_k^T x + alpha ||x||_1`` for every column ``b_k`` of ``B``, with a
mask of the entries allowed to be non-zero: SINDy-PI is ``B = G`` without the diagonal),
column scaling, null vectors.
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
    """Norms of the columns and which count as non-zero (above ``rtol`` times the largest).

    >>> import numpy as np
    >>> column_norms(np.array([[3.0, 0.0], [4.0, 0.0]]))
    (array([5., 0.]), array([ True, False]))
    """
    norms = np.linalg.norm(matrix, axis=0)
    top = np.max(norms, initial=0.0)
    return norms, (norms > 0) & (norms > rtol * top)


def triangular_factor(matrix) -> np.ndarray:
    """``R`` (min(n_rows, F), F) with ``R^T R = A^T A``: least squares on ``A`` done on ``R``."""
    matrix = np.asarray(matrix, dtype=float)
    # "raw": R cut from the leading rows (mode "r" masks the whole tall array)
    return scipy.linalg.qr(matrix, mode="raw", check_finite=False)[1]


def soft_threshold(values, threshold):
    """Proximal operator of ``threshold * |.|``: ``sign(v) * max(|v| - threshold, 0)``."""
    # "+ 0.0" turns the -0.0 of negative entries shrunk to zero into 0.0.
    return np.sign(values) * np.maximum(np.abs(values) - threshold, 0.0) + 0.0


def kkt_violation(gram, targets, coef, alpha, mask=None) -> np.ndarray:
    """Largest violation of the Lasso optimality conditions per column, shape (K,): ``g = G x - b``
    must be ``-alpha sign(x_i)`` on the support and within ``alpha`` off it (masked entries free).
    """
    grad = gram @ coef - targets
    alpha = np.broadcast_to(np.asarray(alpha, dtype=float), (coef.shape[1],))
    violation = np.where(coef != 0, np.abs(grad + alpha * np.sign(coef)),
                         np.maximum(np.abs(grad) - alpha, 0.0))
    if mask is not None:
        violation = np.where(mask, violation, 0.0)
    return violation.max(axis=0, initial=0.0)


@dataclasses.dataclass
class LassoResult:
    """Outcome of :func:`lasso_gram`: ``coef`` (F, K), ``n_iter`` (all stages), ``converged`` (K,),
    ``violation`` (K,) in the units of ``alpha``.
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
    """Exact Lasso optimum ``G_SS x_S = b_S - alpha s`` on each column's significant support and
    signs, accepted where signs and conditions hold (proximal gradient approaches it slowly);
    returns the finished columns.
    """
    finished = []
    for k in columns:
        support = np.flatnonzero(_significant(coef[:, k]))
        if support.size == 0:
            continue
        signs = np.sign(coef[support, k])
        try:
            x = np.linalg.solve(gram[np.ix_(support, support)],
                                targets[support, k] - alpha[k] * signs)
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


def _fista(gram, targets, alpha, mask, coef, lipschitz, tol, max_iter, check_every,
           callback=None, callback_every=100):
    """Accelerated proximal gradient with per-column adaptive restart, updating ``coef``;
    ``callback(coef, converged)`` every ``callback_every`` iterations stops it by returning True.
    """
    n_cols = coef.shape[1]
    active = np.arange(n_cols)
    converged = np.zeros(n_cols, dtype=bool)
    momentum = coef.copy()
    t = np.ones(n_cols)
    previous_pattern = np.sign(coef) * _significant(coef)
    # signed support of each column's last exact-finish attempt
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
    """Solve K Lasso problems sharing one Gram matrix at once (module docstring).

    FISTA on all columns together, with adaptive restart, a continuation path on ``alpha``
    (decades down from the value zeroing every column; columns warm-started by a non-zero
    ``coef_init`` skip it) and an exact finish on stable signed supports. ``gram`` (F, F) of
    unit-norm columns (so that ``alpha`` and ``tol`` are scale free), ``targets`` (F, K) the
    ``A^T y_k``, ``alpha`` > 0 per column, ``mask`` (F, K) the entries allowed to be non-zero.
    A column has converged when its :func:`kkt_violation` is at most ``max(tol * alpha, atol)``
    (``atol``: the gradient's rounding level); ``max_iter`` counts all stages, checks come every
    ``check_every`` iterations, and ``callback(coef, converged) -> bool`` every
    ``callback_every`` stops the solve by returning True. ``warn``: a ``ConvergenceWarning``
    when some column did not converge. Returns a :class:`LassoResult`.
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
        # intermediate stages only warm-start: loose tolerance, bounded effort
        stage_tol = np.maximum(np.where(warm | last, tol, 0.1) * stage_alpha, atol)
        budget = int(max_iter) - n_iter if last else max(1, min(500, int(max_iter) - n_iter))
        if budget <= 0:
            break
        used, converged = _fista(gram, masked_targets, stage_alpha, mask, coef, lipschitz,
                                 stage_tol, budget, int(check_every), callback, int(callback_every))
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
            ConvergenceWarning, stacklevel=2)
    return LassoResult(coef=coef, n_iter=n_iter, converged=converged, violation=violation)


def null_vector(matrix) -> tuple[np.ndarray, float]:
    """Unit ``v`` minimizing ``||A v||`` (largest entry positive) and that minimum.

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
