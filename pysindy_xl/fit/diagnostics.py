"""Fit-time diagnostics of an identified model on its own training states.

A model can be wrong in ways the regression residual does not show: a mass matrix that is
indefinite (noise terms, a coordinate without identifiable inertia, a catalog that cannot
express the dynamics) or a law that no force scales and came out with a negative kinetic
energy (its sign is arbitrary). :func:`orient_free_laws` fixes the second,
:func:`mass_matrix_report` measures the first and warns.
"""

from __future__ import annotations

import warnings

import numpy as np

from .._validation import IdentificationWarning

__all__ = [
    "column_mass_matrices",
    "mass_matrices",
    "orient_free_laws",
    "mass_matrix_report",
]


def mass_matrices(dynamics, states, max_states: int = 2000):
    """Symmetrized mass matrices and their eigenvalues on (up to ``max_states``) states.

    Parameters
    ----------
    dynamics : MassMatrixDynamics
    states : array, shape (N, 4n + 1)
        Stacked variables (:func:`~pysindy_xl.stack_variables`).
    max_states : int

    Returns
    -------
    mass : ndarray, shape (S, n, n)
    eigenvalues : ndarray, shape (S, n)

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> dyn = px.MassMatrixDynamics(c, [2 * c.qdd[0] + c.q[0]])
    >>> mass_matrices(dyn, np.zeros((10, 5)))[1][:2]
    array([[2.],
           [2.]])
    """
    rows = states[np.unique(np.linspace(0, len(states) - 1,
                                        min(len(states), max_states)).astype(int))]
    mass, _ = dynamics.mass_and_forcing(rows)
    mass = (mass + np.swapaxes(mass, 1, 2)) / 2
    return mass, np.linalg.eigvalsh(mass)


def column_mass_matrices(library, states, max_states: int = 200) -> np.ndarray:
    """Each catalog column's contribution to the mass matrix, on (up to ``max_states``) states.

    Every column's Euler-Lagrange expression is affine in the accelerations,
    ``E_j = M_j(q, qd) qdd + rest``, so ``M_j[:, k]`` is the column evaluated with
    ``qdd = e_k`` minus the column with ``qdd = 0``: ``n + 1`` evaluations of the library, no
    symbolic work. A coefficient vector ``xi`` has the mass matrix ``sum_j xi_j M_j``.

    Parameters
    ----------
    library : fitted SymbolicLibrary
    states : array, shape (N, 4n + 1)
        Stacked variables (:func:`~pysindy_xl.stack_variables`); accelerations and forces
        are ignored.
    max_states : int, default 200

    Returns
    -------
    ndarray, shape (S, F, n, n)

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> library = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]).fit()
    >>> column_mass_matrices(library, np.zeros((3, 5)))[0, :, 0, 0]   # d2/dqd2 of qd^2: 2
    array([2., 0.])
    """
    n = library.coords.n
    rows = np.asarray(states, dtype=float)[np.unique(np.linspace(
        0, len(states) - 1, min(len(states), max_states)).astype(int))].copy()
    rows[:, 2 * n:4 * n] = 0.0  # no acceleration, no force
    base = library.transform(rows).reshape(n, len(rows), -1)
    mass = np.empty((len(rows), base.shape[-1], n, n))
    for k in range(n):
        unit = rows.copy()
        unit[:, 2 * n + k] = 1.0
        mass[:, :, :, k] = np.moveaxis(
            library.transform(unit).reshape(n, len(rows), -1) - base, 0, -1)
    return mass


def orient_free_laws(coef, symbolic_matrix, force_columns, mass):
    """Flip the laws that no force scales and whose mass matrix is negative definite.

    Coordinates coupled by identified terms form one law; a law without a non-zero force
    coefficient (implicit, or the implicit part of a mixed fit) is defined up to its sign.

    Parameters
    ----------
    coef : ndarray, shape (F,)
    symbolic_matrix : sympy.Matrix or array of bool, shape (n, F)
        The catalog's columns, or which of their entries are non-zero.
    force_columns : sequence of int
    mass : ndarray, shape (S, n, n)
        Mass matrices at the training states.

    Returns
    -------
    coef : ndarray, shape (F,)
        A new vector (the input is not modified).
    flipped : bool

    Examples
    --------
    >>> import numpy as np, sympy as sp
    >>> coef, flipped = orient_free_laws(np.array([0.0, -0.5]), sp.Matrix([[0, 1]]), [0],
    ...                                  -np.ones((3, 1, 1)))
    >>> coef, flipped
    (array([0. , 0.5]), True)
    """
    coef = np.array(coef, dtype=float)
    nonzero = np.asarray(symbolic_matrix, dtype=object) != 0
    n = nonzero.shape[0]
    active = np.flatnonzero(coef)
    touches = nonzero[:, active].astype(bool).reshape(n, len(active))
    group = np.arange(n)  # union of the coordinates that share an active column
    for column in touches.T:
        members = np.flatnonzero(column)
        if len(members) > 1:
            group[np.isin(group, group[members])] = group[members].min()
    forces = {int(j) for j in force_columns if coef[j] != 0}
    flipped = False
    for label in np.unique(group):
        coordinates = np.flatnonzero(group == label)
        columns = active[touches[coordinates].any(axis=0)]
        if forces & set(columns.tolist()):
            continue  # scaled by a known force: the sign is physical
        if np.all(np.linalg.eigvalsh(mass[:, coordinates][:, :, coordinates]) < 0):
            coef[columns] = -coef[columns] + 0.0
            flipped = True
    return coef, flipped


def mass_matrix_report(mass, eigenvalues, names, remedy: str = "") -> dict:
    """Fraction of states with a positive definite mass matrix, its median condition number;
    warns (:class:`IdentificationWarning`) naming coordinates without positive inertia.

    Definiteness is judged unit free, on ``D M D`` with ``D = diag(max |M_ii|)^(-1/2)``
    (coordinates in micrometres next to radians are fine); the condition number is that of
    ``M`` itself.

    Parameters
    ----------
    mass : ndarray, shape (S, n, n)
    eigenvalues : ndarray, shape (S, n)
    names : list of str
        Coordinate names.
    remedy : str, optional
        What the warning suggests (appended to it).

    Returns
    -------
    dict
        ``positive_definite_fraction`` and ``median_condition``.

    Examples
    --------
    >>> import numpy as np
    >>> mass = np.array([[[2.0, 0.0], [0.0, 1.0]]] * 3)
    >>> mass_matrix_report(mass, np.linalg.eigvalsh(mass), ["a", "b"])
    {'positive_definite_fraction': 1.0, 'median_condition': 2.0}
    >>> micro = mass * [[1e-12, 0.0], [0.0, 1.0]]  # "a" in micrometres
    >>> mass_matrix_report(micro, np.linalg.eigvalsh(micro), ["a", "b"])
    {'positive_definite_fraction': 1.0, 'median_condition': 500000000000.0}
    """
    # Definiteness is judged on D M D, D = diag(max_states |M_ii|)^(-1/2): a congruence (same
    # signs of eigenvalues) that removes the units of the coordinates, so a cart in micrometres
    # next to a pendulum in radians (M_xx 1e-12 times M_thth) is not called singular.
    diagonal = np.diagonal(mass, axis1=1, axis2=2)
    unit = np.max(np.abs(diagonal), axis=0, initial=0.0)
    unit = 1.0 / np.sqrt(np.where((unit > 0) & np.isfinite(unit), unit, 1.0))
    scaled = np.linalg.eigvalsh(mass * unit[None, :, None] * unit[None, None, :])
    scale = max(float(np.abs(scaled).max()), 1e-300)
    definite = scaled.min(axis=1) > 1e-9 * scale
    with np.errstate(divide="ignore"):
        condition = np.where(definite,
                             eigenvalues.max(axis=1) / np.abs(eigenvalues.min(axis=1)), np.inf)
    if not definite.all():
        diagonal = diagonal * unit**2
        missing = [name for i, name in enumerate(names) if np.any(diagonal[:, i] <= 1e-9 * scale)]
        warnings.warn(
            f"the identified mass matrix is not positive definite on {np.mean(~definite):.0%} "
            "of the training states"
            + (f"; no positive inertia on {missing}" if missing else "")
            + ": the model is wrong there (noise terms, an unidentifiable coordinate, or a "
            "catalog that cannot express the dynamics) and will not simulate faithfully"
            + remedy,
            IdentificationWarning, stacklevel=2,
        )
    return {"positive_definite_fraction": float(np.mean(definite)),
            "median_condition": float(np.median(condition))}
