"""MassMatrixDynamics: mass-matrix form, accelerations, simulation and its failure modes."""

import numpy as np
import pytest
import sympy as sp
from scipy.special import ellipk

import pysindy_xl as px
from pysindy_xl.dynamics import force_function

ONE = px.Coordinates(["x"])
X, XD, XDD, TAU = ONE.q[0], ONE.qd[0], ONE.qdd[0], ONE.tau[0]


def test_mass_matrix_and_forcing_of_a_known_system():
    coords = px.Coordinates(["a", "b"])
    (a, b), bd, (add, bdd), (ta, tb) = coords.q, coords.qd[1], coords.qdd, coords.tau
    equations = [2 * add + sp.cos(b) * bdd + 3 * a - ta,
                 sp.cos(b) * add + bdd + sp.sin(b) + sp.Rational(1, 2) * bd - tb]
    dyn = px.MassMatrixDynamics(coords, equations)
    assert dyn.mass_matrix_expr == sp.Matrix([[2, sp.cos(b)], [sp.cos(b), 1]])
    expected_forcing = sp.Matrix([ta - 3 * a, tb - sp.sin(b) - bd / 2])
    assert sp.expand(dyn.forcing_expr - expected_forcing) == sp.zeros(2, 1)
    rng = np.random.default_rng(0)
    q, qd, tau = rng.normal(size=(20, 2)), rng.normal(size=(20, 2)), rng.normal(size=(20, 2))
    acc = dyn.accelerations(q, qd, tau)
    for k in range(20):
        m = np.array([[2, np.cos(q[k, 1])], [np.cos(q[k, 1]), 1]])
        f = np.array([tau[k, 0] - 3 * q[k, 0], tau[k, 1] - np.sin(q[k, 1]) - qd[k, 1] / 2])
        np.testing.assert_allclose(acc[k], np.linalg.solve(m, f), rtol=1e-12, atol=1e-12)
    mass, forcing = dyn.mass_and_forcing(np.column_stack([q, qd, np.zeros((20, 2)), tau,
                                                          np.zeros(20)]))
    assert mass.shape == (20, 2, 2) and forcing.shape == (20, 2)
    np.testing.assert_allclose(mass[:, 0, 0], 2.0)


def test_accelerations_match_cart_pole_ground_truth(cart_pole_system):
    system = cart_pole_system
    coords = system.coords
    equations = list(system.mass_matrix_expr * sp.Matrix(coords.qdd) - system.forcing_expr)
    dyn = px.MassMatrixDynamics(coords, equations)
    assert sp.simplify(dyn.mass_matrix_expr - system.mass_matrix_expr) == sp.zeros(2, 2)
    rng = np.random.default_rng(1)
    q, qd = rng.uniform(-2, 2, (100, 2)), rng.uniform(-2, 2, (100, 2))
    tau = rng.normal(size=(100, 2))
    np.testing.assert_allclose(dyn.accelerations(q, qd, tau), system.accelerations(q, qd, tau),
                               rtol=1e-10, atol=1e-10)
    # unforced when tau is omitted
    np.testing.assert_allclose(dyn.accelerations(q, qd), system.accelerations(q, qd),
                               rtol=1e-10, atol=1e-10)


def test_simulation_matches_cart_pole_ground_truth(cart_pole_system):
    from ground_truth import random_force, random_initial_state

    system = cart_pole_system
    coords = system.coords
    equations = list(system.mass_matrix_expr * sp.Matrix(coords.qdd) - system.forcing_expr)
    dyn = px.MassMatrixDynamics(coords, equations)
    t = np.linspace(0, 3, 301)
    force, x0 = random_force(system, 7), random_initial_state(system, 7)
    truth = system.simulate(x0, t, force)
    sim = dyn.simulate(x0, t, u=force, rtol=1e-10, atol=1e-10)
    assert sim.shape == (len(t), 4)
    np.testing.assert_allclose(sim[:, :2], truth["q"], atol=1e-6)
    np.testing.assert_allclose(sim[:, 2:], truth["qd"], atol=1e-6)


def test_harmonic_oscillator_simulation_is_accurate():
    dyn = px.MassMatrixDynamics(ONE, [XDD + 4 * X])
    t = np.linspace(0, 10, 1001)
    sim = dyn.simulate([1.0, 0.0], t, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(sim[:, 0], np.cos(2 * t), atol=1e-7)
    np.testing.assert_allclose(sim[:, 1], -2 * np.sin(2 * t), atol=1e-7)
    assert np.all(sim[0] == [1.0, 0.0])


@pytest.mark.parametrize("method", ["RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA"])
def test_every_solver_runs(method):
    dyn = px.MassMatrixDynamics(ONE, [XDD + X])
    t = np.linspace(0, 2, 21)
    sim = dyn.simulate([0.0, 1.0], t, method=method, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(sim[:, 0], np.sin(t), atol=1e-5)


def test_forces_as_array_and_callable():
    dyn = px.MassMatrixDynamics(ONE, [XDD - TAU])  # x'' = u
    t = np.linspace(0, 2, 41)
    # a ramp is interpolated exactly: x = t^3 / 6
    ramp = dyn.simulate([0.0, 0.0], t, u=t[:, None])
    np.testing.assert_allclose(ramp[:, 0], t**3 / 6, atol=1e-8)
    wave = dyn.simulate([0.0, 0.0], t, u=lambda s: np.array([np.cos(s)]))
    np.testing.assert_allclose(wave[:, 0], 1 - np.cos(t), atol=1e-8)
    free = dyn.simulate([1.0, 0.5], t)
    np.testing.assert_allclose(free[:, 0], 1 + 0.5 * t, atol=1e-10)


def test_time_dependent_equations_use_absolute_time():
    dyn = px.MassMatrixDynamics(ONE, [XDD - ONE.t])  # x'' = t
    t = np.linspace(1.0, 3.0, 21)
    sim = dyn.simulate([0.0, 0.0], t)
    np.testing.assert_allclose(sim[:, 0], (t**3 - 1) / 6 - (t - 1) / 2, atol=1e-8)


@pytest.mark.parametrize("equation", [XDD**2 + X, sp.sin(XDD), XDD * sp.exp(XDD), 1 / (1 + XDD)])
def test_nonlinear_in_accelerations_rejected(equation):
    with pytest.raises(ValueError, match="equations: not linear in the accelerations"):
        px.MassMatrixDynamics(ONE, [equation])


def test_product_of_accelerations_rejected():
    coords = px.Coordinates(["a", "b"])
    with pytest.raises(ValueError, match="not linear"):
        px.MassMatrixDynamics(coords, [coords.qdd[0] * coords.qdd[1], coords.qdd[1]])


def test_state_dependent_mass_is_accepted():
    dyn = px.MassMatrixDynamics(ONE, [(1 + X**2) * XDD + XD * X])
    assert dyn.mass_matrix_expr == sp.Matrix([[1 + X**2]])
    acc = dyn.accelerations(np.array([[1.0], [2.0]]), np.array([[3.0], [1.0]]))
    np.testing.assert_allclose(acc[:, 0], [-3.0 / 2.0, -2.0 / 5.0])


def test_constructor_checks():
    with pytest.raises(ValueError, match="equations: expected 1 equations, got 2"):
        px.MassMatrixDynamics(ONE, [XDD, XDD])
    with pytest.raises(TypeError, match="coords"):
        px.MassMatrixDynamics(["x"], [XDD])


def test_singular_mass_matrix_in_accelerations():
    dyn = px.MassMatrixDynamics(ONE, [X * XDD + 1])  # mass x: singular at x = 0
    q = np.array([[1.0], [0.0], [2.0], [0.0]])
    with pytest.raises(px.SingularMassMatrixError, match="singular at 2 of 4 states") as info:
        dyn.accelerations(q, np.zeros((4, 1)))
    np.testing.assert_array_equal(info.value.indices, [1, 3])
    assert isinstance(info.value, RuntimeError)


def test_mass_matrix_singular_everywhere():
    coords = px.Coordinates(["a", "b"])
    # the equation of b contains no acceleration at all
    dyn = px.MassMatrixDynamics(coords, [coords.qdd[0] + coords.q[0], coords.q[1] - coords.tau[1]])
    with pytest.raises(px.SingularMassMatrixError) as info:
        dyn.accelerations(np.zeros((3, 2)), np.zeros((3, 2)))
    np.testing.assert_array_equal(info.value.indices, [0, 1, 2])
    x0 = np.array([0.1, 0.2, 0.3, 0.4])
    with pytest.raises(px.SimulationError) as info:
        dyn.simulate(x0, np.linspace(0, 1, 11))
    err = info.value
    assert err.reason == "singular mass matrix"
    assert "singular mass matrix" in str(err)
    np.testing.assert_array_equal(err.states, x0[None, :])
    np.testing.assert_array_equal(err.t, [0.0])
    assert err.t_failed == 0.0


def test_unstable_model_diverges_with_partial_trajectory():
    # x'' = x^3 from x = 1, v = 0 blows up at T = sqrt(2) K(1/2) (energy v^2/2 - x^4/4 = -1/4)
    blow_up = np.sqrt(2) * ellipk(0.5)
    dyn = px.MassMatrixDynamics(ONE, [XDD - X**3])
    t = np.linspace(0, 5, 501)
    x0 = np.array([1.0, 0.0])
    with pytest.raises(px.SimulationError, match="diverged") as info:
        dyn.simulate(x0, t, rtol=1e-10, atol=1e-10)
    err = info.value
    assert err.reason == "diverged"
    assert 1.5 < err.t_failed <= blow_up
    k = len(err.t)
    assert k > 100 and err.states.shape == (k, 2)
    np.testing.assert_array_equal(err.t, t[:k])
    assert err.t[-1] <= err.t_failed
    np.testing.assert_array_equal(err.states[0], x0)
    assert np.all(np.isfinite(err.states))
    assert np.max(np.abs(err.states)) <= 1e6
    # the partial trajectory is the true one: energy is conserved while it is moderate
    moderate = np.abs(err.states[:, 0]) < 5
    energy = err.states[moderate, 1] ** 2 / 2 - err.states[moderate, 0] ** 4 / 4
    np.testing.assert_allclose(energy, -0.25, atol=1e-5)


def test_divergence_bound_is_respected():
    dyn = px.MassMatrixDynamics(ONE, [XDD - X])  # x = cosh(t)
    t = np.linspace(0, 10, 101)
    with pytest.raises(px.SimulationError) as info:
        dyn.simulate([1.0, 0.0], t, divergence_bound=100.0)
    err = info.value
    assert err.reason == "diverged"
    assert np.max(np.abs(err.states)) <= 100.0
    assert err.t[-1] < np.arccosh(100.0) + 0.11
    np.testing.assert_allclose(err.states[:, 0], np.cosh(err.t), rtol=1e-5)


def test_max_evaluations_bound():
    dyn = px.MassMatrixDynamics(ONE, [XDD + 100 * X])
    with pytest.raises(px.SimulationError) as info:
        dyn.simulate([1.0, 0.0], np.linspace(0, 50, 501), max_evaluations=200)
    err = info.value
    assert err.reason == "too many evaluations"
    assert 1 <= len(err.t) < 501
    np.testing.assert_array_equal(err.states[0], [1.0, 0.0])
    np.testing.assert_allclose(err.states[:, 0], np.cos(10 * err.t), atol=1e-5)


def test_timeout_bound():
    dyn = px.MassMatrixDynamics(ONE, [XDD + 100 * X])
    with pytest.raises(px.SimulationError) as info:
        dyn.simulate([1.0, 0.0], np.linspace(0, 50, 501), timeout=0.0)
    assert info.value.reason == "timeout"


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"x0": [1.0]}, r"x0: expected 2 finite values"),
        ({"x0": [1.0, 0.0, 0.0]}, r"x0: expected 2 finite values"),
        ({"x0": [np.nan, 0.0]}, r"x0: expected 2 finite values"),
        ({"x0": [np.inf, 0.0]}, r"x0: expected 2 finite values"),
        ({"t": [0.0]}, r"t: expected a 1-D array of at least 2 times"),
        ({"t": 1.0}, r"t: expected a 1-D array"),
        ({"t": [[0.0, 1.0]]}, r"t: expected a 1-D array"),
        ({"t": [0.0, 1.0, 1.0]}, r"t: times must be strictly increasing"),
        ({"t": [1.0, 0.0]}, r"t: times must be strictly increasing"),
        ({"t": [0.0, np.nan, 2.0]}, r"t: contains NaN or inf"),
        ({"u": np.zeros((3, 1))}, r"u: expected an array of shape \(len\(t\), n\) = \(2, 1\)"),
        ({"u": np.zeros((2, 2))}, r"u: expected an array of shape"),
        ({"u": np.zeros(2)}, r"u: expected an array of shape"),
        ({"u": np.array([[0.0], [np.nan]])}, r"u: contains NaN or inf"),
        ({"u": lambda s: np.zeros(2)}, r"u: the callable must return an array of shape \(1,\)"),
        ({"u": lambda s: np.array([np.nan])}, r"u: u\(.*\) returned"),
        ({"method": "Euler"}, r"method: expected one of"),
    ],
)
def test_simulate_bad_input(kwargs, match):
    dyn = px.MassMatrixDynamics(ONE, [XDD + X - TAU])
    args = {"x0": [1.0, 0.0], "t": [0.0, 1.0], **kwargs}
    with pytest.raises(ValueError, match=match):
        dyn.simulate(args.pop("x0"), args.pop("t"), **args)


@pytest.mark.parametrize(
    "q, qd, tau, match",
    [
        (np.zeros((3, 2)), np.zeros((3, 1)), None, r"qd: expected shape \(3, 2\)"),
        (np.zeros(3), np.zeros(3), None, r"q: expected a 2-D array"),
        (np.zeros((3, 1)), np.zeros((4, 1)), None, r"qd: expected shape \(3, 1\)"),
        (np.zeros((3, 1)), np.zeros((3, 1)), np.zeros((2, 1)), r"tau: expected shape"),
    ],
)
def test_accelerations_bad_shapes(q, qd, tau, match):
    dyn = px.MassMatrixDynamics(ONE, [XDD + X - TAU])
    with pytest.raises(ValueError, match=match):
        dyn.accelerations(q, qd, tau)


@pytest.mark.parametrize("where", ["q", "qd", "tau"])
def test_accelerations_reject_nan(where):
    dyn = px.MassMatrixDynamics(ONE, [XDD + X - TAU])
    data = {"q": np.zeros((3, 1)), "qd": np.zeros((3, 1)), "tau": np.zeros((3, 1))}
    data[where][1, 0] = np.nan
    with pytest.raises(ValueError, match=where):
        dyn.accelerations(data["q"], data["qd"], data["tau"])


def test_force_function_interpolates_and_holds_ends():
    t = np.array([0.0, 1.0, 2.0])
    u = np.array([[0.0, 1.0], [2.0, 1.0], [4.0, -1.0]])
    f = force_function(u, t, 2)
    np.testing.assert_allclose(f(0.5), [1.0, 1.0])
    np.testing.assert_allclose(f(1.5), [3.0, 0.0])
    np.testing.assert_allclose(f(5.0), [4.0, -1.0])
    np.testing.assert_array_equal(force_function(None, t, 2)(0.3), [0.0, 0.0])


def test_non_numeric_u_names_the_argument():
    dyn = px.MassMatrixDynamics(ONE, [XDD + X - TAU])
    with pytest.raises((ValueError, TypeError)) as info:
        dyn.simulate([1.0, 0.0], [0.0, 1.0], u="abc")
    assert str(info.value).startswith("u:")
