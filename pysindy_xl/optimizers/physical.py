r"""Physically consistent explicit regression: rigid-body parameters and friction.

A kinematic catalog's coefficients stand for physical quantities
(:mod:`pysindy_xl.physical`): its base parameters are images ``beta = C pi`` of the bodies'
inertial parameters, its friction columns carry viscous and dry friction. An unconstrained fit
can land outside what rigid bodies realize (a negative mass, an inertia that violates the
triangle inequality, negative damping), most often on noisy data and for parameters the data
barely excite. :class:`PhysicalOptimizer` selects the terms with any explicit optimizer, then
refits the selected terms by least squares under the constraints of rigid bodies: with
``b_u`` the unconstrained refit and ``A`` its normal matrix (corrected for errors in the
variables where the unconstrained refit is),

.. math:: \min_{b, \pi} \; (b - b_u)^T A (b - b_u) \quad \text{s.t.} \quad
          b_{\mathcal B} = C \pi, \; J_k(\pi) \succeq 0 \;\forall k, \; a_j \ge 0, \;
          b_{\mathcal F} \ge 0,

which is the least squares of the regression on the consistent set (``|X b - y|^2`` differs
from it by a constant), a semidefinite program (cvxpy): :math:`J_k` the pseudo-inertia of body
``k``, :math:`a_j` the armatures, :math:`\mathcal F` the friction columns. A consistent ``b_u``
is its own solution: the constraint then changes nothing. The true parameters are consistent,
and the projection onto a closed convex set that holds them is non-expansive: the constrained
estimate is no farther from the truth than ``b_u`` in the norm of ``A`` (the error of the
regression's rows), whatever the noise, as long as the set holds the truth, which is why the
base parameters the selection left out may leave zero (``base_parameters="selected"``).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from sklearn.base import clone

from .._validation import check_instance, check_option
from ..physical.sdp import consistent_least_squares
from ._base import CatalogOptimizer, solve_problem, warn_unexplained
from ._wrapping import WrappingOptimizer
from .explicit import corrected_least_squares, explicit_regression
from .tags import catalog_tags

__all__ = ["PhysicalOptimizer"]

#: Which base parameters the constrained refit fits (see ``base_parameters``).
_BASE_PARAMETERS = ("selected", "all", "support")

#: Attributes of the selecting optimizer that the physical fit reports as its own.
_PASSED_ON = ("inclusion_probability_", "coef_interval_", "coef_samples_", "n_failed_",
              "aggregate_")


class PhysicalOptimizer(WrappingOptimizer, CatalogOptimizer):
    """Explicit regression constrained to physically consistent parameters.

    The terms are selected by ``optimizer`` (any explicit catalog optimizer, bagged or not);
    the selected terms are then refitted on all the rows by least squares subject to rigid
    bodies' constraints (see the module docstring): every body's pseudo-inertia positive
    semidefinite (its mass non-negative), armatures and friction non-negative. It needs the
    problem's ``physical`` structure, which :class:`~pysindy_xl.XLSINDy` passes for catalogs
    whose terms stand for physical parameters (:func:`~pysindy_xl.mujoco.kinematic_catalog`);
    without one the fit is ``optimizer``'s. Needs cvxpy.

    Parameters
    ----------
    optimizer : catalog optimizer, optional
        Selects the terms (cloned); explicit regression (force coefficient -1). Default
        ``ExplicitOptimizer()``.
    base_parameters : {"selected", "support", "all"}, default "selected"
        Which base parameters the estimates fit. ``"selected"``: the unconstrained estimate
        is the selection's (the base parameters it left out are zero), and the constrained
        fit may move every base parameter, those left out too: the consistent set then holds
        the true parameters, and the projection onto it (see the module docstring) brings
        the estimate no farther from them in the metric of the normal matrix, whatever the
        noise. ``"support"``: the base parameters left out stay zero, and must be realizable
        as zero too (the projection within the selection's model; the consistent set then
        need not hold the truth). ``"all"``: both estimates fit every base parameter (the
        unconstrained one noisier than the selection's).
    tolerance : float, default 1e-8
        The unconstrained refit counts as consistent, and is kept as it is, when its friction
        coefficients are non-negative and the constraints would cost at most this share of
        the explained signal (``(b - b_u)^T A (b - b_u) / b_u^T A b_u``, the solver's
        accuracy being about 1e-9).
    solver : str, optional
        cvxpy solver name (``"CLARABEL"``, ``"SCS"``); default the first of
        :data:`~pysindy_xl.physical.sdp.DEFAULT_SOLVERS` that succeeds.

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
    optimizer_ : fitted catalog optimizer
        The one that selected the terms (its ``coef_`` is not constrained).
    unconstrained_coef_ : ndarray, shape (F,)
        The unconstrained least squares on the selected terms.
    consistency_ : dict or None
        ``consistent``: whether the unconstrained refit was physically consistent;
        ``cost``: share of the explained signal the constraints cost;
        ``negative_friction``: columns whose unconstrained friction was negative;
        ``min_pseudo_inertia_eigenvalue``: smallest eigenvalue of the bodies' pseudo-inertias
        in :attr:`inertial_parameters_`, relative to the largest (non-negative up to
        round-off). None without a physical structure.
    inertial_parameters_ : dict or None
        A set of bodies' inertial parameters (and armatures) that realizes the fitted base
        parameters, by name: one of many (base parameters do not determine the bodies).
    selection_, inclusion_probability_, coef_interval_ : as the selecting optimizer's
        (when it has them).

    Examples
    --------
    A pendulum (``L = a qd^2 / 2 + b cos q``, ``b = m l g``) whose terms stand for one
    body's parameters, with a torque that an effect outside the catalog makes look like
    negative damping:

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
        """The selecting optimizer's tags; explicit, it refits a support, and balances its
        problem itself (the selecting optimizer its own; the refit again); see
        :class:`~pysindy_xl.optimizers.CatalogTags`."""
        return dataclasses.replace(catalog_tags(self._base()), requires_forces=True,
                                   can_refit=True, balances_rows=False)

    def __init__(self, optimizer=None, base_parameters="selected", tolerance=1e-8, solver=None):
        self.optimizer = optimizer
        self.base_parameters = base_parameters
        self.tolerance = tolerance
        self.solver = solver

    def _check_params(self):
        if self.optimizer is not None:
            check_instance("optimizer", self.optimizer, "a catalog optimizer", "fit_catalog")
            if not catalog_tags(self.optimizer).requires_forces:
                raise ValueError(f"optimizer: the terms must be selected by explicit "
                                 f"regression, {type(self.optimizer).__name__} is not")
        check_option("base_parameters", self.base_parameters, "choice",
                     choices=_BASE_PARAMETERS)
        check_option("tolerance", self.tolerance, "real", low=0)
        if self.solver is not None and not isinstance(self.solver, str):
            raise TypeError(f"solver: expected a cvxpy solver name, got {self.solver!r}")

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
        """The constrained least squares on a given support (see the module docstring)."""
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
        unconstrained = self._catalog_vector(coef, rest, problem)
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
                else self._catalog_vector(constrained, rest, problem),
                "unconstrained": unconstrained,
                "consistency": {"consistent": bool(consistent), "cost": float(cost),
                                "negative_friction": [int(rest[j]) for j in negative],
                                "min_pseudo_inertia_eigenvalue": float(pseudo.min(initial=0.0)
                                                                       / top)},
                "inertial": dict(zip(structure.names, pi.tolist(), strict=True))}

    @staticmethod
    def _catalog_vector(coef_rest, rest, problem):
        coef = np.zeros(problem.n_features)
        coef[rest] = coef_rest
        coef[problem.force_columns] = -1.0
        return coef
