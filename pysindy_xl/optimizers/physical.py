"""Physically consistent explicit regression: rigid-body parameters and friction
(:class:`PhysicalOptimizer`)."""

from __future__ import annotations

import dataclasses

import numpy as np
from sklearn.base import clone

from .._validation import HasMethods, InstanceOf, Interval, Options, validate_params
from ..physical.sdp import consistent_least_squares
from ._base import CatalogOptimizer, solve_problem, warn_unexplained
from ._wrapping import WrappingOptimizer
from .explicit import catalog_vector, corrected_least_squares, explicit_regression
from .tags import catalog_tags

__all__ = ["PhysicalOptimizer"]

#: Which base parameters the constrained refit fits (see ``base_parameters``).
_BASE_PARAMETERS = ("selected", "all", "support")

#: Attributes of the selecting optimizer that the physical fit reports as its own.
_PASSED_ON = ("inclusion_probability_", "coef_interval_", "coef_samples_", "n_failed_",
              "aggregate_")


class PhysicalOptimizer(WrappingOptimizer, CatalogOptimizer):
    """Explicit regression constrained to physically consistent parameters.

    ``optimizer`` selects the terms; they are refit on all the rows under rigid bodies'
    constraints (pseudo-inertias PSD, armatures and friction non-negative) by
    :func:`~pysindy_xl.physical.consistent_least_squares`: the projection of the unconstrained
    refit onto the consistent set, which holds the true parameters, in the norm of its normal
    matrix, so no farther from them. Needs the problem's ``physical`` structure
    (:func:`~pysindy_xl.mujoco.kinematic_catalog` catalogs; without one the fit is
    ``optimizer``'s) and cvxpy.

    Parameters
    ----------
    optimizer : catalog optimizer, optional
        Explicit optimizer selecting the terms (cloned); default ``ExplicitOptimizer()``.
    base_parameters : {"selected", "support", "all"}, default "selected"
        ``"selected"``: the unconstrained estimate is the selection's, the constrained one may
        move every base parameter (the consistent set then holds the truth). ``"support"``: the
        base parameters left out stay zero. ``"all"``: both estimates fit every base parameter.
    tolerance : float, default 1e-8
        The unconstrained refit is kept when its friction is non-negative and the constraints
        cost at most this share of the explained signal.
    solver : str, optional
        cvxpy solver name; default the first of :data:`~pysindy_xl.physical.sdp.DEFAULT_SOLVERS`
        that succeeds.

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
        Consistent coefficients (base parameters exactly ``C pi``).
    optimizer_ : fitted catalog optimizer
        The one that selected the terms.
    unconstrained_coef_ : ndarray, shape (F,)
        The selecting optimizer's coefficients.
    consistency_ : dict or None
        ``consistent``, ``cost`` (share of the explained signal), ``negative_friction``
        (columns), ``min_pseudo_inertia_eigenvalue`` (relative). None without a structure.
    inertial_parameters_ : dict or None
        One set of inertial parameters (and armatures) realizing the fitted base parameters.
    selection_, inclusion_probability_, coef_interval_ : as the selecting optimizer's.

    Examples
    --------
    A pendulum whose torque looks like negative damping:

    >>> import numpy as np, pysindy_xl as px
    >>> from pysindy_xl.physical import PhysicalStructure
    >>> rng = np.random.default_rng(0)
    >>> q, qd, qdd = rng.normal(size=(3, 200))
    >>> tau = 0.5 * qdd + 2.0 * np.sin(q) - 0.02 * qd
    >>> theta = np.column_stack([tau, qdd, np.sin(q), qd])
    >>> structure = PhysicalStructure.from_maps([{"p.Iyy": 1.0}, {"p.mcx": 9.81}],
    ...                                         base_columns=[1, 2], friction_columns=[3])
    >>> opt = PhysicalOptimizer(px.ExplicitOptimizer(threshold=0.0))
    >>> opt = opt.fit_catalog(theta, 1, [0], physical=structure)
    >>> opt.consistency_["consistent"], opt.unconstrained_coef_[3].round(4), opt.coef_.round(2)
    (False, np.float64(-0.02), array([-1. ,  0.5,  2. ,  0. ]))
    """

    spec_type = "PhysicalOptimizer"

    def catalog_tags(self):
        """What this optimizer can do and needs.

        The selecting optimizer's tags; explicit, refits a support, balances its problem itself.

        Returns
        -------
        CatalogTags
            The tags (:class:`~pysindy_xl.optimizers.tags.CatalogTags`): ``requires_forces``,
            ``can_refit``, ``balances_rows``, ``derivative_estimate``, ...
        """
        return dataclasses.replace(catalog_tags(self._base()), requires_forces=True,
                                   can_refit=True, balances_rows=False)

    _parameter_constraints = {
        "optimizer": [None, HasMethods("a catalog optimizer", "fit_catalog")],
        "base_parameters": [Options(_BASE_PARAMETERS)],
        "tolerance": [Interval("real", 0)],
        "solver": [None, InstanceOf(str, "a cvxpy solver name")],
    }

    def __init__(self, optimizer=None, base_parameters="selected", tolerance=1e-8, solver=None):
        self.optimizer = optimizer
        self.base_parameters = base_parameters
        self.tolerance = tolerance
        self.solver = solver

    def _check_params(self):
        validate_params(self)
        if self.optimizer is not None and not catalog_tags(self.optimizer).requires_forces:
            raise ValueError(f"optimizer: the terms must be selected by explicit "
                             f"regression, {type(self.optimizer).__name__} is not")

    def _solve(self, problem):
        """Select with the base optimizer, then refit its terms under the constraints."""
        base = solve_problem(clone(self._base()), problem)
        self.optimizer_ = base
        for name in _PASSED_ON:
            if hasattr(base, name):
                setattr(self, name, getattr(base, name))
        selection = getattr(base, "selection_", None)
        self._refit(problem.balanced(), np.asarray(base.coef_) != 0)
        self.selection_ = selection
        return self

    def _solve_support(self, problem, support):
        """The constrained least squares on a given support."""
        return self._refit(problem.balanced(), support)

    def _refit(self, problem, support):
        structure = problem.physical
        if structure is not None and self.base_parameters == "all":
            support = support.copy()
            support[structure.base_columns] = True
        fit = self._refit_on(problem, support)
        self.selection_ = None
        self.coef_ = fit["coef"]
        self.unconstrained_coef_ = fit["unconstrained"]
        self.consistency_ = fit["consistency"]
        self.inertial_parameters_ = fit["inertial"]
        self.n_features_in_ = problem.n_features
        self.support_ = self.coef_ != 0
        warn_unexplained("PhysicalOptimizer", problem.theta, problem.n_coordinates,
                         self.coef_, problem.force_columns, 4)
        return self

    def _refit_on(self, problem, support):
        """The unconstrained and the constrained least squares on ``support``."""
        rest, force, moments = explicit_regression(problem)
        structure = problem.physical
        keep = support[rest]
        x = problem.theta[:, rest]
        coef = np.zeros(len(rest))
        sub = None if moments is None else moments[np.ix_(keep, keep)]
        coef[keep], share = corrected_least_squares(x[:, keep], force, sub)
        unconstrained = catalog_vector(coef, rest, problem)
        if structure is None or not structure.constrains:
            return {"coef": unconstrained, "unconstrained": unconstrained,
                    "consistency": None, "inertial": None}
        structure = structure.select(rest)
        normal = x.T @ x
        if moments is not None and share < 0.5:  # as corrected_least_squares corrects
            normal = normal - moments
        free = keep.copy()
        if self.base_parameters != "support":  # every base parameter may leave zero
            free[structure.base_columns] = True
        constrained, pi, cost = consistent_least_squares(
            x, structure, coef, normal=normal, zero=~free, solver=self.solver)
        negative = structure.friction_columns[coef[structure.friction_columns] < 0]
        consistent = cost <= self.tolerance and not len(negative)
        pseudo = np.linalg.eigvalsh(structure.pseudo_inertias(pi)) if len(structure.bodies) \
            else np.zeros((0, 4))
        top = float(np.abs(pseudo).max(initial=0.0)) or 1.0
        return {"coef": unconstrained if consistent
                else catalog_vector(constrained, rest, problem),
                "unconstrained": unconstrained,
                "consistency": {"consistent": bool(consistent), "cost": float(cost),
                                "negative_friction": [int(rest[j]) for j in negative],
                                "min_pseudo_inertia_eigenvalue": float(pseudo.min(initial=0.0)
                                                                       / top)},
                "inertial": dict(zip(structure.names, pi.tolist(), strict=True))}
