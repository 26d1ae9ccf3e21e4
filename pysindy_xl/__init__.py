"""pysindy-xl: sparse identification of mechanical systems from data.

Catalogs of Lagrangian, classical (Newtonian) and external-force terms become one stacked
regression problem (:class:`CatalogRepartition`), solved by explicit, implicit or mixed sparse
regression (:class:`ExplicitOptimizer`, :class:`ImplicitOptimizer`, :class:`MixedOptimizer`)
inside the :class:`XLSINDy` estimator.

The public names are loaded on first use (PEP 562): ``import pysindy_xl`` imports neither
SymPy nor PySINDy until a name that needs them is touched.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ._optional import lazy_attributes

__version__ = "0.1.0"

# public name -> submodule that defines it (imported on first attribute access)
_LAZY = {
    **dict.fromkeys(("Coordinates", "monomials", "products", "stack_variables"), "symbols"),
    **dict.fromkeys(("LagrangeLibrary", "ClassicalLibrary", "ExternalForces",
                     "CatalogRepartition", "JointFrictionLibrary"), "feature_library"),
    "FRICTION_MODELS": "feature_library.joint_friction",
    **dict.fromkeys(("ExplicitOptimizer", "ImplicitOptimizer", "MixedOptimizer",
                     "EnsembleOptimizer", "PhysicalOptimizer", "NoLawFoundError",
                     "TotalLeastSquaresOptimizer"), "optimizers"),
    "XLSINDy": "model",
    **dict.fromkeys(("IdentificationWarning", "UnexplainedCoordinateWarning"), "_validation"),
    **dict.fromkeys(("MassMatrixDynamics", "SimulationError", "SingularMassMatrixError"),
                    "dynamics"),
    **dict.fromkeys(("BumpTestFunctions", "WhittakerSmoother"), "weak"),
    "kinematic_catalog": "mujoco.catalogs.kinematic",  # reads MJCF through mujoco: on first use
    **dict.fromkeys(("AutomaticCatalog", "grow_catalog"), "catalog"),
}

__all__ = ["Coordinates", "monomials", "products", "LagrangeLibrary", "ClassicalLibrary",
           "ExternalForces", "CatalogRepartition", "JointFrictionLibrary", "FRICTION_MODELS",
           "stack_variables", "ExplicitOptimizer",
           "ImplicitOptimizer", "MixedOptimizer", "EnsembleOptimizer", "PhysicalOptimizer",
           "NoLawFoundError", "TotalLeastSquaresOptimizer", "XLSINDy", "IdentificationWarning",
           "UnexplainedCoordinateWarning", "MassMatrixDynamics", "SimulationError",
           "SingularMassMatrixError", "BumpTestFunctions", "WhittakerSmoother", "kinematic_catalog",
           "AutomaticCatalog", "grow_catalog"]

if TYPE_CHECKING:  # static analysers and IDEs see the eager imports
    from ._validation import IdentificationWarning, UnexplainedCoordinateWarning
    from .catalog import AutomaticCatalog, grow_catalog
    from .dynamics import MassMatrixDynamics, SimulationError, SingularMassMatrixError
    from .feature_library import (
        CatalogRepartition,
        ClassicalLibrary,
        ExternalForces,
        JointFrictionLibrary,
        LagrangeLibrary,
    )
    from .feature_library.joint_friction import FRICTION_MODELS
    from .model import XLSINDy
    from .mujoco.catalogs.kinematic import kinematic_catalog
    from .optimizers import (
        EnsembleOptimizer,
        ExplicitOptimizer,
        ImplicitOptimizer,
        MixedOptimizer,
        NoLawFoundError,
        PhysicalOptimizer,
        TotalLeastSquaresOptimizer,
    )
    from .symbols import Coordinates, monomials, products, stack_variables
    from .weak import BumpTestFunctions, WhittakerSmoother

__getattr__, __dir__ = lazy_attributes(__name__, _LAZY)
