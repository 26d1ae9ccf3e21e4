"""Reference catalogs: sizes, the true model inside them, and identification on MuJoCo data."""

import numpy as np
import pytest
import sympy as sp

import pysindy_xl as px
from pysindy_xl.mujoco import (
    SYSTEMS,
    CartPole,
    DoublePendulum,
    classical_terms,
    generate_dataset,
    get_system,
    lagrange_terms,
    reference_catalog,
    true_coefficients,
)


def test_lagrange_terms_are_velocity_times_trig_monomials():
    system = get_system("cart-pole")
    terms = lagrange_terms(system)
    x, theta = system.coords.q
    xd, thd = system.coords.qd
    assert len(terms) == 35 == len(set(terms))
    for expected in (xd**2, thd * xd * sp.cos(theta), thd**2, sp.cos(theta),
                     thd**2 * sp.sin(theta) ** 2):
        assert expected in terms
    assert all(x not in t.free_symbols for t in terms)  # the cart position is not an angle
    assert len(lagrange_terms("double-pendulum")) == 6 * 15 - 1
    assert len(lagrange_terms("cart-double-pendulum")) == 10 * 15 - 1
    assert len(lagrange_terms("cart-pole", velocity_degree=1, trig_degree=1)) == 3 * 3 - 1


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_classical_catalog_contains_every_euler_lagrange_term(name):
    system = get_system(name)
    terms = lagrange_terms(system)
    found, mask = classical_terms(system, terms)
    features = {(m, i) for k, m in enumerate(found) for i in range(system.n) if mask[k, i]}
    # the Euler-Lagrange columns as the package's LagrangeLibrary computes them
    matrix = px.LagrangeLibrary(system.coords, terms).fit().symbolic_matrix()
    needed = set()
    for j in range(matrix.shape[1]):
        for i in range(system.n):
            for term in sp.Add.make_args(sp.expand(matrix[i, j])):
                if term != 0:
                    needed.add((term.as_coeff_Mul()[1], i))
    assert needed == features  # all of them, and nothing else (smallest)


@pytest.mark.parametrize("name", sorted(SYSTEMS))
@pytest.mark.parametrize("kind", ["mixed", "classical"])
def test_true_model_satisfies_the_regression_on_mujoco_data(name, kind):
    """Theta @ xi_true = 0 on MuJoCo samples: catalogs, truth and data agree."""
    system = get_system(name)
    catalog = reference_catalog(system, kind).fit()
    xi, missing = true_coefficients(system, catalog, strict=True)
    assert missing == []
    assert xi[catalog.force_columns_].tolist() == [-1.0]
    tr = generate_dataset(system, n_trajectories=1, duration=2.0, seed=1, sample_every=5,
                          progress=False).trajectories[0]
    theta = catalog.transform(px.stack_variables(tr.q, tr.qd, tr.qdd, tr.tau, tr.t))
    residual = theta @ xi
    scale = np.abs(theta) @ np.abs(xi)
    assert np.max(np.abs(residual) / scale.max()) < 1e-10


def test_friction_options_and_representability():
    catalog = reference_catalog(DoublePendulum(), "mixed", friction="diagonal").fit()
    assert sum(name.startswith("C_") for name in catalog.get_feature_names()) == 2
    xi, missing = true_coefficients(DoublePendulum(), catalog)
    assert len(missing) == 2 and all("theta" in m for m in missing)  # the coupling terms
    with pytest.raises(ValueError, match="lacks"):
        true_coefficients(DoublePendulum(), catalog, strict=True)
    full = reference_catalog("cart-pole", "mixed", friction="full").fit()
    assert sum(name.startswith("C_") for name in full.get_feature_names()) == 4
    auto = reference_catalog("cart-pole", "mixed").fit()
    assert [n for n in auto.get_feature_names() if n.startswith("C_")] == [
        "C_x[x_dot]", "C_theta[theta_dot]"]
    # a Lagrange-only catalog cannot hold friction; without damping the truth is in it
    _, missing = true_coefficients("cart-pole", reference_catalog("cart-pole", "lagrange"))
    assert len(missing) == 2
    undamped = CartPole(cart_damping=0, pole_damping=0)
    _, missing = true_coefficients(undamped, reference_catalog(undamped, "lagrange"), strict=True)
    assert missing == []
    with pytest.raises(ValueError, match="kind"):
        reference_catalog("cart-pole", "newtonian")
    with pytest.raises(ValueError, match="friction"):
        reference_catalog("cart-pole", friction="some")


@pytest.mark.parametrize("kind", ["mixed", "classical", "lagrange"])
def test_cart_pole_identified_exactly_from_mujoco_data(kind):
    system = CartPole(cart_damping=0, pole_damping=0) if kind == "lagrange" else CartPole()
    data = generate_dataset(system, n_trajectories=2, duration=5.0, seed=2, sample_every=4,
                            progress=False)
    catalog = reference_catalog(system, kind)
    model = px.XLSINDy(catalog, px.ExplicitOptimizer()).fit(**data.fit_arguments())
    truth, _ = true_coefficients(system, model.feature_library_, strict=True)
    coef = model.coefficients()
    np.testing.assert_array_equal(coef != 0, truth != 0)
    np.testing.assert_allclose(coef, truth, atol=1e-6 * np.abs(truth).max())


def test_interlink_with_joint_forces_matches_generalized_forces():
    """Fitting joint forces u with interlink B gives the same model as fitting tau = B u."""
    system = DoublePendulum()
    data = generate_dataset(system, n_trajectories=1, duration=3.0, seed=3, sample_every=5,
                            progress=False)
    with_tau = px.XLSINDy(reference_catalog(system), px.ExplicitOptimizer()).fit(
        **data.fit_arguments("tau"))
    with_u = px.XLSINDy(reference_catalog(system, interlink=system.force_matrix()),
                        px.ExplicitOptimizer()).fit(**data.fit_arguments("u"))
    np.testing.assert_allclose(with_u.coefficients(), with_tau.coefficients(), atol=1e-8)
    truth, _ = true_coefficients(system, with_u.feature_library_, strict=True)
    np.testing.assert_allclose(with_u.coefficients(), truth, atol=1e-6 * np.abs(truth).max())
