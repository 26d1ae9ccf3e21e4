"""What a catalog optimizer can do and needs: one frozen :class:`CatalogTags`, like
scikit-learn's estimator tags, returned by ``catalog_tags()`` and read with
:func:`catalog_tags`. A wrapper returns its wrapped optimizer's tags with its own changes.
"""

from __future__ import annotations

import dataclasses

__all__ = ["CatalogTags", "catalog_tags", "TAG_NAMES"]


@dataclasses.dataclass(frozen=True)
class CatalogTags:
    """Capabilities and needs of a catalog optimizer.

    Parameters
    ----------
    requires_forces : bool, default False
        Explicit regression: the problem must have force columns.
    uses_mass_matrices : bool, default False
        The columns' mass matrices improve the fit (computed only then).
    uses_noise_draws : bool, default False
        The draws of the rows' errors improve the fit (passed only then).
    derivative_estimate : {"smoothed", "unbiased"}, default "smoothed"
        Derivatives the strong form should use (a null-space search can lose the law to the
        smoothing bias).
    can_refit : bool, default False
        It refits a given support: ``fit_problem(problem, support=...)``.
    balances_rows : bool, default True
        ``fit_problem`` balances the coordinate blocks; False for optimizers whose parts do.

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
        A catalog optimizer, or any object with ``fit_catalog`` (its attributes of the tags'
        names are read).

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
