"""scikit-learn's ``check_estimator`` on ExplicitOptimizer, with the documented exceptions.

ExplicitOptimizer passes every check except three whose only complaint is the wording or the
class of an error: the package answers bad input through its own validation layer
(:mod:`pysindy_xl._validation`), with a ``TypeError`` or ``ValueError`` that names the
argument. Each exception is listed with the reason, and the package's own answer to the same
input is asserted below.
"""

import warnings

import numpy as np
import pytest
from sklearn.utils.estimator_checks import check_estimator

import pysindy_xl as px

DOCUMENTED_EXCEPTIONS = {
    # sklearn wants ValueError("Complex data not supported"); complex data is the wrong kind
    # of value for the package: TypeError "X: expected real numbers, got complex values"
    "check_complex_data": "TypeError naming X instead of sklearn's ValueError",
    # sklearn wants its own wording for object arrays holding non-numbers
    "check_dtype_object": "TypeError 'X: expected real numbers, got an element of type ...'",
    # sklearn wants its wording "0 feature(s) (shape=(n, 0)) while a minimum of 1 is required"
    "check_estimators_empty_data_messages": "ValueError 'X: expected a non-empty 2-D array'",
}


def test_check_estimator_with_documented_exceptions():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        results = check_estimator(px.ExplicitOptimizer(), on_fail=None)
    failed = {r["check_name"] for r in results if r["status"] == "failed"}
    passed = {r["check_name"] for r in results if r["status"] == "passed"}
    assert failed == set(DOCUMENTED_EXCEPTIONS), failed ^ set(DOCUMENTED_EXCEPTIONS)
    # the contract checks that do apply pass, n_features_in_ and sparse refusal included
    assert {"check_n_features_in", "check_n_features_in_after_fitting", "check_fit2d_1sample",
            "check_estimator_sparse_array", "check_estimators_nan_inf",
            "check_fit_check_is_fitted", "check_estimators_overwrite_params",
            "check_dont_overwrite_parameters", "check_estimators_pickle"} <= passed


@pytest.mark.parametrize("X, error, match", [
    (np.ones((12, 3)) + 1j, TypeError, r"^X: expected real numbers, got complex values"),
    (np.array([[{"a": 1}] * 3] * 12, dtype=object), TypeError,
     r"^X: expected real numbers, got an element of type dict"),
    (np.ones((12, 0)), ValueError, r"^X: expected a non-empty 2-D array, got shape \(12, 0\)"),
])
def test_the_package_answer_to_the_excepted_inputs(X, error, match):
    with pytest.raises(error, match=match):
        px.ExplicitOptimizer().fit(X, np.arange(12.0))


def test_n_features_in_after_fit_and_fit_catalog():
    rng = np.random.default_rng(0)
    theta = rng.normal(size=(60, 4))
    assert px.ExplicitOptimizer().fit(theta, theta @ [1.0, 0, 2, 0]).n_features_in_ == 4
    theta[:, 0] = theta[:, 1:] @ [0.5, 0.0, 1.0]
    assert px.ExplicitOptimizer().fit_catalog(theta, 2, [0]).n_features_in_ == 4
