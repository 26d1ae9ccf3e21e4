"""Reference systems of the automatic catalog's tests: a forced Duffing oscillator integrated by
scipy, and the equations of motion of a one-coordinate ``sympy.physics.mechanics`` model as
numeric callables."""

import warnings

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

#: The Duffing oscillator ``MASS xdd + DAMPING xd + STIFFNESS x + HARDENING x^3 = tau``.
MASS, STIFFNESS, HARDENING, DAMPING = 1.5, 2.0, 1.0, 0.1


def noisy_duffing(noise: float = 0.01, seed: int = 0):
    """8 s of the forced Duffing oscillator at 500 Hz (scipy, 1e-10 tolerances), positions with
    Gaussian noise of ``noise`` times their standard deviation.

    Returns
    -------
    x : ndarray, shape (4000, 1)
    t : ndarray, shape (4000,)
    u : ndarray, shape (4000, 1)
        The applied force.
    """
    t = np.arange(0.0, 8.0, 2e-3)

    def force(s):
        return 2.0 * np.sin(1.3 * s) + 1.0 * np.sin(2.9 * s + 1.0)

    def rhs(s, y):
        return [y[1], (force(s) - DAMPING * y[1] - STIFFNESS * y[0] - HARDENING * y[0] ** 3)
                / MASS]

    y = solve_ivp(rhs, (0, t[-1]), [0.5, 0.0], t_eval=t, rtol=1e-10, atol=1e-10).y
    rng = np.random.default_rng(seed)
    x = y[0] + noise * np.std(y[0]) * rng.normal(size=len(t))
    return x[:, None], t, force(t)[:, None]


def scalar_laws(method, q, qd, tau):
    """The numeric laws of a one-coordinate ``LagrangesMethod`` (equations formed) whose
    generalized force is ``tau``.

    Returns
    -------
    accelerations : callable
        ``accelerations(q, qd, tau)``: ``qdd``.
    forces : callable
        ``forces(q, qd, qdd)``: the ``tau`` that gives ``qdd`` (``M qdd - forcing(tau=0)``).
    """
    mass = sp.lambdify((q, qd, tau), method.mass_matrix[0, 0])
    forcing = sp.lambdify((q, qd, tau), method.forcing[0])

    def accelerations(qv, qdv, tv):
        return forcing(qv, qdv, tv) / mass(qv, qdv, tv)

    def forces(qv, qdv, qddv):
        return mass(qv, qdv, 0.0) * qddv - forcing(qv, qdv, 0.0)

    return accelerations, forces


#: A pendulum on a torsion spring: ``INERTIA_T theta_dd + DAMPING_T theta_dot + WEIGHT sin(theta)
#: + TORSION theta = tau`` (``L = INERTIA_T theta_dot^2 / 2 + WEIGHT cos(theta) - TORSION
#: theta^2 / 2``).
INERTIA_T, WEIGHT, TORSION, DAMPING_T = 0.32, 3.924, 3.0, 0.05


def torsion_pendulum():
    """The pendulum on a torsion spring by ``LagrangesMethod``: a point mass ``WEIGHT / g`` at
    1 m from the pivot, whose rod's own inertia makes up ``INERTIA_T``, with a torque.

    Returns
    -------
    accelerations, forces : callable
        As :func:`scalar_laws`.
    """
    from sympy.physics import mechanics as me
    q = me.dynamicsymbols("q")
    qd = me.dynamicsymbols("q", 1)
    tau = sp.Symbol("tau")
    g = 9.81
    frame = me.ReferenceFrame("N")
    rod = frame.orientnew("A", "Axis", (q, frame.z))
    pivot = me.Point("O")
    pivot.set_vel(frame, 0)
    bob = pivot.locatenew("P", -1.0 * rod.y)
    bob.v2pt_theory(pivot, frame, rod)
    mass = WEIGHT / g
    particle = me.Particle("bob", bob, mass)
    particle.potential_energy = -WEIGHT * sp.cos(q) + TORSION * q ** 2 / 2
    body = me.RigidBody("rod", pivot, rod, 0.0,
                        (me.inertia(rod, 0, 0, INERTIA_T - mass), pivot))
    method = me.LagrangesMethod(me.Lagrangian(frame, particle, body), [q],
                                forcelist=[(rod, (tau - DAMPING_T * qd) * frame.z)], frame=frame)
    method.form_lagranges_equations()
    return scalar_laws(method, q, qd, tau)


#: A rigid rotor on a quartic torsion spring: ``ROTOR_INERTIA q_dd + ROTOR_DAMPING q_dot + K2 q
#: + K4 q^3 = tau`` (``L = ROTOR_INERTIA q_dot^2 / 2 - K2 q^2 / 2 - K4 q^4 / 4``).
ROTOR_INERTIA, K2, K4, ROTOR_DAMPING = 0.2, 2.0, 2.0, 0.05


def quartic_rotor():
    """The rotor on a quartic torsion spring by ``LagrangesMethod``, with viscous damping and a
    torque.

    Returns
    -------
    accelerations, forces : callable
        As :func:`scalar_laws`.
    """
    from sympy.physics import mechanics as me
    q = me.dynamicsymbols("q")
    qd = me.dynamicsymbols("q", 1)
    tau = sp.Symbol("tau")
    frame = me.ReferenceFrame("N")
    rotor = frame.orientnew("A", "Axis", (q, frame.z))
    pivot = me.Point("O")
    pivot.set_vel(frame, 0)
    body = me.RigidBody("rotor", pivot, rotor, 1.0,
                        (me.inertia(rotor, 0, 0, ROTOR_INERTIA), pivot))
    body.potential_energy = K2 * q ** 2 / 2 + K4 * q ** 4 / 4
    method = me.LagrangesMethod(me.Lagrangian(frame, body), [q],
                                forcelist=[(rotor, (tau - ROTOR_DAMPING * qd) * frame.z)],
                                frame=frame)
    method.form_lagranges_equations()
    return scalar_laws(method, q, qd, tau)


def forced_runs(accelerations, seed: int, noise: float, n_runs: int = 2, duration: float = 10.0,
                rate: float = 200.0, amplitude: float = 2.0, frequencies=(0.1, 1.0)):
    """Runs of a one-coordinate law driven by sums of five sines (scipy DOP853, 1e-10
    tolerances), positions with Gaussian noise of ``noise`` times their standard deviation.

    Returns
    -------
    ts, xs, us : list of ndarray
        Times (N,), noisy positions (N, 1) and torques (N, 1) of each run.
    """
    from scipy.integrate import solve_ivp
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1.0 / rate)
    ts, xs, us = [], [], []
    for _ in range(n_runs):
        f, phase = rng.uniform(*frequencies, 5), rng.uniform(0, 2 * np.pi, 5)

        def torque(time, f=f, phase=phase):
            return amplitude * np.sin(2 * np.pi * f * time + phase).sum() / 2.5

        y0 = [rng.uniform(-1, 1), rng.uniform(-0.5, 0.5)]
        solution = solve_ivp(lambda time, y: [y[1], accelerations(y[0], y[1], torque(time))],
                             (t[0], t[-1]), y0, t_eval=t, method="DOP853", rtol=1e-10,
                             atol=1e-10)
        x = solution.y[0][:, None]
        xs.append(x + noise * x.std() * rng.normal(size=x.shape))
        ts.append(t)
        us.append(np.array([[torque(time)] for time in t]))
    return ts, xs, us


def wide_force_error(found, forces):
    """Relative force error of a grown model (``found``: a ``GrowthResult``) against the
    one-angle law ``forces(q, qd, qdd)`` on angles to 2.5 rad, wider than the recordings of
    :func:`forced_runs` on :func:`torsion_pendulum` (within 1.6 rad)."""
    q = np.linspace(-2.5, 2.5, 51)[:, None]
    qd, qdd = np.full_like(q, 0.5), np.full_like(q, 1.0)
    true = forces(q, qd, qdd)
    return float(np.linalg.norm(found.model.predict_forces(q, qd, qdd) - true)
                 / np.linalg.norm(true))


#: A unit mass in the well ``V = WELL_DEPTH log cosh(WELL_RATE x)`` with viscous damping:
#: ``x_dd + WELL_DAMPING x_dot + WELL_DEPTH WELL_RATE tanh(WELL_RATE x) = tau`` (no polynomial
#: or trigonometric family states ``log cosh``: the flexible basis's system).
WELL_DEPTH, WELL_RATE, WELL_DAMPING = 2.0, 2.0, 0.1


def log_cosh_well():
    """The log-cosh well by ``LagrangesMethod``: a particle of unit mass on a line, with
    viscous damping and a force.

    Returns
    -------
    accelerations, forces : callable
        As :func:`scalar_laws`.
    """
    from sympy.physics import mechanics as me
    q = me.dynamicsymbols("q")
    qd = me.dynamicsymbols("q", 1)
    tau = sp.Symbol("tau")
    frame = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(frame, 0)
    point = origin.locatenew("P", q * frame.x)
    point.set_vel(frame, qd * frame.x)
    particle = me.Particle("particle", point, 1.0)
    particle.potential_energy = WELL_DEPTH * sp.log(sp.cosh(WELL_RATE * q))
    method = me.LagrangesMethod(me.Lagrangian(frame, particle), [q],
                                forcelist=[(point, (tau - WELL_DAMPING * qd) * frame.x)],
                                frame=frame)
    method.form_lagranges_equations()
    return scalar_laws(method, q, qd, tau)


#: Two carts on springs, coupled by a third: ``L = CART_MASSES . x_dot^2 / 2 - CART_SPRINGS[0]
#: x1^2 / 2 - CART_SPRINGS[1] x2^2 / 2 - COUPLING (x1 - x2)^2 / 2``, viscous damping
#: ``CART_DAMPING`` on each.
CART_MASSES, CART_SPRINGS, COUPLING, CART_DAMPING = (1.0, 1.5), (2.0, 3.0), 1.6, 0.1


def coupled_carts():
    """Two carts on springs coupled by a spring, by ``LagrangesMethod``, unforced.

    Returns
    -------
    accelerations : callable
        ``accelerations(q, qd)`` of arrays (N, 2): ``qdd`` (N, 2), from sympy's mass matrix and
        forcing.
    """
    from sympy.physics import mechanics as me
    q = me.dynamicsymbols("x1 x2")
    qd = [me.dynamicsymbols(f"x{i + 1}", 1) for i in range(2)]
    frame = me.ReferenceFrame("N")
    origin = me.Point("O")
    origin.set_vel(frame, 0)
    carts = []
    for i, mass in enumerate(CART_MASSES):
        point = origin.locatenew(f"P{i}", q[i] * frame.x)
        point.set_vel(frame, qd[i] * frame.x)
        carts.append(me.Particle(f"cart{i}", point, mass))
    carts[0].potential_energy = CART_SPRINGS[0] * q[0] ** 2 / 2 + COUPLING * (q[0] - q[1]) ** 2 / 2
    carts[1].potential_energy = CART_SPRINGS[1] * q[1] ** 2 / 2
    method = me.LagrangesMethod(me.Lagrangian(frame, *carts), q, forcelist=[
        (cart.point, -CART_DAMPING * qd[i] * frame.x) for i, cart in enumerate(carts)],
        frame=frame)
    method.form_lagranges_equations()
    states = list(q) + list(qd)
    mass = sp.lambdify(states, method.mass_matrix)
    forcing = sp.lambdify(states, method.forcing)

    def accelerations(qv, qdv):
        qv, qdv = np.atleast_2d(qv), np.atleast_2d(qdv)
        return np.array([np.linalg.solve(np.asarray(mass(*a, *b), float),
                                         np.asarray(forcing(*a, *b), float).ravel())
                         for a, b in zip(qv, qdv, strict=True)])

    return accelerations


def damped_forced_runs(restoring, amplitude: float, initial, damping: float = 0.1):
    """Two noise-free runs of ``x'' = u + restoring(x) - damping x'`` (unit mass) driven by
    sums of five sines of amplitude ``amplitude / 2.5`` each, by scipy's DOP853 at 1e-10, at
    200 Hz for 10 s.

    Parameters
    ----------
    restoring : callable
        ``restoring(x) -> force`` of the potential, vectorized.
    amplitude : float
        Scale of the forcing.
    initial : callable
        ``initial(rng, seed) -> x0`` (after the forcing's frequencies and phases are drawn).
    damping : float, default 0.1

    Returns
    -------
    t, xs, dxs, ddxs, us
        Times (N,) and, per run, positions, velocities, accelerations and forces (N, 1).
    """
    from scipy.integrate import solve_ivp

    def force(time, frequencies, phases):
        return amplitude * np.sin(2 * np.pi * frequencies * time + phases).sum() / 2.5

    t = np.arange(0.0, 10.0, 0.005)
    xs, dxs, ddxs, us = [], [], [], []
    for seed in (0, 1):
        rng = np.random.default_rng(seed)
        frequencies, phases = rng.uniform(0.1, 1.0, 5), rng.uniform(0, 2 * np.pi, 5)

        def rhs(time, y, frequencies=frequencies, phases=phases):
            return [y[1], force(time, frequencies, phases) + restoring(y[0]) - damping * y[1]]

        solution = solve_ivp(rhs, (t[0], t[-1]), [initial(rng, seed), 0.0], t_eval=t,
                             method="DOP853", rtol=1e-10, atol=1e-10)
        x, v = solution.y
        u = np.array([force(time, frequencies, phases) for time in t])
        xs.append(x[:, None])
        dxs.append(v[:, None])
        ddxs.append((u + restoring(x) - damping * v)[:, None])
        us.append(u[:, None])
    return t, xs, dxs, ddxs, us


def quiet_growth(*args, **kwargs):
    """:func:`pysindy_xl.catalog.grow_catalog` with its warnings silenced."""
    from pysindy_xl.catalog import grow_catalog
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return grow_catalog(*args, **kwargs)
