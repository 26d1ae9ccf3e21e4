"""Triangular least-squares systems: the reduction of rows to ``[R | Q^T y]`` and its update
after removing columns (the refits of backward elimination).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.linalg.lapack


def triangular_system(x, y):
    """``(R, Q^T y)`` from one QR of ``[x | y]``; the last row keeps the residual norm.

    Parameters
    ----------
    x : array, shape (n_rows, k)
        Columns.
    y : array, shape (n_rows,)
        Target.

    Returns
    -------
    r_factor : ndarray, shape (min(n_rows, k + 1), k)
        Upper triangular: ``R^T R = x^T x``.
    rhs : ndarray, shape (min(n_rows, k + 1),)
        ``Q^T y``: ``R^T rhs = x^T y``, and its last entry (row ``k``) is the residual norm of
        the least-squares fit when ``n_rows > k``.
    """
    x = np.asarray(x, dtype=float)
    stacked = np.empty((x.shape[0], x.shape[1] + 1), order="F")  # LAPACK's layout: no copy
    stacked[:, :-1], stacked[:, -1] = x, y
    # (mode "raw": R without the (rows, k + 1) upper-triangular copy that mode "r" makes)
    r_factor = scipy.linalg.qr(stacked, mode="raw", overwrite_a=True,
                               check_finite=False)[1][: stacked.shape[1]]
    return r_factor[:, :-1], r_factor[:, -1]


def without_columns(r_factor, columns, block: int = 32) -> np.ndarray:
    """The R factor of ``r_factor[:, columns]`` for an upper triangular ``r_factor``.

    Column ``i`` of ``r_factor[:, columns]`` has non-zeros in rows ``0..columns[i]`` only (a
    staircase below the diagonal, one step per removed column). Panels of ``block`` columns are
    triangularized by a QR of just their rows from the diagonal to the lowest non-zero, whose
    ``Q^T`` is applied to the same rows of the later columns (which keeps their staircase):
    ``O(n^2 (b + d))`` for ``d`` removed columns instead of the ``O(n^3)`` of a new QR.

    Parameters
    ----------
    r_factor : ndarray, shape (m, n)
        Upper triangular (trapezoidal) matrix.
    columns : array of int
        The columns kept, increasing.
    block : int, default 32
        Panel width.

    Returns
    -------
    ndarray, shape (min(m, len(columns)), len(columns))
        Upper triangular ``R`` with ``R^T R = A^T A`` for ``A = r_factor[:, columns]`` (the signs
        of its rows may differ from a Householder QR of ``A``).
    """
    columns = np.asarray(columns, dtype=int)
    matrix = np.array(r_factor[:, columns], dtype=float, order="F")
    m, n = matrix.shape
    bottom = np.minimum(columns + 1, m)  # rows below hold zeros
    for start in range(0, min(m, n), block):
        stop = min(start + block, n)
        end = max(int(bottom[stop - 1]), min(stop, m))
        if end <= start + 1 or np.all(bottom[start:stop] <= np.arange(start, stop) + 1):
            continue  # already triangular
        packed, tau, _, info = scipy.linalg.lapack.dgeqrf(matrix[start:end, start:stop])
        if info != 0:
            raise np.linalg.LinAlgError(f"dgeqrf failed (info {info})")
        matrix[start:end, start:stop] = np.triu(packed)
        if stop < n:  # the panel's reflectors on the same rows of the later columns
            trailing = matrix[start:end, stop:]
            trailing, _, info = scipy.linalg.lapack.dormqr(
                "L", "T", packed[:, : len(tau)], tau, trailing, max(1, 64 * trailing.shape[1]))
            if info != 0:
                raise np.linalg.LinAlgError(f"dormqr failed (info {info})")
            matrix[start:end, stop:] = trailing
    return matrix[: min(m, n)]
