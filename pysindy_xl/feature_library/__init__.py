"""Catalog categories as pysindy feature libraries.

See :mod:`pysindy_xl.feature_library._base` for the layout of the stacked regression matrix.
"""

from ..symbols import stack_variables
from ._base import LIBRARY_TYPES, SymbolicLibrary, compile_entries, remembered_weak_values

# the compiled evaluation of symbolic terms is re-exported for the simulators of the package
# (``dynamics``), so that no module outside this folder imports the private ``_compile``
from ._compile import Terms as Terms
from ._compile import compile_terms as compile_terms
from ._compile import decompose as decompose
from ._compile import scalar_function as scalar_function
from ._weak import integrate_by_parts
from .classical import ClassicalLibrary, pysindy_library_terms
from .external_forces import ExternalForces
from .joint_friction import JointFrictionLibrary
from .lagrange import LagrangeLibrary, euler_lagrange
from .polynomial_lagrange import PolynomialLagrangeLibrary
from .repartition import CatalogRepartition
from .spec import SpecError, SpecReader

__all__ = ["SymbolicLibrary", "LagrangeLibrary", "PolynomialLagrangeLibrary", "ClassicalLibrary",
           "ExternalForces", "JointFrictionLibrary", "CatalogRepartition", "stack_variables",
           "remembered_weak_values", "compile_entries", "euler_lagrange", "pysindy_library_terms",
           "integrate_by_parts", "LIBRARY_TYPES", "SpecReader", "SpecError"]
