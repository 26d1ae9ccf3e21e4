"""Weak formulation: test functions and the smoother that feeds the weak columns.

The weak regression matrix itself is built by the catalog libraries
(:meth:`~pysindy_xl.feature_library.SymbolicLibrary.weak_transform`), so the optimizers and
the model use it exactly like the pointwise one.
"""

from .bumps import BumpTestFunctions, corner_frequency
from .bumps import quadrature_weights as quadrature_weights
from .noise import RowWhitener as RowWhitener
from .noise import WeakNoise
from .regression import propagated_draws as propagated_draws
from .regression import propagated_noise, weak_regression
from .smoothing import WhittakerSmoother, differentiate, whittaker_smooth
from .smoothing import finite_difference_weights as finite_difference_weights
from .timegrid import grid_summary as grid_summary
from .timegrid import split_at_gaps as split_at_gaps
from .timegrid import stamp_noise_ratio

# the names imported "as" themselves are the weak fit's internals: importable from here, not
# public (not in __all__)
__all__ = ["BumpTestFunctions", "WhittakerSmoother", "weak_regression", "corner_frequency",
           "whittaker_smooth", "differentiate", "propagated_noise", "WeakNoise",
           "stamp_noise_ratio"]
