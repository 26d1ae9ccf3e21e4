"""The wrap step of the fit stage: a solved catalog problem back in the catalog's terms."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..dynamics import CatalogDynamics
from ..physical.structure import has_parameter_map
from .diagnostics import mass_matrices, mass_matrix_report, orient_free_laws

__all__ = ["WrappedFit", "wrap", "catalog_dynamics", "checked_dynamics"]


def catalog_dynamics(library, coef, held):
    """The identified equations in mass-matrix form (:class:`~pysindy_xl.dynamics.CatalogDynamics`
    of ``library``, ``coef`` (F,) and the ``held`` coordinates); None when no identified term
    contains an acceleration.
    """
    if not library.involves(library.coords.qdd)[:, np.flatnonzero(coef)].any():
        return None
    return CatalogDynamics(library, coef, held)


def checked_dynamics(library, coef, held, states):
    """Orient the laws no force scales, then measure ``M(q)`` on the training ``states``.

    Returns ``(coef, dynamics, check)``: ``coef`` with the laws of negative definite mass matrix
    flipped (:func:`~pysindy_xl.fit.diagnostics.orient_free_laws`), the dynamics (or None) and
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
    """A solved problem in the catalog's terms (:func:`wrap`). Each field is the fitted attribute
    of :class:`~pysindy_xl.XLSINDy` of the same name with a trailing underscore, which sets and
    documents it."""

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
    """The solved ``problem`` (built by :func:`~pysindy_xl.fit.build_problem`, solved by the
    fitted ``optimizer``) in the columns of the fitted ``library`` (``problem.catalog_map``)."""
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
