"""JAX export of identified dynamics and batched fixed-step simulation.

Ground truth: the model's own NumPy code (``XLSINDy.predict`` / ``XLSINDy.simulate`` with
scipy's adaptive solver at tight tolerances), the sympy.physics.mechanics double pendulum of
``ground_truth``, closed-form solutions (harmonic oscillator, cubic blow-up) and central
finite differences. 64-bit checks run inside ``jax.enable_x64(True)`` so that the flag does
not leak into other tests of the same process.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import sympy as sp
from ground_truth import random_force, random_initial_state

import pysindy_xl as px
from pysindy_xl.export.jax_dynamics import (
    BatchSimulation,
    dynamics_function,
    euler_step,
    fast_cos,
    fast_sin,
    rk4_step,
    semi_implicit_euler_step,
    simulate,
    simulate_batch,
)


class Dynamics:
    """Minimal stand-in with the attributes of MassMatrixDynamics."""

    def __init__(self, coords, mass, forcing):
        self.coords = coords
        self.mass_matrix_expr = sp.Matrix(mass)
        self.forcing_expr = sp.Matrix(forcing)


def oscillator(stiffness=4.0, mass=1.0):
    c = px.Coordinates(["x"])
    return Dynamics(c, [[mass]], [c.tau[0] - stiffness * c.q[0]])


@pytest.fixture
def x64():
    with jax.enable_x64(True):
        yield


@pytest.fixture(scope="module")
def identified(double_pendulum_system):
    """An XLSINDy model identified on the ground-truth double pendulum (measured derivatives)."""
    system = double_pendulum_system
    c = system.coords
    trig = [f(q) for q in c.q for f in (sp.sin, sp.cos)]
    terms = px.products([1, *px.monomials(trig, 2)], [1, *px.monomials(c.qd, 2)])
    terms = [term for term in terms if term.free_symbols]
    friction = px.ClassicalLibrary(c, c.qd, mask=np.eye(c.n, dtype=bool))
    library = px.CatalogRepartition([px.LagrangeLibrary(c, terms), friction])
    t = np.arange(0.0, 10.0, 0.01)
    data = system.simulate(random_initial_state(system, 11), t, random_force(system, 11))
    model = px.XLSINDy(library, px.ExplicitOptimizer())
    model.fit(data["q"], t, x_dot=data["qd"], x_ddot=data["qdd"], u=data["tau"])
    return model


def random_states(rng, size, n=2):
    q = rng.uniform(-np.pi, np.pi, (size, n))
    qd = rng.uniform(-3.0, 3.0, (size, n))
    u = rng.uniform(-5.0, 5.0, (size, n))
    return q, qd, u


# --------------------------------------------------------------------------------------
# Export
# --------------------------------------------------------------------------------------
def test_to_jax_matches_predict_float64(identified, x64):
    f = identified.to_jax()
    q, qd, u = random_states(np.random.default_rng(0), 500)
    expected = identified.predict(q, qd, u)
    derivative = np.asarray(jax.jit(f)(np.hstack([q, qd]), u))
    assert derivative.dtype == np.float64
    np.testing.assert_array_equal(derivative[:, :2], qd)
    np.testing.assert_allclose(derivative[:, 2:], expected, rtol=0, atol=1e-10)
    # one state at a time and under vmap: same numbers
    single = np.asarray(f(np.hstack([q[0], qd[0]]), u[0]))
    np.testing.assert_allclose(single[2:], expected[0], rtol=0, atol=1e-10)
    mapped = np.asarray(jax.vmap(f)(jnp.hstack([q, qd]), jnp.asarray(u)))
    np.testing.assert_allclose(mapped, derivative, rtol=0, atol=1e-12)


def test_to_jax_matches_true_equations(double_pendulum_system, x64):
    """The export of the sympy.physics.mechanics model reproduces its NumPy accelerations."""
    system = double_pendulum_system
    q, qd, u = random_states(np.random.default_rng(1), 200)
    f = dynamics_function(system)
    derivative = np.asarray(f(np.hstack([q, qd]), u))
    np.testing.assert_allclose(
        derivative[:, 2:], system.accelerations(q, qd, u), rtol=0, atol=1e-10
    )


def test_float32_by_default_and_input_dtype_kept(identified):
    f = identified.to_jax()
    state, u = np.zeros(4, dtype=np.float32), np.zeros(2, dtype=np.float32)
    assert f(state, u).dtype == jnp.float32
    with jax.enable_x64(True):
        assert f(state, u).dtype == jnp.float32
        assert f(state.astype(np.float64), u).dtype == jnp.float64


def test_solvers_agree_and_pivoting_handles_indefinite_matrices(x64):
    c = px.Coordinates(["a", "b", "c"])
    a, b, d = c.q
    mass = [
        [3 + sp.cos(a), sp.sin(b), 0.2],
        [sp.sin(b), 2 + sp.sin(a) ** 2, sp.cos(d) / 3],
        [0.2, sp.cos(d) / 3, 1.5],
    ]
    forcing = [c.tau[0] - sp.sin(a) * c.qd[1] ** 2, c.tau[1] - 9.81 * sp.sin(b), -c.qd[2]]
    dynamics = Dynamics(c, mass, forcing)
    rng = np.random.default_rng(2)
    state, u = rng.normal(size=(50, 6)), rng.normal(size=(50, 3))
    results = {
        s: np.asarray(dynamics_function(dynamics, solver=s)(state, u))
        for s in ("gauss", "pivoted", "lu")
    }
    assert dynamics_function(dynamics).solver == "gauss"
    np.testing.assert_allclose(results["gauss"], results["lu"], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(results["pivoted"], results["lu"], rtol=1e-12, atol=1e-12)

    swap = Dynamics(px.Coordinates(["x", "y"]), [[0, 1], [1, 0]], [1.0, 2.0])
    assert dynamics_function(swap).solver == "pivoted"
    np.testing.assert_allclose(dynamics_function(swap)(np.zeros(4), np.zeros(2)), [0, 0, 2, 1])
    broken = dynamics_function(swap, solver="gauss")(np.zeros(4), np.zeros(2))
    assert not np.all(np.isfinite(np.asarray(broken)))  # zero pivot: never a silent number


def test_derivative_of_export_matches_finite_differences(identified, x64):
    f = identified.to_jax()
    rng = np.random.default_rng(3)
    q, qd, u = random_states(rng, 1)
    state, u = np.hstack([q, qd])[0], u[0]
    jacobian = np.asarray(jax.jacfwd(f)(state, u))
    eps = 1e-6
    for j in range(4):
        step = np.zeros(4)
        step[j] = eps
        plus = identified.predict(*np.split((state + step)[None], 2, axis=1), u[None])[0]
        minus = identified.predict(*np.split((state - step)[None], 2, axis=1), u[None])[0]
        np.testing.assert_allclose(jacobian[2:, j], (plus - minus) / (2 * eps), atol=1e-6)


def test_time_dependent_forcing(x64):
    c = px.Coordinates(["x"])
    drive = Dynamics(c, [[1]], [sp.cos(c.t)])  # x'' = cos t  =>  x = 1 - cos t from rest
    f = dynamics_function(drive)
    assert f.depends_on_time
    t = np.linspace(0.0, 3.0, 301)
    result = simulate(f, np.zeros(2), None, t[1] - t[0], n_steps=len(t))
    np.testing.assert_allclose(result.states[:, 0], 1 - np.cos(t), atol=1e-9)
    shifted = simulate(f, [1 - np.cos(1.0), np.sin(1.0)], None, 0.01, t0=1.0, n_steps=201)
    np.testing.assert_allclose(shifted.states[-1, 0], 1 - np.cos(3.0), atol=1e-9)


def test_fast_trigonometry_accuracy_and_derivative():
    rng = np.random.default_rng(4)
    for x64, tolerance in ((True, 4e-16), (False, 2e-7)):
        with jax.enable_x64(x64):
            dtype = np.float64 if x64 else np.float32
            for scale in (1.0, 100.0, 1e4):
                x = (rng.uniform(-1, 1, 20000) * scale).astype(dtype)
                sine, cosine = np.asarray(jax.jit(fast_sin)(x)), np.asarray(fast_cos(x))
                assert sine.dtype == dtype
                np.testing.assert_allclose(sine, np.sin(x.astype(np.float64)), atol=tolerance)
                np.testing.assert_allclose(cosine, np.cos(x.astype(np.float64)), atol=tolerance)
    with jax.enable_x64(True):
        x = jnp.linspace(-20, 20, 101)
        np.testing.assert_allclose(jax.vmap(jax.grad(fast_sin))(x), np.cos(x), atol=1e-15)
        np.testing.assert_allclose(jax.vmap(jax.grad(fast_cos))(x), -np.sin(x), atol=1e-15)
        assert np.isnan(fast_sin(jnp.inf)) and np.isnan(fast_cos(jnp.nan))


# --------------------------------------------------------------------------------------
# Simulation
# --------------------------------------------------------------------------------------
@pytest.mark.slow
def test_batched_rk4_matches_model_simulate(identified, double_pendulum_system, x64):
    """Same sampled forces, read linearly between samples by both integrators (the
    reference integrates through a kink at every sample at 1e-11: a short run)."""
    dt, n_samples = 0.002, 251
    t = dt * np.arange(n_samples)
    system = double_pendulum_system
    x0 = np.stack([random_initial_state(system, seed) for seed in (21, 22)])
    forces = np.stack([random_force(system, seed)(t) for seed in (31, 32)])
    result = simulate_batch(identified, x0, forces, dt, interpolation="linear")
    assert result.states.shape == (2, n_samples, 4) and result.states.dtype == jnp.float64
    assert not np.any(result.diverged)
    for k in range(2):
        reference = identified.simulate(
            x0[k], t, forces[k], rtol=1e-11, atol=1e-12, interpolation="linear"
        )
        np.testing.assert_allclose(np.asarray(result.states[k]), reference, rtol=0, atol=1e-6)


def test_held_forces_match_model_simulate_with_previous_interpolation(
    identified, double_pendulum_system, x64
):
    """Zero-order hold: piecewise-constant commands (20 levels over 1 s)."""
    dt, n_samples = 0.002, 501
    t = dt * np.arange(n_samples)
    levels = np.random.default_rng(7).uniform(-5, 5, (20, 2))
    forces = np.repeat(levels, 25, axis=0)[: n_samples - 1]
    forces = np.vstack([forces, forces[-1:]])
    x0 = random_initial_state(double_pendulum_system, 24)
    result = simulate(identified, x0, forces, dt, interpolation="zoh")
    reference = identified.simulate(x0, t, forces, rtol=1e-11, atol=1e-12, interpolation="previous")
    np.testing.assert_allclose(np.asarray(result.states), reference, rtol=0, atol=1e-6)


@pytest.mark.slow
def test_vmap_over_1000_trajectories_equals_python_loop(identified, x64):
    rng = np.random.default_rng(5)
    n_batch, n_samples, dt = 1000, 40, 0.01
    q, qd, _ = random_states(rng, n_batch)
    x0 = np.hstack([q, qd])
    forces = rng.uniform(-5, 5, (n_batch, n_samples, 2))
    f = identified.to_jax()
    batch = simulate_batch(f, x0, forces, dt, method="rk4")
    checked = np.arange(3, n_batch, 20)  # one trajectory in 20, across the whole batch
    looped = np.stack([np.asarray(simulate(f, x0[k], forces[k], dt).states) for k in checked])
    np.testing.assert_allclose(np.asarray(batch.states)[checked], looped, rtol=1e-12,
                               atol=1e-12)
    # and the loop of single steps written by hand (each step compiled once: op by op, the
    # expression's dispatch takes most of a second per step)
    k = 7
    state = jnp.asarray(x0[k])
    step = jax.jit(lambda state, time, force: rk4_step(f, state, time, dt, force))
    for i in range(n_samples - 1):
        state = step(state, i * dt, forces[k, i])
    np.testing.assert_allclose(batch.states[k, -1], state, rtol=1e-12, atol=1e-12)


@pytest.mark.slow
def test_gradient_of_rollout_matches_finite_differences(identified, double_pendulum_system, x64):
    f = identified.to_jax()
    rng = np.random.default_rng(6)
    x0 = jnp.asarray(random_initial_state(double_pendulum_system, 3))
    forces = jnp.asarray(rng.uniform(-2, 2, (151, 2)))
    target = jnp.array([0.3, -0.4])

    def loss(x0, forces):
        states = simulate(f, x0, forces, 0.01, method="rk4").states
        return jnp.sum((states[-1, :2] - target) ** 2) + 0.1 * jnp.mean(states[:, 2:] ** 2)

    grad_x0, grad_u = jax.jit(jax.grad(loss, argnums=(0, 1)))(x0, forces)
    eps = 1e-6
    for j in range(4):
        step = jnp.zeros(4).at[j].set(eps)
        numeric = (loss(x0 + step, forces) - loss(x0 - step, forces)) / (2 * eps)
        np.testing.assert_allclose(grad_x0[j], numeric, rtol=1e-6, atol=1e-9)
    direction = jnp.asarray(rng.normal(size=forces.shape))
    numeric = (loss(x0, forces + eps * direction) - loss(x0, forces - eps * direction)) / (2 * eps)
    np.testing.assert_allclose(jnp.vdot(grad_u, direction), numeric, rtol=1e-6)


def test_divergence_is_reported_per_trajectory_and_frozen(x64):
    c = px.Coordinates(["x"])
    blow_up = Dynamics(c, [[1]], [c.q[0] ** 3])  # from (a, a^2/sqrt 2) x = a / (1 - a t / sqrt 2)
    f = dynamics_function(blow_up)
    x0 = np.array([[0.0, 0.0], [1.0, 1 / np.sqrt(2)], [0.5, 0.25 / np.sqrt(2)]])
    dt, n_samples = 0.01, 400  # blow-up times sqrt(2) and 2 sqrt(2) lie inside
    for bound in (None, 1e3):
        result = simulate_batch(f, x0, None, dt, n_steps=n_samples, bound=bound)
        states = np.asarray(result.states)
        assert np.all(np.isfinite(states))
        assert result.diverged.tolist() == [False, True, True]
        steps = np.asarray(result.divergence_step)
        assert steps[0] == -1
        limit = np.inf if bound is None else bound
        for k in (1, 2):
            assert np.all(np.abs(states[k, : steps[k]]) <= limit)
            frozen = np.broadcast_to(states[k, steps[k] - 1], states[k, steps[k] :].shape)
            np.testing.assert_array_equal(states[k, steps[k] :], frozen)
        # blow-up at t* = sqrt(2) / a: divergence is detected just after
        times = steps[1:] * dt
        assert np.all(times > [np.sqrt(2) - 0.2, 2 * np.sqrt(2) - 0.2])
        assert np.all(times < [np.sqrt(2) + 0.2, 2 * np.sqrt(2) + 0.2])
        np.testing.assert_array_equal(states[0], 0.0)  # the calm one is untouched
    exact = 0.5 / (1 - 0.5 * np.arange(100) * dt / np.sqrt(2))
    np.testing.assert_allclose(states[2, :100, 0], exact, rtol=1e-6)
    # a start outside the bound diverges at sample 0
    out = simulate_batch(f, x0, None, dt, n_steps=3, bound=0.75)
    assert out.divergence_step.tolist() == [-1, 0, -1]


def test_gradient_with_a_diverged_trajectory_stays_finite_under_a_bound(x64):
    c = px.Coordinates(["x"])
    f = dynamics_function(Dynamics(c, [[1]], [c.q[0] ** 3 + c.tau[0]]))
    x0 = jnp.array([[0.1, 0.0], [1.0, 0.7]])  # the second one blows up before t = 2

    def loss(shared_force):
        forces = jnp.broadcast_to(shared_force, (2, 300, 1))
        result = simulate_batch(f, x0, forces, 0.01, bound=1e3)
        final = jnp.sum(result.states[:, -1] ** 2, axis=-1)
        return jnp.sum(jnp.where(result.diverged, 0.0, final)), result.diverged

    (value, diverged), gradient = jax.value_and_grad(loss, has_aux=True)(jnp.zeros((300, 1)))
    assert diverged.tolist() == [False, True]
    assert np.all(np.isfinite(np.asarray(gradient))) and np.any(np.asarray(gradient) != 0)
    # the gradient is the calm trajectory's alone
    calm = jax.grad(lambda u: jnp.sum(simulate(f, x0[0], u, 0.01).states[-1] ** 2))(
        jnp.zeros((300, 1))
    )
    np.testing.assert_allclose(gradient, calm, rtol=1e-12, atol=1e-15)


def test_integrators_converge_at_their_order(x64):
    f = dynamics_function(oscillator(stiffness=4.0))  # x = cos 2t
    errors = {}
    for method in ("rk4", "semi_implicit_euler", "euler"):
        errors[method] = []
        for dt in (0.02, 0.01):
            n = int(round(2.0 / dt)) + 1
            states = simulate(f, [1.0, 0.0], None, dt, n_steps=n, method=method).states
            errors[method].append(abs(float(states[-1, 0]) - np.cos(4.0)))
    order = {m: np.log2(e[0] / e[1]) for m, e in errors.items()}
    assert 3.8 < order["rk4"] < 4.2
    assert 0.8 < order["semi_implicit_euler"] < 1.2 or errors["semi_implicit_euler"][1] < 1e-2
    assert 0.8 < order["euler"] < 1.2
    # symplectic Euler keeps the energy bounded where explicit Euler pumps it up
    long = {
        m: simulate(f, [1.0, 0.0], None, 0.05, n_steps=2000, method=m).states
        for m in ("semi_implicit_euler", "euler")
    }
    energy = {m: 0.5 * s[:, 1] ** 2 + 2.0 * s[:, 0] ** 2 for m, s in long.items()}
    assert np.max(np.abs(energy["semi_implicit_euler"] - 2.0)) < 0.25
    assert energy["euler"][-1] > 10 * 2.0


def test_step_functions_by_hand():
    f = dynamics_function(oscillator(stiffness=1.0))
    state, u = jnp.array([1.0, 0.5]), jnp.array([0.2])
    x = semi_implicit_euler_step(f, state, 0.0, 0.1, u)
    velocity = 0.5 + 0.1 * (0.2 - 1.0)
    np.testing.assert_allclose(x, [1.0 + 0.1 * velocity, velocity], rtol=1e-6)
    np.testing.assert_allclose(euler_step(f, state, 0.0, 0.1, u), [1.05, 0.42], rtol=1e-6)
    # a linear force ramp inside the step: RK4 integrates x'' = u(t) exactly (cubic x)
    c = px.Coordinates(["x"])
    ramp = dynamics_function(Dynamics(c, [[1]], [c.tau[0]]))
    x = rk4_step(ramp, jnp.zeros(2), 0.0, 1.0, jnp.array([0.0]), jnp.array([6.0]))
    np.testing.assert_allclose(x, [1.0, 3.0], rtol=1e-6)  # x = t^3, v = 3 t^2


def test_float_precision_follows_x64_flag(identified):
    x0, forces = np.zeros((2, 4)), np.zeros((2, 5, 2))
    assert simulate_batch(identified, x0, forces, 0.01).states.dtype == jnp.float32
    with jax.enable_x64(True):
        result = simulate_batch(identified, x0, forces, 0.01, final_only=True)
        assert result.states.dtype == jnp.float64 and result.states.shape == (2, 4)
        assert isinstance(result, BatchSimulation)


def test_user_function_without_componentwise_form(x64):
    def damped(state, u, t):  # plain user function of one state
        return jnp.array([state[1], u[0] - state[0] - 0.1 * state[1]])

    c = px.Coordinates(["x"])
    reference = dynamics_function(Dynamics(c, [[1]], [c.tau[0] - c.q[0] - 0.1 * c.qd[0]]))
    x0, forces = np.array([[1.0, 0.0], [0.0, 1.0]]), np.ones((2, 50, 1))
    ours = simulate_batch(damped, x0, forces, 0.05).states
    np.testing.assert_allclose(ours, simulate_batch(reference, x0, forces, 0.05).states, atol=1e-13)


def test_same_function_for_same_model(identified):
    assert identified.to_jax() is identified.to_jax()


# --------------------------------------------------------------------------------------
# Input validation
# --------------------------------------------------------------------------------------
def test_bad_dynamics_are_rejected():
    c = px.Coordinates(["x"])
    with pytest.raises(TypeError, match="dynamics"):
        dynamics_function(object())
    with pytest.raises(ValueError, match="accelerations"):
        dynamics_function(Dynamics(c, [[1]], [c.qdd[0]]))
    with pytest.raises(ValueError, match="symbols"):
        dynamics_function(Dynamics(c, [[1]], [sp.Symbol("k") * c.q[0]]))
    with pytest.raises(ValueError, match="mass_matrix_expr"):
        dynamics_function(Dynamics(c, [[1, 0]], [c.q[0]]))
    with pytest.raises(ValueError, match="solver"):
        dynamics_function(oscillator(), solver="qr")


def test_bad_simulation_inputs_are_rejected():
    f = dynamics_function(oscillator())
    with pytest.raises(ValueError, match="state"):
        f(np.zeros(3), np.zeros(1))
    with pytest.raises(ValueError, match="u"):
        f(np.zeros(2), np.zeros(2))
    good_x0, good_u = np.zeros((3, 2)), np.zeros((3, 10, 1))
    cases = [
        (dict(x0=np.zeros((3, 4))), "x0"),
        (dict(x0=np.zeros(2)), "x0"),
        (dict(u=np.zeros((3, 10, 2))), "u"),
        (dict(u=np.zeros((2, 10, 1))), "u"),
        (dict(x0=np.full((3, 2), np.nan)), "x0"),
        (dict(u=np.full((3, 10, 1), np.inf)), "u"),
        (dict(dt=0.0), "dt"),
        (dict(dt=[0.1, 0.2]), "dt"),
        (dict(method="rk45"), "method"),
        (dict(interpolation="cubic"), "interpolation"),
        (dict(bound=-1.0), "bound"),
        (dict(u=None), "n_steps"),
        (dict(n_steps=5), "n_steps"),
    ]
    for change, name in cases:
        arguments = dict(x0=good_x0, u=good_u, dt=0.1) | change
        x0, u, dt = arguments.pop("x0"), arguments.pop("u"), arguments.pop("dt")
        with pytest.raises(ValueError, match=name):
            simulate_batch(f, x0, u, dt, **arguments)
    with pytest.raises(TypeError, match="f"):
        simulate_batch("rk4", good_x0, good_u, 0.1)
    with pytest.raises(ValueError, match="u"):
        simulate(f, np.zeros(2), np.zeros((3, 10, 1)), 0.1)
