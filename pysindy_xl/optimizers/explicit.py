"""Explicit regression: the forces are known, solve ``Theta_rest @ xi = force``."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import scipy.linalg
from sklearn.exceptions import ConvergenceWarning
from sklearn.linear_model import Lasso, LassoCV

from .._validation import (
    Boolean,
    HasMethods,
    Interval,
    Options,
    check_numeric_array,
    validate_params,
)
from ._base import CatalogOptimizer, warn_unexplained
from .selection import select_support

__all__ = ["ExplicitOptimizer", "hard_threshold_regression", "proximal_gradient_lasso",
           "corrected_least_squares", "explicit_regression", "catalog_vector"]

_METHODS = ("threshold", "lasso", "lassocv", "proximal")


def hard_threshold_regression(x, y, threshold: float = 0.01, max_iter: int = 100, keep=None):
    """Least squares with iterative pruning by the paper's condition value.

    Each round fits the active columns and prunes those whose condition value
    ``|coef_j| * rms(x_j)`` is below ``threshold`` times the largest, until the support is stable.

    Parameters
    ----------
    x : array, shape (n_rows, F)
        Columns.
    y : array, shape (n_rows,)
        Target.
    threshold : float, default 0.01
        Relative condition value below which a term is pruned, in [0, 1).
    max_iter : int, default 100
        Maximal number of prune-and-refit rounds.
    keep : array of bool, shape (F,), optional
        Columns never pruned.

    Returns
    -------
    coef : ndarray, shape (F,)
        The coefficients.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> x = rng.normal(size=(200, 5))
    >>> coef = hard_threshold_regression(x, x @ [2.0, 0, 0, -1.0, 0] + 1e-6 * rng.normal(size=200))
    >>> np.round(coef, 4)
    array([ 2.,  0.,  0., -1.,  0.])
    """
    scale = np.sqrt(np.mean(x**2, axis=0))
    active = np.flatnonzero(scale > 0)
    fixed = np.zeros(x.shape[1], dtype=bool) if keep is None else np.asarray(keep, dtype=bool)
    coef = np.zeros(x.shape[1])
    for _ in range(max_iter):
        if len(active) == 0:
            break
        xs = x[:, active] / scale[active]
        sol = np.linalg.lstsq(xs, y, rcond=None)[0]
        condition = np.abs(sol)
        keep = condition >= threshold * condition.max() if condition.max() > 0 else condition > 0
        keep |= fixed[active]
        coef[:] = 0.0
        coef[active] = sol / scale[active]
        if keep.all():
            break
        active = active[keep]
    return coef


def proximal_gradient_lasso(x, y, alpha: float, max_iter: int = 10_000, tol: float = 1e-10):
    """Lasso ``min 1/(2 n) ||x c - y||^2 + alpha ||c||_1`` by accelerated proximal gradient.

    Parameters
    ----------
    x : array, shape (n_rows, F)
        Normalized columns (the step is set by the largest singular value).
    y : array, shape (n_rows,)
        Target.
    alpha : float
        Regularization weight, >= 0.
    max_iter : int, default 10000
        Iteration budget.
    tol : float, default 1e-10
        Stop when the relative change of the iterate falls below ``tol``.

    Returns
    -------
    coef : ndarray, shape (F,)
        The coefficients.
    converged : bool
        Whether the iteration converged.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.random.default_rng(0).normal(size=(200, 3))
    >>> coef, converged = proximal_gradient_lasso(x, x @ [1.0, 0.0, -2.0], alpha=1e-3)
    >>> coef.round(2), converged
    (array([ 1.,  0., -2.]), True)
    """
    n_rows = x.shape[0]
    gram = x.T @ x / n_rows
    xty = x.T @ y / n_rows
    step = 1.0 / max(np.linalg.eigvalsh(gram)[-1], 1e-300)
    coef = np.zeros(x.shape[1])
    momentum, t_k = coef.copy(), 1.0
    for _ in range(max_iter):
        grad = gram @ momentum - xty
        z = momentum - step * grad
        new = np.sign(z) * np.maximum(np.abs(z) - step * alpha, 0.0)
        t_next = (1 + np.sqrt(1 + 4 * t_k**2)) / 2
        momentum = new + (t_k - 1) / t_next * (new - coef)
        change = np.linalg.norm(new - coef) / max(np.linalg.norm(new), 1e-300)
        coef, t_k = new, t_next
        if change < tol:
            return coef, True
    return coef, False


def corrected_least_squares(x, y, noise_moments=None, max_noise_share: float = 0.5):
    r"""Least squares corrected for errors in the columns (errors in variables).

    With ``x = x_0 + E`` and ``E[E^T E] = S``, ``E[x^T x] = x_0^T x_0 + S`` shrinks least squares
    towards zero. The corrected estimate (Fuller, *Measurement Error Models*, 1987) solves

    .. math:: (x^T x - S)\,\beta = x^T y, \quad\text{i.e.}\quad
              \beta = (I - (x^T x)^{-1} S)^{-1} \beta_{LS},

    from the QR factor of ``x``. Where an eigenvalue of ``(x^T x)^{-1} S`` exceeds
    ``max_noise_share`` the correction would amplify noise: plain least squares is returned.

    Parameters
    ----------
    x : array, shape (n_rows, k)
        Columns.
    y : array, shape (n_rows,)
        Target.
    noise_moments : array, shape (k, k), optional
        ``S``; None gives plain least squares.
    max_noise_share : float, default 0.5
        Largest eigenvalue of ``(x^T x)^-1 S`` for which the correction applies.

    Returns
    -------
    coef : ndarray, shape (k,)
        The coefficients.
    noise_share : float
        Largest eigenvalue of ``(x^T x)^{-1} S`` (0 without ``S``).

    Examples
    --------
    A regressor with noise of 30 % of its spread: least squares shrinks the slope by
    ``1 / (1 + 0.3^2)``, the corrected estimate does not.

    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> truth = rng.normal(size=20000)
    >>> x = (truth + 0.3 * rng.normal(size=20000))[:, None]
    >>> y = 2.0 * truth
    >>> plain, _ = corrected_least_squares(x, y)
    >>> corrected, share = corrected_least_squares(x, y, np.array([[0.09 * 20000]]))
    >>> plain.round(2), corrected.round(2), round(share, 2)
    (array([1.83]), array([2.]), 0.08)
    """
    x = np.asarray(x, dtype=float)
    scale = np.sqrt(np.mean(x**2, axis=0))
    scale[scale == 0] = 1.0
    # on normalized columns: no coefficient loses digits to the units of the others
    coef = np.linalg.lstsq(x / scale, y, rcond=None)[0]
    if noise_moments is None or x.shape[1] == 0:
        return coef / scale, 0.0
    # (mode "raw": R without the (rows, columns) upper-triangular copy that mode "r" makes)
    r_factor = scipy.linalg.qr(x / scale, mode="raw", overwrite_a=True,
                               check_finite=False)[1][: x.shape[1]]
    moments = np.asarray(noise_moments, dtype=float) / np.outer(scale, scale)
    try:
        ratio = scipy.linalg.solve_triangular(
            r_factor, scipy.linalg.solve_triangular(r_factor, moments, trans="T"))
    except (np.linalg.LinAlgError, ValueError):
        return coef / scale, np.inf
    share = float(np.max(np.abs(np.linalg.eigvals(ratio)), initial=0.0))
    if not share < max_noise_share:
        return coef / scale, share
    return np.linalg.solve(np.eye(len(coef)) - ratio, coef) / scale, share


class ExplicitOptimizer(CatalogOptimizer):
    r"""Sparse regression when the generalized forces are known on the coordinates.

    With the force column's coefficient fixed to ``-1`` (the paper's convention),
    ``Theta @ xi = 0`` becomes ``Theta_rest @ xi_rest = f``, ``f`` the summed force columns,
    solved on unit-RMS columns. Hard thresholding (the default) solves least squares on a
    support ``A`` pruned by the condition value ``|xi_j| rms(Theta_j)``,

    .. math:: \min_{\xi_A} \|\Theta_A \xi_A - f\|_2^2,

    the L1 methods the Lasso

    .. math:: \min_\xi \frac{1}{2N} \|\Theta_{rest} \xi - f\|_2^2 + \alpha \|\xi\|_1,

    then (``refit``) least squares on its support. With noise moments ``S = E[E^T E]`` of the
    columns the refit is corrected for errors in variables (:func:`corrected_least_squares`).

    Parameters
    ----------
    method : {"threshold", "lasso", "lassocv", "proximal"} or estimator, default "threshold"
        Hard thresholding (:func:`hard_threshold_regression`), scikit-learn ``Lasso(alpha)`` or
        ``LassoCV``, :func:`proximal_gradient_lasso`, or any estimator with ``fit(X, y)`` and
        ``coef_`` (e.g. pysindy's ``STLSQ``, ``SR3``, ``MIOSR``).
    threshold : "auto" or float, default "auto"
        Pruning of ``"threshold"`` and of the refit. ``"auto"``: the sparsest model within one
        standard error of the best held-out error
        (:func:`~pysindy_xl.optimizers.selection.select_support`; under 10 rows per coordinate
        the 1 % rule). A number in [0, 1): the paper's relative condition value.
    alpha : float, default 1e-4
        Lasso weight of ``"lasso"`` and ``"proximal"`` (unit-RMS columns and target).
    refit : bool, default True
        After an L1 method or an estimator, refit by least squares on the support, pruned with
        ``threshold``.
    max_iter : int, default 1000
        Prune-and-refit rounds of ``"threshold"``; ten times as many L1 iterations.
    select : {"all", "friction"}, default "all"
        Which columns the pruning may drop: any, or only the friction and sensor-offset columns
        of the problem's physical structure (``selectable_columns``); needs ``"threshold"``.

    Attributes
    ----------
    coef_ : ndarray, shape (F,)
        Coefficients of ``fit``'s columns, or the full catalog vector after ``fit_catalog``.
    support_ : ndarray of bool, shape (F,)
        The non-zero coefficients.
    noise_share_ : float or None
        With noise moments: the largest eigenvalue of ``(X^T X)^-1 S`` on the support (the
        correction applies below 0.5).
    selection_ : SelectionResult or None
        With ``threshold="auto"`` (indices of ``fit``'s columns, or of the non-force columns).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> rng = np.random.default_rng(1)
    >>> X = rng.normal(size=(100, 4))
    >>> px.ExplicitOptimizer().fit(X, X @ [0.5, 0.0, -3.0, 0.0]).coef_.round(6)
    array([ 0.5,  0. , -3. ,  0. ])
    """

    spec_type = "ExplicitOptimizer"

    def catalog_tags(self):
        """What this optimizer can do and needs.

        Explicit regression needs force columns (``requires_forces``) and can refit a given
        support (``can_refit``).

        Returns
        -------
        CatalogTags
            The tags (:class:`~pysindy_xl.optimizers.tags.CatalogTags`): ``requires_forces``,
            ``can_refit``, ``balances_rows``, ``derivative_estimate``, ...
        """
        return dataclasses.replace(super().catalog_tags(), requires_forces=True)

    _parameter_constraints = {
        "method": [Options(_METHODS), HasMethods("a method name or an estimator", "fit")],
        "threshold": ["auto", Interval("real", 0, 1, high_open=True)],
        "alpha": [Interval("real", 0)],
        "refit": [Boolean()],
        "max_iter": [Interval("int", 1)],
        "select": [Options(("all", "friction"))],
    }

    def __init__(self, method="threshold", threshold="auto", alpha=1e-4, refit=True,
                 max_iter=1000, select="all"):
        self.method = method
        self.threshold = threshold
        self.alpha = alpha
        self.refit = refit
        self.max_iter = max_iter
        self.select = select

    def _check_params(self):
        validate_params(self)
        if self.select == "friction" and not (isinstance(self.method, str)
                                              and self.method == "threshold"):
            raise ValueError(f"select: 'friction' needs method='threshold', got method="
                             f"{self.method!r}")

    def fit(self, X, y):
        """Solve ``X @ coef_ = y`` sparsely.

        Parameters
        ----------
        X : array, shape (n_rows, F)
            Regression matrix.
        y : array, shape (n_rows,)
            Target.

        Returns
        -------
        self
        """
        return self._fit(X, y, n_blocks=1)

    def _fit(self, X, y, n_blocks, noise_moments=None, keep=None):
        self._check_params()
        X = check_numeric_array(X, "X", finite=False, min_samples=0)
        y = check_numeric_array(y, "y", finite=False, min_samples=0)
        if X.ndim != 2 or X.shape[0] == 0 or X.shape[1] == 0:
            raise ValueError(f"X: expected a non-empty 2-D array, got shape {X.shape}")
        if y.ndim != 1 or y.shape[0] != X.shape[0]:
            raise ValueError(f"y: expected shape ({X.shape[0]},), got {y.shape}")
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(y))):
            raise ValueError("X, y: contain NaN or inf")
        if not np.any(y):
            raise ValueError(
                "y: the force vector is identically zero; explicit regression needs a known "
                "force (use ImplicitOptimizer or MixedOptimizer for unforced data)")
        self.selection_ = None
        self.noise_share_ = None if noise_moments is None else 0.0
        self.n_features_in_ = X.shape[1]
        self.coef_ = self._sparse_coefficients(X, y, n_blocks, noise_moments, keep)
        self.support_ = self.coef_ != 0
        return self

    def _prune(self, X, y, n_blocks, noise_moments=None, keep=None):
        """Sparse least squares with the configured pruning (``keep``: columns never pruned)."""
        if self.threshold != "auto":
            return hard_threshold_regression(X, y, self.threshold, int(self.max_iter), keep)
        n_rows = X.shape[0]
        per_block = n_rows // n_blocks if n_rows % n_blocks == 0 else n_rows
        blocks = n_blocks if n_rows % n_blocks == 0 else 1
        if per_block < 10:  # too few rows to hold any out
            return hard_threshold_regression(X, y, 0.01, int(self.max_iter), keep)
        self.selection_ = select_support(
            X, y, n_blocks=blocks, keep=None if keep is None else np.flatnonzero(keep))
        support = self.selection_.support
        coef = np.zeros(X.shape[1])
        moments = None if noise_moments is None else noise_moments[np.ix_(support, support)]
        coef[support], share = corrected_least_squares(X[:, support], y, moments)
        if noise_moments is not None:
            self.noise_share_ = share
        return coef

    def _sparse_coefficients(self, X, y, n_blocks=1, noise_moments=None, keep=None):
        if self.method == "threshold":
            return self._prune(X, y, n_blocks, noise_moments, keep)
        scale = np.sqrt(np.mean(X**2, axis=0))
        active = scale > 0
        xs = X[:, active] / scale[active]
        y_scale = np.sqrt(np.mean(y**2))
        ys = y / y_scale
        if self.method == "lasso":
            sol = Lasso(alpha=self.alpha, fit_intercept=False, max_iter=int(self.max_iter) * 10)
            sol = self._fit_quietly(sol, xs, ys).coef_
        elif self.method == "lassocv":
            sol = LassoCV(fit_intercept=False, max_iter=int(self.max_iter) * 10)
            sol = self._fit_quietly(sol, xs, ys).coef_
        elif self.method == "proximal":
            sol, converged = proximal_gradient_lasso(xs, ys, self.alpha, int(self.max_iter) * 10)
            if not converged:
                warnings.warn("proximal gradient did not converge; raise max_iter",
                              ConvergenceWarning, stacklevel=3)
        else:
            estimator = self._fit_quietly(self.method, xs, ys)
            sol = np.asarray(estimator.coef_, dtype=float).reshape(-1)
            if sol.shape != (xs.shape[1],):
                raise ValueError(
                    f"method: the estimator's coef_ has {sol.size} entries, expected {xs.shape[1]}")
        coef = np.zeros(X.shape[1])
        coef[active] = sol * y_scale / scale[active]
        if self.refit and np.any(coef):
            support = np.flatnonzero(coef)
            coef[:] = 0.0
            moments = None if noise_moments is None else noise_moments[np.ix_(support, support)]
            coef[support] = self._prune(X[:, support], y, n_blocks, moments)
            if self.selection_ is not None:  # report indices of X, not of the support
                self.selection_.order = support[self.selection_.order]
        return coef

    @staticmethod
    def _fit_quietly(estimator, x, y):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ConvergenceWarning)
            estimator.fit(x, y)
        for w in caught:
            if issubclass(w.category, ConvergenceWarning):
                warnings.warn(f"inner regressor did not converge: {w.message}",
                              ConvergenceWarning, stacklevel=4)
        return estimator

    def _solve(self, problem):
        """The catalog problem with the force coefficient at -1; with noise moments the final fit is
        corrected for attenuation (:func:`corrected_least_squares`).
        """
        rest, force, moments = explicit_regression(problem)
        keep = None
        if self.select == "friction":  # only the joint models may leave
            selectable = (problem.physical.selectable_columns if problem.physical is not None
                          else np.zeros(0, dtype=int))
            keep = ~np.isin(rest, selectable)
        # cross-validation folds stay inside each coordinate's block of rows
        self._fit(problem.theta[:, rest], force, n_blocks=problem.n_coordinates,
                  noise_moments=moments, keep=keep)
        return self._as_catalog_vector(self.coef_, rest, problem)

    def _solve_support(self, problem, support):
        """Least squares on a given support, nothing selected (the ensemble's refit)."""
        rest, force, moments = explicit_regression(problem)
        keep = support[rest]
        coef = np.zeros(len(rest))
        if moments is not None:
            moments = moments[np.ix_(keep, keep)]
        coef[keep], share = corrected_least_squares(problem.theta[:, rest[keep]], force, moments)
        self.selection_ = None
        self.noise_share_ = None if moments is None else share
        return self._as_catalog_vector(coef, rest, problem)

    def _as_catalog_vector(self, coef_rest, rest, problem):
        """Set ``coef_`` over the whole catalog (forces at -1); warn on unexplained coordinates."""
        coef = catalog_vector(coef_rest, rest, problem)
        self.coef_ = coef
        self.n_features_in_ = problem.n_features
        self.support_ = coef != 0
        warn_unexplained("ExplicitOptimizer", problem.theta, problem.n_coordinates, coef,
                         problem.force_columns, 5)
        return self


def explicit_regression(problem):
    """The explicit regression of a catalog problem: columns, right-hand side and noise.

    With the force coefficients fixed to -1, ``Theta @ xi = 0`` reads
    ``Theta_rest @ xi_rest = sum of the force columns``.

    Parameters
    ----------
    problem : CatalogProblem
        The problem, with force columns.

    Returns
    -------
    rest : ndarray of int
        The non-force columns.
    force : ndarray, shape (n_rows,)
        The summed force columns (the right-hand side).
    moments : ndarray, shape (len(rest), len(rest)) or None
        The pooled noise moments restricted to ``rest`` (None without).
    """
    if len(problem.force_columns) == 0:
        raise ValueError("force_columns: explicit regression needs a force column")
    rest = np.setdiff1d(np.arange(problem.n_features), problem.force_columns)
    force = problem.theta[:, problem.force_columns].sum(axis=1)
    moments = problem.pooled_moments()
    return rest, force, None if moments is None else moments[np.ix_(rest, rest)]


def catalog_vector(coef_rest, rest, problem) -> np.ndarray:
    """The catalog vector of coefficients found on the non-force columns, forces at -1.

    Parameters
    ----------
    coef_rest : array, shape (len(rest),)
        Coefficients of the columns ``rest``.
    rest : array of int
        The non-force columns.
    problem : CatalogProblem
        The problem (its number of features and force columns).

    Returns
    -------
    ndarray, shape (F,)
        ``coef_rest`` placed on ``rest``, -1 on the force columns, zero elsewhere.
    """
    coef = np.zeros(problem.n_features)
    coef[rest] = coef_rest
    coef[problem.force_columns] = -1.0
    return coef
