r"""Linear-quadratic regulation of a discrete model near an equilibrium.

:func:`linearize` differentiates ``x_{k+1} = F(x_k, u_k)`` with JAX at ``(x*, u*)``;
:func:`discrete_lqr` solves the discrete algebraic Riccati equation

.. math:: P = Q + A^T P A - A^T P B (R + B^T P B)^{-1} B^T P A, \qquad
          K = (R + B^T P B)^{-1} B^T P A,

and the control ``u = u* - K (x - x*)`` minimizes ``sum_k e_k^T Q e_k + v_k^T R v_k`` of the
linear model, with cost-to-go ``e^T P e``."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.linalg

from .._optional import import_optional

jax = import_optional("jax", purpose="pysindy_xl.control")
jnp = import_optional("jax.numpy", purpose="pysindy_xl.control")

__all__ = ["LQRGain", "discrete_lqr", "linearize"]


class LQRGain(NamedTuple):
    """Result of :func:`discrete_lqr`.

    Parameters
    ----------
    gain : numpy.ndarray (m, N)
        ``K`` of ``u = -K e``.
    cost_to_go : numpy.ndarray (N, N)
        ``P`` of the cost-to-go ``e^T P e``.

    Examples
    --------
    See :func:`discrete_lqr`.
    """

    gain: np.ndarray
    cost_to_go: np.ndarray


def linearize(step, x, u) -> tuple[np.ndarray, np.ndarray]:
    """Jacobians of a discrete model by forward-mode automatic differentiation.

    Parameters
    ----------
    step : callable
        ``F(x (2n,), u (m,)) -> x (2n,)``, pure JAX.
    x : array (2n,)
        State of the linearization.
    u : array (m,)
        Control of the linearization.

    Returns
    -------
    tuple of numpy.ndarray
        ``A = dF/dx`` (2n, 2n) and ``B = dF/du`` (2n, m) at ``(x, u)``.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> a, b = linearize(lambda x, u: jnp.array([x[0] + x[1], x[1] + u[0]]),
    ...                  [0.0, 0.0], [0.0])
    >>> a.tolist(), b.tolist()
    ([[1.0, 1.0], [0.0, 1.0]], [[0.0], [1.0]])
    """
    x = jnp.asarray(x, dtype=jnp.asarray(0.0).dtype)
    u = jnp.asarray(u, dtype=x.dtype)
    a, b = jax.jacfwd(step, argnums=(0, 1))(x, u)
    return np.asarray(a, dtype=float), np.asarray(b, dtype=float)


def discrete_lqr(a, b, state_weights, control_weights) -> LQRGain:
    """Infinite-horizon discrete LQR gain of ``x' = A x + B u`` (module docstring).

    Parameters
    ----------
    a : array (N, N)
        State matrix ``A``.
    b : array (N, m)
        Input matrix ``B``.
    state_weights : array (N, N) or (N,)
        ``Q`` or its diagonal.
    control_weights : array (m, m) or (m,)
        ``R`` or its diagonal.

    Returns
    -------
    LQRGain

    Raises
    ------
    ValueError
        On shapes that do not match, or when ``(A, B)`` cannot be stabilized (no stabilizing
        solution of the Riccati equation).

    Examples
    --------
    >>> a, b = np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.005], [0.1]])
    >>> gain = discrete_lqr(a, b, [1.0, 1.0], [1.0]).gain
    >>> bool(np.all(np.abs(np.linalg.eigvals(a - b @ gain)) < 1))
    True
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"a: expected a square matrix, got shape {a.shape}")
    if b.ndim != 2 or b.shape[0] != a.shape[0]:
        raise ValueError(f"b: expected shape ({a.shape[0]}, m), got {b.shape}")
    q = np.asarray(state_weights, dtype=float)
    q = np.diag(q) if q.ndim == 1 else q
    r = np.asarray(control_weights, dtype=float)
    r = np.diag(r) if r.ndim == 1 else r
    if q.shape != a.shape:
        raise ValueError(f"state_weights: expected shape {a.shape} or ({a.shape[0]},), got "
                         f"{q.shape}")
    if r.shape != (b.shape[1], b.shape[1]):
        raise ValueError(f"control_weights: expected shape {(b.shape[1],) * 2} or "
                         f"({b.shape[1]},), got {r.shape}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ValueError("a, b: the linearization is not finite")
    try:
        p = scipy.linalg.solve_discrete_are(a, b, q, r)
    except (np.linalg.LinAlgError, ValueError) as error:
        raise ValueError(f"a, b: no stabilizing LQR solution ({error})") from None
    gain = np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a)
    if not np.all(np.abs(np.linalg.eigvals(a - b @ gain)) < 1.0):
        raise ValueError("a, b: the LQR gain does not stabilize the linearization")
    return LQRGain(gain, p)
