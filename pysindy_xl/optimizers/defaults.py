"""The optimizer a fit uses when the user names none: chosen from which coordinates are forced
and whether the columns come from estimated (noisy) positions.

One policy, used by :class:`~pysindy_xl.XLSINDy` and, through it, by the command line.
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
                      complete: bool = False, physical: bool = False,
                      selective: bool = False):
    """The default catalog optimizer for the data (or of a given kind).

    * every coordinate forced: explicit regression; on estimated columns bagged,
      ``EnsembleOptimizer(ExplicitOptimizer())``. One cross-validated selection among about a
      hundred candidates keeps a term that only fits the noise in a sizeable share of fits (a
      multiple-comparison effect); the terms most subsample fits keep are the true ones. On
      estimated columns of a complete catalog (every Lagrangian term a physical parameter:
      a kinematic catalog) nothing is selected, ``ExplicitOptimizer(threshold=0.0)``
      (bagged as above for its intervals): no term is spurious there, and on noisy columns
      a selection drops the small true ones (a wrist's armature and damping, whose torques
      are a hundredth of the shoulder's), leaving joints whose torque the model does not
      predict at all. On exact columns the automatic threshold keeps every true term and
      cuts the exact zeros;
    * no coordinate forced: ``ImplicitOptimizer()``; on estimated columns of a complete
      catalog, the errors-in-variables law on all the columns,
      ``TotalLeastSquaresOptimizer()``, for the same reason;
    * some forced: ``MixedOptimizer``, its explicit part bagged on estimated columns as above;
    * explicit regression on a catalog whose terms stand for rigid-body parameters (a
      kinematic catalog): the same, refitted under rigid bodies' constraints,
      ``PhysicalOptimizer(explicit)``. A consistent estimate is kept as it is; an
      inconsistent one (an indefinite mass matrix, a negative mass or friction, most often
      on noisy data and barely excited parameters) is projected onto the consistent set,
      which holds the truth, so the estimate comes no farther from it;
    * explicit regression on a catalog with candidate friction and sensor models per joint
      (``selective``: a kinematic catalog built with ``friction=``): the selection is
      restricted to those columns, ``ExplicitOptimizer(select="friction")`` (bagged on
      estimated columns), refitted physically as above. The base parameters keep the
      no-selection default; the fit decides which friction models each joint needs.

    Parameters
    ----------
    forced : array of bool, shape (n,)
        Coordinates where a force acts.
    estimated : bool, default False
        The columns come from noisy positions only (the weak form propagated the smoother's
        noise estimate into them).
    kind : {"explicit", "implicit", "mixed"}, optional
        The kind of regression; default: from ``forced`` as above. The bagging policy is the
        same whatever the kind.
    complete : bool, default False
        The catalog is complete (``library.complete_catalog``).
    physical : bool, default False
        The catalog's terms stand for rigid-body parameters (``library.physical_structure()``
        is not None).
    selective : bool, default False
        The catalog has joint models to select among (its physical structure's
        ``selectable_columns``).

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
