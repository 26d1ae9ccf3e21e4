"""What a catalog optimizer can do and needs: one tags object, asked in one way.

Like scikit-learn's estimator tags, the capabilities of a catalog optimizer are one frozen
dataclass, :class:`CatalogTags`, returned by its ``catalog_tags()`` method; the fit stage and
the composite optimizers read them with :func:`catalog_tags`, which also answers for
objects that only have ``fit_catalog``. A wrapper (ensemble, physically consistent refit)
returns the tags of the optimizer it wraps with what it changes itself.
"""

from __future__ import annotations

import dataclasses

__all__ = ["CatalogTags", "catalog_tags", "TAG_NAMES"]


@dataclasses.dataclass(frozen=True)
class CatalogTags:
    """Capabilities and needs of a catalog optimizer.

    Attributes
    ----------
    requires_forces : bool, default False
        Explicit regression: the problem must have force columns (the estimator refuses
        unforced data).
    uses_mass_matrices : bool, default False
        The mass matrices of the columns improve the fit (computed only then).
    uses_noise_draws : bool, default False
        The draws of the rows' errors (``CatalogProblem.noise_draws``) improve the fit
        (passed only then).
    derivative_estimate : {"smoothed", "unbiased"}, default "smoothed"
        Derivatives the strong form should use: smoothed (bias small next to the noise) or
        unbiased (a null-space search that the smoothing bias alone can hide the law from).
    can_refit : bool, default False
        It refits a given support: ``fit_problem(problem, support=...)`` (an ensemble's
        last step).
    balances_rows : bool, default True
        ``fit_problem`` balances the coordinate blocks before solving; False for optimizers
        that hand the problem on to others, which balance their own parts.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> px.ExplicitOptimizer().catalog_tags().requires_forces
    True
    >>> px.EnsembleOptimizer(px.ImplicitOptimizer()).catalog_tags().derivative_estimate
    'unbiased'
    """

    requires_forces: bool = False
    uses_mass_matrices: bool = False
    uses_noise_draws: bool = False
    derivative_estimate: str = "smoothed"
    can_refit: bool = False
    balances_rows: bool = True


#: The names of the tags, which optimizers also answer as attributes.
TAG_NAMES = tuple(field.name for field in dataclasses.fields(CatalogTags))


def catalog_tags(optimizer) -> CatalogTags:
    """The :class:`CatalogTags` of ``optimizer``.

    Parameters
    ----------
    optimizer : object
        A catalog optimizer (its ``catalog_tags()``), or any object with ``fit_catalog``,
        whose attributes of the tags' names are read (defaults otherwise).

    Returns
    -------
    CatalogTags

    Examples
    --------
    >>> import pysindy_xl as px
    >>> catalog_tags(px.MixedOptimizer()).balances_rows
    False
    """
    method = getattr(optimizer, "catalog_tags", None)
    if callable(method):
        return method()
    return CatalogTags(**{name: getattr(optimizer, name) for name in TAG_NAMES
                          if hasattr(optimizer, name)})
