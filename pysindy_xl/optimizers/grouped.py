"""Columns that enter a model together: a group is kept whole or left out.

Some catalog columns only mean something together. The natural splines of one coordinate are a
basis of its unknown potential: a sparse selection that keeps some of them and drops the others
fits a curve of the wrong space (its continuation beyond the data, set by the end functions,
changes with the choice). :class:`GroupedOptimizer` runs another optimizer and closes its
support over the groups, then refits the closed support by least squares.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from sklearn.base import clone

from .._validation import Collection, HasMethods, Options, validate_params
from ._base import CatalogOptimizer, pilot_optimizer, solve_problem
from ._wrapping import WrappingOptimizer
from .tags import CatalogTags, catalog_tags

__all__ = ["GroupedOptimizer", "close_groups"]

#: Fitted attributes of the wrapped optimizer that the wrapper answers too (an ensemble's).
_PASSED_ON = ("inclusion_probability_", "coef_interval_", "coef_samples_", "n_failed_",
              "aggregate_", "selection_", "noise_share_")


#: A group's column whose RMS over the rows is below this fraction of the group's largest is
#: not added by the closure: the rows hardly see it (a spline whose support holds almost no
#: data), and least squares would give it an arbitrary coefficient.
SEEN = 1e-2


def _seen(theta, group) -> np.ndarray:
    """The columns of ``group`` that the rows of ``theta`` see (:data:`SEEN`)."""
    if not len(group):
        return group
    rms = np.sqrt(np.mean(np.square(theta[:, group]), axis=0))
    return group[rms >= SEEN * rms.max()] if rms.max() > 0 else group[:0]


def close_groups(support, groups) -> np.ndarray:
    """``support`` with every group that it touches made whole.

    .. math:: S' = S \\cup \\bigcup_{g:\\ g \\cap S \\neq \\emptyset} g

    Parameters
    ----------
    support : array of bool, shape (F,)
        The selected columns.
    groups : sequence of sequence of int
        Column indices of each group (indices outside ``[0, F)`` are ignored).

    Returns
    -------
    ndarray of bool, shape (F,)

    Examples
    --------
    >>> close_groups([True, False, False, True, False], [[1, 2], [3, 4]]).tolist()
    [True, False, False, True, True]
    """
    closed = np.array(support, dtype=bool)
    for group in groups:
        group = np.asarray(group, dtype=int)
        group = group[(group >= 0) & (group < len(closed))]
        if closed[group].any():
            closed[group] = True
    return closed


class GroupedOptimizer(WrappingOptimizer, CatalogOptimizer):
    """Another optimizer's selection, with groups of columns kept whole or left out.

    ``optimizer`` selects the support ``S`` as it would alone; every group that ``S`` touches
    is added whole (:func:`close_groups`), and the closed support is refitted by least squares
    (on the same rows and noise moments, with an optimizer that refits a given support: the
    wrapped one, or an ensemble's base optimizer). A group the selection left out entirely
    stays out. Where nothing can refit a support (a ``MixedOptimizer``), the wrapped
    optimizer's solution is kept as it is.

    Parameters
    ----------
    optimizer : catalog optimizer or None, default None
        The selecting optimizer (None: ``ExplicitOptimizer()``).
    groups : sequence of sequence of int, default ()
        Column indices of each group.
    columns : {"catalog", "problem"}, default "catalog"
        What ``groups`` index: the catalog's columns (those of ``XLSINDy.coef_``, mapped through
        the problem's catalog map; on a problem without one, its own columns), or the
        problem's columns.

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
        Coefficients of the problem's columns.
    optimizer_ : catalog optimizer
        The fitted selecting optimizer.
    closed_ : list of int
        Indices (into ``groups``) of the groups that the closure completed.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> rng = np.random.default_rng(0)
    >>> theta = rng.normal(size=(400, 4))    # column 0: the force, 2 and 3 a group
    >>> theta[:, 0] = theta[:, 1:] @ [1.0, 0.5, 0.01] + 0.3 * rng.normal(size=400)
    >>> (px.ExplicitOptimizer().fit_catalog(theta, 1, [0]).coef_ != 0).tolist()
    [True, True, True, False]
    >>> grouped = GroupedOptimizer(px.ExplicitOptimizer(), groups=[[2, 3]])
    >>> (grouped.fit_catalog(theta, 1, [0]).coef_ != 0).tolist(), grouped.closed_
    ([True, True, True, True], [0])
    """

    spec_type = "GroupedOptimizer"

    _parameter_constraints = {
        "optimizer": [None, HasMethods("a catalog optimizer", "fit_catalog")],
        "groups": [Collection("a sequence of sequences of column indices")],
        "columns": [Options(("catalog", "problem"))],
    }

    def __init__(self, optimizer=None, groups=(), columns="catalog"):
        self.optimizer = optimizer
        self.groups = groups
        self.columns = columns

    def catalog_tags(self) -> CatalogTags:
        """What this optimizer can do and needs: the wrapped optimizer's tags.

        It refits a given support (closed over the groups) where the wrapped optimizer, or the
        single fit that an ensemble bags, does.

        Returns
        -------
        CatalogTags
            The tags (:class:`~pysindy_xl.optimizers.tags.CatalogTags`): ``requires_forces``,
            ``can_refit``, ``balances_rows``, ``derivative_estimate``, ...
        """
        return dataclasses.replace(catalog_tags(self._base()), balances_rows=False,
                                   can_refit=self._refitting(self._base()) is not None)

    def _check_params(self):
        validate_params(self)
        for group in self.groups:
            if np.ndim(group) != 1 or not all(isinstance(j, (int, np.integer))
                                             and not isinstance(j, bool) and j >= 0
                                             for j in group):
                raise ValueError(f"groups: expected sequences of non-negative column indices, "
                                 f"got {group!r}")

    def pilot(self):
        """The pilot of the wrapped optimizer, grouped alike.

        Returns
        -------
        GroupedOptimizer
            Unfitted.
        """
        return GroupedOptimizer(pilot_optimizer(self._base()), groups=self.groups,
                                columns=self.columns)

    def _local_groups(self, problem) -> list:
        """The groups as indices of the problem's columns."""
        origin = problem.catalog_map if self.columns == "catalog" else None
        out = []
        for group in self.groups:
            group = np.asarray(group, dtype=int)
            if origin is not None:
                group = np.searchsorted(origin.columns, group[np.isin(group, origin.columns)])
            group = group[(group >= 0) & (group < problem.n_features)]
            # the closure adds what the rows see (the selection may keep the rest)
            out.append(_seen(problem.theta, group))
        return out

    @staticmethod
    def _refitting(optimizer):
        """An unfitted optimizer that refits a given support like ``optimizer`` (itself, or
        the single fit an ensemble bags), or None."""
        for candidate in (optimizer, pilot_optimizer(optimizer)):
            if catalog_tags(candidate).can_refit:
                return clone(candidate)
        return None

    def _selecting(self, groups):
        """The wrapped optimizer; one that wraps another (an ensemble) with each of its fits
        grouped, on the problem's columns (an ensemble's subsamples have no catalog map)."""
        selecting = clone(self._base())
        params = selecting.get_params(deep=False)
        if "optimizer" in params:
            inner = params["optimizer"]
            selecting.set_params(optimizer=GroupedOptimizer(
                inner, groups=[g.tolist() for g in groups], columns="problem"))
        return selecting

    def _solve(self, problem):
        groups = self._local_groups(problem)
        selecting = solve_problem(self._selecting(groups), problem)
        self.optimizer_ = selecting
        for name in _PASSED_ON:
            if hasattr(selecting, name):
                setattr(self, name, getattr(selecting, name))
        coef = np.asarray(selecting.coef_, dtype=float)
        support = coef != 0
        self.closed_ = [k for k, g in enumerate(groups)
                        if len(g) and support[g].any() and not support[g].all()]
        refitting = self._refitting(self._base())
        if self.closed_ and refitting is not None:
            coef = np.asarray(refitting.fit_problem(problem, close_groups(support, groups)).coef_,
                              dtype=float)
        elif self.closed_:
            self.closed_ = []
        self.coef_ = coef
        return self

    def _solve_support(self, problem, support):
        """Least squares on ``support`` closed over the groups."""
        refitting = self._refitting(self._base())
        if refitting is None:
            raise TypeError(f"{type(self._base()).__name__}: cannot refit a given support")
        closed = close_groups(support, self._local_groups(problem))
        self.closed_ = []
        self.coef_ = np.asarray(refitting.fit_problem(problem, closed).coef_, dtype=float)
        for name in _PASSED_ON:
            if hasattr(refitting, name):
                setattr(self, name, getattr(refitting, name))
        return self
