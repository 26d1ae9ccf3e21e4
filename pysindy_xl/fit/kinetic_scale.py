r"""The scale of an unforced (implicit) law's equations: their kinetic part.

An implicit law ``Theta xi = 0`` fixes each equation only up to its own factor, so a relative
residual needs a scale taken from the law itself. The part of an equation that states the
accelerations is its kinetic part, ``d/dt dT/dqd - dT/dq``: the columns that carry inertia
(:func:`inertial_columns`). :func:`kinetic_relative_residuals` divides each equation's
residual by it; the catalog growth's held-out criterion
(:func:`~pysindy_xl.catalog.criterion.held_out_error`) and the fit-quality ``R^2`` of
unforced fits (:func:`~pysindy_xl.evaluation.quality.fit_quality`) are both made of it.
"""

from __future__ import annotations

import numpy as np

from .diagnostics import column_mass_matrices

__all__ = ["INERTIA_STATES", "inertial_columns", "kinetic_relative_residuals"]

#: States at which :func:`inertial_columns` evaluates the columns' mass matrices.
INERTIA_STATES = 20


def inertial_columns(model, problem) -> np.ndarray:
    """The columns of a fitted model's regression problem that carry inertia.

    A column carries inertia where its mass matrix (the derivative of its Euler-Lagrange
    expression in the accelerations, :func:`~pysindy_xl.fit.diagnostics.column_mass_matrices`)
    is nonzero at one of :data:`INERTIA_STATES` of the problem's states: the terms of the
    Lagrangian quadratic in the velocities; not the potential, the gyroscopic (velocity-linear)
    terms, dissipation or forces.

    Parameters
    ----------
    model : XLSINDy
        Fitted model (its ``feature_library_`` built ``problem``).
    problem : CatalogProblem
        A regression problem of ``model`` with its catalog map
        (:meth:`XLSINDy.regression <pysindy_xl.XLSINDy.regression>`).

    Returns
    -------
    ndarray of int
        Indices of the problem's columns.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
    >>> t = np.linspace(0, 10, 1001)
    >>> x = np.cos(2 * t)[:, None]
    >>> model = px.XLSINDy(lib).fit(x, t, x_dot=-2 * np.sin(2 * t)[:, None], x_ddot=-4 * x)
    >>> problem = model.regression(x, t, x_ddot=-4 * x)
    >>> [model.get_feature_names()[problem.catalog_map.columns[j]]
    ...  for j in inertial_columns(model, problem)]
    ['L[x_dot**2]']
    """
    origin = problem.catalog_map
    mass = column_mass_matrices(model.feature_library_, origin.states, INERTIA_STATES)
    size = np.abs(mass[:, origin.columns]).max(axis=(0, 2, 3))
    return np.flatnonzero(size > 1e-12 * max(float(size.max(initial=0.0)), 1e-300))


def kinetic_relative_residuals(model, problem) -> np.ndarray:
    r"""Each equation's residual relative to its kinetic part.

    With ``Theta`` the problem's rows, ``xi`` the model's coefficients on its columns, and
    ``Theta_i`` the block of rows of coordinate ``i`` (the problem's blocks, one per moving
    coordinate):

    .. math:: e_i = \frac{\|\Theta_i \xi\|}{\|\sum_{j \in K} \Theta_{ij} \xi_j\|},

    ``K`` the columns that carry inertia (:func:`inertial_columns`). ``e_i`` is about the
    relative error of the accelerations that the law predicts in equation ``i``: the
    kinetic part is the one that states them, and it is a property of the law, unlike a
    single term's size (a law may keep a large term that its other terms nearly cancel,
    whose size then says nothing of the law's scale). ``e_i`` is ``inf`` where the kinetic
    part is zero (a law with no inertia in that equation, or one whose inertia cancels).

    Parameters
    ----------
    model : XLSINDy
        Fitted model (its ``coef_`` on the catalog's columns).
    problem : CatalogProblem
        A regression problem of ``model`` (:meth:`XLSINDy.regression
        <pysindy_xl.XLSINDy.regression>`), rows in blocks of equal length, one per coordinate.

    Returns
    -------
    ndarray, shape (problem.n_coordinates,)
        ``e_i`` for each block, in order.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
    >>> t = np.linspace(0, 10, 1001)
    >>> x = np.cos(2 * t)[:, None]   # x_ddot = -4 x: the law qd^2 - 4 q^2, exactly
    >>> model = px.XLSINDy(lib).fit(x, t, x_dot=-2 * np.sin(2 * t)[:, None], x_ddot=-4 * x)
    >>> e = kinetic_relative_residuals(model, model.regression(x, t, x_ddot=-4 * x))
    >>> bool(e[0] < 1e-9)
    True
    >>> e = kinetic_relative_residuals(model, model.regression(x, t, x_ddot=-3 * x))
    >>> round(float(e[0]), 6)  # data with x_ddot = -3 x: |2 (-3 x) + 8 x| / |2 (-3 x)|
    0.333333
    """
    theta, columns = problem.theta, problem.catalog_map.columns
    coef = model.coef_[columns]
    residual = theta @ coef
    kinetic = inertial_columns(model, problem)
    errors = []
    for rows in np.array_split(np.arange(len(theta)), problem.n_coordinates):
        norm = float(np.linalg.norm(theta[np.ix_(rows, kinetic)] @ coef[kinetic]))
        errors.append(np.linalg.norm(residual[rows]) / norm if norm > 0 else np.inf)
    return np.array(errors, dtype=float)
