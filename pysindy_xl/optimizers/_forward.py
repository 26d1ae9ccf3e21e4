"""Forward stepwise selection (orthogonal least squares) on a reduced least-squares system: the
column order of :func:`~pysindy_xl.optimizers.selection.forward_path`.

Each step adds the column ``c`` whose part off the chosen columns, ``o_c = x_c - Q Q^T x_c``,
explains most of the residual ``r``: the largest gain ``(o_c . r)^2 / |o_c|^2``. Instead of
keeping every ``o_c`` up to date (a rank-1 update of the whole ``n x F`` matrix a step), the
squared norms ``|o_c|^2 = |x_c|^2 - sum_i (q_i . x_c)^2`` and correlations ``x_c . r`` come
from two products ``x^T q`` and ``x^T r`` a step. These cheap values carry rounding errors that
cancellation can make large relative to a small ``|o_c|``, so they only bound each gain; the
columns whose bounds reach the best lower bound (usually a handful) get their gain computed
from the explicit ``o_c`` (Gram-Schmidt twice, as accurate as the updated matrix), and the step
picks among those.
"""

from __future__ import annotations

import numpy as np

# rounding bound per accumulated step, relative to |x_c|^2 (for |o_c|^2) and |x_c| |r_0| (for the
# correlation): generous against n = 1000s of rows (eps sqrt(n) ~ 1e-14)
_ROUNDING = 1e-13
# exact gains of all candidates when their explicit parts take fewer multiplications than this
# (then they cost less than the passes of the bounds)
_EXACT_WORK = 200_000


def forward_order(active_mask, xs, residual, max_steps=None) -> np.ndarray:
    """Column order by forward stepwise selection on a reduced system.

    Parameters
    ----------
    active_mask : ndarray of bool, shape (F,)
        Columns that may be chosen.
    xs : ndarray, shape (m, F)
        Columns (rows of a reduced system or data rows).
    residual : ndarray, shape (m,)
        Target.
    max_steps : int, optional
        After this many picks the remaining columns follow in column order (default: all).

    Returns
    -------
    ndarray of int, shape (F,)
        The column order.
    """
    xs = np.ascontiguousarray(xs, dtype=float)  # matrix-vector products at full speed
    n_rows, n_columns = xs.shape
    steps = n_columns if max_steps is None else min(int(max_steps), n_columns)
    norms2 = np.einsum("ij,ij->j", xs, xs)
    norms = np.sqrt(norms2)
    basis = np.zeros((n_rows, min(steps, n_rows)))
    projections = np.zeros((basis.shape[1], n_columns))  # Q^T x
    residual = np.array(residual, dtype=float)
    start_norm = float(np.linalg.norm(residual))
    correlation = xs.T @ residual
    remaining2 = norms2.copy()
    candidates = np.asarray(active_mask, dtype=bool).copy()
    chosen = []
    while candidates.any() and len(chosen) < min(steps, n_rows):
        k = len(chosen)
        j = _best_column(xs, residual, basis[:, :k], projections[:k], candidates, norms2, norms,
                         remaining2, correlation, start_norm)
        if j is None:
            break
        direction = _orthogonal_part(xs[:, [j]], basis[:, :k], projections[:k, [j]])[:, 0]
        direction /= np.linalg.norm(direction)
        residual = residual - direction * (direction @ residual)
        # two matrix-vector products (an (F, 2) matrix product is several times slower)
        basis[:, k], projections[k] = direction, xs.T @ direction
        correlation = xs.T @ residual
        remaining2 = remaining2 - projections[k] ** 2
        chosen.append(j)
        candidates[j] = False
    picked = set(chosen)
    return np.array(chosen + [j for j in range(n_columns) if j not in picked], dtype=int)


def _orthogonal_part(columns, basis, projections):
    """``columns - Q Q^T columns``, Gram-Schmidt twice (``projections`` = ``Q^T columns``)."""
    part = columns - basis @ projections
    return part - basis @ (basis.T @ part)


def _contenders(candidates, norms2, norms, remaining2, correlation, steps, start_norm):
    """The candidates whose gain's upper bound reaches the largest lower bound of a usable
    candidate's gain (bounds from the cheap values and their rounding after ``steps``)."""
    error2 = (_ROUNDING * steps) * norms2                    # on |o_c|^2
    error = (_ROUNDING * steps * start_norm) * norms         # on o_c . r
    size = np.abs(correlation)
    low = np.maximum(size - error, 0.0) ** 2 / (np.maximum(remaining2, 0.0) + error2)
    # certainly usable: the part off the chosen columns is above the threshold
    sure = candidates & (remaining2 - error2 > 1e-20 * norms2)
    floor = low[sure].max(initial=0.0)
    # the upper bound (size + error)^2 / (remaining2 - error2) reaches the floor
    reach = (size + error) ** 2 >= floor * np.maximum(remaining2 - error2, 0.0)
    maybe = remaining2 + error2 > 1e-20 * norms2
    return np.flatnonzero(candidates & reach & maybe)


def _best_column(xs, residual, basis, projections, candidates, norms2, norms, remaining2,
                 correlation, start_norm):
    """The candidate of the largest gain ``(o_c . r)^2 / |o_c|^2`` (None if no candidate has a
    part off the chosen columns above ``1e-20 |x_c|^2``): bounds from the cheap values, exact
    gains for the columns whose upper bound reaches the best lower bound.
    """
    if np.count_nonzero(candidates) * basis.size <= _EXACT_WORK:
        contenders = np.flatnonzero(candidates)
    else:
        contenders = _contenders(candidates, norms2, norms, remaining2, correlation,
                                 basis.shape[1] + 1, start_norm)
    if not len(contenders):
        return None
    parts = _orthogonal_part(xs[:, contenders], basis, projections[:, contenders])
    exact2 = np.einsum("ij,ij->j", parts, parts)
    usable = exact2 > 1e-20 * norms2[contenders]
    if not usable.any():
        return None
    gain = np.where(usable, (parts.T @ residual) ** 2 / np.where(usable, exact2, 1.0), -np.inf)
    return int(contenders[np.argmax(gain)])
