"""Physically consistent identification: PhysicalOptimizer on a small arm's kinematic catalog.

Ground truth is MuJoCo (``mj_fullM``); consistency is checked on the realization the fit
reports (pseudo-inertia eigenvalues, armatures) and on the friction coefficients.
"""

import pickle
import warnings

import mujoco
import numpy as np
import pytest
from kinematic_models import robot_arm
from sklearn.base import clone

import pysindy_xl as px
from pysindy_xl.mujoco import MJCFSystem, generate_dataset, kinematic_catalog
from pysindy_xl.optimizers import CatalogProblem, optimizer_from_spec
from pysindy_xl.physical import PhysicalStructure, realize
from pysindy_xl.quality import fit_quality, quality_lines


@pytest.fixture(scope="module")
def arm():
    system = MJCFSystem(robot_arm(3))
    return system, kinematic_catalog(system)


@pytest.fixture(scope="module")
def inconsistent(arm):
    """Two seconds of positions with 5 % noise: the unconstrained estimate is not physical
    (a negative viscous friction)."""
    system, catalog = arm
    data = generate_dataset(system, n_trajectories=1, duration=2.0, seed=1, noise=0.05,
                            sample_every=4, progress=False)
    arguments = data.fit_arguments(forces="tau")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(catalog.library(), px.PhysicalOptimizer()).fit(**arguments)
    return model, arguments


def _mass_matrices(model, system, trajectory, every):
    """The model's and MuJoCo's (``mj_fullM``) mass matrices at every ``every``-th state."""
    q, qd = trajectory.q[::every], trajectory.qd[::every]
    mass, _ = model.dynamics_.mass_and_forcing(px.stack_variables(q, qd))
    mj_model = system.mj_model()
    mj_data = mujoco.MjData(mj_model)
    reference = np.zeros((len(q), mj_model.nv, mj_model.nv))
    for k, qpos in enumerate(q):
        mj_data.qpos[:] = qpos
        mujoco.mj_forward(mj_model, mj_data)
        mujoco.mj_fullM(mj_model, mj_data, reference[k])
    return mass, reference


def _structure(catalog):
    return PhysicalStructure.from_combination(list(catalog.physical_names),
                                              catalog.combination)


def test_clean_data_recovers_the_base_parameters_and_mujocos_mass_matrix(arm):
    system, catalog = arm
    data = generate_dataset(system, n_trajectories=1, duration=2.0, seed=0, sample_every=4,
                            progress=False)
    model = px.XLSINDy(catalog.library(), px.PhysicalOptimizer(
        px.ExplicitOptimizer(threshold=1e-8))).fit(**data.fit_arguments(forces="tau"))
    assert model.physical_consistency_["consistent"]
    beta = catalog.lagrange_coefficients(model)
    truth = catalog.base_parameters
    assert np.abs(beta - truth).max() < 1e-8 * np.abs(truth).max()
    mass, reference = _mass_matrices(model, system, data.trajectories[0], every=100)
    for identified, exact in zip(mass, reference, strict=True):
        assert np.abs(identified - exact).max() < 1e-7 * np.abs(exact).max()
    # a consistent estimate is kept as the optimizer found it
    np.testing.assert_array_equal(model.optimizer_.coef_, model.optimizer_.unconstrained_coef_)


def test_an_inconsistent_estimate_is_recorded_and_constrained(arm, inconsistent):
    _, catalog = arm
    model, _ = inconsistent
    report = model.physical_consistency_
    assert report["consistent"] is False
    assert report["cost"] > 1e-6 or report["negative_friction"]
    optimizer = model.optimizer_
    assert not np.array_equal(optimizer.coef_, optimizer.unconstrained_coef_)
    # the realization the fit reports: rigid bodies, non-negative armature
    structure = _structure(catalog)
    pi = np.array([optimizer.inertial_parameters_.get(name, 0.0)
                   for name in catalog.physical_names])
    eigenvalues = np.linalg.eigvalsh(structure.pseudo_inertias(pi))
    assert eigenvalues.min() >= -1e-12 * np.abs(eigenvalues).max()
    assert pi[structure.armature].min() >= 0
    # ... which reproduces the identified base parameters
    beta = catalog.lagrange_coefficients(model)
    np.testing.assert_allclose(catalog.combination @ pi, beta, atol=1e-9 * np.abs(beta).max())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the solver's accuracy near the cone's boundary
        _, residual = realize(structure, beta, closeness=1e-9)
    assert residual < 1e-4  # the solver's accuracy on the boundary of the cone
    for values in model.physical_parameters()["friction"].values():
        assert values["viscous"] >= 0 and values["dry"] >= 0
    # the unconstrained fit of the same data is not physical
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plain = px.XLSINDy(catalog.library(), px.ExplicitOptimizer()).fit(**inconsistent[1])
        _, plain_residual = realize(structure, catalog.lagrange_coefficients(plain),
                                    closeness=1e-9)
    friction = plain.physical_parameters()["friction"]
    assert plain_residual > 1e-4 or min(min(v.values()) for v in friction.values()) < 0


def test_the_violation_is_printed_reported_and_saved(inconsistent, tmp_path, capsys):
    model, arguments = inconsistent
    model.print()
    assert "not that of rigid bodies" in capsys.readouterr().out
    quality = fit_quality(model, arguments)
    assert quality["physical_consistency"] == model.physical_consistency_
    assert any("not that of rigid bodies" in line for line in quality_lines(quality))
    path = tmp_path / "arm.json"
    model.save(path)
    loaded = px.XLSINDy.load(path)
    assert loaded.physical_consistency_ == model.physical_consistency_
    np.testing.assert_array_equal(loaded.coefficients(), model.coefficients())
    assert isinstance(loaded.optimizer, px.PhysicalOptimizer)
    assert loaded.optimizer.get_params()["base_parameters"] == "selected"
    trajectory = arguments["x"][0] if isinstance(arguments["x"], list) else arguments["x"]
    velocities = np.gradient(trajectory, axis=0)
    np.testing.assert_allclose(loaded.predict(trajectory[:20], velocities[:20]),
                               model.predict(trajectory[:20], velocities[:20]))
    pickled = pickle.loads(pickle.dumps(model))
    assert pickled.physical_consistency_ == model.physical_consistency_
    np.testing.assert_array_equal(pickled.coefficients(), model.coefficients())


def test_a_catalog_without_physical_meaning_is_fitted_as_by_the_selecting_optimizer():
    c = px.Coordinates(["x"])
    lib = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2])
    t = np.linspace(0, 5, 501)
    x = (np.sin(t) + np.sin(3 * t))[:, None]
    xd = (np.cos(t) + 3 * np.cos(3 * t))[:, None]
    xdd = (-np.sin(t) - 9 * np.sin(3 * t))[:, None]
    arguments = {"x": x, "t": t, "x_dot": xd, "x_ddot": xdd, "u": 2 * xdd + 3 * x}
    plain = px.XLSINDy(lib, px.ExplicitOptimizer()).fit(**arguments)
    physical = px.XLSINDy(lib, px.PhysicalOptimizer()).fit(**arguments)
    np.testing.assert_allclose(physical.coefficients(), plain.coefficients())
    assert physical.physical_consistency_ is None and plain.physical_consistency_ is None


def test_the_structure_follows_the_columns_of_sub_problems():
    structure = PhysicalStructure.from_maps([{"b.m": 1.0}, {"b.mcx": 1.0, "j.armature": 2.0}],
                                            base_columns=[1, 3], friction_columns=[4])
    theta = np.arange(20.0).reshape(4, 5)
    problem = CatalogProblem.from_arrays(theta, 2, [0], physical=structure)
    sub = problem.subproblem(np.array([True, True]), np.array([0, 3, 4]))
    assert sub.physical.base_columns.tolist() == [1]
    assert sub.physical.friction_columns.tolist() == [2]
    np.testing.assert_array_equal(sub.physical.combination, structure.combination[[1]])
    with pytest.raises(TypeError, match="physical"):
        CatalogProblem.from_arrays(theta, 2, [0], physical={"b.m": 1.0})
    with pytest.raises(ValueError, match="physical"):
        CatalogProblem.from_arrays(theta[:, :3], 2, [0], physical=structure)


@pytest.mark.parametrize("params, match", [
    ({"optimizer": px.ImplicitOptimizer()}, "optimizer"),
    ({"base_parameters": "some"}, "base_parameters"),
    ({"tolerance": -1.0}, "tolerance"),
    ({"solver": 3}, "solver"),
])
def test_bad_parameters_are_named(params, match):
    theta = np.column_stack([[1.0, 2.0, 3.0], [0.5, 1.0, 1.5]])
    with pytest.raises((TypeError, ValueError), match=match):
        px.PhysicalOptimizer(**params).fit_catalog(theta, 1, [0])


def test_the_optimizer_is_an_estimator_that_round_trips_its_spec():
    optimizer = px.PhysicalOptimizer(px.EnsembleOptimizer(n_models=4), base_parameters="all",
                                     tolerance=1e-6, solver="CLARABEL")
    assert clone(optimizer).get_params()["base_parameters"] == "all"
    loaded = optimizer_from_spec(optimizer.to_spec())
    assert loaded.get_params()["optimizer"].get_params()["n_models"] == 4
    assert loaded.get_params()["solver"] == "CLARABEL"
    assert loaded.requires_forces and loaded.can_refit


@pytest.mark.parametrize("report", [
    {"consistent": "no"},
    {"consistent": False, "cost": 0.1, "negative_friction": [3],
     "min_pseudo_inertia_eigenvalue": 0.0},
    {"consistent": False, "cost": [], "negative_friction": [],
     "min_pseudo_inertia_eigenvalue": 0.0},
])
def test_a_file_with_a_bad_consistency_report_is_refused(inconsistent, tmp_path, report):
    import json

    model, _ = inconsistent
    path = tmp_path / "arm.json"
    model.save(path)
    document = json.loads(path.read_text())
    document["training"]["physical_consistency"] = report
    path.write_text(json.dumps(document))
    with pytest.raises(ValueError, match="physical_consistency"):
        px.XLSINDy.load(path)


def test_the_default_fit_estimates_every_parameter_consistently(arm):
    """A kinematic catalog has no spurious term: the default fit keeps every column and
    refits under rigid bodies' constraints. Every joint's torque, the last one's (a
    hundredth of the first's) too, is predicted on a fresh noise-free run, and the mass
    matrix matches MuJoCo's, positive definite."""
    system, catalog = arm
    data = generate_dataset(system, n_trajectories=2, duration=4.0, seed=2, noise=0.05,
                            sample_every=2, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = px.XLSINDy(catalog.library()).fit(**data.fit_arguments(forces="tau"))
    assert isinstance(model.optimizer_, px.PhysicalOptimizer)
    lagrange = [j for j, c in enumerate(model.feature_library_.categories_) if c == "lagrange"]
    assert np.all(model.coef_[lagrange] != 0)
    fresh = generate_dataset(system, n_trajectories=1, duration=3.0, seed=7,
                             progress=False).trajectories[0]
    predicted = model.predict_forces(fresh.q, fresh.qd, fresh.qdd)
    error = (np.sqrt(np.mean((predicted - fresh.tau) ** 2, axis=0))
             / np.sqrt(np.mean(fresh.tau**2, axis=0)))
    assert error.max() < 0.05
    mass, reference = _mass_matrices(model, system, fresh, every=50)
    for identified, exact in zip(mass, reference, strict=True):
        assert np.linalg.norm(identified - exact) < 0.03 * np.linalg.norm(exact)
        assert np.linalg.eigvalsh(identified)[0] > 0


@pytest.mark.parametrize("row_scale", [1e-6, 1.0, 1e9])
def test_the_consistent_refit_does_not_depend_on_the_rows_scale(arm, row_scale):
    """Whitened rows of noise-free data are 1e9 in size: the semidefinite program still
    keeps a consistent estimate where it is (it returned nonsense once)."""
    from pysindy_xl.physical.sdp import consistent_least_squares

    _, catalog = arm
    structure = _structure(catalog)
    base = catalog.base_parameters
    x = np.random.default_rng(0).normal(size=(400, len(base))) * row_scale
    coef, _, cost = consistent_least_squares(x, structure.select(np.arange(len(base))), base)
    assert cost < 1e-8  # PhysicalOptimizer's tolerance: kept as it is
    np.testing.assert_allclose(coef, base, atol=1e-4 * np.abs(base).max())
