"""scikit-learn contract of XLSINDy on the weak path: fit leaves its parameters unchanged,
fitted models pickle and predict identically, fit-time mass-matrix diagnostics."""

import pickle
import warnings

import numpy as np
import pytest
from ground_truth import random_force, random_initial_state
from support.paper import paper_catalog

import pysindy_xl as px


@pytest.fixture(scope="module")
def cart_pole_data(cart_pole_system):
    system = cart_pole_system
    t = np.arange(0, 15, 0.01)
    data = system.simulate(random_initial_state(system, 4), t, random_force(system, 4))
    noisy = data["q"] + 0.01 * data["q"].std(0) * np.random.default_rng(0).normal(size=(len(t), 2))
    return system, t, noisy, data


def test_fit_leaves_the_catalog_untouched_and_models_pickle(cart_pole_data):
    system, t, noisy, data = cart_pole_data
    library = paper_catalog(system.coords, [1])
    before = pickle.dumps(library)
    model = px.XLSINDy(library)
    params = model.get_params(deep=False)
    model.fit(noisy, t, u=data["tau"])
    assert pickle.dumps(library) == before  # the user's catalog object is not fitted in place
    assert model.get_params(deep=False) == params
    assert not hasattr(library, "symbolic_matrix_")
    restored = pickle.loads(pickle.dumps(model))
    np.testing.assert_array_equal(restored.coefficients(), model.coefficients())
    states = (data["q"][:50], data["qd"][:50], data["tau"][:50])
    np.testing.assert_array_equal(restored.predict(*states), model.predict(*states))
    # the restored library rebuilds its compiled evaluators (strong and weak) on first use
    z = px.stack_variables(data["q"][:200], data["qd"][:200], data["qdd"][:200],
                           data["tau"][:200], t[:200])
    phi, dphi, _ = px.BumpTestFunctions(width=0.3, n_functions=3).matrices(t[:200])
    np.testing.assert_allclose(restored.feature_library_.weak_transform(z, phi, dphi),
                               model.feature_library_.weak_transform(z, phi, dphi))


@pytest.mark.slow
def test_fitted_models_go_through_joblib_worker_processes(cart_pole_data):
    """Fitted models travel to other processes (loky pickles them) and predict there exactly
    as here; so do unfitted ones, which fit there."""
    import joblib

    system, t, noisy, data = cart_pole_data
    library = paper_catalog(system.coords, [1])
    model = px.XLSINDy(library, px.ExplicitOptimizer()).fit(noisy, t, u=data["tau"])
    states = (data["q"][:50], data["qd"][:50], data["tau"][:50])
    remote = joblib.Parallel(n_jobs=2, backend="loky")(
        joblib.delayed(lambda m, s: m.predict(*s))(m, states) for m in (model, model))
    for predicted in remote:
        np.testing.assert_array_equal(predicted, model.predict(*states))
    refit = joblib.Parallel(n_jobs=2, backend="loky")(
        joblib.delayed(lambda m: m.fit(noisy, t, u=data["tau"]).coefficients())(
            px.XLSINDy(library, px.ExplicitOptimizer())) for _ in range(2))
    for coefficients in refit:
        np.testing.assert_allclose(coefficients, model.coefficients(), rtol=1e-9, atol=1e-12)


def test_an_indefinite_mass_matrix_warns_at_fit_time(cart_pole_data):
    system, t, noisy, data = cart_pole_data
    c = system.coords
    # a catalog without the pole's kinetic energy cannot give theta a positive inertia
    library = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.qd[0] * c.qd[1], c.q[1] ** 2])
    with pytest.warns(px.IdentificationWarning, match="not positive definite"):
        model = px.XLSINDy(library, formulation="strong").fit(
            data["q"], t, x_dot=data["qd"], x_ddot=data["qdd"], u=data["tau"])
    assert model.mass_matrix_check_["positive_definite_fraction"] < 1


def test_a_good_model_passes_the_mass_matrix_check(cart_pole_data):
    system, t, noisy, data = cart_pole_data
    model = px.XLSINDy(paper_catalog(system.coords, [1])).fit(noisy, t, u=data["tau"])
    assert model.mass_matrix_check_["positive_definite_fraction"] == 1.0
    assert np.isfinite(model.mass_matrix_check_["median_condition"])


def test_the_warnings_of_a_fit_point_at_the_callers_line(cart_pole_data):
    """Warnings arise at several depths (optimizer, ensemble, diagnostics); every one names
    the line that called fit, where the user can act on it."""
    system, t, noisy, data = cart_pole_data
    c = system.coords
    library = px.LagrangeLibrary(c, [c.qd[0] ** 2])  # nothing can explain theta
    model = px.XLSINDy(library, px.EnsembleOptimizer(px.ExplicitOptimizer(), n_models=4),
                       formulation="strong")
    with pytest.warns(px.IdentificationWarning) as records:
        model.fit(data["q"], t, x_dot=data["qd"], x_ddot=data["qdd"], u=data["tau"])
    categories = {record.category for record in records}
    assert px.UnexplainedCoordinateWarning in categories  # raised inside the ensemble's fits
    assert any("not positive definite" in str(record.message) for record in records)
    assert {record.filename for record in records} == {__file__}
    # the caller's filters still apply inside the fit
    with warnings.catch_warnings():
        warnings.simplefilter("error", px.UnexplainedCoordinateWarning)
        with pytest.raises(px.UnexplainedCoordinateWarning, match=r"\[1\]"):
            model.fit(data["q"], t, x_dot=data["qd"], x_ddot=data["qdd"], u=data["tau"])


class _WarnsThenFails(px.ExplicitOptimizer):
    def _solve(self, problem):
        warnings.warn("the columns look odd", px.IdentificationWarning, stacklevel=2)
        raise np.linalg.LinAlgError("singular")


def test_a_failed_fit_still_reports_its_warnings_at_the_callers_line(cart_pole_data):
    system, t, noisy, data = cart_pole_data
    model = px.XLSINDy(paper_catalog(system.coords, [1]), _WarnsThenFails())
    with pytest.warns(px.IdentificationWarning, match="look odd") as records:
        with pytest.raises(np.linalg.LinAlgError, match="singular"):
            model.fit(noisy, t, u=data["tau"])
    assert [record.filename for record in records] == [__file__]


def test_a_positions_only_fit_enters_the_model_module_once():
    """The fit is a line, not a star: check -> build -> solve -> wrap are calls out of
    ``model.py`` that return, and nothing the fit calls comes back into ``model.py``."""
    import sys

    import pysindy_xl.model as model_module

    c = px.Coordinates(["x"])
    library = px.LagrangeLibrary(c, [c.qd[0] ** 2, c.q[0] ** 2, c.q[0] ** 4])
    t = np.linspace(0, 20, 2001)
    x = (np.sin(1.3 * t) + 0.4 * np.sin(2.9 * t))[:, None]
    u = 2.0 * (-1.69 * np.sin(1.3 * t) - 3.364 * np.sin(2.9 * t))[:, None] + 3 * x
    noisy = x + 1e-3 * np.random.default_rng(0).normal(size=x.shape)
    model = px.XLSINDy(library)
    entries, returns = [], set()
    here = model_module.__file__
    package = here.rsplit("model.py", 1)[0]

    def profile(frame, event, arg):
        inside, caller = frame.f_code.co_filename, frame.f_back.f_code.co_filename
        if event == "call" and inside == here and caller != here:
            entries.append(frame.f_code.co_name)
        if event == "return" and caller == here and inside != here \
                and inside.startswith(package):
            returns.add(inside[len(package):])

    sys.setprofile(profile)
    try:
        model.fit(noisy, t, u=u)
    finally:
        sys.setprofile(None)
    assert entries == ["fit"]
    # what returns into model.py: the option checks and the steps of the fit stage
    assert returns <= {"_validation.py", "fit/trajectories.py", "fit/build.py",
                       "fit/noise_model.py", "fit/solve.py", "fit/wrap.py"}, returns
    assert model.formulation_ == "weak" and model.dynamics_ is not None
