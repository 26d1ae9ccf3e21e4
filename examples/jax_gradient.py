"""
Gradients through a simulation: fit an initial state, then a force
===================================================================

An identified model exported with ``to_jax`` is a pure JAX function, so a whole simulation
can be differentiated. Here a double pendulum is identified from MuJoCo data, then

1. the unknown initial state of an observed MuJoCo trajectory is recovered by minimizing the
   gap between simulated and observed angles;
2. a torque profile on the first joint is optimized so that the pendulum, starting at rest,
   reaches a target pose at rest after two seconds; the torque is then replayed in MuJoCo.

Both problems are solved with SciPy's BFGS on a jitted ``jax.value_and_grad`` (compiled
once, then each evaluation takes milliseconds): reverse-mode differentiation through the
``lax.scan`` of the RK4 rollout.
"""

import jax
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import minimize

import pysindy_xl as px
from pysindy_xl import mujoco as pxm
from pysindy_xl.export.jax_dynamics import simulate

# Double precision keeps BFGS's line search reliable.
jax.config.update("jax_enable_x64", True)


def with_gradient(function):
    """A jitted ``x -> (value, gradient)`` for scipy.optimize.minimize(jac=True)."""
    compiled = jax.jit(jax.value_and_grad(function))

    def call(x):
        value, gradient = compiled(jnp.asarray(x))
        return float(value), np.asarray(gradient)

    return call


# %%
# Identify the double pendulum (absolute angles, joint damping) from two forced MuJoCo runs.
system = pxm.get_system("double-pendulum")
data = pxm.generate_dataset(
    system, n_trajectories=2, duration=8.0, seed=0, sample_every=5, progress=False
)
model = px.XLSINDy(pxm.reference_catalog(system, "mixed"), px.ExplicitOptimizer())
model.fit(**data.fit_arguments("tau"))
model.print()
f = model.to_jax()

# %%
# 1. Recover an initial state
# ---------------------------
# MuJoCo simulates one unforced second from a state we pretend not to know; we observe the
# angles every 10 ms, with 0.005 rad of measurement noise.
dt, n_samples = 0.01, 101
true_x0 = np.array([0.8, -0.5, 1.2, -2.0])
observed = pxm.simulate_trajectory(system, 1.0, q0=true_x0[:2], qd0=true_x0[2:], sample_every=10)
rng = np.random.default_rng(0)
angles = observed.q + 0.005 * rng.normal(size=observed.q.shape)


def misfit(x0):
    states = simulate(f, x0, None, dt, n_steps=n_samples).states
    return jnp.mean((states[:, :2] - angles) ** 2)


guess = jnp.array([angles[0, 0], angles[0, 1], 0.0, 0.0])  # first sample, at rest
fit = minimize(with_gradient(misfit), guess, jac=True, method="BFGS")
print(f"BFGS: {fit.nit} iterations, misfit {fit.fun:.2e} rad^2")
print("true initial state     ", np.round(true_x0, 3))
print("recovered initial state", np.round(fit.x, 3))

# %%
# 2. Find a torque that reaches a target pose
# -------------------------------------------
# Ten piecewise-constant torques on the first joint (0.2 s each); the cost is the squared
# distance to the target state at t = 2 s plus a small effort penalty.
n_pieces, duration = 10, 2.0
n_steps = int(round(duration / dt)) + 1
target = jnp.array([np.pi / 2, np.pi / 2, 0.0, 0.0])  # both links horizontal, at rest
per_piece = (n_steps - 1) // n_pieces


def forces(pieces):
    """(n_pieces,) torques on theta1 -> (n_steps, 2) generalized forces, held per step."""
    held = jnp.repeat(pieces, per_piece, total_repeat_length=n_steps - 1)
    held = jnp.concatenate([held, held[-1:]])
    return jnp.stack([held, jnp.zeros_like(held)], axis=1)


def cost(pieces):
    final = simulate(f, jnp.zeros(4), forces(pieces), dt, final_only=True).states
    return jnp.sum((final - target) ** 2) + 1e-4 * jnp.mean(pieces**2)


plan = minimize(with_gradient(cost), np.zeros(n_pieces), jac=True, method="BFGS")
pieces = plan.x
print(f"BFGS: {plan.nit} iterations, cost {plan.fun:.2e}")
print("torques (N m):", np.round(pieces, 2))

# %%
# Replay the torques in MuJoCo (1 ms steps, the actuator of hinge 1; a torque on the first
# hinge is the generalized force on theta1) and compare with the model's plan.
mj_dt = system.mj_model().opt.timestep


def signals(times):
    piece = np.minimum(np.round(times / mj_dt).astype(int) // int(round(0.2 / mj_dt)), n_pieces - 1)
    return np.stack([pieces[piece], np.zeros(len(times))], axis=1)


replay = pxm.simulate_trajectory(system, duration, signals=signals, sample_every=10)
planned = np.asarray(simulate(f, jnp.zeros(4), forces(plan.x), dt).states)
print("target state     ", np.round(np.asarray(target), 3))
print("model, final     ", np.round(planned[-1], 3))
print("MuJoCo, final    ", np.round(np.concatenate([replay.q[-1], replay.qd[-1]]), 3))

t = dt * np.arange(n_steps)
fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
for i, name in enumerate(system.coordinate_names):
    top.plot(t, planned[:, i], label=f"{name}, identified model")
    top.plot(replay.t, replay.q[:, i], "k--", lw=1, label=f"{name}, MuJoCo replay")
top.axhline(np.pi / 2, color="grey", lw=0.5)
top.set_ylabel("angle (rad)")
top.legend(fontsize=8)
bottom.step(t[:-1], np.asarray(forces(plan.x))[:-1, 0], where="post")
bottom.set_ylabel("torque on theta1 (N m)")
bottom.set_xlabel("time (s)")
fig.tight_layout()
plt.show()
