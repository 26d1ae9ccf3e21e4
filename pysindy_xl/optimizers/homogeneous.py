r"""Errors-in-variables selection of a homogeneous law ``Theta xi = 0`` (unforced, noisy data).

Without a force, a law is a direction ``xi`` with ``Theta xi = 0``. When the columns carry
errors, ``Theta = Theta_0 + E`` with known second moments ``S = E[E^T E]`` (the weak form
propagates the position noise into them), the true law leaves the residual ``E xi``, whose
expected square is ``xi^T S xi``. The *noise ratio*

.. math:: \rho(\xi) = \frac{\lVert \Theta \xi \rVert^2}{\xi^T S \xi}

is therefore close to 1 for the true law, whatever its scale, and larger for any law the data
contradict. Its minimum over the laws on a support ``s`` is the smallest generalized eigenvalue
of the pencil ``(Theta_s^T Theta_s, S_ss)``; the minimizer is the consistent
(errors-in-variables) estimate of the law on that support (Fuller, *Measurement Error Models*,
1987, section 4.1).

The plain least-squares residual ``||Theta xi|| / ||xi||``, which SINDy-PI minimizes, is small
for laws whose *own noise* ``xi^T S xi`` is small, not only for laws that hold: on a noisy
unforced cart-pole a kinetic-only law, whose columns are smoothed and quiet, fits with half the
residual of the true law. The ratio removes that preference.

Selection
---------
1. **Path.** Backward elimination from all the columns: drop the column whose removal raises
   the smallest generalized eigenvalue least. The constrained eigenvalue of every candidate
   removal comes from one decomposition per step: with ``G V = S V diag(lambda)`` and
   ``V^T S V = I``, forcing ``xi_j = 0`` gives the root in ``[lambda_1, lambda_2]`` of the
   secular equation ``sum_i w_i^2 / (lambda_i - mu) = 0``, ``w = V[j]``.
2. **Swaps.** At high noise the greedy path can lose a true column early, imitated by a
   correlated pair. A second path starts from the best support of the first and refines
   every support by single swaps (:func:`refine_law_by_swaps`) before the next elimination.
3. **Score.** Every support of both paths is scored by ``n_folds``-fold cross-validation over
   contiguous blocks of rows: the law is estimated on the training rows and its noise ratio
   measured on the held-out rows (their share of the moments).
4. **Choice.** The smallest support within one standard error of the best (as
   :func:`~pysindy_xl.optimizers.selection.select_support` does for the explicit problem): a
   support missing a true term has a held-out ratio far above 1, the extra terms of a larger one
   do not lower it beyond its spread.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg

from ._sparse import triangular_factor
from .selection import _fold_labels, _fold_summary

__all__ = [
    "LawSelection",
    "definite_mass",
    "explained_coordinates",
    "law_elimination_path",
    "law_forward_path",
    "noise_ratio_law",
    "refine_law_by_swaps",
    "select_law",
]


def _whitened_factor(r_factor, moments):
    """``(R L^-T, L)`` with ``L L^T`` the (regularized) moments: the noise ratio of ``xi`` is
    ``||R L^-T (L^T xi)||^2 / ||L^T xi||^2``. The moments are regularized relative to their own
    scale, so that a column without noise cannot make them singular."""
    k = moments.shape[0]
    floor = 1e-10 * float(np.trace(moments)) / max(k, 1)
    if not floor > 0:  # no noise at all on these columns: a floor far below the signal's
        floor = max(1e-30 * float(np.sum(r_factor**2)) / max(k, 1), 1e-300)
    lower = np.linalg.cholesky(moments + floor * np.eye(k))
    whitened = scipy.linalg.solve_triangular(lower, r_factor.T, lower=True,
                                             check_finite=False).T
    return whitened, lower


def _pencil(r_factor, moments):
    """Ascending eigenpairs of the pencil ``(R^T R, S)``, ``V^T S V = I``.

    From the singular values of ``R L^-T`` (never from ``R^T R``, which would square the
    condition number: on clean data the true law's residual is at the rounding level of the
    Gram matrix)."""
    whitened, lower = _whitened_factor(r_factor, moments)
    _, singular, wt = np.linalg.svd(whitened, full_matrices=True)
    singular = np.concatenate([singular, np.zeros(wt.shape[0] - singular.size)])
    vectors = scipy.linalg.solve_triangular(lower.T, wt[::-1].T, lower=False,
                                            check_finite=False)
    return singular[::-1] ** 2, vectors


def noise_ratio_law(r_factor, moments) -> tuple[float, np.ndarray]:
    """Smallest noise ratio on all the columns and its law (unit norm, largest entry positive).

    Parameters
    ----------
    r_factor : array, shape (m, k)
        ``Theta`` or any factor with the same ``R^T R = Theta^T Theta`` (the triangular factor).
    moments : array, shape (k, k)
        ``E[E^T E]`` of the errors of the same rows.

    Returns
    -------
    ratio : float
    law : ndarray, shape (k,)

    Examples
    --------
    Two noisy copies of one signal: the law ``a - b = 0`` holds to the noise (ratio ~ 1).

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> signal = rng.normal(size=5000)
    >>> theta = signal[:, None] + 0.1 * rng.normal(size=(5000, 2))
    >>> ratio, law = noise_ratio_law(theta, 0.01 * 5000 * np.eye(2))
    >>> round(ratio, 1), (law / law[0]).round(2)
    (1.0, array([ 1., -1.]))
    """
    values, vectors = _pencil(np.asarray(r_factor, float), np.asarray(moments, float))
    law = vectors[:, 0] / np.linalg.norm(vectors[:, 0])
    return float(values[0]), law * np.sign(law[np.argmax(np.abs(law))])


def explained_coordinates(theta, law, n_blocks: int, min_share: float = 1e-3) -> np.ndarray:
    """Coordinates whose equation a law explains: the squared contributions of its terms in
    that coordinate's rows carry at least ``min_share`` of the largest coordinate's.

    A term that merely touches a coordinate with a negligible coefficient does not explain
    it. ``theta`` must have balanced coordinate blocks
    (:func:`~pysindy_xl.optimizers.coordinate_weights`), so that the shares compare
    equations, not units.

    Parameters
    ----------
    theta : array, shape (n_blocks * N, k)
        Columns of the law's support.
    law : array, shape (k,)
    n_blocks : int
    min_share : float, default 1e-3

    Returns
    -------
    ndarray of bool, shape (n_blocks,)

    Examples
    --------
    >>> import numpy as np
    >>> theta = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 1.0]])
    >>> explained_coordinates(theta, np.array([1.0, 1e-4]), 2).tolist()
    [True, False]
    """
    contributions = (np.asarray(theta, dtype=float) * law).reshape(n_blocks, -1, len(law))
    shares = np.sum(contributions**2, axis=(1, 2))
    return shares >= min_share * max(float(shares.max(initial=0.0)), 1e-300)


def definite_mass(mass_matrices, law) -> bool:
    """Whether the law's mass matrix ``sum_j law_j M_j`` is definite (of either sign: a law
    has no sign) on every state, judged unit free as
    :func:`~pysindy_xl.diagnostics.mass_matrix_report` does.

    Parameters
    ----------
    mass_matrices : array, shape (S, k, n, n)
    law : array, shape (k,)

    Examples
    --------
    >>> import numpy as np
    >>> columns = np.array([[[[1.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 1.0]]]])
    >>> definite_mass(columns, np.array([-2.0, -1.0])), definite_mass(columns, [1.0, 0.0])
    (True, False)
    """
    mass = np.einsum("sfij,f->sij", np.asarray(mass_matrices, dtype=float), law)
    mass = (mass + np.swapaxes(mass, 1, 2)) / 2
    diagonal = np.max(np.abs(np.diagonal(mass, axis1=1, axis2=2)), axis=0, initial=0.0)
    unit = 1.0 / np.sqrt(np.where(diagonal > 0, diagonal, 1.0))
    eigenvalues = np.linalg.eigvalsh(mass * unit[None, :, None] * unit[None, None, :])
    if np.median(np.trace(mass, axis1=1, axis2=2)) < 0:
        eigenvalues = -eigenvalues
    scale = max(float(np.abs(eigenvalues).max(initial=0.0)), 1e-300)
    return bool(np.all(eigenvalues.min(axis=1) > 1e-9 * scale))


def _constrained_minima(values, vectors, n_bisections: int = 48) -> np.ndarray:
    """Smallest eigenvalue of the pencil with ``xi_j = 0``, for every ``j`` at once.

    Parameters
    ----------
    values : array, shape (k,)
        Ascending generalized eigenvalues.
    vectors : array, shape (k, k)
        Their ``S``-orthonormal eigenvectors (columns).

    Returns
    -------
    ndarray, shape (k,)
        The root in ``[values[0], values[1]]`` of ``sum_i w_i^2 / (values[i] - mu)`` with
        ``w = vectors[j]`` (Cauchy interlacing puts it there; the function increases on it).
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


def law_elimination_path(r_factor, moments) -> np.ndarray:
    """Columns ordered from most to least needed by backward elimination of the noise ratio.

    Parameters
    ----------
    r_factor : array, shape (m, F)
        ``Theta`` or its triangular factor, unit-scale columns.
    moments : array, shape (F, F)
        ``E[E^T E]`` on the same columns.

    Returns
    -------
    ndarray of int, shape (F,)
        ``order[:k]`` is the support of size ``k`` (``k >= 2``) of the path.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b, c, d = rng.normal(size=(4, 2000))
    >>> clean = np.column_stack([a, b, a - 2 * b, c, d])
    >>> theta = clean + 0.05 * rng.normal(size=clean.shape)
    >>> order = law_elimination_path(theta, 0.0025 * 2000 * np.eye(5))
    >>> sorted(order[:3].tolist())
    [0, 1, 2]
    """
    support = np.arange(r_factor.shape[1])
    removed = []
    while len(support) > 2:
        kept = _eliminate_one(r_factor, moments, support)
        removed.append(int(np.setdiff1d(support, kept)[0]))
        support = kept
    return np.concatenate([support, removed[::-1]]).astype(int)


def _eliminate_one(r_factor, moments, support) -> np.ndarray:
    """The support without the column whose removal raises the smallest ratio least."""
    support = np.asarray(support, dtype=int)
    values, vectors = _pencil(r_factor[:, support], moments[np.ix_(support, support)])
    return np.delete(support, int(np.argmin(_constrained_minima(values, vectors))))


def law_forward_path(r_factor, moments, max_size=None) -> np.ndarray:
    """Columns in the order forward selection adds them: the pair with the smallest noise
    ratio first, then the column whose addition lowers the ratio most.

    Parameters
    ----------
    r_factor : array, shape (m, F)
        ``Theta`` or its triangular factor, unit-scale columns.
    moments : array, shape (F, F)
    max_size : int, optional
        Stop after this many columns (default: all).

    Returns
    -------
    ndarray of int
        ``order[:k]`` is the support of size ``k`` (``k >= 2``) of the path.
    """
    n_features = r_factor.shape[1]
    max_size = n_features if max_size is None else min(int(max_size), n_features)
    gram = r_factor.T @ r_factor
    diag_gram, diag_moments = np.diag(gram), np.diag(moments)
    # the best pair: for each first column, the best second one from its 1 x 1 pencil
    pairs = np.full(n_features, np.inf)
    partner = np.zeros(n_features, dtype=int)
    for j in range(n_features):
        values, vectors = _pencil(r_factor[:, [j]], moments[np.ix_([j], [j])])
        minima = _bordered_minima(values, vectors.T @ gram[[j]], vectors.T @ moments[[j]],
                                  diag_gram, diag_moments)
        minima[j] = np.inf
        partner[j] = int(np.argmin(minima))
        pairs[j] = minima[partner[j]]
    first = int(np.argmin(pairs))
    support = [first, int(partner[first])]
    while len(support) < max_size:
        outside = np.setdiff1d(np.arange(n_features), support)
        values, vectors = _pencil(r_factor[:, support], moments[np.ix_(support, support)])
        minima = _bordered_minima(values, vectors.T @ gram[np.ix_(support, outside)],
                                  vectors.T @ moments[np.ix_(support, outside)],
                                  diag_gram[outside], diag_moments[outside])
        support.append(int(outside[np.argmin(minima)]))
    return np.array(support, dtype=int)


def _bordered_minima(values, cross_gram, cross_moments, gram_diag, moments_diag,
                     n_bisections: int = 48) -> np.ndarray:
    """Smallest eigenvalue of the pencil with one more column, for every candidate at once.

    With the pencil's eigenpairs ``(lambda, V)`` on the current columns, adding column ``i``
    (Gram column ``c``, moment column ``d``) gives the root in ``[0, lambda_1]`` of
    ``f(mu) = g_ii - mu s_ii - sum_m (a_m - mu b_m)^2 / (lambda_m - mu)``, ``a = V^T c``,
    ``b = V^T d`` (the Schur complement of the bordered pencil; interlacing puts exactly one
    root there).

    Parameters
    ----------
    values : array, shape (k,)
    cross_gram, cross_moments : array, shape (k, m)
        ``V^T c`` and ``V^T d`` of the ``m`` candidates.
    gram_diag, moments_diag : array, shape (m,)

    Returns
    -------
    ndarray, shape (m,)
    """
    low = np.zeros(cross_gram.shape[1])
    high = np.full(cross_gram.shape[1], values[0])
    for _ in range(n_bisections):
        middle = 0.5 * (low + high)
        with np.errstate(divide="ignore", invalid="ignore"):
            coupling = np.sum((cross_gram - middle * cross_moments) ** 2
                              / (values[:, None] - middle), axis=0)
        positive = gram_diag - middle * moments_diag - coupling > 0  # the root lies above
        low = np.where(positive, middle, low)
        high = np.where(positive, high, middle)
    return 0.5 * (low + high)


def _smallest_ratio(r_factor, moments, support) -> float:
    return noise_ratio_law(r_factor[:, support], moments[np.ix_(support, support)])[0]


def refine_law_by_swaps(r_factor, moments, support, max_swaps: int = 50) -> np.ndarray:
    """Best-improvement single swaps of a law's support, lowering its smallest noise ratio.

    The greedy path can lose a true column that a pair of correlated candidates imitates at
    high noise; exchanging one selected column for an unselected one while the ratio drops
    (the 1-swap local search of L0Learn) recovers it. For every removal ``j`` the ratios of
    all the additions come from one decomposition (:func:`_bordered_minima`); the best swap
    is confirmed by an exact computation before it is taken.

    Parameters
    ----------
    r_factor : array, shape (m, F)
        ``Theta`` or its triangular factor, unit-scale columns.
    moments : array, shape (F, F)
    support : array of int
    max_swaps : int, default 50

    Returns
    -------
    ndarray of int
        The refined support, sorted.
    """
    gram = r_factor.T @ r_factor
    support = [int(j) for j in support]
    current = _smallest_ratio(r_factor, moments, support)
    for _ in range(int(max_swaps)):
        outside = np.setdiff1d(np.arange(r_factor.shape[1]), support)
        if outside.size == 0 or len(support) < 3:
            break
        best = (current, None, None)
        for position, removed in enumerate(support):
            rest = support[:position] + support[position + 1:]
            values, vectors = _pencil(r_factor[:, rest], moments[np.ix_(rest, rest)])
            minima = _bordered_minima(values, vectors.T @ gram[np.ix_(rest, outside)],
                                      vectors.T @ moments[np.ix_(rest, outside)],
                                      np.diag(gram)[outside], np.diag(moments)[outside])
            pick = int(np.argmin(minima))
            if minima[pick] < best[0]:
                best = (minima[pick], removed, int(outside[pick]))
        if best[1] is None:
            break
        candidate = sorted(set(support) - {best[1]} | {best[2]})
        ratio = _smallest_ratio(r_factor, moments, candidate)
        if not ratio < current * (1 - 1e-9):
            break
        support, current = candidate, ratio
    return np.array(sorted(support), dtype=int)


@dataclasses.dataclass
class LawSelection:
    """What the errors-in-variables selection chose and why (returned by :func:`select_law`).

    Parameters
    ----------
    order : ndarray of int
        Columns from most to least needed (:func:`law_elimination_path`).
    cv_ratio : ndarray
        Mean held-out noise ratio of the support of each size (index ``k - 1``; inf for
        ``k = 1``, which holds no law).
    cv_spread : ndarray
        Its standard error over the folds.
    size : int
        Chosen number of terms.
    best_size : int
        Size with the lowest held-out ratio.
    rule : str
        How ``size`` was chosen.
    """

    order: np.ndarray
    cv_ratio: np.ndarray
    cv_spread: np.ndarray
    size: int
    best_size: int
    rule: str

    @property
    def support(self) -> np.ndarray:
        """Selected columns, sorted."""
        return np.sort(self.order[: self.size])


def _held_out_ratios(theta, moments, supports, n_blocks, n_folds):
    """Held-out noise ratio and relative squared residual of the law of every support.

    Returns two arrays of shape (n_folds, len(supports)); the relative residual is
    ``||Theta xi||^2 / sum_j ||Theta_j xi_j||^2`` on the held-out rows (inf where a support
    cannot be fitted).

    The supports of a path are prefixes of one column order: with the columns in that order,
    each is a leading block of the triangular factors, so a fold costs one QR and small
    decompositions (not one decomposition of all the rows' factor per support)."""
    ratios = np.full((n_folds, len(supports)), np.inf)
    relative = np.full((n_folds, len(supports)), np.inf)
    longest = np.asarray(max(supports, key=len))
    nested = all(np.array_equal(s, longest[:len(s)]) for s in supports)
    if nested:
        theta = theta[:, longest]
        moments = moments[:, longest][:, :, longest]
        supports = [np.arange(len(s)) for s in supports]
    labels = _fold_labels(theta.shape[0], n_blocks, n_folds)
    blocks = np.arange(theta.shape[0]) // (theta.shape[0] // n_blocks)
    for fold in range(n_folds):
        test = labels == fold
        if not test.any() or test.all():
            continue
        # each block's moments spread evenly over its rows: the fold's share of each block
        share = np.bincount(blocks[test], minlength=n_blocks) / np.bincount(blocks)
        test_moments = np.einsum("b,bfg->fg", share, moments)
        train_moments = moments.sum(axis=0) - test_moments
        r_train = triangular_factor(theta[~test])
        r_test = triangular_factor(theta[test])
        for m, support in enumerate(supports):
            if len(support) < 2 or len(support) > r_train.shape[0]:
                continue
            # leading columns of a triangular factor: its leading rows are all that is needed
            rows = slice(0, len(support)) if nested else slice(None)
            _, law = noise_ratio_law(r_train[rows, support],
                                     train_moments[np.ix_(support, support)])
            noise = law @ test_moments[np.ix_(support, support)] @ law
            test_factor = r_test[:, support]
            residual = np.sum((test_factor @ law) ** 2)
            signal = np.sum((test_factor * law) ** 2)
            if noise > 0 and signal > 0:
                ratios[fold, m] = residual / noise
                relative[fold, m] = residual / signal
    return ratios, relative


def select_law(theta, noise_moments, n_blocks: int = 1, n_folds: int = 5,
               resolution: float = 1e-8, swaps: bool = True, mass_matrices=None
               ) -> tuple[np.ndarray, float, LawSelection]:
    """Sparsest homogeneous law of noisy columns, by held-out noise ratio.

    Candidates are the supports of two paths: the backward path
    (:func:`law_elimination_path`) and, with ``swaps``, a path refined by single swaps
    (:func:`refine_law_by_swaps`) at every size, from the best support of the first down. The
    choice is the smallest support within one standard error of the best of both.

    Parameters
    ----------
    theta : array, shape (n_rows, F)
        Regression matrix, rows ``n_blocks`` equal blocks (coordinates).
    noise_moments : array, shape (n_blocks, F, F)
        ``E[E_b^T E_b]`` of each block's errors.
    n_blocks : int, default 1
    n_folds : int, default 5
    resolution : float, default 1e-8
        Held-out relative squared residuals closer than this to the best count as equal: on
        clean data the moments are tiny and extra terms fit quadrature errors (as for
        :func:`~pysindy_xl.optimizers.selection.select_support`).
    swaps : bool, default True
    mass_matrices : array, shape (S, F, n_blocks, n_blocks), optional
        Each column's contribution to the mass matrix on sample states
        (:func:`~pysindy_xl.diagnostics.column_mass_matrices`): laws whose mass matrix is not
        definite there are not candidates (unless no law is definite).

    Returns
    -------
    law : ndarray, shape (F,)
        Unit-norm law on the selected support (largest entry positive).
    ratio : float
        Its noise ratio on all the rows (~1 for a law that holds to the noise).
    selection : LawSelection

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b, c, d = rng.normal(size=(4, 2000))
    >>> clean = np.column_stack([a, b, a - 2 * b, c, d])
    >>> theta = clean + 0.05 * rng.normal(size=clean.shape)
    >>> law, ratio, selection = select_law(theta, 0.0025 * 2000 * np.eye(5)[None])
    >>> (law / law[0]).round(1) + 0.0, selection.size
    (array([ 1., -2., -1.,  0.,  0.]), 3)
    """
    theta = np.asarray(theta, dtype=float)
    moments = np.asarray(noise_moments, dtype=float)
    scale = np.sqrt(np.mean(theta**2, axis=0))
    scale[scale == 0] = 1.0
    theta = theta / scale
    moments = moments / np.outer(scale, scale)[None]
    # a column without noise of its own (a known force) still gets a floor far below the
    # others' noise, so that the ratios stay finite and comparable
    floor = 1e-10 * np.mean(np.diagonal(moments, axis1=1, axis2=2)) / len(moments)
    moments = moments + floor * np.eye(theta.shape[1])[None]
    total = moments.sum(axis=0)
    r_factor = triangular_factor(theta)
    order = law_elimination_path(r_factor, total)
    forward = law_forward_path(r_factor, total)
    candidates = (
        _scored(theta, moments, [order[:k] for k in range(2, len(order) + 1)], "backward path",
                n_blocks, n_folds)
        + _scored(theta, moments, [forward[:k] for k in range(2, len(forward) + 1)],
                  "forward path", n_blocks, n_folds))
    if not candidates:
        raise ValueError("theta: no law can be cross-validated on these rows")
    if swaps:
        best_path = min(candidates, key=lambda c: c.ratio)
        refined = _refined_path(r_factor, total, best_path.support)
        # and every path support up to the best size, refined at its own size
        seen = {frozenset(c.support.tolist()) for c in candidates + [
            _Candidate(r, 0, 0, 0, "") for r in refined]}
        for c in list(candidates):
            if len(c.support) <= len(best_path.support):
                support = refine_law_by_swaps(r_factor, total, c.support)
                if frozenset(support.tolist()) not in seen:
                    seen.add(frozenset(support.tolist()))
                    refined.append(support)
        candidates += _scored(theta, moments, refined, "swap-refined", n_blocks, n_folds)
    # Admissible laws only, when there are any:
    # - a law that leaves a coordinate out (or enters it with negligible terms) says nothing
    #   about it, and its ratio is measured on the other rows only. Such laws can hold
    #   exactly (the unforced cart-pole's pendulum row alone: the Routhian of the cyclic
    #   cart coordinate); without any law explaining every coordinate (uncoupled subsystems)
    #   the coordinates are left to further laws;
    # - with the columns' mass matrices, a law whose mass matrix is not definite on the
    #   states does not define motion (the unforced cart-pole's momentum balance written as
    #   a Lagrangian is sparse, holds to the friction, and has det M = 0).
    def admissible(candidate):
        support = candidate.support
        law = noise_ratio_law(theta[:, support], total[np.ix_(support, support)])[1]
        if not explained_coordinates(theta[:, support], law, n_blocks).all():
            return False
        return mass_matrices is None or definite_mass(mass_matrices[:, support],
                                                      law / scale[support])

    candidates = [c for c in candidates if admissible(c)] or candidates
    best = min(candidates, key=lambda c: c.ratio)
    # one standard error, or the resolution on the relative residual (clean data: the
    # moments are tiny, the ratios large, and extra terms that fit quadrature errors must not
    # win on that alone) in ratio units, by the best support's ratio-to-relative factor
    resolution_in_ratio = resolution * best.ratio / max(best.relative, 1e-300)
    limit = best.ratio + max(best.spread, resolution_in_ratio)
    chosen = min((c for c in candidates if c.ratio <= limit),
                 key=lambda c: (len(c.support), c.ratio))
    support = chosen.support
    ratio, values = noise_ratio_law(theta[:, support], total[np.ix_(support, support)])
    law = np.zeros(theta.shape[1])
    law[support] = values / scale[support]
    law /= np.linalg.norm(law)
    cv_ratio, cv_spread = np.full(len(order), np.inf), np.full(len(order), np.inf)
    for c in candidates:  # the best of each size
        if c.ratio < cv_ratio[len(c.support) - 1]:
            cv_ratio[len(c.support) - 1], cv_spread[len(c.support) - 1] = c.ratio, c.spread
    selection = LawSelection(
        order=np.concatenate([np.sort(support), order[~np.isin(order, support)]]),
        cv_ratio=cv_ratio, cv_spread=cv_spread, size=len(support),
        best_size=len(best.support), rule=f"one standard error of the noise ratio ({chosen.how})")
    return law * np.sign(law[np.argmax(np.abs(law))]), ratio, selection


@dataclasses.dataclass
class _Candidate:
    support: np.ndarray
    ratio: float  # mean held-out noise ratio
    spread: float  # its standard error over the folds
    relative: float  # mean held-out relative squared residual
    how: str


def _scored(theta, moments, supports, how, n_blocks, n_folds) -> list:
    """Candidates of the supports that can be cross-validated."""
    ratios, relative = _held_out_ratios(theta, moments, supports, n_blocks, n_folds)
    (mean, spread), (relative_mean, _) = _fold_summary(ratios), _fold_summary(relative)
    return [_Candidate(np.asarray(s), mean[m], spread[m], relative_mean[m], how)
            for m, s in enumerate(supports) if np.isfinite(mean[m])]


def _refined_path(r_factor, moments, start) -> list:
    """A second path, refined by swaps at every size: from ``start`` down to two columns,
    each support is swap-refined before the next elimination, so that a true column the
    plain path lost early (imitated by a correlated pair) can come back."""
    supports, support = [], np.asarray(start)
    while len(support) >= 2:
        support = refine_law_by_swaps(r_factor, moments, support)
        supports.append(support)
        if len(support) == 2:
            break
        support = _eliminate_one(r_factor, moments, support)
    return supports
