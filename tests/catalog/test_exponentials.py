"""The exponential family of the automatic catalog: ``exp(a x)`` and ``exp(2 a x)`` of a linear
coordinate with one fitted rate, against a Morse oscillator integrated by scipy at 1e-10."""

import numpy as np
import pytest
import sympy as sp
from support.growth import damped_forced_runs

import pysindy_xl as px
from pysindy_xl.catalog import MOVES
from pysindy_xl.catalog.bases import exponential_pair
from pysindy_xl.catalog.rates import RateFits

RATE = 1.5  # V = 2 (1 - exp(-1.5 x))^2


def _morse_force():
    """The restoring force -dV/dx of the Morse well, from its sympy Lagrangian."""
    x, v = sp.symbols("x v", real=True)
    lagrangian = v ** 2 / 2 - 2 * (1 - sp.exp(-RATE * x)) ** 2
    return sp.lambdify(x, sp.diff(lagrangian, x), "numpy")


def _runs(amplitude=1.5, initial=lambda rng, seed: 0.3 * (seed - 0.5)):
    """Two forced runs x'' = u - dV/dx - 0.1 x' by scipy's DOP853 at 1e-10."""
    return damped_forced_runs(_morse_force(), amplitude, initial)


def test_a_catalog_states_the_exponentials_of_a_rate():
    catalog = px.AutomaticCatalog("x,theta", kinds={"theta": "angle"}, kinetic="constant",
                                  exponentials={"x": -RATE})
    terms = catalog.lagrange_terms()
    x = px.Coordinates(["x", "theta"]).q[0]
    assert exponential_pair(x, -RATE) == [sp.exp(-RATE * x), sp.exp(-2 * RATE * x)]
    assert set(exponential_pair(x, -RATE)) <= set(terms)
    assert catalog.n_terms == px.AutomaticCatalog("x,theta", kinds={"theta": "angle"},
                                                  kinetic="constant").n_terms + 2
    assert "exp(-1.5 x), exp(-3 x)" in catalog.describe()
    # the rate is stored as given (clone, get_params)
    from sklearn.base import clone
    assert clone(catalog).get_params()["exponentials"] == {"x": -RATE}


@pytest.mark.parametrize("bad, error, words", [
    ({"theta": 1.0}, ValueError, "angle"),
    ({"y": 1.0}, ValueError, "not among the coordinates"),
    ({"x": 0.0}, ValueError, "nonzero"),
    ({"x": float("inf")}, ValueError, "finite"),
    ({"x": "fast"}, TypeError, "real rate"),
    ([1.0], TypeError, "mapping"),
])
def test_bad_rates_are_refused_by_name(bad, error, words):
    catalog = px.AutomaticCatalog("x,theta", kinds={"theta": "angle"}, exponentials=bad)
    with pytest.raises(error, match="exponentials") as raised:
        _ = catalog.n_terms
    assert words in str(raised.value)


def test_the_exact_law_simulates_saves_loads_and_exports(tmp_path):
    t, xs, dxs, ddxs, us = _runs()
    catalog = px.AutomaticCatalog("x", kinetic="constant", degree=1,
                                  exponentials={"x": -RATE})
    model = px.XLSINDy(catalog, optimizer=px.ExplicitOptimizer(threshold=0.0)).fit(
        xs, [t, t], x_dot=dxs, x_ddot=ddxs, u=us)
    force = _morse_force()
    q = np.linspace(-0.6, 2.0, 40)[:, None]  # beyond the runs on both sides
    zero = np.zeros_like(q)
    assert np.allclose(model.predict(q, zero), force(q), rtol=1e-6, atol=1e-6)
    # simulate against scipy's integration of the truth
    start = np.array([xs[0][0, 0], dxs[0][0, 0]])
    simulated = model.simulate(start, t[:400], u=lambda time: np.zeros(1))
    from scipy.integrate import solve_ivp
    truth = solve_ivp(lambda _, y: [y[1], force(y[0]) - 0.1 * y[1]], (t[0], t[399]), start,
                      t_eval=t[:400], method="DOP853", rtol=1e-10, atol=1e-10).y.T
    assert np.abs(simulated[:, 0] - truth[:, 0]).max() < 1e-4
    import pickle
    assert np.array_equal(pickle.loads(pickle.dumps(model)).predict(q, zero),
                          model.predict(q, zero))
    assert model.feature_library.get_params()["exponentials"] == {"x": -RATE}  # (unchanged)
    model.save(tmp_path / "morse.json")
    loaded = px.XLSINDy.load(tmp_path / "morse.json")
    assert np.allclose(loaded.predict(q, zero), model.predict(q, zero), rtol=1e-12, atol=0)
    rhs = model.to_jax()  # single precision
    derivative = np.asarray(rhs(np.hstack([q, zero]), np.zeros_like(q)))
    assert np.allclose(derivative[:, 1:], model.predict(q, zero), rtol=1e-4, atol=1e-4)


def test_the_rate_is_fitted_by_variable_projection_free_of_noise():
    t, xs, _, _, us = _runs()
    fixed = {"coordinates": ["x"], "kinds": ["linear"],
             "bounds": [tuple(np.percentile(np.vstack(xs), [1, 99]))]}
    fits = RateFits(fixed, {"x": xs, "t": [t, t], "u": us, "x_dot": None},
                    px.BumpTestFunctions(width=0.3), px.fit.RememberedSmoother())
    start = {"degree": 2, "kinetic": "constant"}
    rates = fits(start)
    assert abs(rates["x"] + RATE) < 1e-3 * RATE
    rate, residual, without = fits.residuals["x"]
    assert residual < 1e-4 < 0.1 < without


def _fresh_run_error(found):
    """RMS relative error of the forces the found law predicts on a fresh run, driven harder
    from deeper in the wall than the training runs, and its share outside their range."""
    t, xs, dxs, ddxs, us = _runs(amplitude=2.2, initial=lambda rng, seed: -0.45 + 0.1 * seed)
    x, xd, xdd, u = (np.vstack(a) for a in (xs, dxs, ddxs, us))
    predicted = found.model.predict_forces(x, xd, xdd)
    return float(np.sqrt(np.mean((predicted - u) ** 2) / np.mean(u ** 2))), x


@pytest.mark.slow
def test_the_growth_finds_the_morse_rate_and_forces_beyond_the_training_range():
    t, xs, _, _, us = _runs()
    noisy = [x + np.random.default_rng(3 + k).normal(0.0, 0.01 * x.std(), x.shape)
             for k, x in enumerate(xs)]
    errors = {}
    for label, moves in (("with", MOVES), ("without", tuple(m for m in MOVES
                                                            if m != "exponentials"))):
        found = px.grow_catalog(noisy, [t, t], us, coordinates=["x"], kinds=["linear"],
                                moves=moves)
        errors[label], fresh = _fresh_run_error(found)
        if label == "with":
            rates = found.catalog.get_params()["exponentials"]
            assert rates is not None and abs(rates["x"] + RATE) < 0.03 * RATE
    training = np.vstack(xs)
    outside = np.mean((fresh < training.min()) | (fresh > training.max()))
    assert outside > 0.05  # the fresh run leaves the training range
    assert errors["with"] < 0.02 < errors["without"]
