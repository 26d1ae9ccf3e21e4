"""Forces that drive a simulation, of time (``u``) and of the state (``feedback``), checked
once and turned into fast callables for the integrator."""

from __future__ import annotations

import numpy as np
import scipy.interpolate

__all__ = ["force_function", "feedback_function"]


_INTERPOLATIONS = ("cubic", "linear", "previous")


def force_function(u, t: np.ndarray, n: int, interpolation: str = "cubic"):
    """The ``u`` argument of ``simulate`` as a checked function of time.

    Parameters
    ----------
    u : None, array (len(t), n) or callable ``u(t) -> (n,)``
        The forces: zero, samples over the times ``t``, or a function of time.
    t : ndarray, shape (T,)
        The simulation's output times.
    n : int
        Number of coordinates.
    interpolation : {"cubic", "linear", "previous"}, default "cubic"
        How an array is read between samples: cubic spline (smooth: adaptive integrators take
        fewer steps), linearly, or zero-order hold (``"previous"``, piecewise-constant commands).

    Returns
    -------
    callable
        ``u(t) -> ndarray (n,)``; an array is held at its first and last value outside ``t``.

    Raises
    ------
    TypeError, ValueError
        When ``u`` has the wrong type, shape or non-finite values.

    Examples
    --------
    >>> import numpy as np
    >>> u = force_function(np.array([[0.0], [2.0], [4.0]]), np.array([0.0, 1.0, 2.0]), 1,
    ...                    interpolation="linear")
    >>> u(0.5)
    array([1.])
    """
    if interpolation not in _INTERPOLATIONS:
        raise ValueError(f"interpolation: expected one of {_INTERPOLATIONS}, got "
                         f"{interpolation!r}")
    if u is None:
        zeros = np.zeros(n)
        return lambda _t: zeros
    if callable(u):
        value = np.asarray(u(float(t[0])), dtype=float)
        if value.shape != (n,):
            raise ValueError(f"u: the callable must return an array of shape ({n},), got "
                             f"{value.shape}")

        def call(s):
            out = np.asarray(u(s), dtype=float)
            if out.shape != (n,) or not np.all(np.isfinite(out)):
                raise ValueError(f"u: u({s}) returned {out!r}, expected {n} finite values")
            return out

        return call
    try:
        u = np.asarray(u, dtype=float)
    except (TypeError, ValueError):
        raise TypeError("u: expected None, an array (len(t), n) or a callable u(t)") from None
    if u.shape != (len(t), n):
        raise ValueError(f"u: expected an array of shape (len(t), n) = {(len(t), n)}, got "
                         f"{u.shape}")
    if not np.all(np.isfinite(u)):
        raise ValueError("u: contains NaN or inf")
    if len(t) == 1:
        return lambda _t: u[0]
    if interpolation == "cubic" and len(t) >= 4:
        spline = scipy.interpolate.CubicSpline(t, u, axis=0, extrapolate=False)
        t_first, t_last = t[0], t[-1]
        return lambda s: u[0] if s <= t_first else u[-1] if s >= t_last else spline(s)
    kind = "previous" if interpolation == "previous" else "linear"
    interpolant = scipy.interpolate.interp1d(t, u, axis=0, kind=kind, assume_sorted=True,
                                             bounds_error=False, fill_value=(u[0], u[-1]))
    return interpolant


def feedback_function(feedback, x0: np.ndarray, t0: float, n: int):
    """The ``feedback`` argument of ``simulate``, checked once and wrapped for the integrator.

    Parameters
    ----------
    feedback : callable or None
        ``feedback(t, q, qd) -> (n,)``.
    x0 : ndarray, shape (2n,)
        Initial state, at which ``feedback`` is checked.
    t0 : float
        Initial time.
    n : int
        Number of coordinates.

    Returns
    -------
    callable or None
        ``f(t, state) -> ndarray (n,)`` (``q``, ``qd`` passed as copies); None without feedback.

    Raises
    ------
    TypeError, ValueError
        When ``feedback`` is not callable or returns the wrong shape or non-finite values.

    Examples
    --------
    >>> import numpy as np
    >>> pd = feedback_function(lambda t, q, qd: -4.0 * q - qd, np.array([1.0, 0.5]), 0.0, 1)
    >>> pd(0.0, np.array([1.0, 0.5]))
    array([-4.5])
    """
    if feedback is None:
        return None
    if not callable(feedback):
        raise TypeError(f"feedback: expected a function f(t, q, qd) -> forces of shape ({n},), "
                        f"got {type(feedback).__name__}")

    def call(s, state):
        out = np.asarray(feedback(s, state[:n].copy(), state[n:].copy()), dtype=float)
        if out.shape != (n,):
            raise ValueError(f"feedback: f(t, q, qd) must return an array of shape ({n},), got "
                             f"shape {out.shape}")
        return out

    first = call(float(t0), np.asarray(x0, dtype=float))
    if not np.all(np.isfinite(first)):
        raise ValueError(f"feedback: f(t, q, qd) at the initial state returned {first!r}, "
                         f"expected {n} finite values")
    return call
