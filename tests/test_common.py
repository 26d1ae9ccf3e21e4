"""scikit-learn's estimator checks over every estimator of the package, the checks that cannot
apply listed per estimator with the reason, and the same contract checked on data each
estimator accepts.

``parametrize_with_checks`` runs every check of scikit-learn's API contract on each estimator of
:data:`ESTIMATORS`: the feature libraries, the optimizers and ``XLSINDy``. A check that cannot
apply to an estimator is listed in :data:`EXPECTED_FAILED_CHECKS` with its reason, and is run as
a strict expected failure: it must fail (a listed check that starts to pass fails the test, so
that the list is trimmed) and every check not listed must pass. The reasons fall into a few
kinds:

* **Fixed input width.** A feature library transforms the stacked variables of its coordinates
  (:func:`~pysindy_xl.feature_library.stack_variables`, width ``4n + 1``) and ``XLSINDy`` fits one
  column per coordinate of its catalog. scikit-learn's checks generate ``X`` of widths of their
  own choosing, which the estimator refuses with a ``ValueError`` naming ``x``. The same contract
  on data of the right width is checked by :func:`test_contract_on_accepted_data`.
* **Catalog-only optimizers.** ``EnsembleOptimizer``, ``PhysicalOptimizer`` and
  ``TotalLeastSquaresOptimizer`` solve catalog problems (``fit_catalog`` / ``fit_problem``): they
  have no ``fit(X, y)`` for the checks to call. Their contract on a catalog problem is checked by
  :func:`test_contract_on_accepted_data`.
* **No law in random data.** ``ImplicitOptimizer.fit(X)`` finds sparse laws ``X @ xi = 0``;
  the checks' random ``X`` hold none, and the fit answers with ``NoLawFoundError``.
* **Wording of the package's validation.** Bad input is answered by the package's own
  validation layer (:mod:`pysindy_xl._validation`), with a ``TypeError`` or ``ValueError`` that
  names the argument, where some checks want scikit-learn's own wording or error class. The
  package's answer to the same input is asserted by :func:`test_the_answer_names_the_argument`.

The feature libraries, the optimizers and ``XLSINDy`` declare what each parameter accepts in a
table, ``_parameter_constraints`` (as scikit-learn's estimators do), checked at ``fit`` by
:func:`pysindy_xl._validation.validate_params`: the table covers every parameter of
``__init__``, a value outside it is refused at ``fit`` (not before) with an error naming the
parameter, values inside it fit, and the documented types name what the table accepts. The
weak-form helpers (``BumpTestFunctions``, ``WhittakerSmoother``) have no ``fit``: their table
is checked where they are used (``matrices``, ``smooth``).
"""

import copy
import inspect
import pickle
import re
import warnings

import joblib
import numpy as np
import pytest
import sympy as sp
from numpydoc.docscrape import ClassDoc
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from sklearn.utils.estimator_checks import check_estimator, parametrize_with_checks
from sklearn.utils.validation import check_is_fitted
from support.files import pendulum

import pysindy_xl as px
from pysindy_xl._validation import Boolean, HasMethods, Interval, Options
from pysindy_xl.feature_library import (
    JointFrictionLibrary,
    PolynomialLagrangeLibrary,
    stack_variables,
)
from pysindy_xl.optimizers import CatalogOptimizer

# ------------------------------------------------------------------------------ the estimators

_TWO = px.Coordinates(["x", "th"])
_ONE = px.Coordinates(["theta"])


def _libraries():
    c = _TWO
    return [
        px.AutomaticCatalog(["x", "th"], kinds={"th": "angle"}),
        px.LagrangeLibrary(c, px.products([1, sp.cos(c.q[1])], px.monomials(c.qd, 2))),
        px.ClassicalLibrary(c, c.qd),
        px.ExternalForces(c),
        px.CatalogRepartition([px.LagrangeLibrary(c, px.monomials(c.qd, 2)),
                               px.ExternalForces(c)]),
        JointFrictionLibrary(c, ["x", "th"]),
        PolynomialLagrangeLibrary(c, px.monomials(c.qd, 2)),
    ]


def _pendulum_catalog():
    """Catalog of the pendulum ``0.5 qdd + 0.2 qd + 4.9 sin q = tau`` of support.files."""
    c = _ONE
    return px.CatalogRepartition([px.LagrangeLibrary(c, [c.qd[0] ** 2, sp.cos(c.q[0])]),
                                  px.ClassicalLibrary(c, c.qd), px.ExternalForces(c)])


def _optimizers():
    return [px.ExplicitOptimizer(), px.ImplicitOptimizer(), px.MixedOptimizer(),
            px.EnsembleOptimizer(n_models=5), px.PhysicalOptimizer(),
            px.TotalLeastSquaresOptimizer()]


#: every estimator of the package, as the checks see it
ESTIMATORS = [*_libraries(), *_optimizers(), px.XLSINDy(_pendulum_catalog())]

# -------------------------------------------------------------- the checks that cannot apply

_WORDING = {
    "check_complex_data": "complex input is a TypeError naming the argument ('...: expected real "
                          "numbers, got complex values'), not sklearn's ValueError 'Complex data "
                          "not supported'",
    "check_dtype_object": "an object array of non-numbers is a TypeError '...: expected real "
                          "numbers, got an element of type ...', not sklearn's wording",
    "check_estimators_empty_data_messages": "an empty array is a ValueError '...: expected a "
                                            "non-empty ... array', not sklearn's '0 feature(s) "
                                            "(shape=(n, 0)) while a minimum of 1 is required'",
}

# the checks that fit or transform the data sklearn generates
_DATA_CHECKS = (
    "check_dict_unchanged", "check_dont_overwrite_parameters", "check_dtype_object",
    "check_estimators_dtypes", "check_estimators_empty_data_messages",
    "check_estimators_fit_returns_self", "check_estimators_nan_inf",
    "check_estimators_overwrite_params", "check_estimators_pickle",
    "check_f_contiguous_array_estimator", "check_fit2d_1feature", "check_fit2d_1sample",
    "check_fit2d_predict1d", "check_fit_check_is_fitted", "check_fit_idempotent",
    "check_fit_score_takes_y", "check_methods_sample_order_invariance",
    "check_methods_subset_invariance", "check_n_features_in", "check_n_features_in_after_fitting",
    "check_pipeline_consistency", "check_positive_only_tag_during_fit",
    "check_readonly_memmap_input",
)
_TRANSFORMER_CHECKS = ("check_transformer_data_not_an_array", "check_transformer_general",
                       "check_transformer_preserve_dtypes")

_LIBRARY_WIDTH = ("the input is the stacked variables of its coordinates (stack_variables, "
                  "width 4n + 1); sklearn's X of other widths is a ValueError naming x")
_LIBRARY = {**dict.fromkeys(_DATA_CHECKS + _TRANSFORMER_CHECKS, _LIBRARY_WIDTH),
            "check_complex_data": _WORDING["check_complex_data"]}

_MODEL_WIDTH = ("x has one column per coordinate of the catalog; sklearn's X of other widths "
                "is a ValueError naming x")
_MODEL = {**dict.fromkeys(_DATA_CHECKS, _MODEL_WIDTH),
          "check_complex_data": _WORDING["check_complex_data"],
          "check_estimators_unfitted": "predict(x, x_dot) needs the velocities: sklearn's "
                                       "predict(X) is a TypeError (the unfitted model's "
                                       "predict(x, x_dot) raises NotFittedError)"}

_CATALOG_ONLY = ("solves catalog problems (fit_catalog / fit_problem) and has no fit(X, y) for "
                 "the check to call")
_CATALOG = {**dict.fromkeys(set(_DATA_CHECKS) - {"check_fit_score_takes_y"}, _CATALOG_ONLY),
            **dict.fromkeys(("check_complex_data", "check_fit1d", "check_estimator_sparse_array",
                             "check_estimator_sparse_matrix", "check_estimator_sparse_tag"),
                            _CATALOG_ONLY)}

_NO_LAW = ("random data hold no sparse law X @ xi = 0: fit raises NoLawFoundError, its answer "
           "to data without a law")
_IMPLICIT = {**dict.fromkeys(set(_DATA_CHECKS) - {"check_fit_check_is_fitted",
                                                  "check_fit_idempotent", "check_n_features_in",
                                                  "check_positive_only_tag_during_fit"}, _NO_LAW),
             "check_complex_data": _WORDING["check_complex_data"],
             "check_estimators_empty_data_messages":
                 _WORDING["check_estimators_empty_data_messages"],
             "check_fit2d_1feature": "one column holds no law between columns: NoLawFoundError "
                                     "'theta: 1 non-zero column(s); implicit regression needs "
                                     "at least 2', not sklearn's wording"}

#: per estimator class, the sklearn checks that cannot apply and why
EXPECTED_FAILED_CHECKS = {
    **dict.fromkeys(("LagrangeLibrary", "ClassicalLibrary", "ExternalForces",
                     "CatalogRepartition", "JointFrictionLibrary", "PolynomialLagrangeLibrary",
                     "AutomaticCatalog"),
                    _LIBRARY),
    "ExplicitOptimizer": _WORDING,
    "ImplicitOptimizer": _IMPLICIT,
    "MixedOptimizer": _WORDING,
    **dict.fromkeys(("EnsembleOptimizer", "PhysicalOptimizer", "TotalLeastSquaresOptimizer"),
                    _CATALOG),
    "XLSINDy": _MODEL,
}

# kept under its historical name: ExplicitOptimizer's exceptions
DOCUMENTED_EXCEPTIONS = EXPECTED_FAILED_CHECKS["ExplicitOptimizer"]


def _expected_failed_checks(estimator):
    return EXPECTED_FAILED_CHECKS[type(estimator).__name__]


def test_every_estimator_is_checked():
    assert {type(e).__name__ for e in ESTIMATORS} == set(EXPECTED_FAILED_CHECKS)


@parametrize_with_checks(ESTIMATORS)
def test_sklearn_checks(estimator, check):
    """Each check passes, or is listed in EXPECTED_FAILED_CHECKS and fails (a strict expected
    failure, answered with its reason; the check's own traceback is not formatted)."""
    name = getattr(check, "func", check).__name__
    reason = _expected_failed_checks(estimator).get(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if reason is None:
            check(estimator)
            return
        try:
            check(estimator)
        except Exception:  # noqa: BLE001 - any failure of a check listed as not applying
            failed = True
        else:
            failed = False
    if failed:  # outside the except clause: no chained traceback to format
        pytest.xfail(reason)
    pytest.fail(f"{name} passes for {type(estimator).__name__}: drop it from "
                f"EXPECTED_FAILED_CHECKS (listed as: {reason})")


# ------------------------------------------------- ExplicitOptimizer: check_estimator in one

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


# ----------------------------------------------------- the excepted inputs: the package's answer

def _fit_bad(estimator, X):
    """Fit ``estimator`` on the bad input ``X`` through the entry point the checks use."""
    if isinstance(estimator, px.XLSINDy):  # one column per coordinate of its catalog
        return estimator.fit(X[:, :1] if X.shape[1] == 9 else X, np.arange(len(X)) * 0.01)
    return estimator.fit(X)


@pytest.mark.parametrize("estimator", [*_libraries(), px.ImplicitOptimizer(),
                                       px.MixedOptimizer(), px.XLSINDy(_pendulum_catalog())],
                         ids=lambda e: type(e).__name__)
def test_the_answer_names_the_argument(estimator):
    """The wording exceptions: complex input is a TypeError naming the argument."""
    with pytest.raises(TypeError, match=r"^(x|X|theta): expected real numbers, got complex"):
        _fit_bad(estimator, np.ones((40, 9)) + 1j)


@pytest.mark.parametrize("estimator", [*_libraries(), px.XLSINDy(_pendulum_catalog())],
                         ids=lambda e: type(e).__name__)
def test_a_wrong_width_names_x_and_the_width(estimator):
    """The fixed-width exceptions: another width is a ValueError naming x and the width."""
    with pytest.raises(ValueError, match=r"^x: expected (1 columns \(one per coordinate\)|the "
                                         r"stacked variables array of shape \(n_samples, 9\))"):
        _fit_bad(estimator, np.ones((40, 3)))


def test_implicit_refuses_data_without_a_law():
    rng = np.random.default_rng(0)
    with pytest.raises(px.NoLawFoundError):
        px.ImplicitOptimizer().fit(rng.normal(size=(30, 4)))


def test_catalog_only_optimizers_have_no_fit():
    for estimator in (px.EnsembleOptimizer(), px.PhysicalOptimizer(),
                      px.TotalLeastSquaresOptimizer()):
        assert not hasattr(estimator, "fit") and callable(estimator.fit_catalog)


# ------------------------------------------------------------ the contract on accepted data

def _library_case(library):
    rng = np.random.default_rng(1)
    q, qd, qdd, tau = rng.normal(size=(4, 50, 2))
    Z = stack_variables(q, qd, qdd, tau, np.arange(50) * 0.01)
    return library, (Z,), {}, lambda e: e.transform(Z)


def _optimizer_case(optimizer):
    """A catalog problem holding the law ``a + 2 c - f = 0`` (force column f, last)."""
    rng = np.random.default_rng(0)
    a = rng.normal(size=(200, 3))
    theta = np.column_stack([a, a @ [1.0, 0.0, 2.0]])
    return optimizer, (theta, 1, [3]), {}, lambda e: e.coef_


def _model_case():
    t, q, qd, qdd, tau = pendulum(401)
    fit_kwargs = {"x_dot": qd, "x_ddot": qdd, "u": tau}
    return (px.XLSINDy(_pendulum_catalog()), (q, t), fit_kwargs,
            lambda e: e.predict(q[:, None], qd[:, None], u=tau[:, None]))


_CASES = {**{type(lib).__name__: (_library_case, lib) for lib in _libraries()},
          **{type(opt).__name__: (_optimizer_case, opt) for opt in _optimizers()},
          "XLSINDy": (lambda _: _model_case(), None)}


def _fit(estimator, args, kwargs):
    if isinstance(estimator, CatalogOptimizer):
        return estimator.fit_catalog(*args, **kwargs)
    return estimator.fit(*args, **kwargs)


def _learned(estimator):
    """The learned attributes (sklearn's test of being fitted, for any estimator)."""
    return [k for k in vars(estimator) if k.endswith("_") and not k.startswith("__")]


#: estimators that break the contract on accepted data, and how (strict expected failures)
CONTRACT_GAPS = {
    "CatalogRepartition": "fit fits the libraries it is given in place, so that they transform "
                          "on their own afterwards (as pysindy's GeneralizedLibrary does; "
                          "test_sub_libraries_transform_after_catalog_fit pins it): its "
                          "parameter `libraries` changes. XLSINDy fits a clone of its catalog",
}


@pytest.mark.parametrize("name", [
    pytest.param(n, marks=pytest.mark.xfail(strict=True, reason=CONTRACT_GAPS[n]))
    if n in CONTRACT_GAPS else n for n in sorted(_CASES)])
def test_contract_on_accepted_data(name):
    """What the sklearn checks would assert, on data of the right width with a law in it:
    unfitted until fit, fit returns self and leaves its parameters and input unchanged, learned
    attributes end in ``_``, refitting and pickling give the same output, a clone is unfitted."""
    make, prototype = _CASES[name]
    estimator, args, kwargs, output = make(clone(prototype) if prototype is not None else None)
    params = joblib.hash(estimator.get_params())
    before = set(vars(estimator))
    inputs = [np.array(a, copy=True) for a in args if isinstance(a, np.ndarray)]
    assert not _learned(estimator)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert _fit(estimator, args, kwargs) is estimator
        assert joblib.hash(estimator.get_params()) == params, "fit changed a parameter"
        learned = {k for k in set(vars(estimator)) - before if not k.startswith("_")}
        assert learned and all(k.endswith("_") for k in learned), learned
        for old, new in zip(inputs, [a for a in args if isinstance(a, np.ndarray)], strict=True):
            np.testing.assert_array_equal(new, old)
        first = np.array(output(estimator), copy=True)
        assert np.all(np.isfinite(first))
        if isinstance(estimator, CatalogOptimizer):
            assert estimator.n_features_in_ == args[0].shape[1]

        loaded = pickle.loads(pickle.dumps(estimator))
        np.testing.assert_array_equal(output(loaded), first)
        assert _fit(estimator, args, kwargs) is estimator
        np.testing.assert_array_equal(output(estimator), first)

    unfitted = clone(estimator)
    assert repr(unfitted) == repr(estimator) and not _learned(unfitted)
    if callable(getattr(estimator, "fit", None)):  # sklearn's own test of being fitted
        check_is_fitted(estimator)
        with pytest.raises(NotFittedError):
            check_is_fitted(unfitted)


@pytest.mark.parametrize("name", sorted(n for n in _CASES if n.endswith("Optimizer")))
def test_optimizers_recover_the_planted_law(name):
    """The contract's catalog problem is solved, not only accepted: ``a + 2 c = f``."""
    make, prototype = _CASES[name]
    estimator, args, kwargs, _ = make(clone(prototype))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        coef = _fit(estimator, args, kwargs).coef_
    np.testing.assert_allclose(coef / -coef[3], [1.0, 0.0, 2.0, -1.0], atol=1e-8)


def test_the_model_of_the_contract_is_the_true_pendulum():
    estimator, args, kwargs, _ = _model_case()
    coef = estimator.fit(*args, **kwargs).coefficients()
    np.testing.assert_allclose(coef, [0.25, 4.9, 0.2, -1.0], rtol=1e-6)


# -------------------------------------------------------- the declared parameter constraints

_CONSTRAINED = [*_libraries(), *_optimizers(), px.XLSINDy(_pendulum_catalog())]
_T = np.linspace(0.0, 10.0, 1001)
#: the weak-form helpers: no fit, the table checked at use (their call on valid data)
_AT_USE = {"BumpTestFunctions": (px.BumpTestFunctions(),
                                 lambda e: e.matrices(_T, np.sin(_T)[:, None])[0].toarray()),
           "WhittakerSmoother": (px.WhittakerSmoother(),
                                 lambda e: e.smooth(np.linspace(0.0, 1.0, 101),
                                                    np.sin(np.linspace(0, 1, 101))[:, None])[0])}
_TABLES = [*_CONSTRAINED, *(e for e, _ in _AT_USE.values())]


class _NotAnInstance:
    """A class where an instance or a value is due: refused by every constraint."""


def _invalid_values(constraints):
    """Values that no constraint of the list accepts: a class, and a complex number where no
    constraint takes any instance."""
    takes_any_instance = any(isinstance(c, HasMethods) and c.method is None for c in constraints)
    return [_NotAnInstance] + ([] if takes_any_instance else [1j])


@pytest.mark.parametrize("estimator", _TABLES, ids=lambda e: type(e).__name__)
def test_every_parameter_is_constrained(estimator):
    """The table declares every parameter of ``__init__``, as scikit-learn's estimators do."""
    params = set(inspect.signature(type(estimator).__init__).parameters) - {"self"}
    assert set(type(estimator)._parameter_constraints) == params


@pytest.mark.parametrize("name, param", [
    (type(e).__name__, p) for e in _CONSTRAINED for p in sorted(type(e)._parameter_constraints)])
def test_a_refused_parameter_is_named_at_fit(name, param):
    """``__init__`` and ``set_params`` store any value; ``fit`` refuses one outside the table
    with a TypeError or ValueError naming the parameter."""
    make, prototype = _CASES[name]
    constraints = type(make(prototype)[0])._parameter_constraints[param]
    for value in _invalid_values(constraints):
        estimator, args, kwargs, _ = make(clone(prototype) if prototype is not None else None)
        estimator.set_params(**{param: value})
        assert estimator.get_params()[param] is value
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with pytest.raises((TypeError, ValueError), match=rf"^{re.escape(param)}: expected"):
                _fit(estimator, args, kwargs)


@pytest.mark.parametrize("name, param", [
    (name, p) for name, (e, _) in _AT_USE.items() for p in sorted(type(e)._parameter_constraints)])
def test_a_refused_parameter_is_named_at_use(name, param):
    """The weak-form helpers store any value and refuse one outside the table where they are
    used, naming the parameter."""
    prototype, use = _AT_USE[name]
    assert np.all(np.isfinite(use(copy.copy(prototype))))  # the defaults are used
    for value in _invalid_values(type(prototype)._parameter_constraints[param]):
        helper = type(prototype)(**{param: value})
        assert getattr(helper, param) is value
        with pytest.raises((TypeError, ValueError), match=rf"^{re.escape(param)}: expected"):
            use(helper)


@pytest.mark.parametrize("name, param, value, error, match", [
    ("LagrangeLibrary", "terms", "x_dot**2", TypeError,
     r"^terms: expected a sympy expression or a sequence of sympy expressions, got the str"),
    ("ClassicalLibrary", "mask", "diagonal", TypeError, r"^mask: expected an array of bool"),
    ("ExternalForces", "interlink", 2.0, TypeError, r"^interlink: expected an array of shape"),
    ("JointFrictionLibrary", "joints", "x", TypeError,
     r"^joints: expected a sequence of joint names, got the str 'x'"),
    ("JointFrictionLibrary", "models", "dry", ValueError, r"^models: expected one of \('viscous'"),
    ("JointFrictionLibrary", "coulomb_scale", 0.0, ValueError,
     r"^coulomb_scale: expected a real number > 0, got 0.0"),
    ("CatalogRepartition", "libraries", px.ExternalForces(_TWO), TypeError,
     r"^libraries: expected a list of pysindy_xl feature libraries"),
    ("AutomaticCatalog", "degree", 1.5, ValueError, r"^degree: expected an integer >= 0"),
    ("AutomaticCatalog", "kinetic", "quadratic", ValueError, r"^kinetic: expected one of"),
    ("PolynomialLagrangeLibrary", "tree", "arm.xml", TypeError,
     r"^tree: expected a KinematicTree or None, got 'arm.xml'"),
])
def test_a_wrong_library_option_names_the_parameter(name, param, value, error, match):
    """Wrong-typed options of the feature libraries: the error of fit names the parameter and
    what it accepts."""
    make, prototype = _CASES[name]
    library, args, kwargs, _ = make(clone(prototype).set_params(**{param: value}))
    with pytest.raises(error, match=match):
        library.fit(*args, **kwargs)


@pytest.mark.parametrize("name, param, value", [
    ("LagrangeLibrary", "terms", _TWO.qd[0] ** 2), ("ClassicalLibrary", "mask", np.ones((2, 2))),
    ("JointFrictionLibrary", "models", "viscous"), ("JointFrictionLibrary", "joints", ("a", "b")),
    ("AutomaticCatalog", "coordinates", "x, th"), ("AutomaticCatalog", "dissipation", None),
    ("AutomaticCatalog", "coulomb_scale", {"x": 0.1, "th": 0.2}),
    ("ExplicitOptimizer", "threshold", 0.05), ("ExplicitOptimizer", "method", "lasso"),
    ("ImplicitOptimizer", "alpha", 1e-3), ("EnsembleOptimizer", "random_state", 7),
    ("EnsembleOptimizer", "random_state", np.random.default_rng(7)),
    ("PhysicalOptimizer", "base_parameters", "all"), ("XLSINDy", "hold_still", False),
    ("XLSINDy", "residual_covariance", False), ("XLSINDy", "optimizer", "explicit"),
])
def test_an_accepted_parameter_fits(name, param, value):
    """Values inside the table fit: the constraints refuse nothing they list."""
    make, prototype = _CASES[name]
    estimator, args, kwargs, output = make(clone(prototype) if prototype is not None else None)
    estimator.set_params(**{param: value})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert np.all(np.isfinite(output(_fit(estimator, args, kwargs))))


def _documented_words(constraint) -> list[str]:
    """What the numpydoc type (or description) of a parameter shows for one constraint."""
    if isinstance(constraint, Options):
        return list(constraint.choices)
    if isinstance(constraint, Boolean):
        return ["bool"]
    if isinstance(constraint, Interval):
        return ["int" if constraint.kind == "int" else "float"]
    if isinstance(constraint, (str, bool)):
        return [str(constraint)]
    return []  # None (see below), instances: described in words of their own


@pytest.mark.parametrize("estimator", _TABLES, ids=lambda e: type(e).__name__)
def test_the_documented_types_follow_the_table(estimator):
    """Each constrained parameter is documented, and its documented type names what the table
    accepts: the options, 'bool', 'int', 'float', the literals, None ('optional')."""
    cls = type(estimator)
    documented = {name.strip(): p for p in ClassDoc(cls)["Parameters"]
                  for name in p.name.split(",")}
    defaults = inspect.signature(cls.__init__).parameters
    for name, constraints in cls._parameter_constraints.items():
        assert name in documented, f"{cls.__name__}: {name} is not documented"
        text = documented[name].type + " " + " ".join(documented[name].desc)
        missing = [w for c in constraints for w in _documented_words(c) if w not in text]
        assert not missing, f"{cls.__name__}.{name}: {documented[name].type!r} lacks {missing}"
        if any(c is None for c in constraints):
            assert ("optional" in text or "None" in text
                    or defaults[name].default is None), f"{cls.__name__}.{name}: None"
