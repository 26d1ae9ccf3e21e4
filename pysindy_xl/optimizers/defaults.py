"""The optimizer a fit uses when the user names none (used by :class:`~pysindy_xl.XLSINDy` and
the command line).
"""

from __future__ import annotations

import numpy as np

from .ensemble import EnsembleOptimizer
from .explicit import ExplicitOptimizer
from .implicit import ImplicitOptimizer
from .mixed import MixedOptimizer
from .physical import PhysicalOptimizer
from .total_least_squares import TotalLeastSquaresOptimizer

__all__ = ["default_optimizer", "SOLVER_KINDS"]

#: The kinds of regression, as named by users (``XLSINDy(optimizer="mixed")``, ``--solver``).
SOLVER_KINDS = ("explicit", "implicit", "mixed")


def default_optimizer(forced, estimated: bool = False, kind: str | None = None,
                      complete: bool = False, physical: bool = False, selective: bool = False):
    """The default catalog optimizer for the data (or of a given kind).

    * every coordinate forced: ``ExplicitOptimizer()``, bagged by :class:`EnsembleOptimizer` on
      estimated columns (one selection among a hundred candidates often keeps a noise term; the
      terms most fits keep are true). On estimated columns of a complete catalog nothing is
      selected (``threshold=0.0``): no term is spurious, and a selection drops small true ones;
    * no coordinate forced: ``ImplicitOptimizer()``; on estimated columns of a complete catalog
      ``TotalLeastSquaresOptimizer()``;
    * some forced: ``MixedOptimizer``, its explicit part bagged on estimated columns;
    * explicit on a catalog of rigid-body parameters (``physical``): refit under rigid bodies'
      constraints, ``PhysicalOptimizer(explicit)``;
    * with joint friction and sensor models to select (``selective``):
      ``ExplicitOptimizer(select="friction")``, bagged on estimated columns, refit physically.

    Parameters
    ----------
    forced : array of bool, shape (n,)
        Coordinates where a force acts.
    estimated : bool, default False
        The columns come from noisy positions only.
    kind : {"explicit", "implicit", "mixed"}, optional
        Default: from ``forced``.
    complete : bool, default False
        The catalog is complete (``library.complete_catalog``).
    physical : bool, default False
        ``library.physical_structure()`` is not None.
    selective : bool, default False
        The physical structure has ``selectable_columns``.

    Returns
    -------
    CatalogOptimizer
        Unfitted.

    Examples
    --------
    >>> import numpy as np
    >>> type(default_optimizer(np.array([True, False]))).__name__
    'MixedOptimizer'
    >>> default_optimizer(np.array([True, True]), estimated=True).optimizer
    ExplicitOptimizer()
    >>> default_optimizer(np.array([True, True]), complete=True, physical=True)
    PhysicalOptimizer(optimizer=ExplicitOptimizer())
    """
    forced = np.asarray(forced, dtype=bool)
    if kind is None:
        kind = "explicit" if forced.all() else "implicit" if not forced.any() else "mixed"
    if kind not in SOLVER_KINDS:
        raise ValueError(f"kind: expected one of {SOLVER_KINDS}, got {kind!r}")
    explicit = EnsembleOptimizer(ExplicitOptimizer()) if estimated else ExplicitOptimizer()
    if kind == "explicit":
        if selective:  # only the joint models are selected
            explicit = ExplicitOptimizer(select="friction")
            explicit = EnsembleOptimizer(explicit) if estimated else explicit
        elif complete and estimated:  # every parameter estimated
            explicit = EnsembleOptimizer(ExplicitOptimizer(threshold=0.0))
        return PhysicalOptimizer(explicit) if physical else explicit
    if kind == "implicit":
        return TotalLeastSquaresOptimizer() if estimated and complete else ImplicitOptimizer()
    return MixedOptimizer(explicit if estimated else None)
