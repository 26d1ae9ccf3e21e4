"""Weak formulation: the weak matrix against independent quadrature of the pointwise one,
the smoother and test functions on their own, and identification from noisy positions
(ground truth: sympy.physics.mechanics systems integrated by scipy at tight tolerance)."""

import numpy as np
import pytest
import sympy as sp
from ground_truth import random_force, random_initial_state
from scipy.integrate import simpson
from support.paper import noisy_run, paper_catalog, true_coefficients, validates

import pysindy_xl as px
from pysindy_xl.feature_library._weak import integrate_by_parts
from pysindy_xl.optimizers.selection import select_support
from pysindy_xl.physical.friction import regularized_dry_friction
from pysindy_xl.weak import BumpTestFunctions, WhittakerSmoother, quadrature_weights

# ---------------------------------------------------------------------------- weak matrix


def _analytic_data(coords, t):
    """Smooth closed-form trajectories with exact derivatives."""
    n = coords.n
    k = np.arange(1, n + 1)
    q = np.sin(np.outer(t, k) * 0.7 + k) + 0.1 * t[:, None]
    qd = 0.7 * k * np.cos(np.outer(t, k) * 0.7 + k) + 0.1
    qdd = -(0.7 * k) ** 2 * np.sin(np.outer(t, k) * 0.7 + k)
    tau = np.cos(np.outer(t, k) * 1.3)
    return q, qd, qdd, tau


@pytest.mark.parametrize("grid", ["uniform", "jittered"])
def test_weak_matrix_is_the_integral_of_the_pointwise_one(grid):
    coords = px.Coordinates(["x", "theta"])
    x, th = coords.q
    xd, thd = coords.qd
    lagrange = px.LagrangeLibrary(coords, [xd**2, thd**2 * sp.cos(th), xd * thd * sp.cos(th),
                                           sp.cos(th), xd * sp.sin(th), x**2 * thd])
    classical = px.ClassicalLibrary(coords, [xd, thd * xd, sp.cos(th) * coords.qdd[1],
                                             x**2 * xd])
    library = px.CatalogRepartition([lagrange, classical]).fit()
    rng = np.random.default_rng(0)
    t = np.linspace(0, 6, 3001)
    if grid == "jittered":
        t[1:-1] += rng.uniform(-0.3, 0.3, len(t) - 2) * (t[1] - t[0])
    q, qd, qdd, tau = _analytic_data(coords, t)
    z = px.stack_variables(q, qd, qdd, tau, t)
    phi, dphi, _ = BumpTestFunctions(width=1.0, n_functions=7).matrices(t)
    weak = library.weak_transform(z, phi, dphi)
    # independent reference: Simpson's rule on the pointwise columns times the bump
    strong = library.transform(z).reshape(2, len(t), -1)
    bumps = (phi.toarray() / quadrature_weights(t))  # the test functions themselves
    reference = np.concatenate([
        simpson(bumps[:, :, None] * strong[c][None], x=t, axis=1) for c in range(2)
    ])
    scale = np.abs(reference).max(axis=0) + 1e-12
    tolerance = 1e-7 if grid == "uniform" else 2e-4
    assert np.abs(weak - reference).max(axis=0).max() / scale.max() < tolerance
    assert np.all(np.abs(weak - reference).max(axis=0) / scale < 50 * tolerance)


def test_integration_by_parts_splits():
    c = px.Coordinates(["x", "y"])
    assert integrate_by_parts(c.qd[0], c) == (c.q[0], 0)  # viscous friction needs no velocity
    p, q = integrate_by_parts(c.q[1] ** 2 * c.qdd[0] + c.tau[0], c)
    assert p == c.q[1] ** 2 * c.qd[0]
    assert sp.expand(q - (2 * c.q[1] * c.qd[1] * c.qd[0] - c.tau[0])) == 0
    # y_dot x_ddot is no velocity gradient (d/dx_dot of G would be y_dot, d/dy_dot zero)
    with pytest.raises(ValueError, match="not the velocity gradient of one function"):
        integrate_by_parts(c.qd[1] * c.qdd[0], c)
    with pytest.raises(ValueError, match="depends on forces or accelerations.*'strong'"):
        integrate_by_parts(c.qdd[0] ** 2, c)


def test_velocity_dependent_accelerations_integrate_by_parts():
    """E = d/dt P - Q for accelerations with velocity-dependent coefficients (a joint
    velocity's function times its derivative; MuJoCo's dry friction with its lead and
    sticking zone): against a bump, -int phi' P - int phi Q equals the quadrature of phi E
    on a fine grid along a known trajectory."""
    c = px.Coordinates(["x", "y"])
    relative = c.qd[0] - c.qd[1]
    entries = [sp.tanh(3 * relative) * (c.qdd[0] - c.qdd[1]) + sp.cos(c.q[1]) * c.qd[0],
               regularized_dry_friction(c.qd[0], c.qdd[0], 0.4, 0.05),
               c.qd[0] ** 2 * sp.sin(c.q[1]) * c.qdd[0]]
    t = np.linspace(0.0, 4.0, 400_001)
    x, xd, xdd = np.sin(1.3 * t), 1.3 * np.cos(1.3 * t), -1.69 * np.sin(1.3 * t)
    y, yd, ydd = 0.5 * np.cos(0.7 * t), -0.35 * np.sin(0.7 * t), -0.245 * np.cos(0.7 * t)
    values = dict(zip([*c.q, *c.qd, *c.qdd], [x, y, xd, yd, xdd, ydd], strict=True))
    phi = np.clip(1 - ((t - 2.0) / 1.8) ** 2, 0, None) ** 3
    dphi = np.gradient(phi, t)

    def at(expr):
        free = sorted(expr.free_symbols, key=str)
        return np.broadcast_to(sp.lambdify(free, expr, "numpy")(*(values[s] for s in free)),
                               t.shape)

    for entry in entries:
        p, q = integrate_by_parts(entry, c)
        assert not (p.free_symbols | q.free_symbols) & set(c.qdd)
        pointwise = simpson(phi * at(entry), x=t)
        weak = -simpson(dphi * at(p), x=t) - simpson(phi * at(q), x=t)
        assert weak == pytest.approx(pointwise, rel=1e-6, abs=1e-9), entry


def test_weak_refuses_unintegrable_classical_term(cart_pole_system):
    system = cart_pole_system
    c = system.coords
    library = paper_catalog(c, [1]) + px.ClassicalLibrary(c, [c.qd[1] * c.qdd[0]])
    t = np.arange(0, 5, 0.01)
    data = system.simulate(random_initial_state(system, 0), t, random_force(system, 0))
    with pytest.raises(ValueError, match="formulation='strong'"):
        px.XLSINDy(library, formulation="weak").fit(data["q"], t, u=data["tau"])


def test_quadrature_on_a_jittered_grid_integrates_by_parts():
    rng = np.random.default_rng(1)
    t = np.sort(rng.uniform(0, 10, 4000))
    phi, dphi, _ = BumpTestFunctions(width=1.5, n_functions=20).matrices(t)
    # int phi q' = -int phi' q for q = sin(1.7 t)
    lhs = phi @ (1.7 * np.cos(1.7 * t))
    rhs = -(dphi @ np.sin(1.7 * t))
    assert np.abs(lhs - rhs).max() < 1e-4 * np.abs(lhs).max()


# ---------------------------------------------------------------------- smoother, widths


def _grid(kind, rng):
    """20 s of samples: uniform at 100 Hz, with 30 % of them lost at random, or logged at
    200 Hz and 50 Hz in alternate seconds."""
    t = np.linspace(0, 20, 2001)
    if kind == "dropped":
        t = np.sort(rng.choice(t, 1400, replace=False))
    elif kind == "two rates":
        t = np.unique(np.concatenate([np.arange(k, k + 1, 0.005 if k % 2 else 0.02)
                                      for k in range(20)] + [[20.0]]))
    return t


@pytest.mark.parametrize("grid", ["uniform", "dropped", "two rates"])
def test_smoother_estimates_noise_and_velocity(grid):
    # Read in sample order, a smooth signal on an irregular grid looks noisy: the noise level
    # and the smoothing weight must come from the actual times (as much phantom noise as
    # the real one, and 5x rougher velocities, when they did not).
    t = _grid(grid, np.random.default_rng(5))
    truth = np.column_stack([np.sin(t) + 0.3 * np.sin(2.3 * t), 0.5 * np.cos(0.7 * t)])
    velocity = np.column_stack([np.cos(t) + 0.69 * np.cos(2.3 * t), -0.35 * np.sin(0.7 * t)])
    sigma = 0.01 * truth.std(axis=0)
    noisy = truth + sigma * np.random.default_rng(2).normal(size=truth.shape)
    smoother = WhittakerSmoother()
    q, qd, _ = smoother.smooth(t, noisy)
    np.testing.assert_allclose(smoother.noise_, sigma, rtol=0.15)
    assert np.all(np.std(q - truth, axis=0) < 0.5 * sigma)
    relative = np.std(qd - velocity, axis=0) / velocity.std(axis=0)
    assert np.all(relative < 0.02), relative
    # clean data pass through
    q, qd, _ = smoother.smooth(t, truth)
    assert np.all(smoother.noise_ < 1e-3 * sigma)
    # the velocity's risk is weighed away from the ends (where the test functions vanish)
    assert np.abs(qd - velocity)[5:-5].max() < 1e-4
    assert np.abs(qd - velocity).max() < 5e-4


@pytest.mark.parametrize("grid", ["dropped", "two rates"])
def test_quadrature_on_irregular_grids_is_fourth_order(grid):
    from scipy.integrate import quad

    t = _grid(grid, np.random.default_rng(6))
    t = t[t <= 6.0]
    phi, _, _ = BumpTestFunctions(width=1.0, n_functions=5).matrices(t)
    centers = np.linspace(t[0] + 1.0, t[-1] - 1.0, 5)

    def f(time):
        return np.sin(2 * np.pi * 1.3 * time) * np.cos(0.7 * time) + 0.5

    reference = np.array([quad(lambda s, c=c: (1 - ((s - c) / 1.0) ** 2) ** 6 * f(s), c - 1.0,
                               c + 1.0, epsabs=1e-13, epsrel=1e-13)[0] for c in centers])
    # the trapezoidal rule is off by 5e-4 on the grid with lost samples
    assert np.abs(phi @ f(t) - reference).max() < 5e-5 * np.abs(reference).max()


def test_bad_options_are_named():
    with pytest.raises(ValueError, match="lam"):
        WhittakerSmoother(lam="loose").smooth(np.arange(10.0), np.zeros((10, 1)))
    with pytest.raises(ValueError, match="width"):
        BumpTestFunctions(width=-1.0).matrices(np.arange(100.0))
    with pytest.raises(ValueError, match="shorter than one test function"):
        BumpTestFunctions(width=50.0).matrices(np.arange(100.0))
    with pytest.raises(ValueError, match="formulation"):
        px.XLSINDy(px.LagrangeLibrary(px.Coordinates(["x"]), [px.Coordinates(["x"]).qd[0] ** 2]),
                   formulation="weakest").fit(np.zeros((50, 1)), 0.1, u=np.ones((50, 1)))


# ------------------------------------------------------------------------ model selection


def test_selection_keeps_small_true_terms_and_cuts_noise_terms():
    rng = np.random.default_rng(3)
    x = rng.normal(size=(2000, 30))
    coef = np.zeros(30)
    coef[[2, 7, 19]] = [1.0, -0.5, 0.004]  # 0.4 % of the largest contribution
    y = x @ coef
    assert select_support(x, y + 1e-10 * rng.normal(size=2000)).support.tolist() == [2, 7, 19]
    noisy = select_support(x, y + 0.2 * rng.normal(size=2000))
    assert set(noisy.support) <= {2, 7, 19} and {2, 7} <= set(noisy.support)


def test_small_damping_survives_on_clean_data(cart_pole_system):
    # joint damping of 0.5 % of the largest term: pruned by a 1 % threshold, kept by the path
    system = cart_pole_system.with_friction([0.3, 0.005])
    t = np.arange(0, 15, 0.005)
    data = system.simulate(random_initial_state(system, 7), t, random_force(system, 7))
    library = paper_catalog(system.coords, [1])
    for formulation, derivatives in (("strong", {"x_dot": data["qd"], "x_ddot": data["qdd"]}),
                                     ("weak", {})):
        model = px.XLSINDy(library, formulation=formulation).fit(
            data["q"], t, u=data["tau"], **derivatives)
        true = true_coefficients(system, library)
        coef = model.coefficients()
        assert np.array_equal(coef != 0, true != 0), formulation
        damping = model.get_feature_names().index("C_theta[theta_dot]")
        assert abs(coef[damping] - 0.005) < 1e-4, (formulation, coef[damping])
        if formulation == "strong":  # one cross-validated selection
            assert model.selection_ is not None
        else:  # positions only: bagged by default, every fit keeps the damping
            assert model.inclusion_probability_[damping] == 1.0


# ------------------------------------------------------- identification from noisy positions


_RATES = {}


def _success_rate(system, angles, level, seeds):
    """``(exact supports, median error, valid models)`` over ``seeds``, computed once per
    module: the sweep's cart-pole cell at 1 % is the CI cell's (same runs, same fits)."""
    key = (system.name, str(system.lagrangian), system.friction.tobytes(), tuple(angles),
           level, tuple(seeds))
    if key not in _RATES:
        _RATES[key] = _measured_success_rate(system, angles, level, seeds)
    return _RATES[key]


def _measured_success_rate(system, angles, level, seeds):
    library = paper_catalog(system.coords, angles)
    true = true_coefficients(system, library.fit())
    exact, errors, valid = 0, [], 0
    for seed in seeds:
        t, noisy, data, _ = noisy_run(system, seed, level)
        model = px.XLSINDy(library).fit(noisy, t, u=data["tau"])
        assert model.formulation_ == "weak"
        coef = model.coefficients()
        support = true != 0
        exact += np.array_equal(coef != 0, support)
        errors.append(np.median(np.abs(coef[support] - true[support]) / np.abs(true[support])))
        valid += validates(model, system, 500 + seed)
    return exact, float(np.median(errors)), valid


@pytest.mark.slow
def test_cart_pole_from_one_percent_noisy_positions(cart_pole_system):
    """CI cell of the noise sweep (measured: 5 of 8 seeds exact at 1 %, see the note)."""
    exact, error, valid = _success_rate(cart_pole_system, [1], 0.01, range(4))
    assert exact >= 2, exact
    assert error < 0.01, error
    assert valid >= 3, valid


_ANGLES = {"cart_pole": [1], "double_pendulum": [0, 1], "cart_double_pendulum": [1, 2]}


@pytest.mark.slow
@pytest.mark.parametrize(("name", "level"), [
    ("cart_pole", 0.01), ("cart_pole", 0.03), ("cart_pole", 0.05),
    ("double_pendulum", 0.01), ("double_pendulum", 0.03), ("double_pendulum", 0.05),
    ("cart_double_pendulum", 0.01), ("cart_double_pendulum", 0.03),
])
def test_noise_sweep_cells(name, level, request):
    system = request.getfixturevalue(f"{name}_system")
    exact, error, valid = _success_rate(system, _ANGLES[name], level, range(4))
    # honest floors of what the method reaches today (measured on 10 seeds in
    # benchmarks/results/noise_sweep.md: exact support 6-10 of 10, median errors 0.1-0.8 %;
    # the targets of issue 10 are higher); four seeds per cell, the sweep's ten are the
    # benchmark's
    assert exact >= 2, exact
    assert error < 0.02, error
    assert valid >= 3, valid


@pytest.mark.parametrize("name", ["cart_pole", "double_pendulum"])
def test_noise_free_positions_are_recovered_exactly_by_the_weak_form(name, request):
    system = request.getfixturevalue(f"{name}_system")
    angles = [1] if name == "cart_pole" else [0, 1]
    library = paper_catalog(system.coords, angles)
    t, _, data, _ = noisy_run(system, 3, 0.0, duration=20.0)
    model = px.XLSINDy(library).fit(data["q"], t, u=data["tau"])
    true = true_coefficients(system, library)
    coef = model.coefficients()
    assert np.array_equal(coef != 0, true != 0)
    support = true != 0
    assert np.max(np.abs(coef[support] - true[support]) / np.abs(true[support])) < 1e-4
    assert validates(model, system, 77)


def test_short_pieces_are_left_out_with_a_warning(cart_pole_system):
    system = cart_pole_system
    t, noisy, data, _ = noisy_run(system, 5, 0.01, duration=20.0)
    library = paper_catalog(system.coords, [1])
    pieces = [slice(0, 1900), slice(1900, 1930)]  # e.g. what constraint exclusion leaves
    with pytest.warns(UserWarning, match=r"trajectories \[1\] are shorter than one test"):
        model = px.XLSINDy(library).fit([noisy[p] for p in pieces], [t[p] for p in pieces],
                                        u=[data["tau"][p] for p in pieces])
    assert len(model.weak_info_["test_functions"]) == 1
    with pytest.raises(ValueError, match="shorter than one test function"):
        px.XLSINDy(library, test_functions=BumpTestFunctions(width=1.0)).fit(
            noisy[:150], t[:150], u=data["tau"][:150])


@pytest.mark.parametrize("formulation", ["strong", "weak"])
def test_sample_mask_excludes_unmodelled_forces(cart_pole_system, formulation):
    """A hidden push (a contact, say) in 8 s < t < 9 s: unmasked it spoils the fit, masked
    out the law is exact again."""
    system = cart_pole_system
    t = np.arange(0.0, 20.0, 0.005)
    recorded = random_force(system, 11)

    def actual(s):
        inside = np.asarray((8.0 < s) & (s < 9.0), dtype=float)
        push = np.array([25.0, 0.0]) * inside[..., None]
        return recorded(s) + push

    data = system.simulate(random_initial_state(system, 11), t, actual)
    tau = recorded(t)
    library = paper_catalog(system.coords, [1])
    true = true_coefficients(system, library)
    kwargs = {"x_dot": data["qd"], "x_ddot": data["qdd"]} if formulation == "strong" else {}
    spoiled = px.XLSINDy(library, formulation=formulation).fit(data["q"], t, u=tau, **kwargs)
    mask = ~((7.9 < t) & (t < 9.1))
    masked = px.XLSINDy(library, formulation=formulation).fit(data["q"], t, u=tau,
                                                            sample_mask=mask, **kwargs)
    support = true != 0
    error = np.abs(masked.coefficients()[support] - true[support]) / np.abs(true[support])
    assert np.array_equal(masked.coefficients() != 0, support)
    assert error.max() < 1e-3
    spoiled_error = np.abs(spoiled.coefficients() - true)[support] / np.abs(true[support])
    assert not np.array_equal(spoiled.coefficients() != 0, support) or spoiled_error.max() > 0.01
    with pytest.raises(ValueError, match="sample_mask"):
        px.XLSINDy(library, formulation=formulation).fit(data["q"], t, u=tau,
                                                         sample_mask=mask[:-1], **kwargs)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_test_function_width_does_not_move_with_the_noise(seed):
    # a drifting cart: after the linear trend the signal is small against noise of a few
    # percent of the spread; half the noise power counted as signal used to push the corner
    # from 0.77 Hz to over 40 Hz (test functions ~50x too narrow)
    from pysindy_xl.weak.bumps import corner_frequency

    t = np.arange(0, 30, 0.01)
    x = (0.2 * t + 0.2 * np.sin(2 * np.pi * 0.7 * t)
         + 0.1 * np.sin(2 * np.pi * 0.3 * t + 1))[:, None]
    clean = corner_frequency(t, x)
    assert 0.7 < clean < 0.85  # the 0.7 Hz component, to the DCT's resolution
    rng = np.random.default_rng(seed)
    for level in (0.01, 0.03, 0.05):
        noisy = x + level * x.std() * rng.normal(size=x.shape)
        assert corner_frequency(t, noisy) == pytest.approx(clean, rel=0.1), level


@pytest.mark.slow
@pytest.mark.parametrize("grid", ["dropped", "two rates"])
def test_positions_on_irregular_grids_are_recovered(grid, double_pendulum_system):
    # Lost samples or a changing logging rate: clean positions identify the true law as on a
    # uniform grid (a 1.5 % median error with 30 % of the samples lost, before the smoother
    # chose its weight on the actual times), and 1 % noise costs about what it costs there.
    system = double_pendulum_system
    library = paper_catalog(system.coords, [0, 1])
    true = true_coefficients(system, library)
    support = true != 0
    t = _grid(grid, np.random.default_rng(7))
    data = system.simulate(random_initial_state(system, 3), t, random_force(system, 3))
    for level, tolerance in ((0.0, 5e-4), (0.01, 1e-2)):
        noise = np.random.default_rng(8).normal(size=data["q"].shape)
        positions = data["q"] + level * data["q"].std(axis=0) * noise
        coef = px.XLSINDy(library).fit(positions, t, u=data["tau"]).coefficients()
        assert np.array_equal(coef != 0, support), level
        error = np.median(np.abs(coef[support] - true[support]) / np.abs(true[support]))
        assert error < tolerance, (level, error)
