"""Catalogs from the kinematic tree against MuJoCo's own rigid-body dynamics.

Ground truth is MuJoCo: its mass matrix (``mj_fullM``, composite rigid bodies), its bias
forces (``qfrc_bias``, recursive Newton-Euler) and, for the number of base parameters, the rank
of an inverse-dynamics regressor obtained by perturbing the inertial parameters of the compiled
model (``mj_inverse`` is linear in them). None of it goes through the catalog's derivation.
"""

import mujoco
import numpy as np
import pytest
from kinematic_models import (
    CART_DOUBLE_PENDULUM,
    MULTI_JOINT_BODY,
    PLANAR_ARM,
    SPATIAL_ARM,
    robot_arm,
    serial_arm,
)

import pysindy_xl as px
from pysindy_xl.mujoco import MJCFSystem, generate_dataset, get_system, reference_catalog
from pysindy_xl.mujoco.catalogs.kinematic import KinematicCatalog, kinematic_catalog

SHIPPED = ["cart-pole", "double-pendulum", "cart-double-pendulum"]
WRITTEN = {"planar-arm": PLANAR_ARM, "spatial-arm": SPATIAL_ARM,
           "cart-two-link": CART_DOUBLE_PENDULUM, "multi-joint-body": MULTI_JOINT_BODY}


def _system(name):
    return get_system(name) if name in SHIPPED else MJCFSystem(WRITTEN[name])


def _mujoco_dynamics(system, qpos, qvel):
    """Mass matrix and bias forces of MuJoCo at joint states (rows of qpos, qvel)."""
    model = system.mj_model()
    data = mujoco.MjData(model)
    masses, biases = [], []
    for position, velocity in zip(qpos, qvel, strict=True):
        data.qpos[:], data.qvel[:] = position, velocity
        mujoco.mj_forward(model, data)
        matrix = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, matrix)
        masses.append(matrix)
        biases.append(data.qfrc_bias.copy())
    return np.array(masses), np.array(biases)


def _random_joint_states(system, n_states, seed):
    rng = np.random.default_rng(seed)
    model = system.mj_model()
    qpos = rng.uniform(-np.pi, np.pi, (n_states, model.nq))
    return qpos, rng.normal(size=(n_states, model.nv))


def _relative_error(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


def _set_inertial(model, body, parameters):
    """Write ten parameters (m, m c, I about the frame origin) into a compiled model."""
    mass, first = parameters[0], np.asarray(parameters[1:4])
    xx, yy, zz, xy, xz, yz = parameters[4:]
    origin = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    centre = first / mass
    central = origin - mass * (centre @ centre * np.eye(3) - np.outer(centre, centre))
    principal, axes = np.linalg.eigh(central)
    if np.linalg.det(axes) < 0:
        axes[:, 0] *= -1
    quaternion = np.zeros(4)
    mujoco.mju_mat2Quat(quaternion, axes.reshape(-1))
    model.body_mass[body], model.body_ipos[body] = mass, centre
    model.body_iquat[body], model.body_inertia[body] = quaternion, principal


def _mujoco_base_parameter_count(system, seed=0):
    """Rank of MuJoCo's inverse-dynamics regressor in (m, m c, I_o) per body and armature.

    Inverse dynamics ``M(q) qdd + bias`` is linear in these parameters, so the difference
    quotient of a perturbed compiled model is an exact regressor column.
    """
    from pysindy_xl.mujoco.catalogs._kinematic_tree import physical_values

    model = system.mj_model()
    data = mujoco.MjData(model)
    rng = np.random.default_rng(seed)
    states = [(rng.uniform(-3, 3, model.nq), rng.normal(size=model.nv),
               rng.normal(size=model.nv)) for _ in range(40)]

    def inverse_dynamics():
        out = []
        matrix = np.zeros((model.nv, model.nv))
        for qpos, qvel, qacc in states:
            data.qpos[:], data.qvel[:] = qpos, qvel
            mujoco.mj_forward(model, data)
            mujoco.mj_fullM(model, data, matrix)
            out.append(matrix @ qacc + data.qfrc_bias)
        return np.concatenate(out)

    reference = inverse_dynamics()
    columns = []
    step = 1e-3
    for body in range(1, model.nbody):
        base = physical_values(model, body)
        for p in range(10):
            # inverse dynamics is linear in these parameters: a difference is exact
            perturbed = base.copy()
            perturbed[p] += step * (base[0] if p == 0 else 0.01)
            _set_inertial(model, body, perturbed)
            columns.append((inverse_dynamics() - reference) / (perturbed[p] - base[p]))
            _set_inertial(model, body, base)
    for dof in range(model.nv):
        model.dof_armature[dof] += step
        columns.append((inverse_dynamics() - reference) / step)
        model.dof_armature[dof] -= step
    matrix = np.column_stack(columns)
    norms = np.linalg.norm(matrix, axis=0)
    # columns of parameters without dynamics are round-off of the difference quotient
    moving = norms > 1e-7 * norms.max()
    singular = np.linalg.svd(matrix[:, moving] / norms[moving], compute_uv=False)
    return int(np.sum(singular > 1e-6 * singular[0]))


@pytest.mark.parametrize("name", SHIPPED + list(WRITTEN))
def test_catalog_reproduces_mujoco_mass_matrix_and_bias(name):
    system = _system(name)
    catalog = kinematic_catalog(system)
    qpos, qvel = _random_joint_states(system, 12, seed=1)
    masses, biases = _mujoco_dynamics(system, qpos, qvel)
    transform = system.joint_to_coordinates
    q, qd, _ = system.to_generalized(qpos, qvel)
    # q = T qpos: M_joint = T^T M_q T, joint forces = T^T generalized forces
    mass_joint = transform.T @ catalog.mass_matrix(q) @ transform
    bias_joint = catalog.bias_forces(q, qd) @ transform
    gravity_joint = catalog.gravity_torque(q) @ transform
    _, gravity = _mujoco_dynamics(system, qpos, np.zeros_like(qvel))
    assert _relative_error(mass_joint, masses) < 1e-9
    assert _relative_error(bias_joint, biases) < 1e-9
    assert _relative_error(gravity_joint, gravity) < 1e-9


@pytest.mark.parametrize("name, expected", [("cart-pole", 4), ("double-pendulum", 7),
                                            ("cart-double-pendulum", 8), ("planar-arm", 11)])
def test_base_parameter_count_matches_theory(name, expected):
    # planar chains: (m c_x, m c_z, I_yy) per link, the cart's total mass, and the armature of
    # every joint but the first (whose armature adds to the first link's inertia)
    catalog = kinematic_catalog(_system(name))
    assert len(catalog.lagrange_terms) == expected


@pytest.mark.parametrize("name", ["spatial-arm", "cart-two-link", "multi-joint-body"])
def test_base_parameter_count_matches_mujoco_regressor_rank(name):
    system = _system(name)
    catalog = kinematic_catalog(system)
    base = _mujoco_base_parameter_count(system)
    assert len(catalog.lagrange_terms) == base
    n_classical = int(catalog.classical_mask.sum())
    library = catalog.library().fit()
    assert library.n_output_features_ == 1 + base + n_classical
    assert len(catalog.classical_terms) == 2 * system.n + int(
        (system.mj_model().jnt_stiffness > 0).sum())


def test_combination_maps_physical_to_base_parameters():
    # the base parameters are the coefficients of the catalog terms: the Lagrangian of the
    # whole parameter set equals the catalog's Lagrangian up to terms without dynamics
    catalog = kinematic_catalog(_system("double-pendulum"))
    assert catalog.parameters[2] == {"link1.Iyy": 1.0, "link2.m": 1.0, "hinge1.armature": 1.0}
    length1 = 1.0
    mass2, point_inertia = 0.8, 1e-6
    iyy1 = 1.0 * length1**2 + point_inertia
    assert catalog.base_parameters[2] == pytest.approx(iyy1 + mass2 * length1**2, rel=1e-12)


def test_true_coefficients_of_shipped_system_zero_the_residual():
    system = get_system("cart-double-pendulum")
    library = reference_catalog(system, "kinematic")
    data = generate_dataset(system, n_trajectories=1, duration=0.5, seed=3, progress=False)
    trajectory = data.trajectories[0]
    from pysindy_xl.feature_library import stack_variables
    from pysindy_xl.mujoco.catalogs.reference import true_coefficients

    xi, missing = true_coefficients(system, library)
    assert missing == []
    theta = library.transform(stack_variables(trajectory.q, trajectory.qd, trajectory.qdd,
                                              trajectory.tau))
    assert np.abs(theta @ xi).max() < 1e-9 * np.abs(trajectory.tau).max()


def test_identification_recovers_mass_matrix_gravity_damping_and_armature():
    system = MJCFSystem(PLANAR_ARM.replace('damping="0.1"', 'damping="0.1" armature="0.02"'),
                        force_amplitude=4.0)
    catalog = kinematic_catalog(system, coulomb=False)
    data = generate_dataset(system, n_trajectories=2, duration=2.0, seed=0, sample_every=5,
                            progress=False)
    model = px.XLSINDy(catalog.library(), optimizer=px.ExplicitOptimizer(threshold=1e-8))
    model.fit(**data.fit_arguments(forces="tau"))
    identified = catalog.lagrange_coefficients(model)
    q, _ = _random_joint_states(system, 20, seed=5)
    masses_true, gravity_true = catalog.mass_matrix(q), catalog.gravity_torque(q)
    _, gravity_mujoco = _mujoco_dynamics(system, q, np.zeros_like(q))
    assert _relative_error(gravity_true, gravity_mujoco) < 1e-9
    assert _relative_error(catalog.mass_matrix(q, identified), masses_true) < 1e-4
    assert _relative_error(catalog.gravity_torque(q, identified), gravity_true) < 1e-4
    coefficients = dict(zip(model.get_feature_names(), model.coefficients(), strict=True))
    for joint, damping in (("shoulder", 0.2), ("elbow", 0.1), ("wrist", 0.05)):
        assert coefficients[f"C_{joint}[{joint}_dot]"] == pytest.approx(damping, rel=0.01)
    armature = [j for j, p in enumerate(catalog.parameters) if p == {"elbow.armature": 1.0}]
    assert len(armature) == 1
    assert identified[armature[0]] == pytest.approx(0.02, rel=0.01)


@pytest.mark.slow
def test_identification_of_spatial_arm():
    system = MJCFSystem(SPATIAL_ARM, force_amplitude=3.0)
    catalog = kinematic_catalog(system)
    data = generate_dataset(system, n_trajectories=2, duration=3.0, seed=1, sample_every=5,
                            progress=False)
    model = px.XLSINDy(catalog.library(), optimizer=px.ExplicitOptimizer(threshold=1e-8))
    model.fit(**data.fit_arguments(forces="tau"))
    identified = catalog.lagrange_coefficients(model)
    q, _ = _random_joint_states(system, 20, seed=5)
    assert _relative_error(catalog.mass_matrix(q, identified), catalog.mass_matrix(q)) < 1e-4
    assert _relative_error(catalog.gravity_torque(q, identified),
                           catalog.gravity_torque(q)) < 1e-4
    coefficients = dict(zip(model.get_feature_names(), model.coefficients(), strict=True))
    for joint, damping in (("j1", 0.3), ("j2", 0.2), ("j3", 0.15), ("j4", 0.05)):
        assert coefficients[f"C_{joint}[{joint}_dot]"] == pytest.approx(damping, rel=0.01)


@pytest.mark.slow
@pytest.mark.parametrize("arm", [serial_arm(5), robot_arm(7)], ids=["tilted-5", "robot-7"])
def test_longer_arms_reproduce_mujoco(arm):
    system = MJCFSystem(arm)
    catalog = kinematic_catalog(system)
    qpos, qvel = _random_joint_states(system, 6, seed=2)
    masses, biases = _mujoco_dynamics(system, qpos, qvel)
    assert _relative_error(catalog.mass_matrix(qpos), masses) < 1e-9
    assert _relative_error(catalog.bias_forces(qpos, qvel), biases) < 1e-9


def test_inputs_are_checked_and_results_cached(tmp_path):
    with pytest.raises(TypeError, match="system"):
        kinematic_catalog(3.5)
    with pytest.raises(ValueError, match="coulomb_scale"):
        kinematic_catalog("cart-pole", coulomb_scale=0.0)
    free = ('<mujoco><worldbody><body><freejoint/><geom size="0.1"/></body></worldbody>'
            "</mujoco>")
    with pytest.raises(ValueError, match="hinge or slide"):
        kinematic_catalog(free)
    catalog = kinematic_catalog("cart-pole")
    assert isinstance(catalog, KinematicCatalog)
    again = kinematic_catalog("cart-pole")
    assert again.lagrange_terms is catalog.lagrange_terms  # cached derivation
    system = get_system("cart-pole")
    assert kinematic_catalog(system).system is system  # bound to the system given
    path = tmp_path / "planar_arm"  # an MJCF file need not end in .xml
    path.write_text(PLANAR_ARM, encoding="utf-8")
    from_file = kinematic_catalog(path)
    assert from_file.system.path == str(path)
    assert from_file.lagrange_terms == kinematic_catalog(PLANAR_ARM).lagrange_terms
    with pytest.raises(ValueError, match="q: expected shape"):
        catalog.mass_matrix(np.zeros(3))
    with pytest.raises(ValueError, match="coefficients"):
        catalog.gravity_torque(np.zeros(2), coefficients=[1.0])


def test_public_export_is_lazy():
    import subprocess
    import sys

    # the module loads on first touch; MuJoCo itself only when a catalog is derived
    module = "pysindy_xl.mujoco.catalogs.kinematic"
    code = (f"import sys, pysindy_xl as px; assert {module!r} not in sys.modules; "
            f"f = px.kinematic_catalog; assert {module!r} in sys.modules; "
            "assert 'mujoco' not in sys.modules; print(f.__name__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "kinematic_catalog"


# -- independent check with the robotics regressor (Pinocchio, optional) ---------------------
def _pinocchio_model(xml, tmp_path):
    pinocchio = pytest.importorskip(
        "pinocchio", reason="Pinocchio (pip package 'pin') is not installed; optional check")
    path = tmp_path / "model.xml"
    path.write_text(xml, encoding="utf-8")
    model = pinocchio.buildModelFromMJCF(str(path))
    return pinocchio, model, model.createData()


def _pinocchio_regressor(pinocchio, model, data, q, qd, qdd):
    """Joint-torque regressor of Pinocchio, with armature columns (Pinocchio leaves them out)."""
    blocks = [np.hstack([pinocchio.computeJointTorqueRegressor(model, data, a, b, c),
                         np.diag(c)]) for a, b, c in zip(q, qd, qdd, strict=True)]
    return np.vstack(blocks)


@pytest.mark.parametrize("name", ["planar-arm", "spatial-arm"])
def test_base_parameter_count_matches_pinocchio(name, tmp_path):
    pinocchio, model, data = _pinocchio_model(WRITTEN[name], tmp_path)
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.uniform(-3, 3, (60, model.nq)), *rng.normal(size=(2, 60, model.nv))
    regressor = _pinocchio_regressor(pinocchio, model, data, q, qd, qdd)
    norms = np.linalg.norm(regressor, axis=0)
    moving = norms > 1e-9 * norms.max()
    singular = np.linalg.svd(regressor[:, moving] / norms[moving], compute_uv=False)
    rank = int(np.sum(singular > 1e-9 * singular[0]))
    assert len(kinematic_catalog(MJCFSystem(WRITTEN[name])).lagrange_terms) == rank


def test_identified_dynamics_match_pinocchio_identification(tmp_path):
    # the same noise-free data identified two ways: XLSINDy on the kinematic catalog, least
    # squares on Pinocchio's regressor (plus damping columns). Base parameters are unique, so
    # the identified mass matrices and gravity torques must agree.
    xml = PLANAR_ARM.replace('damping="0.1"', 'damping="0.1" armature="0.02"')
    pinocchio, model, data = _pinocchio_model(xml, tmp_path)
    system = MJCFSystem(xml, force_amplitude=4.0)
    catalog = kinematic_catalog(system, coulomb=False)
    dataset = generate_dataset(system, n_trajectories=2, duration=2.0, seed=0, sample_every=5,
                               progress=False)
    fitted = px.XLSINDy(catalog.library(), optimizer=px.ExplicitOptimizer(threshold=1e-8))
    fitted.fit(**dataset.fit_arguments(forces="tau"))
    identified = catalog.lagrange_coefficients(fitted)
    q, qd, qdd, tau = (np.vstack([getattr(tr, key) for tr in dataset.trajectories])
                       for key in ("q", "qd", "qdd", "tau"))
    regressor = np.hstack([_pinocchio_regressor(pinocchio, model, data, q, qd, qdd),
                           np.vstack([np.diag(v) for v in qd])])
    parameters = np.linalg.lstsq(regressor, tau.reshape(-1), rcond=None)[0]
    states = _random_joint_states(system, 10, seed=7)[0]
    n = system.n
    zeros = np.zeros((len(states), n))
    gravity_pinocchio = (_pinocchio_regressor(pinocchio, model, data, states, zeros, zeros)
                         @ parameters[:-n]).reshape(-1, n)
    columns = [(_pinocchio_regressor(pinocchio, model, data, states, zeros,
                                     np.tile(np.eye(n)[k], (len(states), 1)))
                @ parameters[:-n]).reshape(-1, n) - gravity_pinocchio for k in range(n)]
    mass_pinocchio = np.stack(columns, axis=2)
    assert _relative_error(catalog.mass_matrix(states, identified), mass_pinocchio) < 1e-6
    assert _relative_error(catalog.gravity_torque(states, identified), gravity_pinocchio) < 1e-6


# -- command line ----------------------------------------------------------------------------
CLI_SHORT = ["--duration", "2", "--trajectories", "1", "--validation-duration", "1",
             "--no-plots", "--quiet"]


def test_cli_demo_with_kinematic_catalog_recovers_the_true_model(tmp_path):
    import json

    from pysindy_xl.cli import main

    assert main(["demo", "double-pendulum", "--catalog", "kinematic", "--out", str(tmp_path),
                 *CLI_SHORT]) == 0
    report = json.loads((tmp_path / "report.json").read_text())
    # the relative hinge's damping is one joint-velocity term (theta2_dot - theta1_dot)
    assert report["coefficient_summary"]["true_model_missing_from_catalog"] == []
    assert report["coefficient_summary"]["max_relative_error"] < 1e-9
    assert report["validation"]["valid"] is True


def test_cli_demo_of_user_mjcf_file_with_kinematic_catalog(tmp_path, capsys):
    from pysindy_xl.cli import main

    path = tmp_path / "planar_arm.xml"
    path.write_text(PLANAR_ARM, encoding="utf-8")
    assert main(["demo", str(path), "--catalog", "kinematic", "--out", str(tmp_path / "out"),
                 *CLI_SHORT]) == 0


def test_identified_model_saves_and_loads(tmp_path):
    # the JSON file stores the terms; the loaded plain LagrangeLibrary has the same features
    system = MJCFSystem(CART_DOUBLE_PENDULUM, force_amplitude=3.0)
    catalog = kinematic_catalog(system)
    data = generate_dataset(system, n_trajectories=1, duration=1.0, seed=0, progress=False)
    model = px.XLSINDy(catalog.library(), optimizer=px.ExplicitOptimizer(threshold=1e-8))
    model.fit(**data.fit_arguments())
    path = tmp_path / "model.json"
    model.save(path)
    loaded = px.XLSINDy.load(path)
    assert loaded.get_feature_names() == model.get_feature_names()
    assert catalog.lagrange_coefficients(loaded) == pytest.approx(catalog.base_parameters,
                                                                  rel=1e-6, abs=1e-9)
    trajectory = data.trajectories[0]
    predicted = loaded.predict(trajectory.q, trajectory.qd, u=trajectory.tau)
    assert np.abs(predicted - trajectory.qdd).max() < 1e-8 * np.abs(trajectory.qdd).max()


def test_polynomial_library_matches_lagrange_library_and_falls_back():
    import sympy as sp

    from pysindy_xl.mujoco.catalogs.kinematic import PolynomialLagrangeLibrary

    c = px.Coordinates(["a", "x"])
    polynomial = [c.qd[0] ** 2 * sp.cos(c.q[0]) ** 3, c.qd[0] * c.qd[1] * sp.sin(c.q[0]),
                  c.q[1] ** 2 * sp.cos(c.q[0]), c.qd[0] * sp.sin(c.q[0])]  # the last: d/dt
    other = [c.t * c.qd[0] ** 2, sp.exp(c.q[1])]  # outside the polynomial class
    data = np.random.default_rng(0).normal(size=(40, 9))
    for terms in (polynomial, polynomial + other):
        fast = PolynomialLagrangeLibrary(c, terms).fit()
        reference = px.LagrangeLibrary(c, terms).fit()
        assert fast.get_feature_names() == reference.get_feature_names()
        assert fast.zero_terms_ == reference.zero_terms_
        assert np.allclose(fast.transform(data), reference.transform(data), rtol=1e-12,
                           atol=1e-12)
    assert PolynomialLagrangeLibrary(c, polynomial).fit().zero_terms_ == [3]
    with pytest.raises(ValueError, match="terms"):
        PolynomialLagrangeLibrary(c, []).fit()


def test_polynomial_library_weak_rows_match_the_symbolic_ones():
    import sympy as sp

    from pysindy_xl.feature_library import PolynomialLagrangeLibrary

    c = px.Coordinates(["theta", "x"])
    terms = [c.qd[0] ** 2 * sp.cos(c.q[0]) ** 2, c.qd[0] * c.qd[1] * sp.sin(c.q[0]),
             c.q[1] ** 2 * sp.cos(c.q[0]), c.qd[1] ** 2]
    t = np.linspace(0, 10, 1001)
    states = px.stack_variables(np.column_stack([np.sin(t), np.cos(1.3 * t)]),
                                np.column_stack([np.cos(t), -1.3 * np.sin(1.3 * t)]))
    phi, dphi, _ = px.BumpTestFunctions(width=1.0).matrices(t)
    fast = PolynomialLagrangeLibrary(c, terms).fit().weak_transform(states, phi, dphi)
    reference = px.LagrangeLibrary(c, terms).fit().weak_transform(states, phi, dphi)
    np.testing.assert_allclose(fast, reference, rtol=1e-12, atol=1e-12 * np.abs(reference).max())
