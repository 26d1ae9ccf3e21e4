"""Mixed regression: activation graph, reductions to explicit / implicit, identification.

Acceptance systems (sympy.physics.mechanics ground truth): the double pendulum on a cart with a
force on the cart only, the double pendulum with a torque on the second joint only, and a
forced cart-pole next to a free double pendulum (a robot with an unactuated, decoupled
subsystem), on which explicit regression alone fails.
"""

import warnings

import numpy as np
import pytest
import sympy as sp
from ground_truth import random_force, random_initial_state
from sklearn.base import clone

import pysindy_xl as px
from pysindy_xl.optimizers.implicit import ImplicitOptimizer, NoLawFoundError
from pysindy_xl.optimizers.mixed import MixedOptimizer, activation_closure

# ---------------------------------------------------------------------------------------------
# Synthetic problems
# ---------------------------------------------------------------------------------------------


def two_oscillators(n=300, seed=0):
    """x1'' + 4 x1 + 0.3 x1' = u (forced) and x2'' + 9 x2 = 0 (free), columns:
    force, x1'', x1, x1', x2'', x2, a distractor in each equation."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 30, n)
    u = np.sin(1.3 * t) + 0.5 * np.sin(0.4 * t + 1)
    x1 = np.sin(t) + 0.3 * np.cos(2.2 * t)
    x1d = np.gradient(x1, t)
    x2 = np.cos(3 * t + rng.uniform())
    a1 = u - 4 * x1 - 0.3 * x1d
    zero = np.zeros(n)
    distractor1, distractor2 = np.cos(0.7 * t), np.sin(0.9 * t)
    block1 = np.column_stack([u, a1, x1, x1d, zero, zero, distractor1, zero])
    block2 = np.column_stack([zero, zero, zero, zero, -9 * x2, x2, zero, distractor2])
    truth = np.array([-1.0, 1.0, 4.0, 0.3, 1.0, 9.0, 0.0, 0.0])
    return np.vstack([block1, block2]), truth


def assert_oscillators(coef, truth):
    """Forced part exact (force -1 fixes the scale); free law [1, 9] up to its scale."""
    explicit = [0, 1, 2, 3, 6]
    np.testing.assert_allclose(coef[explicit], truth[explicit], rtol=1e-8, atol=1e-10)
    assert coef[7] == 0 and coef[4] != 0
    np.testing.assert_allclose(coef[5] / coef[4], 9.0, rtol=1e-8)


def test_activation_closure():
    touches = np.array([
        [1, 1, 0, 0, 0],
        [0, 1, 1, 0, 0],
        [0, 0, 1, 0, 0],
        [0, 0, 0, 1, 1],
    ], dtype=bool)
    coords, cols = activation_closure(touches, np.array([1, 0, 0, 0], dtype=bool))
    np.testing.assert_array_equal(coords, [1, 1, 1, 0])
    np.testing.assert_array_equal(cols, [1, 1, 1, 0, 0])
    coords, cols = activation_closure(touches, np.zeros(4, dtype=bool))
    assert not coords.any() and not cols.any()


def test_mixed_solves_the_forced_and_the_free_oscillator():
    theta, truth = two_oscillators()
    opt = MixedOptimizer().fit_catalog(theta, 2, [0])
    assert opt.mode_ == "mixed"
    np.testing.assert_array_equal(opt.explicit_coordinates_, [True, False])
    np.testing.assert_array_equal(opt.implicit_coordinates_, [False, True])
    np.testing.assert_array_equal(opt.explicit_columns_, [0, 1, 2, 3, 6])
    np.testing.assert_array_equal(opt.implicit_columns_, [4, 5, 7])
    assert_oscillators(opt.coef_, truth)


def test_explicit_alone_misses_the_free_oscillator():
    theta, truth = two_oscillators()
    with pytest.warns(px.UnexplainedCoordinateWarning, match=r"coordinate\(s\) \[1\]"):
        explicit = px.ExplicitOptimizer().fit_catalog(theta, 2, [0])
    assert not np.any(explicit.coef_[[4, 5]]), "explicit regression cannot fix a free law's scale"
    # the mixed fit solves that coordinate implicitly and does not pass the warning on
    with warnings.catch_warnings():
        warnings.simplefilter("error", px.UnexplainedCoordinateWarning)
        assert px.MixedOptimizer().fit_catalog(theta, 2, [0]).mode_ == "mixed"


def test_reduces_to_explicit_when_every_coordinate_is_forced():
    theta, _ = two_oscillators()
    n = theta.shape[0] // 2
    forced = theta.copy()
    forced[n:, 0] = np.cos(0.8 * np.arange(n))  # a force on the second coordinate too
    forced[n:, 4] += forced[n:, 0]            # its law: x2'' + 9 x2 = u2
    mixed = MixedOptimizer().fit_catalog(forced, 2, [0])
    explicit = px.ExplicitOptimizer().fit_catalog(forced, 2, [0])
    assert mixed.mode_ == "explicit" and mixed.implicit_optimizer_ is None
    np.testing.assert_array_equal(mixed.coef_, explicit.coef_)


def test_reduces_to_implicit_without_force():
    theta, _ = two_oscillators()
    theta = theta.copy()
    n = theta.shape[0] // 2
    theta[:n, 0] = 0.0                           # no force at all ...
    theta[:n, 1] = -4 * theta[:n, 2] - 0.3 * theta[:n, 3]  # ... and a free first oscillator
    mixed = MixedOptimizer().fit_catalog(theta, 2, [0])
    implicit = ImplicitOptimizer().fit_catalog(theta, 2, [0])
    assert mixed.mode_ == "implicit" and mixed.explicit_optimizer_ is None
    np.testing.assert_array_equal(mixed.coef_, implicit.coef_)


def test_nothing_left_to_solve_is_an_error():
    theta, _ = two_oscillators()
    n = theta.shape[0] // 2
    # The free oscillator's columns also enter the forced equation: the activation reaches
    # both coordinates, the explicit solution explains only the forced one, and no column is
    # left that touches the free coordinate alone.
    coupled = theta[:, :7].copy()
    coupled[:n, 4] = 1e-3 * np.sin(np.arange(n))
    coupled[:n, 5] = 1e-3 * np.cos(np.arange(n))
    with pytest.warns(UserWarning, match=r"coordinate\(s\) \[1\]; solving them implicitly"):
        with pytest.raises(ValueError, match="nothing left to solve"):
            MixedOptimizer().fit_catalog(coupled, 2, [0])


def test_free_subsystem_reachable_only_through_discarded_terms_is_solved_implicitly():
    theta, truth = two_oscillators()
    n = theta.shape[0] // 2
    coupling = np.sin(0.37 * np.arange(2 * n))[:, None]  # touches both equations, not a term
    opt = MixedOptimizer()
    with pytest.warns(UserWarning, match="solving them implicitly"):
        opt.fit_catalog(np.hstack([theta, coupling]), 2, [0])
    assert opt.mode_ == "mixed" and opt.activated_coordinates_.all()
    assert opt.coef_[8] == 0
    assert_oscillators(opt.coef_, truth)


def test_failed_implicit_part_names_the_coordinates():
    theta, _ = two_oscillators()
    n = theta.shape[0] // 2
    noisy = theta.copy()
    noisy[n:, [4, 5, 7]] = np.random.default_rng(1).normal(size=(n, 3))  # no law there
    with pytest.raises(NoLawFoundError, match=r"coordinate\(s\) \[1\]"):
        MixedOptimizer().fit_catalog(noisy, 2, [0])


def test_contract_and_validation():
    opt = MixedOptimizer(implicit_optimizer=ImplicitOptimizer(alpha=1e-6))
    assert clone(opt).get_params()["implicit_optimizer"].alpha == 1e-6
    theta, _ = two_oscillators()
    # one block without structure: the explicit part with a right-hand side, else implicit
    n = theta.shape[0] // 2
    np.testing.assert_allclose(opt.fit(theta[:n, 1:4], theta[:n, 0]).coef_, [1.0, 4.0, 0.3],
                               rtol=1e-8)
    assert opt.mode_ == "explicit"
    law = opt.fit(theta[n:, 4:6]).coef_
    np.testing.assert_allclose(law / law[0], [1.0, 9.0], rtol=1e-8)
    with pytest.raises(TypeError, match="fit_catalog"):
        MixedOptimizer(px.EnsembleOptimizer()).fit(theta[:n, 1:4], theta[:n, 0])
    with pytest.raises(TypeError, match="explicit_optimizer"):
        MixedOptimizer(explicit_optimizer=object()).fit_catalog(theta, 2, [0])
    with pytest.raises(ValueError, match="rtol"):
        MixedOptimizer(rtol=2.0).fit_catalog(theta, 2, [0])
    with pytest.raises(ValueError, match="force_columns"):
        MixedOptimizer().fit_catalog(theta, 2, [8])
    assert opt.fit_catalog(theta, 2, [0]) is opt


# ---------------------------------------------------------------------------------------------
# Acceptance with ground truth
# ---------------------------------------------------------------------------------------------


def paper_catalog(coords, angles, velocities=None):
    """Velocity monomials (degree 2) x trigonometric monomials of the angles (degree 2), plus
    viscous friction on every coordinate (as in the explicit acceptance tests)."""
    velocities = coords.qd if velocities is None else velocities
    trig = [f(coords.q[i]) for i in angles for f in (sp.sin, sp.cos)]
    terms = px.products([1, *px.monomials(trig, 2)], [1, *px.monomials(velocities, 2)])
    return [t for t in terms if t.free_symbols]


def friction_library(coords):
    return px.ClassicalLibrary(coords, coords.qd, mask=np.eye(coords.n, dtype=bool))


def forced_runs(system, active, seeds, duration=15.0, dt=0.005):
    t = np.arange(0.0, duration, dt)
    return [
        system.simulate(random_initial_state(system, s), t, random_force(system, s, active=active))
        for s in seeds
    ]


def fit(library, optimizer, q, qd, qdd, u, t):
    model = px.XLSINDy(library, optimizer)
    return model.fit(q, t, x_dot=qd, x_ddot=qdd, u=u)


def check_terms(coef, true, names, columns, rel_tol=0.02, scale_free=False):
    """Support equal to the truth on ``columns``; coefficients within rel_tol (after the
    least-squares scale when ``scale_free``)."""
    coef, true, names = coef[columns], true[columns], np.asarray(names)[columns]
    support = true != 0
    false_terms = names[(coef != 0) & ~support]
    missed = names[(coef == 0) & support]
    assert not len(false_terms), f"false terms: {false_terms}"
    assert not len(missed), f"missed terms: {missed}"
    if scale_free:
        coef = coef * (coef[support] @ true[support]) / (coef[support] @ coef[support])
    rel = np.abs(coef[support] - true[support]) / np.abs(true[support])
    assert rel.max() < rel_tol, f"worst relative error {rel.max():.2e} on " \
                                f"{names[support][np.argmax(rel)]}"


PARTIAL = {
    # system fixture, angles, forced coordinates
    "cart_double_pendulum_cart_force": ("cart_double_pendulum_system", [1, 2], [0]),
    "double_pendulum_second_torque": ("double_pendulum_system", [0, 1], [1]),
}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(PARTIAL))
def test_partially_forced_coupled_systems(name, request):
    """Every coordinate is coupled to the forced one, so the activation reaches all of them and
    mixed regression is the explicit regression on the whole catalog: both recover the system
    (explicit does not do worse here; it fails only on decoupled free subsystems, see below)."""
    fixture, angles, active = PARTIAL[name]
    system = request.getfixturevalue(fixture)
    coords = system.coords
    library = px.CatalogRepartition([
        px.LagrangeLibrary(coords, paper_catalog(coords, angles)), friction_library(coords)
    ])
    runs = forced_runs(system, active, seeds=(0, 1))
    args = [[r[k] for r in runs] for k in ("q", "qd", "qdd", "tau", "t")]
    mixed = fit(library, MixedOptimizer(), *args)
    assert mixed.optimizer_.mode_ == "explicit"
    assert mixed.optimizer_.activated_coordinates_.all()
    np.testing.assert_array_equal(
        mixed.optimizer_.forced_coordinates_, np.isin(np.arange(coords.n), active)
    )
    friction = {(coords.qd[i], i): c for i, c in enumerate(system.friction)}
    true = library.ideal_coefficients(lagrangian=system.lagrangian, classical=friction)
    everything = np.arange(len(true))
    check_terms(mixed.coefficients(), true, mixed.get_feature_names(), everything)
    explicit = fit(library, px.ExplicitOptimizer(), *args)
    np.testing.assert_array_equal(explicit.coefficients(), mixed.coefficients())


@pytest.mark.slow
def test_forced_cart_pole_next_to_a_free_double_pendulum(cart_pole_system,
                                                         double_pendulum_system):
    """A robot whose actuated part (cart-pole, force on the cart) is decoupled from an
    unactuated double pendulum: mixed regression identifies both; explicit alone cannot."""
    cart, pendulum = cart_pole_system, double_pendulum_system
    coords = px.Coordinates(["x", "theta", "theta1", "theta2"])
    x, th, th1, th2 = coords.q
    cart_terms = paper_catalog(coords, [1], velocities=coords.qd[:2])
    c12 = sp.cos(th1) * sp.cos(th2) + sp.sin(th1) * sp.sin(th2)
    pendulum_terms = px.products([1, c12], px.monomials(coords.qd[2:], 2)) + [
        sp.cos(th1), sp.cos(th2), sp.sin(th1), sp.sin(th2)
    ]
    # c12 times one velocity monomial enters as a single expression: split it into monomials.
    pendulum_terms = [t for term in pendulum_terms for t in sp.expand(term).as_ordered_terms()]
    library = px.CatalogRepartition([
        px.LagrangeLibrary(coords, cart_terms + pendulum_terms), friction_library(coords)
    ]).fit()
    t = np.arange(0.0, 15.0, 0.005)
    runs = []
    for seed in (0, 1, 2):
        a = cart.simulate(random_initial_state(cart, seed), t, random_force(cart, seed, [0]))
        b = pendulum.simulate(random_initial_state(pendulum, seed), t)
        runs.append({k: np.hstack([a[k], b[k]]) for k in ("q", "qd", "qdd", "tau")})
    args = [[r[k] for r in runs] for k in ("q", "qd", "qdd", "tau")] + [[t] * 3]

    friction = {(coords.qd[i], i): c
                for i, c in enumerate(np.concatenate([cart.friction, pendulum.friction]))}
    true = library.ideal_coefficients(lagrangian=cart.lagrangian + pendulum.lagrangian,
                                      classical=friction)
    names = library.get_feature_names()
    symbolic = library.symbolic_matrix()
    touches_pendulum = np.array([
        bool(symbolic[2, j] != 0 or symbolic[3, j] != 0) for j in range(len(names))
    ])
    touches_pendulum[library.force_columns_] = False  # the force acts on the cart only
    cart_columns = np.flatnonzero(~touches_pendulum)
    pendulum_columns = np.flatnonzero(touches_pendulum)

    mixed = fit(library, MixedOptimizer(), *args)
    opt = mixed.optimizer_
    assert opt.mode_ == "mixed"
    np.testing.assert_array_equal(opt.explicit_coordinates_, [True, True, False, False])
    coef = mixed.coefficients()
    check_terms(coef, true, names, cart_columns)                     # force fixes the scale
    check_terms(coef, true, names, pendulum_columns, scale_free=True)  # a free law's scale is not

    assert mixed.mass_matrix_check_["positive_definite_fraction"] == 1.0  # sign normalized

    # explicit regression leaves the pendulum without inertia, and fit says so
    with pytest.warns(px.IdentificationWarning, match=r"no positive inertia on \['theta1', "
                                                       r"'theta2'\]"):
        explicit = fit(library, px.ExplicitOptimizer(), *args)
    assert not np.any(explicit.coefficients()[pendulum_columns]), \
        "explicit regression found terms for the unforced, decoupled pendulum"
