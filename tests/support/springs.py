"""A mass hanging on a spring under gravity, ``m xdd = m g - k x - c xd``, integrated by scipy
at 1e-10: free runs for the tests of unforced fits and of the honest exit."""

import numpy as np
from scipy.integrate import solve_ivp

#: Mass, stiffness, gravity and damping of the hanging spring (at rest at ``x = 2.45``).
MASS, STIFFNESS, G, DAMPING = 1.0, 4.0, 9.81, 0.1


def hanging_spring_acceleration(x, xd):
    """The true acceleration ``g - (k x + c xd) / m``."""
    return G - (STIFFNESS * x + DAMPING * xd) / MASS


def hanging_spring(duration=10.0, rate=200.0, starts=((2.0, 0.3), (2.9, -0.4))):
    """Free runs of the hanging spring sampled at ``rate`` Hz, one per initial state.

    Returns
    -------
    t : ndarray, shape (N,)
    x, xd, xdd : list of ndarray, shape (N, 1)
        Positions, velocities and accelerations of each run.
    """
    t = np.arange(0.0, duration, 1.0 / rate)
    x, xd, xdd = [], [], []
    for y0 in starts:
        y = solve_ivp(lambda _, s: [s[1], hanging_spring_acceleration(*s)], (0, t[-1]), y0,
                      t_eval=t, method="DOP853", rtol=1e-10, atol=1e-10).y
        x.append(y[0][:, None])
        xd.append(y[1][:, None])
        xdd.append(hanging_spring_acceleration(*y)[:, None])
    return t, x, xd, xdd
