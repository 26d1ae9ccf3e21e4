"""Friction and sensor models of real joints in the kinematic catalog, selected per joint.

Ground truth: MuJoCo's inverse dynamics (``mj_inverse`` of the arm without its damping) plus
the friction formula written out here, with known asymmetric Coulomb, Stribeck and torque
offsets that differ from joint to joint, 1 % torque noise and quantized positions. The fit
must find which models each joint has, their values, and predict held-out torques at the
noise floor; the default catalog (viscous + Coulomb) cannot.
"""

import json
import pickle

import mujoco
import numpy as np
import pytest
from kinematic_models import PLANAR_ARM

import pysindy_xl as px
from pysindy_xl.feature_library import JointFrictionLibrary
from pysindy_xl.mujoco import MJCFSystem, kinematic_catalog
from pysindy_xl.optimizers import default_optimizer
from pysindy_xl.physical import PhysicalStructure

EPS, VS = 0.01, 0.1
MODELS = ("viscous", "coulomb", "asymmetric", "stribeck", "offset")
# per joint (rows: shoulder, elbow, wrist), columns in MODELS order. An asymmetry differs
# from an offset only at rest (|qd| < EPS): the shoulder, with 0.5 % of its samples there and
# a torque noise of 0.06 N m, could not tell an asymmetry of 0.1 N m from an offset
TRUTH = np.array([[0.20, 0.40, 0.00, 0.00, 0.15],
                  [0.10, 0.30, 0.00, 0.25, -0.10],
                  [0.05, 0.12, 0.05, 0.08, 0.00]])


def joint_friction(qd, truth=TRUTH):
    """The friction torque of every joint, written out (not the library's columns)."""
    sign = np.tanh(qd / EPS)
    return (truth[:, 0] * qd + truth[:, 1] * sign + truth[:, 2] * sign**2
            + truth[:, 3] * sign * np.exp(-((qd / VS) ** 2)) + truth[:, 4])


def excitation(n, duration, rng, dt=0.002):
    """A finite Fourier series per joint: exact velocities and accelerations."""
    t = np.arange(0.0, duration, dt)
    harmonics = np.arange(1, 6)
    w = 2 * np.pi * 0.12 * harmonics
    a, b = rng.normal(size=(2, 5, n)) * 0.4 / harmonics[:, None]
    s, c = np.sin(np.outer(t, w)), np.cos(np.outer(t, w))
    return (t, s @ a + c @ b, (c * w) @ a - (s * w) @ b,
            -(s * w**2) @ a - (c * w**2) @ b)


@pytest.fixture(scope="module")
def arm():
    system = MJCFSystem(PLANAR_ARM)
    rng = np.random.default_rng(3)
    t, q, qd, qdd = excitation(system.n, 24.0, rng)
    model = system.mj_model()
    model.dof_damping[:] = 0.0  # the friction is all in the formula
    data = mujoco.MjData(model)
    rigid = np.empty_like(q)
    for k in range(len(t)):
        data.qpos[:], data.qvel[:], data.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(model, data)
        rigid[k] = data.qfrc_inverse
    tau = rigid + joint_friction(qd)
    noise = 0.01 * tau.std(axis=0) * rng.normal(size=tau.shape)
    measured_q = np.round(q / 1e-5) * 1e-5  # an encoder's quantization
    split = 2 * len(t) // 3
    fit = slice(0, split)
    catalog = kinematic_catalog(system, friction="all")
    identified = px.XLSINDy(catalog.library()).fit(
        measured_q[fit], t[fit], x_dot=qd[fit], x_ddot=qdd[fit], u=(tau + noise)[fit])
    held_out = (q[split:], qd[split:], qdd[split:], (tau + noise)[split:], noise[split:])
    return system, catalog, identified, held_out, (measured_q[fit], t[fit], qd[fit],
                                                    qdd[fit], (tau + noise)[fit])


def _rms(a):
    return np.sqrt(np.mean(a**2, axis=0))


def test_each_joint_gets_the_friction_it_has(arm):
    _, _, model, _, _ = arm
    assert model.optimizer_.optimizer_.select == "friction"
    found = model.physical_parameters()["joint_friction"]
    for joint, truth in zip(("shoulder", "elbow", "wrist"), TRUTH, strict=True):
        values = np.array([found[joint][m] for m in MODELS])
        # the models a joint does not have are dropped, the others within a few %
        assert np.array_equal(values != 0, truth != 0), (joint, values)
        present = truth != 0
        assert np.allclose(values[present], truth[present], rtol=0.04), (joint, values)
    assert found["wrist"]["coulomb_positive"] == pytest.approx(0.17, rel=0.03)
    assert found["wrist"]["coulomb_negative"] == pytest.approx(0.07, rel=0.03)
    # viscous and Coulomb are also the coordinates' friction (each joint is one coordinate)
    friction = model.physical_parameters()["friction"]
    assert friction["elbow"]["dry"] == found["elbow"]["coulomb"]


def test_held_out_torques_are_predicted_at_the_noise_floor(arm):
    system, _, model, (q, qd, qdd, tau, noise), train = arm
    error = _rms(model.predict_forces(q, qd, qdd) - tau)
    floor = _rms(noise)
    assert np.all(error < 1.1 * floor), (error, floor)
    # the viscous + Coulomb catalog cannot: the offsets and Stribeck terms stay in its error
    plain = px.XLSINDy(kinematic_catalog(system).library()).fit(
        train[0], train[1], x_dot=train[2], x_ddot=train[3], u=train[4])
    plain_error = _rms(plain.predict_forces(q, qd, qdd) - tau)
    assert np.all(plain_error > 1.3 * floor) and np.all(plain_error[1:] > 3 * floor[1:]), (
        plain_error, floor)


def test_the_model_saves_loads_and_exports_with_its_friction(arm, tmp_path):
    system, _, model, (q, qd, qdd, tau, _), _ = arm
    path = tmp_path / "arm.json"
    model.save(path)
    assert "JointFrictionLibrary" in path.read_text()
    json.loads(path.read_text())
    loaded = px.XLSINDy.load(path)
    states = slice(0, 2000, 50)
    expected = model.predict_forces(q[states], qd[states], qdd[states])
    assert np.allclose(loaded.predict_forces(q[states], qd[states], qdd[states]), expected,
                       rtol=1e-10, atol=1e-12)
    assert loaded.physical_parameters()["joint_friction"] == \
        model.physical_parameters()["joint_friction"]
    copy = pickle.loads(pickle.dumps(model))
    assert np.array_equal(copy.predict_forces(q[states], qd[states], qdd[states]), expected)
    # the JAX export evaluates the same friction (asymmetric, Stribeck, offset included)
    jax = pytest.importorskip("jax")
    with jax.enable_x64(True):
        f = model.to_jax()
        state = np.column_stack([q[states], qd[states]])
        acceleration = np.asarray(jax.vmap(f)(state, tau[states]))[:, system.n:]
    np.testing.assert_allclose(acceleration, model.predict(q[states], qd[states], tau[states]),
                               rtol=1e-9, atol=1e-9 * np.abs(qdd).max())
    # MJCF keeps damping and frictionloss, and says what it cannot hold
    written = model.to_mjcf(tmp_path / "arm.xml", template=system)
    found = model.physical_parameters()["joint_friction"]
    mj = mujoco.MjModel.from_xml_path(str(tmp_path / "arm.xml"))
    for k, joint in enumerate(("shoulder", "elbow", "wrist")):
        assert mj.dof_damping[k] == pytest.approx(found[joint]["viscous"], rel=1e-5)
        assert mj.dof_frictionloss[k] == pytest.approx(found[joint]["coulomb"], rel=1e-5)
    assert written["dropped"]["elbow"] == {"stribeck": found["elbow"]["stribeck"],
                                           "offset": found["elbow"]["offset"]}


def test_the_identified_arm_simulates_under_the_measured_torques(arm):
    _, _, model, (q, qd, qdd, tau, _), _ = arm
    window = slice(0, 51)  # 0.1 s: the smooth signs make the equations stiff near rest
    t = np.arange(51) * 0.002
    states = model.simulate(np.concatenate([q[0], qd[0]]), t, u=tau[window])
    assert np.abs(states[:, :3] - q[window]).max() < 1e-3


def test_the_default_catalog_and_fit_are_unchanged():
    catalog = kinematic_catalog(MJCFSystem(PLANAR_ARM))
    library = catalog.library().fit()
    assert not any(isinstance(lib, JointFrictionLibrary) for lib in library.libraries_)
    assert len(library.physical_structure().selectable_columns) == 0
    forced = np.ones(3, dtype=bool)
    assert default_optimizer(forced, True, complete=True, physical=True).optimizer \
        .optimizer.threshold == 0.0
    chosen = default_optimizer(forced, True, complete=True, physical=True, selective=True)
    assert chosen.optimizer.optimizer.select == "friction"


def test_selection_keeps_every_other_column():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(600, 6))
    # columns 0-2 stand for base parameters (one of them a tiny 1e-4), 3-5 for friction
    y = x @ [1.0, 1e-4, -0.5, 0.3, 0.0, 0.0] + 0.05 * rng.normal(size=600)
    physical = PhysicalStructure.from_maps([{"b.m": 1.0}, {"b.mcx": 1.0}, {"b.Iyy": 1.0}],
                                           base_columns=[1, 2, 3], friction_columns=[4],
                                           selectable_columns=[4, 5, 6])
    theta = np.column_stack([-y, x])
    optimizer = px.ExplicitOptimizer(select="friction").fit_catalog(theta, 1, [0],
                                                                    physical=physical)
    assert np.flatnonzero(optimizer.coef_).tolist() == [0, 1, 2, 3, 4]
    everything = px.ExplicitOptimizer().fit_catalog(theta, 1, [0], physical=physical)
    assert everything.coef_[2] == 0  # the tiny base parameter is cut by a free selection


@pytest.mark.parametrize("options, match", [
    ({"friction": "bogus"}, "friction"),
    ({"friction": ["viscous", "sticky"]}, "friction"),
    ({"friction": "all", "stribeck_scale": 0.0}, "stribeck_scale"),
])
def test_bad_friction_options_are_named(options, match):
    with pytest.raises(ValueError, match=match):
        kinematic_catalog(MJCFSystem(PLANAR_ARM), **options)


def test_bad_library_and_optimizer_arguments_are_named():
    c = px.Coordinates(["a"])
    with pytest.raises(ValueError, match="models"):
        JointFrictionLibrary(c, ["j"], models=("viscous", "wobble")).fit()
    with pytest.raises(ValueError, match="weights"):
        JointFrictionLibrary(c, ["j"], weights=np.ones((2, 1))).fit()
    with pytest.raises(ValueError, match="select"):
        px.ExplicitOptimizer(method="lasso", select="friction").fit(np.ones((20, 2)),
                                                                    np.ones(20))
