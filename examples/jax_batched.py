"""
Ten thousand simulations at once with JAX
=========================================

A double pendulum is identified from MuJoCo data and exported with ``to_jax``. One call to
:func:`pysindy_xl.export.jax_dynamics.simulate_batch` then integrates 10,000 trajectories with
fixed-step RK4 (``lax.scan`` over time, vectorized over trajectories) on whatever device JAX
uses. Two uses of such batches:

* uncertainty quantification: how fast does a 1 mrad uncertainty on the initial angles grow
  for this chaotic system?
* robustness: trajectories that blow up (here: a deliberately bad integrator) are flagged and
  frozen one by one, the rest of the batch carries on.
"""

import time

import jax
import matplotlib.pyplot as plt
import numpy as np

import pysindy_xl as px
from pysindy_xl import mujoco as pxm
from pysindy_xl.export.jax_dynamics import simulate_batch

# Single precision (the default of JAX): twice as fast as double on CPU.
jax.config.update("jax_enable_x64", False)

# %%
# Identify the double pendulum from two forced MuJoCo runs.
system = pxm.get_system("double-pendulum")
data = pxm.generate_dataset(
    system, n_trajectories=2, duration=8.0, seed=0, sample_every=5, progress=False
)
model = px.XLSINDy(pxm.reference_catalog(system, "mixed"), px.ExplicitOptimizer())
model.fit(**data.fit_arguments("tau"))
f = model.to_jax()

# %%
# An ensemble of 10,000 unforced trajectories whose initial angles differ by about 1 mrad.
rng = np.random.default_rng(0)
n_batch, dt, n_steps = 10_000, 0.005, 801
x0 = np.zeros((n_batch, 4))
x0[:, :2] = [2.8, 3.0] + 1e-3 * rng.normal(size=(n_batch, 2))

result = simulate_batch(f, x0, None, dt, n_steps=n_steps)  # compiles, then runs
start = time.perf_counter()
result = simulate_batch(f, x0, None, dt, n_steps=n_steps)
result.states.block_until_ready()
elapsed = time.perf_counter() - start
print(
    f"{n_batch} trajectories x {n_steps - 1} RK4 steps in {elapsed:.2f} s on "
    f"{jax.devices()[0].platform}: {1e6 * elapsed / (n_batch * (n_steps - 1)):.3f} us "
    f"per trajectory-step ({result.states.dtype})"
)
print(f"diverged: {int(result.diverged.sum())}")

# %%
# The spread of the outer angle: tight for a second or so, then the ensemble fans out.
t = dt * np.arange(n_steps)
theta2 = np.asarray(result.states[:, :, 1])
low, median, high = np.percentile(theta2, [5, 50, 95], axis=0)
fig, ax = plt.subplots(figsize=(7, 3.5))
ax.plot(t, theta2[:20].T, color="tab:blue", lw=0.5, alpha=0.6)
ax.fill_between(t, low, high, color="tab:orange", alpha=0.3, label="5-95 % of 10,000")
ax.plot(t, median, color="tab:orange", label="median")
ax.set_xlabel("time (s)")
ax.set_ylabel("theta2 (rad)")
ax.legend()
fig.tight_layout()
spread = high - low
print(
    "time at which the 5-95 % band of theta2 exceeds 0.1 rad:",
    f"{t[np.argmax(spread > 0.1)]:.2f} s",
)

# %%
# Divergence is reported per trajectory. Explicit Euler with a far too coarse step (0.1 s)
# pumps energy into the fastest trajectories; with a bound of 100 on every state entry, those
# that leave it are frozen at their last state inside and flagged with the step where they
# left. RK4 with the same step stays inside.
x0 = np.hstack([rng.uniform(-3, 3, (n_batch, 2)), rng.uniform(-6, 6, (n_batch, 2))])
euler = simulate_batch(f, x0, None, 0.1, n_steps=61, method="euler", bound=100.0)
rk4 = simulate_batch(f, x0, None, 0.1, n_steps=61, method="rk4", bound=100.0)
steps = np.asarray(euler.divergence_step)[np.asarray(euler.diverged)]
print(
    f"explicit Euler: {int(euler.diverged.sum())} of {n_batch} diverged "
    f"(median step {np.median(steps):.0f} of 60); RK4: {int(rk4.diverged.sum())}"
)
print("all states finite:", bool(np.isfinite(np.asarray(euler.states)).all()))
plt.show()
