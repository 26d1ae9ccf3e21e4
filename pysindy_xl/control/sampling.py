r"""Sampling-based model-predictive control (MPPI, path-integral weighting).

Each planning step perturbs the current plan ``U`` (H, m) with ``K`` smooth random sequences
(Gaussian values at ``knots`` points, interpolated linearly over the horizon), clips them to the
control limits, rolls all of them out on the model (one ``jax.lax.scan`` over the horizon,
``vmap`` over the samples, compiled once) and averages them with the weights

.. math:: w_s \propto \exp\!\left(-\frac{J_s - \min J}{\lambda (\bar J - \min J)}\right),

the temperature ``lambda`` relative to the spread of the costs. The plan of the next step is this
one shifted by a period (warm start). A sample whose rollout leaves the finite numbers costs
``1e10``."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from .._optional import import_optional

jax = import_optional("jax", purpose="pysindy_xl.control")
jnp = import_optional("jax.numpy", purpose="pysindy_xl.control")

__all__ = ["SamplingPlanner", "interpolation_matrix", "rollout", "sampling_planner",
           "trajectory_cost"]

_DIVERGED_COST = 1e10


class SamplingPlanner(NamedTuple):
    """Pure functions of a sampling planner (:func:`sampling_planner`).

    Parameters
    ----------
    init : callable
        ``init() -> plan`` (H, m) of zeros.
    plan : callable
        ``plan(x (2n,), plan (H, m), key) -> (u (m,), plan, cost)``: the control to apply now,
        the optimized plan (not shifted) and the lowest sampled cost; compiled.
    shift : callable
        ``shift(plan) -> plan``: the warm start of the next period.
    horizon : int
        ``H``, control periods planned.
    n_controls : int
        ``m``.

    Examples
    --------
    See :func:`sampling_planner`.
    """

    init: Callable
    plan: Callable
    shift: Callable
    horizon: int
    n_controls: int


def rollout(step, x0, controls):
    """States of ``x_{k+1} = step(x_k, u_k)`` from ``x0``, one ``jax.lax.scan``.

    Parameters
    ----------
    step : callable
        ``step(x (2n,), u (m,)) -> x (2n,)``.
    x0 : array (2n,)
        Initial state.
    controls : array (H, m)
        Controls of the ``H`` steps.

    Returns
    -------
    jax.Array
        ``x_1..x_H`` (H, 2n).

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> step = lambda x, u: x + u
    >>> rollout(step, jnp.zeros(1), jnp.ones((3, 1)))[:, 0].tolist()
    [1.0, 2.0, 3.0]
    """
    def body(x, u):
        x1 = step(x, u)
        return x1, x1

    _, states = jax.lax.scan(body, x0, controls)
    return states


def trajectory_cost(step, cost, x0, controls):
    r"""``J = sum_k running(x_k, u_k) + terminal(x_H)`` of the rollout from ``x0``.

    Parameters
    ----------
    step : callable
        ``step(x, u) -> x``.
    cost : Cost
        Running and terminal cost (:mod:`pysindy_xl.control.costs`).
    x0 : array (2n,)
        Initial state.
    controls : array (H, m)
        Controls of the ``H`` steps.

    Returns
    -------
    jax.Array
        The scalar cost, ``1e10`` when it is not finite.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from pysindy_xl.control.costs import Cost
    >>> cost = Cost(lambda x, u: jnp.sum(x ** 2), lambda x: 0.0)
    >>> float(trajectory_cost(lambda x, u: x + u, cost, jnp.zeros(1), jnp.ones((3, 1))))
    5.0
    """
    def body(x, u):
        return step(x, u), cost.running(x, u)

    final, running = jax.lax.scan(body, x0, controls)
    total = jnp.sum(running) + cost.terminal(final)
    return jnp.where(jnp.isfinite(total), total, _DIVERGED_COST)


def interpolation_matrix(horizon: int, knots: int) -> np.ndarray:
    """Linear interpolation from ``knots`` equally spaced values to ``horizon`` samples.

    Parameters
    ----------
    horizon : int
        Samples ``H`` (>= 1).
    knots : int
        Values (>= 2).

    Returns
    -------
    numpy.ndarray
        ``P`` (horizon, knots), rows summing to one.

    Examples
    --------
    >>> interpolation_matrix(3, 2).tolist()
    [[1.0, 0.0], [0.5, 0.5], [0.0, 1.0]]
    """
    if knots < 2 or horizon < 1:
        raise ValueError(f"knots, horizon: expected knots >= 2 and horizon >= 1, got {knots}, "
                         f"{horizon}")
    where = np.linspace(0.0, knots - 1.0, horizon)
    eye = np.eye(knots)
    return np.stack([np.interp(where, np.arange(knots), eye[k]) for k in range(knots)], axis=1)


def _positive_int(value, name):
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ValueError(f"{name}: expected a positive integer, got {value!r}")
    return int(value)


def sampling_planner(step, cost, horizon: int, control_limit, n_samples: int = 256,
                     noise: float = 0.4, knots: int = 8, temperature: float = 0.05,
                     iterations: int = 1) -> SamplingPlanner:
    """A compiled MPPI planner on the discrete model ``step``.

    Parameters
    ----------
    step : callable
        ``x_{k+1} = step(x_k, u_k)`` (:func:`~pysindy_xl.control.discrete.discrete_dynamics`),
        with attribute ``n_controls`` or ``control_limit`` of the right size.
    cost : Cost
        Running and terminal cost (:mod:`pysindy_xl.control.costs`).
    horizon : int
        Planning horizon ``H`` in control periods.
    control_limit : float or array (m,)
        Symmetric box ``|u_j| <= control_limit_j``.
    n_samples : int, default 256
        Sampled sequences per iteration (the current plan is always one of them).
    noise : float, default 0.4
        Standard deviation of the perturbations, as a fraction of ``control_limit``.
    knots : int, default 8
        Independent values per perturbation over the horizon.
    temperature : float, default 0.05
        ``lambda`` of the weights, relative to the spread of the costs.
    iterations : int, default 1
        Sampling rounds per planning step (the noise halves each round).

    Returns
    -------
    SamplingPlanner

    Examples
    --------
    A double integrator brought to the origin:

    >>> import jax, jax.numpy as jnp
    >>> from pysindy_xl.control import discrete_dynamics, quadratic_cost
    >>> step = discrete_dynamics(lambda x, tau: jnp.array([x[1], tau[0]]), 0.1, [[1.0]], 1)
    >>> planner = sampling_planner(step, quadratic_cost([0.0, 0.0], [1.0, 0.1], [0.01]),
    ...                            horizon=20, control_limit=2.0)
    >>> x, plan, key = jnp.array([1.0, 0.0]), planner.init(), jax.random.PRNGKey(0)
    >>> for _ in range(60):
    ...     key, sub = jax.random.split(key)
    ...     u, plan, _ = planner.plan(x, plan, sub)
    ...     x, plan = step(x, u), planner.shift(plan)
    >>> bool(jnp.all(jnp.abs(x) < 0.1))
    True
    """
    horizon = _positive_int(horizon, "horizon")
    n_samples = _positive_int(n_samples, "n_samples")
    iterations = _positive_int(iterations, "iterations")
    knots = max(2, min(_positive_int(knots, "knots"), horizon))
    m = getattr(step, "n_controls", None)
    limit = np.asarray(control_limit, dtype=float).reshape(-1)
    if m is None:
        m = limit.size
    if limit.size == 1:
        limit = np.full(m, float(limit[0]))
    if limit.shape != (m,) or not np.all(limit > 0) or not np.all(np.isfinite(limit)):
        raise ValueError(f"control_limit: expected a positive number or {m} positive numbers, "
                         f"got {np.asarray(control_limit).tolist()!r}")
    if not (np.isfinite(noise) and noise > 0):
        raise ValueError(f"noise: expected a positive fraction of the limit, got {noise!r}")
    if not (np.isfinite(temperature) and temperature > 0):
        raise ValueError(f"temperature: expected a positive number, got {temperature!r}")
    interp = interpolation_matrix(horizon, knots)
    sigma = float(noise) * limit
    costs_of = jax.vmap(lambda x0, u: trajectory_cost(step, cost, x0, u), in_axes=(None, 0))

    def one_round(x0, plan, key, scale):
        dtype = plan.dtype
        z = jax.random.normal(key, (n_samples, knots, m), dtype=dtype)
        perturbation = jnp.einsum("hk,skm->shm", jnp.asarray(interp, dtype), z)
        perturbation = perturbation * jnp.asarray(sigma, dtype) * scale
        perturbation = perturbation.at[0].set(0.0)  # the current plan competes
        bound = jnp.asarray(limit, dtype)
        candidates = jnp.clip(plan[None] + perturbation, -bound, bound)
        costs = costs_of(x0, candidates)
        best = jnp.min(costs)
        spread = jnp.maximum(jnp.mean(costs) - best, 1e-9)
        weights = jax.nn.softmax(-(costs - best) / (temperature * spread))
        return jnp.einsum("s,shm->hm", weights, candidates), best

    @jax.jit
    def plan_fn(x0, plan, key):
        x0 = jnp.asarray(x0)
        plan = jnp.asarray(plan, dtype=x0.dtype)
        best = jnp.asarray(0.0, x0.dtype)
        for k, sub in enumerate(jax.random.split(key, iterations)):
            plan, best = one_round(x0, plan, sub, 0.5 ** k)
        return plan[0], plan, best

    @jax.jit
    def shift(plan):
        return jnp.concatenate([plan[1:], plan[-1:]], axis=0)

    def init():
        return jnp.zeros((horizon, m), dtype=jnp.asarray(0.0).dtype)

    return SamplingPlanner(init, plan_fn, shift, horizon, m)
