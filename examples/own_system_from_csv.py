"""
Your own system from a CSV: a catalog that builds itself
========================================================

A rig nobody wrote a model file for: a pendulum whose pivot carries a torsion spring, driven by
a motor. The recording holds the angle and the motor torque, nothing else. Given only the name
of the coordinate and its kind (an angle), :func:`pysindy_xl.grow_catalog` starts from the
smallest catalog in a Lagrangian's shape, grows it while the error on held-out blocks of the
runs drops, and returns the discovered Lagrangian. The same runs from the command line::

    pysindy-xl identify rig.csv --coordinates theta --angles theta

The first section only *writes* the CSV (a simulation with measurement noise), so that the
example is self-contained; with a real recording, start at the second one.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import pysindy_xl as px
from pysindy_xl.data import load_data

# %%
# A stand-in for the rig
# ----------------------
# ``0.32 theta'' + 0.05 theta' + 3.924 sin(theta) + 3 theta = tau``: gravity and a torsion spring,
# which no sine or cosine states. Two runs of 10 s at 200 Hz, angles with 1 % noise.
rng = np.random.default_rng(0)
folder = Path(tempfile.mkdtemp())


def torque(t, run):
    return 1.2 * np.sin((0.9 + 0.4 * run) * t) + 0.8 * np.sin(3.1 * t + run)


def rig(t, s, run):
    theta, omega = s
    return [omega, (torque(t, run) - 0.05 * omega - 3.924 * np.sin(theta) - 3.0 * theta) / 0.32]


rows = []
t = np.arange(0, 10, 0.005)
for run in range(2):
    theta = solve_ivp(rig, (0, t[-1]), [0.8 * run, 0.0], t_eval=t, args=(run,), rtol=1e-10,
                      atol=1e-10).y[0]
    theta += 0.01 * theta.std() * rng.normal(size=len(t))
    rows.append(np.c_[t, theta, torque(t, run), np.full(len(t), run)])
csv = folder / "rig.csv"
np.savetxt(csv, np.vstack(rows), delimiter=",", header="t,theta,tau_theta,trajectory",
           comments="")

# %%
# Grow the catalog
# ----------------
# The recording is read like any CSV (columns ``t``, the coordinate, ``tau_NAME`` and a
# ``trajectory`` id). Each step of the growth is one catalog fitted on three fifths of each run
# and scored on the other two: the last block, and the block reaching farthest from the
# median angle, where a sine series standing in for ``theta^2`` would fail.
data = load_data(str(csv), coordinates=["theta"])
arguments = data.fit_arguments()
found = px.grow_catalog(arguments["x"], arguments["t"], arguments["u"],
                        coordinates=["theta"], kinds="angle")
print(found.table())

# %%
# The discovered Lagrangian
# -------------------------
# ``L = 0.16 theta'^2 + 3.924 cos(theta) - 1.5 theta^2``: the kinetic energy, gravity and the
# torsion spring, plus the viscous friction among the forces.
found.model.print(precision=3)

# %%
# Validation on a run the fit never saw
# -------------------------------------
# A new torque profile, simulated by the identified model and by the true rig.
t_new = np.arange(0, 6, 0.005)
truth = solve_ivp(rig, (0, t_new[-1]), [0.3, 0.0], t_eval=t_new, args=(5,), rtol=1e-10,
                  atol=1e-10).y[0]
simulated = found.model.simulate(np.array([0.3, 0.0]), t_new,
                                 u=lambda time: np.array([torque(time, 5)]))[:, 0]
print(f"position RMSE over 6 s: {np.sqrt(np.mean((simulated - truth) ** 2)):.2e} rad")

figure, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5))
top.plot(t_new, truth, color="black", label="rig")
top.plot(t_new, simulated, "--", color="tab:orange", label="identified model")
top.set_ylabel("theta (rad)")
top.legend()
steps = found.steps
bottom.semilogy(range(len(steps)), [s.criterion for s in steps], "o-", color="tab:blue")
for k, step in enumerate(steps):
    bottom.annotate(step.move, (k, step.criterion), fontsize="x-small", rotation=30)
bottom.set_xlabel("growth step")
bottom.set_ylabel("held-out error")
figure.tight_layout()
plt.show()
