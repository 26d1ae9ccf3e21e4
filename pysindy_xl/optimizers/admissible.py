r"""Sparse laws with a positive definite mass matrix: starts for the unforced law search.

Greedy paths end in sparse near-laws that define no motion (a momentum balance of rank-one
inertia). With ``Mbar_j`` each column's mean mass matrix in reference units, the convex
*admissible lasso* (cvxpy, reweighted as Candès, Wakin and Boyd, 2008)

.. math:: \min_\xi \; \lVert \Theta \xi \rVert^2 + \lambda \sum_j w_j |\xi_j|
          \quad \text{s.t.} \quad \sum_j \xi_j \bar M_j \succeq I

excludes them; its supports are starts that the caller refines by noise ratio.
"""

from __future__ import annotations

import functools

import numpy as np

from .._optional import import_optional

__all__ = ["admissible_supports", "reference_mass_matrices"]

#: Penalties of the admissible lasso, relative to the residual of the densest admissible law.
PENALTIES = (0.03, 0.1, 0.3, 1.0, 3.0)


def reference_mass_matrices(mass_matrices) -> np.ndarray:
    """Each column's mass matrix averaged over the states, symmetric and unit free.

    Per coordinate, in units of the median non-zero diagonal magnitude (1 where none).

    Parameters
    ----------
    mass_matrices : array, shape (S, F, n, n)
        The columns' mass matrices at ``S`` states.

    Returns
    -------
    ndarray, shape (F, n, n)
        The reference mass matrices.
    """
    mean = np.mean(np.asarray(mass_matrices, dtype=float), axis=0)
    mean = (mean + np.swapaxes(mean, 1, 2)) / 2
    diagonal = np.abs(np.diagonal(mean, axis1=1, axis2=2))  # (F, n)
    carried = diagonal > 0
    reference = np.array([np.median(diagonal[carried[:, i], i]) if carried[:, i].any()
                          else 1.0 for i in range(mean.shape[-1])])
    return mean / np.sqrt(np.outer(reference, reference))[None]


@functools.cache
def _solver():
    """Clarabel when installed, else cvxpy's choice (looked up once: ``installed_solvers``
    probes every solver's import on each call)."""
    cp = import_optional("cvxpy", "admissible starts")
    return cp.CLARABEL if "CLARABEL" in cp.installed_solvers() else None


def admissible_supports(r_factor, mass_matrices, penalties=PENALTIES, n_reweight: int = 5) -> list:
    """Supports of sparse laws whose mean mass matrix is positive definite (admissible lasso).

    Parameters
    ----------
    r_factor : array, shape (m, F)
        ``Theta`` or a factor with its Gram matrix.
    mass_matrices : array, shape (S, F, n, n)
        The columns' mass matrices, in the law's units.
    penalties : sequence of float, default PENALTIES
        Lasso weights, relative to the densest admissible law's squared residual.
    n_reweight : int, default 5
        Reweighted solves per penalty.

    Returns
    -------
    list of ndarray of int
        One support (sorted) per penalty that gave a law; empty without cvxpy or when no
        combination has a definite mass matrix.
    """
    cp = import_optional("cvxpy", "admissible starts")
    r_factor = np.asarray(r_factor, dtype=float)
    reference = reference_mass_matrices(mass_matrices)
    n_features, n = r_factor.shape[1], reference.shape[-1]
    carries = np.flatnonzero(np.any(reference != 0, axis=(1, 2)))
    if carries.size == 0:
        return []
    # the mean mass matrix as one linear map of the law (n * n entries, symmetric)
    inertia = reference[carries].reshape(carries.size, n * n).T
    xi = cp.Variable(n_features)
    weights = cp.Parameter(n_features, nonneg=True)  # lambda * w_j (one parameter: DPP)
    mass = cp.reshape(inertia @ xi[carries], (n, n), order="C")
    problem = cp.Problem(cp.Minimize(cp.sum_squares(r_factor @ xi) + weights @ cp.abs(xi)),
                         [(mass + mass.T) / 2 >> np.eye(n)])

    solver = _solver()

    def solve(values):
        weights.value = values
        try:
            problem.solve(solver=solver)
        except cp.error.SolverError:
            return None
        if problem.status not in ("optimal", "optimal_inaccurate") or xi.value is None:
            return None
        return np.asarray(xi.value, dtype=float)

    dense = solve(np.zeros(n_features))
    if dense is None:
        return []
    # (floored: on clean data the densest law's residual is at the rounding level)
    residual = max(float(np.sum((r_factor @ dense) ** 2)), 1e-14 * float(np.sum(r_factor**2)))
    supports = []
    for penalty in penalties:
        law = dense
        values = np.full(n_features, penalty * residual)
        for _ in range(int(n_reweight)):
            found = solve(values)
            if found is None:
                break
            law = found
            values = penalty * residual / (np.abs(law) + 1e-3 * np.abs(law).max())
        support = np.flatnonzero(np.abs(law) > 1e-4 * np.abs(law).max())
        if law is not dense and support.size >= 2:
            supports.append(support)
    return supports
