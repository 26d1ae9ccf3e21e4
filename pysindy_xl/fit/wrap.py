"""The wrap step of the fit stage: a solved catalog problem back in the catalog's terms."""

from __future__ import annotations

import numpy as np

from ..dynamics import CatalogDynamics
from ..report.equations import has_parameter_map
from .diagnostics import mass_matrices, mass_matrix_report, orient_free_laws

__all__ = ["fitted_state", "catalog_dynamics", "checked_dynamics"]


def catalog_dynamics(library, coef, held):
    """The identified equations in mass-matrix form, or None.

    Parameters
    ----------
    library : fitted CatalogRepartition
        The catalog.
    coef : array, shape (F,)
        Its coefficients.
    held : bool array, shape (n,)
        Coordinates held still (their equation becomes ``qdd_c = 0``).

    Returns
    -------
    CatalogDynamics or None
        :class:`~pysindy_xl.dynamics.CatalogDynamics`; None when no identified term contains
        an acceleration.
    """
    if not library.involves(library.coords.qdd)[:, np.flatnonzero(coef)].any():
        return None
    return CatalogDynamics(library, coef, held)


def checked_dynamics(library, coef, held, states):
    """Orient the laws no force scales, then measure ``M(q)`` on the training states.

    Parameters
    ----------
    library : fitted CatalogRepartition
        The catalog.
    coef : array, shape (F,)
        Its coefficients.
    held : bool array, shape (n,)
        Coordinates held still.
    states : ndarray, shape (S, 4n + 1)
        The training states.

    Returns
    -------
    coef : ndarray, shape (F,)
        With the laws of negative definite mass matrix flipped
        (:func:`~pysindy_xl.fit.diagnostics.orient_free_laws`).
    dynamics : CatalogDynamics or None
        The identified dynamics.
    check : dict or None
        :func:`~pysindy_xl.fit.diagnostics.mass_matrix_report` (None without dynamics).
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
        The catalog.
    problem : CatalogProblem
        The problem (built by :func:`~pysindy_xl.fit.build_problem`).
    optimizer : catalog optimizer
        Fitted on ``problem``.

    Returns
    -------
    dict of str to object
        Attribute name (``coef_``, ``dynamics_``, ``feature_library_``...) to value, as
        documented by :class:`~pysindy_xl.XLSINDy`.
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
