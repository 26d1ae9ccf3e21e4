"""SINDy-PI's building blocks: homothetic grouping, extraction of laws, the null-space warm
start and the cvxpy reference solver of problem (1) of
:class:`~pysindy_xl.optimizers.ImplicitOptimizer`.
"""

from __future__ import annotations

import warnings

import numpy as np
from sklearn.exceptions import ConvergenceWarning

from ._sparse import null_vector

__all__ = ["extract_laws", "homothetic_groups"]


def homothetic_groups(vectors, angle_tol: float, order=None) -> list[np.ndarray]:
    """Group column vectors along the same line (up to sign), greedily.

    Each unassigned column, visited in ``order``, seeds a group with the unassigned columns within
    ``angle_tol`` degrees of it.

    Parameters
    ----------
    vectors : array, shape (F, K)
        Columns to group (zero columns are never grouped).
    angle_tol : float
        Angular tolerance in degrees.
    order : array of int, optional
        Seeding order, best first (default: column order).

    Returns
    -------
    list of ndarray of int
        Groups (sorted indices) in seeding order, singletons included.

    Examples
    --------
    >>> import numpy as np
    >>> v = np.array([[1.0, -2.0, 0.0], [1.0, -2.0, 1.0]])
    >>> homothetic_groups(v, angle_tol=1.0)
    [array([0, 1]), array([2])]
    """
    vectors = np.asarray(vectors, dtype=float)
    norms = np.linalg.norm(vectors, axis=0)
    valid = norms > 0
    unit = np.where(valid, vectors / np.where(valid, norms, 1.0), 0.0)
    cosines = np.abs(unit.T @ unit)
    threshold = np.cos(np.deg2rad(angle_tol))
    order = np.arange(vectors.shape[1]) if order is None else np.asarray(order, dtype=int)
    free = valid.copy()
    groups = []
    for seed in order:
        if not free[seed]:
            continue
        members = np.flatnonzero(free & (cosines[seed] >= threshold))
        members = np.union1d(members, [seed])
        free[members] = False
        groups.append(members)
    return groups


def _principal_direction(unit_vectors) -> np.ndarray:
    """Leading left singular vector of sign-aligned unit columns, largest entry positive."""
    u, _, _ = np.linalg.svd(unit_vectors, full_matrices=False)
    direction = u[:, 0]
    return direction * np.sign(direction[np.argmax(np.abs(direction))])


def extract_laws(directions, groups, r_factor, *, refit: bool, threshold: float,
                 min_membership: float, max_residual_ratio: float, angle_tol: float):
    """``(laws, law_groups, residuals)`` of the homothetic groups: each group's principal direction
    (``directions`` (F, F), unit columns ``e_j - X[:, j]``), refit on its support with
    ``r_factor``, kept when it qualifies; best first, duplicates dropped. The keyword arguments
    are as in :class:`~pysindy_xl.ImplicitOptimizer`.
    """
    unit = directions / np.linalg.norm(directions, axis=0)
    candidates = []
    for group in groups:
        members = unit[:, group]
        # signs aligned on the first member: one cluster for the SVD
        members = members * np.sign(members.T @ members[:, 0])[None, :]
        direction = _principal_direction(members)
        if refit:
            law = _refit_on_support(direction, r_factor, threshold)
        else:
            law = np.where(np.abs(direction) >= threshold * np.max(np.abs(direction)),
                           direction, 0.0)
        support = np.flatnonzero(law)
        if np.intersect1d(group, support).size < min_membership * support.size:
            continue
        residual = float(np.linalg.norm(r_factor @ law) / np.linalg.norm(law))
        candidates.append((law, group, residual))
    if not candidates:
        return [], [], []
    best = min(c[2] for c in candidates)
    limit = max(best, 1e-12) * max_residual_ratio
    kept = [c for c in candidates if c[2] <= limit]
    # drop the same law reached from two groups
    laws, law_groups, residuals = [], [], []
    cos_tol = np.cos(np.deg2rad(angle_tol))
    for law, group, residual in sorted(kept, key=lambda c: c[2]):
        unit_law = law / np.linalg.norm(law)
        if any(abs(unit_law @ other) / np.linalg.norm(other) >= cos_tol for other in laws):
            continue
        laws.append(law)
        law_groups.append(group)
        residuals.append(residual)
    return laws, law_groups, residuals


def _refit_on_support(direction, r_factor, threshold: float) -> np.ndarray:
    """Null vector of the normalized matrix on the direction's support, pruned iteratively."""
    support = np.flatnonzero(np.abs(direction) >= threshold * np.max(np.abs(direction)))
    law = np.zeros_like(direction)
    while support.size >= 2:
        values, _ = null_vector(r_factor[:, support])
        small = np.abs(values) < threshold * np.max(np.abs(values))
        if not np.any(small):
            law[support] = values
            return law
        support = support[~small]
    return direction  # degenerate support: keep the clustered direction


def null_space_start(r_factor) -> np.ndarray:
    """Warm start from the near-null space ``V`` of the normalized matrix: column j starts at
    ``-v / v_j``, ``v = V V[j]^T``, exact for a column of an exact law (zero without weight
    there). The problem is convex: the start changes the speed, not the solution.
    """
    _, singular, vt = np.linalg.svd(r_factor, full_matrices=True)
    singular = np.concatenate([singular, np.zeros(vt.shape[0] - singular.size)])
    small = singular <= max(10 * singular[-1], 1e-8 * singular[0])
    basis = vt[small].T
    projector = basis @ basis.T
    weight = np.diag(projector).copy()
    start = np.zeros_like(projector)
    columns = np.flatnonzero(weight >= 1e-4)
    start[:, columns] = -projector[:, columns] / weight[columns]
    np.fill_diagonal(start, 0.0)
    return start


def solve_cvxpy(r_factor, alpha, solver=None):
    """Problem (1) with cvxpy on the triangular factor; returns (X, converged)."""
    import cvxpy as cp

    n = r_factor.shape[1]
    x = cp.Variable((n, n))
    objective = 0.5 * cp.sum_squares(r_factor @ x - r_factor) + alpha * cp.sum(cp.abs(x))
    problem = cp.Problem(cp.Minimize(objective), [cp.diag(x) == 0])
    try:
        problem.solve(solver=solver)
    except cp.error.SolverError as error:
        raise RuntimeError(f"ImplicitOptimizer: cvxpy solver {solver!r} failed: {error}") from error
    if x.value is None:
        raise RuntimeError(f"ImplicitOptimizer: cvxpy returned no solution ({problem.status})")
    converged = problem.status == cp.OPTIMAL
    if not converged:
        warnings.warn(f"ImplicitOptimizer: cvxpy status {problem.status!r}", ConvergenceWarning,
                      stacklevel=5)
    solution = np.array(x.value)
    np.fill_diagonal(solution, 0.0)
    return solution, converged
