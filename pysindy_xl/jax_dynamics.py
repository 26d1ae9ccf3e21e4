"""Identified dynamics as pure JAX functions, and batched fixed-step simulation.

The identified equations of motion are linear in the accelerations,
``M(q, qd) qdd = f(q, qd, tau, t)``. :func:`dynamics_function` compiles ``M`` and
``f`` from their sympy expressions into one JAX function and solves for ``qdd``;
the result is pure, so it can be ``jax.jit``-ed, ``jax.vmap``-ed and differentiated.

:func:`simulate` (one trajectory) and :func:`simulate_batch` (many at once) integrate
it with a fixed-step scheme inside ``jax.lax.scan``. They compute in ``float64`` when
``jax_enable_x64`` is on and in ``float32`` otherwise, and report diverging
trajectories (NaN, inf or a user bound) per trajectory instead of failing the batch.

Conventions
-----------
- state: ``[q_1..q_n, qd_1..qd_n]`` (shape ``(2n,)``), forces ``u``: ``(n,)``.
- A force signal of ``T`` samples, ``u[k]`` at ``t0 + k dt``, yields ``T`` states
  (``T - 1`` steps), ``states[0] = x0``, like ``XLSINDy.simulate``.
- ``interpolation="zoh"`` holds ``u[k]`` over ``[t_k, t_k+1)`` (what a digital
  controller or ``mj_step`` does); ``"linear"`` interpolates between ``u[k]`` and
  ``u[k+1]`` inside the step (what an ODE solver fed a sampled signal usually sees).
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import sympy as sp

__all__ = [
    "BatchSimulation",
    "dynamics_function",
    "euler_step",
    "rk4_step",
    "semi_implicit_euler_step",
    "simulate",
    "simulate_batch",
]

#: Largest system solved by unrolled Gaussian elimination; larger ones call LAPACK.
_UNROLLED_MAX_N = 4


# --------------------------------------------------------------------------------------
# Export: sympy mass-matrix form -> JAX function
# --------------------------------------------------------------------------------------
def _as_matrix(expr, name: str, shape: tuple[int, int]) -> sp.Matrix:
    try:
        matrix = sp.Matrix(expr)
    except (TypeError, ValueError, sp.SympifyError):
        raise TypeError(f"{name}: expected a sympy Matrix, got {type(expr).__name__}") from None
    if matrix.shape != shape:
        if shape[1] == 1 and matrix.shape == (1, shape[0]):
            matrix = matrix.T
        else:
            raise ValueError(f"{name}: expected shape {shape}, got {matrix.shape}")
    return matrix


def _check_symbols(matrix: sp.Matrix, name: str, coords) -> None:
    allowed = set(coords.q) | set(coords.qd) | set(coords.tau) | {coords.t}
    unknown = matrix.free_symbols - allowed
    if unknown & set(coords.qdd):
        raise ValueError(
            f"{name}: contains accelerations {sorted(map(str, unknown & set(coords.qdd)))}; "
            "expected the mass-matrix form M(q, qd) qdd = f(q, qd, tau, t)"
        )
    if unknown:
        raise ValueError(
            f"{name}: contains symbols {sorted(map(str, unknown))} that are not positions, "
            "velocities, forces or time of the coordinates"
        )


def _unrolled_solve(a: list[list], b: list) -> list:
    """Solve ``a x = b`` for a small matrix given as nested lists of scalars.

    Gaussian elimination with partial pivoting, written out entry by entry so that
    under ``vmap`` every operation is an elementwise vector operation over the batch
    (LAPACK's batched LU is far slower for 2x2 systems). Pivot choice by
    compare-and-swap keeps it branch free.
    """
    n = len(b)
    a = [list(row) for row in a]
    b = list(b)
    for k in range(n):
        for i in range(k + 1, n):
            swap = jnp.abs(a[i][k]) > jnp.abs(a[k][k])
            row_k = [jnp.where(swap, a[i][j], a[k][j]) for j in range(k, n)]
            row_i = [jnp.where(swap, a[k][j], a[i][j]) for j in range(k, n)]
            a[k][k:], a[i][k:] = row_k, row_i
            b[k], b[i] = jnp.where(swap, b[i], b[k]), jnp.where(swap, b[k], b[i])
        for i in range(k + 1, n):
            factor = a[i][k] / a[k][k]
            for j in range(k + 1, n):
                a[i][j] = a[i][j] - factor * a[k][j]
            b[i] = b[i] - factor * b[k]
    x = [None] * n
    for i in reversed(range(n)):
        acc = b[i]
        for j in range(i + 1, n):
            acc = acc - a[i][j] * x[j]
        x[i] = acc / a[i][i]
    return x


def dynamics_function(dynamics, *, solver: str = "auto"):
    """Compile identified mass-matrix dynamics into a pure JAX function.

    Parameters
    ----------
    dynamics : MassMatrixDynamics
        Any object with attributes ``coords`` (:class:`pysindy_xl.Coordinates`),
        ``mass_matrix_expr`` (sympy Matrix ``(n, n)`` in positions and velocities) and
        ``forcing_expr`` (sympy Matrix ``(n, 1)`` in positions, velocities, forces and
        time), such that ``M(q, qd) qdd = f(q, qd, tau, t)``.
    solver : {"auto", "unrolled", "lu"}
        How ``qdd`` is solved for. ``"unrolled"``: Gaussian elimination with partial
        pivoting written out entry by entry (fast under ``vmap`` for small ``n``);
        ``"lu"``: :func:`jax.numpy.linalg.solve`; ``"auto"``: unrolled for
        ``n <= 4``, LU above.

    Returns
    -------
    callable
        ``f(state, u, t=0.0) -> d(state)/dt`` with ``state = [q, qd]`` of shape
        ``(..., 2n)``, ``u`` of shape ``(..., n)`` and ``t`` a scalar or an array
        broadcastable to the batch shape; returns ``[qd, qdd]`` of shape ``(..., 2n)``
        in the floating dtype of the inputs. Leading batch dimensions broadcast.
        The function carries the attributes ``n_coordinates`` and ``depends_on_time``.
        A singular mass matrix gives non-finite accelerations, which the simulators
        report as divergence.

    Examples
    --------
    >>> import sympy as sp, jax.numpy as jnp
    >>> from types import SimpleNamespace
    >>> import pysindy_xl as px
    >>> from pysindy_xl.jax_dynamics import dynamics_function
    >>> c = px.Coordinates(["x"])
    >>> spring = SimpleNamespace(coords=c, mass_matrix_expr=sp.Matrix([[2]]),
    ...                          forcing_expr=sp.Matrix([c.tau[0] - 4 * c.q[0]]))
    >>> f = dynamics_function(spring)
    >>> f(jnp.array([1.0, 0.5]), jnp.array([0.0]))
    Array([ 0.5, -2. ], dtype=float32)
    """
    for attribute in ("coords", "mass_matrix_expr", "forcing_expr"):
        if not hasattr(dynamics, attribute):
            raise TypeError(
                f"dynamics: expected a MassMatrixDynamics-like object with attribute "
                f"{attribute!r}, got {type(dynamics).__name__}"
            )
    if solver not in ("auto", "unrolled", "lu"):
        raise ValueError(f"solver: expected 'auto', 'unrolled' or 'lu', got {solver!r}")
    coords = dynamics.coords
    n = coords.n
    mass = _as_matrix(dynamics.mass_matrix_expr, "dynamics.mass_matrix_expr", (n, n))
    forcing = _as_matrix(dynamics.forcing_expr, "dynamics.forcing_expr", (n, 1))
    _check_symbols(mass, "dynamics.mass_matrix_expr", coords)
    _check_symbols(forcing, "dynamics.forcing_expr", coords)
    if solver == "auto":
        solver = "unrolled" if n <= _UNROLLED_MAX_N else "lu"

    # One lambdify over every entry of M and f shares common subexpressions
    # (sin/cos of the same angles appear in both).
    entries = list(mass) + list(forcing)
    arguments = list(coords.q) + list(coords.qd) + list(coords.tau) + [coords.t]
    evaluate = sp.lambdify(arguments, entries, modules="jax", cse=True)

    def single(state, u, t):
        dtype = state.dtype
        values = evaluate(*(state[i] for i in range(2 * n)), *(u[i] for i in range(n)), t)
        # Constant entries come back as Python numbers: give every entry the state dtype.
        values = [jnp.asarray(v, dtype=dtype) for v in values]
        m = [values[i * n : (i + 1) * n] for i in range(n)]
        rhs = values[n * n :]
        if solver == "unrolled":
            qdd = jnp.stack(_unrolled_solve(m, rhs))
        else:
            qdd = jnp.linalg.solve(jnp.stack([jnp.stack(row) for row in m]), jnp.stack(rhs))
        return jnp.concatenate([state[n:], qdd])

    vectorized = jnp.vectorize(single, signature="(s),(n),()->(s)")

    def dynamics_fn(state, u, t=0.0):
        state = jnp.asarray(state)
        u = jnp.asarray(u)
        if state.ndim < 1 or state.shape[-1] != 2 * n:
            raise ValueError(f"state: expected shape (..., {2 * n}), got {state.shape}")
        if u.ndim < 1 or u.shape[-1] != n:
            raise ValueError(f"u: expected shape (..., {n}), got {u.shape}")
        dtype = jnp.result_type(state, u, 0.0)
        if not jnp.issubdtype(dtype, jnp.floating):
            raise TypeError(f"state, u: expected real arrays, got dtype {dtype}")
        return vectorized(state.astype(dtype), u.astype(dtype), jnp.asarray(t, dtype=dtype))

    dynamics_fn.n_coordinates = n
    dynamics_fn.depends_on_time = coords.t in (mass.free_symbols | forcing.free_symbols)
    dynamics_fn.__doc__ = (
        f"d(state)/dt of the identified {n}-coordinate system {list(coords.names)}: "
        "f(state (..., 2n), u (..., n), t=0.0) -> [qd, qdd] (..., 2n)."
    )
    return dynamics_fn


# --------------------------------------------------------------------------------------
# Fixed-step schemes: pure functions of one state
# --------------------------------------------------------------------------------------
def _force_at(u_start, u_end, fraction):
    """Force at ``t + fraction * dt``: held when ``u_end`` is None, else linear."""
    if u_end is None:
        return u_start
    return u_start + fraction * (u_end - u_start)


def rk4_step(f, state, t, dt, u_start, u_end=None):
    """One classical Runge-Kutta step of ``d(state)/dt = f(state, u, t)``.

    Parameters
    ----------
    f : callable
        ``f(state, u, t) -> d(state)/dt``, e.g. from :func:`dynamics_function`.
    state : array (2n,)
    t, dt : float
        Time at the start of the step and step length.
    u_start : array (n,)
        Force at ``t``.
    u_end : array (n,), optional
        Force at ``t + dt``; when given the force is interpolated linearly inside the
        step, otherwise ``u_start`` is held.

    Returns
    -------
    array (2n,)
        State at ``t + dt``.
    """
    u_mid = _force_at(u_start, u_end, 0.5)
    u_last = _force_at(u_start, u_end, 1.0)
    k1 = f(state, u_start, t)
    k2 = f(state + 0.5 * dt * k1, u_mid, t + 0.5 * dt)
    k3 = f(state + 0.5 * dt * k2, u_mid, t + 0.5 * dt)
    k4 = f(state + dt * k3, u_last, t + dt)
    return state + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def semi_implicit_euler_step(f, state, t, dt, u_start, u_end=None):
    """One semi-implicit (symplectic) Euler step: velocities first, then positions.

    ``qd' = qd + dt qdd(q, qd, u(t))``, ``q' = q + dt qd'``. Same parameters as
    :func:`rk4_step`; ``u_end`` is accepted for a uniform signature and unused (a
    first-order scheme only samples the force at the start of the step).
    """
    del u_end
    n = state.shape[-1] // 2
    qdd = f(state, u_start, t)[..., n:]
    qd = state[..., n:] + dt * qdd
    q = state[..., :n] + dt * qd
    return jnp.concatenate([q, qd], axis=-1)


def euler_step(f, state, t, dt, u_start, u_end=None):
    """One explicit Euler step. Same parameters as :func:`rk4_step` (``u_end`` unused)."""
    del u_end
    return state + dt * f(state, u_start, t)


_STEPS = {
    "rk4": rk4_step,
    "semi_implicit_euler": semi_implicit_euler_step,
    "euler": euler_step,
}


# --------------------------------------------------------------------------------------
# Rollouts
# --------------------------------------------------------------------------------------
class BatchSimulation(NamedTuple):
    """Result of :func:`simulate` / :func:`simulate_batch` (a JAX pytree).

    Attributes
    ----------
    states : array (B, T, 2n), or (B, 2n) with ``final_only``; no ``B`` axis for
        :func:`simulate`.
        A diverged trajectory is frozen at its last accepted state: every sample from
        ``divergence_step`` on repeats it.
    diverged : bool array (B,)
        Whether the trajectory left the finite / bounded region.
    divergence_step : int array (B,)
        Index of the first sample that would have been non-finite or out of bound,
        ``-1`` for trajectories that did not diverge.
    """

    states: jax.Array
    diverged: jax.Array
    divergence_step: jax.Array


def _is_bad(state, bound):
    return ~jnp.all(jnp.isfinite(state) & (jnp.abs(state) <= bound), axis=-1)


def _rollout(f, step, x0, u, dt, t0, bound, linear, final_only):
    """Scan one trajectory: x0 (2n,), u (T, n) -> BatchSimulation without batch axis."""
    n_steps = u.shape[0] - 1
    bad0 = _is_bad(x0, bound)

    def body(carry, inputs):
        state, diverged, divergence_step, k = carry
        u_start, u_end = inputs
        t = t0 + k.astype(dt.dtype) * dt
        proposed = step(f, state, t, dt, u_start, u_end)
        bad = _is_bad(proposed, bound)
        divergence_step = jnp.where(bad & ~diverged, k + 1, divergence_step)
        diverged = diverged | bad
        # Freeze: a diverged trajectory keeps its last accepted state, so NaN never
        # propagates and the rest of the batch is untouched.
        state = jnp.where(diverged, state, proposed)
        return (state, diverged, divergence_step, k + 1), (None if final_only else state)

    carry0 = (x0, bad0, jnp.where(bad0, 0, -1), jnp.asarray(0, dtype=jnp.int32))
    (final, diverged, divergence_step, _), history = jax.lax.scan(
        body, carry0, (u[:-1], u[1:] if linear else None), length=n_steps
    )
    states = final if final_only else jnp.concatenate([x0[None], history], axis=0)
    return BatchSimulation(states, diverged, divergence_step)


@partial(jax.jit, static_argnames=("f", "method", "linear", "final_only", "batched"))
def _simulate_compiled(f, x0, u, dt, t0, bound, method, linear, final_only, batched):
    def run(x0, u):
        return _rollout(f, _STEPS[method], x0, u, dt, t0, bound, linear, final_only)

    if batched:
        run = jax.vmap(run)
    return run(x0, u)


def _float_dtype():
    """``float64`` when ``jax_enable_x64`` is on, else ``float32``."""
    return jnp.asarray(0.0).dtype


def _is_concrete(x) -> bool:
    return not isinstance(x, jax.core.Tracer)


def _prepare(f, x0, u, dt, t0, n_steps, method, interpolation, bound, batched):
    """Validate and convert the inputs shared by simulate and simulate_batch."""
    if hasattr(f, "to_jax") and not hasattr(f, "n_coordinates"):
        f = f.to_jax()
    if not callable(f):
        raise TypeError(f"f: expected a callable f(state, u, t), got {type(f).__name__}")
    if method not in _STEPS:
        raise ValueError(f"method: expected one of {sorted(_STEPS)}, got {method!r}")
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
        u = jnp.zeros(x0.shape[:lead] + (n_steps, n), dtype=dtype)
    else:
        u = jnp.asarray(u, dtype=dtype)
        if u.ndim != 2 + lead or u.shape[:lead] != x0.shape[:lead] or u.shape[-1] != n:
            shape = "(B, T, n)" if batched else "(T, n)"
            raise ValueError(
                f"u: expected shape {shape} = {x0.shape[:lead] + ('T', n)}, got {u.shape}"
            )
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
    if _is_concrete(dt) and not bool(dt > 0):
        raise ValueError(f"dt: expected a positive finite time step, got {float(dt)}")
    t0 = jnp.asarray(t0, dtype=dtype)
    if bound is None:
        bound = np.inf
    elif not np.isscalar(bound) or not bound > 0:
        raise ValueError(f"bound: expected None or a positive number, got {bound!r}")
    bound = jnp.asarray(bound, dtype=dtype)
    return f, x0, u, dt, t0, bound


def simulate(
    f,
    x0,
    u,
    dt,
    *,
    t0=0.0,
    n_steps=None,
    method="rk4",
    interpolation="zoh",
    bound=None,
    final_only=False,
):
    """Integrate one trajectory with a fixed step inside ``jax.lax.scan``.

    Parameters
    ----------
    f : callable or model
        ``f(state, u, t) -> d(state)/dt`` (see :func:`dynamics_function`), or any
        object with a ``to_jax()`` method such as a fitted ``XLSINDy``.
        Pass the same function object between calls to reuse the compiled code.
    x0 : array (2n,)
        Initial state ``[q, qd]``.
    u : array (T, n) or None
        Generalized forces sampled at ``t0 + k dt``; ``None`` means zero force and
        needs ``n_steps``.
    dt : float
        Time step.
    t0 : float, default 0.0
        Time of the first sample (matters for time-dependent dynamics).
    n_steps : int, optional
        Number of output samples ``T`` when ``u`` is None.
    method : {"rk4", "semi_implicit_euler", "euler"}
    interpolation : {"zoh", "linear"}
        Force inside a step: held at ``u[k]`` or linear between ``u[k]`` and ``u[k+1]``.
    bound : float, optional
        A trajectory diverges when a state entry becomes NaN/inf or, if given, exceeds
        ``bound`` in absolute value.
    final_only : bool, default False
        Return only the final state (saves memory for long or large runs).

    Returns
    -------
    BatchSimulation
        ``states`` (T, 2n) (or (2n,)), scalar ``diverged`` and ``divergence_step``.
        Differentiable with respect to ``x0``, ``u``, ``dt`` and ``t0``.

    Examples
    --------
    >>> import sympy as sp, jax.numpy as jnp
    >>> from types import SimpleNamespace
    >>> import pysindy_xl as px
    >>> from pysindy_xl.jax_dynamics import dynamics_function, simulate
    >>> c = px.Coordinates(["x"])
    >>> oscillator = SimpleNamespace(coords=c, mass_matrix_expr=sp.Matrix([[1]]),
    ...                              forcing_expr=sp.Matrix([-c.q[0]]))
    >>> f = dynamics_function(oscillator)
    >>> result = simulate(f, jnp.array([1.0, 0.0]), None, 0.01, n_steps=315)
    >>> result.states.shape, bool(result.diverged)
    ((315, 2), False)
    >>> round(float(result.states[-1, 0]), 3)  # cos(3.14)
    -1.0
    """
    f, x0, u, dt, t0, bound = _prepare(
        f, x0, u, dt, t0, n_steps, method, interpolation, bound, batched=False
    )
    return _simulate_compiled(
        f, x0, u, dt, t0, bound, method, interpolation == "linear", bool(final_only), False
    )


def simulate_batch(
    f,
    x0,
    u,
    dt,
    *,
    t0=0.0,
    n_steps=None,
    method="rk4",
    interpolation="zoh",
    bound=None,
    final_only=False,
):
    """Integrate ``B`` trajectories at once (``vmap`` of :func:`simulate`).

    Runs on the default JAX device (CPU, or GPU where present). Trajectories are
    independent: one that diverges is frozen and reported, the others carry on.

    Parameters
    ----------
    f : callable or model
        As in :func:`simulate`.
    x0 : array (B, 2n)
        Initial states.
    u : array (B, T, n) or None
        Force signal of each trajectory (``None``: zero force, needs ``n_steps``).
    dt, t0, n_steps, method, interpolation, bound, final_only
        As in :func:`simulate`; shared by all trajectories.

    Returns
    -------
    BatchSimulation
        ``states`` (B, T, 2n) (or (B, 2n) with ``final_only``), ``diverged`` (B,),
        ``divergence_step`` (B,).

    Examples
    --------
    >>> import sympy as sp, jax.numpy as jnp
    >>> from types import SimpleNamespace
    >>> import pysindy_xl as px
    >>> from pysindy_xl.jax_dynamics import dynamics_function, simulate_batch
    >>> c = px.Coordinates(["x"])
    >>> unstable = SimpleNamespace(coords=c, mass_matrix_expr=sp.Matrix([[1]]),
    ...                            forcing_expr=sp.Matrix([c.q[0] ** 3]))
    >>> f = dynamics_function(unstable)
    >>> out = simulate_batch(f, jnp.array([[0.1, 0.0], [10.0, 0.0]]), None, 0.1,
    ...                      n_steps=50, bound=1e3)
    >>> out.diverged.tolist(), out.divergence_step.tolist()
    ([False, True], [-1, 2])
    """
    f, x0, u, dt, t0, bound = _prepare(
        f, x0, u, dt, t0, n_steps, method, interpolation, bound, batched=True
    )
    return _simulate_compiled(
        f, x0, u, dt, t0, bound, method, interpolation == "linear", bool(final_only), True
    )
