"""Weak formulation: test functions and the smoother that feeds the weak columns.

The weak regression matrix itself is built by the catalog libraries
(:meth:`~pysindy_xl.feature_library.SymbolicLibrary.weak_transform`), so the optimizers and
the model use it exactly like the pointwise one.
"""

from .bumps import BumpTestFunctions, corner_frequency, quadrature_weights
from .noise import RowWhitener, WeakNoise
from .regression import propagated_draws, propagated_noise, weak_regression
from .smoothing import (
    WhittakerSmoother,
    differentiate,
    finite_difference_weights,
    whittaker_smooth,
)
from .timegrid import grid_summary, split_at_gaps, stamp_noise_ratio

__all__ = ["BumpTestFunctions", "WhittakerSmoother", "corner_frequency", "differentiate",
           "finite_difference_weights", "quadrature_weights", "whittaker_smooth",
           "weak_regression", "propagated_noise", "propagated_draws", "WeakNoise", "RowWhitener",
           "split_at_gaps", "grid_summary", "stamp_noise_ratio"]
