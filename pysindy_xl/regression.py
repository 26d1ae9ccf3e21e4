"""The regression stage: a catalog and trajectories in, the rows of the regression out.

Every consumer of a catalog's regression goes through here: :meth:`XLSINDy.fit
<pysindy_xl.XLSINDy.fit>`, the fit-quality report (:mod:`pysindy_xl.quality`) and the CLI.

* :func:`trajectory_data` validates the arrays of ``fit`` (one trajectory or a list) and
  estimates missing velocities and accelerations with a differentiation function;
* :func:`build_regression` turns them into the stacked rows of the chosen formulation:
  ``"strong"``, the catalog's columns at every unmasked sample
  (:meth:`SymbolicLibrary.transform <pysindy_xl.feature_library.SymbolicLibrary.transform>`),
  or ``"weak"``, the columns integrated against test functions of smoothed positions
  (:func:`~pysindy_xl.weak.weak_regression`), with the propagated noise of the positions.
  Without forces (no ``u``) the default test functions come in several widths
  (:data:`UNFORCED_WIDTH_MULTIPLES`): an unforced law is known only up to a factor and is
  told from the other laws the catalog holds by the noise ratio alone, which one width's rows
  determine poorly from noisy positions; a force column fixes the scale of a forced law, whose
  rows keep the single width.

Rows are coordinate-major over all trajectories: ``theta`` has shape ``(n * R, F)`` with
``R`` rows (samples or test functions) per coordinate.
"""

from __future__ import annotations

import copy
import dataclasses
import warnings

import numpy as np
import pysindy as ps
from sklearn.base import clone

from ._inputs import trajectory_arrays
from .feature_library import stack_variables
from .optimizers import pilot_optimizer, solve_problem
from .weak import BumpTestFunctions, WhittakerSmoother, differentiate, weak_regression
from .weak.smoothing import is_uniform

__all__ = ["Regression", "build_regression", "trajectory_data", "differentiation_function",
           "solve_weak_problem", "FORMULATIONS"]

FORMULATIONS = ("auto", "strong", "weak")

#: Test-function widths of the unforced weak form, in multiples of the spectrum's width
#: (:class:`~pysindy_xl.weak.BumpTestFunctions`, ``width_multiples``).
UNFORCED_WIDTH_MULTIPLES = (1.0, 1.5, 2.0)


@dataclasses.dataclass
class Regression:
    """The rows of a catalog's regression and what the fit needs to remember of them.

    Attributes
    ----------
    theta : ndarray, shape (n * R, F)
        Stacked regression matrix, rows coordinate-major.
    states : ndarray, shape (S, 4n + 1)
        The library inputs the rows come from (smoothed for the weak form), for the checks of
        the catalog's domain, its dependent columns and the mass matrix.
    formulation : {"strong", "weak"}
    noise : WeakNoise or None
        Weak form on estimated positions: the noise the rows carry
        (:class:`~pysindy_xl.weak.WeakNoise`).
    weak_info : dict or None
        Weak form: the test-function half-width, test functions per trajectory and the
        smoother's noise estimate.
    """

    theta: np.ndarray
    states: np.ndarray
    formulation: str
    noise: object = None
    weak_info: dict | None = None


def differentiation_function(method=None, unbiased: bool = False):
    """The function ``derivative(values, t)`` that estimates missing derivatives.

    Parameters
    ----------
    method : pysindy differentiation method, optional
        Used as it is when given.
    unbiased : bool, default False
        Without ``method``: fourth-order finite differences (no smoothing bias, which a
        null-space search of unforced data cannot tell from the law) instead of
        ``ps.SmoothedFiniteDifference()`` (robust to moderate noise; off a uniform grid its
        Savitzky-Golay smoothing is done on the actual times).

    Returns
    -------
    callable
        Checks that the result has the shape of its input and is finite.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 101)
    >>> d = differentiation_function(unbiased=True)(t[:, None] ** 2, t)
    >>> bool(np.allclose(d[:, 0], 2 * t))
    True
    """
    if method is None:
        method = ps.FiniteDifference(order=4) if unbiased else _smoothed_difference
    if not callable(method):
        raise TypeError("differentiation_method: expected a pysindy differentiation method")

    def derivative(values, t):
        result = np.asarray(method(values, t), dtype=float)
        if result.shape != values.shape or not np.all(np.isfinite(result)):
            raise ValueError("differentiation_method: returned an invalid derivative")
        return result

    return derivative


def _smoothed_difference(values, t):
    """``ps.SmoothedFiniteDifference()`` (Savitzky-Golay, 11 samples, cubic, then central
    differences) with its smoothing done on the actual times off a uniform grid: read in
    sample order, a smooth signal on jittered stamps looks noisy (a 1 kHz log jittering by
    8 %: accelerations 10 times their own size in error)."""
    if np.isscalar(t) or is_uniform(t) or len(t) < 11:
        return ps.SmoothedFiniteDifference()(values, t)
    return ps.FiniteDifference()(differentiate(t, values, 0, stencil=11, degree=3), t)


def trajectory_data(x, t, x_dot, x_ddot, u, n: int, sample_mask=None,
                    derivative=None) -> list[dict]:
    """The validated trajectories of ``fit``: one dict of arrays per trajectory.

    Parameters
    ----------
    x, t, x_dot, x_ddot, u, sample_mask
        As :meth:`XLSINDy.fit <pysindy_xl.XLSINDy.fit>` takes them (``t`` already defaulted).
    n : int
        Coordinates.
    derivative : callable, optional
        ``derivative(values, t)`` (:func:`differentiation_function`) for missing velocities
        and accelerations; without it they stay None.

    Returns
    -------
    list of dict
        Keys ``"x"``, ``"t"``, ``"x_dot"``, ``"x_ddot"``, ``"u"``, ``"mask"``.
    """
    data = trajectory_arrays(x, t, x_dot, x_ddot, u, sample_mask, n)
    if derivative is not None:
        for arrays in data:
            if arrays["x_dot"] is None:
                arrays["x_dot"] = derivative(arrays["x"], arrays["t"])
            if arrays["x_ddot"] is None:
                arrays["x_ddot"] = derivative(arrays["x_dot"], arrays["t"])
    return data


def build_regression(library, data, formulation: str, test_functions=None, smoother=None,
                     half_width=None, moving=None, propagate=True) -> Regression:
    """The rows of a fitted catalog on trajectories, in the strong or weak formulation.

    Parameters
    ----------
    library : fitted CatalogRepartition
    data : list of dict
        From :func:`trajectory_data`; the strong form needs ``x_dot`` and ``x_ddot``.
    formulation : {"strong", "weak"}
    test_functions, smoother : optional
        Weak form: default ``BumpTestFunctions()`` (of the widths
        :data:`UNFORCED_WIDTH_MULTIPLES` when no trajectory has forces) and
        ``WhittakerSmoother()``; the smoother is copied (smoothing fits it).
    half_width : float, optional
        Weak form: the test functions' half-width (default: chosen from the data, as in a fit).
    moving : array of bool, shape (n,), optional
        Weak form: the coordinates whose spectra choose the default half-width (default all;
        a fit leaves out those that hold still, :mod:`pysindy_xl.still`).
    propagate : bool, default True
        Weak form: propagate the noise of the positions into the rows (``Regression.noise``);
        False: the rows only.

    Returns
    -------
    Regression

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> library = px.CatalogRepartition([px.LagrangeLibrary(c, [c.qd[0] ** 2])]).fit()
    >>> t = np.linspace(0, 1, 11)
    >>> data = trajectory_data(np.sin(t), t, np.cos(t), -np.sin(t), None, 1)
    >>> build_regression(library, data, "strong").theta.shape
    (11, 2)
    """
    if formulation == "weak":
        if test_functions is None:
            unforced = all(d["u"] is None for d in data)
            test_functions = BumpTestFunctions(
                width_multiples=UNFORCED_WIDTH_MULTIPLES if unforced else None)
        theta, states, noise, info = weak_regression(
            library, data, test_functions,
            copy.deepcopy(smoother) or WhittakerSmoother(),
            noise="draws" if propagate else "none",
            half_width=half_width, width_columns=moving)
        return Regression(theta, states, "weak", noise, info)
    if formulation != "strong":
        raise ValueError(f"formulation: expected 'strong' or 'weak', got {formulation!r}")
    states = np.vstack([
        stack_variables(d["x"], d["x_dot"], d["x_ddot"], d["u"], d["t"])[d["mask"]]
        for d in data])
    if len(states) == 0:
        raise ValueError("sample_mask: no sample left to fit")
    return Regression(library.transform(states), states, "strong")


#: Fits on whitened rows at most (:func:`solve_weak_problem`): the last one is kept even when
#: its support still differs from the law that weighed it.
MAX_REWEIGHTS = 3


def solve_weak_problem(optimizer, problem, noise=None, weigh=False):
    """Fit ``optimizer`` on ``problem``, given the propagated noise of its rows.

    With ``noise`` (:class:`~pysindy_xl.weak.WeakNoise`, the rows' errors drawn again) the
    problem gets its noise moments and the draws themselves (for the optimizers that use
    them, :func:`~pysindy_xl.optimizers.solve_problem`). With ``weigh`` the fit is
    iteratively reweighted: the rows are whitened by the covariance of the residual of the
    latest law (:meth:`~pysindy_xl.weak.WeakNoise.whitener`, starting from the optimizer's
    pilot law) and refitted, until the support found is the one that set the weights (at most
    :data:`MAX_REWEIGHTS` fits); only the answer's warnings are shown.

    Parameters
    ----------
    optimizer : catalog optimizer
        Fitted in place (the reweighted fits on clones).
    problem : CatalogProblem
    noise : WeakNoise, optional
    weigh : bool, default False

    Returns
    -------
    The fitted optimizer.
    """
    def fit(optimizer, rows, propagated, whitened=False):
        # whitened rows are each in units of their own noise: rebalancing the blocks by
        # their scales would undo the weighting (an undriven coordinate's rows, where
        # the law is tested hardest, weighed 30 times less than a driven one's)
        moments, draws = ((None, None) if propagated is None
                          else (propagated.moments(), propagated.draws))
        return solve_problem(optimizer, dataclasses.replace(
            problem, theta=rows, noise_moments=moments, noise_draws=draws,
            balance=not whitened))

    def unweighted(reason):  # said only of a fit that succeeds
        fitted = fit(optimizer, problem.theta, noise)
        warnings.warn(f"residual_covariance: {reason}; the rows are fitted unweighted",
                      UserWarning, stacklevel=3)
        return fitted

    if noise is None or not weigh:
        return fit(optimizer, problem.theta, noise)
    try:
        with warnings.catch_warnings():  # the pilot only sets the first weights
            warnings.simplefilter("ignore")
            law = fit(pilot_optimizer(optimizer), problem.theta, noise).coef_
    except (ValueError, RuntimeError, np.linalg.LinAlgError) as error:
        return unweighted(f"the pilot fit failed ({error})")
    for _ in range(MAX_REWEIGHTS):
        whiten = noise.whitener(law)
        if whiten is None:
            return unweighted("the residual of the law carries no noise")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fitted = fit(clone(optimizer), whiten(problem.theta), noise.whitened(whiten),
                         whitened=True)
        settled = np.array_equal(fitted.coef_ != 0, law != 0)
        law = fitted.coef_
        if settled:
            break
    for record in caught:
        warnings.warn(record.message, record.category, stacklevel=3)
    return fitted
