"""Stable and faithful MuJoCo integration chosen from the model; unstable runs refused."""

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from pysindy_xl.mujoco import MJCFSystem, generate_dataset  # noqa: E402
from pysindy_xl.simulation import integration  # noqa: E402
from pysindy_xl.simulation.integration import (  # noqa: E402
    BIAS_TOLERANCE,
    RK4_BOUND,
    RK4_HELD_BOUND,
    RK4_HELD_MAX_SUBSTEPS,
    RK4_MAX_SUBSTEPS,
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
    choice = choose_integration(model, held_control=True)  # a forced run's
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


# Two links driven by torque motors, which generate_dataset drives through a tracking servo
# (its stiffest mode about 250 1/s: h |lambda| = 0.5 at the 2 ms step).
MOTOR_ARM = """
<mujoco model="motor_arm">
  <option timestep="0.002" gravity="0 0 -9.81"><flag contact="disable"/></option>
  <worldbody>
    <body name="upper" pos="0 0 0.5">
      <joint name="shoulder" axis="0 1 0" damping="0.1" armature="0.05" range="-2.5 2.5"/>
      <inertial pos="0.15 0 0" mass="1.0" diaginertia="0.01 0.02 0.02"/>
      <body name="fore" pos="0.3 0 0">
        <joint name="elbow" axis="0 1 0" damping="0.1" armature="0.02" range="-2.5 2.5"/>
        <inertial pos="0.1 0 0" mass="0.5" diaginertia="2e-3 4e-3 4e-3"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="shoulder"/><motor joint="elbow"/></actuator>
</mujoco>
"""


def _velocity_gain(trajectory):
    """Per coordinate, the recorded velocities' change over bumps (``-int phi' qd``) in units
    of the recorded accelerations' (``int phi qdd``, MuJoCo's ``mj_forward`` at each sample):
    1 where the positions follow the continuous equations under the recorded forces."""
    t = trajectory.t
    h, half = t[1] - t[0], 0.3
    centres = np.arange(t[0] + half, t[-1] - half, 0.1)
    s = (t[None, :] - centres[:, None]) / half
    inside = np.abs(s) < 1
    phi = np.where(inside, (1 - s**2) ** 6, 0.0) * h
    dphi = np.where(inside, -12 * s * (1 - s**2) ** 5 / half, 0.0) * h
    accelerations, changes = phi @ trajectory.qdd, -(dphi @ trajectory.qd)
    return (accelerations * changes).sum(0) / (accelerations**2).sum(0)


def test_tracked_motors_follow_the_continuous_equations(monkeypatch):
    system = MJCFSystem(MOTOR_ARM)
    data = generate_dataset(system, n_trajectories=1, duration=3.0, seed=0, progress=False,
                            control="tracking")
    meta = data.metadata
    assert meta["tracking"] is not None and meta["integrator"] == "RK4"
    assert meta["integration"]["stability"] <= RK4_HELD_BOUND
    assert np.abs(_velocity_gain(data.trajectories[0]) - 1).max() < 5e-4
    # bounded for stability only, the servo's held control leaves the positions 1 % off
    monkeypatch.setattr(integration, "RK4_HELD_BOUND", RK4_BOUND)
    coarse = generate_dataset(system, n_trajectories=1, duration=3.0, seed=0, progress=False,
                              control="tracking")
    assert coarse.metadata["substeps"] < meta["substeps"]
    assert np.abs(_velocity_gain(coarse.trajectories[0]) - 1).max() > 5e-3


def test_held_control_tightens_only_the_rk4_bound():
    model = MJCFSystem(MOTOR_ARM).mj_model()
    free, held = choose_integration(model), choose_integration(model, held_control=True)
    # motors alone: no stiff mode to resolve, the same step
    assert (free.integrator, free.substeps) == (held.integrator, held.substeps) == ("RK4", 1)
    stiff = MJCFSystem(STIFF_ARM).mj_model()
    stiff.actuator_gainprm[:, 0] /= 1000  # kp 0.3 and 3, kv 0.03 and 0.3
    stiff.actuator_biasprm[:, 1:3] /= 1000
    free, held = choose_integration(stiff), choose_integration(stiff, held_control=True)
    assert free.integrator == held.integrator == "RK4"
    assert held.substeps > free.substeps
    assert held.stability <= RK4_HELD_BOUND < free.stability <= RK4_BOUND


# STIFF_ARM with a softer wrist servo (kp 30, kv 3 on 1e-3 kg m^2, |lambda| ~ 3e3 1/s): a
# held control needs 124 RK4 substeps, over the unforced ceiling, where the cost alone picks
# implicitfast (199 substeps, inertia bias h (kv + damping) 3 % of the wrist's inertia).
HELD_ARM = STIFF_ARM.replace('kp="3000" kv="300"', 'kp="30" kv="3"')


@pytest.mark.slow
def test_held_control_keeps_rk4_past_the_unforced_ceiling(monkeypatch):
    system = MJCFSystem(HELD_ARM)
    model = system.mj_model()
    choice = choose_integration(model, held_control=True)
    assert choice.integrator == "RK4" and choice.stability <= RK4_HELD_BOUND
    assert RK4_MAX_SUBSTEPS < choice.substeps <= RK4_HELD_MAX_SUBSTEPS
    assert choose_integration(model).substeps <= RK4_MAX_SUBSTEPS  # the same stiffness
    data = generate_dataset(system, n_trajectories=1, duration=1.5, seed=0, progress=False)
    assert (data.metadata["integrator"], data.metadata["substeps"]) == ("RK4", choice.substeps)
    # the recorded velocities change as MuJoCo's continuous accelerations say
    faithful = np.abs(_velocity_gain(data.trajectories[0]) - 1).max()
    assert faithful < 1e-3
    # at the unforced ceiling the cheaper implicit step is taken; its inertia bias
    # h (kv + damping) slows the light wrist's velocity changes by about 1 %
    monkeypatch.setattr(integration, "RK4_HELD_MAX_SUBSTEPS", RK4_MAX_SUBSTEPS)
    biased = generate_dataset(system, n_trajectories=1, duration=1.5, seed=0, progress=False)
    assert biased.metadata["integrator"] == "implicitfast"
    assert np.abs(_velocity_gain(biased.trajectories[0]) - 1).max() > max(5e-3, 10 * faithful)
