"""Reference systems of the automatic catalog's tests: a forced Duffing oscillator integrated by
scipy, and the equations of motion of a one-coordinate ``sympy.physics.mechanics`` model as
numeric callables."""

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
