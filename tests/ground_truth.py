"""Independent ground truth for the tests: textbook systems derived with sympy.physics.mechanics.

The equations of motion come from :class:`sympy.physics.mechanics.LagrangesMethod` (particles,
frames, gravity, viscous friction and external generalized forces through the force list), not
from pysindy_xl's own Euler-Lagrange code, so that tests compare the package against something it
did not compute itself.

Conventions (all systems): point masses, gravity ``G = 9.81`` along ``-y``, angles measured from
the downward vertical (absolute angles for the double pendulums). On coordinate ``i`` act the
viscous friction ``-c_i * qd_i`` and the external generalized force ``tau_i``.

Systems: :func:`cart_pole`, :func:`double_pendulum`, :func:`cart_double_pendulum`,
:func:`triple_pendulum`. Each returns a
:class:`TrueSystem` with vectorized accelerations and a tight-tolerance :meth:`TrueSystem.simulate`.
Forcing signals: :func:`sum_of_sines`, :func:`random_force`; initial states:
:func:`random_initial_state`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp
from sympy.physics import mechanics as me

from pysindy_xl import Coordinates

G = 9.81

__all__ = [
    "G",
    "TrueSystem",
    "cart_pole",
    "double_pendulum",
    "cart_double_pendulum",
    "triple_pendulum",
    "sum_of_sines",
    "random_force",
    "random_initial_state",
]


# --------------------------------------------------------------------------------------------
# The system container
# --------------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, eq=False)
class TrueSystem:
    """A mechanical system with known equations ``M(q) qdd = f(q, qd, tau)``.

    Parameters
    ----------
    name : str
    coords : pysindy_xl.Coordinates
    lagrangian : sympy.Expr
        ``T - V`` in the symbols ``coords.q`` / ``coords.qd``, trig-expanded (``cos(a - b)``
        appears as ``cos(a) cos(b) + sin(a) sin(b)``).
    friction : numpy.ndarray of shape (n,)
        Viscous friction coefficients ``c_i``: generalized force ``-c_i * qd_i`` on coordinate i.
    mass_matrix_expr : sympy.Matrix (n, n)
        Mass matrix in ``coords.q``.
    forcing_symbolic : sympy.Matrix (n, 1)
        Right-hand side in ``coords.q, coords.qd, coords.tau`` and the friction symbols
        ``friction_symbols`` (kept symbolic so :meth:`with_friction` needs no new derivation).
    friction_symbols : tuple of sympy.Symbol
    energy_expr : sympy.Expr
        Total mechanical energy ``T + V``.
    force_amplitude : numpy.ndarray of shape (n,)
        Peak generalized force per coordinate that keeps forced trajectories lively but tame;
        used by :func:`random_force`.
    """

    name: str
    coords: Coordinates
    lagrangian: sp.Expr
    friction: np.ndarray
    mass_matrix_expr: sp.Matrix
    forcing_symbolic: sp.Matrix
    friction_symbols: tuple
    energy_expr: sp.Expr
    force_amplitude: np.ndarray
    _compiled: dict = dataclasses.field(default_factory=dict, repr=False)

    def __post_init__(self):
        friction = np.asarray(self.friction, dtype=float)
        if friction.shape != (self.n,) or not np.all(np.isfinite(friction)):
            raise ValueError(f"friction: expected {self.n} finite values, got {self.friction!r}")
        object.__setattr__(self, "friction", friction)
        object.__setattr__(self, "force_amplitude", np.asarray(self.force_amplitude, dtype=float))
        if not self._compiled:
            self._compiled.update(self._compile())

    # ---- structure ---------------------------------------------------------------------------

    @property
    def n(self) -> int:
        """Number of generalized coordinates."""
        return self.coords.n

    @property
    def forcing_expr(self) -> sp.Matrix:
        """Right-hand side ``f(q, qd, tau)`` with this system's friction values substituted."""
        values = {c: sp.Float(v) for c, v in zip(self.friction_symbols, self.friction, strict=True)}
        return self.forcing_symbolic.xreplace(values)

    def with_friction(self, friction) -> TrueSystem:
        """Same system with other friction coefficients; reuses the compiled functions.

        Parameters
        ----------
        friction : array_like of shape (n,)

        Returns
        -------
        TrueSystem
        """
        return dataclasses.replace(self, friction=np.asarray(friction, dtype=float))

    def _compile(self) -> dict:
        """Lambdify mass matrix, forcing and energy once (entries kept separate to broadcast)."""
        c = self.coords
        args = (*c.q, *c.qd, *c.tau, *self.friction_symbols)
        mass = sp.lambdify(args, list(self.mass_matrix_expr), "numpy", cse=True)
        forcing = sp.lambdify(args, list(self.forcing_symbolic), "numpy", cse=True)
        energy = sp.lambdify((*c.q, *c.qd), [self.energy_expr], "numpy", cse=True)
        return {"mass": mass, "forcing": forcing, "energy": energy}

    # ---- numerics ----------------------------------------------------------------------------

    def _as_samples(self, value, name: str, n_samples: int | None = None) -> np.ndarray:
        array = np.asarray(value, dtype=float)
        if array.ndim == 1:
            array = array[None, :]
        if array.ndim != 2 or array.shape[1] != self.n:
            raise ValueError(f"{name}: expected shape (N, {self.n}), got {np.shape(value)}")
        if n_samples is not None and array.shape[0] != n_samples:
            raise ValueError(f"{name}: expected {n_samples} rows, got {array.shape[0]}")
        if not np.all(np.isfinite(array)):
            raise ValueError(f"{name}: contains NaN or inf")
        return array

    def _stack(self, entries, n_samples: int, shape: tuple) -> np.ndarray:
        # Constant entries come back as Python scalars; broadcast before stacking.
        columns = [np.broadcast_to(np.asarray(e, dtype=float), (n_samples,)) for e in entries]
        return np.stack(columns, axis=-1).reshape((n_samples, *shape))

    def _arguments(self, q, qd, tau):
        one_dim = np.ndim(q) == 1
        q = self._as_samples(q, "q")
        qd = self._as_samples(qd, "qd", q.shape[0])
        if tau is None:
            tau = np.zeros_like(q)
        tau = self._as_samples(tau, "tau", q.shape[0])
        args = (*q.T, *qd.T, *tau.T, *self.friction)
        return args, q.shape[0], one_dim

    def mass_matrix(self, q) -> np.ndarray:
        """Numeric mass matrices, shape (N, n, n) for q of shape (N, n)."""
        zeros = np.zeros_like(self._as_samples(q, "q"))
        args, n_samples, _ = self._arguments(q, zeros, None)
        return self._stack(self._compiled["mass"](*args), n_samples, (self.n, self.n))

    def accelerations(self, q, qd, tau=None) -> np.ndarray:
        """True accelerations ``qdd = M(q)^-1 f(q, qd, tau)``, batched over samples.

        Parameters
        ----------
        q, qd : array_like of shape (N, n) (or (n,) for one sample)
        tau : array_like of shape (N, n), optional
            Generalized forces; None means zero.

        Returns
        -------
        numpy.ndarray of shape (N, n) (or (n,) when q was one-dimensional)
        """
        args, n_samples, one_dim = self._arguments(q, qd, tau)
        qdd = self._solve(args, n_samples)
        return qdd[0] if one_dim else qdd

    def _solve(self, args, n_samples: int) -> np.ndarray:
        if n_samples == 1 and np.ndim(args[0]) == 0:
            # Fast path for the integrator: scalar entries, no broadcasting machinery.
            mass = np.array(self._compiled["mass"](*args), dtype=float).reshape(self.n, self.n)
            forcing = np.array(self._compiled["forcing"](*args), dtype=float)
            return np.linalg.solve(mass, forcing)[None, :]
        mass = self._stack(self._compiled["mass"](*args), n_samples, (self.n, self.n))
        forcing = self._stack(self._compiled["forcing"](*args), n_samples, (self.n, 1))
        return np.linalg.solve(mass, forcing)[..., 0]

    def energy(self, q, qd) -> np.ndarray:
        """Total mechanical energy ``T + V`` per sample, shape (N,)."""
        one_dim = np.ndim(q) == 1
        q = self._as_samples(q, "q")
        qd = self._as_samples(qd, "qd", q.shape[0])
        (values,) = self._compiled["energy"](*q.T, *qd.T)
        values = np.broadcast_to(np.asarray(values, dtype=float), (q.shape[0],)).copy()
        return values[0] if one_dim else values

    def simulate(self, x0, t, force=None, rtol: float = 1e-10, atol: float = 1e-10) -> dict:
        """Integrate the true dynamics with ``solve_ivp`` (DOP853).

        Parameters
        ----------
        x0 : array_like of shape (2n,)
            Initial state ``[q_1..q_n, qd_1..qd_n]``.
        t : array_like of shape (N,)
            Strictly increasing output times; integration starts at ``t[0]``.
        force : callable, optional
            ``u(t) -> (n,)`` generalized forces (vectorized callables ``u(times) -> (N, n)``
            are used as such for the returned ``tau``). None means unforced.
        rtol, atol : float
            Integrator tolerances.

        Returns
        -------
        dict
            ``t`` (N,), ``q``, ``qd``, ``qdd``, ``tau`` (each (N, n)); ``qdd`` is evaluated from
            the true dynamics at the returned states.
        """
        n = self.n
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (2 * n,) or not np.all(np.isfinite(x0)):
            raise ValueError(f"x0: expected {2 * n} finite values, got shape {x0.shape}")
        t = np.asarray(t, dtype=float)
        if t.ndim != 1 or t.size < 2 or not np.all(np.diff(t) > 0):
            raise ValueError("t: expected a strictly increasing 1-D array of at least 2 times")
        if force is not None and not callable(force):
            raise TypeError(f"force: expected None or a callable u(t), got {type(force).__name__}")

        def tau_at(time: float) -> np.ndarray:
            if force is None:
                return np.zeros(n)
            return np.asarray(force(time), dtype=float).reshape(n)

        def rhs(time, state):
            # Inputs are trusted here: skip the validation of accelerations() for speed.
            qdd = self._solve((*state, *tau_at(time), *self.friction), 1)
            return np.concatenate([state[n:], qdd[0]])

        solution = solve_ivp(
            rhs, (t[0], t[-1]), x0, method="DOP853", t_eval=t, rtol=rtol, atol=atol
        )
        if not solution.success:
            raise RuntimeError(f"{self.name}: integration failed: {solution.message}")
        q, qd = solution.y[:n].T, solution.y[n:].T
        tau = _evaluate_force(force, t, n)
        return {"t": t, "q": q, "qd": qd, "qdd": self.accelerations(q, qd, tau), "tau": tau}


def _evaluate_force(force, t: np.ndarray, n: int) -> np.ndarray:
    """Force on all times: vectorized call when the callable supports it, else one by one."""
    if force is None:
        return np.zeros((t.size, n))
    try:
        values = np.asarray(force(t), dtype=float)
    except (TypeError, ValueError):
        values = None
    if values is None or values.shape != (t.size, n):
        values = np.array([np.asarray(force(s), dtype=float).reshape(n) for s in t])
    if not np.all(np.isfinite(values)):
        raise ValueError("force: returned NaN or inf")
    return values


# --------------------------------------------------------------------------------------------
# Derivation with sympy.physics.mechanics
# --------------------------------------------------------------------------------------------


def _derive(
    name: str,
    coords: Coordinates,
    build: Callable,
    friction: Sequence[float],
    force_amplitude: Sequence[float],
) -> TrueSystem:
    """Run LagrangesMethod on the particles and loads that ``build`` creates.

    ``build(q, qd, frame, origin)`` receives the dynamic symbols and returns ``particles`` and
    ``carriers``: for each coordinate, the (Point, direction) or (ReferenceFrame, axis) on which
    its generalized force acts as a force or torque; with absolute coordinates the partial
    velocity (angular velocity) of that carrier with respect to ``qd_i`` is the unit direction
    and zero for the others, so the load becomes exactly the generalized force on coordinate i.
    """
    n = coords.n
    q = me.dynamicsymbols(" ".join(f"{s}_q" for s in coords.names), seq=True)
    qd = [qi.diff(me.dynamicsymbols._t) for qi in q]
    frame = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(frame, 0)
    particles, carriers = build(q, qd, frame, origin)
    if len(carriers) != n:
        raise ValueError(f"build: expected {n} load carriers, got {len(carriers)}")

    friction_symbols = tuple(sp.Symbol(f"c_{s}", real=True) for s in coords.names)
    loads = []
    for i, (carrier, direction) in enumerate(carriers):
        generalized = coords.tau[i] - friction_symbols[i] * qd[i]
        loads.append((carrier, generalized * direction))

    lagrangian = me.Lagrangian(frame, *particles)
    method = me.LagrangesMethod(lagrangian, q, forcelist=loads, frame=frame)
    method.form_lagranges_equations()

    to_symbols = {**dict(zip(qd, coords.qd, strict=True)), **dict(zip(q, coords.q, strict=True))}

    def plain(expr):
        # Derivatives are keys too, and xreplace matches them before their inner q(t).
        return expr.xreplace(to_symbols)

    energy = sum(p.kinetic_energy(frame) + p.potential_energy for p in particles)
    return TrueSystem(
        name=name,
        coords=coords,
        lagrangian=sp.expand(sp.expand_trig(plain(lagrangian))),
        friction=np.asarray(friction, dtype=float),
        mass_matrix_expr=sp.simplify(plain(method.mass_matrix)),
        forcing_symbolic=plain(method.forcing),
        friction_symbols=friction_symbols,
        energy_expr=sp.expand(sp.expand_trig(plain(energy))),
        force_amplitude=np.asarray(force_amplitude, dtype=float),
    )


def _particle(label: str, point: me.Point, mass: float, frame, origin) -> me.Particle:
    particle = me.Particle(label, point, mass)
    particle.potential_energy = mass * G * point.pos_from(origin).dot(frame.y)
    return particle


def _link(frame, angle, label: str) -> me.ReferenceFrame:
    """A body frame rotated by the absolute ``angle`` about z; ``-link.y`` hangs down at 0."""
    return frame.orientnew(label, "Axis", [angle, frame.z])


def _attach(label: str, base: me.Point, link: me.ReferenceFrame, length: float, frame):
    point = base.locatenew(label, -length * link.y)
    point.set_vel(frame, point.pos_from(base).dt(frame) + base.vel(frame))
    return point


def _check_positive(**values):
    for key, value in values.items():
        if not np.isfinite(value) or value <= 0:
            raise ValueError(f"{key}: expected a positive finite number, got {value!r}")


def _check_friction(friction, n: int) -> np.ndarray:
    friction = np.asarray(friction, dtype=float)
    if friction.shape != (n,) or not np.all(np.isfinite(friction)) or np.any(friction < 0):
        raise ValueError(f"friction: expected {n} non-negative finite values, got {friction!r}")
    return friction


def cart_pole(
    m_cart: float = 1.0, m_pole: float = 0.5, length: float = 1.0, friction=(0.3, 0.1)
) -> TrueSystem:
    """Cart on a horizontal rail with a pendulum (point mass at the tip), coordinates x, theta.

    ``theta = 0``: pendulum hanging down. Tip at ``(x + l sin(theta), -l cos(theta))``.

    Parameters
    ----------
    m_cart, m_pole, length : float
    friction : sequence of 2 float
        Viscous coefficients on x and theta.

    Returns
    -------
    TrueSystem
    """
    _check_positive(m_cart=m_cart, m_pole=m_pole, length=length)
    friction = _check_friction(friction, 2)

    def build(q, qd, frame, origin):
        x, theta = q
        cart = origin.locatenew("C", x * frame.x)
        cart.set_vel(frame, qd[0] * frame.x)
        pole = _link(frame, theta, "A")
        tip = _attach("P", cart, pole, length, frame)
        particles = [
            _particle("cart", cart, m_cart, frame, origin),
            _particle("tip", tip, m_pole, frame, origin),
        ]
        return particles, [(cart, frame.x), (pole, frame.z)]

    # Peak forces: a few tenths of g on the cart, about half the pole's gravity torque.
    return _derive("cart_pole", Coordinates(["x", "theta"]), build, friction, [3.0, 3.0])


def double_pendulum(
    m1: float = 1.0, m2: float = 1.0, l1: float = 1.0, l2: float = 1.0, friction=(0.2, 0.15)
) -> TrueSystem:
    """Planar double pendulum of point masses, absolute angles theta1, theta2 from the vertical.

    Parameters
    ----------
    m1, m2, l1, l2 : float
    friction : sequence of 2 float

    Returns
    -------
    TrueSystem
    """
    _check_positive(m1=m1, m2=m2, l1=l1, l2=l2)
    friction = _check_friction(friction, 2)

    def build(q, qd, frame, origin):
        link1, link2 = _link(frame, q[0], "A"), _link(frame, q[1], "B")
        p1 = _attach("P1", origin, link1, l1, frame)
        p2 = _attach("P2", p1, link2, l2, frame)
        particles = [
            _particle("bob1", p1, m1, frame, origin),
            _particle("bob2", p2, m2, frame, origin),
        ]
        return particles, [(link1, frame.z), (link2, frame.z)]

    return _derive(
        "double_pendulum", Coordinates(["theta1", "theta2"]), build, friction, [10.0, 5.0]
    )


def triple_pendulum(
    m1: float = 1.0,
    m2: float = 1.0,
    m3: float = 1.0,
    l1: float = 1.0,
    l2: float = 1.0,
    l3: float = 1.0,
    friction=(0.2, 0.15, 0.1),
) -> TrueSystem:
    """Planar three-link pendulum of point masses (chaotic), absolute angles theta1..theta3.

    Parameters
    ----------
    m1, m2, m3, l1, l2, l3 : float
    friction : sequence of 3 float

    Returns
    -------
    TrueSystem
    """
    _check_positive(m1=m1, m2=m2, m3=m3, l1=l1, l2=l2, l3=l3)
    friction = _check_friction(friction, 3)

    def build(q, qd, frame, origin):
        links = [_link(frame, q[k], label) for k, label in enumerate("ABC")]
        p1 = _attach("P1", origin, links[0], l1, frame)
        p2 = _attach("P2", p1, links[1], l2, frame)
        p3 = _attach("P3", p2, links[2], l3, frame)
        particles = [
            _particle("bob1", p1, m1, frame, origin),
            _particle("bob2", p2, m2, frame, origin),
            _particle("bob3", p3, m3, frame, origin),
        ]
        return particles, [(link, frame.z) for link in links]

    return _derive(
        "triple_pendulum",
        Coordinates(["theta1", "theta2", "theta3"]),
        build,
        friction,
        [15.0, 8.0, 3.0],
    )


def cart_double_pendulum(
    m_cart: float = 1.0,
    m1: float = 0.5,
    m2: float = 0.5,
    l1: float = 1.0,
    l2: float = 1.0,
    friction=(0.3, 0.1, 0.1),
) -> TrueSystem:
    """Cart carrying a double pendulum of point masses; coordinates x, theta1, theta2.

    Parameters
    ----------
    m_cart, m1, m2, l1, l2 : float
    friction : sequence of 3 float

    Returns
    -------
    TrueSystem
    """
    _check_positive(m_cart=m_cart, m1=m1, m2=m2, l1=l1, l2=l2)
    friction = _check_friction(friction, 3)

    def build(q, qd, frame, origin):
        cart = origin.locatenew("C", q[0] * frame.x)
        cart.set_vel(frame, qd[0] * frame.x)
        link1, link2 = _link(frame, q[1], "A"), _link(frame, q[2], "B")
        p1 = _attach("P1", cart, link1, l1, frame)
        p2 = _attach("P2", p1, link2, l2, frame)
        particles = [
            _particle("cart", cart, m_cart, frame, origin),
            _particle("bob1", p1, m1, frame, origin),
            _particle("bob2", p2, m2, frame, origin),
        ]
        return particles, [(cart, frame.x), (link1, frame.z), (link2, frame.z)]

    return _derive(
        "cart_double_pendulum",
        Coordinates(["x", "theta1", "theta2"]),
        build,
        friction,
        [4.0, 4.0, 2.0],
    )


# --------------------------------------------------------------------------------------------
# Excitation and initial states
# --------------------------------------------------------------------------------------------


def sum_of_sines(
    n: int,
    active,
    seed: int,
    amplitude=1.0,
    n_components: int = 6,
    f_min: float = 0.1,
    f_max: float = 1.5,
) -> Callable:
    """A random, reproducible sum of sinusoids on the active coordinates, zero elsewhere.

    Coordinate i receives ``amplitude_i * sum_k w_k sin(2 pi f_k t + phi_k)`` with frequencies
    ``f_k`` uniform in ``[f_min, f_max]`` Hz, phases uniform, weights ``w_k > 0`` summing to one,
    so ``|u_i(t)| <= amplitude_i``.

    Parameters
    ----------
    n : int
        Number of coordinates.
    active : sequence of int or boolean mask of length n
        Coordinates that are forced.
    seed : int
    amplitude : float or array_like of shape (n,)
        Peak force per coordinate.
    n_components : int
    f_min, f_max : float
        Frequency band in Hz.

    Returns
    -------
    callable
        ``u(t)``: scalar t -> array (n,); array of times (N,) -> array (N, n).

    Examples
    --------
    >>> u = sum_of_sines(2, [0], seed=0, amplitude=2.0)
    >>> u(0.3).shape, u(np.linspace(0, 1, 5)).shape, float(u(0.3)[1])
    ((2,), (5, 2), 0.0)
    """
    if not isinstance(n, int) or n < 1:
        raise ValueError(f"n: expected a positive integer, got {n!r}")
    mask = np.zeros(n, dtype=bool)
    active = np.asarray(active)
    if active.dtype == bool:
        if active.shape != (n,):
            raise ValueError(f"active: boolean mask must have length {n}, got {active.shape}")
        mask = active.copy()
    else:
        indices = active.astype(int).ravel()
        if np.any((indices < 0) | (indices >= n)):
            raise ValueError(f"active: indices must be in [0, {n}), got {indices.tolist()}")
        mask[indices] = True
    amplitude = np.broadcast_to(np.asarray(amplitude, dtype=float), (n,)).copy()
    if not np.all(np.isfinite(amplitude)) or np.any(amplitude < 0):
        raise ValueError(f"amplitude: expected non-negative finite values, got {amplitude!r}")
    if not isinstance(n_components, int) or n_components < 1:
        raise ValueError(f"n_components: expected a positive integer, got {n_components!r}")
    if not 0 < f_min <= f_max:
        raise ValueError(f"f_min, f_max: expected 0 < f_min <= f_max, got {f_min}, {f_max}")

    rng = np.random.default_rng(seed)
    omega = 2 * np.pi * rng.uniform(f_min, f_max, size=(n_components, n))
    phase = rng.uniform(0, 2 * np.pi, size=(n_components, n))
    weight = rng.uniform(0.5, 1.0, size=(n_components, n))
    weight *= (amplitude * mask) / weight.sum(axis=0)

    def force(t):
        times = np.asarray(t, dtype=float)
        values = np.sum(weight * np.sin(omega * times[..., None, None] + phase), axis=-2)
        return values

    return force


def random_force(system: TrueSystem, seed: int, active=None, **kwargs) -> Callable:
    """:func:`sum_of_sines` with the system's ``force_amplitude`` (all coordinates by default).

    Parameters
    ----------
    system : TrueSystem
    seed : int
    active : sequence of int or boolean mask, optional
        Forced coordinates; default all.
    **kwargs
        Passed to :func:`sum_of_sines` (``n_components``, ``f_min``, ``f_max``, ``amplitude``).

    Returns
    -------
    callable
    """
    active = np.arange(system.n) if active is None else active
    kwargs.setdefault("amplitude", system.force_amplitude)
    return sum_of_sines(system.n, active, seed, **kwargs)


def random_initial_state(system: TrueSystem, seed: int) -> np.ndarray:
    """A reproducible initial state ``[q, qd]`` of shape (2n,).

    Angles uniform in ``[-1.5, 1.5]`` rad, angular rates in ``[-1.5, 1.5]`` rad/s, cart position
    in ``[-0.5, 0.5]`` m and cart velocity in ``[-0.3, 0.3]`` m/s (coordinate named ``x``).

    Parameters
    ----------
    system : TrueSystem
    seed : int

    Returns
    -------
    numpy.ndarray of shape (2n,)
    """
    rng = np.random.default_rng(seed)
    is_cart = np.array([name == "x" for name in system.coords.names])
    q = np.where(is_cart, rng.uniform(-0.5, 0.5, system.n), rng.uniform(-1.5, 1.5, system.n))
    qd = np.where(is_cart, rng.uniform(-0.3, 0.3, system.n), rng.uniform(-1.5, 1.5, system.n))
    return np.concatenate([q, qd])
