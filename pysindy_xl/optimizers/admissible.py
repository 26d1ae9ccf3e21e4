r"""Sparse laws with a positive definite mass matrix: starts for the unforced law search.

An unforced law ``Theta xi = 0`` is only defined up to a factor, and a product catalog holds
many sparse combinations that nearly vanish on the data without being a Lagrangian of the
system: the balance of a conserved momentum written with constant inertia terms (its mass
matrix has rank one: it is one equation, not ``n``), or a law on the rows of some coordinates
only. Their noise ratios are small, so greedy paths over the whole catalog end in them, and
no support on those paths is admissible (:func:`~pysindy_xl.optimizers.laws.
definite_mass`). The true law is the one that also defines motion: its mass matrix
``M(xi) = sum_j xi_j M_j`` is positive definite.

That requirement also fixes the scale. With ``Mbar_j`` each column's mass matrix averaged over
the sample states, in units of a reference inertia per coordinate (the median magnitude of
the columns' diagonal entries), the *admissible lasso*

.. math:: \min_\xi \; \lVert \Theta \xi \rVert^2 + \lambda \sum_j w_j |\xi_j|
          \quad \text{s.t.} \quad \sum_j \xi_j \bar M_j \succeq I

is convex (a quadratic objective under a linear matrix inequality, an ``n x n`` semidefinite
constraint) and excludes the laws of rank-deficient inertia, where a linear normalization
(a unit diagonal, a unit mean kinetic energy) does not. It is solved for a few penalties
``lambda`` relative to the residual of the densest admissible law (``lambda = 0``), each
sparsified by reweighting (``w_j = 1 / (|xi_j| + eps)``, Candès, Wakin and Boyd, 2008). The
supports are starts, not answers: the least-squares residual prefers quiet columns (see
:mod:`~pysindy_xl.optimizers.noise_ratio`), so the caller refines each by the noise ratio's
backward elimination and scores it as every other candidate.

The problems are handed to cvxpy.
"""

from __future__ import annotations

import numpy as np

from .._optional import import_optional

__all__ = ["admissible_supports", "reference_mass_matrices"]

#: Penalties of the admissible lasso, relative to the residual of the densest admissible law.
PENALTIES = (0.03, 0.1, 0.3, 1.0, 3.0)


def reference_mass_matrices(mass_matrices) -> np.ndarray:
    """Each column's mass matrix (of ``mass_matrices``, (S, F, n, n)) averaged over the states,
    symmetric, in units of a reference inertia per coordinate: the median of the non-zero
    magnitudes of the columns' diagonal entries for that coordinate (1 where no column has
    one). Shape (F, n, n).

    Examples
    --------
    >>> import numpy as np
    >>> m = np.zeros((1, 2, 2, 2)); m[0, 0] = [[4.0, 0.0], [0.0, 0.0]]; m[0, 1] = np.eye(2)
    >>> reference_mass_matrices(m)[0].tolist()
    [[1.6, 0.0], [0.0, 0.0]]
    """
    mean = np.mean(np.asarray(mass_matrices, dtype=float), axis=0)
    mean = (mean + np.swapaxes(mean, 1, 2)) / 2
    diagonal = np.abs(np.diagonal(mean, axis1=1, axis2=2))  # (F, n)
    carried = diagonal > 0
    reference = np.array([np.median(diagonal[carried[:, i], i]) if carried[:, i].any()
                          else 1.0 for i in range(mean.shape[-1])])
    return mean / np.sqrt(np.outer(reference, reference))[None]


def admissible_supports(r_factor, mass_matrices, penalties=PENALTIES,
                        n_reweight: int = 5) -> list:
    """Supports of sparse laws with a positive definite mean mass matrix (admissible lasso).

    Parameters
    ----------
    r_factor : array, shape (m, F)
        ``Theta`` or a factor with the same Gram matrix, in the units of the law.
    mass_matrices : array, shape (S, F, n, n)
        Each column's mass matrix on sample states, in the same units (a law ``xi`` has the
        mass matrix ``sum_j xi_j M_j``).
    penalties : sequence of float
        ``lambda`` relative to the squared residual of the densest admissible law.
    n_reweight : int, default 5
        Solves per penalty (the first unweighted).

    Returns
    -------
    list of ndarray of int
        One support per penalty that gave a law, sorted; empty without cvxpy or when the
        inequality cannot be met (no combination of the columns has a definite mass matrix).

    Examples
    --------
    Two coordinates: columns 0 and 1 carry their inertia, column 2 is a potential; the law
    ``c0 + c1 + c2 = 0`` holds, and so, about as well, does ``c2 + c3 = 0``, whose column 3
    has an inertia of rank one (it is one equation, not two):

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b, c = rng.normal(size=(3, 400))
    >>> theta = np.column_stack([a, b, -(a + b), a + b + 1e-3 * c])
    >>> mass = np.zeros((1, 4, 2, 2))
    >>> mass[0, 0, 0, 0] = mass[0, 1, 1, 1] = 1.0
    >>> mass[0, 3] = [[1.0, 1.0], [1.0, 1.0]]
    >>> {tuple(s.tolist()) for s in admissible_supports(theta, mass)}
    {(0, 1, 2)}
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

    def solve(values):
        weights.value = values
        try:
            problem.solve(solver=cp.CLARABEL if "CLARABEL" in cp.installed_solvers() else None)
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
