r"""Iterative LQR (iLQR) trajectory optimization with JAX derivatives.

Around the current trajectory, the dynamics are linearized (``A_k``, ``B_k`` by ``jax.jacfwd``)
and the cost expanded to second order (gradients and Hessians by JAX); a backward Riccati pass
gives the affine update ``du_k = k_k + K_k dx_k`` (Levenberg-Marquardt regularized ``Q_uu``),
and a forward pass on the nonlinear model applies it with a step ``alpha`` chosen among a few
(all rolled out at once, ``vmap``), controls clipped to their box. The whole solve is one
compiled ``jax.lax`` loop."""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np

from .._optional import import_optional
from .._validation import check_numeric_array, check_option

jax = import_optional("jax", purpose="pysindy_xl.control")
jnp = import_optional("jax.numpy", purpose="pysindy_xl.control")

__all__ = ["ILQRSolution", "ilqr"]

_ALPHAS = (1.0, 0.5, 0.25, 0.1, 0.03, 0.01)


class ILQRSolution(NamedTuple):
    """Result of :func:`ilqr`.

    Parameters
    ----------
    states : jax.Array (H + 1, 2n)
        States of the final trajectory, ``x_0`` included.
    controls : jax.Array (H, m)
        Controls of the final trajectory (within ``control_limit`` when given).
    gains : jax.Array (H, m, 2n)
        Feedback ``K_k`` of the final trajectory: ``u = u_k + K_k (x - x_k)``.
    cost : jax.Array
        Final cost.
    iterations : jax.Array
        Iterations done.

    Examples
    --------
    See :func:`ilqr`.
    """

    states: object
    controls: object
    gains: object
    cost: object
    iterations: object


def _forward(step, cost, x0, nominal_x, nominal_u, k_ff, k_fb, alpha, low, high):
    def body(carry, inputs):
        x, total = carry
        xn, un, kf, kb = inputs
        u = jnp.clip(un + alpha * kf + kb @ (x - xn), low, high)
        return (step(x, u), total + cost.running(x, u)), (x, u)

    (final, total), (xs, us) = jax.lax.scan(body, (x0, jnp.zeros((), x0.dtype)),
                                            (nominal_x[:-1], nominal_u, k_ff, k_fb))
    total = total + cost.terminal(final)
    total = jnp.where(jnp.isfinite(total), total, jnp.inf)
    return jnp.concatenate([xs, final[None]], axis=0), us, total


def _backward(step, cost, xs, us, mu):
    n_x, m = xs.shape[1], us.shape[1]
    lx_f = jax.grad(cost.terminal)(xs[-1])
    lxx_f = jax.hessian(cost.terminal)(xs[-1])
    jac = jax.vmap(jax.jacfwd(step, argnums=(0, 1)))(xs[:-1], us)
    grads = jax.vmap(jax.grad(cost.running, argnums=(0, 1)))(xs[:-1], us)
    hess = jax.vmap(jax.hessian(cost.running, argnums=(0, 1)))(xs[:-1], us)
    eye = jnp.eye(m, dtype=xs.dtype)

    def body(carry, inputs):
        vx, vxx = carry
        (a, b), (lx, lu), ((lxx, lxu), (_, luu)) = inputs
        qx = lx + a.T @ vx
        qu = lu + b.T @ vx
        qxx = lxx + a.T @ vxx @ a
        qux = lxu.T + b.T @ vxx @ a
        quu = luu + b.T @ vxx @ b + mu * eye
        quu = 0.5 * (quu + quu.T)
        k_ff = -jnp.linalg.solve(quu, qu)
        k_fb = -jnp.linalg.solve(quu, qux)
        vx = qx + k_fb.T @ quu @ k_ff + k_fb.T @ qu + qux.T @ k_ff
        vxx = qxx + k_fb.T @ quu @ k_fb + k_fb.T @ qux + qux.T @ k_fb
        return (vx, 0.5 * (vxx + vxx.T)), (k_ff, k_fb)

    del n_x
    _, (k_ff, k_fb) = jax.lax.scan(body, (lx_f, lxx_f), (jac, grads, hess), reverse=True)
    return k_ff, k_fb


def ilqr(step, cost, x0, controls, control_limit=None, iterations: int = 50,
         tolerance: float = 1e-6, regularization: float = 1e-6) -> ILQRSolution:
    r"""Minimize ``sum_k running(x_k, u_k) + terminal(x_H)`` over ``u`` by iLQR.

    Parameters
    ----------
    step : callable
        Discrete model ``x_{k+1} = step(x_k, u_k)``, pure JAX.
    cost : Cost
        :class:`~pysindy_xl.control.costs.Cost`, twice differentiable.
    x0 : array (2n,)
        Initial state.
    controls : array (H, m)
        Initial guess (warm start).
    control_limit : float or array (m,), optional
        Box ``|u_j| <= control_limit_j`` (clipped in the forward pass); none by default.
    iterations : int, default 50
        Most iterations.
    tolerance : float, default 1e-6
        Stop when the relative decrease of the cost is below it.
    regularization : float, default 1e-6
        Initial ``mu`` added to ``Q_uu`` (grown tenfold after a failed step, shrunk after a
        good one).

    Returns
    -------
    ILQRSolution

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from pysindy_xl.control import discrete_dynamics, quadratic_cost
    >>> step = discrete_dynamics(lambda x, tau: jnp.array([x[1], tau[0]]), 0.1, [[1.0]], 1)
    >>> cost = quadratic_cost([0.0, 0.0], [1.0, 0.1], [0.01], terminal_weights=[100.0, 10.0])
    >>> solution = ilqr(step, cost, jnp.array([1.0, 0.0]), jnp.zeros((30, 1)))
    >>> bool(jnp.all(jnp.abs(solution.states[-1]) < 0.05))
    True
    """
    if not callable(step):
        raise TypeError(f"step: expected a callable step(x, u), got {type(step).__name__}")
    x0 = jnp.asarray(check_numeric_array(x0, "x0", ndim=1), dtype=jnp.asarray(0.0).dtype)
    controls = check_numeric_array(controls, "controls", min_samples=0)
    if controls.ndim != 2 or controls.shape[0] < 1 or controls.shape[1] < 1:
        raise ValueError(f"controls: expected an initial guess (H, m), H and m at least 1, "
                         f"got shape {controls.shape}")
    controls = jnp.asarray(controls, dtype=x0.dtype)
    check_option("tolerance", tolerance, "real", low=0)
    check_option("regularization", regularization, "real", low=0)
    m = controls.shape[1]
    if control_limit is None:
        limit = np.full(m, np.inf)
    else:
        limit = np.asarray(control_limit, dtype=float).reshape(-1)
        limit = np.full(m, limit[0]) if limit.size == 1 else limit
        if limit.shape != (m,) or not np.all(limit > 0):
            raise ValueError(f"control_limit: expected a positive number or {m} of them, got "
                             f"{np.asarray(control_limit).tolist()!r}")
    if isinstance(iterations, bool) or not isinstance(iterations, int | np.integer) \
            or iterations < 1:
        raise ValueError(f"iterations: expected a positive integer, got {iterations!r}")
    return _solve(step, cost, x0, controls, jnp.asarray(limit, x0.dtype), int(iterations),
                  float(tolerance), float(regularization))


def _solve(step, cost, x0, controls, limit, iterations, tolerance, regularization):
    return _compiled(step, cost, iterations, tolerance, regularization)(x0, controls, limit)


@lru_cache(maxsize=32)
def _compiled(step, cost, iterations, tolerance, regularization):
    """The compiled solver of one model and cost (kept: a planner calls it every period)."""

    @jax.jit
    def run(x0, controls, limit):
        low, high = -limit, limit
        controls = jnp.clip(controls, low, high)
        h, m = controls.shape
        zero_ff = jnp.zeros((h, m), x0.dtype)
        zero_fb = jnp.zeros((h, m, x0.shape[0]), x0.dtype)
        xs0 = jnp.zeros((h + 1, x0.shape[0]), x0.dtype)
        xs, us, total = _forward(step, cost, x0, xs0, controls, zero_ff, zero_fb, 0.0, low,
                                 high)
        alphas = jnp.asarray(_ALPHAS, x0.dtype)
        forward_all = jax.vmap(
            lambda k_ff, k_fb, xs, us, a: _forward(step, cost, x0, xs, us, k_ff, k_fb, a, low,
                                                   high),
            in_axes=(None, None, None, None, 0))

        def cond(carry):
            _, _, _, _, _, it, done = carry
            return (it < iterations) & ~done

        def body(carry):
            xs, us, total, k_fb, mu, it, _ = carry
            k_ff, k_fb_new = _backward(step, cost, xs, us, mu)
            xs_all, us_all, totals = forward_all(k_ff, k_fb_new, xs, us, alphas)
            best = jnp.argmin(totals)
            improved = totals[best] < total
            decrease = (total - totals[best]) / jnp.maximum(jnp.abs(total), 1e-12)
            xs = jnp.where(improved, xs_all[best], xs)
            us = jnp.where(improved, us_all[best], us)
            k_fb = jnp.where(improved, k_fb_new, k_fb)
            done = improved & (decrease < tolerance)
            done = done | (~improved & (mu > 1e8))
            mu = jnp.where(improved, jnp.maximum(mu / 10.0, 1e-9), mu * 10.0)
            total = jnp.where(improved, totals[best], total)
            return xs, us, total, k_fb, mu, it + 1, done

        carry = (xs, us, total, zero_fb, jnp.asarray(regularization, x0.dtype),
                 jnp.asarray(0), jnp.asarray(False))
        xs, us, total, _, mu, it, _ = jax.lax.while_loop(cond, body, carry)
        # the feedback gains of the final trajectory (not of the one before the last step)
        _, k_fb = _backward(step, cost, xs, us, jnp.minimum(mu, regularization))
        return ILQRSolution(xs, us, k_fb, total, it)

    return run
