"""Catalog categories as pysindy feature libraries.

See :mod:`pysindy_xl.feature_library._base` for the layout of the stacked regression matrix.
"""

from ._base import LIBRARY_TYPES, SymbolicLibrary, compile_entries, stack_variables
from ._weak import integrate_by_parts
from .classical import ClassicalLibrary, pysindy_library_terms
from .external_forces import ExternalForces
from .joint_friction import JointFrictionLibrary
from .lagrange import LagrangeLibrary, euler_lagrange
from .polynomial_lagrange import PolynomialLagrangeLibrary
from .repartition import CatalogRepartition
from .spec import SpecError, SpecReader

__all__ = [
    "SymbolicLibrary",
    "LagrangeLibrary",
    "PolynomialLagrangeLibrary",
    "ClassicalLibrary",
    "ExternalForces",
    "JointFrictionLibrary",
    "CatalogRepartition",
    "stack_variables",
    "compile_entries",
    "euler_lagrange",
    "pysindy_library_terms",
    "integrate_by_parts",
    "LIBRARY_TYPES",
    "SpecReader",
    "SpecError",
]
