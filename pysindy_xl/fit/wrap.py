"""The wrap step of the fit stage: a solved catalog problem back in the catalog's terms."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..dynamics import CatalogDynamics
from ..physical.structure import has_parameter_map
from .diagnostics import mass_matrices, mass_matrix_report, orient_free_laws

__all__ = ["WrappedFit", "wrap", "catalog_dynamics", "checked_dynamics"]


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


@dataclasses.dataclass(frozen=True)
class WrappedFit:
    """A solved problem in the catalog's terms (:func:`wrap`).

    Each field is the fitted attribute of :class:`~pysindy_xl.XLSINDy` of the same name with a
    trailing underscore, which sets and documents it (``coef`` is ``coef_``, ...).

    Parameters
    ----------
    coef : ndarray, shape (F,)
        The coefficients on every catalog column.
    dynamics : CatalogDynamics or None
        The identified equations in mass-matrix form.
    mass_matrix_check : dict or None
        :func:`~pysindy_xl.fit.diagnostics.mass_matrix_report` on the training states.
    dropped_features : dict of str to str
        Features left out before the regression, with the reason.
    still_coordinates : list of str
        Coordinates held still.
    forced_coordinates : ndarray of bool, shape (n,)
        Coordinates a recorded force acts on.
    n_coordinates : int
        Number of coordinates.
    n_samples : int
        Samples (states) of the fit.
    formulation : {"strong", "weak"}
        The formulation used.
    weak_info : dict or None
        The weak regression's information.
    selection : object
        How the sparsity was chosen (the optimizer's ``selection_``), or None.
    inclusion_probability, coef_interval : ndarray or None
        An ensemble's, on the catalog's columns.
    physical_consistency : dict or None
        A physically constrained fit's report.
    """

    coef: np.ndarray
    dynamics: CatalogDynamics | None
    mass_matrix_check: dict | None
    dropped_features: dict
    still_coordinates: list
    forced_coordinates: np.ndarray
    n_coordinates: int
    n_samples: int
    formulation: str
    weak_info: dict | None
    selection: object
    inclusion_probability: np.ndarray | None
    coef_interval: np.ndarray | None
    physical_consistency: dict | None


def wrap(library, problem, optimizer) -> WrappedFit:
    """A solved problem in the columns of the fitted catalog.

    Parameters
    ----------
    library : fitted CatalogRepartition
        The catalog.
    problem : CatalogProblem
        Built by :func:`~pysindy_xl.fit.build_problem` (its ``catalog_map`` maps the problem's
        columns back to the catalog's).
    optimizer : catalog optimizer
        Fitted on ``problem``.

    Returns
    -------
    WrappedFit
        The coefficients on every catalog column (laws no force scales oriented to a positive
        definite mass matrix), the dynamics and the rest of the estimator's fitted state.
    """
    origin, names = problem.catalog_map, library.get_feature_names()
    held = ~origin.coordinates
    coef, dynamics, check = checked_dynamics(library, origin.to_catalog(optimizer.coef_), held,
                                             origin.states)
    bagged = hasattr(optimizer, "inclusion_probability_")  # an ensemble: to the catalog
    report = getattr(optimizer, "consistency_", None)  # a physically constrained fit
    return WrappedFit(
        coef=coef, dynamics=dynamics, mass_matrix_check=check,
        dropped_features={names[j]: why for j, why in origin.dropped.items()},
        still_coordinates=[name for name, h in zip(library.coords.names, held, strict=True)
                           if h],
        forced_coordinates=origin.forced, n_coordinates=library.coords.n,
        n_samples=origin.states.shape[0], formulation=origin.formulation,
        weak_info=origin.weak_info, selection=getattr(optimizer, "selection_", None),
        inclusion_probability=(origin.to_catalog(optimizer.inclusion_probability_)
                               if bagged else None),
        coef_interval=origin.to_catalog(optimizer.coef_interval_) if bagged else None,
        physical_consistency=None if report is None else {
            **report, "negative_friction": [names[origin.columns[j]]
                                            for j in report["negative_friction"]]})
