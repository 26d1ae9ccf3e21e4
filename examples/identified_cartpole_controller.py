"""
A controller designed on the identified cart-pole, run in MuJoCo
================================================================

The paper's stated next step is model-based control on identified models. Here a cart-pole is
identified from noisy MuJoCo positions (weak formulation, kinematic catalog); a balance
controller for the upright pole is then designed **on the identified model only**: an LQR gain
from the model's linearization, refined by a short cross-entropy search through the Gymnasium
environment ``model.to_gymnasium(dt)``. The same controller finally runs in MuJoCo, from the
same initial state, and both trajectories are plotted.
"""

import time

import matplotlib.pyplot as plt
import mujoco
import numpy as np
from scipy.linalg import solve_continuous_are

import pysindy_xl as px
from pysindy_xl.mujoco import generate_dataset, get_system, reference_catalog

start = time.perf_counter()

# %%
# Identification: two randomly forced 5 s trajectories, positions only with 1 % noise.
system = get_system("cart-pole")
data = generate_dataset(system, n_trajectories=2, duration=5.0, seed=0, noise=0.01,
                        noise_model="positions", progress=False)
model = px.XLSINDy(reference_catalog(system, "kinematic"))
model.fit(**data.fit_arguments(forces="tau"))
print(f"{model.formulation_} formulation, {np.count_nonzero(model.coefficients())} terms")
model.print()

# %%
# Design on the identified model: linearize ``M(q) qdd = f(q, qd, u)`` at the upright pole
# (``theta = pi``) by finite differences, with the force on the cart as the input, and solve
# the continuous-time Riccati equation.
upright = np.array([0.0, np.pi, 0.0, 0.0])
derivative = model.dynamics_.state_derivative


def linearization(state, eps=1e-6):
    a = np.empty((4, 4))
    for k in range(4):
        step = np.zeros(4)
        step[k] = eps
        a[:, k] = (derivative(state + step, np.zeros(2))
                   - derivative(state - step, np.zeros(2))) / (2 * eps)
    b = (derivative(state, np.array([eps, 0.0]))
         - derivative(state, np.array([-eps, 0.0])))[:, None] / (2 * eps)
    return a, b


A, B = linearization(upright)
Q, R = np.diag([1.0, 20.0, 0.5, 1.0]), np.array([[0.1]])
K_lqr = (np.linalg.solve(R, B.T @ solve_continuous_are(A, B, Q, R)))[0]
print("LQR gain on the identified model:", np.round(K_lqr, 2))


def controller(gain):
    def act(state):
        error = state - upright
        error[1] = (error[1] + np.pi) % (2 * np.pi) - np.pi  # wrapped angle
        return np.array([-gain @ error])
    return act


# %%
# Refinement through the Gymnasium environment of the identified model: a cross-entropy
# search over the four gains, scoring episodes of 4 s from two tilted starts (quadratic cost,
# forces limited to 15 N, large penalty when the pole falls).
dt = 0.02
limit = 15.0
env = model.to_gymnasium(
    dt, actuated=["x"], action_bounds=limit, max_episode_steps=200, substeps=2,
    reward=lambda s, a, s1: -float((s1[0] ** 2) + 10 * np.cos(s1[1] / 2) ** 2
                                   + 0.1 * s1[2] ** 2 + 0.01 * a[0] ** 2),
    terminated=lambda s1: abs(np.cos(s1[1] / 2)) > np.sin(0.6),  # 0.6 rad from upright
)
starts = [np.array([0.0, np.pi - 0.3, 0.0, 0.0]), np.array([0.3, np.pi + 0.2, 0.0, -0.5])]


def episode_return(gain):
    act, total = controller(gain), 0.0
    for state in starts:
        observation, _ = env.reset(options={"state": state})
        for _ in range(200):
            observation, reward, terminated, truncated, _ = env.step(act(observation))
            total += reward
            if terminated:
                total -= 1e3
                break
            if truncated:
                break
    return total


rng = np.random.default_rng(0)
mean, spread = K_lqr.copy(), 0.3 * np.abs(K_lqr) + 0.1
best_gain, best = mean.copy(), episode_return(mean)
print(f"identified model, LQR gain: return {best:.1f}")
for iteration in range(1):  # one round: the LQR gain is already close
    gains = mean + spread * rng.standard_normal((12, 4))
    returns = np.array([episode_return(g) for g in gains])
    elite = gains[np.argsort(returns)[-3:]]
    mean, spread = elite.mean(axis=0), elite.std(axis=0) + 0.02 * np.abs(mean)
    if returns.max() > best:
        best, best_gain = returns.max(), gains[np.argmax(returns)]
    print(f"cross-entropy iteration {iteration + 1}: best return {best:.1f}")
print("gain used:", np.round(best_gain, 2))

# %%
# The same controller in MuJoCo and in the identified model, from the same tilted start: the
# force is computed every ``dt`` from the state and held (zero-order hold) over the 1 ms MuJoCo
# steps.
act = controller(best_gain)
state0 = starts[0]
mj_model = system.mj_model()
mj_data = mujoco.MjData(mj_model)
mj_data.qpos[:], mj_data.qvel[:] = system.from_generalized(state0[:2], state0[2:])
steps_per_dt = int(round(dt / mj_model.opt.timestep))
n_steps = int(6.0 / dt)
mujoco_states, model_states = [state0.copy()], [state0.copy()]
observation, _ = env.reset(options={"state": state0})
env.max_episode_steps = None
for _ in range(n_steps):
    q, qd, _ = system.to_generalized(mj_data.qpos, mj_data.qvel)
    mj_data.ctrl[:] = [np.clip(act(np.r_[q, qd])[0], -limit, limit), 0.0]
    for _ in range(steps_per_dt):
        mujoco.mj_step(mj_model, mj_data)
    q, qd, _ = system.to_generalized(mj_data.qpos, mj_data.qvel)
    mujoco_states.append(np.r_[q, qd])
    observation, *_ = env.step(act(observation))
    model_states.append(observation)
times = dt * np.arange(n_steps + 1)
mujoco_states, model_states = np.array(mujoco_states), np.array(model_states)
final = np.abs(mujoco_states[-1] - upright)
print(f"MuJoCo after {times[-1]:g} s: |x| = {final[0]:.3f} m, |theta - pi| = {final[1]:.4f} rad")
gap = np.abs(mujoco_states - model_states).max(axis=0)
print(f"largest difference MuJoCo vs identified model: x {gap[0]:.3f} m, theta {gap[1]:.4f} rad")
print(f"example ran in {time.perf_counter() - start:.1f} s")

# %%
# Both trajectories under the controller designed on the identified model.
fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 4.5))
for k, name in enumerate(["x [m]", "theta [rad]"]):
    axes[k].plot(times, mujoco_states[:, k], "k--", lw=1.2, label="MuJoCo")
    axes[k].plot(times, model_states[:, k], lw=1.2, label="identified model (Gymnasium env)")
    axes[k].set_ylabel(name)
axes[1].axhline(np.pi, color="gray", lw=0.6)
axes[0].legend(loc="upper right")
axes[-1].set_xlabel("t [s]")
axes[0].set_title("Balance controller designed on the identified cart-pole")
fig.tight_layout()
