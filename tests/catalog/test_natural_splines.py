"""Natural cubic splines: the basis, and spline potentials that continue beyond the data."""

import numpy as np
import pytest
import sympy as sp
from support.growth import damped_forced_runs

import pysindy_xl as px
from pysindy_xl.catalog.bases import natural_splines


def _values(basis, x, points):
    f = sp.lambdify(x, basis, "numpy")
    return np.array([np.broadcast_to(v, np.shape(points)) for v in f(points)], dtype=float)


def test_natural_splines_span_the_natural_space_and_continue_linearly():
    x = sp.Symbol("x", real=True)
    low, high, k = -1.0, 2.0, 7
    basis = natural_splines(x, low, high, k)
    assert len(basis) == k
    grid = np.linspace(-4.0, 5.0, 901)
    values = _values(basis, x, grid)
    assert np.allclose(values.sum(axis=0), 1.0, atol=1e-12)  # partition of unity
    # the line is in the span (least squares reproduces it to rounding)
    coef = np.linalg.lstsq(values.T, grid, rcond=None)[0]
    assert np.allclose(values.T @ coef, grid, atol=1e-9)
    # beyond the end knots every function is a line: zero second differences
    step = 1e-2
    for outside in (np.linspace(-4.0, low - 0.05, 20), np.linspace(high + 0.05, 5.0, 20)):
        second = (_values(basis, x, outside + step) - 2 * _values(basis, x, outside)
                  + _values(basis, x, outside - step)) / step ** 2
        assert np.abs(second).max() < 1e-8
    # inside, a cubic spline (not a line), twice continuously differentiable across the ends
    h = 1e-4
    for end in (low, high):
        around = np.array([end - 2 * h, end - h, end, end + h, end + 2 * h])
        v = _values(basis, x, around)
        left = (v[:, 2] - 2 * v[:, 1] + v[:, 0]) / h ** 2
        right = (v[:, 4] - 2 * v[:, 3] + v[:, 2]) / h ** 2
        assert np.abs(left).max() < 1e-2 and np.abs(right).max() < 1e-2  # natural: f'' = 0
    middle = _values(basis, x, np.array([0.4, 0.5, 0.6]))
    assert np.abs(middle[:, 0] - 2 * middle[:, 1] + middle[:, 2]).max() > 1e-4


def test_natural_splines_refuse_too_few_knots():
    x = sp.Symbol("x", real=True)
    with pytest.raises(ValueError, match="splines: expected at least 4"):
        natural_splines(x, 0.0, 1.0, 3)
    with pytest.raises(ValueError, match="splines: expected at least 4 natural splines of 'x'"):
        px.AutomaticCatalog(["x"], splines=3, bounds=[(0.0, 1.0)]).fit()


def _log_cosh_runs():
    """x'' = u - 4 tanh(2 x) - 0.1 x' (V = 2 log cosh 2x, unit mass), by scipy at 1e-10."""
    return damped_forced_runs(lambda x: -4 * np.tanh(2 * x), 3.0,
                              lambda rng, seed: rng.uniform(-1, 1))


def test_a_spline_potential_continues_with_a_constant_force_beyond_the_data(tmp_path):
    t, xs, dxs, ddxs, us = _log_cosh_runs()
    stacked = np.vstack(xs)[:, 0]
    bounds = [tuple(np.percentile(stacked, [1, 99]))]
    catalog = px.AutomaticCatalog(["x"], bounds=bounds, splines=12, kinetic="constant")
    model = px.XLSINDy(catalog, optimizer=px.ExplicitOptimizer(threshold=0.0)).fit(
        xs, [t, t], x_dot=dxs, x_ddot=ddxs, u=us)
    # the restoring force saturates (4 tanh 2x): beyond the data it is nearly constant, which is
    # what a natural spline's linear continuation states (a B-spline would fall to zero there)
    span = stacked.max() - stacked.min()
    q = np.r_[np.linspace(stacked.min() - 0.3 * span, stacked.min(), 20),
              np.linspace(stacked.max(), stacked.max() + 0.3 * span, 20)][:, None]
    zero = np.zeros_like(q)
    truth = 4 * np.tanh(2 * q)
    predicted = model.predict_forces(q, zero, zero)
    assert np.abs(predicted - truth).max() < 0.05 * 4
    # simulate, save and load go through the restricted grammar
    x0 = np.array([stacked.max() + 0.2 * span, 0.0])
    simulated = model.simulate(x0, t[:200], u=lambda _: np.zeros(1))
    assert np.all(np.isfinite(simulated))
    path = tmp_path / "spline.json"
    model.save(path)
    loaded = px.XLSINDy.load(path)
    assert np.allclose(loaded.predict_forces(q, zero, zero), predicted, rtol=1e-10, atol=1e-12)


def test_the_reported_spline_potential_is_the_identified_one():
    """GrowthResult.spline_potentials samples the potential the splines state: on the log-cosh
    well (V = 2 log cosh 2x, fitted with splines alone), the true potential to within 1 % of
    its range, up to the constant that no force shows."""
    from pysindy_xl.catalog.path import GrowthResult

    t, xs, dxs, ddxs, us = _log_cosh_runs()
    bounds = [tuple(np.percentile(np.vstack(xs)[:, 0], [1, 99]))]
    catalog = px.AutomaticCatalog(["x"], bounds=bounds, splines=12, degree=0,
                                  kinetic="constant")
    model = px.XLSINDy(catalog, optimizer=px.ExplicitOptimizer(threshold=0.0)).fit(
        xs, [t, t], x_dot=dxs, x_ddot=ddxs, u=us)
    found = GrowthResult(model, catalog, [], "forces", 0.0)
    grid, values = found.spline_potentials(n_points=11)["x"]
    np.testing.assert_allclose(grid, np.linspace(*bounds[0], 11))
    truth = 2 * np.log(np.cosh(2 * grid))
    shown, expected = values - values.mean(), truth - truth.mean()
    assert np.abs(shown - expected).max() < 0.01 * np.ptp(truth)
    with pytest.raises(ValueError, match="n_points: expected an integer >= 2"):
        found.spline_potentials(n_points=1)
