"""Identified dynamics as pure JAX functions, and batched fixed-step simulation.

:func:`dynamics_function` compiles ``M(q, qd) qdd = f(q, qd, tau, t)`` into one pure JAX
function of the state (``jit``, ``vmap`` and ``grad`` apply); :func:`simulate` and
:func:`simulate_batch` integrate it with a fixed step inside ``jax.lax.scan``, in ``float64``
when ``jax_enable_x64`` is on (else ``float32``), reporting divergence per trajectory.

State ``[q_1..q_n, qd_1..qd_n]`` (2n,), forces ``u`` (n,). ``T`` force samples, ``u[k]`` at
``t0 + k dt``, give ``T`` states, ``states[0] = x0``. ``interpolation="zoh"`` holds ``u[k]``
over a step (a digital controller, ``mj_step``); ``"linear"`` interpolates to ``u[k+1]``."""

from __future__ import annotations

import inspect
import weakref
from functools import partial

import numpy as np
import sympy as sp

from .._optional import import_optional
from ..physical.rigid_body import rigid_body_dynamics
from ..symbols import Coordinates
from ._jax_rollout import BatchSimulation, simulate, simulate_batch
from ._jax_steps import euler_step, rk4_step, semi_implicit_euler_step
from ._jax_trig import fast_cos, fast_sin

jax = import_optional("jax", purpose="pysindy_xl.export.jax_dynamics (XLSINDy.to_jax)")
jnp = import_optional("jax.numpy", purpose="pysindy_xl.export.jax_dynamics (XLSINDy.to_jax)")

__all__ = ["BatchSimulation", "dynamics_function", "euler_step", "fast_cos", "fast_sin",
           "rk4_step", "semi_implicit_euler_step", "simulate", "simulate_batch"]

#: Largest system solved by unrolled Gaussian elimination; larger ones call LAPACK.
_UNROLLED_MAX_N = 4
#: Largest arm (rigid-body kernel) whose SPD mass matrix is solved by unrolled elimination
#: (about 1.6x faster than batched LU for 7 joints, equal to rounding).
_UNROLLED_RIGID_MAX_N = 8


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
        raise ValueError(f"{name}: contains accelerations "
                         f"{sorted(map(str, unknown & set(coords.qdd)))}; expected the "
                         "mass-matrix form M(q, qd) qdd = f(q, qd, tau, t)")
    if unknown:
        raise ValueError(f"{name}: contains symbols {sorted(map(str, unknown))} that are not "
                         "positions, velocities, forces or time of the coordinates")


def _unrolled_solve(a: list[list], b: list, pivoting: bool) -> list:
    """Solve ``a x = b`` for a small matrix given entry by entry, by Gaussian elimination written
    out elementwise over the batch (XLA vectorizes it; batched LAPACK LU does not). Optional
    partial pivoting by branch-free compare-and-swap; SPD (Lagrangian) mass matrices need none."""
    n = len(b)
    a = [list(row) for row in a]
    b = list(b)
    for k in range(n):
        if pivoting:
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


def _lu_solve(a: list[list], b: list) -> list:
    matrix = jnp.stack([jnp.stack(jnp.broadcast_arrays(*row), axis=-1) for row in a], axis=-2)
    rhs = jnp.stack(jnp.broadcast_arrays(*b), axis=-1)
    matrix, rhs = jnp.broadcast_arrays(matrix, rhs[..., None])
    solution = jnp.linalg.solve(matrix, rhs)[..., 0]
    return [solution[..., i] for i in range(len(b))]


def _numerically_positive_definite(dynamics, n_samples: int = 64) -> bool:
    """:func:`_looks_positive_definite` from the dynamics' own numerical ``mass_and_forcing``
    (nothing symbolic built)."""
    from ..feature_library import stack_variables
    n = dynamics.coords.n
    rng = np.random.default_rng(0)
    try:
        z = stack_variables(rng.uniform(-np.pi, np.pi, (n_samples, n)),
                            rng.uniform(-3.0, 3.0, (n_samples, n)), None,
                            rng.uniform(-3.0, 3.0, (n_samples, n)),
                            rng.uniform(0.0, 10.0, n_samples))
        with np.errstate(all="ignore"):
            matrices = np.asarray(dynamics.mass_and_forcing(z)[0], dtype=float)
    except (TypeError, ValueError, ArithmeticError, AttributeError):
        return False  # cannot tell: keep pivoting
    return _positive_definite(matrices)


def _positive_definite(matrices: np.ndarray) -> bool:
    """Whether every matrix (N, n, n) is finite, symmetric and positive definite."""
    if not np.all(np.isfinite(matrices)):
        return False
    scale = np.max(np.abs(matrices), axis=(1, 2), keepdims=True)
    if np.any(np.abs(matrices - np.swapaxes(matrices, 1, 2)) > 1e-9 * scale):
        return False
    return bool(np.all(np.linalg.eigvalsh(matrices)[:, 0] > 1e-12 * scale[:, 0, 0]))


def _looks_positive_definite(mass: sp.Matrix, coords, n_samples: int = 64) -> bool:
    """Whether ``M`` is symmetric positive definite at random states, i.e. whether elimination may
    skip pivoting (a wrong "yes" costs accuracy only on unphysical mass matrices)."""
    arguments = list(coords.q) + list(coords.qd) + list(coords.tau) + [coords.t]
    rng = np.random.default_rng(0)
    samples = np.concatenate([rng.uniform(-np.pi, np.pi, (n_samples, coords.n)),
                              rng.uniform(-3.0, 3.0, (n_samples, 2 * coords.n)),
                              rng.uniform(0.0, 10.0, (n_samples, 1))], axis=1)
    try:
        evaluate = sp.lambdify(arguments, mass, modules="numpy")
        with np.errstate(all="ignore"):
            matrices = np.stack([np.asarray(evaluate(*row), dtype=float) for row in samples])
    except (TypeError, ValueError, ArithmeticError, NameError):
        return False  # cannot tell: keep pivoting
    return _positive_definite(matrices)


_SOLVERS = {
    "auto": None,
    "gauss": partial(_unrolled_solve, pivoting=False),
    "pivoted": partial(_unrolled_solve, pivoting=True),
    "lu": _lu_solve,
}


def _componentwise_function(evaluate, n: int, solve):
    """``g(state, u, t) -> d(state)/dt`` on tuples of per-component arrays (XLA vectorizes these
    on CPU, not code assembling a stacked output)."""

    def componentwise(state, u, t):
        shape = jnp.broadcast_shapes(*(jnp.shape(c) for c in (*state, *u)))
        dtype = jnp.result_type(*state, *u)
        # Constant entries come back as Python numbers: make every entry an array.
        values = [jnp.asarray(v, dtype=dtype) for v in evaluate(*state, *u, t)]
        mass = [values[i * n : (i + 1) * n] for i in range(n)]
        qdd = solve(mass, values[n * n :])
        qdd = [jnp.broadcast_to(a, shape) for a in qdd]
        return tuple(state[n:]) + tuple(qdd)

    return componentwise


_MISSING = object()

# Compiled functions per dynamics object: the simulators' jit cache is keyed by the function,
# so handing out the same function for the same model avoids recompiling on every call.
_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def dynamics_function(dynamics, *, solver: str = "auto", fast_trig: bool = True):
    """Compile identified mass-matrix dynamics into a pure JAX function.

    Parameters
    ----------
    dynamics : MassMatrixDynamics
        Or any object with ``coords``, ``mass_matrix_expr`` (n, n) and ``forcing_expr`` (n, 1).
    solver : {"auto", "gauss", "pivoted", "lu"}
        How ``qdd`` is solved for: elimination written out (vectorizes) without pivoting (exact
        to rounding on SPD mass matrices) or with partial pivoting, or
        :func:`jax.numpy.linalg.solve`. ``"auto"``: for ``n <= 4``, ``"gauss"`` when ``M`` is
        SPD at random states, else ``"pivoted"``, a kinematic-catalog model evaluated through
        its written-out polynomials rather than the rigid-body kernel; above, ``"lu"``, except
        ``"gauss"`` for a kinematic-catalog arm of up to 8 joints with an SPD ``M``.
    fast_trig : bool, default True
        ``sin``, ``cos`` by :func:`fast_sin`, :func:`fast_cos`, else ``jax.numpy``'s.

    Returns
    -------
    callable
        ``f(state, u, t=0.0) -> [qd, qdd]``, ``state`` (..., 2n), ``u`` (..., n), batch
        dimensions broadcast, a singular ``M`` giving non-finite accelerations. Attributes
        ``n_coordinates``, ``depends_on_time``, ``solver`` and ``componentwise`` (the same on
        tuples of per-component arrays). The same object is returned for the same arguments.

    Examples
    --------
    >>> import sympy as sp, jax.numpy as jnp
    >>> from types import SimpleNamespace
    >>> import pysindy_xl as px
    >>> from pysindy_xl.export.jax_dynamics import dynamics_function
    >>> c = px.Coordinates(["x"])
    >>> spring = SimpleNamespace(coords=c, mass_matrix_expr=sp.Matrix([[2]]),
    ...                          forcing_expr=sp.Matrix([c.tau[0] - 4 * c.q[0]]))
    >>> f = dynamics_function(spring)
    >>> f(jnp.array([1.0, 0.5]), jnp.array([0.0]))
    Array([ 0.5, -2. ], dtype=float32)
    """
    for attribute in ("coords", "mass_matrix_expr", "forcing_expr"):
        # statically: reading the expressions builds them (minutes for a robot arm's)
        if inspect.getattr_static(dynamics, attribute, _MISSING) is _MISSING:
            raise TypeError(f"dynamics: expected a MassMatrixDynamics-like object with attribute "
                            f"{attribute!r}, got {type(dynamics).__name__}")
    if solver not in _SOLVERS:
        raise ValueError(f"solver: expected one of {list(_SOLVERS)}, got {solver!r}")
    key = (solver, bool(fast_trig))
    try:
        cached = _CACHE.setdefault(dynamics, {})
    except TypeError:  # not hashable or not weak-referenceable: compile every time
        cached = {}
    if key not in cached:
        cached[key] = _compile(dynamics, solver, bool(fast_trig))
    return cached[key]


def _compile(dynamics, solver: str, fast_trig: bool):
    coords = dynamics.coords
    if not isinstance(coords, Coordinates):
        raise TypeError(f"dynamics.coords: expected pysindy_xl.Coordinates, got "
                        f"{type(coords).__name__}")
    n = coords.n
    arguments = list(coords.q) + list(coords.qd) + list(coords.tau) + [coords.t]
    modules = [{"sin": fast_sin, "cos": fast_cos}, "jax"] if fast_trig else ["jax"]
    terms = getattr(dynamics, "numeric_terms", None) or getattr(dynamics, "terms", None)
    rigid_parts = tuple(getattr(dynamics, "rigid_parts", ()))
    if rigid_parts and solver == "auto" and n <= _UNROLLED_MAX_N:
        # a small system: its written-out polynomials (the expression path) and unrolled
        # elimination beat the rigid-body kernel with batched LU many times over
        terms, rigid_parts = dynamics.terms, ()
        evaluate = _terms_function(terms, arguments, modules)
        solver = "gauss" if _numerically_positive_definite(dynamics) else "pivoted"
        depends_on_time = any(coords.t in atom.free_symbols for atom in terms.atoms)
    elif terms is not None and (solver != "auto" or n > _UNROLLED_MAX_N or rigid_parts):
        # polynomial terms: any size, nothing symbolic built, nothing lambdified whole
        evaluate = _terms_function(terms, arguments, modules)
        if solver == "auto":
            solver = ("gauss" if rigid_parts and n <= _UNROLLED_RIGID_MAX_N
                      and _numerically_positive_definite(dynamics) else "lu")
        depends_on_time = any(coords.t in atom.free_symbols for atom in terms.atoms)
    else:
        mass = _as_matrix(dynamics.mass_matrix_expr, "dynamics.mass_matrix_expr", (n, n))
        forcing = _as_matrix(dynamics.forcing_expr, "dynamics.forcing_expr", (n, 1))
        _check_symbols(mass, "dynamics.mass_matrix_expr", coords)
        _check_symbols(forcing, "dynamics.forcing_expr", coords)
        if solver == "auto":
            solver = "gauss" if _looks_positive_definite(mass, coords) else "pivoted"
        depends_on_time = coords.t in (mass.free_symbols | forcing.free_symbols)
        evaluate = (_terms_function(terms, arguments, modules) if terms is not None
                    # one lambdify over every entry shares the common subexpressions
                    else sp.lambdify(arguments, list(mass) + list(forcing), modules=modules,
                                     cse=True))
    if rigid_parts:
        evaluate = _with_rigid_bodies(evaluate, rigid_parts, dynamics, n)
    componentwise = _componentwise_function(evaluate, n, _SOLVERS[solver])

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
        t = jnp.asarray(t, dtype=dtype)
        batch = jnp.broadcast_shapes(state.shape[:-1], u.shape[:-1], t.shape)
        state = jnp.broadcast_to(state.astype(dtype), batch + (2 * n,))
        u = jnp.broadcast_to(u.astype(dtype), batch + (n,))
        derivative = componentwise(tuple(state[..., i] for i in range(2 * n)),
                                   tuple(u[..., i] for i in range(n)), t)
        return jnp.stack(derivative, axis=-1)

    dynamics_fn.n_coordinates = n
    dynamics_fn.depends_on_time = depends_on_time
    dynamics_fn.componentwise = componentwise
    dynamics_fn.solver = solver
    dynamics_fn.__doc__ = (f"d(state)/dt of the identified {n}-coordinate system "
                           f"{list(coords.names)}: f(state (..., 2n), u (..., n), t=0.0) -> "
                           "[qd, qdd] (..., 2n).")
    return dynamics_fn


def _terms_function(terms, arguments, modules):
    """``evaluate(*arguments) -> entries`` of polynomial :class:`Terms` in JAX: each atom and its
    powers once, monomials as products of gathered powers, entries as a scatter-add, so that a
    handful of array operations serve any number of terms."""
    position = {symbol: k for k, symbol in enumerate(arguments)}
    used = sorted({a for entry in terms.entries for _, key in entry for a, _ in key})
    local = {a: k for k, a in enumerate(used)}
    atoms = [terms.atoms[a] for a in used]
    unknown = set().union(*(atom.free_symbols for atom in atoms)) - set(arguments)
    if unknown:
        raise ValueError(f"dynamics: the equations contain {sorted(map(str, unknown))}, "
                         "not positions, velocities, forces or time")
    functions = [position[atom] if atom in position
                 else sp.lambdify(arguments, atom, modules=modules) for atom in atoms]
    keys = sorted({key for entry in terms.entries for _, key in entry})
    monomial = {key: k for k, key in enumerate(keys)}
    width = max((len(key) for key in keys), default=1) or 1
    max_power = max((p for key in keys for _, p in key), default=1)
    # int32 indices: JAX's own index type whether or not x64 is enabled
    atom_index = np.zeros((len(keys), width), dtype=np.int32)
    power_index = np.zeros((len(keys), width), dtype=np.int32)  # power 0: the factor 1
    for k, key in enumerate(keys):
        for w, (a, p) in enumerate(key):
            atom_index[k, w], power_index[k, w] = local[a], p
    coefficients = np.array([c for entry in terms.entries for c, _ in entry], dtype=float)
    which_monomial = np.array([monomial[key] for entry in terms.entries for _, key in entry],
                              dtype=np.int32)
    which_entry = np.array([e for e, entry in enumerate(terms.entries) for _ in entry],
                           dtype=np.int32)
    n_entries = len(terms.entries)

    def evaluate(*values):
        batch = jnp.broadcast_shapes(*(jnp.shape(v) for v in values))
        dtype = jnp.result_type(*values, 0.0)
        atom_values = [jnp.broadcast_to(jnp.asarray(values[f] if isinstance(f, int)
                                                    else f(*values), dtype=dtype), batch)
                       for f in functions]
        base = jnp.stack(atom_values, axis=-1) if atom_values else jnp.zeros(batch + (1,),
                                                                              dtype)
        powers = [jnp.ones_like(base)]
        for _ in range(max_power):
            powers.append(powers[-1] * base)
        table = jnp.stack(powers, axis=-1)  # (..., atoms, max_power + 1)
        monomials = jnp.ones(batch + (len(keys),), dtype)
        for w in range(width):
            monomials = monomials * table[..., atom_index[:, w], power_index[:, w]]
        contributions = coefficients.astype(dtype) * monomials[..., which_monomial]
        entries = jnp.zeros(batch + (n_entries,), dtype).at[..., which_entry].add(
            contributions)
        return [entries[..., k] for k in range(n_entries)]

    return evaluate


def _with_rigid_bodies(evaluate, rigid_parts, dynamics, n: int):
    """``evaluate`` plus the rigid-body kernel's ``M`` and ``-bias``, zero for held coordinates."""
    moving = ~np.asarray(getattr(dynamics, "_held", np.zeros(n, dtype=bool)))
    parts = [(tree, np.asarray(pi, dtype=float)) for tree, pi in rigid_parts]

    def evaluate_all(*values):
        entries = evaluate(*values)
        batch = jnp.broadcast_shapes(*(jnp.shape(v) for v in values))
        dtype = jnp.result_type(*values, 0.0)
        q = jnp.reshape(jnp.stack([jnp.broadcast_to(v, batch) for v in values[:n]], -1),
                        (-1, n)).astype(dtype)
        qd = jnp.reshape(jnp.stack([jnp.broadcast_to(v, batch) for v in values[n:2 * n]],
                                   -1), (-1, n)).astype(dtype)
        mass, bias = 0.0, 0.0
        for tree, pi in parts:
            part_mass, part_bias = rigid_body_dynamics(tree, pi.astype(dtype), q, qd, xp=jnp)
            mass, bias = mass + part_mass, bias + part_bias
        mass = jnp.reshape(mass * moving[:, None], batch + (n * n,))
        force = jnp.reshape(-bias * moving, batch + (n,))
        rigid = [mass[..., k] for k in range(n * n)] + [force[..., k] for k in range(n)]
        return [e + r for e, r in zip(entries, rigid, strict=True)]

    return evaluate_all
