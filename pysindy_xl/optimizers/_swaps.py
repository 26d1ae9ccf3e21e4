"""Single-swap refinement of a support on a reduced least-squares system (the 1-swap search of
:func:`~pysindy_xl.optimizers.selection.refine_by_swaps`).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg


def _best_swap(usable, support, remaining2, correlation, removed, norms2, rss, y_norm2):
    """The exchange ``(c, j)`` (column ``c`` in for the ``j``-th selected) lowering the residual
    most, or ``(None, None)``; arrays as computed in :func:`swap_search`.
    """
    allowed = usable.copy()
    allowed[support] = False
    allowed = allowed[:, None] & (remaining2 > 1e-10 * norms2[:, None])
    gain = np.where(allowed, correlation**2 / np.where(allowed, remaining2, 1.0), -np.inf)
    # swapping out j for c changes the residual by removed_j^2 - gain[c, j]
    change = removed**2 - gain
    c, j = np.unravel_index(np.argmin(change), change.shape)
    # a strict, scale-aware improvement: rounding must not swap equivalent columns
    if not change[c, j] < -(1e-9 * rss + 1e-14 * y_norm2):
        return None, None
    return c, j


def swap_search(xs, y, usable, support, max_swaps, rss=None, previous=None):
    """Best-improvement 1-swap search on a reduced system: with ``x_S = Q R``, dropping column
    ``j`` (direction ``u_j ~ Q R^-T e_j``) adds ``(u_j . y)^2`` to the residual and leaves
    candidate ``c`` the component ``C_c + u_j (u_j . x_c)``: all ``k x F`` gains from the one
    product ``Q^T x`` (cost ``O(n k F)`` a step).
    ``rss`` and ``previous`` continue from a first step of :func:`first_swaps`.
    """
    support = np.asarray(support, dtype=int)
    norms2 = np.sum(xs**2, axis=0)
    y_norm2 = float(y @ y)
    for _ in range(max_swaps + 1):
        basis, r_factor = np.linalg.qr(xs[:, support])
        residual = y - basis @ (basis.T @ y)
        new_rss = float(residual @ residual)
        if rss is not None and not new_rss < rss:  # the predicted gain did not materialize
            return np.sort(previous)
        rss, previous = new_rss, support.copy()
        try:
            directions = basis @ scipy.linalg.solve_triangular(
                r_factor, np.eye(len(support)), trans="T", check_finite=False)
        except (np.linalg.LinAlgError, ValueError):
            break
        directions /= np.linalg.norm(directions, axis=0)
        # everything from one (k, F) product: P = Q^T x, so u_j . x_c = (Q^T u_j) . P_c and the
        # part of x_c off the support has the squared norm |x_c|^2 - |P_c|^2
        in_span = basis.T @ xs                           # (k, F)
        along = in_span.T @ (basis.T @ directions)       # (F, k): u_j . x_c
        removed = directions.T @ y                       # (k,): u_j . y
        remaining2 = np.maximum(norms2 - np.sum(in_span**2, axis=0), 0.0)[:, None] + along**2
        correlation = (xs.T @ residual)[:, None] + along * removed
        c, j = _best_swap(usable, support, remaining2, correlation, removed, norms2, rss, y_norm2)
        if c is None:
            break
        support = support.copy()
        support[j] = c
    return np.sort(support)


def first_swaps(xs, y, usable, order, sizes):
    """The first step of :func:`swap_search` from every ``order[:k]``, ``k`` in ``sizes``:
    ``{k: (rss, swapped support or None)}``, from one complete QR of ``x[:, order]`` (sizes
    past a zero pivot left out).
    """
    largest = max(sizes, default=0)
    q_factor, r_factor = np.linalg.qr(xs[:, order[:largest]], mode="complete")
    diag = np.abs(np.diag(r_factor))
    if np.any(diag == 0):
        largest = int(np.argmax(diag == 0))
        r_factor = r_factor[:largest]
    if largest == 0:
        return {}
    head = r_factor[:largest, :largest]
    inverse = scipy.linalg.solve_triangular(head, np.eye(largest), check_finite=False)
    big_b, small_b = q_factor.T @ xs, q_factor.T @ y
    norms2 = np.sum(xs**2, axis=0)
    y_norm2 = float(y @ y)
    # tail sums: what lies off the span of the first k columns
    remaining_base = np.cumsum((big_b**2)[::-1], axis=0)[::-1]          # (m, F) from row k
    correlation_base = np.cumsum((big_b * small_b[:, None])[::-1], axis=0)[::-1]
    rss_tail = np.cumsum((small_b**2)[::-1])[::-1]
    # along[k - 1][j, c] = inv(R)[j, :k] @ B[:k, c] (rows j < k), as cumulative sums over i
    along_all = np.cumsum(inverse[:, :, None] * big_b[None, :largest, :], axis=1)
    removed_all = np.cumsum(inverse * small_b[None, :largest], axis=1)  # (j, k - 1)
    row_norms = np.sqrt(np.cumsum(inverse**2, axis=1))                  # (j, k - 1)
    out = {}
    for k in sizes:
        if k > largest:
            continue
        norm = row_norms[:k, k - 1]
        along = (along_all[:k, k - 1, :] / norm[:, None]).T               # (F, k)
        removed = removed_all[:k, k - 1] / norm
        if k < xs.shape[0]:
            remaining2 = remaining_base[k][:, None] + along**2
            correlation = correlation_base[k][:, None] + along * removed
            rss = float(rss_tail[k])
        else:
            remaining2, correlation, rss = along**2, along * removed, 0.0
        support = np.asarray(order[:k], dtype=int)
        c, j = _best_swap(usable, support, remaining2, correlation, removed, norms2, rss, y_norm2)
        swapped = None
        if c is not None:
            swapped = support.copy()
            swapped[j] = c
        out[k] = (rss, swapped)
    return out
