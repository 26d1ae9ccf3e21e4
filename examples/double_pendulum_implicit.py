"""
Unforced double pendulum: implicit identification
=================================================

Without any applied force there is no known right-hand side to regress on: the equations of
motion are only known to satisfy ``Theta @ xi = 0``. :class:`~pysindy_xl.ImplicitOptimizer`
solves the SINDy-PI problem (every catalog column regressed on all the others), then finds the
law as a cluster of *homothetic* columns of the solution matrix: all the columns of the terms
that belong to the law point in the same direction.

This example identifies a frictionless double pendulum (point masses, absolute angles from the
downward vertical) from a few free swings, shows the solution matrix and the cluster, and
checks the identified model on a fresh initial condition.
"""

import matplotlib.pyplot as plt
import numpy as np
import pysindy as ps
import sympy as sp
from scipy.integrate import solve_ivp

import pysindy_xl as px

# %%
# Ground truth
# ------------
# Masses ``m1 = m2 = 1``, lengths ``l1 = 1``, ``l2 = 0.8``; the classical mass matrix and
# Coriolis / gravity terms, integrated with tight tolerances.
m1, m2, l1, l2, g = 1.0, 1.0, 1.0, 0.8, 9.81


def true_rhs(t, s):
    th1, th2, w1, w2 = s
    c, s12 = np.cos(th1 - th2), np.sin(th1 - th2)
    mass = np.array([[(m1 + m2) * l1**2, m2 * l1 * l2 * c], [m2 * l1 * l2 * c, m2 * l2**2]])
    rhs = np.array([
        -m2 * l1 * l2 * s12 * w2**2 - (m1 + m2) * g * l1 * np.sin(th1),
        m2 * l1 * l2 * s12 * w1**2 - m2 * g * l2 * np.sin(th2),
    ])
    return np.concatenate([s[2:], np.linalg.solve(mass, rhs)])


def swing(x0, duration, dt=0.01):
    t = np.arange(0, duration, dt)
    sol = solve_ivp(true_rhs, (0, t[-1]), x0, t_eval=t, rtol=1e-10, atol=1e-10)
    return t, sol.y.T


# Three free swings (no force: ``u`` is left out of ``fit``).
initial_states = [[1.2, -0.4, 0.0, 0.0], [-0.6, 1.5, 0.5, 0.0], [2.0, 2.2, 0.0, -1.0]]
swings = [swing(x0, 8.0) for x0 in initial_states]
t = [time for time, _ in swings]
q = [states[:, :2] for _, states in swings]

# %%
# Catalog
# -------
# Candidate Lagrangian terms: products of trigonometric monomials of both angles (degree 2)
# and velocity monomials (degree 2). ``cos(th1 - th2)`` of the true Lagrangian is
# ``cos th1 cos th2 + sin th1 sin th2``, so it is in the span of the catalog.
coords = px.Coordinates(["theta1", "theta2"])
th1, th2 = coords.q
trig = px.monomials([sp.sin(th1), sp.cos(th1), sp.sin(th2), sp.cos(th2)], 2)
terms = [t for t in px.products([1, *trig], [1, *px.monomials(coords.qd, 2)]) if t.free_symbols]
catalog = px.CatalogRepartition([px.LagrangeLibrary(coords, terms)])
print(f"{len(terms)} candidate Lagrangian terms")

# %%
# Implicit identification
# -----------------------
# Velocities and accelerations are computed from the positions with any pysindy
# differentiation method; an implicit law has no force to anchor it, so it needs accurate
# accelerations: fourth-order finite differences on these clean samples. Columns that are
# exact combinations of others (``sin^2 + cos^2 = 1`` times anything, total time
# derivatives) are dropped before the regression: ``model.dropped_features_`` lists them.
model = px.XLSINDy(catalog, px.ImplicitOptimizer(),
                   differentiation_method=ps.FiniteDifference(order=4))
model.fit(q, t)
print(f"{len(model.dropped_features_)} dependent columns dropped before the regression")
model.print()

# %%
# An implicit law is only defined up to a factor. Comparing ratios with the truth: the
# Lagrangian is ``0.5 (m1 + m2) l1^2 th1d^2 + 0.5 m2 l2^2 th2d^2 + m2 l1 l2 th1d th2d
# cos(th1 - th2) + (m1 + m2) g l1 cos th1 + m2 g l2 cos th2``.
lagrangian = sp.expand(model.lagrangian())
w1, w2 = coords.qd
scale = lagrangian.coeff(w1**2) / (0.5 * (m1 + m2) * l1**2)
truth = {
    "theta2_dot**2": (w2**2, 0.5 * m2 * l2**2),
    "cos(theta1)": (sp.cos(th1), (m1 + m2) * g * l1),
    "cos(theta2)": (sp.cos(th2), m2 * g * l2),
}
for name, (term, value) in truth.items():
    found = float(lagrangian.coeff(term).subs({w1: 0, w2: 0, th1: 0, th2: 0})) / float(scale)
    print(f"{name:>14}: identified {found:8.4f}   true {value:8.4f}")

# %%
# The solution matrix and its cluster
# -----------------------------------
# Column ``j`` of the SINDy-PI solution ``X`` expresses catalog column ``j`` with the others.
# For a column that belongs to the law, the direction ``e_j - X[:, j]`` is the law itself (up
# to scale), so those columns are *homothetic*. Below left: ``|X|`` on unit-norm columns
# (paper's Figure 2A). Right: each column's direction against the identified law; the
# cluster of the law sits at ``|cos| = 1`` with a small residual.
optimizer = model.optimizer_
names = model.get_feature_names()
kept = [j for j, name in enumerate(names) if name not in model.dropped_features_]
solution = optimizer.normalized_solution_matrix_
directions = np.eye(len(kept)) - solution
law = optimizer.coef_ * optimizer.column_norms_  # the law on unit-norm columns
cosine = np.abs(law @ directions) / (np.linalg.norm(law) * np.linalg.norm(directions, axis=0))
in_law = optimizer.coef_ != 0

fig, (ax_matrix, ax_cluster) = plt.subplots(1, 2, figsize=(11, 4.5))
image = ax_matrix.imshow(np.log10(np.abs(solution) + 1e-6), cmap="viridis", vmin=-6, vmax=0)
ax_matrix.set(title="SINDy-PI solution matrix, log10 |X|",
              xlabel="column j (red marks: terms of the law)", ylabel="row")
fig.colorbar(image, ax=ax_matrix, shrink=0.8)
ax_matrix.plot(np.flatnonzero(in_law), np.full(in_law.sum(), len(kept) + 0.5), "^",
               color="C3", clip_on=False)
residuals = optimizer.column_residuals_
ax_cluster.semilogx(residuals[~in_law], cosine[~in_law], "o", color="0.6", label="other terms")
ax_cluster.semilogx(residuals[in_law], cosine[in_law], "o", color="C3", label="terms of the law")
ax_cluster.set(xlabel="relative residual of the column's direction",
               ylabel="|cos| to the identified law", title="Homothetic cluster")
ax_cluster.legend(loc="lower left")
fig.tight_layout()

# %%
# Validation on a fresh swing
# ---------------------------
t_val = np.arange(0, 5, 0.01)
x0 = [0.9, 0.3, -0.5, 0.8]
truth_val = swing(x0, 5.0)[1]
prediction = model.simulate(x0, t_val)
error = np.sqrt(np.mean((prediction[:, :2] - truth_val[:, :2]) ** 2))
print(f"validation angle RMSE over 5 s: {error:.2e} rad")

fig, ax = plt.subplots(figsize=(8, 3.5))
for k, name in enumerate(coords.names):
    ax.plot(t_val, truth_val[:, k], "k--", lw=1)
    ax.plot(t_val, prediction[:, k], label=f"identified {name}")
ax.set(xlabel="t [s]", ylabel="angle [rad]", title="Identified model (solid) vs truth (dashed)")
ax.legend()
fig.tight_layout()
