"""Catalog optimizers: explicit, implicit (SINDy-PI) and mixed regression.

See :mod:`pysindy_xl.optimizers._base` for the ``fit_catalog`` protocol they share.
"""

from ._base import (
    CatalogOptimizer,
    balance_coordinates,
    coordinate_weights,
    independent_columns,
)
from .ensemble import EnsembleOptimizer
from .explicit import (
    ExplicitOptimizer,
    corrected_least_squares,
    hard_threshold_regression,
    proximal_gradient_lasso,
)
from .homogeneous import LawSelection, select_law
from .implicit import ImplicitOptimizer, NoLawFoundError, homothetic_groups
from .mixed import MixedOptimizer, activation_closure
from .selection import SelectionResult, refine_by_swaps, select_support

__all__ = [
    "CatalogOptimizer",
    "ExplicitOptimizer",
    "ImplicitOptimizer",
    "MixedOptimizer",
    "EnsembleOptimizer",
    "NoLawFoundError",
    "independent_columns",
    "coordinate_weights",
    "balance_coordinates",
    "hard_threshold_regression",
    "proximal_gradient_lasso",
    "corrected_least_squares",
    "homothetic_groups",
    "activation_closure",
    "select_support",
    "refine_by_swaps",
    "SelectionResult",
    "select_law",
    "LawSelection",
]
