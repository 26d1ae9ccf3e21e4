"""Planners on known models: iLQR against the Riccati recursion of a double integrator and the
LQR of the cart-pole at the upright; the sampling planner within its limits; the LQR gain.

Ground truth: NumPy Riccati recursions and central finite differences of the true cart-pole
(``ground_truth`` / MuJoCo's parameters), computed independently of JAX's derivatives."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

import pysindy_xl as px
from pysindy_xl.control import (
    discrete_dynamics,
    discrete_lqr,
    ilqr,
    linearize,
    quadratic_cost,
    sampling_planner,
)
from pysindy_xl.control.discrete import actuation_matrix, continuous_dynamics
from pysindy_xl.mujoco import get_system

DT = 0.1
A = np.array([[1.0, DT], [0.0, 1.0]])  # exact discretization of x'' = u, zero-order hold
B = np.array([[DT ** 2 / 2], [DT]])


def _double_integrator():
    return discrete_dynamics(lambda x, tau: jnp.array([x[1], tau[0]]), DT, [[1.0]], substeps=1)


def _riccati_controls(x0, q, r, qf, horizon):
    """Optimal open-loop controls of the finite-horizon LQR, by the backward recursion."""
    p, gains = qf, []
    for _ in range(horizon):
        k = np.linalg.solve(r + B.T @ p @ B, B.T @ p @ A)
        p = q + A.T @ p @ (A - B @ k)
        gains.append(k)
    x, controls = np.asarray(x0, float), []
    for k in reversed(gains):
        u = -k @ x
        controls.append(u)
        x = A @ x + B @ u
    return np.array(controls), x


def test_ilqr_converges_to_the_riccati_solution_of_a_double_integrator():
    q, r, qf = np.diag([1.0, 0.1]), np.array([[0.01]]), np.diag([100.0, 10.0])
    with jax.enable_x64(True):
        cost = quadratic_cost([0.0, 0.0], q, r, terminal_weights=qf)
        solution = ilqr(_double_integrator(), cost, jnp.array([1.0, -0.5]), jnp.zeros((30, 1)))
        expected, final = _riccati_controls([1.0, -0.5], q, r, qf, 30)
        np.testing.assert_allclose(np.asarray(solution.controls), expected, atol=1e-8)
        np.testing.assert_allclose(np.asarray(solution.states[-1]), final, atol=1e-8)
        assert int(solution.iterations) <= 5  # linear-quadratic: exact after one step


@pytest.mark.parametrize("change, error, match", [
    ({"x0": [np.nan, 0.0]}, ValueError, "x0: contains NaN or inf"),
    ({"x0": [1j, 0.0]}, TypeError, "x0: expected real numbers, got complex values"),
    ({"controls": np.zeros((0, 1))}, ValueError, r"controls: expected an initial guess \(H, m\)"),
    ({"step": 3}, TypeError, "step: expected a callable"),
    ({"tolerance": -1.0}, ValueError, "tolerance: expected a real number >= 0"),
    ({"regularization": float("nan")}, ValueError, "regularization: expected a real number"),
])
def test_ilqr_refuses_bad_input_by_name(change, error, match):
    cost = quadratic_cost([0.0, 0.0], [1.0, 0.1], [0.01])
    arguments = {"step": _double_integrator(), "cost": cost, "x0": [1.0, 0.0],
                 "controls": np.zeros((10, 1)), **change}
    with pytest.raises(error, match=match):
        ilqr(**arguments)


@pytest.mark.parametrize("arguments, error, match", [
    (([0.0, 0.0], [-1.0, 1.0], [1.0]), ValueError, "state_weights: expected symmetric positive"),
    (([0.0, 0.0], [1.0, 1.0], [[-1.0]]), ValueError, "control_weights: expected symmetric"),
    (([0.0, 0.0], [[1.0, 2.0], [0.0, 1.0]], [1.0]), ValueError, "state_weights: expected"),
    (([0.0, np.nan], [1.0, 1.0], [1.0]), ValueError, "goal: contains NaN or inf"),
    (([0.0, 0.0], [1.0, 1.0], [1j]), TypeError, "control_weights: expected real numbers"),
])
def test_a_cost_without_a_minimum_is_refused(arguments, error, match):
    """Weights that are not positive semidefinite make a cost that a planner lowers by
    leaving the goal."""
    with pytest.raises(error, match=match):
        quadratic_cost(*arguments)


def test_discrete_dynamics_needs_a_function():
    with pytest.raises(TypeError, match="f: expected a callable"):
        discrete_dynamics(3, DT, [[1.0]])


def test_ilqr_respects_the_control_limit():
    with jax.enable_x64(True):
        cost = quadratic_cost([0.0, 0.0], [1.0, 0.1], [1e-4], terminal_weights=[100.0, 10.0])
        solution = ilqr(_double_integrator(), cost, jnp.array([1.0, 0.0]), jnp.zeros((40, 1)),
                        control_limit=1.5)
        controls = np.asarray(solution.controls)
        assert np.max(np.abs(controls)) <= 1.5 + 1e-12
        assert np.max(np.abs(controls)) > 1.4  # the limit binds
        assert np.all(np.abs(np.asarray(solution.states[-1])) < 0.05)


def _true_cart_pole():
    system = get_system("cart-pole")
    equations = [e - tau for e, tau in zip(system.equations_of_motion(), system.coords.tau,
                                           strict=True)]
    return system, px.MassMatrixDynamics(system.coords, equations)


def _finite_difference_linearization(dynamics, x, dt, eps=1e-6):
    """A, B of the RK4 step (one step of dt) by central differences of the NumPy model."""
    def step(state, force):
        f = lambda s: dynamics.state_derivative(s, np.array([force, 0.0]))  # noqa: E731
        k1 = f(state)
        k2 = f(state + 0.5 * dt * k1)
        k3 = f(state + 0.5 * dt * k2)
        k4 = f(state + dt * k3)
        return state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    a = np.column_stack([(step(x + eps * e, 0.0) - step(x - eps * e, 0.0)) / (2 * eps)
                         for e in np.eye(4)])
    b = ((step(x, eps) - step(x, -eps)) / (2 * eps))[:, None]
    return a, b


def test_linearization_and_lqr_match_finite_differences_at_the_upright():
    system, dynamics = _true_cart_pole()
    upright = np.array([0.0, np.pi, 0.0, 0.0])
    with jax.enable_x64(True):
        step = discrete_dynamics(continuous_dynamics(dynamics), 0.02,
                                 actuation_matrix(system.coordinate_names, ["x"]), substeps=1)
        a, b = linearize(step, upright, [0.0])
    a_fd, b_fd = _finite_difference_linearization(dynamics, upright, 0.02)
    np.testing.assert_allclose(a, a_fd, atol=1e-7)
    np.testing.assert_allclose(b, b_fd, atol=1e-7)
    q, r = np.diag([1.0, 10.0, 0.1, 0.1]), np.array([[0.1]])
    gain = discrete_lqr(a, b, q, r)
    p = scipy.linalg.solve_discrete_are(a_fd, b_fd, q, r)
    expected = np.linalg.solve(r + b_fd.T @ p @ b_fd, b_fd.T @ p @ a_fd)
    np.testing.assert_allclose(gain.gain, expected, rtol=1e-5)


@pytest.mark.slow
def test_ilqr_matches_lqr_near_the_upright():
    """iLQR on the nonlinear cart-pole from a small tilt, with the LQR's weights and its
    cost-to-go as terminal cost: the first feedback gain and command are the LQR's."""
    system, dynamics = _true_cart_pole()
    upright = np.array([0.0, np.pi, 0.0, 0.0])
    q, r = np.diag([1.0, 10.0, 0.1, 0.1]), np.array([[0.1]])
    a, b = _finite_difference_linearization(dynamics, upright, 0.02)
    p = scipy.linalg.solve_discrete_are(a, b, q, r)
    lqr_gain = np.linalg.solve(r + b.T @ p @ b, b.T @ p @ a)
    x0 = upright + np.array([0.0, 0.01, 0.0, 0.0])
    with jax.enable_x64(True):
        step = discrete_dynamics(continuous_dynamics(dynamics), 0.02,
                                 actuation_matrix(system.coordinate_names, ["x"]), substeps=1)
        cost = quadratic_cost(upright, q, r, terminal_weights=p, angles=[1])
        solution = ilqr(step, cost, jnp.asarray(x0), jnp.zeros((50, 1)), iterations=30)
    gains = np.asarray(solution.gains)
    np.testing.assert_allclose(-gains[0], lqr_gain, rtol=1e-3)
    u0 = float(np.asarray(solution.controls)[0, 0])
    assert u0 == pytest.approx(float((-lqr_gain @ (x0 - upright))[0]), rel=1e-3)


def test_sampling_planner_brings_a_double_integrator_home_within_its_limit():
    step = _double_integrator()
    planner = sampling_planner(step, quadratic_cost([0.0, 0.0], [1.0, 0.1], [0.01]),
                               horizon=20, control_limit=0.8, n_samples=128)
    x, plan = jnp.array([1.0, 0.0]), planner.init()
    keys = jax.random.split(jax.random.PRNGKey(3), 80)
    applied = []
    for key in keys:
        u, plan, _ = planner.plan(x, plan, key)
        applied.append(float(u[0]))
        x, plan = step(x, u), planner.shift(plan)
    assert np.max(np.abs(applied)) <= 0.8 + 1e-6
    assert np.all(np.abs(np.asarray(x)) < 0.05)


def test_discrete_lqr_refuses_an_uncontrollable_unstable_pair():
    with pytest.raises(ValueError, match="a, b"):
        discrete_lqr(np.diag([1.5, 1.0]), np.array([[0.0], [1.0]]), [1.0, 1.0], [1.0])
