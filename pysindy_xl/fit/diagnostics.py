"""Fit-time diagnostics of an identified model on its own training states: the sign of laws
no force scales (:func:`orient_free_laws`), the definiteness of the mass matrix
(:func:`mass_matrix_report`) and what it found wrong (:func:`mass_matrix_failure`).
"""

from __future__ import annotations

import warnings

import numpy as np

from .._validation import IdentificationWarning

__all__ = ["column_mass_matrices", "mass_matrices", "orient_free_laws", "mass_matrix_report",
           "mass_matrix_failure"]


def mass_matrices(dynamics, states, max_states: int = 2000):
    """Symmetrized mass matrices of identified dynamics and their eigenvalues.

    Parameters
    ----------
    dynamics : MassMatrixDynamics
        The identified dynamics.
    states : ndarray, shape (N, 4n + 1)
        Library inputs (:func:`~pysindy_xl.feature_library.stack_variables`).
    max_states : int, default 2000
        At most this many states, evenly spaced, are used.

    Returns
    -------
    mass : ndarray, shape (S, n, n)
        ``(M + M^T) / 2`` at each state used.
    eigenvalues : ndarray, shape (S, n)
        Their eigenvalues, ascending.

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
    """Each catalog column's mass matrix on up to ``max_states`` states.

    A column is affine in the accelerations, ``E_j = M_j(q, qd) qdd + rest``, so ``M_j[:, k]``
    is the column at ``qdd = e_k`` minus the column at ``qdd = 0``: ``n + 1`` evaluations, no
    symbolic work. Coefficients ``xi`` have the mass matrix ``sum_j xi_j M_j``.

    Parameters
    ----------
    library : fitted SymbolicLibrary
        The catalog.
    states : ndarray, shape (N, 4n + 1)
        Library inputs.
    max_states : int, default 200
        At most this many states, evenly spaced, are used.

    Returns
    -------
    ndarray, shape (S, F, n, n)
        ``M_j`` of every column ``j`` at each state used.

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

    Coordinates coupled by identified terms form one law; without a non-zero force coefficient
    its sign is arbitrary, and the sign of a positive definite mass matrix is chosen.

    Parameters
    ----------
    coef : ndarray, shape (F,)
        The coefficients.
    symbolic_matrix : sympy.Matrix, shape (n, F)
        The catalog's columns (their non-zero entries couple coordinates).
    force_columns : sequence of int
        The force columns.
    mass : ndarray, shape (S, n, n)
        The identified mass matrices on the training states.

    Returns
    -------
    coef : ndarray, shape (F,)
        A new coefficient vector.
    flipped : bool
        Whether some law was flipped.

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
    """How positive definite the identified mass matrix is on the training states.

    Warns (:class:`~pysindy_xl.IdentificationWarning`, ending with ``remedy``) naming the
    coordinates without positive inertia. Definiteness is judged unit free, on ``D M D`` with
    ``D = diag(max |M_ii|)^(-1/2)``; the condition number is that of ``M``.

    Parameters
    ----------
    mass : ndarray, shape (S, n, n)
        Symmetrized mass matrices (:func:`mass_matrices`).
    eigenvalues : ndarray, shape (S, n)
        Their eigenvalues.
    names : sequence of str
        Coordinate names.
    remedy : str, default ""
        Appended to the warning.

    Returns
    -------
    dict
        ``positive_definite_fraction`` (fraction of states) and ``median_condition``.

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
    # D M D: a congruence (same signs of eigenvalues) free of the coordinates' units
    diagonal = np.diagonal(mass, axis1=1, axis2=2)
    unit = np.max(np.abs(diagonal), axis=0, initial=0.0)
    unit = 1.0 / np.sqrt(np.where((unit > 0) & np.isfinite(unit), unit, 1.0))
    scaled = np.linalg.eigvalsh(mass * unit[None, :, None] * unit[None, None, :])
    scale = max(float(np.abs(scaled).max()), 1e-300)
    definite = scaled.min(axis=1) > 1e-9 * scale
    with np.errstate(divide="ignore"):
        condition = np.where(definite,
                             eigenvalues.max(axis=1) / np.abs(eigenvalues.min(axis=1)), np.inf)
    report = {"positive_definite_fraction": float(np.mean(definite)),
              "median_condition": float(np.median(condition))}
    failure = mass_matrix_failure(report)
    if failure is not None:
        diagonal = diagonal * unit**2
        missing = [name for i, name in enumerate(names) if np.any(diagonal[:, i] <= 1e-9 * scale)]
        warnings.warn(
            failure + (f"; no positive inertia on {missing}" if missing else "")
            + ": the model is wrong there (noise terms, an unidentifiable coordinate, or a "
            "catalog that cannot express the dynamics) and will not simulate faithfully"
            + remedy,
            IdentificationWarning, stacklevel=2)
    return report


def mass_matrix_failure(check) -> str | None:
    """What the mass-matrix check of a fit found wrong, or None when it found nothing.

    The one rule by which the fit warns (:func:`mass_matrix_report`) and by which
    ``pysindy-xl identify`` fails a model (:func:`~pysindy_xl.cli.automatic.honest_exit`): the
    identified mass matrix ``M(q)`` must be positive definite on every checked training state.
    Where it is not, the kinetic energy ``qd^T M qd / 2`` is not positive: no mechanical
    system has that law. And a run is continuous: where ``M`` is positive definite on some of
    its states and not on others, it is singular between them, the equations give no
    acceleration there, and the model cannot be simulated along its own data.

    Parameters
    ----------
    check : dict or None
        :func:`mass_matrix_report`'s figures (``XLSINDy.mass_matrix_check_``); None (a model
        without accelerations, or not checked) finds nothing.

    Returns
    -------
    str or None
        ``"the identified mass matrix is not positive definite on P% of the training
        states"`` when ``positive_definite_fraction`` is below 1 (``P`` its complement), else
        None (also when the fraction is not a number).

    Examples
    --------
    >>> mass_matrix_failure({"positive_definite_fraction": 1.0, "median_condition": 2.0}) is None
    True
    >>> mass_matrix_failure({"positive_definite_fraction": 0.4885, "median_condition": np.inf})
    'the identified mass matrix is not positive definite on 51% of the training states'
    >>> mass_matrix_failure({"positive_definite_fraction": 0.9995, "median_condition": 3.0})
    'the identified mass matrix is not positive definite on 0.05% of the training states'
    """
    if check is None:
        return None
    fraction = float(check["positive_definite_fraction"])
    if not fraction < 1.0:
        return None
    share = 100.0 * (1.0 - fraction)
    share = f"{share:.0f}" if share >= 1 else f"{share:.2g}"
    return f"the identified mass matrix is not positive definite on {share}% of the training states"
