"""Computed-torque tracking on the MuJoCo double pendulum (both joints driven by motors):
the model's inverse dynamics as feedforward cut the PD law's tracking error many times over.

Ground truth: MuJoCo is the plant; the model is the system's Lagrangian equations (sympy)."""

import numpy as np
import pytest
import sympy as sp

import pysindy_xl as px
from pysindy_xl.control.computed_torque import ComputedTorque
from pysindy_xl.control.plant import MuJoCoPlant
from pysindy_xl.mujoco import get_system


def _reference(t):
    w = np.array([2.0 * np.pi * 0.8, 2.0 * np.pi * 1.1])
    a = np.array([0.8, 0.6])
    return a * np.sin(w * t), a * w * np.cos(w * t), -a * w ** 2 * np.sin(w * t)


def _rms_error(controller):
    plant = MuJoCoPlant("double-pendulum", ["theta1", "theta2"], force_limit=200.0,
                        control_dt=0.002)
    q0, qd0, _ = _reference(0.0)
    plant.reset(q0, qd0)
    episode = plant.run(controller, 3.0)
    q_ref = np.stack([_reference(t)[0] for t in episode.t])
    return float(np.sqrt(np.mean((episode.q - q_ref) ** 2)))


@pytest.fixture(scope="module")
def true_model():
    system = get_system("double-pendulum")
    return px.MassMatrixDynamics(system.coords, [
        e - tau for e, tau in zip(system.equations_of_motion(), system.coords.tau, strict=True)])


@pytest.mark.parametrize("mode", ["feedforward", "computed-torque"])
def test_identified_feedforward_beats_pd_alone(true_model, mode):
    kp, kd = (30.0, 3.0) if mode == "feedforward" else (100.0, 20.0)
    pd = _rms_error(ComputedTorque(None, _reference, kp=30.0, kd=3.0, n=2))
    model = _rms_error(ComputedTorque(true_model, _reference, kp=kp, kd=kd, n=2, mode=mode))
    assert model < pd / 5


def test_tabulated_feedforward_matches_the_model_along_the_reference(true_model):
    times = np.linspace(0.0, 1.0, 501)
    tabulated = ComputedTorque(true_model, _reference, kp=5.0, kd=1.0, n=2,
                               feedforward_times=times)
    direct = ComputedTorque(true_model, _reference, kp=5.0, kd=1.0, n=2)
    state = np.array([0.1, -0.2, 0.3, 0.0])
    for t in (0.0, 0.5, 0.998):  # on the grid
        np.testing.assert_allclose(tabulated(state, t), direct(state, t), rtol=1e-9)


def test_bad_gains_and_modes_are_refused(true_model):
    with pytest.raises(ValueError, match="kp: expected a gain >= 0 or 2"):
        ComputedTorque(true_model, _reference, kp=[1.0, 2.0, 3.0], kd=1.0, n=2)
    with pytest.raises(ValueError, match="mode: expected one of"):
        ComputedTorque(true_model, _reference, kp=1.0, kd=1.0, n=2, mode="pid")
    with pytest.raises(TypeError, match="model: expected a fitted model"):
        ComputedTorque(object(), _reference, kp=1.0, kd=1.0, n=2)


def test_min_speed_raises_the_reference_speeds_keeping_their_sign():
    c = px.Coordinates(["x"])
    # a force that reads the velocity: tau = x'' + x' (unit mass, unit damping)
    model = px.MassMatrixDynamics(c, [c.qdd[0] + c.qd[0] - c.tau[0]])
    speeds = iter([0.0, 0.05, -0.05, 0.3, -0.3])

    def reference(t):
        return np.zeros(1), np.array([next(speeds)]), np.zeros(1)

    control = ComputedTorque(model, reference, kp=0.0, kd=0.0, n=1, min_speed=0.1)
    state = np.zeros(2)
    got = [float(control(state, 0.0)[0]) for _ in range(5)]
    # the feedforward reads the speeds 0.1, 0.1, -0.1, 0.3, -0.3 (the PD part is off)
    np.testing.assert_allclose(got, [0.1, 0.1, -0.1, 0.3, -0.3], rtol=1e-12)
    with pytest.raises(ValueError, match="min_speed: expected a gain >= 0 or 1"):
        ComputedTorque(model, reference, kp=0.0, kd=0.0, n=1, min_speed=[0.1, 0.2])


_DRY_PENDULUM = """<mujoco><option timestep="0.002"/><worldbody><body>
  <joint name="a" type="hinge" axis="0 1 0" armature="0.1" damping="0.2" frictionloss="0.5"/>
  <inertial pos="0 0 -0.5" mass="1" diaginertia="0.01 0.01 0.01"/>
</body></worldbody><actuator><motor joint="a"/></actuator></mujoco>"""


def test_sliding_feedforward_of_mujocos_dry_friction_against_mj_inverse():
    """A pendulum with MuJoCo's dry friction, modelled with its regularized law (first-order
    lead): where the joint slides the model's forces are MuJoCo's inverse dynamics; through a
    reversal sampled inside the sticking zone the lead is an inertia spike ``F tau / s``,
    which ``min_speed`` removes (the force then stays within the friction jump ``2 F``).
    Ground truth: ``mj_inverse``."""
    from pysindy_xl.mujoco import MJCFSystem, import_mujoco
    from pysindy_xl.mujoco.systems.friction import dry_friction_scales
    from pysindy_xl.physical.friction import regularized_dry_friction
    mujoco = import_mujoco()
    system = MJCFSystem(_DRY_PENDULUM)
    mj_model = system.mj_model()
    data = mujoco.MjData(mj_model)
    scale, lead = (float(v[0]) for v in dry_friction_scales(mj_model))
    c = system.coords
    q, qd, qdd = c.q[0], c.qd[0], c.qdd[0]
    friction = 0.5 * regularized_dry_friction(qd, qdd, scale, lead)
    # inertia about the hinge: Iyy + m l^2 + armature; gravity m g l sin(q); damping 0.2
    model = px.MassMatrixDynamics(c, [0.36 * qdd + 0.2 * qd + 0.5 * 9.81 * sp.sin(q)
                                      + friction - c.tau[0]])

    def inverse(position, velocity, acceleration):
        data.qpos[:], data.qvel[:], data.qacc[:] = position, velocity, acceleration
        mujoco.mj_inverse(mj_model, data)
        return float(data.qfrc_inverse[0])

    omega, amplitude = 2 * np.pi, 0.5

    def reference(t):
        return (np.array([amplitude * np.sin(omega * t)]),
                np.array([amplitude * omega * np.cos(omega * t)]),
                np.array([-amplitude * omega ** 2 * np.sin(omega * t)]))

    sliding = ComputedTorque(model, reference, kp=0.0, kd=0.0, n=1)
    for t in (0.05, 0.1, 0.4, 0.6, 0.9):  # |qd| far above tau |qdd| + s: sliding
        want = inverse(*(part[0] for part in reference(t)))
        assert float(sliding(np.zeros(2), t)[0]) == pytest.approx(want, abs=1e-9)
    times = np.array([0.0, 0.25, 0.5])  # 0.25: a reversal (qd = 0), inside the zone
    state = np.zeros(2)
    pointwise = ComputedTorque(model, reference, kp=0.0, kd=0.0, n=1, feedforward_times=times)
    floored = ComputedTorque(model, reference, kp=0.0, kd=0.0, n=1, feedforward_times=times,
                             min_speed=2 * scale)
    want = inverse(*(part[0] for part in reference(0.25)))
    spike = abs(0.5 * lead / scale * amplitude * omega ** 2)
    assert spike > 20 * 0.5  # the zone's inertia is large: the test can tell
    assert abs(float(pointwise(state, 0.25)[0]) - want) > spike / 2
    # within the friction jump, plus the damping of the raised speed
    assert abs(float(floored(state, 0.25)[0]) - want) <= 2 * 0.5 + 0.2 * 2 * scale + 1e-9
