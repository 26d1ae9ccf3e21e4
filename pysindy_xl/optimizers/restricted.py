"""A selection among some of the catalog's columns only.

A catalog growth judges a catalog by the terms its fits keep on parts of the data; the fit of
the chosen catalog on all the data is another selection, over every column. Where that
selection keeps more terms than the judged fits, and terms none of them kept, the model is
larger than any judged.
:class:`RestrictedOptimizer` runs another optimizer on the given columns alone: it may leave
more of them out, never take others in.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from sklearn.base import clone

from .._validation import Boolean, Collection, HasMethods, validate_params
from ._base import CatalogOptimizer, pilot_optimizer, solve_problem
from ._wrapping import WrappingOptimizer
from .tags import CatalogTags, catalog_tags

__all__ = ["RestrictedOptimizer"]


class RestrictedOptimizer(WrappingOptimizer, CatalogOptimizer):
    """Another optimizer's fit on some of the catalog's columns; the others are zero.

    With ``C`` the allowed columns, the wrapped optimizer solves the problem of the columns
    ``theta[:, C]`` (with their noise moments, mass matrices and force columns), and

    .. math:: \\xi_j = 0 \\quad (j \\notin C).

    Parameters
    ----------
    optimizer : catalog optimizer or None, default None
        The optimizer fitted on the allowed columns (None: ``ExplicitOptimizer()``).
    columns : sequence of int, default ()
        The allowed catalog columns (those of ``XLSINDy.coef_``, mapped through the problem's
        catalog map; on a problem without one, its own columns). The force columns are always
        allowed. Empty: every column.
    select : bool, default True
        Whether the wrapped optimizer selects among the allowed columns. False: every allowed
        column is kept and refitted on every row, nothing selected (the wrapped optimizer's
        refit of a given support, or that of the single fit an ensemble bags; a wrapped
        optimizer without one is refused at fit time).

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
        Coefficients of the problem's columns (zero outside the allowed ones).
    optimizer_ : catalog optimizer
        The fitted wrapped optimizer.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> rng = np.random.default_rng(0)
    >>> theta = rng.normal(size=(400, 4))    # column 0: the force
    >>> theta[:, 0] = theta[:, 1:] @ [1.0, 0.5, 0.2] + 0.01 * rng.normal(size=400)
    >>> restricted = RestrictedOptimizer(px.ExplicitOptimizer(), columns=[1, 2])
    >>> (restricted.fit_catalog(theta, 1, [0]).coef_ != 0).tolist()
    [True, True, True, False]
    >>> given = RestrictedOptimizer(px.ExplicitOptimizer(threshold=0.5), columns=[1, 2],
    ...                             select=False)
    >>> (given.fit_catalog(theta, 1, [0]).coef_ != 0).tolist()   # 0.5 kept though below it
    [True, True, True, False]
    """

    spec_type = "RestrictedOptimizer"

    _parameter_constraints = {
        "optimizer": [None, HasMethods("a catalog optimizer", "fit_catalog")],
        "columns": [Collection("a sequence of column indices")],
        "select": [Boolean()],
    }

    def __init__(self, optimizer=None, columns=(), select=True):
        self.optimizer = optimizer
        self.columns = columns
        self.select = select

    def catalog_tags(self) -> CatalogTags:
        """What this optimizer can do and needs: the wrapped optimizer's tags.

        Returns
        -------
        CatalogTags
            The tags (:class:`~pysindy_xl.optimizers.tags.CatalogTags`) of ``optimizer``,
            which balances the rows itself.
        """
        return dataclasses.replace(catalog_tags(self._base()), balances_rows=False)

    def _check_params(self):
        validate_params(self)
        if np.ndim(self.columns) != 1 or not all(
                isinstance(j, (int, np.integer)) and not isinstance(j, bool) and j >= 0
                for j in self.columns):
            raise ValueError(f"columns: expected a sequence of non-negative column indices, got "
                             f"{self.columns!r}")

    def _allowed(self, problem) -> np.ndarray:
        """The problem's columns allowed: the given ones and the force columns."""
        if not len(self.columns):
            return np.arange(problem.n_features)
        columns = np.asarray(self.columns, dtype=int)
        origin = problem.catalog_map
        allowed = (np.isin(origin.columns, columns) if origin is not None
                   else np.isin(np.arange(problem.n_features), columns))
        allowed[np.asarray(problem.force_columns, dtype=int)] = True
        return np.flatnonzero(allowed)

    def _solve(self, problem):
        allowed = self._allowed(problem)
        sub = problem.subproblem(np.ones(problem.n_coordinates, dtype=bool), allowed)
        if problem.catalog_map is not None:  # (the wrapped optimizer's groups name the catalog)
            sub = dataclasses.replace(sub, catalog_map=dataclasses.replace(
                problem.catalog_map, columns=np.asarray(problem.catalog_map.columns)[allowed]))
        if self.select:
            fitted = solve_problem(clone(self._base()), sub)
        else:
            fitted = _refitting(self._base()).fit_problem(sub, np.ones(sub.n_features, bool))
        self.optimizer_ = fitted
        self.coef_ = _spread(fitted.coef_, allowed, problem.n_features)
        for name in _PER_COLUMN:  # (an ensemble's, on the problem's columns)
            if hasattr(fitted, name):
                setattr(self, name, _spread(getattr(fitted, name), allowed, problem.n_features))
        return self


def _refitting(optimizer):
    """An unfitted optimizer that refits a given support like ``optimizer``: itself, or the
    single fit an ensemble bags (``TypeError`` where neither can)."""
    for candidate in (optimizer, pilot_optimizer(optimizer)):
        if catalog_tags(candidate).can_refit:
            return clone(candidate)
    raise TypeError(f"optimizer: {type(optimizer).__name__} cannot refit a given support "
                    "(select=False needs the tag can_refit, or an ensemble of such fits)")


#: Fitted attributes of the wrapped optimizer, by column (the last axis), that the wrapper
#: answers too.
_PER_COLUMN = ("inclusion_probability_", "coef_interval_")


def _spread(values, allowed, n_features: int) -> np.ndarray:
    """``values`` of the allowed columns (the last axis) on all ``n_features`` columns, zero
    elsewhere."""
    values = np.asarray(values, dtype=float)
    out = np.zeros((*values.shape[:-1], n_features))
    out[..., allowed] = values
    return out
