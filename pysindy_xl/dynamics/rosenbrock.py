r"""Fixed-step, linearly implicit simulation of ``M(q, qd) qdd = g(t, q, qd)``: stiff closed loops.

A servo's velocity gain on a light link gives modes up to ``|lambda| ~ kv / M ~ 1e5 1/s``,
which explicit solvers can only follow at tiny steps; a Rosenbrock method solves one linear
system per stage instead, so its step is set by the motion alone.

ROS2 (Verwer, Spee, Blom and Hundsdorfer, 1999), L-stable and of order two for any matrix
``J`` (a W-method), on ``y = (q, v)`` with ``F(t, y) = (v, M^{-1} g)``:

.. math::

    W = I - \gamma h J, \quad \gamma = 1 + 1/\sqrt 2, \quad
    W k_1 = F(t_n, y_n), \quad W k_2 = F(t_n + h, y_n + h k_1) - 2 k_1, \quad
    y_{n+1} = y_n + \tfrac32 h k_1 + \tfrac12 h k_2 .

``J = [[0, 1], [M^{-1} G_q, M^{-1} G_v]]`` with ``G_q = dg/dq``, ``G_v = dg/dv`` (secant
differences, refreshed every ``jacobian_every`` steps), so ``W k = r`` reduces to one
``n x n`` system,

.. math:: (M - \gamma h G_v - \gamma^2 h^2 G_q)\, k_v = M r_v + \gamma h G_q r_q, \quad
          k_q = r_q + \gamma h k_v .
"""

from __future__ import annotations

import math
import time as _time

import numpy as np

__all__ = ["ros2", "GAMMA"]

#: ROS2's ``gamma`` (L-stable choice).
GAMMA = 1.0 + 1.0 / math.sqrt(2.0)


class RosenbrockStop(Exception):
    """The run stopped at time ``t`` for ``reason``; ``states`` are the outputs reached."""

    def __init__(self, t: float, reason: str, states=None):
        super().__init__(reason)
        self.t, self.reason, self.states = t, reason, states


def _jacobians(parts, s, state, n, dq, dv):
    """Central secant differences ``dg/dq``, ``dg/dv`` at ``state``."""
    columns = []
    for offset, delta in ((0, dq), (n, dv)):
        block = np.empty((n, n))
        for j in range(n):
            up, down = state.copy(), state.copy()
            up[offset + j] += delta
            down[offset + j] -= delta
            block[:, j] = (parts(s, up)[1] - parts(s, down)[1]) / (2 * delta)
        columns.append(block)
    return columns


def ros2(parts, x0, t, step, jacobian_every: int = 50, divergence_bound: float = np.inf,
         timeout: float | None = None, dq: float = 1e-4, dv: float = 1e-2,
         tolerance: float | None = 1e-5):
    """Integrate ``M(q, v) qdd = g(t, q, v)`` with the two-stage Rosenbrock method ROS2.

    L-stable and linearly implicit (module docstring): one linear solve per stage, with a
    secant Jacobian refreshed every ``jacobian_every`` steps; for stiff closed loops.

    Parameters
    ----------
    parts : callable
        ``parts(t, state) -> (M, g)``: the mass matrix (n, n) and the forces (n,) at
        ``state = [q, v]``.
    x0 : array, shape (2n,)
        Initial state.
    t : array, shape (T,)
        Output times, strictly increasing.
    step : float
        Largest step.
    jacobian_every : int, default 50
        Steps between two secant Jacobians (``4n`` evaluations each).
    divergence_bound : float, default inf
        The run stops when a state component exceeds it.
    timeout : float or None, default None
        The run stops after this many seconds (None: no bound).
    dq, dv : float, default 1e-4 and 1e-2
        Secant steps in positions and velocities (a secant over ``dv`` averages a smooth
        dry-friction sign).
    tolerance : float or None, default 1e-5
        Bound on the local error relative to ``1 + |y_i|`` (against the embedded first-order
        step ``h (k_1 + k_2) / 2``); None: fixed steps.

    Returns
    -------
    ndarray, shape (T, 2n)
        The states at ``t``.

    Raises
    ------
    RosenbrockStop
        With the valid rows, on a non-finite or singular step, divergence or timeout.

    Examples
    --------
    A stiff oscillator ``1e-3 qdd = -100 q - 100 qd`` (modes near -1 and -1e5 1/s) at 10 ms:

    >>> import numpy as np
    >>> parts = lambda s, y: (np.array([[1e-3]]), np.array([-100 * y[0] - 100 * y[1]]))
    >>> x = ros2(parts, [1.0, 0.0], np.linspace(0.0, 1.0, 11), 0.01)
    >>> bool(abs(x[-1, 0] - np.exp(-1.0)) < 1e-3)
    True
    """
    x0 = np.asarray(x0, dtype=float)
    n = x0.size // 2
    out = np.empty((len(t), 2 * n))
    out[0] = x0
    state = x0.copy()
    start = _time.perf_counter()
    count = 0
    g_q = g_v = None
    h = step
    k = 1
    try:
        for k in range(1, len(t)):
            s, s1 = float(t[k - 1]), float(t[k])
            if tolerance is None:
                h = (s1 - s) / max(1, math.ceil((s1 - s) / step * (1 - 1e-12)))
            while s < s1 - 1e-12 * max(1.0, abs(s1)):
                h = min(h, step, s1 - s)
                if g_q is None or count % jacobian_every == 0:
                    g_q, g_v = _jacobians(parts, s, state, n, dq, dv)
                    if timeout is not None and _time.perf_counter() - start > timeout:
                        raise RosenbrockStop(s, "timeout", out[:k])
                count += 1
                new, error = _step(parts, s, state, h, g_q, g_v, n)
                if tolerance is not None:
                    ratio = float(np.max(np.abs(error) / (tolerance * (1 + np.abs(state)))))
                    if not np.isfinite(ratio) or ratio > 1:  # reject, retry smaller
                        h *= max(0.2, 0.9 / math.sqrt(ratio)) if np.isfinite(ratio) else 0.2
                        if h < 1e-12 * max(1.0, abs(s)):
                            raise RosenbrockStop(s, "step size underflow", out[:k])
                        continue
                if not np.all(np.isfinite(new)):
                    raise RosenbrockStop(s + h, "non-finite derivative", out[:k])
                if np.max(np.abs(new)) > divergence_bound:
                    raise RosenbrockStop(s + h, "diverged", out[:k])
                state, s = new, s + h
                if tolerance is not None:
                    h *= min(2.0, 0.9 / math.sqrt(max(ratio, 1e-4)))
            out[k] = state
    except RosenbrockStop as stop:
        if stop.states is None:
            stop.states = out[:k]
        raise
    return out


def _step(parts, s, state, h, g_q, g_v, n):
    """One ROS2 step from ``state`` at ``s``: the new state and the local error estimate."""
    mass, force = parts(s, state)
    velocity = state[n:]
    matrix = mass - GAMMA * h * g_v - (GAMMA * h) ** 2 * g_q
    try:
        k1_v = np.linalg.solve(matrix, force + GAMMA * h * g_q @ velocity)
        k1_q = velocity + GAMMA * h * k1_v
        probe = state + h * np.concatenate([k1_q, k1_v])
        mass2, force2 = parts(s + h, probe)
        r_q = probe[n:] - 2 * k1_q
        r_v = np.linalg.solve(mass2, force2) - 2 * k1_v
        k2_v = np.linalg.solve(matrix, mass @ r_v + GAMMA * h * g_q @ r_q)
    except np.linalg.LinAlgError:
        raise RosenbrockStop(s, "singular mass matrix") from None
    k2_q = r_q + GAMMA * h * k2_v
    k1, k2 = np.concatenate([k1_q, k1_v]), np.concatenate([k2_q, k2_v])
    return state + h * (1.5 * k1 + 0.5 * k2), 0.5 * h * (k1 + k2)
