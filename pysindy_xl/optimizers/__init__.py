"""Catalog optimizers: explicit, implicit (SINDy-PI) and mixed regression."""

from ._base import CatalogOptimizer, independent_columns
from .explicit import ExplicitOptimizer, hard_threshold_regression, proximal_gradient_lasso

__all__ = [
    "CatalogOptimizer",
    "ExplicitOptimizer",
    "independent_columns",
    "hard_threshold_regression",
    "proximal_gradient_lasso",
]
