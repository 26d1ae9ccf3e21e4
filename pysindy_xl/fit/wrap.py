"""The wrap step of the fit stage: a solved catalog problem back in the catalog's terms.

:func:`fitted_state` maps the optimizer's coefficients (and an ensemble's inclusion
probabilities and intervals) back to the catalog's columns through the problem's
:class:`~pysindy_xl.fit.CatalogMap`, builds the identified dynamics in mass-matrix form
(:func:`catalog_dynamics`), orients the laws no force scales and measures the mass matrix on
the training states (:func:`checked_dynamics`): the fitted attributes of
:class:`~pysindy_xl.XLSINDy`.
"""

from __future__ import annotations

import numpy as np

from ..dynamics import CatalogDynamics
from ..report.equations import has_parameter_map
from .diagnostics import mass_matrices, mass_matrix_report, orient_free_laws

__all__ = ["fitted_state", "catalog_dynamics", "checked_dynamics"]


def catalog_dynamics(library, coef, held):
    """The identified equations in mass-matrix form, combined numerically from the catalog's
    columns (:class:`~pysindy_xl.dynamics.CatalogDynamics`); None when no identified term
    contains an acceleration.

    Parameters
    ----------
    library : fitted CatalogRepartition
    coef : ndarray, shape (F,)
    held : ndarray of bool, shape (n,)
        Coordinates the model holds (zero acceleration).

    Returns
    -------
    CatalogDynamics or None
    """
    if not library.involves(library.coords.qdd)[:, np.flatnonzero(coef)].any():
        return None
    return CatalogDynamics(library, coef, held)


def checked_dynamics(library, coef, held, states):
    """Orient the laws no force scales, then measure ``M(q)`` on the training ``states``.

    Returns
    -------
    coef : ndarray, shape (F,)
        With the laws whose mass matrix was negative definite flipped
        (:func:`~pysindy_xl.fit.diagnostics.orient_free_laws`).
    dynamics : CatalogDynamics or None
    check : dict or None
        :func:`~pysindy_xl.fit.diagnostics.mass_matrix_report` (warns when the mass matrix
        is not positive definite); None without dynamics.
    """
    dynamics = catalog_dynamics(library, coef, held)
    if dynamics is None:
        return coef, None, None
    mass, eig = mass_matrices(dynamics, states)
    nonzero = library.entry_sizes() > 0
    nonzero[held] = False  # held equations are not the catalog's
    coef, flipped = orient_free_laws(coef, nonzero, library.force_columns_, mass)
    if flipped:
        dynamics = catalog_dynamics(library, coef, held)
        mass, eig = mass_matrices(dynamics, states)
    remedy = ("; fit with optimizer=px.PhysicalOptimizer(...) for parameters of rigid "
              "bodies, whose mass matrix is positive definite"
              if has_parameter_map(library) else "")
    return coef, dynamics, mass_matrix_report(mass, eig, library.coords.names, remedy)


def fitted_state(library, problem, optimizer) -> dict:
    """The fitted attributes of :class:`~pysindy_xl.XLSINDy` from a solved problem.

    Parameters
    ----------
    library : fitted CatalogRepartition
    problem : CatalogProblem
        Built by :func:`~pysindy_xl.fit.build_problem` (with its ``catalog_map``).
    optimizer : fitted catalog optimizer

    Returns
    -------
    dict
        Attribute name -> value (``coef_``, ``dynamics_``, ``mass_matrix_check_``, ...).
    """
    origin = problem.catalog_map
    names = library.get_feature_names()
    state = {"feature_library_": library, "optimizer_": optimizer,
             "inclusion_probability_": None, "coef_interval_": None}
    if hasattr(optimizer, "inclusion_probability_"):  # an ensemble: map to the catalog
        state["inclusion_probability_"] = origin.to_catalog(optimizer.inclusion_probability_)
        state["coef_interval_"] = origin.to_catalog(optimizer.coef_interval_)
    report = getattr(optimizer, "consistency_", None)  # a physically constrained fit
    held = ~origin.coordinates
    coef, dynamics, check = checked_dynamics(library, origin.to_catalog(optimizer.coef_), held,
                                             origin.states)
    return {**state, "coef_": coef, "dynamics_": dynamics, "mass_matrix_check_": check,
            "dropped_features_": {names[j]: why for j, why in origin.dropped.items()},
            "physical_consistency_": None if report is None else {
                **report, "negative_friction": [names[origin.columns[j]]
                                                for j in report["negative_friction"]]},
            "n_coordinates_": library.coords.n, "n_samples_": origin.states.shape[0],
            "forced_coordinates_": origin.forced,
            "still_coordinates_": [name for name, h in zip(library.coords.names, held,
                                                           strict=True) if h],
            "formulation_": origin.formulation, "weak_info_": origin.weak_info,
            "selection_": getattr(optimizer, "selection_", None)}
