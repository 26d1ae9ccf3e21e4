"""SINDy-PI's building blocks: homothetic grouping of solution columns, the null-space warm
start of the batched Lasso and the cvxpy reference solver (see
:class:`~pysindy_xl.optimizers.ImplicitOptimizer` for problem (1) they serve)."""

from __future__ import annotations

import warnings

import numpy as np
from sklearn.exceptions import ConvergenceWarning

__all__ = ["homothetic_groups"]


def homothetic_groups(vectors, angle_tol: float, order=None) -> list[np.ndarray]:
    """Group column vectors that point along the same line (up to sign), greedily.

    Columns are visited in ``order``; each unassigned column seeds a group with every other
    unassigned column whose angle to it (modulo sign) is at most ``angle_tol`` degrees.

    Parameters
    ----------
    vectors : array, shape (F, K)
        Columns to group (zero columns are never grouped).
    angle_tol : float
        Angular tolerance in degrees.
    order : array of int, optional
        Seeding order, best candidate first (default: column order).

    Returns
    -------
    list of ndarray of int
        Groups (sorted indices), in seeding order; singletons included.

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


def _null_space_start(r_factor) -> np.ndarray:
    """Warm start of the fast solver from the (near-)null space of the normalized matrix.

    With ``V`` the right singular vectors of the smallest singular values (within a factor 10 of
    the smallest, or below 1e-8 of the largest), column j's least-norm representation by the
    others along that space is ``-v / v_j`` with ``v = V V[j]^T``. For a column of an exact law
    this is the exact (unshrunk) solution, so the solver only has to apply the L1 shrinkage;
    columns with no weight on that space start from zero. The problem is convex: the start
    changes the speed, not the solution.
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


def _solve_cvxpy(r_factor, alpha, solver=None):
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
        warnings.warn(
            f"ImplicitOptimizer: cvxpy status {problem.status!r}", ConvergenceWarning, stacklevel=5
        )
    solution = np.array(x.value)
    np.fill_diagonal(solution, 0.0)
    return solution, converged
