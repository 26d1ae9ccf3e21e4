"""XLSINDy input validation: every public call refuses bad input with a message naming it."""

import numpy as np
import pysindy as ps
import pytest
from sklearn.exceptions import NotFittedError

import pysindy_xl as px

COORDS = px.Coordinates(["x"])
X, XD = COORDS.q[0], COORDS.qd[0]
N = 401


def _library():
    return px.LagrangeLibrary(COORDS, [XD**2, X**2, X**4])


def _data():
    """Forced oscillator x'' + 3 x = u (L = xd^2/2 - 3/2 x^2), exact derivatives."""
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
    return px.XLSINDy(_library(), px.ExplicitOptimizer()).fit(**data)


def test_reference_fit_is_correct(fitted, data):
    # guards the other tests: the valid call works and identifies the oscillator
    np.testing.assert_allclose(fitted.coefficients(), [-1.0, 0.5, -1.5, 0.0], atol=1e-9)
    np.testing.assert_allclose(fitted.predict(data["x"], data["x_dot"], data["u"]),
                               data["x_ddot"], atol=1e-9)


def _with(data, **changes):
    out = dict(data)
    out.update(changes)
    return out


def _nan_at(a, value=np.nan):
    a = np.array(a, dtype=float)
    a[len(a) // 2, 0] = value
    return a


FIT_ERRORS = {
    "x_3d": (lambda d: _with(d, x=d["x"][None]), ValueError, r"x: expected a 2-D array"),
    "x_columns": (lambda d: _with(d, x=np.hstack([d["x"], d["x"]])), ValueError,
                  r"x: expected 1 columns"),
    "x_nan": (lambda d: _with(d, x=_nan_at(d["x"])), ValueError, r"x: contains NaN or inf"),
    "x_inf": (lambda d: _with(d, x=_nan_at(d["x"], np.inf)), ValueError, r"x: contains NaN"),
    "x_text": (lambda d: _with(d, x=np.full((N, 1), "a")), TypeError, r"x: expected real numbers"),
    "x_few": (lambda d: {k: (v[:3] if k != "u" else v[:3]) for k, v in d.items()}, ValueError,
              r"x: expected at least 5 samples"),
    "x_dot_nan": (lambda d: _with(d, x_dot=_nan_at(d["x_dot"])), ValueError,
                  r"x_dot: contains NaN or inf"),
    "x_ddot_inf": (lambda d: _with(d, x_ddot=_nan_at(d["x_ddot"], -np.inf)), ValueError,
                   r"x_ddot: contains NaN or inf"),
    "u_nan": (lambda d: _with(d, u=_nan_at(d["u"])), ValueError, r"u: contains NaN or inf"),
    "x_dot_short": (lambda d: _with(d, x_dot=d["x_dot"][:-1]), ValueError,
                    r"x_dot: expected shape \(401, 1\), got \(400, 1\)"),
    "x_ddot_long": (lambda d: _with(d, x_ddot=np.vstack([d["x_ddot"], [[0.0]]])), ValueError,
                    r"x_ddot: expected shape \(401, 1\)"),
    "u_short": (lambda d: _with(d, u=d["u"][1:]), ValueError, r"u: expected shape \(401, 1\)"),
    "u_columns": (lambda d: _with(d, u=np.hstack([d["u"], d["u"]])), ValueError,
                  r"u: expected shape \(401, 1\), got \(401, 2\)"),
    "t_short": (lambda d: _with(d, t=d["t"][:-1]), ValueError,
                r"t: expected 401 times \(one per sample\), got 400"),
    "t_decreasing": (lambda d: _with(d, t=d["t"][::-1]), ValueError,
                     r"t: times must be strictly increasing"),
    "t_repeated": (lambda d: _with(d, t=np.r_[d["t"][:10], d["t"][9:-1]]), ValueError,
                   r"t: times must be strictly increasing"),
    "t_nan": (lambda d: _with(d, t=np.r_[d["t"][:-1], np.nan]), ValueError, r"t: contains NaN"),
    "t_2d": (lambda d: _with(d, t=d["t"][:, None]), ValueError, r"t: expected a 1-D array"),
    "t_text": (lambda d: _with(d, t="fast"), TypeError, r"t: expected a time step"),
    "dt_negative": (lambda d: _with(d, t=-0.02), ValueError,
                    r"t: the time step must be positive and finite"),
    "dt_zero": (lambda d: _with(d, t=0.0), ValueError, r"t: the time step must be positive"),
    "dt_inf": (lambda d: _with(d, t=np.inf), ValueError, r"t: the time step must be positive"),
    "x_list_u_array": (lambda d: _with(d, x=[d["x"]], t=[d["t"]], x_dot=[d["x_dot"]],
                                       x_ddot=[d["x_ddot"]]), ValueError,
                       r"u: expected the same layout as x \(1 trajectories\)"),
    "x_array_u_list": (lambda d: _with(d, u=[d["u"]]), ValueError,
                       r"u: expected the same layout as x \(1 array\)"),
    "x_array_x_dot_list": (lambda d: _with(d, x_dot=[d["x_dot"]]), ValueError,
                           r"x_dot: expected the same layout as x"),
    "x_array_t_list": (lambda d: _with(d, t=[d["t"]]), ValueError,
                       r"t: a list of times needs x to be a list of the same length"),
    "list_lengths": (lambda d: _with(d, x=[d["x"], d["x"]], t=[d["t"]] * 2,
                                     x_dot=[d["x_dot"]] * 2, x_ddot=[d["x_ddot"]] * 2,
                                     u=[d["u"]]), ValueError,
                     r"u: expected the same layout as x \(2 trajectories\)"),
    "t_list_length": (lambda d: _with(d, x=[d["x"], d["x"]], t=[d["t"]] * 3,
                                      x_dot=[d["x_dot"]] * 2, x_ddot=[d["x_ddot"]] * 2,
                                      u=[d["u"]] * 2), ValueError,
                      r"t: a list of times needs x to be a list of the same length"),
    "empty_list": (lambda d: _with(d, x=[], t=[], x_dot=[], x_ddot=[], u=[]), ValueError,
                   r"x: expected at least one trajectory"),
    "second_trajectory_nan": (lambda d: _with(d, x=[d["x"], _nan_at(d["x"])], t=[d["t"]] * 2,
                                              x_dot=[d["x_dot"]] * 2, x_ddot=[d["x_ddot"]] * 2,
                                              u=[d["u"]] * 2), ValueError,
                              r"x\[1\]: contains NaN or inf"),
    "second_t_decreasing": (lambda d: _with(d, x=[d["x"]] * 2, t=[d["t"], d["t"][::-1]],
                                            x_dot=[d["x_dot"]] * 2, x_ddot=[d["x_ddot"]] * 2,
                                            u=[d["u"]] * 2), ValueError,
                            r"t\[1\]: times must be strictly increasing"),
    "second_u_short": (lambda d: _with(d, x=[d["x"]] * 2, t=[d["t"]] * 2,
                                       x_dot=[d["x_dot"]] * 2, x_ddot=[d["x_ddot"]] * 2,
                                       u=[d["u"], d["u"][:-1]]), ValueError,
                       r"u\[1\]: expected shape \(401, 1\)"),
}


@pytest.mark.parametrize("case", list(FIT_ERRORS))
def test_fit_rejects_bad_input(case, data):
    make, error, match = FIT_ERRORS[case]
    model = px.XLSINDy(_library(), px.ExplicitOptimizer())
    with pytest.raises(error, match=match):
        model.fit(**make(data))
    assert not hasattr(model, "coef_")


def test_fit_accepts_several_trajectories_of_different_lengths(data):
    half = N // 2
    pieces = {k: [v[:half], v[half:]] for k, v in data.items()}
    model = px.XLSINDy(_library(), px.ExplicitOptimizer()).fit(**pieces)
    np.testing.assert_allclose(model.coefficients(), [-1.0, 0.5, -1.5, 0.0], atol=1e-9)
    assert model.n_samples_ == N
    # a scalar time step applies to every trajectory
    model = px.XLSINDy(_library(), px.ExplicitOptimizer()).fit(
        **{**pieces, "t": float(data["t"][1] - data["t"][0])})
    np.testing.assert_allclose(model.coefficients(), [-1.0, 0.5, -1.5, 0.0], atol=1e-9)


def test_catalog_without_acceleration_term_rejected(data):
    no_velocity = px.LagrangeLibrary(COORDS, [X**2, X**4])
    with pytest.raises(ValueError, match="feature_library: no term contains an acceleration"):
        px.XLSINDy(no_velocity, px.ExplicitOptimizer()).fit(**data)
    friction_only = px.ClassicalLibrary(COORDS, [XD, X])
    with pytest.raises(ValueError, match="feature_library: no term contains an acceleration"):
        px.XLSINDy(friction_only, px.ExplicitOptimizer()).fit(**data)


@pytest.mark.parametrize(
    "library, error, match",
    [
        (None, ValueError, "feature_library: a catalog is required"),
        (ps.PolynomialLibrary(), TypeError, "feature_library: expected a pysindy_xl library"),
        ("L", TypeError, "feature_library"),
    ],
)
def test_bad_feature_library(library, error, match, data):
    with pytest.raises(error, match=match):
        px.XLSINDy(library, px.ExplicitOptimizer()).fit(**data)


# (a 1-D x of one coordinate and a pysindy optimizer are accepted: tests/test_pysindy_parity.py)
@pytest.mark.parametrize("optimizer", [object(), 3])
def test_wrong_optimizer_type(optimizer, data):
    with pytest.raises(TypeError, match="optimizer: expected a catalog optimizer"):
        px.XLSINDy(_library(), optimizer).fit(**data)


def test_optimizer_named_by_its_kind(data):
    # a kind of regression names the default optimizer of that kind; others are refused
    model = px.XLSINDy(_library(), "explicit").fit(**data)
    assert type(model.optimizer_) is px.ExplicitOptimizer
    with pytest.raises(ValueError, match=r"optimizer: expected one of \('explicit', "):
        px.XLSINDy(_library(), "lasso").fit(**data)
    with pytest.raises(ValueError, match="u: explicit regression needs the generalized forces"):
        px.XLSINDy(_library(), "explicit").fit(data["x"], data["t"])


def test_bad_differentiation_method(data):
    with pytest.raises(TypeError, match="differentiation_method"):
        px.XLSINDy(_library(), px.ExplicitOptimizer(), differentiation_method="fd").fit(
            data["x"], data["t"], u=data["u"])


def test_differentiation_method_returning_garbage(data):
    def broken(x, t):
        return np.full_like(x, np.nan)

    with pytest.raises(ValueError, match="differentiation_method: returned an invalid"):
        px.XLSINDy(_library(), px.ExplicitOptimizer(), differentiation_method=broken).fit(
            data["x"], data["t"], u=data["u"])


@pytest.mark.parametrize("u", ["absent", "zero"])
def test_explicit_optimizer_on_unforced_data(u, data):
    kwargs = _with(data, u=np.zeros_like(data["u"])) if u == "zero" else _with(data, u=None)
    with pytest.raises(ValueError, match="force"):
        px.XLSINDy(_library(), px.ExplicitOptimizer()).fit(**kwargs)


def test_explicit_optimizer_on_unforced_data_names_u(data):
    with pytest.raises(ValueError) as info:
        px.XLSINDy(_library(), px.ExplicitOptimizer()).fit(**_with(data, u=None))
    assert str(info.value).startswith("u:")


UNFITTED_CALLS = {
    "predict": lambda m, d: m.predict(d["x"], d["x_dot"]),
    "simulate": lambda m, d: m.simulate([1.0, 0.0], d["t"]),
    "coefficients": lambda m, d: m.coefficients(),
    "equations": lambda m, d: m.equations(),
    "get_feature_names": lambda m, d: m.get_feature_names(),
    "lagrangian": lambda m, d: m.lagrangian(),
    "print": lambda m, d: m.print(),
    "score": lambda m, d: m.score(**d),
    "save": lambda m, d: m.save("never_written.json"),
    "to_jax": lambda m, d: m.to_jax(),
}


@pytest.mark.parametrize("call", list(UNFITTED_CALLS))
def test_unfitted_model_raises_not_fitted(call, data, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    model = px.XLSINDy(_library(), px.ExplicitOptimizer())
    with pytest.raises(NotFittedError):
        UNFITTED_CALLS[call](model, data)
    assert not (tmp_path / "never_written.json").exists()


PREDICT_ERRORS = {
    "x_dot_short": (lambda d: (d["x"], d["x_dot"][:-1], None), r"x_dot: expected shape"),
    "x_columns": (lambda d: (np.hstack([d["x"]] * 2), np.hstack([d["x_dot"]] * 2), None),
                  r"x: expected 1 columns"),
    "x_nan": (lambda d: (_nan_at(d["x"]), d["x_dot"], None), r"x: contains NaN or inf"),
    "x_dot_inf": (lambda d: (d["x"], _nan_at(d["x_dot"], np.inf), None),
                  r"x_dot: contains NaN or inf"),
    "u_nan": (lambda d: (d["x"], d["x_dot"], _nan_at(d["u"])), r"u: contains NaN or inf"),
    "u_short": (lambda d: (d["x"], d["x_dot"], d["u"][:-1]), r"u: expected shape"),
    "x_dot_missing": (lambda d: (d["x"], None, None), r"x_dot"),
    "layout": (lambda d: ([d["x"]], d["x_dot"], None), r"x_dot: expected the same layout"),
    "layout_u": (lambda d: ([d["x"]], [d["x_dot"]], d["u"]), r"expected the same layout"),
    "list_length": (lambda d: ([d["x"]] * 2, [d["x_dot"]], None), r"expected the same layout"),
    "list_item": (lambda d: ([d["x"], d["x"]], [d["x_dot"], _nan_at(d["x_dot"])], None),
                  r"x_dot\[1\]: contains NaN"),
}


@pytest.mark.parametrize("case", list(PREDICT_ERRORS))
def test_predict_rejects_bad_input(case, fitted, data):
    make, match = PREDICT_ERRORS[case]
    with pytest.raises(ValueError, match=match):
        fitted.predict(*make(data))


def test_predict_keeps_the_layout_of_x(fitted, data):
    single = fitted.predict(data["x"], data["x_dot"], data["u"])
    several = fitted.predict([data["x"], data["x"][:10]], [data["x_dot"], data["x_dot"][:10]],
                             [data["u"], data["u"][:10]])
    assert isinstance(several, list) and len(several) == 2
    np.testing.assert_array_equal(several[0], single)
    np.testing.assert_array_equal(several[1], single[:10])


SIMULATE_ERRORS = {
    "x0_length": (lambda d: ([1.0, 0.0, 0.0], d["t"][:50], None), r"x0: expected 2 finite"),
    "x0_nan": (lambda d: ([np.nan, 0.0], d["t"][:50], None), r"x0: expected 2 finite"),
    "t_decreasing": (lambda d: ([1.0, 0.0], d["t"][:50][::-1], None),
                     r"t: times must be strictly increasing"),
    "t_scalar": (lambda d: ([1.0, 0.0], 0.01, None), r"t: expected a 1-D array"),
    "t_nan": (lambda d: ([1.0, 0.0], np.r_[d["t"][:5], np.nan], None), r"t: contains NaN"),
    "u_short": (lambda d: ([1.0, 0.0], d["t"][:50], d["u"][:49]), r"u: expected an array of"),
    "u_nan": (lambda d: ([1.0, 0.0], d["t"][:50], _nan_at(d["u"][:50])), r"u: contains NaN"),
    "u_callable_shape": (lambda d: ([1.0, 0.0], d["t"][:50], lambda s: np.zeros(3)),
                         r"u: the callable must return an array of shape \(1,\)"),
}


@pytest.mark.parametrize("case", list(SIMULATE_ERRORS))
def test_simulate_rejects_bad_input(case, fitted, data):
    make, match = SIMULATE_ERRORS[case]
    x0, t, u = make(data)
    with pytest.raises(ValueError, match=match):
        fitted.simulate(x0, t, u)


def test_simulate_reproduces_training_trajectory(fitted, data):
    t = data["t"][:200]
    sim = fitted.simulate([data["x"][0, 0], data["x_dot"][0, 0]], t, data["u"][:200])
    # u is interpolated linearly between samples: small, bounded interpolation error
    np.testing.assert_allclose(sim[:, 0], data["x"][:200, 0], atol=1e-3)


def test_score_rejects_bad_input_and_scores_good_input(fitted, data):
    assert fitted.score(**data) == pytest.approx(1.0, abs=1e-12)
    with pytest.raises(ValueError, match=r"x_ddot: contains NaN"):
        fitted.score(**_with(data, x_ddot=_nan_at(data["x_ddot"])))
    with pytest.raises(ValueError, match=r"t: expected 401 times"):
        fitted.score(**_with(data, t=data["t"][:-1]))


def test_model_without_acceleration_cannot_predict(data):
    # only the force column survives: the equations contain no acceleration
    model = px.XLSINDy(_library(), px.ExplicitOptimizer()).fit(**data)
    model.coef_ = np.array([-1.0, 0.0, 0.0, 0.0])
    model._build_dynamics()
    assert model.dynamics_ is None
    with pytest.raises(ValueError, match="contain no acceleration"):
        model.predict(data["x"], data["x_dot"])
    with pytest.raises(ValueError, match="contain no acceleration"):
        model.simulate([1.0, 0.0], data["t"])
