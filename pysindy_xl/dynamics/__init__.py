"""Identified dynamics: the mass-matrix form ``M(q, qd) qdd = f(q, qd, tau, t)`` of equations
(:mod:`.mass_matrix`) or of a catalog (:mod:`.catalog`), and the forces that drive a simulation
(:mod:`.inputs`); what a fitted model does with them is :mod:`pysindy_xl.fitted.dynamics`."""

from .catalog import CatalogDynamics
from .inputs import feedback_function, force_function
from .mass_matrix import DynamicsError, MassMatrixDynamics, SimulationError, SingularMassMatrixError

__all__ = ["MassMatrixDynamics", "CatalogDynamics", "DynamicsError", "SingularMassMatrixError",
           "SimulationError", "force_function", "feedback_function"]
