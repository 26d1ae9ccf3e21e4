"""Discrete-time dynamics of an identified model, for planning.

A planner sees ``x_{k+1} = F(x_k, u_k)``: ``substeps`` fixed Runge-Kutta steps of
``xdot = f(x, B u)`` over one control period ``dt`` with the control ``u`` (m,) held (zero-order
hold, as a digital controller drives a plant), ``B`` (n, m) mapping the actuators to the
generalized forces of the coordinates."""

from __future__ import annotations

import numpy as np

from .._optional import import_optional

jax = import_optional("jax", purpose="pysindy_xl.control")
jnp = import_optional("jax.numpy", purpose="pysindy_xl.control")

__all__ = ["actuation_matrix", "continuous_dynamics", "discrete_dynamics"]


def continuous_dynamics(model):
    """The JAX function ``f(state, tau) -> d(state)/dt`` of a model.

    Parameters
    ----------
    model : XLSINDy, MassMatrixDynamics or callable
        A fitted model (its :meth:`~pysindy_xl.XLSINDy.to_jax`), mass-matrix dynamics
        (:func:`~pysindy_xl.export.jax_dynamics.dynamics_function`) or a JAX function
        ``f(state (2n,), tau (n,)) -> (2n,)`` with an ``n_coordinates`` attribute.

    Returns
    -------
    callable
        ``f`` with ``f.n_coordinates``.

    Raises
    ------
    TypeError
        If ``model`` gives no accelerations (neither ``to_jax``, mass-matrix expressions nor an
        ``n_coordinates`` attribute), or is not fitted.

    Examples
    --------
    >>> import pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> f = continuous_dynamics(px.MassMatrixDynamics(c, [2 * c.qdd[0] - c.tau[0]]))
    >>> [float(v) for v in f(jnp.array([0.0, 1.0]), jnp.array([4.0]))]
    [1.0, 2.0]
    """
    if callable(model) and hasattr(model, "n_coordinates") and not hasattr(model, "to_jax"):
        return model
    if hasattr(model, "to_jax"):
        try:
            return model.to_jax()
        except (AttributeError, ValueError) as error:
            raise TypeError(f"model: expected a fitted model that gives accelerations "
                            f"(M(q) qdd = f), got {type(model).__name__} ({error})") from None
    if hasattr(model, "mass_matrix_expr") and hasattr(model, "coords"):
        from ..export.jax_dynamics import dynamics_function
        return dynamics_function(model)
    raise TypeError(f"model: expected a fitted XLSINDy, a MassMatrixDynamics or a JAX function "
                    f"f(state, tau) with attribute n_coordinates, i.e. a model that gives "
                    f"accelerations; got {type(model).__name__}")


def actuation_matrix(coordinate_names, actuated) -> np.ndarray:
    """``B`` (n, m): actuator ``j`` pushes coordinate ``actuated[j]`` with unit gain.

    Parameters
    ----------
    coordinate_names : sequence of str
        The ``n`` coordinates.
    actuated : str or sequence of str
        The ``m`` pushed coordinates.

    Returns
    -------
    numpy.ndarray
        ``B`` (n, m), generalized forces ``tau = B u``.

    Examples
    --------
    >>> actuation_matrix(["x", "theta"], ["x"])
    array([[1.],
           [0.]])
    """
    names = list(coordinate_names)
    if isinstance(actuated, str):
        actuated = [actuated]
    unknown = [a for a in actuated if a not in names]
    if unknown or not list(actuated):
        raise ValueError(f"actuated: expected a non-empty list of coordinates among {names}, "
                         f"got {list(actuated)!r}")
    matrix = np.zeros((len(names), len(actuated)))
    for j, name in enumerate(actuated):
        matrix[names.index(name), j] = 1.0
    return matrix


def discrete_dynamics(f, dt: float, actuation, substeps: int = 2):
    r"""``F(x, u)``: one control period of ``xdot = f(x, B u)`` by ``substeps`` RK4 steps.

    Parameters
    ----------
    f : callable
        ``f(state (2n,), tau (n,)) -> d(state)/dt`` (:func:`continuous_dynamics`).
    dt : float
        Control period (s).
    actuation : array (n, m)
        ``B`` of :func:`actuation_matrix`.
    substeps : int, default 2
        RK4 steps per period.

    Returns
    -------
    callable
        Pure ``F(x (2n,), u (m,)) -> x (2n,)``: ``jit``, ``vmap``, ``grad`` apply.

    Examples
    --------
    >>> import jax.numpy as jnp
    >>> double_integrator = lambda x, tau: jnp.array([x[1], tau[0]])
    >>> step = discrete_dynamics(double_integrator, 0.1, [[1.0]], substeps=1)
    >>> [round(float(v), 6) for v in step(jnp.array([0.0, 1.0]), jnp.array([2.0]))]
    [0.11, 1.2]
    """
    if not callable(f):
        raise TypeError(f"f: expected a callable f(state, tau), got {type(f).__name__}")
    dt = float(dt)
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt: expected a positive control period, got {dt!r}")
    if isinstance(substeps, bool) or not isinstance(substeps, int | np.integer) or substeps < 1:
        raise ValueError(f"substeps: expected an integer >= 1, got {substeps!r}")
    matrix = np.asarray(actuation, dtype=float)
    if matrix.ndim != 2:
        raise ValueError(f"actuation: expected a matrix (n, m), got shape {matrix.shape}")
    n = getattr(f, "n_coordinates", matrix.shape[0])
    if matrix.shape[0] != n:
        raise ValueError(f"actuation: expected {n} rows (one per coordinate), got shape "
                         f"{matrix.shape}")
    h = dt / int(substeps)

    def step(x, u):
        tau = jnp.asarray(matrix, dtype=x.dtype) @ u
        for _ in range(int(substeps)):
            k1 = f(x, tau)
            k2 = f(x + 0.5 * h * k1, tau)
            k3 = f(x + 0.5 * h * k2, tau)
            k4 = f(x + h * k3, tau)
            x = x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        return x

    step.n_coordinates = n
    step.n_controls = matrix.shape[1]
    step.dt = dt
    return step
