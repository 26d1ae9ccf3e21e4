r"""The noise ratio of a homogeneous law ``Theta xi = 0`` and the paths of supports it orders.

With column errors of known moments ``S = E[E^T E]``, the *noise ratio*

.. math:: \rho(\xi) = \frac{\lVert \Theta \xi \rVert^2}{\xi^T S \xi}

is about 1 for the true law and larger for laws the data contradict (the plain residual
prefers laws on quiet columns). Its minimum on a support is the smallest eigenvalue of the
pencil ``(Theta_s^T Theta_s, S_ss)``, from the singular values of ``R L^-T`` (``L L^T = S``;
Fuller, 1987, 4.1). The paths and swaps solve the pencil's secular equations for all
candidates at once. ``r_factor`` (m, F) is ``Theta`` or a factor with its ``R^T R``;
``moments`` (F, F) those of the same rows.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.linalg.lapack

from ._triangular import solve_triangular

__all__ = ["law_elimination_path", "law_forward_path", "noise_ratio_law", "refine_law_by_swaps",
           "smallest_pair"]


def _whitened_factor(r_factor, moments):
    """``(R L^-T, L)``, ``L L^T`` the moments regularized relative to their own scale (a column
    without noise cannot make them singular); stacks (leading axes) at once.
    """
    k = moments.shape[-1]
    floor = 1e-10 * np.trace(moments, axis1=-2, axis2=-1) / max(k, 1)
    if not np.all(floor > 0):  # no noise at all on some columns: a floor far below the signal's
        signal_floor = np.maximum(1e-30 * np.sum(r_factor**2, axis=(-2, -1)) / max(k, 1), 1e-300)
        floor = np.where(floor > 0, floor, signal_floor)
    lower = np.linalg.cholesky(moments + floor[..., None, None] * np.eye(k))
    if lower.ndim == 2:
        whitened = solve_triangular(lower, r_factor.T, lower=True).T
    else:  # a stack: LAPACK's triangular solve has no batched form in numpy
        whitened = np.swapaxes(np.linalg.solve(lower, np.swapaxes(r_factor, -1, -2)), -1, -2)
    return whitened, lower


def noise_pencil(r_factor, moments):
    """Ascending eigenpairs of the pencil ``(R^T R, S)``, ``V^T S V = I``, from the singular values
    of ``R L^-T`` (the Gram matrix would square the condition number). Stacks (..., m, k) and
    (..., k, k) give values (..., k) and vectors (..., k, k).
    """
    whitened, lower = _whitened_factor(r_factor, moments)
    # all k right singular vectors; the left ones only as many as needed (a tall factor)
    m, k = whitened.shape[-2:]
    _, singular, wt = np.linalg.svd(whitened, full_matrices=m < k)
    singular = np.concatenate([singular, np.zeros(singular.shape[:-1] + (k - singular.shape[-1],))],
                              axis=-1)
    eigenvectors = np.swapaxes(wt[..., ::-1, :], -1, -2)
    if lower.ndim == 2:
        vectors = solve_triangular(lower.T, eigenvectors)
    else:
        vectors = np.linalg.solve(np.swapaxes(lower, -1, -2), eigenvectors)
    return singular[..., ::-1] ** 2, vectors


#: Pencils of at least this many columns get their smallest pair alone (:func:`smallest_pair`);
#: below it, the full decomposition costs less than the extra calls.
SMALLEST_ALONE = 24


def smallest_pair(r_factor, moments):
    """The smallest eigenpair of the pencil ``(R^T R, S)``: ``noise_pencil``'s first value and
    vector, the same numbers to rounding.

    From ``W = R L^-T`` made triangular (``R`` as given when it is upper triangular, else its QR),
    the pair is the largest eigenpair of ``W^-1 W^-T``: a triangular inverse and one eigenpair
    of a symmetric matrix (LAPACK's ``dsyevr``), where the SVD computes all of them. The largest
    eigenvalue of ``W^-1 W^-T`` is the dominant one, so its vector carries no more rounding than
    the SVD's smallest singular vector. Pencils of fewer than :data:`SMALLEST_ALONE` columns,
    wide ones and singular ``W`` go through :func:`noise_pencil`.

    Parameters
    ----------
    r_factor : ndarray, shape (..., m, k)
        ``Theta``, or a factor ``R`` with ``R^T R = Theta^T Theta`` (stacks along leading axes).
    moments : ndarray, shape (..., k, k)
        Noise moments ``S`` of the same columns.

    Returns
    -------
    value : ndarray, shape (...)
        The smallest eigenvalue (the smallest noise ratio).
    vector : ndarray, shape (..., k)
        Its eigenvector, ``v^T S v = 1`` (either sign).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> theta = rng.normal(size=(300, 50))
    >>> value, vector = smallest_pair(theta, np.eye(50))
    >>> values, vectors = noise_pencil(theta, np.eye(50))
    >>> bool(np.isclose(value, values[0])), bool(np.isclose(abs(vector @ vectors[:, 0]), 1.0))
    (True, True)
    """
    r_factor, moments = np.asarray(r_factor, dtype=float), np.asarray(moments, dtype=float)
    m, k = r_factor.shape[-2:]
    if k < SMALLEST_ALONE or m < k:
        values, vectors = noise_pencil(r_factor, moments)
        return values[..., 0], vectors[..., :, 0]
    lead = r_factor.shape[:-2]
    flat_r, flat_s = r_factor.reshape(-1, m, k), moments.reshape(-1, k, k)
    value, vector = np.empty(flat_r.shape[0]), np.empty((flat_r.shape[0], k))
    for i, (factor, noise) in enumerate(zip(flat_r, flat_s, strict=True)):
        value[i], vector[i] = _smallest_alone(factor, noise)
    return value.reshape(lead), vector.reshape(lead + (k,))


def _smallest_alone(r_factor, moments):
    """:func:`smallest_pair` of one pencil of at least as many rows as columns."""
    k = r_factor.shape[1]
    if not _upper_triangular(r_factor):
        r_factor = scipy.linalg.qr(r_factor, mode="r", check_finite=False)[0][:k]
    whitened, lower = _whitened_factor(r_factor, moments)  # upper triangular, as R
    inverse, info = scipy.linalg.lapack.dtrtri(whitened)
    if info == 0 and np.isfinite(inverse).all():
        gram = inverse @ inverse.T
        top, vectors, _, _, info = scipy.linalg.lapack.dsyevr(gram, range="I", il=k, iu=k)
        if info == 0 and 0 < top[0] < np.inf:
            vector = solve_triangular(lower.T, vectors[:, 0])
            if np.isfinite(vector).all():
                return 1.0 / top[0], vector
    values, vectors = noise_pencil(r_factor, moments)  # singular: the SVD's zero
    return values[0], vectors[:, 0]


def noise_ratio_law(r_factor, moments) -> tuple[float, np.ndarray]:
    r"""Smallest noise ratio on all the columns and its law.

    .. math:: \rho = \min_{\xi \ne 0} \frac{\lVert \Theta \xi \rVert^2}{\xi^T S \xi},

    the smallest generalized eigenvalue of ``(Theta^T Theta, S)``: about 1 for a law that holds
    to the noise.

    Parameters
    ----------
    r_factor : array, shape (m, F)
        ``Theta``, or a factor ``R`` with ``R^T R = Theta^T Theta``.
    moments : array, shape (F, F)
        Noise moments ``S = E[E^T E]`` of the columns.

    Returns
    -------
    ratio : float
        ``rho``.
    law : ndarray, shape (F,)
        The minimizer, of unit norm with its largest entry positive.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> signal = rng.normal(size=5000)
    >>> theta = signal[:, None] + 0.1 * rng.normal(size=(5000, 2))
    >>> ratio, law = noise_ratio_law(theta, 0.01 * 5000 * np.eye(2))
    >>> round(ratio, 1), (law / law[0]).round(2)
    (1.0, array([ 1., -1.]))
    """
    value, vector = smallest_pair(r_factor, moments)
    law = vector / np.linalg.norm(vector)
    return float(value), law * np.sign(law[np.argmax(np.abs(law))])


# Secular helpers: ``values`` (k,) or (k, m) and ``vectors`` (k, k) the current pencil;
# ``cross_gram``, ``cross_moments`` (k, m) = V^T of m candidates' columns; ``*_diag`` (m,).
def _constrained_minima(values, vectors, n_bisections: int = 48) -> np.ndarray:
    """Smallest eigenvalue of the pencil with ``xi_j = 0``, for every ``j``: the root in
    ``[values[0], values[1]]`` (interlacing) of ``sum_i w_i^2 / (values[i] - mu)``,
    ``w = vectors[j]``.
    """
    weights = vectors**2  # row j: w_i^2 of the constraint xi_j = 0
    low = np.full(values.size, values[0])
    high = np.full(values.size, values[1])
    for _ in range(n_bisections):
        middle = 0.5 * (low + high)
        with np.errstate(divide="ignore", invalid="ignore"):
            secular = np.sum(weights / (values[None, :] - middle[:, None]), axis=1)
        below = secular < 0  # the root lies above the middle
        low = np.where(below, middle, low)
        high = np.where(below, high, middle)
    return 0.5 * (low + high)


def _bisected_argmin(above, low, high, n_bisections: int = 48) -> int:
    """``argmin`` of the roots that ``n_bisections`` bisections of each candidate's bracket
    ``[low, high]`` give, ``above(middle, alive)`` telling where each alive candidate's root lies
    above its middle: the same index as bisecting all of them and taking the argmin, without
    bisecting the candidates that cannot win.

    A candidate whose bracket starts above the lowest bracket's end ends above that candidate,
    and one starting at it ends there at best: both are dropped (the latter only after the
    candidate it would tie with, as ``argmin`` keeps the first). A single one left is the
    answer.
    """
    low, high = np.array(low, dtype=float), np.array(high, dtype=float)
    alive = np.arange(low.size)
    # finite brackets stay finite (their middles): only then are they compared
    finite = bool(np.isfinite(low).all() and np.isfinite(high).all())
    for step in range(n_bisections):
        if alive.size == 1:
            return int(alive[0])
        middle = 0.5 * (low + high)
        up = above(middle, alive)
        np.copyto(low, middle, where=up)
        np.copyto(high, middle, where=~up)
        if finite and step % _PRUNE_EVERY == _PRUNE_EVERY - 1:
            first = int(np.argmin(high))  # ends at or below high[first]
            bound = high[first]
            keep = (low < bound) | ((low == bound) & (alive <= alive[first]))
            if not keep.all():
                alive, low, high = alive[keep], low[keep], high[keep]
    return int(alive[np.argmin(0.5 * (low + high))])


#: Bisections between two looks for candidates that cannot win (each look costs about as
#: much as a bisection of few candidates).
_PRUNE_EVERY = 4


def _least_constrained(values, vectors) -> int:
    """``argmin`` of :func:`_constrained_minima` (the same bisections, only where they can win).
    """
    weights = [np.arange(values.size), vectors**2]  # the alive candidates' rows

    def above(middle, alive):
        if alive.size != weights[0].size:
            weights[:] = [alive, vectors[alive] ** 2]
        secular = np.sum(weights[1] / (values[None, :] - middle[:, None]), axis=1)
        return secular < 0

    with np.errstate(divide="ignore", invalid="ignore"):
        return _bisected_argmin(above, np.full(values.size, values[0]),
                                np.full(values.size, values[1]))


def law_elimination_path(r_factor, moments) -> np.ndarray:
    """Columns ordered from most to least needed, by backward elimination of the noise ratio.

    Parameters
    ----------
    r_factor : array, shape (m, F)
        ``Theta``, or a factor ``R`` with ``R^T R = Theta^T Theta``.
    moments : array, shape (F, F)
        Noise moments ``S = E[E^T E]`` of the columns.

    Returns
    -------
    ndarray of int, shape (F,)
        The column order (the last eliminated first).
    """
    support = np.arange(r_factor.shape[1])
    removed = []
    while len(support) > 2:
        kept = eliminate_one(r_factor, moments, support)
        removed.append(int(np.setdiff1d(support, kept)[0]))
        support = kept
    return np.concatenate([support, removed[::-1]]).astype(int)


def _upper_triangular(matrix) -> bool:
    """Whether a square matrix has zeros below its diagonal."""
    return matrix.shape[0] == matrix.shape[1] and not np.tril(matrix, -1).any()


def eliminate_one(r_factor, moments, support) -> np.ndarray:
    """The support without the column whose removal raises the smallest ratio least."""
    support = np.asarray(support, dtype=int)
    values, vectors = noise_pencil(r_factor[:, support], moments[np.ix_(support, support)])
    return np.delete(support, _least_constrained(values, vectors))


def law_forward_path(r_factor, moments, max_size=None) -> np.ndarray:
    """Columns in the order forward selection adds them.

    The best pair first, then the column lowering the noise ratio most.

    Parameters
    ----------
    r_factor : array, shape (m, F)
        ``Theta``, or a factor ``R`` with ``R^T R = Theta^T Theta``.
    moments : array, shape (F, F)
        Noise moments ``S = E[E^T E]`` of the columns.
    max_size : int, optional
        Stop after this many columns; default None: all.

    Returns
    -------
    ndarray of int
        The column order.
    """
    n_features = r_factor.shape[1]
    max_size = n_features if max_size is None else min(int(max_size), n_features)
    gram = r_factor.T @ r_factor
    diag_gram, diag_moments = np.diag(gram), np.diag(moments)
    # the best pair, from every column's 1 x 1 pencil bordered by every other column
    values, vectors = noise_pencil(r_factor.T[:, :, None], diag_moments[:, None, None])
    scale = vectors[:, 0, 0][:, None]  # (F, 1): the pencils' single eigenvectors
    pairs = np.flatnonzero(~np.eye(n_features, dtype=bool))  # not a column with itself
    pair = _least_bordered(
        np.repeat(values[:, 0], n_features)[None], (scale * gram).reshape(1, -1),
        (scale * moments).reshape(1, -1), np.tile(diag_gram, n_features),
        np.tile(diag_moments, n_features), pairs)
    first, second = np.unravel_index(pair, (n_features, n_features))
    support = [int(first), int(second)]
    while len(support) < max_size:
        outside = np.setdiff1d(np.arange(n_features), support)
        values, vectors = noise_pencil(r_factor[:, support], moments[np.ix_(support, support)])
        best = _least_bordered(values, vectors.T @ gram[np.ix_(support, outside)],
                               vectors.T @ moments[np.ix_(support, outside)],
                               diag_gram[outside], diag_moments[outside])
        support.append(int(outside[best]))
    return np.array(support, dtype=int)


def _bordered_secular(mu, values, cross_gram, cross_moments, gram_diag, moments_diag):
    """The bordered pencil's secular function ``f(mu)`` of every candidate (last axis); positive
    where the candidate's root lies above ``mu``.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        coupling = np.sum((cross_gram - mu * cross_moments) ** 2 / (values - mu), axis=-2)
    return gram_diag - mu * moments_diag - coupling


def _bordered_minima(values, cross_gram, cross_moments, gram_diag, moments_diag,
                     n_bisections: int = 48) -> np.ndarray:
    """Smallest eigenvalue of the pencil with one more column, for every candidate at once: the
    root in ``[0, lambda_1]`` of ``f(mu) = g_ii - mu s_ii - sum_m (a_m - mu b_m)^2 / (lambda_m -
    mu)``, ``a = V^T c``, ``b = V^T d`` (``c``, ``d`` the candidate's Gram and moment columns).
    """
    values = values[:, None] if values.ndim == 1 else values
    low = np.zeros(cross_gram.shape[1])
    high = np.broadcast_to(values[0], low.shape)
    for _ in range(n_bisections):
        middle = 0.5 * (low + high)
        positive = _bordered_secular(middle, values, cross_gram, cross_moments,
                                     gram_diag, moments_diag) > 0  # the root lies above
        low = np.where(positive, middle, low)
        high = np.where(positive, high, middle)
    return 0.5 * (low + high)


def _least_bordered(values, cross_gram, cross_moments, gram_diag, moments_diag,
                    candidates=None) -> int:
    """``argmin`` of :func:`_bordered_minima` over ``candidates`` (default all; an index of all
    the candidates), by the same bisections, only where they can win."""
    values = values[:, None] if values.ndim == 1 else values
    candidates = (np.arange(cross_gram.shape[1]) if candidates is None
                  else np.asarray(candidates, dtype=int))
    parts = [None]  # the alive candidates' arrays

    def above(middle, alive):
        if parts[0] is None or alive.size != parts[0].size:
            chosen = candidates[alive]
            parts[:] = [alive, values if values.shape[1] == 1 else values[:, chosen],
                        cross_gram[:, chosen], cross_moments[:, chosen], gram_diag[chosen],
                        moments_diag[chosen]]
        return _bordered_secular(middle, *parts[1:]) > 0  # the root lies above

    high = np.broadcast_to(values[0], (cross_gram.shape[1],))[candidates]
    return int(candidates[_bisected_argmin(above, np.zeros(candidates.size), high)])


def _smallest_bordered_root(ceiling, values, cross_gram, cross_moments, gram_diag,
                            moments_diag, n_bisections: int = 48):
    """``(index, root)`` of the candidate with the smallest bordered root below ``ceiling``, or
    None: the argmin of :func:`_bordered_minima` by one shared bisection, dropping candidates as
    soon as a root is bracketed below theirs (at a local optimum: one evaluation).
    """
    def secular(mu, alive):
        return _bordered_secular(mu, values[:, alive], cross_gram[:, alive],
                                 cross_moments[:, alive], gram_diag[alive], moments_diag[alive])

    alive = np.flatnonzero(~(secular(ceiling, slice(None)) > 0))
    if alive.size == 0:
        return None
    low, high = 0.0, float(ceiling)
    for _ in range(n_bisections):
        middle = 0.5 * (low + high)
        below = ~(secular(middle, alive) > 0)
        if below.any():  # some root lies at or below the middle: the others cannot win
            alive, high = alive[below], middle
        else:
            low = middle
    return int(alive[0]), 0.5 * (low + high)


def _smallest_ratio(r_factor, moments, support) -> float:
    return noise_ratio_law(r_factor[:, support], moments[np.ix_(support, support)])[0]


def refine_law_by_swaps(r_factor, moments, support, max_swaps: int = 50,
                        memo: dict | None = None) -> np.ndarray:
    """Best-improvement single swaps of a law's support, lowering its smallest noise ratio.

    Recovers a true column that a correlated pair imitated on the greedy path (L0Learn's 1-swap
    search); swaps are screened from the support's own pencil and confirmed exactly.

    Parameters
    ----------
    r_factor : array, shape (m, F)
        ``Theta``, or a factor ``R`` with ``R^T R = Theta^T Theta``.
    moments : array, shape (F, F)
        Noise moments ``S = E[E^T E]`` of the columns.
    support : array of int
        The starting support.
    max_swaps : int, default 50
        At most this many swaps.
    memo : dict, optional
        Shared between calls on the same arguments: visited supports to where their search
        ended. Default None.

    Returns
    -------
    ndarray of int
        The refined support, sorted.
    """
    memo = {} if memo is None else memo
    gram = r_factor.T @ r_factor
    support = sorted(int(j) for j in support)
    visited = []
    current = _smallest_ratio(r_factor, moments, support)
    for _ in range(int(max_swaps)):
        key = frozenset(support)
        if key in memo:
            support = sorted(memo[key])
            break
        visited.append(key)
        outside = np.setdiff1d(np.arange(r_factor.shape[1]), support)
        if outside.size == 0 or len(support) < 3 or not current > 0:
            break
        best = _best_swap(r_factor, moments, gram, support, outside, current)
        if best is None:
            break
        candidate = sorted(set(support) - {best[0]} | {best[1]})
        ratio = _smallest_ratio(r_factor, moments, candidate)
        if not ratio < current * (1 - 1e-9):
            break
        support, current = candidate, ratio
    memo.update(dict.fromkeys(visited, tuple(support)))
    return np.array(sorted(support), dtype=int)


def _swap_secular_at_the_law(values, vectors, cross_gram, cross_moments, gram_diag,
                             moments_diag) -> np.ndarray:
    """Secular function at the support's ratio ``c = lambda_1`` of every swap ``j -> i``, (k, n).

    ``A = G - c S`` is positive definite on ``s - j``, so the swap lowers the ratio iff the Schur
    complement of ``i`` is negative; in the pencil's eigenbasis it is

    .. math:: f_{ji} = a_{ii} - P_i + 2 x_i Q_{ji} / y_j - x_i^2 R_j / y_j^2

    with ``w = V^T u`` (``u = A_si``, ``x = w_1``), ``y = V_{j1}`` and ``P, Q, R`` the sums over
    ``m >= 2`` of ``w_m^2``, ``V_{jm} w_m``, ``V_{jm}^2`` over ``lambda_m - lambda_1``. Positive
    where the swap cannot lower the ratio; not finite where ``y_j = 0``.
    """
    law_ratio = values[0]
    gaps = values[1:] - law_ratio
    w = cross_gram - law_ratio * cross_moments  # (k, n)
    x, y = w[0], vectors[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        scaled = w[1:] / gaps[:, None]
        p_term = np.sum(w[1:] * scaled, axis=0)  # (n,)
        q_term = vectors[:, 1:] @ scaled  # (k, n)
        r_term = (vectors[:, 1:] ** 2) @ (1.0 / gaps)  # (k,)
        schur = (gram_diag - law_ratio * moments_diag - p_term)[None, :] \
            + 2 * x[None, :] * q_term / y[:, None] - x[None, :] ** 2 * (r_term / y**2)[:, None]
    return schur


def _best_swap(r_factor, moments, gram, support, outside, current):
    """``(removed, added)`` of the swap with the smallest ratio below ``current``, or None."""
    k = len(support)
    # the support's own k x k factor
    factor = scipy.linalg.qr(r_factor[:, support], mode="r", check_finite=False)[0][:k]
    gram_out, moments_out = gram[np.ix_(support, outside)], moments[np.ix_(support, outside)]
    gram_diag, moments_diag = np.diag(gram)[outside], np.diag(moments)[outside]
    values, vectors = noise_pencil(factor, moments[np.ix_(support, support)])
    screen = _swap_secular_at_the_law(values, vectors, vectors.T @ gram_out,
                                      vectors.T @ moments_out, gram_diag, moments_diag)
    removals = np.flatnonzero(np.any(~(screen > 0), axis=1))
    if removals.size == 0:
        return None
    # (r, k-1): the support's positions without each removal
    keep = np.arange(k - 1)[None, :] + (np.arange(k - 1)[None, :] >= removals[:, None])
    rest = np.asarray(support)[keep]
    values, vectors = noise_pencil(np.swapaxes(factor[:, keep], 0, 1),
                              moments[rest[:, :, None], rest[:, None, :]])
    # (k-1, r * n): removal-major, so candidate j * n + i swaps removals[j] for outside[i]
    n_out = outside.size
    values = np.repeat(values.T, n_out, axis=1)
    cross_gram = np.einsum("rab,rao->bro", vectors, gram_out[keep]).reshape(k - 1, -1)
    cross_moments = np.einsum("rab,rao->bro", vectors, moments_out[keep]).reshape(k - 1, -1)
    found = _smallest_bordered_root(current, values, cross_gram, cross_moments,
                                    np.tile(gram_diag, removals.size),
                                    np.tile(moments_diag, removals.size))
    if found is None:
        return None
    position, addition = divmod(found[0], n_out)
    return support[removals[position]], int(outside[addition])
