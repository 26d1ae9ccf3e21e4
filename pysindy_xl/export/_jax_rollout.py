"""Batched fixed-step rollouts of JAX dynamics inside ``jax.lax.scan`` (exported by
:mod:`.jax_dynamics`)."""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import numpy as np

from .._optional import import_optional
from ._jax_steps import STEPS

jax = import_optional("jax", purpose="pysindy_xl.export.jax_dynamics (XLSINDy.to_jax)")
jnp = import_optional("jax.numpy", purpose="pysindy_xl.export.jax_dynamics (XLSINDy.to_jax)")

__all__ = ["BatchSimulation", "simulate", "simulate_batch"]


class BatchSimulation(NamedTuple):
    """Result of :func:`simulate` / :func:`simulate_batch` (a JAX pytree).

    Parameters
    ----------
    states : jax.Array of shape (B, T, 2n)
        The trajectories, or (B, 2n) with ``final_only``; no ``B`` axis for :func:`simulate`.
        A diverged trajectory is frozen at its last accepted state.
    diverged : jax.Array of bool, shape (B,)
        Whether each trajectory left the finite / bounded region.
    divergence_step : jax.Array of int, shape (B,)
        Its first sample out of the region, else ``-1``.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> from pysindy_xl.export.jax_dynamics import simulate
    >>> result = simulate(lambda x, u, t: -x, jnp.array([1.0, 0.0]), None, 0.1, n_steps=3)
    >>> result.states.shape, bool(result.diverged), int(result.divergence_step)
    ((3, 2), False, -1)
    """

    states: jax.Array
    diverged: jax.Array
    divergence_step: jax.Array


def _is_bad(components, bound):
    bad = False
    for c in components:
        bad = bad | ~(jnp.isfinite(c) & (jnp.abs(c) <= bound))
    return bad


def _generic_componentwise(f, batch_ndim: int):
    """Adapt a user ``f(state (2n,), u (n,), t)`` to the per-component layout."""
    for _ in range(batch_ndim):
        f = jax.vmap(f, in_axes=(0, 0, None))

    def componentwise(state, u, t):
        derivative = f(jnp.stack(state, axis=-1), jnp.stack(u, axis=-1), t)
        return tuple(derivative[..., i] for i in range(len(state)))

    return componentwise


@partial(jax.jit, static_argnames=("f", "method", "linear", "final_only"))
def _simulate_compiled(f, x0, u, dt, t0, bound, method, linear, final_only):
    """Scan ``T - 1`` steps: x0 (..., 2n), u (..., T, n) -> BatchSimulation."""
    step = STEPS[method]
    batch_ndim = x0.ndim - 1
    g = getattr(f, "componentwise", None) or _generic_componentwise(f, batch_ndim)
    n_steps = u.shape[-2] - 1
    # Time first, then component: each scan step reads n per-component arrays.
    u_seq = jnp.moveaxis(u, (-2, -1), (0, 1))
    state0 = tuple(x0[..., i] for i in range(x0.shape[-1]))
    bad0 = _is_bad(state0, bound)

    def body(carry, inputs):
        state, diverged, divergence_step, k = carry
        u_start, u_end = inputs
        t = t0 + k.astype(dt.dtype) * dt
        proposed = step(g, state, t, dt, tuple(u_start), None if u_end is None else tuple(u_end))
        bad = _is_bad(proposed, bound)
        divergence_step = jnp.where(bad & ~diverged, k + 1, divergence_step)
        diverged = diverged | bad
        # Freeze: a diverged trajectory keeps its last accepted state, so NaN never
        # propagates and the rest of the batch is untouched.
        state = tuple(jnp.where(diverged, s, p) for s, p in zip(state, proposed, strict=True))
        return (state, diverged, divergence_step, k + 1), (None if final_only else jnp.stack(state))

    carry0 = (state0, bad0, jnp.where(bad0, 0, -1), jnp.asarray(0, dtype=jnp.int32))
    inputs = (u_seq[:-1], u_seq[1:] if linear else None)
    (final, diverged, divergence_step, _), history = jax.lax.scan(body, carry0, inputs,
                                                                  length=n_steps)
    if final_only:
        states = jnp.stack(final, axis=-1)
    else:
        history = jnp.concatenate([jnp.stack(state0)[None], history], axis=0)
        states = jnp.moveaxis(history, (0, 1), (-2, -1))
    return BatchSimulation(states, diverged, divergence_step)


def _float_dtype():
    """``float64`` when ``jax_enable_x64`` is on, else ``float32``."""
    return jnp.asarray(0.0).dtype


def _is_concrete(x) -> bool:
    return not isinstance(x, jax.core.Tracer)


def _prepare(f, x0, u, dt, t0, n_steps, method, interpolation, bound, batched):
    """Validate and convert the inputs of :func:`simulate` and :func:`simulate_batch`."""
    if hasattr(f, "to_jax") and not hasattr(f, "n_coordinates"):
        f = f.to_jax()
    if not callable(f):
        raise TypeError(f"f: expected a callable f(state, u, t), got {type(f).__name__}")
    if method not in STEPS:
        raise ValueError(f"method: expected one of {sorted(STEPS)}, got {method!r}")
    if interpolation not in ("zoh", "linear"):
        raise ValueError(f"interpolation: expected 'zoh' or 'linear', got {interpolation!r}")
    dtype = _float_dtype()
    lead = 1 if batched else 0
    x0 = jnp.asarray(x0, dtype=dtype)
    if x0.ndim != 1 + lead or x0.shape[-1] % 2 or x0.shape[-1] == 0:
        expected = "(B, 2n)" if batched else "(2n,)"
        raise ValueError(f"x0: expected shape {expected} with 2n even, got {x0.shape}")
    n = x0.shape[-1] // 2
    if getattr(f, "n_coordinates", n) != n:
        raise ValueError(f"x0: expected 2n = {2 * f.n_coordinates} state entries, got {2 * n}")
    if u is None:
        if n_steps is None:
            raise ValueError("n_steps: required when u is None (number of output samples)")
        if not isinstance(n_steps, int | np.integer) or n_steps < 1:
            raise ValueError(f"n_steps: expected a positive integer, got {n_steps!r}")
        u = jnp.zeros(x0.shape[:lead] + (int(n_steps), n), dtype=dtype)
    else:
        u = jnp.asarray(u, dtype=dtype)
        if u.ndim != 2 + lead or u.shape[:lead] != x0.shape[:lead] or u.shape[-1] != n:
            shape = "(B, T, n)" if batched else "(T, n)"
            raise ValueError(f"u: expected shape {shape} = {x0.shape[:lead] + ('T', n)}, "
                             f"got {u.shape}")
        if n_steps is not None and n_steps != u.shape[lead]:
            raise ValueError(f"n_steps: {n_steps} does not match u with {u.shape[lead]} samples")
        if u.shape[lead] < 1:
            raise ValueError("u: expected at least one time sample")
    if _is_concrete(x0) and not bool(jnp.all(jnp.isfinite(x0))):
        raise ValueError("x0: contains NaN or inf")
    if _is_concrete(u) and not bool(jnp.all(jnp.isfinite(u))):
        raise ValueError("u: contains NaN or inf")
    dt = jnp.asarray(dt, dtype=dtype)
    if dt.ndim != 0:
        raise ValueError(f"dt: expected a scalar time step, got shape {dt.shape}")
    if _is_concrete(dt) and not bool(jnp.isfinite(dt) & (dt > 0)):
        raise ValueError(f"dt: expected a positive finite time step, got {float(dt)}")
    t0 = jnp.asarray(t0, dtype=dtype)
    if t0.ndim != 0:
        raise ValueError(f"t0: expected a scalar start time, got shape {t0.shape}")
    if bound is None:
        bound = np.inf
    elif not isinstance(bound, int | float | np.number) or not bound > 0:
        raise ValueError(f"bound: expected None or a positive number, got {bound!r}")
    bound = jnp.asarray(bound, dtype=dtype)
    return f, x0, u, dt, t0, bound


def simulate(f, x0, u, dt, *, t0=0.0, n_steps=None, method="rk4", interpolation="zoh",
             bound=None, final_only=False):
    """Integrate one trajectory with a fixed step inside ``jax.lax.scan``.

    Parameters
    ----------
    f : callable or model
        ``f(state, u, t) -> d(state)/dt`` (:func:`dynamics_function`), or an object with
        ``to_jax()`` such as a fitted ``XLSINDy``; the same object reuses the compiled code.
    x0 : array (2n,)
        Initial state ``[q, qd]``.
    u : array (T, n) or None
        Generalized forces sampled at ``t0 + k dt``; ``None`` (zero) needs ``n_steps``.
    dt : float
        Time step.
    t0 : float, default=0.0
        Time of the first sample.
    n_steps : int, default=None
        Number of output samples ``T`` when ``u`` is None.
    method : {"rk4", "semi_implicit_euler", "euler"}, default="rk4"
        The fixed-step scheme.
    interpolation : {"zoh", "linear"}, default="zoh"
        Force inside a step: held at ``u[k]`` or linear between ``u[k]`` and ``u[k+1]``.
    bound : float, default=None
        A trajectory diverges when a state entry becomes NaN/inf or exceeds ``bound``.
    final_only : bool, default=False
        Return only the final state.

    Returns
    -------
    BatchSimulation
        Differentiable in ``x0``, ``u``, ``dt`` and ``t0`` (mask diverged trajectories out of a
        loss, with a ``bound`` low enough that no infinity is reached).

    Examples
    --------
    >>> import sympy as sp, jax.numpy as jnp
    >>> from types import SimpleNamespace
    >>> import pysindy_xl as px
    >>> from pysindy_xl.export.jax_dynamics import dynamics_function, simulate
    >>> c = px.Coordinates(["x"])
    >>> oscillator = SimpleNamespace(coords=c, mass_matrix_expr=sp.Matrix([[1]]),
    ...                              forcing_expr=sp.Matrix([-c.q[0]]))
    >>> result = simulate(dynamics_function(oscillator), jnp.array([1.0, 0.0]), None, 0.01,
    ...                   n_steps=315)
    >>> result.states.shape, bool(result.diverged), int(result.divergence_step)
    ((315, 2), False, -1)
    >>> round(float(result.states[-1, 0]), 3)  # cos(3.14)
    -1.0
    """
    return _run(f, x0, u, dt, t0, n_steps, method, interpolation, bound, final_only, False)


def simulate_batch(f, x0, u, dt, *, t0=0.0, n_steps=None, method="rk4", interpolation="zoh",
                   bound=None, final_only=False):
    """Integrate ``B`` independent trajectories at once (``vmap`` of :func:`simulate`).

    One that diverges is frozen and reported, the others carry on.

    Parameters
    ----------
    f : callable or model
        ``f(state, u, t) -> d(state)/dt`` (:func:`dynamics_function`), or an object with
        ``to_jax()`` such as a fitted ``XLSINDy``.
    x0 : array_like of shape (B, 2n)
        Initial states ``[q, qd]``.
    u : array_like of shape (B, T, n) or None
        Generalized forces of each trajectory at ``t0 + k dt``; None (zero) needs
        ``n_steps``.
    dt : float
        Time step, shared.
    t0 : float, default=0.0
        Time of the first sample, shared.
    n_steps : int, default=None
        Number of output samples ``T`` when ``u`` is None.
    method : {"rk4", "semi_implicit_euler", "euler"}, default="rk4"
        The fixed-step scheme.
    interpolation : {"zoh", "linear"}, default="zoh"
        Force inside a step: held at ``u[k]`` or linear between ``u[k]`` and ``u[k+1]``.
    bound : float, default=None
        A trajectory diverges when a state entry becomes NaN/inf or exceeds ``bound``.
    final_only : bool, default=False
        Return only the final states.

    Returns
    -------
    BatchSimulation
        ``states`` (B, T, 2n) (or (B, 2n)), ``diverged`` (B,), ``divergence_step`` (B,).

    Examples
    --------

    >>> import sympy as sp, jax.numpy as jnp
    >>> from types import SimpleNamespace
    >>> import pysindy_xl as px
    >>> from pysindy_xl.export.jax_dynamics import dynamics_function, simulate_batch
    >>> c = px.Coordinates(["x"])
    >>> unstable = SimpleNamespace(coords=c, mass_matrix_expr=sp.Matrix([[1]]),
    ...                            forcing_expr=sp.Matrix([c.q[0] ** 3]))
    >>> out = simulate_batch(dynamics_function(unstable), jnp.array([[0.1, 0.0], [10.0, 0.0]]),
    ...                      None, 0.1, n_steps=50, bound=1e3)
    >>> out.diverged.tolist(), out.divergence_step.tolist()
    ([False, True], [-1, 2])
    """
    return _run(f, x0, u, dt, t0, n_steps, method, interpolation, bound, final_only, True)


def _run(f, x0, u, dt, t0, n_steps, method, interpolation, bound, final_only, batched):
    f, x0, u, dt, t0, bound = _prepare(f, x0, u, dt, t0, n_steps, method, interpolation,
                                       bound, batched)
    return _simulate_compiled(f, x0, u, dt, t0, bound, method, interpolation == "linear",
                              bool(final_only))
