"""Mixed regression: explicit where a force reaches, implicit on the rest
(:class:`MixedOptimizer`)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
from sklearn.base import clone

from .._validation import (
    HasMethods,
    Interval,
    UnexplainedCoordinateWarning,
    check_instance,
    validate_params,
)
from ._base import CatalogOptimizer, pilot_optimizer, solve_problem
from .implicit import ImplicitOptimizer, NoLawFoundError, coordinates_touched
from .problem import balance_coordinates
from .tags import catalog_tags

__all__ = ["MixedOptimizer", "activation_closure"]


def activation_closure(touches, seed) -> tuple[np.ndarray, np.ndarray]:
    """Fixed point of the activation graph.

    Parameters
    ----------
    touches : array of bool, shape (n_coordinates, F)
        ``touches[c, j]``: column j enters the equation of coordinate c.
    seed : array of bool, shape (n_coordinates,)
        Initially activated coordinates.

    Returns
    -------
    coordinates : ndarray of bool, shape (n_coordinates,)
        The coordinates activated at the start (the forced ones).
    columns : ndarray of bool, shape (F,)
        Columns touching an activated coordinate.

    Examples
    --------
    >>> import numpy as np
    >>> touches = np.array([[1, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1]], dtype=bool)
    >>> activation_closure(touches, np.array([True, False, False]))
    (array([ True,  True, False]), array([ True,  True, False, False]))
    """
    touches = np.asarray(touches, dtype=bool)
    coordinates = np.asarray(seed, dtype=bool).copy()
    while True:
        columns = touches[coordinates].any(axis=0)
        grown = coordinates | touches[:, columns].any(axis=1)
        if np.array_equal(grown, coordinates):
            return coordinates, columns
        coordinates = grown


class MixedOptimizer(CatalogOptimizer):
    """Explicit regression on the force-activated subsystem, implicit regression on the rest.

    Column j *touches* coordinate c when it is not zero in c's rows. From the forced
    coordinates, every column touching an activated coordinate activates all it touches
    (:func:`activation_closure`); that block is solved explicitly, and the coordinates no
    identified term enters are solved implicitly with the columns touching no explicit
    coordinate; the two coefficient vectors (disjoint columns) are summed. Every coordinate
    reached: the explicit optimizer's result; no force: the implicit optimizer's. Standalone
    use: :meth:`fit_catalog` with the number of coordinates and the force columns.

    Parameters
    ----------
    explicit_optimizer : estimator, optional
        Optimizer of the activated block (cloned); default ``ExplicitOptimizer()``.
    implicit_optimizer : estimator, optional
        Optimizer of the rest (cloned); default ``ImplicitOptimizer()``.
    rtol : float, default 1e-10
        A column block at most ``rtol`` times the column's largest does not touch its coordinate.

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
        The explicit and implicit coefficients summed (disjoint columns).
    mode_ : {"explicit", "implicit", "mixed"}
        Which parts were used.
    forced_coordinates_, activated_coordinates_ : ndarray of bool, shape (n_coordinates,)
        Coordinates with a non-zero force, and their activation closure.
    explicit_coordinates_, implicit_coordinates_ : ndarray of bool, shape (n_coordinates,)
        After the update from the explicit solution.
    explicit_columns_, implicit_columns_ : ndarray of int
        The columns of each part.
    explicit_optimizer_, implicit_optimizer_ : estimator or None
        The fitted parts (None when unused).
    inclusion_probability_, coef_interval_ : ndarray, shape (F,) and (2, F)
        Those of an :class:`EnsembleOptimizer` explicit part when it explains every coordinate.

    Examples
    --------
    ``x1'' + 4 x1 = u`` forced and ``x2'' + 9 x2 = 0`` free (columns: force, x1'', x1, x2'', x2):

    >>> import numpy as np, pysindy_xl as px
    >>> t = np.linspace(0, 20, 200)
    >>> u, x1, x2, zero = np.sin(1.3 * t), np.sin(t), np.cos(3 * t), np.zeros(200)
    >>> theta = np.block([[np.column_stack([u, u - 4 * x1, x1, zero, zero])],
    ...                   [np.column_stack([zero, zero, zero, -9 * x2, x2])]])
    >>> opt = px.MixedOptimizer().fit_catalog(theta, 2, [0])
    >>> opt.mode_, np.round(opt.coef_, 6)
    ('mixed', array([-1.,  1.,  4.,  1.,  9.]))
    """

    spec_type = "MixedOptimizer"

    def catalog_tags(self):
        """What this optimizer can do and needs.

        The parts balance their own sub-problems; mass matrices and draws are used where one
        does.

        Returns
        -------
        CatalogTags
            The tags (:class:`~pysindy_xl.optimizers.tags.CatalogTags`): ``requires_forces``,
            ``can_refit``, ``balances_rows``, ``derivative_estimate``, ...
        """
        parts = [catalog_tags(part) for part in self._sub_optimizers()]
        return dataclasses.replace(
            super().catalog_tags(), balances_rows=False,
            uses_mass_matrices=any(tags.uses_mass_matrices for tags in parts),
            uses_noise_draws=any(tags.uses_noise_draws for tags in parts))

    _parameter_constraints = {
        "explicit_optimizer": [None, HasMethods("an optimizer", "fit_catalog")],
        "implicit_optimizer": [None, HasMethods("an optimizer", "fit_catalog")],
        "rtol": [Interval("real", 0, 1, high_open=True)],
    }

    def __init__(self, explicit_optimizer=None, implicit_optimizer=None, rtol=1e-10):
        self.explicit_optimizer = explicit_optimizer
        self.implicit_optimizer = implicit_optimizer
        self.rtol = rtol

    def _check_params(self):
        validate_params(self)

    def _sub_optimizers(self):
        from .explicit import ExplicitOptimizer

        explicit, implicit = self.explicit_optimizer, self.implicit_optimizer
        explicit = ExplicitOptimizer() if explicit is None else explicit
        implicit = ImplicitOptimizer() if implicit is None else implicit
        for name, opt in (("explicit_optimizer", explicit), ("implicit_optimizer", implicit)):
            check_instance(name, opt, "an optimizer")
            if not hasattr(opt, "fit_catalog"):
                raise TypeError(f"{name}: expected an optimizer with fit_catalog, got {opt!r}")
        return clone(explicit), clone(implicit)

    def pilot(self):
        """The same mixed regression with the pilots of both parts.

        Returns
        -------
        MixedOptimizer
            Unfitted, with ``explicit_optimizer.pilot()`` and ``implicit_optimizer.pilot()``.
        """
        explicit, implicit = self._sub_optimizers()  # validated clones
        return clone(self).set_params(explicit_optimizer=pilot_optimizer(explicit),
                                      implicit_optimizer=pilot_optimizer(implicit))

    def fit(self, X, y=None):
        """Regression on one block of rows: the explicit part ``X @ coef_ = y`` given ``y``, else
        the implicit part ``X @ coef_ = 0``.

        Parameters
        ----------
        X : array, shape (n_rows, F)
            Regression matrix.
        y : array, shape (n_rows,), optional
            Right-hand side of the explicit part; default None: the implicit part ``X @ coef_ = 0``.

        Returns
        -------
        self
        """
        self._check_params()
        explicit, implicit = self._sub_optimizers()
        part = implicit if y is None else explicit
        if not callable(getattr(part, "fit", None)):
            raise TypeError(f"{type(part).__name__} has no fit(X, y); call fit_catalog(theta, "
                            "n_coordinates, force_columns)")
        fitted = part.fit(X) if y is None else part.fit(X, y)
        self.mode_ = "implicit" if y is None else "explicit"
        self.coef_ = np.asarray(fitted.coef_, dtype=float).copy()
        self.n_features_in_ = fitted.n_features_in_
        return self

    def _solve(self, problem):
        """Mixed explicit/implicit regression, each part on its sub-problem."""
        explicit, implicit = self._sub_optimizers()
        theta, n, force_columns = problem.theta, problem.n_coordinates, problem.force_columns

        n_features = theta.shape[1]
        # balanced here only to decide which coordinates a column touches
        touches = coordinates_touched(balance_coordinates(theta, n, force_columns), n, self.rtol)
        forced = touches[:, force_columns].any(axis=1)
        activated, activated_columns = activation_closure(touches, forced)
        self.forced_coordinates_ = forced
        self.activated_coordinates_ = activated
        self.explicit_optimizer_ = None
        self.implicit_optimizer_ = None
        for name in ("inclusion_probability_", "coef_interval_"):  # of an earlier fit
            self.__dict__.pop(name, None)

        if not forced.any():
            self._set_mode("implicit", np.zeros(n, bool), np.array([], int), np.arange(n_features))
            self.implicit_optimizer_ = solve_problem(implicit, problem.subproblem(
                np.ones(n, bool), np.arange(n_features), force_columns))
            self.coef_ = np.asarray(self.implicit_optimizer_.coef_, dtype=float).copy()
            return self

        coef = np.zeros(n_features)
        explicit_cols = (np.arange(n_features) if activated.all()
                         else np.flatnonzero(activated_columns))
        with warnings.catch_warnings():
            # coordinates the explicit part leaves unexplained are solved implicitly below
            warnings.simplefilter("ignore", UnexplainedCoordinateWarning)
            self.explicit_optimizer_ = solve_problem(explicit, problem.subproblem(
                activated, explicit_cols, np.flatnonzero(np.isin(explicit_cols, force_columns))))
        coef[explicit_cols] = self.explicit_optimizer_.coef_
        explained = touches[:, coef != 0].any(axis=1)
        if explained.all():
            self._set_mode("explicit", explained, explicit_cols, np.array([], int))
            self.coef_ = coef
            part = self.explicit_optimizer_
            if hasattr(part, "inclusion_probability_"):  # the model is one ensemble's
                self.inclusion_probability_ = np.zeros(n_features)
                self.inclusion_probability_[explicit_cols] = part.inclusion_probability_
                self.coef_interval_ = np.zeros((2, n_features))
                self.coef_interval_[:, explicit_cols] = part.coef_interval_
            return self

        remaining = ~explained
        implicit_mask = ~touches[explained].any(axis=0) & touches[remaining].any(axis=0)
        implicit_mask[force_columns] = False
        implicit_cols = np.flatnonzero(implicit_mask)
        self._set_mode("mixed", explained, explicit_cols, implicit_cols)
        released = np.flatnonzero(activated & remaining)
        if released.size:
            warnings.warn(f"MixedOptimizer: no identified explicit term enters coordinate(s) "
                          f"{released.tolist()}; solving them implicitly", stacklevel=2)
        if implicit_cols.size == 0:
            raise ValueError(
                f"theta: coordinate(s) {np.flatnonzero(remaining).tolist()} receive no force and "
                "no catalog column is left for them (every column touching them also touches an "
                "explicitly identified coordinate); nothing left to solve implicitly")
        try:
            self.implicit_optimizer_ = solve_problem(
                implicit, problem.subproblem(remaining, implicit_cols, []))
        except NoLawFoundError as error:
            raise NoLawFoundError(f"MixedOptimizer: implicit part on coordinate(s) "
                                  f"{np.flatnonzero(remaining).tolist()}: {error}") from error
        coef[implicit_cols] += self.implicit_optimizer_.coef_
        self.coef_ = coef
        return self

    def _set_mode(self, mode, explicit_coordinates, explicit_columns, implicit_columns):
        self.mode_ = mode
        self.explicit_coordinates_ = np.asarray(explicit_coordinates, dtype=bool)
        self.implicit_coordinates_ = ~self.explicit_coordinates_
        self.explicit_columns_ = np.asarray(explicit_columns, dtype=int)
        self.implicit_columns_ = np.asarray(implicit_columns, dtype=int)
