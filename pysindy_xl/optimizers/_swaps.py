"""Single-swap refinement of a support on a reduced least-squares system (the 1-swap search of
:func:`~pysindy_xl.optimizers.selection.refine_by_swaps`).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.linalg.lapack

from ._triangular import solve_triangular


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
    c, j = divmod(int(np.argmin(change)), change.shape[1])  # (row, column)
    # a strict, scale-aware improvement: rounding must not swap equivalent columns
    if not change[c, j] < -(1e-9 * rss + 1e-14 * y_norm2):
        return None, None
    return c, j


def swap_search(xs, y, usable, support, max_swaps, rss=None, previous=None, norms2=None,
                start=None, memo=None):
    """Best-improvement 1-swap search on a reduced system.

    With an orthonormal basis ``Q`` of the support's span and ``P = Q^T x`` (``k x F``), the
    direction that only column ``j`` adds to the span is ``u_j ~ Q w_j``, ``w_j = P_S^-T e_j``;
    dropping ``j`` adds ``(u_j . y)^2`` to the residual and leaves candidate ``c`` the component
    ``C_c + u_j (u_j . x_c)``, with ``u_j . x_c = w_j . P_c`` and ``|C_c|^2 = |x_c|^2 - |P_c|^2``.
    After a swap, ``Q`` and ``P`` are updated instead of recomputed (:func:`_exchanged`): a
    step costs ``O(n F)`` (a new row of ``P`` and ``x^T r``) instead of the ``O(n k F)`` of a
    new ``Q^T x``.
    ``rss`` and ``previous`` continue from a first step of :func:`first_swaps`, ``start`` is
    its ``(Q, P)`` of ``support``; ``norms2``, the squared column norms, may be given (computed
    once for many searches). ``memo`` (a dict shared by searches on the same system) maps the
    supports a search went through to where it ended: a search reaching one of them ends there
    too.
    """
    support = np.array(support, dtype=int)
    xs = np.ascontiguousarray(xs)
    norms2 = column_norms2(xs) if norms2 is None else norms2
    y_norm2 = float(y @ y)
    if start is None:
        basis = np.linalg.qr(xs[:, support])[0]
        in_span = np.ascontiguousarray(basis.T) @ xs           # (k, F)
    else:
        basis, in_span = start
    residual = y - basis @ (basis.T @ y)
    x_residual = xs.T @ residual
    passed = []  # the supports this search went through
    for _ in range(max_swaps + 1):
        new_rss = float(residual @ residual)
        if rss is not None and not new_rss < rss:  # the predicted gain did not materialize
            return _remembered(memo, passed, np.sort(previous))
        rss, previous = new_rss, support.copy()
        key = frozenset(support.tolist())
        if memo is not None and key in memo:  # the rest of the way is known
            return _remembered(memo, passed, memo[key])
        passed.append(key)
        try:
            weights = np.linalg.inv(in_span[:, support]).T     # column j: w_j
        except np.linalg.LinAlgError:
            break
        weights /= _column_norms(weights)
        along = in_span.T @ weights                            # (F, k): u_j . x_c
        removed = weights.T @ (basis.T @ y)                    # (k,): u_j . y
        in_span2 = np.einsum("ij,ij->j", in_span, in_span)
        remaining2 = np.maximum(norms2 - in_span2, 0.0)[:, None] + along**2
        correlation = x_residual[:, None] + along * removed
        c, j = _best_swap(usable, support, remaining2, correlation, removed, norms2, rss, y_norm2)
        if c is None:
            break
        support[j] = c
        basis, in_span = _exchanged(xs, basis, in_span, weights[:, j], c)
        residual = y - basis @ (basis.T @ y)
        x_residual = xs.T @ residual
    return _remembered(memo, passed, np.sort(support))


def _remembered(memo, passed, end):
    """``end``, recorded in ``memo`` (if any) as the end of every support in ``passed``."""
    if memo is not None:
        memo.update(dict.fromkeys(passed, end))
    return end


def _exchanged(xs, basis, in_span, weight, column):
    """``(Q, Q^T x)`` after the direction ``Q weight`` leaves the span (a rotation within it)
    and the part of ``x[:, column]`` off the rest (Gram-Schmidt twice) enters as the last basis
    vector: its products with the columns are the new last row."""
    rotation = _complement(weight)
    basis, in_span = basis @ rotation, rotation.T @ in_span
    part = xs[:, column] - basis @ in_span[:, column]
    part -= basis @ (basis.T @ part)
    part /= _norm(part)
    return np.column_stack([basis, part]), np.vstack([in_span, xs.T @ part])


def _complement(vector):
    """An orthonormal basis ``(k, k - 1)`` of the complement of ``vector``: the last columns of
    the Householder reflection that maps ``vector`` onto the first axis."""
    head = vector / _norm(vector)
    reflector = head.copy()
    reflector[0] += 1.0 if head[0] >= 0 else -1.0
    # H = I - 2 v v^T / (v^T v) = I - v v^T / |v_0| for v = head + sign(head_0) e_0
    return np.eye(len(vector))[:, 1:] - np.outer(reflector, reflector[1:]) / abs(reflector[0])


# np.linalg.norm's own arithmetic without its argument handling (the searches call it on small
# vectors tens of thousands of times): the same numbers
def _norm(vector):
    """``np.linalg.norm(vector)`` of a real 1-D array."""
    vector = vector.ravel(order="K")  # (contiguous, as norm makes it)
    return np.sqrt(vector.dot(vector))


def _column_norms(matrix):
    """``np.linalg.norm(matrix, axis=0)`` of a real 2-D array."""
    return np.sqrt(np.add.reduce(matrix * matrix, axis=0))


def column_norms2(xs):
    """Squared norms of the columns.

    Parameters
    ----------
    xs : ndarray, shape (n_rows, F)
        Columns.

    Returns
    -------
    ndarray, shape (F,)
        ``sum_i xs[i, c]^2`` per column ``c``.
    """
    return np.einsum("ij,ij->j", xs, xs)


def _reflected(xs, y, columns):
    """``(Q^T xs, Q^T y, R)`` for the complete ``Q`` of the QR of ``columns`` (its Householder
    reflectors applied to ``xs`` and ``y``, ``O(n k F)``, without forming ``Q``).
    """
    packed, tau, work, info = scipy.linalg.lapack.dgeqrf(columns)
    if info != 0:
        raise np.linalg.LinAlgError(f"dgeqrf failed (info {info})")
    both = np.asfortranarray(np.column_stack([xs, y]))
    lwork = max(1, 64 * both.shape[1])
    both, work, info = scipy.linalg.lapack.dormqr("L", "T", packed[:, : len(tau)], tau, both, lwork,
                                                  overwrite_c=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"dormqr failed (info {info})")
    return both[:, :-1], both[:, -1], np.triu(packed[: columns.shape[1]]), (packed, tau)


def _tail_sums(head, rest):
    """``out[k] = rest + sum(head[k:], axis=0)``: sums from row ``k`` of ``head`` stacked on
    rows whose sum is ``rest``."""
    return np.cumsum(head[::-1], axis=0)[::-1] + rest


def first_swaps(xs, y, usable, order, sizes, norms2=None):
    """The first step of :func:`swap_search` from every ``order[:k]``, ``k`` in ``sizes``:
    ``{k: (rss, swapped support or None, its (Q, Q^T x) or None)}``, from one QR of
    ``x[:, order]`` whose reflectors give ``Q^T x`` for its complete ``Q`` (sizes past a zero
    pivot left out).
    """
    largest = max(sizes, default=0)
    if largest == 0:
        return {}
    xs = np.ascontiguousarray(xs)
    big_b, small_b, r_factor, (packed, tau) = _reflected(xs, y, xs[:, order[:largest]])
    diag = np.abs(np.diag(r_factor))
    if np.any(diag == 0):
        largest = int(np.argmax(diag == 0))
        r_factor = r_factor[:largest]
    if largest == 0:
        return {}
    inverse = solve_triangular(r_factor[:largest, :largest], np.eye(largest))
    norms2 = column_norms2(xs) if norms2 is None else norms2
    y_norm2 = float(y @ y)
    # tail sums from row k (k <= largest): what lies off the span of the first k columns
    head, tail = big_b[: largest + 1], big_b[largest + 1:]
    y_head, y_tail = small_b[: largest + 1], small_b[largest + 1:]
    remaining_base = _tail_sums(head**2, np.einsum("ij,ij->j", tail, tail))      # (k, F)
    correlation_base = _tail_sums(head * y_head[:, None], y_tail @ tail)
    rss_tail = _tail_sums(y_head**2, y_tail @ y_tail)
    # along[k - 1][j, c] = inv(R)[j, :k] @ B[:k, c] (rows j < k), as cumulative sums over i
    along_all = np.cumsum(inverse[:, :, None] * big_b[None, :largest, :], axis=1)
    removed_all = np.cumsum(inverse * small_b[None, :largest], axis=1)  # (j, k - 1)
    row_norms = np.sqrt(np.cumsum(inverse**2, axis=1))                  # (j, k - 1)
    out, basis = {}, None
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
        swapped = start = None
        if c is not None:
            swapped = support.copy()
            swapped[j] = c
            # (Q, Q^T x) of the swapped support from those of order[:k]: R_k^-T e_j is row j
            # of inv(R)[:k, :k]
            if basis is None and packed.shape[0] >= packed.shape[1]:
                basis, _, info = scipy.linalg.lapack.dorgqr(packed, tau)
                if info != 0:
                    raise np.linalg.LinAlgError(f"dorgqr failed (info {info})")
            if basis is not None:
                start = _exchanged(xs, basis[:, :k], big_b[:k], inverse[j, :k], c)
        out[k] = (rss, swapped, start)
    return out
