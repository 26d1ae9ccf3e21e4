"""Fixed-step integrators of ``x' = f(x, u, t)`` for JAX (see :mod:`.jax_dynamics`).

Every step is pure, ``step(f, state, t, dt, u_start, u_end=None) -> state at t + dt`` in the
layout of ``state`` (an array (..., 2n) or a tuple of 2n arrays, as ``f`` takes it);
``u_start`` is the force at ``t``; ``u_end``, the force at ``t + dt``, is interpolated
linearly by the schemes that sample the force more than once (otherwise ``u_start`` is held)."""

from __future__ import annotations

from .._optional import import_optional

jax = import_optional("jax", purpose="pysindy_xl.export.jax_dynamics (XLSINDy.to_jax)")
jnp = import_optional("jax.numpy", purpose="pysindy_xl.export.jax_dynamics (XLSINDy.to_jax)")

__all__ = ["euler_step", "rk4_step", "semi_implicit_euler_step"]


def _force_at(u_start, u_end, fraction):
    """Force at ``t + fraction * dt``: held when ``u_end`` is None, else linear."""
    if u_end is None:
        return u_start
    return jax.tree.map(lambda a, b: a + fraction * (b - a), u_start, u_end)


def _axpy(x, a, y):
    """``x + a * y`` on arrays or tuples of arrays."""
    return jax.tree.map(lambda xi, yi: xi + a * yi, x, y)


def rk4_step(f, state, t, dt, u_start, u_end=None):
    """One classical Runge-Kutta step (arguments in the module docstring).

    Parameters
    ----------
    f : callable
        ``f(state, u, t) -> d(state)/dt``.
    state : jax.Array of shape (..., 2n) or tuple of 2n arrays
        The state ``[q, qd]`` at ``t``, in the layout ``f`` takes.
    t : float
        The time at the start of the step.
    dt : float
        The step.
    u_start : jax.Array of shape (..., n)
        The force at ``t``.
    u_end : jax.Array of shape (..., n), default=None
        The force at ``t + dt``, interpolated linearly by schemes that sample the force inside
        the step; None holds ``u_start``.

    Returns
    -------
    jax.Array or tuple
        The state at ``t + dt``, in the layout of ``state``.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from pysindy_xl.export.jax_dynamics import rk4_step
    >>> decay = lambda x, u, t: -x + u
    >>> x = rk4_step(decay, jnp.array([1.0, 2.0]), 0.0, 0.1, jnp.array([0.0, 0.0]))
    >>> [round(float(v), 6) for v in x]  # exp(-0.1) = 0.904837...
    [0.904837, 1.809675]
    """
    u_mid = _force_at(u_start, u_end, 0.5)
    u_last = _force_at(u_start, u_end, 1.0)
    k1 = f(state, u_start, t)
    k2 = f(_axpy(state, 0.5 * dt, k1), u_mid, t + 0.5 * dt)
    k3 = f(_axpy(state, 0.5 * dt, k2), u_mid, t + 0.5 * dt)
    k4 = f(_axpy(state, dt, k3), u_last, t + dt)
    return jax.tree.map(
        lambda x, a, b, c, d: x + (dt / 6.0) * (a + 2.0 * b + 2.0 * c + d),
        state, k1, k2, k3, k4,
    )  # fmt: skip


def _split_state(state):
    if isinstance(state, tuple):
        n = len(state) // 2
        return state[:n], state[n:]
    n = state.shape[-1] // 2
    return state[..., :n], state[..., n:]


def _join_state(q, qd):
    if isinstance(q, tuple):
        return q + qd
    return jnp.concatenate([q, qd], axis=-1)


def semi_implicit_euler_step(f, state, t, dt, u_start, u_end=None):
    """One semi-implicit (symplectic) Euler step, ``qd' = qd + dt qdd``, ``q' = q + dt qd'``:
    first order, energy of conservative systems kept bounded.

    Parameters
    ----------
    f : callable
        ``f(state, u, t) -> d(state)/dt``.
    state : jax.Array of shape (..., 2n) or tuple of 2n arrays
        The state ``[q, qd]`` at ``t``, in the layout ``f`` takes.
    t : float
        The time at the start of the step.
    dt : float
        The step.
    u_start : jax.Array of shape (..., n)
        The force at ``t``.
    u_end : jax.Array of shape (..., n), default=None
        The force at ``t + dt``, interpolated linearly by schemes that sample the force inside
        the step; None holds ``u_start``.

    Returns
    -------
    jax.Array or tuple
        The state at ``t + dt``, in the layout of ``state``.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from pysindy_xl.export.jax_dynamics import semi_implicit_euler_step
    >>> spring = lambda x, u, t: jnp.array([x[1], u[0] - x[0]])
    >>> semi_implicit_euler_step(spring, jnp.array([1.0, 0.0]), 0.0, 0.1, jnp.array([0.0]))
    Array([ 0.99, -0.1 ], dtype=float32)
    """
    del u_end
    q, qd = _split_state(state)
    _, qdd = _split_state(f(state, u_start, t))
    qd = _axpy(qd, dt, qdd)
    return _join_state(_axpy(q, dt, qd), qd)


def euler_step(f, state, t, dt, u_start, u_end=None):
    """One explicit Euler step, ``state + dt f(state, u(t), t)``.

    Parameters
    ----------
    f : callable
        ``f(state, u, t) -> d(state)/dt``.
    state : jax.Array of shape (..., 2n) or tuple of 2n arrays
        The state ``[q, qd]`` at ``t``, in the layout ``f`` takes.
    t : float
        The time at the start of the step.
    dt : float
        The step.
    u_start : jax.Array of shape (..., n)
        The force at ``t``.
    u_end : jax.Array of shape (..., n), default=None
        The force at ``t + dt``, interpolated linearly by schemes that sample the force inside
        the step; None holds ``u_start``.

    Returns
    -------
    jax.Array or tuple
        The state at ``t + dt``, in the layout of ``state``.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from pysindy_xl.export.jax_dynamics import euler_step
    >>> spring = lambda x, u, t: jnp.array([x[1], u[0] - x[0]])
    >>> euler_step(spring, jnp.array([1.0, 0.0]), 0.0, 0.1, jnp.array([0.0]))
    Array([ 1. , -0.1], dtype=float32)
    """
    del u_end
    return _axpy(state, dt, f(state, u_start, t))


STEPS = {"rk4": rk4_step, "semi_implicit_euler": semi_implicit_euler_step, "euler": euler_step}
