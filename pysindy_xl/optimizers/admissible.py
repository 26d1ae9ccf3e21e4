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
import scipy.sparse

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


def _clarabel_solves(problem, xi, weights):
    """A function ``weights -> law or None`` solving ``problem`` with Clarabel on cvxpy's own
    data, canonicalized once; None where the data are not as expected (cvxpy then solves).

    The weights enter only the linear objective, each as the coefficient of one variable
    (``|xi_j|``'s epigraph), so the data Clarabel gets are cvxpy's with that entry replaced.
    As ``problem.solve`` (warm start, its default), the solver of the previous solve is
    updated with the new data: every solve is the one ``problem.solve`` makes, without
    canonicalizing again.
    """
    cp = import_optional("cvxpy", "admissible starts")
    try:
        import clarabel
        from cvxpy.reductions.solvers.conic_solvers.clarabel_conif import (
            CLARABEL,
            dims_to_solver_cones,
        )
    except ImportError:  # pragma: no cover - Clarabel is looked up before
        return None
    n_features = xi.size
    try:
        weights.value = np.zeros(n_features)
        data, _, _ = problem.get_problem_data(cp.CLARABEL)
        base = np.array(data[cp.settings.C], dtype=float)
        program = data["param_prob"]
        start = program.var_id_to_col[xi.id]
        # the linear objective's map of the parameters: weight j's column
        column = program.param_id_to_col[weights.id]
        block = scipy.sparse.csc_array(program.q)[:, column:column + n_features].toarray()
    except Exception:  # noqa: BLE001 - any surprise: cvxpy solves as usual
        return None
    # each weight the coefficient (exactly 1) of its own entry, which is 0 without it
    entries = np.argmax(block != 0, axis=0)
    expected = np.zeros_like(block)
    expected[entries, np.arange(n_features)] = 1.0
    if block.shape[0] != base.size + 1 or not np.array_equal(block, expected) \
            or np.unique(entries).size != n_features or np.any(base[entries] != 0):
        return None
    matrix, offset = data[cp.settings.A], data[cp.settings.B]
    quadratic = data.get(cp.settings.P)
    quadratic = (scipy.sparse.csc_array((base.size, base.size)) if quadratic is None
                 else quadratic)
    quadratic = scipy.sparse.triu(quadratic).tocsc()
    cones = dims_to_solver_cones(data[cp.reductions.solvers.conic_solvers.conic_solver
                                      .ConicSolver.DIMS])
    accepted = {"Solved", "AlmostSolved"}  # cvxpy's optimal and optimal_inaccurate
    cache = []  # as cvxpy's warm start: one solver, its data updated in place

    def solve(values):
        linear = base.copy()
        linear[entries] = values
        solver = None
        try:
            if cache and hasattr(cache[0], "update") and cache[0].is_data_update_allowed():
                solver = cache[0]
                try:
                    solver.update(P=quadratic, q=linear, A=matrix, b=offset,
                                  settings=CLARABEL.parse_solver_opts(False, {},
                                                                      solver.get_settings()))
                except Exception:  # noqa: BLE001 - as cvxpy: a new solver
                    solver = None
            if solver is None:
                solver = clarabel.DefaultSolver(quadratic, linear, matrix, offset, cones,
                                                CLARABEL.parse_solver_opts(False, {}))
            solution = solver.solve()
        except Exception:  # noqa: BLE001 - as cvxpy's SolverError
            return None
        cache[:] = [solver]
        if str(solution.status) not in accepted or solution.x is None:
            return None
        return np.asarray(solution.x, dtype=float)[start:start + n_features]

    return solve


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

    def solve_with_cvxpy(values):
        weights.value = values
        try:
            problem.solve(solver=solver)
        except cp.error.SolverError:
            return None
        if problem.status not in ("optimal", "optimal_inaccurate") or xi.value is None:
            return None
        return np.asarray(xi.value, dtype=float)

    solve = (_clarabel_solves(problem, xi, weights) if solver is not None else None) \
        or solve_with_cvxpy

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
