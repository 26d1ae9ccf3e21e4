"""Triangular least-squares systems: the reduction of rows to ``[R | Q^T y]``, its update after
removing columns (the refits of backward elimination), and triangular solves.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.linalg.lapack


def solve_triangular(a, b, lower: bool = False, trans: int = 0):
    """``scipy.linalg.solve_triangular(a, b, trans, lower, check_finite=False)`` of float arrays:
    the same LAPACK call (``trtrs``, on ``a`` or its transpose as SciPy chooses), without SciPy's
    argument handling and batching, which cost more than the solve on the small systems that
    the selections solve tens of thousands of times per fit.

    Parameters
    ----------
    a : ndarray, shape (k, k)
        Triangular matrix (float).
    b : ndarray, shape (k,) or (k, n)
        Right-hand side (float).
    lower : bool, default False
        ``a`` is lower triangular.
    trans : {0, 1}, default 0
        Solve ``a x = b`` (0) or ``a^T x = b`` (1).

    Returns
    -------
    ndarray, shape of ``b``
        The solution.

    Raises
    ------
    numpy.linalg.LinAlgError
        If ``a`` has a zero on its diagonal.

    Examples
    --------
    >>> import numpy as np
    >>> solve_triangular(np.array([[2.0, 1.0], [0.0, 4.0]]), np.array([4.0, 8.0])).tolist()
    [1.0, 2.0]
    """
    if b.size == 0:
        return scipy.linalg.solve_triangular(a, b, trans=trans, lower=lower, check_finite=False)
    if a.flags.f_contiguous:
        x, info = scipy.linalg.lapack.dtrtrs(a, b, lower=lower, trans=trans)
    else:  # the transposed system (LAPACK's layout), as SciPy solves it
        x, info = scipy.linalg.lapack.dtrtrs(a.T, b, lower=not lower, trans=not trans)
    if info > 0:
        raise np.linalg.LinAlgError(f"singular matrix: resolution failed at diagonal {info - 1}")
    if info < 0:
        raise ValueError(f"illegal value in {-info}-th argument of internal trtrs")
    return x


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
