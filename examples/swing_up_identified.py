"""
Swing-up on a model identified seconds earlier
==============================================

The learning loop of :mod:`pysindy_xl.control` on the MuJoCo cart-pole: two seconds of
excitation within a 10 N force limit, an identification from the positions alone (1 % noise)
with the generic catalog (coordinates and their kinds, no model file), then sampling MPC with an
LQR catch near the top, planned on the identified model only and run on MuJoCo. If the attempt
fails, its recording joins the data and the model is identified again.

The figure shows the successful attempt on the plant: a strip of frames, the angle and the cart
position within the track, and the force within its limit.
"""

import time

import matplotlib.pyplot as plt
import numpy as np

from pysindy_xl.control import learn_to_control

start = time.perf_counter()

# %%
# The loop: explore, identify, swing up, until the pendulum stays upright for 2 s.
result = learn_to_control("cart-pole", task="swing-up", catalog="generic", noise=0.01, seed=0,
                          force_limit=10.0, log=print)
print(f"success: {result.success} after {result.interaction_s:.2f} s on the plant "
      f"({result.episodes} episodes, catalog {result.catalog})")
print(f"median planning step: {result.mpc_step_ms:.1f} ms, largest force "
      f"{result.max_abs_force:.1f} N, largest |x| {result.max_abs_x:.2f} m")
print("identified equations:")
for equation in result.equations:
    print("  ", equation)

# %%
# The final attempt on MuJoCo: frames every 0.4 s, then the angle, the cart and the force.
episode = result.final_episode
length = 0.8  # the pole's length, for drawing only
fig = plt.figure(figsize=(10, 7))
strip = fig.add_subplot(3, 1, 1)
times = np.arange(0.0, episode.t[-1], 0.4)
for k, t in enumerate(times):
    i = np.searchsorted(episode.t, t)
    x, theta = episode.q[i]
    offset = 1.2 * k  # frames side by side
    strip.plot([offset - 0.15, offset + 0.15], [0, 0], color="tab:blue", lw=6)
    strip.plot([offset, offset + length * np.sin(theta)], [0, -length * np.cos(theta)],
               color="0.3", lw=2)
    strip.plot(offset + length * np.sin(theta), -length * np.cos(theta), "o", color="tab:red")
    strip.text(offset, -1.05, f"{t:.1f} s", ha="center", fontsize=8)
strip.set_aspect("equal")
strip.axis("off")
strip.set_title("Swing-up on MuJoCo, planned on the identified model")
u_times = np.arange(len(episode.controls)) * 0.02
ax = fig.add_subplot(3, 1, 2)
ax.plot(episode.t, episode.q[:, 1], label="theta [rad]")
ax.plot(episode.t, episode.q[:, 0], label="x [m]")
ax.axhline(np.pi, color="gray", lw=0.6)
ax.axhspan(np.pi - 0.2, np.pi + 0.2, color="tab:green", alpha=0.15, label="upright +-0.2 rad")
ax.axhline(1.5, color="k", ls=":", lw=0.8)
ax.axhline(-1.5, color="k", ls=":", lw=0.8)
ax.legend(loc="lower right", fontsize=8)
ax = fig.add_subplot(3, 1, 3)
ax.step(u_times, episode.controls[:, 0], where="post")
ax.axhline(10.0, color="k", ls=":", lw=0.8)
ax.axhline(-10.0, color="k", ls=":", lw=0.8)
ax.set_ylabel("force [N]")
ax.set_xlabel("t [s]")
fig.tight_layout()
print(f"example ran in {time.perf_counter() - start:.0f} s")
