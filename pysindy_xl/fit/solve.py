"""The solve step of the fit stage: the optimizer for a problem, and the reweighting solver."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
from sklearn.base import clone

from ..optimizers import (
    ExplicitOptimizer,
    catalog_tags,
    default_optimizer,
    pilot_optimizer,
    solve_problem,
)
from .build import with_mass_matrices

__all__ = ["resolve_optimizer", "solve", "MAX_REWEIGHTS"]

#: Fits on whitened rows at most (:func:`solve`): the last one is kept even when its support
#: still differs from the law that weighed it.
MAX_REWEIGHTS = 3


def resolve_optimizer(optimizer, problem, library):
    """The unfitted optimizer that fits a problem.

    Parameters
    ----------
    optimizer : catalog optimizer, regressor, str or None
        A catalog optimizer is cloned; a regressor with ``fit(X, y)`` (a pysindy optimizer)
        runs as ``ExplicitOptimizer(method=...)``; a kind ("explicit", "implicit", "mixed")
        or None gets :func:`~pysindy_xl.optimizers.default_optimizer` for the problem's data.
    problem : CatalogProblem
        From :func:`~pysindy_xl.fit.build_problem`.
    library : fitted CatalogRepartition or None
        The catalog, read by the default optimizer.

    Returns
    -------
    catalog optimizer
        Unfitted.

    Examples
    --------
    >>> import numpy as np, pysindy as ps, pysindy_xl as px
    >>> problem = px.optimizers.CatalogProblem.from_arrays(np.eye(3), 1, [0])
    >>> resolve_optimizer(ps.STLSQ(), problem, None)
    ExplicitOptimizer(method=STLSQ())
    """
    if optimizer is None or isinstance(optimizer, str):
        origin = problem.catalog_map
        structure = library.physical_structure()
        return default_optimizer(
            origin.forced[origin.coordinates], problem.row_noise is not None, kind=optimizer,
            complete=library.complete_catalog,
            physical=structure is not None,
            selective=structure is not None and len(structure.selectable_columns) > 0)
    if not hasattr(optimizer, "fit_catalog"):
        if callable(getattr(optimizer, "fit", None)):
            # a pysindy (or scikit-learn) regressor: explicit regression through it
            return ExplicitOptimizer(method=clone(optimizer))
        raise TypeError("optimizer: expected a catalog optimizer with fit_catalog "
                        "(ExplicitOptimizer, ImplicitOptimizer, MixedOptimizer) or a regressor "
                        f"with fit(X, y) such as pysindy's STLSQ, got {type(optimizer).__name__}")
    return clone(optimizer)


def solve(optimizer, problem, library=None, weigh=False):
    r"""Fit ``optimizer`` on ``problem``, reweighting rows that carry estimated noise.

    Given ``library``, the problem gets the mass matrices of its columns when the optimizer's
    tags ask for them. With ``weigh`` and ``problem.row_noise`` the fit is iteratively
    reweighted (the reweighting of WENDy): the rows are whitened by the covariance ``S`` of the
    residual of the latest law ``xi``,

    .. math:: \min_\xi \; \| S(\xi)^{-1/2} \, \Theta \xi \|^2,

    starting from the pilot law (:meth:`~pysindy_xl.weak.WeakNoise.whitener`), and refitted
    unbalanced, until the support is the one that set the weights (at most
    :data:`MAX_REWEIGHTS` fits).

    Parameters
    ----------
    optimizer : catalog optimizer
        Unfitted (:func:`resolve_optimizer`).
    problem : CatalogProblem
        From :func:`~pysindy_xl.fit.build_problem`.
    library : fitted CatalogRepartition, optional
        The catalog; default None (no mass matrices).
    weigh : bool or "auto", default False
        Reweight by the rows' noise; ``"auto"``: when some coordinate of the problem is forced.

    Returns
    -------
    catalog optimizer
        The fitted optimizer (``coef_`` on the problem's columns).

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> theta = np.column_stack([[1.0, 2.0, 3.0], [0.5, 1.0, 1.5]])
    >>> problem = px.optimizers.CatalogProblem.from_arrays(theta, 1, [0])
    >>> solve(px.ExplicitOptimizer(), problem).coef_
    array([-1.,  2.])
    """
    noise = problem.row_noise
    if isinstance(weigh, str) and weigh == "auto":
        origin = problem.catalog_map
        weigh = origin is not None and bool(origin.forced[origin.coordinates].any())
    if noise is not None and library is not None and catalog_tags(optimizer).uses_mass_matrices:
        problem = with_mass_matrices(problem, library)

    def unweighted(reason):  # said only of a fit that succeeds
        fitted = solve_problem(optimizer, problem)
        warnings.warn(f"residual_covariance: {reason}; the rows are fitted unweighted",
                      UserWarning, stacklevel=3)
        return fitted

    if noise is None or not weigh:
        return solve_problem(optimizer, problem)
    try:
        with warnings.catch_warnings():  # the pilot only sets the first weights
            warnings.simplefilter("ignore")
            law = solve_problem(pilot_optimizer(optimizer), problem).coef_
    except (ValueError, RuntimeError, np.linalg.LinAlgError) as error:
        return unweighted(f"the pilot fit failed ({error})")
    for _ in range(MAX_REWEIGHTS):
        whiten = noise.whitener(law)
        if whiten is None:
            return unweighted("the residual of the law carries no noise")
        whitened = noise.whitened(whiten)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fitted = solve_problem(clone(optimizer), dataclasses.replace(
                problem, theta=whiten(problem.theta), noise_moments=whitened.moments(),
                noise_draws=whitened.draws, balance=False, row_noise=whitened))
        settled = np.array_equal(fitted.coef_ != 0, law != 0)
        law = fitted.coef_
        if settled:
            break
    for record in caught:
        warnings.warn(record.message, record.category, stacklevel=3)
    return fitted
