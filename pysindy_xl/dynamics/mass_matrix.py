"""Mass-matrix form of identified equations, ``M(q, qd) qdd = f(q, qd, tau, t)``, and simulation.

``M`` holds the equations' coefficients of ``qdd`` and ``f`` minus their value at ``qdd = 0``,
both kept as polynomials in a few atoms (:class:`~pysindy_xl.feature_library.Terms`): one
vectorized kernel evaluates many states, flat generated code one state, and a batched linear
solve gives the accelerations; nothing is solved symbolically or lambdified whole."""

from __future__ import annotations

import time as _time

import numpy as np
import scipy.integrate
import sympy as sp

from .._validation import check_numeric_array, check_option, check_times
from ..feature_library import Terms, compile_terms, decompose, scalar_function
from ..symbols import Coordinates, stack_variables
from .inputs import feedback_function, force_function

__all__ = ["MassMatrixDynamics", "DynamicsError", "SingularMassMatrixError", "SimulationError",
           "force_function"]


class DynamicsError(RuntimeError):
    """Base class of the errors raised by identified dynamics.

    >>> issubclass(SimulationError, DynamicsError), issubclass(SingularMassMatrixError,
    ...                                                        DynamicsError)
    (True, True)
    """


class SingularMassMatrixError(DynamicsError):
    """The identified mass matrix is singular (or numerically so) at the samples ``indices``.

    >>> import pysindy_xl as px
    >>> c = px.Coordinates(["x", "y"])
    >>> dyn = px.MassMatrixDynamics(c, [c.qdd[0] - c.tau[0], c.qdd[0] + c.q[1]])
    >>> try:
    ...     dyn.accelerations([[0.0, 0.0]], [[0.0, 0.0]])
    ... except px.SingularMassMatrixError as err:
    ...     print(err.indices)
    [0]
    """

    def __init__(self, message: str, indices=()):
        super().__init__(message)
        self.indices = np.asarray(indices, dtype=int)


class SimulationError(DynamicsError):
    """A simulation stopped before its end, at time ``t_failed`` for ``reason`` (``"diverged"``,
    ``"singular mass matrix"``, ``"non-finite derivative"``, ``"too many evaluations"``,
    ``"timeout"`` or ``"integrator failure (...)"``); ``t`` (k,) and ``states`` (k, 2n) are
    the valid part of the trajectory.

    >>> import numpy as np, pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> unstable = px.MassMatrixDynamics(c, [c.qdd[0] - c.q[0] ** 3])
    >>> try:
    ...     unstable.simulate([1.0, 0.0], np.linspace(0, 5, 51))
    ... except px.SimulationError as err:
    ...     print(err.reason, err.t_failed < 2.0, err.states[0])
    diverged True [1. 0.]
    """

    def __init__(self, message: str, t_failed: float, t, states, reason: str):
        super().__init__(message)
        self.t_failed = float(t_failed)
        self.t = np.asarray(t, dtype=float)
        self.states = np.asarray(states, dtype=float)
        self.reason = reason


class MassMatrixDynamics:
    """Equations ``E(q, qd, qdd, tau, t) = 0``, one per coordinate of ``coords`` and linear in
    ``coords.qdd``, in mass-matrix form: ``mass_matrix_expr`` ``M(q, qd)`` (n, n) and
    ``forcing_expr`` ``f(q, qd, tau, t)`` (n, 1), ``M qdd = f``.

    >>> import pysindy_xl as px
    >>> c = px.Coordinates(["x"])
    >>> dyn = px.MassMatrixDynamics(c, [2 * c.qdd[0] + 3 * c.q[0] - c.tau[0]])
    >>> dyn.mass_matrix_expr, dyn.forcing_expr
    (Matrix([[2]]), Matrix([[tau_x - 3*x]]))
    """

    def __init__(self, coords: Coordinates, equations):
        if not isinstance(coords, Coordinates):
            raise TypeError(f"coords: expected Coordinates, got {type(coords).__name__}")
        from ..expressions import as_expression
        if isinstance(equations, (str, sp.Basic)) or not hasattr(equations, "__iter__"):
            raise TypeError("equations: expected a list of expressions, one per coordinate")
        table = coords.symbol_table()
        equations = [as_expression(e, table, f"equations[{k}]")
                     for k, e in enumerate(equations)]
        if len(equations) != coords.n:
            raise ValueError(f"equations: expected {coords.n} equations, got {len(equations)}")
        qdd = sp.Matrix(coords.qdd)
        eqs = sp.Matrix(equations)
        mass = eqs.jacobian(qdd)
        if any(sp.diff(m, a) != 0 for m in mass for a in coords.qdd):
            raise ValueError("equations: not linear in the accelerations")
        zero = {a: 0 for a in coords.qdd}
        self.coords = coords
        self.equations = equations
        self.mass_matrix_expr = mass
        self.forcing_expr = -eqs.subs(zero)
        self._n = coords.n
        self._terms = decompose(list(self.mass_matrix_expr) + list(self.forcing_expr))
        self._compile()

    def _compile(self):
        self._evaluate = compile_terms(self.coords.variables, self._terms)
        self._vectorized_at_one_state = sum(
            len(entry) for entry in self._terms.entries) > _SCALAR_TERMS

    #: ``(tree, pi)`` pairs evaluated by the rigid-body kernel (:class:`CatalogDynamics`).
    rigid_parts: tuple = ()

    @property
    def terms(self) -> Terms:
        """``M`` (n * n entries, row-major) then ``f`` (n entries) as polynomials in atoms."""
        return self._terms

    @property
    def numeric_terms(self) -> Terms:
        """The part of :attr:`terms` read as polynomials (evaluators add :attr:`rigid_parts`)."""
        return self._terms

    @property
    def n_terms(self) -> int:
        """Monomials of ``M`` and ``f`` together: how long the written equations are."""
        count = self.__dict__.get("_n_terms")
        if count is None:
            count = self._n_terms = sum(len(entry) for entry in self.terms.entries)
        return count

    def _evaluate_scalar(self, *values):
        """Entries at one state: generated code on Python floats (far faster than NumPy on length-1
        arrays), or the vectorized kernel past :data:`_SCALAR_TERMS` terms; generated on first use.
        """
        if self._vectorized_at_one_state:
            return [float(v[0]) for v in self._evaluate(np.array([values], dtype=float))]
        function = self.__dict__.get("_scalar_function")
        if function is None:
            function = scalar_function(self.coords.variables, self._terms,
                                       modules=({"sign": _sign}, "math"))
            self._scalar_function = function
        return function(*values)

    def __getstate__(self):
        # compiled functions are generated code: rebuilt from the terms on unpickling
        state = self.__dict__.copy()
        state.pop("_evaluate", None)
        state.pop("_scalar_function", None)
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._compile()

    def mass_and_forcing(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``M`` (N, n, n) and ``f`` (N, n) at the rows of stacked variables ``z`` (N, 4n + 1)
        (:func:`~pysindy_xl.stack_variables`)."""
        n, n_samples = self._n, z.shape[0]
        values = [np.broadcast_to(v, (n_samples,)) for v in self._evaluate(z)]
        mass = np.stack(values[: n * n], axis=-1).reshape(n_samples, n, n)
        force = np.stack(values[n * n :], axis=-1)
        return mass, force

    def accelerations(self, q, qd, tau=None, t=None, rcond: float = 1e-12) -> np.ndarray:
        """Accelerations ``qdd = M^-1 f`` at many states: ``q``, ``qd``, forces ``tau`` (zero when
        absent) of shape (N, n), times ``t`` (N,). Raises :class:`SingularMassMatrixError` where
        ``M``'s reciprocal condition number is below ``rcond``."""
        arrays = {"q": q, "qd": qd, "tau": tau, "t": t}
        for name, value in arrays.items():
            if value is None:
                continue
            arrays[name] = check_numeric_array(value, name, min_samples=0)
        z = stack_variables(arrays["q"], arrays["qd"], None, arrays["tau"], arrays["t"])
        mass, force = self.mass_and_forcing(z)
        singular = self._singular(mass, rcond)
        if np.any(singular):
            idx = np.flatnonzero(singular)
            raise SingularMassMatrixError(
                f"the identified mass matrix is singular at {len(idx)} of {len(z)} states "
                f"(first at sample {idx[0]}); the equations of some coordinates contain no "
                "acceleration there",
                idx,
            )
        return np.linalg.solve(mass, force[..., None])[..., 0]

    def state_derivative(self, state, u=None, t: float = 0.0) -> np.ndarray:
        """``d(state)/dt = [qd, M^-1 f]`` at one state ``[q, qd]`` with forces ``u`` (n,) (zero when
        absent): the simulators' fast path. Raises :class:`SingularMassMatrixError` if ``M`` is
        singular there or ``M``, ``f`` not finite.

        >>> import pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> px.MassMatrixDynamics(c, [2 * c.qdd[0] + c.q[0]]).state_derivative([1.0, 3.0])
        array([ 3. , -0.5])
        """
        n = self._n
        state = np.asarray(state, dtype=float)
        inputs = [0.0] * n if u is None else np.asarray(u, dtype=float).tolist()
        try:
            mass, force = self._scalar_parts(state, inputs, t)
        except (OverflowError, ValueError, ZeroDivisionError) as err:
            raise SingularMassMatrixError(f"cannot evaluate the dynamics: {err}", [0]) from None
        if not (np.all(np.isfinite(mass)) and np.all(np.isfinite(force))):
            raise SingularMassMatrixError("the dynamics are not finite at this state", [0])
        if not abs(np.linalg.det(mass)) > 1e-12 * np.prod(np.linalg.norm(mass, axis=1)):
            raise SingularMassMatrixError("the identified mass matrix is singular", [0])
        return np.concatenate([state[n:], np.linalg.solve(mass, force)])

    def _scalar_parts(self, state, inputs, t):
        """``M`` (n, n) and ``f`` (n,) at one state (n + n floats) and forces (n floats)."""
        n = self._n
        values = self._evaluate_scalar(*state.tolist(), *([0.0] * n), *inputs, t)
        return (np.array(values[: n * n], dtype=float).reshape(n, n),
                np.array(values[n * n:], dtype=float))

    @staticmethod
    def _singular(mass: np.ndarray, rcond: float) -> np.ndarray:
        if not np.all(np.isfinite(mass)):
            return ~np.all(np.isfinite(mass), axis=(1, 2))
        s = np.linalg.svd(mass, compute_uv=False)
        return ~(s[:, -1] > rcond * s[:, 0])

    def simulate(self, x0, t, u=None, *, method: str = "DOP853", rtol: float = 1e-8,
                 atol: float = 1e-10, divergence_bound: float = 1e6,
                 max_evaluations: int = 1_000_000, timeout: float | None = 300.0,
                 interpolation: str = "cubic", feedback=None,
                 step: float | None = None) -> np.ndarray:
        """Integrate the dynamics with one of scipy's adaptive ODE solvers, or ROS2; returns the
        states (T, 2n), or raises :class:`SimulationError` (with the valid part of the trajectory)
        when the run stops early.

        Parameters
        ----------
        x0 : array, shape (2n,)
            Initial state ``[q_1..q_n, qd_1..qd_n]``.
        t : array, shape (T,)
            Strictly increasing output times.
        u : None, array (T, n) or callable ``u(t) -> (n,)``
            Generalized forces, a function of time (open loop).
        method : {"DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA", "ROS2"}
            scipy's solver (``"Radau"`` or ``"BDF"`` for stiff models), or the L-stable
            Rosenbrock method of :mod:`pysindy_xl.dynamics.rosenbrock` for stiff closed loops
            (steps of at most ``step``, local error bound ``1e-3 (1 + |y|)``, tolerances unused).
        rtol, atol, divergence_bound, max_evaluations, timeout : float
            Solver tolerances; the run stops when a state component exceeds ``divergence_bound``,
            after ``max_evaluations`` right-hand sides or ``timeout`` seconds (None: no bound).
        interpolation : {"cubic", "linear", "previous"}
            How an array ``u`` is read between samples (:func:`force_function`).
        feedback : callable, optional
            ``feedback(t, q, qd) -> (n,)``, added to ``u`` at every step: a closed loop (servo,
            controller; :func:`pysindy_xl.mujoco.actuator_law` gives an MJCF's).
        step : float, optional
            Largest step of ``"ROS2"`` (default: the smallest spacing of ``t``).

        Examples
        --------
        A unit mass driven to ``q = 1`` by a PD controller:

        >>> import numpy as np, pysindy_xl as px
        >>> c = px.Coordinates(["x"])
        >>> mass = px.MassMatrixDynamics(c, [c.qdd[0] - c.tau[0]])
        >>> pd = lambda t, q, qd: 4.0 * (1.0 - q) - 4.0 * qd
        >>> states = mass.simulate([0.0, 0.0], np.linspace(0.0, 10.0, 11), feedback=pd)
        >>> round(float(states[-1, 0]), 3)
        1.0
        """
        n = self._n
        rtol = check_option("rtol", rtol, "real", low=0, low_open=True)
        atol = check_option("atol", atol, "real", low=0)
        divergence_bound = check_option("divergence_bound", divergence_bound, "real", low=0,
                                        low_open=True, allow_inf=True)
        max_evaluations = check_option("max_evaluations", max_evaluations, "int", low=1)
        timeout = check_option("timeout", timeout, "real", low=0,
                               allow_none=True, allow_inf=True)
        if not isinstance(method, str) and not isinstance(method, type):
            raise TypeError(f"method: expected a solver name, got {type(method).__name__}")
        x0 = check_numeric_array(x0, "x0", finite=False, min_samples=0).reshape(-1)
        if x0.shape != (2 * n,) or not np.all(np.isfinite(x0)):
            raise ValueError(f"x0: expected {2 * n} finite values [q, qd], got {x0.shape}")
        t = check_times(t, "t")
        force = force_function(u, t, n, interpolation)
        law = feedback_function(feedback, x0, t[0], n)
        counter = {"n": 0}
        start = _time.perf_counter()

        def rhs(s, state):
            counter["n"] += 1
            if counter["n"] > max_evaluations:
                raise _Stop(s, "too many evaluations")
            if timeout is not None and counter["n"] % 256 == 0:
                if _time.perf_counter() - start > timeout:
                    raise _Stop(s, "timeout")
            inputs = force(s) if law is None else force(s) + law(s, state)
            try:
                derivative = self.state_derivative(state, inputs, s)
            except SingularMassMatrixError as err:
                reason = "singular mass matrix" if "singular" in str(err) else \
                    "non-finite derivative"
                raise _Stop(s, reason) from None
            if not np.all(np.isfinite(derivative)):
                raise _Stop(s, "non-finite derivative")
            return derivative

        if method == "ROS2":
            return self._simulate_ros2(x0, t, force, law, step, divergence_bound, timeout)
        solver_class = _SOLVERS.get(method)
        if solver_class is None:
            raise ValueError(f"method: expected one of {[*sorted(_SOLVERS), 'ROS2']}, got "
                             f"{method!r}")
        out = np.empty((len(t), 2 * n))
        out[0] = x0
        filled = 1
        try:
            solver = solver_class(rhs, t[0], x0, t[-1], rtol=rtol, atol=atol)
            while filled < len(t):
                message = solver.step()
                if solver.status == "failed":
                    raise _Stop(solver.t, f"integrator failure ({message})")
                stop = filled + np.searchsorted(t[filled:], solver.t, side="right")
                if stop > filled:
                    out[filled:stop] = solver.dense_output()(t[filled:stop]).T
                    bad = np.flatnonzero(np.max(np.abs(out[filled:stop]), axis=1)
                                         > divergence_bound)
                    if len(bad):
                        filled += bad[0]
                        raise _Stop(t[filled], "diverged")
                    filled = stop
                elif np.max(np.abs(solver.y)) > divergence_bound:
                    raise _Stop(solver.t, "diverged")
        except _Stop as stop:
            raise SimulationError(
                f"simulation stopped at t={stop.t:.6g}: {stop.reason}",
                stop.t, t[:filled], out[:filled], stop.reason,
            ) from None
        return out

    def _simulate_ros2(self, x0, t, force, law, step, divergence_bound, timeout):
        """:meth:`simulate` with :func:`pysindy_xl.dynamics.rosenbrock.ros2`."""
        from .rosenbrock import RosenbrockStop, ros2
        step = float(np.min(np.diff(t))) if step is None else check_option(
            "step", step, "real", low=0, low_open=True)

        def parts(s, state):
            inputs = force(s) if law is None else force(s) + law(s, state)
            try:
                return self._scalar_parts(state, np.asarray(inputs, dtype=float).tolist(), s)
            except (OverflowError, ValueError, ZeroDivisionError):
                raise RosenbrockStop(s, "non-finite derivative") from None

        try:
            return ros2(parts, x0, t, step, divergence_bound=divergence_bound,
                        timeout=timeout, tolerance=1e-3)
        except RosenbrockStop as stop:
            states = x0[None] if stop.states is None else stop.states
            raise SimulationError(f"simulation stopped at t={stop.t:.6g}: {stop.reason}",
                                  stop.t, t[:len(states)], states, stop.reason) from None


#: Terms of ``M`` and ``f`` above which one state is evaluated by the vectorized kernel.
_SCALAR_TERMS = 1000

_SOLVERS = {name: getattr(scipy.integrate, name)
            for name in ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")}


def _sign(value: float) -> float:
    return float(np.sign(value))


class _Stop(Exception):
    def __init__(self, t, reason):
        super().__init__(reason)
        self.t, self.reason = float(t), reason
