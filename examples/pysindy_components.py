"""
PySINDy optimizers, libraries and differentiation inside pysindy-xl
===================================================================

pysindy-xl is built on PySINDy, and PySINDy's building blocks plug into it:

* any PySINDy optimizer (``STLSQ``, ``SR3``, ``MIOSR``...) through
  ``ExplicitOptimizer(method=...)``;
* any PySINDy feature library whose feature names describe its features
  (``PolynomialLibrary``, ``FourierLibrary``...) as a *classical* (Newtonian) category through
  ``ClassicalLibrary(coords, library)``, evaluated on the state ``(q, qd)``;
* any PySINDy differentiation method through ``differentiation_method``.

The system is a forced Duffing oscillator with friction,
``x_ddot + c x_dot + k x + k3 x^3 = u``.
"""

import matplotlib.pyplot as plt
import numpy as np
import pysindy as ps
from scipy.integrate import solve_ivp

import pysindy_xl as px

c, k, k3 = 0.1, 2.0, 0.5


def force(t):
    return 1.5 * np.sin(0.9 * t) + 0.8 * np.sin(2.3 * t + 0.4)


def duffing(t, s):
    x, v = s
    return [v, force(t) - c * v - k * x - k3 * x**3]


t = np.arange(0, 30, 0.005)
x = solve_ivp(duffing, (0, t[-1]), [1.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-10).y[0]
q, u = x[:, None], force(t)[:, None]
coords = px.Coordinates(["x"])
position, velocity = coords.q[0], coords.qd[0]

# %%
# A PySINDy optimizer on a Lagrangian catalog
# -------------------------------------------
# ``STLSQ`` runs on unit-RMS columns and a unit-RMS target inside ``ExplicitOptimizer``, so
# its threshold is relative. The selected support is refit by least squares afterwards
# (``refit=True``), which removes the ridge shrinkage. Terms such as ``x * x_dot`` are total
# time derivatives with no dynamics: they are dropped before the regression.
lagrange = px.LagrangeLibrary(coords, px.monomials([position, velocity], 4))
friction = px.ClassicalLibrary(coords, [velocity])
model = px.XLSINDy(
    lagrange + friction,
    px.ExplicitOptimizer(method=ps.STLSQ(threshold=0.02, alpha=1e-6)),
    differentiation_method=ps.FiniteDifference(order=4),
)
model.fit(q, t, u=u)
model.print()
print("dropped before the regression:", sorted(model.dropped_features_))

# %%
# A PySINDy library as the classical category
# -------------------------------------------
# Keep only the kinetic term as a Lagrangian and let a cubic ``PolynomialLibrary`` in
# ``(x, x_dot)`` describe every other force, Newton style. Its features become symbolic terms
# (``x``, ``x_dot``, ``x**2``, ``x*x_dot``...), so the identified model prints, simulates and
# saves like any other.
polynomial = px.ClassicalLibrary(coords, ps.PolynomialLibrary(degree=3, include_bias=False))
hybrid = px.XLSINDy(
    px.LagrangeLibrary(coords, [velocity**2]) + polynomial,
    px.ExplicitOptimizer(method=ps.STLSQ(threshold=0.02, alpha=1e-6)),
    differentiation_method=ps.SmoothedFiniteDifference(),
)
hybrid.fit(q, t, u=u)
hybrid.print()

# %%
# Both models against a new excitation
# ------------------------------------
t_val = np.arange(0, 15, 0.01)


def new_force(s):
    return np.array([2.0 * np.cos(1.4 * s)])


truth = solve_ivp(lambda s, y: [y[1], new_force(s)[0] - c * y[1] - k * y[0] - k3 * y[0] ** 3],
                  (0, t_val[-1]), [-0.5, 0.5], t_eval=t_val, rtol=1e-10, atol=1e-10).y[0]
fig, ax = plt.subplots(figsize=(8, 3.5))
ax.plot(t_val, truth, "k--", lw=1, label="truth")
for label, fitted in (("Lagrangian catalog + STLSQ", model), ("PolynomialLibrary", hybrid)):
    trajectory = fitted.simulate([-0.5, 0.5], t_val, u=new_force)[:, 0]
    print(f"{label}: validation RMSE {np.sqrt(np.mean((trajectory - truth) ** 2)):.2e}")
    ax.plot(t_val, trajectory, label=label, alpha=0.8)
ax.set(xlabel="t [s]", ylabel="x")
ax.legend(loc="upper right")
fig.tight_layout()
