"""XLSINDy: the estimator that identifies a mechanical system from trajectories."""

from __future__ import annotations

import warnings

import numpy as np
import threadpoolctl
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from ._validation import IdentificationWarning, check_instance, check_option
from .dynamics.fitted import DynamicsMixin
from .feature_library import remembered_weak_values
from .fit import (
    FORMULATIONS,
    build_problem,
    catalog_dynamics,
    check_fit,
    choose_noise_model,
    estimator_trajectories,
    fit_smoother,
    fitted_state,
    resolve_optimizer,
    solve,
)
from .io import invalid_model_file, read_model_file
from .optimizers import SOLVER_KINDS, CatalogProblem
from .report.inspection import InspectionMixin

__all__ = ["XLSINDy", "IdentificationWarning"]


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
        :class:`~pysindy_xl.MixedOptimizer` or anything with ``fit_catalog``; a pysindy
        optimizer (``ps.STLSQ()``, ``ps.SR3()``, ...) or any regressor with ``fit(X, y)`` and
        ``coef_`` runs as ``ExplicitOptimizer(method=...)``; the name of a kind of regression
        gets the default optimizer of that kind. Default: chosen from the data by
        :func:`~pysindy_xl.optimizers.default_optimizer`: explicit when every coordinate is
        forced, implicit when none is, mixed otherwise; explicit fits (and explicit parts)
        from positions only are bagged, ``EnsembleOptimizer(ExplicitOptimizer())``: the
        model keeps the terms that most of 20 subsample fits select, and reports inclusion
        probabilities and coefficient intervals (measured in the "Noisy data" guide). For
        parameters that rigid bodies can have (a kinematic catalog), pass
        :class:`~pysindy_xl.PhysicalOptimizer`.
    differentiation_method : pysindy differentiation method, optional
        Used for velocities and accelerations that are not given (strong form). Default, by
        the optimizer's ``derivative_estimate``: ``ps.SmoothedFiniteDifference()`` (finite
        differences after a Savitzky-Golay smoothing, robust to moderate noise, which plain
        finite differences amplify twice for accelerations) for explicit and mixed fits;
        ``ps.FiniteDifference(order=4)`` for implicit fits of unforced data, whose null-space
        search needs unbiased derivatives (the smoothing bias alone can hide the law).
    formulation : {"auto", "strong", "weak"}, default "auto"
        ``"strong"``: the Euler-Lagrange columns evaluated pointwise, which needs
        accelerations. ``"weak"``: each equation integrated against test functions, with the
        accelerations removed by integration by parts (``int phi E dt = -int phi' P dt -
        int phi Q dt``, see :meth:`SymbolicLibrary.weak_transform
        <pysindy_xl.feature_library.SymbolicLibrary.weak_transform>`), fed by smoothed
        positions and velocities: the robust choice for measured positions. ``"auto"``: strong
        when a ``differentiation_method`` is set, or when ``x_dot`` and ``x_ddot`` are given
        and no entry is an impulse (an acceleration with a switching coefficient, such as
        MuJoCo's dry friction's lead; :func:`~pysindy_xl.fit.resolve_formulation`), weak
        otherwise.
    test_functions : BumpTestFunctions, optional
        Test functions of the weak formulation (default: bumps whose width comes from the
        data's spectrum; on unforced data bumps of three widths,
        :data:`~pysindy_xl.fit.UNFORCED_WIDTH_MULTIPLES`).
    smoother : WhittakerSmoother, optional
        Estimates positions and velocities for the weak formulation from noisy positions
        (default ``WhittakerSmoother()``: smoothness chosen from the data). Measured
        ``x_dot`` is used as given.
    residual_covariance : bool or "auto", default "auto"
        Weak formulation on positions only (the smoother estimated the noise, no ``x_dot``):
        weigh the rows by the covariance of the residual, generalized least squares
        iteratively reweighted from a pilot law (:func:`pysindy_xl.fit.solve`; the rows of
        overlapping test functions are correlated). ``"auto"``: when some coordinate is
        forced, where the weighting finds more exact laws (on unforced data it finds fewer:
        the "Noisy data" guide has the figures). ``False``: one fit of the rows as they are.
    blas_threads : int or None, default 1
        BLAS threads during ``fit`` (threadpoolctl). The fit's linear algebra is many QR
        factorizations of tall, narrow matrices, where threads mostly compete (measured in
        ``benchmarks/blas_threads.py``). ``None`` keeps the library default.
    t_default : float, default 1.0
        Time step used when ``fit`` or ``score`` get no ``t`` (as in PySINDy).
    drop_dependent : bool, default True
        Remove catalog columns that are zero or exact linear combinations of preferred columns
        (see :func:`~pysindy_xl.optimizers.independent_columns`): a sparse regression on an
        exactly rank-deficient matrix is a lottery. The test runs on random points of the
        data's bounding box, so it finds identities of the catalog, not the physical law.
    hold_still : float or False, default 2.0
        Leave out of the regression the coordinates that hold still in the data: undriven,
        and on every trajectory at rest or in uniform motion up to ``hold_still`` times the
        noise level estimated from the positions (the standard deviation of their departure
        from a straight line in time); see :mod:`pysindy_xl.fit.still` for the criterion.
        Their equations and the catalog columns that involve their motion (or only their
        positions) are removed, the other coordinates are identified as if they were
        absent, and the model holds them (zero acceleration), saying so in :meth:`print`.
        ``False``: every coordinate is fitted (a constant coordinate is then an error).

    Attributes
    ----------
    feature_library_ : CatalogRepartition
    optimizer_ : fitted catalog optimizer
    coef_ : ndarray, shape (F,)
    dropped_features_ : dict of str to str
        Features removed before regression, with the reason.
    still_coordinates_ : list of str
        Coordinates that held still in the data (``hold_still``): left out of the regression
        and held by the model (zero acceleration).
    dynamics_ : CatalogDynamics
        The identified equations in mass-matrix form (``None`` if they contain no acceleration).
    n_coordinates_ : int
    n_samples_ : int
        Samples used in the fit, all trajectories together.
    formulation_ : {"strong", "weak"}
        The formulation used.
    weak_info_ : dict or None
        Weak formulation: test-function half-width (s), test functions per piece, the
        smoother's noise estimate per coordinate (first piece), the time grid (``time_grid``:
        uniform or not, median, smallest and largest step), the gaps the trajectories were
        cut at (``gaps``: trajectory, time, length) and each piece's trajectory
        (``segments``); see :func:`~pysindy_xl.weak.weak_regression`.
    selection_ : SelectionResult, LawSelection or None
        How the sparsity was chosen, when the optimizer reports it (``threshold="auto"``;
        an unforced law selected from noisy data by its noise ratio). None after a bagged
        fit (the default for forced positions-only data), where no single selection made the
        model: see ``inclusion_probability_``.
    inclusion_probability_, coef_interval_ : ndarray or None
        With an :class:`~pysindy_xl.EnsembleOptimizer`: per catalog feature, the fraction of
        the ensemble's fits that include it and the interval of its coefficient,
        shapes (F,) and (2, F); ``print(uncertainty=True)`` shows them.
    physical_consistency_ : dict or None
        After a physically constrained fit (:class:`~pysindy_xl.PhysicalOptimizer`): whether
        the unconstrained estimate was consistent, what the constraints cost, the features
        whose friction came out negative (see ``PhysicalOptimizer.consistency_``).
    mass_matrix_check_ : dict or None
        The identified mass matrix on (up to 2,000 of) the training states: fraction where it
        is positive definite and median condition number. Below 1, ``fit`` warns with an
        :class:`IdentificationWarning` naming coordinates without positive inertia. A law that
        no force scales (sign free) is flipped when its mass matrix is negative definite.

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
                   formulation=None) -> CatalogProblem:
        """The catalog problem of the fitted model on data, built as :meth:`fit` builds it
        (:func:`~pysindy_xl.fit.build_problem`, every catalog column but those of the
        coordinates held still).

        ``problem.theta @ coef_[problem.catalog_map.columns]`` is zero for data that obey the
        identified equations exactly (the fit-quality report of
        :func:`pysindy_xl.quality.fit_quality` is made of it).

        Parameters
        ----------
        x, t, x_dot, x_ddot, u, sample_mask
            As in :meth:`fit`.
        formulation : {"strong", "weak"}, optional
            Default: the fit's; the weak form uses the fit's test-function width.

        Returns
        -------
        CatalogProblem
            With its ``catalog_map`` (:class:`~pysindy_xl.fit.CatalogMap`).
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
                             still=self._held())

    # -- fit ---------------------------------------------------------------------------------
    def fit(self, x, t=None, x_dot=None, x_ddot=None, u=None, sample_mask=None):
        """Identify the equations of motion.

        Parameters
        ----------
        x : array (N, n) or list of arrays
            Positions, one trajectory or several.
        t : float, array (N,) or list of arrays, optional
            Time step or sample times (strictly increasing), matching ``x``; default
            ``t_default``. Stamps as a logger wrote them (jittered, with gaps) are used as
            they are: the weak form smooths, integrates and propagates the noise on the
            actual times and cuts a trajectory at a gap its test functions cannot span
            (:mod:`~pysindy_xl.weak.timegrid`; recorded in ``weak_info_``); a repeated stamp
            raises a ``ValueError`` naming it.
        x_dot, x_ddot : same layout as ``x``, optional
            Measured velocities and accelerations; computed with ``differentiation_method``
            when absent.
        u : same layout as ``x``, optional
            Generalized forces (inputs); ``None`` means unforced (implicit identification).
        sample_mask : bool array (N,) or list of them, optional
            Samples the equations must explain (``True``); ``False`` marks samples where
            unmodelled forces act (contacts, joint limits, outliers). The strong form drops
            their rows; the weak form drops every test function whose support touches one.
            Differentiation and smoothing still use the whole trajectory.

        Returns
        -------
        self
        """
        self._check_options()
        # The warnings of the fit come from several depths (libraries, smoother, optimizers,
        # ensembles); recorded here and re-emitted, they all point at the caller's line. The
        # caller's filters still apply inside ("error" raises where the warning arises).
        caught = []
        try:
            threads = None if self.blas_threads is None else int(self.blas_threads)
            with warnings.catch_warnings(record=True) as caught:
                with threadpoolctl.threadpool_limits(limits=threads, user_api="blas"):
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
        for name, value in fitted_state(library, problem, optimizer).items():  # wrap
            setattr(self, name, value)
        return self

    def _check_options(self):
        """Options of the estimator, checked at the start of fit (one layer: _validation)."""
        check_option("drop_dependent", self.drop_dependent, "bool")
        if self.hold_still is not False:  # a threshold; True is refused (not a number)
            check_option("hold_still", self.hold_still, "real", low=0)
        value = self.residual_covariance
        if not (isinstance(value, (bool, np.bool_)) or (isinstance(value, str)
                                                          and value == "auto")):
            raise TypeError("residual_covariance: expected True, False or 'auto', got the "
                            f"{type(value).__name__} {value!r}")
        if self.blas_threads is not None:
            check_option("blas_threads", self.blas_threads, "int", low=1)
        check_option("formulation", self.formulation, "choice", choices=FORMULATIONS)
        if np.ndim(self.t_default) == 0:
            check_option("t_default", self.t_default, "real", low=0, low_open=True)
        for name, what, method in (("differentiation_method", "a pysindy differentiation "
                                    "method", "__call__"),
                                   ("smoother", "a smoother", "smooth"),
                                   ("test_functions", "test functions", "matrices")):
            value = getattr(self, name)
            if value is not None:
                check_instance(name, value, what, method)
        if isinstance(self.optimizer, str):
            check_option("optimizer", self.optimizer, "choice", choices=SOLVER_KINDS)
        for name in ("feature_library", "optimizer"):
            value = getattr(self, name)
            if isinstance(value, type):
                check_instance(name, value, name.replace("_", " "))

    def _build_dynamics(self):
        """``dynamics_`` from the fitted coefficients
        (:func:`~pysindy_xl.fit.wrap.catalog_dynamics`)."""
        self.dynamics_ = catalog_dynamics(self.feature_library_, self.coef_, self._held())

    def _held(self) -> np.ndarray:
        """Mask of the coordinates held by the model (``still_coordinates_``)."""
        names = self.feature_library_.coords.names
        return np.isin(names, list(getattr(self, "still_coordinates_", ())))

    # -- persistence ---------------------------------------------------------------------------
    @classmethod
    def load(cls, path) -> XLSINDy:
        """Load a model written by :meth:`save`; parses only the restricted term grammar and
        the registered library and optimizer types (:mod:`pysindy_xl.io`).

        Parameters
        ----------
        path : str or os.PathLike

        Returns
        -------
        XLSINDy
            A fitted model that predicts and simulates like the saved one.

        Raises
        ------
        ValueError
            If the file is not a valid model file (the message says what is wrong).
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
