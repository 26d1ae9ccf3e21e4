"""
Forced cart-pole: explicit identification
=========================================

A cart-pole with viscous friction is driven by random forces on both coordinates. Its
Lagrangian and friction are identified from positions only with a paper-style catalog:
velocity monomials times trigonometric monomials (Lagrange) plus viscous friction (classical).
"""

import matplotlib.pyplot as plt
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

import pysindy_xl as px

# %%
# Ground truth: cart (mass 1) and a point-mass pole (mass 0.5, length 1), friction on both.
M, m, l, g, c = 1.0, 0.5, 1.0, 9.81, np.array([0.3, 0.1])


def force(t):
    return np.array([2.0 * np.sin(1.1 * t) + np.sin(2.9 * t), 1.5 * np.sin(1.7 * t + 1.0)])


def true_rhs(t, s):
    x, th, xd, thd = s
    mass = np.array([[M + m, m * l * np.cos(th)], [m * l * np.cos(th), m * l**2]])
    rhs = force(t) - c * s[2:] + np.array([m * l * thd**2 * np.sin(th), -m * g * l * np.sin(th)])
    return np.concatenate([s[2:], np.linalg.solve(mass, rhs)])


t = np.arange(0, 20, 0.005)
sol = solve_ivp(true_rhs, (t[0], t[-1]), [0.0, 0.5, 0.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-10)
q = sol.y[:2].T
u = np.array([force(s) for s in t])

# %%
# The catalog: 35 candidate Lagrangian terms and 2 friction terms.
coords = px.Coordinates(["x", "theta"])
trig = [sp.sin(coords.q[1]), sp.cos(coords.q[1])]
terms = [
    term
    for term in px.products([1, *px.monomials(trig, 2)], [1, *px.monomials(coords.qd, 2)])
    if term.free_symbols
]
catalog = px.CatalogRepartition([
    px.ExternalForces(coords),
    px.LagrangeLibrary(coords, terms),
    px.ClassicalLibrary(coords, coords.qd, mask=np.eye(2, dtype=bool)),
])

# %%
# Identify from positions only (velocities and accelerations are differentiated).
model = px.XLSINDy(catalog, px.ExplicitOptimizer())
model.fit(q, t, u=u)
model.print()

# %%
# Validate on a fresh initial condition.
t_val = np.arange(0, 10, 0.01)
x0 = [0.2, -1.0, 0.0, 0.5]
truth = solve_ivp(true_rhs, (0, 10), x0, t_eval=t_val, rtol=1e-10, atol=1e-10).y.T
pred = model.simulate(x0, t_val, u=force)
rmse = np.sqrt(np.mean((pred[:, :2] - truth[:, :2]) ** 2))
print(f"validation position RMSE over 10 s: {rmse:.2e}")

# %%
# Identified model against the truth on the validation run.
fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 4.5))
for k, name in enumerate(coords.names):
    axes[k].plot(t_val, truth[:, k], "k--", lw=1, label="truth")
    axes[k].plot(t_val, pred[:, k], lw=1, label="identified")
    axes[k].set_ylabel(name)
axes[0].legend(loc="upper right")
axes[-1].set_xlabel("t [s]")
fig.tight_layout()
