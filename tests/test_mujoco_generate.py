"""Data generation: forcing modes, reproducibility, noise levels, consistency of the samples."""

import numpy as np
import pytest

from pysindy_xl.data import add_noise
from pysindy_xl.mujoco import (
    CartPole,
    DoublePendulum,
    SumOfSinusoids,
    generate_dataset,
    simulate_trajectory,
)


@pytest.mark.parametrize("noise_model", ["positions", "all"])
def test_same_seed_same_data_other_seed_other_data(noise_model):
    kwargs = dict(n_trajectories=2, duration=0.5, noise=0.01, noise_model=noise_model,
                  progress=False)
    a = generate_dataset("cart-pole", seed=7, **kwargs)
    b = generate_dataset("cart-pole", seed=7, **kwargs)
    c = generate_dataset("cart-pole", seed=8, **kwargs)
    keys = ("q", "tau", "u") if noise_model == "positions" else ("q", "qd", "qdd", "tau", "u")
    assert a.has("qdd") == (noise_model == "all")
    for ta, tb, tc in zip(a.trajectories, b.trajectories, c.trajectories, strict=True):
        for key in keys:
            np.testing.assert_array_equal(getattr(ta, key), getattr(tb, key))
        assert not np.allclose(ta.q, tc.q)
    assert not np.allclose(a.trajectories[0].q, a.trajectories[1].q)


def test_forcing_modes():
    explicit = generate_dataset("double-pendulum", n_trajectories=1, duration=1.0, seed=0,
                                progress=False).trajectories[0]
    assert np.all(np.abs(explicit.u).max(axis=0) > 0.1)
    implicit = generate_dataset("double-pendulum", n_trajectories=1, duration=1.0, seed=0,
                                forcing="implicit", progress=False).trajectories[0]
    assert np.all(implicit.u == 0) and np.all(implicit.tau == 0)
    assert np.abs(implicit.qd[0]).max() > 0  # random initial condition
    # mixed on the second (relative) hinge only: generalized force -u on theta1, +u on theta2
    mixed = generate_dataset("double-pendulum", n_trajectories=1, duration=1.0, seed=0,
                             forcing="mixed", actuators=["hinge2"],
                             progress=False).trajectories[0]
    assert np.all(mixed.u[:, 0] == 0) and np.abs(mixed.u[:, 1]).max() > 0.1
    np.testing.assert_allclose(mixed.tau[:, 0], -mixed.u[:, 1])
    np.testing.assert_allclose(mixed.tau[:, 1], mixed.u[:, 1])
    default = generate_dataset(CartPole(), n_trajectories=1, duration=0.5, seed=0,
                               forcing="mixed", progress=False).trajectories[0]
    assert np.abs(default.u[:, 0]).max() > 0 and np.all(default.u[:, 1] == 0)


def test_samples_are_consistent_time_series():
    tr = generate_dataset("cart-double-pendulum", n_trajectories=1, duration=2.0, seed=2,
                          progress=False).trajectories[0]
    dt = tr.t[1] - tr.t[0]
    assert dt == pytest.approx(1e-3)
    # velocities are the derivative of positions, accelerations that of velocities
    np.testing.assert_allclose(np.gradient(tr.q, dt, axis=0)[1:-1], tr.qd[1:-1],
                               atol=1e-4 * np.abs(tr.qd).max())
    np.testing.assert_allclose(np.gradient(tr.qd, dt, axis=0)[1:-1], tr.qdd[1:-1],
                               atol=1e-3 * np.abs(tr.qdd).max())


def test_sample_every_and_duration():
    tr = generate_dataset("cart-pole", n_trajectories=1, duration=1.0, seed=0, sample_every=10,
                          progress=False).trajectories[0]
    assert tr.q.shape == (101, 2)
    np.testing.assert_allclose(np.diff(tr.t), 0.01)


def test_noise_levels_are_relative_to_each_column():
    rng = np.random.default_rng(0)
    clean = simulate_trajectory("double-pendulum", 5.0, q0=[1.0, -0.5],
                                signals=SumOfSinusoids.random([2.0, 1.0], rng))
    noisy = add_noise(clean, {"q": 0.1, "qdd": 0.02}, np.random.default_rng(1),
                      DoublePendulum().force_matrix())
    ratio = (noisy.q - clean.q).std(axis=0) / clean.q.std(axis=0)
    np.testing.assert_allclose(ratio, 0.1, rtol=0.05)
    ratio = (noisy.qdd - clean.qdd).std(axis=0) / clean.qdd.std(axis=0)
    np.testing.assert_allclose(ratio, 0.02, rtol=0.05)
    np.testing.assert_array_equal(noisy.qd, clean.qd)
    np.testing.assert_array_equal(noisy.tau, clean.tau)
    forced = add_noise(clean, {"tau": 0.1}, np.random.default_rng(1),
                       DoublePendulum().force_matrix())
    np.testing.assert_allclose(forced.tau, forced.u @ DoublePendulum().force_matrix().T)


def test_sum_of_sinusoids():
    rng = np.random.default_rng(0)
    signal = SumOfSinusoids.random([3.0, 0.0], rng, n_components=4, max_frequency=2.0)
    values = signal(np.linspace(0, 20, 2001))
    assert values.shape == (2001, 2)
    assert np.abs(values[:, 0]).max() <= 3.0 and np.abs(values[:, 0]).max() > 1.0
    assert np.all(values[:, 1] == 0)
    assert signal(0.5).shape == (2,)
    again = SumOfSinusoids.from_dict(signal.to_dict())
    np.testing.assert_array_equal(again(1.3), signal(1.3))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(forcing="sideways"), "forcing"),
        (dict(forcing="mixed", actuators=["elbow"]), "actuators"),
        (dict(forcing="explicit", actuators=["slider"]), "actuators"),
        (dict(noise=-0.1), "noise"),
        (dict(noise={"velocity": 0.1}), "noise"),
        (dict(n_trajectories=0), "n_trajectories"),
        (dict(duration=-1.0), "duration"),
        (dict(sample_every=0), "sample_every"),
    ],
)
def test_generation_errors(kwargs, match):
    kwargs = {"duration": 0.1, "progress": False, **kwargs}
    with pytest.raises(ValueError, match=match):
        generate_dataset("cart-pole", **kwargs)


def test_model_without_actuator_only_implicit():
    xml = """<mujoco><option timestep="0.002"/><worldbody><body>
      <joint name="a" type="hinge" axis="0 1 0"/>
      <geom type="sphere" size="0.1" pos="0 0 -1" mass="1"/></body></worldbody></mujoco>"""
    from pysindy_xl.mujoco import MJCFSystem

    system = MJCFSystem(xml)
    with pytest.raises(ValueError, match="no actuator"):
        generate_dataset(system, duration=0.1, progress=False)
    data = generate_dataset(system, n_trajectories=1, duration=0.1, forcing="implicit", seed=0,
                            progress=False)
    assert data.trajectories[0].q.shape == (51, 1)


def test_shipped_systems_keep_their_force_amplitudes():
    """Without ctrlrange the forcing peaks at the system's force amplitudes (no back-off)."""
    system = CartPole()
    data = generate_dataset(system, n_trajectories=2, duration=0.2, seed=0, progress=False)
    expected = [system.force_amplitudes[j] for j in system.joint_names]
    for tr in data.trajectories:
        signals = SumOfSinusoids.from_dict(tr.info["signals"])
        np.testing.assert_allclose(signals.amplitudes.sum(axis=1), expected)
        assert "backoff" not in tr.info
    half = generate_dataset(system, n_trajectories=1, duration=0.2, seed=0, amplitude=0.5,
                            progress=False).trajectories[0]
    np.testing.assert_allclose(
        SumOfSinusoids.from_dict(half.info["signals"]).amplitudes.sum(axis=1),
        0.5 * np.array(expected))


SERVO_ARM = """<mujoco model="servo_arm"><option timestep="0.002" integrator="implicitfast"
  gravity="0 0 -9.81"><flag contact="disable"/></option><worldbody>
  <body name="l1"><joint name="j1" type="hinge" axis="0 1 0" damping="0.5" armature="0.01"/>
    <inertial pos="0.1 0 -0.05" mass="1.0" diaginertia="0.01 0.012 0.008"/>
    <body name="l2" pos="0.3 0 0"><joint name="j2" type="hinge" axis="0 1 0" damping="0.3"
      armature="0.01"/><inertial pos="0.1 0 0" mass="0.6" diaginertia="0.005 0.006 0.004"/>
  </body></body></worldbody>
  <actuator><position joint="j1" kp="40" kv="4" ctrlrange="-1 1"/>
    <position joint="j2" kp="20" kv="2" ctrlrange="-1 1"/></actuator></mujoco>"""


def _position_bias(trajectory):
    """Largest gap between the accelerations of the recorded positions (second differences)
    and the continuous accelerations MuJoCo reports, relative to their range."""
    h = trajectory.t[1] - trajectory.t[0]
    differenced = (trajectory.q[2:] - 2 * trajectory.q[1:-1] + trajectory.q[:-2]) / h**2
    return np.abs(differenced - trajectory.qdd[1:-1]).max() / np.ptp(trajectory.qdd)


def test_implicit_steps_are_replaced_where_they_bias_the_positions():
    from pysindy_xl.mujoco import MJCFSystem
    from pysindy_xl.simulation.generate import faithful_integrator

    system = MJCFSystem(SERVO_ARM)
    assert faithful_integrator(system.mj_model()) == "RK4"
    faithful = generate_dataset(system, n_trajectories=1, duration=2.0, seed=1, progress=False)
    authored = generate_dataset(system, n_trajectories=1, duration=2.0, seed=1,
                                integrator="model", progress=False)
    assert faithful.metadata["integrator"] == "RK4"
    assert authored.metadata["integrator"] == "implicitfast"
    # the implicit step's positions disagree with the continuous accelerations by the
    # velocity forces times the step; RK4's only by the differencing error
    assert _position_bias(authored.trajectories[0]) > 10 * _position_bias(
        faithful.trajectories[0])


RK4_SERVO_ARM = """
<mujoco model="servo_arm">
  <option gravity="0 0 -9.81" timestep="0.002" integrator="RK4"><flag contact="disable"/></option>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" damping="0.3"/>
      <inertial pos="0.2 0 0" mass="1.5" diaginertia="0.01 0.03 0.03"/>
      <body name="fore" pos="0.4 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0" damping="0.15"/>
        <inertial pos="0.15 0 0" mass="0.8" diaginertia="0.005 0.01 0.01"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position joint="shoulder" kp="200" kv="4" ctrlrange="-1.5 1.5"/>
    <position joint="elbow" kp="120" kv="2" ctrlrange="-1.5 1.5"/>
  </actuator>
</mujoco>
"""


def test_servo_samples_obey_the_continuous_law():
    """Recorded forces are the servo law under the control of the sample's own instant, and
    positions alone give the joint damping back: a control held from the start of each step
    lags the signal by half a step, which the servos' kp turn into a spurious damping of
    kp * h / 2 (0.2 and 0.12 here, against 0.3 and 0.15)."""
    import pysindy_xl as px
    from pysindy_xl.mujoco import MJCFSystem, actuator_law, kinematic_catalog

    system = MJCFSystem(RK4_SERVO_ARM)
    data = generate_dataset(system, n_trajectories=2, duration=6.0, seed=3, progress=False)
    for trajectory in data.trajectories:
        law = actuator_law(system, SumOfSinusoids.from_dict(trajectory.info["signals"]))
        np.testing.assert_allclose(law(trajectory.t, trajectory.q, trajectory.qd),
                                   trajectory.tau, atol=1e-9 * np.abs(trajectory.tau).max())
    arguments = data.fit_arguments()
    model = px.XLSINDy(kinematic_catalog(system).library()).fit(
        arguments["x"], arguments["t"], u=arguments["u"])  # positions only: the weak form
    friction = model.physical_parameters()["friction"]
    np.testing.assert_allclose([friction[j]["viscous"] for j in ("shoulder", "elbow")],
                               [0.3, 0.15], rtol=0.1)


def test_driven_servo_runs_start_on_the_reference():
    """A random initial error would make the servos jump at it (saturating, far faster than
    the reference): driven runs start where every servo follows its reference with no
    force, moving at the reference's rate."""
    from pysindy_xl.mujoco import MJCFSystem, actuator_law

    system = MJCFSystem(RK4_SERVO_ARM)
    data = generate_dataset(system, n_trajectories=2, duration=0.5, seed=1, progress=False)
    for trajectory in data.trajectories:
        signals = SumOfSinusoids.from_dict(trajectory.info["signals"])
        reference = np.clip(signals(np.array([0.0, 1e-5]))[:, :2], -1.5, 1.5)
        q0, qd0 = np.array(trajectory.info["q0"]), np.array(trajectory.info["qd0"])
        # the run starts at zero servo force; the recording once its stiff modes have settled
        np.testing.assert_allclose(qd0, (reference[1] - reference[0]) / 1e-5, rtol=1e-3,
                                   atol=1e-6)
        np.testing.assert_allclose(actuator_law(system, signals)(0.0, q0, qd0), 0.0,
                                   atol=1e-9)
        assert np.abs(q0 - reference[0]).max() > 1e-3  # behind a moving reference
        assert trajectory.t[0] == trajectory.info["settle"] > 0
    undriven = generate_dataset(system, n_trajectories=1, duration=0.1, seed=1,
                                forcing="implicit", progress=False).trajectories[0]
    assert np.abs(undriven.q[0]).max() > 0.05  # nothing to track: the random state stays
