"""ExplicitOptimizer: sparse recovery on synthetic problems, parameters, the catalog protocol."""

import warnings

import numpy as np
import pysindy as ps
import pytest
from sklearn.base import BaseEstimator, clone
from sklearn.exceptions import ConvergenceWarning
from sklearn.linear_model import Lasso

import pysindy_xl as px
from pysindy_xl.optimizers import CatalogProblem, hard_threshold_regression, proximal_gradient_lasso

# Column scales spanning 6 orders of magnitude: the optimizer must normalize internally.
SCALES = np.array([1.0, 10.0, 0.1, 1.0, 5.0, 1.0, 0.01, 1e3])
TRUE = np.array([2.0, 0.0, 0.0, -1.5, 0.0, 0.3, 0.0, 0.0]) / SCALES


def _problem(seed=0, n_rows=300, noise=0.0):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n_rows, len(SCALES))) * SCALES
    y = x @ TRUE + noise * rng.normal(size=n_rows)
    return x, y


METHODS = {
    "threshold": "threshold",
    "lasso": "lasso",
    "lassocv": "lassocv",
    "proximal": "proximal",
    "stlsq": ps.STLSQ(threshold=0.05),
    "sklearn_lasso": Lasso(alpha=1e-4, fit_intercept=False),
}


@pytest.mark.parametrize("name", list(METHODS))
def test_each_method_recovers_sparse_vector(name):
    x, y = _problem()
    opt = px.ExplicitOptimizer(method=METHODS[name]).fit(x, y)
    np.testing.assert_array_equal(opt.support_, TRUE != 0)
    np.testing.assert_allclose(opt.coef_, TRUE, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("name", ["threshold", "lasso", "proximal"])
def test_recovery_with_noise(name):
    x, y = _problem(seed=1, n_rows=2000, noise=1e-3)
    opt = px.ExplicitOptimizer(method=METHODS[name]).fit(x, y)
    np.testing.assert_array_equal(opt.support_, TRUE != 0)
    support = TRUE != 0
    assert np.max(np.abs(opt.coef_[support] / TRUE[support] - 1)) < 1e-3


def test_refit_removes_l1_shrinkage():
    x, y = _problem()
    biased = px.ExplicitOptimizer(method="lasso", alpha=0.05, refit=False).fit(x, y)
    refitted = px.ExplicitOptimizer(method="lasso", alpha=0.05, refit=True).fit(x, y)
    support = TRUE != 0
    # a strong L1 weight shrinks the coefficients towards zero ...
    assert np.all(np.abs(biased.coef_[support]) < np.abs(TRUE[support]))
    # ... and the least-squares refit on the selected support removes the bias
    np.testing.assert_allclose(refitted.coef_, TRUE, rtol=1e-9, atol=1e-12)


def test_threshold_prunes_by_condition_value():
    rng = np.random.default_rng(2)
    x = rng.normal(size=(500, 3)) * [1.0, 1e4, 1.0]
    # the second term is numerically large but contributes 0.5 % of the first one
    y = x @ [1.0, 0.005 / 1e4, 0.0] + 1e-6 * rng.normal(size=500)
    pruned = hard_threshold_regression(x, y, threshold=0.01)
    assert pruned[1] == 0.0 and pruned[2] == 0.0
    # refitted on the remaining column: plain least squares of y on x_0
    expected = np.linalg.lstsq(x[:, :1], y, rcond=None)[0][0]
    assert pruned[0] == pytest.approx(expected, rel=1e-12)
    kept = hard_threshold_regression(x, y, threshold=1e-3)
    assert kept[1] == pytest.approx(0.005 / 1e4, rel=1e-3)
    assert kept[2] == 0.0


def test_proximal_gradient_solves_lasso_like_sklearn():
    x, y = _problem(seed=3)
    xs = x / np.sqrt(np.mean(x**2, axis=0))
    alpha = 0.01
    coef, converged = proximal_gradient_lasso(xs, y, alpha)
    assert converged
    reference = Lasso(alpha=alpha, fit_intercept=False, tol=1e-12, max_iter=100_000).fit(xs, y)
    np.testing.assert_allclose(coef, reference.coef_, atol=1e-7)


@pytest.mark.parametrize(
    "params, error, match",
    [
        ({"method": "foo"}, ValueError, "method: expected one of"),
        ({"method": 3}, TypeError, "method"),
        ({"method": object()}, TypeError, "method"),
        ({"threshold": 1.0}, ValueError, "threshold"),
        ({"threshold": -0.1}, ValueError, "threshold"),
        ({"threshold": np.nan}, ValueError, "threshold"),
        ({"alpha": -1.0}, ValueError, "alpha"),
        ({"max_iter": 0}, ValueError, "max_iter"),
        ({"max_iter": -5}, ValueError, "max_iter"),
    ],
)
def test_bad_parameters_rejected_at_fit(params, error, match):
    x, y = _problem()
    opt = px.ExplicitOptimizer(**params)  # constructor only stores
    with pytest.raises(error, match=match):
        opt.fit(x, y)


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")
def test_nan_alpha_rejected():
    x, y = _problem()
    with pytest.raises(ValueError, match="alpha"):
        px.ExplicitOptimizer(method="proximal", alpha=np.nan).fit(x, y)


def test_non_numeric_max_iter_names_the_argument():
    x, y = _problem()
    with pytest.raises((ValueError, TypeError)) as info:
        px.ExplicitOptimizer(max_iter="abc").fit(x, y)
    assert "max_iter" in str(info.value)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda x, y: (x, np.zeros_like(y)), "y: the force vector is identically zero"),
        (lambda x, y: (x, y[:-1]), r"y: expected shape \(300,\)"),
        (lambda x, y: (x, y[:, None]), "y: expected shape"),
        (lambda x, y: (x[:, :, None], y), "X: expected a non-empty 2-D array"),
        (lambda x, y: (x[:0], y[:0]), "X: expected a non-empty"),
        (lambda x, y: (np.where(x > 2, np.nan, x), y), "X, y: contain NaN or inf"),
        (lambda x, y: (x, np.where(y > 2, np.inf, y)), "X, y: contain NaN or inf"),
    ],
)
def test_bad_data_rejected(make, match):
    x, y = _problem()
    with pytest.raises(ValueError, match=match):
        px.ExplicitOptimizer().fit(*make(x, y))


def test_zero_columns_get_zero_coefficients():
    x, y = _problem()
    x = np.column_stack([x, np.zeros(len(x))])
    for method in ("threshold", "lasso", "proximal"):
        opt = px.ExplicitOptimizer(method=method).fit(x, y)
        assert opt.coef_[-1] == 0.0
        np.testing.assert_allclose(opt.coef_[:-1], TRUE, rtol=1e-9, atol=1e-12)


def test_fit_catalog_fixes_force_coefficient():
    x, y = _problem()
    n_rows = len(y) // 2  # two coordinates of 150 samples each
    # force column in the middle of the catalog; theta @ xi = 0 with xi_force = -1
    theta = np.column_stack([x[:, :3], y, x[:, 3:]])
    opt = px.ExplicitOptimizer().fit_catalog(theta, 2, [3])
    assert opt.coef_.shape == (theta.shape[1],)
    assert opt.coef_[3] == -1.0
    np.testing.assert_allclose(np.delete(opt.coef_, 3), TRUE, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(opt.support_, opt.coef_ != 0)
    assert np.max(np.abs(theta @ opt.coef_)) < 1e-9
    assert n_rows * 2 == theta.shape[0]


def test_fit_catalog_with_several_force_columns():
    x, y = _problem()
    theta = np.column_stack([0.25 * y, x, 0.75 * y])
    opt = px.ExplicitOptimizer().fit_catalog(theta, 1, [0, 9])
    assert opt.coef_[0] == -1.0 and opt.coef_[9] == -1.0
    np.testing.assert_allclose(opt.coef_[1:9], TRUE, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(
    "args, match",
    [
        (lambda t: (t, 1, []), "force_columns: explicit regression needs a force column"),
        (lambda t: (t, 1, None), "force_columns"),
        (lambda t: (t, 1, [9]), r"force_columns: indices must lie in \[0, 9\)"),
        (lambda t: (t, 1, [-1]), "force_columns"),
        (lambda t: (t, 0, [0]), "n_coordinates"),
        (lambda t: (t, 1.5, [0]), "n_coordinates"),
        (lambda t: (t, 7, [0]), "theta: 300 rows is not a multiple of n_coordinates=7"),
        (lambda t: (t[:, :0], 1, [0]), "theta: expected a non-empty 2-D array"),
        (lambda t: (t[:, 0], 1, [0]), "theta: expected a non-empty 2-D array"),
        (lambda t: (np.where(t > 3, np.nan, t), 1, [0]), "theta: contains NaN"),
    ],
)
def test_fit_catalog_bad_arguments(args, match):
    x, y = _problem()
    theta = np.column_stack([y, x])
    with pytest.raises(ValueError, match=match):
        px.ExplicitOptimizer().fit_catalog(*args(theta))


def test_fit_catalog_rejects_zero_force():
    x, _ = _problem()
    theta = np.column_stack([np.zeros(len(x)), x])
    with pytest.raises(ValueError, match="force vector is identically zero"):
        px.ExplicitOptimizer().fit_catalog(theta, 2, [0])


class _StubbornRegressor(BaseEstimator):
    """Least squares that always complains it did not converge."""

    def fit(self, x, y):
        warnings.warn("stubborn: gave up", ConvergenceWarning, stacklevel=2)
        self.coef_ = np.linalg.lstsq(x, y, rcond=None)[0]
        return self


class _WrongSizeRegressor(BaseEstimator):
    def fit(self, x, y):
        self.coef_ = np.zeros(x.shape[1] + 1)
        return self


def test_non_converging_inner_regressor_warns():
    x, y = _problem()
    with pytest.warns(ConvergenceWarning, match="inner regressor did not converge: stubborn"):
        opt = px.ExplicitOptimizer(method=_StubbornRegressor()).fit(x, y)
    np.testing.assert_allclose(opt.coef_, TRUE, rtol=1e-9, atol=1e-12)


def test_non_converging_lasso_warns():
    rng = np.random.default_rng(0)
    z = rng.normal(size=(300, 20))
    x = z @ (np.eye(20) + 0.95 * np.ones((20, 20)))  # strongly correlated columns
    y = x @ rng.normal(size=20)
    with pytest.warns(ConvergenceWarning, match="inner regressor did not converge"):
        px.ExplicitOptimizer(method="lasso", alpha=1e-6, max_iter=1).fit(x, y)


def test_non_converging_proximal_gradient_warns():
    x, y = _problem()
    with pytest.warns(ConvergenceWarning, match="proximal gradient did not converge"):
        px.ExplicitOptimizer(method="proximal", max_iter=1).fit(x, y)


def test_converging_methods_do_not_warn():
    x, y = _problem()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for method in ("threshold", "lasso", "proximal"):
            px.ExplicitOptimizer(method=method).fit(x, y)


def test_estimator_with_wrong_coef_size_rejected():
    x, y = _problem()
    with pytest.raises(ValueError, match="method: the estimator's coef_ has 9 entries"):
        px.ExplicitOptimizer(method=_WrongSizeRegressor()).fit(x, y)


def test_clone_keeps_parameters_and_wrapped_estimator():
    opt = px.ExplicitOptimizer(method=ps.STLSQ(threshold=0.3), threshold=0.05, alpha=1e-3,
                               refit=False, max_iter=7)
    copy = clone(opt)
    params = copy.get_params(deep=True)
    assert params["threshold"] == 0.05 and params["alpha"] == 1e-3
    assert params["refit"] is False and params["max_iter"] == 7
    assert params["method__threshold"] == 0.3
    assert copy.method is not opt.method
    x, y = _problem()
    np.testing.assert_array_equal(copy.fit(x, y).coef_, opt.fit(x, y).coef_)
    assert not hasattr(clone(opt), "coef_")


def _two_coordinate_catalog(seed=0, n_rows=200):
    """Columns [force (coordinate 0 only), a (coordinate 0), b (coordinate 1)]: the force is
    2 a, and coordinate 1 (unforced) has b alone, so b's least-squares coefficient is 0."""
    a, b = np.random.default_rng(seed).normal(size=(2, n_rows))
    zero = np.zeros(n_rows)
    return np.column_stack([np.r_[2 * a, zero], np.r_[a, zero], np.r_[zero, b]])


def test_a_coordinate_no_identified_term_enters_is_named():
    theta = _two_coordinate_catalog()
    with pytest.warns(px.UnexplainedCoordinateWarning, match=r"besides the forces enters the "
                      r"equation of coordinate\(s\) \[1\]; the model cannot predict them"):
        opt = px.ExplicitOptimizer().fit_catalog(theta, 2, [0])
    np.testing.assert_allclose(opt.coef_, [-1.0, 2.0, 0.0], atol=1e-12)
    # b kept by hand gets a coefficient of round-off size: still no explanation of coordinate 1
    with pytest.warns(px.IdentificationWarning, match=r"coordinate\(s\) \[1\]"):
        kept = px.ExplicitOptimizer().fit_problem(
            CatalogProblem.from_arrays(theta, 2, [0]), np.array([True, True, True]))
    assert abs(kept.coef_[2]) < 1e-12
    with pytest.warns(px.IdentificationWarning, match=r"coordinate\(s\) \[0, 1\]"):
        px.ExplicitOptimizer().fit_problem(
            CatalogProblem.from_arrays(theta, 2, [0]), np.array([True, False, False]))


def test_explained_coordinates_do_not_warn():
    theta = _two_coordinate_catalog()
    theta[200:, 0] = 0.5 * theta[200:, 2]  # coordinate 1 forced too, by b / 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        opt = px.ExplicitOptimizer().fit_catalog(theta, 2, [0])
    np.testing.assert_allclose(opt.coef_, [-1.0, 2.0, 0.5], rtol=1e-9)


def _disagreeing_blocks(seed=0, n_rows=200):
    """Two forced coordinates whose noisy rows disagree on the shared coefficient of column
    1 (2.0 in block 0, 3.0 in block 1), block 1 a thousand times smaller: which answer comes
    out depends only on how the blocks are weighed against each other."""
    rng = np.random.default_rng(seed)
    a, b, u0, u1 = rng.normal(size=(4, n_rows))
    block0 = np.column_stack([2 * a + 0.1 * u0, a, np.zeros(n_rows)])
    block1 = 1e-3 * np.column_stack([3 * a + b + 0.1 * u1, a, b])
    return np.vstack([block0, block1])


def test_balance_false_fits_the_blocks_as_weighed_by_the_caller():
    """``balance=False`` (rows already weighed, e.g. whitened by the residual's covariance):
    the least squares of the stacked rows as given; the default first rebalances the blocks
    by ``coordinate_weights``. Reference: ``numpy.linalg.lstsq`` of either system."""
    theta = _disagreeing_blocks()
    support = np.array([True, True, True])
    as_given = np.linalg.lstsq(theta[:, 1:], theta[:, 0], rcond=None)[0]
    weights = px.optimizers.coordinate_weights(theta, 2, [0])
    balanced = px.optimizers.balance_coordinates(theta, 2, [0])
    rebalanced = np.linalg.lstsq(balanced[:, 1:], balanced[:, 0], rcond=None)[0]
    assert weights[1] / weights[0] > 100  # the small block is weighed up
    assert abs(as_given[0] - rebalanced[0]) > 0.3  # so the two answers differ
    unbalanced = px.ExplicitOptimizer().fit_problem(
        CatalogProblem.from_arrays(theta, 2, [0], balance=False), support)
    np.testing.assert_allclose(unbalanced.coef_[1:], as_given, rtol=1e-10)
    default = px.ExplicitOptimizer().fit_problem(
        CatalogProblem.from_arrays(theta, 2, [0]), support)
    np.testing.assert_allclose(default.coef_[1:], rebalanced, rtol=1e-10)
    # the selection weighs the rows the same way: column 2, which only the small block
    # needs, is not worth a term as given, and is one when the blocks are rebalanced
    assert px.ExplicitOptimizer().fit_catalog(theta, 2, [0], balance=False).coef_[2] == 0
    assert np.all(px.ExplicitOptimizer().fit_catalog(theta, 2, [0]).coef_ != 0)


@pytest.mark.parametrize("optimizer", [px.ExplicitOptimizer(), px.ImplicitOptimizer(),
                                       px.MixedOptimizer(), px.EnsembleOptimizer(n_models=2)],
                         ids=lambda o: type(o).__name__)
def test_balance_must_be_a_bool(optimizer):
    with pytest.raises(TypeError, match="balance: expected True or False, got the str 'no'"):
        optimizer.fit_catalog(_disagreeing_blocks(), 2, [0], balance="no")
