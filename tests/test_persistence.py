"""JSON persistence: exact round trip of a fitted cart-pole model, tampered files refused."""

import json
import pickle

import numpy as np
import pysindy as ps
import pytest
import scipy.integrate
import sympy as sp
from ground_truth import random_force, random_initial_state
from support.paper import paper_catalog

import pysindy_xl as px
from pysindy_xl.io import FORMAT, VERSION, save_model
from pysindy_xl.quality import fit_quality


@pytest.fixture(scope="module")
def cart_pole_model(cart_pole_system):
    system = cart_pole_system
    t = np.arange(0.0, 5.0, 0.01)
    data = system.simulate(random_initial_state(system, 4), t, random_force(system, 4))
    library = paper_catalog(system.coords, [1])
    model = px.XLSINDy(library, px.ExplicitOptimizer())
    model.fit(data["q"], data["t"], x_dot=data["qd"], x_ddot=data["qdd"], u=data["tau"])
    return model, data


@pytest.fixture(scope="module")
def saved(cart_pole_model, tmp_path_factory):
    model, _ = cart_pole_model
    path = tmp_path_factory.mktemp("models") / "cart_pole.json"
    model.save(path)
    return path


@pytest.fixture(scope="module")
def loaded(saved):
    return px.XLSINDy.load(saved)


def test_fitted_model_is_the_true_one(cart_pole_model, cart_pole_system):
    # guards the round-trip tests: they compare a meaningful model
    model, _ = cart_pole_model
    system = cart_pole_system
    friction = {(system.coords.qd[i], i): c for i, c in enumerate(system.friction)}
    true = model.feature_library_.ideal_coefficients(lagrangian=system.lagrangian,
                                                     classical=friction)
    np.testing.assert_allclose(model.coefficients(), true, atol=1e-8)


def test_round_trip_gives_identical_coefficients_and_structure(cart_pole_model, loaded):
    model, _ = cart_pole_model
    np.testing.assert_array_equal(loaded.coefficients(), model.coefficients())
    assert loaded.get_feature_names() == model.get_feature_names()
    assert loaded.equations() == model.equations()
    assert loaded.lagrangian() == model.lagrangian()
    assert loaded.dropped_features_ == model.dropped_features_
    np.testing.assert_array_equal(loaded.forced_coordinates_, model.forced_coordinates_)
    assert loaded.n_coordinates_ == 2
    assert loaded.feature_library_.coords == model.feature_library_.coords
    assert loaded.dynamics_.mass_matrix_expr == model.dynamics_.mass_matrix_expr
    assert loaded.dynamics_.forcing_expr == model.dynamics_.forcing_expr
    assert isinstance(loaded.optimizer_, px.ExplicitOptimizer)
    assert loaded.optimizer_.get_params() == model.optimizer_.get_params()


def test_round_trip_gives_identical_predictions(cart_pole_model, loaded):
    model, data = cart_pole_model
    before = model.predict(data["q"], data["qd"], data["tau"])
    after = loaded.predict(data["q"], data["qd"], data["tau"])
    np.testing.assert_array_equal(after, before)
    np.testing.assert_allclose(after, data["qdd"], atol=1e-6)


def test_round_trip_gives_identical_simulations(cart_pole_model, loaded, cart_pole_system):
    model, _ = cart_pole_model
    t = np.arange(0.0, 1.0, 0.01)
    x0 = random_initial_state(cart_pole_system, 9)
    force = random_force(cart_pole_system, 9)
    np.testing.assert_array_equal(loaded.simulate(x0, t, u=force), model.simulate(x0, t, u=force))
    u = force(t)
    np.testing.assert_array_equal(loaded.simulate(x0, t, u=u), model.simulate(x0, t, u=u))


def test_saving_a_loaded_model_gives_the_same_file(loaded, saved, tmp_path):
    again = tmp_path / "again.json"
    save_model(loaded, again)
    first, second = json.loads(saved.read_text()), json.loads(again.read_text())
    assert second == first


def test_file_is_plain_json_without_pickle(saved, cart_pole_model, tmp_path, monkeypatch):
    raw = saved.read_bytes()
    assert not raw.startswith(b"\x80")  # pickle protocol marker
    document = json.loads(raw.decode("utf-8"))
    assert document["format"] == FORMAT and document["version"] == VERSION
    assert document["coordinates"] == ["x", "theta"]
    assert len(document["coefficients"]) == len(document["feature_names"])
    assert all(isinstance(c, float) for c in document["coefficients"])
    library_types = [lib["type"] for lib in document["feature_library"]["libraries"]]
    assert library_types == ["ExternalForces", "LagrangeLibrary", "ClassicalLibrary"]

    def forbidden(*args, **kwargs):
        raise AssertionError("pickle must not be used")

    for name in ("load", "loads", "dump", "dumps", "Unpickler", "Pickler"):
        monkeypatch.setattr(pickle, name, forbidden)
    model, _ = cart_pole_model
    path = tmp_path / "no_pickle.json"
    model.save(str(path))  # str paths work as well as pathlib ones
    reloaded = px.XLSINDy.load(str(path))
    np.testing.assert_array_equal(reloaded.coefficients(), model.coefficients())


# --------------------------------------------------------------------------------------------
# tampered files
# --------------------------------------------------------------------------------------------


def _tamper(saved, tmp_path, change):
    document = json.loads(saved.read_text())
    change(document)
    path = tmp_path / "tampered.json"
    path.write_text(json.dumps(document))
    return path


def _lagrange_spec(document):
    return next(lib for lib in document["feature_library"]["libraries"]
                if lib["type"] == "LagrangeLibrary")


def _classical_spec(document):
    return next(lib for lib in document["feature_library"]["libraries"]
                if lib["type"] == "ClassicalLibrary")


def _set(key, value):
    def change(document):
        document[key] = value
    return change


TAMPERED = {
    "format": (_set("format", "pickle"), r"'format' must be 'pysindy-xl-model'"),
    "format_missing": (lambda d: d.pop("format"), r"'format' must be"),
    "version": (_set("version", 99), r"unsupported version 99"),
    "version_string": (_set("version", "1"), r"unsupported version '1'"),
    "coefficients_short": (lambda d: d["coefficients"].pop(), r"'coefficients' must be one number"),
    "coefficients_long": (lambda d: d["coefficients"].append(0.0), r"'coefficients' must be"),
    "coefficient_string": (lambda d: d["coefficients"].__setitem__(1, "0.5"),
                           r"'coefficients' must be one number per feature"),
    "coefficient_bool": (lambda d: d["coefficients"].__setitem__(1, True), r"'coefficients'"),
    "coefficient_null": (lambda d: d["coefficients"].__setitem__(1, None), r"'coefficients'"),
    "coefficients_missing": (lambda d: d.pop("coefficients"), r"'coefficients'"),
    "import_term": (lambda d: _lagrange_spec(d)["terms"].__setitem__(
        0, "__import__('os').system('echo pwned')"), r"cannot parse expression"),
    "dunder_term": (lambda d: _lagrange_spec(d)["terms"].__setitem__(0, "x.__class__"),
                    r"cannot parse expression"),
    "unknown_function_term": (lambda d: _lagrange_spec(d)["terms"].__setitem__(0, "open(x)"),
                              r"unknown function 'open'"),
    "unknown_symbol_term": (lambda d: _lagrange_spec(d)["terms"].__setitem__(0, "y_dot**2"),
                            r"unknown symbol 'y_dot'"),
    "acceleration_in_lagrangian": (lambda d: _lagrange_spec(d)["terms"].__setitem__(
        0, "x_ddot"), r"catalog: terms"),
    "terms_not_strings": (lambda d: _lagrange_spec(d)["terms"].__setitem__(0, 3),
                          r"LagrangeLibrary.terms must be a non-empty list of strings"),
    "terms_empty": (lambda d: _lagrange_spec(d).__setitem__("terms", []),
                    r"LagrangeLibrary.terms must be a non-empty list"),
    "unknown_library": (lambda d: _lagrange_spec(d).__setitem__("type", "os.system"),
                        r"unknown library type 'os.system'"),
    "library_not_object": (lambda d: d["feature_library"]["libraries"].__setitem__(0, "lib"),
                           r"library spec must be an object"),
    "libraries_empty": (lambda d: d["feature_library"].__setitem__("libraries", []),
                        r"libraries must be a non-empty list"),
    "mask_shape": (lambda d: _classical_spec(d).__setitem__("mask", [[1, 0]]),
                   r"ClassicalLibrary.mask must be a 0/1 matrix \(n_terms, n\)"),
    "mask_values": (lambda d: _classical_spec(d).__setitem__("mask", [[1, 0], [0, 7]]),
                    r"ClassicalLibrary.mask must be a 0/1 matrix"),
    "mask_missing": (lambda d: _classical_spec(d).pop("mask"), r"ClassicalLibrary.mask"),
    "interlink_shape": (lambda d: d["feature_library"]["libraries"][0].__setitem__(
        "interlink", [[1.0]]), r"ExternalForces.interlink must be a finite \(n, n\) matrix"),
    "interlink_text": (lambda d: d["feature_library"]["libraries"][0].__setitem__(
        "interlink", [["a", 0], [0, 1]]), r"ExternalForces.interlink must be a numeric"),
    "feature_names": (lambda d: d["feature_names"].__setitem__(1, "L[evil]"),
                      r"feature_names do not match the catalog"),
    "coordinates_reserved": (_set("coordinates", ["x", "t"]), r"names: 't' is reserved"),
    "coordinates_not_list": (_set("coordinates", "x"), r"'coordinates' must be a list"),
    "forced_length": (_set("forced_coordinates", [True]), r"'forced_coordinates' must have"),
    "forced_not_flags": (_set("forced_coordinates", [[None, []], True]),
                         r"'forced_coordinates' must have one flag"),
    "mask_ragged": (lambda d: _classical_spec(d).__setitem__("mask", [[1, [0]], [0, 1]]),
                    r"ClassicalLibrary.mask must be a 0/1 matrix"),
    "dropped_not_object": (_set("dropped_features", ["a"]), r"'dropped_features' must be"),
}


@pytest.mark.parametrize("case", list(TAMPERED))
def test_tampered_file_rejected(case, saved, tmp_path):
    change, match = TAMPERED[case]
    path = _tamper(saved, tmp_path, change)
    with pytest.raises(ValueError, match="is not a valid pysindy-xl model file") as info:
        px.XLSINDy.load(path)
    assert info.match(match)


@pytest.mark.parametrize("literal", ["NaN", "Infinity", "-Infinity"])
def test_non_finite_coefficient_rejected(literal, saved, tmp_path):
    document = json.loads(saved.read_text())
    document["coefficients"][2] = "PLACEHOLDER"
    text = json.dumps(document).replace('"PLACEHOLDER"', literal)
    path = tmp_path / "nan.json"
    path.write_text(text)
    with pytest.raises(ValueError, match=f"non-finite number {literal}"):
        px.XLSINDy.load(path)


def test_overflowing_coefficient_rejected(saved, tmp_path):
    document = json.loads(saved.read_text())
    document["coefficients"][2] = "PLACEHOLDER"
    path = tmp_path / "overflow.json"
    path.write_text(json.dumps(document).replace('"PLACEHOLDER"', "1e999"))
    with pytest.raises(ValueError, match="coefficients"):
        px.XLSINDy.load(path)


def test_deeply_nested_term_rejected(saved, tmp_path):
    path = _tamper(saved, tmp_path, lambda d: _lagrange_spec(d)["terms"].__setitem__(
        0, "(" * 400 + "x_dot" + ")" * 400))
    with pytest.raises(ValueError, match="is not a valid pysindy-xl model file"):
        px.XLSINDy.load(path)


@pytest.mark.parametrize(
    "content",
    [
        "not json at all",
        "{\"format\": ",
        "",
        "[1, 2, 3]",
        "\"pysindy-xl-model\"",
        "null",
    ],
)
def test_non_json_or_non_object_file_rejected(content, tmp_path):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(ValueError, match="is not a valid pysindy-xl model file"):
        px.XLSINDy.load(path)


def test_pickle_file_rejected_without_unpickling(tmp_path, monkeypatch):
    path = tmp_path / "model.pkl"
    path.write_bytes(pickle.dumps({"format": FORMAT, "version": VERSION}))

    def forbidden(*args, **kwargs):
        raise AssertionError("pickle must not be used")

    monkeypatch.setattr(pickle, "loads", forbidden)
    monkeypatch.setattr(pickle, "load", forbidden)
    with pytest.raises(ValueError, match="not JSON"):
        px.XLSINDy.load(path)


def test_missing_file_and_directory_rejected(tmp_path):
    with pytest.raises(ValueError, match="path: no such file"):
        px.XLSINDy.load(tmp_path / "missing.json")
    with pytest.raises(ValueError, match="path: no such file"):
        px.XLSINDy.load(tmp_path)


def test_full_precision_constants_and_interlink_survive_round_trip(tmp_path):
    coords = px.Coordinates(["x"])
    x, xd = coords.q[0], coords.qd[0]
    third = sp.Float(1 / 3)  # 15 printed digits would not reproduce it
    library = px.CatalogRepartition([
        px.ExternalForces(coords, interlink=[[0.7]]),
        px.LagrangeLibrary(coords, [xd**2, third * x**2, sp.cos(third * x)]),
        px.ClassicalLibrary(coords, [np.pi * xd], mask=[[1]]),
    ])
    t = np.linspace(0, 8, 401)
    q = (np.cos(2 * t) + 0.1 * t)[:, None]
    qd, qdd = (-2 * np.sin(2 * t) + 0.1)[:, None], (-4 * np.cos(2 * t))[:, None]
    u = (qdd + 3 * q + 0.2 * qd) / 0.7  # 0.7 u = x'' + 3 x + 0.2 x'
    model = px.XLSINDy(library, px.ExplicitOptimizer()).fit(q, t, x_dot=qd, x_ddot=qdd, u=u)
    np.testing.assert_allclose(model.predict(q, qd, u), qdd, atol=1e-8)
    path = tmp_path / "precise.json"
    model.save(path)
    loaded = px.XLSINDy.load(path)
    assert loaded.get_feature_names() == model.get_feature_names()
    np.testing.assert_array_equal(loaded.coefficients(), model.coefficients())
    np.testing.assert_array_equal(loaded.predict(q, qd, u), model.predict(q, qd, u))
    theta = model.feature_library_.transform(np.column_stack([q, qd, qdd, u, t]))
    np.testing.assert_array_equal(
        loaded.feature_library_.transform(np.column_stack([q, qd, qdd, u, t])), theta)


@pytest.mark.parametrize("bad", ["cos(theta)/0", "0/0*cos(theta)", "sqrt(-1)*cos(theta)",
                                 "log(0)*cos(theta)"])
def test_non_finite_or_complex_term_rejected(bad, saved, tmp_path):
    coords = px.Coordinates(["x", "theta"])

    def change(document):
        # a consistent forgery: the feature name matches the forged term
        terms = _lagrange_spec(document)["terms"]
        k = terms.index("cos(theta)")
        terms[k] = bad
        # the test itself may use sympy's parser on its own constant strings
        name = f"L[{sp.parse_expr(bad, local_dict=coords.symbol_table())}]"
        document["feature_names"][document["feature_names"].index("L[cos(theta)]")] = name

    path = _tamper(saved, tmp_path, change)
    with pytest.raises(ValueError, match="is not a valid pysindy-xl model file"):
        px.XLSINDy.load(path)


# ------------------------------------------------- a bagged fit keeps its uncertainty on disk


@pytest.fixture(scope="module")
def noisy_model(cart_pole_system, tmp_path_factory):
    """The default fit of noisy positions (bagged), saved and loaded back."""
    system = cart_pole_system
    t = np.arange(0.0, 20.0, 0.01)
    data = system.simulate(random_initial_state(system, 2), t, random_force(system, 2))
    noisy = data["q"] + 0.01 * data["q"].std(axis=0) * np.random.default_rng(2).normal(
        size=data["q"].shape)
    model = px.XLSINDy(paper_catalog(system.coords, [1])).fit(noisy, t, u=data["tau"])
    path = tmp_path_factory.mktemp("models") / "noisy.json"
    model.save(path)
    return model, path, data


def test_bagged_fit_round_trip_keeps_inclusion_and_intervals(noisy_model):
    model, path, data = noisy_model
    assert isinstance(model.optimizer_, px.EnsembleOptimizer)  # the default for noisy positions
    loaded = px.XLSINDy.load(path)
    np.testing.assert_array_equal(loaded.inclusion_probability_, model.inclusion_probability_)
    np.testing.assert_array_equal(loaded.coef_interval_, model.coef_interval_)
    assert isinstance(loaded.optimizer_, px.EnsembleOptimizer)
    assert isinstance(loaded.optimizer_.optimizer, px.ExplicitOptimizer)
    assert loaded.optimizer_.get_params(deep=False)["n_models"] == 20
    np.testing.assert_array_equal(loaded.predict(data["q"], data["qd"], data["tau"]),
                                  model.predict(data["q"], data["qd"], data["tau"]))


@pytest.mark.parametrize("uncertainty, message", [
    ({"inclusion_probability": [0.5], "coef_interval": [[0], [1]]}, "one number in"),
    ("everything is certain", "must be an object"),
    ({"coef_interval": None}, "must be an object"),
])
def test_tampered_uncertainty_is_refused(noisy_model, tmp_path, uncertainty, message):
    _, path, _ = noisy_model
    document = json.loads(path.read_text())
    document["uncertainty"] = uncertainty
    target = tmp_path / "tampered.json"
    target.write_text(json.dumps(document))
    with pytest.raises(ValueError, match=f"not a valid pysindy-xl model file: .*{message}"):
        px.XLSINDy.load(target)


def test_tampered_interval_bounds_and_probabilities_are_refused(noisy_model, tmp_path):
    _, path, _ = noisy_model
    for change in ("probability above one", "low above high"):
        document = json.loads(path.read_text())
        uncertainty = document["uncertainty"]
        if change == "probability above one":
            uncertainty["inclusion_probability"][0] = 1.5
        else:
            uncertainty["coef_interval"][0][1] = uncertainty["coef_interval"][1][1] + 1.0
        target = tmp_path / "tampered.json"
        target.write_text(json.dumps(document))
        with pytest.raises(ValueError, match="uncertainty"):
            px.XLSINDy.load(target)


def test_an_ensemble_inside_an_ensemble_is_refused(noisy_model, tmp_path):
    _, path, _ = noisy_model
    document = json.loads(path.read_text())
    document["optimizer"]["params"]["optimizer"] = {"type": "EnsembleOptimizer", "params": {}}
    target = tmp_path / "nested.json"
    target.write_text(json.dumps(document))
    with pytest.raises(ValueError, match="cannot bag another EnsembleOptimizer"):
        px.XLSINDy.load(target)


def test_ensemble_sampling_survives_the_file_and_bad_values_are_refused(noisy_model, tmp_path):
    _, path, _ = noisy_model
    document = json.loads(path.read_text())
    document["optimizer"]["params"]["sampling"] = "complementary_pairs"
    target = tmp_path / "pairs.json"
    target.write_text(json.dumps(document))
    assert px.XLSINDy.load(target).optimizer_.sampling == "complementary_pairs"
    for bad, message in (("bootstrap", "sampling"), (True, "sampling")):
        document["optimizer"]["params"]["sampling"] = bad
        target.write_text(json.dumps(document))
        with pytest.raises(ValueError, match=message):
            px.XLSINDy.load(target)
    document["optimizer"]["params"].update(sampling="complementary_pairs", n_models=5)
    target.write_text(json.dumps(document))
    with pytest.raises(ValueError, match="even"):
        px.XLSINDy.load(target)


# ------------------------------------- settings and diagnostics of the fit survive the file


@pytest.fixture(scope="module")
def weak_model(tmp_path_factory):
    """A single cross-validated weak fit of a noisy forced oscillator with non-default
    settings: ``x'' + 0.1 x' + 3 x = u``."""
    coords = px.Coordinates(["x"])
    library = px.CatalogRepartition([
        px.ExternalForces(coords),
        px.LagrangeLibrary(coords, [coords.qd[0] ** 2, coords.q[0] ** 2, coords.q[0] ** 4]),
        px.ClassicalLibrary(coords, [coords.qd[0]])])
    t = np.linspace(0, 20, 2001)

    def force(time):
        return np.sin(1.3 * time) + 0.5 * np.sin(3.1 * time)

    solution = scipy.integrate.solve_ivp(
        lambda time, y: [y[1], force(time) - 3 * y[0] - 0.1 * y[1]], (0, 20), [1.0, 0.0],
        t_eval=t, rtol=1e-10, atol=1e-10)
    x = solution.y[0][:, None] + 0.01 * np.random.default_rng(0).normal(size=(2001, 1))
    arguments = {"x": x, "t": t, "u": force(t)[:, None]}
    smoother = px.WhittakerSmoother(order=2)
    model = px.XLSINDy(library, px.ExplicitOptimizer(), smoother=smoother, t_default=0.5,
                       test_functions=px.BumpTestFunctions(width_factor=1.2, power=5))
    model.fit(**arguments)
    path = tmp_path_factory.mktemp("models") / "weak.json"
    model.save(path)
    return model, path, arguments


def test_weak_fit_keeps_its_settings_and_diagnostics(weak_model):
    model, path, arguments = weak_model
    np.testing.assert_allclose(model.coefficients()[[0, 1, 2, 4]], [-1.0, 0.5, -1.5, 0.1],
                               rtol=0.05)  # guards the comparison: a meaningful fit
    assert not hasattr(model.smoother, "lam_")  # fit smooths with a copy of the parameter
    loaded = px.XLSINDy.load(path)
    assert loaded.formulation_ == "weak" and loaded.n_samples_ == model.n_samples_ == 2001
    # the file keeps the width, the test functions and the noise (not the time grid's report)
    kept = ("half_width", "test_functions", "noise")
    assert loaded.weak_info_ == {key: model.weak_info_[key] for key in kept}
    assert loaded.mass_matrix_check_ == model.mass_matrix_check_
    assert type(loaded.selection_) is type(model.selection_)
    np.testing.assert_array_equal(loaded.selection_.order, model.selection_.order)
    np.testing.assert_array_equal(loaded.selection_.cv_error, model.selection_.cv_error)
    assert (loaded.selection_.size, loaded.selection_.rule) == (model.selection_.size,
                                                                model.selection_.rule)
    assert loaded.t_default == 0.5
    assert vars(loaded.test_functions) == vars(model.test_functions)
    assert loaded.smoother.order == 2
    # the loaded model rebuilds the regression it was fitted on
    assert fit_quality(loaded, arguments) == fit_quality(model, arguments)


def test_files_without_settings_or_diagnostics_still_load(weak_model, tmp_path):
    model, path, _ = weak_model
    document = json.loads(path.read_text())
    del document["settings"], document["training"]
    target = tmp_path / "older.json"
    target.write_text(json.dumps(document))
    loaded = px.XLSINDy.load(target)
    assert loaded.formulation_ is None and loaded.selection_ is None
    assert loaded.test_functions is None and loaded.t_default == 1.0
    np.testing.assert_array_equal(loaded.coefficients(), model.coefficients())


def test_non_finite_diagnostics_round_trip_as_strings(weak_model, tmp_path):
    _, path, _ = weak_model
    document = json.loads(path.read_text())
    document["training"]["selection"]["fields"]["cv_error"][0] = "inf"
    document["training"]["mass_matrix_check"]["median_condition"] = "nan"
    target = tmp_path / "inf.json"
    target.write_text(json.dumps(document))
    loaded = px.XLSINDy.load(target)
    assert loaded.selection_.cv_error[0] == np.inf
    assert np.isnan(loaded.mass_matrix_check_["median_condition"])
    save_model(loaded, tmp_path / "again.json")
    assert json.loads((tmp_path / "again.json").read_text())["training"] == document["training"]


def test_unsaveable_setting_warns_and_is_left_out(weak_model, tmp_path):
    model, _, arguments = weak_model
    custom = px.XLSINDy(model.feature_library, px.ExplicitOptimizer(),
                        differentiation_method=ps.SmoothedFiniteDifference())
    custom.fit(arguments["x"], arguments["t"], u=arguments["u"])
    with pytest.warns(UserWarning, match="differentiation_method: SmoothedFiniteDifference"):
        custom.save(tmp_path / "custom.json")
    assert px.XLSINDy.load(tmp_path / "custom.json").differentiation_method is None
    plain = px.XLSINDy(model.feature_library, px.ExplicitOptimizer(),
                       differentiation_method=ps.FiniteDifference(order=2))
    plain.fit(arguments["x"], arguments["t"], u=arguments["u"])
    plain.save(tmp_path / "plain.json")
    method = px.XLSINDy.load(tmp_path / "plain.json").differentiation_method
    assert isinstance(method, ps.FiniteDifference) and method.order == 2


def _training(key, value):
    def change(document):
        document["training"][key] = value
    return change


def _setting(key, value):
    def change(document):
        document["settings"][key] = value
    return change


def _selection_field(key, value):
    def change(document):
        document["training"]["selection"]["fields"][key] = value
    return change


TAMPERED_TRAINING = {
    "formulation": (_training("formulation", "pointwise"), "training.formulation"),
    "samples": (_training("n_samples", -3), "training.n_samples"),
    "weak_info": (_training("weak_info", {"half_width": 1.0}), "training.weak_info"),
    "half_width": (lambda d: d["training"]["weak_info"].__setitem__("half_width", -1.0),
                   "training.weak_info.half_width must be positive"),
    "check": (_training("mass_matrix_check", {"positive_definite_fraction": "all"}),
              "training.mass_matrix_check"),
    "selection_type": (lambda d: d["training"]["selection"].__setitem__("type", "os.system"),
                       "training.selection must be null or"),
    "selection_order": (_selection_field("order", [0, 99]), "training.selection.order"),
    "selection_size": (_selection_field("size", True), "training.selection.size"),
    "selection_error": (_selection_field("cv_error", ["zero"]),
                        "training.selection.cv_error"),
    "selection_missing": (lambda d: d["training"]["selection"]["fields"].pop("rule"),
                          "training.selection.fields must be"),
    "setting_unknown": (_setting("verbose", True), "'settings' must be an object"),
    "setting_value": (_setting("t_default", -1.0), "settings: t_default"),
    "setting_type": (_setting("smoother", {"type": "eval", "params": {}}), "settings.smoother"),
    "setting_param": (_setting("test_functions", {"type": "BumpTestFunctions",
                                                  "params": {"power": 0}}),
                      "settings.test_functions: power"),
    "setting_unknown_param": (_setting("smoother", {"type": "WhittakerSmoother",
                                                    "params": {"window": 3}}),
                              "settings.smoother: .*window"),
}


@pytest.mark.parametrize("case", list(TAMPERED_TRAINING))
def test_tampered_settings_or_diagnostics_are_refused(case, weak_model, tmp_path):
    change, match = TAMPERED_TRAINING[case]
    _, path, _ = weak_model
    with pytest.raises(ValueError, match=f"not a valid pysindy-xl model file: {match}"):
        px.XLSINDy.load(_tamper(path, tmp_path, change))
