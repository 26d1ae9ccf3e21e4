"""XLSINDy: the estimator that identifies a mechanical system from trajectories."""

from __future__ import annotations

import contextlib
import sys
import warnings

import numpy as np
import threadpoolctl
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from ._validation import (
    Boolean,
    HasMethods,
    IdentificationWarning,
    InstanceOf,
    Interval,
    Options,
    check_option,
    validate_params,
)
from .feature_library import remembered_weak_values
from .fit import (
    FORMULATIONS,
    build_problem,
    catalog_dynamics,
    check_fit,
    choose_noise_model,
    estimator_trajectories,
    fit_smoother,
    resolve_optimizer,
    solve,
)
from .fit.wrap import wrap
from .fitted.dynamics import DynamicsMixin
from .fitted.inspection import InspectionMixin
from .io import invalid_model_file, read_model_file
from .optimizers import SOLVER_KINDS, CatalogProblem

__all__ = ["XLSINDy", "IdentificationWarning"]


_CONTROLLER: list = []  # [(modules loaded, threadpoolctl.ThreadpoolController)]


def _blas_limit(threads):
    """``threadpoolctl.threadpool_limits(limits=threads, user_api="blas")`` (no limit for
    None), by a controller kept while no module is imported: its scan of the loaded libraries
    costs a few milliseconds, as much as a small fit (a growth makes hundreds)."""
    if threads is None:
        return contextlib.nullcontext()
    loaded = len(sys.modules)
    if not _CONTROLLER or _CONTROLLER[0][0] != loaded:
        _CONTROLLER[:] = [(loaded, threadpoolctl.ThreadpoolController())]
    return _CONTROLLER[0][1].limit(limits=threads, user_api="blas")


class XLSINDy(InspectionMixin, DynamicsMixin, BaseEstimator):
    """Sparse identification of a mechanical system from position trajectories.

    Builds the stacked regression matrix of a catalog (Lagrangian, classical and force terms,
    see :class:`~pysindy_xl.CatalogRepartition`), removes exactly dependent columns, solves it
    with a catalog optimizer and exposes the identified equations of motion in mass-matrix form.

    Parameters
    ----------
    feature_library : SymbolicLibrary or CatalogRepartition
        The catalog. A single library is wrapped in a ``CatalogRepartition`` (which adds the
        force column).
    optimizer : catalog optimizer or {"explicit", "implicit", "mixed"}, optional
        :class:`~pysindy_xl.ExplicitOptimizer`, :class:`~pysindy_xl.ImplicitOptimizer`,
        :class:`~pysindy_xl.MixedOptimizer`, :class:`~pysindy_xl.PhysicalOptimizer` (rigid-body
        parameters) or anything with ``fit_catalog``; a pysindy optimizer or any regressor with
        ``fit(X, y)`` and ``coef_`` runs as ``ExplicitOptimizer(method=...)``; a kind's name
        gets that kind's default. Default: :func:`~pysindy_xl.optimizers.default_optimizer`
        (explicit when every coordinate is forced, implicit when none is, mixed otherwise;
        explicit fits from positions only bagged by an :class:`~pysindy_xl.EnsembleOptimizer`).
    differentiation_method : pysindy differentiation method, optional
        For velocities and accelerations not given (strong form). Default, by the optimizer's
        ``derivative_estimate``: ``ps.SmoothedFiniteDifference()`` for explicit and mixed fits,
        ``ps.FiniteDifference(order=4)`` (unbiased, for the null-space search) for implicit.
    formulation : {"auto", "strong", "weak"}, default "auto"
        ``"strong"``: Euler-Lagrange columns evaluated pointwise (needs accelerations).
        ``"weak"``: each equation integrated against test functions, accelerations removed by
        parts (``int phi E dt = -int phi' P dt - int phi Q dt``), fed by smoothed positions and
        velocities: robust on measured positions. ``"auto"``: strong with a
        ``differentiation_method``, or with ``x_dot`` and ``x_ddot`` and no impulse entry
        (:func:`~pysindy_xl.fit.resolve_formulation`), weak otherwise.
    test_functions : BumpTestFunctions, optional
        Weak-form test functions (default: width from the data's spectrum; unforced data:
        three widths, :data:`~pysindy_xl.fit.UNFORCED_WIDTH_MULTIPLES`).
    smoother : WhittakerSmoother, optional
        Positions and velocities for the weak form from noisy positions (default
        ``WhittakerSmoother()``, smoothness from the data). Measured ``x_dot`` is used as given.
    residual_covariance : bool or "auto", default "auto"
        Weak form on positions only: weigh the rows by the residual's covariance (overlapping
        test functions correlate them), iteratively reweighted from a pilot law
        (:func:`pysindy_xl.fit.solve`). ``"auto"``: when some coordinate is forced.
    blas_threads : int or None, default 1
        BLAS threads during ``fit`` (threadpoolctl; the fit's many tall, narrow QR
        factorizations gain little from threads). ``None`` keeps the library default.
    t_default : float, default 1.0
        Time step used when ``fit`` or ``score`` get no ``t`` (as in PySINDy).
    drop_dependent : bool, default True
        Remove catalog columns that are zero or exact linear combinations of preferred ones
        (:func:`~pysindy_xl.optimizers.independent_columns`), tested on random points of the
        data's bounding box: identities of the catalog, not the physical law.
    hold_still : float or False, default 2.0
        Coordinates that are undriven and at rest or in uniform motion up to ``hold_still``
        times their estimated noise (:mod:`pysindy_xl.fit.still`) are left out with their
        columns and held by the model (zero acceleration), as :meth:`print` says. ``False``:
        fit every coordinate.

    Attributes
    ----------
    feature_library_ : CatalogRepartition
        The fitted catalog (a clone of ``feature_library``, a force column added when absent).
    optimizer_ : fitted catalog optimizer
        The optimizer that solved the regression (a clone of ``optimizer`` or the default).
    coef_ : ndarray, shape (F,)
        One coefficient per catalog feature (:meth:`get_feature_names`), zero for the
        features left out; the identified equations are ``Theta(q, qd, qdd, tau) @ coef_ = 0``.
    dropped_features_ : dict of str to str
        Features removed before regression, with the reason.
    still_coordinates_ : list of str
        Coordinates held still (``hold_still``).
    forced_coordinates_ : ndarray of bool, shape (n,)
        Coordinates that a non-zero force drives in the data.
    dynamics_ : CatalogDynamics
        The identified equations in mass-matrix form (``None`` if they contain no acceleration).
    n_coordinates_ : int
        Number of coordinates ``n``.
    n_samples_ : int
        Samples used in the fit, all trajectories together.
    formulation_ : {"strong", "weak"}
        The formulation used (``formulation`` resolved).
    weak_info_ : dict or None
        Weak form: half-width, test functions per piece, noise estimate, ``time_grid``,
        ``gaps`` and ``segments`` (:func:`~pysindy_xl.weak.weak_regression`).
    selection_ : SelectionResult, LawSelection or None
        How the sparsity was chosen, when the optimizer reports it (None after a bagged fit:
        see ``inclusion_probability_``).
    inclusion_probability_, coef_interval_ : ndarray or None
        With an :class:`~pysindy_xl.EnsembleOptimizer`: per feature, the fraction of fits that
        include it and its coefficient's interval, shapes (F,) and (2, F).
    physical_consistency_ : dict or None
        After a :class:`~pysindy_xl.PhysicalOptimizer` fit: its ``consistency_``.
    mass_matrix_check_ : dict or None
        The identified mass matrix on (up to 2,000) training states: fraction positive
        definite and median condition number; below 1, ``fit`` warns with an
        :class:`IdentificationWarning`. A sign-free law is flipped when it is negative definite.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2, c.q[0] ** 4])
    >>> t = np.linspace(0, 10, 2001)
    >>> u = np.sin(1.3 * t)[:, None]
    >>> x = np.column_stack([np.cos(2 * t) + 0.1 * t])
    >>> xd, xdd = -2 * np.sin(2 * t)[:, None] + 0.1, -4 * np.cos(2 * t)[:, None]
    >>> model = px.XLSINDy(lib).fit(x, t, x_dot=xd, x_ddot=xdd, u=xdd + 3 * x)
    >>> model.print()
    L = -1.5*x**2 + 0.5*x_dot**2
    (x) 3.0*x + 1.0*x_ddot = tau_x
    """

    _parameter_constraints = {
        "feature_library": [None, HasMethods("feature library")],
        "optimizer": [None, Options(SOLVER_KINDS), HasMethods("optimizer")],
        "differentiation_method": [None, HasMethods("a pysindy differentiation method",
                                                    "__call__")],
        "drop_dependent": [Boolean()],
        "formulation": [Options(FORMULATIONS)],
        "test_functions": [None, HasMethods("test functions", "matrices")],
        "smoother": [None, HasMethods("a smoother", "smooth")],
        "t_default": [Interval("real", 0, low_open=True),
                      InstanceOf((np.ndarray, list, tuple), "an array of sample times")],
        "blas_threads": [None, Interval("int", 1)],
        "residual_covariance": ["auto", Boolean()],
        "hold_still": [False, Interval("real", 0)],
    }

    def __init__(self, feature_library=None, optimizer=None, differentiation_method=None,
                 drop_dependent=True, formulation="auto", test_functions=None, smoother=None,
                 t_default=1.0, blas_threads=1, residual_covariance="auto", hold_still=2.0):
        self.feature_library = feature_library
        self.optimizer = optimizer
        self.differentiation_method = differentiation_method
        self.drop_dependent = drop_dependent
        self.formulation = formulation
        self.test_functions = test_functions
        self.smoother = smoother
        self.t_default = t_default
        self.blas_threads = blas_threads
        self.residual_covariance = residual_covariance
        self.hold_still = hold_still

    def regression(self, x, t=None, x_dot=None, x_ddot=None, u=None, sample_mask=None,
                   formulation=None, propagate_noise=True) -> CatalogProblem:
        """The regression problem of the fitted model's catalog on data, built as :meth:`fit`
        builds it.

        Stacks the catalog's columns ``Theta`` on the data (:func:`~pysindy_xl.fit.build_problem`,
        without the columns of still coordinates): ``problem.theta @
        coef_[problem.catalog_map.columns]`` is zero for data that obey the identified
        equations exactly (:func:`pysindy_xl.quality.fit_quality` measures its residual).

        Parameters
        ----------
        x : array (N, n) or list of arrays
            Positions, one trajectory or several.
        t : float, array (N,) or list of arrays, optional
            Time step or sample times; default None: ``t_default``.
        x_dot, x_ddot : same layout as ``x``, optional
            Measured velocities and accelerations; default None: estimated as in :meth:`fit`.
        u : same layout as ``x``, optional
            Generalized forces; default None (unforced).
        sample_mask : bool array (N,) or list of them, optional
            ``False`` marks samples to leave out, as in :meth:`fit`; default None (all).
        formulation : {"strong", "weak"}, optional
            Default None: the fit's ``formulation_``.
        propagate_noise : bool, default True
            Weak form: propagate the noise of the positions into the rows (``row_noise``), as
            :meth:`fit` does; False leaves ``row_noise`` out (the rows are the same, built at a
            fraction of the cost).

        Returns
        -------
        CatalogProblem
            ``theta`` (rows by catalog columns), ``catalog_map`` and the row layout
            (:class:`~pysindy_xl.optimizers.CatalogProblem`).

        Examples
        --------
        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
        >>> t = np.linspace(0, 5, 501)[:, None]
        >>> x = np.sin(t) + np.sin(2.3 * t) / 2
        >>> xd, xdd = np.cos(t) + 1.15 * np.cos(2.3 * t), -np.sin(t) - 2.645 * np.sin(2.3 * t)
        >>> model = px.XLSINDy(lib).fit(x, t[:, 0], x_dot=xd, x_ddot=xdd, u=xdd + 3 * x)
        >>> problem = model.regression(x, t[:, 0], x_dot=xd, x_ddot=xdd, u=xdd + 3 * x)
        >>> residual = problem.theta @ model.coef_[problem.catalog_map.columns]
        >>> bool(np.abs(residual).max() < 1e-8)
        True
        """
        check_is_fitted(self, "coef_")
        formulation = formulation or self.formulation_ or "strong"
        if formulation not in ("strong", "weak"):
            raise ValueError(f"formulation: expected 'strong' or 'weak', got {formulation!r}")
        data = estimator_trajectories(self, x, t, x_dot, x_ddot, u, self.n_coordinates_,
                                      formulation == "strong", sample_mask)
        info = self.weak_info_ if formulation == self.formulation_ else None
        return build_problem(self.feature_library_, data, formulation,
                             test_functions=self.test_functions, smoother=self.smoother,
                             half_width=None if info is None else info["half_width"],
                             still=self._held(),
                             propagate=check_option("propagate_noise", propagate_noise, "bool"))

    def fit(self, x, t=None, x_dot=None, x_ddot=None, u=None, sample_mask=None):
        """Identify the equations of motion.

        Parameters
        ----------
        x : array (N, n) or list of arrays
            Positions, one trajectory or several.
        t : float, array (N,) or list of arrays, optional
            Time step or strictly increasing sample times, matching ``x``; default
            ``t_default``. Jittered stamps are used as they are; the weak form cuts a
            trajectory at a gap its test functions cannot span (:mod:`~pysindy_xl.weak.timegrid`).
        x_dot, x_ddot : same layout as ``x``, optional
            Measured velocities and accelerations; computed with ``differentiation_method``
            when absent.
        u : same layout as ``x``, optional
            Generalized forces (inputs); ``None`` means unforced (implicit identification).
        sample_mask : bool array (N,) or list of them, optional
            ``False`` marks samples where unmodelled forces act (contacts, limits, outliers):
            the strong form drops their rows, the weak form the test functions touching one.

        Returns
        -------
        self : XLSINDy
            The fitted estimator (fitted attributes end in ``_``; the parameters are not
            changed).
        """
        self._check_options()
        # warnings from every depth of the fit, re-emitted to point at the caller's line
        caught = []
        try:
            threads = None if self.blas_threads is None else int(self.blas_threads)
            with warnings.catch_warnings(record=True) as caught:
                with _blas_limit(threads):
                    self._fit(x, t, x_dot, x_ddot, u, sample_mask)
        finally:  # also when the fit fails: its warnings may say why
            for record in caught:
                warnings.warn(record.message, record.category, stacklevel=2)
        return self

    def _fit(self, x, t, x_dot, x_ddot, u, sample_mask):
        """check -> build -> choose the noise model -> solve -> wrap."""
        library, data, formulation = check_fit(self, x, t, x_dot, x_ddot, u, sample_mask)
        smoother = fit_smoother(self.smoother)  # the candidates' rows smooth alike
        with remembered_weak_values(library):  # the candidates' rows share its values
            problem = build_problem(library, data, formulation,
                                    test_functions=self.test_functions, smoother=smoother,
                                    hold_still=self.hold_still,
                                    drop_dependent=self.drop_dependent)
            optimizer = resolve_optimizer(self.optimizer, problem, library)
            problem, weigh = choose_noise_model(problem, library, data, optimizer,
                                                smoother, self.residual_covariance,
                                                self.test_functions)
        optimizer = solve(optimizer, problem, library, weigh=weigh)
        self._wrap(library, problem, optimizer)
        return self

    def _wrap(self, library, problem, optimizer):
        """The fitted attributes (see Attributes) from the solved ``problem``."""
        fitted = wrap(library, problem, optimizer)  # the solution in the catalog's terms
        self.feature_library_, self.optimizer_ = library, optimizer
        self.coef_, self.dynamics_ = fitted.coef, fitted.dynamics
        self.mass_matrix_check_ = fitted.mass_matrix_check
        self.dropped_features_ = fitted.dropped_features
        self.still_coordinates_ = fitted.still_coordinates
        self.forced_coordinates_ = fitted.forced_coordinates
        self.n_coordinates_, self.n_samples_ = fitted.n_coordinates, fitted.n_samples
        self.formulation_, self.weak_info_ = fitted.formulation, fitted.weak_info
        self.selection_ = fitted.selection
        self.inclusion_probability_ = fitted.inclusion_probability
        self.coef_interval_ = fitted.coef_interval
        self.physical_consistency_ = fitted.physical_consistency

    def _check_options(self):
        """Options of the estimator (``_parameter_constraints``), checked at the start of fit."""
        validate_params(self)

    def _build_dynamics(self):
        """``dynamics_`` from the fitted coefficients."""
        self.dynamics_ = catalog_dynamics(self.feature_library_, self.coef_, self._held())

    def _held(self) -> np.ndarray:
        """Mask of the coordinates held by the model (``still_coordinates_``)."""
        names = self.feature_library_.coords.names
        return np.isin(names, list(getattr(self, "still_coordinates_", ())))

    @classmethod
    def load(cls, path) -> XLSINDy:
        """Load a fitted model written by :meth:`save`.

        Parses only the restricted term grammar and the registered library and optimizer types
        (:mod:`pysindy_xl.io`): no code in the file is executed, and its size is bounded.

        Parameters
        ----------
        path : str or path-like
            A JSON file written by :meth:`save`.

        Returns
        -------
        XLSINDy
            The fitted model, with the same coefficients and equations.

        Raises
        ------
        ValueError
            When the file is invalid, saying what is wrong.

        Examples
        --------
        See :meth:`save`.
        """
        contents = read_model_file(path)
        model = cls(feature_library=contents.feature_library, optimizer=contents.optimizer,
                    **contents.settings)
        try:
            model._check_options()
        except (TypeError, ValueError) as err:
            raise invalid_model_file(path, f"settings: {err}") from None
        for name, value in contents.fitted.items():
            setattr(model, name, value)
        model._build_dynamics()
        return model
