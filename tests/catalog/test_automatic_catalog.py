"""AutomaticCatalog: the candidate terms, their libraries, splines, bad input."""

import pickle
import warnings

import numpy as np
import pytest
import sympy as sp
from sklearn.base import clone

import pysindy_xl as px
from pysindy_xl.catalog import AutomaticCatalog, bspline
from pysindy_xl.feature_library import PolynomialLagrangeLibrary


def _names(catalog):
    return catalog.fit().get_feature_names()


def test_terms_follow_the_shape_of_a_lagrangian():
    cat = AutomaticCatalog(["r", "theta"], kinds={"theta": "angle"}, interaction=2)
    names = _names(cat)
    c = px.Coordinates(["r", "theta"])
    r, th = c.q
    rd, thd = c.qd
    terms = set(cat.lagrange_terms())
    # kinetic with configuration-dependent coefficients, potentials across coordinates
    for needed in (rd ** 2, thd ** 2, r ** 2 * thd ** 2, r * sp.cos(th), r ** 2, r,
                   sp.sin(th) * r * rd * thd):
        assert needed in terms, needed
    # no constant, no f(q_i) qd_i (a total time derivative), no bare angle by default
    assert sp.Integer(1) not in terms and r * rd not in terms
    hidden = {sp.sin(th): sp.Symbol("s"), sp.cos(th): sp.Symbol("c")}
    assert not any(t.xreplace(hidden).has(th) for t in terms)
    assert names[0] == "F[tau]" and names[-2:] == ["C_r[r_dot]", "C_theta[theta_dot]"]
    assert cat.n_terms == len(names) - 1 == len(terms) + 2
    # the trigonometric polynomials take the fast derivation
    assert [type(lib).__name__ for lib in cat.libraries] == [
        "ExternalForces", "PolynomialLagrangeLibrary", "ClassicalLibrary"]


def test_angle_powers_gyroscopic_and_coulomb_terms():
    cat = AutomaticCatalog("x,theta", kinds=["linear", "angle"], angle_degree=2, gyroscopic=True,
                           dissipation=("viscous", "coulomb"), coulomb_scale=0.5)
    c = px.Coordinates(["x", "theta"])
    x, th = c.q
    xd, thd = c.qd
    terms = set(cat.lagrange_terms())
    assert {th, th ** 2, x * thd, sp.sin(th) * xd, sp.cos(th) * xd} <= terms
    assert th * thd not in terms  # a total time derivative
    names = _names(cat)
    assert "C_x[tanh(2.0*x_dot)]" in names and "C_theta[tanh(2.0*theta_dot)]" in names
    # bare angles go to the symbolic library, the rest stays fast
    kinds = [type(lib).__name__ for lib in cat.libraries]
    assert kinds == ["ExternalForces", "PolynomialLagrangeLibrary", "LagrangeLibrary",
                     "ClassicalLibrary"]
    assert all(not t.has(sp.sin(th)) for t in cat.libraries[2].terms)


def test_catalog_clones_pickles_and_saves(tmp_path):
    cat = AutomaticCatalog(["x"], degree=4)
    again = clone(cat)
    assert again.get_params() == cat.get_params() and _names(again) == _names(cat)
    t = np.linspace(0, 10, 1001)
    x = (np.sin(t) + 0.4 * np.sin(2.3 * t))[:, None]
    xd = (np.cos(t) + 0.92 * np.cos(2.3 * t))[:, None]
    xdd = (-np.sin(t) - 2.116 * np.sin(2.3 * t))[:, None]
    u = 1.5 * xdd + 2.0 * x + 0.5 * x ** 3
    model = px.XLSINDy(cat).fit(x, t, x_dot=xd, x_ddot=xdd, u=u)
    found = dict(zip(model.get_feature_names(), model.coefficients(), strict=True))
    assert found["L[x_dot**2]"] == pytest.approx(0.75, rel=1e-6)
    assert found["L[x**2]"] == pytest.approx(-1.0, rel=1e-6)
    assert found["L[x**4]"] == pytest.approx(-0.125, rel=1e-6)
    restored = pickle.loads(pickle.dumps(model))
    assert np.allclose(restored.predict(x, xd, u), xdd)
    path = tmp_path / "model.json"
    model.save(path)
    loaded = px.XLSINDy.load(path)
    assert loaded.get_feature_names() == model.get_feature_names()
    assert np.allclose(loaded.predict(x, xd, u), xdd)


def test_bspline_is_a_partition_of_unity_and_simulates():
    q = sp.Symbol("q", real=True)
    centers = np.arange(-3.0, 4.0)
    total = sum(bspline(q, c, 1.0) for c in centers)
    values = [float(total.subs(q, v)) for v in np.linspace(-1.0, 1.0, 7)]
    assert np.allclose(values, 1.0)
    # a spline potential: usable by simulate (and to_jax when JAX is there)
    cat = AutomaticCatalog(["x"], degree=0, splines=5, bounds=[(-2.0, 2.0)], dissipation=())
    t = np.linspace(0, 6, 601)
    x = np.sin(t)[:, None]
    model = px.XLSINDy(cat).fit(x, t, x_dot=np.cos(t)[:, None], x_ddot=-x,
                                u=-x + 0.3 * np.tanh(3 * x))
    simulated = model.simulate(np.array([0.5, 0.0]), t[:100], u=lambda _: np.zeros(1))
    assert np.all(np.isfinite(simulated))
    jax = pytest.importorskip("jax")
    f = model.to_jax()
    state = np.array([0.3, 0.1])
    expected = model.predict(state[None, :1], state[None, 1:], np.zeros((1, 1)))[0, 0]
    assert float(f(jax.numpy.asarray(state), jax.numpy.zeros(1))[1]) == pytest.approx(
        expected, rel=1e-5)


@pytest.mark.parametrize("kwargs, message", [
    ({"kinds": {"x": "spring"}}, "kinds: coordinate 'x' has the unknown kind 'spring'"),
    ({"kinds": ["linear", "angle"]}, "kinds: expected one kind per coordinate"),
    ({"kinds": {"y": "angle"}}, r"kinds: \['y'\] are not among the coordinates"),
    ({"degree": 12, "interaction": 1, "max_terms": 5}, "max_terms: the catalog would have"),
    ({"dissipation": ("stribeck",)}, "dissipation: unknown model 'stribeck'"),
    ({"splines": 4}, "bounds: B-splines of 'x' need its range"),
    ({"coordinates": []}, "coordinates: expected a non-empty list"),
    ({"bounds": [(1.0, -1.0)]}, "bounds: expected finite low < high for 'x'"),
    ({"bounds": {"x": (0.0, np.inf)}}, "bounds: expected finite low < high for 'x'"),
    ({"bounds": [(0.0, 1.0, 2.0)]}, r"bounds: expected a pair \(low, high\) of real numbers"),
])
def test_bad_parameters_name_the_argument(kwargs, message):
    params = {"coordinates": ["x"], **kwargs}
    with pytest.raises(ValueError, match=message):
        AutomaticCatalog(**params).fit()


def test_polynomial_library_warns_when_an_angle_is_also_bare():
    c = px.Coordinates(["theta"])
    th, thd = c.q[0], c.qd[0]
    with pytest.warns(UserWarning, match="theta enters both through sin/cos and bare"):
        mixed = PolynomialLagrangeLibrary(c, [thd ** 2, sp.cos(th), th ** 2]).fit()
    data = np.random.default_rng(0).normal(size=(20, 5))
    reference = px.LagrangeLibrary(c, [thd ** 2, sp.cos(th), th ** 2]).fit()
    assert np.allclose(mixed.transform(data), reference.transform(data))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        PolynomialLagrangeLibrary(c, [thd ** 2, sp.cos(th)]).fit()


def test_coupled_damping_puts_every_velocity_in_every_equation():
    """``"coupled"``: each velocity's viscous force in every equation (with ``"viscous"``) or
    in the others' only (alone); ``n_terms`` counts the columns."""
    names, kinds = ["x", "a"], ["linear", "angle"]
    plain = AutomaticCatalog(names, kinds=kinds, kinetic="constant")
    coupled = AutomaticCatalog(names, kinds=kinds, kinetic="constant",
                               dissipation=("viscous", "coupled"))
    alone = AutomaticCatalog(names, kinds=kinds, kinetic="constant", dissipation="coupled")
    assert coupled.n_terms == plain.n_terms + 2 and alone.n_terms == plain.n_terms
    assert "dissipation viscous+coupled" in coupled.describe()
    assert coupled.libraries[-1].fit().get_feature_names() == \
        ["C_x[x_dot]", "C_a[x_dot]", "C_x[a_dot]", "C_a[a_dot]"]
    assert alone.libraries[-1].fit().get_feature_names() == ["C_a[x_dot]", "C_x[a_dot]"]
    with pytest.raises(ValueError, match="dissipation: expected one of"):
        _ = AutomaticCatalog(names, kinds=kinds, dissipation="rayleigh").n_terms
