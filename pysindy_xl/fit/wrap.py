"""The wrap step of the fit stage: a solved catalog problem back in the catalog's terms."""

from __future__ import annotations

import numpy as np

from ..dynamics import CatalogDynamics
from ..physical.structure import has_parameter_map
from .diagnostics import mass_matrices, mass_matrix_report, orient_free_laws

__all__ = ["catalog_dynamics", "checked_dynamics"]


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

