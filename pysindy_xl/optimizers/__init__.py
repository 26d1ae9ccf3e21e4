"""Catalog optimizers: explicit, implicit (SINDy-PI; total least squares on complete catalogs),
mixed, ensemble, grouped and physically consistent regression.

Each solves a :class:`~pysindy_xl.optimizers.problem.CatalogProblem` through one entry
point, ``fit_problem``, and says what it can do and needs in one
:class:`~pysindy_xl.optimizers.tags.CatalogTags`; see
:mod:`pysindy_xl.optimizers._base` for the template of a fit that they share.
"""

from ._base import OPTIMIZER_TYPES, CatalogOptimizer, independent_columns
from ._base import optimizer_from_spec as optimizer_from_spec
from ._base import pilot_optimizer as pilot_optimizer
from ._base import solve_problem as solve_problem
from .defaults import SOLVER_KINDS, default_optimizer
from .ensemble import EnsembleOptimizer
from .explicit import (
    ExplicitOptimizer,
    corrected_least_squares,
    hard_threshold_regression,
    proximal_gradient_lasso,
)
from .grouped import GroupedOptimizer, close_groups
from .homogeneous import LawSelection, select_law
from .implicit import ImplicitOptimizer, NoLawFoundError
from .implicit import homothetic_groups as homothetic_groups
from .laws import UndeterminedLawWarning
from .mixed import MixedOptimizer, activation_closure
from .physical import PhysicalOptimizer
from .problem import CatalogProblem, coordinate_weights
from .problem import balance_coordinates as balance_coordinates
from .restricted import RestrictedOptimizer
from .selection import SelectionResult, refine_by_swaps, select_support
from .tags import CatalogTags, catalog_tags
from .total_least_squares import TotalLeastSquaresOptimizer

# the names imported "as" themselves serve the package (persistence, the fit's pilot, the
# solver entry, the block balancing, SINDy-PI's grouping): importable from here, not in __all__
__all__ = ["CatalogOptimizer", "CatalogProblem", "CatalogTags", "catalog_tags", "OPTIMIZER_TYPES",
           "default_optimizer", "SOLVER_KINDS", "ExplicitOptimizer", "ImplicitOptimizer",
           "MixedOptimizer", "EnsembleOptimizer", "GroupedOptimizer", "close_groups",
           "PhysicalOptimizer", "RestrictedOptimizer", "NoLawFoundError",
           "TotalLeastSquaresOptimizer", "UndeterminedLawWarning", "independent_columns",
           "coordinate_weights", "hard_threshold_regression", "proximal_gradient_lasso",
           "corrected_least_squares", "activation_closure", "select_support", "refine_by_swaps",
           "SelectionResult", "select_law", "LawSelection"]
