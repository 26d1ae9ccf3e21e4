"""
Your own recordings: identify a system from CSV or NPZ files
============================================================

Measured data usually come as a file written by a data logger: sample times, joint angles and
the commanded torques, several runs one after the other. This example identifies a
motor-driven pendulum with friction from such files, in CSV and in NPZ form, then saves the
identified model as JSON and reloads it.

The first section only *writes* the files (from a simulation with measurement noise) so that
the example is self-contained; with real data, start at the second one.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pysindy as ps
import sympy as sp
from scipy.integrate import solve_ivp

import pysindy_xl as px
from pysindy_xl.mujoco import load_dataset

# %%
# A stand-in for the data logger
# ------------------------------
# A point mass ``m = 0.3`` kg on a massless rod ``l = 0.4`` m, viscous friction
# ``c = 0.03`` N m s, driven by a motor torque. Two runs of 15 s at 200 Hz, angles measured
# with 2e-4 rad of noise.
m, l, g, c = 0.3, 0.4, 9.81, 0.03
rng = np.random.default_rng(0)
folder = Path(tempfile.mkdtemp())


def torque(t, run):
    return 0.35 * np.sin((1.1 + 0.3 * run) * t) + 0.2 * np.sin(3.7 * t + run)


def pendulum(t, s, run):
    theta, omega = s
    return [omega, (torque(t, run) - c * omega - m * g * l * np.sin(theta)) / (m * l**2)]


rows = []
for run in range(2):
    t = np.arange(0, 15, 0.005)
    theta = solve_ivp(pendulum, (0, t[-1]), [0.5 * run, 0.0], t_eval=t, args=(run,),
                      rtol=1e-10, atol=1e-10).y[0]
    theta += 2e-4 * rng.normal(size=t.shape)
    rows.append(np.column_stack([np.full_like(t, run), t, theta, torque(t, run)]))
rows = np.vstack(rows)
csv_path = folder / "pendulum.csv"
np.savetxt(csv_path, rows, delimiter=",", header="run,t,theta,torque", comments="")
print(csv_path.read_text().splitlines()[:3])

# %%
# Reading a CSV file
# ------------------
# ``np.genfromtxt(..., names=True)`` reads the header; each run becomes one trajectory. Lists
# of arrays are passed to ``fit`` as they are: derivatives are computed per trajectory, so
# nothing is differentiated across the jump from one run to the next.
data = np.genfromtxt(csv_path, delimiter=",", names=True)
runs = [data[data["run"] == k] for k in np.unique(data["run"])]
t = [run["t"] for run in runs]
q = [run["theta"][:, None] for run in runs]  # (N, n): one column per coordinate
u = [run["torque"][:, None] for run in runs]

# %%
# Catalog and fit
# ---------------
# Candidate Lagrangian terms in ``theta`` and ``theta_dot``, and viscous friction. The noise is
# amplified by the second derivative: a smoothing differentiation method (pysindy's
# ``SmoothedFiniteDifference``, a Savitzky-Golay filter) keeps the accelerations usable.
coords = px.Coordinates(["theta"])
theta_symbol, omega_symbol = coords.q[0], coords.qd[0]
terms = [
    term
    for term in px.products([1, sp.sin(theta_symbol), sp.cos(theta_symbol)],
                            [1, omega_symbol, omega_symbol**2])
    if term.free_symbols
]
catalog = px.LagrangeLibrary(coords, terms) + px.ClassicalLibrary(coords, [omega_symbol])
model = px.XLSINDy(
    catalog,
    px.ExplicitOptimizer(),
    differentiation_method=ps.SmoothedFiniteDifference(smoother_kws={"window_length": 31}),
)
model.fit(q, t, u=u)
model.print()
print(f"true: m l^2 / 2 = {m * l**2 / 2:.4f}, m g l = {m * g * l:.4f}, c = {c}")

# %%
# The same data in an NPZ file
# ----------------------------
# pysindy-xl's dataset layout (:func:`pysindy_xl.mujoco.load_dataset`) is a plain NPZ with
# arrays ``t`` (N,), ``q`` (N, n), optionally ``tau`` (N, n) and an integer ``trajectory``
# id per sample; metadata such as coordinate names go in a JSON side-car file. It never
# needs pickle.
npz_path = folder / "pendulum.npz"
np.savez(npz_path, t=data["t"], q=data["theta"][:, None], tau=data["torque"][:, None],
         trajectory=data["run"].astype(int))
(folder / "pendulum.json").write_text('{"coordinate_names": ["theta"]}')
dataset = load_dataset(npz_path)
print(dataset)
model_npz = px.XLSINDy(catalog, px.ExplicitOptimizer(),
                       differentiation_method=ps.SmoothedFiniteDifference(
                           smoother_kws={"window_length": 31}))
model_npz.fit([tr.q for tr in dataset.trajectories], [tr.t for tr in dataset.trajectories],
              u=[tr.tau for tr in dataset.trajectories])
print("same coefficients as from the CSV file:",
      np.allclose(model_npz.coefficients(), model.coefficients()))

# %%
# Save, reload, simulate
# ----------------------
# Models are saved as JSON (catalog specification and coefficients); loading parses the terms
# with a restricted grammar and never executes code from the file.
model_path = folder / "pendulum_model.json"
model.save(model_path)
reloaded = px.XLSINDy.load(model_path)

recording = runs[1]
start = [recording["theta"][0], 0.0]
simulated = reloaded.simulate(start, recording["t"], u=recording["torque"][:, None])
error = np.sqrt(np.mean((simulated[:, 0] - recording["theta"]) ** 2))
print(f"RMSE between the recording and the simulated model: {error:.2e} rad")

fig, ax = plt.subplots(figsize=(8, 3.5))
ax.plot(recording["t"], recording["theta"], "k.", ms=1, label="recording (run 1)")
ax.plot(recording["t"], simulated[:, 0], label="identified model, simulated")
ax.set(xlabel="t [s]", ylabel="theta [rad]")
ax.legend(loc="upper right")
fig.tight_layout()
