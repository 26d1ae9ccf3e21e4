"""Implicit regression: SINDy-PI's constrained problem and homothetic-column clustering.

Without a known force there is no left-hand side: we look for sparse ``xi`` with
``Theta @ xi = 0``. Following SINDy-PI, every column is regressed on all the others,

    min_X  1/2 ||Theta~ X - Theta~||_F^2 + alpha ||X||_1   s.t.  diag(X) = 0,        (1)

on the column-normalized matrix ``Theta~ = Theta D^-1`` (``D`` = column norms, so ``alpha`` is
scale free). If ``xi`` is a law and column j belongs to it (``xi_j != 0``), column j of the
solution is ``-xi / xi_j`` (diagonal entry removed): all the columns of a law's support give the
same direction ``v_j = e_j - X[:, j]`` up to scale. Columns that belong to no law give unrelated,
dense directions. The post-processing of the paper therefore groups the ``v_j`` that are
homothetic (within an angular tolerance), keeps the groups that look like laws and takes each
group's principal direction (SVD).

Solvers
-------
The squared Frobenius loss of (1) separates into one Lasso per column, all sharing the Gram
matrix ``G = Theta~^T Theta~``::

    column j:  min_x 1/2 x^T G x - G[:, j]^T x + alpha ||x||_1,   x_j = 0.

``solver="fista"`` (default) solves the F problems at once with accelerated proximal gradient
on ``G`` (:func:`pysindy_xl.optimizers._sparse.lasso_gram`: one matrix-matrix product per
iteration, the diagonal constraint as a mask, a continuation path on alpha, an exact finish on
the detected support). Two things exploit the implicit structure: the columns of a law start
from their exact representation read off the near-null space of ``Theta~`` (an SVD of the
``F x F`` factor below), so they only have to absorb the L1 shrinkage; and with
``early_stopping`` the iterations stop once the extracted laws are stable and every column of
their groups has converged, leaving the columns that belong to no law (whose ill-conditioned
Lasso problems are the slow ones, and which cannot be homothetic to a law: a column's own
entry is 1 in its direction and 0 in any law without it) possibly inexact (see
``column_converged_``). ``solver="cvxpy"`` hands the same problem (1), written with the
triangular factor ``R`` of ``Theta~ = Q R`` (``||Theta~ X - Theta~|| = ||R X - R||``, so the
size does not grow with the number of samples), to a conic solver. Both minimize the same
objective, so up to solver tolerance (and early stopping) they return the same law columns and
the same laws; the tests check that they recover the same support.

The paper writes the loss unsquared, ``||Theta X - Theta||_F``; its optimality conditions are
those of (1) with ``alpha`` replaced by ``alpha * ||Theta X* - Theta||_F``, so it traces the
same family of solutions with a rescaled weight.

Normalization of the laws
-------------------------
A law is defined up to a factor: a force column in its support gets ``-1`` (the explicit
convention ``EL(L) + friction = tau``), else its dominant term ``+1``
(:func:`~pysindy_xl.optimizers.laws.normalize_law`). Laws of decoupled subsystems live on
disjoint supports: ``coef_`` is their sum (:func:`~pysindy_xl.optimizers.laws.combine_laws`).
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import scipy.sparse.csgraph
from sklearn.exceptions import ConvergenceWarning

from .._validation import check_option
from ._base import CatalogOptimizer, coordinates_touched, warn_unexplained
from ._sindy_pi import extract_laws, homothetic_groups, null_space_start, solve_cvxpy
from ._sparse import column_norms, lasso_gram, null_vector, triangular_factor
from .homogeneous import select_laws
from .laws import UndeterminedLawWarning, combine_laws, normalize_law
from .noise_ratio import noise_ratio_law
from .problem import CatalogProblem

__all__ = ["ImplicitOptimizer", "NoLawFoundError", "coordinates_touched", "homothetic_groups"]

_SOLVERS = ("fista", "cvxpy")

#: Early stopping: iterations of the fast solver between two extractions of the laws in
#: its first _PROBE_ITER iterations (its convergence checks: exact laws settle within a few),
#: and after them (the solve restarted).
_LAW_CHECK_EVERY = 10
_PROBE_ITER = 50
_LAW_CHECK_EVERY_LONG = 100


class NoLawFoundError(RuntimeError):
    """Implicit regression found no sparse law in the regression matrix."""


class ImplicitOptimizer(CatalogOptimizer):
    """SINDy-PI constrained regression with homothetic-column clustering (unforced systems).

    Solves problem (1) of the module documentation, groups the homothetic columns of the
    solution matrix, takes each group's principal direction, refits it on its support (the
    smallest right singular vector of the normalized matrix restricted to the support, pruned
    with ``threshold``: this removes the L1 shrinkage), keeps the laws that qualify (at least
    ``min_group_size`` members, members making up at least ``min_membership`` of the law's
    terms, a residual within ``max_residual_ratio`` of the best law's) and combines the laws
    with disjoint supports into ``coef_``.

    Given the noise moments of the columns (:meth:`fit_catalog`; the weak form on positions
    passes them), the laws are instead selected by their held-out *noise ratio*
    (:func:`~pysindy_xl.optimizers.select_law`): problem (1) minimizes the plain residual,
    which on noisy columns prefers laws whose columns are quiet to laws that hold. A law
    must then cover every coordinate it can; a further law is sought on the coordinates left
    unexplained (uncoupled subsystems) and kept when its ratio is within
    ``max_residual_ratio`` of the first's. The SINDy-PI attributes (``solution_matrix_``,
    ``groups_``, ``alpha_``, ...) are not set in that mode.

    Parameters
    ----------
    alpha : float or "auto", default "auto"
        L1 weight (the paper's lambda) of problem (1) on unit-norm columns. The squared loss
        weighs a residual r as r^2 / 2 against alpha ||x||_1, so for the law to be every law
        column's optimum, alpha must lie below the squared residual of the next-best (false)
        representations, ``s_2^2`` (``s_1 <= s_2`` the two smallest singular values of the
        normalized matrix; ``s_1`` is the law's own residual), and above the law's ``s_1^2``
        (noise). ``"auto"`` takes their geometric mean ``s_1 s_2``, clipped to
        ``[1e-12, 1e-3]``; the chosen value is ``alpha_``. The extracted laws are refit on their
        support, so a small alpha costs no accuracy.
    solver : {"fista", "cvxpy"}, default "fista"
        Fast batched proximal-gradient solver or the cvxpy reference formulation.
    cvxpy_solver : str, optional
        Solver name passed to ``cvxpy.Problem.solve`` (e.g. ``"CLARABEL"``, ``"SCS"``,
        ``"OSQP"``); default: cvxpy's choice.
    angle_tol : float, default 5.0
        Angular tolerance (degrees) of the homothetic grouping.
    min_group_size : int, default 2
        Smallest group that can be a law (a law with k terms has up to k members).
    min_membership : float, default 0.1
        Smallest fraction of a law's terms that must be members of its group. Every column of a
        true law can reach it; a dense near-dependency is reached by few of its columns.
    max_residual_ratio : float, default 10.0
        Laws whose relative residual ``||Theta~ d|| / ||d||`` (``d`` on unit-norm columns)
        exceeds this many times the best law's (or 1e-12, whichever is larger) are rejected as
        near-dependencies.
    threshold : float, default 1e-3
        Terms whose normalized contribution is below ``threshold`` times the law's largest are
        pruned during the refit.
    refit : bool, default True
        Refit each law on its support (else keep the group's principal direction).
    tol : float, default 1e-4
        Relative optimality tolerance of the fast solver (see ``lasso_gram``); for cvxpy, the
        solver's own defaults apply.
    max_iter : int, default 20000
        Iteration budget of the fast solver.
    early_stopping : bool, default True
        Fast solver only: stop as soon as the extracted laws are identical at two consecutive
        checks and every column of their groups has converged; the other columns (which
        belong to no law) may then be left inexact, see ``column_converged_``. The laws are
        checked every 10 iterations during the first 50 (exact laws settle there); if they
        have not settled, the solve starts over with a check every 100 iterations. False
        solves every column to ``tol``.

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
        Combined law (see the module documentation for its normalization).
    solution_matrix_ : ndarray, shape (F, F)
        SINDy-PI solution ``X`` in the original column units (``Theta @ X ~ Theta`` on the law
        columns, zero diagonal); rows/columns of zero features are zero.
    normalized_solution_matrix_ : ndarray, shape (F, F)
        The same on unit-norm columns, ``D X D^-1`` (the matrix to plot, paper's Figure 2A).
    column_norms_ : ndarray, shape (F,)
        Norms of the columns of ``theta`` after the coordinate blocks are balanced
        (:func:`~pysindy_xl.optimizers.coordinate_weights`; unchanged for one coordinate).
    column_residuals_ : ndarray, shape (F,)
        Relative residual of each column's direction ``||Theta~ v_j|| / ||v_j||`` (inf for zero
        columns).
    groups_ : list of ndarray of int
        Homothetic groups of at least ``min_group_size`` columns, best seeded first.
    laws_ : ndarray, shape (n_laws, F)
        Accepted laws, normalized, best (smallest residual) first.
    law_groups_ : list of ndarray of int
        The group each law was extracted from.
    law_residuals_ : ndarray, shape (n_laws,)
        Relative residual of each law.
    combined_laws_ : list of int
        Indices of the laws summed into ``coef_``.
    alpha_ : float
        The L1 weight used.
    n_iter_ : int
        Iterations of the fast solver (0 for cvxpy).
    converged_ : bool
        Every column converged, or (early stopping) every column of the laws did and the
        laws were stable.
    column_converged_ : ndarray of bool, shape (F,)
    selection_method_ : {"sindy-pi", "noise ratio", "given support"}
        How the laws were found (the last by a refit of a given support).
    selection_ : LawSelection
        Noise-ratio mode: how the first law's support was chosen (held-out ratio per size).
    law_selections_ : list of LawSelection
        Noise-ratio mode: the same for every law.
    law_noise_ratios_ : ndarray, shape (n_laws,)
        Noise-ratio mode: each law's noise ratio on all the rows (about 1 when it holds to
        the noise).
    undetermined_ : ndarray, shape (k, F)
        Noise-ratio mode: other laws (different terms, normalized as ``coef_``) that the
        data hold as well as the first law (``selection_.rivals``); empty when the data
        decide. A :class:`~pysindy_xl.optimizers.UndeterminedLawWarning` names their terms.
    law_holds_ : bool
        Noise-ratio mode: whether the first law is admissible (explains every coordinate,
        definite mass matrix) and holds to the noise; a
        :class:`~pysindy_xl.optimizers.UndeterminedLawWarning` says so when it does not.

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
        """Uses the mass matrices and noise draws; wants unbiased derivatives (see
        :class:`~pysindy_xl.optimizers.CatalogTags`)."""
        return dataclasses.replace(super().catalog_tags(), uses_mass_matrices=True,
                                   uses_noise_draws=True, derivative_estimate="unbiased")

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

    # ------------------------------------------------------------------ validation
    def _check_params(self):
        check_option("solver", self.solver, "choice", choices=_SOLVERS)
        if not (isinstance(self.alpha, str) and self.alpha == "auto"):
            if isinstance(self.alpha, str):
                raise ValueError(f"alpha: expected a positive number or 'auto', got "
                                 f"{self.alpha!r}")
            check_option("alpha", self.alpha, "real", low=0, low_open=True)
        check_option("angle_tol", self.angle_tol, "real", low=0, high=90, low_open=True,
                     high_open=True)
        check_option("min_membership", self.min_membership, "real", low=0, high=1)
        check_option("max_residual_ratio", self.max_residual_ratio, "real", low=1,
                     allow_inf=True)
        check_option("threshold", self.threshold, "real", low=0, high=1, high_open=True)
        check_option("tol", self.tol, "real", low=0, low_open=True)
        check_option("min_group_size", self.min_group_size, "int", low=1)
        check_option("max_iter", self.max_iter, "int", low=1)
        check_option("refit", self.refit, "bool")
        check_option("early_stopping", self.early_stopping, "bool")

    # ------------------------------------------------------------------ public API
    def fit(self, X, y=None):
        """Find the sparse laws ``X @ xi = 0`` of a regression matrix.

        Parameters
        ----------
        X : array, shape (n_rows, F)
            Regression matrix (one block: no coordinate structure, no force column).
        y : None
            Ignored; present for scikit-learn compatibility.

        Returns
        -------
        self
        """
        problem = CatalogProblem.from_arrays(X, 1, [])
        return self._fit(problem.theta, 1, problem.force_columns, None)

    def _solve(self, problem):
        """Implicit regression on the (balanced) catalog problem.

        Identically zero force columns (unforced data) are ignored; non-zero ones are
        ordinary columns and fix the scale of a law containing them (coef -1). With noise
        moments, the laws are selected by their held-out noise ratio
        (:func:`~pysindy_xl.optimizers.select_law`) instead of problem (1): the least-squares
        residual that problem (1) minimizes prefers laws whose columns are quiet over laws
        that hold; ``selection_method_`` says which was used. With mass matrices too, laws
        whose mass matrix is not definite at the sample states are not selected, unless no
        candidate law is definite.
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
        """The laws on a given support, nothing selected.

        The columns of ``support`` fall into groups that share no coordinate (uncoupled
        subsystems: a chain of columns touching common coordinates links the members of a
        group). Each group of at least two columns gets the law its columns fit best on every
        row: with noise moments, the smallest noise ratio
        (:func:`~pysindy_xl.optimizers.noise_ratio.noise_ratio_law`), otherwise the smallest
        right singular vector of the unit-norm columns, as the refit of a full fit. The laws
        are normalized as there and summed. :class:`EnsembleOptimizer` uses it to refit the
        terms its fits agree on with all the data: a median of laws fitted on different
        supports is no law.
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
        _, labels = scipy.sparse.csgraph.connected_components(touches.T @ touches,
                                                              directed=False)
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
        self.law_residuals_ = np.array([  # as for problem (1): on unit-norm columns
            np.linalg.norm(theta @ law) / np.linalg.norm(law * norms) for law in laws])
        self.law_noise_ratios_ = None if moments is None else np.asarray(ratios)
        self.law_groups_ = [np.flatnonzero(law) for law in laws]
        self._set_laws(laws, norms, force_columns, None)
        warn_unexplained("ImplicitOptimizer", theta, n_coordinates, self.coef_, force_columns)
        return self

    def _set_laws(self, laws, norms, force_columns, reference_columns):
        """``laws_`` normalized (module documentation) and their disjoint sum ``coef_``."""
        self.laws_ = np.array([normalize_law(law, norms, force_columns, reference_columns)
                               for law in laws])
        self.coef_, self.combined_laws_ = combine_laws(self.laws_)

    # ------------------------------------------------------------------ core
    def _fit_noisy(self, theta, n_coordinates, force_columns, reference_columns, moments,
                   mass_matrices, draws=None):
        """Laws selected by held-out noise ratio, one per group of coordinates they explain
        (each fold with its rows' own noise moments, given the draws of the rows' errors)."""
        self._check_params()
        self.selection_method_ = "noise ratio"
        norms = column_norms(theta)[0]
        self.column_norms_ = norms
        laws, ratios, selections = select_laws(theta, moments, n_coordinates, mass_matrices,
                                               self.max_residual_ratio, draws)
        if not laws:
            raise NoLawFoundError(
                "ImplicitOptimizer: no law could be selected from the noisy columns (too few "
                "non-zero columns or rows for cross-validation)"
            )
        self.selection_ = selections[0]
        self.law_selections_ = selections
        self.law_noise_ratios_ = np.asarray(ratios)
        self.law_residuals_ = np.array([  # as for problem (1): on unit-norm columns
            np.linalg.norm(theta @ law) / np.linalg.norm(law * norms) for law in laws])
        self.law_groups_ = [np.flatnonzero(law) for law in laws]
        self._set_laws(laws, norms, force_columns, reference_columns)
        self._report_rivals(theta, moments, selections[0], laws[0], norms,
                            force_columns, reference_columns)
        return self

    def _report_rivals(self, theta, moments, selection, law, norms, force_columns,
                       reference_columns):
        """``undetermined_``: the rival laws of the first law's selection, normalized;
        ``law_holds_``: whether the first law is admissible and holds to the noise (held-out
        noise ratio not above 1 by more than two standard errors, or a relative residual at
        the quadrature level). A warning says what is undetermined or not found."""
        size = selection.size
        ratio, spread = selection.cv_ratio[size - 1], selection.cv_spread[size - 1]
        holds = ratio - 2 * spread <= 1 or ratio <= 2 or selection.cv_relative < 1e-8
        self.law_holds_ = bool(selection.admissible and holds)
        if not self.law_holds_:
            reason = ("its mass matrix is not definite on the states or it leaves a coordinate "
                      "unexplained" if not selection.admissible else
                      f"its held-out noise ratio is {ratio:.3g} +- {spread:.2g} (about 1 for a "
                      "law that holds)")
            warnings.warn(
                f"ImplicitOptimizer: no law that holds to the noise was found in the catalog "
                f"({reason}); the returned law is the best found, not a determined one. Record "
                "more trajectories, reduce the noise or force a coordinate.",
                UndeterminedLawWarning, stacklevel=4)
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
            raise NoLawFoundError(
                f"theta: {active.size} non-zero column(s); implicit regression needs at least 2"
            )
        scaled = (theta if active.size == n_features else theta[:, active]) / norms[active]
        r_factor = triangular_factor(scaled)
        x_scaled = self._sindy_pi_matrix(r_factor)

        # The SINDy-PI matrix in both unit systems, embedded in the full catalog.
        self.column_norms_ = norms
        self.normalized_solution_matrix_ = np.zeros((n_features, n_features))
        self.normalized_solution_matrix_[np.ix_(active, active)] = x_scaled
        self.solution_matrix_ = np.zeros((n_features, n_features))
        self.solution_matrix_[np.ix_(active, active)] = (
            x_scaled * norms[active][None, :] / norms[active][:, None]
        )
        converged = np.zeros(n_features, dtype=bool)
        converged[active] = self._column_converged
        self.column_converged_ = converged

        residuals, groups, laws, law_groups, law_residuals = self._post_process(
            x_scaled, r_factor
        )
        self.column_residuals_ = np.full(n_features, np.inf)
        self.column_residuals_[active] = residuals
        self.groups_ = [active[g] for g in groups]
        if not laws:
            raise NoLawFoundError(
                "ImplicitOptimizer: no group of homothetic columns qualifies as a law "
                f"({len(groups)} group(s) of >= {self.min_group_size} columns). Try a smaller "
                "alpha, a larger angle_tol, or check that the catalog can express the dynamics."
            )
        full_laws = np.zeros((len(laws), n_features))
        full_laws[:, active] = np.array(laws) / norms[active]
        self.law_groups_ = [active[g] for g in law_groups]
        self.law_residuals_ = np.asarray(law_residuals)
        self._set_laws(full_laws, norms, force_columns, reference_columns)
        return self

    def plot(self, feature_names=None, axes=None):
        """The paper's Figure 2: solution matrix, homothetic groups, extracted law.

        Panel A shows ``|normalized_solution_matrix_|`` (log scale), panel B the unit
        directions ``e_j - X[:, j]`` of the columns of each law's group (one colour per law),
        panel C the combined coefficients ``coef_``.

        Parameters
        ----------
        feature_names : list of str, optional
            Labels of the catalog columns (e.g. ``library.get_feature_names()``).
        axes : sequence of 3 matplotlib Axes, optional
            Where to draw; default: a new figure with three panels.

        Returns
        -------
        list of matplotlib.axes.Axes
        """
        import matplotlib.pyplot as plt
        from sklearn.utils.validation import check_is_fitted

        check_is_fitted(self, "coef_")
        if self.selection_method_ != "sindy-pi":
            raise ValueError(
                "plot: the laws were selected by noise ratio (noise moments were given), "
                "there is no SINDy-PI solution matrix to draw; see selection_ instead"
            )
        if axes is None:
            _, axes = plt.subplots(1, 3, figsize=(15, 4.5), constrained_layout=True)
        x = np.abs(self.normalized_solution_matrix_)
        floor = max(x.max(initial=0.0) * 1e-8, 1e-300)
        image = axes[0].imshow(np.log10(np.maximum(x, floor)), cmap="viridis")
        axes[0].set(title="A: |X| (SINDy-PI solution, log10)", xlabel="column j",
                    ylabel="feature")
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
                ax.set_xticks(np.arange(len(feature_names)), feature_names, rotation=90,
                              fontsize=6)
        return list(axes)

    def _post_process(self, x_scaled, r_factor):
        """Column residuals, homothetic groups and the laws (best first), normalized space."""
        directions = np.eye(x_scaled.shape[0]) - x_scaled
        residuals = np.linalg.norm(r_factor @ directions, axis=0) / np.linalg.norm(
            directions, axis=0
        )
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
            # Stop once the extracted laws are the same at two consecutive checks and every
            # column that supports them has converged: the other columns cannot change them.
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
            # Exact laws (clean data) are read off the start: a short probe that extracts
            # them at every convergence check ends there. Otherwise the solve starts over,
            # the laws extracted every _LAW_CHECK_EVERY_LONG iterations only (an extraction
            # clusters all the columns; laws that take long to settle would pay for it).
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
                "alpha); raise max_iter or alpha",
                ConvergenceWarning,
                stacklevel=4,
            )
        return result.coef

    def _resolve_alpha(self, r_factor):
        if not isinstance(self.alpha, str):
            return float(self.alpha)
        singular = np.linalg.svd(r_factor, compute_uv=False)
        singular = np.concatenate([singular, np.zeros(r_factor.shape[1] - singular.size)])
        smallest, second = singular[-1], singular[-2]
        return float(np.clip(smallest * second / singular[0] ** 2, 1e-12, 1e-3))
