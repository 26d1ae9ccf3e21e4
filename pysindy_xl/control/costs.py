r"""Costs of a trajectory, written as pure JAX functions.

A :class:`Cost` is a pair ``running(x, u) -> float`` (per control period) and
``terminal(x) -> float``; a plan minimizes

.. math:: J = \sum_{k=0}^{H-1} \ell(x_k, u_k) + \ell_f(x_H).

Any pair of JAX functions of one state (and control) is a cost; :func:`quadratic_cost` and
:func:`swing_up_cost` build the usual ones. Angles are compared on the circle."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from .._optional import import_optional
from .._validation import check_numeric_array

jnp = import_optional("jax.numpy", purpose="pysindy_xl.control")

__all__ = ["Cost", "angle_error", "quadratic_cost", "swing_up_cost"]


class Cost(NamedTuple):
    """A trajectory cost: two pure JAX functions.

    Parameters
    ----------
    running : callable
        ``running(x (2n,), u (m,)) -> scalar``, the cost of one control period.
    terminal : callable
        ``terminal(x (2n,)) -> scalar``, the cost of the final state.

    Examples
    --------
    >>> cost = Cost(lambda x, u: jnp.sum(x ** 2) + jnp.sum(u ** 2), lambda x: jnp.sum(x ** 2))
    >>> float(cost.terminal(jnp.array([1.0, 2.0])))
    5.0
    """

    running: Callable
    terminal: Callable


def _angle_mask(n: int, angles) -> np.ndarray:
    mask = np.zeros(2 * n, dtype=bool)
    for i in angles:
        if not 0 <= int(i) < n:
            raise ValueError(f"angles: expected coordinate indices in [0, {n}), got {list(angles)}")
        mask[int(i)] = True
    return mask


def angle_error(x, goal, angle_mask):
    """``x - goal`` with the entries flagged in ``angle_mask`` wrapped to ``(-pi, pi]``.

    Parameters
    ----------
    x, goal : array (..., 2n)
        States.
    angle_mask : bool array (2n,)
        Entries compared on the circle.

    Returns
    -------
    jax.Array
        The difference, shape of ``x``.

    Examples
    --------
    >>> import numpy as np
    >>> err = angle_error(jnp.array([0.0, -3.0]), jnp.array([0.0, np.pi]), np.array([False, True]))
    >>> round(float(err[1]), 4)  # -3 - pi + 2 pi
    0.1416
    """
    error = x - goal
    wrapped = jnp.mod(error + jnp.pi, 2.0 * jnp.pi) - jnp.pi
    return jnp.where(angle_mask, wrapped, error)


def _matrix(value, size: int, name: str) -> np.ndarray:
    """The weights ``value`` (a diagonal or a matrix) as a symmetric positive semidefinite
    ``(size, size)`` matrix: other weights make a cost without a minimum (the planners would
    push the state away from the goal)."""
    value = check_numeric_array(value, name, ndim=(1, 2), min_samples=0)
    if value.ndim == 1:
        value = np.diag(value)
    if value.shape != (size, size):
        raise ValueError(f"{name}: expected a vector ({size},) or a matrix ({size}, {size}), "
                         f"got shape {value.shape}")
    scale = max(float(np.abs(value).max()), 1e-300)
    if (not np.allclose(value, value.T, rtol=0, atol=1e-12 * scale)
            or np.linalg.eigvalsh(value).min() < -1e-12 * scale):
        raise ValueError(f"{name}: expected symmetric positive semidefinite weights "
                         "(non-negative on the diagonal)")
    return value


def quadratic_cost(goal, state_weights, control_weights, terminal_weights=None, angles=(),
                   goal_control=None) -> Cost:
    r"""``(x - g)^T Q (x - g) + (u - u_g)^T R (u - u_g)``, terminal ``(x - g)^T Q_f (x - g)``.

    Parameters
    ----------
    goal : array (2n,)
        Goal state ``g``.
    state_weights, control_weights : array
        ``Q`` (2n, 2n) and ``R`` (m, m), or their diagonals.
    terminal_weights : array, optional
        ``Q_f`` (default ``Q``).
    angles : sequence of int, default ()
        Coordinates whose error is wrapped on the circle.
    goal_control : array (m,), optional
        ``u_g`` (default zero).

    Returns
    -------
    Cost

    Examples
    --------
    >>> cost = quadratic_cost([0.0, 0.0], [1.0, 0.1], [0.01])
    >>> round(float(cost.running(jnp.array([1.0, 2.0]), jnp.array([10.0]))), 4)
    2.4
    """
    goal = check_numeric_array(goal, "goal", min_samples=0)
    if goal.ndim != 1 or goal.size % 2:
        raise ValueError(f"goal: expected a state (2n,), got shape {goal.shape}")
    q = _matrix(state_weights, goal.size, "state_weights")
    qf = q if terminal_weights is None else _matrix(terminal_weights, goal.size,
                                                    "terminal_weights")
    r = check_numeric_array(control_weights, "control_weights", min_samples=0)
    m = r.shape[0] if r.ndim else 1
    r = _matrix(r.reshape(-1) if r.ndim < 2 else r, m, "control_weights")
    u_goal = np.zeros(m) if goal_control is None else np.asarray(goal_control, dtype=float)
    mask = _angle_mask(goal.size // 2, angles)

    def running(x, u):
        e = angle_error(x, goal, mask)
        v = u - u_goal
        return e @ q @ e + v @ r @ v

    def terminal(x):
        e = angle_error(x, goal, mask)
        return e @ qf @ e

    return Cost(running, terminal)


def swing_up_cost(n: int, angles, upright=None, track_limit: float | None = None,
                  force_limit=None, angle_weight: float = 10.0, position_weight: float = 1.0,
                  velocity_weight: float = 0.1, control_weight: float = 1e-3,
                  terminal_factor: float = 10.0, wall_weight: float = 1e3,
                  wall_margin: float = 0.2) -> Cost:
    r"""Swing-up cost: bring every pendulum angle upright and the rest to zero.

    .. math:: \ell = w_\theta \sum_i (1 - \cos(\theta_i - \theta_i^\star))
              + w_x \|p\|^2 + w_v \|\dot q\|^2 + w_u \|u / u_{max}\|^2
              + w_{wall} \sum_j \max(0, |p_j| - (p_{max} - \delta))^2

    over the angles ``theta`` (goal ``theta*``, default ``pi``: up, with 0 hanging), the other
    positions ``p``, and the track (``|p| <= p_max``, kept with a margin ``delta``). The
    terminal cost is the state part times ``terminal_factor``.

    Parameters
    ----------
    n : int
        Number of coordinates.
    angles : sequence of int
        Indices of the pendulum angles.
    upright : array (len(angles),), optional
        Goal angles (default ``pi`` each).
    track_limit : float, optional
        ``p_max`` of the other positions (no wall when None).
    force_limit : float or array (m,), optional
        Scale of the controls in the control term (default 1).
    angle_weight : float, default 10.0
        ``w_theta``, weight of the angles' distance from upright.
    position_weight : float, default 1.0
        ``w_x``, weight of the other positions.
    velocity_weight : float, default 0.1
        ``w_v``, weight of the velocities.
    control_weight : float, default 1e-3
        ``w_u``, weight of the scaled controls.
    terminal_factor : float, default 10.0
        Factor of the state part in the terminal cost.
    wall_weight : float, default 1e3
        ``w_wall``, weight of the track's walls.
    wall_margin : float, default 0.2
        ``delta``: the walls start this far inside the track (m).

    Returns
    -------
    Cost

    Examples
    --------
    >>> cost = swing_up_cost(2, angles=[1])
    >>> float(cost.terminal(jnp.array([0.0, np.pi, 0.0, 0.0])))  # upright, at rest
    0.0
    >>> float(cost.terminal(jnp.array([0.0, 0.0, 0.0, 0.0])))  # hanging: 10 * 2 * 10
    200.0
    """
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise ValueError(f"n: expected a positive number of coordinates, got {n!r}")
    angles = [int(i) for i in angles]
    _angle_mask(n, angles)
    others = [i for i in range(n) if i not in angles]
    upright = np.full(len(angles), np.pi) if upright is None else np.asarray(upright, float)
    if upright.shape != (len(angles),):
        raise ValueError(f"upright: expected shape ({len(angles)},), got {upright.shape}")
    scale = 1.0 if force_limit is None else np.asarray(force_limit, dtype=float)
    wall = np.inf if track_limit is None else float(track_limit) - float(wall_margin)
    angle_index, other_index = np.array(angles, dtype=int), np.array(others, dtype=int)

    def state_cost(x):
        theta = x[angle_index]
        cost = angle_weight * jnp.sum(1.0 - jnp.cos(theta - upright))
        cost = cost + velocity_weight * jnp.sum(x[n:] ** 2)
        if other_index.size:
            p = x[other_index]
            cost = cost + position_weight * jnp.sum(p ** 2)
            if np.isfinite(wall):
                cost = cost + wall_weight * jnp.sum(jnp.maximum(jnp.abs(p) - wall, 0.0) ** 2)
        return cost

    def running(x, u):
        return state_cost(x) + control_weight * jnp.sum((u / scale) ** 2)

    def terminal(x):
        return terminal_factor * state_cost(x)

    return Cost(running, terminal)
