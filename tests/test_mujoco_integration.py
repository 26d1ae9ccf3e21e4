"""Stable and faithful MuJoCo integration chosen from the model; unstable runs refused."""

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from pysindy_xl.mujoco import MJCFSystem, generate_dataset  # noqa: E402
from pysindy_xl.simulation.integration import (  # noqa: E402
    BIAS_TOLERANCE,
    RK4_BOUND,
    UnstableSimulationError,
    choose_integration,
    linear_modes,
)

# A stiff servo (kv = 300 N m s/rad) on a light wrist link (1e-3 kg m^2, no armature) at
# MuJoCo's 2 ms step, as published arm models have them: h |lambda| ~ 600 at the model step.
STIFF_ARM = """
<mujoco model="stiff_arm">
  <option timestep="0.002" integrator="implicitfast" gravity="0 0 -9.81">
    <flag contact="disable"/></option>
  <worldbody>
    <body name="upper" pos="0 0 0.5">
      <joint name="shoulder" axis="0 1 0" damping="0.5" range="-2 2"/>
      <inertial pos="0.15 0 0" mass="1.0" diaginertia="0.01 0.02 0.02"/>
      <body name="wrist" pos="0.3 0 0">
        <joint name="wrist" axis="1 0 0" damping="0.1" range="-2 2"/>
        <inertial pos="0 0 0" mass="0.2" diaginertia="1e-3 1e-3 1e-3"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position joint="shoulder" kp="300" kv="30" ctrlrange="-1 1"/>
    <position joint="wrist" kp="3000" kv="300" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""


def _inverse_dynamics_residual(system, trajectory):
    """RMS of MuJoCo's inverse dynamics at the recorded positions' own accelerations (central
    differences) minus the recorded actuator forces, relative to their RMS."""
    model = system.mj_model()
    data = mujoco.MjData(model)
    h = trajectory.t[1] - trajectory.t[0]
    q = trajectory.q
    qd = (q[2:] - q[:-2]) / (2 * h)
    qdd = (q[2:] - 2 * q[1:-1] + q[:-2]) / h**2
    residual = np.empty_like(qd)
    for k in range(len(qd)):  # MuJoCo evaluates one state per call
        data.qpos[:], data.qvel[:], data.qacc[:] = q[k + 1], qd[k], qdd[k]
        mujoco.mj_inverse(model, data)
        residual[k] = data.qfrc_inverse - trajectory.u[k + 1]
    forces = trajectory.u[1:-1]
    return np.sqrt(np.mean(residual**2)) / np.sqrt(np.mean(forces**2))


def test_stiff_servo_on_a_light_link_gets_a_stable_faithful_integration():
    system = MJCFSystem(STIFF_ARM)
    model = system.mj_model()
    rate, _ = linear_modes(model)
    assert model.opt.timestep * rate > 100  # RK4 at the model's step: far outside its region
    choice = choose_integration(model)
    assert choice.stability <= RK4_BOUND or choice.bias <= BIAS_TOLERANCE
    data = generate_dataset(system, n_trajectories=1, duration=0.1, seed=0, progress=False)
    meta = data.metadata
    assert (meta["integrator"], meta["substeps"]) == (choice.integrator, choice.substeps)
    assert meta["substeps"] > 100 and meta["integration"]["reason"]
    assert set(meta["peak_velocity"]) == {"shoulder", "wrist"}
    trajectory = data.trajectories[0]
    assert np.all(np.isfinite(trajectory.q)) and np.abs(trajectory.qd).max() < 20
    # the recorded positions obey MuJoCo's continuous dynamics (its inverse dynamics at their
    # own finite-difference accelerations give the recorded forces); the model's own implicit
    # step at 2 ms adds h (kv + damping) = 0.6 kg m^2 to a 1e-3 kg m^2 link and does not
    faithful = _inverse_dynamics_residual(system, trajectory)
    authored = generate_dataset(system, n_trajectories=1, duration=0.1, seed=0,
                                integrator="model", progress=False)
    assert faithful < 0.02
    assert _inverse_dynamics_residual(system, authored.trajectories[0]) > 10 * faithful


def test_unstable_run_is_refused_naming_the_option():
    system = MJCFSystem(STIFF_ARM)
    with pytest.raises(UnstableSimulationError, match="integrator='auto'"):
        generate_dataset(system, n_trajectories=1, duration=0.1, seed=0, integrator="RK4",
                         progress=False)
