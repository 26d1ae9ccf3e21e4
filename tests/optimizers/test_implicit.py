"""Implicit regression (SINDy-PI + homothetic clustering): numerics and identification.

Synthetic matrices with planted sparse null vectors check the solver, the clustering, the
normalization and the failure modes; the acceptance tests identify the unforced cart-pole and
the unforced double pendulum with friction against sympy.physics.mechanics ground truth.
"""

import warnings

import numpy as np
import pytest
from ground_truth import random_initial_state
from sklearn.base import clone
from sklearn.exceptions import ConvergenceWarning
from support.paper import paper_catalog

import pysindy_xl as px
from pysindy_xl.optimizers._sparse import kkt_violation, lasso_gram
from pysindy_xl.optimizers.implicit import (
    ImplicitOptimizer,
    NoLawFoundError,
    coordinates_touched,
    homothetic_groups,
)

# ---------------------------------------------------------------------------------------------
# Synthetic problems
# ---------------------------------------------------------------------------------------------


def planted_matrix(n_rows=400, n_free=12, laws=((0, [1, 2, 3], [2.0, -0.5, 1.5]),), seed=0):
    """Random smooth-ish columns plus dependent columns ``col_k = sum_i c_i col_i``.

    Returns the matrix and the true laws as vectors (dependent column coefficient -1).
    """
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 10, n_rows)
    free = np.column_stack([
        np.sin(rng.uniform(0.3, 3) * t + rng.uniform(0, 6)) * rng.uniform(0.5, 5)
        + 0.3 * rng.normal(size=n_rows)
        for _ in range(n_free)
    ])
    columns = [free]
    truths = []
    for k, (_, idx, coefs) in enumerate(laws):
        dependent = free[:, idx] @ np.asarray(coefs)
        columns.append(dependent[:, None])
        law = np.zeros(n_free + len(laws))
        law[idx] = coefs
        law[n_free + k] = -1.0
        truths.append(law)
    return np.hstack(columns), truths


def same_direction(a, b, rtol=1e-6):
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    return min(np.linalg.norm(a - b), np.linalg.norm(a + b)) < rtol


def test_lasso_gram_matches_per_column_reference():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(60, 8))
    a /= np.linalg.norm(a, axis=0)
    gram = a.T @ a
    mask = ~np.eye(8, dtype=bool)
    result = lasso_gram(gram, gram, 1e-2, mask=mask, tol=1e-6)
    assert result.converged.all()
    assert np.all(np.diag(result.coef) == 0)
    assert kkt_violation(gram, gram, result.coef, 1e-2, mask).max() <= 1e-8
    # Same optimum as scikit-learn's coordinate descent (objective 1/(2n) scaling: alpha / n).
    from sklearn.linear_model import Lasso

    for j in range(8):
        others = np.flatnonzero(mask[:, j])
        ref = Lasso(alpha=1e-2 / 60, fit_intercept=False, tol=1e-12, max_iter=100000)
        ref.fit(a[:, others], a[:, j])
        np.testing.assert_allclose(result.coef[others, j], ref.coef_, atol=1e-6)


def test_lasso_gram_warns_when_not_converged():
    rng = np.random.default_rng(4)
    a = rng.normal(size=(50, 30))
    a[:, 1] = a[:, 0] + 1e-6 * rng.normal(size=50)  # nearly collinear: slow
    a /= np.linalg.norm(a, axis=0)
    gram = a.T @ a
    with pytest.warns(ConvergenceWarning, match="did not converge"):
        lasso_gram(gram, gram, 1e-8, mask=~np.eye(30, dtype=bool), max_iter=3)


@pytest.mark.parametrize("solver", ["fista", "cvxpy"])
def test_planted_law_is_recovered_exactly(solver):
    theta, (truth,) = planted_matrix()
    opt = ImplicitOptimizer(solver=solver).fit(theta)
    assert opt.coef_.shape == (theta.shape[1],)
    assert np.array_equal(opt.coef_ != 0, truth != 0)
    assert same_direction(opt.coef_, truth)
    # Normalization: the dominant contribution |coef_k| * ||theta_k|| carries +1.
    contribution = np.abs(opt.coef_) * np.linalg.norm(theta, axis=0)
    assert opt.coef_[np.argmax(contribution)] == 1.0
    assert len(opt.laws_) == 1 and opt.combined_laws_ == [0]
    assert opt.law_residuals_[0] < 1e-12
    # The law's group holds columns of the law only, and the SINDy-PI matrix maps back.
    assert set(opt.law_groups_[0]) <= set(np.flatnonzero(truth))
    for j in opt.law_groups_[0]:
        column = opt.solution_matrix_[:, j]
        assert column[j] == 0
        # Up to the L1 shrinkage, the column is explained by the others.
        assert np.linalg.norm(theta @ column - theta[:, j]) < 1e-2 * np.linalg.norm(theta[:, j])


def test_fast_and_cvxpy_agree_on_the_solution_matrix():
    theta, _ = planted_matrix(n_free=10, seed=2)
    alpha = 1e-3
    fast = ImplicitOptimizer(alpha=alpha, early_stopping=False, tol=1e-6).fit(theta)
    ref = ImplicitOptimizer(alpha=alpha, solver="cvxpy").fit(theta)
    x_fast = fast.normalized_solution_matrix_
    x_ref = ref.normalized_solution_matrix_
    # Same problem: the fast solver's optimum is at least as good (the conic solver stops at
    # its own tolerance) and both matrices agree entry by entry.
    scaled = theta / np.linalg.norm(theta, axis=0)
    gram = scaled.T @ scaled

    def objective(x):
        return np.sum(0.5 * np.sum(x * (gram @ x), 0) - np.sum(gram * x, 0)) + alpha * np.abs(
            x).sum()

    assert objective(x_fast) <= objective(x_ref) + 1e-9
    assert np.abs(x_fast - x_ref).max() < 1e-3
    assert np.array_equal(np.abs(x_ref) > 1e-3, np.abs(x_fast) > 1e-3)
    np.testing.assert_array_equal(fast.coef_ != 0, ref.coef_ != 0)


def test_early_stopping_finds_the_full_solve_laws_in_few_iterations():
    # An exact law is read off the null-space start: the laws are checked at every
    # convergence check, so the solver stops within a few checks with the very law (bit for
    # bit: the refit depends on the support only) that solving every column gives.
    theta, (truth,) = planted_matrix(n_free=20, seed=5)
    early = ImplicitOptimizer().fit(theta)
    full = ImplicitOptimizer(early_stopping=False).fit(theta)
    assert early.converged_ and early.n_iter_ <= 30 < full.n_iter_
    assert np.array_equal(early.coef_ != 0, truth != 0)
    np.testing.assert_array_equal(early.coef_, full.coef_)
    # Noisy columns: the laws do not settle within the probe, the solve starts over (laws
    # checked every 100 iterations) and still stops long before every column converges.
    noisy = theta + 1e-3 * np.random.default_rng(5).normal(size=theta.shape) * theta.std(0)
    early = ImplicitOptimizer().fit(noisy)
    full = ImplicitOptimizer(early_stopping=False).fit(noisy)
    assert early.converged_ and 50 < early.n_iter_ < full.n_iter_
    assert np.array_equal(early.coef_ != 0, truth != 0)
    np.testing.assert_array_equal(early.coef_, full.coef_)


def test_triangular_factor_is_scipys_r():
    import scipy.linalg

    from pysindy_xl.optimizers._sparse import triangular_factor

    rng = np.random.default_rng(0)
    for shape in [(500, 7), (7, 7), (3, 5), (1, 4)]:
        matrix = rng.normal(size=shape)
        expected = scipy.linalg.qr(matrix, mode="r")[0][: min(shape)]
        np.testing.assert_array_equal(triangular_factor(matrix), expected)
    r_factor = triangular_factor(matrix := rng.normal(size=(200, 6)))
    np.testing.assert_allclose(r_factor.T @ r_factor, matrix.T @ matrix, rtol=1e-12)
    assert np.array_equal(r_factor, np.triu(r_factor))


def test_decoupled_laws_are_combined_on_disjoint_supports():
    theta, truths = planted_matrix(
        n_free=12, laws=((0, [0, 1, 2], [1.0, -2.0, 0.7]), (1, [6, 7], [3.0, 0.4])), seed=5
    )
    opt = ImplicitOptimizer().fit(theta)
    assert len(opt.laws_) == 2
    for truth in truths:
        assert any(same_direction(law, truth) for law in opt.laws_)
    assert sorted(opt.combined_laws_) == [0, 1]
    np.testing.assert_allclose(opt.coef_, opt.laws_.sum(axis=0))
    assert np.allclose(theta @ opt.coef_, 0, atol=1e-9 * np.abs(theta).max())


def test_force_column_fixes_the_scale_and_reference_columns_pick_the_pivot():
    theta, (truth,) = planted_matrix(seed=6)
    n_rows = theta.shape[0]
    # Two "coordinates" of n_rows / 2 samples each; treat the dependent column as the force.
    force = theta.shape[1] - 1
    opt = ImplicitOptimizer().fit_catalog(theta, 2, [force])
    assert opt.coef_[force] == -1.0
    np.testing.assert_allclose(opt.coef_, truth, rtol=1e-8)
    # Without a force: the pivot among the reference columns is +1.
    opt = ImplicitOptimizer().fit_catalog(theta, 2, [], reference_columns=[2])
    assert opt.coef_[2] == 1.0
    assert n_rows % 2 == 0


def test_no_law_raises():
    rng = np.random.default_rng(8)
    theta = rng.normal(size=(300, 10))
    with pytest.raises(NoLawFoundError, match="no group"):
        ImplicitOptimizer().fit(theta)


def test_parameters_and_inputs_are_validated():
    theta, _ = planted_matrix()
    for bad in ({"alpha": 0.0}, {"solver": "scs"}, {"angle_tol": 95}, {"threshold": 1.0},
                {"max_iter": 0}, {"min_group_size": 1.5}, {"max_residual_ratio": 0.5}):
        with pytest.raises(ValueError, match=next(iter(bad))):
            ImplicitOptimizer(**bad).fit(theta)
    bad_theta = theta.copy()
    bad_theta[0, 0] = np.nan
    with pytest.raises(ValueError, match="theta"):
        ImplicitOptimizer().fit(bad_theta)
    with pytest.raises(ValueError, match="n_coordinates"):
        ImplicitOptimizer().fit_catalog(theta[:399], 2, [])
    with pytest.raises(ValueError, match="reference_columns"):
        ImplicitOptimizer().fit_catalog(theta, 2, [], reference_columns=[99])


def test_sklearn_contract():
    opt = ImplicitOptimizer(alpha=1e-3, solver="cvxpy", angle_tol=3.0)
    assert clone(opt).get_params() == opt.get_params()
    theta, _ = planted_matrix()
    assert opt.fit(theta) is opt
    assert clone(opt).get_params()["solver"] == "cvxpy"
    assert not hasattr(clone(opt), "coef_")


def test_helpers():
    theta = np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [3.0, 1.0]])
    np.testing.assert_array_equal(coordinates_touched(theta, 2), [[True, False], [True, True]])
    vectors = np.array([[1.0, -2.0, 0.0, 1.0], [1.0, -2.0, 1.0, 1.001]])
    groups = homothetic_groups(vectors, angle_tol=1.0, order=[2, 0, 1, 3])
    assert [g.tolist() for g in groups] == [[2], [0, 1, 3]]


# ---------------------------------------------------------------------------------------------
# Acceptance: unforced cart-pole and double pendulum with friction
# ---------------------------------------------------------------------------------------------


def unforced_runs(system, seeds, duration=15.0, dt=0.005):
    t = np.arange(0.0, duration, dt)
    return [system.simulate(random_initial_state(system, s), t) for s in seeds]


def fit_unforced(system, library, optimizer, seeds=(0, 1, 2)):
    runs = unforced_runs(system, seeds)
    model = px.XLSINDy(library, optimizer)
    model.fit([r["q"] for r in runs], [r["t"] for r in runs], x_dot=[r["qd"] for r in runs],
              x_ddot=[r["qdd"] for r in runs])
    return model


def check_up_to_scale(model, system, library, rel_tol=0.02):
    """Every true term, no false one, coefficients within rel_tol after scale normalization."""
    friction = {(system.coords.qd[i], i): c for i, c in enumerate(system.friction)}
    true = library.ideal_coefficients(lagrangian=system.lagrangian, classical=friction,
                                      forces=0.0)
    coef = model.coefficients()
    names = np.array(model.get_feature_names())
    support = true != 0
    assert not np.any(coef[library.force_columns_]), "unforced fit used the force column"
    false_terms = names[(coef != 0) & ~support]
    missed = names[(coef == 0) & support]
    assert not len(false_terms), f"false terms: {false_terms}"
    assert not len(missed), f"missed terms: {missed}"
    scale = (coef[support] @ true[support]) / (coef[support] @ coef[support])
    rel = np.abs(scale * coef[support] - true[support]) / np.abs(true[support])
    assert rel.max() < rel_tol, f"worst relative error {rel.max():.2e} on " \
                                f"{names[support][np.argmax(rel)]}"
    return coef


SYSTEMS = {
    "cart_pole": ("cart_pole_system", [1]),
    "double_pendulum": ("double_pendulum_system", [0, 1]),
}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SYSTEMS))
def test_implicit_identification_of_unforced_systems(name, request):
    fixture, angles = SYSTEMS[name]
    system = request.getfixturevalue(fixture)
    library = paper_catalog(system.coords, angles)
    model = fit_unforced(system, library, ImplicitOptimizer())
    fast = check_up_to_scale(model, system, library)
    assert model.optimizer_.converged_
    # The identified equations contain the accelerations: the model simulates.
    x0 = random_initial_state(system, 42)
    t = np.arange(0.0, 3.0, 0.01)
    truth = system.simulate(x0, t)
    sim = model.simulate(x0, t)
    assert np.sqrt(np.mean((sim[:, : system.n] - truth["q"]) ** 2)) < 1e-3
    # The cvxpy reference formulation recovers the same support.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        reference = fit_unforced(system, library, ImplicitOptimizer(solver="cvxpy"))
    np.testing.assert_array_equal(reference.coefficients() != 0, fast != 0)


def test_figure_2_plot(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    theta, _ = planted_matrix()
    opt = ImplicitOptimizer().fit(theta)
    axes = opt.plot(feature_names=[f"f{k}" for k in range(theta.shape[1])])
    assert len(axes) == 3
    axes[0].figure.savefig(tmp_path / "figure2.png")
    assert (tmp_path / "figure2.png").stat().st_size > 0
