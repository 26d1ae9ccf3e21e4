"""Checks of the ground-truth module against physics derived by hand.

The reference systems in ``ground_truth.py`` come from sympy.physics.mechanics; here they are
compared with hand-written Lagrangians, textbook closed forms and energy balances.
"""

import numpy as np
import pytest
import sympy as sp
from ground_truth import (
    G,
    cart_double_pendulum,
    cart_pole,
    double_pendulum,
    random_force,
    random_initial_state,
    sum_of_sines,
)

SYSTEM_FIXTURES = ["cart_pole_system", "double_pendulum_system", "cart_double_pendulum_system"]


# ---- hand-derived Lagrangians (T - V with V = m g y, angles from the downward vertical) --------


def cart_pole_lagrangian(coords, m_cart=1.0, m_pole=0.5, length=1.0):
    x, th = coords.q
    xd, thd = coords.qd
    kinetic = (
        sp.Rational(1, 2) * (m_cart + m_pole) * xd**2
        + m_pole * length * xd * thd * sp.cos(th)
        + sp.Rational(1, 2) * m_pole * length**2 * thd**2
    )
    return kinetic + m_pole * G * length * sp.cos(th)


def double_pendulum_lagrangian(coords, m1=1.0, m2=1.0, l1=1.0, l2=1.0):
    t1, t2 = coords.q
    w1, w2 = coords.qd
    kinetic = (
        sp.Rational(1, 2) * (m1 + m2) * l1**2 * w1**2
        + sp.Rational(1, 2) * m2 * l2**2 * w2**2
        + m2 * l1 * l2 * w1 * w2 * sp.cos(t1 - t2)
    )
    return kinetic + (m1 + m2) * G * l1 * sp.cos(t1) + m2 * G * l2 * sp.cos(t2)


def cart_double_pendulum_lagrangian(coords, m_cart=1.0, m1=0.5, m2=0.5, l1=1.0, l2=1.0):
    x, t1, t2 = coords.q
    xd, w1, w2 = coords.qd
    kinetic = (
        sp.Rational(1, 2) * (m_cart + m1 + m2) * xd**2
        + sp.Rational(1, 2) * (m1 + m2) * l1**2 * w1**2
        + sp.Rational(1, 2) * m2 * l2**2 * w2**2
        + (m1 + m2) * l1 * xd * w1 * sp.cos(t1)
        + m2 * l2 * xd * w2 * sp.cos(t2)
        + m2 * l1 * l2 * w1 * w2 * sp.cos(t1 - t2)
    )
    return kinetic + (m1 + m2) * G * l1 * sp.cos(t1) + m2 * G * l2 * sp.cos(t2)


HAND_LAGRANGIANS = {
    "cart_pole": cart_pole_lagrangian,
    "double_pendulum": double_pendulum_lagrangian,
    "cart_double_pendulum": cart_double_pendulum_lagrangian,
}


def hand_energy(system, q, qd):
    """T + V from the hand Lagrangian: T is its part quadratic in qd, V = T - L."""
    coords = system.coords
    lagrangian = HAND_LAGRANGIANS[system.name](coords)
    scale = sp.Symbol("s")
    scaled = lagrangian.xreplace({v: scale * v for v in coords.qd})
    kinetic = sp.expand(scaled).coeff(scale, 2)
    energy = sp.lambdify((*coords.q, *coords.qd), 2 * kinetic - lagrangian, "numpy")
    return np.broadcast_to(energy(*q.T, *qd.T), (q.shape[0],))


def euler_lagrange_residual(system, lagrangian, q, qd, qdd, tau, friction):
    """d/dt dL/dqd - dL/dq + c qd - tau per sample, from the chain rule on a hand Lagrangian."""
    c = system.coords
    rows = []
    for i in range(c.n):
        momentum = sp.diff(lagrangian, c.qd[i])
        time_derivative = sum(
            sp.diff(momentum, c.q[j]) * c.qd[j] + sp.diff(momentum, c.qd[j]) * c.qdd[j]
            for j in range(c.n)
        )
        rows.append(time_derivative - sp.diff(lagrangian, c.q[i]))
    residual = sp.lambdify((*c.q, *c.qd, *c.qdd), rows, "numpy")(*q.T, *qd.T, *qdd.T)
    residual = np.stack([np.broadcast_to(r, (q.shape[0],)) for r in residual], axis=1)
    return residual + friction * qd - tau


def derivative(values, t):
    """Fourth-order central difference (uniform grid) and the slice of samples it covers."""
    dt = t[1] - t[0]
    rate = (values[:-4] - 8 * values[1:-3] + 8 * values[3:-1] - values[4:]) / (12 * dt)
    return rate, slice(2, -2)


def random_samples(system, n_samples, seed):
    rng = np.random.default_rng(seed)
    n = system.n
    q = rng.uniform(-np.pi, np.pi, (n_samples, n))
    qd = rng.uniform(-3, 3, (n_samples, n))
    tau = rng.uniform(-5, 5, (n_samples, n))
    return q, qd, tau


# ---- structure ------------------------------------------------------------------------------


@pytest.mark.parametrize("fixture", SYSTEM_FIXTURES)
def test_lagrangian_matches_hand_derivation(fixture, request):
    system = request.getfixturevalue(fixture)
    hand = sp.expand(sp.expand_trig(HAND_LAGRANGIANS[system.name](system.coords)))
    assert sp.simplify(system.lagrangian - hand) == 0
    # Expanded form: trigonometric functions only of single coordinates, no cos(a - b).
    for function in system.lagrangian.atoms(sp.sin, sp.cos):
        assert function.args[0] in system.coords.q
    assert system.lagrangian.free_symbols <= set(system.coords.q + system.coords.qd)


@pytest.mark.parametrize("fixture", SYSTEM_FIXTURES)
def test_accelerations_satisfy_hand_euler_lagrange_equations(fixture, request):
    system = request.getfixturevalue(fixture)
    q, qd, tau = random_samples(system, 200, seed=1)
    qdd = system.accelerations(q, qd, tau)
    assert qdd.shape == (200, system.n)
    lagrangian = HAND_LAGRANGIANS[system.name](system.coords)
    residual = euler_lagrange_residual(system, lagrangian, q, qd, qdd, tau, system.friction)
    np.testing.assert_allclose(residual, 0.0, atol=1e-10)


def test_cart_pole_matches_textbook_closed_form():
    m_cart, m_pole, length, friction = 1.7, 0.4, 0.8, np.array([0.25, 0.05])
    system = cart_pole(m_cart=m_cart, m_pole=m_pole, length=length, friction=friction)
    q, qd, tau = random_samples(system, 500, seed=2)
    th, xd, thd = q[:, 1], qd[:, 0], qd[:, 1]
    # Cramer's rule on (M+m) xdd + m l cos th thdd = F1 and m l cos th xdd + m l^2 thdd = F2.
    f1 = tau[:, 0] - friction[0] * xd + m_pole * length * np.sin(th) * thd**2
    f2 = tau[:, 1] - friction[1] * thd - m_pole * G * length * np.sin(th)
    det = m_pole * length**2 * (m_cart + m_pole * np.sin(th) ** 2)
    xdd = (m_pole * length**2 * f1 - m_pole * length * np.cos(th) * f2) / det
    thdd = ((m_cart + m_pole) * f2 - m_pole * length * np.cos(th) * f1) / det
    np.testing.assert_allclose(
        system.accelerations(q, qd, tau), np.column_stack([xdd, thdd]), rtol=1e-11, atol=1e-11
    )


def test_double_pendulum_matches_textbook_closed_form():
    m1, m2, l1, l2 = 1.3, 0.7, 0.9, 1.2
    system = double_pendulum(m1=m1, m2=m2, l1=l1, l2=l2, friction=(0.0, 0.0))
    q, qd, _ = random_samples(system, 500, seed=3)
    t1, t2, w1, w2 = q[:, 0], q[:, 1], qd[:, 0], qd[:, 1]
    delta = t1 - t2
    den = 2 * m1 + m2 - m2 * np.cos(2 * delta)
    a1 = (
        -G * (2 * m1 + m2) * np.sin(t1)
        - m2 * G * np.sin(t1 - 2 * t2)
        - 2 * np.sin(delta) * m2 * (w2**2 * l2 + w1**2 * l1 * np.cos(delta))
    ) / (l1 * den)
    a2 = (
        2
        * np.sin(delta)
        * (w1**2 * l1 * (m1 + m2) + G * (m1 + m2) * np.cos(t1) + w2**2 * l2 * m2 * np.cos(delta))
    ) / (l2 * den)
    np.testing.assert_allclose(
        system.accelerations(q, qd), np.column_stack([a1, a2]), rtol=1e-11, atol=1e-11
    )


def test_cart_double_pendulum_with_other_parameters(cart_double_pendulum_system):
    params = dict(m_cart=2.1, m1=0.3, m2=0.8, l1=0.7, l2=1.4)
    friction = np.array([0.4, 0.02, 0.07])
    system = cart_double_pendulum(**params, friction=friction)
    q, qd, tau = random_samples(system, 100, seed=4)
    lagrangian = cart_double_pendulum_lagrangian(system.coords, **params)
    residual = euler_lagrange_residual(
        system, lagrangian, q, qd, system.accelerations(q, qd, tau), tau, friction
    )
    np.testing.assert_allclose(residual, 0.0, atol=1e-10)
    # Different parameters must give different dynamics (guards against ignored arguments).
    default = cart_double_pendulum_system.accelerations(q, qd, tau)
    assert np.max(np.abs(default - system.accelerations(q, qd, tau))) > 0.1


@pytest.mark.parametrize("fixture", SYSTEM_FIXTURES)
def test_energy_method_matches_hand_energy(fixture, request):
    system = request.getfixturevalue(fixture)
    q, qd, _ = random_samples(system, 50, seed=5)
    np.testing.assert_allclose(system.energy(q, qd), hand_energy(system, q, qd), atol=1e-12)


# ---- trajectories ---------------------------------------------------------------------------


@pytest.mark.parametrize("fixture", SYSTEM_FIXTURES)
def test_energy_conserved_without_friction_and_force(fixture, request):
    system = request.getfixturevalue(fixture)
    system = system.with_friction(np.zeros(system.n))
    t = np.linspace(0.0, 10.0, 501)
    result = system.simulate(random_initial_state(system, seed=6), t)
    energy = hand_energy(system, result["q"], result["qd"])
    assert np.ptp(result["q"][:, -1]) > 0.5  # it actually moves
    drift = np.max(np.abs(energy - energy[0])) / np.abs(energy[0])
    assert drift < 1e-8


@pytest.mark.parametrize("fixture", SYSTEM_FIXTURES)
def test_energy_balance_with_friction_and_force(fixture, request):
    system = request.getfixturevalue(fixture)
    force = random_force(system, seed=7)
    t = np.linspace(0.0, 4.0, 4001)
    result = system.simulate(random_initial_state(system, seed=7), t, force=force)
    q, qd, tau = result["q"], result["qd"], result["tau"]
    energy_rate, inner = derivative(hand_energy(system, q, qd), t)
    power = np.sum((tau - system.friction * qd) * qd, axis=1)
    assert np.max(np.abs(power)) > 1.0
    np.testing.assert_allclose(energy_rate, power[inner], atol=1e-6 * np.max(np.abs(power)))


def test_friction_alone_dissipates_energy(double_pendulum_system):
    t = np.linspace(0.0, 10.0, 4001)
    x0 = random_initial_state(double_pendulum_system, seed=8)
    result = double_pendulum_system.simulate(x0, t)
    energy = hand_energy(double_pendulum_system, result["q"], result["qd"])
    dissipated = np.sum(double_pendulum_system.friction * result["qd"] ** 2, axis=1)
    energy_rate, inner = derivative(energy, t)
    np.testing.assert_allclose(energy_rate, -dissipated[inner], atol=1e-6 * dissipated.max())
    assert energy[-1] < energy[0] - 1.0


def test_simulate_outputs_are_consistent(cart_double_pendulum_system):
    system = cart_double_pendulum_system
    force = random_force(system, seed=9)
    t = np.linspace(0.0, 3.0, 3001)
    x0 = random_initial_state(system, seed=9)
    result = system.simulate(x0, t, force=force)
    assert set(result) == {"t", "q", "qd", "qdd", "tau"}
    for key in ("q", "qd", "qdd", "tau"):
        assert result[key].shape == (t.size, system.n)
    np.testing.assert_array_equal(result["t"], t)
    np.testing.assert_allclose(np.concatenate([result["q"][0], result["qd"][0]]), x0)
    np.testing.assert_allclose(result["tau"], force(t))
    velocity, inner = derivative(result["q"], t)
    np.testing.assert_allclose(velocity, result["qd"][inner], atol=1e-7)
    acceleration, inner = derivative(result["qd"], t)
    np.testing.assert_allclose(acceleration, result["qdd"][inner], atol=1e-6)


def test_simulate_accepts_scalar_only_force(cart_pole_system):
    def push(time):
        return np.array([float(np.sin(time)), 0.0])  # float() fails on arrays of times

    t = np.linspace(0.0, 1.0, 11)
    result = cart_pole_system.simulate(np.zeros(4), t, force=push)
    np.testing.assert_allclose(result["tau"][:, 0], np.sin(t))
    assert result["q"][-1, 0] > 0.05


# ---- vectorization, inputs and helpers ------------------------------------------------------


def test_accelerations_vectorized_matches_per_sample(cart_double_pendulum_system):
    system = cart_double_pendulum_system
    q, qd, tau = random_samples(system, 20, seed=10)
    batch = system.accelerations(q, qd, tau)
    single = np.array([system.accelerations(a, b, c) for a, b, c in zip(q, qd, tau, strict=True)])
    np.testing.assert_allclose(batch, single, rtol=1e-13)
    np.testing.assert_allclose(
        system.accelerations(q, qd), system.accelerations(q, qd, np.zeros_like(q))
    )


def test_with_friction_changes_only_friction(cart_pole_system):
    frictionless = cart_pole_system.with_friction([0.0, 0.0])
    assert frictionless._compiled is cart_pole_system._compiled
    np.testing.assert_array_equal(cart_pole_system.friction, [0.3, 0.1])
    q, qd, tau = random_samples(cart_pole_system, 10, seed=11)
    mass = cart_pole_system.mass_matrix(q)
    difference = np.einsum(
        "nij,nj->ni",
        mass,
        cart_pole_system.accelerations(q, qd, tau) - frictionless.accelerations(q, qd, tau),
    )
    np.testing.assert_allclose(difference, -cart_pole_system.friction * qd, atol=1e-12)


def test_bad_inputs_raise(cart_pole_system):
    with pytest.raises(ValueError, match="q"):
        cart_pole_system.accelerations(np.zeros((5, 3)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="tau"):
        cart_pole_system.accelerations(np.zeros((5, 2)), np.zeros((5, 2)), np.zeros((4, 2)))
    with pytest.raises(ValueError, match="NaN"):
        cart_pole_system.accelerations(np.full((1, 2), np.nan), np.zeros((1, 2)))
    with pytest.raises(ValueError, match="x0"):
        cart_pole_system.simulate(np.zeros(3), np.linspace(0, 1, 5))
    with pytest.raises(ValueError, match="t:"):
        cart_pole_system.simulate(np.zeros(4), np.array([0.0, 1.0, 0.5]))
    with pytest.raises(TypeError, match="force"):
        cart_pole_system.simulate(np.zeros(4), np.linspace(0, 1, 5), force=np.ones(2))
    with pytest.raises(ValueError, match="friction"):
        cart_pole(friction=(0.1,))
    with pytest.raises(ValueError, match="length"):
        cart_pole(length=-1.0)


def test_sum_of_sines_properties():
    t = np.linspace(0.0, 30.0, 3001)
    force = sum_of_sines(3, [0, 2], seed=12, amplitude=[2.0, 5.0, 0.5])
    values = force(t)
    assert values.shape == (t.size, 3)
    np.testing.assert_array_equal(values[:, 1], 0.0)
    assert np.all(np.abs(values) <= np.array([2.0, 5.0, 0.5]) + 1e-12)
    assert np.max(np.abs(values[:, 0])) > 0.5 and np.max(np.abs(values[:, 2])) > 0.1
    np.testing.assert_allclose(np.array([force(s) for s in t[:50]]), values[:50], rtol=1e-14)
    np.testing.assert_array_equal(sum_of_sines(3, [0, 2], 12, [2.0, 5.0, 0.5])(t), values)
    assert not np.allclose(sum_of_sines(3, [0, 2], 13, [2.0, 5.0, 0.5])(t), values)
    mask = sum_of_sines(3, np.array([True, False, True]), 12, [2.0, 5.0, 0.5])(t)
    np.testing.assert_array_equal(mask, values)
    with pytest.raises(ValueError, match="active"):
        sum_of_sines(3, [3], seed=0)
    with pytest.raises(ValueError, match="f_min"):
        sum_of_sines(3, [0], seed=0, f_min=2.0, f_max=1.0)


def test_random_initial_state_is_reproducible(cart_double_pendulum_system):
    system = cart_double_pendulum_system
    a = random_initial_state(system, seed=13)
    assert a.shape == (6,)
    np.testing.assert_array_equal(a, random_initial_state(system, seed=13))
    assert not np.allclose(a, random_initial_state(system, seed=14))
    assert abs(a[0]) <= 0.5 and np.all(np.abs(a[1:3]) <= 1.5)
