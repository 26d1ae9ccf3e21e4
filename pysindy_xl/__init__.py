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
    "kinematic_catalog",
]
__version__ = "0.1.0"


def __getattr__(name):
    # the kinematic catalog reads MJCF through mujoco: import it on first use only, so that
    # ``import pysindy_xl`` stays light
    if name == "kinematic_catalog":
        from .mujoco.kinematic import kinematic_catalog

        return kinematic_catalog
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
