"""Implicit regression of unforced systems: SINDy-PI's constrained problem and homothetic-column
clustering (:class:`ImplicitOptimizer`).
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import scipy.sparse.csgraph
from sklearn.exceptions import ConvergenceWarning

from .._validation import Boolean, InstanceOf, Interval, Options, validate_params
from ._base import CatalogOptimizer, coordinates_touched, warn_unexplained
from ._sindy_pi import extract_laws, homothetic_groups, null_space_start, solve_cvxpy
from ._sparse import column_norms, lasso_gram, null_vector, triangular_factor
from .homogeneous import select_laws
from .laws import UndeterminedLawWarning, combine_laws, normalize_law
from .noise_ratio import noise_ratio_law
from .problem import CatalogProblem

__all__ = ["ImplicitOptimizer", "NoLawFoundError", "coordinates_touched", "homothetic_groups"]

_SOLVERS = ("fista", "cvxpy")

#: Early stopping: iterations between two extractions of the laws in the first _PROBE_ITER
#: iterations (exact laws settle there), and after them (the solve restarted).
_LAW_CHECK_EVERY = 10
#: A law holds to the noise when its held-out noise ratio is at most ``_HOLDS_RATIO`` (a noise
#: estimate off by up to 2x), or within two standard errors of 1 and at most
#: ``_FOLD_SPREAD_RATIO``: the standard error tolerates the folds' variation about a law near
#: the noise, not a residual ten times the noise power whose folds vary wildly (a misfit
#: localized in some blocks, or clean data: ``4e12 +- 2e12`` is no evidence of holding).
_HOLDS_RATIO = 2.0
_FOLD_SPREAD_RATIO = 10.0
#: A law this exact (mean held-out relative squared residual) holds on clean data, whatever
#: its noise ratio (no noise to measure it against).
_EXACT_RELATIVE = 1e-8
_PROBE_ITER = 50
_LAW_CHECK_EVERY_LONG = 100


class NoLawFoundError(RuntimeError):
    """Implicit regression found no sparse law in the regression matrix.

    A ``RuntimeError``: the data do not single out a law (too short, too noisy, or a catalog
    that cannot express the dynamics).

    Examples
    --------
    >>> import pysindy_xl as px
    >>> issubclass(px.NoLawFoundError, RuntimeError)
    True
    """


class ImplicitOptimizer(CatalogOptimizer):
    """SINDy-PI constrained regression with homothetic-column clustering (unforced systems).

    Every column of the normalized ``Theta~ = Theta D^-1`` is regressed on the others,

        min_X  1/2 ||Theta~ X - Theta~||_F^2 + alpha ||X||_1   s.t.  diag(X) = 0,        (1)

    so the columns j of a law ``xi`` give one direction ``v_j = e_j - X[:, j]`` up to scale,
    the others unrelated dense ones. Homothetic directions are grouped, each group's principal
    direction refit on its support (pruned with ``threshold``), the qualifying laws normalized
    (:func:`~pysindy_xl.optimizers.laws.normalize_law`) and those of disjoint supports summed
    into ``coef_``. ``"fista"`` solves the per-column Lassos of (1) at once from the near-null
    space (:func:`~pysindy_xl.optimizers._sparse.lasso_gram`), ``"cvxpy"`` solves (1) on the
    triangular factor of ``Theta~``. Given the columns' noise moments, the laws are instead
    selected by held-out noise ratio (:func:`~pysindy_xl.optimizers.select_law`), which prefers
    laws that hold over laws on quiet columns; the SINDy-PI attributes are then not set.

    Parameters
    ----------
    alpha : float or "auto", default "auto"
        L1 weight of (1) on unit-norm columns. ``"auto"``: ``s_1 s_2`` (the two smallest singular
        values of the normalized matrix, between the law's and the next-best residual),
        clipped to ``[1e-12, 1e-3]``; stored in ``alpha_``.
    solver : {"fista", "cvxpy"}, default "fista"
        The solver of (1): the fast per-column Lassos or cvxpy.
    cvxpy_solver : str, optional
        Passed to ``cvxpy.Problem.solve``; default: cvxpy's choice.
    angle_tol : float, default 5.0
        Angular tolerance (degrees) of the homothetic grouping.
    min_group_size : int, default 2
        Smallest group that can be a law.
    min_membership : float, default 0.1
        Smallest fraction of a law's terms that must be members of its group.
    max_residual_ratio : float, default 10.0
        Laws whose relative residual exceeds this many times the best law's are rejected (in
        noise-ratio mode: further laws whose ratio does).
    threshold : float, default 1e-3
        Relative contribution below which a term is pruned in the refit.
    refit : bool, default True
        Refit each law on its support (else keep the group's principal direction).
    tol : float, default 1e-4
        Relative optimality tolerance of the fast solver.
    max_iter : int, default 20000
        Iteration budget of the fast solver.
    early_stopping : bool, default True
        Fast solver: stop once the laws are the same at two checks and their columns converged.

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
        Combined law.
    solution_matrix_, normalized_solution_matrix_ : ndarray, shape (F, F)
        SINDy-PI solution ``X`` in the original units and on unit-norm columns (``D X D^-1``).
    column_norms_ : ndarray, shape (F,)
        Norms of the columns after the coordinate blocks are balanced.
    column_residuals_ : ndarray, shape (F,)
        ``||Theta~ v_j|| / ||v_j||`` of each column's direction (inf for zero columns).
    groups_ : list of ndarray of int
        Homothetic groups of at least ``min_group_size`` columns.
    laws_ : ndarray, shape (n_laws, F)
        Accepted laws, normalized, best first.
    law_groups_ : list of ndarray of int
        The columns of each homothetic group that became a law.
    law_residuals_ : ndarray, shape (n_laws,)
        Relative residual of each law.
    combined_laws_ : list of int
        Indices of the laws summed into ``coef_``.
    alpha_ : float
        The L1 weight used.
    n_iter_ : int
        Iterations of the fast solver (0 for cvxpy).
    converged_ : bool
        Whether the fast solver converged.
    column_converged_ : ndarray of bool, shape (F,)
        Per column, whether its Lasso converged.
    selection_method_ : {"sindy-pi", "noise ratio", "given support"}
        How the law was chosen.
    selection_, law_selections_ : LawSelection, list of LawSelection
        Noise-ratio mode: how the first law's (every law's) support was chosen.
    law_noise_ratios_ : ndarray, shape (n_laws,)
        Noise-ratio mode: each law's noise ratio (about 1 when it holds to the noise).
    undetermined_ : ndarray, shape (k, F)
        Noise-ratio mode: rival laws the data hold as well as the first; an
        :class:`~pysindy_xl.optimizers.UndeterminedLawWarning` names their terms.
    law_holds_ : bool
        Noise-ratio mode: the first law is admissible and holds to the noise: its held-out noise
        ratio is at most 2, or within two standard errors of 1 and at most 10, or its held-out
        relative squared residual is below 1e-8 (exact, clean data).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> rng = np.random.default_rng(0)
    >>> a, b, c = rng.normal(size=(3, 200))
    >>> theta = np.column_stack([a, b, 2 * a - 0.5 * b, c])   # law: col2 - 2 a + 0.5 b = 0
    >>> opt = px.ImplicitOptimizer().fit(theta)
    >>> opt.coef_.round(6), [g.tolist() for g in opt.law_groups_]
    (array([-2. ,  0.5,  1. ,  0. ]), [[0, 1, 2]])
    """

    spec_type = "ImplicitOptimizer"

    def catalog_tags(self):
        """What this optimizer can do and needs.

        It uses the columns' mass matrices and noise draws and wants unbiased derivatives
        (``derivative_estimate``).

        Returns
        -------
        CatalogTags
            The tags (:class:`~pysindy_xl.optimizers.tags.CatalogTags`): ``requires_forces``,
            ``can_refit``, ``balances_rows``, ``derivative_estimate``, ...
        """
        return dataclasses.replace(super().catalog_tags(), uses_mass_matrices=True,
                                   uses_noise_draws=True, derivative_estimate="unbiased")

    _parameter_constraints = {
        "alpha": ["auto", Interval("real", 0, low_open=True)],
        "solver": [Options(_SOLVERS)],
        "cvxpy_solver": [None, InstanceOf(str, "a cvxpy solver name")],
        "angle_tol": [Interval("real", 0, 90, low_open=True, high_open=True)],
        "min_group_size": [Interval("int", 1)],
        "min_membership": [Interval("real", 0, 1)],
        "max_residual_ratio": [Interval("real", 1, allow_inf=True)],
        "threshold": [Interval("real", 0, 1, high_open=True)],
        "refit": [Boolean()],
        "tol": [Interval("real", 0, low_open=True)],
        "max_iter": [Interval("int", 1)],
        "early_stopping": [Boolean()],
    }

    def __init__(self, alpha="auto", solver="fista", cvxpy_solver=None, angle_tol=5.0,
                 min_group_size=2, min_membership=0.1, max_residual_ratio=10.0, threshold=1e-3,
                 refit=True, tol=1e-4, max_iter=20_000, early_stopping=True):
        self.alpha = alpha
        self.solver = solver
        self.cvxpy_solver = cvxpy_solver
        self.angle_tol = angle_tol
        self.min_group_size = min_group_size
        self.min_membership = min_membership
        self.max_residual_ratio = max_residual_ratio
        self.threshold = threshold
        self.refit = refit
        self.tol = tol
        self.max_iter = max_iter
        self.early_stopping = early_stopping

    def _check_params(self):
        validate_params(self)

    def fit(self, X, y=None):
        """Find the sparse laws ``X @ xi = 0`` of a regression matrix.

        Parameters
        ----------
        X : array, shape (n_rows, F)
            Regression matrix (one block, no force column).
        y : None
            Ignored.

        Returns
        -------
        self
        """
        problem = CatalogProblem.from_arrays(X, 1, [])
        self._fit(problem.theta, 1, problem.force_columns, None)
        self.n_features_in_ = problem.n_features
        return self

    def _solve(self, problem):
        """Problem (1), or with noise moments the noise-ratio selection (laws with a mass matrix
        indefinite at the states are avoided); zero force columns are ignored, others fix the scale.
        """
        theta, n = problem.theta, problem.n_coordinates
        if problem.noise_moments is None:
            self._fit(theta, n, problem.force_columns, problem.reference_columns)
        else:
            self._fit_noisy(theta, n, problem.force_columns, problem.reference_columns,
                            problem.noise_moments, problem.mass_matrices, problem.noise_draws)
        warn_unexplained("ImplicitOptimizer", theta, n, self.coef_, problem.force_columns)
        return self

    def _solve_support(self, problem, support):
        """The laws on a given support, nothing selected: one per group of columns sharing
        coordinates, fitted on every row (smallest noise ratio, or smallest right singular vector),
        normalized and summed. The ensemble's refit.
        """
        theta, n_coordinates = problem.theta, problem.n_coordinates
        force_columns = problem.force_columns
        norms, nonzero = column_norms(theta)
        columns = np.flatnonzero(support & nonzero)
        moments = problem.pooled_moments()
        if columns.size < 2:
            raise NoLawFoundError(f"support: {columns.size} non-zero column(s) given; a law "
                                  "needs at least two terms")
        touches = coordinates_touched(theta[:, columns], n_coordinates).astype(int)
        _, labels = scipy.sparse.csgraph.connected_components(touches.T @ touches, directed=False)
        laws, ratios = [], []
        for label in np.unique(labels):
            group = columns[labels == label]
            if group.size < 2:  # one column alone is a law only where it vanishes
                continue
            law = np.zeros(theta.shape[1])
            if moments is None:
                law[group] = null_vector(theta[:, group] / norms[group])[0] / norms[group]
                ratios.append(np.nan)
            else:
                ratio, law[group] = noise_ratio_law(triangular_factor(theta[:, group]),
                                                    moments[np.ix_(group, group)])
                ratios.append(ratio)
            laws.append(law)
        if not laws:
            raise NoLawFoundError(f"support: no two non-zero columns of {columns.tolist()} "
                                  "share a coordinate; a law needs at least two terms")
        self.selection_method_ = "given support"
        self.selection_ = None
        self.column_norms_ = norms
        self.law_noise_ratios_ = None if moments is None else np.asarray(ratios)
        self._set_selected_laws(theta, laws, norms, force_columns, None)
        warn_unexplained("ImplicitOptimizer", theta, n_coordinates, self.coef_, force_columns)
        return self

    def _set_selected_laws(self, theta, laws, norms, force_columns, reference_columns):
        """:meth:`_set_laws`, with the laws' residuals (as for problem (1)) and supports."""
        self.law_residuals_ = np.array([
            np.linalg.norm(theta @ law) / np.linalg.norm(law * norms) for law in laws])
        self.law_groups_ = [np.flatnonzero(law) for law in laws]
        self._set_laws(laws, norms, force_columns, reference_columns)

    def _set_laws(self, laws, norms, force_columns, reference_columns):
        """``laws_`` normalized and their disjoint sum ``coef_``."""
        self.laws_ = np.array([normalize_law(law, norms, force_columns, reference_columns)
                               for law in laws])
        self.coef_, self.combined_laws_ = combine_laws(self.laws_)

    def _fit_noisy(self, theta, n_coordinates, force_columns, reference_columns, moments,
                   mass_matrices, draws=None):
        """Laws selected by held-out noise ratio, one per group of coordinates they explain."""
        self._check_params()
        self.selection_method_ = "noise ratio"
        norms = column_norms(theta)[0]
        self.column_norms_ = norms
        laws, ratios, selections = select_laws(theta, moments, n_coordinates, mass_matrices,
                                               self.max_residual_ratio, draws)
        if not laws:
            raise NoLawFoundError("ImplicitOptimizer: no law could be selected from the noisy "
                                  "columns (too few non-zero columns or rows for cross-validation)")
        self.selection_ = selections[0]
        self.law_selections_ = selections
        self.law_noise_ratios_ = np.asarray(ratios)
        self._set_selected_laws(theta, laws, norms, force_columns, reference_columns)
        self._report_rivals(theta, moments, selections[0], laws[0], norms,
                            force_columns, reference_columns)
        return self

    def _report_rivals(self, theta, moments, selection, law, norms, force_columns,
                       reference_columns):
        """Set ``undetermined_`` (rival laws, normalized) and ``law_holds_`` (admissible and
        :func:`_holds_to_noise`), warning when the law is undetermined or not found.
        """
        size = selection.size
        ratio, spread = selection.cv_ratio[size - 1], selection.cv_spread[size - 1]
        holds = _holds_to_noise(ratio, spread, selection.cv_relative)
        self.law_holds_ = bool(selection.admissible and holds)
        if not self.law_holds_:
            reason = ("its mass matrix is not definite on the states or it leaves a coordinate "
                      "unexplained" if not selection.admissible else
                      f"its held-out noise ratio is {ratio:.3g} +- {spread:.2g} (about 1 for a "
                      "law that holds)")
            warnings.warn("ImplicitOptimizer: no law that holds to the noise was found in the "
                          f"catalog ({reason}); the returned law is the best found, not a "
                          "determined one. Record more trajectories, reduce the noise or force a "
                          "coordinate.", UndeterminedLawWarning, stacklevel=4)
        pooled = moments.sum(axis=0)
        found = []
        for support in selection.rivals:
            rival = np.zeros(theta.shape[1])
            rival[support] = noise_ratio_law(triangular_factor(theta[:, support]),
                                             pooled[np.ix_(support, support)])[1]
            found.append(normalize_law(rival, norms, force_columns, reference_columns))
        self.undetermined_ = np.array(found).reshape(len(found), theta.shape[1])
        if found:
            differ = sorted({int(j) for rival in found
                             for j in np.flatnonzero((rival != 0) != (law != 0))})
            warnings.warn(
                f"ImplicitOptimizer: the data hold {len(found)} other law(s) with different "
                "terms as well as the chosen one (held-out noise ratio within its standard "
                f"error): the terms {differ} (columns of the problem) are undetermined, see "
                "undetermined_. Record trajectories at more energy levels, reduce the noise "
                "or force a coordinate.", UndeterminedLawWarning, stacklevel=4)

    def _fit(self, theta, n_coordinates, force_columns, reference_columns):
        self._check_params()
        self.selection_method_ = "sindy-pi"
        n_features = theta.shape[1]
        norms, nonzero = column_norms(theta)
        active = np.flatnonzero(nonzero)
        if active.size < 2:
            raise NoLawFoundError(f"theta: {active.size} non-zero column(s); implicit regression "
                                  "needs at least 2")
        scaled = (theta if active.size == n_features else theta[:, active]) / norms[active]
        r_factor = triangular_factor(scaled)
        x_scaled = self._sindy_pi_matrix(r_factor)

        self.column_norms_ = norms
        self.normalized_solution_matrix_ = np.zeros((n_features, n_features))
        self.normalized_solution_matrix_[np.ix_(active, active)] = x_scaled
        self.solution_matrix_ = np.zeros((n_features, n_features))
        self.solution_matrix_[np.ix_(active, active)] = (x_scaled * norms[active][None, :]
                                                         / norms[active][:, None])
        converged = np.zeros(n_features, dtype=bool)
        converged[active] = self._column_converged
        self.column_converged_ = converged

        residuals, groups, laws, law_groups, law_residuals = self._post_process(x_scaled, r_factor)
        self.column_residuals_ = np.full(n_features, np.inf)
        self.column_residuals_[active] = residuals
        self.groups_ = [active[g] for g in groups]
        if not laws:
            raise NoLawFoundError(
                "ImplicitOptimizer: no group of homothetic columns qualifies as a law "
                f"({len(groups)} group(s) of >= {self.min_group_size} columns). Try a smaller "
                "alpha, a larger angle_tol, or check that the catalog can express the dynamics.")
        full_laws = np.zeros((len(laws), n_features))
        full_laws[:, active] = np.array(laws) / norms[active]
        self.law_groups_ = [active[g] for g in law_groups]
        self.law_residuals_ = np.asarray(law_residuals)
        self._set_laws(full_laws, norms, force_columns, reference_columns)
        return self

    def plot(self, feature_names=None, axes=None):
        """The paper's Figure 2: ``|normalized_solution_matrix_|`` (A), the unit directions of each
        law's group (B), ``coef_`` (C).

        Parameters
        ----------
        feature_names : list of str, optional
            Labels of the catalog columns.
        axes : sequence of 3 matplotlib Axes, optional
            Default: a new figure.

        Returns
        -------
        list of matplotlib.axes.Axes
        """
        import matplotlib.pyplot as plt
        from sklearn.utils.validation import check_is_fitted

        check_is_fitted(self, "coef_")
        if self.selection_method_ != "sindy-pi":
            raise ValueError("plot: the laws were selected by noise ratio (noise moments were "
                             "given), there is no SINDy-PI solution matrix to draw; see selection_ "
                             "instead")
        if axes is None:
            _, axes = plt.subplots(1, 3, figsize=(15, 4.5), constrained_layout=True)
        x = np.abs(self.normalized_solution_matrix_)
        floor = max(x.max(initial=0.0) * 1e-8, 1e-300)
        image = axes[0].imshow(np.log10(np.maximum(x, floor)), cmap="viridis")
        axes[0].set(title="A: |X| (SINDy-PI solution, log10)", xlabel="column j", ylabel="feature")
        plt.colorbar(image, ax=axes[0], shrink=0.8)
        directions = np.eye(x.shape[0]) - self.normalized_solution_matrix_
        for k, group in enumerate(self.law_groups_):
            for j in group:
                d = directions[:, j] / np.linalg.norm(directions[:, j])
                d = d * np.sign(d[np.argmax(np.abs(d))])
                axes[1].plot(d, color=f"C{k}", alpha=0.6, label=f"law {k}" if j == group[0]
                             else None)
        axes[1].set(title="B: homothetic columns of each law", xlabel="feature",
                    ylabel="unit direction")
        axes[1].legend()
        axes[2].bar(np.arange(self.coef_.size), self.coef_, color="C3")
        axes[2].set(title="C: extracted law (coef_)", xlabel="feature", ylabel="coefficient")
        if feature_names is not None:
            for ax in axes[1:]:
                ax.set_xticks(np.arange(len(feature_names)), feature_names, rotation=90, fontsize=6)
        return list(axes)

    def _post_process(self, x_scaled, r_factor):
        """Column residuals, homothetic groups and laws (best first), in the normalized space."""
        directions = np.eye(x_scaled.shape[0]) - x_scaled
        residuals = (np.linalg.norm(r_factor @ directions, axis=0)
                     / np.linalg.norm(directions, axis=0))
        order = np.argsort(residuals, kind="stable")
        groups = homothetic_groups(directions, self.angle_tol, order)
        groups = [g for g in groups if g.size >= self.min_group_size]
        laws, law_groups, law_residuals = extract_laws(
            directions, groups, r_factor, refit=self.refit, threshold=self.threshold,
            min_membership=self.min_membership, max_residual_ratio=self.max_residual_ratio,
            angle_tol=self.angle_tol)
        return residuals, groups, laws, law_groups, law_residuals

    def _sindy_pi_matrix(self, r_factor):
        n = r_factor.shape[1]
        self.alpha_ = self._resolve_alpha(r_factor)
        if self.solver == "cvxpy":
            self.n_iter_ = 0
            solution, converged = solve_cvxpy(r_factor, self.alpha_, self.cvxpy_solver)
            self.converged_ = converged
            self._column_converged = np.full(n, converged)
            return solution
        gram = r_factor.T @ r_factor
        mask = ~np.eye(n, dtype=bool)
        state = {"signature": None, "stable": False}

        def laws_settled(coef, converged):
            # stable laws whose columns converged: the other columns cannot change them
            _, _, laws, law_groups, _ = self._post_process(coef, r_factor)
            if not laws:
                state["signature"] = None
                return False
            members = np.concatenate(law_groups)
            signature = tuple(tuple(np.flatnonzero(law)) for law in laws)
            settled = signature == state["signature"] and bool(np.all(converged[members]))
            state["signature"] = signature
            state["stable"] = settled
            return settled

        start = null_space_start(r_factor)

        def run(max_iter, callback, every=_LAW_CHECK_EVERY):
            return lasso_gram(gram, gram, self.alpha_, mask=mask, coef_init=start, tol=self.tol,
                              max_iter=max_iter, warn=False, callback=callback,
                              callback_every=every)

        if not self.early_stopping:
            result = run(int(self.max_iter), None)
            self.n_iter_ = result.n_iter
        else:
            # a short probe ends on exact laws (read off the start); otherwise start over,
            # extracting the laws (a clustering of all columns) less often
            result = run(min(_PROBE_ITER, int(self.max_iter)), laws_settled)
            self.n_iter_ = result.n_iter
            if not (state["stable"] or np.all(result.converged)):
                state.update(signature=None, stable=False)
                result = run(int(self.max_iter), laws_settled, _LAW_CHECK_EVERY_LONG)
                self.n_iter_ += result.n_iter
        self._column_converged = result.converged
        self.converged_ = bool(np.all(result.converged) or state["stable"])
        if not self.converged_:
            warnings.warn(
                f"ImplicitOptimizer: the fast solver did not converge on "
                f"{int(np.sum(~result.converged))} of {n} columns in {self.max_iter} iterations "
                f"(largest optimality violation {np.max(result.violation) / self.alpha_:.2e} x "
                "alpha); raise max_iter or alpha", ConvergenceWarning, stacklevel=4)
        return result.coef

    def _resolve_alpha(self, r_factor):
        if not isinstance(self.alpha, str):
            return float(self.alpha)
        singular = np.linalg.svd(r_factor, compute_uv=False)
        singular = np.concatenate([singular, np.zeros(r_factor.shape[1] - singular.size)])
        smallest, second = singular[-1], singular[-2]
        return float(np.clip(smallest * second / singular[0] ** 2, 1e-12, 1e-3))


def _holds_to_noise(ratio, spread, relative) -> bool:
    """Whether a law of held-out noise ratio ``ratio +- spread`` (mean and standard error over
    the folds) and mean held-out relative squared residual ``relative`` holds to the noise:
    ``ratio <= 2``, or ``ratio - 2 spread <= 1`` with ``ratio <= 10``, or ``relative < 1e-8``
    (exact on clean data)."""
    within_folds = ratio - 2 * spread <= 1 and ratio <= _FOLD_SPREAD_RATIO
    return bool(ratio <= _HOLDS_RATIO or within_folds or relative < _EXACT_RELATIVE)
