"""The trajectories of a fit: checked arrays, the formulation, missing derivatives.

The first step of the fit stage (:mod:`pysindy_xl.fit`): :func:`trajectory_data` validates the
arrays of ``fit`` (one trajectory or a list) and estimates missing velocities and
accelerations with a differentiation function (:func:`differentiation_function`), which the
strong form needs; :func:`resolve_formulation` chooses between the strong and the weak form.
"""

from __future__ import annotations

import numpy as np
import pysindy as ps

from .._inputs import trajectory_arrays
from ..weak import differentiate
from ..weak.smoothing import is_uniform

__all__ = ["trajectory_data", "differentiation_function", "resolve_formulation",
           "FORMULATIONS"]

FORMULATIONS = ("auto", "strong", "weak")


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


def resolve_formulation(formulation: str, measured: bool, differentiation_method=None) -> str:
    """The formulation a fit uses: ``"strong"`` or ``"weak"``.

    The one place that resolves ``formulation="auto"``: strong when the derivatives are
    ``measured`` (velocities and accelerations given) or a ``differentiation_method`` is set,
    weak (integrated against test functions of smoothed positions) otherwise.

    Parameters
    ----------
    formulation : {"auto", "strong", "weak"}
    measured : bool
        Whether ``x_dot`` and ``x_ddot`` were given.
    differentiation_method : optional
        The estimator's.

    Returns
    -------
    str

    Examples
    --------
    >>> resolve_formulation("auto", measured=False), resolve_formulation("auto", True)
    ('weak', 'strong')
    """
    if formulation != "auto":
        return formulation
    return "strong" if measured or differentiation_method is not None else "weak"
