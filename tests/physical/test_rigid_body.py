"""The rigid-body kernel against MuJoCo, and the models that simulate with it.

Ground truth is MuJoCo's own mass matrix (``mj_fullM``) and bias forces (``qfrc_bias``) of the
compiled MJCF, mapped to the system's coordinates; none of it goes through the kernel or the
catalog's derivation.
"""

import json

import mujoco
import numpy as np
import pytest
from kinematic_models import (
    CART_DOUBLE_PENDULUM,
    MULTI_JOINT_BODY,
    PLANAR_ARM,
    SPATIAL_ARM,
    robot_arm,
)

from pysindy_xl.dynamics import CatalogDynamics
from pysindy_xl.feature_library import stack_variables
from pysindy_xl.mujoco import MJCFSystem, get_system, kinematic_catalog
from pysindy_xl.physical.rigid_body import (
    KinematicTree,
    physical_parameters_from_base,
    rigid_body_dynamics,
)

MODELS = {"cart-pole": None, "double-pendulum": None, "cart-double-pendulum": None,
          "planar-arm": PLANAR_ARM, "spatial-arm": SPATIAL_ARM,
          "cart-two-link": CART_DOUBLE_PENDULUM, "multi-joint-body": MULTI_JOINT_BODY,
          "robot-arm-7": robot_arm(7)}


def _system(name):
    xml = MODELS[name]
    return get_system(name) if xml is None else MJCFSystem(xml)


def _mujoco_in_coordinates(system, q, qd):
    """MuJoCo's M and bias at system states, in the system's coordinates (q = T qpos)."""
    model = system.mj_model()
    data = mujoco.MjData(model)
    inverse = np.linalg.inv(system.joint_to_coordinates)
    masses, biases = [], []
    for position, velocity in zip(q @ inverse.T, qd @ inverse.T, strict=True):
        data.qpos[:], data.qvel[:] = position, velocity
        mujoco.mj_forward(model, data)
        matrix = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, matrix)
        masses.append(inverse.T @ matrix @ inverse)
        biases.append(inverse.T @ data.qfrc_bias)
    return np.array(masses), np.array(biases)


def _states(n, count=12, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, (count, n)), rng.normal(size=(count, n))


@pytest.mark.parametrize("name", list(MODELS))
def test_kernel_matches_mujoco_from_base_parameters(name):
    """The least-norm physical parameters of the MJCF's base parameters reproduce MuJoCo's
    dynamics: the kernel depends on the base parameters only, like the catalog."""
    system = _system(name)
    catalog = kinematic_catalog(system)
    tree = catalog.tree
    pi = physical_parameters_from_base(tree, catalog.parameters, catalog.base_parameters)
    q, qd = _states(system.n)
    mass, bias = rigid_body_dynamics(tree, pi, q, qd)
    true_mass, true_bias = _mujoco_in_coordinates(system, q, qd)
    scale_mass, scale_bias = np.abs(true_mass).max(), np.abs(true_bias).max()
    np.testing.assert_allclose(mass, true_mass, rtol=0, atol=1e-12 * scale_mass)
    np.testing.assert_allclose(bias, true_bias, rtol=0, atol=1e-11 * scale_bias)


def test_kernel_of_the_true_bodies_matches_mujoco():
    """With every body's own ten parameters (not a base-parameter preimage)."""
    system = MJCFSystem(SPATIAL_ARM)
    catalog = kinematic_catalog(system)
    index = {name: k for k, name in enumerate(catalog.tree.physical_names)}
    pi = np.zeros(len(index))
    for name, value in zip(catalog.physical_names, catalog.physical_values, strict=True):
        pi[index[name]] = value
    q, qd = _states(system.n, seed=3)
    mass, bias = rigid_body_dynamics(catalog.tree, pi, q, qd)
    true_mass, true_bias = _mujoco_in_coordinates(system, q, qd)
    np.testing.assert_allclose(mass, true_mass, atol=1e-12)
    np.testing.assert_allclose(bias, true_bias, atol=1e-11)


def test_catalog_dynamics_with_the_kernel_equal_the_written_equations():
    """A model with the tree and one without it (its columns' monomials) give the same M
    and f, also for coefficients no rigid body has, and for a held coordinate."""
    system = MJCFSystem(robot_arm(4))
    catalog = kinematic_catalog(system)
    coef = catalog.true_coefficients() * np.random.default_rng(2).uniform(
        -2, 2, len(catalog.true_coefficients()))
    with_tree = catalog.library(interlink=system.force_matrix()).fit()
    written = catalog.library(interlink=system.force_matrix())
    written.libraries[1].tree = None
    written.fit()
    held = np.array([False, False, True, False])
    q, qd = _states(system.n, count=20, seed=5)
    z = stack_variables(q, qd, None, np.random.default_rng(6).normal(size=q.shape))
    for flags in (None, held):
        fast, slow = CatalogDynamics(with_tree, coef, flags), CatalogDynamics(written, coef,
                                                                            flags)
        assert len(fast.rigid_parts) == 1 and not slow.rigid_parts
        for a, b in zip(fast.mass_and_forcing(z), slow.mass_and_forcing(z), strict=True):
            np.testing.assert_allclose(a, b, atol=1e-10 * np.abs(b).max())
        state = np.concatenate([q[0], qd[0]])
        np.testing.assert_allclose(fast.state_derivative(state, z[0, 3 * 4:4 * 4]),
                                   slow.state_derivative(state, z[0, 3 * 4:4 * 4]),
                                   rtol=1e-9, atol=1e-9)
    # the written equations still hold every column's monomials; the evaluators read few
    assert fast.n_terms == slow.n_terms
    assert sum(len(e) for e in fast.numeric_terms.entries) < fast.n_terms / 10


def test_tree_round_trips_through_json():
    tree = kinematic_catalog(MJCFSystem(MULTI_JOINT_BODY)).tree
    again = KinematicTree.from_dict(json.loads(json.dumps(tree.to_dict())))
    assert again.physical_names == tree.physical_names
    q, qd = _states(len(tree.joint_names))
    pi = np.random.default_rng(0).normal(size=len(tree.physical_names))
    for a, b in zip(rigid_body_dynamics(tree, pi, q, qd), rigid_body_dynamics(again, pi, q, qd),
                    strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("change, message", [
    ({"parents": [0]}, "parents"),
    ({"joint_axes": [[0.0, 0.0, 2.0]]}, "unit"),
    ({"joint_to_coordinates": [[0.0]]}, "invertible"),
    ({"offsets": [[np.nan, 0.0, 0.0]]}, "offsets"),
    ({"body_names": "b"}, "body_names"),
])
def test_bad_trees_are_refused(change, message):
    base = {"body_names": ["b"], "parents": [-1], "offsets": [[0.0, 0.0, 0.0]],
            "rotations": [np.eye(3).tolist()], "joint_names": ["j"], "joint_bodies": [0],
            "joint_hinge": [True], "joint_axes": [[0.0, 1.0, 0.0]],
            "joint_anchors": [[0.0, 0.0, 0.0]], "joint_references": [0.0],
            "joint_to_coordinates": [[1.0]], "gravity": [0.0, 0.0, -9.81]}
    KinematicTree.from_dict(base)
    with pytest.raises(ValueError, match=message):
        KinematicTree.from_dict({**base, **change})


@pytest.mark.slow  # (a five-link arm: the JAX compilation is most of it)
def test_jax_kernel_matches_numpy():
    jax = pytest.importorskip("jax")
    from pysindy_xl.export.jax_dynamics import dynamics_function

    system = MJCFSystem(robot_arm(5))
    catalog = kinematic_catalog(system)
    library = catalog.library(interlink=system.force_matrix()).fit()
    dynamics = CatalogDynamics(library, catalog.true_coefficients())
    function = dynamics_function(dynamics)
    rng = np.random.default_rng(1)
    states = np.concatenate(_states(system.n, count=6, seed=1), axis=1)
    forces = rng.normal(size=(6, system.n))
    with jax.enable_x64(True):
        got = np.asarray(function(states, forces))
    expected = np.array([dynamics.state_derivative(s, u) for s, u in zip(states, forces,
                                                                             strict=True)])
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)


@pytest.fixture(scope="module")
def saved_arm(tmp_path_factory):
    """A model of a three-joint arm fitted on noise-free MuJoCo data, and its file."""
    import pysindy_xl as px
    from pysindy_xl.mujoco import generate_dataset

    system = MJCFSystem(PLANAR_ARM, force_amplitude=4.0)
    catalog = kinematic_catalog(system, coulomb=False)
    data = generate_dataset(system, n_trajectories=1, duration=1.0, seed=0, sample_every=5,
                            progress=False)
    model = px.XLSINDy(catalog.library(), optimizer=px.ExplicitOptimizer(threshold=1e-8))
    model.fit(**data.fit_arguments(forces="tau"))
    path = tmp_path_factory.mktemp("arm") / "arm.json"
    model.save(path)
    return model, path, json.loads(path.read_text())


def test_saved_arm_simulates_with_its_tree(saved_arm):
    import pysindy_xl as px

    model, path, _ = saved_arm
    loaded = px.XLSINDy.load(path)
    assert len(loaded.dynamics_.rigid_parts) == 1
    t = np.linspace(0.0, 0.5, 51)
    x0 = np.array([0.3, -0.2, 0.1, 0.0, 0.5, 0.0])
    np.testing.assert_allclose(loaded.simulate(x0, t), model.simulate(x0, t), rtol=0,
                               atol=1e-10)


@pytest.mark.parametrize("change, message", [
    (lambda tree: tree.pop("gravity"), "fields"),
    (lambda tree: tree.update(joint_axes=[[0.0, 0.0, 2.0]] * 3), "unit"),
    (lambda tree: tree.update(joint_names=["a", "b"]), "joint"),
    (lambda tree: tree.update(body_names=["b"] * 2000), "1000 bodies"),
])
def test_hostile_trees_are_refused_on_load(saved_arm, tmp_path, change, message):
    import pysindy_xl as px

    _, _, document = saved_arm
    document = json.loads(json.dumps(document))
    lagrange = next(spec for spec in document["feature_library"]["libraries"]
                    if "tree" in spec)
    change(lagrange["tree"])
    path = tmp_path / "hostile.json"
    path.write_text(json.dumps(document))
    with pytest.raises(ValueError, match=message):
        px.XLSINDy.load(path)
