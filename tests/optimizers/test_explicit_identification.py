"""End-to-end explicit identification against sympy.physics.mechanics ground truth.

Each system is simulated with scipy under random sum-of-sines forces on every coordinate,
identified with a paper-style Lagrange catalog plus classical viscous friction, and checked
coefficient by coefficient against the true Lagrangian expanded in the catalog, then by
simulating a fresh validation trajectory.
"""

import numpy as np
import pytest
from ground_truth import random_force, random_initial_state
from support.paper import paper_catalog, true_coefficients

import pysindy_xl as px

SYSTEMS = {
    "cart_pole": ("cart_pole_system", [1]),
    "double_pendulum": ("double_pendulum_system", [0, 1]),
    "cart_double_pendulum": ("cart_double_pendulum_system", [1, 2]),
}


def _dataset(system, seed, duration=20.0, dt=0.005):
    t = np.arange(0.0, duration, dt)
    return system.simulate(random_initial_state(system, seed), t, random_force(system, seed))


def _check_model(model, system, library, rel_tol):
    true = true_coefficients(system, library)
    coef = model.coefficients()
    names = np.array(model.get_feature_names())
    support = true != 0
    false_terms = names[(coef != 0) & ~support]
    missed = names[(coef == 0) & support]
    assert not len(false_terms), f"false terms: {false_terms}"
    assert not len(missed), f"missed terms: {missed}"
    rel = np.abs(coef[support] - true[support]) / np.abs(true[support])
    worst = names[support][np.argmax(rel)]
    assert rel.max() < rel_tol, f"worst relative error {rel.max():.2e} on {worst}"


def _check_validation(model, system, seed):
    t = np.arange(0.0, 10.0, 0.01)
    force = random_force(system, seed)
    x0 = random_initial_state(system, seed)
    truth = system.simulate(x0, t, force)
    sim = model.simulate(x0, t, u=lambda s: force(s))
    rmse = np.sqrt(np.mean((sim[:, : system.n] - truth["q"]) ** 2))
    assert rmse < 1e-2, f"validation position RMSE {rmse:.3e}"
    return rmse


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SYSTEMS))
def test_explicit_recovery_with_measured_derivatives(name, request):
    fixture, angles = SYSTEMS[name]
    system = request.getfixturevalue(fixture)
    data = _dataset(system, seed=1)
    library = paper_catalog(system.coords, angles)
    assert library.fit().n_output_features_ > 20
    model = px.XLSINDy(library, px.ExplicitOptimizer())
    model.fit(data["q"], data["t"], x_dot=data["qd"], x_ddot=data["qdd"], u=data["tau"])
    _check_model(model, system, library, rel_tol=1e-2)
    _check_validation(model, system, seed=101)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SYSTEMS))
def test_explicit_recovery_from_positions_only(name, request):
    fixture, angles = SYSTEMS[name]
    system = request.getfixturevalue(fixture)
    runs = [_dataset(system, seed=s, duration=15.0) for s in (2, 3)]
    library = paper_catalog(system.coords, angles)
    model = px.XLSINDy(library, px.ExplicitOptimizer())
    model.fit([r["q"] for r in runs], [r["t"] for r in runs], u=[r["tau"] for r in runs])
    _check_model(model, system, library, rel_tol=5e-2)
    _check_validation(model, system, seed=102)


def test_lasso_and_pysindy_optimizers_recover_cart_pole(cart_pole_system):
    import pysindy as ps

    system = cart_pole_system
    data = _dataset(system, seed=4, duration=10.0, dt=0.01)
    library = paper_catalog(system.coords, [1])
    for method in ("lasso", "proximal", ps.STLSQ(threshold=1e-3)):
        model = px.XLSINDy(library, px.ExplicitOptimizer(method=method, alpha=1e-5, max_iter=20000))
        model.fit(data["q"], data["t"], x_dot=data["qd"], x_ddot=data["qdd"], u=data["tau"])
        _check_model(model, system, library, rel_tol=1e-2)


def test_dependent_columns_are_reported(cart_pole_system):
    system = cart_pole_system
    data = _dataset(system, seed=5, duration=5.0, dt=0.01)
    library = paper_catalog(system.coords, [1])
    model = px.XLSINDy(library).fit(data["q"], data["t"], x_dot=data["qd"], x_ddot=data["qdd"],
                                    u=data["tau"])
    dropped = model.dropped_features_
    # theta_dot**2 is kept; one of the cos^2 / sin^2 variants is an exact combination
    assert "L[theta_dot**2]" not in dropped
    assert dropped.get("L[theta_dot**2*cos(theta)**2]") == "linear combination" or \
        dropped.get("L[theta_dot**2*sin(theta)**2]") == "linear combination"
    # x_dot * f(theta) is not a total derivative, but theta_dot * f(theta) is: zero column
    assert dropped["L[theta_dot*cos(theta)]"] == "zero column"
    assert all(model.coefficients()[model.get_feature_names().index(k)] == 0 for k in dropped)
