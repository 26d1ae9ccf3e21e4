"""The anchored-spring family of the automatic catalog: the length of a spring between a point
moved by one coordinate and an anchor off its path, with its geometry fitted by variable
projection, against an offset spring pendulum and an oblique spring slider integrated by
scipy at 1e-10 (truth from their sympy potentials)."""

import numpy as np
import pytest
import sympy as sp
from support.growth import damped_forced_runs

import pysindy_xl as px
from pysindy_xl.catalog import MORE_MOVES, MOVES
from pysindy_xl.catalog.anchors import AnchorFits, length_force
from pysindy_xl.catalog.bases import anchored_spring

# the pendulum of the second blind set: bob 0.5 at 0.5, spring k = 6, rest 0.3, anchored at
# (0.4, -0.8) from the pivot: |bob - anchor|^2 = 1.05 (1 - e cos(theta - phi))
MASS, LENGTH, STIFFNESS, REST = 0.5, 0.5, 6.0, 0.3
INERTIA = MASS * LENGTH ** 2
E, PHI = float(np.hypot(0.4, 0.8) / 1.05), float(np.arctan2(0.4, 0.8))


def _pendulum_potential(theta):
    d = sp.sqrt(1.05 - 0.4 * sp.sin(theta) - 0.8 * sp.cos(theta))
    return -MASS * 9.81 * LENGTH * sp.cos(theta) + STIFFNESS / 2 * (d - REST) ** 2


def _slider_potential(x):  # the first blind set's slider: k = 4, anchor 1 off the rod, rest 0.5
    return 2.0 * (sp.sqrt(1 + x ** 2) - 0.5) ** 2


def _runs(potential, scale, amplitude):
    """Two forced runs, unit inertia after dividing by ``scale``: ``q'' = u - V'(q) / scale -
    0.1 q'`` by scipy's DOP853 at 1e-10."""
    q = sp.Symbol("q", real=True)
    restoring = sp.lambdify(q, -sp.diff(potential(q), q) / scale, "numpy")
    return damped_forced_runs(restoring, amplitude, lambda rng, seed: 0.2 * seed), restoring


def _fits(name, kind, runs):
    t, xs, _, _, us = runs
    return AnchorFits({"coordinates": [name], "kinds": [kind]},
                      {"x": xs, "t": [t, t], "u": us, "x_dot": None},
                      px.BumpTestFunctions(width=0.3), px.fit.RememberedSmoother())


def test_a_catalog_states_the_springs_length():
    theta, x = sp.symbols("theta x", real=True)
    assert str(anchored_spring(theta, "angle", (0.85, 0.46))) == \
        "sqrt(1 - 0.85*cos(theta - 0.46))"
    # the length squared is the first catalog's: a quadratic of x, a cosine of theta
    d = anchored_spring(x, "linear", (0.3, 2.0))
    assert sp.simplify(sp.expand(d ** 2) - (x ** 2 - 0.6 * x + 4.09)) == 0
    catalog = px.AutomaticCatalog("x,theta", kinds={"theta": "angle"}, kinetic="constant",
                                  anchors={"theta": (0.85, 0.46)})
    plain = px.AutomaticCatalog("x,theta", kinds={"theta": "angle"}, kinetic="constant")
    assert catalog.n_terms == plain.n_terms + 1
    theta = px.Coordinates(["x", "theta"]).q[1]
    assert anchored_spring(theta, "angle", (0.85, 0.46)) in catalog.lagrange_terms()
    assert "sqrt(1 - 0.85*cos(theta - 0.46))" in catalog.describe()
    from sklearn.base import clone
    assert clone(catalog).get_params()["anchors"] == {"theta": (0.85, 0.46)}
    # the move is a default one, tried late (with the exponentials, before the splines)
    assert "anchored_springs" in MOVES and "anchored_springs" not in MORE_MOVES


@pytest.mark.parametrize("bad, error, words", [
    ({"theta": (1.2, 0.0)}, ValueError, "(0, 1)"),
    ({"x": (0.0, -1.0)}, ValueError, "positive"),
    ({"x": (0.0, float("nan"))}, ValueError, "finite"),
    ({"x": 1.0}, ValueError, "pair"),
    ({"y": (0.0, 1.0)}, ValueError, "not among the coordinates"),
    ([(0.0, 1.0)], TypeError, "mapping"),
])
def test_bad_anchors_are_refused_by_name(bad, error, words):
    catalog = px.AutomaticCatalog("x,theta", kinds={"theta": "angle"}, anchors=bad)
    with pytest.raises(error, match="anchors") as raised:
        _ = catalog.n_terms
    assert words in str(raised.value)


def test_an_unknown_move_is_refused_by_name():
    t = np.linspace(0.0, 1.0, 50)
    with pytest.raises(ValueError, match="moves: unknown") as raised:
        px.grow_catalog([t[:, None]], [t], [t[:, None]], coordinates=["x"],
                        moves=MOVES + ("anchored_spring",))
    assert "anchored_springs" in str(raised.value)  # (the right name among the expected)


def test_the_length_force_is_the_derivative_of_the_length():
    theta = sp.Symbol("theta", real=True)
    q = np.linspace(-3.0, 3.0, 13)
    for kind, anchor in (("angle", (E, PHI)), ("linear", (0.3, 0.7))):
        exact = sp.lambdify(theta, sp.diff(anchored_spring(theta, kind, anchor), theta))
        assert np.allclose(length_force(kind, anchor, q), exact(q), rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("system", ["pendulum", "slider"])
def test_variable_projection_finds_the_anchor_free_of_noise(system):
    if system == "pendulum":
        runs, _ = _runs(_pendulum_potential, INERTIA, 4.0)
        fits, name, truth = _fits("theta", "angle", runs), "theta", (E, PHI)
    else:
        runs, _ = _runs(_slider_potential, 1.0, 3.0)
        fits, name, truth = _fits("x", "linear", runs), "x", (0.0, 1.0)
    start = {"degree": 2, "trig_degree": 1, "kinetic": "constant"}
    anchors = fits(start)
    assert np.allclose(anchors[name], truth, atol=2e-3), anchors
    _, residual, without = fits.residuals[name]
    assert residual < 1e-4 < 0.01 < without


def test_the_exact_law_simulates_saves_loads_and_exports(tmp_path):
    (t, xs, dxs, ddxs, us), restoring = _runs(_pendulum_potential, INERTIA, 4.0)
    catalog = px.AutomaticCatalog("theta", kinds="angle", kinetic="constant",
                                  anchors={"theta": (E, PHI)})
    model = px.XLSINDy(catalog, optimizer=px.ExplicitOptimizer(threshold=0.0)).fit(
        xs, [t, t], x_dot=dxs, x_ddot=ddxs, u=us)
    assert "sqrt(1 - 0.851835" in str(model.lagrangian())
    # the force beyond the recorded range, all around the circle
    low, high = np.vstack(xs).min(), np.vstack(xs).max()
    q = np.linspace(-np.pi, np.pi, 41)[:, None]
    assert low > -np.pi + 0.5 and high < np.pi - 0.5
    zero = np.zeros_like(q)
    assert np.allclose(model.predict(q, zero), restoring(q), rtol=1e-6, atol=1e-6)
    start = np.array([xs[0][0, 0], dxs[0][0, 0]])
    simulated = model.simulate(start, t[:400], u=lambda time: np.zeros(1))
    from scipy.integrate import solve_ivp
    truth = solve_ivp(lambda _, y: [y[1], restoring(y[0]) - 0.1 * y[1]], (t[0], t[399]),
                      start, t_eval=t[:400], method="DOP853", rtol=1e-10, atol=1e-10).y.T
    assert np.abs(simulated[:, 0] - truth[:, 0]).max() < 1e-4
    model.save(tmp_path / "pendulum.json")
    loaded = px.XLSINDy.load(tmp_path / "pendulum.json")
    assert np.allclose(loaded.predict(q, zero), model.predict(q, zero), rtol=1e-12, atol=0)
    rhs = model.to_jax()  # single precision
    derivative = np.asarray(rhs(np.hstack([q, zero]), np.zeros_like(q)))
    assert np.allclose(derivative[:, 1:], model.predict(q, zero), rtol=1e-4, atol=1e-4)


def _grown(noise):
    (t, xs, _, _, us), restoring = _runs(_slider_potential, 1.0, 3.0)
    noisy = [x + np.random.default_rng(5 + k).normal(0.0, noise * x.std(), x.shape)
             for k, x in enumerate(xs)]
    found = px.grow_catalog(noisy, [t, t], us, coordinates=["x"], kinds=["linear"],
                            moves=MOVES + ("anchored_springs",))
    return found, restoring, xs


def _check_slider_law(found, restoring, xs, tolerance):
    anchors = found.catalog.get_params()["anchors"]
    assert anchors is not None and np.allclose(anchors["x"], (0.0, 1.0), atol=0.05), anchors
    # V = 2 (d - 0.5)^2 = 2 d^2 - 2 d + const, d = sqrt(x^2 + 1): L holds 0.5 x_dot^2,
    # -2 x^2 and +2 d
    lagrangian = found.model.lagrangian()
    symbols = {str(s): s for s in lagrangian.free_symbols}
    x, x_dot = symbols["x"], symbols["x_dot"]
    terms = sp.Add.make_args(sp.expand(lagrangian))
    lengths = [t for t in terms if any(p.exp == sp.Rational(1, 2) for p in t.atoms(sp.Pow))]
    assert len(lengths) == 1, lagrangian
    length_coefficient = float(lengths[0].as_coeff_Mul()[0])
    assert abs(length_coefficient - 2.0) < tolerance * 2.0, lagrangian
    for term, value in {x_dot ** 2: 0.5, x ** 2: -2.0}.items():
        found_value = float(sp.expand(lagrangian).coeff(term))
        assert abs(found_value - value) < tolerance * abs(value), (term, lagrangian)
    # the force beyond the recorded range
    span = np.abs(np.vstack(xs)).max()
    q = np.linspace(-2 * span, 2 * span, 41)[:, None]
    zero = np.zeros_like(q)
    true = restoring(q)
    assert np.linalg.norm(found.model.predict(q, zero) - true) < tolerance * np.linalg.norm(true)


def test_the_growth_with_the_move_finds_the_slider_law():
    found, restoring, xs = _grown(0.0)
    _check_slider_law(found, restoring, xs, 0.01)


@pytest.mark.slow
def test_the_growth_with_the_move_finds_the_slider_law_at_one_percent_noise():
    found, restoring, xs = _grown(0.01)
    _check_slider_law(found, restoring, xs, 0.05)


def test_the_move_applies_once_and_the_backward_phase_takes_it_out():
    from pysindy_xl.catalog.backward import removed
    from pysindy_xl.catalog.moves import START, holds, moved

    grown = dict(START, trig_degree=3)
    state = moved(grown, "anchored_springs", ["angle"], 1, anchors=lambda s: {"theta": (E, PHI)})
    # the length takes the place of the degrees that stood in for it
    assert state["anchors"] == {"theta": (E, PHI)} and state["trig_degree"] == 1
    assert moved(state, "anchored_springs", ["angle"], 1, anchors={"theta": (0.5, 0.0)}) is None
    assert moved(START, "anchored_springs", ["angle"], 1) is None  # (no anchors fitted)
    assert moved(START, "anchored_springs", ["angle"], 1, anchors=lambda s: {}) is None
    assert holds(state, START) and not holds(START, state)
    assert "anchors" not in removed(state, "anchored_springs", ["angle"], START)
    assert removed(START, "anchored_springs", ["angle"], START) is None


def test_an_anchor_on_the_path_is_refused_as_a_stand_in():
    """A torsion pendulum (``V = k/2 theta^2 - m g l cos(theta)``, no spring's length): from
    the first catalog (sines and cosines, no power of theta) the residual falls towards an
    anchor on the circle's far side, ``sqrt(1 + cos theta)``, a half-angle cosine that stands in
    for ``theta^2``; that end of the range is refused, as its far end is."""
    def torsion(theta):
        return 1.5 * theta ** 2 - 3.924 * sp.cos(theta)

    runs, _ = _runs(torsion, 1.0, 3.0)
    fits = _fits("theta", "angle", runs)
    anchors = fits({"degree": 2, "trig_degree": 1, "kinetic": "constant"})
    assert "theta" not in anchors, anchors
