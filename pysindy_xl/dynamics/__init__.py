"""Identified dynamics: the mass-matrix form of the equations, simulation, and what a fitted
model does with them.

* :mod:`~pysindy_xl.dynamics.mass_matrix`: ``M(q, qd) qdd = f(q, qd, tau, t)`` from equations
  (:class:`MassMatrixDynamics`), accelerations and simulation;
* :mod:`~pysindy_xl.dynamics.catalog`: the same from a catalog and its coefficients
  (:class:`CatalogDynamics`);
* :mod:`~pysindy_xl.dynamics.inputs`: forces as functions of time and of the state;
* :mod:`~pysindy_xl.dynamics.fitted`: prediction, scores, simulation and exports of a fitted
  :class:`~pysindy_xl.XLSINDy`.
"""

from .catalog import CatalogDynamics
from .inputs import feedback_function, force_function
from .mass_matrix import (
    DynamicsError,
    MassMatrixDynamics,
    SimulationError,
    SingularMassMatrixError,
)

__all__ = [
    "MassMatrixDynamics",
    "CatalogDynamics",
    "DynamicsError",
    "SingularMassMatrixError",
    "SimulationError",
    "force_function",
    "feedback_function",
]
