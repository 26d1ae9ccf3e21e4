"""pysindy-xl: sparse identification of mechanical systems from data.

Catalogs of Lagrangian, classical (Newtonian) and external-force terms become one stacked
regression problem (:class:`CatalogRepartition`), solved by explicit, implicit or mixed sparse
regression (:class:`ExplicitOptimizer`, :class:`ImplicitOptimizer`, :class:`MixedOptimizer`)
inside the :class:`XLSINDy` estimator.
"""

from .dynamics import MassMatrixDynamics, SimulationError, SingularMassMatrixError
from .feature_library import (
    CatalogRepartition,
    ClassicalLibrary,
    ExternalForces,
    LagrangeLibrary,
    stack_variables,
)
from .model import XLSINDy
from .optimizers import ExplicitOptimizer, ImplicitOptimizer, MixedOptimizer, NoLawFoundError
from .symbols import Coordinates, monomials, products
from .weak import BumpTestFunctions, WhittakerSmoother

__all__ = [
    "Coordinates",
    "monomials",
    "products",
    "LagrangeLibrary",
    "ClassicalLibrary",
    "ExternalForces",
    "CatalogRepartition",
    "stack_variables",
    "ExplicitOptimizer",
    "ImplicitOptimizer",
    "MixedOptimizer",
    "NoLawFoundError",
    "XLSINDy",
    "MassMatrixDynamics",
    "SimulationError",
    "SingularMassMatrixError",
    "BumpTestFunctions",
    "WhittakerSmoother",
]
__version__ = "0.1.0"
