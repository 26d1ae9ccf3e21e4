"""Closed-loop validation of servo-driven systems: the MJCF's actuator law against MuJoCo's
``qfrc_actuator``, simulation under a feedback law, and validation verdicts on a servo arm
(the exact model passes, a wrong inertia fails)."""

import copy

import mujoco
import numpy as np
import pytest

import pysindy_xl as px
from pysindy_xl.dynamics import CatalogDynamics
from pysindy_xl.mujoco import (
    DoublePendulum,
    MJCFSystem,
    SumOfSinusoids,
    actuator_law,
    generate_dataset,
    kinematic_catalog,
    validate_model,
    validation_trajectory,
)
from pysindy_xl.simulation.generate import actuator_force_function

# Every supported kind of actuator, two on one joint, clamps on controls, forces and the joint.
ACTUATED = """
<mujoco><option gravity="0 0 -9.81"><flag contact="disable"/></option><worldbody>
<body pos="0 0 1"><joint name="a" axis="0 1 0" armature="0.02" damping="0.3"
                         actuatorfrcrange="-6 6"/>
<inertial pos="0.2 0 0" mass="1" diaginertia="0.01 0.01 0.01"/>
<body pos="0.4 0 0"><joint name="b" axis="0 1 0" armature="0.01" damping="0.1"/>
<inertial pos="0.15 0 0" mass="0.5" diaginertia="0.005 0.005 0.005"/>
<body pos="0.3 0 0"><joint name="c" type="slide" axis="1 0 0" damping="0.2"/>
<inertial pos="0.05 0 0" mass="0.3" diaginertia="0.001 0.001 0.001"/>
</body></body></body></worldbody>
<actuator>
  <position joint="a" kp="40" kv="3" ctrlrange="-1 1" forcerange="-5 5" gear="2"/>
  <motor joint="a" gear="0.5" ctrlrange="-2 2"/>
  <velocity joint="b" kv="4" forcerange="-3 3"/>
  <general joint="c" gaintype="affine" gainprm="2 0.5 0.3" biastype="affine"
           biasprm="0.1 -20 -1.5" ctrlrange="-1 1"/>
</actuator></mujoco>
"""

SERVO_ARM = """
<mujoco model="servo_arm">
  <compiler angle="radian"/>
  <option gravity="0 0 -9.81" timestep="0.002" integrator="implicitfast">
    <flag contact="disable"/>
  </option>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" axis="0 1 0" armature="0.02" damping="0.3" range="-2 2"/>
      <inertial pos="0.05 0.01 -0.3" mass="1.2" fullinertia="0.05 0.04 0.02 0.003 -0.002 0.001"/>
      <body name="fore" pos="0.02 0 -0.6">
        <joint name="elbow" axis="0.1 1 0" armature="0.01" damping="0.1" range="-2 2"/>
        <inertial pos="-0.03 0.02 -0.25" mass="0.8"
                  fullinertia="0.03 0.035 0.01 -0.002 0.001 0.003"/>
        <body name="hand" pos="0 0.01 -0.5">
          <joint name="wrist" axis="1 0 0.2" armature="0.005" damping="0.05" range="-2 2"/>
          <inertial pos="0.04 -0.01 -0.08" mass="0.4"
                    fullinertia="0.004 0.005 0.002 0.0003 -0.0002 0.0004"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position joint="shoulder" kp="60" kv="4" ctrlrange="-1.5 1.5" forcerange="-25 25"/>
    <position joint="elbow" kp="30" kv="2" ctrlrange="-1.5 1.5"/>
    <position joint="wrist" kp="8" kv="0.4" ctrlrange="-1.5 1.5"/>
  </actuator>
</mujoco>
"""


class ServoDoublePendulum(DoublePendulum):
    """The double pendulum (absolute angles, relative second hinge) with position servos."""

    def xml(self):
        return super().xml().replace(
            '<motor name="hinge1_motor" joint="hinge1" gear="1" ctrllimited="false"/>',
            '<position name="s1" joint="hinge1" kp="30" kv="2" forcerange="-8 8"/>').replace(
            '<motor name="hinge2_motor" joint="hinge2" gear="1" ctrllimited="false"/>',
            '<position name="s2" joint="hinge2" kp="10" kv="1" ctrlrange="-0.5 0.5" '
            'gear="1.5"/>')


@pytest.mark.parametrize("system", [MJCFSystem(ACTUATED), ServoDoublePendulum()],
                         ids=["every-actuator", "servo-double-pendulum"])
@pytest.mark.parametrize("force_input", ["tau", "u"])
def test_actuator_law_is_mujocos_qfrc_actuator(system, force_input):
    model = system.mj_model()
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    signals = SumOfSinusoids(2 * rng.normal(size=(model.nu, 3)),
                             rng.uniform(0.1, 2, (model.nu, 3)),
                             rng.uniform(0, 6, (model.nu, 3)), offsets=rng.normal(size=model.nu))
    law = actuator_law(system, signals, force_input)
    assert law.state_dependent
    n_states = 100
    t = rng.uniform(0, 5, n_states)
    q, qd = rng.normal(size=(n_states, system.n)), 3 * rng.normal(size=(n_states, system.n))
    forces = law(t, q, qd)  # all states at once
    reference = np.empty_like(forces)
    clamped = 0
    for k in range(n_states):
        data.qpos[:], data.qvel[:] = system.from_generalized(q[k], qd[k])
        data.ctrl[:] = signals(t[k])
        mujoco.mj_forward(model, data)
        joint = data.qfrc_actuator
        reference[k] = joint if force_input == "u" else system.force_matrix() @ joint
        limited = model.actuator_forcelimited.astype(bool)
        clamped += np.any(np.isclose(np.abs(data.actuator_force[limited]),
                                     model.actuator_forcerange[limited, 1]))
        np.testing.assert_allclose(law(t[k], q[k], qd[k]), forces[k], rtol=1e-12, atol=1e-12)
    assert np.abs(forces - reference).max() <= 1e-10 * np.abs(reference).max()
    assert clamped > 10  # the force limits act on many of the states
    assert np.any(np.abs(signals(t)) > 1)  # and the control ranges


def test_actuator_law_of_motors_is_a_function_of_time():
    signals = SumOfSinusoids([[1.0], [0.0]], [[1.0], [1.0]], [[0.0], [0.0]])
    law = actuator_law("cart-pole", signals)
    assert not law.state_dependent
    np.testing.assert_allclose(law(np.array([0.25, 0.5])), [[1.0, 0.0], [0.0, 0.0]], atol=1e-15)
    np.testing.assert_array_equal(actuator_force_function("cart-pole", signals)(0.25), [1, 0])
    # servos: no function of time alone; zero controls by default
    servo = ServoDoublePendulum()
    assert actuator_force_function(servo, signals) is None
    assert actuator_law(servo).signals is None
    np.testing.assert_allclose(actuator_law(servo)(0.0, [0.0, 0.0], [0.0, 0.0]), 0.0)
    with pytest.raises(ValueError, match="q, qd"):
        actuator_law(servo)(0.0)
    with pytest.raises(ValueError, match="force_input"):
        actuator_law(servo, force_input="ctrl")
    with pytest.raises(TypeError, match="signals"):
        actuator_law(servo, signals=[1.0, 2.0])
    muscle = MJCFSystem(ACTUATED.replace('<velocity joint="b" kv="4" forcerange="-3 3"/>',
                                         '<general joint="b" dyntype="filter" dynprm="0.1"/>'))
    assert actuator_law(muscle) is None  # activation dynamics: not a law of the state


def test_simulate_with_a_feedback_law():
    c = px.Coordinates(["x"])
    library = px.CatalogRepartition([px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])])
    dynamics = CatalogDynamics(library.fit(), np.array([-1.0, 0.5, -0.5]))  # x'' + x = u
    t = np.linspace(0.0, 8.0, 81)
    pd = lambda s, q, qd: 9.0 * (0.5 - q) - 6.0 * qd + 0.5  # noqa: E731
    states = dynamics.simulate([0.0, 0.0], t, feedback=pd)
    # x'' + 6 x' + 10 x = 5: critically damped around 0.5 with the spring's force fed forward
    expected = 0.5 - 0.5 * np.exp(-3 * t) * (np.cos(t) + 3 * np.sin(t))
    np.testing.assert_allclose(states[:, 0], expected, atol=1e-6)
    # u and feedback add up
    both = dynamics.simulate([0.0, 0.0], t, u=lambda s: np.array([0.5]),
                             feedback=lambda s, q, qd: 9.0 * (0.5 - q) - 6.0 * qd)
    np.testing.assert_allclose(both, states, atol=1e-7)
    with pytest.raises(ValueError, match=r"feedback: .*shape \(1,\)"):
        dynamics.simulate([0.0, 0.0], t, feedback=lambda s, q, qd: np.zeros(2))
    with pytest.raises(TypeError, match="feedback"):
        dynamics.simulate([0.0, 0.0], t, feedback=np.zeros(1))
    with pytest.raises(ValueError, match="feedback"):
        dynamics.simulate([0.0, 0.0], t, feedback=lambda s, q, qd: np.full(1, np.nan))


@pytest.fixture(scope="module")
def servo_arm():
    system = MJCFSystem(SERVO_ARM)
    data = generate_dataset(system, n_trajectories=2, duration=2.0, seed=0, sample_every=4,
                            progress=False)
    assert data.metadata["integrator"] == "RK4"  # implicitfast would bias the inertias
    model = px.XLSINDy(kinematic_catalog(system).library(),
                       px.ExplicitOptimizer(threshold=1e-8))
    return system, model.fit(**data.fit_arguments(forces="tau"))


@pytest.fixture(scope="module")
def exact_closed_loop(servo_arm):
    """A fresh reference of the servo arm and the exact model's closed-loop validation on it
    (one simulation, shared by the tests that compare against it)."""
    system, model = servo_arm
    reference = validation_trajectory(system, duration=2.0, seed=1)
    return reference, validate_model(model, system, trajectory=reference)


def test_exact_servo_arm_is_valid_in_closed_loop(servo_arm, exact_closed_loop):
    system, model = servo_arm
    reference, closed = exact_closed_loop
    assert closed.drive == "closed-loop" and closed.valid
    assert closed.position_rmse < 1e-5 and closed.force_error < 1e-4
    summary = closed.to_dict()
    assert summary["drive"] == "closed-loop" and summary["force_error"] == closed.force_error
    # replaying the servo forces open loop compares two experiments: far worse, same model
    replay = validate_model(model, system, trajectory=reference, drive="open-loop")
    assert replay.drive == "open-loop" and replay.force_error is None
    assert replay.position_rmse > 100 * closed.position_rmse
    # unforced: the servos hold their zero reference, in MuJoCo and in the model
    still = validate_model(model, system, duration=1.0, seed=2, forcing="implicit")
    assert still.drive == "closed-loop" and still.valid and still.position_rmse < 1e-5


def test_wrong_inertia_fails_closed_loop_validation(servo_arm, exact_closed_loop):
    system, model = servo_arm
    wrong = copy.deepcopy(model)
    inertia = wrong.get_feature_names().index("L[0.5*shoulder_dot**2]")
    wrong.coef_[inertia] *= 1.3
    wrong._build_dynamics()
    reference, exact = exact_closed_loop
    result = validate_model(wrong, system, trajectory=reference)
    assert result.drive == "closed-loop" and not result.valid and result.failure is None
    assert result.force_error > 0.05  # the servos push differently to track the reference
    assert result.position_rmse > 1000 * exact.position_rmse
    # the positions alone stay within the divergence bound: the servos hide the error there
    assert result.divergence_time is None
    loose = validate_model(wrong, system, trajectory=reference, force_bound=1.0)
    assert loose.valid


def test_drive_errors(servo_arm):
    system, model = servo_arm
    reference = validation_trajectory(system, duration=0.2, seed=1)
    with pytest.raises(ValueError, match="drive"):
        validate_model(model, system, trajectory=reference, drive="servo")
    with pytest.raises(ValueError, match="force_bound"):
        validate_model(model, system, trajectory=reference, force_bound=0)
    reference.info.pop("signals")
    with pytest.raises(ValueError, match="drive: closed loop .*no controls"):
        validate_model(model, system, trajectory=reference, drive="closed-loop")
    assert validate_model(model, system, trajectory=reference).drive == "open-loop"


def test_mujoco_and_model_simulators_agree(servo_arm, exact_closed_loop):
    """MuJoCo stepping the identified parameters and scipy integrating the identified
    equations are the same closed loop: the exact model and a wrong one get the same
    trajectories and verdicts from both."""
    system, model = servo_arm
    reference, fast = exact_closed_loop
    assert fast.simulator == "mujoco" and fast.to_dict()["simulator"] == "mujoco"
    slow = validate_model(model, system, trajectory=reference, simulator="model")
    assert slow.simulator == "model" and slow.valid and fast.valid
    n = system.n
    assert np.abs(fast.prediction[:, :n] - slow.prediction[:, :n]).max() < 1e-5
    assert np.abs(fast.prediction[:, n:] - slow.prediction[:, n:]).max() < 1e-3
    wrong = copy.deepcopy(model)
    wrong.coef_[wrong.get_feature_names().index("L[0.5*shoulder_dot**2]")] *= 1.3
    wrong._build_dynamics()
    results = [validate_model(wrong, system, trajectory=reference, simulator=simulator)
               for simulator in ("mujoco", "model")]
    assert [r.simulator for r in results] == ["mujoco", "model"]
    assert not any(r.valid for r in results)
    gap = np.abs(results[0].prediction - results[1].prediction)
    assert gap[:, :n].max() < 1e-4 * np.abs(reference.q).max()
    assert results[0].force_error == pytest.approx(results[1].force_error, rel=1e-3)


def test_models_mujoco_cannot_state_fall_back(servo_arm):
    """A model whose equations MuJoCo does not reproduce (here: equations that no longer
    match its coefficients) is integrated by its own simulator; asking for MuJoCo is an
    error."""
    from pysindy_xl.export.mjcf import identified_mj_model

    system, model = servo_arm
    reference = validation_trajectory(system, duration=0.2, seed=1)
    stale = copy.deepcopy(model)  # coefficients changed, equations not rebuilt: they differ
    stale.coef_[stale.get_feature_names().index("L[0.5*shoulder_dot**2]")] *= 1.3
    mj_model, reason = identified_mj_model(stale, system)
    assert mj_model is None and "differs from the model" in reason
    assert validate_model(stale, system, trajectory=reference).simulator == "model"
    with pytest.raises(ValueError, match="simulator: MuJoCo cannot step this model"):
        validate_model(stale, system, trajectory=reference, simulator="mujoco")
    with pytest.raises(ValueError, match="simulator: expected"):
        validate_model(model, system, trajectory=reference, simulator="jax")
    # an indefinite mass matrix: MuJoCo cannot factor it, the model is not stepped there
    indefinite = copy.deepcopy(model)
    indefinite.coef_[indefinite.get_feature_names().index("L[0.5*wrist_dot**2]")] -= 1.0
    indefinite._build_dynamics()
    mj_model, reason = identified_mj_model(indefinite, system)
    assert mj_model is None and "not positive definite" in reason
