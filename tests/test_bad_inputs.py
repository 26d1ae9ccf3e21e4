"""Every bad input answered: one test per class of issue 13, each asserting the exception type
and that the message names the argument and what was expected."""

import numpy as np
import pytest
import sympy as sp

import pysindy_xl as px
from pysindy_xl._validation import check_indices, check_numeric_array, check_option

COORDS = px.Coordinates(["x"])
X, XD = COORDS.q[0], COORDS.qd[0]
N = 401


def _library(terms=None):
    return px.LagrangeLibrary(COORDS, terms or [XD**2, X**2, X**4])


def _data():
    """Forced oscillator x'' + 3 x = u, exact derivatives (x takes negative values)."""
    t = np.linspace(0, 8, N)
    x = (np.cos(2 * t) + 0.1 * t)[:, None]
    xd = (-2 * np.sin(2 * t) + 0.1)[:, None]
    xdd = (-4 * np.cos(2 * t))[:, None]
    return {"x": x, "t": t, "x_dot": xd, "x_ddot": xdd, "u": xdd + 3 * x}


@pytest.fixture(scope="module")
def data():
    return _data()


@pytest.fixture(scope="module")
def fitted(data):
    model = px.XLSINDy(_library(), px.ExplicitOptimizer()).fit(**data)
    np.testing.assert_allclose(model.coefficients(), [-1.0, 0.5, -1.5, 0.0], atol=1e-9)
    return model


def _fit(data, library=None, optimizer=None, **changes):
    kwargs = dict(data, **changes)
    return px.XLSINDy(library or _library(), optimizer or px.ExplicitOptimizer()).fit(**kwargs)


# -- arrays -----------------------------------------------------------------------------------
ARRAY_CASES = {
    "x_complex": ({"x": _data()["x"] + 1j}, TypeError, r"x: expected real numbers, got complex"),
    "x_bool": ({"x": _data()["x"] > 0}, TypeError, r"x: expected real numbers, got booleans"),
    "x_str": ({"x": _data()["x"].astype(str)}, TypeError, r"x: expected real numbers, got an "
              r"array of str"),
    "x_objects": ({"x": np.array([[object()]] * N)}, TypeError, r"x: expected real numbers"),
    "x_empty": ({"x": np.zeros((0, 1))}, ValueError, r"x: expected a non-empty array"),
    "x_no_columns": ({"x": np.zeros((N, 0))}, ValueError, r"x: expected a non-empty array"),
    "x_constant": ({"x": np.ones((N, 1)), "x_dot": np.zeros((N, 1)),
                    "x_ddot": np.zeros((N, 1))}, ValueError, r"x: coordinate 'x' is constant"),
    "x_dot_complex": ({"x_dot": _data()["x_dot"] * 1j}, TypeError, r"x_dot: expected real"),
    "u_datetime": ({"u": np.arange(N).astype("datetime64[s]")[:, None]}, TypeError,
                   r"u: expected real numbers \(seconds\), got datetime64"),
    "t_str": ({"t": "0.02"}, TypeError, r"t: expected a time step in seconds"),
    "t_bool": ({"t": True}, TypeError, r"t: expected a time step in seconds"),
    "t_datetimes": ({"t": np.arange(N).astype("datetime64[s]")}, TypeError,
                    r"t: expected real numbers \(seconds\)"),
    "t_str_array": ({"t": np.linspace(0, 8, N).astype(str)}, TypeError, r"t: expected real"),
    "t_complex": ({"t": np.linspace(0, 8, N) + 0j}, TypeError, r"t: expected real numbers"),
}


@pytest.mark.parametrize("case", list(ARRAY_CASES))
def test_fit_array_classes(case, data):
    changes, error, match = ARRAY_CASES[case]
    with pytest.raises(error, match=match):
        _fit(data, **changes)


def test_list_of_trajectories_with_a_missing_force(data):
    with pytest.raises(ValueError, match=r"u\[1\]: is None; give an array for every trajectory"):
        px.XLSINDy(_library(), px.ExplicitOptimizer()).fit(
            [data["x"]] * 2, [data["t"]] * 2, [data["x_dot"]] * 2, [data["x_ddot"]] * 2,
            u=[data["u"], None])


def test_predict_array_classes(fitted, data):
    with pytest.raises(TypeError, match=r"x: expected real numbers, got complex"):
        fitted.predict(data["x"] + 1j, data["x_dot"])
    with pytest.raises(ValueError, match=r"x: expected a non-empty array"):
        fitted.predict(np.zeros((0, 1)), np.zeros((0, 1)))
    with pytest.raises(TypeError, match=r"x_dot: expected real numbers, got an array of str"):
        fitted.predict(data["x"], data["x_dot"].astype(str))


def test_predict_overflow_is_an_error():
    # values beyond 1e100 are refused; an equation that overflows below that is an error too
    lib = _library([XD**2, X**2, sp.exp(X)])
    t = np.linspace(0, 8, N)
    x = (np.cos(2 * t) + 0.1 * t)[:, None]
    xd, xdd = (-2 * np.sin(2 * t) + 0.1)[:, None], (-4 * np.cos(2 * t))[:, None]
    u = xdd + 3 * x + np.exp(x)  # L = xd^2/2 - 3/2 x^2 - exp(x)
    model = px.XLSINDy(lib, px.ExplicitOptimizer()).fit(x, t, xd, xdd, u=u)
    np.testing.assert_allclose(model.coefficients(), [-1.0, 0.5, -1.5, -1.0], atol=1e-6)
    np.testing.assert_allclose(model.predict(x, xd, u), xdd, atol=1e-6)
    with pytest.raises(ValueError, match=r"x: values up to 1e\+200 in magnitude are too large"):
        model.predict(np.full((3, 1), 1e200), np.zeros((3, 1)))
    with pytest.raises(ValueError, match=r"x: the identified equations are not finite .* at 2 "
                                         r"of 3 samples, first at sample 1"):
        model.predict(np.array([[0.5], [1e3], [800.0]]), np.zeros((3, 1)))


def test_fractional_force_column_index():
    theta = np.random.default_rng(0).normal(size=(20, 3))
    with pytest.raises(TypeError, match=r"force_columns: expected integer indices, got 0.5"):
        px.ExplicitOptimizer().fit_catalog(theta, 1, [0.5])
    with pytest.raises(TypeError, match=r"force_columns: expected integer indices, got True"):
        px.ExplicitOptimizer().fit_catalog(theta, 1, [True])


def test_empty_or_zero_column_regression():
    with pytest.raises(ValueError, match=r"theta: expected a non-empty 2-D array"):
        px.ExplicitOptimizer().fit_catalog(np.zeros((20, 0)), 1, [])
    with pytest.raises(ValueError, match=r"X: expected a non-empty 2-D array"):
        px.ExplicitOptimizer().fit(np.zeros((20, 0)), np.ones(20))
    with pytest.raises(TypeError, match=r"X: expected real numbers, got an array of str"):
        px.ExplicitOptimizer().fit(np.full((10, 3), "a"), np.ones(10))


def test_library_transform_array_classes():
    lib = _library().fit()
    with pytest.raises(TypeError, match=r"x: expected real numbers, got complex"):
        lib.transform(np.ones((3, 5)) + 1j)
    with pytest.raises(ValueError, match=r"x: expected at least one sample"):
        lib.transform(np.ones((0, 5)))
    with pytest.raises(ValueError, match=r"feature_library: the term L\[x\*\*4\] is NaN or inf"):
        lib.transform(np.full((3, 5), 1e200))


# -- options ----------------------------------------------------------------------------------
OPTION_CASES = {
    "drop_dependent_str": (dict(drop_dependent="no"), None, TypeError,
                           r"drop_dependent: expected True or False, got the str 'no'"),
    "formulation_unknown": (dict(formulation="strongest"), None, ValueError, r"formulation: "),
    "residual_covariance_str": (dict(residual_covariance="yes"), None, TypeError,
                                r"residual_covariance: expected True, False or 'auto', got "
                                r"the str 'yes'"),
    "residual_covariance_int": (dict(residual_covariance=1), None, TypeError,
                                r"residual_covariance: expected True, False or 'auto', got "
                                r"the int 1"),
    "t_default_str": (dict(t_default="0.02"), None, TypeError, r"t_default: expected a real"),
    "t_default_negative": (dict(t_default=-1.0), None, ValueError, r"t_default: expected a real"),
    "smoother_class": (dict(smoother=px.WhittakerSmoother), None, TypeError,
                       r"smoother: expected an instance .* write WhittakerSmoother\(\)"),
    "optimizer_class": (dict(optimizer=px.ExplicitOptimizer), None, TypeError,
                        r"optimizer: expected an instance .*write ExplicitOptimizer\(\)"),
    "library_class": (dict(feature_library=px.LagrangeLibrary), None, TypeError,
                      r"feature_library: expected an instance .*write LagrangeLibrary\(\)"),
    "refit_str": ({}, px.ExplicitOptimizer(refit="False"), TypeError,
                  r"refit: expected True or False, got the str 'False'"),
    "alpha_str": ({}, px.ExplicitOptimizer(method="lasso", alpha="0.1"), TypeError,
                  r"alpha: expected a real number >= 0, got the str '0.1'"),
    "max_iter_str": ({}, px.ExplicitOptimizer(max_iter="10"), TypeError,
                     r"max_iter: expected an integer >= 1, got the str '10'"),
    "max_iter_float": ({}, px.ExplicitOptimizer(max_iter=2.5), ValueError,
                       r"max_iter: expected an integer >= 1, got 2.5"),
    "threshold_nan": ({}, px.ExplicitOptimizer(threshold=np.nan), ValueError, r"threshold: "),
    "method_class": ({}, px.ExplicitOptimizer(method=px.ExplicitOptimizer), TypeError,
                     r"method: expected an instance"),
}


@pytest.mark.parametrize("case", list(OPTION_CASES))
def test_option_classes(case, data):
    params, optimizer, error, match = OPTION_CASES[case]
    kwargs = {"feature_library": _library(),
              "optimizer": optimizer or px.ExplicitOptimizer(), **params}
    with pytest.raises(error, match=match):
        px.XLSINDy(**kwargs).fit(**data)


@pytest.mark.parametrize("params, match", [
    ({"alpha": "auto", "tol": "1e-4"}, r"tol: expected a real number > 0, got the str"),
    ({"threshold": "0.1"}, r"threshold: expected a real number in \[0, 1\), got the str"),
    ({"max_residual_ratio": np.nan}, r"max_residual_ratio: expected a real number >= 1"),
    ({"early_stopping": "yes"}, r"early_stopping: expected True or False"),
    ({"min_group_size": 0}, r"min_group_size: expected an integer >= 1"),
])
def test_implicit_option_classes(params, match):
    theta = np.random.default_rng(0).normal(size=(40, 3))
    with pytest.raises((TypeError, ValueError), match=match):
        px.ImplicitOptimizer(**params).fit(theta)


SIMULATE_CASES = {
    "rtol_negative": ({"rtol": -1.0}, ValueError, r"rtol: expected a real number > 0"),
    "rtol_str": ({"rtol": "1e-3"}, TypeError, r"rtol: expected a real number > 0, got the str"),
    "atol_nan": ({"atol": np.nan}, ValueError, r"atol: expected a real number >= 0, got nan"),
    "timeout_negative": ({"timeout": -1.0}, ValueError, r"timeout: expected a real number >= 0"),
    "max_evaluations_negative": ({"max_evaluations": -5}, ValueError,
                                 r"max_evaluations: expected an integer >= 1, got -5"),
    "max_evaluations_float": ({"max_evaluations": 1e3}, ValueError, r"max_evaluations: "),
    "divergence_bound_nan": ({"divergence_bound": np.nan}, ValueError,
                             r"divergence_bound: expected a real number > 0"),
    "divergence_bound_negative": ({"divergence_bound": -1.0}, ValueError, r"divergence_bound"),
}


@pytest.mark.parametrize("case", list(SIMULATE_CASES))
def test_simulate_option_classes(case, fitted):
    options, error, match = SIMULATE_CASES[case]
    with pytest.raises(error, match=match):
        fitted.simulate([1.0, 0.0], np.linspace(0, 1, 11), **options)


def test_simulate_accepts_unbounded_options(fitted):
    out = fitted.simulate([1.0, 0.0], np.linspace(0, 1, 11), divergence_bound=np.inf,
                          timeout=None)
    np.testing.assert_allclose(out[:, 0], np.cos(np.sqrt(3) * np.linspace(0, 1, 11)),
                               atol=1e-6)


def test_simulate_complex_initial_state(fitted):
    with pytest.raises(TypeError, match=r"x0: expected real numbers, got complex"):
        fitted.simulate([1.0 + 1j, 0.0], np.linspace(0, 1, 11))


# -- symbolic terms ---------------------------------------------------------------------------
def test_term_nan_on_the_data_is_named(data):
    # log(x) is NaN where x <= 0 (its Euler-Lagrange column -1/x is finite there)
    with pytest.raises(ValueError, match=r"the Lagrangian term log\(x\) is NaN or inf on \d+ of "
                                         r"401 samples"):
        _fit(data, library=_library([XD**2, X**2, sp.log(X)]))


def test_term_not_twice_differentiable(data):
    with pytest.raises(ValueError, match=r"the term L\[x_dot\*\*2\*Abs\(x_dot\)\] cannot be "
                                         r"used.*DiracDelta.*differentiable twice"):
        _fit(data, library=_library([XD**2, X**2, sp.Abs(XD) ** 3]))


def test_term_with_a_derivative(data):
    term = sp.Derivative(sp.Function("f")(X), X)
    with pytest.raises(ValueError, match=r"terms: Derivative\(f\(x\), x\) contains Derivative"):
        _fit(data, library=_library([XD**2, X**2, term]))


def test_term_with_an_undefined_function(data):
    with pytest.raises(ValueError, match=r"terms: .* contains f"):
        _fit(data, library=_library([XD**2, X**2, sp.Function("f")(X)]))


def test_catalog_nested_in_itself(data):
    catalog = px.CatalogRepartition([_library()])
    catalog.libraries.append(catalog)
    with pytest.raises(ValueError, match=r"libraries: the catalog contains itself"):
        _fit(data, library=catalog)


def test_monomials_numpy_degree():
    assert px.monomials([X], np.int64(2)) == [X, X**2]


# -- the helpers themselves -------------------------------------------------------------------
@pytest.mark.parametrize("value, kind, kwargs, error", [
    ("True", "bool", {}, TypeError), (1, "bool", {}, TypeError),
    ("3", "int", {}, TypeError), (np.float64(3.5), "int", {}, ValueError),
    (True, "real", {}, TypeError), (np.inf, "real", {}, ValueError),
    (np.nan, "real", {"allow_inf": True}, ValueError), (0.0, "real", {"low": 0, "low_open": True},
                                                        ValueError),
    (2.0, "real", {"high": 1}, ValueError), ("c", "choice", {"choices": ("a", "b")}, ValueError),
    ([1], "choice", {"choices": ("a",)}, TypeError), (None, "int", {}, TypeError),
])
def test_check_option_refuses(value, kind, kwargs, error):
    with pytest.raises(error, match=r"^opt: expected"):
        check_option("opt", value, kind, **kwargs)


@pytest.mark.parametrize("value, kind, kwargs, expected", [
    (np.True_, "bool", {}, True), (np.int64(4), "int", {}, 4), (np.float32(0.5), "real", {}, 0.5),
    (np.inf, "real", {"allow_inf": True}, np.inf), (None, "real", {"allow_none": True}, None),
    ("b", "choice", {"choices": ("a", "b")}, "b"),
])
def test_check_option_accepts(value, kind, kwargs, expected):
    out = check_option("opt", value, kind, **kwargs)
    assert out == expected and type(out) is type(expected)


def test_check_numeric_array_and_indices():
    assert check_numeric_array(np.array([1, 2], dtype=np.int8), "a").dtype == float
    assert check_numeric_array(np.array([1.0, 2.0], dtype=object), "a").tolist() == [1.0, 2.0]
    with pytest.raises(TypeError, match=r"a: expected real numbers, got an element of type str"):
        check_numeric_array(np.array([1.0, "x"], dtype=object), "a")
    with pytest.raises(ValueError, match=r"a: expected a rectangular array"):
        check_numeric_array([[1.0], [1.0, 2.0]], "a")
    with pytest.raises(TypeError, match=r"a: expected real numbers \(seconds\)"):
        check_numeric_array(np.array([1, 2], dtype="timedelta64[s]"), "a")
    assert check_indices(np.array([2, 0]), "i", 3).tolist() == [2, 0]
    with pytest.raises(ValueError, match=r"i: indices must lie in \[0, 3\)"):
        check_indices([3], "i", 3)


# -- strings in public helpers: the restricted grammar, never sympify ---------------------------
def test_mass_matrix_dynamics_parses_strings_with_the_grammar():
    dynamics = px.MassMatrixDynamics(COORDS, ["2*x_ddot + 3*x - tau_x"])
    assert dynamics.mass_matrix_expr == sp.Matrix([[2]])
    with pytest.raises(ValueError, match=r"equations\[0\]: cannot parse expression"):
        px.MassMatrixDynamics(COORDS, ['__import__("os").system("true")'])
    with pytest.raises(TypeError, match=r"equations: expected a list of expressions"):
        px.MassMatrixDynamics(COORDS, "x_ddot + x")


def test_ideal_coefficients_parses_strings_with_the_grammar():
    lib = px.LagrangeLibrary(COORDS, [XD**2, X**2]) + px.ClassicalLibrary(COORDS, [XD])
    np.testing.assert_allclose(
        lib.ideal_coefficients(lagrangian="x_dot**2/2 - 2*x**2", classical={("x_dot", 0): 0.1}),
        [-1.0, 0.5, -2.0, 0.1])
    with pytest.raises(ValueError, match=r"lagrangian: cannot parse expression 'eval\(1\)': "
                                         r"unknown function 'eval'"):
        lib.ideal_coefficients(lagrangian="eval(1)")


@pytest.mark.parametrize("names", [["θ"], ["x", "ｘ"], ["café"]])
def test_non_ascii_coordinate_names(names):
    # accepted before, saved, and then the file did not load (or collided after normalization)
    with pytest.raises(ValueError, match=r"names: .* is not ASCII"):
        px.Coordinates(names)


def test_score_metric_must_be_a_function(fitted, data):
    assert fitted.score(**data) == pytest.approx(1.0, abs=1e-9)
    with pytest.raises(TypeError, match=r"metric: expected a function metric\(true, predicted\) "
                                        r"with a __call__ method, got str"):
        fitted.score(**data, metric="r2")


def test_a_high_power_is_evaluated_without_recursion(data):
    # |x_dot| exceeds 1 here, so the column overflows: a clear error naming the term, never
    # a RecursionError
    with pytest.raises(ValueError, match=r"L\[x_dot\*\*1500\] is NaN or inf"):
        px.XLSINDy(_library([XD**2, X**2, XD**1500]), px.ExplicitOptimizer()).fit(**data)
    small = {**data, "x_dot": data["x_dot"] / 10}  # |x_dot| < 1: evaluated, no overflow
    column = px.CatalogRepartition([_library([XD**2, XD**1501])]).fit().transform(
        px.stack_variables(small["x"], small["x_dot"]))
    np.testing.assert_array_equal(column[:, 2], 0.0)  # d/dt(1501 x_dot**1500) underflows


def test_physical_parameters_refuse_strings():
    from pysindy_xl.mujoco import get_system

    for value in ("2", "heavy", True):
        with pytest.raises(TypeError, match="cart_mass: expected a real number > 0"):
            get_system("cart-pole", cart_mass=value)


def test_trajectories_name_the_series_that_is_not_numeric():
    from pysindy_xl.data import Dataset, Trajectory

    with pytest.raises(TypeError, match=r"q: expected real numbers, got an array of str"):
        Trajectory(t=[0.0, 1.0], q=[["a"], ["b"]])
    with pytest.raises(TypeError, match="qd: expected real numbers, got complex"):
        Trajectory(t=[0.0, 1.0], q=[[0.0], [1.0]], qd=[[1j], [0.0]])
    trajectory = Trajectory(t=[0.0, 1.0], q=[[0.0], [1.0]])
    for names in (3, "x", [1]):
        with pytest.raises(TypeError, match="coordinate_names: expected a sequence of str"):
            Dataset([trajectory], names)


def test_coordinate_names_of_loaded_data(tmp_path):
    from pysindy_xl.data import load_data

    t = np.linspace(0, 1, 11)
    np.savez(tmp_path / "run.npz", t=t, q=np.sin(t))
    with pytest.raises(TypeError, match="coordinates: expected a list of names or a comma"):
        load_data(tmp_path / "run.npz", coordinates=3)
    assert load_data(tmp_path / "run.npz", coordinates="theta").coordinate_names == ("theta",)


def test_sample_every_longer_than_the_run():
    from pysindy_xl.mujoco import generate_dataset

    with pytest.raises(ValueError, match="sample_every: recording every 1000 steps .* fewer "
                                         "than two samples in a run of 0.1 s"):
        generate_dataset("cart-pole", n_trajectories=1, duration=0.1, sample_every=1000)


# -- issue 43: arguments that ended deep inside with an unrelated message -----------------------
def _library_with(extra):
    return px.CatalogRepartition([px.ExternalForces(COORDS), _library(), extra])


BOUNDARY_CASES = {
    # "cannot reshape array of size 0" from the catalog merge
    "classical_mask_all_false": (
        lambda data: _fit(data, library=_library_with(px.ClassicalLibrary(COORDS, [XD],
                                                                          mask=[[False]]))),
        ValueError, r"mask: selects no equation for any term; expected at least one True"),
    "interlink_all_zero": (
        lambda data: _fit(data, library=px.CatalogRepartition(
            [px.ExternalForces(COORDS, interlink=[[0.0]]), _library()])),
        ValueError, r"interlink: is all zero, so no input acts on any coordinate"),
}


@pytest.mark.parametrize("case", list(BOUNDARY_CASES))
def test_boundary_classes(case, data):
    call, error, match = BOUNDARY_CASES[case]
    with pytest.raises(error, match=match):
        call(data)


def test_validate_a_model_on_a_system_of_other_coordinates(fitted):
    # was "x0: expected 2 finite values" from inside simulate
    from pysindy_xl.mujoco import validate_model

    with pytest.raises(ValueError, match=r"model: identified on 1 coordinates, but the reference "
                                         r"has 2 \['x', 'theta'\]"):
        validate_model(fitted, "cart-pole", duration=0.2, seed=0)


@pytest.mark.parametrize("names", [3, "x", [1]])
def test_coordinate_names_of_a_dataset_file(tmp_path, names):
    # was "object of type 'int' has no len()"
    import json

    from pysindy_xl.data import load_dataset

    t = np.linspace(0, 1, 11)
    np.savez(tmp_path / "run.npz", t=t, q=np.sin(t),
             metadata=json.dumps({"coordinate_names": names}))
    with pytest.raises(ValueError, match=r"metadata: coordinate_names: expected a list of str"):
        load_dataset(tmp_path / "run.npz")


def test_predicted_forces_of_another_number_of_coordinates_are_refused():
    c = px.Coordinates(["x", "y"])
    library = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2, c.qd[1] ** 2, c.q[1] ** 2])
    t = np.linspace(0, 5, 501)
    x = np.column_stack([np.sin(t), np.cos(2 * t)])
    xd = np.column_stack([np.cos(t), -2 * np.sin(2 * t)])
    xdd = np.column_stack([-np.sin(t), -4 * np.cos(2 * t)])
    model = px.XLSINDy(library).fit(x, t, x_dot=xd, x_ddot=xdd, u=2 * xdd + 3 * x)
    for wrong in (x[:, :1], np.column_stack([x, x])):
        with pytest.raises(ValueError, match="x: expected 2 columns"):
            model.predict_forces(wrong, wrong, wrong)
