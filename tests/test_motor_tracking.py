"""Servo starts and torque-motor tracking: a stiff, force-limited servo on a light link started
where its force vanishes follows the continuous equations (scipy) instead of chattering between
its force limits; an arm whose plain motors cannot hold it against gravity is tracked inside
its joint ranges, its recorded torques are the controller's and MuJoCo's inverse dynamics, and
its closed-loop validation uses the same controller."""

import copy

import mujoco
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import pysindy_xl as px
from pysindy_xl.mujoco import (
    MJCFSystem,
    SumOfSinusoids,
    generate_dataset,
    kinematic_catalog,
    simulate_trajectory,
    start_on_reference,
    validate_model,
    validation_trajectory,
)
from pysindy_xl.simulation.generate import ConstraintWarning
from pysindy_xl.simulation.signals import motor_tracking

# a wrist of a published arm: kp 800, kv 80 and a 20 N m force limit on 1.4e-4 kg m^2
WRIST = """
<mujoco><option timestep="0.002" integrator="implicitfast" gravity="0 0 0"/>
  <worldbody><body><joint name="roll" axis="0 0 1" damping="2"/>
    <inertial pos="0 0 0" mass="0.2" diaginertia="1.4e-4 1.4e-4 1.4e-4"/></body></worldbody>
  <actuator><position joint="roll" kp="800" kv="80" forcerange="-20 20"/></actuator>
</mujoco>
"""


def _continuous_wrist(signals, q0, qd0, t):
    """The wrist's continuous equations, ``m qdd = clip(kp (ref - q) - kv qd) - d qd``."""
    def rhs(time, x):
        force = np.clip(800 * (signals(time)[0] - x[0]) - 80 * x[1], -20, 20)
        return [x[1], (force - 2 * x[1]) / 1.4e-4]

    return solve_ivp(rhs, (t[0], t[-1]), [q0, qd0], method="Radau", t_eval=t, rtol=1e-10,
                     atol=1e-12, max_step=1e-3).y.T


def test_servo_start_on_a_moving_reference_follows_the_continuous_equations():
    system = MJCFSystem(WRIST)
    signals = SumOfSinusoids([[0.2]], [[1 / np.pi]], [[0.0]])  # 0.2 sin(2 t): 0.4 rad/s at 0
    q0, qd0 = start_on_reference(system, signals, [0.3], [0.0])
    np.testing.assert_allclose([q0[0], qd0[0]], [-80 * 0.4 / 800, 0.4], atol=1e-6)
    # implicitfast at 155 substeps: kv h / m = 7.4, unstable whenever the force is clamped
    run = simulate_trajectory(system, 0.2, signals, q0, qd0, sample_every=5,
                              integrator="implicitfast", substeps=155)
    truth = _continuous_wrist(signals, q0[0], qd0[0], run.t)
    assert np.abs(run.q[:, 0] - truth[:, 0]).max() < 1e-6
    assert np.abs(run.qd[:, 0] - truth[:, 1]).max() < 1e-3
    assert np.abs(run.u).max() < 5  # far from the 20 N m limit
    # on the reference itself at its rate the servo asks kv * 0.4 = 32 N m: clamped, the
    # time stepping chatters between the limits while the continuous solution settles
    chatter = simulate_trajectory(system, 0.2, signals, [0.0], [0.4], sample_every=5,
                                  integrator="implicitfast", substeps=155)
    truth = _continuous_wrist(signals, 0.0, 0.4, chatter.t)
    assert np.abs(chatter.qd[:, 0] - truth[:, 1]).max() > 0.1


# a two-link arm held out horizontally by plain torque motors (no ctrlrange): gravity's
# 5 N m at the shoulder outweighs the 1 N m random torques
MOTOR_ARM = """
<mujoco><compiler angle="radian"/>
  <option timestep="0.002" gravity="0 0 -9.81"><flag contact="disable"/></option>
  <worldbody><body name="upper">
    <joint name="shoulder" axis="0 1 0" damping="0.3" armature="0.01" range="-1 1"/>
    <inertial pos="0.25 0 0.01" mass="1.2" diaginertia="0.01 0.02 0.02"/>
    <body name="fore" pos="0.5 0 0">
      <joint name="elbow" axis="0 1 0" damping="0.1" armature="0.005" range="-1.5 1.5"/>
      <inertial pos="0.2 0.01 0" mass="0.6" diaginertia="0.004 0.008 0.008"/>
    </body></body></worldbody>
  <actuator><motor joint="shoulder"/><motor joint="elbow"/></actuator>
</mujoco>
"""


@pytest.fixture(scope="module")
def tracked_arm():
    system = MJCFSystem(MOTOR_ARM)
    data = generate_dataset(system, n_trajectories=2, duration=3.0, seed=0, sample_every=4,
                            progress=False)
    model = px.XLSINDy(kinematic_catalog(system).library(),
                       px.ExplicitOptimizer(threshold=1e-8))
    return system, data, model.fit(**data.fit_arguments(forces="tau"))


def test_motors_that_cannot_hold_the_arm_track_inside_the_ranges(tracked_arm):
    system, data, _ = tracked_arm
    controller = data.metadata["tracking"]
    assert controller["actuators"] == [0, 1]
    assert data.metadata["constraints"]["active_fraction"] == 0.0
    model = system.mj_model()  # the arm as authored: motors
    state = mujoco.MjData(model)
    for trajectory in data.trajectories:
        assert trajectory.info["tracking"] == controller
        assert np.ptp(trajectory.q, axis=0).min() > 0.3  # excited, not parked
        reference = SumOfSinusoids.from_dict(trajectory.info["signals"])(trajectory.t)
        kp, kv = np.array(controller["kp"]), np.array(controller["kv"])
        np.testing.assert_allclose(trajectory.u, kp * (reference - trajectory.q)
                                   - kv * trajectory.qd, atol=1e-9)
        # the recorded torques drive the authored arm: its inverse dynamics give them back
        for k in range(0, trajectory.n_samples, 50):
            state.qpos[:], state.qvel[:] = trajectory.q[k], trajectory.qd[k]
            state.qacc[:] = trajectory.qdd[k]
            mujoco.mj_inverse(model, state)
            np.testing.assert_allclose(state.qfrc_inverse, trajectory.u[k], atol=1e-8)
    # the same random torques open loop: the arm falls onto its stops
    with pytest.warns(ConstraintWarning, match="shoulder"):
        fallen = generate_dataset(system, n_trajectories=1, duration=3.0, seed=0,
                                  sample_every=4, control="open-loop", backoff=False,
                                  progress=False)
    assert fallen.metadata["tracking"] is None
    assert fallen.metadata["constraints"]["active_fraction"] > 0.5
    with pytest.raises(ValueError, match="control"):
        motor_tracking(system, model, control="pd")
    with pytest.raises(ValueError, match="control: 'tracking'"):
        motor_tracking(MJCFSystem(WRIST), MJCFSystem(WRIST).mj_model(), control="tracking")


def test_tracked_arm_is_validated_under_the_same_controller(tracked_arm):
    system, _, model = tracked_arm
    reference = validation_trajectory(system, duration=0.6, seed=1)
    assert reference.info["tracking"]["actuators"] == [0, 1]
    fast = validate_model(model, system, trajectory=reference)
    assert fast.drive == "closed-loop" and fast.simulator == "mujoco"
    assert fast.valid and fast.force_error < 1e-4 and fast.position_rmse < 1e-5
    slow = validate_model(model, system, trajectory=reference, simulator="model")
    assert slow.valid and np.abs(slow.prediction - fast.prediction)[:, :2].max() < 1e-5
    wrong = copy.deepcopy(model)  # gravity 20 % too strong
    gravity = [k for k, name in enumerate(wrong.get_feature_names()) if "9.81" in name]
    wrong.coef_[gravity] *= 1.2
    wrong._build_dynamics()
    result = validate_model(wrong, system, trajectory=reference)
    assert result.drive == "closed-loop" and not result.valid and result.force_error > 0.05
