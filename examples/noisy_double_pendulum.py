"""
Double pendulum from noisy positions: weak form
===============================================

Real sensors record positions with noise; velocities and accelerations must be estimated. The
pointwise (strong) Euler-Lagrange columns need accelerations, and differentiating noisy
positions twice mostly amplifies the noise. The weak form integrates each equation against
smooth test functions and moves the time derivative onto them, so no acceleration is ever
estimated; the velocities it still needs come from a smoother tuned on the data, and the
sparsity is chosen by cross-validation, bagged over subsamples of the test functions. Here
the two formulations meet the same recording: a forced double pendulum with friction, 1 %
noise on the angles and nothing else.
"""

import matplotlib.pyplot as plt
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

import pysindy_xl as px

# %%
# Ground truth: point masses m1 = m2 = 1 on rods l1 = l2 = 1, absolute angles, viscous
# friction on each angle, sum-of-sines torques on both joints.
g, c = 9.81, np.array([0.2, 0.15])


def torque(t):
    return np.array([6 * np.sin(0.9 * t) + 3 * np.sin(2.3 * t + 1), 3 * np.sin(1.4 * t + 2)])


def true_rhs(t, s):
    a, b, ad, bd = s
    mass = np.array([[2.0, np.cos(a - b)], [np.cos(a - b), 1.0]])
    rhs = torque(t) - c * s[2:] + np.array([
        -np.sin(a - b) * bd**2 - 2 * g * np.sin(a),
        np.sin(a - b) * ad**2 - g * np.sin(b),
    ])
    return np.concatenate([s[2:], np.linalg.solve(mass, rhs)])


t = np.arange(0, 30, 0.01)
sol = solve_ivp(true_rhs, (t[0], t[-1]), [0.5, -0.3, 0, 0], t_eval=t, rtol=1e-10, atol=1e-10)
q_true = sol.y[:2].T
u = np.array([torque(s) for s in t])
rng = np.random.default_rng(0)
q_noisy = q_true + 0.01 * q_true.std(axis=0) * rng.normal(size=q_true.shape)

# %%
# A paper-style catalog: velocity monomials times trigonometric monomials of both angles
# (Lagrange) and viscous friction (classical).
coords = px.Coordinates(["theta1", "theta2"])
trig = [f(q) for q in coords.q for f in (sp.sin, sp.cos)]
terms = [term for term in px.products([1, *px.monomials(trig, 2)],
                                      [1, *px.monomials(coords.qd, 2)]) if term.free_symbols]
catalog = px.CatalogRepartition([
    px.LagrangeLibrary(coords, terms),
    px.ClassicalLibrary(coords, coords.qd, mask=np.eye(2, dtype=bool)),
])

# %%
# Strong form: accelerations by (smoothed) finite differences of the noisy angles.
strong = px.XLSINDy(catalog, formulation="strong").fit(q_noisy, t, u=u)
print(f"strong: {np.count_nonzero(strong.coefficients())} terms")

# %%
# Weak form (the default when only positions are given): test functions and smoother are
# chosen from the data; 20 cross-validated fits on subsamples of the test functions vote on
# the terms, and the model keeps those most of them select (with inclusion probabilities
# and 95 % intervals).
weak = px.XLSINDy(catalog).fit(q_noisy, t, u=u)
weak.print(precision=3, uncertainty=True)
print(f"weak: {np.count_nonzero(weak.coefficients())} terms; test-function half-width "
      f"{weak.weak_info_['half_width']:.2f} s; estimated noise {weak.weak_info_['noise']}")

# %%
# Against the true coefficients (the true Lagrangian expanded in the catalog):
th1, th2 = coords.q
true_lagrangian = (coords.qd[0] ** 2 + coords.qd[1] ** 2 / 2
                   + coords.qd[0] * coords.qd[1] * sp.cos(th1 - th2)
                   + 2 * g * sp.cos(th1) + g * sp.cos(th2))
true = catalog.ideal_coefficients(lagrangian=sp.expand_trig(true_lagrangian),
                                  classical={(coords.qd[0], 0): c[0], (coords.qd[1], 1): c[1]})
for name, model in (("strong", strong), ("weak", weak)):
    coef, support = model.coefficients(), true != 0
    error = np.abs(coef[support] - true[support]) / np.abs(true[support])
    print(f"{name:6s}: exact support {np.array_equal(coef != 0, support)}, "
          f"{np.count_nonzero(coef[~support])} false terms, largest error {error.max():.1%}")

# %%
# Both models simulated from a fresh state under new torques, against the truth. The true
# Lagrangian is ``theta1_dot**2 + 0.5 theta2_dot**2 + theta1_dot theta2_dot cos(theta1 -
# theta2) + 2 g cos(theta1) + g cos(theta2)``.
t_val = np.arange(0, 5, 0.01)
x0 = np.array([-0.4, 0.6, 0.5, -0.5])
truth = solve_ivp(true_rhs, (0, 5), x0, t_eval=t_val, rtol=1e-10, atol=1e-10).y[:2].T
fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
for i, ax in enumerate(axes):
    ax.plot(t_val, truth[:, i], "k", lw=2, label="truth")
    for name, model, style in (("weak", weak, "C0--"), ("strong", strong, "C3:")):
        try:
            states = model.simulate(x0, t_val, u=torque)
        except px.SimulationError as error:  # a diverging model stops early
            states = error.states
        ax.plot(t_val[: len(states)], states[:, i], style, label=name)
    ax.set_ylabel(coords.names[i])
    ax.set_ylim(1.5 * truth[:, i].min() - 0.2, 1.5 * truth[:, i].max() + 0.2)
axes[0].legend(loc="upper right")
axes[1].set_xlabel("t (s)")
fig.suptitle("1 % position noise: strong vs weak formulation")
fig.tight_layout()
plt.show()
