"""
Double pendulum on a cart, force on the cart only: mixed identification
=======================================================================

Robots are rarely actuated on every joint. Here a motor pushes the cart of a double pendulum
on a cart, and the two pendulum joints are free. The known force only anchors the scale of the
terms that it "activates" (the equation of the cart, and every term coupled to it); the rest of
the dynamics has no known right-hand side. :class:`~pysindy_xl.MixedOptimizer` solves the
explicit regression on the force-activated part of the catalog and the implicit one on the
rest, so one model covers both. Viscous friction on every joint is part of the catalog
(classical terms).
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
# Cart of mass ``M = 1``, point masses ``m1 = m2 = 0.5`` on links ``l1 = 1``, ``l2 = 0.8``,
# absolute angles from the downward vertical, viscous friction ``c`` on each joint.
M, m1, m2, l1, l2, g = 1.0, 0.5, 0.5, 1.0, 0.8, 9.81
c = np.array([0.2, 0.05, 0.05])


def cart_force(t):
    return 3.0 * np.sin(1.3 * t) + 2.0 * np.sin(3.1 * t + 0.5) + 1.0 * np.sin(5.3 * t + 1.0)


def true_rhs(t, s):
    x, th1, th2, xd, w1, w2 = s
    c1, s1, c2, s2 = np.cos(th1), np.sin(th1), np.cos(th2), np.sin(th2)
    c12, s12 = np.cos(th1 - th2), np.sin(th1 - th2)
    mass = np.array([
        [M + m1 + m2, (m1 + m2) * l1 * c1, m2 * l2 * c2],
        [(m1 + m2) * l1 * c1, (m1 + m2) * l1**2, m2 * l1 * l2 * c12],
        [m2 * l2 * c2, m2 * l1 * l2 * c12, m2 * l2**2],
    ])
    rhs = np.array([
        cart_force(t) + (m1 + m2) * l1 * s1 * w1**2 + m2 * l2 * s2 * w2**2,
        -m2 * l1 * l2 * s12 * w2**2 - (m1 + m2) * g * l1 * s1,
        m2 * l1 * l2 * s12 * w1**2 - m2 * g * l2 * s2,
    ]) - c * s[3:]
    return np.concatenate([s[3:], np.linalg.solve(mass, rhs)])


def simulate_truth(x0, t):
    return solve_ivp(true_rhs, (t[0], t[-1]), x0, t_eval=t, rtol=1e-10, atol=1e-10).y.T


t = np.arange(0, 12, 0.005)
states = simulate_truth([0.0, 0.4, -0.3, 0.0, 0.0, 0.0], t)
q = states[:, :3]
# Generalized forces, one column per coordinate: only the cart is driven.
u = np.column_stack([cart_force(t), np.zeros_like(t), np.zeros_like(t)])

# %%
# Catalog
# -------
# Lagrange: trigonometric monomials of the two angles times velocity monomials. Classical:
# viscous friction on each coordinate. The force column is added by ``CatalogRepartition``.
coords = px.Coordinates(["x", "theta1", "theta2"])
_, th1, th2 = coords.q
trig = px.monomials([sp.sin(th1), sp.cos(th1), sp.sin(th2), sp.cos(th2)], 2)
terms = [t for t in px.products([1, *trig], [1, *px.monomials(coords.qd, 2)]) if t.free_symbols]
catalog = px.CatalogRepartition([
    px.ExternalForces(coords),
    px.LagrangeLibrary(coords, terms),
    px.ClassicalLibrary(coords, coords.qd, mask=np.eye(3, dtype=bool)),
])
print(f"{len(terms)} Lagrangian terms + 3 friction terms")

# %%
# Mixed identification
# --------------------
# ``u`` has zero columns for the pendulum joints: the model sees which coordinates are
# forced (``model.forced_coordinates_``). Two settings matter here:
#
# * the friction of the pendulum joints is a small force next to the cart's inertia and
#   motor force, so the explicit part prunes terms below 0.3 % (instead of 1 %) of the
#   largest contribution;
# * fourth-order finite differences give accurate accelerations on these clean samples.
model = px.XLSINDy(
    catalog,
    px.MixedOptimizer(explicit_optimizer=px.ExplicitOptimizer(threshold=3e-3)),
    differentiation_method=ps.FiniteDifference(order=4),
)
model.fit(q, t, u=u)
print("forced coordinates:", model.forced_coordinates_)
model.print()

# %%
# Which part was explicit? The force on the cart reaches both pendulum equations through the
# coupling terms (``x_dot * theta1_dot * cos(theta1)``...), so every coordinate is
# *activated* and the force fixes the scale of the whole Lagrangian: here the mixed solver
# reduces to explicit regression. A subsystem that no force reaches (``mode_ == "mixed"``)
# would be identified implicitly, up to a factor.
optimizer = model.optimizer_
print("mode:", optimizer.mode_)
print("activated coordinates:", optimizer.activated_coordinates_)

# %%
# Check a few coefficients against the truth: the cart's kinetic term ``(M + m1 + m2) / 2``,
# the gravity terms ``(m1 + m2) g l1 cos th1`` and ``m2 g l2 cos th2`` and the frictions.
names = model.get_feature_names()
coef = model.coefficients()
expected = {
    "L[x_dot**2]": (M + m1 + m2) / 2,
    "L[cos(theta1)]": (m1 + m2) * g * l1,
    "L[cos(theta2)]": m2 * g * l2,
    "C_x[x_dot]": c[0],
    "C_theta1[theta1_dot]": c[1],
    "C_theta2[theta2_dot]": c[2],
}
for name, value in expected.items():
    print(f"{name:>22}: identified {coef[names.index(name)]:8.4f}   true {value:8.4f}")

# %%
# Validation with a new force signal and initial state
# ----------------------------------------------------
t_val = np.arange(0, 6, 0.01)
x0 = [0.1, -0.5, 0.6, 0.0, 0.3, 0.0]
truth = simulate_truth(x0, t_val)
prediction = model.simulate(x0, t_val, u=lambda s: np.array([cart_force(s), 0.0, 0.0]))
rmse = np.sqrt(np.mean((prediction[:, :3] - truth[:, :3]) ** 2, axis=0))
for name, value in zip(coords.names, rmse, strict=True):
    print(f"validation RMSE of {name} over 6 s: {value:.2e}")

fig, axes = plt.subplots(3, 1, figsize=(8, 6), sharex=True)
for k, (ax, name) in enumerate(zip(axes, coords.names, strict=True)):
    ax.plot(t_val, truth[:, k], "k--", lw=1, label="truth")
    ax.plot(t_val, prediction[:, k], label="identified")
    ax.set_ylabel(name)
axes[0].legend(loc="upper right")
axes[-1].set_xlabel("t [s]")
fig.suptitle("Double pendulum on a cart, force on the cart only")
fig.tight_layout()

# %%
# The coefficient vector: a handful of active terms among the catalog.
fig, ax = plt.subplots(figsize=(8, 3))
active = np.flatnonzero(coef)
ax.bar(range(len(coef)), np.abs(coef), color="C0")
ax.set_yscale("log")
ax.set(xlabel="catalog feature", ylabel="|coefficient|",
       title=f"{len(active)} active terms out of {len(coef)}")
fig.tight_layout()
