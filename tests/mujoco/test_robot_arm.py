"""A seven-joint arm with full inertia tensors, armature and damping, identified end to end.

The equations of such an arm have thousands of monomials: the identified dynamics must never
be expanded or lambdified as one expression (that overflowed Python's compiler), and the saved
model must load. Ground truth is MuJoCo: ``qacc`` of an RK4 run with fine steps for the fit,
the same run for the simulation, ``mj_fullM`` for the mass matrix.
"""

import mujoco
import numpy as np
import pytest
import sympy as sp
from kinematic_models import robot_arm

import pysindy_xl as px
from pysindy_xl.mujoco import MJCFSystem, generate_dataset, kinematic_catalog


@pytest.fixture(scope="module")
def arm():
    system = MJCFSystem(robot_arm(7))
    catalog = kinematic_catalog(system)
    data = generate_dataset(system, n_trajectories=2, duration=2.0, seed=0, sample_every=4,
                            progress=False)
    model = px.XLSINDy(catalog.library(), px.ExplicitOptimizer(threshold=1e-8))
    return system, catalog, data, model.fit(**data.fit_arguments(forces="tau"))


def test_the_arm_is_identified_exactly(arm):
    system, catalog, data, model = arm
    trajectory = data.trajectories[1]
    predicted = model.predict(trajectory.q, trajectory.qd, u=trajectory.tau)
    assert np.abs(predicted - trajectory.qdd).max() < 1e-8 * np.abs(trajectory.qdd).max()
    # the identified mass matrix against MuJoCo's at recorded states
    mj_model = system.mj_model()
    mj_data = mujoco.MjData(mj_model)
    states = px.stack_variables(trajectory.q[::50], trajectory.qd[::50])
    mass, _ = model.dynamics_.mass_and_forcing(states)
    for k, qpos in enumerate(trajectory.q[::50]):
        mj_data.qpos[:] = qpos
        mujoco.mj_forward(mj_model, mj_data)
        reference = np.zeros((mj_model.nv, mj_model.nv))
        mujoco.mj_fullM(mj_model, mj_data, reference)
        assert np.abs(mass[k] - reference).max() < 1e-7 * np.abs(reference).max()


def test_the_identified_arm_simulates_like_mujoco(arm):
    _, _, data, model = arm
    trajectory = data.trajectories[0]
    steps = 400  # 0.8 s at 2 ms
    simulated = model.simulate(np.r_[trajectory.q[0], trajectory.qd[0]], trajectory.t[:steps],
                               u=trajectory.tau[:steps])
    error = np.abs(simulated[:, :7] - trajectory.q[:steps]).max()
    assert error < 1e-3 * np.ptp(trajectory.q[:steps], axis=0).max()


def test_the_saved_arm_loads_and_predicts_identically(arm, tmp_path):
    _, _, data, model = arm
    path = tmp_path / "arm.json"
    model.save(path)
    loaded = px.XLSINDy.load(path)
    trajectory = data.trajectories[0]
    np.testing.assert_array_equal(loaded.predict(trajectory.q, trajectory.qd, trajectory.tau),
                                  model.predict(trajectory.q, trajectory.qd, trajectory.tau))


def test_torque_prediction_tells_the_exact_model_from_a_wrong_inertia(arm):
    import copy

    from pysindy_xl.quality import force_prediction

    system, catalog, data, model = arm
    fresh = generate_dataset(system, n_trajectories=1, duration=1.0, seed=7, sample_every=4,
                             progress=False).trajectories[0]
    exact = force_prediction(model, fresh.q, fresh.t, fresh.tau, fresh.qd, fresh.qdd)
    assert exact["worst"] < 1e-7
    # the same model with one link's inertia 20 % off: the torques say so
    wrong = copy.deepcopy(model)
    names = wrong.get_feature_names()
    inertia = max((j for j, name in enumerate(names) if name.startswith("L[")),
                  key=lambda j: abs(wrong.coef_[j]))
    wrong.coef_[inertia] *= 1.2
    wrong._build_dynamics()
    assert force_prediction(wrong, fresh.q, fresh.t, fresh.tau, fresh.qd, fresh.qdd)[
        "worst"] > 1e-2
    # from positions only, derivatives estimated by the model's smoother
    smoothed = force_prediction(model, fresh.q, fresh.t, fresh.tau)
    assert smoothed["worst"] < 0.05


def test_equations_with_thousands_of_terms_simulate():
    # one equation whose forcing is a sum of 3000 monomials: a single expression of that
    # depth cannot be compiled by Python
    c = px.Coordinates(["x"])
    x, v = c.q[0], c.qd[0]
    forcing = sp.Add(*(sp.Float(1e-4 / (k + 1)) * sp.cos(x) ** (k % 7) * v ** (k % 5)
                       * sp.sin(x) ** (k % 3) for k in range(3000)))
    dynamics = px.MassMatrixDynamics(c, [c.qdd[0] + x - forcing])
    t = np.linspace(0, 1, 11)
    simulated = dynamics.simulate([0.1, 0.0], t)
    assert np.all(np.isfinite(simulated))
    derivative = dynamics.state_derivative(simulated[-1])
    np.testing.assert_allclose(derivative[1], dynamics.accelerations(
        simulated[-1:, :1], simulated[-1:, 1:])[0, 0], rtol=1e-12)


def test_physical_parameters_are_the_face_of_the_arm(arm, tmp_path, capsys):
    _, catalog, _, model = arm
    parameters = model.physical_parameters()
    values = np.array([entry["value"] for entry in parameters["base_parameters"]])
    np.testing.assert_allclose(values, catalog.base_parameters, rtol=1e-6, atol=1e-9)
    assert [entry["stands_for"] for entry in parameters["base_parameters"]] == [
        dict(p) for p in catalog.parameters]
    for joint in model.feature_library_.coords.names:  # damping 0.1 on every joint
        assert parameters["friction"][joint]["viscous"] == pytest.approx(0.1, rel=1e-6)
        assert abs(parameters["friction"][joint]["dry"]) < 1e-8
    model.print()
    printed = capsys.readouterr().out
    assert "base parameters" in printed and "a0.armature" in printed
    assert "(a0)" not in printed  # the pages of equations only on request
    path = tmp_path / "arm.json"
    model.save(path)
    assert px.XLSINDy.load(path).physical_parameters() == parameters


@pytest.mark.slow
def test_the_arm_exports_to_jax(arm):
    jax = pytest.importorskip("jax")
    _, _, data, model = arm
    trajectory = data.trajectories[0]
    with jax.enable_x64(True):
        f = model.to_jax()
        states = np.hstack([trajectory.q[:20], trajectory.qd[:20]])
        derivative = np.asarray(jax.vmap(f)(states, trajectory.tau[:20]))
    np.testing.assert_allclose(derivative[:, 7:], trajectory.qdd[:20], rtol=1e-7,
                               atol=1e-7 * np.abs(trajectory.qdd).max())


def test_the_identified_arm_exported_to_mjcf_simulates_like_the_model(arm, tmp_path):
    system, catalog, data, model = arm
    path = tmp_path / "identified.xml"
    written = model.to_mjcf(path, template=system)
    assert written["residual"] < 1e-6
    exported = MJCFSystem(str(path))
    mj_model = exported.mj_model()
    mj_data = mujoco.MjData(mj_model)
    trajectory = data.trajectories[0]
    states = px.stack_variables(trajectory.q[::100], trajectory.qd[::100])
    mass, forcing = model.dynamics_.mass_and_forcing(states)
    for k, (qpos, qvel) in enumerate(zip(trajectory.q[::100], trajectory.qd[::100],
                                         strict=True)):
        mj_data.qpos[:], mj_data.qvel[:] = qpos, qvel
        mujoco.mj_forward(mj_model, mj_data)
        reference = np.zeros((mj_model.nv, mj_model.nv))
        mujoco.mj_fullM(mj_model, mj_data, reference)
        assert np.abs(mass[k] - reference).max() < 1e-5 * np.abs(reference).max()
        # unforced: M qdd = f(q, qd, 0) = -(Coriolis + gravity) - damping * qd
        unforced = mj_data.qfrc_passive - mj_data.qfrc_bias
        assert np.abs(forcing[k] - unforced).max() < 1e-5 * np.abs(unforced).max()
    # bodies the exporter wrote are rigid bodies: positive masses and inertias
    assert np.all(mj_model.body_mass[1:] > 0) and np.all(mj_model.body_inertia[1:] >= 0)


DIAGONAL_INERTIA_ARM = """
<mujoco model="diagonal_arm">
  <option gravity="0 0 -9.81" timestep="0.002" integrator="RK4"><flag contact="disable"/></option>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" damping="0.3" armature="0.02"/>
      <inertial pos="0.2 0 0" mass="1.5" diaginertia="0.01 0.03 0.03"/>
      <body name="fore" pos="0.4 0 0" euler="0 0 20">
        <joint name="elbow" type="hinge" axis="0 0.3 1" damping="0.15" armature="0.01"/>
        <inertial pos="0.15 0.02 0" mass="0.8" diaginertia="0.005 0.01 0.012"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor joint="shoulder"/><motor joint="elbow"/></actuator>
</mujoco>
"""


def test_a_template_with_diagonal_inertias_exports(tmp_path):
    """MJCF states an inertia diagonal (``diaginertia``) or full; MuJoCo refuses both at
    once: the exporter writes principal axes, whichever the template used."""
    system = MJCFSystem(DIAGONAL_INERTIA_ARM)
    catalog = kinematic_catalog(system)
    data = generate_dataset(system, n_trajectories=1, duration=2.0, seed=0, sample_every=4,
                            progress=False)
    model = px.XLSINDy(catalog.library(), px.ExplicitOptimizer(threshold=1e-8)).fit(
        **data.fit_arguments(forces="tau"))
    path = tmp_path / "identified.xml"
    assert model.to_mjcf(path, template=system)["residual"] < 1e-4
    exported = MJCFSystem(str(path)).mj_model()
    mj_data = mujoco.MjData(exported)
    qpos = np.array([0.4, -0.7])
    mj_data.qpos[:] = qpos
    mujoco.mj_forward(exported, mj_data)
    mass = np.zeros((2, 2))
    mujoco.mj_fullM(exported, mj_data, mass)
    identified, _ = model.dynamics_.mass_and_forcing(px.stack_variables(qpos[None],
                                                                        np.zeros((1, 2))))
    np.testing.assert_allclose(mass, identified[0], rtol=1e-4, atol=1e-6)
