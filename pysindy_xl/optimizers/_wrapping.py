"""Optimizers that wrap a selecting optimizer.

:class:`~pysindy_xl.optimizers.EnsembleOptimizer` (bagging) and
:class:`~pysindy_xl.optimizers.PhysicalOptimizer` (the constrained refit) run another catalog
optimizer, their ``optimizer`` parameter, on the problem. Their tags
(:class:`~pysindy_xl.optimizers.CatalogTags`) are those of the optimizer they wrap, with what
the wrapper changes; their pilot is the wrapped optimizer's.
"""

from __future__ import annotations

from ._base import pilot_optimizer
from .explicit import ExplicitOptimizer

__all__ = ["WrappingOptimizer"]


class WrappingOptimizer:
    """Mixin: the wrapped optimizer ``self.optimizer`` (default ``ExplicitOptimizer()``)."""

    def _base(self):
        return ExplicitOptimizer() if self.optimizer is None else self.optimizer

    def pilot(self):
        """Unfitted stand-in for a first estimate of the law: the wrapped optimizer's pilot
        (see :func:`~pysindy_xl.optimizers._base.pilot_optimizer`), on all the rows."""
        return pilot_optimizer(self._base())
