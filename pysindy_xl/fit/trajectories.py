"""The check step of the fit stage: the catalog, the formulation, the checked trajectories."""

from __future__ import annotations

import numpy as np
import pysindy as ps
from sklearn.base import clone

from .._inputs import trajectory_arrays
from ..feature_library import CatalogRepartition, SymbolicLibrary
from ..optimizers import catalog_tags
from ..weak import differentiate
from ..weak.smoothing import is_uniform

__all__ = ["check_fit", "estimator_trajectories", "trajectory_data",
           "differentiation_function", "resolve_formulation", "FORMULATIONS"]

FORMULATIONS = ("auto", "strong", "weak")


def differentiation_function(method=None, unbiased: bool = False):
    """The function that estimates missing derivatives, checking its result.

    Parameters
    ----------
    method : pysindy differentiation method, optional
        Used as it is; default None: ``unbiased`` decides.
    unbiased : bool, default False
        Without ``method``: fourth-order finite differences (no smoothing bias, which a
        null-space search of unforced data cannot tell from the law), else
        ``ps.SmoothedFiniteDifference()`` (smoothing on the actual times off a uniform grid).

    Returns
    -------
    callable
        ``derivative(values, t) -> ndarray`` of the shape of ``values``, checked finite.

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
    """``ps.SmoothedFiniteDifference()`` with its smoothing done on the actual times off a uniform
    grid: read in sample order, a smooth signal on jittered stamps looks noisy.
    """
    if np.isscalar(t) or is_uniform(t) or len(t) < 11:
        return ps.SmoothedFiniteDifference()(values, t)
    return ps.FiniteDifference()(differentiate(t, values, 0, stencil=11, degree=3), t)


def trajectory_data(x, t, x_dot, x_ddot, u, n: int, sample_mask=None,
                    derivative=None) -> list[dict]:
    """The validated trajectories of ``fit``: one dict of arrays per trajectory.

    Parameters
    ----------
    x : array (N, n) or list of arrays
        Positions, as :meth:`XLSINDy.fit <pysindy_xl.XLSINDy.fit>` takes them.
    t : float, array (N,) or list of arrays
        Time step or sample times (not None).
    x_dot, x_ddot : same layout as ``x`` or None
        Measured velocities and accelerations.
    u : same layout as ``x`` or None
        Generalized forces.
    n : int
        Number of coordinates.
    sample_mask : bool array (N,) or list of them, optional
        Samples to leave out; default None.
    derivative : callable, optional
        ``derivative(values, t)`` (:func:`differentiation_function`) fills missing velocities
        and accelerations; default None: they stay None.

    Returns
    -------
    list of dict
        Per trajectory: ``"x"``, ``"t"``, ``"x_dot"``, ``"x_ddot"``, ``"u"``, ``"mask"``.

    Raises
    ------
    ValueError
        Naming the argument, for wrong shapes, mismatched lengths, NaN or inf, or times not
        strictly increasing.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 11)
    >>> data = trajectory_data(np.sin(t), t, None, None, None, 1)
    >>> data[0]["x"].shape, data[0]["x_dot"]
    ((11, 1), None)
    """
    data = trajectory_arrays(x, t, x_dot, x_ddot, u, sample_mask, n)
    if derivative is not None:
        for arrays in data:
            if arrays["x_dot"] is None:
                arrays["x_dot"] = derivative(arrays["x"], arrays["t"])
            if arrays["x_ddot"] is None:
                arrays["x_ddot"] = derivative(arrays["x_dot"], arrays["t"])
    return data


def resolve_formulation(formulation: str, measured: bool, differentiation_method=None,
                        impulsive: bool = False) -> str:
    """The formulation a fit uses, ``"strong"`` or ``"weak"``: the one place that resolves "auto".

    Strong when a ``differentiation_method`` is set, or when the derivatives are ``measured``
    and no catalog entry is ``impulsive`` (sampled pointwise an impulse is caught or missed by
    chance; integrated by parts it is exact); weak otherwise.

    Parameters
    ----------
    formulation : {"auto", "strong", "weak"}
        The estimator's setting; ``"strong"`` and ``"weak"`` come back as they are.
    measured : bool
        Whether velocities and accelerations are given for every trajectory.
    differentiation_method : pysindy differentiation method, optional
        The estimator's setting; default None.
    impulsive : bool, default False
        Whether an acceleration enters a column with a switching coefficient
        (:meth:`~pysindy_xl.feature_library.SymbolicLibrary.impulsive`).

    Returns
    -------
    str
        ``"strong"`` or ``"weak"``.

    Examples
    --------
    >>> resolve_formulation("auto", measured=False), resolve_formulation("auto", True)
    ('weak', 'strong')
    >>> resolve_formulation("auto", True, impulsive=True)
    'weak'
    """
    if formulation != "auto":
        return formulation
    if differentiation_method is not None:
        return "strong"
    return "strong" if measured and not impulsive else "weak"


def _catalog(feature_library) -> CatalogRepartition:
    """The estimator's catalog as a :class:`~pysindy_xl.CatalogRepartition`."""
    if feature_library is None:
        raise ValueError("feature_library: a catalog is required (e.g. LagrangeLibrary)")
    if isinstance(feature_library, CatalogRepartition):
        feature_library.flat_libraries()  # a catalog nested in itself: a clear error
        return feature_library
    if isinstance(feature_library, SymbolicLibrary):
        return CatalogRepartition([feature_library])
    raise TypeError(
        "feature_library: expected a pysindy_xl library (LagrangeLibrary, ClassicalLibrary, "
        f"ExternalForces, CatalogRepartition), got {type(feature_library).__name__}")


def estimator_trajectories(estimator, x, t, x_dot, x_ddot, u, n, differentiate=True,
                           sample_mask=None) -> list[dict]:
    """The checked trajectories of a call of an :class:`~pysindy_xl.XLSINDy`.

    Parameters
    ----------
    estimator : XLSINDy
        The estimator (its ``t_default``, ``differentiation_method`` and optimizer's tags).
    x, t, x_dot, x_ddot, u
        As :meth:`XLSINDy.fit <pysindy_xl.XLSINDy.fit>` takes them; ``t`` None defaults to
        ``estimator.t_default``.
    n : int
        Number of coordinates.
    differentiate : bool, default True
        Estimate missing derivatives with the estimator's ``differentiation_method`` or the
        estimate its optimizer's tags prefer (``derivative_estimate``; unforced data:
        unbiased); False: they stay None.
    sample_mask : bool array (N,) or list of them, optional
        Samples to leave out; default None.

    Returns
    -------
    list of dict
        As :func:`trajectory_data`.
    """
    derivative = None
    if differentiate:
        optimizer = estimator.optimizer
        prefers = ("unbiased" if optimizer is None or optimizer == "implicit" else
                   "smoothed" if isinstance(optimizer, str)
                   else catalog_tags(optimizer).derivative_estimate)
        derivative = differentiation_function(estimator.differentiation_method,
                                              unbiased=u is None and prefers == "unbiased")
    return trajectory_data(x, estimator.t_default if t is None else t, x_dot, x_ddot, u, n,
                           sample_mask, derivative)


def check_fit(estimator, x, t, x_dot, x_ddot, u, sample_mask):
    """The check step of ``estimator.fit``: its catalog, trajectories and formulation.

    Parameters
    ----------
    estimator : XLSINDy
        Read, never changed (the catalog is cloned before it is fitted).
    x, t, x_dot, x_ddot, u, sample_mask
        As :meth:`XLSINDy.fit <pysindy_xl.XLSINDy.fit>` takes them (None where absent).

    Returns
    -------
    library, data, formulation
        The fitted catalog, :func:`trajectory_data` (with the derivatives the strong form
        needs) and ``"strong"`` or ``"weak"``.

    Raises
    ------
    ValueError
        Naming the argument: bad arrays, a catalog without accelerations, an explicit
        optimizer without forces.

    Examples
    --------
    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> model = px.XLSINDy(px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2]))
    >>> t = np.linspace(0, 1, 101)
    >>> library, data, formulation = check_fit(model, np.sin(t), t, None, None, np.cos(t), None)
    >>> library.get_feature_names(), formulation, data[0]["x_dot"]
    (['F[tau]', 'L[x_dot**2]', 'L[x**2]'], 'weak', None)
    """
    library = clone(_catalog(estimator.feature_library))
    library.fit()
    measured = x_dot is not None and x_ddot is not None
    formulation = resolve_formulation(
        estimator.formulation, measured, estimator.differentiation_method,
        impulsive=measured and estimator.formulation == "auto" and library.impulsive())
    data = estimator_trajectories(estimator, x, t, x_dot, x_ddot, u, library.coords.n,
                                  formulation == "strong", sample_mask)
    if not library.involves(library.coords.qdd).any():
        raise ValueError("feature_library: no term contains an acceleration; add Lagrangian terms "
                         "with velocities (e.g. q_dot**2) or classical terms in q_ddot")
    optimizer = estimator.optimizer
    if u is None and (optimizer == "explicit" or catalog_tags(optimizer).requires_forces):
        raise ValueError("u: explicit regression needs the generalized forces; pass u, or use "
                         "ImplicitOptimizer / MixedOptimizer for unforced data")
    return library, data, formulation
