"""Optimizers that wrap a selecting optimizer, and answer for it what the fit asks first.

:class:`~pysindy_xl.optimizers.EnsembleOptimizer` (bagging) and
:class:`~pysindy_xl.optimizers.PhysicalOptimizer` (the constrained refit) run another catalog
optimizer, their ``optimizer`` parameter, on the problem. Before any fit,
:class:`~pysindy_xl.XLSINDy` asks an optimizer whether it needs the columns' mass matrices,
which derivative estimate its rows want, and which cheaper optimizer gives a pilot law: a
wrapper's answers are those of the optimizer it wraps.
"""

from __future__ import annotations

from ._base import pilot_optimizer
from .explicit import ExplicitOptimizer

__all__ = ["WrappingOptimizer"]


class WrappingOptimizer:
    """Mixin: capabilities delegated to ``self.optimizer`` (default ``ExplicitOptimizer()``)."""

    def _base(self):
        return ExplicitOptimizer() if self.optimizer is None else self.optimizer

    @property
    def uses_mass_matrices(self) -> bool:
        """As the wrapped optimizer."""
        return getattr(self._base(), "uses_mass_matrices", False)

    @property
    def uses_noise_draws(self) -> bool:
        """As the wrapped optimizer."""
        return getattr(self._base(), "uses_noise_draws", False)

    @property
    def derivative_estimate(self) -> str:
        """As the wrapped optimizer."""
        return getattr(self._base(), "derivative_estimate", "smoothed")

    def pilot(self):
        """Unfitted stand-in for a first estimate of the law: the wrapped optimizer's pilot
        (see :func:`~pysindy_xl.optimizers._base.pilot_optimizer`), on all the rows."""
        return pilot_optimizer(self._base())
