"""
A 7-joint servo arm from noisy encoders: identify, validate, export
===================================================================

A Panda-like arm: seven hinge joints, every one a position servo with motor armature, joint
damping and limits, stepped by MuJoCo's ``implicitfast`` integrator as published arm models
are. We record two runs with 1 % noise on the joint positions only (encoders; torques as the
servos applied them), identify the arm from its MJCF's kinematic tree, and check the model
the way roboticists do: the physical parameters next to the MJCF's, torque prediction on a
fresh run, the servos driving the identified model in closed loop, and the identified arm
exported back to MuJoCo.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import mujoco
import numpy as np

import pysindy_xl as px
from pysindy_xl.mujoco import generate_dataset, validate_model
from pysindy_xl.quality import force_prediction

# %%
# The arm. Each link: joint axis, offset from its parent, centre of mass, mass and principal
# inertias (realistic for a 7-joint arm of about 16 kg).
LINKS = [("0 0 1", "0 0 0.333", "0 -0.03 -0.07", 4.97, "0.70 0.70 0.009", 2.8),
         ("0 1 0", "0 0 0", "0 -0.07 0.03", 0.65, "0.008 0.028 0.025", 1.7),
         ("0 0 1", "0 0 0.316", "0.04 0.02 -0.07", 3.23, "0.037 0.036 0.010", 2.8),
         ("0 -1 0", "0.083 0 0", "-0.05 0.10 0.03", 3.59, "0.026 0.019 0.028", 2.0),
         ("0 0 1", "-0.083 0 0.384", "-0.01 0.04 -0.11", 1.23, "0.036 0.029 0.008", 2.8),
         ("0 -1 0", "0 0 0", "0.06 -0.01 0.01", 1.67, "0.002 0.004 0.005", 1.6),
         ("0 0 1", "0.088 0 -0.107", "0.01 0.01 0.08", 0.74, "0.013 0.010 0.004", 2.8)]
body = ""
for k, (axis, pos, com, mass, inertia, limit) in reversed(list(enumerate(LINKS))):
    body = (f'<body name="link{k}" pos="{pos}"><joint name="j{k}" axis="{axis}" '
            f'range="{-limit} {limit}" armature="{0.1 / (k + 1):.4f}" '
            f'damping="{0.5 / (k + 1):.4f}"/><inertial pos="{com}" mass="{mass}" '
            f'diaginertia="{inertia}"/>{body}</body>')
servos = "".join(f'<position joint="j{k}" kp="{200 / (k + 1):.1f}" kv="{10 / (k + 1):.2f}" '
                 f'ctrlrange="{-0.8 * link[5]} {0.8 * link[5]}"/>'
                 for k, link in enumerate(LINKS))
folder = Path(tempfile.mkdtemp())
path = folder / "arm7.xml"
path.write_text(f'<mujoco model="arm7"><compiler angle="radian"/>'
                f'<option timestep="0.002" integrator="implicitfast"><flag contact="disable"/>'
                f"</option><worldbody>{body}</worldbody><actuator>{servos}</actuator></mujoco>",
                encoding="utf-8")

# %%
# The catalog: one term per base parameter (the combinations of masses, first and second
# moments and armatures the dynamics determine), viscous and smooth dry friction per joint.
catalog = px.kinematic_catalog(str(path))
arm = catalog.system
print(f"{catalog.n_candidates} inertial parameters -> {len(catalog.lagrange_terms)} base "
      f"parameters (derived in {catalog.build_seconds:.1f} s)")

# %%
# Data: the servos track random references inside the joint limits; the generator integrates
# with RK4 (the implicit step would bias the positions, see the robot-arm guide) and records
# the torques the servos applied. Noise: 1 % of each joint's spread, on the positions only.
data = generate_dataset(arm, n_trajectories=2, duration=6.0, noise=0.01, seed=0,
                        sample_every=2, progress=False)
print(data.metadata["integrator"], sum(len(tr.t) for tr in data.trajectories), "samples")

# %%
# The default fit of a kinematic catalog: every parameter estimated from the weak form of the
# noisy positions, then refitted physically consistent (each body's pseudo-inertia positive
# semidefinite, armature and friction non-negative).
model = px.XLSINDy(catalog.library()).fit(**data.fit_arguments(forces="tau"))
model.print()

# %%
# Torque prediction on a fresh run (the standard metric of robot identification): the torques
# the identified model needs to move as recorded, against the measured ones. The run's exact
# positions isolate the model's own error; from noisy encoders the differentiation of the
# fresh positions adds its own.
fresh = generate_dataset(arm, n_trajectories=1, duration=4.0, seed=1, sample_every=2,
                         progress=False).trajectories[0]
prediction = force_prediction(model, fresh.q, fresh.t, fresh.tau)
print("relative RMS torque error per joint:",
      {joint: round(error, 4) for joint, error in prediction["relative_rms"].items()})
fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 4))
for ax, joint in zip(axes, (1, 6), strict=True):
    ax.plot(fresh.t, fresh.tau[:, joint], label="measured")
    ax.plot(fresh.t, prediction["predicted"][:, joint], "--", label="identified model")
    ax.set_ylabel(f"torque j{joint} (N m)")
axes[0].legend()
axes[-1].set_xlabel("time (s)")
fig.tight_layout()

# %%
# Closed loop: the MJCF's servos, driven by a fresh run's reference, act on the identified
# model's own state, as they acted on MuJoCo's.
result = validate_model(model, arm, duration=2.0, seed=2)
print(result.drive, "valid" if result.valid else "INVALID",
      f"position RMSE {result.position_rmse:.2e}, actuator force error {result.force_error:.3f}")

# %%
# Export: an MJCF whose bodies carry rigid-body inertials reproducing the identified base
# parameters, with the identified damping and friction. MuJoCo's mass matrix of the exported
# arm against the original's.
exported = model.to_mjcf(folder / "identified.xml", template=arm)
original = arm.mj_model()
identified = mujoco.MjModel.from_xml_path(str(folder / "identified.xml"))
errors = []
for qpos in np.random.default_rng(0).uniform(-1.5, 1.5, size=(20, 7)):
    matrices = []
    for mj_model in (original, identified):
        mj_data = mujoco.MjData(mj_model)
        mj_data.qpos[:] = qpos
        mujoco.mj_forward(mj_model, mj_data)
        matrix = np.zeros((7, 7))
        mujoco.mj_fullM(mj_model, mj_data, matrix)
        matrices.append(matrix)
    errors.append(np.linalg.norm(matrices[1] - matrices[0]) / np.linalg.norm(matrices[0]))
print(f"realization residual {exported['residual']:.1e}; mass-matrix error of the exported "
      f"arm against the MJCF's: {np.mean(errors):.2%} (mean over 20 states)")
plt.show()
