"""Optimizers that run another catalog optimizer (``optimizer``): the ensemble and the physical
refit; their tags and pilot are the wrapped optimizer's.
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
        """The wrapped optimizer's pilot (:func:`~pysindy_xl.optimizers._base.pilot_optimizer`).

        Returns
        -------
        CatalogOptimizer
            Unfitted: the pilot of ``optimizer`` (default ``ExplicitOptimizer()``).
        """
        return pilot_optimizer(self._base())
